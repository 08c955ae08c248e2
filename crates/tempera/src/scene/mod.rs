//! The renderable scene: geometry behind an accelerator, materials, lights and camera, and the
//! [`SceneBuilder`] through which loaders and built-in scenes create it.

mod builder;
#[cfg(test)]
mod tests;

pub use builder::{
    AreaEmission, ChainDefaults, MaterialId, PrototypeId, PrototypeShape, RenderDefaults, SceneBuilder, SceneError,
};

use crate::accel::{Accel, AccelKind, SceneAccel};
use crate::bsdf::SurfaceBsdf;
use crate::camera::{Camera, CameraDesc};
use crate::film::FilmDesc;
use crate::geometry::{Geometry, Ray, SurfacePoint};
use crate::light::{Light, LightSampler};
use crate::material::Material;
use crate::math::frame::Frame;
use crate::math::{Rgb, Vec3};
use crate::medium::{Medium, MediumInterface};
use crate::texture::Texture;

/// Sentinel for "no light" in the per-primitive light table.
const NO_LIGHT: u32 = u32::MAX;

/// Nesting limit when resolving `mix` materials.
const MAX_MIX_DEPTH: usize = 16;

/// Parametric step of the finite differences in bump mapping (pbrt-v4's fallback when ray
/// differentials are unavailable).
const BUMP_STEP: f32 = 5e-4;

