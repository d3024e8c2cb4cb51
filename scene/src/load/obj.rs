//! Wavefront OBJ through `tobj`, with every object of the file merged into one mesh.

use std::io::BufReader;
use std::path::Path;

use glam::Vec3;

use crate::error::SceneError;
use crate::load::read_file;
use crate::mesh::Mesh;

/// Reads the OBJ file at `path` (its .mtl is not needed: only geometry is read).
pub fn load_obj(path: &Path) -> Result<Mesh, SceneError> {
    let bytes = read_file(path)?;
    parse_obj(path, &bytes)
}

/// Parses OBJ text. Polygons are fan-triangulated; vertices are split where normals or
/// texture coordinates differ (seams), which the builder sees through by position.
pub fn parse_obj(path: &Path, bytes: &[u8]) -> Result<Mesh, SceneError> {
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
    // Materials do not matter to geometry; a missing .mtl must not fail the load.
    let (models, _materials) = tobj::load_obj_buf(&mut reader, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| SceneError::Obj {
        path: path.to_owned(),
        reason: describe(e),
    })?;

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
    for model in &models {
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
        mesh.indices.extend(m.indices.iter().map(|&i| i + base));
    }
    Ok(mesh)
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
