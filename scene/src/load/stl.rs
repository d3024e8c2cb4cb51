//! STL, ASCII and binary. STL stores unconnected triangles; vertices are welded by exact
//! position so that the builder sees a connected surface, and facet normals are
//! discarded in favour of generated smooth ones (a welded vertex has no single facet).

use std::collections::HashMap;
use std::path::Path;

use glam::Vec3;

use crate::error::SceneError;
use crate::load::read_file;
use crate::mesh::Mesh;

/// Reads the STL file at `path`, binary or ASCII (told apart by its size and start).
pub fn load_stl(path: &Path) -> Result<Mesh, SceneError> {
    let bytes = read_file(path)?;
    parse_stl(path, &bytes)
}

/// Binary when the size matches the triangle count in the 84-byte header; ASCII when
/// the text starts with `solid`. Some exporters write `solid` into binary headers, so
/// the size test goes first.
pub fn parse_stl(path: &Path, bytes: &[u8]) -> Result<Mesh, SceneError> {
    let source = path.display().to_string();
    if bytes.len() >= 84 {
        let count = u32::from_le_bytes(bytes[80..84].try_into().unwrap()) as u64;
        if 84 + 50 * count == bytes.len() as u64 {
            return parse_binary(path, &source, &bytes[84..], count);
        }
    }
    let text_start = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(bytes.len());
    if bytes[text_start..].starts_with(b"solid") {
        let text = std::str::from_utf8(bytes).map_err(|e| SceneError::Stl {
            path: path.to_owned(),
            line: None,
            reason: format!("ASCII STL with invalid UTF-8 at byte {}", e.valid_up_to()),
        })?;
        return parse_ascii(path, &source, text);
    }
    if bytes.len() >= 84 {
        let count = u32::from_le_bytes(bytes[80..84].try_into().unwrap()) as u64;
        // Refuse oversized claims before reporting the size mismatch: the count is what
        // the user would otherwise try to fix.
        Mesh::check_limits(&source, 0, count)?;
        return Err(SceneError::Stl {
            path: path.to_owned(),
            line: None,
            reason: format!(
                "binary header declares {count} triangles ({} bytes) but the file has {} bytes; it is truncated or not an STL file",
                84 + 50 * count,
                bytes.len()
            ),
        });
    }
    Err(SceneError::Stl {
        path: path.to_owned(),
        line: None,
        reason: "neither ASCII (starting with `solid`) nor a binary STL of at least 84 bytes"
            .into(),
    })
}

fn parse_binary(path: &Path, source: &str, body: &[u8], count: u64) -> Result<Mesh, SceneError> {
    Mesh::check_limits(source, count * 3, count)?;
    let mut welder = Welder::new(source, count as usize);
    for (t, record) in body.chunks_exact(50).enumerate() {
        let f = |o: usize| f32::from_le_bytes(record[o..o + 4].try_into().unwrap());
        // Bytes 0..12 hold the facet normal, ignored (see the module doc).
        let corners = [12, 24, 36].map(|o| Vec3::new(f(o), f(o + 4), f(o + 8)));
        if let Some((k, c)) = corners.iter().enumerate().find(|(_, c)| !c.is_finite()) {
            return Err(non_finite(
                path,
                format!("triangle {t}, corner {k}"),
                c.to_array(),
            ));
        }
        welder.polygon(&corners);
    }
    Ok(welder.finish())
}

fn parse_ascii(path: &Path, source: &str, text: &str) -> Result<Mesh, SceneError> {
    let err = |line: usize, reason: String| SceneError::Stl {
        path: path.to_owned(),
        line: Some(line),
        reason,
    };
    let mut welder = Welder::new(source, 0);
    let mut polygon: Vec<Vec3> = Vec::new();
    let mut in_loop = false;
    for (i, line) in text.lines().enumerate() {
        let line_no = i + 1;
        let mut words = line.split_whitespace();
        match words.next() {
            Some("vertex") => {
                if !in_loop {
                    return Err(err(line_no, "`vertex` outside `outer loop`".into()));
                }
                let mut c = [0f32; 3];
                for v in &mut c {
                    *v = words
                        .next()
                        .and_then(|w| w.parse().ok())
                        .ok_or_else(|| err(line_no, "a `vertex` needs 3 numbers".into()))?;
                }
                if !Vec3::from(c).is_finite() {
                    return Err(non_finite(path, format!("line {line_no}"), c));
                }
                polygon.push(Vec3::from(c));
            }
            Some("outer") => {
                in_loop = true;
                polygon.clear();
            }
            Some("endloop") => {
                if polygon.len() < 3 {
                    return Err(err(
                        line_no,
                        format!(
                            "a facet has {} vertices; facets need at least 3",
                            polygon.len()
                        ),
                    ));
                }
                // Facets with more than three vertices are fan-triangulated.
                welder.polygon(&polygon);
                Mesh::check_limits(source, 0, welder.triangles() as u64)?;
                in_loop = false;
            }
            Some("solid" | "facet" | "endfacet" | "endsolid") | None => {}
            Some(other) => {
                return Err(err(line_no, format!("unexpected keyword `{other}`")));
            }
        }
    }
    if in_loop {
        return Err(err(
            text.lines().count(),
            "the file ends inside a facet; it is truncated".into(),
        ));
    }
    Ok(welder.finish())
}

/// A corner with an infinite or NaN coordinate (`inf` and `1e39` parse as infinity).
fn non_finite(path: &Path, location: String, corner: [f32; 3]) -> SceneError {
    let value = corner
        .into_iter()
        .find(|c| !c.is_finite())
        .unwrap_or(f32::NAN);
    SceneError::NonFiniteAttribute {
        source_name: path.display().to_string(),
        location,
        attribute: "vertex position".into(),
        value,
    }
}

/// Joins corners with bit-identical positions into one vertex.
struct Welder {
    mesh: Mesh,
    map: HashMap<[u32; 3], u32>,
}

impl Welder {
    fn new(source: &str, triangles: usize) -> Self {
        let mut mesh = Mesh {
            source: source.to_owned(),
            ..Mesh::default()
        };
        mesh.indices.reserve(triangles * 3);
        Self {
            mesh,
            map: HashMap::with_capacity(triangles / 2),
        }
    }

    fn vertex(&mut self, p: Vec3) -> u32 {
        let key = (p + Vec3::ZERO).to_array().map(f32::to_bits);
        let positions = &mut self.mesh.positions;
        *self.map.entry(key).or_insert_with(|| {
            positions.push(p);
            (positions.len() - 1) as u32
        })
    }

    fn polygon(&mut self, corners: &[Vec3]) {
        let ids: Vec<u32> = corners.iter().map(|&p| self.vertex(p)).collect();
        for k in 1..ids.len() - 1 {
            self.mesh
                .indices
                .extend_from_slice(&[ids[0], ids[k], ids[k + 1]]);
        }
    }

    fn triangles(&self) -> usize {
        self.mesh.indices.len() / 3
    }

    fn finish(self) -> Mesh {
        self.mesh
    }
}
