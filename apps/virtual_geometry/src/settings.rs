//! What a frame is asked for beyond its pipeline: the viewport, and every choice a caller
//! may make over the pipeline's own (an implementation, a threshold, a debug view, the
//! lights, a host's target). A setting left `None` keeps what the pipeline says, so the
//! shipped frame and a user's file take the same settings the same way.

use crate::adaptive_occlusion::OcclusionPolicy;
use meshlight::gpu_scene::cascades::CascadeSettings;
use meshlight::graph::{GraphError, Result};
use meshlight::resolve::DebugView;
use meshlight_light_clustering::ClusteringSettings;
use std::collections::BTreeMap;

/// The environment variables that set a few settings for sweeps (benchmarks, bisecting a
/// regression), read by [`FrameSettings::new`].
pub mod env {
    /// `cull_lod`'s `sw_threshold_px`, in pixels.
    pub const SW_THRESHOLD_PX: &str = "MESHLIGHT_SW_THRESHOLD_PX";
    /// `on` or `off`: the hardware rasteriser (see [`super::FrameSettings::hardware`]).
    pub const HARDWARE_RASTER: &str = "MESHLIGHT_HARDWARE_RASTER";
    /// `fill_clusters`' `occlusion_min_clusters`.
    pub const OCCLUSION_MIN_CLUSTERS: &str = "MESHLIGHT_OCCLUSION_MIN_CLUSTERS";
    /// `sw_raster`'s `big_triangle_px`.
    pub const BIG_TRIANGLE_PX: &str = "MESHLIGHT_BIG_TRIANGLE_PX";
    /// `always`, `adaptive` or `MIN_HIDDEN/PROBE_EVERY`: when a two-pass frame tests
    /// occlusion (see [`crate::adaptive_occlusion::OcclusionPolicy::parse`]).
    pub const OCCLUSION_POLICY: &str = "MESHLIGHT_OCCLUSION_POLICY";
}

/// A host application's targets: the frame ends by drawing its image into the host's
/// colour texture (and, with `depth`, the scene's depth into the host's depth texture),
/// so the host composites its own raster geometry by depth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HostTargets {
    /// The format of the host's colour texture (a swapchain's `Bgra8UnormSrgb`, say).
    pub color: wgpu::TextureFormat,
    /// Whether the scene's depth goes into the host's depth texture: a `Depth32Float`
    /// texture, which resolve writes reverse-Z (1 at the near plane, 0 far away and
    /// where nothing was drawn).
    pub depth: bool,
}

/// The sun's shadow: its cascades and how a receiver is compared with them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowSettings {
    /// How many cascades, their resolution, how far shadows reach and how the view is
    /// split between them.
    pub cascades: CascadeSettings,
    /// How far a receiver moves towards the light before it is compared, in texels of
    /// its cascade: against acne on surfaces facing the sun.
    pub depth_bias: f32,
    /// How far a receiver moves along its normal, in texels of its cascade: against
    /// acne on surfaces the sun grazes.
    pub normal_bias: f32,
    /// The shadow views' LOD threshold is the camera's times `2^lod_bias` (in the
    /// shadow view's texels): 0 keeps a texel of error, 1 allows two (fewer triangles
    /// drawn into the maps, coarser silhouettes in the shadow). Applied to each
    /// cascade's View (its LOD scale), so one walk serves the camera and the cascades.
    pub lod_bias: f32,
    /// Keep a cascade's map while its view and the scene stay as they were when it was
    /// drawn (nothing moved or streamed in, the camera still): the cascade's passes are
    /// left out of the frame. Off, every cascade is drawn every frame.
    pub cache: bool,
    /// How the cascades' candidates are listed: by the camera's walk (the default: one
    /// walk for every view), as the pipeline file says, or a walk per cascade.
    pub walk: super::shadows::ShadowWalk,
}

