//! `depth_pyramid` on the GPU (lavapipe in CI) against the CPU pyramid
//! (`meshlight_shaders::cpu::occlusion::DepthPyramid::from_visibility`), exactly: odd, even
//! and one-pixel sizes, one tile and many, both implementations, frames in a row with
//! different depths (so a counter left unreset or a level left stale shows), random
//! depths with empty pixels; the texture form where the adapter has 64-bit texture
//! atomics; and a pyramid texture not declared with `texture_desc`.

use meshlight_graph::*;
use meshlight_pass_depth_pyramid::{DepthPyramid, Method, pyramid_extent, texture_desc};
use meshlight_shaders::cpu::occlusion;

mod common;
use common::{
    BUFFER_USAGE, PYRAMID_USAGE, VISIBILITY_TEXTURE_USAGE, Visibility, add_pyramid_pass,
    import_visibility,
};

use meshlight_testing::{gpu, texture};

/// What a frame's visibility target holds.
#[derive(Clone, Copy, Debug)]
enum Depths {
    /// Uniform depths in (0, 1) with about one pixel in eight empty (0).
    WithEmpty(u64),
    /// Depths in [0.5, 1), nothing empty: every level differs from a frame with empty
    /// pixels, the top one included.
    Near(u64),
}

fn visibility(w: u32, h: u32, depths: Depths) -> Vec<u64> {
    let (seed, near) = match depths {
        Depths::WithEmpty(s) => (s, false),
        Depths::Near(s) => (s, true),
    };
    let mut s = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    (0..w as u64 * h as u64)
        .map(|i| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            // 24 random bits: k / 2^24 is an exact, normal f32 for k ≥ 1.
            let k = (s >> 40) as u32;
            let depth = if near {
                0.5 + (k >> 1) as f32 / (1u32 << 24) as f32
            } else if s % 8 == 0 {
                0.0
            } else {
                k.max(1) as f32 / (1u32 << 24) as f32
            };
            (depth.to_bits() as u64) << 32 | (i as u32 & 0xffff_ff7f) as u64
        })
        .collect()
}

/// How the visibility target is held and whether a persistent counter is bound.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Form {
    texture: bool,
    counter: bool,
}

const BUFFER: Form = Form {
    texture: false,
    counter: false,
};

/// The visibility target the test writes each frame.
enum Source {
    Buffer(wgpu::Buffer),
    Texture(wgpu::Texture),
}

/// Every level of the pyramid after each frame, and the `counter` buffer at the end.
struct Frames {
    levels: Vec<Vec<Vec<f32>>>,
    counter: Option<u32>,
}

/// Runs `pass` once per entry of `frames`, the visibility target rewritten before each,
/// and reads every level back after each.
fn run(pass: DepthPyramid, form: Form, frames: &[Vec<u64>]) -> Result<Frames> {
    let (w, h) = (pass.width, pass.height);
    let gpu = gpu();
    let mut g = GraphBuilder::new();
    let visibility = if form.texture {
        Visibility::Texture
    } else {
        Visibility::Buffer(u64::from(w) * u64::from(h))
    };
    let desc = texture_desc(w, h);
    add_pyramid_pass(&mut g, pass, visibility, desc.clone(), form.counter)?;
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu))?;

    let source = if form.texture {
        Source::Texture(texture(
            &gpu,
            "visibility",
            &TextureDesc::d2(wgpu::TextureFormat::R64Uint, w, h),
            VISIBILITY_TEXTURE_USAGE,
        ))
    } else {
        Source::Buffer(gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("visibility"),
            size: w as u64 * h as u64 * 8,
            usage: BUFFER_USAGE,
            mapped_at_creation: false,
        }))
    };
    let pyramid_texture = texture(&gpu, "pyramid", &desc, PYRAMID_USAGE);
    let counter = gpu.buffer_with_data("counter", &[0; 4], BUFFER_USAGE);
    let mut imports = Imports::new().texture("pyramid", &pyramid_texture);
    imports = match &source {
        Source::Texture(t) => imports.texture("visibility", t),
        Source::Buffer(b) => imports.buffer("visibility", b),
    };
    if form.counter {
        imports = imports.buffer("counter", &counter);
    }
    let mut exec = Executor::new(gpu);
    let mut levels = Vec::new();
    for values in frames {
        let bytes: &[u8] = bytemuck::cast_slice(values);
        match &source {
            Source::Texture(t) => exec.queue().write_texture(
                t.as_image_copy(),
                bytes,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(w * 8),
                    rows_per_image: Some(h),
                },
                t.size(),
            ),
            Source::Buffer(b) => exec.queue().write_buffer(b, 0, bytes),
        }
        exec.execute(&compiled, &imports)?;
        exec.finish()?;
        levels.push(read_levels(&exec.gpu, &pyramid_texture, w, h)?);
    }
    let counter = if form.counter {
        let bytes = exec.gpu.read_buffer(&counter, 0, 4)?;
        Some(u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]))
    } else {
        None
    };
    Ok(Frames { levels, counter })
}

