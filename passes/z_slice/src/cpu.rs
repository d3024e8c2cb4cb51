//! The reference of `z_slice.wgsl`: the same f32 operations in the same order, one object
//! after another. The GPU's `log2`, `sqrt` and division are not correctly rounded and it
//! may fuse multiply-adds, so an object whose deciding value lies within a hair of a
//! threshold may come out differently there; [`Extent::closeness`] measures that hair.

use meshlight_shaders::cpu::layout::{ClusterGrid, ClusterableKind, ClusterableObject, View};
use meshlight_shaders::cpu::light::z_slice_of_depth;

/// Count words of `slice_counts` (see the crate docs).
pub const COUNT_WORDS: usize = 8;
/// `[0]`: instances requested, which may exceed the capacity.
pub const WORD_REQUESTED: usize = 0;
/// `[1]`: the list's capacity; overflow = requested − capacity.
pub const WORD_CAPACITY: usize = 1;
/// `[2]`: objects skipped as invalid.
pub const WORD_INVALID: usize = 2;
/// `[3]`: objects culled (range 0, outside the frustum, nearer than the near plane).
pub const WORD_CULLED: usize = 3;
/// `WORD_VISIBLE + kind`: objects of that kind given at least one slice.
pub const WORD_VISIBLE: usize = 4;

/// Ranges above this, infinity included, are this (`RANGE_LIMIT` in the WGSL).
pub const RANGE_LIMIT: f32 = 1e30;
const MIN_DIRECTION_SQUARED: f32 = 1e-12;
/// `SQRT_2` of the WGSL, which writes it as `1.4142135` (the same f32 value; a test
/// reads the WGSL to keep it so): a decal's box reaches `r√2` from its axis.
pub const SQRT_2: f32 = std::f32::consts::SQRT_2;
/// `SQRT_3` of the WGSL, written there as `1.7320508`: a box of half-extent `r` reaches
/// `r√3` from its centre, the radius its frustum test uses.
pub const SQRT_3: f32 = 1.732_050_8;

/// `SliceInstance`: one (object, slice) pair of the list.
#[repr(C)]
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    Hash,
    PartialOrd,
    Ord,
    bytemuck::Pod,
    bytemuck::Zeroable,
)]
pub struct SliceInstance {
    /// Index into `objects`.
    pub object: u32,
    /// Depth slice, below the grid's depth.
    pub slice: u32,
}

/// What became of one object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outcome {
    /// NaN or infinite position, NaN or negative range, unknown kind, or a spot or decal
    /// with no usable direction (or a spot with a non-finite angle): counted, not drawn.
    Invalid,
    /// Range 0, outside the frustum, or wholly nearer than the near plane.
    Culled,
    /// Slices `first..=last`.
    Visible {
        /// The slice of the bounds' nearest depth.
        first: u32,
        /// The slice of the farthest depth (never before `first`).
        last: u32,
    },
}

/// The view-space depth interval of one object and the values that decided it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extent {
    /// Invalid, culled, or the slices given.
    pub outcome: Outcome,
    /// View-space depth of the bounds' nearest point.
    pub near_depth: f32,
    /// View-space depth of the bounds' farthest point.
    pub far_depth: f32,
    /// Radius of the sphere given to the frustum test.
    pub bound: f32,
    /// The sphere's smallest `dot(plane, centre) + w + radius` over the planes (negative:
    /// outside).
    pub frustum_margin: f32,
    /// `|dot(plane, centre)| + |w|` of that plane: the scale the margin is relative to.
    pub frustum_scale: f32,
    /// The near-plane distance of the view the object was tested against.
    pub view_near: f32,
}

