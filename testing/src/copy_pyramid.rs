//! A pass that copies an uploaded pyramid into a history's current half, so that the
//! next frame's first pass (cull or walk) reads it as last frame's pyramid.

use meshlight_graph::prelude::*;
use meshlight_graph::{Bindings, GraphBuilder, History, Texture};

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

/// A history texture `name` of `desc` that a pass fills every frame from the imported
/// texture `upload` (which the caller writes, e.g. with [`crate::write_pyramid`]): the
/// next frame's first pass reads it, through `prev`, as last frame's pyramid.
pub fn uploaded_history(
    g: &mut GraphBuilder,
    name: &str,
    upload: &str,
    desc: &TextureDesc,
    usage: wgpu::TextureUsages,
) -> Result<History<Texture>> {
    let history = g.history_texture(name, desc.clone());
    let source = g.import_texture(upload, desc.clone(), usage);
    let copy = CopyPyramid {
        levels: desc.mip_levels,
        size: [desc.width, desc.height],
    };
    let bindings = Bindings::new()
        .bind("source", source)
        .bind("target", history.current);
    g.add_pass(&format!("copy_{name}"), copy, bindings)?;
    Ok(history)
}

/// The R32Float texture that holds `pyramid`: level 0 rounded up to powers of two, so
/// every mip wgpu makes (sizes rounded down) holds the level the pyramid's rule makes
/// (sizes rounded up), with one mip per level.
pub fn pyramid_texture_desc(
    pyramid: &meshlight_shaders::cpu::occlusion::DepthPyramid,
) -> TextureDesc {
    let (w, h, _) = pyramid.levels[0];
    TextureDesc::d2(
        wgpu::TextureFormat::R32Float,
        w.next_power_of_two(),
        h.next_power_of_two(),
    )
    .with_mips(pyramid.levels.len() as u32)
}
