//! A procedural ground: a square heightfield of gentle hills, tessellated into a regular
//! grid and baked through the same meshlet LOD DAG as any mesh, so its far parts draw
//! from coarse levels and its hills occlude what lies behind them.
//!
//! Heights are fractal gradient noise written here (no tables, no transcendental
//! functions: only integer hashing and f32 adds and multiplies in a fixed order), so the
//! same [`Terrain`] gives the same bytes on every machine. [`Terrain::surface_height`]
//! is the height of the triangulated LOD-0 surface itself, which is what objects placed
//! on the ground must stand on: the noise between two grid vertices is not drawn.

use glam::{Vec2, Vec3};

use crate::error::SceneError;
use crate::mesh::Mesh;

/// A square of heightfield on the x–z plane, +y up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Terrain {
    /// The corner of least x and z, world units.
    pub origin: Vec2,
    /// Side of the square, world units.
    pub size: f32,
    /// Grid cells per side: `2 · cells²` triangles.
    pub cells: u32,
    /// Heights lie within about ±`amplitude` of 0 (the octaves' amplitudes sum to it).
    pub amplitude: f32,
    /// Wavelength of the first, broadest octave, world units.
    pub wavelength: f32,
    /// Octaves of noise, each half the wavelength and half the amplitude of the one
    /// before.
    pub octaves: u32,
    /// Seed of the noise: terrains differing only in it have different hills, the same
    /// on every machine.
    pub seed: u32,
    /// Texture coordinates per world unit (`uv = (x, z) · uv_scale`).
    pub uv_scale: f32,
    /// A calm spot, e.g. where a camera stands: within `calm_radius` of `calm_centre`
    /// the ground is flat at height 0, and the hills rise to their full height by three
    /// times that distance (a smoothstep). 0: no calm spot.
    pub calm_centre: Vec2,
    /// Radius of the flat calm spot, world units.
    pub calm_radius: f32,
}

impl Terrain {
    /// Triangles of [`Terrain::mesh`].
    pub fn triangle_count(&self) -> u64 {
        2 * self.cells as u64 * self.cells as u64
    }

    /// The height at world `(x, z)` (defined everywhere, also off the square): the
    /// noise, faded out around the calm spot.
    pub fn height(&self, x: f32, z: f32) -> f32 {
        self.noise(x, z) * self.calm(x, z)
    }

    /// 0 within `calm_radius` of the calm spot, 1 from three times that on.
    fn calm(&self, x: f32, z: f32) -> f32 {
        if self.calm_radius <= 0.0 {
            return 1.0;
        }
        let d = (Vec2::new(x, z) - self.calm_centre).length();
        let t = ((d - self.calm_radius) / (2.0 * self.calm_radius)).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    }

    /// Fractal gradient noise, about ±`amplitude`.
    fn noise(&self, x: f32, z: f32) -> f32 {
        let octaves = self.octaves.max(1);
        // Amplitudes 1, 1/2, 1/4, … scaled so that they sum to `amplitude`.
        let norm = self.amplitude / (2.0 - 0.5f32.powi(octaves as i32 - 1));
        let mut frequency = 1.0 / self.wavelength;
        let mut weight = norm;
        let mut sum = 0.0;
        for octave in 0..octaves {
            let seed = self.seed.wrapping_add(octave.wrapping_mul(0x9e37_79b9));
            // Gradient noise peaks near ±0.7; doubled so each octave spans about ±1.4·weight
            // at its extremes and ±weight typically.
            sum += weight * 2.0 * gradient_noise(x * frequency, z * frequency, seed);
            frequency *= 2.0;
            weight *= 0.5;
        }
        sum
    }

    /// World `(x, z)` of grid vertex `(i, j)`: `i` along x, `j` along z.
    pub fn vertex_xz(&self, i: u32, j: u32) -> Vec2 {
        let step = self.size / self.cells as f32;
        self.origin + Vec2::new(i as f32 * step, j as f32 * step)
    }

