//! A primary-sample-space state evaluated as one bidirectional strategy of a given path depth:
//! the MMLT target of Hachisuka, Kaplanyan & Dachsbacher 2014 (pbrt-v4 §13.4.2). The first
//! camera-stream number chooses the technique `s = min(⌊u·(k+2)⌋, k+1)`, the state's value is
//! `(k+2)·w_{s,t}·f/p` and the chain's target its luminance.

use super::State;
use super::chain::{EvalContext, GroupValue};
use super::importance::ImportanceMap;
use crate::bidir::{Connection, Heuristic, Paths, Subpaths, camera_subpath_vertices, connect, light_subpath_vertices};
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
    /// The value does not depend on the film numbers (light tracing, `t = 1`, lands where its
    /// connection reaches the film).
    pub film_unread: bool,
    /// The value was NaN, infinite or negative (it then counts as zero).
    pub invalid: bool,
}

impl Contribution {
    pub const ZERO: Contribution =
        Contribution { l: Rgb::ZERO, raster: Vec2::ZERO, f: 0.0, technique: 0, film_unread: false, invalid: false };
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

    fn film_unread(&self) -> bool {
        self.film_unread
    }

    fn splat(&self, splats: &SharedSplats, scale: f32) {
        splats.add(self.raster, self.l * scale);
    }

    fn weight(&self) -> f32 {
        if self.f > 0.0 { luminance(self.l) / self.f } else { 0.0 }
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
    /// The factor the target's value is multiplied by where the contribution lands
    /// ([`ImportanceMap`]; 1 without a map).
    pub factor: f32,
}

/// The raster position of the film sample `u` (each coordinate kept inside the film).
pub(crate) fn raster_position(scene: &Scene, u: Vec2) -> Vec2 {
    let (w, h) = (scene.film.width as f32, scene.film.height as f32);
    Vec2::new((u.x * w).min(w - 1e-3), (u.y * h).min(h - 1e-3))
}

/// The technique `(s, t)` of depth `k` that camera-stream number `u` chooses, and the number
/// of the depth's strategies.
pub(crate) fn technique(k: usize, u: f32) -> (usize, usize, usize) {
    let n = if k == 0 { 1 } else { k + 2 };
    let s = if k == 0 { 0 } else { ((u * n as f32) as usize).min(k + 1) };
    (s, k + 2 - s, n)
}

/// Evaluates the state of `sampler` as a path of depth `k`: the first camera-stream number
/// chooses the technique `s = min(⌊u·(k+2)⌋, k+1)` (depth 0 has the single technique (0, 2),
/// as in pbrt-v4), the next two the film position. The subpaths are left in `paths`. With an
/// `importance` map, the value is the target shaped by it ([`ImportanceMap`]).
pub fn evaluate_connection(
    scene: &Scene,
    k: usize,
    cx: &mut EvalContext,
    paths: &mut Paths,
    importance: Option<&ImportanceMap>,
) -> Evaluated {
    let (sampler, rays) = (&mut cx.sampler, &mut cx.rays);
    sampler.start_stream(Stream::Camera);
    let (s, t, n) = technique(k, sampler.next_1d());
    let raster = raster_position(scene, sampler.next_2d());
    let none = Evaluated { s, t, n, raster, connection: None, factor: 1.0 };
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
    Evaluated { connection, ..none }.shaped(k, importance)
}

impl Evaluated {
    /// The film position the contribution lands on: the camera ray's, or where light tracing
    /// (`t = 1`) reached the film.
    pub fn landing(&self) -> Vec2 {
        match (self.t, self.connection.as_ref().and_then(|c| c.raster)) {
            (1, Some(r)) => r,
            _ => self.raster,
        }
    }

    /// The evaluation with the factor `importance` gives depth `k` where it lands.
    fn shaped(self, k: usize, importance: Option<&ImportanceMap>) -> Self {
        Self { factor: ImportanceMap::of(importance, k, self.landing()), ..self }
    }

