//! The reference: the hardware clusters drawn by a plain rasteriser on the CPU, with the
//! pass's conventions (slot ids, pixel centres, top-left rule, counter-clockwise front
//! faces in NDC, NDC depth interpolated linearly in screen space) but no fixed point:
//! edge functions in f64 at the exact pixel centres. It tells coverage and ids apart
//! from the hardware's sub-pixel rounding, which the GPU test bounds.

use glam::{Mat4, Vec2, Vec3, Vec4};
use meshlight_gpu_scene::{SceneData, surface};
use meshlight_scene::asset::format::{MeshletRecord, PayloadLayout};
use meshlight_scene::asset::triangles;
use meshlight_scene::compress::get_bits;
use meshlight_shaders::cpu::layout::{Cluster, MATERIAL_FLAG_DOUBLE_SIDED, Mesh, View};
use meshlight_shaders::cpu::visbuffer;
use std::ops::Range;

/// The slots instances `0..hw_count` draw: `C - hw_count .. C` (instance `j` draws
/// `C - 1 - j`), clamped to the capacity.
pub fn hardware_slots(capacity: u32, hw_count: u32) -> Range<u32> {
    capacity - hw_count.min(capacity)..capacity
}

/// A meshlet's mesh-space positions (grid decoded as the shader does: integer add, then
/// `origin + q * step`) and its triangles' local corners, read from the scene's payload.
pub fn decode_geometry(
    scene: &SceneData,
    mesh: &Mesh,
    m: &MeshletRecord,
) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let layout = PayloadLayout::of(m, mesh.flags);
    let start = (m.data_offset as usize).min(scene.payload.len());
    let data = &scene.payload[start..];
    let axis = m.axis_bits();
    let stride = m.vertex_stride() as usize;
    let grid = mesh.position_grid;
    let positions = (0..m.vertex_count() as usize)
        .map(|v| {
            let mut at = v * stride;
            let q = [0, 1, 2].map(|k| {
                let d = get_bits(data, at, axis[k]).unwrap_or(0);
                at += axis[k] as usize;
                m.grid_min[k].wrapping_add(d)
            });
            Vec3::new(
                grid[0] + q[0] as f32 * grid[3],
                grid[1] + q[1] as f32 * grid[3],
                grid[2] + q[2] as f32 * grid[3],
            )
        })
        .collect();
    let block = data.get(layout.triangles as usize..).unwrap_or(&[]);
    let (vc, tc) = (m.vertex_count(), m.triangle_count());
    let corners = (0..tc)
        .map(|t| triangles::decode(block, t, m.triangle_bits(), vc, tc))
        .collect();
    (positions, corners)
}

/// The clip-space position of a mesh-space point, with the shaders' operations.
pub fn clip_position(world_from_local: &Mat4, view_projection: &Mat4, p: Vec3) -> Vec4 {
    let world = *world_from_local * p.extend(1.0);
    *view_projection * world.truncate().extend(1.0)
}

