//! Object instancing: a prototype is geometry with its own BVH and materials, stored once; an
//! instance places it with a transformation. The scene's top-level BVH sees each instance as one
//! primitive; intersecting it transforms the ray into the prototype's space and traverses the
//! prototype's BVH (a two-level hierarchy, pbrt-v4 §7.1.4).

use super::{Geometry, PrimHit, Ray, SurfacePoint};
use crate::accel::{Accel, Bvh};
use crate::math::{Mat3, Mat4, Vec3};

/// Geometry shared by instances.
#[derive(Clone, Debug)]
pub struct Prototype {
    pub geometry: Geometry,
    pub bvh: Bvh,
    /// Material index of each of the prototype's shapes.
    pub shape_material: Vec<u32>,
}

impl Prototype {
    pub fn new(mut geometry: Geometry, shape_material: Vec<u32>) -> Self {
        let bvh = Bvh::build(&mut geometry);
        Self { geometry, bvh, shape_material }
    }
}

/// A prototype placed in the world.
#[derive(Clone, Debug)]
pub struct Instance {
    pub prototype: u32,
    pub to_world: Mat4,
    to_object: Mat4,
    normal_to_world: Mat3,
}

impl Instance {
    /// `None` when `to_world` is not invertible.
    pub fn new(prototype: u32, to_world: Mat4) -> Option<Self> {
        let to_object = to_world.inverse();
        if !to_object.is_finite() || to_world.determinant().abs() < 1e-20 {
            return None;
        }
        let normal_to_world = Mat3::from_mat4(to_object).transpose();
        Some(Self { prototype, to_world, to_object, normal_to_world })
    }

    /// The ray in the prototype's space, with unit direction, and the factor by which
    /// distances grow from world to prototype space (`t_object = t_world · scale`).
    #[inline]
    pub fn object_ray(&self, ray: &Ray) -> (Ray, f32) {
        let d = self.to_object.transform_vector3(ray.d);
        let scale = d.length();
        (Ray::new(self.to_object.transform_point3(ray.o), d / scale), scale)
    }

    /// Intersects the instance; the hit's `prim` is set by the caller.
    #[inline]
    pub fn intersect(&self, prototype: &Prototype, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        let (obj, scale) = self.object_ray(ray);
        let hit = prototype.bvh.intersect(&prototype.geometry, &obj, t_max * scale)?;
        Some(PrimHit { prim: 0, t: hit.t / scale, b: hit.b, inner: hit.prim })
    }

    /// Surface data of a hit, in world space.
    pub fn surface(&self, prototype: &Prototype, ray: &Ray, hit: &PrimHit) -> SurfacePoint {
        let (obj, scale) = self.object_ray(ray);
        let inner = PrimHit { prim: hit.inner, t: hit.t * scale, b: hit.b, inner: 0 };
        let s = prototype.geometry.surface(&obj, &inner);
        let normal = |n: Vec3| (self.normal_to_world * n).normalize_or_zero();
        SurfacePoint {
            p: self.to_world.transform_point3(s.p),
            ng: normal(s.ng),
            ns: normal(s.ns),
            uv: s.uv,
            dpdu: self.to_world.transform_vector3(s.dpdu),
            dpdv: self.to_world.transform_vector3(s.dpdv),
        }
    }

    /// World-space bounds of the placed prototype.
    pub fn bounds(&self, prototype: &Prototype) -> (Vec3, Vec3) {
        let (lo, hi) = prototype.geometry.world_bounds();
        let mut out = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        if !lo.is_finite() || !hi.is_finite() {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        for i in 0..8 {
            let c = Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            let p = self.to_world.transform_point3(c);
            out = (out.0.min(p), out.1.max(p));
        }
        out
    }
}
