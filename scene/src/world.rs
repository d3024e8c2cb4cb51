//! A generated world of unique geometry: a square grid of terrain tiles, each its own
//! square of one rolling landscape, and on each tile a knot of its own shape. No two
//! meshes are alike, so nothing is shared between instances and the scene's bytes grow
//! with its area: the kind of scene that cannot all be resident, which streaming is for.
//!
//! Each mesh is generated in world space (a tile where it lies, its knot standing on
//! it), so a directory of the baked meshes is drawn as the world with one instance per
//! asset at the origin. Everything is deterministic: the same [`World`] gives the same
//! bytes on every machine.

use std::f32::consts::TAU;
use std::path::{Path, PathBuf};

use glam::{Quat, Vec2, Vec3};
use rayon::prelude::*;

use crate::error::SceneError;
use crate::mesh::Mesh;
use crate::procedural::{Knot, knot_mesh};
use crate::terrain::{Terrain, hash};

/// A generated world's size and seed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct World {
    /// Tiles per side: `tiles²` ground tiles (and as many knots).
    pub tiles: u32,
    /// Side of a tile, world units.
    pub tile_size: f32,
    /// Grid cells per tile side: each tile's ground has `2 · cells²` triangles.
    pub cells: u32,
    /// Tube segments of each tile's knot (`16 · segments²` triangles); 0: no knots.
    pub knot_segments: u32,
    /// Worlds differing only in it have other hills and other knots.
    pub seed: u32,
}

/// Coprime (p, q) pairs: each a closed knot of one tube.
const KNOTS: [(u32, u32); 10] = [
    (2, 3),
    (3, 2),
    (2, 5),
    (3, 5),
    (3, 4),
    (4, 3),
    (5, 2),
    (5, 3),
    (2, 7),
    (3, 7),
];

/// One generated mesh: where it goes under the output directory, and the mesh.
pub struct WorldMesh {
    /// Relative path of its file, e.g. `ground/ground_003_007.glb`.
    pub name: String,
    /// The mesh, in world space.
    pub mesh: Mesh,
}

impl Default for World {
    /// 8 × 8 tiles of 64 units, 512² cells and a 96-segment knot each: 64 grounds of
    /// 524,288 triangles and 64 knots of 147,456 (43 M triangles in all).
    fn default() -> Self {
        Self {
            tiles: 8,
            tile_size: 64.0,
            cells: 512,
            knot_segments: 96,
            seed: 1,
        }
    }
}

impl World {
    /// Refuses a world the generator cannot make, naming the setting to change.
    pub fn check(&self) -> Result<(), SceneError> {
        let bad = |what: String| Err(SceneError::InvalidOption(format!("world: {what}")));
        if self.tiles == 0 || self.tiles > 1024 {
            return bad(format!(
                "tiles per side must be 1..=1024, got {}",
                self.tiles
            ));
        }
        if !(self.tile_size.is_finite() && self.tile_size > 0.0) {
            return bad(format!("the tile size must be > 0, got {}", self.tile_size));
        }
        if self.knot_segments > 0 && self.knot_segments < 3 {
            return bad(format!(
                "knot segments must be 0 (no knots) or at least 3, got {}",
                self.knot_segments
            ));
        }
        self.tile_terrain(0, 0).check()?;
        if self.knot_segments > 0 {
            let triangles = crate::procedural::procedural_triangle_count(self.knot_segments);
            Mesh::check_limits("knot", triangles as u64 / 2, triangles as u64)?;
        }
        Ok(())
    }

    /// Meshes of the world: a ground per tile, and a knot per tile when it has them.
    pub fn mesh_count(&self) -> u32 {
        let tiles = self.tiles * self.tiles;
        match self.knot_segments {
            0 => tiles,
            _ => 2 * tiles,
        }
    }

    /// Triangles of all its meshes.
    pub fn triangle_count(&self) -> u64 {
        let tiles = u64::from(self.tiles) * u64::from(self.tiles);
        let ground = 2 * u64::from(self.cells) * u64::from(self.cells);
        let knot = match self.knot_segments {
            0 => 0,
            s => crate::procedural::procedural_triangle_count(s) as u64,
        };
        tiles * (ground + knot)
    }

    /// The corner of least x and z, and the side of the whole world.
    pub fn extent(&self) -> (Vec2, f32) {
        let side = self.tiles as f32 * self.tile_size;
        (Vec2::splat(-0.5 * side), side)
    }

