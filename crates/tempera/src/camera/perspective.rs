//! The perspective camera with optional thin lens (pbrt-v4 §5.2, importance §16.1.1). pbrt's
//! conventions: camera space looks down +z, raster x grows to camera +x and raster y downwards,
//! and `fov` spans the shorter image axis.

use super::CameraSample;
use crate::geometry::Ray;
use crate::math::warp::concentric_disk;
use crate::math::{Mat4, Rgb, Vec2, Vec3};
use std::f32::consts::PI;

/// The image axis the field of view spans.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FovAxis {
    /// pbrt's convention.
    #[default]
    Shorter,
    X,
    Y,
    Larger,
    Diagonal,
}

/// Resolution-independent camera parameters, as a scene file gives them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraDesc {
    pub camera_to_world: Mat4,
    /// Full field of view in degrees along `fov_axis`.
    pub fov_degrees: f32,
    pub fov_axis: FovAxis,
    pub lens_radius: f32,
    pub focal_distance: f32,
    /// Explicit screen window `[x_min, x_max, y_min, y_max]` on the `z = 1` plane before the
    /// fov scaling; `None` derives it from the aspect ratio.
    pub screen_window: Option<[f32; 4]>,
}

impl CameraDesc {
    /// pbrt's `LookAt`: camera +x is `up × dir`, +y the corrected up, +z the view direction.
    pub fn look_at(eye: Vec3, target: Vec3, up: Vec3, fov_degrees: f32) -> Self {
        let dir = (target - eye).normalize();
        let right = up.normalize().cross(dir).normalize();
        let new_up = dir.cross(right);
        let camera_to_world = Mat4::from_cols(right.extend(0.0), new_up.extend(0.0), dir.extend(0.0), eye.extend(1.0));
        Self {
            camera_to_world,
            fov_degrees,
            fov_axis: FovAxis::Shorter,
            lens_radius: 0.0,
            focal_distance: 1.0,
            screen_window: None,
        }
    }

    pub fn build(&self, width: u32, height: u32) -> PerspectiveCamera {
        PerspectiveCamera::new(self, width, height)
    }
}

#[derive(Clone, Debug)]
pub struct PerspectiveCamera {
    pub resolution: (u32, u32),
    camera_to_world: Mat4,
    world_to_camera: Mat4,
    /// Screen window on the `z = 1` plane: `[x_min, x_max, y_min, y_max]`.
    window: [f32; 4],
    lens_radius: f32,
    focal_distance: f32,
    /// Area of the screen window on the `z = 1` plane.
    image_area: f32,
}

impl PerspectiveCamera {
    pub fn new(desc: &CameraDesc, width: u32, height: u32) -> Self {
        let aspect = width as f32 / height as f32;
        let base = desc.screen_window.unwrap_or(if aspect >= 1.0 {
            [-aspect, aspect, -1.0, 1.0]
        } else {
            [-1.0, 1.0, -1.0 / aspect, 1.0 / aspect]
        });
        // The base window has half-extent 1 along the shorter axis; the fov spans `fov_axis`.
        let (hx, hy) = (0.5 * (base[1] - base[0]), 0.5 * (base[3] - base[2]));
        let extent = match (desc.fov_axis, desc.screen_window) {
            (_, Some(_)) | (FovAxis::Shorter, None) => 1.0,
            (FovAxis::X, None) => hx,
            (FovAxis::Y, None) => hy,
            (FovAxis::Larger, None) => hx.max(hy),
            (FovAxis::Diagonal, None) => hx.hypot(hy),
        };
        let tan = (desc.fov_degrees.to_radians() * 0.5).tan() / extent;
        let window = base.map(|v| v * tan);
        let image_area = (window[1] - window[0]) * (window[3] - window[2]);
        Self {
            resolution: (width, height),
            camera_to_world: desc.camera_to_world,
            world_to_camera: desc.camera_to_world.inverse(),
            window,
            lens_radius: desc.lens_radius.max(0.0),
            focal_distance: desc.focal_distance.max(1e-6),
            image_area,
        }
    }

