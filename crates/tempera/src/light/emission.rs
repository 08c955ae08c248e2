//! Sampling light leaving emitters, for light subpaths (pbrt-v4 §12, `SampleLe`/`PDF_Le`):
//! a position (area density, or a delta) and a direction (solid-angle density, or a delta).
//! Directional and environment lights emit from a disk of the scene's bounding radius.

use super::{Light, infinite::InfiniteLight};
use crate::geometry::ray::offset_origin;
use crate::geometry::{Geometry, Ray};
use crate::math::frame::Frame;
use crate::math::warp::{
    UNIFORM_SPHERE_PDF, concentric_disk, cosine_hemisphere, cosine_hemisphere_pdf, uniform_cone, uniform_cone_pdf,
    uniform_sphere,
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
