//! Material slots through the builder: a mesh of five materials in twenty patches is
//! one asset whose meshlets each hold one material at every level, the coarsest cut
//! still draws each material over the area it covers at full detail, and slots the
//! format cannot hold are refused, at bake time and in a damaged asset.

mod common;

use common::damage::{record_mut, reseal};
use common::generators::{in_memory, welded_sphere};

use std::collections::BTreeMap;
use std::path::Path;

use glam::Vec3;
use meshlight_scene::asset::format::{AssetHeader, MeshletRecord, SECTION_MESHLETS};
use meshlight_scene::cache::mesh_key;
use meshlight_scene::mesh::MAX_MATERIALS;
use meshlight_scene::{BuildOptions, Built, Mesh, MeshletAsset, SceneError, build_asset};

const SLOTS: u32 = 5;

/// A welded unit sphere whose triangles take slot `(band + 2 · sector) mod 5` by the
/// latitude band (5) and longitude sector (4) of their centroids: twenty patches, each
/// slot in four of them, with borders along both directions. Vertices on a border are
/// shared by two slots until cleaning splits them.
fn patched_sphere() -> Mesh {
    let mut mesh = in_memory("patched sphere", welded_sphere(48, 96));
    mesh.materials = mesh
        .indices
        .chunks_exact(3)
        .map(|t| {
            let c = t.iter().map(|&v| mesh.positions[v as usize]).sum::<Vec3>() / 3.0;
            let band = (((c.z + 1.0) * 0.5 * 5.0) as u32).min(4);
            let sector = (((c.y.atan2(c.x) / std::f32::consts::TAU + 0.5) * 4.0) as u32).min(3);
            (band + 2 * sector) % SLOTS
        })
        .collect();
    mesh
}

fn built() -> Built {
    build_asset(&patched_sphere(), &BuildOptions::default(), &mut |_| {}).unwrap()
}

fn area(positions: &[Vec3], t: &[u32]) -> f32 {
    let [a, b, c] = [t[0], t[1], t[2]].map(|v| positions[v as usize]);
    (b - a).cross(c - a).length() * 0.5
}

#[test]
fn every_meshlet_at_every_level_holds_one_material() {
    let built = built();
    let h = built.asset.header();
    assert_eq!(h.material_count, SLOTS);
    assert!(h.level_count >= 4, "{} levels", h.level_count);
    // Cleaning gave each slot its own copies of the border vertices.
    let slots = built.mesh.vertex_materials();
    for (t, corners) in built.mesh.indices.chunks_exact(3).enumerate() {
        for &v in corners {
            assert_eq!(slots[v as usize], built.mesh.materials[t], "triangle {t}");
        }
    }
    // Every cluster of the DAG: its corners are vertices of its slot.
    for (i, c) in built.dag.clusters.iter().enumerate() {
        for &v in &c.indices {
            assert_eq!(
                slots[v as usize], c.material,
                "cluster {i} (level {}) of slot {} has a corner of slot {}",
                c.level, c.material, slots[v as usize]
            );
        }
    }
    // The asset records the same slots: (level, slot) → triangles agree.
    let mut in_dag: BTreeMap<(u32, u32), u32> = BTreeMap::new();
    for c in &built.dag.clusters {
        *in_dag.entry((c.level, c.material)).or_default() += c.triangle_count() as u32;
    }
    let mut in_asset: BTreeMap<(u32, u32), u32> = BTreeMap::new();
    for m in built.asset.meshlets() {
        *in_asset.entry((m.level(), m.material())).or_default() += m.triangle_count();
    }
    assert_eq!(in_dag, in_asset);
    // Each slot reaches the top levels: materials are not simplified away.
    let top = built.dag.level_count - 1;
    for slot in 0..SLOTS {
        assert!(
            in_dag
                .keys()
                .any(|&(level, s)| s == slot && level + 1 >= top),
            "slot {slot} is missing near the top level {top}: {in_dag:?}"
        );
    }
}

