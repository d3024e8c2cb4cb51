//! The reference of `meshlight::froxel`: which froxels a clusterable object touches. Each
//! function mirrors its WGSL namesake operation for operation.
//!
//! The GPU may fuse multiply-adds, and its `sqrt`, `exp2` and division are not correctly
//! rounded, so a test whose values lie within a hair of their threshold may go the other
//! way there. Each decision therefore carries a [`closeness`](Decision::closeness): the
//! distance of its deciding value from the threshold, relative to the magnitudes of the
//! numbers the test read. Tests allow the GPU to differ only where that is tiny.

use super::layout::{ClusterGrid, ClusterableKind, ClusterableObject, View};
use super::light::z_slice_start;

/// `FROXEL_FAR_END`: where the last slice's box ends.
pub const FROXEL_FAR_END: f32 = 1e15;
/// `FROXEL_RANGE_LIMIT`: ranges above this are this.
pub const FROXEL_RANGE_LIMIT: f32 = 1e30;

type Vec3 = [f32; 3];

fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn scale(a: Vec3, s: f32) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: Vec3, b: Vec3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn abs3(a: Vec3) -> Vec3 {
    a.map(f32::abs)
}
fn col(m: &[[f32; 4]; 4], i: usize) -> Vec3 {
    [m[i][0], m[i][1], m[i][2]]
}
fn max_abs(a: Vec3) -> f32 {
    a[0].abs().max(a[1].abs()).max(a[2].abs())
}

/// `view_point`: world → view for a point.
pub fn view_point(m: &[[f32; 4]; 4], p: Vec3) -> Vec3 {
    add(
        add(
            add(scale(col(m, 0), p[0]), scale(col(m, 1), p[1])),
            scale(col(m, 2), p[2]),
        ),
        col(m, 3),
    )
}

/// `view_direction`: world → view for a direction.
pub fn view_direction(m: &[[f32; 4]; 4], d: Vec3) -> Vec3 {
    add(
        add(scale(col(m, 0), d[0]), scale(col(m, 1), d[1])),
        scale(col(m, 2), d[2]),
    )
}

fn unit(v: Vec3) -> Vec3 {
    scale(v, 1.0 / (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())
}

/// `ViewObject`: an object in view space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewObject {
    /// The object's position, view space.
    pub center: Vec3,
    /// How far it reaches (a light's range, a box's half-extent).
    pub range: f32,
    /// Probes and decals: the box's half-axes; spot lights: the unit axis in `[2]`.
    pub axes: [Vec3; 3],
    /// `ClusterableKind` as its number, which picks the test.
    pub kind: u32,
    /// Spot lights: cosine of the half-angle.
    pub cos_angle: f32,
    /// Spot lights: sine of the half-angle.
    pub sin_angle: f32,
}

/// `view_object`.
pub fn view_object(view: &View, object: &ClusterableObject) -> ViewObject {
    let m = &view.view;
    let [px, py, pz, range] = object.position_range;
    let range = range.min(FROXEL_RANGE_LIMIT);
    let direction = [
        object.direction_cos_angle[0],
        object.direction_cos_angle[1],
        object.direction_cos_angle[2],
    ];
    let mut axes = [[0.0; 3]; 3];
    if object.kind == ClusterableKind::SpotLight as u32 {
        axes[2] = unit(view_direction(m, direction));
    } else if object.kind == ClusterableKind::Probe as u32 {
        axes = [0, 1, 2].map(|i| scale(col(m, i), range));
    } else if object.kind == ClusterableKind::Decal as u32 {
        let n = unit(direction);
        let s = if n[2] >= 0.0 { 1.0 } else { -1.0 };
        let a = -1.0 / (s + n[2]);
        let b = n[0] * n[1] * a;
        let t1 = [1.0 + s * n[0] * n[0] * a, s * b, -s * n[0]];
        let t2 = [b, s + n[1] * n[1] * a, -n[1]];
        axes = [t1, t2, n].map(|v| scale(view_direction(m, v), range));
    }
    ViewObject {
        center: view_point(m, [px, py, pz]),
        range,
        axes,
        kind: object.kind,
        cos_angle: object.direction_cos_angle[3],
        sin_angle: object.sin_angle,
    }
}

impl ViewObject {
    fn is_box(&self) -> bool {
        self.kind == ClusterableKind::Probe as u32 || self.kind == ClusterableKind::Decal as u32
    }

    /// `view_half_extent`.
    pub fn half_extent(&self) -> Vec3 {
        if self.is_box() {
            add(
                add(abs3(self.axes[0]), abs3(self.axes[1])),
                abs3(self.axes[2]),
            )
        } else {
            [self.range; 3]
        }
    }
}

