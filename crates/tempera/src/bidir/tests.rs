//! Tests of the bidirectional machinery: MIS weights form a partition of unity over the
//! strategies that can produce a fixed path.

use super::*;
use crate::math::Vec2;
use crate::sampler::IndependentSampler;
use crate::scene::Scene;

/// Finds a camera subpath whose vertex `t - 1` lies on an emitter (a path of `t` vertices).
fn path_to_light(scene: &Scene, t: usize, seed: u64) -> Vec<Vertex> {
    let mut rays = 0;
    let mut camera = Vec::new();
    for i in 0..100_000u64 {
        let mut sampler = IndependentSampler::new(seed, i);
        let raster = Vec2::new(16.0 + 8.0 * (i % 7) as f32 / 7.0, 16.0);
        let ray = scene.camera.generate_ray(raster, Vec2::splat(0.5));
        camera_subpath(scene, ray, &mut sampler, t as u32 + 2, &mut camera, &mut rays);
        if camera.len() >= t && camera[t - 1].is_light() && camera[..t].iter().all(|v| !v.delta) {
            camera.truncate(t);
            return camera;
        }
    }
    panic!("no camera path reached a light in {t} vertices");
}

/// The MIS weights of every strategy for the path `x_0 … x_{n-1}` (camera first, light last),
/// each computed from subpaths laid out as that strategy would have produced them.
fn all_weights(scene: &Scene, x: &[Vertex], heuristic: Heuristic) -> Vec<f32> {
    let n = x.len();
    let light_index = x[n - 1].light.expect("the last vertex is on an emitter");
    let light_vertex = |p: &Vertex| {
        let mut v = Vertex::light(light_index, p.p, p.ng, p.beta, 0.0, false);
        v.surface = p.surface;
        v
    };
    // Densities of each vertex as generated from the camera side and from the light side.
    let from_camera = |i: usize| -> f32 {
        match i {
            0 => 0.0,
            1 => x[0].pdf(scene, None, &x[1]),
            _ => x[i - 1].pdf(scene, Some(&x[i - 2]), &x[i]),
        }
    };
    let lv = light_vertex(&x[n - 1]);
    let from_light = |i: usize| -> f32 {
        if i == n - 1 {
            lv.pdf_light_origin(scene, &x[n - 2])
        } else if i == n - 2 {
            lv.pdf_light(scene, &x[n - 2])
        } else {
            let prev = if i + 2 == n - 1 { lv } else { x[i + 2] };
            x[i + 1].pdf(scene, Some(&prev), &x[i])
        }
    };
    let mut weights = Vec::new();
    for s in 0..n {
        let t = n - s;
        if t == 0 || (s == 1 && t == 1) {
            continue;
        }
        let camera: Vec<Vertex> =
            (0..t).map(|i| Vertex { pdf_fwd: from_camera(i), pdf_rev: from_light(i), ..x[i] }).collect();
        let light: Vec<Vertex> = (0..s)
            .map(|j| {
                let i = n - 1 - j;
                let base = if i == n - 1 { lv } else { x[i] };
                Vertex { pdf_fwd: from_light(i), pdf_rev: from_camera(i), ..base }
            })
            .collect();
        let sampled = match (s, t) {
            (1, _) => Some(light[0]),
            (_, 1) => Some(Vertex::camera(x[0].p, crate::math::Rgb::ONE)),
            _ => None,
        };
        weights.push(mis_weight(scene, &light, &camera, sampled.as_ref(), s, t, heuristic));
    }
    weights
}

#[test]
fn mis_weights_over_all_strategies_sum_to_one() {
    let scene = crate::scenes::cornell_box(32, 32).build().unwrap();
    for heuristic in [Heuristic::Power, Heuristic::Balance] {
        for (t, seed) in [(3, 1), (4, 2), (5, 3), (6, 4)] {
            let x = path_to_light(&scene, t, seed);
            let w = all_weights(&scene, &x, heuristic);
            let sum: f32 = w.iter().sum();
            assert!((sum - 1.0).abs() < 1e-3, "{heuristic:?}, path of {t} vertices: weights {w:?} sum to {sum}");
            assert!(w.iter().all(|&v| (0.0..=1.0).contains(&v)));
        }
    }
}

#[test]
fn connections_expose_what_re_evaluation_needs() {
    let scene = crate::scenes::cornell_box(32, 32).build().unwrap();
    let (mut camera, mut light, mut rays) = (Vec::new(), Vec::new(), 0);
    let mut checked = 0;
    for i in 0..2000u64 {
        let mut sampler = IndependentSampler::new(9, i);
        let ray = scene.camera.generate_ray(Vec2::new(16.3, 12.7), Vec2::splat(0.5));
        camera_subpath(&scene, ray, &mut sampler, 5, &mut camera, &mut rays);
        light_subpath(&scene, &mut sampler, 5, &mut light, &mut rays);
        for t in 2..=camera.len() {
            for s in 2..=light.len() {
                let paths = Subpaths { light: &light, camera: &camera };
                let Some(c) = connect(&scene, paths, (s, t), &mut sampler, Heuristic::Power, &mut rays) else {
                    continue;
                };
                let w = mis_weight_with(&scene, &light, &camera, None, (s, t), &c.rev, Heuristic::Power);
                assert_eq!(w, c.weight, "the exposed reverse densities reproduce the weight");
                let l = light[s - 1].beta * c.f_light * c.f_camera * camera[t - 1].beta * c.g;
                assert!((l - c.l).abs().max_element() <= 1e-6 * c.l.max_element(), "{l} vs {}", c.l);
                checked += 1;
            }
        }
    }
    assert!(checked > 100, "only {checked} connections checked");
}
