//! Wavefront OBJ through `tobj`, with every object of the file merged into one mesh.

use std::io::BufReader;
use std::path::Path;

use glam::Vec3;

use crate::error::SceneError;
use crate::load::gltf::referenced_path;
use crate::load::read_file;
use crate::mesh::Mesh;
use crate::texture::{Image, decode_image};

/// Reads the OBJ file at `path` (its .mtl is not needed: only geometry is read).
pub fn load_obj(path: &Path) -> Result<Mesh, SceneError> {
    let bytes = read_file(path)?;
    parse_obj(path, &bytes)
}

/// Parses OBJ text. Polygons are fan-triangulated; vertices are split where normals or
/// texture coordinates differ (seams), which the builder sees through by position.
pub fn parse_obj(path: &Path, bytes: &[u8]) -> Result<Mesh, SceneError> {
    // Materials do not matter to geometry; a missing .mtl must not fail the load.
    let (models, _) = parse_models(path, bytes, |_| Err(tobj::LoadError::OpenFileFailed))?;
    Ok(merge(path, &models, |_| 0).0)
}

fn parse_models(
    path: &Path,
    bytes: &[u8],
    material_loader: impl Fn(&Path) -> tobj::MTLLoadResult,
) -> Result<(Vec<tobj::Model>, Vec<tobj::Material>), SceneError> {
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    check_finite(path, bytes)?;
    check_face_indices(bytes).map_err(|reason| SceneError::Obj {
        path: path.to_owned(),
        reason,
    })?;
    let mut reader = BufReader::new(bytes);
    let (models, materials) =
        tobj::load_obj_buf(&mut reader, &options, material_loader).map_err(|e| {
            SceneError::Obj {
                path: path.to_owned(),
                reason: describe(e),
            }
        })?;
    // A material file that failed was reported by the loader.
    Ok((models, materials.unwrap_or_default()))
}

/// Every model merged into one mesh; `slot_of(model)` gives each model's triangles
/// their material slot, kept only when some slot is not 0. Also returns how many slots.
fn merge(
    path: &Path,
    models: &[tobj::Model],
    mut slot_of: impl FnMut(&tobj::Model) -> u32,
) -> (Mesh, u32) {
    let mut mesh = Mesh {
        source: path.display().to_string(),
        ..Mesh::default()
    };
    let all_normals = models
        .iter()
        .all(|m| m.mesh.normals.len() == m.mesh.positions.len());
    let all_uvs = models
        .iter()
        .all(|m| m.mesh.texcoords.len() / 2 == m.mesh.positions.len() / 3)
        && models.iter().any(|m| !m.mesh.texcoords.is_empty());
    // `v x y z r g b` lines: the colours tools write, read as sRGB like a colour
    // texture's (OBJ names no colour space), alpha 1.
    let all_colors = models
        .iter()
        .all(|m| m.mesh.vertex_color.len() == m.mesh.positions.len())
        && models.iter().any(|m| !m.mesh.vertex_color.is_empty());
    let mut slots = 1;
    for model in models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        if all_normals {
            mesh.normals.extend(
                m.normals
                    .chunks_exact(3)
                    .map(|n| Vec3::new(n[0], n[1], n[2])),
            );
        }
        if all_uvs {
            mesh.uvs
                .extend(m.texcoords.chunks_exact(2).map(|t| [t[0], t[1]]));
        }
        if all_colors {
            mesh.colors.extend(m.vertex_color.chunks_exact(3).map(|c| {
                let linear = crate::texture::srgb_to_linear;
                [linear(c[0]), linear(c[1]), linear(c[2]), 1.0]
            }));
        }
        mesh.indices.extend(m.indices.iter().map(|&i| i + base));
        let slot = slot_of(model);
        slots = slots.max(slot + 1);
        mesh.materials
            .extend(std::iter::repeat_n(slot, m.indices.len() / 3));
    }
    if slots == 1 {
        mesh.materials.clear();
    }
    (mesh, slots)
}

/// One material of an OBJ file's `.mtl`, as meshlight draws it.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjMaterial {
    /// Its `newmtl` name (`default` for faces that name none).
    pub name: String,
    /// `Kd`, the diffuse colour, taken as linear RGB (white where absent).
    pub diffuse: [f32; 3],
    /// `map_Kd`, decoded, its rows flipped so that OBJ's V (up the image) addresses
    /// it as glTF's V (down the image) does; `None` where absent or unusable (the
    /// warning says why).
    pub diffuse_texture: Option<std::sync::Arc<Image>>,
}