/// Twice the signed area of (a, b, p) in y-down screen coordinates; positive when p lies
/// right of a→b as the screen shows it. A triangle counter-clockwise in NDC (y up), a
/// front face, has a negative area here.
pub fn edge(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

/// A top or left edge of a triangle of positive [`edge`] area on the y-down screen: a
/// horizontal edge going right, or an edge going up.
fn top_left(a: [f64; 2], b: [f64; 2]) -> bool {
    let d = [b[0] - a[0], b[1] - a[1]];
    d[1] < 0.0 || (d[1] == 0.0 && d[0] > 0.0)
}

/// Calls `f(x, y, depth)` for every pixel centre a screen triangle (pixels, NDC depth)
/// covers in a `width` × `height` viewport. Front faces are counter-clockwise in NDC
/// (negative [`edge`] area); back faces and degenerate triangles cover nothing.
pub fn cover_triangle(
    v: [([f64; 2], f64); 3],
    width: u32,
    height: u32,
    mut f: impl FnMut(u32, u32, f32),
) {
    // Swapping two corners makes a front face's area positive; the top-left rule is a
    // property of the edges, not of their direction, so it is unchanged.
    let [(p0, z0), (p2, z2), (p1, z1)] = v;
    let area = edge(p0, p1, p2);
    if area.is_nan() || area <= 0.0 {
        return;
    }
    let inside = |e: f64, a: [f64; 2], b: [f64; 2]| e > 0.0 || (e == 0.0 && top_left(a, b));
    let lo = |i: usize| (p0[i].min(p1[i]).min(p2[i]) - 0.5).ceil().max(0.0);
    let hi = |i: usize, n: u32| {
        (p0[i].max(p1[i]).max(p2[i]) - 0.5)
            .floor()
            .min(n as f64 - 1.0)
    };
    let (x0, x1, y0, y1) = (lo(0), hi(0, width), lo(1), hi(1, height));
    if x0 > x1 || y0 > y1 {
        return;
    }
    for y in y0 as u32..=y1 as u32 {
        for x in x0 as u32..=x1 as u32 {
            let p = [x as f64 + 0.5, y as f64 + 0.5];
            let (e0, e1, e2) = (edge(p1, p2, p), edge(p2, p0, p), edge(p0, p1, p));
            if inside(e0, p1, p2) && inside(e1, p2, p0) && inside(e2, p0, p1) {
                let depth = z0 + (e1 / area) * (z1 - z0) + (e2 / area) * (z2 - z0);
                f(x, y, depth as f32);
            }
        }
    }
}

/// The visibility buffer after the hardware pass: `initial` (what the software pass
/// left, row-major `width` × `height`) with the clusters of [`hardware_slots`]`(capacity,
/// hw_count)` of `raster_clusters` (capacity = its length) drawn over it by atomicMax,
/// each with its slot as visibility id; back faces are dropped unless the cluster's
/// material is double-sided, and pixels a MASK material cuts out
/// ([`surface::cut_out`], the pass's `alpha_mask`) are left as they were. Triangles with a corner at or behind the camera
/// plane (w <= 0), which the hardware clips, are left out: scenes given to this
/// reference lie in front of the near plane. Clusters naming a missing instance,
/// meshlet or mesh draw nothing.
pub fn rasterize(
    scene: &SceneData,
    view: &View,
    raster_clusters: &[Cluster],
    hw_count: u32,
    initial: &[u64],
    width: u32,
    height: u32,
) -> Vec<u64> {
    let mut out = initial.to_vec();
    out.resize(width as usize * height as usize, visbuffer::EMPTY);
    let view_projection = Mat4::from_cols_array_2d(&view.view_projection);
    let size = [width as f64, height as f64];
    for slot in hardware_slots(raster_clusters.len() as u32, hw_count) {
        let cluster = raster_clusters[slot as usize];
        let Some(instance) = scene.instances.get(cluster.instance as usize) else {
            continue;
        };
        let (Some(m), Some(mesh)) = (
            scene.meshlets.get(cluster.meshlet as usize),
            scene.meshes.get(instance.mesh as usize),
        ) else {
            continue;
        };
        let world_from_local = Mat4::from_cols_array_2d(&instance.world_from_local);
        let two_sided = scene
            .cluster_material(cluster.instance, cluster.meshlet)
            .is_some_and(|m| m.flags & MATERIAL_FLAG_DOUBLE_SIDED != 0);
        let (positions, corners) = decode_geometry(scene, mesh, m);
        let screen: Vec<Option<([f64; 2], f64)>> = positions
            .iter()
            .map(|&p| {
                let c = clip_position(&world_from_local, &view_projection, p);
                let (x, y, z, w) = (c.x as f64, c.y as f64, c.z as f64, c.w as f64);
                (w > 0.0).then(|| {
                    let ndc = [x / w, y / w];
                    (
                        [
                            (ndc[0] * 0.5 + 0.5) * size[0],
                            (0.5 - ndc[1] * 0.5) * size[1],
                        ],
                        z / w,
                    )
                })
            })
            .collect();
        for (t, c) in corners.iter().enumerate() {
            let v = c.map(|k| screen.get(k as usize).copied().flatten());
            let [Some(a), Some(b), Some(c)] = v else {
                continue;
            };
            // A two-sided back face (clockwise in NDC, positive area on the y-down
            // screen) is turned to face the eye, as raster.wgsl turns it.
            let turned = two_sided && edge(a.0, b.0, c.0) > 0.0;
            let corners = if turned { [a, c, b] } else { [a, b, c] };
            cover_triangle(corners, width, height, |x, y, depth| {
                let pixel = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let viewport = Vec2::new(width as f32, height as f32);
                if surface::cut_out(
                    scene,
                    &view.view_projection,
                    viewport,
                    &cluster,
                    t as u32,
                    pixel,
                ) {
                    return;
                }
                let px = &mut out[(y * width + x) as usize];
                *px = (*px).max(visbuffer::pack(depth, slot, t as u32));
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn covered(v: [[f64; 2]; 3], w: u32, h: u32) -> Vec<u32> {
        let mut out = vec![0; (w * h) as usize];
        cover_triangle(v.map(|p| (p, 0.5)), w, h, |x, y, _| {
            out[(y * w + x) as usize] += 1
        });
        out
    }

    #[test]
    fn slots_fill_from_the_right_end() {
        assert_eq!(hardware_slots(10, 3), 7..10);
        assert_eq!(hardware_slots(10, 0), 10..10);
        assert_eq!(hardware_slots(4, 9), 0..4);
    }

    #[test]
    fn shared_edges_cover_each_pixel_once_and_back_faces_nothing() {
        // A quad through pixel centres split along its diagonal, both halves
        // counter-clockwise in NDC (y up): every centre inside or on the quad's top and
        // left edges once.
        let (a, b, c, d) = ([1.5, 1.5], [6.5, 1.5], [6.5, 5.5], [1.5, 5.5]);
        let one = covered([a, c, b], 8, 8);
        let two = covered([a, d, c], 8, 8);
        for y in 0..8usize {
            for x in 0..8usize {
                let n = one[y * 8 + x] + two[y * 8 + x];
                let want = u32::from((1..6).contains(&x) && (1..5).contains(&y));
                assert_eq!(n, want, "pixel ({x}, {y})");
            }
        }
        assert!(covered([a, b, c], 8, 8).iter().all(|&n| n == 0));
    }

    #[test]
    fn depth_is_interpolated_linearly_in_screen_space() {
        let v = [([0.0, 0.0], 0.2), ([0.0, 8.0], 1.0), ([8.0, 0.0], 0.6)];
        cover_triangle(v, 8, 8, |x, y, depth| {
            let want = 0.2 + 0.4 * (x as f64 + 0.5) / 8.0 + 0.8 * (y as f64 + 0.5) / 8.0;
            assert!((depth as f64 - want).abs() < 1e-6, "({x}, {y})");
        });
    }
}
