//! The CPU reference of `brdf.wgsl`: glTF's metallic-roughness model, operation for
//! operation, so that the shaded view is checked against it within a step of 8 bits.

use glam::Vec3;

/// The reflectance at normal incidence of every dielectric (glTF's 4%).
pub const DIELECTRIC_SPECULAR: f32 = 0.04;
/// Smallest GGX alpha: a perfect mirror's highlight is a point no pixel samples.
pub const MIN_ALPHA: f32 = 0.002;

/// A surface as the lights see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// Diffuse albedo: the base colour of the non-metallic part.
    pub diffuse: Vec3,
    /// Specular reflectance at normal incidence.
    pub specular: Vec3,
    /// GGX alpha: roughness squared.
    pub alpha: f32,
}

impl Surface {
    /// `surface`: from the base colour and the metallic and roughness factors.
    pub fn new(base: Vec3, metallic: f32, roughness: f32) -> Self {
        Self {
            diffuse: base * (1.0 - metallic),
            specular: Vec3::splat(DIELECTRIC_SPECULAR).lerp(base, metallic),
            alpha: (roughness * roughness).max(MIN_ALPHA),
        }
    }

    /// `light_response`: what a light of unit colour from direction `l` adds towards
    /// the eye at `v` (unit vectors): `(diffuse + π · GGX specular) · n·l`.
    pub fn light_response(&self, n: Vec3, v: Vec3, l: Vec3) -> Vec3 {
        let nl = n.dot(l);
        if nl <= 0.0 {
            return Vec3::ZERO;
        }
        let nv = n.dot(v).max(1e-4);
        let h = (v + l).normalize();
        let nh = n.dot(h).max(0.0);
        let vh = v.dot(h).max(0.0);
        let a2 = self.alpha * self.alpha;
        let q = nh * nh * (a2 - 1.0) + 1.0;
        let d = a2 / (std::f32::consts::PI * q * q);
        let vis = 0.5
            / (nl * (nv * nv * (1.0 - a2) + a2).sqrt() + nv * (nl * nl * (1.0 - a2) + a2).sqrt());
        let f = self.specular + (Vec3::ONE - self.specular) * (1.0 - vh).powf(5.0);
        (self.diffuse + std::f32::consts::PI * d * vis * f) * nl
    }

    /// `ambient_response`: what a uniform ambient light of unit colour adds.
    pub fn ambient_response(&self) -> Vec3 {
        self.diffuse + self.specular
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rough_white_dielectric_is_lambert_plus_a_faint_highlight() {
        let s = Surface::new(Vec3::ONE, 0.0, 1.0);
        let n = Vec3::Z;
        // Lit and seen head-on: Lambert's 1 plus 4% of a broad lobe.
        let head_on = s.light_response(n, n, n).x;
        assert!((1.0..1.1).contains(&head_on), "{head_on}");
        // From below the horizon: nothing.
        assert_eq!(s.light_response(n, n, -n), Vec3::ZERO);
        // Lit at 60°: half, give or take the highlight.
        let l = Vec3::new(3f32.sqrt() / 2.0, 0.0, 0.5);
        let r = s.light_response(n, n, l).x;
        assert!((0.5..0.56).contains(&r), "{r}");
    }

    #[test]
    fn a_smooth_metal_reflects_its_colour_only_near_the_mirror_direction() {
        let gold = Vec3::new(1.0, 0.8, 0.3);
        let s = Surface::new(gold, 1.0, 0.2);
        assert_eq!(s.diffuse, Vec3::ZERO);
        let n = Vec3::Z;
        let l = Vec3::new(0.6, 0.0, 0.8);
        let mirror = Vec3::new(-0.6, 0.0, 0.8);
        let off = Vec3::new(0.6, 0.0, 0.8);
        let at_mirror = s.light_response(n, mirror, l);
        let away = s.light_response(n, off, l);
        assert!(at_mirror.x > 10.0 * away.x, "{at_mirror} vs {away}");
        // Tinted by the base colour.
        assert!(at_mirror.z < at_mirror.y && at_mirror.y < at_mirror.x);
        assert_eq!(s.ambient_response(), gold);
    }
}