/// An OBJ file with its materials: the mesh with a slot per material its faces use (in
/// order of first use), and each slot's material.
#[derive(Debug, Clone)]
pub struct ObjScene {
    /// The geometry, `materials` holding the slots (empty when there is one).
    pub mesh: Mesh,
    /// Per slot, its material.
    pub materials: Vec<ObjMaterial>,
    /// What could not be used (a missing `.mtl`, a texture that does not decode): the
    /// mesh is drawn with what remains.
    pub warnings: Vec<String>,
}

/// Reads the OBJ file at `path` with the `.mtl` files it names (beside it, under the
/// rule glTF's URIs follow: relative, inside the model's folder) and their `map_Kd`
/// textures. A missing or unreadable `.mtl` or texture is a warning, not an error: the
/// geometry is still drawn, in white or the `Kd` colour.
pub fn load_obj_scene(path: &Path) -> Result<ObjScene, SceneError> {
    let bytes = read_file(path)?;
    let warnings = std::cell::RefCell::new(Vec::new());
    let warn = |w: String| warnings.borrow_mut().push(w);
    let (models, materials) = parse_models(path, &bytes, |mtl| {
        let name = mtl.to_string_lossy();
        let read = referenced_path(path, &name)
            .map_err(|why| format!("{name} {why}"))
            .and_then(|p| read_file(&p).map_err(|e| e.to_string()));
        match read {
            Ok(text) => tobj::load_mtl_buf(&mut BufReader::new(&text[..])).inspect_err(|e| {
                warn(format!(
                    "{}: its material file {name} does not parse ({e}); drawn in white",
                    path.display()
                ))
            }),
            Err(why) => {
                warn(format!(
                    "{}: its material file cannot be used ({why}); drawn in white",
                    path.display()
                ));
                Err(tobj::LoadError::OpenFileFailed)
            }
        }
    })?;
    // Slots in order of first use; faces with no material share one.
    let mut order: Vec<Option<usize>> = Vec::new();
    let (mesh, _) = merge(path, &models, |model| {
        let id = model.mesh.material_id.filter(|&i| i < materials.len());
        match order.iter().position(|&o| o == id) {
            Some(slot) => slot as u32,
            None => {
                order.push(id);
                order.len() as u32 - 1
            }
        }
    });
    let slots = order
        .into_iter()
        .map(|id| match id.map(|i| &materials[i]) {
            None => ObjMaterial {
                name: "default".into(),
                diffuse: [1.0; 3],
                diffuse_texture: None,
            },
            Some(m) => ObjMaterial {
                name: m.name.clone(),
                diffuse: m
                    .diffuse
                    .filter(|d| d.iter().all(|c| c.is_finite()))
                    .map_or([1.0; 3], |d| d.map(|c| c.clamp(0.0, 1.0))),
                diffuse_texture: m.diffuse_texture.as_ref().and_then(|t| {
                    match load_texture(path, t) {
                        Ok(image) => Some(std::sync::Arc::new(image)),
                        Err(why) => {
                            warn(format!(
                                "{}: material {:?}: its map_Kd {why}; drawn in its Kd colour",
                                path.display(),
                                m.name
                            ));
                            None
                        }
                    }
                }),
            },
        })
        .collect();
    Ok(ObjScene {
        mesh,
        materials: slots,
        warnings: warnings.into_inner(),
    })
}

/// Whether OBJ text names a material library (a `mtllib` line): without one, every face
/// is in the default material, and [`load_obj_scene`] has nothing to add to [`parse_obj`].
pub fn names_material_library(bytes: &[u8]) -> bool {
    bytes.split(|&b| b == b'\n').any(|line| {
        line.split(|b| b.is_ascii_whitespace())
            .find(|w| !w.is_empty())
            == Some(b"mtllib")
    })
}

/// A `map_Kd` file beside the model, decoded and flipped to glTF's V.
fn load_texture(model: &Path, name: &str) -> Result<Image, String> {
    let file = referenced_path(model, name).map_err(|why| format!("{name} {why}"))?;
    let bytes = read_file(&file).map_err(|e| e.to_string())?;
    let mut image = decode_image(&bytes, name).map_err(|e| e.to_string())?;
    let row = image.width as usize * 4;
    let rows: Vec<&[u8]> = image.rgba.chunks_exact(row).rev().collect();
    image.rgba = rows.concat();
    Ok(image)
}

