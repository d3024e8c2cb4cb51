//! The one-pass graph the contract and GPU tests both bind `depth_pyramid` in.
// Each test binary includes this module and uses part of it.
#![allow(dead_code)]

use meshlight_graph::*;
use meshlight_pass_depth_pyramid::DepthPyramid;

/// What buffers the tests import are made with: bound as storage, filled, read back.
pub const BUFFER_USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_DST)
    .union(wgpu::BufferUsages::COPY_SRC);
/// The R64Uint visibility target's usage: written by the test, read by the pass.
pub const VISIBILITY_TEXTURE_USAGE: wgpu::TextureUsages =
    wgpu::TextureUsages::STORAGE_BINDING.union(wgpu::TextureUsages::COPY_DST);
/// The pyramid's usage: written by the pass, read back by the test.
pub const PYRAMID_USAGE: wgpu::TextureUsages =
    wgpu::TextureUsages::STORAGE_BINDING.union(wgpu::TextureUsages::COPY_SRC);

/// How the visibility target is imported.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Visibility {
    /// A `w × h` R64Uint storage texture.
    Texture,
    /// A buffer of this many u64 values.
    Buffer(u64),
}

/// A buffer of `values` u64 values, imported as `visibility`.
pub fn import_visibility_values(g: &mut GraphBuilder, values: u64) -> Handle<Buffer> {
    g.import_buffer(
        "visibility",
        BufferDesc::array(Element::U64, values),
        BUFFER_USAGE,
    )
}

/// A buffer of `w × h` u64 values, imported as `visibility`.
pub fn import_visibility(g: &mut GraphBuilder, w: u32, h: u32) -> Handle<Buffer> {
    import_visibility_values(g, u64::from(w) * u64::from(h))
}

/// Adds `pass` as `pyramid`, its slots bound to imports of the same names: the
/// visibility target as `visibility` says, the pyramid texture as `pyramid` describes
/// it and, with `counter`, a one-word persistent `counter`. Compile and record check the
/// bindings against the pass's params, so each test chooses what to get wrong.
pub fn add_pyramid_pass(
    g: &mut GraphBuilder,
    pass: DepthPyramid,
    visibility: Visibility,
    pyramid: TextureDesc,
    counter: bool,
) -> Result<()> {
    // At least one texel, so that a pass with a zero size reaches its own check.
    let (w, h) = (pass.width.max(1), pass.height.max(1));
    let visibility = match visibility {
        Visibility::Texture => g
            .import_texture(
                "visibility",
                TextureDesc::d2(wgpu::TextureFormat::R64Uint, w, h),
                VISIBILITY_TEXTURE_USAGE,
            )
            .erase(),
        Visibility::Buffer(values) => import_visibility_values(g, values).erase(),
    };
    let pyramid = g.import_texture("pyramid", pyramid, PYRAMID_USAGE);
    let mut bindings = Bindings::new()
        .bind("visibility", visibility)
        .bind("pyramid", pyramid);
    if counter {
        let counter = g.import_buffer("counter", BufferDesc::array(Element::U32, 1), BUFFER_USAGE);
        bindings = bindings.bind("counter", counter);
    }
    g.add_pass("pyramid", pass, bindings)?;
    Ok(())
}
