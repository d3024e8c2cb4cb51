//! Assets whose checksum is valid but whose contents are not: each inconsistency class is
//! refused with an error naming the field, before any count is trusted for an
//! allocation; and meshes whose coordinates the quantiser cannot represent are refused
//! at bake time instead of producing such an asset.

mod common;

use common::damage::{good_words, record_mut, refused, refused_saying, reseal};

use std::path::Path;

use meshlight_scene::asset::format::{
    AssetHeader, GroupRecord, MeshletRecord, PageRecord, SECTION_CHILDREN, SECTION_GROUPS,
    SECTION_MESHLETS, SECTION_PAGES, SECTION_PAYLOAD,
};
use meshlight_scene::load::parse_obj;
use meshlight_scene::mesh::{MAX_COORDINATE, MIN_EXTENT};
use meshlight_scene::{BuildOptions, MeshletAsset, SceneError, build_asset, procedural_mesh};

fn header(words: &mut [u32]) -> &mut AssetHeader {
    bytemuck::from_bytes_mut(bytemuck::cast_slice_mut(&mut words[..AssetHeader::WORDS]))
}

fn meshlet(words: &mut [u32], i: usize) -> &mut MeshletRecord {
    record_mut(words, SECTION_MESHLETS, i)
}

#[test]
fn the_resealed_undamaged_asset_loads() {
    let mut w = good_words();
    reseal(&mut w);
    let len = w.len() as u64 * 4;
    MeshletAsset::from_words(w, len, Path::new("ok.mlasset")).unwrap();
}

#[test]
fn header_counts_are_checked_before_anything_is_allocated() {
    // These drove a 100 GB allocation and a 1.5 GB one before being checked.
    refused("level count 2^32-1", "header.level_count", |w| {
        header(w).level_count = u32::MAX
    });
    refused("level count 2^24", "header.level_count", |w| {
        header(w).level_count = 1 << 24
    });
    refused("level count 0", "header.level_count", |w| {
        header(w).level_count = 0
    });
    refused("meshlet count", "header.meshlet_count", |w| {
        header(w).meshlet_count = u32::MAX
    });
    refused("group count", "header.group_count", |w| {
        header(w).group_count += 1
    });
}

#[test]
fn quantisation_grid_must_be_usable() {
    refused("NaN step", "header.quant_step", |w| {
        header(w).quant_step = f32::NAN
    });
    refused("zero step", "header.quant_step", |w| {
        header(w).quant_step = 0.0
    });
    refused("infinite origin", "header.quant_origin", |w| {
        header(w).quant_origin[1] = f32::INFINITY
    });
    refused("grid overflow", "header.quant_origin", |w| {
        header(w).quant_step = f32::MAX / 2.0
    });
    refused("grid bits", "header.quant_bits", |w| {
        header(w).quant_bits = 40
    });
}

#[test]
fn totals_must_agree_with_the_records() {
    refused("total triangles", "header.total_triangles", |w| {
        header(w).total_triangles += 1
    });
    refused("total vertices", "header.total_vertices", |w| {
        header(w).total_vertices -= 1
    });
    refused("LOD-0 triangles", "header.lod0_triangles", |w| {
        header(w).lod0_triangles = 7
    });
    refused("LOD-0 meshlets", "header.lod0_meshlets", |w| {
        header(w).lod0_meshlets += 1
    });
    refused("root count", "header.root_count", |w| {
        header(w).root_count += 1
    });
}

