//! Meshes of the kinds users bring that the builder once refused, written the way
//! exporters write them (full-precision text, unwelded binary STL, GLB), so that the
//! tests go through the same loaders as `meshlight bake`.

use std::fmt::Write as _;

/// A UV sphere of `rings` × `segments` as an exporter writes one: a grid of
/// `(rings + 1) × (segments + 1)` vertices computed in double precision and printed at
/// full precision, so the seam column and every pole row are separate vertices whose
/// positions differ by about 1e-16 (sin(2π), sin(π)) rather than repeat bit for bit.
/// Texture coordinates follow the grid, so the seam is also a real UV seam.
pub struct Sphere {
    pub rings: u32,
    pub segments: u32,
    pub radius: f64,
    pub centre: [f64; 3],
}

impl Sphere {
    pub fn unit(rings: u32, segments: u32) -> Self {
        Self {
            rings,
            segments,
            radius: 1.0,
            centre: [0.0; 3],
        }
    }

    fn vertex(&self, r: u32, s: u32) -> [f64; 3] {
        let theta = std::f64::consts::PI * r as f64 / self.rings as f64;
        let phi = std::f64::consts::TAU * s as f64 / self.segments as f64;
        [
            self.centre[0] + self.radius * theta.sin() * phi.cos(),
            self.centre[1] + self.radius * theta.sin() * phi.sin(),
            self.centre[2] + self.radius * theta.cos(),
        ]
    }

    /// Appends the sphere to an OBJ text whose `v` lines so far number `base`; returns
    /// the new count. Quads are split in two, so the pole rows give slivers whose two
    /// pole corners differ by 1e-16.
    pub fn write_obj(&self, obj: &mut String, base: u32) -> u32 {
        let row = self.segments + 1;
        for r in 0..=self.rings {
            for s in 0..=self.segments {
                let [x, y, z] = self.vertex(r, s);
                let _ = writeln!(obj, "v {x:?} {y:?} {z:?}");
                let (u, v) = (
                    s as f64 / self.segments as f64,
                    r as f64 / self.rings as f64,
                );
                let _ = writeln!(obj, "vt {u:?} {v:?}");
            }
        }
        let id = |r: u32, s: u32| base + r * row + s + 1;
        for r in 0..self.rings {
            for s in 0..self.segments {
                let (a, b, c, d) = (id(r, s), id(r + 1, s), id(r + 1, s + 1), id(r, s + 1));
                let _ = writeln!(obj, "f {a}/{a} {b}/{b} {c}/{c}");
                let _ = writeln!(obj, "f {a}/{a} {c}/{c} {d}/{d}");
            }
        }
        base + (self.rings + 1) * row
    }

    pub fn obj(&self) -> String {
        let mut obj = String::new();
        self.write_obj(&mut obj, 0);
        obj
    }

    /// The sphere's triangles as corner positions in single precision.
    pub fn triangles(&self) -> Vec<[[f32; 3]; 3]> {
        let p = |r, s| self.vertex(r, s).map(|c| c as f32);
        let mut out = Vec::new();
        for r in 0..self.rings {
            for s in 0..self.segments {
                let (a, b, c, d) = (p(r, s), p(r + 1, s), p(r + 1, s + 1), p(r, s + 1));
                out.push([a, b, c]);
                out.push([a, c, d]);
            }
        }
        out
    }
}

/// Several spheres in one OBJ.
pub fn spheres_obj(spheres: &[Sphere]) -> String {
    let mut obj = String::new();
    let mut base = 0;
    for s in spheres {
        base = s.write_obj(&mut obj, base);
    }
    obj
}

/// A deterministic hash of `i` into 0..1.
pub fn hash01(i: u32, salt: u32) -> f32 {
    let mut x = i.wrapping_mul(0x9e37_79b9) ^ salt.wrapping_mul(0x85eb_ca6b);
    x ^= x >> 15;
    x = x.wrapping_mul(0x2c1b_3c6d);
    x ^= x >> 12;
    (x % 1_000_003) as f32 / 1_000_003.0
}

