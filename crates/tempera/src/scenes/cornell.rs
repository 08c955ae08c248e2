//! A diffuse Cornell box and the white furnace: the analytic scenes integrators are tested on.

use super::quad;
use crate::camera::CameraDesc;
use crate::film::FilmDesc;
use crate::geometry::{Shape, Sphere};
use crate::light::{InfiniteLight, Light};
use crate::material::Material;
use crate::math::{Rgb, Vec3};
use crate::scene::{AreaEmission, RenderDefaults, SceneBuilder};

/// Adds the five walls of the room `[-1, 1] × [0, 2] × [-1, 1]` (open towards +z). Camera +x
/// maps to world −x, so the red wall at x = +1 appears on the left.
pub(super) fn add_room(b: &mut SceneBuilder) {
    let white = b.add_material(Material::diffuse(Rgb::splat(0.73)));
    let red = b.add_material(Material::diffuse(Rgb::new(0.63, 0.065, 0.05)));
    let green = b.add_material(Material::diffuse(Rgb::new(0.14, 0.45, 0.091)));
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let walls = [
        (quad(v(-1., 0., -1.), v(-1., 0., 1.), v(1., 0., 1.), v(1., 0., -1.)), white),
        (quad(v(-1., 2., -1.), v(1., 2., -1.), v(1., 2., 1.), v(-1., 2., 1.)), white),
        (quad(v(-1., 0., -1.), v(1., 0., -1.), v(1., 2., -1.), v(-1., 2., -1.)), white),
        (quad(v(1., 0., -1.), v(1., 0., 1.), v(1., 2., 1.), v(1., 2., -1.)), red),
        (quad(v(-1., 0., -1.), v(-1., 2., -1.), v(-1., 2., 1.), v(-1., 0., 1.)), green),
    ];
    for (shape, m) in walls {
        b.add_shape(shape, m, None);
    }
}

/// Adds a downward-facing square ceiling light of half-size `half`, centred at depth `z`.
pub(super) fn add_ceiling_light(b: &mut SceneBuilder, half: f32, z: f32, radiance: Rgb) {
    let black = b.add_material(Material::diffuse(Rgb::ZERO));
    let y = 1.999;
    let light = quad(
        Vec3::new(-half, y, z - half),
        Vec3::new(half, y, z - half),
        Vec3::new(half, y, z + half),
        Vec3::new(-half, y, z + half),
    );
    b.add_shape(light, black, Some(AreaEmission { radiance: radiance.into(), scale: 1.0, two_sided: false }));
}

pub(super) fn room_camera(fov: f32) -> CameraDesc {
    CameraDesc::look_at(Vec3::new(0.0, 1.0, 3.9), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, fov)
}

/// The classic diffuse Cornell box with two diffuse boxes replaced by a diffuse sphere.
pub fn cornell_box(width: u32, height: u32) -> SceneBuilder {
    let mut b = SceneBuilder::new();
    add_room(&mut b);
    add_ceiling_light(&mut b, 0.25, 0.0, Rgb::new(17.0, 12.0, 4.0));
    let white = b.add_material(Material::diffuse(Rgb::splat(0.73)));
    b.add_shape(
        Shape::Sphere(Sphere { center: Vec3::new(0.3, 0.4, -0.2), radius: 0.4, reverse_orientation: false }),
        white,
        None,
    );
    b.set_camera(room_camera(38.0));
    b.set_film(FilmDesc { width, height, ..FilmDesc::default() });
    b.set_defaults(RenderDefaults { spp: 64, max_depth: 5, ..RenderDefaults::default() });
    b
}

/// A diffuse sphere of albedo `albedo` under a uniform sky of radiance 1: with the sphere
/// convex, every pixel on it must be exactly `albedo` and every sky pixel 1.
pub fn furnace(albedo: f32, width: u32, height: u32) -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let m = b.add_material(Material::diffuse(Rgb::splat(albedo)));
    b.add_shape(Shape::Sphere(Sphere { center: Vec3::ZERO, radius: 1.0, reverse_orientation: false }), m, None);
    b.add_light(Light::Infinite(InfiniteLight::uniform(Rgb::ONE)));
    b.set_camera(CameraDesc::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, 40.0));
    b.set_film(FilmDesc { width, height, ..FilmDesc::default() });
    b.set_defaults(RenderDefaults { spp: 16, max_depth: 8, ..RenderDefaults::default() });
    b
}
