//! The reference rasteriser: the WGSL kernel's steps on the CPU, in the same order and
//! with the same integer and float operations, producing the visibility buffer. Each
//! f32 operation here rounds once, as IEEE 754 says; the kernel makes its own do the
//! same on any driver (see the crate docs), which is what lets the test compare bits.

use glam::{Vec2, Vec4};
use meshlight_gpu_scene::{SceneData, surface};
use meshlight_scene::asset::format::PayloadLayout;
use meshlight_shaders::cpu::layout::{Cluster, MATERIAL_FLAG_DOUBLE_SIDED, View};
use meshlight_shaders::cpu::visbuffer;

/// Screen coordinates (pixels) at or beyond this make a vertex unusable; see the crate
/// docs for why it keeps every edge-function product inside i64.
pub const MAX_SCREEN: f32 = 1_048_576.0;

/// `count` bits from bit `bit` of the little-endian word pair, as `meshlight::math::read_bits`.
fn read_bits(words: [u32; 2], bit: u32, count: u32) -> u32 {
    let value = (u64::from(words[1]) << 32 | u64::from(words[0])) >> bit;
    if count >= 32 {
        value as u32
    } else {
        (value as u32) & ((1u32 << count) - 1)
    }
}

fn bits(word: u32, offset: u32, count: u32) -> u32 {
    (word >> offset) & ((1u32 << count) - 1)
}

fn word(payload: &[u32], i: u32) -> u32 {
    payload.get(i as usize).copied().unwrap_or(0)
}

/// Clip-space |x| and |y| up to `GUARD * w`: the guard band triangles are clipped to
/// (see the crate docs).
pub const GUARD: f32 = 63.0;

/// A vertex after the transform: 8-bit fixed-point screen position and NDC depth, or
/// `None` when it is behind the camera (w <= 0) or too far off screen.
pub type ScreenVertex = Option<([i32; 2], f32)>;

/// Signed distance of a clip-space position to clipping plane `k` (inside when >= 0):
/// 0 the near plane (depth z / w at most 1 in reverse Z), 1 to 4 the guard band's sides.
pub fn plane_distance(c: Vec4, k: usize) -> f32 {
    let band = GUARD * c.w;
    match k {
        0 => c.w - c.z,
        1 => band + c.x,
        2 => band - c.x,
        3 => band + c.y,
        _ => band - c.y,
    }
}

/// Inside every clipping plane (each [`plane_distance`] >= 0): the triangle is drawn
/// without clipping.
pub fn inside(c: Vec4) -> bool {
    let band = GUARD * c.w;
    c.w > 0.0 && c.z <= c.w && c.x.abs() <= band && c.y.abs() <= band
}

/// Where the edge from inside corner `a` to outside corner `b` crosses a plane; always
/// from the inside corner, so neighbours sharing the edge find the same point.
fn crossing(a: Vec4, b: Vec4, da: f32, db: f32) -> Vec4 {
    let t = da / (da - db);
    let d = b - a;
    Vec4::new(a.x + t * d.x, a.y + t * d.y, a.z + t * d.z, a.w + t * d.w)
}

/// A triangle clipped to the near plane and the guard band (Sutherland–Hodgman, planes
/// in that order): a convex polygon in the triangle's winding, empty when nothing is
/// left.
pub fn clip_triangle(corners: [Vec4; 3]) -> Vec<Vec4> {
    let mut poly = corners.to_vec();
    for k in 0..5 {
        let mut out = Vec::with_capacity(poly.len() + 1);
        for i in 0..poly.len() {
            let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
            let (dp, dq) = (plane_distance(p, k), plane_distance(q, k));
            if dp >= 0.0 {
                out.push(p);
                if dq < 0.0 {
                    out.push(crossing(p, q, dp, dq));
                }
            } else if dq >= 0.0 {
                out.push(crossing(q, p, dq, dp));
            }
        }
        if out.len() < 3 {
            return Vec::new();
        }
        poly = out;
    }
    poly
}

