//! glTF 2.0 (.gltf with external or embedded buffers, and .glb): every triangle
//! primitive of the default scene, with node transforms applied, merged into one mesh.
//!
//! The file is parsed without the crate's validation and read from its JSON directly:
//! the node tree is expanded by [`nodes`] (cycles and runaway instancing refused before
//! anything is allocated) and accessors by [`accessor`] (types, ranges and strides
//! checked before anything is read), so no damaged file reaches a reader that panics.

mod accessor;
mod buffers;
pub use buffers::percent_decode;
mod nodes;

use std::path::Path;

use glam::{Mat3, Vec3};
use gltf::json::validation::Checked;
use gltf::json::{Root, mesh::Mode};

use self::accessor::{Role, check, declared_count};
use self::buffers::load_buffers;
use self::nodes::{Instance, NodeError, expand};
use crate::error::SceneError;
use crate::load::{LoadOptions, read_file};
use crate::mesh::Mesh;

/// [`load_gltf_with`] with the default [`LoadOptions`].
pub fn load_gltf(path: &Path) -> Result<Mesh, SceneError> {
    load_gltf_with(path, &LoadOptions::default())
}

/// Reads the glTF or GLB file at `path`, refusing a node tree that would expand beyond
/// `options.max_triangles` before expanding it.
pub fn load_gltf_with(path: &Path, options: &LoadOptions) -> Result<Mesh, SceneError> {
    let budget = options.max_triangles;
    let bytes = read_file(path)?;
    let err = |reason: String| SceneError::Gltf {
        path: path.to_owned(),
        reason,
    };
    check_glb_header(&bytes).map_err(err)?;
    let gltf = gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| err(e.to_string()))?;
    let root: &Root = gltf.document.as_json();
    let position = Checked::Valid(gltf::Semantic::Positions);
    let normal = Checked::Valid(gltf::Semantic::Normals);
    let texcoord = Checked::Valid(gltf::Semantic::TexCoords(0));
    let mesh_name = |mi: usize| {
        root.meshes[mi]
            .name
            .clone()
            .unwrap_or_else(|| format!("#{mi}"))
    };

    // Per mesh: the triangles its accessors declare, which bounds the node expansion.
    let mut mesh_triangles = Vec::with_capacity(root.meshes.len());
    for (mi, m) in root.meshes.iter().enumerate() {
        let mut triangles = 0u64;
        for (pi, p) in m.primitives.iter().enumerate() {
            let Some(&pos) = p.attributes.get(&position) else {
                return Err(SceneError::GltfMissingPosition {
                    path: path.to_owned(),
                    mesh: mesh_name(mi),
                    primitive: pi,
                });
            };
            let at = |e: String| err(format!("mesh {:?} primitive {pi}: {e}", mesh_name(mi)));
            let corners = match p.indices {
                Some(i) => declared_count(root, i.value(), Role::Indices).map_err(at)?,
                None => declared_count(root, pos.value(), Role::Position).map_err(at)?,
            };
            triangles = triangles.saturating_add(corners / 3);
        }
        mesh_triangles.push(triangles);
    }

    let scene = root.scene.map(|s| s.value()).or(if root.scenes.is_empty() {
        None
    } else {
        Some(0)
    });
    let instances = match scene {
        Some(s) => {
            let scene = root.scenes.get(s).ok_or_else(|| {
                err(format!(
                    "the default scene is {s}, but the file has only {} scenes",
                    root.scenes.len()
                ))
            })?;
            let roots: Vec<usize> = scene.nodes.iter().map(|n| n.value()).collect();
            expand(root, &roots, &mesh_triangles, budget)
                .map_err(|e| node_error(path, root, e, budget))?
        }
        // No scene: every mesh untransformed rather than nothing.
        None => {
            let total: u64 = mesh_triangles.iter().fold(0, |a, &t| a.saturating_add(t));
            Mesh::check_limits(&path.display().to_string(), 0, total)?;
            if total > budget {
                return Err(over_budget(path, total, budget));
            }
            (0..root.meshes.len())
                .map(|mesh| Instance {
                    mesh,
                    transform: glam::Mat4::IDENTITY,
                })
                .collect()
        }
    };

    let buffers = load_buffers(root, gltf.blob.clone(), path)?;

    let mut mesh = Mesh {
        source: path.display().to_string(),
        ..Mesh::default()
    };
    let mut any_missing_uv = false;
    let mut uv_parts: Vec<Option<Vec<[f32; 2]>>> = Vec::new();
    let mut normals_complete = true;
    for Instance {
        mesh: mi,
        transform,
    } in &instances
    {
        let name = mesh_name(*mi);
        for (pi, p) in root.meshes[*mi].primitives.iter().enumerate() {
            let at = |e: String| err(format!("mesh {name:?} primitive {pi}: {e}"));
            match p.mode {
                Checked::Valid(Mode::Triangles) => {}
                Checked::Valid(other) => {
                    log::warn!(
                        "{}: mesh {name:?} primitive {pi} is {other:?}, not triangles; skipped",
                        path.display()
                    );
                    continue;
                }
                Checked::Invalid => {
                    return Err(at(
                        "unknown primitive mode; glTF modes are 0 to 6 (4 = triangles)".into(),
                    ));
                }
            }
            let pos = check(
                root,
                &buffers,
                p.attributes[&position].value(),
                Role::Position,
            )
            .map_err(at)?;
            let count = pos.count;
            Mesh::check_limits(&mesh.source, (mesh.positions.len() + count) as u64, 0)?;
            let accessor_of = |semantic: &Checked<gltf::Semantic>| p.attributes[semantic].value();
            let finite = |values: &[f32], width: usize, accessor: usize, role: &str| match values
                .iter()
                .position(|v| !v.is_finite())
            {
                None => Ok(()),
                Some(k) => Err(SceneError::NonFiniteAttribute {
                    source_name: path.display().to_string(),
                    location: format!(
                        "mesh {name:?} primitive {pi}, accessor {accessor}, element {}",
                        k / width
                    ),
                    attribute: role.to_owned(),
                    value: values[k],
                }),
            };
            let positions = pos.read_vec3(&buffers);
            finite(
                positions.as_flattened(),
                3,
                accessor_of(&position),
                "POSITION",
            )?;
            let base = mesh.positions.len() as u32;
            let normal_matrix = Mat3::from_mat4(*transform).inverse().transpose();
            match p.attributes.get(&normal) {
                Some(n) => {
                    let n = check(root, &buffers, n.value(), Role::Normal).map_err(at)?;
                    if n.count != count {
                        return Err(at(format!(
                            "NORMAL has {} elements, POSITION {count}",
                            n.count
                        )));
                    }
                    let read = n.read_vec3(&buffers);
                    finite(read.as_flattened(), 3, accessor_of(&normal), "NORMAL")?;
                    mesh.normals.extend(
                        read.into_iter()
                            .map(|n| (normal_matrix * Vec3::from(n)).normalize_or_zero()),
                    );
                }
                None => {
                    normals_complete = false;
                    mesh.normals.extend(std::iter::repeat_n(Vec3::ZERO, count));
                }
            }
            let uvs = match p.attributes.get(&texcoord) {
                Some(t) => {
                    let t = check(root, &buffers, t.value(), Role::TexCoord).map_err(at)?;
                    let read = t.read_vec2(&buffers);
                    finite(read.as_flattened(), 2, accessor_of(&texcoord), "TEXCOORD_0")?;
                    Some(read)
                }
                None => None,
            };
            match &uvs {
                Some(t) if t.len() == count => {}
                _ => any_missing_uv = true,
            }
            uv_parts.push(uvs);
            mesh.positions.extend(
                positions
                    .iter()
                    .map(|&p| transform.transform_point3(Vec3::from(p))),
            );
            let mut indices: Vec<u32> = match p.indices {
                Some(i) => check(root, &buffers, i.value(), Role::Indices)
                    .map_err(at)?
                    .read_indices(&buffers),
                None => (0..count as u32).collect(),
            };
            if !indices.len().is_multiple_of(3) {
                return Err(at(format!(
                    "{} indices is not a whole number of triangles",
                    indices.len()
                )));
            }
            if transform.determinant() < 0.0 {
                // A mirroring transform turns counter-clockwise into clockwise.
                for t in indices.chunks_exact_mut(3) {
                    t.swap(1, 2);
                }
            }
            if let Some(k) = indices.iter().position(|&i| i as usize >= count) {
                return Err(SceneError::IndexOutOfRange {
                    source_name: format!("{} (mesh {name:?}, primitive {pi})", path.display()),
                    triangle: k / 3,
                    index: indices[k],
                    vertex_count: count,
                });
            }
            mesh.indices.extend(indices.iter().map(|&i| i + base));
            Mesh::check_limits(&mesh.source, 0, (mesh.indices.len() / 3) as u64)?;
        }
    }
    if !normals_complete {
        // Normals from some primitives only: regenerate all, so shading is consistent.
        mesh.normals.clear();
    }
    if !any_missing_uv && !uv_parts.is_empty() {
        mesh.uvs = uv_parts.into_iter().flatten().flatten().collect();
    }
    Ok(mesh)
}