#[test]
fn meshlet_records_must_fit_the_header() {
    refused("grid minimum past the grid", "meshlet[0].grid_min", |w| {
        let top = (1u32 << header(w).quant_bits) - 1;
        meshlet(w, 0).grid_min[0] = top + 1;
    });
    refused("grid minimum near u32::MAX", "meshlet[0].grid_min", |w| {
        meshlet(w, 0).grid_min[2] = u32::MAX - 1
    });
    refused("level past the level count", "meshlet[0].counts", |w| {
        let levels = header(w).level_count;
        let m = meshlet(w, 0);
        m.counts = (m.counts & 0xffff) | (levels << 16);
    });
    refused("high count bits", "meshlet[1].counts", |w| {
        meshlet(w, 1).counts |= 1 << 30
    });
    refused("NaN bounds", "meshlet[2].bounds", |w| {
        meshlet(w, 2).bounds[0] = f32::NAN
    });
    refused("negative radius", "meshlet[2].bounds", |w| {
        meshlet(w, 2).bounds[3] = -1.0
    });
    refused(
        "parent group past the groups",
        "meshlet[3].parent_group",
        |w| {
            let groups = header(w).group_count;
            meshlet(w, 3).parent_group = groups;
        },
    );
    refused(
        "LOD-0 meshlet with a source group",
        "meshlet[0].source_group",
        |w| meshlet(w, 0).source_group = 0,
    );
    refused("NaN group error", "group[0].error", |w| {
        let at = header(w).sections[meshlight_scene::asset::format::SECTION_GROUPS].offset as usize
            + std::mem::offset_of!(meshlight_scene::asset::format::GroupRecord, error) / 4;
        w[at] = f32::NAN.to_bits();
    });
}

#[test]
fn header_bounds_flags_and_layout_must_be_consistent() {
    refused("inverted bounds", "header.bounds_min", |w| {
        let h = header(w);
        h.bounds_min[0] = h.bounds_max[0] + 1.0;
    });
    refused("NaN bounds", "header.bounds_min", |w| {
        header(w).bounds_max[2] = f32::NAN
    });
    refused("unknown flag bits", "header.flags", |w| {
        header(w).flags |= 0x8000
    });
    refused("trailing bytes", "file size", |w| {
        w.extend_from_slice(&[0, 0])
    });
    refused("overlapping sections", "header.sections[1].offset", |w| {
        header(w).sections[1].offset -= 1
    });
}

#[test]
fn coordinates_beyond_the_quantiser_are_refused_at_bake_time() {
    let one_huge = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1e38 1 0\nf 1 2 3\nf 2 4 3\n";
    let all_huge = "v 1e30 1e30 1e30\nv 1.1e30 1e30 1e30\nv 1e30 1.1e30 1e30\nf 1 2 3\n";
    for (name, text) in [("one-huge.obj", one_huge), ("all-huge.obj", all_huge)] {
        let mesh = parse_obj(Path::new(name), text.as_bytes()).unwrap();
        let err = build_asset(&mesh, &BuildOptions::default(), &mut |_| {}).unwrap_err();
        match &err {
            SceneError::CoordinateRange { limit, .. } => assert_eq!(*limit, MAX_COORDINATE),
            other => panic!("{name}: {other:?}"),
        }
        let msg = err.to_string();
        assert!(
            msg.contains(name) && msg.contains("scale the mesh down"),
            "{msg}"
        );
    }
    // Just inside the limit, a mesh bakes into an asset that loads and verifies.
    let s = MAX_COORDINATE * 0.5;
    let text = format!(
        "v {s} {s} {s}\nv {} {s} {s}\nv {s} {} {s}\nf 1 2 3\n",
        s * 1.5,
        s * 1.5
    );
    let mesh = parse_obj(Path::new("big.obj"), text.as_bytes()).unwrap();
    let built = build_asset(&mesh, &BuildOptions::default(), &mut |_| {}).unwrap();
    let dir = common::scratch("big-coordinates");
    let path = dir.join("big.mlasset");
    built.asset.save(&path).unwrap();
    let loaded = MeshletAsset::load(&path).unwrap();
    assert!(meshlight_scene::verify::verify(&loaded).is_empty());
}

/// A closed tetrahedron `scale` units across, as OBJ text.
fn tetrahedron_obj(scale: f32) -> String {
    format!(
        "v 0 0 0\nv {scale:e} 0 0\nv 0 {scale:e} 0\nv 0 0 {scale:e}\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
    )
}

