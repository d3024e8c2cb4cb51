//! A mesh written as a binary glTF file (`.glb`): one primitive with positions, normals,
//! UVs where the mesh has them and 32-bit indices, placed by one node at the origin.
//! What the world generator writes, so that `bake` reads generated meshes through the
//! same loader as a user's.

use crate::mesh::Mesh;

/// The `.glb` bytes of `mesh`.
pub fn mesh_glb(mesh: &Mesh, name: &str) -> Vec<u8> {
    let mut bin = Vec::new();
    let mut views = Vec::new();
    let mut view = |bin: &mut Vec<u8>, bytes: &[u8], target: u32| {
        let offset = bin.len();
        bin.extend_from_slice(bytes);
        views.push(format!(
            r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{},"target":{target}}}"#,
            bytes.len()
        ));
        views.len() - 1
    };
    const ARRAY: u32 = 34962;
    const ELEMENTS: u32 = 34963;
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for p in &mesh.positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let n = mesh.positions.len();
    let positions = view(&mut bin, bytemuck::cast_slice(&mesh.positions), ARRAY);
    let mut accessors = vec![format!(
        r#"{{"bufferView":{positions},"componentType":5126,"count":{n},"type":"VEC3","min":[{},{},{}],"max":[{},{},{}]}}"#,
        lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
    )];
    let mut attributes = vec![r#""POSITION":0"#.to_string()];
    if mesh.normals.len() == n {
        let v = view(&mut bin, bytemuck::cast_slice(&mesh.normals), ARRAY);
        accessors.push(format!(
            r#"{{"bufferView":{v},"componentType":5126,"count":{n},"type":"VEC3"}}"#
        ));
        attributes.push(format!(r#""NORMAL":{}"#, accessors.len() - 1));
    }
    if mesh.uvs.len() == n {
        let v = view(&mut bin, bytemuck::cast_slice(&mesh.uvs), ARRAY);
        accessors.push(format!(
            r#"{{"bufferView":{v},"componentType":5126,"count":{n},"type":"VEC2"}}"#
        ));
        attributes.push(format!(r#""TEXCOORD_0":{}"#, accessors.len() - 1));
    }
    let v = view(&mut bin, bytemuck::cast_slice(&mesh.indices), ELEMENTS);
    accessors.push(format!(
        r#"{{"bufferView":{v},"componentType":5125,"count":{},"type":"SCALAR"}}"#,
        mesh.indices.len()
    ));
    let indices = accessors.len() - 1;
    // A name is JSON text: keep it to characters that need no escaping.
    let name: String = name
        .chars()
        .map(|c| match c.is_ascii_alphanumeric() || "-_. ".contains(c) {
            true => c,
            false => '_',
        })
        .collect();
    let json = format!(
        r#"{{"asset":{{"version":"2.0","generator":"meshlight"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0,"name":"{name}"}}],"meshes":[{{"name":"{name}","primitives":[{{"attributes":{{{}}},"indices":{indices}}}]}}],"buffers":[{{"byteLength":{}}}],"bufferViews":[{}],"accessors":[{}]}}"#,
        attributes.join(","),
        bin.len(),
        views.join(","),
        accessors.join(",")
    );
    container(json.into_bytes(), bin)
}

/// The GLB container: a 12-byte header, the JSON chunk padded with spaces and the
/// binary chunk padded with zeros, each to 4 bytes.
fn container(mut json: Vec<u8>, mut bin: Vec<u8>) -> Vec<u8> {
    json.resize(json.len().next_multiple_of(4), b' ');
    bin.resize(bin.len().next_multiple_of(4), 0);
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}