/// Refuses a `v`, `vt` or `vn` line holding a number that is not finite: `inf`, `nan`,
/// or one too large for single precision (`1e39` reads as infinity). The mesh would
/// otherwise reach the builder with a NaN texture coordinate silently accepted, or an
/// infinity found only later without its line.
fn check_finite(path: &Path, bytes: &[u8]) -> Result<(), SceneError> {
    for (n, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let mut words = line
            .split(|b| b.is_ascii_whitespace())
            .filter(|w| !w.is_empty());
        let attribute = match words.next() {
            Some(b"v") => "position (`v`)",
            Some(b"vt") => "texture coordinate (`vt`)",
            Some(b"vn") => "normal (`vn`)",
            _ => continue,
        };
        for word in words {
            // Malformed numbers are tobj's to report.
            let Some(value) = std::str::from_utf8(word)
                .ok()
                .and_then(|w| w.parse::<f32>().ok())
            else {
                continue;
            };
            if !value.is_finite() {
                return Err(SceneError::NonFiniteAttribute {
                    source_name: path.display().to_string(),
                    location: format!("line {}", n + 1),
                    attribute: attribute.into(),
                    value,
                });
            }
        }
    }
    Ok(())
}

/// Checks every face index against the `v`, `vt` and `vn` lines before `tobj` sees it:
/// `tobj` turns an index before the start of the file (`-11` with three entries) into a
/// huge one and overflows multiplying it, and so would an absurdly large index.
fn check_face_indices(bytes: &[u8]) -> Result<(), String> {
    // Totals first: a face may refer to entries listed after it.
    let mut totals = [0i64; 3];
    for line in bytes.split(|&b| b == b'\n') {
        match line
            .split(|b| b.is_ascii_whitespace())
            .find(|w| !w.is_empty())
        {
            Some(b"v") => totals[0] += 1,
            Some(b"vt") => totals[1] += 1,
            Some(b"vn") => totals[2] += 1,
            _ => {}
        }
    }
    let names = ["vertex", "texture coordinate", "normal"];
    let mut seen = [0i64; 3];
    for (n, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let mut words = line
            .split(|b| b.is_ascii_whitespace())
            .filter(|w| !w.is_empty());
        match words.next() {
            Some(b"v") => seen[0] += 1,
            Some(b"vt") => seen[1] += 1,
            Some(b"vn") => seen[2] += 1,
            Some(b"f") => {
                for corner in words {
                    for (k, part) in corner.split(|&b| b == b'/').enumerate().take(3) {
                        let Some(i) = std::str::from_utf8(part)
                            .ok()
                            .filter(|p| !p.is_empty())
                            .and_then(|p| p.parse::<i64>().ok())
                        else {
                            continue; // empty (`1//1`) or malformed: tobj reports those
                        };
                        let valid = if i < 0 {
                            seen[k] + i >= 0
                        } else {
                            i >= 1 && i <= totals[k]
                        };
                        if !valid {
                            return Err(format!(
                                "line {}: a face refers to {} index {i}, but the file has {} \
                                 ({} before this line); the file is truncated or corrupt",
                                n + 1,
                                names[k],
                                totals[k],
                                seen[k]
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}

fn describe(e: tobj::LoadError) -> String {
    use tobj::LoadError as E;
    match e {
        E::PositionParseError => "a `v` line has a malformed coordinate; each needs 3 numbers".into(),
        E::NormalParseError => "a `vn` line has a malformed coordinate; each needs 3 numbers".into(),
        E::TexcoordParseError => "a `vt` line has a malformed coordinate".into(),
        E::FaceParseError => "an `f` line is malformed; faces list 3 or more vertex indices".into(),
        E::InvalidPolygon => "a face has fewer than 3 vertices".into(),
        E::FaceVertexOutOfBounds => {
            "a face refers to a vertex index beyond the `v` lines of the file; the file is truncated or corrupt".into()
        }
        E::FaceTexCoordOutOfBounds => "a face refers to a texture coordinate that does not exist".into(),
        E::FaceNormalOutOfBounds => "a face refers to a normal that does not exist".into(),
        other => other.to_string(),
    }
}