    /// The height of the drawn LOD-0 surface at world `(x, z)`: the grid cell's two
    /// triangles interpolate the noise at its corners. Clamped to the square's edge
    /// outside it.
    pub fn surface_height(&self, x: f32, z: f32) -> f32 {
        let cells = self.cells.max(1);
        let step = self.size / cells as f32;
        let u = ((x - self.origin.x) / step).clamp(0.0, cells as f32);
        let v = ((z - self.origin.y) / step).clamp(0.0, cells as f32);
        let (i, j) = ((u as u32).min(cells - 1), (v as u32).min(cells - 1));
        let (fx, fz) = (u - i as f32, v - j as f32);
        let h = |di: u32, dj: u32| {
            let p = self.vertex_xz(i + di, j + dj);
            self.height(p.x, p.y)
        };
        let (h00, h01, h10, h11) = (h(0, 0), h(0, 1), h(1, 0), h(1, 1));
        // The diagonal runs from (i, j) to (i + 1, j + 1), as in `mesh`.
        if fz >= fx {
            h00 + fz * (h01 - h00) + fx * (h11 - h01)
        } else {
            h00 + fx * (h10 - h00) + fz * (h11 - h10)
        }
    }

    /// Refuses a terrain the generator cannot make, naming the field to change.
    pub fn check(&self) -> Result<(), SceneError> {
        let bad = |what: String| Err(SceneError::InvalidOption(format!("terrain: {what}")));
        if self.cells == 0 {
            return bad("`cells` must be at least 1".into());
        }
        let finite = [
            self.origin.x,
            self.origin.y,
            self.size,
            self.amplitude,
            self.wavelength,
            self.uv_scale,
            self.calm_centre.x,
            self.calm_centre.y,
            self.calm_radius,
        ]
        .iter()
        .all(|v| v.is_finite());
        if !finite {
            return bad(format!("every number must be finite, got {self:?}"));
        }
        if self.size <= 0.0 || self.wavelength <= 0.0 {
            return bad(format!(
                "`size` and `wavelength` must be > 0, got {} and {}",
                self.size, self.wavelength
            ));
        }
        if self.amplitude < 0.0 {
            return bad(format!(
                "`amplitude` must not be negative, got {}",
                self.amplitude
            ));
        }
        let side = self.cells as u64 + 1;
        Mesh::check_limits("terrain", side * side, self.triangle_count())
    }

    /// The grid as a mesh: `(cells + 1)²` vertices, counter-clockwise seen from +y,
    /// smooth normals, UVs from x and z.
    pub fn mesh(&self) -> Result<Mesh, SceneError> {
        self.check()?;
        let side = self.cells + 1;
        let mut positions = Vec::with_capacity(side as usize * side as usize);
        let mut uvs = Vec::with_capacity(positions.capacity());
        for j in 0..side {
            for i in 0..side {
                let p = self.vertex_xz(i, j);
                positions.push(Vec3::new(p.x, self.height(p.x, p.y), p.y));
                uvs.push([p.x * self.uv_scale, p.y * self.uv_scale]);
            }
        }
        let mut indices = Vec::with_capacity(self.triangle_count() as usize * 3);
        let v = |i: u32, j: u32| j * side + i;
        for j in 0..self.cells {
            for i in 0..self.cells {
                let (v00, v10, v01, v11) = (v(i, j), v(i + 1, j), v(i, j + 1), v(i + 1, j + 1));
                indices.extend_from_slice(&[v00, v01, v11, v00, v11, v10]);
            }
        }
        let mut mesh = Mesh {
            source: format!(
                "procedural terrain ({} cells, {} triangles)",
                self.cells,
                self.triangle_count()
            ),
            positions,
            normals: Vec::new(),
            uvs,
            colors: Vec::new(),
            indices,
            materials: Vec::new(),
        };
        mesh.generate_normals();
        Ok(mesh)
    }
}

/// lowbias32: a well-mixed 32-bit hash.
pub(crate) fn hash(mut h: u32) -> u32 {
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846c_a68b);
    h ^= h >> 16;
    h
}