    /// Whether rays depend on their lens sample (a thin lens of positive radius).
    pub fn has_lens(&self) -> bool {
        self.lens_radius > 0.0
    }

    fn lens_area(&self) -> f32 {
        if self.lens_radius > 0.0 { PI * self.lens_radius * self.lens_radius } else { 1.0 }
    }

    /// Camera-space point on the `z = 1` plane for a raster position.
    fn raster_to_plane(&self, raster: Vec2) -> Vec3 {
        let (w, h) = (self.resolution.0 as f32, self.resolution.1 as f32);
        let [x0, x1, y0, y1] = self.window;
        Vec3::new(x0 + raster.x / w * (x1 - x0), y1 - raster.y / h * (y1 - y0), 1.0)
    }

    /// Raster position of a camera-space direction through the `z = 1` plane, if on the film.
    fn plane_to_raster(&self, p: Vec3) -> Option<Vec2> {
        let (w, h) = (self.resolution.0 as f32, self.resolution.1 as f32);
        let [x0, x1, y0, y1] = self.window;
        let r = Vec2::new((p.x / p.z - x0) / (x1 - x0) * w, (y1 - p.y / p.z) / (y1 - y0) * h);
        (r.x >= 0.0 && r.x < w && r.y >= 0.0 && r.y < h).then_some(r)
    }

    pub fn generate_ray(&self, raster: Vec2, u: Vec2) -> Ray {
        let dir = self.raster_to_plane(raster).normalize();
        let (o, d) = if self.lens_radius > 0.0 {
            let lens = concentric_disk(u) * self.lens_radius;
            let p_lens = Vec3::new(lens.x, lens.y, 0.0);
            let p_focus = dir * (self.focal_distance / dir.z);
            (p_lens, (p_focus - p_lens).normalize())
        } else {
            (Vec3::ZERO, dir)
        };
        Ray::new(self.camera_to_world.transform_point3(o), self.camera_to_world.transform_vector3(d).normalize())
    }

    fn forward(&self) -> Vec3 {
        self.camera_to_world.transform_vector3(Vec3::Z).normalize()
    }

    /// Importance and raster position of a world-space ray leaving the lens.
    pub fn we(&self, ray: &Ray) -> Option<(Rgb, Vec2)> {
        let o = self.world_to_camera.transform_point3(ray.o);
        let d = self.world_to_camera.transform_vector3(ray.d).normalize();
        let cos = d.z;
        if cos <= 0.0 {
            return None;
        }
        let t = if self.lens_radius > 0.0 { self.focal_distance } else { 1.0 } / cos;
        let raster = self.plane_to_raster(o + d * t)?;
        let cos2 = cos * cos;
        Some((Rgb::splat(1.0 / (self.image_area * self.lens_area() * cos2 * cos2)), raster))
    }

    pub fn pdf_we(&self, ray: &Ray) -> (f32, f32) {
        let o = self.world_to_camera.transform_point3(ray.o);
        let d = self.world_to_camera.transform_vector3(ray.d).normalize();
        let cos = d.z;
        if cos <= 0.0 {
            return (0.0, 0.0);
        }
        let t = if self.lens_radius > 0.0 { self.focal_distance } else { 1.0 } / cos;
        if self.plane_to_raster(o + d * t).is_none() {
            return (0.0, 0.0);
        }
        (1.0 / self.lens_area(), 1.0 / (self.image_area * cos * cos * cos))
    }