/// The snapped screen vertex of a clip-space position for a `size` pixel viewport.
pub fn snap(clip: Vec4, size: [f32; 2]) -> ScreenVertex {
    let ndc = clip.truncate() / clip.w;
    let s = [(ndc.x * 0.5 + 0.5) * size[0], (0.5 - ndc.y * 0.5) * size[1]];
    let ok = clip.w > 0.0 && s[0].abs() < MAX_SCREEN && s[1].abs() < MAX_SCREEN;
    // WGSL `round` rounds half to even.
    ok.then(|| {
        (
            [
                (s[0] * 256.0).round_ties_even() as i32,
                (s[1] * 256.0).round_ties_even() as i32,
            ],
            ndc.z,
        )
    })
}

/// Twice the signed area of (a, b, p): positive right of a→b on the y-down screen.
pub fn edge(a: [i32; 2], b: [i32; 2], p: [i32; 2]) -> i64 {
    i64::from(b[0] - a[0]) * i64::from(p[1] - a[1])
        - i64::from(b[1] - a[1]) * i64::from(p[0] - a[0])
}

/// A top or left edge of a clockwise (front-facing) triangle on the y-down screen.
pub fn top_left(a: [i32; 2], b: [i32; 2]) -> bool {
    let d = [b[0] - a[0], b[1] - a[1]];
    d[1] < 0 || (d[1] == 0 && d[0] > 0)
}

/// Calls `f(x, y, depth)` for every pixel of a `width` × `height` viewport a screen
/// triangle covers, with the top-left rule; back faces and degenerate triangles cover
/// nothing.
pub fn cover_triangle(
    v: [([i32; 2], f32); 3],
    width: u32,
    height: u32,
    mut f: impl FnMut(u32, u32, f32),
) {
    let [(p0, z0), (p1, z1), (p2, z2)] = v;
    let area = edge(p0, p1, p2);
    if area <= 0 || width == 0 || height == 0 {
        return;
    }
    let bias = [
        if top_left(p1, p2) { 0 } else { -1 },
        if top_left(p2, p0) { 0 } else { -1 },
        if top_left(p0, p1) { 0 } else { -1 },
    ];
    let mn = [p0[0].min(p1[0]).min(p2[0]), p0[1].min(p1[1]).min(p2[1])];
    let mx = [p0[0].max(p1[0]).max(p2[0]), p0[1].max(p1[1]).max(p2[1])];
    let lo = [
        ((mn[0] - 128 + 255) >> 8).max(0),
        ((mn[1] - 128 + 255) >> 8).max(0),
    ];
    let hi = [
        ((mx[0] - 128) >> 8).min(width as i32 - 1),
        ((mx[1] - 128) >> 8).min(height as i32 - 1),
    ];
    let fa = area as f32;
    let gradient = [(z1 - z0) / fa, (z2 - z0) / fa];
    for y in lo[1]..=hi[1] {
        for x in lo[0]..=hi[0] {
            let p = [x * 256 + 128, y * 256 + 128];
            let e0 = edge(p1, p2, p);
            let e1 = edge(p2, p0, p);
            let e2 = edge(p0, p1, p);
            if e0 + bias[0] < 0 || e1 + bias[1] < 0 || e2 + bias[2] < 0 {
                continue;
            }
            let depth = z0 + e1 as f32 * gradient[0] + e2 as f32 * gradient[1];
            f(x as u32, y as u32, depth);
        }
    }
}

/// `m * (p, 1)` for a column-major matrix, summed column by column in the order the
/// kernel writes it (`m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3]`), so that both round
/// alike; a matrix-vector product of a math library may sum in another order.
pub fn affine(m: &[[f32; 4]; 4], p: [f32; 3]) -> [f32; 4] {
    std::array::from_fn(|k| m[0][k] * p[0] + m[1][k] * p[1] + m[2][k] * p[2] + m[3][k])
}

