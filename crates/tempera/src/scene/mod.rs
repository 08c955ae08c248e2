//! The renderable scene: geometry behind an accelerator, materials, lights and camera, and the
//! [`SceneBuilder`] through which loaders and built-in scenes create it.

mod builder;

pub use builder::{AreaEmission, MaterialId, RenderDefaults, SceneBuilder, SceneError};

use crate::accel::{Accel, Bvh};
use crate::bsdf::SurfaceBsdf;
use crate::camera::{Camera, CameraDesc};
use crate::film::FilmDesc;
use crate::geometry::{Geometry, Ray, SurfacePoint};
use crate::light::{Light, LightSampler};
use crate::material::Material;
use crate::math::frame::Frame;
use crate::math::{Rgb, Vec3};

/// Sentinel for "no light" in the per-primitive light table.
const NO_LIGHT: u32 = u32::MAX;

/// A ray's hit with everything shading needs.
#[derive(Clone, Copy, Debug)]
pub struct Interaction {
    pub surface: SurfacePoint,
    pub t: f32,
    /// Unit direction towards where the ray came from.
    pub wo: Vec3,
    pub prim: u32,
    pub material: u32,
}

pub struct Scene {
    pub geometry: Geometry,
    accel: Bvh,
    pub materials: Vec<Material>,
    shape_material: Vec<u32>,
    prim_light: Vec<u32>,
    pub lights: Vec<Light>,
    pub light_sampler: LightSampler,
    /// Indices of infinite lights (seen by escaping rays).
    pub infinite_lights: Vec<u32>,
    pub camera_desc: CameraDesc,
    pub camera: Camera,
    pub film: FilmDesc,
    pub defaults: RenderDefaults,
    pub bounds: (Vec3, Vec3),
}

impl Scene {
    /// Nearest surface hit along `ray`.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<Interaction> {
        let hit = self.accel.intersect(&self.geometry, ray, f32::INFINITY)?;
        let surface = self.geometry.surface(ray, &hit);
        let shape = self.geometry.prims[hit.prim as usize].shape;
        Some(Interaction {
            surface,
            t: hit.t,
            wo: -ray.d,
            prim: hit.prim,
            material: self.shape_material[shape as usize],
        })
    }

    /// True when something blocks `ray` before `t_max`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.accel.occluded(&self.geometry, ray, t_max)
    }

    /// The light attached to primitive `prim`, if it emits.
    #[inline]
    pub fn area_light(&self, prim: u32) -> Option<(u32, &Light)> {
        let l = self.prim_light[prim as usize];
        (l != NO_LIGHT).then(|| (l, &self.lights[l as usize]))
    }

    /// Radiance emitted from the hit towards `wo`.
    pub fn emitted(&self, it: &Interaction) -> Rgb {
        match self.area_light(it.prim) {
            Some((_, Light::Area(l))) => l.l(&it.surface, it.wo),
            _ => Rgb::ZERO,
        }
    }

    /// The BSDF at a hit, placed in its shading frame.
    #[inline]
    pub fn bsdf(&self, it: &Interaction) -> SurfaceBsdf {
        let s = &it.surface;
        SurfaceBsdf {
            bsdf: self.materials[it.material as usize].bsdf(s.uv),
            frame: Frame::from_normal_tangent(s.ns, s.dpdu),
            ng: s.ng,
        }
    }

    /// Radius of the bounding sphere of the geometry.
    pub fn radius(&self) -> f32 {
        let (lo, hi) = self.bounds;
        if lo.is_finite() && hi.is_finite() { 0.5 * (hi - lo).length() } else { 1.0 }
    }

    /// Changes the film resolution, keeping the camera's field-of-view convention.
    pub fn set_resolution(&mut self, width: u32, height: u32) {
        self.film.width = width;
        self.film.height = height;
        self.camera = Camera::Perspective(self.camera_desc.build(width, height));
    }
}