/// Every level of the pyramid of a `w × h` source, each `level_size` of it, row-major.
fn read_levels(gpu: &GpuContext, texture: &wgpu::Texture, w: u32, h: u32) -> Result<Vec<Vec<f32>>> {
    let extent = pyramid_extent(w, h);
    let row = |lw: u32| (lw * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) as u64;
    let mut offsets = Vec::new();
    let mut size = 0;
    for l in 0..extent.mip_levels {
        let [lw, lh] = extent.level_size(l);
        offsets.push(size);
        size += row(lw) * lh as u64;
    }
    let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("pyramid readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    for l in 0..extent.mip_levels {
        let [lw, lh] = extent.level_size(l);
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: l,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &staging,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: offsets[l as usize],
                    bytes_per_row: Some(row(lw) as u32),
                    rows_per_image: Some(lh),
                },
            },
            wgpu::Extent3d {
                width: lw,
                height: lh,
                depth_or_array_layers: 1,
            },
        );
    }
    gpu.queue.submit([encoder.finish()]);
    let bytes = gpu.map_and_read(&staging)?;
    Ok((0..extent.mip_levels)
        .map(|l| {
            let [lw, lh] = extent.level_size(l);
            (0..lh)
                .flat_map(|y| {
                    let start = (offsets[l as usize] + y as u64 * row(lw)) as usize;
                    bytemuck::pod_collect_to_vec::<u8, f32>(&bytes[start..start + lw as usize * 4])
                })
                .collect()
        })
        .collect())
}

/// Panics at the first texel whose bits differ from the reference's.
fn assert_levels_equal(got: &[Vec<f32>], want: &occlusion::DepthPyramid, what: &str) {
    assert_eq!(got.len(), want.levels.len(), "{what}: level count");
    for (l, (g, (lw, _, w))) in got.iter().zip(&want.levels).enumerate() {
        let lw = *lw;
        if let Some(i) = g
            .iter()
            .zip(w)
            .position(|(a, b)| a.to_bits() != b.to_bits())
        {
            panic!(
                "{what}: level {l} texel ({}, {}) is {}, the reference {}",
                i as u32 % lw,
                i as u32 / lw,
                g[i],
                w[i]
            );
        }
    }
}

/// Two frames (empty pixels, then none) of `method` at `w × h` in `form`, each equal to
/// the reference.
fn check(method: Method, w: u32, h: u32, form: Form) -> Frames {
    let frames = [
        visibility(w, h, Depths::WithEmpty(w as u64 * 31 + h as u64)),
        visibility(w, h, Depths::Near(w as u64 + 7 * h as u64)),
    ];
    let got = run(DepthPyramid::new(w, h, method), form, &frames).unwrap_or_else(|e| panic!("{e}"));
    for (i, (values, levels)) in frames.iter().zip(&got.levels).enumerate() {
        let want = occlusion::DepthPyramid::from_visibility(values, w, h);
        assert_levels_equal(
            levels,
            &want,
            &format!("{method:?} {w}×{h} {form:?} frame {i}"),
        );
    }
    // The frames' top levels differ, so a level the second frame failed to write shows.
    let top = |levels: &Vec<Vec<f32>>| levels.last().unwrap()[0];
    assert_ne!(top(&got.levels[0]), top(&got.levels[1]), "{w}×{h}");
    got
}

