//! Scene-level tests: alpha cut-outs, `mix` material selection and bump mapping.

use super::*;
use crate::camera::CameraDesc;
use crate::material::{Material, MixMaterial};
use crate::math::rng::Pcg32;
use crate::math::{Mat4, Quat, Vec2};
use crate::scenes::quad;
use crate::texture::{Image, ImageTexture};
use std::sync::Arc;

fn unit_quad() -> crate::geometry::Shape {
    // uv (0,0)..(1,1) over [0,2]×[0,1] in the z = 0 plane, facing +z.
    let p =
        vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(2.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
    let uv = vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)];
    let mesh = crate::geometry::TriangleMesh::new(p, vec![[0, 1, 2], [0, 2, 3]], None, Some(uv)).unwrap();
    crate::geometry::Shape::Mesh(mesh)
}

fn builder() -> SceneBuilder {
    let mut b = SceneBuilder::new();
    b.set_camera(CameraDesc::look_at(Vec3::new(1.0, 0.5, 3.0), Vec3::new(1.0, 0.5, 0.0), Vec3::Y, 40.0));
    b
}

fn down_ray(rng: &mut Pcg32) -> Ray {
    let o = Vec3::new(0.1 + 1.8 * rng.next_f32(), 0.1 + 0.8 * rng.next_f32(), 1.0);
    Ray::new(o, -Vec3::Z)
}

#[test]
fn alpha_cuts_out_and_is_consistent_per_ray() {
    for (alpha, want) in [(0.0f32, 0.0f64), (1.0, 1.0), (0.3, 0.3)] {
        let mut b = builder();
        let m = b.add_material(Material::diffuse(Rgb::ONE));
        b.add_shape_with_alpha(unit_quad(), m, None, Some(alpha.into()));
        let scene = b.build().unwrap();
        let mut rng = Pcg32::new(4, 4);
        let n = 20_000;
        let mut hits = 0;
        for _ in 0..n {
            let ray = down_ray(&mut rng);
            let hit = scene.intersect(&ray).is_some();
            assert_eq!(hit, scene.intersect(&ray).is_some(), "the same ray must see the same surface");
            assert_eq!(hit, scene.occluded(&ray, 10.0), "shadow rays agree with camera rays");
            hits += usize::from(hit);
        }
        let frac = hits as f64 / f64::from(n);
        assert!((frac - want).abs() < 0.015, "alpha {alpha}: {frac} of rays hit");
    }
}

#[test]
fn mix_chooses_the_second_material_with_probability_amount() {
    let mix = MixMaterial { materials: [3, 7], amount: 0.25.into() };
    let mut rng = Pcg32::new(1, 2);
    let n = 40_000;
    let mut second = 0;
    for _ in 0..n {
        let p = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        let wo = Vec3::new(rng.next_f32(), rng.next_f32(), 1.0).normalize();
        let m = mix.choose(Vec2::ZERO, p, wo);
        assert_eq!(m, mix.choose(Vec2::ZERO, p, wo), "deterministic for a point and direction");
        second += usize::from(m == 7);
    }
    assert!((second as f64 / f64::from(n) - 0.25).abs() < 0.01);
    assert_eq!(MixMaterial { materials: [3, 7], amount: 0.0.into() }.choose(Vec2::ZERO, Vec3::ONE, Vec3::Z), 3);
    assert_eq!(MixMaterial { materials: [3, 7], amount: 1.0.into() }.choose(Vec2::ZERO, Vec3::ONE, Vec3::Z), 7);

    let mut b = builder();
    let a = b.add_material(Material::diffuse(Rgb::ONE));
    let c = b.add_material(Material::diffuse(Rgb::ZERO));
    let mixed = b.add_material(Material::Mix(MixMaterial { materials: [a.0, c.0], amount: 1.0.into() }));
    b.add_shape(quad(Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y), mixed, None);
    let scene = b.build().unwrap();
    let it = scene.intersect(&Ray::new(Vec3::new(0.5, 0.5, 1.0), -Vec3::Z)).unwrap();
    let f = scene.bsdf(&it).eval(Vec3::Z, Vec3::Z, crate::bsdf::TransportMode::Radiance);
    assert_eq!(f, Rgb::ZERO, "amount 1 resolves to the second (black) material");
}

