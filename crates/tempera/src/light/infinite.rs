//! Infinite (environment) lights: constant radiance, latitude–longitude maps, and pbrt-v4's
//! octahedral equal-area square maps (Clarberg 2008), importance-sampled with a piecewise-constant
//! distribution over pixels (pbrt-v4 §12.5). Lookups are nearest-pixel so that the sampling
//! density is exactly proportional to the radiance it samples. In the light's local frame +z is
//! up; lat-long rows run from +z (top row) to −z and columns from φ = 0 around +z.

use super::LightSample;
use crate::math::distribution::Distribution2D;
use crate::math::warp::{
    UNIFORM_SPHERE_PDF, equal_area_sphere_to_square, equal_area_square_to_sphere, spherical_phi, uniform_sphere,
};
use crate::math::{Mat3, Rgb, Vec2, Vec3, luminance};
use crate::texture::Image;
use std::f32::consts::PI;
use std::sync::Arc;

/// Parametrisation of an environment image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnvironmentMap {
    LatLong,
    EqualArea,
}

#[derive(Clone, Debug)]
struct ImageEnvironment {
    image: Arc<Image>,
    map: EnvironmentMap,
    distribution: Distribution2D,
}

#[derive(Clone, Debug)]
pub struct InfiniteLight {
    /// Rotation from the light's frame to world space.
    to_world: Mat3,
    to_local: Mat3,
    scale: Rgb,
    image: Option<ImageEnvironment>,
}

impl InfiniteLight {
    /// Constant radiance from every direction.
    pub fn uniform(radiance: Rgb) -> Self {
        Self { to_world: Mat3::IDENTITY, to_local: Mat3::IDENTITY, scale: radiance, image: None }
    }

    /// An image map in the given parametrisation; `to_world` is a rotation, `scale` multiplies it.
    pub fn image(image: Arc<Image>, map: EnvironmentMap, to_world: Mat3, scale: Rgb) -> Self {
        let (w, h) = (image.width, image.height);
        let values: Vec<f32> = (0..h)
            .flat_map(|y| {
                let sin_theta = match map {
                    EnvironmentMap::LatLong => ((y as f32 + 0.5) / h as f32 * PI).sin(),
                    EnvironmentMap::EqualArea => 1.0,
                };
                let image = &image;
                (0..w).map(move |x| luminance(image.get(x, y)).max(0.0) * sin_theta)
            })
            .collect();
        let distribution = Distribution2D::new(&values, w, h);
        let to_local = to_world.inverse();
        Self { to_world, to_local, scale, image: Some(ImageEnvironment { image, map, distribution }) }
    }

    fn dir_to_uv(map: EnvironmentMap, d: Vec3) -> Vec2 {
        match map {
            EnvironmentMap::LatLong => Vec2::new(spherical_phi(d) / (2.0 * PI), d.z.clamp(-1.0, 1.0).acos() / PI),
            EnvironmentMap::EqualArea => equal_area_sphere_to_square(d),
        }
    }

    fn uv_to_dir(map: EnvironmentMap, uv: Vec2) -> (Vec3, f32) {
        match map {
            EnvironmentMap::LatLong => {
                let (theta, phi) = (uv.y * PI, uv.x * 2.0 * PI);
                let d = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
                let sin_theta = theta.sin();
                let jacobian = if sin_theta > 0.0 { 1.0 / (2.0 * PI * PI * sin_theta) } else { 0.0 };
                (d, jacobian)
            }
            EnvironmentMap::EqualArea => (equal_area_square_to_sphere(uv), 1.0 / (4.0 * PI)),
        }
    }

    fn lookup(env: &ImageEnvironment, uv: Vec2) -> Rgb {
        let (w, h) = (env.image.width, env.image.height);
        let x = ((uv.x * w as f32) as usize).min(w - 1);
        let y = ((uv.y * h as f32) as usize).min(h - 1);
        env.image.get(x, y)
    }

    /// Radiance received by a ray escaping in world direction `dir`.
    pub fn le(&self, dir: Vec3) -> Rgb {
        match &self.image {
            None => self.scale,
            Some(env) => {
                let d = (self.to_local * dir).normalize();
                Self::lookup(env, Self::dir_to_uv(env.map, d)) * self.scale
            }
        }
    }

    pub fn sample_li(&self, reference: Vec3, u: Vec2) -> Option<LightSample> {
        let (wi, pdf) = match &self.image {
            None => (uniform_sphere(u), UNIFORM_SPHERE_PDF),
            Some(env) => {
                let (uv, pdf_uv) = env.distribution.sample(u);
                let (d, jacobian) = Self::uv_to_dir(env.map, uv);
                ((self.to_world * d).normalize(), pdf_uv * jacobian)
            }
        };
        Some(LightSample {
            li: self.le(wi),
            wi,
            p: reference + wi * 1e7,
            n: Vec3::ZERO,
            dist: f32::INFINITY,
            pdf,
            delta: false,
        })
    }

    /// Solid-angle density of [`Self::sample_li`].
    pub fn pdf_dir(&self, dir: Vec3) -> f32 {
        match &self.image {
            None => UNIFORM_SPHERE_PDF,
            Some(env) => {
                let d = (self.to_local * dir).normalize();
                let uv = Self::dir_to_uv(env.map, d);
                let jacobian = match env.map {
                    EnvironmentMap::LatLong => {
                        let sin_theta = (1.0 - d.z * d.z).max(0.0).sqrt();
                        if sin_theta > 0.0 { 1.0 / (2.0 * PI * PI * sin_theta) } else { 0.0 }
                    }
                    EnvironmentMap::EqualArea => 1.0 / (4.0 * PI),
                };
                env.distribution.pdf(uv) * jacobian
            }
        }
    }

    /// Power through a disk of the scene's bounding radius: π r² · average radiance · π.
    pub fn power(&self, scene_radius: f32) -> f32 {
        let avg = match &self.image {
            None => luminance(self.scale),
            Some(env) => {
                let (w, h) = (env.image.width, env.image.height);
                let (mut sum, mut weight) = (0.0f64, 0.0f64);
                for y in 0..h {
                    let s = match env.map {
                        EnvironmentMap::LatLong => ((y as f32 + 0.5) / h as f32 * PI).sin(),
                        EnvironmentMap::EqualArea => 1.0,
                    };
                    for x in 0..w {
                        sum += f64::from(luminance(env.image.get(x, y) * self.scale) * s);
                        weight += f64::from(s);
                    }
                }
                (sum / weight.max(1e-30)) as f32
            }
        };
        PI * PI * scene_radius * scene_radius * avg
    }
}