impl Default for ShadowSettings {
    /// The default cascades ([`CascadeSettings::default`]: four 2048² to 100 units), one
    /// texel of depth and normal bias, no LOD bias, maps kept while nothing changes, one
    /// walk for every view.
    fn default() -> Self {
        Self {
            cascades: CascadeSettings::default(),
            depth_bias: 1.0,
            normal_bias: 1.0,
            lod_bias: 0.0,
            cache: true,
            walk: super::shadows::ShadowWalk::WithCamera,
        }
    }
}

impl ShadowSettings {
    /// Checks every number, naming the first one out of range and what to give.
    pub fn validate(&self) -> Result<()> {
        self.cascades.validate().map_err(|e| GraphError::Setting {
            setting: "shadows".into(),
            message: e.to_string(),
        })?;
        for (name, value, range) in [
            ("depth_bias", self.depth_bias, 0.0..=64.0),
            ("normal_bias", self.normal_bias, 0.0..=64.0),
            ("lod_bias", self.lod_bias, -4.0..=8.0),
        ] {
            if !range.contains(&value) {
                return Err(GraphError::Setting {
                    setting: format!("shadows.{name}"),
                    message: format!(
                        "{value} is outside {}..={}; give a number in that range",
                        range.start(),
                        range.end()
                    ),
                });
            }
        }
        Ok(())
    }
}

/// What a frame is asked for. `None` everywhere but the viewport: the pipeline's own
/// frame.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// What every `resolve` pass shows; `None`: the pipeline's (the shipped frame:
    /// shaded).
    pub view: Option<DebugView>,
    /// Screen-space error (pixels) the LOD cut may show, in the walk and the cull alike
    /// (they must agree, or clusters of the cut are pruned); `None`: the pipeline's.
    pub lod_threshold_px: Option<f32>,
    /// Screen-box size under which a cluster is rasterised in software; `None`: the
    /// pipeline's (`auto` in the shipped frame: the adapter class's split).
    pub sw_threshold_px: Option<f32>,
    /// An implementation per stage, over the pipeline's (`auto` included), e.g.
    /// `sw_raster` → `buffer`. `fill_clusters` → `workgroup_per_instance` is the flat
    /// fill ([`Self::hierarchy`] off).
    pub implementations: BTreeMap<String, String>,
    /// `Some(false)`: no hardware rasteriser; culling sends every cluster to software,
    /// which clips those crossing the near plane. `Some(true)`: one on every adapter.
    /// `None`: on where a split is given ([`Self::sw_threshold_px`] asks for both
    /// rasterisers), else the pipeline's (the shipped frame: the adapter class decides,
    /// see `meshlight::graph::AdapterClass::hardware_raster`).
    /// `MESHLIGHT_HARDWARE_RASTER` sets it.
    pub hardware: Option<bool>,
    /// Initial candidate-list and raster-slot sizes (the renderer grows them on
    /// overflow); `None`: the pipeline's `[params]`.
    pub clusters: Option<u64>,
    /// See [`Self::clusters`].
    pub slots: Option<u64>,
    /// Resolve the `depth` and `material_depth` targets: a fullscreen fragment pass
    /// each, which only a frame compositing raster geometry over the image needs.
    pub depth: bool,
    /// See [`Self::depth`].
    pub material_depth: bool,
    /// The software rasteriser divides exactly in integers (bit-exact on every driver,
    /// slower); `None`: the pipeline's.
    pub exact_division: Option<bool>,
    /// Cluster the renderer's lights and shade with them; `None` takes the light
    /// clustering's passes out of the frame.
    pub clustering: Option<ClusteringSettings>,
    /// Keep the visibility target (`visbuffer`), the slot list (`raster_clusters`) and
    /// the culling passes' counters after the frame, for `Executor::read_buffer` (tests,
    /// debugging).
    pub keep_visibility: bool,
    /// Two-pass occlusion culling: the shipped frame is `pipelines/virtual_geometry.toml`
    /// with it and `pipelines/virtual_geometry_one_pass.toml` without. A pipeline file
    /// of the caller's decides for itself.
    pub occlusion: bool,
    /// When a two-pass frame tests occlusion: while it culls enough to pay for itself
    /// (the default), or every frame ([`OcclusionPolicy::ALWAYS`]). The `occlusion`
    /// view tests every frame whatever this says.
    pub occlusion_policy: OcclusionPolicy,
    /// `fill` walks each visible instance's culling hierarchy; off, every cluster of
    /// every instance in view is a candidate (`workgroup_per_instance`).
    pub hierarchy: bool,
    /// The walk tests a node against the pyramid only with at least this many meshlets
    /// below; `None`: the pipeline's. `MESHLIGHT_OCCLUSION_MIN_CLUSTERS` sets it.
    pub occlusion_min_clusters: Option<u32>,
    /// `sw_raster`'s `big_triangle_px`; `None`: the pipeline's.
    /// `MESHLIGHT_BIG_TRIANGLE_PX` sets it.
    pub big_triangle_px: Option<u32>,
    /// A host's targets the frame draws into, instead of leaving its image in `color`.
    pub host: Option<HostTargets>,
    /// Direction towards the sun, world space (any length but zero): every `resolve`
    /// pass's `light_direction`, which the shadow cascades follow too; `None`: the
    /// pipeline's.
    pub sun_direction: Option<glam::Vec3>,
    /// The sun's shadow, drawn by the pipeline's shadow stage (the passes over the view
    /// set `cascades`); `None` takes that stage out, and the image is unshadowed.
    pub shadows: Option<ShadowSettings>,
}