/// A binary STL of `triangles`, each written with its own three corners (STL has no
/// shared vertices). Each corner is nudged by a few units in the last place, as corners
/// recomputed per triangle by an exporter are, so exact welding does not join them.
pub fn soup_stl(triangles: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut out = vec![0u8; 80];
    out.extend_from_slice(&(triangles.len() as u32).to_le_bytes());
    for (t, tri) in triangles.iter().enumerate() {
        out.extend_from_slice(&[0u8; 12]);
        for (k, corner) in tri.iter().enumerate() {
            for (axis, &c) in corner.iter().enumerate() {
                let ulps = (hash01(t as u32 * 9 + k as u32 * 3 + axis as u32, 7) * 7.0) as i32 - 3;
                let nudged = if c == 0.0 {
                    c
                } else {
                    f32::from_bits((c.to_bits() as i32 + ulps) as u32)
                };
                out.extend_from_slice(&nudged.to_le_bytes());
            }
        }
        out.extend_from_slice(&[0u8; 2]);
    }
    out
}

/// A GLB holding one mesh of `positions` and u32 `indices`.
pub fn glb(positions: &[[f32; 3]], indices: &[u32]) -> Vec<u8> {
    let mut bin: Vec<u8> = bytemuck::cast_slice(positions).to_vec();
    let index_offset = bin.len();
    bin.extend_from_slice(bytemuck::cast_slice(indices));
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let (lo, hi) = positions.iter().fold(
        ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
        |(lo, hi), p| {
            (
                [0, 1, 2].map(|k| lo[k].min(p[k])),
                [0, 1, 2].map(|k| hi[k].max(p[k])),
            )
        },
    );
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
        "buffers":[{{"byteLength":{}}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{index_offset}}},{{"buffer":0,"byteOffset":{index_offset},"byteLength":{}}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3","min":{lo:?},"max":{hi:?}}},
        {{"bufferView":1,"componentType":5125,"count":{},"type":"SCALAR"}}]}}"#,
        bin.len(),
        indices.len() * 4,
        positions.len(),
        indices.len()
    );
    super::gltf::glb_container(&json, &bin)
}

/// A closed unit UV sphere, welded: one vertex per pole, no seam column; triangles
/// counter-clockwise from outside. Returns positions and indices.
pub fn welded_sphere(rings: u32, segments: u32) -> (Vec<[f32; 3]>, Vec<u32>) {
    let mut positions = vec![[0.0f32, 0.0, 1.0]];
    for r in 1..rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = std::f32::consts::TAU * s as f32 / segments as f32;
            positions.push([
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ]);
        }
    }
    positions.push([0.0, 0.0, -1.0]);
    let bottom = positions.len() as u32 - 1;
    let ring = |r: u32, s: u32| 1 + (r - 1) * segments + s % segments;
    let indices = sphere_indices(rings, segments, [0, bottom], ring, |_, _| false);
    (positions, indices)
}

/// The triangles of a sphere of `rings` × `segments` grid points: a fan at each pole
/// (`poles`: north, south) and two triangles per quad of rings `r`, `r + 1`
/// (`ring(r, s)` the point), split along the other diagonal where `other(r, s)`;
/// counter-clockwise from outside.
fn sphere_indices(
    rings: u32,
    segments: u32,
    [north, south]: [u32; 2],
    ring: impl Fn(u32, u32) -> u32,
    other: impl Fn(u32, u32) -> bool,
) -> Vec<u32> {
    let mut indices = Vec::new();
    for s in 0..segments {
        indices.extend_from_slice(&[north, ring(1, s), ring(1, s + 1)]);
        indices.extend_from_slice(&[south, ring(rings - 1, s + 1), ring(rings - 1, s)]);
        for r in 1..rings - 1 {
            let (a, b, c, d) = (
                ring(r, s),
                ring(r, s + 1),
                ring(r + 1, s),
                ring(r + 1, s + 1),
            );
            if other(r, s) {
                indices.extend_from_slice(&[a, c, b, b, c, d]);
            } else {
                indices.extend_from_slice(&[a, c, d, a, d, b]);
            }
        }
    }
    indices
}