    /// The contribution of the strategy with unweighted value `l` and MIS weight `weight`:
    /// `n·w·l` at the state's film position (or where light tracing reached the film), valued
    /// as its luminance times [`Self::factor`]; an invalid value (NaN, infinite or negative)
    /// gives a zero contribution marked invalid.
    pub fn contribution(&self, l: Rgb, weight: f32) -> Contribution {
        let zero = self.zero();
        let l = l * (weight * self.n as f32);
        let f = luminance(l) * self.factor;
        if !valid_radiance(l) || !f.is_finite() {
            return Contribution { invalid: true, ..zero };
        }
        Contribution { l, raster: self.landing(), f: f.max(0.0), ..zero }
    }

    /// The contribution of the evaluated strategy (zero when it could not be connected).
    pub fn untempered(&self) -> Contribution {
        match &self.connection {
            Some(c) => self.contribution(c.l, c.weight),
            None => self.zero(),
        }
    }

    /// A zero contribution of the evaluated strategy.
    fn zero(&self) -> Contribution {
        Contribution { technique: self.s, film_unread: self.t == 1, ..Contribution::ZERO }
    }
}

/// Evaluates the state of `cx.sampler` as a path of every depth `k < depths` at once: pushes
/// each depth's value, invalid flag and rays to `out` (what [`evaluate`] at that depth gives
/// for a sampler holding the same numbers), and returns the rays traced in all.
///
/// Each depth reads the camera stream's first number (its technique), the film position and
/// lens sample, and then a prefix of one camera random walk and of one light random walk:
/// a walk consumes the same numbers per vertex whatever its length and stops at its last
/// vertex, and a connection recomputes the reverse densities and delta flags at its endpoints
/// ([`crate::bidir::reverse_pdfs`]), so the prefix of a longer walk connects as the shorter walk
/// does. The two walks are as long as the longest prefix any depth needs. With a counter-based
/// first state ([`crate::sampler::PssSampler::with_first_state`]) the numbers do not depend on
/// the order the streams are read in either, so this is the value a fresh sampler of the
/// same state gives at each depth. A depth's rays are those its own evaluation would trace:
/// the walks' rays up to its prefixes (a walk traces one ray per vertex after its first, and one
/// more where it ends early), and its connection's. `importance` shapes the values as
/// [`evaluate_connection`]'s.
pub fn evaluate_depths(
    scene: &Scene,
    depths: usize,
    cx: &mut EvalContext,
    out: &mut Vec<GroupValue>,
    importance: Option<&ImportanceMap>,
) -> u64 {
    out.clear();
    let mut paths = std::mem::take(&mut cx.paths);
    let (sampler, rays) = (&mut cx.sampler, &mut cx.rays);
    let start = *rays;
    sampler.start_stream(Stream::Camera);
    let u = sampler.next_1d();
    let raster = raster_position(scene, sampler.next_2d());
    let techniques = (0..depths).map(|k| technique(k, u));
    let t_max = techniques.clone().map(|(_, t, _)| t).max().unwrap_or(0);
    let s_max = techniques.clone().map(|(s, _, _)| s).max().unwrap_or(0);
    paths.camera.clear();
    let mut camera_rays = 0;
    if t_max > 1 {
        let ray = scene.camera.generate_ray(raster, scene.camera.lens_sample(sampler));
        *rays += 1;
        camera_subpath_vertices(scene, ray, sampler, t_max, &mut paths.camera, &mut camera_rays);
    }
    paths.light.clear();
    let mut light_rays = 0;
    if s_max > 1 {
        light_subpath_vertices(scene, sampler, s_max, &mut paths.light, &mut light_rays);
    }
    *rays += camera_rays + light_rays;
    // The rays a walk of `len` vertices (of the first `traced` rays in all) spends on a prefix of
    // `n` vertices.
    let prefix_rays = |n: usize, len: usize, traced: u64| if n > len { traced } else { traced.min(n as u64 - 1) };
    for (k, (s, t, n)) in techniques.enumerate() {
        let mut own = 0;
        let camera_built = t <= 1 || paths.camera.len() >= t;
        if t > 1 {
            // The camera ray counts once where it is generated and again in the walk.
            own += 1 + prefix_rays(t, paths.camera.len(), camera_rays);
        }
        // A depth's own evaluation builds its light subpath only once its camera subpath is
        // complete.
        if s > 1 && camera_built {
            own += prefix_rays(s, paths.light.len(), light_rays);
        }
        let none = Evaluated { s, t, n, raster, connection: None, factor: 1.0 };
        let e = if camera_built && (s <= 1 || paths.light.len() >= s) {
            // The subpaths the depth's own evaluation builds: none for `s ≤ 1` or `t ≤ 1`.
            let light = if s > 1 { &paths.light[..s] } else { &[] };
            let camera = if t > 1 { &paths.camera[..t] } else { &[] };
            let before = *rays;
            let connection = connect(scene, Subpaths { light, camera }, (s, t), sampler, Heuristic::Power, rays);
            own += *rays - before;
            Evaluated { connection, ..none }.shaped(k, importance)
        } else {
            none
        };
        let c = e.untempered();
        out.push(GroupValue { value: c.f, invalid: c.invalid, rays: own });
    }
    cx.paths = paths;
    *rays - start
}

/// Evaluates the state of `cx.sampler` as a path of depth `k` ([`evaluate_connection`], the
/// subpaths left in `cx.paths`).
pub fn evaluate(scene: &Scene, k: usize, cx: &mut EvalContext, importance: Option<&ImportanceMap>) -> Contribution {
    let mut paths = std::mem::take(&mut cx.paths);
    let e = evaluate_connection(scene, k, cx, &mut paths, importance);
    cx.paths = paths;
    e.untempered()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bidir::Tempering;
    use crate::mcmc::{ChainSettings, Target, TemperedTarget, sampler_for};

    /// Every depth's value of a bootstrap sample, valued at all depths from one pair of
    /// subpaths, is bit for bit the value its own evaluation gives, with the rays that
    /// evaluation traces: on the default scene (glossy and smooth surfaces, spheres, disks),
    /// a Cornell box seen through a thin lens, and one filled with a scattering medium.
    #[test]
    fn depths_valued_together_equal_each_depth_valued_alone() {
        let mut default = crate::scenes::default_scene().build().unwrap();
        default.set_resolution(16, 16);
        let lens = crate::testing::thin_lens_cornell_box(16, 0.25);
        let fog = crate::testing::foggy_cornell_box(16);
        let settings = ChainSettings::new(0, 0, 0.01, 0.3);
        let depths = 9;
        for (name, scene) in [("default", default), ("thin lens", lens), ("fog", fog)] {
            let mut nonzero = vec![0; depths];
            let (mut out, mut main_out) = (Vec::new(), Vec::new());
            let temper = Tempering { a: 0.0, heuristic: Heuristic::Power, roughen_mis: false };
            let main = TemperedTarget::new(&scene, 0, temper, 0.0);
            assert!(main.values_groups_together());
            for i in 0..3000 {
                let mut cx = EvalContext::new(sampler_for(17, 0, i, &settings));
                let traced = evaluate_depths(&scene, depths, &mut cx, &mut out, None);
                assert_eq!(traced, cx.rays);
                assert_eq!(out.len(), depths);
                // Tempered MMLT's main target values them as MMLT does.
                main.value_groups(&mut EvalContext::new(sampler_for(17, 0, i, &settings)), depths, &mut main_out);
                assert_eq!(main_out, out);
                for (k, &GroupValue { value: f, invalid, rays }) in out.iter().enumerate() {
                    let mut alone = EvalContext::new(sampler_for(17, k, i, &settings));
                    let c = evaluate(&scene, k, &mut alone, None);
                    assert_eq!(f.to_bits(), c.f.to_bits(), "{name}: sample {i}, depth {k}");
                    assert_eq!(invalid, c.invalid, "{name}: sample {i}, depth {k}");
                    assert_eq!(
                        rays,
                        alone.rays,
                        "{name}: rays of sample {i}, depth {k}: {c:?}, camera {} light {} traced {traced}",
                        cx.paths.camera.len(),
                        cx.paths.light.len()
                    );
                    nonzero[k] += usize::from(f > 0.0);
                }
            }
            // Depth 0 sees the lights directly, a small part of the film.
            assert!(
                nonzero[0] > 0 && nonzero[1..].iter().all(|&n| n >= 100),
                "{name}: too few non-zero values to mean anything: {nonzero:?}"
            );
        }
    }
}
