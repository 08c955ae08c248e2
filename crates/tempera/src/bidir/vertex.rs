//! Path vertices of bidirectional path tracing with their forward and reverse area-measure
//! densities (Veach 1997 §10.2; pbrt-v4 §13.3 follows the same bookkeeping). Densities are per
//! unit area at the vertex, except at infinite-light vertices where they stay per solid angle.
//!
//! In homogeneous participating media ([`crate::medium`]) a path may scatter at a point inside
//! a medium: a [`VertexKind::Medium`] vertex, whose scattering function is the medium's phase
//! function and whose area density has no cosine factor (pbrt-v4 §13.3.2). The densities kept
//! here are the directional ones only; the free-flight distances' densities are left out of
//! them, as pbrt-v4's BDPT leaves them out, and the throughput carries each flight's own
//! weight. Every strategy then computes its MIS weight from the same quantities, so the weights
//! still sum to one over the strategies that can make a path.

use crate::bsdf::{SurfaceBsdf, TransportMode};
use crate::geometry::{Ray, SurfacePoint};
use crate::light::{Light, SceneSphere};
use crate::math::{Rgb, Vec3};
use crate::medium::MediumInterface;
use crate::scene::Scene;
use std::f32::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexKind {
    Camera,
    Light,
    Surface,
    /// A scattering point inside a participating medium.
    Medium,
}

#[derive(Clone, Copy, Debug)]
pub struct Vertex {
    pub kind: VertexKind,
    pub p: Vec3,
    /// Geometric normal; zero for points not on a surface (pinhole, point lights, infinite).
    pub ng: Vec3,
    /// Shading normal (equal to `ng` away from surfaces).
    pub ns: Vec3,
    /// Surface data, for emission at area lights.
    pub surface: Option<SurfacePoint>,
    pub bsdf: Option<SurfaceBsdf>,
    /// Unit direction towards the previous vertex of the subpath.
    pub wo: Vec3,
    /// Throughput of the subpath up to and including this vertex.
    pub beta: Rgb,
    pub pdf_fwd: f32,
    pub pdf_rev: f32,
    /// Sampled from a Dirac delta BSDF lobe.
    pub delta: bool,
    /// The emitter at this vertex (light vertices and emissive surfaces).
    pub light: Option<u32>,
    /// An infinite or directional light (at infinity, direction-only).
    pub infinite: bool,
    /// The medium the vertex sits in: for a surface, the one its incoming ray travelled in
    /// (`None`: vacuum).
    pub medium: Option<u32>,
    /// The media a surface vertex separates, when its surface bounds any.
    pub interface: Option<MediumInterface>,
}

impl Vertex {
    pub fn camera(p: Vec3, beta: Rgb) -> Self {
        Self {
            kind: VertexKind::Camera,
            p,
            ng: Vec3::ZERO,
            ns: Vec3::ZERO,
            surface: None,
            bsdf: None,
            wo: Vec3::ZERO,
            beta,
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
            delta: false,
            light: None,
            infinite: false,
            medium: None,
            interface: None,
        }
    }

    /// A scattering point at `p` in medium `medium`, reached along `-wo`.
    pub fn in_medium(p: Vec3, wo: Vec3, medium: u32, beta: Rgb) -> Self {
        Self { kind: VertexKind::Medium, wo, medium: Some(medium), ..Self::camera(p, beta) }
    }

    /// The medium a ray leaving this vertex along `w` travels in.
    #[inline]
    pub fn medium_towards(&self, w: Vec3) -> Option<u32> {
        match self.interface {
            Some(mi) => mi.towards(self.ng, w),
            None => self.medium,
        }
    }

    pub fn light(light: u32, p: Vec3, n: Vec3, beta: Rgb, pdf_fwd: f32, infinite: bool) -> Self {
        Self { kind: VertexKind::Light, ng: n, ns: n, light: Some(light), infinite, pdf_fwd, ..Self::camera(p, beta) }
    }

    /// The vertex where a camera ray escapes: an infinite light far along `ray`.
    pub fn escaped(ray: &Ray, scene: &Scene, beta: Rgb, pdf_fwd: f32) -> Self {
        let far = ray.o + ray.d * (1e4 * scene.radius().max(1.0));
        Self { kind: VertexKind::Light, infinite: true, pdf_fwd, ..Self::camera(far, beta) }
    }

    #[inline]
    pub fn is_on_surface(&self) -> bool {
        self.ng != Vec3::ZERO
    }

    /// True when this vertex emits light (a light vertex, or a surface on an emitter).
    pub fn is_light(&self) -> bool {
        self.kind == VertexKind::Light || self.light.is_some()
    }

    /// A light vertex whose position or direction is a Dirac delta.
    pub fn is_delta_light(&self, scene: &Scene) -> bool {
        self.kind == VertexKind::Light
            && self.light.is_some_and(|l| {
                let l = &scene.lights[l as usize];
                l.is_delta_position() || l.is_delta_direction()
            })
    }

    /// A connection can be made to this vertex (no delta lobe, no delta direction).
    pub fn connectible(&self, scene: &Scene) -> bool {
        match self.kind {
            VertexKind::Camera => true,
            VertexKind::Light => self.light.is_none_or(|l| !scene.lights[l as usize].is_delta_direction()),
            VertexKind::Surface => self.bsdf.is_some_and(|b| !b.is_delta()),
            VertexKind::Medium => true,
        }
    }