/// The first nine sizes fit the top step's smallest block (32 × 32 tiles, 4096 pixels a
/// side); the last four take its 64- and 128-tile blocks, in each direction, and the
/// largest size there is.
const SIZES: [(u32, u32); 13] = [
    (1, 1),
    (3, 5),
    (37, 23),
    (64, 64),
    (65, 33),
    (129, 1),
    (1, 300),
    (280, 158),
    (300, 260),
    (4160, 130),
    (8300, 2),
    (3, 9000),
    (16384, 1),
];

#[test]
fn single_pass_matches_the_reference_at_every_size_frame_after_frame() {
    for (w, h) in SIZES {
        check(Method::SinglePass, w, h, BUFFER);
    }
}

#[test]
fn two_pass_matches_the_reference_at_every_size_frame_after_frame() {
    for (w, h) in SIZES {
        check(Method::TwoPass, w, h, BUFFER);
    }
}

#[test]
fn both_match_the_reference_at_2240_by_1260() {
    check(Method::SinglePass, 2240, 1260, BUFFER);
    check(Method::TwoPass, 2240, 1260, BUFFER);
}

#[test]
fn a_persistent_counter_is_left_at_zero_and_needs_no_clear() {
    // Three frames on one imported counter: the second and third only complete their
    // top levels if the last workgroup of the one before set it back to 0.
    let form = Form {
        texture: false,
        counter: true,
    };
    for (w, h) in [(280, 158), (129, 1), (37, 23)] {
        let frames = [
            visibility(w, h, Depths::WithEmpty(1)),
            visibility(w, h, Depths::Near(2)),
            visibility(w, h, Depths::WithEmpty(3)),
        ];
        let got =
            run(DepthPyramid::single_pass(w, h), form, &frames).unwrap_or_else(|e| panic!("{e}"));
        for (i, (values, levels)) in frames.iter().zip(&got.levels).enumerate() {
            assert_levels_equal(
                levels,
                &occlusion::DepthPyramid::from_visibility(values, w, h),
                &format!("{w}×{h} frame {i}"),
            );
        }
        assert_eq!(got.counter, Some(0), "{w}×{h}");
    }
}

#[test]
fn the_texture_form_matches_the_reference_where_the_adapter_has_it() {
    let needed = wgpu::Features::SHADER_INT64 | wgpu::Features::TEXTURE_INT64_ATOMIC;
    let form = Form {
        texture: true,
        counter: false,
    };
    if gpu().features.contains(needed) {
        for method in [Method::SinglePass, Method::TwoPass] {
            for (w, h) in [(37, 23), (280, 158)] {
                check(method, w, h, form);
            }
        }
    } else {
        // lavapipe: the texture form is refused at compile, naming the missing feature
        // (pyramid.wgsl's texture variant is validated in tests/shaders.rs).
        let frames = [visibility(37, 23, Depths::WithEmpty(1))];
        match run(DepthPyramid::single_pass(37, 23), form, &frames) {
            Err(GraphError::MissingFeature { features, .. }) => {
                assert!(features.contains("TEXTURE_INT64_ATOMIC"), "{features}")
            }
            Err(other) => panic!("{other}"),
            Ok(_) => panic!("ran the texture form without TEXTURE_INT64_ATOMIC"),
        }
    }
}

#[test]
fn a_pyramid_not_declared_with_texture_desc_is_an_error_naming_it() {
    let (w, h) = (37, 23);
    let gpu = gpu();
    let mut g = GraphBuilder::new();
    let vis = import_visibility(&mut g, w, h);
    // A full chain of the level-0 size: its rounded-down mips are too small.
    let naive = TextureDesc::d2(wgpu::TextureFormat::R32Float, 19, 12).with_full_mips();
    let pyramid = g.import_texture("pyramid", naive.clone(), PYRAMID_USAGE);
    g.add_pass(
        "pyramid",
        DepthPyramid::single_pass(w, h),
        Bindings::new()
            .bind("visibility", vis)
            .bind("pyramid", pyramid),
    )
    .unwrap();
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let vis_buffer =
        gpu.buffer_with_data("visibility", &vec![0; (w * h * 8) as usize], BUFFER_USAGE);
    let texture = texture(&gpu, "pyramid", &naive, PYRAMID_USAGE);
    let imports = Imports::new()
        .buffer("visibility", &vis_buffer)
        .texture("pyramid", &texture);
    let mut exec = Executor::new(gpu);
    let e = exec.execute(&compiled, &imports).unwrap_err().to_string();
    assert!(
        e.contains("texture_desc(37, 23)") && e.contains("`pyramid`"),
        "{e}"
    );
}

