//! `present` on the GPU (lavapipe in CI) against its reference: an image drawn into
//! targets of other formats keeps its bytes (channel order following the format, sRGB
//! targets within one step of rounding), and a target nothing can draw colour into is
//! refused at compile, naming the format.

use meshlight_graph::*;
use meshlight_pass_present::{COLOR_FORMAT, Present, cpu};
use meshlight_testing::{gpu, read_texture, texture};

const W: u32 = 37;
const H: u32 = 11;

/// An image with every byte value in each channel somewhere.
fn image() -> Vec<u8> {
    (0..W * H)
        .flat_map(|i| {
            let i = i as u8;
            [i, i.wrapping_mul(7), 255 - i, i.wrapping_add(91)]
        })
        .collect()
}

fn graph(format: wgpu::TextureFormat) -> GraphBuilder {
    let mut g = GraphBuilder::new();
    g.import_texture(
        "color",
        TextureDesc::d2(COLOR_FORMAT, W, H),
        wgpu::TextureUsages::TEXTURE_BINDING,
    );
    g.import_texture(
        "target",
        TextureDesc::d2(format, W, H),
        wgpu::TextureUsages::RENDER_ATTACHMENT,
    );
    g.add_pass("present", Present, Bindings::new()).unwrap();
    g
}

/// The target's bytes as RGBA, whatever its channel order.
fn as_rgba(format: wgpu::TextureFormat, bytes: &[u8]) -> Vec<[u8; 4]> {
    bytes
        .chunks(4)
        .map(|t| match format {
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb => {
                [t[2], t[1], t[0], t[3]]
            }
            _ => [t[0], t[1], t[2], t[3]],
        })
        .collect()
}

#[test]
fn the_image_keeps_its_bytes_in_every_target_format() {
    let gpu = gpu();
    let desc = TextureDesc::d2(COLOR_FORMAT, W, H);
    let color = texture(
        &gpu,
        "color",
        &desc,
        wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
    );
    let pixels = image();
    gpu.queue.write_texture(
        color.as_image_copy(),
        &pixels,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(4 * W),
            rows_per_image: Some(H),
        },
        color.size(),
    );
    let mut exec = Executor::new(gpu);
    for format in [
        wgpu::TextureFormat::Rgba8Unorm,
        wgpu::TextureFormat::Rgba8UnormSrgb,
        wgpu::TextureFormat::Bgra8Unorm,
        wgpu::TextureFormat::Bgra8UnormSrgb,
    ] {
        let target = texture(
            &exec.gpu,
            "target",
            &TextureDesc::d2(format, W, H),
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        );
        let compiled = graph(format)
            .compile(&CompileOptions::for_gpu(&exec.gpu))
            .unwrap_or_else(|e| panic!("{format:?}: {e}"));
        let imports = Imports::new()
            .texture("color", &color)
            .texture("target", &target);
        exec.execute(&compiled, &imports)
            .unwrap_or_else(|e| panic!("{format:?}: {e}"));
        exec.finish().unwrap();
        let shown = as_rgba(
            format,
            &read_texture(&exec.gpu, &target, wgpu::TextureAspect::All),
        );
        let tolerance = cpu::within_rounding(format.is_srgb());
        let mut off = 0;
        for (i, (got, texel)) in shown.iter().zip(pixels.chunks(4)).enumerate() {
            let want = cpu::presented([texel[0], texel[1], texel[2], texel[3]]);
            if got.iter().zip(want).any(|(g, w)| g.abs_diff(w) > tolerance) {
                off += 1;
                assert!(off < 5, "{format:?} pixel {i}: {got:?}, want {want:?}");
            }
        }
        assert_eq!(off, 0, "{format:?}");
    }
}

#[test]
fn a_target_nothing_draws_colour_into_is_refused_naming_its_format() {
    for format in [
        wgpu::TextureFormat::Depth32Float,
        wgpu::TextureFormat::R32Uint,
    ] {
        let err = graph(format)
            .compile(&CompileOptions::new(wgpu::Features::empty()))
            .err()
            .unwrap_or_else(|| panic!("{format:?} was accepted"));
        assert!(
            matches!(&err, GraphError::Parameter { pass, message }
                if pass == "present" && message.contains(&format!("{format:?}"))),
            "{err}"
        );
    }
}
