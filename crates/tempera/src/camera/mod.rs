//! Cameras. A closed enum of camera models; today the perspective camera with optional thin
//! lens. Each model generates rays, evaluates its importance `We` and samples a direction towards
//! its lens from a scene point (what light tracing and MMLT need to splat onto the film).

pub mod perspective;

pub use perspective::{CameraDesc, FovAxis, PerspectiveCamera};

use crate::geometry::Ray;
use crate::math::{Rgb, Vec2, Vec3};
use crate::sampler::Sampler;

/// A sampled connection from a scene point to the camera lens.
#[derive(Clone, Copy, Debug)]
pub struct CameraSample {
    /// Unit direction from the scene point towards the lens point.
    pub wi: Vec3,
    pub dist: f32,
    pub p_lens: Vec3,
    /// Importance `We` carried along the connection.
    pub importance: Rgb,
    /// Solid-angle density at the scene point.
    pub pdf: f32,
    /// Raster position the connection lands on.
    pub raster: Vec2,
}

#[derive(Clone, Debug)]
pub enum Camera {
    Perspective(PerspectiveCamera),
}

impl Camera {
    pub fn resolution(&self) -> (u32, u32) {
        match self {
            Camera::Perspective(c) => c.resolution,
        }
    }

    /// A primary ray through raster position `raster` (pixels, y down) with lens sample `u`.
    #[inline]
    pub fn generate_ray(&self, raster: Vec2, u: Vec2) -> Ray {
        match self {
            Camera::Perspective(c) => c.generate_ray(raster, u),
        }
    }

    /// Whether the camera's rays depend on their lens sample (a thin lens; a pinhole's do
    /// not).
    #[inline]
    pub fn has_lens(&self) -> bool {
        match self {
            Camera::Perspective(c) => c.has_lens(),
        }
    }

    /// A lens sample for [`Self::generate_ray`] or [`Self::sample_wi`]: two numbers from
    /// `sampler` for a camera with a lens, none for a pinhole, whose rays do not depend on it
    /// (a primary-sample-space sampler's numbers cost a perturbation each).
    #[inline]
    pub fn lens_sample(&self, sampler: &mut impl Sampler) -> Vec2 {
        if self.has_lens() { sampler.next_2d() } else { Vec2::new(0.5, 0.5) }
    }

    /// Importance of a ray leaving the lens, and the raster position it passes through.
    pub fn we(&self, ray: &Ray) -> Option<(Rgb, Vec2)> {
        match self {
            Camera::Perspective(c) => c.we(ray),
        }
    }

    /// Positional (area) and directional (solid-angle) densities of [`Self::generate_ray`] for
    /// a uniformly chosen raster position.
    pub fn pdf_we(&self, ray: &Ray) -> (f32, f32) {
        match self {
            Camera::Perspective(c) => c.pdf_we(ray),
        }
    }

    /// Samples a lens point as seen from `reference`.
    pub fn sample_wi(&self, reference: Vec3, u: Vec2) -> Option<CameraSample> {
        match self {
            Camera::Perspective(c) => c.sample_wi(reference, u),
        }
    }
}