/// A mesh too small for any position grid is refused naming its extent and the limit
/// (it used to end in an internal error from the asset's own checks); one just above
/// the limit bakes into an asset that loads and verifies.
#[test]
fn meshes_smaller_than_the_position_grid_resolves_are_refused_naming_the_limit() {
    for scale in [1e-36f32, 1e-33, MIN_EXTENT * 0.5] {
        let mesh = parse_obj(Path::new("tiny.obj"), tetrahedron_obj(scale).as_bytes()).unwrap();
        let err = build_asset(&mesh, &BuildOptions::default(), &mut |_| {}).unwrap_err();
        match &err {
            SceneError::ExtentTooSmall { extent, limit, .. } => {
                assert_eq!((*extent, *limit), (scale, MIN_EXTENT))
            }
            other => panic!("{scale:e}: {other:?}"),
        }
        let msg = err.to_string();
        assert!(
            msg.contains("tiny.obj") && msg.contains("scale the mesh up"),
            "{msg}"
        );
        assert!(!msg.contains("report"), "{msg}");
    }
    for scale in [MIN_EXTENT * 2.0, 1e-20] {
        let mesh = parse_obj(Path::new("small.obj"), tetrahedron_obj(scale).as_bytes()).unwrap();
        let built = build_asset(&mesh, &BuildOptions::default(), &mut |_| {})
            .unwrap_or_else(|e| panic!("{scale:e}: {e}"));
        let dir = common::scratch(&format!("small-{scale:e}"));
        let path = dir.join("small.mlasset");
        built.asset.save(&path).unwrap();
        let loaded = MeshletAsset::load(&path).unwrap();
        assert!(
            meshlight_scene::verify::verify(&loaded).is_empty(),
            "{scale:e}"
        );
    }
}

fn group(words: &mut [u32], i: usize) -> &mut GroupRecord {
    record_mut(words, SECTION_GROUPS, i)
}

fn records(words: &[u32]) -> (Vec<MeshletRecord>, Vec<GroupRecord>) {
    let h: &AssetHeader = bytemuck::from_bytes(bytemuck::cast_slice(&words[..AssetHeader::WORDS]));
    let section = |i: usize| {
        let s = h.sections[i];
        &words[s.offset as usize..(s.offset + s.words) as usize]
    };
    (
        bytemuck::cast_slice(section(SECTION_MESHLETS)).to_vec(),
        bytemuck::cast_slice(section(SECTION_GROUPS)).to_vec(),
    )
}

/// The first meshlet of level 1: one made by simplifying a group.
fn first_level_one_meshlet(words: &[u32]) -> usize {
    let (meshlets, _) = records(words);
    meshlets.iter().position(|m| m.level() == 1).unwrap()
}

#[test]
fn meshlets_are_stored_page_by_page() {
    refused_saying(
        "a root after a group's children",
        "parent_group",
        "the roots first",
        |w| {
            let last = header(w).meshlet_count as usize - 1;
            meshlet(w, last).parent_group = u32::MAX;
        },
    );
    refused_saying(
        "a child of group 2 among group 1's",
        "parent_group",
        "page by page",
        |w| {
            let (meshlets, _) = records(w);
            let i = meshlets.iter().position(|m| m.parent_group == 1).unwrap();
            meshlet(w, i).parent_group = 2;
        },
    );
    refused_saying(
        "a group's children listed out of order",
        "group[1].first_child",
        "after the previous group's",
        |w| {
            let first = group(w, 1).first_child as usize;
            let at = header(w).sections[SECTION_CHILDREN].offset as usize + first;
            w.swap(at, at + 1);
        },
    );
    refused_saying(
        "a page record one word off",
        "page[3]",
        "children's payload",
        |w| record_mut::<PageRecord>(w, SECTION_PAGES, 3).first_word += 1,
    );
    refused_saying(
        "a page record one word short",
        "page[0]",
        "children's payload",
        |w| record_mut::<PageRecord>(w, SECTION_PAGES, 0).words -= 1,
    );
    refused_saying(
        "a resident part one word long",
        "header.resident_words",
        "roots' payload",
        |w| header(w).resident_words += 1,
    );
}

#[test]
fn group_links_must_be_consistent() {
    refused_saying(
        "a child above its group",
        "group[",
        "below its child",
        |w| {
            let (_, groups) = records(w);
            let g = groups.iter().position(|g| g.level > 0).unwrap();
            group(w, g).level = 0;
        },
    );
    refused_saying(
        "a source group of the wrong level",
        "source_group",
        "one level above",
        |w| {
            let (_, groups) = records(w);
            let i = first_level_one_meshlet(w);
            let other = groups.iter().position(|g| g.level == 1).unwrap();
            meshlet(w, i).source_group = other as u32;
        },
    );
    refused_saying(
        "a group without outputs",
        "group[0]",
        "no simplified meshlets",
        |w| {
            let (meshlets, groups) = records(w);
            let other = (1..groups.len()).find(|&g| groups[g].level == 0).unwrap();
            for (i, m) in meshlets.iter().enumerate() {
                if m.source_group == 0 {
                    meshlet(w, i).source_group = other as u32;
                }
            }
        },
    );
    refused_saying(
        "a child naming another parent",
        "parent_group",
        "lists the meshlet",
        |w| {
            // The last of group 0's children, so that the order still holds.
            let (meshlets, _) = records(w);
            let i = meshlets.iter().rposition(|m| m.parent_group == 0).unwrap();
            meshlet(w, i).parent_group = 1;
        },
    );
}

