//! Analytic spheres: intersection with the precision-improved quadratic of Haines et al.
//! ("Precision Improvements for Ray/Sphere Intersection", Ray Tracing Gems ch. 7), area sampling,
//! and sampling of the visible cone from an outside point (pbrt-v4 §6.2.4).

use super::{Ray, SurfacePoint};
use crate::math::frame::Frame;
use crate::math::warp::{spherical_direction, uniform_sphere};
use crate::math::{Vec2, Vec3, safe_sqrt};
use std::f32::consts::PI;

#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
    /// Normals point inwards when set.
    pub reverse_orientation: bool,
}

/// A point sampled on a shape, with its density either per area or per solid angle.
#[derive(Clone, Copy, Debug)]
pub struct ShapeSample {
    pub point: SurfacePoint,
    pub pdf: f32,
}

impl Sphere {
    pub fn area(&self) -> f32 {
        4.0 * PI * self.radius * self.radius
    }

    /// Nearest intersection distance in `(0, t_max)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let f = ray.o - self.center;
        let b = -f.dot(ray.d);
        let r2 = self.radius * self.radius;
        let l = f + b * ray.d;
        let disc = r2 - l.length_squared();
        if disc < 0.0 {
            return None;
        }
        let c = f.length_squared() - r2;
        let q = b + disc.sqrt().copysign(b);
        let (mut t0, mut t1) = (c / q, q);
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        if t0 > 0.0 && t0 < t_max {
            Some(t0)
        } else if t1 > 0.0 && t1 < t_max {
            Some(t1)
        } else {
            None
        }
    }

    /// Surface data at a point on (or numerically near) the sphere.
    pub fn surface(&self, p: Vec3) -> SurfacePoint {
        let mut n = (p - self.center).normalize_or_zero();
        if n == Vec3::ZERO {
            n = Vec3::Z;
        }
        let p = self.center + n * self.radius;
        let phi = {
            let a = n.y.atan2(n.x);
            if a < 0.0 { a + 2.0 * PI } else { a }
        };
        let theta = n.z.clamp(-1.0, 1.0).acos();
        let uv = Vec2::new(phi / (2.0 * PI), 1.0 - theta / PI);
        let mut dpdu = Vec3::new(-2.0 * PI * n.y, 2.0 * PI * n.x, 0.0);
        if dpdu.length_squared() < 1e-12 {
            dpdu = Frame::from_z(n).s;
        }
        // v = 1 - θ/π, so dp/dv = -π · dp/dθ.
        let dpdv = -PI * self.radius * Vec3::new(n.z * phi.cos(), n.z * phi.sin(), -theta.sin());
        let n = if self.reverse_orientation { -n } else { n };
        SurfacePoint { p, ng: n, ns: n, uv, dpdu, dpdv }
    }

    /// Uniform sample over the whole surface, density per unit area.
    pub fn sample_area(&self, u: Vec2) -> ShapeSample {
        let p = self.center + self.radius * uniform_sphere(u);
        ShapeSample { point: self.surface(p), pdf: 1.0 / self.area() }
    }

    /// Samples the cone of directions subtended by the sphere from `reference`; the density is
    /// per unit solid angle. Falls back to area sampling (converted to solid angle) from inside.
    pub fn sample_from(&self, reference: Vec3, u: Vec2) -> Option<ShapeSample> {
        let dc2 = (reference - self.center).length_squared();
        let r2 = self.radius * self.radius;
        if dc2 <= r2 * 1.0001 {
            let s = self.sample_area(u);
            let w = s.point.p - reference;
            let d2 = w.length_squared();
            let cos = s.point.ng.dot(-w.normalize_or_zero()).abs();
            if d2 == 0.0 || cos == 0.0 {
                return None;
            }
            return Some(ShapeSample { point: s.point, pdf: s.pdf * d2 / cos });
        }
        let sin2_max = r2 / dc2;
        let sin_max = sin2_max.sqrt();
        let cos_max = safe_sqrt(1.0 - sin2_max);
        let mut one_minus_cos_max = 1.0 - cos_max;
        let mut cos_theta = (cos_max - 1.0) * u.x + 1.0;
        let mut sin2_theta = 1.0 - cos_theta * cos_theta;
        if sin2_max < 0.000_685_23 {
            // Small cones: Taylor expansion keeps precision.
            sin2_theta = sin2_max * u.x;
            cos_theta = (1.0 - sin2_theta).sqrt();
            one_minus_cos_max = sin2_max / 2.0;
        }
        let cos_alpha = sin2_theta / sin_max + cos_theta * safe_sqrt(1.0 - sin2_theta / sin2_max);
        let sin_alpha = safe_sqrt(1.0 - cos_alpha * cos_alpha);
        let phi = u.y * 2.0 * PI;
        let w = spherical_direction(sin_alpha, cos_alpha, phi);
        let frame = Frame::from_z((self.center - reference).normalize());
        let n = frame.to_world(-w);
        let point = self.surface(self.center + n * self.radius);
        Some(ShapeSample { point, pdf: 1.0 / (2.0 * PI * one_minus_cos_max) })
    }

    /// Solid-angle density of [`Self::sample_from`] for a direction that hits the sphere at `hit`.
    pub fn pdf_from(&self, reference: Vec3, hit: &SurfacePoint) -> f32 {
        let dc2 = (reference - self.center).length_squared();
        let r2 = self.radius * self.radius;
        if dc2 <= r2 * 1.0001 {
            let w = hit.p - reference;
            let cos = hit.ng.dot(w.normalize_or_zero()).abs();
            return if cos == 0.0 { 0.0 } else { w.length_squared() / (cos * self.area()) };
        }
        let sin2_max = r2 / dc2;
        let cos_max = safe_sqrt(1.0 - sin2_max);
        let one_minus = if sin2_max < 0.000_685_23 { sin2_max / 2.0 } else { 1.0 - cos_max };
        1.0 / (2.0 * PI * one_minus)
    }
}
