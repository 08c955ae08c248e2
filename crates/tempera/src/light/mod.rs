//! Light sources (pbrt-v4 ch. 12): a closed enum over area, point, spot, distant and infinite
//! lights, the sample record they return, and selection of a light in proportion to its power.

pub mod area;
pub mod emission;
pub mod infinite;
pub mod point;
pub mod sampler;

#[cfg(test)]
mod tests;

pub use area::AreaLight;
pub use emission::{EmissionSample, SceneSphere};
pub use infinite::{EnvironmentMap, InfiniteLight};
pub use point::{DistantLight, PointLight, SpotLight};
pub use sampler::LightSampler;

use crate::geometry::{Geometry, SurfacePoint};
use crate::math::{Rgb, Vec2, Vec3};

/// Incident illumination sampled at a reference point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Radiance (or, for delta lights, the incident intensity term) arriving along `-wi`.
    pub li: Rgb,
    /// Unit direction from the reference point towards the light.
    pub wi: Vec3,
    /// The sampled point on the light (for shadow rays); far away for directional lights.
    pub p: Vec3,
    /// Surface normal at `p` for area lights, zero otherwise.
    pub n: Vec3,
    /// Distance to `p`; infinite for directional and environment lights.
    pub dist: f32,
    /// Solid-angle density, or 1 for delta lights.
    pub pdf: f32,
    pub delta: bool,
}

#[derive(Clone, Debug)]
pub enum Light {
    Area(AreaLight),
    Point(PointLight),
    Spot(SpotLight),
    Distant(DistantLight),
    Infinite(InfiniteLight),
}

impl Light {
    /// Samples incident light at `reference`.
    pub fn sample_li(&self, geometry: &Geometry, reference: Vec3, u: Vec2) -> Option<LightSample> {
        let s = match self {
            Light::Area(l) => l.sample_li(geometry, reference, u),
            Light::Point(l) => l.sample_li(reference),
            Light::Spot(l) => l.sample_li(reference),
            Light::Distant(l) => Some(l.sample_li(reference)),
            Light::Infinite(l) => l.sample_li(reference, u),
        }?;
        (s.pdf > 0.0 && s.li.max_element() > 0.0 && s.li.is_finite()).then_some(s)
    }

    /// Solid-angle density of [`Self::sample_li`] for the point `hit` on an area light.
    pub fn pdf_li_area(&self, geometry: &Geometry, reference: Vec3, hit: &SurfacePoint) -> f32 {
        match self {
            Light::Area(l) => l.pdf_li(geometry, reference, hit),
            Light::Point(_) | Light::Spot(_) | Light::Distant(_) | Light::Infinite(_) => 0.0,
        }
    }

    /// Solid-angle density of [`Self::sample_li`] for direction `dir` of an infinite light.
    pub fn pdf_li_dir(&self, dir: Vec3) -> f32 {
        match self {
            Light::Infinite(l) => l.pdf_dir(dir),
            Light::Area(_) | Light::Point(_) | Light::Spot(_) | Light::Distant(_) => 0.0,
        }
    }

    /// Radiance an escaping ray with direction `dir` receives from this light.
    pub fn le(&self, dir: Vec3) -> Rgb {
        match self {
            Light::Infinite(l) => l.le(dir),
            Light::Area(_) | Light::Point(_) | Light::Spot(_) | Light::Distant(_) => Rgb::ZERO,
        }
    }

    /// Emitted power (luminance), used to choose lights.
    pub fn power(&self, geometry: &Geometry, scene_radius: f32) -> f32 {
        match self {
            Light::Area(l) => l.power(geometry),
            Light::Point(l) => l.power(),
            Light::Spot(l) => l.power(),
            Light::Distant(l) => l.power(scene_radius),
            Light::Infinite(l) => l.power(scene_radius),
        }
    }

    pub fn is_delta(&self) -> bool {
        matches!(self, Light::Point(_) | Light::Spot(_) | Light::Distant(_))
    }

    pub fn is_infinite(&self) -> bool {
        matches!(self, Light::Infinite(_))
    }
}
