//! The generated world: unique meshes, tiles that meet, files the loader reads back as
//! generated, the same bytes every time.

mod common;

use meshlight_scene::load::load_mesh;
use meshlight_scene::{SceneError, World};

fn small() -> World {
    World {
        tiles: 2,
        tile_size: 16.0,
        cells: 24,
        knot_segments: 6,
        seed: 7,
    }
}

#[test]
fn every_mesh_is_its_own_and_neighbouring_grounds_meet() {
    let world = small();
    assert_eq!(world.mesh_count(), 8);
    let meshes: Vec<_> = (0..world.mesh_count())
        .map(|i| world.mesh(i).unwrap())
        .collect();
    let triangles: u64 = meshes.iter().map(|m| m.mesh.indices.len() as u64 / 3).sum();
    assert_eq!(triangles, world.triangle_count());
    // No two meshes alike, in shape (not only in place): positions relative to their
    // first vertex differ.
    for (a, ma) in meshes.iter().enumerate() {
        for mb in &meshes[a + 1..] {
            let rel = |m: &meshlight_scene::Mesh| -> Vec<[u32; 3]> {
                let o = m.positions[0];
                m.positions
                    .iter()
                    .map(|p| (*p - o).to_array().map(f32::to_bits))
                    .collect()
            };
            assert_ne!(rel(&ma.mesh), rel(&mb.mesh), "{} and {}", ma.name, mb.name);
        }
    }
    // Ground (0, 0)'s right edge is ground (1, 0)'s left edge, point for point.
    let side = world.cells as usize + 1;
    let (left, right) = (&meshes[0].mesh, &meshes[1].mesh);
    for j in 0..side {
        let a = left.positions[j * side + side - 1];
        let b = right.positions[j * side];
        assert!((a - b).length() < 1e-4, "row {j}: {a} and {b}");
    }
    // The knots stand on their tiles, within the world.
    let (corner, extent) = world.extent();
    for knot in &meshes[4..] {
        for p in &knot.mesh.positions {
            assert!(p.x > corner.x && p.x < corner.x + extent, "{}", knot.name);
            assert!(p.z > corner.y && p.z < corner.y + extent, "{}", knot.name);
        }
    }
    // The same world, the same meshes.
    assert_eq!(
        world.mesh(5).unwrap().mesh.positions,
        meshes[5].mesh.positions
    );
    assert!(world.mesh(8).is_err());
}

#[test]
fn written_files_load_back_as_generated() {
    let world = small();
    let dir = common::scratch("world");
    let mut names = std::sync::Mutex::new(Vec::new());
    let bytes = world
        .write(&dir, &|name, _| {
            names.lock().unwrap().push(name.to_string())
        })
        .unwrap();
    assert!(bytes > 0);
    let names = names.get_mut().unwrap();
    names.sort();
    assert_eq!(names.len(), 8);
    assert_eq!(names[0], "ground/ground_000_000.glb");
    assert_eq!(names[7], "knots/knot_001_001.glb");
    for i in [0, 3, 4, 7] {
        let m = world.mesh(i).unwrap();
        let loaded = load_mesh(&dir.join(&m.name)).unwrap();
        assert_eq!(loaded.positions, m.mesh.positions, "{}", m.name);
        assert_eq!(loaded.indices, m.mesh.indices, "{}", m.name);
        assert_eq!(loaded.uvs, m.mesh.uvs, "{}", m.name);
    }
}

#[test]
fn a_world_it_cannot_make_is_refused_naming_the_setting() {
    for (world, says) in [
        (
            World {
                tiles: 0,
                ..small()
            },
            "tiles per side",
        ),
        (
            World {
                tile_size: f32::NAN,
                ..small()
            },
            "tile size",
        ),
        (
            World {
                knot_segments: 2,
                ..small()
            },
            "knot segments",
        ),
        (
            World {
                cells: 0,
                ..small()
            },
            "cells",
        ),
    ] {
        let err = world.check().unwrap_err();
        assert!(matches!(err, SceneError::InvalidOption(_)), "{err:?}");
        assert!(err.to_string().contains(says), "{says}: {err}");
    }
}