/// The value of an environment variable, parsed; unset or unparsable: `None`.
fn from_env<T: std::str::FromStr>(name: &str) -> Option<T> {
    std::env::var(name).ok().and_then(|v| v.trim().parse().ok())
}

impl FrameSettings {
    /// The pipeline's own frame at `width × height`, with the sweep variables of [`env`]
    /// applied.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            view: None,
            lod_threshold_px: None,
            sw_threshold_px: from_env(env::SW_THRESHOLD_PX),
            implementations: BTreeMap::new(),
            hardware: std::env::var(env::HARDWARE_RASTER)
                .ok()
                .and_then(|v| match v.trim() {
                    "on" | "1" | "true" => Some(true),
                    "off" | "0" | "false" => Some(false),
                    _ => None,
                }),
            clusters: None,
            slots: None,
            depth: false,
            material_depth: false,
            exact_division: None,
            clustering: None,
            keep_visibility: false,
            occlusion: true,
            occlusion_policy: std::env::var(env::OCCLUSION_POLICY)
                .ok()
                .and_then(|v| OcclusionPolicy::parse(&v))
                .unwrap_or_default(),
            hierarchy: true,
            occlusion_min_clusters: from_env(env::OCCLUSION_MIN_CLUSTERS),
            big_triangle_px: from_env(env::BIG_TRIANGLE_PX),
            host: None,
            sun_direction: None,
            shadows: None,
        }
    }

    /// Runs `stage` with `implementation` (see [`Self::implementations`]).
    pub fn with_implementation(mut self, stage: &str, implementation: &str) -> Self {
        self.implementations
            .insert(stage.to_string(), implementation.to_string());
        self
    }

    /// Shows `view`.
    pub fn with_view(mut self, view: DebugView) -> Self {
        self.view = Some(view);
        self
    }

    /// A viewport of 0, or past the device's 2-D texture limit, named with what to do.
    pub fn check_viewport(&self, max_dimension: u32) -> Result<()> {
        let (w, h) = (self.width, self.height);
        if w == 0 || h == 0 || w > max_dimension || h > max_dimension {
            return Err(GraphError::Setting {
                setting: "the viewport".into(),
                message: format!(
                    "the viewport {w} × {h} must be at least 1 × 1 and at most {max_dimension} on each side (this device's 2-D texture limit); change --width/--height"
                ),
            });
        }
        Ok(())
    }
}
