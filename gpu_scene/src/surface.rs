//! `meshlight::surface` (shaders/src/wgsl/surface.wgsl) on the CPU, in f32 and in the
//! same order: a listed triangle's corners decoded from the payload, perspective-correct
//! barycentrics at a pixel, the coordinates a material's maps are sampled at, and
//! whether a MASK material cuts the pixel out. The resolve's reference shades through
//! these, and both rasterisers' references ask [`cut_out`] what their kernels ask.

use glam::{Mat4, Vec2, Vec3, Vec4};
use meshlight_scene::asset::format::{MeshletRecord, PayloadLayout};
use meshlight_scene::asset::triangles;
use meshlight_scene::compress::{NORMAL_BITS, decode_color, decode_octahedral, get_bits};
use meshlight_shaders::cpu::layout::{
    Cluster, MAP_BASE_COLOR, MATERIAL_FLAG_MASK, MESH_FLAG_COLORS, MESH_FLAG_UVS, Mesh, TextureRef,
    material_uv, material_uv_step, uv_transform_at,
};

use crate::SceneData;
use crate::texture::sample_texture;

/// One corner of a triangle, decoded from the payload as the shaders decode it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Corner {
    /// Mesh space: `grid.xyz + (grid_min + offset) · grid.w`, the integer add first.
    pub position: Vec3,
    /// Mesh-space unit normal.
    pub normal: Vec3,
    /// `uv_grid.xy + (origin + offset << shift) · uv_grid.zw`, or 0 when the mesh has no
    /// UVs.
    pub uv: Vec2,
    /// Linear RGBA vertex colour, or white when the mesh has none.
    pub color: Vec4,
}

/// The three corners of triangle `t` of meshlet `m`, in winding order. Offsets past the
/// payload read as zeros, as a storage-buffer read past the end may.
pub fn triangle_corners(scene: &SceneData, mesh: &Mesh, m: &MeshletRecord, t: u32) -> [Corner; 3] {
    let has_uvs = mesh.flags & MESH_FLAG_UVS != 0;
    let layout = PayloadLayout::of(m, mesh.flags);
    let start = (m.data_offset as usize).min(scene.payload.len());
    let data = &scene.payload[start..];
    let block = data.get(layout.triangles as usize..).unwrap_or(&[]);
    let (vc, tc) = (m.vertex_count(), m.triangle_count());
    let corners = triangles::decode(block, t, m.triangle_bits(), vc, tc);
    let axis = m.axis_bits();
    let (normal_min, normal_bits) = (m.normal_min(), m.normal_bits());
    let stride = m.vertex_stride() as usize;
    let grid = mesh.position_grid;
    let uv_grid = mesh.uv_grid;
    corners.map(|v| {
        let mut at = v as usize * stride;
        let mut field = |bits: u32| {
            let d = get_bits(data, at, bits).unwrap_or(0);
            at += bits as usize;
            d
        };
        let q = [0, 1, 2].map(|k| m.grid_min[k].wrapping_add(field(axis[k])));
        let position = Vec3::new(grid[0], grid[1], grid[2])
            + Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32) * grid[3];
        let oct = [0, 1].map(|k| normal_min[k] + field(normal_bits[k]) as i32);
        let normal = decode_octahedral(oct, NORMAL_BITS);
        let uv = if has_uvs {
            let read = |at: u32| data.get(at as usize).copied().unwrap_or(0);
            let origin = [read(layout.uvs), read(layout.uvs + 1)];
            let offsets = data.get(layout.uv_words as usize..).unwrap_or(&[]);
            let [bu, bv] = m.uv_bits();
            let at = (v * (bu + bv)) as usize;
            let offset = [
                get_bits(offsets, at, bu).unwrap_or(0),
                get_bits(offsets, at + bu as usize, bv).unwrap_or(0),
            ];
            // The low 24 bits of an origin word are its code, the high 8 the shift.
            let code = |k: usize| {
                let shift = (origin[k] >> 24) & 31;
                (origin[k] & 0xff_ffff).wrapping_add(offset[k] << shift) as f32
            };
            Vec2::new(uv_grid[0], uv_grid[1])
                + Vec2::new(code(0), code(1)) * Vec2::new(uv_grid[2], uv_grid[3])
        } else {
            Vec2::ZERO
        };
        let color = if mesh.flags & MESH_FLAG_COLORS != 0 {
            let word = data.get((layout.colors + v) as usize).copied().unwrap_or(0);
            Vec4::from_array(decode_color(word))
        } else {
            Vec4::ONE
        };
        Corner {
            position,
            normal,
            uv,
            color,
        }
    })
}

/// Perspective-correct barycentrics at a pixel and their change per pixel step in x
/// and y (`Barycentrics`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Barycentrics {
    /// The perspective-correct barycentrics at the pixel centre.
    pub b: Vec3,
    /// Their change one pixel to the right.
    pub ddx: Vec3,
    /// Their change one pixel down.
    pub ddy: Vec3,
}