/// One triangle of a cluster as the kernel rasterises it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenTriangle {
    /// The triangle's index in its meshlet (the visibility buffer's triangle field).
    pub index: u32,
    /// Snapped corners with NDC depth, ready for [`cover_triangle`]: the meshlet's
    /// corners (0, 2, 1), because the mesh's front faces are counter-clockwise in NDC
    /// (y up) and so counter-clockwise on the screen, while `cover_triangle` keeps
    /// clockwise ones.
    pub corners: [([i32; 2], f32); 3],
}

/// The triangles of `cluster` in meshlet order, for a `width` × `height` viewport: as
/// they are when every corner is inside the clip volume (see [`inside`]) and snaps,
/// else the pieces of the clipped polygon (several with one index). A cluster naming a
/// missing instance, meshlet or mesh has none.
pub fn screen_triangles(
    scene: &SceneData,
    view: &View,
    cluster: &Cluster,
    width: u32,
    height: u32,
) -> Vec<ScreenTriangle> {
    let (Some(instance), Some(m)) = (
        scene.instances.get(cluster.instance as usize),
        scene.meshlets.get(cluster.meshlet as usize),
    ) else {
        return Vec::new();
    };
    let Some(mesh) = scene.meshes.get(instance.mesh as usize) else {
        return Vec::new();
    };
    let size = [width as f32, height as f32];
    let grid = mesh.position_grid;
    let vertex_count = bits(m.counts, 0, 8);
    let triangle_count = bits(m.counts, 8, 8);
    let axis = [bits(m.bits, 0, 5), bits(m.bits, 5, 5), bits(m.bits, 10, 5)];
    let normal = [bits(m.normals, 24, 4), bits(m.normals, 28, 4)];
    let stride = axis.iter().sum::<u32>() + normal[0] + normal[1];
    let clip: Vec<Vec4> = (0..vertex_count)
        .map(|v| {
            let mut bit = v * stride;
            let mut q = [0u32; 3];
            for a in 0..3 {
                let w = m.data_offset + bit / 32;
                let offset = read_bits(
                    [word(&scene.payload, w), word(&scene.payload, w + 1)],
                    bit % 32,
                    axis[a],
                );
                q[a] = m.grid_min[a].wrapping_add(offset);
                bit += axis[a];
            }
            let p = [
                grid[0] + q[0] as f32 * grid[3],
                grid[1] + q[1] as f32 * grid[3],
                grid[2] + q[2] as f32 * grid[3],
            ];
            let world = affine(&instance.world_from_local, p);
            Vec4::from_array(affine(
                &view.view_projection,
                [world[0], world[1], world[2]],
            ))
        })
        .collect();
    // Usable as they are: snapped, and inside the clip volume.
    let screen: Vec<ScreenVertex> = clip
        .iter()
        .map(|&c| snap(c, size).filter(|_| inside(c)))
        .collect();
    // Where the triangle records start: the asset format's one definition of the layout.
    let triangle_word = m.data_offset + PayloadLayout::of(m, mesh.flags).triangles;
    let field_bits = [bits(m.bits, 24, 4), bits(m.bits, 28, 4)];
    let triangle_stride = field_bits[0] + 2 * field_bits[1];
    (0..triangle_count)
        .flat_map(|t| {
            let bit = t * triangle_stride;
            let w = triangle_word + bit / 32;
            let record = read_bits(
                [word(&scene.payload, w), word(&scene.payload, w + 1)],
                bit % 32,
                triangle_stride,
            );
            let predicted = (((t + 1) * vertex_count) / triangle_count.max(1)) as i32;
            let bias = 1i32 << (field_bits[0].max(1) - 1);
            let first = predicted + bits(record, 0, field_bits[0]) as i32 - bias;
            let d1 = bits(record, field_bits[0], field_bits[1]) as i32;
            let d2 = bits(record, field_bits[0] + field_bits[1], field_bits[1]) as i32;
            let last = vertex_count.max(1) as i32 - 1;
            let corners = [first, first - d2, first - d1].map(|c| c.clamp(0, last) as usize);
            if let [Some(Some(a)), Some(Some(b)), Some(Some(c))] =
                corners.map(|k| screen.get(k).copied())
            {
                return vec![ScreenTriangle {
                    index: t,
                    corners: [a, b, c],
                }];
            }
            let Some(corners) = corners
                .iter()
                .map(|&k| clip.get(k).copied())
                .collect::<Option<Vec<Vec4>>>()
            else {
                return Vec::new();
            };
            // Clipped in the meshlet's corner order, as the kernel clips.
            clipped_pieces(&clip_triangle([corners[0], corners[2], corners[1]]), size)
                .into_iter()
                .map(|corners| ScreenTriangle { index: t, corners })
                .collect()
        })
        .collect()
}