/// Eight unit gradients, so no `sin`/`cos` is needed to pick one.
const GRADIENTS: [[f32; 2]; 8] = [
    [1.0, 0.0],
    [-1.0, 0.0],
    [0.0, 1.0],
    [0.0, -1.0],
    [
        std::f32::consts::FRAC_1_SQRT_2,
        std::f32::consts::FRAC_1_SQRT_2,
    ],
    [
        -std::f32::consts::FRAC_1_SQRT_2,
        std::f32::consts::FRAC_1_SQRT_2,
    ],
    [
        std::f32::consts::FRAC_1_SQRT_2,
        -std::f32::consts::FRAC_1_SQRT_2,
    ],
    [
        -std::f32::consts::FRAC_1_SQRT_2,
        -std::f32::consts::FRAC_1_SQRT_2,
    ],
];

/// Gradient noise: a hashed unit gradient at each lattice point, its dot product with
/// the offset to `(x, z)`, blended with the quintic fade (continuous slope, so shading
/// shows no lattice). Zero at lattice points; within about ±0.71.
fn gradient_noise(x: f32, z: f32, seed: u32) -> f32 {
    let (x0, z0) = (x.floor(), z.floor());
    let (fx, fz) = (x - x0, z - z0);
    let (ix, iz) = (x0 as i32, z0 as i32);
    let corner = |dx: i32, dz: i32| {
        let key = (ix.wrapping_add(dx) as u32)
            .wrapping_mul(0x8da6_b343)
            .wrapping_add((iz.wrapping_add(dz) as u32).wrapping_mul(0xd816_3841))
            ^ seed;
        let g = GRADIENTS[(hash(key) & 7) as usize];
        g[0] * (fx - dx as f32) + g[1] * (fz - dz as f32)
    };
    let fade = |t: f32| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    let (u, v) = (fade(fx), fade(fz));
    let a = corner(0, 0) + u * (corner(1, 0) - corner(0, 0));
    let b = corner(0, 1) + u * (corner(1, 1) - corner(0, 1));
    a + v * (b - a)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> Terrain {
        Terrain {
            origin: Vec2::new(-10.0, -5.0),
            size: 40.0,
            cells: 16,
            amplitude: 3.0,
            wavelength: 20.0,
            octaves: 4,
            seed: 7,
            uv_scale: 0.25,
            calm_centre: Vec2::ZERO,
            calm_radius: 0.0,
        }
    }

    #[test]
    fn the_mesh_is_the_grid_of_heights_facing_up() {
        let t = small();
        let mesh = t.mesh().unwrap();
        assert_eq!(mesh.positions.len(), 17 * 17);
        assert_eq!(mesh.triangle_count() as u64, t.triangle_count());
        assert_eq!(mesh.uvs.len(), mesh.positions.len());
        for p in &mesh.positions {
            assert_eq!(p.y, t.height(p.x, p.z));
        }
        // Counter-clockwise seen from above: every face normal points up.
        for tri in mesh.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[tri[k] as usize]);
            assert!((b - a).cross(c - a).y > 0.0);
        }
        assert!(mesh.normals.iter().all(|n| n.y > 0.0));
        let (min, max) = mesh.bounds();
        assert_eq!((min.x, min.z, max.x, max.z), (-10.0, -5.0, 30.0, 35.0));
        // Hills, not a plane, and within the stated amplitude (with the noise's peaks).
        assert!(max.y - min.y > 1.0, "{min} {max}");
        assert!(max.y.abs().max(min.y.abs()) <= 1.5 * t.amplitude);
    }

    #[test]
    fn the_calm_spot_is_flat_and_the_hills_rise_around_it() {
        let t = Terrain {
            calm_centre: Vec2::new(5.0, 5.0),
            calm_radius: 4.0,
            ..small()
        };
        for (dx, dz) in [(0.0, 0.0), (3.9, 0.0), (-1.0, 2.5)] {
            assert_eq!(t.height(5.0 + dx, 5.0 + dz), 0.0);
        }
        // From three radii on, the hills are the uncalmed ones.
        let free = small();
        for p in [Vec2::new(-8.0, 20.0), Vec2::new(25.0, 30.0)] {
            assert_eq!(t.height(p.x, p.y), free.height(p.x, p.y));
        }
        // In between, calmer.
        let p = Vec2::new(5.0 + 8.0, 5.0);
        assert!(t.height(p.x, p.y).abs() < free.height(p.x, p.y).abs());
    }

    #[test]
    fn same_terrain_same_bytes_and_the_seed_changes_it() {
        let a = small().mesh().unwrap();
        assert_eq!(a, small().mesh().unwrap());
        let other = Terrain { seed: 8, ..small() }.mesh().unwrap();
        assert_ne!(a.positions, other.positions);
    }

    #[test]
    fn the_surface_height_interpolates_the_drawn_triangles() {
        let t = small();
        let mesh = t.mesh().unwrap();
        // At vertices it is the vertex height.
        for p in mesh.positions.iter().step_by(7) {
            assert!((t.surface_height(p.x, p.z) - p.y).abs() < 1e-4);
        }
        // Inside each triangle it lies on the triangle's plane.
        for (k, tri) in mesh.indices.chunks_exact(3).enumerate().step_by(5) {
            let [a, b, c] = [0, 1, 2].map(|i| mesh.positions[tri[i] as usize]);
            let w = [0.2 + 0.01 * (k % 7) as f32, 0.3, 0.0];
            let w = [w[0], w[1], 1.0 - w[0] - w[1]];
            let p = a * w[0] + b * w[1] + c * w[2];
            let h = t.surface_height(p.x, p.z);
            assert!((h - p.y).abs() < 1e-4, "triangle {k}: {h} vs {}", p.y);
        }
        // Between vertices the noise itself differs from the surface somewhere.
        let step = t.size / t.cells as f32;
        let off = (0..t.cells)
            .map(|i| t.vertex_xz(i, 3) + Vec2::splat(step * 0.5))
            .any(|p| (t.height(p.x, p.y) - t.surface_height(p.x, p.y)).abs() > 1e-3);
        assert!(off);
    }

    #[test]
    fn a_terrain_bakes_into_a_dag_that_meets_every_quality_target() {
        // An open grid (its border is a mesh boundary, unlike the closed procedural
        // knot) through the whole builder, with both groupings.
        use crate::verify::{quality, verify};
        use crate::{BuildOptions, Grouping, build_asset};
        let t = Terrain {
            cells: 48,
            ..small()
        };
        for grouping in [Grouping::Partition, Grouping::Metis] {
            let options = BuildOptions {
                grouping,
                ..BuildOptions::default()
            };
            let built = build_asset(&t.mesh().unwrap(), &options, &mut |_| {}).unwrap();
            let asset = &built.asset;
            let h = asset.header();
            assert_eq!(h.lod0_triangles as u64, t.triangle_count());
            let problems = verify(asset);
            assert!(problems.is_empty(), "{grouping:?}: {problems:#?}");
            assert!(
                crate::watertight::crack_problems(asset).is_empty(),
                "{grouping:?}"
            );
            let q = quality(asset);
            assert!(q.warnings.is_empty(), "{grouping:?}: {:#?}", q.warnings);
            assert!(q.worst_ratio <= 0.55 && q.total_ratio <= 2.1, "{q:?}");
            assert!((1..=3).contains(&h.root_count), "{} roots", h.root_count);
            assert!(h.level_count >= 3, "{} levels", h.level_count);
        }
    }

    #[test]
    fn bad_terrains_are_errors_naming_the_field() {
        for (t, field) in [
            (
                Terrain {
                    cells: 0,
                    ..small()
                },
                "`cells`",
            ),
            (
                Terrain {
                    size: 0.0,
                    ..small()
                },
                "`size`",
            ),
            (
                Terrain {
                    wavelength: -1.0,
                    ..small()
                },
                "`wavelength`",
            ),
            (
                Terrain {
                    amplitude: -1.0,
                    ..small()
                },
                "`amplitude`",
            ),
            (
                Terrain {
                    uv_scale: f32::NAN,
                    ..small()
                },
                "finite",
            ),
        ] {
            let e = t.mesh().unwrap_err().to_string();
            assert!(e.contains(field), "{e}");
        }
        let huge = Terrain {
            cells: 1 << 16,
            ..small()
        };
        assert!(matches!(huge.mesh(), Err(SceneError::TooLarge { .. })));
    }
}