    /// The ground of tile `(i, j)`: its square of the one landscape, so neighbours meet.
    pub fn tile_terrain(&self, i: u32, j: u32) -> Terrain {
        let (corner, _) = self.extent();
        Terrain {
            origin: corner + Vec2::new(i as f32, j as f32) * self.tile_size,
            size: self.tile_size,
            cells: self.cells,
            amplitude: 0.12 * self.tile_size,
            wavelength: 1.5 * self.tile_size,
            octaves: 7,
            seed: self.seed,
            uv_scale: 4.0 / self.tile_size,
            calm_centre: Vec2::ZERO,
            calm_radius: 0.0,
        }
    }

    /// Mesh `index`: the grounds in row order, then the knots.
    pub fn mesh(&self, index: u32) -> Result<WorldMesh, SceneError> {
        let tiles = self.tiles * self.tiles;
        if index >= self.mesh_count() {
            return Err(SceneError::InvalidOption(format!(
                "world: mesh {index} is past its {} meshes",
                self.mesh_count()
            )));
        }
        let tile = index % tiles;
        let (i, j) = (tile % self.tiles, tile / self.tiles);
        if index < tiles {
            let mut mesh = self.tile_terrain(i, j).mesh()?;
            mesh.source = format!("world ground tile ({i}, {j})");
            return Ok(WorldMesh {
                name: format!("ground/ground_{i:03}_{j:03}.glb"),
                mesh,
            });
        }
        Ok(WorldMesh {
            name: format!("knots/knot_{i:03}_{j:03}.glb"),
            mesh: self.knot(i, j),
        })
    }

    /// Tile `(i, j)`'s knot: its own (p, q), bumps and turn, lying on its side and
    /// standing on the ground near the tile's centre.
    fn knot(&self, i: u32, j: u32) -> Mesh {
        let h = hash(self.seed ^ hash(i.wrapping_mul(0x9e37_79b9) ^ hash(j)));
        let (p, q) = KNOTS[(h % KNOTS.len() as u32) as usize];
        let unit = |k: u32| (hash(h ^ k) >> 8) as f32 / (1u32 << 24) as f32;
        let knot = Knot {
            p,
            q,
            phase: TAU * unit(1),
        };
        let mut mesh = knot_mesh(self.knot_segments, knot);
        // The knot spans about ±3.5 across and ±1.5 through; a fifth of a tile across.
        let scale = self.tile_size * (0.05 + 0.02 * unit(2));
        let terrain = self.tile_terrain(i, j);
        let centre = terrain.origin
            + Vec2::splat(0.5 * self.tile_size)
            + (Vec2::new(unit(3), unit(4)) - 0.5) * 0.3 * self.tile_size;
        let ground = terrain.surface_height(centre.x, centre.y);
        let turn = Quat::from_rotation_y(TAU * unit(5)) * Quat::from_rotation_x(-0.5 * TAU / 2.0);
        let at = Vec3::new(centre.x, ground + 1.2 * scale, centre.y);
        for v in &mut mesh.positions {
            *v = at + turn * (*v * scale);
        }
        for n in &mut mesh.normals {
            *n = turn * *n;
        }
        mesh.source = format!("world knot ({i}, {j}): {}", mesh.source);
        mesh
    }

    /// Writes every mesh as a `.glb` file under `dir` (`ground/…` and `knots/…`), on all
    /// cores, calling `written` with each file's name and size; returns the bytes
    /// written. `meshlight bake DIR -o OUT` then bakes the world.
    pub fn write(
        &self,
        dir: &Path,
        written: &(dyn Fn(&str, u64) + Sync),
    ) -> Result<u64, SceneError> {
        self.check()?;
        for sub in ["ground", "knots"] {
            let path = dir.join(sub);
            std::fs::create_dir_all(&path).map_err(|source| SceneError::Write { path, source })?;
        }
        (0..self.mesh_count())
            .into_par_iter()
            .map(|index| {
                let m = self.mesh(index)?;
                let bytes = crate::glb::mesh_glb(&m.mesh, &m.name);
                let path: PathBuf = dir.join(&m.name);
                std::fs::write(&path, &bytes).map_err(|source| SceneError::Write {
                    path: path.clone(),
                    source,
                })?;
                written(&m.name, bytes.len() as u64);
                Ok(bytes.len() as u64)
            })
            .sum()
    }
}