/// The roots are the coarsest cut (each drawn whenever nothing finer is): there each
/// slot still covers about the share of the surface it covers at LOD 0, so a far view
/// shows every material where the full mesh has it. (Shares, not areas: a sphere of a
/// few dozen triangles has lost a fifth of its area to its flat faces.)
#[test]
fn the_coarsest_cut_keeps_each_materials_share_of_the_surface() {
    let built = built();
    let positions = &built.mesh.positions;
    let mut full = [0f32; SLOTS as usize];
    let mut coarse = [0f32; SLOTS as usize];
    for c in &built.dag.clusters {
        let sums: Vec<&mut [f32; SLOTS as usize]> = match (c.level, c.parent_group) {
            (0, meshlight_scene::dag::NO_GROUP) => vec![&mut full, &mut coarse],
            (0, _) => vec![&mut full],
            (_, meshlight_scene::dag::NO_GROUP) => vec![&mut coarse],
            _ => vec![],
        };
        let a: f32 = c.indices.chunks_exact(3).map(|t| area(positions, t)).sum();
        for s in sums {
            s[c.material as usize] += a;
        }
    }
    let roots = built.dag.roots().count();
    let root_triangles: usize = built.dag.roots().map(|c| c.triangle_count()).sum();
    eprintln!("{roots} roots, {root_triangles} triangles; areas {full:?} → {coarse:?}");
    let (full_total, coarse_total) = (full.iter().sum::<f32>(), coarse.iter().sum::<f32>());
    for slot in 0..SLOTS as usize {
        let ratio = (coarse[slot] / coarse_total) / (full[slot] / full_total);
        assert!(
            (0.85..=1.15).contains(&ratio),
            "slot {slot}: {} of {full_total} at LOD 0, {} of {coarse_total} at the roots",
            full[slot],
            coarse[slot]
        );
    }
    // The material borders do not hold the roots at full detail.
    assert!(
        root_triangles * 4 < built.mesh.triangle_count(),
        "{root_triangles} root triangles of {}",
        built.mesh.triangle_count()
    );
}

#[test]
fn slots_are_part_of_the_cache_key() {
    let mesh = patched_sphere();
    let mut other = mesh.clone();
    other.materials[0] = (other.materials[0] + 1) % SLOTS;
    let options = BuildOptions::default();
    assert_ne!(mesh_key(&mesh, &options), mesh_key(&other, &options));
}

#[test]
fn slots_the_format_cannot_hold_are_refused_when_cleaning() {
    let mut mesh = patched_sphere();
    mesh.materials[7] = MAX_MATERIALS;
    match mesh.clone().clean() {
        Err(e @ SceneError::TooManyMaterials { triangle: 7, .. }) => {
            let msg = e.to_string();
            assert!(
                msg.contains("patched sphere") && msg.contains("256") && msg.contains("split"),
                "{msg}"
            );
        }
        other => panic!("expected TooManyMaterials, got {other:?}"),
    }
    mesh.materials.truncate(10);
    match mesh.clean() {
        Err(e @ SceneError::AttributeMismatch { .. }) => {
            assert!(e.to_string().contains("10 material slots"), "{e}")
        }
        other => panic!("expected AttributeMismatch, got {other:?}"),
    }
}

fn damaged(edit: impl FnOnce(&mut Vec<u32>)) -> String {
    let mut words: Vec<u32> = bytemuck::cast_slice(built().asset.bytes()).to_vec();
    edit(&mut words);
    reseal(&mut words);
    let len = words.len() as u64 * 4;
    match MeshletAsset::from_words(words, len, Path::new("bad.mlasset")) {
        Err(e @ SceneError::AssetField { .. }) => e.to_string(),
        other => panic!("expected a field error, got {:?}", other.map(|_| ())),
    }
}

fn header(w: &mut [u32]) -> &mut AssetHeader {
    bytemuck::from_bytes_mut(bytemuck::cast_slice_mut(&mut w[..AssetHeader::WORDS]))
}

#[test]
fn an_asset_whose_slots_are_out_of_range_is_refused() {
    let msg = damaged(|w| {
        let m: &mut MeshletRecord = record_mut(w, SECTION_MESHLETS, 3);
        m.counts = (m.counts & 0x00ff_ffff) | (SLOTS << 24);
    });
    assert!(
        msg.contains("meshlet[3].counts") && msg.contains("material slot 5"),
        "{msg}"
    );
    for count in [0, MAX_MATERIALS + 1] {
        let msg = damaged(|w| header(w).material_count = count);
        assert!(msg.contains("header.material_count"), "{msg}");
    }
}