#[test]
fn bump_mapping_tilts_the_shading_normal_by_the_displacement_slope() {
    // Displacement rising linearly in u with slope k: d = 0.05 + k·u inside the texel centres.
    let k = 0.1f32;
    let img = Image::new(2, 1, vec![Rgb::splat(0.05 + 0.25 * k), Rgb::splat(0.05 + 0.75 * k)]);
    let mut tex = ImageTexture::new(Arc::new(img));
    tex.wrap = crate::texture::WrapMode::Clamp;
    let mut b = builder();
    let m = b.add_material(Material::diffuse(Rgb::ONE));
    b.set_displacement(m, Texture::Image(tex));
    b.add_shape(unit_quad(), m, None);
    let scene = b.build().unwrap();
    let it = scene.intersect(&Ray::new(Vec3::new(1.0, 0.5, 1.0), -Vec3::Z)).unwrap();
    let n = scene.bsdf(&it).frame.n;
    // ∂p/∂u = (2, 0, 0) + k·z, ∂p/∂v = (0, 1, 0): n' ∝ (-k, 0, 2).
    let want = Vec3::new(-k, 0.0, 2.0).normalize();
    assert!((n - want).length() < 1e-3, "{n} vs {want}");
}

#[test]
fn instances_intersect_like_flattened_copies() {
    use crate::geometry::{Shape, Sphere};
    let transforms = [
        Mat4::from_translation(Vec3::new(3.0, 0.0, 0.0)),
        Mat4::from_rotation_translation(
            Quat::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.8),
            Vec3::new(0.0, 2.0, -1.0),
        ),
        Mat4::from_scale_rotation_translation(
            Vec3::new(1.0, 0.5, 2.0),
            Quat::from_axis_angle(Vec3::Z, 0.3),
            Vec3::new(-2.0, -1.0, 0.5),
        ),
        Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)) * Mat4::from_translation(Vec3::new(1.0, -2.0, 0.0)),
    ];
    let parts = |b: &mut SceneBuilder| {
        let red = b.add_material(Material::diffuse(Rgb::new(1.0, 0.0, 0.0)));
        let blue = b.add_material(Material::diffuse(Rgb::new(0.0, 0.0, 1.0)));
        (
            vec![
                (
                    Shape::Sphere(Sphere { center: Vec3::new(0.0, 0.0, 0.5), radius: 0.5, reverse_orientation: false }),
                    red,
                ),
                (unit_quad(), blue),
            ],
            red,
            blue,
        )
    };
    let mut inst = builder();
    let (shapes, ..) = parts(&mut inst);
    let proto = inst.add_prototype(shapes.into_iter().map(|(s, m)| (s, m, None)).collect());
    for m in transforms {
        inst.add_instance(proto, m);
    }
    let mut flat = builder();
    let (shapes, ..) = parts(&mut flat);
    for m in transforms {
        for (shape, material) in &shapes {
            let mut mesh = match shape {
                Shape::Mesh(mesh) => mesh.clone(),
                Shape::Sphere(s) => {
                    // Compare against the analytic sphere only under similarity transforms.
                    if m.determinant() < 0.0 || (m.x_axis.length() - m.y_axis.length()).abs() > 1e-5 {
                        continue;
                    }
                    let c = m.transform_point3(s.center);
                    flat.add_shape(
                        Shape::Sphere(Sphere { center: c, radius: s.radius * m.x_axis.length(), ..*s }),
                        *material,
                        None,
                    );
                    continue;
                }
                Shape::Disk(_) => unreachable!(),
            };
            mesh.transform(&m);
            flat.add_shape(Shape::Mesh(mesh), *material, None);
        }
    }
    let (inst, flat) = (inst.build().unwrap(), flat.build().unwrap());
    assert_eq!(inst.geometry.prototypes.len(), 1, "geometry is stored once");
    let mut rng = Pcg32::new(8, 8);
    let mut compared = 0;
    for _ in 0..20_000 {
        let o = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 12.0 - Vec3::splat(6.0);
        let target = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 6.0 - Vec3::splat(3.0);
        let ray = Ray::new(o, (target - o).normalize());
        let (a, b) = (inst.intersect(&ray), flat.intersect(&ray));
        let Some(b) = b else { continue };
        // Spheres under non-similarity transforms are only in the instanced scene.
        let Some(a) = a else { panic!("instanced scene missed a hit at t = {}", b.t) };
        if (a.t - b.t).abs() > 1e-4 * b.t.max(1.0) {
            assert!(a.t < b.t, "instanced hit farther than flattened: {} vs {}", a.t, b.t);
            continue;
        }
        compared += 1;
        assert!((a.surface.p - b.surface.p).length() < 1e-3);
        assert!((a.surface.ng - b.surface.ng).length() < 1e-3, "{} vs {}", a.surface.ng, b.surface.ng);
        assert_eq!(a.material, b.material);
        assert!(inst.occluded(&ray, b.t * 1.001));
    }
    assert!(compared > 1000, "only {compared} hits compared");
}