#[test]
fn a_history_pyramid_is_right_in_both_textures_it_alternates_between() {
    // A history resource is written into one texture one frame and the other the next,
    // so the pass's per-level views must follow the bound texture.
    let (w, h) = (280, 158);
    for method in [Method::SinglePass, Method::TwoPass] {
        let gpu = gpu();
        let mut g = GraphBuilder::new();
        let vis = import_visibility(&mut g, w, h);
        let pyramid = g.history_texture("pyramid", texture_desc(w, h));
        g.add_pass(
            "pyramid",
            DepthPyramid::new(w, h, method),
            Bindings::new()
                .bind("visibility", vis)
                .bind("pyramid", pyramid.current),
        )
        .unwrap();
        let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
        let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("visibility"),
            size: (w * h * 8) as u64,
            usage: BUFFER_USAGE,
            mapped_at_creation: false,
        });
        let imports = Imports::new().buffer("visibility", &buffer);
        let mut exec = Executor::new(gpu);
        let padded_width = texture_desc(w, h).width as usize;
        for frame in 0..4 {
            let values = if frame % 2 == 0 {
                visibility(w, h, Depths::WithEmpty(frame))
            } else {
                visibility(w, h, Depths::Near(frame))
            };
            exec.queue()
                .write_buffer(&buffer, 0, bytemuck::cast_slice(&values));
            exec.execute(&compiled, &imports)
                .unwrap_or_else(|e| panic!("{e}"));
            exec.finish().unwrap();
            let bytes = exec.read_texture("pyramid").unwrap();
            let texels: Vec<f32> = bytemuck::pod_collect_to_vec(&bytes);
            let want = occlusion::DepthPyramid::from_visibility(&values, w, h);
            let [lw, lh] = want.level_size(0);
            let level0: Vec<f32> = (0..lh as usize)
                .flat_map(|y| texels[y * padded_width..y * padded_width + lw as usize].to_vec())
                .collect();
            let want0 = occlusion::DepthPyramid {
                levels: vec![want.levels[0].clone()],
            };
            assert_levels_equal(&[level0], &want0, &format!("{method:?} frame {frame}"));
        }
    }
}

#[test]
fn random_sizes_match_the_reference() {
    use proptest::prelude::*;
    use proptest::test_runner::{Config, TestRunner};
    // Sides across tile boundaries (128) and up to three tiles, odd and even.
    let strategy = (1u32..400, 1u32..400, any::<bool>(), any::<u64>());
    let mut runner = TestRunner::new(Config {
        cases: 12,
        failure_persistence: None,
        ..Config::default()
    });
    runner
        .run(&strategy, |(w, h, single, seed)| {
            let method = if single {
                Method::SinglePass
            } else {
                Method::TwoPass
            };
            let frames = [visibility(w, h, Depths::WithEmpty(seed))];
            let got = run(DepthPyramid::new(w, h, method), BUFFER, &frames)
                .map_err(|e| TestCaseError::fail(e.to_string()))?;
            let want = occlusion::DepthPyramid::from_visibility(&frames[0], w, h);
            for (l, (g, (_, _, r))) in got.levels[0].iter().zip(&want.levels).enumerate() {
                let same = g.iter().zip(r).all(|(a, b)| a.to_bits() == b.to_bits());
                prop_assert!(same, "{method:?} {w}×{h} seed {seed}: level {l} differs");
            }
            Ok(())
        })
        .unwrap_or_else(|e| panic!("{e}"));
}
