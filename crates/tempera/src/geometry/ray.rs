//! Rays and robust spawning of secondary rays off a surface.

use crate::math::Vec3;

/// A ray with unit-length direction.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub o: Vec3,
    pub d: Vec3,
}

impl Ray {
    #[inline]
    pub fn new(o: Vec3, d: Vec3) -> Self {
        Self { o, d }
    }

    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }
}

/// Offset scale for spawning rays: relative to the magnitude of the point so that large scenes
/// keep working, with a floor for points near the origin.
#[inline]
pub fn offset_scale(p: Vec3) -> f32 {
    1e-4 * (1.0 + p.abs().max_element() * 0.05)
}

/// Moves `p` off the surface with geometric normal `ng` to the side that `w` points to.
#[inline]
pub fn offset_origin(p: Vec3, ng: Vec3, w: Vec3) -> Vec3 {
    let off = ng * offset_scale(p);
    if w.dot(ng) >= 0.0 { p + off } else { p - off }
}

/// A ray leaving a surface point in direction `w` (unit length).
#[inline]
pub fn spawn_ray(p: Vec3, ng: Vec3, w: Vec3) -> Ray {
    Ray::new(offset_origin(p, ng, w), w)
}

/// A shadow ray from a surface point towards `target`; returns the ray and the distance to test
/// (slightly short of the target so that the target's own surface is not hit).
#[inline]
pub fn spawn_ray_to(p: Vec3, ng: Vec3, target: Vec3) -> (Ray, f32) {
    let o = offset_origin(p, ng, target - p);
    let delta = target - o;
    let dist = delta.length();
    let d = delta / dist;
    (Ray::new(o, d), dist * (1.0 - 1e-4) - offset_scale(target))
}
