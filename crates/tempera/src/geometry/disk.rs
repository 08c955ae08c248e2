//! Analytic disks: ray–plane intersection clipped to a radius, and uniform area sampling by the
//! concentric map (pbrt-v4 §6.4).

use super::sphere::ShapeSample;
use super::{Ray, SurfacePoint};
use crate::math::frame::Frame;
use crate::math::warp::concentric_disk;
use crate::math::{Vec2, Vec3};
use std::f32::consts::PI;

#[derive(Clone, Copy, Debug)]
pub struct Disk {
    pub center: Vec3,
    /// Local frame; the disk lies in its `s`–`t` plane and faces `n`.
    pub frame: Frame,
    pub radius: f32,
    pub reverse_orientation: bool,
}

impl Disk {
    pub fn new(center: Vec3, normal: Vec3, radius: f32) -> Self {
        Self { center, frame: Frame::from_z(normal.normalize()), radius, reverse_orientation: false }
    }

    pub fn area(&self) -> f32 {
        PI * self.radius * self.radius
    }

    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let n = self.frame.n;
        let denom = ray.d.dot(n);
        if denom == 0.0 {
            return None;
        }
        let t = (self.center - ray.o).dot(n) / denom;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let p = ray.at(t) - self.center;
        let r2 = p.length_squared() - p.dot(n).powi(2);
        (r2 <= self.radius * self.radius).then_some(t)
    }

    pub fn surface(&self, p: Vec3) -> SurfacePoint {
        let local = self.frame.to_local(p - self.center);
        let dist = Vec2::new(local.x, local.y).length();
        let phi = {
            let a = local.y.atan2(local.x);
            if a < 0.0 { a + 2.0 * PI } else { a }
        };
        let uv = Vec2::new(phi / (2.0 * PI), 1.0 - dist / self.radius);
        let p = self.center + self.frame.s * local.x + self.frame.t * local.y;
        let n = if self.reverse_orientation { -self.frame.n } else { self.frame.n };
        let dpdu = self.frame.to_world(Vec3::new(-local.y, local.x, 0.0)) * 2.0 * PI;
        let dpdu = if dpdu.length_squared() > 0.0 { dpdu } else { self.frame.s };
        // v = 1 - r/R, so dp/dv points inwards with length R.
        let radial = if dist > 0.0 { (p - self.center) / dist } else { self.frame.t };
        let dpdv = -radial * self.radius;
        SurfacePoint { p, ng: n, ns: n, uv, dpdu, dpdv }
    }

    pub fn sample_area(&self, u: Vec2) -> ShapeSample {
        let d = concentric_disk(u) * self.radius;
        let p = self.center + self.frame.s * d.x + self.frame.t * d.y;
        ShapeSample { point: self.surface(p), pdf: 1.0 / self.area() }
    }
}
