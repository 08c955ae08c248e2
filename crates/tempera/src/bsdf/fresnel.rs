//! Fresnel reflectance for dielectrics and conductors (complex index of refraction), refraction,
//! and the hemispherical diffuse Fresnel reflectance (pbrt-v4 §9.3).

use crate::math::{Rgb, Vec3, safe_sqrt};

/// Unpolarised Fresnel reflectance of a dielectric interface. `cos_i` is measured on the side
/// the light arrives from; negative values mean arrival from inside (`eta` = inside / outside).
pub fn dielectric(cos_i: f32, eta: f32) -> f32 {
    let mut cos_i = cos_i.clamp(-1.0, 1.0);
    let mut eta = eta;
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_i = 1.0 - cos_i * cos_i;
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = safe_sqrt(1.0 - sin2_t);
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_parl * r_parl + r_perp * r_perp)
}

#[derive(Clone, Copy, Debug)]
struct Complex {
    re: f32,
    im: f32,
}

impl Complex {
    fn new(re: f32, im: f32) -> Self {
        Self { re, im }
    }
    fn add(self, o: Self) -> Self {
        Self::new(self.re + o.re, self.im + o.im)
    }
    fn sub(self, o: Self) -> Self {
        Self::new(self.re - o.re, self.im - o.im)
    }
    fn mul(self, o: Self) -> Self {
        Self::new(self.re * o.re - self.im * o.im, self.re * o.im + self.im * o.re)
    }
    fn scale(self, s: f32) -> Self {
        Self::new(self.re * s, self.im * s)
    }
    fn norm(self) -> f32 {
        self.re * self.re + self.im * self.im
    }
    fn div(self, o: Self) -> Self {
        let s = 1.0 / o.norm();
        Self::new((self.re * o.re + self.im * o.im) * s, (self.im * o.re - self.re * o.im) * s)
    }
    fn sqrt(self) -> Self {
        let n = self.norm().sqrt();
        if n == 0.0 {
            return Self::new(0.0, 0.0);
        }
        let t1 = (0.5 * (n + self.re.abs())).sqrt();
        let t2 = 0.5 * self.im / t1;
        if self.re >= 0.0 { Self::new(t1, t2) } else { Self::new(t2.abs(), t1.copysign(self.im)) }
    }
}

/// Fresnel reflectance of a conductor with complex index `eta + i·k` for one channel.
pub fn conductor(cos_i: f32, eta: f32, k: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let eta = Complex::new(eta, k);
    let sin2_i = 1.0 - cos_i * cos_i;
    let sin2_t = Complex::new(sin2_i, 0.0).div(eta.mul(eta));
    let cos_t = Complex::new(1.0, 0.0).sub(sin2_t).sqrt();
    let ci = Complex::new(cos_i, 0.0);
    let eci = eta.scale(cos_i);
    let r_parl = eci.sub(cos_t).div(eci.add(cos_t));
    let ect = eta.mul(cos_t);
    let r_perp = ci.sub(ect).div(ci.add(ect));
    let r = 0.5 * (r_parl.norm() + r_perp.norm());
    if r.is_finite() { r.clamp(0.0, 1.0) } else { 1.0 }
}

/// Per-channel conductor Fresnel reflectance.
pub fn conductor_rgb(cos_i: f32, eta: Rgb, k: Rgb) -> Rgb {
    Rgb::new(conductor(cos_i, eta.x, k.x), conductor(cos_i, eta.y, k.y), conductor(cos_i, eta.z, k.z))
}

/// pbrt-v4's `reflectance` parametrisation of a conductor: `eta = 1`, `k = 2·sqrt(r)/sqrt(1-r)`,
/// which reflects exactly `r` at normal incidence.
pub fn conductor_from_reflectance(r: Rgb) -> (Rgb, Rgb) {
    let r = r.clamp(Rgb::ZERO, Rgb::splat(0.9999));
    let k = Rgb::new(
        2.0 * r.x.sqrt() / (1.0 - r.x).sqrt(),
        2.0 * r.y.sqrt() / (1.0 - r.y).sqrt(),
        2.0 * r.z.sqrt() / (1.0 - r.z).sqrt(),
    );
    (Rgb::ONE, k)
}

/// Refracts `wi` about `n` (same side as `wi`) with relative index `eta` (transmitted side over
/// incident side, flipped when `wi` is below `n`). Returns the direction and the effective eta,
/// or `None` under total internal reflection.
pub fn refract(wi: Vec3, n: Vec3, eta: f32) -> Option<(Vec3, f32)> {
    let mut cos_i = n.dot(wi);
    let (mut eta, mut n) = (eta, n);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = safe_sqrt(1.0 - sin2_t);
    Some((-wi / eta + (cos_i / eta - cos_t) * n, eta))
}

/// Hemispherical average `2∫ F(μ) μ dμ` of the dielectric reflectance for light arriving on the
/// side where the relative index is `eta` (numerical quadrature).
pub fn diffuse_reflectance(eta: f32) -> f32 {
    let n = 2000;
    let sum: f64 = (0..n)
        .map(|i| {
            let mu = (i as f32 + 0.5) / n as f32;
            f64::from(dielectric(mu, eta) * mu)
        })
        .sum();
    (2.0 * sum / f64::from(n)) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_limits() {
        assert!((dielectric(1.0, 1.5) - 0.04).abs() < 1e-4);
        assert_eq!(dielectric(-0.1, 1.5), 1.0, "total internal reflection");
        assert!((dielectric(0.0, 1.5) - 1.0).abs() < 1e-4, "grazing");
    }

    #[test]
    fn conductor_matches_dielectric_without_absorption_and_reflectance_parametrisation() {
        for cos in [0.1, 0.5, 0.9, 1.0] {
            assert!((conductor(cos, 1.5, 0.0) - dielectric(cos, 1.5)).abs() < 1e-4);
        }
        let (eta, k) = conductor_from_reflectance(Rgb::new(0.2, 0.5, 0.9));
        let r = conductor_rgb(1.0, eta, k);
        assert!((r - Rgb::new(0.2, 0.5, 0.9)).abs().max_element() < 1e-3, "{r}");
    }

    #[test]
    fn diffuse_fresnel_relation() {
        // Energy balance across the interface: 1 - Fdr(eta) = eta² (1 - Fdr(1/eta)).
        let (ext, int) = (diffuse_reflectance(1.5), diffuse_reflectance(1.0 / 1.5));
        assert!((1.0 - ext - 1.5 * 1.5 * (1.0 - int)).abs() < 2e-3, "{ext} {int}");
        assert!((ext - 0.092).abs() < 0.005);
    }

    #[test]
    fn refraction_obeys_snell() {
        let wi = Vec3::new(0.6, 0.0, 0.8);
        let (wt, eta) = refract(wi, Vec3::Z, 1.5).unwrap();
        assert_eq!(eta, 1.5);
        assert!((wt.length() - 1.0).abs() < 1e-5);
        assert!((0.6f32 - 1.5 * wt.x.abs()).abs() < 1e-5 && wt.z < 0.0);
        assert!(refract(Vec3::new(0.9, 0.0, -0.435_889_9).normalize(), Vec3::Z, 1.5).is_none());
    }
}