/// `froxel_depths`: where slice `slice`'s box begins and ends.
pub fn froxel_depths(view: &View, grid: &ClusterGrid, slice: u32) -> [f32; 2] {
    let z0 = if slice > 0 {
        z_slice_start(grid, slice)
    } else {
        view.near
    };
    let z1 = if slice + 1 < grid.dims[2] {
        z_slice_start(grid, slice + 1)
    } else {
        FROXEL_FAR_END
    };
    [z0, z1]
}

fn unproject(view: &View, ndc: [f32; 2], depth: f32) -> Vec3 {
    let ip = &view.inverse_projection;
    let p: [f32; 4] = std::array::from_fn(|i| {
        ip[0][i] * ndc[0] + ip[1][i] * ndc[1] + ip[2][i] * depth + ip[3][i]
    });
    [p[0] / p[3], p[1] / p[3], p[2] / p[3]]
}

/// `pixel_line`: the view-space points of a pixel at NDC depth 1 and 0.5.
pub fn pixel_line(view: &View, pixel: [f32; 2]) -> [Vec3; 2] {
    let uv = [
        pixel[0] * view.inverse_viewport_size[0],
        pixel[1] * view.inverse_viewport_size[1],
    ];
    let ndc = [uv[0] * 2.0 + -1.0, uv[1] * -2.0 + 1.0];
    [unproject(view, ndc, 1.0), unproject(view, ndc, 0.5)]
}

/// `line_at_depth`.
pub fn line_at_depth(line: [Vec3; 2], depth: f32) -> Vec3 {
    let [a, b] = line;
    let t = (depth + a[2]) / (a[2] - b[2]);
    add(a, scale(sub(b, a), t))
}

/// `Aabb`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// The smallest corner, view space.
    pub min: Vec3,
    /// The largest corner, view space.
    pub max: Vec3,
}

/// `froxel_aabb`: the view-space box of froxel `(x, y, slice)`.
pub fn froxel_aabb(view: &View, grid: &ClusterGrid, froxel: [u32; 3]) -> Aabb {
    let tile_min = [
        froxel[0] as f32 * grid.tile_size[0],
        froxel[1] as f32 * grid.tile_size[1],
    ];
    let tile_max = [
        (tile_min[0] + grid.tile_size[0]).min(view.viewport_size[0]),
        (tile_min[1] + grid.tile_size[1]).min(view.viewport_size[1]),
    ];
    let [z0, z1] = froxel_depths(view, grid, froxel[2]);
    let mut lo = [3.4e38f32; 3];
    let mut hi = [-3.4e38f32; 3];
    for corner in 0..4 {
        let pixel = [
            if corner & 1 != 0 {
                tile_max[0]
            } else {
                tile_min[0]
            },
            if corner & 2 != 0 {
                tile_max[1]
            } else {
                tile_min[1]
            },
        ];
        let line = pixel_line(view, pixel);
        let (p0, p1) = (line_at_depth(line, z0), line_at_depth(line, z1));
        for i in 0..3 {
            lo[i] = lo[i].min(p0[i].min(p1[i]));
            hi[i] = hi[i].max(p0[i].max(p1[i]));
        }
    }
    Aabb { min: lo, max: hi }
}

/// `TileRect`, both corners inclusive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileRect {
    /// The first tile, `[x, y]`.
    pub min: [u32; 2],
    /// The last tile, `[x, y]` (inclusive).
    pub max: [u32; 2],
}

impl TileRect {
    /// The rectangle of no tiles (`min.x > max.x`), what an object that misses the slice gets.
    pub const EMPTY: TileRect = TileRect {
        min: [1, 0],
        max: [0, 0],
    };
    /// Whether the rectangle holds no tile.
    pub fn is_empty(&self) -> bool {
        self.min[0] > self.max[0] || self.min[1] > self.max[1]
    }
    /// The tiles, row by row.
    pub fn tiles(&self) -> impl Iterator<Item = [u32; 2]> + '_ {
        let rows = if self.is_empty() {
            0..0
        } else {
            self.min[1]..self.max[1] + 1
        };
        rows.flat_map(move |y| (self.min[0]..=self.max[0]).map(move |x| [x, y]))
    }
}

/// A decision and how close its deciding value came to the threshold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Decision {
    /// The decision.
    pub value: bool,
    /// `|value − threshold| / scale`: under about 1e-5 the GPU may decide otherwise.
    pub closeness: f32,
}

