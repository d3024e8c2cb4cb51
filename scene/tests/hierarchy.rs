//! The culling hierarchy in the asset: built for real meshes with every structural
//! property the loader checks (and bounds that really enclose what is below), refused
//! with a typed error naming the field when any of those properties is broken (with a
//! valid checksum, so only the structural checks can notice), and files of the format
//! before it refused with the re-bake message.

mod common;

use common::damage::{record_mut, refused};

use std::collections::HashSet;
use std::path::Path;

use meshlight_scene::asset::format::{
    AssetHeader, GroupRecord, MAGIC, MeshletRecord, NO_GROUP, NodeRecord, ROOT_PARENT_ERROR,
    SECTION_CHILDREN, SECTION_GROUPS, SECTION_MESHLETS, SECTION_NODE_CLUSTERS, SECTION_NODES,
    SECTION_PAYLOAD, VERSION,
};
use meshlight_scene::hierarchy::{MAX_CHILDREN, depth, encloses, meshlet_lod};
use meshlight_scene::load::load_mesh;
use meshlight_scene::{BuildOptions, MeshletAsset, SceneError, build_asset, procedural_mesh};

fn bake(mesh: &meshlight_scene::Mesh) -> MeshletAsset {
    build_asset(mesh, &BuildOptions::default(), &mut |_| {})
        .unwrap()
        .asset
}

/// Walks the tree from the root and checks, independently of the loader's code, what the
/// GPU traversal relies on: every meshlet reached exactly once, every group's children
/// forming one leaf, and every node bounding the spheres and errors of every meshlet below.
fn check_tree(asset: &MeshletAsset) {
    let nodes = asset.nodes();
    let groups = asset.groups();
    let meshlets = asset.meshlets();
    let mut reached = vec![0u32; meshlets.len()];
    let mut visited = vec![false; nodes.len()];
    let mut leaf_groups = HashSet::new();
    let mut stack = vec![(0usize, Vec::<usize>::new())];
    while let Some((i, ancestors)) = stack.pop() {
        assert!(!visited[i], "node {i} reached twice");
        visited[i] = true;
        let n = &nodes[i];
        let mut path = ancestors.clone();
        path.push(i);
        if n.is_leaf() {
            let below = asset.node_meshlets(n);
            let parent = meshlets[below[0] as usize].parent_group;
            assert!(
                leaf_groups.insert(parent),
                "two leaves of group {parent:#x}"
            );
            if parent != NO_GROUP {
                let mut want: Vec<u32> = asset.group_children(&groups[parent as usize]).to_vec();
                let mut got = below.to_vec();
                want.sort();
                got.sort();
                assert_eq!(got, want, "leaf {i} is not group {parent}'s children");
            }
            for &m in below {
                reached[m as usize] += 1;
                let record = &meshlets[m as usize];
                let ((own_sphere, own_error), parent) = meshlet_lod(record, groups);
                for &a in &path {
                    let a = &nodes[a];
                    assert!(encloses(a.bounds, record.bounds), "culling sphere");
                    assert!(encloses(a.lod_sphere, own_sphere), "own LOD sphere");
                    assert!(a.min_error <= own_error);
                    match parent {
                        Some((sphere, error)) => {
                            assert!(encloses(a.lod_sphere, sphere), "parent LOD sphere");
                            assert!(a.max_parent_error >= error);
                        }
                        None => assert_eq!(a.max_parent_error, ROOT_PARENT_ERROR),
                    }
                }
            }
        } else {
            assert!(n.child_count <= MAX_CHILDREN);
            for c in n.children() {
                assert!(c > i, "child {c} before its parent {i}");
                stack.push((c, path.clone()));
            }
        }
    }
    assert!(visited.iter().all(|&v| v), "a node is unreachable");
    assert!(
        reached.iter().all(|&r| r == 1),
        "a meshlet not reached once"
    );
    let groups_with_leaf = leaf_groups.iter().filter(|&&g| g != NO_GROUP).count();
    assert_eq!(groups_with_leaf, groups.len(), "every group is one leaf");
}

#[test]
fn real_meshes_get_a_valid_hierarchy_that_bounds_every_meshlet() {
    for asset in [
        bake(&procedural_mesh(24)),
        bake(&load_mesh(&common::shared_mesh("stanford-bunny.obj")).unwrap()),
        bake(&load_mesh(&common::shared_mesh("spot.obj")).unwrap()),
    ] {
        assert_eq!(asset.header().version, VERSION);
        assert_eq!(asset.nodes().len() as u32, asset.header().node_count);
        check_tree(&asset);
        // The loader accepts what the builder writes.
        let words: Vec<u32> = bytemuck::cast_slice(asset.bytes()).to_vec();
        let len = words.len() as u64 * 4;
        MeshletAsset::from_words(words, len, Path::new("ok.mlasset")).unwrap();
        // Fewer nodes than meshlets, and a tree of bounded depth: levels plus a few.
        let h = asset.header();
        assert!(asset.nodes().len() < h.meshlet_count as usize / 2);
        assert!(
            depth(asset.nodes()) <= 2 * h.level_count + 4,
            "depth {} for {} levels",
            depth(asset.nodes()),
            h.level_count
        );
    }
}