impl Extent {
    /// The smallest relative distance of any deciding value to its threshold: the
    /// frustum margin, the far depth against the near plane, and the near and far depths
    /// against the slice boundaries `z_slice_start(1..dims.z)` (in f64). An object the
    /// GPU decides differently must have this under 1e-5.
    pub fn closeness(&self, grid: &ClusterGrid) -> f32 {
        if matches!(self.outcome, Outcome::Invalid) {
            // Decided by bits alone: never close.
            return f32::INFINITY;
        }
        let mut c = (self.frustum_margin.abs() / self.frustum_scale.max(self.bound)).max(0.0);
        if self.near_depth.is_finite() && self.far_depth.is_finite() {
            let span = self
                .far_depth
                .abs()
                .max(self.view_near.abs())
                .max(f32::MIN_POSITIVE);
            c = c.min((self.far_depth - self.view_near).abs() / span);
            for depth in [self.near_depth, self.far_depth] {
                c = c.min(slice_boundary_closeness(grid, depth));
            }
        }
        c
    }
}

/// Relative distance of `depth` to the nearest internal slice boundary.
pub fn slice_boundary_closeness(grid: &ClusterGrid, depth: f32) -> f32 {
    if grid.dims[2] < 2 || depth <= 0.0 {
        return f32::INFINITY;
    }
    let (scale, bias) = (grid.z_slice_scale as f64, grid.z_slice_bias as f64);
    let t = (depth as f64).log2() * scale + bias;
    let s = t.round().clamp(1.0, grid.dims[2] as f64 - 1.0);
    let boundary = ((s - bias) / scale).exp2();
    ((depth as f64 - boundary).abs() / boundary) as f32
}

fn is_finite(x: f32) -> bool {
    x.to_bits() & 0x7f80_0000 != 0x7f80_0000
}

fn is_finite3(v: [f32; 3]) -> bool {
    v.iter().all(|&x| is_finite(x))
}

/// `sector_reach` of the WGSL.
pub fn sector_reach(range: f32, cos_to_axis: f32, cos_angle: f32, sin_angle: f32) -> f32 {
    if cos_to_axis >= cos_angle {
        return range;
    }
    let sin_to_axis = (1.0 - cos_to_axis * cos_to_axis).max(0.0).sqrt();
    (range * (cos_to_axis * cos_angle + sin_to_axis * sin_angle)).max(0.0)
}

