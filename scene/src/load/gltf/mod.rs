//! glTF 2.0 (.gltf with external or embedded buffers, and .glb). A file's default scene
//! is read two ways: kept as a scene ([`load_gltf_scene`]: each mesh read once, in its
//! own space, and each node that places it an instance with its world transform, plus
//! the cameras the nodes carry), or merged into one mesh with the node transforms
//! applied ([`load_gltf`]), for baking one asset from a file.
//!
//! The file is parsed without the crate's validation and read from its JSON directly:
//! the node tree is expanded by [`nodes`] (cycles and runaway instancing refused before
//! anything is allocated) and accessors by [`accessor`] (types, ranges and strides
//! checked before anything is read), so no damaged file reaches a reader that panics.

mod accessor;
mod buffers;
mod compressed;
mod draco;
pub use buffers::{percent_decode, referenced_path};
mod images;
pub use images::{SceneTexture, Wrap};
mod materials;
pub use materials::{
    AlphaMode, DEFAULT_MATERIAL, IDENTITY_UV_TRANSFORM, SceneMaterial, TextureRef, UvTransform,
    texture_transform,
};
mod nodes;
mod scene;
pub use scene::{
    CameraProjection, GltfScene, SceneCamera, SceneInstance, SceneMesh, load_gltf_scene,
    load_gltf_scene_with,
};

use std::path::Path;

use glam::{Mat3, Mat4, Vec3};
use gltf::json::validation::Checked;
use gltf::json::{Root, mesh::Mode};

use self::accessor::{Role, check, declared_count};
use self::buffers::load_buffers;
use self::nodes::{NodeError, Placement, expand};
use crate::error::SceneError;
use crate::load::{LoadOptions, read_file};
use crate::mesh::Mesh;

/// [`load_gltf_with`] with the default [`LoadOptions`].
pub fn load_gltf(path: &Path) -> Result<Mesh, SceneError> {
    load_gltf_with(path, &LoadOptions::default())
}

/// Reads the glTF or GLB file at `path` as one mesh: every triangle primitive of every
/// node's mesh, transformed into world space, refusing a node tree that would expand
/// beyond `options.max_triangles` before expanding it.
pub fn load_gltf_with(path: &Path, options: &LoadOptions) -> Result<Mesh, SceneError> {
    let mut file = GltfFile::open(path)?;
    let placed = file.placements(Some(options.max_triangles))?;
    let buffers = file.buffers()?;
    // Each mesh read once, however many nodes place it.
    let mut meshes: Vec<Option<Option<Mesh>>> = vec![None; file.root().meshes.len()];
    let mut merged = Mesh {
        source: path.display().to_string(),
        ..Mesh::default()
    };
    let (mut normals, mut uvs, mut colors) = (true, true, false);
    for Placement {
        mesh, transform, ..
    } in &placed
    {
        let Some(m) = mesh else { continue };
        if meshes[*m].is_none() {
            // One mesh for a single material: the slots of the parts are not kept.
            meshes[*m] = Some(file.read_mesh(&buffers, *m)?.map(|(mut mesh, _)| {
                mesh.materials.clear();
                mesh
            }));
        }
        let Some(Some(part)) = &meshes[*m] else {
            continue;
        };
        Mesh::check_limits(
            &merged.source,
            (merged.positions.len() + part.positions.len()) as u64,
            ((merged.indices.len() + part.indices.len()) / 3) as u64,
        )?;
        normals &= !part.normals.is_empty();
        uvs &= part.has_uvs();
        colors |= part.has_colors();
        append_transformed(&mut merged, part, *transform);
    }
    if !normals {
        // Normals from some meshes only: regenerate all, so shading is consistent.
        merged.normals.clear();
    }
    if !uvs {
        merged.uvs.clear();
    }
    if !colors {
        merged.colors.clear();
    }
    Ok(merged)
}