#[test]
fn the_hierarchy_is_byte_identical_whatever_the_thread_count() {
    let mesh = procedural_mesh(20);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| bake(&mesh));
    let many = bake(&mesh);
    assert_eq!(one.bytes(), many.bytes());
}

fn header(words: &[u32]) -> AssetHeader {
    *bytemuck::from_bytes(bytemuck::cast_slice(&words[..AssetHeader::WORDS]))
}

fn node(words: &mut [u32], i: usize) -> &mut NodeRecord {
    record_mut(words, SECTION_NODES, i)
}

fn list(words: &mut [u32]) -> &mut [u32] {
    let s = header(words).sections[SECTION_NODE_CLUSTERS];
    &mut words[s.offset as usize..(s.offset + s.words) as usize]
}

fn nodes(words: &[u32]) -> Vec<NodeRecord> {
    let s = header(words).sections[SECTION_NODES];
    bytemuck::cast_slice(&words[s.offset as usize..(s.offset + s.words) as usize]).to_vec()
}

/// The first leaf and the first internal node other than the root.
fn first_leaf(words: &[u32]) -> usize {
    nodes(words).iter().position(|n| n.is_leaf()).unwrap()
}

fn first_inner(words: &[u32]) -> usize {
    (1..nodes(words).len())
        .find(|&i| !nodes(words)[i].is_leaf())
        .unwrap()
}

#[test]
fn damaged_tree_structure_is_refused() {
    refused("child past the nodes", "node[0].first_child", |w| {
        let count = header(w).node_count;
        node(w, 0).first_child = count;
    });
    refused("huge child range", "node[0].first_child", |w| {
        node(w, 0).child_count = u32::MAX
    });
    refused("a cycle back to the root", "first_child", |w| {
        let i = first_inner(w);
        node(w, i).first_child = 0;
    });
    refused("a node as its own child", "first_child", |w| {
        let i = first_inner(w);
        node(w, i).first_child = i as u32;
    });
    refused("too many children", "node[0].first_child", |w| {
        node(w, 0).child_count = MAX_CHILDREN + 1
    });
    refused("children shared by two parents", "node[", |w| {
        let inner: Vec<usize> = (1..nodes(w).len())
            .filter(|&i| !nodes(w)[i].is_leaf())
            .collect();
        let b = nodes(w)[inner[1]];
        let a = node(w, inner[0]);
        a.first_child = b.first_child;
        a.child_count = b.child_count;
    });
    refused("a leaf with a child index", "first_child", |w| {
        let i = first_leaf(w);
        node(w, i).first_child = 1;
    });
    refused("reserved words", "reserved", |w| node(w, 1).reserved[1] = 7);
    refused("node count off by one", "header.node_count", |w| {
        let h: &mut AssetHeader =
            bytemuck::from_bytes_mut(bytemuck::cast_slice_mut(&mut w[..AssetHeader::WORDS]));
        h.node_count += 1;
    });
}

#[test]
fn damaged_cluster_lists_are_refused() {
    refused("a meshlet listed twice", "node_clusters[", |w| {
        let l = list(w);
        l[1] = l[0];
    });
    refused("a meshlet past the meshlets", "node_clusters[", |w| {
        let count = header(w).meshlet_count;
        list(w)[3] = count;
    });
    refused("a leaf range past the list", "first_cluster", |w| {
        let i = first_leaf(w);
        node(w, i).first_cluster = u32::MAX - 1;
    });
    refused("an empty leaf", "first_cluster", |w| {
        let i = first_leaf(w);
        node(w, i).cluster_count = 0;
    });
    refused(
        "a root not covering the list",
        "node[0].cluster_count",
        |w| node(w, 0).cluster_count -= 1,
    );
    refused("children not tiling their parent", "node[", |w| {
        let i = first_inner(w);
        let first = node(w, i).first_child as usize;
        node(w, first).first_cluster += 1;
    });
    refused("a leaf mixing two groups", "node[", |w| {
        // Swap one meshlet of the first group leaf with one of another leaf.
        let ns = nodes(w);
        let leaves: Vec<usize> = (0..ns.len())
            .filter(|&i| ns[i].is_leaf() && ns[i].cluster_count > 1)
            .collect();
        let (a, b) = (ns[leaves[0]].first_cluster, ns[leaves[1]].first_cluster);
        list(w).swap(a as usize, b as usize);
    });
}

