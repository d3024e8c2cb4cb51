//! Helpers every crate's tests share: the GPU they run on and a runner for one pass.
//! A dev-dependency only; nothing in a library depends on it.

pub mod copy_pyramid;
pub mod features;
pub mod frames;
pub mod gltf_writer;
pub mod pass_errors;
pub mod shader_variants;
pub mod xvfb;
use meshlight_graph::{
    Bindings, BufferDesc, CompileOptions, Executor, FrameData, GpuContext, GraphBuilder,
    GraphError, Imports, Pass, Result, TextureDesc, file::Params,
};

/// The first Vulkan adapter, opened with every feature it has that a pass may use.
/// Without one the test fails with the error, which says how to install a driver
/// (lavapipe with apt-get).
pub fn gpu() -> GpuContext {
    GpuContext::with_available(wgpu::Features::all()).unwrap_or_else(|e| panic!("{e}"))
}

/// An executor on [`gpu`].
pub fn executor() -> Executor {
    Executor::new(gpu())
}

/// A buffer the pass reads: imported under `name` with these contents.
pub struct Input<'a> {
    pub name: &'static str,
    pub desc: BufferDesc,
    pub bytes: &'a [u8],
}

/// A buffer the pass writes: created under `name`, exported, read back after the frame.
pub struct Output {
    pub name: &'static str,
    pub desc: BufferDesc,
}

/// Runs `pass` for one frame on `exec` with its slots bound to the inputs and outputs of
/// the same names, and returns each output's bytes in order.
pub fn run_one_pass(
    exec: &mut Executor,
    pass: impl Pass + 'static,
    inputs: &[Input],
    outputs: &[Output],
    frame: &FrameData,
) -> Result<Vec<Vec<u8>>> {
    let mut g = GraphBuilder::new();
    for i in inputs {
        g.import_buffer(i.name, i.desc.clone(), USAGE);
    }
    for o in outputs {
        g.create_buffer(o.name, o.desc.clone());
    }
    let written = g.add_pass("pass", pass, Bindings::new())?;
    for o in outputs {
        g.export(written.buffer(o.name)?);
    }
    let names: Vec<&str> = outputs.iter().map(|o| o.name).collect();
    run_graph(exec, g, inputs, &names, frame)
}

/// Compiles `g` for `exec`'s GPU and runs it for one frame with each of `inputs` made
/// on the GPU and imported under its name (`g` declares those imports), then returns
/// the bytes of each exported buffer `outputs` names, in order.
pub fn run_graph(
    exec: &mut Executor,
    g: GraphBuilder,
    inputs: &[Input],
    outputs: &[&str],
    frame: &FrameData,
) -> Result<Vec<Vec<u8>>> {
    let compiled = g.compile(&CompileOptions::for_gpu(&exec.gpu))?;
    let buffers: Vec<wgpu::Buffer> = inputs
        .iter()
        .map(|i| exec.gpu.buffer_with_data(i.name, i.bytes, USAGE))
        .collect();
    let imports = inputs
        .iter()
        .zip(&buffers)
        .fold(Imports::new(), |imports, (i, b)| imports.buffer(i.name, b));
    exec.execute_frame(&compiled, &imports, frame)?;
    outputs.iter().map(|name| exec.read_buffer(name)).collect()
}

/// A texture as `desc` describes it (its size, format, mips and layers), for a test to
/// import or fill: what the graph itself would create for that description.
pub fn texture(
    gpu: &GpuContext,
    label: &str,
    desc: &TextureDesc,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: desc.width,
            height: desc.height,
            depth_or_array_layers: desc.layers,
        },
        mip_level_count: desc.mip_levels,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: desc.format,
        usage,
        view_formats: &[],
    })
}

/// Copies mip 0 of `texture` (which needs COPY_SRC) to the CPU, rows tightly packed.
///
/// Unlike [`GpuContext::read_texture`] it takes the aspect, so a depth texture's depth
/// can be read on its own.
pub fn read_texture(
    gpu: &GpuContext,
    texture: &wgpu::Texture,
    aspect: wgpu::TextureAspect,
) -> Vec<u8> {
    let format = texture.format();
    let texel = format
        .block_copy_size(Some(aspect))
        .unwrap_or_else(|| panic!("{format:?}'s {aspect:?} cannot be copied to a buffer"));
    let (width, height) = (texture.width(), texture.height());
    let row = width * texel;
    let padded = row.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("texture readback"),
        size: u64::from(padded) * u64::from(height),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &staging,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(height),
            },
        },
        wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
    );
    gpu.queue.submit([encoder.finish()]);
    let bytes = gpu.map_and_read(&staging).unwrap_or_else(|e| panic!("{e}"));
    bytes
        .chunks(padded as usize)
        .flat_map(|r| &r[..row as usize])
        .copied()
        .collect()
}