/// Appends `part` placed by `transform` to `into`: positions transformed, normals by
/// the inverse transpose, and the winding flipped where the transform mirrors (a
/// mirroring transform turns counter-clockwise into clockwise).
fn append_transformed(into: &mut Mesh, part: &Mesh, transform: Mat4) {
    let base = into.positions.len() as u32;
    into.positions.extend(
        part.positions
            .iter()
            .map(|&p| transform.transform_point3(p)),
    );
    let normal_matrix = Mat3::from_mat4(transform).inverse().transpose();
    into.normals.extend(
        part.normals
            .iter()
            .map(|&n| (normal_matrix * n).normalize_or_zero()),
    );
    into.uvs.extend_from_slice(&part.uvs);
    // White where a part has no colours (glTF's default); cleared after merging when no
    // part has any.
    match part.has_colors() {
        true => into.colors.extend_from_slice(&part.colors),
        false => into
            .colors
            .extend(std::iter::repeat_n([1.0; 4], part.positions.len())),
    }
    let mirrored = transform.determinant() < 0.0;
    for t in part.indices.chunks_exact(3) {
        let [a, b, c] = [t[0] + base, t[1] + base, t[2] + base];
        into.indices
            .extend_from_slice(&if mirrored { [a, c, b] } else { [a, b, c] });
    }
}

/// Extensions a file may require that the loader reads (the material extensions meshlight
/// ignores are never required by a valid file, as they only add to the core material).
const READ_EXTENSIONS: &[&str] = &[
    compressed::EXTENSION,
    draco::EXTENSION,
    "KHR_mesh_quantization",
];

/// A parsed glTF file: its JSON checked only as far as each step needs.
struct GltfFile<'p> {
    path: &'p Path,
    root: Root,
    /// A `.glb`'s binary chunk.
    blob: Option<Vec<u8>>,
}

