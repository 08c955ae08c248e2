//! Diffuse area lights on any primitive: uniform or textured radiance, one- or two-sided
//! (pbrt-v4 §12.2). Sampling defers to the shape (cone sampling for spheres, area sampling
//! otherwise), densities are per solid angle at the reference point.

use super::LightSample;
use crate::geometry::{Geometry, SurfacePoint};
use crate::math::{Rgb, Vec2, Vec3, luminance};
use crate::texture::Texture;
use std::f32::consts::PI;

#[derive(Clone, Debug)]
pub struct AreaLight {
    /// Index of the emitting primitive in the geometry's (accelerator-ordered) table.
    pub prim: u32,
    pub radiance: Texture,
    pub scale: f32,
    pub two_sided: bool,
}

impl AreaLight {
    /// Radiance leaving surface point `sp` in direction `w`.
    #[inline]
    pub fn l(&self, sp: &SurfacePoint, w: Vec3) -> Rgb {
        if !self.two_sided && sp.ng.dot(w) < 0.0 {
            return Rgb::ZERO;
        }
        self.radiance.eval(sp.uv) * self.scale
    }

    pub fn sample_li(&self, geometry: &Geometry, reference: Vec3, u: Vec2) -> Option<LightSample> {
        let s = geometry.sample_from(self.prim, reference, u)?;
        let delta = s.point.p - reference;
        let dist = delta.length();
        if dist == 0.0 {
            return None;
        }
        let wi = delta / dist;
        Some(LightSample { li: self.l(&s.point, -wi), wi, p: s.point.p, n: s.point.ng, dist, pdf: s.pdf, delta: false })
    }

    pub fn pdf_li(&self, geometry: &Geometry, reference: Vec3, hit: &SurfacePoint) -> f32 {
        geometry.pdf_from(self.prim, reference, hit)
    }

    pub fn power(&self, geometry: &Geometry) -> f32 {
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        luminance(self.radiance.average()) * self.scale * geometry.area(self.prim) * PI * sides
    }
}
