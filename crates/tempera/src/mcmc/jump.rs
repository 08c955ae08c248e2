//! Reversible jumps between the techniques of one path (Bitterli, Jakob, Novák & Jarosz 2018,
//! "Reversible Jump Metropolis Light Transport using Inverse Mappings", ACM TOG 37(1)): a
//! proposal that keeps the current state's path and changes the bidirectional technique
//! `(s, t)` that makes it, by inverting the sampling of every vertex the new technique samples
//! into the primary-sample numbers that produce it. Numbers the new technique reads but the
//! path does not fix are fresh uniforms, as a large step's are.
//!
//! The map from one technique's numbers to the other's has the Jacobian `p_{s'}(x)/p_s(x)`
//! (the two techniques' densities of the path), so the jump is accepted with
//! `min(1, π(u')/π(u) · p_{s'}/p_s)`; for MMLT's target `n·w_s·f/p_s` that is the ratio of the
//! MIS weights `w_{s'}/w_s`. The densities' ratio is read off the two evaluations as
//! `(f/p_s)/(f/p_{s'})`. Numbers that choose among intervals (the technique, a lobe, a light)
//! are drawn uniformly inside the interval that gives the path, as the reverse jump draws them,
//! and the interval's width is part of the density. A jump whose new evaluation does not
//! rebuild the path (rounding, or a vertex the new technique cannot connect) is rejected.
//!
//! No jump is proposed from a path with a vertex whose sampling is not inverted here (a layered
//! BSDF, a medium, a thin lens, a light other than triangles, points and spots): that depends
//! on the path alone, so a jump and its reverse are possible together or not at all.

use super::strategy::technique;
use super::{EvalContext, Evaluated, evaluate_connection};
use crate::bidir::{Paths, Vertex, VertexKind};
use crate::bsdf::SampleInverse;
use crate::geometry::Ray;
use crate::geometry::ray::offset_origin;
use crate::light::Light;
use crate::math::rng::Pcg32;
use crate::math::{Vec3, luminance};
use crate::sampler::{PssSampler, Stream};
use crate::scene::Scene;

/// The largest `f32` below one: a number the sampler may hold.
const BELOW_ONE: f32 = 1.0 - f32::EPSILON / 2.0;

/// A planned jump: the new technique, the numbers it pins, and the path it must rebuild.
#[derive(Clone, Debug)]
pub struct Plan {
    pub s: usize,
    pins: Vec<(Stream, usize, f32)>,
    positions: Vec<Vec3>,
}

/// The vertices of the path an evaluated strategy made, from the light to the camera.
pub fn vertices<'a>(e: &'a Evaluated, paths: &'a Paths) -> Option<Vec<&'a Vertex>> {
    let c = e.connection.as_ref()?;
    let (s, t) = (e.s, e.t);
    if (s > 1 && paths.light.len() < s) || (t > 1 && paths.camera.len() < t) {
        return None;
    }
    let mut path = Vec::with_capacity(s + t);
    if s == 1 {
        path.push(c.sampled.as_ref()?);
    } else {
        path.extend(&paths.light[..s]);
    }
    if t == 1 {
        path.push(c.sampled.as_ref()?);
    } else {
        path.extend(paths.camera[..t].iter().rev());
    }
    Some(path)
}

/// Whether every vertex of `path` (light to camera) has sampling that is inverted here.
fn invertible(scene: &Scene, path: &[&Vertex]) -> bool {
    let (Some(first), Some(last)) = (path.first(), path.last()) else { return false };
    if scene.has_media() || scene.camera.has_lens() || last.kind != VertexKind::Camera || path.len() < 3 {
        return false;
    }
    let light = match first.light.and_then(|l| scene.lights.get(l as usize)) {
        Some(Light::Point(_) | Light::Spot(_)) => true,
        Some(Light::Area(a)) => scene.geometry.sample_area_inverse(a.prim, first.p).is_some(),
        _ => false,
    };
    light
        && path[1..path.len() - 1]
            .iter()
            .all(|v| v.kind == VertexKind::Surface && v.bsdf.is_some_and(|b| b.bsdf.invertible()))
}

