//! Stage `present`: the frame's image drawn into a target of any colour format.
//!
//! `resolve` writes the frame's image into `color`, an `Rgba8Unorm` storage texture of
//! sRGB-encoded bytes (what a PNG holds). A host application renders to its own texture
//! instead, typically a swapchain image (`Bgra8UnormSrgb`, which cannot be a storage
//! texture). This pass draws `color` into such a `target` with one fullscreen triangle,
//! so the host gets the same pixels whatever its format: channel order follows the
//! target's format, and an sRGB target is handed linear light so that its own encoding
//! stores the image's bytes (to within one step of rounding).
//!
//! # Contract
//!
//! | slot     | access        | holds | |
//! |----------|---------------|-------|---|
//! | `color`  | sampled       | rgba8unorm | the frame's image, sRGB-encoded |
//! | `target` | render target | any colour format | the host's texture, the image's size |
//!
//! [`cpu::presented`] is the reference of one texel.

#![warn(missing_docs)]

use meshlight_graph::file::{Params, Registry};
use meshlight_graph::prelude::*;
use meshlight_graph::{ColorAttachment, ColorTarget};
use meshlight_shaders::{PassShader, pass_shader, shader_defs};

/// The stage name pipelines use.
pub const STAGE: &str = "present";

/// The format of the image the pass reads: what `resolve` writes.
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// The pass's shader.
pub const SHADER: PassShader = pass_shader!("present::present", "present.wgsl");

/// The slots of stage `present`.
pub fn contract() -> StageContract {
    StageContract {
        stage: STAGE,
        slots: vec![
            Slot::texture(
                "color",
                Access::Sampled,
                Some(COLOR_FORMAT),
                "the frame's image, sRGB-encoded bytes",
            ),
            Slot::texture(
                "target",
                Access::RenderTarget,
                None,
                "the host's texture of the image's size, in any colour format",
            ),
        ],
    }
}

shader_defs! {
    /// The variant for the target's format.
    struct PresentDefs {
        /// The target encodes to sRGB when it stores: hand it linear light.
        srgb: bool => "SRGB_TARGET",
    }
}

/// The one implementation: a fullscreen triangle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Present;

impl Present {
    /// From a pipeline entry: `present` takes no parameters (its sizes are its slots').
    pub fn from_params(params: &Params) -> Result<Self> {
        params.only(&[])?;
        Ok(Self)
    }
}

impl Pass for Present {
    fn implementation(&self) -> Implementation {
        Implementation::new("fullscreen", contract())
    }

    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        let format = ctx.format("target").ok_or_else(|| {
            GraphError::parameter("`target` must be bound to a colour texture".to_string())
        })?;
        if format.is_depth_stencil_format() || !format.is_srgb() && !renderable_colour(format) {
            return Err(GraphError::parameter(format!(
                "`target` is {format:?}, which a render pass cannot draw colour into; give a colour format such as Bgra8UnormSrgb or Rgba8Unorm"
            )));
        }
        let defs = PresentDefs {
            srgb: format.is_srgb(),
        };
        ctx.shader_defs(&defs);
        ctx.program(
            "present",
            ProgramDesc::render(&SHADER, "fullscreen_vs")
                .defs(&defs)
                .fragment("present_fs")
                .target(ColorTarget::new("target"))
                .layout(BindingLayout::from_shader_render("present")),
        );
        Ok(())
    }

    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let program = ctx.render("present")?;
        let group = ctx.bind_group(&program, 0, &[])?;
        let mut pass = ctx.render_pass(&[ColorAttachment::new("target")], None)?;
        pass.set_pipeline(&program.pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.draw(0..3, 0..1);
        Ok(())
    }
}

/// Whether a non-sRGB colour format takes a float colour from a fragment shader (normalised
/// or float formats; integer formats do not).
fn renderable_colour(format: wgpu::TextureFormat) -> bool {
    matches!(
        format.sample_type(None, None),
        Some(wgpu::TextureSampleType::Float { .. })
    )
}

/// Registers [`Present`] as implementation `fullscreen` of stage `present`.
pub fn register(r: &mut Registry) {
    r.register(STAGE, "fullscreen", Present::from_params);
}

/// The reference of one texel.
pub mod cpu {
    /// What a target of the given kind stores for an image texel `rgba` (sRGB-encoded
    /// bytes): the same bytes, alpha opaque. Through an sRGB target the value is decoded
    /// by the shader and encoded again by the target, which may round to a neighbouring
    /// byte: [`within_rounding`] says how far.
    pub fn presented(rgba: [u8; 4]) -> [u8; 4] {
        [rgba[0], rgba[1], rgba[2], 255]
    }

    /// Bytes an sRGB round trip (decode in the shader, encode in the target) may move a
    /// channel by.
    pub fn within_rounding(srgb_target: bool) -> u8 {
        if srgb_target { 1 } else { 0 }
    }
}