/// A closed sphere (welded: one pole vertex, no seam column) with fins like a scan's
/// debris: on every `fin_every`-th of its edges a thin triangle stands out, sharing the
/// edge, so that edge has three triangles (non-manifold) and each fin adds two open
/// border edges. Returns positions and indices.
pub fn finned_sphere(rings: u32, segments: u32, fin_every: usize) -> (Vec<[f32; 3]>, Vec<u32>) {
    let (mut positions, mut indices) = welded_sphere(rings, segments);
    let closed = indices.len() / 3;
    for t in (0..closed).step_by(fin_every) {
        let (a, b) = (indices[t * 3], indices[t * 3 + 1]);
        let [pa, pb] = [a, b].map(|v| glam::Vec3::from(positions[v as usize]));
        let mid = (pa + pb) * 0.5;
        let tip = mid + mid.normalize() * 0.05 * (1.0 + hash01(t as u32, 3));
        positions.push(tip.to_array());
        let tip = positions.len() as u32 - 1;
        indices.extend_from_slice(&[a, b, tip]);
    }
    (positions, indices)
}

/// Generated `(positions, indices)` as an in-memory mesh named `source`, for tests that
/// build without going through a file.
pub fn in_memory(
    source: &str,
    (positions, indices): (Vec<[f32; 3]>, Vec<u32>),
) -> meshlight_scene::Mesh {
    meshlight_scene::Mesh {
        source: source.into(),
        positions: positions.into_iter().map(glam::Vec3::from).collect(),
        indices,
        ..meshlight_scene::Mesh::default()
    }
}

/// A square of `n × n` cells over [0, 1]², two triangles each, with each grid point's
/// height and UV given by `at(x, y) -> (z, uv)` (normals all +Z: the tests using it look
/// at positions and UVs).
pub fn textured_square(
    source: &str,
    n: u32,
    at: impl Fn(f32, f32) -> (f32, [f32; 2]),
) -> meshlight_scene::Mesh {
    let mut mesh = meshlight_scene::Mesh {
        source: source.into(),
        ..meshlight_scene::Mesh::default()
    };
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
            let (z, uv) = at(x, y);
            mesh.positions.push(glam::Vec3::new(x, y, z));
            mesh.normals.push(glam::Vec3::Z);
            mesh.uvs.push(uv);
        }
    }
    let id = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            mesh.indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    mesh
}

/// A welded sphere of radius 3 around (10, -2, 5) with unit normals and a tiling map
/// (UVs in 0..4 × 0..4), as arrays a glTF writer takes: what the compressed-file tests
/// compress and compare the loaded mesh with.
pub struct AttributedSphere {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub uvs: Vec<[f32; 2]>,
    pub indices: Vec<u32>,
}

impl AttributedSphere {
    pub fn new(rings: u32, segments: u32) -> Self {
        let (unit, indices) = welded_sphere(rings, segments);
        Self {
            positions: unit
                .iter()
                .map(|p| [10.0 + 3.0 * p[0], -2.0 + 3.0 * p[1], 5.0 + 3.0 * p[2]])
                .collect(),
            normals: unit.clone(),
            uvs: unit
                .iter()
                .map(|p| {
                    [
                        4.0 * (p[1].atan2(p[0]) / std::f32::consts::TAU + 0.5),
                        2.0 * (1.0 - p[2]),
                    ]
                })
                .collect(),
            indices,
        }
    }
}

