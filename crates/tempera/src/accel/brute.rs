//! Brute-force intersection over every primitive: the ground truth the BVH is tested against.

use super::Accel;
use crate::geometry::{Geometry, PrimHit, Ray, RayShear};

#[derive(Clone, Copy, Debug, Default)]
pub struct BruteForce;

impl Accel for BruteForce {
    fn intersect(&self, geometry: &Geometry, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        let shear = RayShear::new(ray);
        let mut best: Option<PrimHit> = None;
        let mut t_best = t_max;
        for i in 0..geometry.prims.len() as u32 {
            if let Some(hit) = geometry.intersect_prim(i, ray, &shear, t_best) {
                t_best = hit.t;
                best = Some(hit);
            }
        }
        best
    }

    fn occluded(&self, geometry: &Geometry, ray: &Ray, t_max: f32) -> bool {
        let shear = RayShear::new(ray);
        (0..geometry.prims.len() as u32).any(|i| geometry.intersect_prim(i, ray, &shear, t_max).is_some())
    }
}