impl Decision {
    /// `lhs <= rhs`, relative to `scale`.
    fn at_most(lhs: f32, rhs: f32, scale: f32) -> Self {
        Decision {
            value: lhs <= rhs,
            closeness: (lhs - rhs).abs() / scale.max(f32::MIN_POSITIVE),
        }
    }
    /// Both: the closer of two trues, the farther of the falses (a robust false decides).
    fn and(self, other: Decision) -> Decision {
        match (self.value, other.value) {
            (true, true) => Decision {
                value: true,
                closeness: self.closeness.min(other.closeness),
            },
            (false, false) => Decision {
                value: false,
                closeness: self.closeness.max(other.closeness),
            },
            (false, true) => self,
            (true, false) => other,
        }
    }
    fn not(self) -> Decision {
        Decision {
            value: !self.value,
            ..self
        }
    }
}

/// `froxel_rect`: the tiles an instance of `o` in slice `slice` walks, and how close the
/// rectangle's edges came to a tile boundary (or the depth cut to emptiness), relative to
/// the viewport.
pub fn froxel_rect(view: &View, grid: &ClusterGrid, o: &ViewObject, slice: u32) -> (TileRect, f32) {
    let [z0, z1] = froxel_depths(view, grid, slice);
    let half = o.half_extent();
    let depth = -o.center[2];
    let z_lo = z0.max(view.near).max(depth - half[2]);
    let z_hi = z1.min(depth + half[2]);
    let cut = Decision::at_most(z_lo, z_hi, z_lo.abs().max(z_hi.abs()) + half[2]);
    if !cut.value {
        return (TileRect::EMPTY, cut.closeness);
    }
    let lo = [o.center[0] - half[0], o.center[1] - half[1]];
    let hi = [o.center[0] + half[0], o.center[1] + half[1]];
    let p = &view.projection;
    let mut pixel_lo = [3.4e38f32; 2];
    let mut pixel_hi = [-3.4e38f32; 2];
    for corner in 0..8 {
        let x = if corner & 1 != 0 { hi[0] } else { lo[0] };
        let y = if corner & 2 != 0 { hi[1] } else { lo[1] };
        let z = -(if corner & 4 != 0 { z_hi } else { z_lo });
        let clip: [f32; 4] =
            std::array::from_fn(|i| p[0][i] * x + p[1][i] * y + p[2][i] * z + p[3][i]);
        let ndc = [clip[0] / clip[3], clip[1] / clip[3]];
        let pixel = [
            (ndc[0] * 0.5 + 0.5) * view.viewport_size[0],
            (ndc[1] * -0.5 + 0.5) * view.viewport_size[1],
        ];
        for i in 0..2 {
            pixel_lo[i] = pixel_lo[i].min(pixel[i]);
            pixel_hi[i] = pixel_hi[i].max(pixel[i]);
        }
    }
    let mut closeness = cut.closeness;
    let mut rect = TileRect::EMPTY;
    for i in 0..2 {
        let last = (grid.dims[i] - 1) as f32;
        let tile = |pixel: f32| (pixel / grid.tile_size[i]).floor().max(0.0).min(last);
        rect.min[i] = tile(pixel_lo[i]) as u32;
        rect.max[i] = tile(pixel_hi[i]) as u32;
        // A tile boundary inside the grid that an edge nearly touches.
        for pixel in [pixel_lo[i], pixel_hi[i]] {
            let boundary = (pixel / grid.tile_size[i]).round();
            if (1.0..=last).contains(&boundary) {
                let distance = (pixel - boundary * grid.tile_size[i]).abs();
                closeness = closeness.min(distance / (view.viewport_size[i] + pixel.abs()));
            }
        }
    }
    (rect, closeness)
}

/// `sphere_touches_aabb`.
pub fn sphere_touches_aabb(center: Vec3, radius: f32, aabb: &Aabb) -> Decision {
    let d: Vec3 = std::array::from_fn(|i| center[i] - center[i].clamp(aabb.min[i], aabb.max[i]));
    let magnitude = max_abs(center)
        .max(max_abs(aabb.min))
        .max(max_abs(aabb.max))
        + radius;
    let squared = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    // Compared as distances, so the closeness is linear in the coordinates.
    let decision = Decision::at_most(squared.sqrt(), radius, magnitude);
    Decision {
        value: squared <= radius * radius,
        ..decision
    }
}