/// Pipeline-file params from TOML text, as a `[[pass]]`'s `params` table holds them.
pub fn params(text: &str) -> Params {
    Params::new(text.parse().unwrap_or_else(|e| panic!("{text}: {e}")))
}

/// The message of a [`GraphError::Parameter`]: what a test of bad params reads to check
/// that it names what to change. Any other outcome fails the test.
pub fn parameter_message<T>(result: Result<T>) -> String {
    match result {
        Err(GraphError::Parameter { message, .. }) => message,
        Err(other) => panic!("not a parameter error: {other}"),
        Ok(_) => panic!("accepted: a {}", std::any::type_name::<T>()),
    }
}

/// Checks a pass's params as `parse` reads them (from a pipeline file, or `from_params`):
/// each of `accepted` parses, and each `(text, key)` of `refused` is a parameter error
/// whose message names `key`.
pub fn assert_params<T>(
    parse: impl Fn(&str) -> Result<T>,
    accepted: &[&str],
    refused: &[(&str, &str)],
) {
    for text in accepted {
        if let Err(e) = parse(text) {
            panic!("`{text}` was refused: {e}");
        }
    }
    for (text, key) in refused {
        let message = parameter_message(parse(text));
        assert!(message.contains(key), "`{text}`: {message}");
    }
}

/// What test buffers are made with: bound as storage, filled, read back, and usable as
/// indirect arguments, so one constant serves every pass's buffers.
pub const USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_DST)
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::INDIRECT);

/// The project's seeded generator, for tests' random inputs.
pub use meshlight_shaders::cpu::rng::Rng;

/// The test meshes shipped in `assets/meshes`, baked with the default options once per
/// test binary.
#[cfg(feature = "meshes")]
pub mod meshes {
    use meshlight_scene::{BuildOptions, MeshletAsset, build_asset};
    use std::collections::HashMap;
    use std::sync::{Mutex, OnceLock};

    /// `assets/meshes/{file}` baked with [`BuildOptions::default`]; later calls return
    /// the same asset.
    pub fn baked(file: &'static str) -> &'static MeshletAsset {
        static BAKED: OnceLock<Mutex<HashMap<&'static str, &'static MeshletAsset>>> =
            OnceLock::new();
        let mut baked = BAKED.get_or_init(Default::default).lock().unwrap();
        baked.entry(file).or_insert_with(|| {
            let path = format!("{}/../assets/meshes/{file}", env!("CARGO_MANIFEST_DIR"));
            let mesh = meshlight_scene::load::load_mesh(std::path::Path::new(&path))
                .unwrap_or_else(|e| panic!("{path}: {e}"));
            let built = build_asset(&mesh, &BuildOptions::default(), &mut |_| {})
                .unwrap_or_else(|e| panic!("{path}: {e}"));
            Box::leak(Box::new(built.asset))
        })
    }

    /// The Stanford bunny.
    pub fn bunny() -> &'static MeshletAsset {
        baked("stanford-bunny.obj")
    }

    /// Keenan Crane's spot.
    pub fn spot() -> &'static MeshletAsset {
        baked("spot.obj")
    }
}

/// Writes every level of a CPU-built depth pyramid into the mips of `texture` (R32Float,
/// at least as large as level 0), so a pass can be tested against a known pyramid.
pub fn write_pyramid(
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    pyramid: &meshlight_shaders::cpu::occlusion::DepthPyramid,
) {
    for (level, (w, h, texels)) in pyramid.levels.iter().enumerate() {
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: level as u32,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(texels),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(w * 4),
                rows_per_image: Some(*h),
            },
            wgpu::Extent3d {
                width: *w,
                height: *h,
                depth_or_array_layers: 1,
            },
        );
    }
}
