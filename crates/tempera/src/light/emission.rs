//! Sampling light leaving emitters, for light subpaths (pbrt-v4 §12, `SampleLe`/`PDF_Le`):
//! a position (area density, or a delta) and a direction (solid-angle density, or a delta).
//! Directional and environment lights emit from a disk of the scene's bounding radius.

use super::{Light, infinite::InfiniteLight};
use crate::geometry::ray::offset_origin;
use crate::geometry::{Geometry, Ray};
use crate::math::frame::Frame;
use crate::math::warp::{
    UNIFORM_SPHERE_PDF, concentric_disk, cosine_hemisphere, cosine_hemisphere_inverse, cosine_hemisphere_pdf,
    uniform_cone, uniform_cone_inverse, uniform_cone_pdf, uniform_sphere, uniform_sphere_inverse,
};
use crate::math::{Rgb, Vec2, Vec3};
use std::f32::consts::PI;

/// The scene's bounding sphere, which directional lights must cover.
#[derive(Clone, Copy, Debug)]
pub struct SceneSphere {
    pub center: Vec3,
    pub radius: f32,
}

/// Light leaving an emitter.
#[derive(Clone, Copy, Debug)]
pub struct EmissionSample {
    pub ray: Ray,
    /// Surface normal at the origin (the emission direction for directional lights, zero for
    /// point-like lights).
    pub n: Vec3,
    pub le: Rgb,
    /// Area density of the origin (1 for a delta position).
    pub pdf_pos: f32,
    /// Solid-angle density of the direction (1 for a delta direction).
    pub pdf_dir: f32,
}

fn disk_origin(sphere: SceneSphere, dir: Vec3, u: Vec2) -> Vec3 {
    let frame = Frame::from_z(dir);
    let d = concentric_disk(u) * sphere.radius;
    sphere.center + frame.s * d.x + frame.t * d.y - dir * sphere.radius
}

impl Light {
    /// The numbers with which [`Self::sample_le`] emits from `p` along `dir` (the inverse
    /// mapping of Bitterli et al. 2017): the position's sample (`None` for a point-like light,
    /// where any value does) and the direction's. Area lights on triangles, point and spot
    /// lights; `None` for other lights and shapes, and for directions they do not emit in.
    pub fn sample_le_inverse(&self, geometry: &Geometry, p: Vec3, dir: Vec3) -> Option<(Option<Vec2>, Vec2)> {
        match self {
            Light::Area(l) => {
                let u_pos = geometry.sample_area_inverse(l.prim, p)?;
                let ng = geometry.sample_area(l.prim, u_pos)?.point.ng;
                let cos = ng.dot(dir);
                let flip = cos < 0.0;
                if cos == 0.0 || (flip && !l.two_sided) {
                    return None;
                }
                let local = Frame::from_z(if flip { -ng } else { ng }).to_local(dir);
                let mut u = cosine_hemisphere_inverse(local);
                if l.two_sided {
                    u.x = if flip { 0.5 * u.x } else { 0.5 * (u.x + 1.0) }.min(1.0 - f32::EPSILON);
                }
                Some((Some(u_pos), u))
            }
            Light::Point(_) => Some((None, uniform_sphere_inverse(dir))),
            Light::Spot(l) => {
                let local = l.frame.to_local(dir);
                (local.z >= l.cos_falloff_end).then(|| (None, uniform_cone_inverse(local, l.cos_falloff_end)))
            }
            Light::Distant(_) | Light::Infinite(_) => None,
        }
    }

    /// The sample with which [`Self::sample_li`] chooses the point `p` of this light: the
    /// triangle's sample for an area light on a triangle, `Some(None)` for a point or spot
    /// light (whose one point any value gives), `None` otherwise.
    pub fn sample_li_inverse(&self, geometry: &Geometry, p: Vec3) -> Option<Option<Vec2>> {
        match self {
            Light::Area(l) => geometry.sample_area_inverse(l.prim, p).map(Some),
            Light::Point(_) | Light::Spot(_) => Some(None),
            Light::Distant(_) | Light::Infinite(_) => None,
        }
    }

