//! glTF 2.0 (.gltf with external or embedded buffers, and .glb): every triangle
//! primitive of the default scene, with node transforms applied, merged into one mesh.

use std::path::Path;

use glam::{Mat3, Mat4, Vec3};

use crate::error::SceneError;
use crate::load::read_file;
use crate::mesh::Mesh;

pub fn load_gltf(path: &Path) -> Result<Mesh, SceneError> {
    let bytes = read_file(path)?;
    let err = |reason: String| SceneError::Gltf {
        path: path.to_owned(),
        reason,
    };
    // The validator reports a primitive without POSITION as generic "missing data"; look
    // for that case first so the error can name the mesh and primitive.
    if let Ok(raw) = gltf::Gltf::from_slice_without_validation(&bytes) {
        // The raw JSON, not the accessor API: unvalidated indices may be out of range.
        let position = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
        for (mi, m) in raw.document.as_json().meshes.iter().enumerate() {
            for (pi, p) in m.primitives.iter().enumerate() {
                if !p.attributes.contains_key(&position) {
                    return Err(SceneError::GltfMissingPosition {
                        path: path.to_owned(),
                        mesh: m.name.clone().unwrap_or_else(|| format!("#{mi}")),
                        primitive: pi,
                    });
                }
            }
        }
    }
    let gltf = gltf::Gltf::from_slice(&bytes).map_err(|e| err(e.to_string()))?;
    let base = path.parent();
    let buffers = gltf::import_buffers(&gltf.document, base, gltf.blob.clone()).map_err(|e| {
        err(format!(
            "cannot load its buffers ({e}); keep .bin files beside the .gltf"
        ))
    })?;

    let mut mesh = Mesh {
        source: path.display().to_string(),
        ..Mesh::default()
    };
    let mut primitives = Vec::new();
    let scene = gltf
        .document
        .default_scene()
        .or_else(|| gltf.document.scenes().next());
    match scene {
        Some(scene) => {
            for node in scene.nodes() {
                collect(node, Mat4::IDENTITY, &mut primitives);
            }
        }
        // No scene: take every mesh untransformed rather than nothing.
        None => {
            for m in gltf.document.meshes() {
                primitives.push((m, Mat4::IDENTITY));
            }
        }
    }

    let mut any_missing_uv = false;
    let mut uv_parts: Vec<Option<Vec<[f32; 2]>>> = Vec::new();
    let mut normals_complete = true;
    for (gmesh, transform) in &primitives {
        let mesh_name = gmesh
            .name()
            .map(str::to_owned)
            .unwrap_or_else(|| format!("#{}", gmesh.index()));
        for (pi, primitive) in gmesh.primitives().enumerate() {
            if primitive.mode() != gltf::mesh::Mode::Triangles {
                log::warn!(
                    "{}: mesh {mesh_name:?} primitive {pi} is not triangles; skipped",
                    path.display()
                );
                continue;
            }
            let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let positions: Vec<Vec3> = reader
                .read_positions()
                .ok_or_else(|| SceneError::GltfMissingPosition {
                    path: path.to_owned(),
                    mesh: mesh_name.clone(),
                    primitive: pi,
                })?
                .map(Vec3::from)
                .collect();
            let base = mesh.positions.len() as u32;
            Mesh::check_limits(
                &mesh.source,
                (mesh.positions.len() + positions.len()) as u64,
                0,
            )?;
            let normal_matrix = Mat3::from_mat4(*transform).inverse().transpose();
            match reader.read_normals() {
                Some(n) => {
                    let n: Vec<Vec3> = n
                        .map(|n| (normal_matrix * Vec3::from(n)).normalize_or_zero())
                        .collect();
                    if n.len() != positions.len() {
                        return Err(err(format!(
                            "mesh {mesh_name:?} primitive {pi}: NORMAL has {} elements, POSITION {}",
                            n.len(),
                            positions.len()
                        )));
                    }
                    mesh.normals.extend(n);
                }
                None => {
                    normals_complete = false;
                    mesh.normals
                        .extend(std::iter::repeat_n(Vec3::ZERO, positions.len()));
                }
            }
            let uvs = reader
                .read_tex_coords(0)
                .map(|t| t.into_f32().collect::<Vec<_>>());
            match &uvs {
                Some(t) if t.len() == positions.len() => {}
                _ => any_missing_uv = true,
            }
            uv_parts.push(uvs);
            mesh.positions
                .extend(positions.iter().map(|&p| transform.transform_point3(p)));
            let count = positions.len() as u32;
            let flip = transform.determinant() < 0.0;
            let mut indices: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..count).collect(),
            };
            if !indices.len().is_multiple_of(3) {
                return Err(err(format!(
                    "mesh {mesh_name:?} primitive {pi}: {} indices is not a whole number of triangles",
                    indices.len()
                )));
            }
            if flip {
                // A mirroring transform turns counter-clockwise into clockwise.
                for t in indices.chunks_exact_mut(3) {
                    t.swap(1, 2);
                }
            }
            if let Some(at) = indices.iter().position(|&i| i >= count) {
                return Err(SceneError::IndexOutOfRange {
                    source_name: format!("{} (mesh {mesh_name:?}, primitive {pi})", path.display()),
                    triangle: at / 3,
                    index: indices[at],
                    vertex_count: count as usize,
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

fn collect<'a>(node: gltf::Node<'a>, parent: Mat4, out: &mut Vec<(gltf::Mesh<'a>, Mat4)>) {
    let local = Mat4::from_cols_array_2d(&node.transform().matrix());
    let world = parent * local;
    if let Some(m) = node.mesh() {
        out.push((m, world));
    }
    for child in node.children() {
        collect(child, world, out);
    }
}
