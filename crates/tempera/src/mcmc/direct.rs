//! The normalisation of path depth 0 — emitters seen directly — from points sampled on the
//! emitters and connected to the camera (the light-tracing strategy `(1, 1)`, which MMLT's
//! depth-0 chains do not use; Veach 1997 §10.2). MMLT's depth-0 target is the luminance of the
//! emission a camera ray through a uniform film position sees, so its mean `b_0` is the film's
//! mean luminance of directly visible emission. A point `y` on an area light (chosen by the
//! light sampler, `pmf`, then by area, `p_A`) seen from the lens estimates the same quantity:
//! `L_e(y → lens) W_e |cos θ_y| / (p_ω · p_A · pmf)` with `p_ω` the lens sample's solid-angle
//! density at `y`, zero when occluded or off the film — exactly how light tracing splats onto
//! the film. Camera rays find a small light rarely; points on the light almost always see the
//! lens. Environment lights are seen directly too but are not points on a surface: scenes
//! with any keep the bootstrap's estimate. Through participating media each estimate carries
//! the transmittance between the emitter and the lens, the expectation of the depth-0 camera
//! paths' free-flight weights.

use super::{Moments, target_value};
use crate::geometry::spawn_ray_to;
use crate::light::Light;
use crate::math::rng::{Pcg32, hash};
use crate::math::{Vec2, luminance};
use crate::scene::Scene;
use rayon::prelude::*;

/// `samples` emitter-to-camera estimates of `b_0` (seeded by `seed`) and the rays traced, or
/// `None` when the scene has an environment light (or no light).
pub fn direct_emission(scene: &Scene, seed: u64, samples: usize) -> Option<(Moments, u64)> {
    if !scene.infinite_lights.is_empty() || scene.lights.is_empty() {
        return None;
    }
    let values: Vec<(f32, u64)> = (0..samples)
        .into_par_iter()
        .map(|i| {
            let mut rng = Pcg32::new(hash(&[seed, 0xd1ec7, i as u64]), 3);
            sample(scene, &mut rng).unwrap_or((0.0, 0))
        })
        .collect();
    let mut moments = Moments::default();
    for &(v, _) in &values {
        moments.push(f64::from(target_value(v)));
    }
    Some((moments, values.iter().map(|v| v.1).sum()))
}

/// One estimate and the rays it traced (`None`: zero without a ray).
fn sample(scene: &Scene, rng: &mut Pcg32) -> Option<(f32, u64)> {
    let u_light = rng.next_f32();
    let u_pos = Vec2::new(rng.next_f32(), rng.next_f32());
    let u_lens = Vec2::new(rng.next_f32(), rng.next_f32());
    let (index, pmf) = scene.light_sampler.sample(u_light)?;
    let Light::Area(light) = &scene.lights[index] else { return None };
    let s = scene.geometry.sample_area(light.prim, u_pos)?;
    let cs = scene.camera.sample_wi(s.point.p, u_lens)?;
    if !(cs.pdf > 0.0 && s.pdf > 0.0 && pmf > 0.0) || cs.importance.max_element() <= 0.0 {
        return None;
    }
    let le = light.l(&s.point, cs.wi);
    if le.max_element() <= 0.0 {
        return None;
    }
    let cos = s.point.ng.dot(cs.wi).abs();
    if scene.has_media() {
        // Through media: what the emitted light keeps on its way to the lens.
        let mut rays = 0;
        let medium = scene.light_medium(index, s.point.ng, cs.wi);
        let tr = scene.transmittance(s.point.p, s.point.ng, cs.p_lens, false, medium, &mut rays);
        return Some((luminance(le * tr * cs.importance * (cos / (cs.pdf * s.pdf * pmf))), rays));
    }
    let (ray, t_max) = spawn_ray_to(s.point.p, s.point.ng, cs.p_lens);
    if scene.occluded(&ray, t_max) {
        return Some((0.0, 1));
    }
    Some((luminance(le * cs.importance * (cos / (cs.pdf * s.pdf * pmf))), 1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::{assert_same_mean, mmlt_target_moments};

    /// The emitter-to-camera estimate of `b_0` has the camera rays' expectation (their
    /// difference within four combined standard errors) and a far smaller relative error at the
    /// same number of samples, on a small ceiling light (the default scene) and a larger one
    /// (the Cornell box).
    #[test]
    fn emitter_samples_estimate_the_depth_zero_normalisation_with_less_error() {
        for (name, scene) in [
            ("default", crate::scenes::default_scene().build().unwrap()),
            ("cornell", crate::scenes::cornell_box(16, 16).build().unwrap()),
        ] {
            let mut scene = scene;
            scene.set_resolution(16, 16);
            let n = 1_000_000;
            let rays = mmlt_target_moments(&scene, 0, 5, n);
            let (emitters, _) = direct_emission(&scene, 5, n).expect("no environment light");
            let (ea, eb) = assert_same_mean(name, &rays, &emitters);
            assert!(eb < 0.2 * ea && ea > 0.0, "{name}: relative errors {eb} (emitters) vs {ea} (camera rays)");
        }
    }
}
