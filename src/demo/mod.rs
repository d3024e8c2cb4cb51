//! The built-in default-scene renderer: a compute rasteriser writing a 64-bit visibility
//! buffer, then a shading pass into an RGBA8 image. It draws the procedural mesh until the
//! virtual-geometry passes take over, and it is real GPU work through the frame graph.

pub mod cpu;

use glam::{Mat4, Vec3};
use meshlight_graph::*;

pub const RASTER_SHADER: PassShader = PassShader {
    name: "demo::raster",
    source: include_str!("raster.wgsl"),
    file_path: "src/demo/raster.wgsl",
};
pub const SHADE_SHADER: PassShader = PassShader {
    name: "demo::shade",
    source: include_str!("shade.wgsl"),
    file_path: "src/demo/shade.wgsl",
};

/// Visibility values: `(1 - depth) << 32 | triangle + 1`, zero where nothing was drawn.
pub fn visbuffer_element() -> Element {
    Element::U64
}

const WORKGROUP: u32 = 64;

/// A 2-D dispatch covering `threads` under the per-dimension limit.
fn dispatch_size(threads: u32) -> (u32, u32, u32) {
    let groups = threads.div_ceil(WORKGROUP).max(1);
    let x = groups.min(65_535);
    (x, groups.div_ceil(x), x * WORKGROUP)
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct RasterParams {
    view_proj: [f32; 16],
    width: u32,
    height: u32,
    triangle_count: u32,
    threads_per_row: u32,
}

/// The frame input holding the view-projection matrix (16 f32, column-major): the camera
/// changes every frame without the graph being rebuilt.
pub const VIEW_INPUT: &str = "view";

/// The frame inputs of the default-scene graph for a camera.
pub fn frame_data(view_proj: Mat4) -> FrameData {
    FrameData::new().with(VIEW_INPUT, bytemuck::bytes_of(&view_proj.to_cols_array()))
}

/// Stage `demo_raster`: triangles → visibility buffer, seen through the frame's view.
pub struct DemoRaster {
    pub width: u32,
    pub height: u32,
    pub triangle_count: u32,
}

pub fn raster_contract() -> StageContract {
    StageContract {
        stage: "demo_raster",
        slots: vec![
            Slot::buffer(
                "positions",
                Access::StorageRead,
                Element::VEC4_F32,
                "world-space vertex positions (w = 1)",
            ),
            Slot::buffer(
                "indices",
                Access::StorageRead,
                Element::U32,
                "three indices per triangle",
            ),
            Slot::buffer(
                "visbuffer",
                Access::ClearedReadWrite,
                visbuffer_element(),
                "one 64-bit visibility value per pixel; cleared by the pass, then atomicMax",
            ),
        ],
    }
}

impl Pass for DemoRaster {
    fn contract(&self) -> StageContract {
        raster_contract()
    }
    fn implementation(&self) -> &'static str {
        "compute"
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        ctx.require_features(
            wgpu::Features::SHADER_INT64 | wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX,
        );
        ctx.min_bytes("visbuffer", self.width as u64 * self.height as u64 * 8);
        ctx.min_bytes("indices", self.triangle_count as u64 * 12);
        ctx.frame_input(VIEW_INPUT);
        let layout = BindingLayout::compute("demo_raster")
            .slot(0, "positions")
            .slot(1, "indices")
            .slot(2, "visbuffer")
            .uniform(3);
        for entry in ["clear", "raster"] {
            ctx.program(
                entry,
                ProgramDesc::compute(&RASTER_SHADER, entry).layout(layout.clone()),
            );
        }
        let (cx, cy, _) = dispatch_size(self.width * self.height);
        let (rx, ry, _) = dispatch_size(self.triangle_count);
        ctx.dispatch("clear", [cx, cy, 1]);
        ctx.dispatch("raster", [rx, ry, 1]);
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let clear = ctx.compute("clear")?;
        let raster = ctx.compute("raster")?;
        let (cx, cy, c_row) = dispatch_size(self.width * self.height);
        let (rx, ry, r_row) = dispatch_size(self.triangle_count);
        let view: [f32; 16] = ctx
            .frame_bytes(VIEW_INPUT)?
            .get(..64)
            .map(bytemuck::pod_read_unaligned)
            .ok_or_else(|| GraphError::Record {
                pass: ctx.pass_name().to_string(),
                message: format!("frame input `{VIEW_INPUT}` must hold 16 f32 (64 bytes)"),
            })?;
        let params = |threads_per_row| RasterParams {
            view_proj: view,
            width: self.width,
            height: self.height,
            triangle_count: self.triangle_count,
            threads_per_row,
        };
        let clear_bg = ctx.bind_group(&clear, 0, &[(3, bytemuck::bytes_of(&params(c_row)))])?;
        let raster_bg = ctx.bind_group(&raster, 0, &[(3, bytemuck::bytes_of(&params(r_row)))])?;
        let mut pass = ctx.compute_pass();
        pass.set_pipeline(&clear.pipeline);
        pass.set_bind_group(0, &clear_bg, &[]);
        pass.dispatch_workgroups(cx, cy, 1);
        pass.set_pipeline(&raster.pipeline);
        pass.set_bind_group(0, &raster_bg, &[]);
        pass.dispatch_workgroups(rx, ry, 1);
        Ok(())
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ShadeParams {
    light_dir: [f32; 4],
    width: u32,
    height: u32,
    threads_per_row: u32,
    _pad: u32,
}

/// Stage `demo_shade`: visibility buffer → RGBA8 image.
pub struct DemoShade {
    pub width: u32,
    pub height: u32,
    pub light_dir: Vec3,
}

pub fn shade_contract() -> StageContract {
    StageContract {
        stage: "demo_shade",
        slots: vec![
            Slot::buffer(
                "positions",
                Access::StorageRead,
                Element::VEC4_F32,
                "world-space vertex positions",
            ),
            Slot::buffer(
                "indices",
                Access::StorageRead,
                Element::U32,
                "three indices per triangle",
            ),
            Slot::buffer(
                "visbuffer",
                Access::StorageRead,
                visbuffer_element(),
                "visibility from the raster pass",
            ),
            Slot::buffer(
                "image",
                Access::StorageWrite,
                Element::U32,
                "RGBA8 pixels, row-major",
            ),
        ],
    }
}

impl Pass for DemoShade {
    fn contract(&self) -> StageContract {
        shade_contract()
    }
    fn implementation(&self) -> &'static str {
        "compute"
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        ctx.min_bytes("image", self.width as u64 * self.height as u64 * 4);
        let layout = BindingLayout::compute("demo_shade")
            .slot(0, "positions")
            .slot(1, "indices")
            .slot(2, "visbuffer")
            .slot(3, "image")
            .uniform(4);
        ctx.program(
            "shade",
            ProgramDesc::compute(&SHADE_SHADER, "shade").layout(layout),
        );
        let (x, y, _) = dispatch_size(self.width * self.height);
        ctx.dispatch("shade", [x, y, 1]);
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let program = ctx.compute("shade")?;
        let (x, y, row) = dispatch_size(self.width * self.height);
        let params = ShadeParams {
            light_dir: self.light_dir.extend(0.0).to_array(),
            width: self.width,
            height: self.height,
            threads_per_row: row,
            _pad: 0,
        };
        let bg = ctx.bind_group(&program, 0, &[(4, bytemuck::bytes_of(&params))])?;
        let mut pass = ctx.compute_pass();
        pass.set_pipeline(&program.pipeline);
        pass.set_bind_group(0, &bg, &[]);
        pass.dispatch_workgroups(x, y, 1);
        Ok(())
    }
}

/// A camera looking at the mesh's bounding sphere from above and to the side.
pub fn camera_for(positions: &[Vec3], width: u32, height: u32) -> Mat4 {
    let (min, max) = positions.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let center = (min + max) * 0.5;
    let radius = ((max - min).length() * 0.5).max(1e-6);
    let eye = center + Vec3::new(0.45, 0.55, 1.0).normalize() * radius * 2.6;
    let proj = glam::camera::rh::proj::directx::perspective(
        40f32.to_radians(),
        width as f32 / height as f32,
        radius * 0.5,
        radius * 6.0,
    );
    proj * glam::camera::rh::view::look_at_mat4(eye, center, Vec3::Y)
}

pub const LIGHT_DIR: Vec3 = Vec3::new(0.4, 0.8, 0.5);

/// The default-scene graph: positions and indices imported, visibility transient, image
/// imported; the camera comes with each frame ([`frame_data`]).
pub fn graph(
    positions_bytes: u64,
    triangles: u32,
    width: u32,
    height: u32,
) -> Result<GraphBuilder> {
    let mut g = GraphBuilder::new();
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    g.import_buffer(
        "positions",
        BufferDesc::bytes(Element::VEC4_F32, positions_bytes),
        usage,
    );
    g.import_buffer(
        "indices",
        BufferDesc::array(Element::U32, triangles as u64 * 3),
        usage,
    );
    g.create_buffer(
        "visbuffer",
        BufferDesc::array(visbuffer_element(), width as u64 * height as u64),
    );
    g.import_buffer(
        "image",
        BufferDesc::array(Element::U32, width as u64 * height as u64),
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    );
    g.add_pass(
        "raster",
        DemoRaster {
            width,
            height,
            triangle_count: triangles,
        },
        Bindings::new(),
    )?;
    g.add_pass(
        "shade",
        DemoShade {
            width,
            height,
            light_dir: LIGHT_DIR,
        },
        Bindings::new(),
    )?;
    Ok(g)
}

/// Result of rendering a mesh: RGBA8 pixels and the frame's statistics.
pub struct Rendered {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    pub stats: FrameStats,
    pub adapter: String,
    pub plan: Plan,
}

pub fn render(positions: &[Vec3], indices: &[u32], width: u32, height: u32) -> Result<Rendered> {
    let adapter = GpuAdapter::select()?;
    let view_proj = camera_for(positions, width, height);
    let padded: Vec<[f32; 4]> = positions.iter().map(|p| [p.x, p.y, p.z, 1.0]).collect();
    let triangles = (indices.len() / 3) as u32;
    let compiled = graph(padded.len() as u64 * 16, triangles, width, height)?
        .compile(&CompileOptions::for_adapter(&adapter))?;
    let gpu = adapter.open(compiled.plan.enabled_features)?;
    let name = gpu.info.name.clone();
    let usage = wgpu::BufferUsages::STORAGE;
    let pos = gpu.buffer_with_data("positions", bytemuck::cast_slice(&padded), usage);
    let idx = gpu.buffer_with_data("indices", bytemuck::cast_slice(indices), usage);
    let image = gpu.buffer_with_data(
        "image",
        &[],
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    );
    let image = if image.size() < width as u64 * height as u64 * 4 {
        gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("image"),
            size: width as u64 * height as u64 * 4,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        })
    } else {
        image
    };
    let mut exec = Executor::new(gpu);
    let imports = Imports::new()
        .buffer("positions", &pos)
        .buffer("indices", &idx)
        .buffer("image", &image);
    exec.execute_frame(&compiled, &imports, &frame_data(view_proj))?;
    let stats = exec
        .finish()?
        .expect("a frame was executed, so its statistics exist");
    let rgba = exec
        .gpu
        .read_buffer(&image, 0, width as u64 * height as u64 * 4)?;
    Ok(Rendered {
        width,
        height,
        rgba,
        stats,
        adapter: name,
        plan: compiled.plan,
    })
}
