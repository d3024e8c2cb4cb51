//! The shared WGSL meshlet decoder against the asset's CPU decoder, on every meshlet of
//! a real mesh with UVs and of the procedural mesh (also on a 24-bit grid): grid offsets
//! exactly, read through one window of words as the passes read them and field by
//! field; positions, normals and UVs to float rounding; triangles exactly. Also the
//! record layouts WGSL sees.

use meshlight_gpu_scene::gpu::elements;
use meshlight_gpu_scene::{GpuScene, SceneData, data::Limits, names};
use meshlight_graph::*;
use meshlight_scene::asset::format::{GroupRecord, MeshletRecord};
use meshlight_scene::{BuildOptions, MeshletAsset, build_asset};
use meshlight_shaders::pass_shader;
use std::mem::size_of;

const DECODE: PassShader = pass_shader!("test::decode", "decode.wgsl");

struct Decode {
    meshlets: u32,
}

impl Pass for Decode {
    fn implementation(&self) -> Implementation {
        Implementation::new(
            "test",
            StageContract {
                stage: "decode",
                slots: vec![
                    Slot::buffer("meshlets", Access::StorageRead, elements::MESHLET, ""),
                    Slot::buffer("payload", Access::StorageRead, Element::U32, ""),
                    Slot::buffer("meshes", Access::StorageRead, elements::MESH, ""),
                    Slot::buffer("vertices", Access::StorageWrite, Element::VEC4_F32, ""),
                    Slot::buffer("triangles", Access::StorageWrite, Element::VEC4_F32, ""),
                    Slot::buffer("mismatched", Access::ClearedReadWrite, Element::U32, ""),
                ],
            },
        )
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        let layout = BindingLayout::compute("decode")
            .slot(0, "meshlets")
            .slot(1, "payload")
            .slot(2, "meshes")
            .slot(3, "vertices")
            .slot(4, "triangles")
            .slot(5, "mismatched");
        ctx.program(
            "decode",
            ProgramDesc::compute(&DECODE, "decode").layout(layout),
        );
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        ctx.clear("mismatched")?;
        let grid = [self.meshlets.min(65_535), self.meshlets.div_ceil(65_535), 1];
        ctx.dispatch_compute("decode", &[], Workgroups::Direct(grid))
    }
}

use meshlight_testing::gpu;

fn check(asset: &MeshletAsset) {
    let gpu = gpu();
    let mut data = SceneData::new(Limits::default());
    data.add_mesh("test", asset).unwrap();
    let scene = GpuScene::new(&gpu, &mut data);
    let n = asset.meshlets().len() as u32;
    let mut g = GraphBuilder::new();
    scene.import(&mut g);
    let vertices = g.create_buffer(
        "vertices",
        BufferDesc::array(Element::VEC4_F32, n as u64 * 255 * 3),
    );
    let triangles = g.create_buffer(
        "triangles",
        BufferDesc::array(Element::VEC4_F32, n as u64 * 128),
    );
    let mismatched = g.create_buffer(
        "mismatched",
        BufferDesc::array(Element::U32, n as u64 * 255),
    );
    let out = g
        .add_pass(
            "decode",
            Decode { meshlets: n },
            Bindings::new()
                .bind("vertices", vertices)
                .bind("triangles", triangles)
                .bind("mismatched", mismatched),
        )
        .unwrap();
    g.export(out.buffer("vertices").unwrap());
    g.export(out.buffer("mismatched").unwrap());
    g.export(out.buffer("triangles").unwrap());
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let mut exec = Executor::new(gpu);
    exec.execute(&compiled, &scene.imports()).unwrap();
    let v: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&exec.read_buffer("vertices").unwrap());
    let t: Vec<[u32; 4]> = bytemuck::pod_collect_to_vec(&exec.read_buffer("triangles").unwrap());
    let mismatched: Vec<u32> =
        bytemuck::pod_collect_to_vec(&exec.read_buffer("mismatched").unwrap());
    let differing = mismatched.iter().filter(|&&m| m != 0).count();
    assert_eq!(
        differing, 0,
        "{differing} vertices read differently through one window and field by field"
    );
    let has_uvs = asset.header().has_uvs();
    for i in 0..n as usize {
        let d = asset.decode_meshlet(i);
        for (k, q) in d.grid.iter().enumerate() {
            let at = (i * 255 + k) * 3;
            let [p, nrm, offsets] = [v[at], v[at + 1], v[at + 2]];
            // The grid offsets are exact.
            for axis in 0..3 {
                let got = offsets[axis].to_bits() + asset.meshlets()[i].grid_min[axis];
                assert_eq!(got, q[axis], "meshlet {i} vertex {k} axis {axis}");
                let want = d.positions[k][axis];
                assert!(
                    (p[axis] - want).abs() <= want.abs() * 2e-7 + 1e-7,
                    "meshlet {i} vertex {k}: {p:?} vs {:?}",
                    d.positions[k]
                );
            }
            let want = d.normals[k];
            let err = (nrm[0] - want.x).abs() + (nrm[1] - want.y).abs() + (nrm[2] - want.z).abs();
            assert!(
                err < 1e-5,
                "meshlet {i} vertex {k}: normal {nrm:?} vs {want:?}"
            );
            if has_uvs {
                let uv = d.uvs[k];
                assert!(
                    (p[3] - uv[0]).abs() < 1e-6 && (nrm[3] - uv[1]).abs() < 1e-6,
                    "uv of meshlet {i} vertex {k}"
                );
            }
        }
        for (k, tri) in d.triangles.iter().enumerate() {
            let got = t[i * 128 + k];
            assert_eq!(got[3], 1, "meshlet {i} triangle {k} not decoded");
            assert_eq!(
                [got[0], got[1], got[2]],
                tri.map(u32::from),
                "meshlet {i} triangle {k}"
            );
        }
    }
}

