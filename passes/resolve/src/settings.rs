//! What the resolve pass is asked for: its size, the debug view shown in `color`, and
//! the light of the shaded view; read from code or from a pipeline file's params.

use glam::Vec3;
use meshlight_graph::prelude::*;
use std::fmt;
use std::str::FromStr;

/// What the `color` target shows. The discriminants are the `VIEW_*` constants of
/// shade.wgsl, which the pass hands to the shader as they are.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum DebugView {
    /// The lit surface (textured, or checkered where the material asks) over a sky
    /// gradient.
    #[default]
    Shaded = 0,
    /// A colour per visibility cluster id (per slot of `raster_clusters`).
    Clusters = 1,
    /// A colour per triangle: the visibility value's low word.
    Triangles = 2,
    /// A colour per LOD level of the pixel's meshlet.
    Lod = 3,
    /// Which rasteriser drew the pixel: software or hardware.
    Raster = 4,
    /// The reverse-Z depth as grey, `depth^(1/4)`.
    Depth = 5,
    /// A heat map of the point and spot lights in each pixel's froxel (black: none; red:
    /// 32 or more). Needs light clustering in the frame.
    LightCount = 6,
    /// Mip `pyramid_mip` of the depth pyramid bound to the `pyramid` slot, as grey
    /// `depth^(1/4)`: each pixel shows the texel of that mip that covers it.
    Pyramid = 7,
    /// Which culling pass drew each pixel's cluster (first: green, second: blue, from
    /// the `second_counts` slot), tinted red by the share of the pixel's instance that
    /// occlusion culled (the `occluded_per_instance` slot), over the shaded brightness.
    Occlusion = 8,
    /// A colour per material: the pixel's instance's material plus its meshlet's slot.
    Material = 9,
    /// The texture coordinates: red `fract(u)`, green `fract(v)`.
    Uv = 10,
    /// The shading normal (normal map applied), world space, as `n · 0.5 + 0.5`.
    Normal = 11,
    /// The mip level the base colour texture is read at (the level the filter starts
    /// from), a colour per level as the `lod` view colours LOD levels; black where the
    /// material has no base colour texture.
    Mip = 12,
    /// The base colour (factor times texture), unlit, linear.
    BaseColor = 13,
    /// How many levels coarser than the view wants each cluster is drawn because a page
    /// it needs is not in the streaming pool (the `stream_errors` slot): green at the
    /// wanted level, yellow one level coarser, orange two, red three or more, over the
    /// shaded brightness. Estimated from the missing group's error in pixels against
    /// `lod_threshold_px` (errors about double a level); all green when the scene does
    /// not stream.
    Residency = 14,
    /// The sun's shadow: each pixel coloured by the cascade it reads (red, green, blue,
    /// yellow from the nearest; grey past the last) and dimmed where the sun does not
    /// reach it (`0.3 + 0.7 · shadow factor`). Needs the `shadow_maps` slot bound.
    Shadow = 15,
}

impl DebugView {
    /// Every view, in discriminant order.
    pub const ALL: [DebugView; 16] = [
        DebugView::Shaded,
        DebugView::Clusters,
        DebugView::Triangles,
        DebugView::Lod,
        DebugView::Raster,
        DebugView::Depth,
        DebugView::LightCount,
        DebugView::Pyramid,
        DebugView::Occlusion,
        DebugView::Material,
        DebugView::Uv,
        DebugView::Normal,
        DebugView::Mip,
        DebugView::BaseColor,
        DebugView::Residency,
        DebugView::Shadow,
    ];

    /// The name pipeline files and the command line use.
    pub fn name(self) -> &'static str {
        match self {
            DebugView::Shaded => "shaded",
            DebugView::Clusters => "clusters",
            DebugView::Triangles => "triangles",
            DebugView::Lod => "lod",
            DebugView::Raster => "raster",
            DebugView::Depth => "depth",
            DebugView::LightCount => "light-count",
            DebugView::Pyramid => "pyramid",
            DebugView::Occlusion => "occlusion",
            DebugView::Material => "material",
            DebugView::Uv => "uv",
            DebugView::Normal => "normal",
            DebugView::Mip => "mip",
            DebugView::BaseColor => "base-color",
            DebugView::Residency => "residency",
            DebugView::Shadow => "shadow",
        }
    }

    /// True for views that show light clustering's lists.
    pub fn needs_lights(self) -> bool {
        self == DebugView::LightCount
    }

    /// True for views that show a depth pyramid (the `pyramid` slot).
    pub fn needs_pyramid(self) -> bool {
        self == DebugView::Pyramid
    }

    /// True for views that show the sun's shadow cascades (the `shadow_maps` slot).
    pub fn needs_shadows(self) -> bool {
        self == DebugView::Shadow
    }

    /// True for views that read the culling passes' records (`second_counts`,
    /// `occluded_per_instance`), which a frame binds only for them.
    pub fn needs_occlusion_records(self) -> bool {
        self == DebugView::Occlusion
    }

    /// The view called `name` (as [`DebugView::name`] spells it).
    pub fn parse(name: &str) -> std::result::Result<Self, UnknownView> {
        Self::ALL
            .into_iter()
            .find(|v| v.name() == name)
            .ok_or_else(|| UnknownView(name.to_string()))
    }
}

