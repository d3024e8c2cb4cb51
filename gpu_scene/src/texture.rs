//! `meshlight::texture` (shaders/src/wgsl/texture.wgsl) on the CPU, in f32 and in the
//! same order: trilinear sampling of the scene's `textures` buffer through a material's
//! map, for the references of the passes that sample it.

use glam::{Vec2, Vec4};
use meshlight_shaders::cpu::layout::{TextureRef, TextureWrap, mip_offset};

/// `wrap_coordinate`: a coordinate brought into 0..1 (0..2 mirrored) before texels are
/// addressed.
fn wrap_coordinate(u: f32, mode: TextureWrap) -> f32 {
    match mode {
        TextureWrap::Clamp => u.clamp(0.0, 1.0),
        TextureWrap::Mirror => u - 2.0 * (u * 0.5).floor(),
        TextureWrap::Repeat => u - u.floor(),
    }
}

/// `wrap_index`: texel `i` of a line of `side` texels.
fn wrap_index(i: i32, side: i32, mode: TextureWrap) -> i32 {
    match mode {
        TextureWrap::Clamp => i.clamp(0, side - 1),
        TextureWrap::Mirror => {
            let m = i.rem_euclid(2 * side);
            if m >= side { 2 * side - 1 - m } else { m }
        }
        TextureWrap::Repeat => i.rem_euclid(side),
    }
}

fn texel(textures: &[u32], map: &TextureRef, start: u32, side: i32, x: i32, y: i32) -> Vec4 {
    let at = start as usize
        + (wrap_index(y, side, map.wrap[1]) * side + wrap_index(x, side, map.wrap[0])) as usize;
    let word = textures.get(at).copied().unwrap_or(0);
    let bytes = word.to_le_bytes();
    let c = Vec4::from_array(bytes.map(|b| b as f32 / 255.0));
    if map.srgb {
        // `srgb_decoded`: the table the buffer starts with.
        let decoded = |b: u8| f32::from_bits(textures.get(b as usize).copied().unwrap_or(0));
        Vec4::new(decoded(bytes[0]), decoded(bytes[1]), decoded(bytes[2]), c.w)
    } else {
        c
    }
}

/// `sample_level`: bilinear filtering of `level` at `uv` (already wrapped).
pub fn sample_level(textures: &[u32], map: &TextureRef, uv: Vec2, level: u32) -> Vec4 {
    let side = 1i32 << (map.size_log2 - level);
    let start = map.texels + mip_offset(map.size_log2, level) as u32;
    let p = uv * side as f32 - Vec2::splat(0.5);
    let corner = p.floor();
    let f = p - corner;
    let (x, y) = (corner.x as i32, corner.y as i32);
    let t = |dx, dy| texel(textures, map, start, side, x + dx, y + dy);
    let top = t(0, 0).lerp(t(1, 0), f.x);
    let bottom = t(0, 1).lerp(t(1, 1), f.x);
    top.lerp(bottom, f.y)
}

/// `texture_lod`: log2 of the footprint's longer axis in level-0 texels, clamped to the
/// chain.
pub fn texture_lod(map: &TextureRef, uv_dx: Vec2, uv_dy: Vec2) -> f32 {
    let rho = uv_dx.length().max(uv_dy.length()) * map.size() as f32;
    rho.max(1e-20).log2().clamp(0.0, map.size_log2 as f32)
}