    /// Samples an emitted ray: `u_pos` chooses the origin, `u_dir` the direction.
    pub fn sample_le(
        &self,
        geometry: &Geometry,
        sphere: SceneSphere,
        u_pos: Vec2,
        u_dir: Vec2,
    ) -> Option<EmissionSample> {
        let s = match self {
            Light::Area(l) => {
                let sample = geometry.sample_area(l.prim, u_pos)?;
                let p = sample.point;
                let (mut u, flip) = (u_dir, l.two_sided && u_dir.x < 0.5);
                if l.two_sided {
                    u.x = if flip { 2.0 * u.x } else { 2.0 * u.x - 1.0 }.clamp(0.0, 1.0 - f32::EPSILON);
                }
                let local = cosine_hemisphere(u);
                let n = if flip { -p.ng } else { p.ng };
                let dir = Frame::from_z(n).to_world(local);
                let side = if l.two_sided { 0.5 } else { 1.0 };
                EmissionSample {
                    ray: Ray::new(offset_origin(p.p, p.ng, dir), dir),
                    n: p.ng,
                    le: l.l(&p, dir),
                    pdf_pos: sample.pdf,
                    pdf_dir: side * cosine_hemisphere_pdf(local.z),
                }
            }
            Light::Point(l) => {
                let dir = uniform_sphere(u_dir);
                EmissionSample {
                    ray: Ray::new(l.position, dir),
                    n: Vec3::ZERO,
                    le: l.intensity,
                    pdf_pos: 1.0,
                    pdf_dir: UNIFORM_SPHERE_PDF,
                }
            }
            Light::Spot(l) => {
                let dir = l.frame.to_world(uniform_cone(u_dir, l.cos_falloff_end));
                EmissionSample {
                    ray: Ray::new(l.position, dir),
                    n: Vec3::ZERO,
                    le: l.i(dir),
                    pdf_pos: 1.0,
                    pdf_dir: uniform_cone_pdf(l.cos_falloff_end),
                }
            }
            Light::Distant(l) => {
                let dir = -l.to_light;
                EmissionSample {
                    ray: Ray::new(disk_origin(sphere, dir, u_pos), dir),
                    n: dir,
                    le: l.radiance,
                    pdf_pos: 1.0 / (PI * sphere.radius * sphere.radius),
                    pdf_dir: 1.0,
                }
            }
            Light::Infinite(l) => {
                let ls = l.sample_li(sphere.center, u_dir)?;
                let dir = -ls.wi;
                EmissionSample {
                    ray: Ray::new(disk_origin(sphere, dir, u_pos), dir),
                    n: dir,
                    le: ls.li,
                    pdf_pos: 1.0 / (PI * sphere.radius * sphere.radius),
                    pdf_dir: ls.pdf,
                }
            }
        };
        (s.pdf_pos > 0.0 && s.pdf_dir > 0.0 && s.le.max_element() > 0.0 && s.le.is_finite()).then_some(s)
    }

    /// Densities `(pdf_pos, pdf_dir)` of [`Self::sample_le`] emitting along `dir` from a point
    /// with normal `n` (for area lights) — the reverse densities bidirectional MIS needs.
    pub fn pdf_le(&self, geometry: &Geometry, sphere: SceneSphere, dir: Vec3, n: Vec3) -> (f32, f32) {
        match self {
            Light::Area(l) => {
                let cos = n.dot(dir);
                if !l.two_sided && cos <= 0.0 {
                    return (1.0 / geometry.area(l.prim), 0.0);
                }
                let side = if l.two_sided { 0.5 } else { 1.0 };
                (1.0 / geometry.area(l.prim), side * cosine_hemisphere_pdf(cos.abs()))
            }
            Light::Point(_) => (0.0, UNIFORM_SPHERE_PDF),
            Light::Spot(l) => {
                let inside = dir.dot(l.frame.n) >= l.cos_falloff_end;
                (0.0, if inside { uniform_cone_pdf(l.cos_falloff_end) } else { 0.0 })
            }
            Light::Distant(_) => (1.0 / (PI * sphere.radius * sphere.radius), 0.0),
            Light::Infinite(l) => (1.0 / (PI * sphere.radius * sphere.radius), InfiniteLight::pdf_dir(l, -dir)),
        }
    }

    /// True when the light's positions are a delta (point and spot lights).
    pub fn is_delta_position(&self) -> bool {
        matches!(self, Light::Point(_) | Light::Spot(_))
    }

    /// True when the light's directions are a delta (distant lights).
    pub fn is_delta_direction(&self) -> bool {
        matches!(self, Light::Distant(_))
    }
}
