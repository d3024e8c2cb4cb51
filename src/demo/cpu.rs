//! CPU reference of the demo rasteriser: the same float edge functions, the same
//! visibility packing, the same "largest value wins" rule.

use glam::{Mat4, Vec3, Vec4};

fn edge(a: [f32; 2], b: [f32; 2], p: [f32; 2]) -> f32 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

/// One visibility value per pixel, as the GPU pass writes them.
pub fn rasterise(
    positions: &[Vec3],
    indices: &[u32],
    view_proj: Mat4,
    width: u32,
    height: u32,
) -> Vec<u64> {
    let mut vis = vec![0u64; (width * height) as usize];
    let screen = |c: Vec4| {
        let n = c.truncate() / c.w;
        [
            (n.x * 0.5 + 0.5) * width as f32,
            (0.5 - n.y * 0.5) * height as f32,
            n.z,
        ]
    };
    for (t, tri) in indices.chunks_exact(3).enumerate() {
        let c: Vec<Vec4> = tri
            .iter()
            .map(|&i| view_proj * positions[i as usize].extend(1.0))
            .collect();
        if c.iter().any(|c| c.w <= 0.0) {
            continue;
        }
        let s: Vec<[f32; 3]> = c.iter().map(|&c| screen(c)).collect();
        let xy = |i: usize| [s[i][0], s[i][1]];
        let area = edge(xy(0), xy(1), xy(2));
        if area >= 0.0 {
            continue;
        }
        let lo_x = s
            .iter()
            .map(|v| v[0])
            .fold(f32::MAX, f32::min)
            .floor()
            .max(0.0);
        let lo_y = s
            .iter()
            .map(|v| v[1])
            .fold(f32::MAX, f32::min)
            .floor()
            .max(0.0);
        let hi_x = s
            .iter()
            .map(|v| v[0])
            .fold(f32::MIN, f32::max)
            .ceil()
            .min(width as f32 - 1.0);
        let hi_y = s
            .iter()
            .map(|v| v[1])
            .fold(f32::MIN, f32::max)
            .ceil()
            .min(height as f32 - 1.0);
        let mut y = lo_y;
        while y <= hi_y {
            let mut x = lo_x;
            while x <= hi_x {
                let p = [x + 0.5, y + 0.5];
                let w0 = edge(xy(1), xy(2), p) / area;
                let w1 = edge(xy(2), xy(0), p) / area;
                let w2 = 1.0 - w0 - w1;
                if w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0 {
                    let z = w0 * s[0][2] + w1 * s[1][2] + w2 * s[2][2];
                    if (0.0..=1.0).contains(&z) {
                        let value = ((1.0 - z).to_bits() as u64) << 32 | (t as u64 + 1);
                        let px = &mut vis[(y as u32 * width + x as u32) as usize];
                        *px = (*px).max(value);
                    }
                }
                x += 1.0;
            }
            y += 1.0;
        }
    }
    vis
}

/// CPU reference of the shading pass: the same background gradient, face-normal lighting
/// and sRGB-ish packing, from a given visibility buffer.
pub fn shade(
    vis: &[u64],
    positions: &[Vec3],
    indices: &[u32],
    width: u32,
    height: u32,
    light_dir: Vec3,
) -> Vec<u32> {
    let light = light_dir.normalize();
    (0..width * height)
        .map(|i| {
            let v = vis[i as usize];
            let color = if v as u32 == 0 {
                let t = (i / width) as f32 / height as f32;
                Vec3::new(0.20, 0.24, 0.30).lerp(Vec3::new(0.05, 0.06, 0.08), t)
            } else {
                let t = (v as u32 - 1) as usize;
                let [a, b, c] = [0, 1, 2].map(|k| positions[indices[3 * t + k] as usize]);
                let n = (b - a).cross(c - a).normalize();
                let diffuse = n.dot(light).max(0.0);
                let ambient =
                    Vec3::new(0.10, 0.08, 0.07).lerp(Vec3::new(0.18, 0.22, 0.30), n.y * 0.5 + 0.5);
                Vec3::new(0.85, 0.55, 0.30) * (diffuse * Vec3::new(1.0, 0.95, 0.85) + ambient)
            };
            let srgb = color.clamp(Vec3::ZERO, Vec3::ONE).powf(1.0 / 2.2);
            let [r, g, b] = (srgb * 255.0).round().to_array().map(|x| x as u32);
            r | (g << 8) | (b << 16) | (255 << 24)
        })
        .collect()
}