/// `barycentrics`: the clip-space corners, the pixel position (centres at +0.5) and the
/// viewport size in pixels.
pub fn barycentrics(clip: [Vec4; 3], pixel: Vec2, size: Vec2) -> Barycentrics {
    let [c0, c1, c2] = clip;
    let p = Vec2::new(pixel.x * 2.0 / size.x - 1.0, 1.0 - pixel.y * 2.0 / size.y);
    let step = Vec2::new(2.0 / size.x, -2.0 / size.y);
    let iw = Vec3::new(1.0 / c0.w, 1.0 / c1.w, 1.0 / c2.w);
    let n0 = c0.truncate().truncate() * iw.x;
    let d1 = c1.truncate().truncate() * iw.y - n0;
    let d2 = c2.truncate().truncate() * iw.z - n0;
    let dp = p - n0;
    let det = d1.x * d2.y - d1.y * d2.x;
    if det.abs() < 1e-30 {
        return Barycentrics {
            b: Vec3::X,
            ..Default::default()
        };
    }
    let inv_det = 1.0 / det;
    let l1 = (dp.x * d2.y - dp.y * d2.x) * inv_det;
    let l2 = (d1.x * dp.y - d1.y * dp.x) * inv_det;
    let l = Vec3::new(1.0 - l1 - l2, l1, l2);
    let gx = Vec3::new(d1.y - d2.y, d2.y, -d1.y) * inv_det * step.x;
    let gy = Vec3::new(d2.x - d1.x, -d2.x, d1.x) * inv_det * step.y;
    let q = l * iw;
    let s = 1.0 / (q.x + q.y + q.z);
    let b = q * s;
    let sx = gx.dot(iw);
    let sy = gy.dot(iw);
    Barycentrics {
        b,
        ddx: (gx * iw - b * sx) * s,
        ddy: (gy * iw - b * sy) * s,
    }
}

/// Texture coordinates at a pixel and their change per pixel step (`SampleUv`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SampleUv {
    /// At the pixel centre.
    pub uv: Vec2,
    /// Their change one pixel to the right.
    pub dx: Vec2,
    /// ... and one pixel down.
    pub dy: Vec2,
}

/// `interpolated_uv`: the corners' coordinates at the pixel `b` describes.
pub fn interpolated_uv(uv: [Vec2; 3], b: &Barycentrics) -> SampleUv {
    let weigh = |w: Vec3| uv[0] * w.x + uv[1] * w.y + uv[2] * w.z;
    SampleUv {
        uv: weigh(b.b),
        dx: weigh(b.ddx),
        dy: weigh(b.ddy),
    }
}

/// `uv_transform_rows`: the texture transform at word `word` of `textures`, zeros where
/// it lies past the buffer (as the shader's reads would give).
pub fn uv_transform_rows(textures: &[u32], word: u32) -> [[f32; 3]; 2] {
    uv_transform_at(textures, word).unwrap_or_default()
}

/// `transformed_uv`: `s` through the transform of rows `r`.
pub fn transformed_uv(r: &[[f32; 3]; 2], s: SampleUv) -> SampleUv {
    SampleUv {
        uv: Vec2::from(material_uv(r, s.uv.to_array())),
        dx: Vec2::from(material_uv_step(r, s.dx.to_array())),
        dy: Vec2::from(material_uv_step(r, s.dy.to_array())),
    }
}

/// `base_alpha`: the factor, times the alpha of `map` at `s` where there is one.
pub fn base_alpha(textures: &[u32], map: [u32; 2], factor: f32, s: &SampleUv) -> f32 {
    match TextureRef::from_words(map) {
        Some(map) => factor * sample_texture(textures, &map, s.uv, s.dx, s.dy).w,
        None => factor,
    }
}

/// `cut_out` (`cut_at` of `cut_out_setup`): whether the pixel centred at `pixel` of triangle `t` of `cluster`, drawn
/// through `view_projection` into a `size` pixel viewport, is left undrawn because its
/// material is MASK and the base colour's alpha there is below the cutoff. A cluster
/// naming a missing instance, meshlet or material is never cut out.
pub fn cut_out(
    scene: &SceneData,
    view_projection: &[[f32; 4]; 4],
    size: Vec2,
    cluster: &Cluster,
    t: u32,
    pixel: Vec2,
) -> bool {
    let Some(material) = scene.cluster_material(cluster.instance, cluster.meshlet) else {
        return false;
    };
    if material.flags & MATERIAL_FLAG_MASK == 0 {
        return false;
    }
    let instance = scene.instances[cluster.instance as usize];
    let m = scene.meshlets[cluster.meshlet as usize];
    let Some(mesh) = scene.meshes.get(instance.mesh as usize) else {
        return false;
    };
    let corners = triangle_corners(scene, mesh, &m, t);
    let world_from_local = Mat4::from_cols_array_2d(&instance.world_from_local);
    let view_projection = Mat4::from_cols_array_2d(view_projection);
    let clip = corners.map(|c| {
        let world = (world_from_local * c.position.extend(1.0)).truncate();
        view_projection * world.extend(1.0)
    });
    let b = barycentrics(clip, pixel, size);
    let mut s = interpolated_uv(corners.map(|c| c.uv), &b);
    if material.uv_transform != 0 {
        s = transformed_uv(
            &uv_transform_rows(&scene.textures, material.uv_transform),
            s,
        );
    }
    let map = material.maps[MAP_BASE_COLOR];
    let mut alpha = base_alpha(&scene.textures, map, material.base_color[3], &s);
    if mesh.flags & MESH_FLAG_COLORS != 0 {
        let [c0, c1, c2] = corners.map(|c| c.color.w);
        alpha *= c0 * b.b.x + c1 * b.b.y + c2 * b.b.z;
    }
    alpha < material.alpha_cutoff
}
