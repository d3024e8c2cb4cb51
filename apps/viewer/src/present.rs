//! Getting the frame onto the window: a pass of the graph copies `color` into a texture
//! the viewer owns (no wait for the GPU, no readback), and a fullscreen triangle draws
//! that texture into the window's surface, under the overlay.

use meshlight::graph::{
    Access, Bindings, GraphBuilder, Implementation, Pass, RecordContext, Result, SetupContext,
    Slot, StageContract, TextureDesc,
};
use meshlight::resolve::COLOR_FORMAT;
use meshlight_virtual_geometry::FrameSettings;

/// The imported texture the frame's image is copied into.
pub const PRESENT: &str = "present";
/// The stage of the copy pass, as the plan and its dumps name it.
pub const STAGE: &str = "present_copy";
/// How the viewer's texture is used: copied into by the graph, sampled by the blit.
pub const PRESENT_USAGE: wgpu::TextureUsages =
    wgpu::TextureUsages::COPY_DST.union(wgpu::TextureUsages::TEXTURE_BINDING);

/// Copies the resolved `color` into the viewer's [`PRESENT`] texture at the end of the
/// frame.
struct CopyToPresent;

impl Pass for CopyToPresent {
    fn implementation(&self) -> Implementation {
        Implementation::new(
            "copy",
            StageContract {
                stage: STAGE,
                slots: vec![
                    Slot::texture(
                        "color",
                        Access::CopySrc,
                        Some(COLOR_FORMAT),
                        "the frame's resolved image",
                    ),
                    Slot::texture(
                        PRESENT,
                        Access::CopyDst,
                        Some(COLOR_FORMAT),
                        "the viewer's texture, drawn into the window",
                    ),
                ],
            },
        )
    }
    fn setup(&self, ctx: &mut SetupContext<'_>) -> Result<()> {
        ctx.needs_encoder("a texture copy is an encoder command");
        ctx.side_effect();
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let (color, _) = ctx.texture("color")?;
        let (present, _) = ctx.texture(PRESENT)?;
        ctx.encoder().copy_texture_to_texture(
            color.as_image_copy(),
            present.as_image_copy(),
            color.size(),
        );
        Ok(())
    }
}

/// Adds the copy (and the imported texture it writes) to a frame graph.
pub fn add_present(g: &mut GraphBuilder, s: &FrameSettings) -> Result<()> {
    g.import_texture(
        PRESENT,
        TextureDesc::d2(COLOR_FORMAT, s.width, s.height),
        PRESENT_USAGE,
    );
    g.add_pass("present", CopyToPresent, Bindings::new())?;
    Ok(())
}

/// The viewer's texture for a viewport.
pub fn present_texture(device: &wgpu::Device, width: u32, height: u32) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(PRESENT),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: COLOR_FORMAT,
        usage: PRESENT_USAGE,
        view_formats: &[],
    })
}

const BLIT_WGSL: &str = r"
@group(0) @binding(0) var image: texture_2d<f32>;

@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

// One texel per pixel: the image is rendered at the window's size. The bytes go through
// unchanged (the surface is configured without sRGB encoding, as the image is already
// encoded), so the window shows what the PNG holds.
@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let size = vec2<i32>(textureDimensions(image));
    let at = min(vec2<i32>(p.xy), size - 1);
    return vec4<f32>(textureLoad(image, at, 0).rgb, 1.0);
}
";

/// Draws the viewer's texture over the whole target.
pub struct Blit {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    bind_group: Option<(wgpu::Texture, wgpu::BindGroup)>,
}

impl Blit {
    pub fn new(device: &wgpu::Device, target: wgpu::TextureFormat) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("blit"),
            source: wgpu::ShaderSource::Wgsl(BLIT_WGSL.into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("blit image"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("blit"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("blit"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(target.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        Self {
            pipeline,
            layout,
            bind_group: None,
        }
    }

    /// Draws `image` into the pass's target.
    pub fn draw(
        &mut self,
        device: &wgpu::Device,
        pass: &mut wgpu::RenderPass<'_>,
        image: &wgpu::Texture,
    ) {
        if self.bind_group.as_ref().is_none_or(|(t, _)| t != image) {
            let view = image.create_view(&wgpu::TextureViewDescriptor::default());
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("blit image"),
                layout: &self.layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&view),
                }],
            });
            self.bind_group = Some((image.clone(), group));
        }
        let (_, group) = self.bind_group.as_ref().expect("made above");
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.draw(0..3, 0..1);
    }
}