/// Where a ray from `v` towards `q` starts: off the surface as [`offset_origin`] puts it
/// (an area light's point projected onto its triangle first: a light subpath's first vertex is
/// already offset), at the point itself for cameras and point-like lights. Directions between
/// vertices are taken from these origins, as the random walks took them, so that an inverted
/// direction reaches the next vertex where the walk reached it.
fn origin(scene: &Scene, v: &Vertex, q: Vec3) -> Vec3 {
    match v.kind {
        VertexKind::Surface => offset_origin(v.p, v.ng, q - v.p),
        VertexKind::Light if v.ng != Vec3::ZERO => {
            let on_light = v.light.and_then(|l| match scene.lights.get(l as usize)? {
                Light::Area(a) => {
                    let u = scene.geometry.sample_area_inverse(a.prim, v.p)?;
                    Some(scene.geometry.sample_area(a.prim, u)?.point.p)
                }
                _ => None,
            });
            let p = on_light.unwrap_or(v.p);
            offset_origin(p, v.ng, q - p)
        }
        _ => v.p,
    }
}

/// The direction in which a ray leaves `from` to reach `to`.
fn leaving(scene: &Scene, from: &Vertex, to: &Vertex) -> Vec3 {
    (to.p - origin(scene, from, to.p)).normalize()
}

/// The directions a random walk meets at `v`: from its previous vertex `prev` (pointing back
/// to where the ray came from) and towards its next vertex `next`.
fn walk_directions(scene: &Scene, prev: &Vertex, v: &Vertex, next: &Vertex) -> (Vec3, Vec3) {
    (-leaving(scene, prev, v), leaving(scene, v, next))
}

/// Pins the numbers of a BSDF sample at `index` of `stream` (the lobe's number, then the
/// direction's two), each given to `pin` as `(stream, index, value)`.
pub(super) fn pin_bsdf(
    mut pin: impl FnMut((Stream, usize, f32)),
    stream: Stream,
    index: usize,
    inv: SampleInverse,
    rng: &mut Pcg32,
) {
    if let Some((lo, hi)) = inv.uc {
        pin((stream, index, (lo + (hi - lo) * rng.next_f32()).min(BELOW_ONE)));
    }
    if let Some(u) = inv.u {
        pin((stream, index + 1, u.x));
        pin((stream, index + 2, u.y));
    }
}

/// Plans a jump of the path that strategy `e` of depth `k` made (its subpaths in `paths`) to
/// another of the depth's techniques, chosen uniformly; `None` where the path's sampling is not
/// inverted here or no numbers produce it under the chosen technique.
pub fn plan(scene: &Scene, k: usize, e: &Evaluated, paths: &Paths, rng: &mut Pcg32) -> Option<Plan> {
    if k == 0 || e.n < 2 {
        return None;
    }
    let path = vertices(e, paths)?;
    if path.len() != k + 2 || !invertible(scene, &path) {
        return None;
    }
    let n = e.n;
    let mut s = ((rng.next_f32() * (n - 1) as f32) as usize).min(n - 2);
    if s >= e.s {
        s += 1;
    }
    let t = k + 2 - s;
    let u_technique = ((s as f32 + rng.next_f32()) / n as f32).min(BELOW_ONE);
    if technique(k, u_technique).0 != s {
        return None;
    }
    let mut pins = vec![(Stream::Camera, 0, u_technique)];
    // The camera subpath: the film position, then a BSDF sample at each vertex but its last
    // (a pinhole takes no lens sample).
    let camera = k + 1;
    if t >= 2 {
        let (_, raster) = scene.camera.we(&Ray::new(path[camera].p, leaving(scene, path[camera], path[camera - 1])))?;
        let (w, h) = (scene.film.width as f32, scene.film.height as f32);
        pins.push((Stream::Camera, 1, (raster.x / w).min(BELOW_ONE)));
        pins.push((Stream::Camera, 2, (raster.y / h).min(BELOW_ONE)));
        for i in 1..t - 1 {
            let v = path[camera - i];
            let (wo, wi) = walk_directions(scene, path[camera - i + 1], v, path[camera - i - 1]);
            let inv = v.bsdf?.sample_inverse(wo, wi)?;
            pin_bsdf(|p| pins.push(p), Stream::Camera, 3 + 3 * (i - 1), inv, rng);
        }
    }
    // The light: its choice, then (light subpath) its emission and a BSDF sample at each vertex
    // but the last, or (next-event estimation) the point on it.
    let index = path[0].light? as usize;
    let light = scene.lights.get(index)?;
    let (lo, hi) = scene.light_sampler.interval(index);
    let u_light = (lo + (hi - lo) * rng.next_f32()).min(BELOW_ONE);
    if scene.light_sampler.sample(u_light)?.0 != index {
        return None;
    }
    if s >= 2 {
        let (u_pos, u_dir) = light.sample_le_inverse(&scene.geometry, path[0].p, leaving(scene, path[0], path[1]))?;
        pins.push((Stream::Light, 0, u_light));
        if let Some(u) = u_pos {
            pins.push((Stream::Light, 1, u.x));
            pins.push((Stream::Light, 2, u.y));
        }
        pins.push((Stream::Light, 3, u_dir.x));
        pins.push((Stream::Light, 4, u_dir.y));
        for j in 1..s - 1 {
            let (wo, wi) = walk_directions(scene, path[j - 1], path[j], path[j + 1]);
            let inv = path[j].bsdf?.sample_inverse(wo, wi)?;
            pin_bsdf(|p| pins.push(p), Stream::Light, 5 + 3 * (j - 1), inv, rng);
        }
    } else if s == 1 {
        pins.push((Stream::Connection, 0, u_light));
        if let Some(u) = light.sample_li_inverse(&scene.geometry, path[0].p)? {
            pins.push((Stream::Connection, 1, u.x));
            pins.push((Stream::Connection, 2, u.y));
        }
    }
    Some(Plan { s, pins, positions: path.iter().map(|v| v.p).collect() })
}