impl fmt::Display for DebugView {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for DebugView {
    type Err = UnknownView;
    fn from_str(s: &str) -> std::result::Result<Self, UnknownView> {
        Self::parse(s)
    }
}

/// A view name that is none of [`DebugView::ALL`]; its message lists the valid ones.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownView(pub String);

impl fmt::Display for UnknownView {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = DebugView::ALL.iter().map(|v| v.name()).collect();
        write!(
            f,
            "unknown view `{}`; use one of: {}",
            self.0,
            names.join(", ")
        )
    }
}

impl std::error::Error for UnknownView {}

/// How the shaded view lights the surface, and which view `color` shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// World-space direction towards the light; normalised when the pass records.
    pub light_direction: Vec3,
    /// Linear RGB radiance of the light.
    pub light_color: Vec3,
    /// Linear RGB ambient term, so faces turned away from the light keep their shape.
    pub ambient_color: Vec3,
    /// What the `color` target shows: the shaded image or a debug view.
    pub view: DebugView,
    /// Checker squares per UV unit.
    pub checker_scale: f32,
    /// The mip the `pyramid` view shows (0: the finest, half the viewport's size).
    pub pyramid_mip: u32,
    /// The LOD cut's threshold in pixels, as the culling pass has it: the `residency`
    /// view measures missing detail against it.
    pub lod_threshold_px: f32,
}

impl Default for Settings {
    /// A sun from the upper left, in front of a camera looking down −z; a slightly blue
    /// ambient, as from the sky.
    fn default() -> Self {
        Self {
            light_direction: Vec3::new(-0.5, 0.8, 0.35),
            light_color: Vec3::splat(1.0),
            ambient_color: Vec3::new(0.22, 0.25, 0.3),
            view: DebugView::Shaded,
            checker_scale: 8.0,
            pyramid_mip: 0,
            lod_threshold_px: 1.0,
        }
    }
}

/// The `compute` implementation of `resolve`: `width` × `height` is the visibility
/// buffer's size and the size of the three targets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resolve {
    /// The visibility buffer's width, and the targets'.
    pub width: u32,
    /// The visibility buffer's height, and the targets'.
    pub height: u32,
    /// Lighting and the debug view: what may change between frames without a new graph.
    pub settings: Settings,
    /// Multiply the base colour by the meshes' vertex colours (`MESH_FLAG_COLORS`).
    /// Off, the shader holds no code for them: on an H200 that code cost the resolve of
    /// a scene without colours 5%, which the renderer spares it by turning this on only
    /// for a scene with a coloured mesh.
    pub vertex_colors: bool,
}

/// The params a pipeline file may give; any other key is an error.
pub const KEYS: [&str; 10] = [
    "width",
    "height",
    "view",
    "checker_scale",
    "light_direction",
    "light_color",
    "ambient_color",
    "pyramid_mip",
    "vertex_colors",
    "lod_threshold_px",
];