/// The fan of a polygon clipped from a triangle in the meshlet's corner order: pieces
/// (0, k + 1, k + 2), snapped and given to [`cover_triangle`] as (0, k + 2, k + 1), as
/// the kernel turns every triangle; pieces with a corner that does not snap (a viewport
/// past 16,384 pixels) are left out.
pub fn clipped_pieces(poly: &[Vec4], size: [f32; 2]) -> Vec<[([i32; 2], f32); 3]> {
    (0..poly.len().saturating_sub(2))
        .filter_map(|k| {
            Some([
                snap(poly[0], size)?,
                snap(poly[k + 2], size)?,
                snap(poly[k + 1], size)?,
            ])
        })
        .collect()
}

/// Whether `cluster` is drawn with a double-sided material (raster.wgsl's
/// `double_sided`): its back faces are turned to face the eye rather than dropped.
pub fn double_sided(scene: &SceneData, cluster: &Cluster) -> bool {
    scene
        .cluster_material(cluster.instance, cluster.meshlet)
        .is_some_and(|m| m.flags & MATERIAL_FLAG_DOUBLE_SIDED != 0)
}

/// `corners` as [`cover_triangle`] takes them, swapped where they are a back face (a
/// counter-clockwise, negative-area triangle on the y-down screen), as raster.wgsl's
/// `triangle_setup` turns a two-sided back face.
pub fn facing_the_eye(corners: [([i32; 2], f32); 3]) -> [([i32; 2], f32); 3] {
    let [a, b, c] = corners;
    if edge(a.0, b.0, c.0) < 0 {
        [a, c, b]
    } else {
        corners
    }
}

/// The visibility buffer (row-major, `width` × `height`, 0 = empty) of `clusters` drawn
/// from `scene` through `view`; the visibility cluster id is the index into `clusters`.
/// Clusters naming a missing instance or meshlet draw nothing. The pass's `two_sided`
/// and `alpha_mask` are both on: back faces of double-sided materials are turned, and
/// pixels a MASK material cuts out ([`surface::cut_out`]) are not written.
pub fn rasterize(
    scene: &SceneData,
    view: &View,
    clusters: &[Cluster],
    width: u32,
    height: u32,
) -> Vec<u64> {
    let mut out = vec![visbuffer::EMPTY; width as usize * height as usize];
    let size = Vec2::new(width as f32, height as f32);
    for (id, cluster) in clusters.iter().enumerate() {
        let two_sided = double_sided(scene, cluster);
        for tri in screen_triangles(scene, view, cluster, width, height) {
            let corners = if two_sided {
                facing_the_eye(tri.corners)
            } else {
                tri.corners
            };
            cover_triangle(corners, width, height, |x, y, depth| {
                let pixel = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                if surface::cut_out(
                    scene,
                    &view.view_projection,
                    size,
                    cluster,
                    tri.index,
                    pixel,
                ) {
                    return;
                }
                let px = &mut out[(y * width + x) as usize];
                *px = (*px).max(visbuffer::pack(depth, id as u32, tri.index));
            });
        }
    }
    out
}
