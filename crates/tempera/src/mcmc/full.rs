//! The primary-sample-space MLT target of Kelemen et al. 2002 over bidirectional path tracing
//! (the "path sample list" of Mitsuba's PSSMLT): one state is a camera and a light subpath of
//! full length, evaluated with every strategy `(s, t)` and its MIS weight, exactly as one BDPT
//! sample. Its contributions land at the state's film position or, for light tracing
//! (`t = 1`), wherever the connection reaches the film. The target is the sum of the
//! contributions' luminances, so every contribution is splatted as `C_i / f`.

use super::{EvalContext, State, valid_radiance};
use crate::bidir::{Heuristic, camera_subpath, connect, light_subpath};
use crate::film::SharedSplats;
use crate::math::{Rgb, Vec2, luminance};
use crate::sampler::{Sampler, Stream};
use crate::scene::Scene;

/// Every contribution of one state and the target value.
#[derive(Clone, Debug, Default)]
pub struct FullContribution {
    pub splats: Vec<(Vec2, Rgb)>,
    pub f: f32,
    /// A contribution was NaN, infinite or negative (it was dropped).
    pub invalid: bool,
}

impl State for FullContribution {
    fn value(&self) -> f32 {
        self.f
    }

    fn invalid(&self) -> bool {
        self.invalid
    }

    fn technique(&self) -> usize {
        0
    }

    fn splat(&self, splats: &SharedSplats, scale: f32) {
        for &(raster, l) in &self.splats {
            splats.add(raster, l * scale);
        }
    }
}

/// Evaluates the state of `cx.sampler` as one BDPT sample with paths of at most `max_depth`
/// scattering events (invalid contributions are dropped and the result marked invalid);
/// `recycled`'s storage is reused.
pub fn evaluate_full(
    scene: &Scene,
    max_depth: u32,
    cx: &mut EvalContext,
    recycled: FullContribution,
) -> FullContribution {
    let mut out = recycled;
    out.splats.clear();
    out.f = 0.0;
    out.invalid = false;
    let EvalContext { sampler, paths, rays, .. } = cx;
    sampler.start_stream(Stream::Camera);
    let film = sampler.next_2d();
    let lens = scene.camera.lens_sample(sampler);
    let raster = super::strategy::raster_position(scene, film);
    let ray = scene.camera.generate_ray(raster, lens);
    *rays += 1;
    camera_subpath(scene, ray, sampler, max_depth, &mut paths.camera, rays);
    light_subpath(scene, sampler, max_depth, &mut paths.light, rays);
    let mut at_pixel = Rgb::ZERO;
    for t in 1..=paths.camera.len() {
        for s in 0..=paths.light.len() {
            let depth = (s + t) as i64 - 2;
            if (s == 1 && t == 1) || depth < 0 || depth > i64::from(max_depth) {
                continue;
            }
            let Some(c) = connect(scene, paths.subpaths(), (s, t), sampler, Heuristic::Power, rays) else {
                continue;
            };
            let v = c.l * c.weight;
            if !valid_radiance(v) {
                out.invalid = true;
                continue;
            }
            match (t, c.raster) {
                (1, Some(r)) => {
                    if v.max_element() > 0.0 {
                        out.splats.push((r, v));
                    }
                }
                _ => at_pixel += v,
            }
        }
    }
    if at_pixel.max_element() > 0.0 {
        out.splats.push((raster, at_pixel));
    }
    out.f = out.splats.iter().map(|&(_, l)| luminance(l)).sum::<f32>().max(0.0);
    if !out.f.is_finite() {
        out.splats.clear();
        out.f = 0.0;
        out.invalid = true;
    }
    out
}