/// `object_extent` of the WGSL, with the deciding values for [`Extent::closeness`].
pub fn object_extent(view: &View, grid: &ClusterGrid, object: &ClusterableObject) -> Extent {
    let mut extent = Extent {
        outcome: Outcome::Invalid,
        near_depth: 0.0,
        far_depth: 0.0,
        bound: 0.0,
        frustum_margin: 0.0,
        frustum_scale: 0.0,
        view_near: view.near,
    };
    let [px, py, pz, range] = object.position_range;
    let p = [px, py, pz];
    let range_bits = range.to_bits();
    let magnitude = range_bits & 0x7fff_ffff;
    let is_nan = magnitude > 0x7f80_0000;
    let is_negative = range_bits != magnitude && magnitude != 0;
    if object.kind >= ClusterableKind::COUNT || !is_finite3(p) || is_nan || is_negative {
        return extent;
    }
    let m = &view.view;
    let spot = object.kind == ClusterableKind::SpotLight as u32;
    let mut axis_z = 0.0f32;
    if spot || object.kind == ClusterableKind::Decal as u32 {
        let [dx, dy, dz, cos_angle] = object.direction_cos_angle;
        if !is_finite3([dx, dy, dz]) || dx * dx + dy * dy + dz * dz < MIN_DIRECTION_SQUARED {
            return extent;
        }
        if spot && !(is_finite(cos_angle) && is_finite(object.sin_angle)) {
            return extent;
        }
        let v: [f32; 3] = std::array::from_fn(|i| m[0][i] * dx + m[1][i] * dy + m[2][i] * dz);
        axis_z = v[2] / (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    }
    extent.outcome = Outcome::Culled;
    if magnitude == 0 {
        return extent;
    }
    let range = range.min(RANGE_LIMIT);
    let mut bound = range;
    let mut reach_near = range;
    let mut reach_far = range;
    if spot {
        let cos_angle = object.direction_cos_angle[3];
        reach_near = sector_reach(range, axis_z, cos_angle, object.sin_angle);
        reach_far = sector_reach(range, -axis_z, cos_angle, object.sin_angle);
    } else if object.kind == ClusterableKind::Probe as u32 {
        let reach = range * (m[0][2].abs() + m[1][2].abs() + m[2][2].abs());
        reach_near = reach;
        reach_far = reach;
        bound = range * SQRT_3;
    } else if object.kind == ClusterableKind::Decal as u32 {
        let across = (1.0 - axis_z * axis_z).max(0.0).sqrt();
        let reach = range * axis_z.abs() + range * SQRT_2 * across;
        reach_near = reach;
        reach_far = reach;
        bound = range * SQRT_3;
    }
    // `sphere_in_frustum`: outside when `dot(n, c) + w < -radius` for any plane.
    extent.bound = bound;
    extent.frustum_margin = f32::INFINITY;
    let mut inside = true;
    for plane in &view.frustum {
        let d = plane[0] * p[0] + plane[1] * p[1] + plane[2] * p[2];
        if d + plane[3] < -bound {
            inside = false;
        }
        let margin = d + plane[3] + bound;
        if margin.abs() < extent.frustum_margin.abs() {
            extent.frustum_margin = margin;
            extent.frustum_scale = d.abs() + plane[3].abs();
        }
    }
    if !inside {
        return extent;
    }
    let depth = -(m[0][2] * p[0] + m[1][2] * p[1] + m[2][2] * p[2] + m[3][2]);
    let far_depth = depth + reach_far;
    extent.near_depth = depth - reach_near;
    extent.far_depth = far_depth;
    if far_depth < view.near {
        return extent;
    }
    let first = z_slice_of_depth(grid, extent.near_depth);
    let last = z_slice_of_depth(grid, far_depth).max(first);
    extent.outcome = Outcome::Visible { first, last };
    extent
}

/// What the pass leaves in its outputs, less the order of the list.
#[derive(Clone, Debug, PartialEq)]
pub struct ZSliceResult {
    /// Every (object, slice) pair, in object order, capacity ignored.
    pub pairs: Vec<SliceInstance>,
    /// `slice_counts` (see the crate docs).
    pub counts: [u32; COUNT_WORDS],
    /// `slice_draw_args`: `[quad_vertices, instances written, 0, 0]`.
    pub draw_args: [u32; 4],
    /// `slice_dispatch_args`: `[x, y, 1]`.
    pub dispatch_args: [u32; 3],
}

/// Instances per workgroup in the dispatch arguments (`INSTANCES_PER_GROUP`).
pub const INSTANCES_PER_GROUP: u32 = 64;

/// `fold_dispatch` of the WGSL: `groups` workgroups as `[x, y, 1]` under the limit.
pub fn fold_dispatch(groups: u32, max_per_dimension: u32) -> [u32; 3] {
    meshlight_shaders::cpu::dispatch::fold_dispatch(groups, max_per_dimension)
}

/// The whole pass over `objects` with a list of `capacity` entries.
pub fn cpu_z_slice(
    view: &View,
    grid: &ClusterGrid,
    objects: &[ClusterableObject],
    capacity: u32,
    quad_vertices: u32,
    max_per_dimension: u32,
) -> ZSliceResult {
    let mut counts = [0u32; COUNT_WORDS];
    counts[WORD_CAPACITY] = capacity;
    let mut pairs = Vec::new();
    for (i, object) in objects.iter().enumerate() {
        match object_extent(view, grid, object).outcome {
            Outcome::Invalid => counts[WORD_INVALID] += 1,
            Outcome::Culled => counts[WORD_CULLED] += 1,
            Outcome::Visible { first, last } => {
                counts[WORD_VISIBLE + object.kind as usize] += 1;
                counts[WORD_REQUESTED] += last - first + 1;
                pairs.extend((first..=last).map(|slice| SliceInstance {
                    object: i as u32,
                    slice,
                }));
            }
        }
    }
    let written = counts[WORD_REQUESTED].min(capacity);
    ZSliceResult {
        pairs,
        counts,
        draw_args: [quad_vertices, written, 0, 0],
        dispatch_args: fold_dispatch(written.div_ceil(INSTANCES_PER_GROUP), max_per_dimension),
    }
}