impl Resolve {
    /// A `width` × `height` resolve with the default [`Settings`].
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            settings: Settings::default(),
            vertex_colors: false,
        }
    }

    /// The same pass showing `view`.
    pub fn with_view(mut self, view: DebugView) -> Self {
        self.settings.view = view;
        self
    }

    /// Reads `width`, `height` (required, > 0), `view` (a [`DebugView`] name, default
    /// `shaded`), `checker_scale` (> 0, default 8), and `light_direction` (non-zero),
    /// `light_color`, `ambient_color` (non-negative) as `[x, y, z]` arrays, and
    /// `pyramid_mip` (default 0; checked against the bound pyramid when the pass records),
    /// `vertex_colors` (default false), `lod_threshold_px` (> 0, default 1: the culling
    /// pass's, for the `residency` view).
    pub fn from_params(params: &Params) -> Result<Self> {
        params.only(&KEYS)?;
        let [width, height] = params.size("the visibility buffer")?;
        let defaults = Settings::default();
        let view = DebugView::parse(&params.string("view", defaults.view.name())?)
            .map_err(|e| GraphError::parameter(format!("`view`: {e}")))?;
        let checker_scale = params.f32("checker_scale", defaults.checker_scale)?;
        if checker_scale <= 0.0 {
            return Err(GraphError::parameter(format!(
                "`checker_scale` (checker squares per UV unit) must be > 0, got {checker_scale}"
            )));
        }
        let light_direction = Vec3::from_array(
            params.f32_array("light_direction", defaults.light_direction.to_array())?,
        );
        if light_direction.normalize_or_zero() == Vec3::ZERO {
            return Err(GraphError::parameter(format!(
                "`light_direction` (towards the light) must not be zero, got {light_direction}"
            )));
        }
        let lod_threshold_px = params.f32("lod_threshold_px", defaults.lod_threshold_px)?;
        if !(lod_threshold_px > 0.0 && lod_threshold_px.is_finite()) {
            return Err(GraphError::parameter(format!(
                "`lod_threshold_px` (the culling pass's LOD threshold, for the `residency` view) must be > 0, got {lod_threshold_px}"
            )));
        }
        let colour = |key: &str, default: Vec3| -> Result<Vec3> {
            let c = Vec3::from_array(params.f32_array(key, default.to_array())?);
            if c.min_element() < 0.0 {
                return Err(GraphError::parameter(format!(
                    "`{key}` (linear RGB) must not be negative, got {c}"
                )));
            }
            Ok(c)
        };
        Ok(Self {
            width,
            height,
            settings: Settings {
                light_direction,
                light_color: colour("light_color", defaults.light_color)?,
                ambient_color: colour("ambient_color", defaults.ambient_color)?,
                view,
                checker_scale,
                pyramid_mip: params.u32("pyramid_mip", defaults.pyramid_mip)?,
                lod_threshold_px,
            },
            vertex_colors: params.bool("vertex_colors", false)?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshlight_testing::params;

    #[test]
    fn names_round_trip_and_match_the_shader_constants() {
        for (i, v) in DebugView::ALL.into_iter().enumerate() {
            assert_eq!(v as u32, i as u32);
            assert_eq!(v.name().parse::<DebugView>(), Ok(v));
            assert_eq!(v.to_string(), v.name());
        }
        let e = "normals".parse::<DebugView>().unwrap_err().to_string();
        assert!(e.contains("`normals`"), "{e}");
        for v in DebugView::ALL {
            assert!(e.contains(v.name()), "{e} lacks {v}");
        }
    }

    #[test]
    fn params_are_read_with_their_defaults() {
        let r = Resolve::from_params(&params("width = 64\nheight = 48")).unwrap();
        assert_eq!(r, Resolve::new(64, 48));
        let r = Resolve::from_params(&params(
            "width = 8\nheight = 4\nview = \"lod\"\nchecker_scale = 2.5\n\
             light_direction = [0, 1, 0]\nlight_color = [2, 1.5, 1]\nambient_color = [0.0, 0.0, 0.1]\n\
             pyramid_mip = 3",
        ))
        .unwrap();
        assert_eq!((r.width, r.height), (8, 4));
        let s = r.settings;
        assert_eq!(s.view, DebugView::Lod);
        assert_eq!(s.checker_scale, 2.5);
        assert_eq!(s.light_direction, Vec3::Y);
        assert_eq!(s.light_color, Vec3::new(2.0, 1.5, 1.0));
        assert_eq!(s.ambient_color, Vec3::new(0.0, 0.0, 0.1));
        assert_eq!(s.pyramid_mip, 3);
        // An integer scale is a number too.
        let r = Resolve::from_params(&params("width = 8\nheight = 4\nchecker_scale = 3"));
        assert_eq!(r.unwrap().settings.checker_scale, 3.0);
    }

    #[test]
    fn bad_params_are_errors_that_name_what_to_change() {
        let wrong_size = "width = 0\nheight = 48";
        let wrong_view = "width = 4\nheight = 4\nview = \"normals\"";
        let wrong_scale = "width = 4\nheight = 4\nchecker_scale = \"big\"";
        let wrong_color = "width = 4\nheight = 4\nlight_color = [1, -1, 1]";
        meshlight_testing::assert_params(
            |text| Resolve::from_params(&params(text)),
            &[],
            &[
                (wrong_size, "`width`"),
                (wrong_size, "0 × 48"),
                ("height = 48", "`width`"),
                (wrong_view, "`normals`"),
                (wrong_view, "shaded, clusters"),
                ("width = 4\nheight = 4\nwidht = 4", "`widht`"),
                (wrong_scale, "`checker_scale`"),
                (wrong_scale, "big"),
                ("width = 4\nheight = 4\nchecker_scale = 0", "> 0"),
                (
                    "width = 4\nheight = 4\nlight_direction = [1, 2]",
                    "three finite numbers",
                ),
                (
                    "width = 4\nheight = 4\nlight_direction = [0, 0, 0]",
                    "must not be zero",
                ),
                (wrong_color, "`light_color`"),
                (wrong_color, "negative"),
            ],
        );
    }
}