    /// Unit direction and squared distance from this vertex to `other`.
    #[inline]
    pub fn towards(&self, other: &Vertex) -> (Vec3, f32) {
        let d = other.p - self.p;
        let d2 = d.length_squared();
        (d / d2.sqrt(), d2)
    }

    /// The BSDF value (the phase function's, in a medium) for scattering from `wo` towards
    /// `next`.
    pub fn f(&self, scene: &Scene, next: &Vertex, mode: TransportMode) -> Rgb {
        match (&self.bsdf, self.kind) {
            (Some(b), VertexKind::Surface) => b.eval(self.wo, self.towards(next).0, mode),
            (_, VertexKind::Medium) => Rgb::splat(self.phase(scene, self.wo, self.towards(next).0)),
            _ => Rgb::ZERO,
        }
    }

    /// The phase function of a medium vertex for `wo`, `wi` pointing away from it.
    #[inline]
    fn phase(&self, scene: &Scene, wo: Vec3, wi: Vec3) -> f32 {
        self.medium.map_or(0.0, |m| scene.media[m as usize].phase(wo, wi))
    }

    /// Converts a solid-angle density at this vertex into an area density at `next`.
    pub fn convert_density(&self, pdf: f32, next: &Vertex) -> f32 {
        if next.infinite {
            return pdf;
        }
        let (w, d2) = self.towards(next);
        if d2 == 0.0 {
            return 0.0;
        }
        let cos = if next.is_on_surface() { next.ng.dot(w).abs() } else { 1.0 };
        pdf * cos / d2
    }

    /// Area density with which this vertex, reached from `prev`, samples `next`.
    pub fn pdf(&self, scene: &Scene, prev: Option<&Vertex>, next: &Vertex) -> f32 {
        match self.kind {
            VertexKind::Light => self.pdf_light(scene, next),
            VertexKind::Camera => {
                let (w, _) = self.towards(next);
                let (_, pdf_dir) = scene.camera.pdf_we(&Ray::new(self.p, w));
                self.convert_density(pdf_dir, next)
            }
            VertexKind::Surface => {
                let (Some(bsdf), Some(prev)) = (&self.bsdf, prev) else { return 0.0 };
                let wo = self.towards(prev).0;
                let wi = self.towards(next).0;
                self.convert_density(bsdf.pdf(wo, wi), next)
            }
            VertexKind::Medium => {
                let Some(prev) = prev else { return 0.0 };
                let (wo, wi) = (self.towards(prev).0, self.towards(next).0);
                self.convert_density(self.phase(scene, wo, wi), next)
            }
        }
    }

    fn sphere(scene: &Scene) -> SceneSphere {
        let (lo, hi) = scene.bounds;
        let center = if lo.is_finite() && hi.is_finite() { 0.5 * (lo + hi) } else { Vec3::ZERO };
        SceneSphere { center, radius: scene.radius().max(1e-3) }
    }

    /// Area density with which this light vertex emits towards `next`.
    pub fn pdf_light(&self, scene: &Scene, next: &Vertex) -> f32 {
        let (w, d2) = self.towards(next);
        let mut pdf = if self.infinite {
            let r = Self::sphere(scene).radius;
            1.0 / (PI * r * r)
        } else {
            let Some(l) = self.light else { return 0.0 };
            let (_, pdf_dir) = scene.lights[l as usize].pdf_le(&scene.geometry, Self::sphere(scene), w, self.ng);
            pdf_dir / d2
        };
        if next.is_on_surface() {
            pdf *= next.ng.dot(w).abs();
        }
        pdf
    }

    /// Density with which light sampling chooses this vertex as the origin of a light subpath
    /// that continues towards `next`.
    pub fn pdf_light_origin(&self, scene: &Scene, next: &Vertex) -> f32 {
        let (w, _) = self.towards(next);
        if self.infinite {
            return infinite_light_density(scene, w);
        }
        let Some(l) = self.light else { return 0.0 };
        let (pdf_pos, _) = scene.lights[l as usize].pdf_le(&scene.geometry, Self::sphere(scene), w, self.ng);
        scene.light_sampler.pmf(l as usize) * pdf_pos
    }

    /// Radiance this light vertex emits towards `towards`.
    pub fn le(&self, scene: &Scene, towards: &Vertex) -> Rgb {
        if !self.is_light() {
            return Rgb::ZERO;
        }
        let (w, _) = self.towards(towards);
        if self.infinite {
            return scene.infinite_lights.iter().map(|&i| scene.lights[i as usize].le(-w)).sum();
        }
        match (self.light.map(|l| &scene.lights[l as usize]), &self.surface) {
            (Some(Light::Area(a)), Some(s)) => a.l(s, w),
            _ => Rgb::ZERO,
        }
    }
}

/// Combined solid-angle density of choosing and sampling a direction on every infinite light,
/// for light travelling along `w`.
pub fn infinite_light_density(scene: &Scene, w: Vec3) -> f32 {
    scene
        .infinite_lights
        .iter()
        .map(|&i| scene.light_sampler.pmf(i as usize) * scene.lights[i as usize].pdf_li_dir(-w))
        .sum()
}

/// The scene's bounding sphere.
pub fn scene_sphere(scene: &Scene) -> SceneSphere {
    Vertex::sphere(scene)
}