#[test]
fn bounds_and_grid_must_be_in_range() {
    refused_saying(
        "bounds whose size overflows",
        "header.bounds",
        "finite and positive",
        |w| {
            let h = header(w);
            h.bounds_min[0] = -3e38;
            h.bounds_max[0] = 3e38;
        },
    );
    refused_saying("a denormal step", "header.quant_step", "extent", |w| {
        header(w).quant_step = 1e-40
    });
    refused_saying(
        "a step twice the grid's",
        "header.quant_step",
        "extent",
        |w| header(w).quant_step *= 2.0,
    );
    refused("a step of 1e38", "header.quant_", |w| {
        header(w).quant_step = 1e38
    });
}

#[test]
fn spheres_must_lie_around_the_mesh() {
    refused_saying(
        "a culling radius of f32::MAX",
        "meshlet[2].bounds",
        "beyond the mesh",
        |w| meshlet(w, 2).bounds[3] = f32::MAX,
    );
    refused_saying(
        "a culling sphere far away",
        "meshlet[3].bounds",
        "beyond the mesh",
        |w| meshlet(w, 3).bounds[1] = 1e30,
    );
    refused_saying(
        "a LOD radius of 1e30",
        "group[1].lod_sphere",
        "beyond the mesh",
        |w| group(w, 1).lod_sphere[3] = 1e30,
    );
}

/// The source's counts, which nothing draws by, still agree with the meshlets: a
/// header that says otherwise was not written by the bake.
#[test]
fn the_source_counts_agree_with_the_meshlets() {
    refused_saying(
        "a triangle more in the source",
        "header.input_triangles",
        "dropped make",
        |w| header(w).input_triangles += 1,
    );
    refused_saying(
        "a dropped triangle fewer",
        "header.input_triangles",
        "dropped make",
        |w| header(w).dropped_duplicate = header(w).dropped_duplicate.wrapping_sub(1),
    );
    refused_saying(
        "more LOD-0 vertices than its records",
        "header.lod0_vertices",
        "at most all its meshlets' vertex records",
        |w| header(w).lod0_vertices = header(w).total_vertices + 1,
    );
    refused_saying(
        "fewer LOD-0 vertices than one meshlet holds",
        "header.lod0_vertices",
        "at least",
        |w| header(w).lod0_vertices = 2,
    );
}

#[test]
fn every_payload_word_belongs_to_one_meshlet() {
    refused_saying(
        "a word no meshlet refers to",
        &format!("sections[{SECTION_PAYLOAD}]"),
        "belongs to one meshlet",
        |w| {
            let s = header(w).sections;
            let end = (s[SECTION_PAYLOAD].offset + s[SECTION_PAYLOAD].words) as usize;
            w.insert(end, 0);
            let h = header(w);
            h.sections[SECTION_PAYLOAD].words += 1;
            for later in SECTION_PAYLOAD + 1..h.sections.len() {
                h.sections[later].offset += 1;
            }
        },
    );
    refused_saying(
        "two meshlets sharing words",
        "meshlet[1].data_offset",
        "follows",
        |w| meshlet(w, 1).data_offset -= 1,
    );
}