#[test]
fn one_sided_materials_are_black_from_behind() {
    let mut b = builder();
    let m = b.add_material(Material::diffuse(Rgb::ONE));
    b.set_one_sided(m);
    b.add_shape(unit_quad(), m, None);
    let scene = b.build().unwrap();
    let eval = |o: Vec3, d: Vec3| {
        let it = scene.intersect(&Ray::new(o, d)).unwrap();
        scene.bsdf(&it).eval(it.wo, it.wo, crate::bsdf::TransportMode::Radiance)
    };
    assert!(eval(Vec3::new(1.0, 0.5, 1.0), -Vec3::Z).x > 0.0, "front side reflects");
    assert_eq!(eval(Vec3::new(1.0, 0.5, -1.0), Vec3::Z), Rgb::ZERO, "back side is black");
}

/// Area lights are listed in the scene's order (shape, then triangle), whatever order the
/// accelerator put the primitive table in: 300 emitting triangles scattered over two shapes,
/// which the BVH reorders by position.
#[test]
fn area_lights_follow_the_scene_order_not_the_trees() {
    let mut b = builder();
    let m = b.add_material(Material::diffuse(Rgb::ONE));
    let mut rng = Pcg32::new(9, 1);
    for _ in 0..2 {
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for t in 0..150u32 {
            let c = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 10.0;
            positions.extend([c, c + Vec3::X * 0.1, c + Vec3::Y * 0.1]);
            indices.push([3 * t, 3 * t + 1, 3 * t + 2]);
        }
        let mesh = crate::geometry::TriangleMesh::new(positions, indices, None, None).unwrap();
        let emission = AreaEmission { radiance: Rgb::ONE.into(), scale: 1.0, two_sided: false };
        b.add_shape(crate::geometry::Shape::Mesh(mesh), m, Some(emission));
    }
    let scene = b.build().unwrap();
    let order: Vec<(u32, u32)> = scene
        .lights
        .iter()
        .map(|l| match l {
            Light::Area(a) => {
                let r = scene.geometry.prims[a.prim as usize];
                (r.shape, r.index)
            }
            _ => panic!("only area lights here"),
        })
        .collect();
    assert_eq!(order.len(), 300);
    let reordered = (0..scene.geometry.prims.len()).any(|p| {
        let r = scene.geometry.prims[p];
        (r.shape as usize * 150 + r.index as usize) != p
    });
    assert!(reordered, "the tree left the primitive table in scene order; the test shows nothing");
    assert!(order.windows(2).all(|w| w[0] < w[1]), "area lights out of scene order");
    for (l, a) in scene.lights.iter().enumerate() {
        let Light::Area(a) = a else { unreachable!() };
        assert_eq!(scene.prim_light[a.prim as usize], l as u32);
    }
}
