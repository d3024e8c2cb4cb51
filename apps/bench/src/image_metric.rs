//! How far an image is from a reference, for the LOD's quality (`lod-quality`): PSNR over
//! the colour channels and the mean SSIM of the luma.
//!
//! Why both: PSNR weighs every pixel's error alike, so a few pixels of silhouette that
//! moved by one pixel count like noise; SSIM compares local structure (8 × 8 windows
//! every 4 pixels), which is what a coarser LOD changes, and is 1 for equal images. The
//! constants are SSIM's usual ones for 8-bit data (K1 = 0.01, K2 = 0.03).

/// Peak signal-to-noise ratio of RGBA8 `image` against `reference` over R, G and B, in
/// dB; infinite for equal images.
pub fn psnr(image: &[u8], reference: &[u8]) -> f64 {
    assert_eq!(image.len(), reference.len(), "images of one size");
    let (mut sum, mut n) = (0f64, 0u64);
    for (a, b) in image.chunks_exact(4).zip(reference.chunks_exact(4)) {
        for k in 0..3 {
            let d = f64::from(a[k]) - f64::from(b[k]);
            sum += d * d;
            n += 1;
        }
    }
    let mse = sum / n.max(1) as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (255.0f64 * 255.0 / mse).log10()
    }
}

/// Window side and step of [`ssim`].
const WINDOW: usize = 8;
const STEP: usize = 4;

/// Mean SSIM of the luma (Rec. 601 weights) of RGBA8 `image` against `reference`, both
/// `width` × `height`, over 8 × 8 windows every 4 pixels: 1 for equal images.
pub fn ssim(image: &[u8], reference: &[u8], width: usize, height: usize) -> f64 {
    assert_eq!(image.len(), width * height * 4, "image of width × height");
    assert_eq!(reference.len(), image.len(), "images of one size");
    let luma = |rgba: &[u8]| -> Vec<f64> {
        rgba.chunks_exact(4)
            .map(|p| 0.299 * f64::from(p[0]) + 0.587 * f64::from(p[1]) + 0.114 * f64::from(p[2]))
            .collect()
    };
    let (x, y) = (luma(image), luma(reference));
    let (c1, c2) = ((0.01f64 * 255.0).powi(2), (0.03f64 * 255.0).powi(2));
    let (mut total, mut windows) = (0f64, 0u64);
    let starts = |size: usize| (0..=size.saturating_sub(WINDOW)).step_by(STEP);
    for top in starts(height) {
        for left in starts(width) {
            let n = (WINDOW * WINDOW) as f64;
            let (mut sx, mut sy, mut sxx, mut syy, mut sxy) = (0f64, 0f64, 0f64, 0f64, 0f64);
            for row in top..(top + WINDOW).min(height) {
                for col in left..(left + WINDOW).min(width) {
                    let (a, b) = (x[row * width + col], y[row * width + col]);
                    sx += a;
                    sy += b;
                    sxx += a * a;
                    syy += b * b;
                    sxy += a * b;
                }
            }
            let (mx, my) = (sx / n, sy / n);
            let (vx, vy, cov) = (sxx / n - mx * mx, syy / n - my * my, sxy / n - mx * my);
            total += ((2.0 * mx * my + c1) * (2.0 * cov + c2))
                / ((mx * mx + my * my + c1) * (vx + vy + c2));
            windows += 1;
        }
    }
    total / windows.max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: usize, height: usize, at: impl Fn(usize, usize) -> u8) -> Vec<u8> {
        (0..width * height)
            .flat_map(|i| {
                let v = at(i % width, i / width);
                [v, v, v, 255]
            })
            .collect()
    }

    #[test]
    fn equal_images_are_perfect() {
        let a = image(32, 24, |x, y| ((x * 7 + y * 13) % 256) as u8);
        assert_eq!(psnr(&a, &a), f64::INFINITY);
        assert!((ssim(&a, &a, 32, 24) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn psnr_of_a_known_error() {
        // Every channel 16 off: MSE 256, PSNR = 10 log10(255² / 256).
        let a = image(16, 16, |_, _| 100);
        let b = image(16, 16, |_, _| 116);
        let want = 10.0 * (255.0f64 * 255.0 / 256.0).log10();
        assert!((psnr(&a, &b) - want).abs() < 1e-9);
    }

    #[test]
    fn ssim_falls_as_structure_is_lost() {
        // A checkerboard against itself shifted by a pixel (structure inverted), and
        // against a flat image of its mean (structure gone): both well below 1, and a
        // slight brightness change keeps most of it.
        let board = image(64, 64, |x, y| if (x + y) % 2 == 0 { 40 } else { 200 });
        let shifted = image(64, 64, |x, y| if (x + y + 1) % 2 == 0 { 40 } else { 200 });
        let flat = image(64, 64, |_, _| 120);
        let brighter = image(64, 64, |x, y| if (x + y) % 2 == 0 { 44 } else { 204 });
        let inverted = ssim(&shifted, &board, 64, 64);
        let gone = ssim(&flat, &board, 64, 64);
        let close = ssim(&brighter, &board, 64, 64);
        assert!(inverted < 0.0, "{inverted}");
        assert!(gone < 0.1, "{gone}");
        assert!(close > 0.99, "{close}");
    }
}