/// `separates`.
fn separates(axis: Vec3, t: Vec3, e: Vec3, o: &ViewObject) -> Decision {
    let distance = (t[0] * axis[0] + t[1] * axis[1] + t[2] * axis[2]).abs();
    let froxel_reach = e[0] * axis[0].abs() + e[1] * axis[1].abs() + e[2] * axis[2].abs();
    let object_reach =
        dot(o.axes[0], axis).abs() + dot(o.axes[1], axis).abs() + dot(o.axes[2], axis).abs();
    let magnitude = (max_abs(t) + max_abs(e) + o.axes.iter().map(|a| max_abs(*a)).sum::<f32>())
        * (axis[0].abs() + axis[1].abs() + axis[2].abs());
    Decision::at_most(distance, froxel_reach + object_reach, magnitude).not()
}

/// `box_touches_aabb`: the fifteen separating axes.
pub fn box_touches_aabb(o: &ViewObject, aabb: &Aabb) -> Decision {
    let c = scale(add(aabb.min, aabb.max), 0.5);
    let e = scale(sub(aabb.max, aabb.min), 0.5);
    let t = sub(o.center, c);
    let mut axes = Vec::with_capacity(15);
    for k in 0..3 {
        let mut unit_axis = [0.0; 3];
        unit_axis[k] = 1.0;
        axes.push(unit_axis);
        axes.push(o.axes[k]);
    }
    for v in o.axes {
        axes.push([0.0, -v[2], v[1]]);
        axes.push([v[2], 0.0, -v[0]]);
        axes.push([-v[1], v[0], 0.0]);
    }
    let mut result = Decision {
        value: true,
        closeness: f32::INFINITY,
    };
    for axis in axes {
        // A zero axis (a cross product of parallel axes) separates nothing on either side.
        if axis == [0.0; 3] {
            continue;
        }
        result = result.and(separates(axis, t, e, o).not());
    }
    result
}

/// `cone_touches_sphere`.
pub fn cone_touches_sphere(o: &ViewObject, center: Vec3, radius: f32) -> Decision {
    let v = sub(center, o.center);
    let axis = o.axes[2];
    let along = v[0] * axis[0] + v[1] * axis[1] + v[2] * axis[2];
    let across = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2] - along * along)
        .max(0.0)
        .sqrt();
    let to_side = o.cos_angle * across - o.sin_angle * along;
    let magnitude = max_abs(center) + max_abs(o.center) + radius + o.range;
    Decision::at_most(to_side, radius, magnitude)
        .and(Decision::at_most(along, o.range + radius, magnitude))
        .and(Decision::at_most(-radius, along, magnitude))
}

/// `object_touches_froxel`.
pub fn object_touches_froxel(o: &ViewObject, aabb: &Aabb) -> Decision {
    if o.is_box() {
        return box_touches_aabb(o, aabb);
    }
    let sphere = sphere_touches_aabb(o.center, o.range, aabb);
    if !sphere.value || o.kind != ClusterableKind::SpotLight as u32 {
        return sphere;
    }
    let center = scale(add(aabb.min, aabb.max), 0.5);
    let h = scale(sub(aabb.max, aabb.min), 0.5);
    sphere.and(cone_touches_sphere(
        o,
        center,
        (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt(),
    ))
}

/// What one instance `(o, slice)` tests.
#[derive(Clone, Debug, PartialEq)]
pub struct InstanceFroxels {
    /// The tiles the instance covers.
    pub rect: TileRect,
    /// How close the rectangle's edges (or its depth cut) came to going otherwise.
    pub rect_closeness: f32,
    /// Every froxel walked, as `cluster_index`, in rectangle order, with its decision; on
    /// the rectangle's edge a true decision's closeness includes `rect_closeness`.
    pub tested: Vec<(u32, Decision)>,
}

impl InstanceFroxels {
    /// The froxels the object touches.
    pub fn touched(&self) -> impl Iterator<Item = u32> + '_ {
        self.tested.iter().filter(|(_, d)| d.value).map(|(f, _)| *f)
    }
}

/// The froxels instance `(o, slice)` walks and which of them it touches.
pub fn instance_froxels(
    view: &View,
    grid: &ClusterGrid,
    o: &ViewObject,
    slice: u32,
) -> InstanceFroxels {
    let (rect, rect_closeness) = froxel_rect(view, grid, o, slice);
    let tested = rect
        .tiles()
        .map(|[x, y]| {
            let mut decision = object_touches_froxel(o, &froxel_aabb(view, grid, [x, y, slice]));
            let on_edge =
                x == rect.min[0] || x == rect.max[0] || y == rect.min[1] || y == rect.max[1];
            if on_edge && decision.value {
                decision.closeness = decision.closeness.min(rect_closeness);
            }
            (super::light::cluster_index(grid, [x, y, slice]), decision)
        })
        .collect();
    InstanceFroxels {
        rect,
        rect_closeness,
        tested,
    }
}
