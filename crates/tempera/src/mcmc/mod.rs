//! Markov-chain machinery shared by the MCMC integrators: evaluating a primary-sample-space
//! state as one bidirectional strategy of a given path depth (the MMLT target of Hachisuka,
//! Kaplanyan & Dachsbacher 2014), and the chain statistics.

pub mod chain;
pub mod full;
pub mod stats;
pub mod tempered;

pub use chain::{Chain, State, Target};
pub use full::{FullContribution, evaluate_full};
pub use stats::{DepthStats, Moments, SwapStats};
pub use tempered::{TemperedState, TemperedTarget};

use crate::bidir::{Connection, Heuristic, Subpaths, Vertex, camera_subpath_vertices, connect, light_subpath_vertices};
use crate::film::SharedSplats;
use crate::math::{Rgb, Vec2, luminance};
use crate::sampler::{PssSampler, Sampler, Stream};
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
}

impl Contribution {
    pub const ZERO: Contribution = Contribution { l: Rgb::ZERO, raster: Vec2::ZERO, f: 0.0, technique: 0 };
}

impl State for Contribution {
    fn value(&self) -> f32 {
        self.f
    }

    fn technique(&self) -> usize {
        self.technique
    }

    fn splat(&self, splats: &SharedSplats, scale: f32) {
        splats.add(self.raster, self.l * scale);
    }
}

/// Scratch space for subpaths.
#[derive(Default)]
pub struct Paths {
    camera: Vec<Vertex>,
    light: Vec<Vertex>,
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
pub fn evaluate_connection(
    scene: &Scene,
    k: usize,
    sampler: &mut PssSampler,
    paths: &mut Paths,
    rays: &mut u64,
) -> Evaluated {
    sampler.start_stream(Stream::Camera);
    let u = sampler.next_1d();
    let n = if k == 0 { 1 } else { k + 2 };
    let s = if k == 0 { 0 } else { ((u * n as f32) as usize).min(k + 1) };
    let t = k + 2 - s;
    let film = sampler.next_2d();
    let lens = sampler.next_2d();
    let (w, h) = (scene.film.width as f32, scene.film.height as f32);
    let raster = Vec2::new((film.x * w).min(w - 1e-3), (film.y * h).min(h - 1e-3));
    let none = Evaluated { s, t, n, raster, connection: None };
    paths.camera.clear();
    if t > 1 {
        let ray = scene.camera.generate_ray(raster, lens);
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
    let subpaths = Subpaths { light: &paths.light, camera: &paths.camera };
    let connection = connect(scene, subpaths, (s, t), sampler, Heuristic::Power, rays);
    Evaluated { connection, ..none }
}

impl Evaluated {
    /// The contribution of the strategy with unweighted value `l` and MIS weight `weight`:
    /// `n·w·l` at the state's film position (or where light tracing reached the film), and
    /// whether it was invalid (NaN, infinite or negative; then it counts as zero).
    pub fn contribution(&self, l: Rgb, weight: f32) -> (Contribution, bool) {
        let zero = Contribution { technique: self.s, ..Contribution::ZERO };
        let l = l * (weight * self.n as f32);
        let f = luminance(l);
        if !l.is_finite() || !f.is_finite() || l.min_element() < 0.0 {
            return (zero, true);
        }
        let raster = match (self.t, self.connection.and_then(|c| c.raster)) {
            (1, Some(r)) => r,
            _ => self.raster,
        };
        (Contribution { l, raster, f: f.max(0.0), technique: self.s }, false)
    }
}

/// Evaluates the state of `sampler` as a path of depth `k` ([`evaluate_connection`]). Returns
/// the contribution and whether its value was invalid (NaN, infinite or negative).
pub fn evaluate(
    scene: &Scene,
    k: usize,
    sampler: &mut PssSampler,
    paths: &mut Paths,
    rays: &mut u64,
) -> (Contribution, bool) {
    let e = evaluate_connection(scene, k, sampler, paths, rays);
    match e.connection {
        Some(c) => e.contribution(c.l, c.weight),
        None => (Contribution { technique: e.s, ..Contribution::ZERO }, false),
    }
}
