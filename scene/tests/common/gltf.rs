//! Pieces the glTF loader tests build their files from: the tetrahedron as a glTF
//! buffer, and the GLB container that carries a JSON document and its buffer in one file.

/// The tetrahedron's buffer: 4 positions (48 bytes), 12 u16 indices (24), 4 UVs (32).
pub fn tetrahedron_buffer() -> Vec<u8> {
    let (p, idx) = super::tetrahedron();
    let mut buf: Vec<u8> = bytemuck::cast_slice(&p).to_vec();
    buf.extend_from_slice(bytemuck::cast_slice(&idx));
    let uvs: [[f32; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
    buf.extend_from_slice(bytemuck::cast_slice(&uvs));
    buf
}

/// A GLB file: the header, `json` as the JSON chunk (padded with spaces, as the format
/// wants every chunk a multiple of 4 bytes) and `bin`, already so padded, as the binary
/// chunk.
pub fn glb_container(json: &str, bin: &[u8]) -> Vec<u8> {
    assert!(bin.len().is_multiple_of(4), "pad the binary chunk first");
    let mut json = json.as_bytes().to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&((12 + 8 + json.len() + 8 + bin.len()) as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(bin);
    glb
}
