//! A pass that copies an uploaded pyramid into a history's current half, so that the
//! next frame's first pass (cull or walk) reads it as last frame's pyramid.

use meshlight_graph::prelude::*;

/// Copies mips `0 .. levels` of slot `source` into slot `target` (both R32Float, level
/// 0 `size`).
pub struct CopyPyramid {
    pub levels: u32,
    pub size: [u32; 2],
}

impl Pass for CopyPyramid {
    fn implementation(&self) -> Implementation {
        let f = Some(wgpu::TextureFormat::R32Float);
        Implementation::new(
            "copy",
            StageContract {
                stage: "copy_pyramid",
                slots: vec![
                    Slot::texture("source", Access::CopySrc, f, ""),
                    Slot::texture("target", Access::CopyDst, f, ""),
                ],
            },
        )
    }
    fn setup(&self, _: &mut SetupContext) -> Result<()> {
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let (source, _) = ctx.texture("source")?;
        let (target, _) = ctx.texture("target")?;
        fn at(texture: &wgpu::Texture, level: u32) -> wgpu::TexelCopyTextureInfo<'_> {
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: level,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            }
        }
        for level in 0..self.levels {
            ctx.encoder().copy_texture_to_texture(
                at(&source, level),
                at(&target, level),
                wgpu::Extent3d {
                    width: (self.size[0] >> level).max(1),
                    height: (self.size[1] >> level).max(1),
                    depth_or_array_layers: 1,
                },
            );
        }
        Ok(())
    }
}