#[test]
fn bounds_and_errors_that_do_not_hold_what_is_below_are_refused() {
    refused("a NaN sphere", "bounds", |w| {
        node(w, 2).bounds[1] = f32::NAN
    });
    refused("a leaf sphere too small", "bounds", |w| {
        let i = first_leaf(w);
        node(w, i).bounds[3] *= 0.5;
    });
    refused("a leaf LOD sphere moved", "bounds", |w| {
        let i = first_leaf(w);
        let n = node(w, i);
        n.lod_sphere[0] += n.lod_sphere[3];
    });
    refused("an inner sphere one ulp too small", "node[0].bounds", |w| {
        let r = &mut node(w, 0).bounds[3];
        *r = r.next_down();
    });
    refused(
        "a root error below a child's",
        "node[0].max_parent_error",
        |w| node(w, 0).max_parent_error = 0.0,
    );
    refused("a leaf minimum above its meshlets'", "min_error", |w| {
        let i = first_leaf(w);
        node(w, i).min_error = 1e30;
    });
    refused("a negative error", "min_error", |w| {
        node(w, 3).min_error = -1.0
    });
    refused("an infinite error", "max_parent_error", |w| {
        node(w, 3).max_parent_error = f32::INFINITY
    });
    // Since pages, a group's children are also its page's range, which is checked first.
    refused("a leaf that is not all of its group", "page[", |w| {
        // The group of the first group leaf now claims one child less than its leaf holds.
        let ns = nodes(w);
        let leaf = ns
            .iter()
            .position(|n| {
                n.is_leaf() && n.cluster_count > 1 && n.max_parent_error < ROOT_PARENT_ERROR
            })
            .unwrap();
        let m = list(w)[ns[leaf].first_cluster as usize] as usize;
        let g = record_mut::<MeshletRecord>(w, SECTION_MESHLETS, m).parent_group as usize;
        record_mut::<GroupRecord>(w, SECTION_GROUPS, g).child_count -= 1;
    });
}

/// The file format 3 wrote (the header without `node_count`, four sections): what an
/// asset baked before the hierarchy existed looks like.
fn format_3_file(asset: &MeshletAsset) -> Vec<u8> {
    let h = asset.header();
    let words: &[u32] = bytemuck::cast_slice(asset.bytes());
    let section = |i: usize| {
        let s = h.sections[i];
        &words[s.offset as usize..(s.offset + s.words) as usize]
    };
    let mut head: Vec<u32> = Vec::new();
    // By value: a byte array's address need not be aligned for a cast to words.
    head.extend(
        MAGIC
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])),
    );
    head.push(3);
    head.push(h.flags);
    head.extend_from_slice(&[0; 4]); // file size and checksum, set below
    head.extend_from_slice(&[h.meshlet_count, h.group_count, h.level_count, h.root_count]);
    head.extend_from_slice(&[h.lod0_meshlets, h.lod0_triangles, h.total_triangles]);
    head.extend_from_slice(&[h.total_vertices, h.lod0_vertices, h.dropped_degenerate]);
    for v in h
        .bounds_min
        .iter()
        .chain(&h.bounds_max)
        .chain(&h.quant_origin)
    {
        head.push(v.to_bits());
    }
    head.push(h.quant_step.to_bits());
    head.push(h.quant_bits);
    for v in h.uv_min.iter().chain(&h.uv_step) {
        head.push(v.to_bits());
    }
    let header_words = head.len() + 8;
    let mut body = Vec::new();
    for i in [
        SECTION_MESHLETS,
        SECTION_GROUPS,
        SECTION_CHILDREN,
        SECTION_PAYLOAD,
    ] {
        head.push((header_words + body.len()) as u32);
        head.push(section(i).len() as u32);
        body.extend_from_slice(section(i));
    }
    let size = ((head.len() + body.len()) * 4) as u64;
    head[4] = size as u32;
    head[5] = (size >> 32) as u32;
    // Format 3's checksum: the header (checksum words zero) seeds the body's XXH3-64.
    let seed = xxhash_rust::xxh3::xxh3_64(bytemuck::cast_slice(&head));
    let sum = xxhash_rust::xxh3::xxh3_64_with_seed(bytemuck::cast_slice(&body), seed);
    head[6] = sum as u32;
    head[7] = (sum >> 32) as u32;
    head.extend_from_slice(&body);
    bytemuck::cast_slice(&head).to_vec()
}

#[test]
fn an_asset_of_the_format_before_the_hierarchy_asks_to_be_rebaked() {
    let asset = bake(&procedural_mesh(6));
    let old = format_3_file(&asset);
    let dir = common::scratch("old-version");
    for (name, bytes) in [
        ("old.mlasset", old.clone()),
        // Cut shorter than this format's header: still the version, not "truncated".
        ("old-short.mlasset", old[..64].to_vec()),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, &bytes).unwrap();
        let err = MeshletAsset::load(&path).unwrap_err();
        assert!(
            matches!(err, SceneError::AssetVersion { found: 3, expected, .. } if expected == VERSION),
            "{name}: {err:?}"
        );
        let msg = err.to_string();
        assert!(
            msg.contains("version 3") && msg.contains("re-bake") && msg.contains(name),
            "{msg}"
        );
    }
    // This test writes the format before the current one.
    const { assert!(VERSION > 3) };
}