/// What a raw scan of a figure has beyond its surface, for [`scan_figure`].
#[derive(Debug, Clone, Copy)]
pub struct ScanFlaws {
    /// Radial noise per vertex, in units of the mean edge length.
    pub noise: f32,
    /// Share of the surface's triangles cut out in small holes (patches of about six).
    pub holes: f32,
    /// Floating specks near the surface: tiny closed tetrahedra, four triangles each.
    pub specks: u32,
    /// Share of the surface's triangles written with the other winding.
    pub flipped: f32,
}

/// A scanned figure as a capture program writes it: a lumpy closed body (a sphere
/// displaced by a few lobes) triangulated irregularly (jittered grid points, each quad's
/// diagonal chosen at random), with `flaws`. Returns positions and indices.
pub fn scan_figure(rings: u32, segments: u32, flaws: ScanFlaws) -> (Vec<[f32; 3]>, Vec<u32>) {
    use glam::Vec3;
    let radius = |d: Vec3| {
        1.0 + 0.25 * (3.0 * d.x).sin() * (2.0 * d.y).cos() + 0.15 * (4.0 * d.z + d.x).sin()
    };
    let edge = std::f32::consts::PI / rings as f32;
    let mut positions = Vec::new();
    let mut at = |d: Vec3, i: u32| {
        let n = (hash01(i, 11) - 0.5) * 2.0 * flaws.noise * edge;
        positions.push((d * (radius(d) + n)).to_array());
        positions.len() as u32 - 1
    };
    let north = at(Vec3::Z, 0);
    let mut grid = Vec::new();
    for r in 1..rings {
        for s in 0..segments {
            let i = r * segments + s;
            let theta =
                std::f32::consts::PI * (r as f32 + (hash01(i, 1) - 0.5) * 0.6) / rings as f32;
            let phi =
                std::f32::consts::TAU * (s as f32 + (hash01(i, 2) - 0.5) * 0.6) / segments as f32;
            let d = Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            grid.push(at(d, i));
        }
    }
    let south = at(-Vec3::Z, 1);
    let ring = |r: u32, s: u32| grid[((r - 1) * segments + s % segments) as usize];
    let indices = sphere_indices(rings, segments, [north, south], ring, |r, s| {
        hash01(r * segments + s, 5) >= 0.5
    });
    // Holes: a triangle and the five after it, at seeded places.
    let triangles = indices.len() / 3;
    let mut keep = vec![true; triangles];
    let holes = (triangles as f32 * flaws.holes / 6.0) as u32;
    for h in 0..holes {
        let t = (hash01(h, 21) * triangles as f32) as usize;
        keep[t..(t + 6).min(triangles)].fill(false);
    }
    let mut indices: Vec<u32> = indices
        .chunks_exact(3)
        .zip(&keep)
        .enumerate()
        .filter(|(_, (_, k))| **k)
        .flat_map(|(i, (t, _))| match hash01(i as u32, 41) < flaws.flipped {
            true => [t[0], t[2], t[1]],
            false => [t[0], t[1], t[2]],
        })
        .collect();
    for k in 0..flaws.specks {
        let d = Vec3::new(
            hash01(k, 31) - 0.5,
            hash01(k, 32) - 0.5,
            hash01(k, 33) - 0.5,
        )
        .normalize_or(Vec3::X);
        let centre = d * (radius(d) + edge * (1.0 + 3.0 * hash01(k, 34)));
        let size = edge * (0.3 + hash01(k, 35));
        let corner = |v: Vec3| (centre + v * size).to_array();
        let base = positions.len() as u32;
        positions.extend([
            corner(Vec3::new(1.0, 1.0, 1.0)),
            corner(Vec3::new(1.0, -1.0, -1.0)),
            corner(Vec3::new(-1.0, 1.0, -1.0)),
            corner(Vec3::new(-1.0, -1.0, 1.0)),
        ]);
        for t in [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]] {
            indices.extend(t.map(|v| base + v));
        }
    }
    (positions, indices)
}