impl Plan {
    /// Begins the jump's proposal in `sampler` with the planned numbers.
    pub fn apply(&self, sampler: &mut PssSampler) {
        sampler.start_jump();
        for &(stream, index, value) in &self.pins {
            sampler.pin(stream, index, value);
        }
    }

    /// `p_{s'}(x)/p_s(x)`, the jump's Jacobian, where the proposal `new` (its subpaths in
    /// `paths`) rebuilt the path of `current` with the planned technique; 0 otherwise (the
    /// jump is then rejected).
    pub fn jacobian(&self, current: &Evaluated, new: &Evaluated, paths: &Paths) -> f32 {
        let (Some(c), Some(n)) = (&current.connection, &new.connection) else { return 0.0 };
        if new.s != self.s {
            return 0.0;
        }
        let Some(path) = vertices(new, paths) else { return 0.0 };
        let p = &self.positions;
        if path.len() != p.len() {
            return 0.0;
        }
        for (i, v) in path.iter().enumerate() {
            // Within a thousandth of the shorter adjacent edge.
            let edge = |j: Option<usize>| j.and_then(|j| p.get(j)).map_or(f32::INFINITY, |q| (*q - p[i]).length());
            let tolerance = 1e-3 * edge(i.checked_sub(1)).min(edge(Some(i + 1)));
            let moved = (v.p - p[i]).length();
            if moved.is_nan() || moved > tolerance {
                return 0.0;
            }
        }
        let (a, b) = (luminance(c.l), luminance(n.l));
        if a > 0.0 && b > 0.0 && (a / b).is_finite() { a / b } else { 0.0 }
    }
}

