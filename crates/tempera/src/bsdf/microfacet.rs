//! The anisotropic GGX (Trowbridge–Reitz) microfacet distribution with the height-correlated
//! Smith masking-shadowing term and sampling of visible normals (Heitz 2018, "Sampling the GGX
//! Distribution of Visible Normals", JCGT 7(4); pbrt-v4 §9.6). Directions are in the local
//! shading frame (normal = +z).

use crate::math::warp::{polar_disk, polar_disk_inverse};
use crate::math::{Vec2, Vec3, safe_sqrt};
use std::f32::consts::PI;

/// Below this alpha a lobe is treated as perfectly specular.
pub const SMOOTH_ALPHA: f32 = 1e-3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    pub alpha_x: f32,
    pub alpha_y: f32,
}

impl Ggx {
    pub fn new(alpha_x: f32, alpha_y: f32) -> Self {
        Self { alpha_x: alpha_x.max(0.0), alpha_y: alpha_y.max(0.0) }
    }

    pub fn isotropic(alpha: f32) -> Self {
        Self::new(alpha, alpha)
    }

    /// pbrt's mapping from a perceptual roughness in `[0, 1]` to alpha.
    pub fn roughness_to_alpha(roughness: f32) -> f32 {
        roughness.max(0.0).sqrt()
    }

    /// The distribution with each alpha replaced by `R(α, a) = min(1, √(α² + a²))`, the
    /// roughening of tempered MMLT (Šik & Křivánek 2016): `a = 0` is the identity, larger `a`
    /// flattens the lobe, and alpha never exceeds 1. Smooth (delta) distributions are returned
    /// unchanged: roughening only ever widens lobes that can already be connected.
    pub fn roughened(&self, a: f32) -> Self {
        if a <= 0.0 || self.effectively_smooth() {
            return *self;
        }
        let r = |alpha: f32| alpha.hypot(a).min(1.0).max(alpha);
        Self { alpha_x: r(self.alpha_x), alpha_y: r(self.alpha_y) }
    }

    #[inline]
    pub fn effectively_smooth(&self) -> bool {
        self.alpha_x.max(self.alpha_y) < SMOOTH_ALPHA
    }

    /// Normal distribution D(wm).
    #[inline]
    pub fn d(&self, wm: Vec3) -> f32 {
        let cos2 = wm.z * wm.z;
        if cos2 < 1e-12 {
            return 0.0;
        }
        let e = (wm.x * wm.x / (self.alpha_x * self.alpha_x) + wm.y * wm.y / (self.alpha_y * self.alpha_y)) / cos2;
        let v = 1.0 / (PI * self.alpha_x * self.alpha_y * cos2 * cos2 * (1.0 + e) * (1.0 + e));
        if v.is_finite() { v } else { 0.0 }
    }

    /// Smith's Λ(w).
    #[inline]
    pub fn lambda(&self, w: Vec3) -> f32 {
        let cos2 = w.z * w.z;
        if cos2 == 0.0 {
            return f32::INFINITY;
        }
        let a2_tan2 = (w.x * w.x * self.alpha_x * self.alpha_x + w.y * w.y * self.alpha_y * self.alpha_y) / cos2;
        ((1.0 + a2_tan2).sqrt() - 1.0) * 0.5
    }

    #[inline]
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing G(wo, wi).
    #[inline]
    pub fn g(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Density of visible normals seen from `w`: `G1(w) / |cos θ_w| · D(wm) · |w·wm|`.
    #[inline]
    pub fn pdf(&self, w: Vec3, wm: Vec3) -> f32 {
        let cos = w.z.abs();
        if cos == 0.0 {
            return 0.0;
        }
        self.g1(w) / cos * self.d(wm) * w.dot(wm).abs()
    }

    /// Samples a visible normal (upper hemisphere) as seen from `w`.
    pub fn sample_wm(&self, w: Vec3, u: Vec2) -> Vec3 {
        let (wh, t1, t2) = self.visible_frame(w);
        let mut p = polar_disk(u);
        let h = safe_sqrt(1.0 - p.x * p.x);
        let s = (1.0 + wh.z) * 0.5;
        p.y = (1.0 - s) * h + s * p.y;
        let pz = safe_sqrt(1.0 - p.length_squared());
        let nh = p.x * t1 + p.y * t2 + pz * wh;
        Vec3::new(self.alpha_x * nh.x, self.alpha_y * nh.y, nh.z.max(1e-6)).normalize()
    }

    /// The stretched view direction `wh` (upper hemisphere) of [`Self::sample_wm`] and the two
    /// tangents of the disk its samples are projected from.
    fn visible_frame(&self, w: Vec3) -> (Vec3, Vec3, Vec3) {
        let mut wh = Vec3::new(self.alpha_x * w.x, self.alpha_y * w.y, w.z).normalize();
        if wh.z < 0.0 {
            wh = -wh;
        }
        let t1 = if wh.z < 0.99999 { Vec3::Z.cross(wh).normalize() } else { Vec3::X };
        let t2 = wh.cross(t1);
        (wh, t1, t2)
    }

    /// The sample `u` with which [`Self::sample_wm`] produces the normal `wm` (upper
    /// hemisphere) seen from `w`, undoing its steps in reverse order (Bitterli et al. 2017,
    /// "Reversible Jump Metropolis Light Transport using Inverse Mappings", §5); `None` where
    /// `wm` is not visible from `w`.
    pub fn sample_wm_inverse(&self, w: Vec3, wm: Vec3) -> Option<Vec2> {
        let (wh, t1, t2) = self.visible_frame(w);
        let nh = Vec3::new(wm.x / self.alpha_x, wm.y / self.alpha_y, wm.z).normalize();
        if nh.dot(wh).is_nan() || nh.dot(wh) < 0.0 {
            return None;
        }
        let (px, py) = (nh.dot(t1), nh.dot(t2));
        let h = safe_sqrt(1.0 - px * px);
        let s = (1.0 + wh.z) * 0.5;
        Some(polar_disk_inverse(Vec2::new(px, (py - (1.0 - s) * h) / s)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projected_ndf_integrates_to_one() {
        // ∫ D(wm) cos θm dωm = 1 over the hemisphere.
        for ggx in [Ggx::isotropic(0.3), Ggx::new(0.15, 0.6)] {
            let (nt, np) = (800, 400);
            let mut sum = 0.0f64;
            for i in 0..nt {
                let mu = (i as f32 + 0.5) / nt as f32;
                let s = (1.0 - mu * mu).sqrt();
                for j in 0..np {
                    let phi = 2.0 * PI * (j as f32 + 0.5) / np as f32;
                    let wm = Vec3::new(s * phi.cos(), s * phi.sin(), mu);
                    sum += f64::from(ggx.d(wm) * mu);
                }
            }
            let integral = sum * 2.0 * std::f64::consts::PI / f64::from(nt * np);
            assert!((integral - 1.0).abs() < 5e-3, "{integral}");
        }
    }
}
