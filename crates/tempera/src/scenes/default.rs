//! The embedded default scene: a Cornell-style room lit by a small ceiling light, with a rough
//! glass sphere (GGX alpha 0.03) focusing a caustic onto the floor, a glossy aluminium mirror
//! panel (alpha 0.02) and a glossy gold sphere (alpha 0.05) in which that caustic is seen again.
//! The reflected caustic is a specular–diffuse–specular path family: the kind plain MMLT
//! explores poorly and tempering targets.

use super::cornell::{add_ceiling_light, add_room, room_camera};
use super::oriented_quad;
use crate::film::FilmDesc;
use crate::geometry::{Shape, Sphere};
use crate::material::{ConductorFresnel, ConductorMaterial, DielectricMaterial, Material, Roughness};
use crate::math::{Rgb, Vec3};
use crate::scene::{RenderDefaults, SceneBuilder};

/// Complex IOR of gold and aluminium at the sRGB primaries' dominant wavelengths
/// (approximately 650, 550 and 450 nm; values from refractiveindex.info tabulations).
const GOLD: (Rgb, Rgb) = (Rgb::new(0.143, 0.374, 1.442), Rgb::new(3.983, 2.385, 1.603));
const ALUMINIUM: (Rgb, Rgb) = (Rgb::new(1.657, 0.880, 0.521), Rgb::new(9.224, 6.270, 4.837));

fn conductor((eta, k): (Rgb, Rgb), alpha: f32) -> Material {
    Material::Conductor(ConductorMaterial {
        fresnel: ConductorFresnel::Ior { eta: eta.into(), k: k.into() },
        roughness: Roughness::alpha(alpha),
        tint: 1.0.into(),
    })
}

pub fn default_scene() -> SceneBuilder {
    let mut b = SceneBuilder::new();
    add_room(&mut b);
    add_ceiling_light(&mut b, 0.15, -0.3, Rgb::new(17.0, 12.0, 4.0) * 2.5);

    let glass =
        b.add_material(Material::Dielectric(DielectricMaterial { eta: 1.5, roughness: Roughness::alpha(0.03) }));
    let glass_sphere = Sphere { center: Vec3::new(0.35, 0.38, 0.25), radius: 0.38, reverse_orientation: false };
    b.add_shape(Shape::Sphere(glass_sphere), glass, None);

    let gold = b.add_material(conductor(GOLD, 0.05));
    let gold_sphere = Sphere { center: Vec3::new(-0.45, 0.32, -0.35), radius: 0.32, reverse_orientation: false };
    b.add_shape(Shape::Sphere(gold_sphere), gold, None);

    let mirror = b.add_material(conductor(ALUMINIUM, 0.02));
    let normal = Vec3::new(0.28, -0.21, 0.94).normalize();
    let panel = oriented_quad(Vec3::new(-0.45, 0.9, -0.9), normal, Vec3::X, 0.4, 0.35);
    b.add_shape(panel, mirror, None);

    b.set_camera(room_camera(38.0));
    b.set_film(FilmDesc { width: 512, height: 512, ..FilmDesc::default() });
    b.set_defaults(RenderDefaults { spp: 64, max_depth: 8, ..RenderDefaults::default() });
    b
}