/// The GLB header's length, checked before the glTF crate subtracts the header size from
/// it (a length below 12 overflowed there).
fn check_glb_header(bytes: &[u8]) -> Result<(), String> {
    if !bytes.starts_with(b"glTF") {
        return Ok(());
    }
    let Some(length) = bytes.get(8..12) else {
        return Err(format!(
            "a .glb of {} bytes is shorter than its 12-byte header; it is truncated",
            bytes.len()
        ));
    };
    let length = u32::from_le_bytes([length[0], length[1], length[2], length[3]]) as usize;
    if length < 12 || length > bytes.len() {
        return Err(format!(
            "the GLB header says the file is {length} bytes, but it is {} bytes; it is \
             truncated or damaged",
            bytes.len()
        ));
    }
    Ok(())
}

fn over_budget(path: &Path, count: u64, budget: u64) -> SceneError {
    SceneError::TriangleBudget {
        path: path.to_owned(),
        count,
        budget,
        limit: crate::mesh::MAX_TRIANGLES,
    }
}

fn node_error(path: &Path, root: &Root, e: NodeError, budget: u64) -> SceneError {
    let source = path.display().to_string();
    let reason = match e {
        NodeError::MissingNode { parent, node } => format!(
            "{} lists node {node}, but the file has only {} nodes",
            parent.map_or("the scene".to_owned(), |p| format!("node {p}")),
            root.nodes.len()
        ),
        NodeError::MissingMesh { node, mesh } => format!(
            "node {node} refers to mesh {mesh}, but the file has only {} meshes",
            root.meshes.len()
        ),
        NodeError::Cycle { node, through } => format!(
            "node {node} is its own descendant (listed as a child of node {through}); \
             glTF node trees must not loop, fix the `children` lists"
        ),
        NodeError::BadTransform { node } => format!(
            "node {node} has a non-finite or zero-rotation transform; fix its matrix or TRS"
        ),
        NodeError::TooManyInstances { count } => format!(
            "the node tree expands to {count} node instances (more than {}); \
             subtrees are shared too many times over",
            nodes::MAX_NODE_INSTANCES
        ),
        NodeError::TooManyTriangles { count } if count <= crate::mesh::MAX_TRIANGLES => {
            return over_budget(path, count, budget);
        }
        NodeError::TooManyTriangles { count } => {
            return SceneError::TooLarge {
                source_name: format!("{source} (expanded node tree)"),
                what: "triangles",
                count,
                limit: crate::mesh::MAX_TRIANGLES,
            };
        }
    };
    SceneError::Gltf {
        path: path.to_owned(),
        reason,
    }
}