/// The shading frame perturbed by the displacement texture `d` (Blinn 1978; pbrt-v4 §10.5.3):
/// `∂p'/∂u = ∂p/∂u + (∂d/∂u) n`, likewise for v, `n' = ∂p'/∂u × ∂p'/∂v` on the side of `n`.
fn bump(d: &Texture, s: &SurfacePoint) -> Frame {
    let base = Frame::from_normal_tangent(s.ns, s.dpdu);
    let usable = |v: Vec3| v.length_squared() > 0.0 && v.is_finite();
    let (dpdu, dpdv) = if usable(s.dpdu) && usable(s.dpdv) { (s.dpdu, s.dpdv) } else { (base.s, base.t) };
    let d0 = d.eval_float(s.uv);
    let du = (d.eval_float(s.uv + crate::math::Vec2::new(BUMP_STEP, 0.0)) - d0) / BUMP_STEP;
    let dv = (d.eval_float(s.uv + crate::math::Vec2::new(0.0, BUMP_STEP)) - d0) / BUMP_STEP;
    let (pu, pv) = (dpdu + du * s.ns, dpdv + dv * s.ns);
    let n = pu.cross(pv).normalize_or_zero();
    if n == Vec3::ZERO || !n.is_finite() {
        return base;
    }
    Frame::from_normal_tangent(if n.dot(s.ns) < 0.0 { -n } else { n }, pu)
}

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
    accel: SceneAccel,
    pub materials: Vec<Material>,
    /// Bump-map displacement per material.
    displacement: Vec<Option<Texture>>,
    /// Materials that are black seen from behind their geometric normal (Mitsuba's default).
    one_sided: Vec<bool>,
    shape_material: Vec<u32>,
    /// The media each shape separates, where it bounds any (shapes outside instances).
    shape_medium: Vec<Option<MediumInterface>>,
    /// Homogeneous participating media ([`crate::medium`]).
    pub media: Vec<Medium>,
    /// The medium the camera sits in (`None`: vacuum).
    pub camera_medium: Option<u32>,
    /// Per light, the medium it sits in where its surface bounds none (`None`: vacuum).
    light_media: Vec<Option<u32>>,
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
    /// The accelerator the scene was built with.
    pub fn accel_kind(&self) -> AccelKind {
        self.accel.kind()
    }

    /// Nearest surface hit along `ray`.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<Interaction> {
        let hit = self.accel.intersect(&self.geometry, ray, f32::INFINITY)?;
        let surface = self.geometry.surface(ray, &hit);
        let material = match self.geometry.instance(hit.prim) {
            Some((_, proto)) => proto.shape_material[proto.geometry.prims[hit.inner as usize].shape as usize],
            None => self.shape_material[self.geometry.prims[hit.prim as usize].shape as usize],
        };
        Some(Interaction { surface, t: hit.t, wo: -ray.d, prim: hit.prim, material })
    }

    /// True when something blocks `ray` before `t_max`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.accel.occluded(&self.geometry, ray, t_max)
    }

    /// True when the scene holds participating media.
    #[inline]
    pub fn has_media(&self) -> bool {
        !self.media.is_empty()
    }

    /// The media the hit surface separates, if it bounds any.
    #[inline]
    pub fn medium_interface(&self, it: &Interaction) -> Option<MediumInterface> {
        self.prim_medium_interface(it.prim)
    }

    /// The media primitive `prim` separates, if it bounds any.
    #[inline]
    pub fn prim_medium_interface(&self, prim: u32) -> Option<MediumInterface> {
        if self.media.is_empty() || self.geometry.instance(prim).is_some() {
            return None;
        }
        let shape = self.geometry.prims[prim as usize].shape as usize;
        self.shape_medium.get(shape).copied().flatten()
    }

    /// The medium light `light` emits into along `w` (`n`: its surface normal, for area
    /// lights whose surface bounds media).
    pub fn light_medium(&self, light: usize, n: Vec3, w: Vec3) -> Option<u32> {
        if let Some(Light::Area(a)) = self.lights.get(light)
            && let Some(mi) = self.prim_medium_interface(a.prim)
        {
            return mi.towards(n, w);
        }
        self.light_media.get(light).copied().flatten()
    }

    /// True when the hit surface only bounds media (pbrt's `interface` material): rays pass
    /// through it unchanged.
    #[inline]
    pub fn is_interface(&self, it: &Interaction) -> bool {
        matches!(self.materials.get(it.material as usize), Some(Material::Interface))
    }

    /// The medium a ray in `current` is in after leaving the hit along `w`.
    #[inline]
    pub fn medium_after(&self, it: &Interaction, w: Vec3, current: Option<u32>) -> Option<u32> {
        match self.medium_interface(it) {
            Some(mi) => mi.towards(it.surface.ng, w),
            None => current,
        }
    }

    /// The transmittance from `p` (on a surface with geometric normal `ng`, or in a medium
    /// where `ng` is zero) to `target` (a point, or a direction when `to_infinity`), starting in
    /// `medium`: the product of every medium's transmittance along the way, through surfaces
    /// that only bound media; zero when anything else blocks it. Counts the rays it traces.
    pub fn transmittance(
        &self,
        p: Vec3,
        ng: Vec3,
        target: Vec3,
        to_infinity: bool,
        mut medium: Option<u32>,
        rays: &mut u64,
    ) -> Rgb {
        use crate::geometry::{spawn_ray, spawn_ray_to};
        let (mut ray, mut t_max) =
            if to_infinity { (spawn_ray(p, ng, target), f32::INFINITY) } else { spawn_ray_to(p, ng, target) };
        let mut tr = Rgb::ONE;
        // Each crossing moves the origin past a surface; a bound keeps degenerate
        // geometry from looping.
        for _ in 0..256 {
            *rays += 1;
            let hit = self.intersect(&ray).filter(|it| it.t < t_max);
            let along = hit.as_ref().map_or(t_max, |it| it.t);
            if let Some(m) = medium {
                tr *= self.media[m as usize].transmittance(along);
            }
            let Some(it) = hit else { return tr };
            if !self.is_interface(&it) || tr.max_element() <= 0.0 {
                return Rgb::ZERO;
            }
            medium = self.medium_after(&it, ray.d, medium);
            let next = spawn_ray(it.surface.p, it.surface.ng, ray.d);
            t_max = if to_infinity { f32::INFINITY } else { (target - next.o).dot(ray.d) * (1.0 - 1e-4) };
            ray = next;
        }
        Rgb::ZERO
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

    /// The material at a hit, with `mix` materials resolved.
    fn resolve_material(&self, it: &Interaction) -> u32 {
        let mut index = it.material;
        for _ in 0..MAX_MIX_DEPTH {
            match &self.materials[index as usize] {
                Material::Mix(m) => index = m.choose(it.surface.uv, it.surface.p, it.wo),
                _ => break,
            }
        }
        index
    }

    /// The BSDF at a hit, placed in its (possibly bump-mapped) shading frame.
    #[inline]
    pub fn bsdf(&self, it: &Interaction) -> SurfaceBsdf {
        let s = &it.surface;
        let material = self.resolve_material(it) as usize;
        let frame = match &self.displacement[material] {
            Some(d) => bump(d, s),
            None => Frame::from_normal_tangent(s.ns, s.dpdu),
        };
        let bsdf = if self.one_sided[material] && it.wo.dot(s.ng) < 0.0 {
            crate::bsdf::Bsdf::Diffuse(crate::bsdf::Diffuse { reflectance: Rgb::ZERO })
        } else {
            self.materials[material].bsdf(s.uv)
        };
        SurfaceBsdf { bsdf, frame, ng: s.ng }
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