    pub fn sample_wi(&self, reference: Vec3, u: Vec2) -> Option<CameraSample> {
        let lens = concentric_disk(u) * self.lens_radius;
        let p_lens = self.camera_to_world.transform_point3(Vec3::new(lens.x, lens.y, 0.0));
        let delta = p_lens - reference;
        let dist = delta.length();
        if dist == 0.0 {
            return None;
        }
        let wi = delta / dist;
        let (importance, raster) = self.we(&Ray::new(p_lens, -wi))?;
        let cos = self.forward().dot(wi).abs();
        let pdf = dist * dist / (cos * self.lens_area());
        Some(CameraSample { wi, dist, p_lens, importance, pdf, raster })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::Pcg32;

    fn cameras() -> Vec<PerspectiveCamera> {
        let mut desc = CameraDesc::look_at(Vec3::new(1.0, 2.0, -5.0), Vec3::new(0.0, 0.5, 0.0), Vec3::Y, 40.0);
        let pinhole = desc.build(64, 48);
        desc.lens_radius = 0.1;
        desc.focal_distance = 4.0;
        let lens = desc.build(40, 70);
        vec![pinhole, lens]
    }

    #[test]
    fn fov_spans_the_shorter_axis() {
        let desc = CameraDesc::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 90.0);
        for (w, h) in [(200, 100), (100, 200)] {
            let cam = desc.build(w, h);
            let short_axis_edge = if w > h {
                cam.generate_ray(Vec2::new(w as f32 / 2.0, 0.0), Vec2::ZERO)
            } else {
                cam.generate_ray(Vec2::new(0.0, h as f32 / 2.0), Vec2::ZERO)
            };
            let angle = short_axis_edge.d.dot(Vec3::Z).acos().to_degrees();
            assert!((angle - 45.0).abs() < 1e-3, "half fov on the short axis: {angle}");
        }
    }

    #[test]
    fn fov_axis_selects_the_spanned_axis() {
        let mut desc = CameraDesc::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 90.0);
        let edge_angle = |cam: &PerspectiveCamera, raster: Vec2| {
            cam.generate_ray(raster, Vec2::ZERO).d.dot(Vec3::Z).acos().to_degrees()
        };
        for (axis, raster) in [(FovAxis::X, Vec2::new(0.0, 50.0)), (FovAxis::Y, Vec2::new(100.0, 0.0))] {
            desc.fov_axis = axis;
            for (w, h) in [(200, 100), (100, 200)] {
                let cam = desc.build(w, h);
                let r =
                    if axis == FovAxis::X { Vec2::new(0.0, h as f32 / 2.0) } else { Vec2::new(w as f32 / 2.0, 0.0) };
                let _ = raster;
                assert!((edge_angle(&cam, r) - 45.0).abs() < 1e-3, "{axis:?} {w}x{h}");
            }
        }
        desc.fov_axis = FovAxis::Diagonal;
        let cam = desc.build(300, 400);
        assert!((edge_angle(&cam, Vec2::ZERO) - 45.0).abs() < 1e-3);
    }

    #[test]
    fn raster_round_trips_through_the_scene() {
        let mut rng = Pcg32::new(4, 4);
        for cam in cameras() {
            let (w, h) = cam.resolution;
            for _ in 0..2000 {
                let raster = Vec2::new(rng.next_f32() * w as f32, rng.next_f32() * h as f32);
                let u = Vec2::new(rng.next_f32(), rng.next_f32());
                let ray = cam.generate_ray(raster, u);
                let p = ray.at(0.5 + 10.0 * rng.next_f32());
                let s = cam.sample_wi(p, u).expect("visible point maps back");
                assert!((s.raster - raster).length() < 2e-2, "{raster} -> {}", s.raster);
                assert!((s.p_lens - ray.o).length() < 1e-4);
                let (we, r2) = cam.we(&ray).unwrap();
                assert!((we - s.importance).abs().max_element() < 1e-3 * we.x);
                assert!((r2 - raster).length() < 2e-2);
            }
        }
    }

    #[test]
    fn importance_is_normalised() {
        // A pinhole's We satisfies ∫ We(ω) cos θ dω = 1 over the film's solid angle.
        let cam = &cameras()[0];
        let mut rng = Pcg32::new(6, 6);
        let n = 2_000_000;
        let mut sum = 0.0f64;
        let o = cam.camera_to_world.transform_point3(Vec3::ZERO);
        let fwd = cam.forward();
        for _ in 0..n {
            let d = crate::math::warp::uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32()));
            if let Some((we, _)) = cam.we(&Ray::new(o, d)) {
                sum += f64::from(we.x * d.dot(fwd)) * 4.0 * std::f64::consts::PI;
            }
        }
        let integral = sum / f64::from(n);
        assert!((integral - 1.0).abs() < 0.02, "{integral}");
    }
}