impl<'p> GltfFile<'p> {
    fn open(path: &'p Path) -> Result<Self, SceneError> {
        let bytes = read_file(path)?;
        let err = |reason: String| SceneError::Gltf {
            path: path.to_owned(),
            reason,
        };
        check_glb_header(&bytes).map_err(err)?;
        let gltf =
            gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| err(e.to_string()))?;
        let file = Self {
            path,
            root: gltf.document.into_json(),
            blob: gltf.blob,
        };
        file.check_extensions()?;
        Ok(file)
    }

    /// Refuses a file that requires an extension this loader does not read (its data
    /// would be misread: a Basis Universal texture has no PNG or JPEG to decode),
    /// naming the extension and a way out.
    fn check_extensions(&self) -> Result<(), SceneError> {
        let root = self.root();
        if let Some(unread) = root
            .extensions_required
            .iter()
            .find(|e| !READ_EXTENSIONS.contains(&e.as_str()))
        {
            let way_out = match unread.as_str() {
                "KHR_texture_basisu" | "EXT_texture_webp" | "EXT_texture_avif" => {
                    "convert its textures to PNG or JPEG, e.g. with glTF-Transform's \
                     `png` or `jpeg` commands"
                }
                _ => "export the scene again without it",
            };
            return Err(self.err(format!(
                "it requires the extension {unread}, which meshlight does not read; {way_out}"
            )));
        }
        Ok(())
    }

    fn root(&self) -> &Root {
        &self.root
    }

    fn err(&self, reason: String) -> SceneError {
        SceneError::Gltf {
            path: self.path.to_owned(),
            reason,
        }
    }

    fn mesh_name(&self, mi: usize) -> String {
        self.root().meshes[mi]
            .name
            .clone()
            .unwrap_or_else(|| format!("#{mi}"))
    }

    /// Per mesh, the triangles its accessors declare (before anything is read), which
    /// bounds what the node tree may expand to.
    fn mesh_triangles(&self) -> Result<Vec<u64>, SceneError> {
        let root = self.root();
        let position = Checked::Valid(gltf::Semantic::Positions);
        let mut out = Vec::with_capacity(root.meshes.len());
        for (mi, m) in root.meshes.iter().enumerate() {
            let mut triangles = 0u64;
            for (pi, p) in m.primitives.iter().enumerate() {
                let Some(&pos) = p.attributes.get(&position) else {
                    return Err(SceneError::GltfMissingPosition {
                        path: self.path.to_owned(),
                        mesh: self.mesh_name(mi),
                        primitive: pi,
                    });
                };
                let at = |e: String| {
                    self.err(format!("mesh {:?} primitive {pi}: {e}", self.mesh_name(mi)))
                };
                let corners = match p.indices {
                    Some(i) => declared_count(root, i.value(), Role::Indices).map_err(at)?,
                    None => declared_count(root, pos.value(), Role::Position).map_err(at)?,
                };
                triangles = triangles.saturating_add(corners / 3);
            }
            out.push(triangles);
        }
        Ok(out)
    }

    /// Every node of the default scene with its world transform (every mesh
    /// untransformed where the file has no scene). With `expanded_budget`, a tree whose
    /// placed meshes add up to more triangles is refused before it is expanded.
    fn placements(&self, expanded_budget: Option<u64>) -> Result<Vec<Placement>, SceneError> {
        let root = self.root();
        let mesh_triangles = self.mesh_triangles()?;
        let scene = root.scene.map(|s| s.value()).or(if root.scenes.is_empty() {
            None
        } else {
            Some(0)
        });
        match scene {
            Some(s) => {
                let scene = root.scenes.get(s).ok_or_else(|| {
                    self.err(format!(
                        "the default scene is {s}, but the file has only {} scenes",
                        root.scenes.len()
                    ))
                })?;
                let roots: Vec<usize> = scene.nodes.iter().map(|n| n.value()).collect();
                expand(root, &roots, &mesh_triangles, expanded_budget)
                    .map_err(|e| node_error(self.path, root, e, expanded_budget))
            }
            // No scene: every mesh untransformed rather than nothing.
            None => {
                let total: u64 = mesh_triangles.iter().fold(0, |a, &t| a.saturating_add(t));
                Mesh::check_limits(&self.path.display().to_string(), 0, total)?;
                if let Some(budget) = expanded_budget.filter(|&b| total > b) {
                    return Err(over_budget(self.path, total, budget));
                }
                Ok((0..root.meshes.len())
                    .map(|mesh| Placement {
                        node: None,
                        mesh: Some(mesh),
                        camera: None,
                        transform: Mat4::IDENTITY,
                    })
                    .collect())
            }
        }
    }

    /// The file's buffers, with its compressed views and Draco-compressed primitives
    /// decoded (each such view or accessor then points at a buffer of its own, appended
    /// after the file's).
    fn buffers(&mut self) -> Result<Vec<Vec<u8>>, SceneError> {
        let mut buffers = load_buffers(&self.root, self.blob.take(), self.path)?;
        compressed::decode_views(&mut self.root, &mut buffers).map_err(|e| self.err(e))?;
        draco::decode_primitives(&mut self.root, &mut buffers).map_err(|e| self.err(e))?;
        Ok(buffers)
    }

    /// Mesh `mi`'s triangle primitives merged, in the mesh's own space, each triangle
    /// with its material slot ([`Mesh::materials`]), and the file's material behind
    /// each slot (a primitive's, or [`DEFAULT_MATERIAL`]); `None` when it has no
    /// triangles (points or lines only, each skipped with a warning). Normals are kept
    /// only where every primitive has them, UVs likewise; vertex colours where any
    /// primitive has them (white for the others).
    fn read_mesh(
        &self,
        buffers: &[Vec<u8>],
        mi: usize,
    ) -> Result<Option<(Mesh, Vec<u32>)>, SceneError> {
        let root = self.root();
        let path = self.path;
        let position = Checked::Valid(gltf::Semantic::Positions);
        let normal = Checked::Valid(gltf::Semantic::Normals);
        let texcoord = Checked::Valid(gltf::Semantic::TexCoords(0));
        let color = Checked::Valid(gltf::Semantic::Colors(0));
        let name = self.mesh_name(mi);
        let mut mesh = Mesh {
            source: format!("{} (mesh {name:?})", path.display()),
            ..Mesh::default()
        };
        let (mut normals_complete, mut uvs_complete, mut any) = (true, true, false);
        let mut any_colors = false;
        // The file's material behind each of the mesh's slots, in order of first use.
        let mut slots: Vec<u32> = Vec::new();
        for (pi, p) in root.meshes[mi].primitives.iter().enumerate() {
            let at = |e: String| self.err(format!("mesh {name:?} primitive {pi}: {e}"));
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
            any = true;
            let material = match p.material {
                Some(m) if m.value() >= root.materials.len() => {
                    return Err(at(format!(
                        "its material is {}, but the file has only {} materials",
                        m.value(),
                        root.materials.len()
                    )));
                }
                Some(m) => m.value() as u32,
                None => DEFAULT_MATERIAL,
            };
            let pos = check(
                root,
                buffers,
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
            let positions = pos.read_vec3(buffers);
            finite(
                positions.as_flattened(),
                3,
                accessor_of(&position),
                "POSITION",
            )?;
            let base = mesh.positions.len() as u32;
            match p.attributes.get(&normal) {
                Some(n) => {
                    let n = check(root, buffers, n.value(), Role::Normal).map_err(at)?;
                    if n.count != count {
                        return Err(at(format!(
                            "NORMAL has {} elements, POSITION {count}",
                            n.count
                        )));
                    }
                    let read = n.read_vec3(buffers);
                    finite(read.as_flattened(), 3, accessor_of(&normal), "NORMAL")?;
                    mesh.normals
                        .extend(read.into_iter().map(|n| Vec3::from(n).normalize_or_zero()));
                }
                None => {
                    normals_complete = false;
                    mesh.normals.extend(std::iter::repeat_n(Vec3::ZERO, count));
                }
            }
            match p.attributes.get(&texcoord) {
                Some(t) => {
                    let t = check(root, buffers, t.value(), Role::TexCoord).map_err(at)?;
                    let read = t.read_vec2(buffers);
                    finite(read.as_flattened(), 2, accessor_of(&texcoord), "TEXCOORD_0")?;
                    if read.len() == count {
                        mesh.uvs.extend(read);
                    } else {
                        uvs_complete = false;
                    }
                }
                None => uvs_complete = false,
            }
            // White where a primitive has no colours, glTF's default.
            match p.attributes.get(&color) {
                Some(c) => {
                    let c = check(root, buffers, c.value(), Role::Color).map_err(at)?;
                    if c.count != count {
                        return Err(at(format!(
                            "COLOR_0 has {} elements, POSITION {count}",
                            c.count
                        )));
                    }
                    let read = c.read_rgba(buffers);
                    finite(read.as_flattened(), 4, accessor_of(&color), "COLOR_0")?;
                    mesh.colors
                        .extend(read.into_iter().map(|c| c.map(|v| v.clamp(0.0, 1.0))));
                    any_colors = true;
                }
                None => mesh.colors.extend(std::iter::repeat_n([1.0; 4], count)),
            }
            mesh.positions
                .extend(positions.iter().map(|&p| Vec3::from(p)));
            let indices: Vec<u32> = match p.indices {
                Some(i) => check(root, buffers, i.value(), Role::Indices)
                    .map_err(at)?
                    .read_indices(buffers),
                None => (0..count as u32).collect(),
            };
            if !indices.len().is_multiple_of(3) {
                return Err(at(format!(
                    "{} indices is not a whole number of triangles",
                    indices.len()
                )));
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
            let slot = match slots.iter().position(|&m| m == material) {
                Some(slot) => slot as u32,
                None => {
                    slots.push(material);
                    (slots.len() - 1) as u32
                }
            };
            if slot >= crate::mesh::MAX_MATERIALS {
                return Err(SceneError::TooManyMaterials {
                    source_name: mesh.source.clone(),
                    triangle: mesh.indices.len() / 3,
                    slot,
                    limit: crate::mesh::MAX_MATERIALS,
                });
            }
            mesh.materials
                .extend(std::iter::repeat_n(slot, indices.len() / 3));
            Mesh::check_limits(&mesh.source, 0, (mesh.indices.len() / 3) as u64)?;
        }
        if !any {
            return Ok(None);
        }
        if !normals_complete {
            mesh.normals.clear();
        }
        if !uvs_complete {
            mesh.uvs.clear();
        }
        if !any_colors {
            mesh.colors.clear();
        }
        if slots.len() <= 1 {
            // One material: every triangle's slot is 0, which an empty list says.
            mesh.materials.clear();
        }
        Ok(Some((mesh, slots)))
    }
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

fn node_error(path: &Path, root: &Root, e: NodeError, budget: Option<u64>) -> SceneError {
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
            return over_budget(path, count, budget.unwrap_or(crate::mesh::MAX_TRIANGLES));
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