/// `sample_texture`: trilinear filtering of `map` at `uv` for a pixel footprint of
/// `uv_dx`, `uv_dy`.
pub fn sample_texture(
    textures: &[u32],
    map: &TextureRef,
    uv: Vec2,
    uv_dx: Vec2,
    uv_dy: Vec2,
) -> Vec4 {
    let wrapped = Vec2::new(
        wrap_coordinate(uv.x, map.wrap[0]),
        wrap_coordinate(uv.y, map.wrap[1]),
    );
    let lod = texture_lod(map, uv_dx, uv_dy);
    let fine = lod.floor() as u32;
    let blend = lod - fine as f32;
    let c = sample_level(textures, map, wrapped, fine);
    if blend <= 0.0 {
        return c;
    }
    c.lerp(sample_level(textures, map, wrapped, fine + 1), blend)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2 × 2 texture (and its 1 × 1 mip) of four grey levels, repeat-wrapped.
    fn two_by_two(wrap: TextureWrap) -> (Vec<u32>, TextureRef) {
        let grey = |v: u8| u32::from_le_bytes([v, v, v, 255]);
        let words = vec![grey(0), grey(100), grey(200), grey(40), grey(85)];
        let map = TextureRef {
            texels: 0,
            size_log2: 1,
            srgb: false,
            wrap: [wrap; 2],
        };
        (words, map)
    }

    #[test]
    fn texel_centres_give_the_texel_and_edges_wrap_by_mode() {
        let (words, map) = two_by_two(TextureWrap::Repeat);
        let at = |uv: Vec2, map: &TextureRef| sample_level(&words, map, uv, 0).x * 255.0;
        assert!((at(Vec2::new(0.25, 0.25), &map) - 0.0).abs() < 1e-3);
        assert!((at(Vec2::new(0.75, 0.25), &map) - 100.0).abs() < 1e-3);
        assert!((at(Vec2::new(0.25, 0.75), &map) - 200.0).abs() < 1e-3);
        // At u = 0 a repeating texture averages its first and last column.
        assert!((at(Vec2::new(0.0, 0.25), &map) - 50.0).abs() < 1e-3);
        let clamp = TextureRef {
            wrap: [TextureWrap::Clamp; 2],
            ..map
        };
        assert!((at(Vec2::new(0.0, 0.25), &clamp) - 0.0).abs() < 1e-3);
        let mirror = TextureRef {
            wrap: [TextureWrap::Mirror; 2],
            ..map
        };
        // Mirrored, the texel left of column 0 is column 0 again.
        assert!((at(Vec2::new(0.0, 0.25), &mirror) - 0.0).abs() < 1e-3);
        // And u in 1..2 runs back: u = 1.25 is u = 0.75.
        let uv = Vec2::new(wrap_coordinate(1.25, TextureWrap::Mirror), 0.25);
        assert!((at(uv, &mirror) - 100.0).abs() < 1e-3);
    }

    #[test]
    fn the_level_follows_the_footprint_and_trilinear_blends_two() {
        let (words, map) = two_by_two(TextureWrap::Repeat);
        let uv = Vec2::new(0.25, 0.25);
        // Half a texture per pixel step on a side-2 texture: one texel, level 0.
        assert_eq!(texture_lod(&map, Vec2::new(0.5, 0.0), Vec2::ZERO), 0.0);
        // One texture per step: two texels, level 1 (the 1 × 1 mip).
        assert_eq!(
            texture_lod(&map, Vec2::new(1.0, 0.0), Vec2::new(0.0, 0.3)),
            1.0
        );
        let coarse = sample_texture(&words, &map, uv, Vec2::X, Vec2::ZERO).x * 255.0;
        assert!((coarse - 85.0).abs() < 1e-3);
        // Halfway (footprint of sqrt 2 texels): the mean of the two levels.
        let half = sample_texture(&words, &map, uv, Vec2::new(0.5f32.sqrt(), 0.0), Vec2::ZERO);
        assert!((half.x * 255.0 - 42.5).abs() < 1e-2, "{}", half.x * 255.0);
        // Tiling UVs far from 0 address the same texel.
        let far = sample_texture(
            &words,
            &map,
            uv + Vec2::splat(4096.0),
            Vec2::ZERO,
            Vec2::ZERO,
        );
        assert!((far.x * 255.0).abs() < 1e-3);
    }

    #[test]
    fn srgb_texels_are_decoded_before_they_are_weighed() {
        let mut words = crate::data::srgb_table().to_vec();
        words.push(u32::from_le_bytes([188, 188, 188, 255]));
        let map = TextureRef {
            texels: 256,
            size_log2: 0,
            srgb: true,
            wrap: [TextureWrap::Repeat; 2],
        };
        let c = sample_texture(&words, &map, Vec2::splat(0.5), Vec2::ZERO, Vec2::ZERO);
        assert!((c.x - 0.5).abs() < 0.005 && (c.w - 1.0).abs() < 1e-6, "{c}");
    }
}