/// Proposes a jump of the state `cx.sampler` holds, as a path of depth `k`, planned
/// ([`plan`]) from the state's evaluation held in `cx` (`cx.held`, recorded when the state
/// was accepted). Returns the proposal's evaluation (its subpaths left in `cx.paths`, and
/// recorded in `cx.last`) and the Jacobian, or `None` where no jump was begun (the sampler is
/// then unchanged).
pub fn propose(
    scene: &Scene,
    k: usize,
    cx: &mut EvalContext,
    rng: &mut Pcg32,
    importance: Option<&super::importance::ImportanceMap>,
) -> Option<(Evaluated, f32)> {
    let current = cx.held?;
    let plan = plan(scene, k, &current, &cx.held_paths, rng)?;
    plan.apply(&mut cx.sampler);
    let mut paths = std::mem::take(&mut cx.paths);
    let new = evaluate_connection(scene, k, cx, &mut paths, importance);
    let jacobian = plan.jacobian(&current, &new, &paths);
    cx.paths = paths;
    cx.last = Some(new);
    Some((new, jacobian))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bidir::{Heuristic, Tempering};
    use crate::mcmc::{Chain, State, TemperedTarget};

    /// Jumps alone keep a chain on its path and move it between the path's techniques with the
    /// stationary probabilities its target gives them, `π(u_s)·p_s(x)`: for the MMLT target the
    /// path's MIS weights `w_s(x)` (which sum to one over the techniques), for a hot replica's
    /// roughened target its value over the unweighted `f/p_s`. On the default scene (a triangle
    /// light, diffuse walls, rough glass and gold spheres), paths of depths 2 to 4. A wrong
    /// Jacobian would weigh each technique by `w_s/p_s` instead.
    #[test]
    fn jumps_alone_visit_a_paths_techniques_in_proportion_to_their_target() {
        let mut scene = crate::scenes::default_scene().build().unwrap();
        scene.set_resolution(32, 32);
        let (mut tested, mut seed, mut accepted) = (0, 0u64, 0);
        while tested < 8 && seed < 20_000 {
            seed += 1;
            let k = 2 + (seed % 3) as usize;
            // Every other path under a hot replica's target.
            let a = if tested % 2 == 0 { 0.0 } else { 0.4 };
            let temper = Tempering { a, heuristic: Heuristic::Power, roughen_mis: false };
            let target = TemperedTarget::new(&scene, k, temper, a);
            let sampler = PssSampler::new(seed, 0, 0.01, 0.3).with_jumps(1.0);
            let mut chain = Chain::start(&target, sampler, Pcg32::new(seed, 3), k);
            let start = chain.state();
            let Some(e) = start.evaluated.as_ref().filter(|_| start.value() > 0.0) else { continue };
            let Some(path) = vertices(e, &start.paths) else { continue };
            if !invertible(&scene, &path) {
                continue;
            }
            let mut positions: Vec<Vec3> = path.iter().map(|v| v.p).collect();
            let steps = 20_000;
            let (mut visits, mut weights, mut odds) = (vec![0u64; k + 2], vec![f32::NAN; k + 2], vec![0.0; k + 2]);
            for _ in 0..steps {
                chain.mutate(&target, None);
                let state = chain.state();
                let e = state.evaluated.as_ref().expect("evaluated");
                let now: Vec<Vec3> = vertices(e, &state.paths).expect("a path").iter().map(|v| v.p).collect();
                // The light's point is offset off the light where a light subpath starts there;
                // every other vertex stays within rounding of where it was.
                let moved: Vec<f32> = now.iter().zip(&positions).map(|(a, b)| (*a - *b).length()).collect();
                assert!(moved[0] < 2e-4 && moved[1..].iter().all(|&d| d < 1e-4), "the path moved: {moved:?}");
                positions = now;
                visits[e.s] += 1;
                let c = e.connection.as_ref().expect("connected");
                weights[e.s] = c.weight;
                odds[e.s] = state.value() / luminance(c.l);
            }
            accepted += chain.stats.jumps_accepted;
            let expected: Vec<f32> = if a == 0.0 {
                let visited: f32 = weights.iter().filter(|w| !w.is_nan()).sum();
                assert!((visited - 1.0).abs() < 1e-3, "seed {seed}: visited weights sum to {visited}: {weights:?}");
                weights.iter().map(|w| if w.is_nan() { 0.0 } else { *w }).collect()
            } else {
                let sum: f32 = odds.iter().sum();
                odds.iter().map(|o| o / sum).collect()
            };
            for (s, (&n, &p)) in visits.iter().zip(&expected).enumerate() {
                let share = n as f32 / steps as f32;
                assert!((share - p).abs() < 0.03, "seed {seed}, depth {k}, a = {a}, s = {s}: {share} of the time, {p}");
            }
            tested += 1;
        }
        assert_eq!(tested, 8);
        assert!(accepted > 5000, "{accepted} jumps accepted");
    }

    /// MMLT's depth target, whose chains hold their state's path in their context, makes the
    /// same chain as the tempered target's main replica, whose states keep their paths: jumps
    /// and mutations mixed, every value bit for bit.
    #[test]
    fn held_and_stored_paths_make_the_same_chain() {
        let mut scene = crate::scenes::default_scene().build().unwrap();
        scene.set_resolution(32, 32);
        let temper = Tempering { a: 0.0, heuristic: Heuristic::Power, roughen_mis: false };
        let k = 3;
        let stored = TemperedTarget::new(&scene, k, temper, 0.0);
        let held = crate::integrator::mmlt::DepthTarget { scene: &scene, depth: k, importance: None };
        let mut compared = 0;
        for seed in 1..40 {
            let sampler = || PssSampler::new(seed, 0, 0.01, 0.3).with_jumps(0.5);
            let mut a = Chain::start(&stored, sampler(), Pcg32::new(seed, 3), k);
            let mut b = Chain::start(&held, sampler(), Pcg32::new(seed, 3), k);
            for _ in 0..300 {
                a.mutate(&stored, None);
                b.mutate(&held, None);
                assert_eq!(a.state().value().to_bits(), b.state().value().to_bits());
                assert_eq!(a.state().technique(), b.state().technique());
            }
            assert_eq!(a.stats, b.stats);
            compared += a.stats.jumps_accepted;
        }
        assert!(compared > 100, "{compared} jumps accepted");
    }
}
