//! Delta lights: isotropic point lights, spotlights with pbrt-v4's smoothstep falloff, and
//! distant (directional) lights (pbrt-v4 §12.1, §12.4).

use super::LightSample;
use crate::math::frame::Frame;
use crate::math::{Rgb, Vec3, luminance};
use std::f32::consts::PI;

/// Illumination at `reference` from a point emitter at `position` whose intensity towards
/// world direction `w` (leaving the light) is `intensity(w)`: a delta sample, `I/d²`.
fn sample_point(position: Vec3, reference: Vec3, intensity: impl Fn(Vec3) -> Rgb) -> Option<LightSample> {
    let delta = position - reference;
    let d2 = delta.length_squared();
    if d2 == 0.0 {
        return None;
    }
    let dist = d2.sqrt();
    let wi = delta / dist;
    Some(LightSample { li: intensity(-wi) / d2, wi, p: position, n: Vec3::ZERO, dist, pdf: 1.0, delta: true })
}

#[derive(Clone, Debug)]
pub struct PointLight {
    pub position: Vec3,
    /// Radiant intensity (already scaled).
    pub intensity: Rgb,
}

impl PointLight {
    pub fn sample_li(&self, reference: Vec3) -> Option<LightSample> {
        sample_point(self.position, reference, |_| self.intensity)
    }

    pub fn power(&self) -> f32 {
        4.0 * PI * luminance(self.intensity)
    }
}

#[derive(Clone, Debug)]
pub struct SpotLight {
    pub position: Vec3,
    /// Frame whose `n` is the spot axis.
    pub frame: Frame,
    pub intensity: Rgb,
    pub cos_falloff_start: f32,
    pub cos_falloff_end: f32,
}

fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    if a == b {
        return if x < a { 0.0 } else { 1.0 };
    }
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl SpotLight {
    /// A spotlight at `position` pointing at `target`; `cone_angle` is the half-angle of the
    /// full cone, `cone_delta` the width of the falloff band (degrees, as in pbrt).
    pub fn new(position: Vec3, target: Vec3, intensity: Rgb, cone_angle: f32, cone_delta: f32) -> Self {
        let axis = (target - position).normalize();
        Self {
            position,
            frame: Frame::from_z(axis),
            intensity,
            cos_falloff_start: (cone_angle - cone_delta).to_radians().cos(),
            cos_falloff_end: cone_angle.to_radians().cos(),
        }
    }

    /// Intensity in world direction `w` leaving the light.
    pub fn i(&self, w: Vec3) -> Rgb {
        self.intensity * smoothstep(self.cos_falloff_end, self.cos_falloff_start, w.dot(self.frame.n))
    }

    pub fn sample_li(&self, reference: Vec3) -> Option<LightSample> {
        sample_point(self.position, reference, |w| self.i(w))
    }

    pub fn power(&self) -> f32 {
        luminance(self.intensity) * 2.0 * PI * (1.0 - 0.5 * (self.cos_falloff_start + self.cos_falloff_end))
    }
}

#[derive(Clone, Debug)]
pub struct DistantLight {
    /// Unit direction from the scene towards the light.
    pub to_light: Vec3,
    /// Radiance-like scale: the irradiance on a surface facing the light.
    pub radiance: Rgb,
}

impl DistantLight {
    pub fn sample_li(&self, reference: Vec3) -> LightSample {
        LightSample {
            li: self.radiance,
            wi: self.to_light,
            p: reference + self.to_light * 1e7,
            n: Vec3::ZERO,
            dist: f32::INFINITY,
            pdf: 1.0,
            delta: true,
        }
    }

    pub fn power(&self, scene_radius: f32) -> f32 {
        PI * scene_radius * scene_radius * luminance(self.radiance)
    }
}