/// What `inspect` rejects for a DAG violation (here a group whose error is below its
/// child's, which the structural checks cannot see), loading for the renderer refuses
/// with the same message.
#[test]
fn loading_for_the_renderer_refuses_what_inspect_rejects() {
    use meshlight_scene::inspect::inspect;
    let dir = common::scratch("load-verified");
    let good = dir.join("good.mlasset");
    let built = build_asset(&procedural_mesh(12), &BuildOptions::default(), &mut |_| {}).unwrap();
    built.asset.save(&good).unwrap();
    MeshletAsset::load_verified(&good).unwrap();
    built.asset.check_all(&good).unwrap();

    let broken = meshlight_scene::damaged::error_below_child(&built).unwrap();
    let bad = dir.join("bad.mlasset");
    broken.save(&bad).unwrap();
    MeshletAsset::load(&bad).expect("structurally sound");
    let inspect = inspect(&bad).unwrap().verdict().unwrap_err();
    let load = MeshletAsset::load_verified(&bad).unwrap_err();
    assert!(matches!(load, SceneError::AssetCorrupt { .. }), "{load:?}");
    assert_eq!(load.to_string(), inspect.to_string());
    assert!(load.to_string().contains("below child"), "{load}");
    assert_eq!(
        broken.check_all(&bad).unwrap_err().to_string(),
        load.to_string()
    );
}

/// A UV grid whose largest encoded UV (`uv_min + (2^24 + 65535 · 2^8) · uv_step`) is
/// past the f32 range decodes to infinity on the GPU: refused at load, naming the
/// fields. So is a meshlet whose UV offsets are shifted past the grid.
#[test]
fn a_uv_grid_that_overflows_f32_is_refused() {
    let mut mesh =
        common::generators::in_memory("uv sphere", common::generators::welded_sphere(12, 24));
    mesh.uvs = mesh.positions.iter().map(|p| [p.x, p.y]).collect();
    let built = build_asset(&mesh, &BuildOptions::default(), &mut |_| {}).unwrap();
    assert!(built.asset.header().has_uvs());
    let words: Vec<u32> = bytemuck::cast_slice(built.asset.bytes()).to_vec();
    let load = |edit: &dyn Fn(&mut AssetHeader)| {
        let mut w = words.clone();
        edit(header(&mut w));
        reseal(&mut w);
        let len = w.len() as u64 * 4;
        MeshletAsset::from_words(w, len, Path::new("uv.mlasset"))
    };
    assert!(load(&|_| {}).is_ok());
    let err = load(&|h| {
        h.uv_min[1] = 3e38;
        h.uv_step[1] = 1e35;
    })
    .unwrap_err();
    match &err {
        SceneError::AssetField { field, .. } => {
            assert!(field.contains("uv_min/uv_step"), "{err}");
            assert!(err.to_string().contains("f32 range"), "{err}");
        }
        other => panic!("{other:?}"),
    }
    // Meshlet 3's v offsets shifted by 9: codes past the grid.
    let m = built.asset.meshlets()[3];
    let at = built.asset.header().sections[meshlight_scene::asset::format::SECTION_PAYLOAD].offset
        + m.data_offset
        + meshlight_scene::asset::format::PayloadLayout::of(
            &m,
            meshlight_scene::asset::format::FLAG_UVS,
        )
        .uvs
        + 1;
    let mut w = words.clone();
    w[at as usize] = (w[at as usize] & 0xff_ffff) | (9 << 24);
    reseal(&mut w);
    let len = w.len() as u64 * 4;
    let err = MeshletAsset::from_words(w, len, Path::new("uv.mlasset")).unwrap_err();
    match &err {
        SceneError::AssetField { field, .. } => {
            assert!(field.contains("meshlet[3].data_offset"), "{err}");
            assert!(err.to_string().contains("shifted by 9"), "{err}");
        }
        other => panic!("{other:?}"),
    }
}

/// A meshlet whose vertex records decode outside the header's bounds (its grid origin
/// moved along the mesh's shortest axis, where the cubic grid reaches past the mesh, so
/// every other check still holds) is refused at load: the culling spheres come from the
/// bounds, so such vertices could be culled while on screen.
#[test]
fn vertices_decoded_outside_the_bounds_are_refused() {
    refused_saying(
        "grid origin moved past the bounds",
        "meshlet[0].data_offset",
        "outside the header's bounds",
        |w| {
            let h = *header(w);
            let extent = [0, 1, 2].map(|k| h.bounds_max[k] - h.bounds_min[k]);
            let k = (0..3)
                .min_by(|&a, &b| extent[a].total_cmp(&extent[b]))
                .unwrap();
            let top = (1u32 << h.quant_bits) - 1;
            let m = meshlet(w, 0);
            let reach = (1u32 << m.axis_bits()[k]) - 1;
            m.grid_min[k] = top - reach;
        },
    );
}
