//! Pieces the glTF loader tests build their files from: the tetrahedron as a glTF
//! buffer, the unit quad as a primitive, and the GLB container that carries a JSON
//! document and its buffer in one file.

use meshlight_testing::gltf_writer::Primitive;

/// A unit quad in the XY plane, two triangles facing +Z, with its normals.
pub fn unit_quad() -> Primitive {
    Primitive {
        positions: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        normals: Some(vec![[0.0, 0.0, 1.0]; 4]),
        indices: vec![0, 1, 2, 0, 2, 3],
        ..Primitive::default()
    }
}

/// The tetrahedron's buffer: 4 positions (48 bytes), 12 u16 indices (24), 4 UVs (32).
pub fn tetrahedron_buffer() -> Vec<u8> {
    let (p, idx) = super::tetrahedron();
    let mut buf: Vec<u8> = bytemuck::cast_slice(&p).to_vec();
    buf.extend_from_slice(bytemuck::cast_slice(&idx));
    let uvs: [[f32; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
    buf.extend_from_slice(bytemuck::cast_slice(&uvs));
    buf
}

pub use meshlight_testing::gltf_writer::glb_container;
