//! Ray–scene intersection: the [`Accel`] trait, a wide BVH behind it ([`bvh::Bvh`]) and a
//! brute-force reference used to test it.

pub mod brute;
pub mod bvh;

pub use brute::BruteForce;
pub use bvh::Bvh;

use crate::geometry::{Geometry, PrimHit, Ray};

/// Finds the nearest hit along a ray, or whether anything blocks a segment.
pub trait Accel: Send + Sync {
    /// Nearest hit with `0 < t < t_max`.
    fn intersect(&self, geometry: &Geometry, ray: &Ray, t_max: f32) -> Option<PrimHit>;
    /// True when any primitive is hit with `0 < t < t_max`.
    fn occluded(&self, geometry: &Geometry, ray: &Ray, t_max: f32) -> bool;
}
