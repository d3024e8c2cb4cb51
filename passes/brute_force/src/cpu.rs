//! The reference: the same draw on the CPU, with the pass's conventions (the shaders'
//! clip position, reverse-Z depth cleared to 0 with a `Greater` test, instance-major
//! draw order, `instance + 1` ids) and `hw_raster`'s float rasteriser for coverage (pixel
//! centres, top-left rule, counter-clockwise front faces in NDC, NDC depth interpolated
//! linearly in screen space, edge functions in f64). It differs from the hardware only
//! where the hardware's sub-pixel rounding moves an edge across a pixel centre, which
//! the GPU test bounds.

use crate::{EMPTY_ID, instance_id};
use glam::{Mat4, Vec3};
use meshlight_pass_hw_raster::cpu::{clip_position, cover_triangle};
use meshlight_shaders::cpu::layout::{Instance, View};

/// The two targets after the pass, row-major `width` × `height`.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Columns of both targets.
    pub width: u32,
    /// Rows of both targets.
    pub height: u32,
    /// Reverse-Z NDC depth of the nearest surface; 0 where empty.
    pub depth: Vec<f32>,
    /// [`instance_id`] of the nearest surface; [`EMPTY_ID`] where empty.
    pub ids: Vec<u32>,
    /// Triangles left out because a corner lies outside the depth range (`w <= 0`,
    /// `z > w` nearer than the near plane, `z < 0` beyond a finite far plane): the
    /// hardware clips those, this reference does not, so scenes compared with it keep
    /// this at 0.
    pub clipped_triangles: u64,
}

impl Image {
    /// Pixels some triangle covers.
    pub fn covered(&self) -> usize {
        self.ids.iter().filter(|&&id| id != EMPTY_ID).count()
    }
}

/// Draws `indices` (three per triangle, into `positions`, mesh space) once per instance
/// of `instances`, in instance order, as the pass does for a `width` × `height` viewport.
/// Indices past the end of `positions` leave their triangle out.
pub fn draw(
    positions: &[[f32; 4]],
    indices: &[u32],
    instances: &[Instance],
    view: &View,
    width: u32,
    height: u32,
) -> Image {
    let pixels = width as usize * height as usize;
    let mut image = Image {
        width,
        height,
        depth: vec![0.0; pixels],
        ids: vec![EMPTY_ID; pixels],
        clipped_triangles: 0,
    };
    let view_projection = Mat4::from_cols_array_2d(&view.view_projection);
    let size = [width as f64, height as f64];
    for (i, instance) in instances.iter().enumerate() {
        let id = instance_id(i as u32);
        let world_from_local = Mat4::from_cols_array_2d(&instance.world_from_local);
        // Pixels (y down) and NDC depth of every vertex, or None where the hardware
        // would clip.
        let screen: Vec<Option<([f64; 2], f64)>> = positions
            .iter()
            .map(|p| {
                let c = clip_position(
                    &world_from_local,
                    &view_projection,
                    Vec3::new(p[0], p[1], p[2]),
                );
                let (x, y, z, w) = (c.x as f64, c.y as f64, c.z as f64, c.w as f64);
                (w > 0.0 && (0.0..=w).contains(&z)).then(|| {
                    (
                        [(x / w * 0.5 + 0.5) * size[0], (0.5 - y / w * 0.5) * size[1]],
                        z / w,
                    )
                })
            })
            .collect();
        for t in indices.chunks_exact(3) {
            let corners = [t[0], t[1], t[2]].map(|k| screen.get(k as usize).copied());
            // An index past the end of `positions`.
            let [Some(a), Some(b), Some(c)] = corners else {
                continue;
            };
            // A corner the hardware would clip.
            let [Some(a), Some(b), Some(c)] = [a, b, c] else {
                image.clipped_triangles += 1;
                continue;
            };
            cover_triangle([a, b, c], width, height, |x, y, depth| {
                let at = (y * width + x) as usize;
                if depth > image.depth[at] {
                    image.depth[at] = depth;
                    image.ids[at] = id;
                }
            });
        }
    }
    image
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A camera at the origin looking down -z, 90° vertical field of view, near 1, for
    /// a square viewport: the plane z = -d shows x, y in -d..d.
    fn view(size: u32) -> View {
        let projection = glam::camera::rh::proj::directx::perspective_infinite_reverse(
            90f32.to_radians(),
            1.0,
            1.0,
        );
        View {
            view_projection: projection.to_cols_array_2d(),
            viewport_size: [size as f32; 2],
            ..Default::default()
        }
    }

    fn at(translation: Vec3, scale: f32) -> Instance {
        let m = Mat4::from_translation(translation) * Mat4::from_scale(Vec3::splat(scale));
        Instance {
            world_from_local: m.to_cols_array_2d(),
            ..Default::default()
        }
    }

    /// A square -1..1 in x and y at z = 0, counter-clockwise seen from +z.
    fn quad() -> (Vec<[f32; 4]>, Vec<u32>) {
        let p = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]
            .map(|[x, y]| [x, y, 0.0, 1.0])
            .to_vec();
        (p, vec![0, 1, 2, 0, 2, 3])
    }

    #[test]
    fn the_nearer_instance_wins_whatever_the_order() {
        let (p, i) = quad();
        let v = view(16);
        // Instance 0 at distance 2 covers the middle half of the screen; instance 1,
        // twice as large at distance 1.25 and offset right, the whole right half.
        let far = at(Vec3::new(0.0, 0.0, -2.0), 1.0);
        let near = at(Vec3::new(2.0, 0.0, -1.25), 2.0);
        let image = draw(&p, &i, &[far, near], &v, 16, 16);
        assert_eq!(image.clipped_triangles, 0);
        let swapped = draw(&p, &i, &[near, far], &v, 16, 16);
        for y in 0..16 {
            for x in 0..16 {
                let k = y * 16 + x;
                let in_far = (4..12).contains(&x) && (4..12).contains(&y);
                let in_near = x >= 8;
                let want = if in_near {
                    2
                } else if in_far {
                    1
                } else {
                    EMPTY_ID
                };
                assert_eq!(image.ids[k], want, "({x}, {y})");
                let other = [EMPTY_ID, 2, 1][want as usize];
                assert_eq!(swapped.ids[k], other, "swapped ({x}, {y})");
                assert_eq!(image.depth[k], swapped.depth[k]);
                // Reverse-Z with near 1: depth = near / distance.
                let d = [0.0, 0.5, 0.8][want as usize];
                assert!(
                    (image.depth[k] - d).abs() < 1e-6,
                    "({x}, {y}) {}",
                    image.depth[k]
                );
            }
        }
        assert_eq!(image.covered(), 8 * 16 + 4 * 8);
    }

    #[test]
    fn back_faces_and_clipped_triangles_draw_nothing() {
        let (p, mut i) = quad();
        let v = view(16);
        // Seen from behind: both triangles are back faces.
        i.swap(1, 2);
        i.swap(4, 5);
        let image = draw(&p, &i, &[at(Vec3::new(0.0, 0.0, -2.0), 1.0)], &v, 16, 16);
        assert_eq!(image.covered(), 0);
        assert_eq!(image.clipped_triangles, 0);
        // Nearer than the near plane: counted, not drawn.
        let (p, i) = quad();
        let image = draw(&p, &i, &[at(Vec3::new(0.0, 0.0, -0.5), 1.0)], &v, 16, 16);
        assert_eq!(image.covered(), 0);
        assert_eq!(image.clipped_triangles, 2);
    }
}
