//! A primary-sample-space state evaluated as one bidirectional strategy of a given path depth:
//! the MMLT target of Hachisuka, Kaplanyan & Dachsbacher 2014 (pbrt-v4 §13.4.2). The first
//! camera-stream number chooses the technique `s = min(⌊u·(k+2)⌋, k+1)`, the state's value is
//! `(k+2)·w_{s,t}·f/p` and the chain's target its luminance.

use super::State;
use super::chain::EvalContext;
use crate::bidir::{Connection, Heuristic, Paths, camera_subpath_vertices, connect, light_subpath_vertices};
use crate::film::SharedSplats;
use crate::math::{Rgb, Vec2, luminance};
use crate::sampler::{Sampler, Stream};
use crate::scene::Scene;

/// A state's contribution: the radiance it adds and where on the film.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Contribution {
    /// `(k+2)·w·f/p`: the MIS-weighted strategy value times the number of strategies.
    pub l: Rgb,
    pub raster: Vec2,
    /// The chain's target: luminance of `l`, or 0 for invalid values.
    pub f: f32,
    /// The technique `s` (light-subpath vertices) the state chose.
    pub technique: usize,
    /// The value was NaN, infinite or negative (it then counts as zero).
    pub invalid: bool,
}

impl Contribution {
    pub const ZERO: Contribution =
        Contribution { l: Rgb::ZERO, raster: Vec2::ZERO, f: 0.0, technique: 0, invalid: false };
}

impl State for Contribution {
    fn value(&self) -> f32 {
        self.f
    }

    fn invalid(&self) -> bool {
        self.invalid
    }

    fn technique(&self) -> usize {
        self.technique
    }

    fn splat(&self, splats: &SharedSplats, scale: f32) {
        splats.add(self.raster, self.l * scale);
    }

    fn clamp_value(&mut self, c: f32) {
        self.f = self.f.min(c);
    }
}

/// Whether a radiance value may reach the film: finite and not negative.
pub fn valid_radiance(l: Rgb) -> bool {
    l.is_finite() && l.min_element() >= 0.0
}

/// A state evaluated as one strategy: what re-evaluating it under another target needs.
#[derive(Clone, Copy, Debug)]
pub struct Evaluated {
    pub s: usize,
    pub t: usize,
    /// Strategies of the depth (the technique's selection probability is `1/n`).
    pub n: usize,
    /// The film position the camera stream chose.
    pub raster: Vec2,
    /// The strategy's evaluation, `None` when the subpaths could not be built or connected.
    pub connection: Option<Connection>,
}

/// Evaluates the state of `sampler` as a path of depth `k`: the first camera-stream number
/// chooses the technique `s = min(⌊u·(k+2)⌋, k+1)` (depth 0 has the single technique (0, 2),
/// as in pbrt-v4), the next two the film position. The subpaths are left in `paths`.
pub fn evaluate_connection(scene: &Scene, k: usize, cx: &mut EvalContext, paths: &mut Paths) -> Evaluated {
    let (sampler, rays) = (&mut cx.sampler, &mut cx.rays);
    sampler.start_stream(Stream::Camera);
    let u = sampler.next_1d();
    let n = if k == 0 { 1 } else { k + 2 };
    let s = if k == 0 { 0 } else { ((u * n as f32) as usize).min(k + 1) };
    let t = k + 2 - s;
    let film = sampler.next_2d();
    let (w, h) = (scene.film.width as f32, scene.film.height as f32);
    let raster = Vec2::new((film.x * w).min(w - 1e-3), (film.y * h).min(h - 1e-3));
    let none = Evaluated { s, t, n, raster, connection: None };
    paths.camera.clear();
    if t > 1 {
        // The lens sample only where a camera ray is generated.
        let ray = scene.camera.generate_ray(raster, scene.camera.lens_sample(sampler));
        *rays += 1;
        camera_subpath_vertices(scene, ray, sampler, t, &mut paths.camera, rays);
        if paths.camera.len() != t {
            return none;
        }
    }
    paths.light.clear();
    if s > 1 {
        light_subpath_vertices(scene, sampler, s, &mut paths.light, rays);
        if paths.light.len() != s {
            return none;
        }
    }
    let connection = connect(scene, paths.subpaths(), (s, t), sampler, Heuristic::Power, rays);
    Evaluated { connection, ..none }
}

impl Evaluated {
    /// The contribution of the strategy with unweighted value `l` and MIS weight `weight`:
    /// `n·w·l` at the state's film position (or where light tracing reached the film); an
    /// invalid value (NaN, infinite or negative) gives a zero contribution marked invalid.
    pub fn contribution(&self, l: Rgb, weight: f32) -> Contribution {
        let zero = Contribution { technique: self.s, ..Contribution::ZERO };
        let l = l * (weight * self.n as f32);
        let f = luminance(l);
        if !valid_radiance(l) || !f.is_finite() {
            return Contribution { invalid: true, ..zero };
        }
        let raster = match (self.t, self.connection.as_ref().and_then(|c| c.raster)) {
            (1, Some(r)) => r,
            _ => self.raster,
        };
        Contribution { l, raster, f: f.max(0.0), technique: self.s, invalid: false }
    }

    /// The contribution of the evaluated strategy (zero when it could not be connected).
    pub fn untempered(&self) -> Contribution {
        match &self.connection {
            Some(c) => self.contribution(c.l, c.weight),
            None => Contribution { technique: self.s, ..Contribution::ZERO },
        }
    }
}

/// Evaluates the state of `cx.sampler` as a path of depth `k` ([`evaluate_connection`], the
/// subpaths left in `cx.paths`).
pub fn evaluate(scene: &Scene, k: usize, cx: &mut EvalContext) -> Contribution {
    let mut paths = std::mem::take(&mut cx.paths);
    let e = evaluate_connection(scene, k, cx, &mut paths);
    cx.paths = paths;
    e.untempered()
}