#[test]
fn gpu_decoding_equals_the_asset_decoder_on_the_procedural_mesh() {
    let mesh = meshlight_scene::procedural_mesh(12);
    let built = build_asset(&mesh, &BuildOptions::default(), &mut |_| {}).unwrap();
    check(&built.asset);
}

#[test]
fn gpu_decoding_equals_the_asset_decoder_on_a_mesh_with_uvs() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/meshes/spot.obj");
    let mesh = meshlight_scene::load::load_mesh(std::path::Path::new(path)).unwrap();
    let built = build_asset(&mesh, &BuildOptions::default(), &mut |_| {}).unwrap();
    assert!(
        built.asset.header().has_uvs(),
        "spot.obj has texture coordinates"
    );
    check(&built.asset);
}

/// A 24-bit position grid, the widest the builder makes: the meshlets' grid offsets
/// take up to 72 bits, so a vertex's third offset starts past the window's second word
/// (the last select of `meshlet_grid_offsets`).
#[test]
fn gpu_decoding_equals_the_asset_decoder_with_24_bit_positions() {
    let mesh = meshlight_scene::procedural_mesh(12);
    let options = BuildOptions {
        position_bits: meshlight_scene::compress::PositionBits::Fixed(24),
        ..BuildOptions::default()
    };
    let built = build_asset(&mesh, &options, &mut |_| {}).unwrap();
    // Some vertex's z offset starts at bit 64 or later of its window: its record starts
    // at `vertex * stride % 32`, and x and y take a.x + a.y bits before it.
    let reaches_third_word = built.asset.meshlets().iter().any(|m| {
        let [x, y, _] = m.axis_bits();
        let stride = m.vertex_stride();
        let vertices = m.counts & 0xff;
        (0..vertices).any(|v| (v * stride) % 32 + x + y >= 64)
    });
    assert!(
        reaches_third_word,
        "no grid offset starts in the window's third word"
    );
    check(&built.asset);
}

#[test]
fn records_have_the_sizes_the_wgsl_strides_assume() {
    // `array<Meshlet>` has a 52-byte stride in WGSL (scalars and arrays of 4-byte
    // elements only); `MeshletGroup` starts with a vec4 and is 32 bytes.
    assert_eq!(size_of::<MeshletRecord>(), 52);
    assert_eq!(size_of::<GroupRecord>(), 32);
    let mut library =
        meshlight_shaders::ShaderLibrary::new(meshlight_shaders::Capabilities::all()).unwrap();
    let module = library
        .compose(&DECODE, &[])
        .unwrap_or_else(|e| panic!("{e}"));
    let stride = module
        .types
        .iter()
        .find_map(|(_, ty)| match ty.inner {
            naga::TypeInner::Array { base, stride, .. }
                if module.types[base]
                    .name
                    .as_deref()
                    .is_some_and(|n| n.starts_with("Meshlet")) =>
            {
                Some(stride)
            }
            _ => None,
        })
        .expect("array<Meshlet> in the module");
    assert_eq!(stride, 52);
    let _ = names::MESHLETS;
}
