//! Lens steps: a small step that moves a path's pixel and keeps the rest of the path, the
//! lens perturbation of Veach & Guibas ("Metropolis Light Transport", SIGGRAPH 1997, §5.3.3)
//! taken to primary sample space through the inverse of the first camera vertex's scattering
//! (as the reversible jumps of [`super::jump`] invert every vertex's).
//!
//! A film step ([`crate::sampler::PssSampler::with_film_steps`]) moves the film position and
//! keeps every other number, so the first camera vertex `x₁` moves and the path after it
//! scatters by the same local directions from there: the second vertex `x₂` moves with `x₁`, and
//! a path that reaches the light through a narrow gap is broken. A lens step moves the film
//! position by the same kernel, finds the new `x₁'` and sets `x₁'`'s scattering numbers to those
//! that send the path to the current `x₂` ([`crate::bsdf::Bsdf::sample_inverse`]): the path keeps
//! `x₂`, and every later vertex whose scattering does not depend on the incoming direction
//! (diffuse ones) keeps its place too.
//!
//! With every other number fixed, the map from the film and `x₁`'s numbers `(f, v)` to
//! `(f', v')` at a given film offset has the Jacobian `∂v'/∂v = p_A(x₂ | x₁')/p_A(x₂ | x₁)`: the
//! densities, per unit area at `x₂`, with which `x₁'` and `x₁` sample `x₂` (the walk's forward
//! density of `x₂`, a lobe's choice included: a number that chooses a lobe is drawn uniformly in
//! the lobe's interval, as [`super::jump`] draws it). A lens step is accepted with
//! `min(1, π(u')/π(u) · p_A(x₂ | x₁')/p_A(x₂ | x₁))`.
//!
//! A lens step is defined where the state's technique has a camera subpath of at least three
//! vertices (`t ≥ 3`), its first vertex on a surface whose sampling is inverted here, not delta,
//! and its second on a surface, in a scene without media seen through a pinhole ([`plan`]).
//! Where it is not, the step is a film step. Which of the two a state takes depends on the
//! state alone, and a proposal is accepted only where the state it reaches takes the same kind
//! ([`jacobian`]), so each step and its reverse exist together: the chain moves by two
//! reversible kernels, each confined to its own states. A state that does not read its film
//! numbers (light tracing) proposes itself ([`LensStep::Stay`]), as its film step does.

use super::jump::pin_bsdf;
use super::strategy::raster_position;
use super::{EvalContext, Evaluated};
use crate::bidir::{Paths, VertexKind};
use crate::geometry::ray::offset_origin;
use crate::math::Vec3;
use crate::math::rng::Pcg32;
use crate::sampler::{Sampler, Stream};
use crate::scene::Scene;

/// Where a lens step leaves the chain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LensStep {
    /// The state has no lens step and does not read its film numbers: it proposes itself,
    /// accepted, with no evaluation (the sampler's proposal is to be rejected, which gives its
    /// numbers back).
    Stay,
    /// The lens step was begun but cannot keep the path's second vertex (the new first vertex
    /// cannot scatter towards it): rejected, with no evaluation.
    Reject,
    /// The proposal was evaluated: the step's Jacobian ([`jacobian`]; 0 rejects it), and
    /// whether it was a lens step (or a film step, from a state without one).
    Proposed { jacobian: f32, lens: bool },
}

/// A lens step planned from the current state: the technique's camera vertices, the second
/// camera vertex's position and the density with which the first sampled it.
#[derive(Clone, Copy, Debug)]
pub struct Plan {
    t: usize,
    x1: Vec3,
    x2: Vec3,
    pdf: f32,
}

/// The camera stream's index of the first camera vertex's lobe number (its direction's two
/// follow): after the technique's number and the film position (a pinhole takes no lens sample).
const FIRST_VERTEX: usize = 3;

/// The lens step of the state whose evaluation is `e` (its subpaths in `paths`), where it has
/// one.
pub fn plan(scene: &Scene, e: &Evaluated, paths: &Paths) -> Option<Plan> {
    if e.t < 3 || e.connection.is_none() || scene.has_media() || scene.camera.has_lens() {
        return None;
    }
    let (x1, x2) = (paths.camera.get(1)?, paths.camera.get(2)?);
    let rough = x1.kind == VertexKind::Surface && !x1.delta && x1.bsdf.is_some_and(|b| b.bsdf.invertible());
    if !rough || x2.kind != VertexKind::Surface || !(x2.pdf_fwd > 0.0 && x2.pdf_fwd.is_finite()) {
        return None;
    }
    Some(Plan { t: e.t, x1: x1.p, x2: x2.p, pdf: x2.pdf_fwd })
}

impl Plan {
    /// Sets the first camera vertex's numbers of the proposal `cx.sampler` has begun (a lens
    /// step: its film position already moved) so that the new first vertex scatters towards the
    /// current second one. Returns whether it could (the new first vertex is a surface whose
    /// sampling is inverted here and can scatter that way). Traces the camera ray.
    pub fn pin(&self, scene: &Scene, cx: &mut EvalContext, rng: &mut Pcg32) -> bool {
        let sampler = &mut cx.sampler;
        sampler.start_stream(Stream::Camera);
        sampler.next_1d();
        let raster = raster_position(scene, sampler.next_2d());
        let ray = scene.camera.generate_ray(raster, scene.camera.lens_sample(sampler));
        cx.rays += 1;
        let Some(it) = scene.intersect(&ray) else { return false };
        let bsdf = scene.bsdf(&it);
        if !bsdf.bsdf.invertible() {
            return false;
        }
        let (p, ng) = (it.surface.p, it.surface.ng);
        let wi = (self.x2 - offset_origin(p, ng, self.x2 - p)).normalize();
        let Some(inverse) = bsdf.sample_inverse(it.wo, wi) else { return false };
        pin_bsdf(
            |(stream, index, value)| sampler.pin(stream, index, value),
            Stream::Camera,
            FIRST_VERTEX,
            inverse,
            rng,
        );
        true
    }

    /// `p_A(x₂ | x₁')/p_A(x₂ | x₁)`, where the proposal `new` (its subpaths in `paths`) kept the
    /// second camera vertex within rounding (a thousandth of the shorter of its two edges);
    /// 0 otherwise.
    pub fn jacobian(&self, new: &Evaluated, paths: &Paths) -> f32 {
        let (Some(x1), Some(x2)) = (paths.camera.get(1), paths.camera.get(2)) else { return 0.0 };
        if new.t != self.t || x2.kind != VertexKind::Surface {
            return 0.0;
        }
        let tolerance = 1e-3 * (self.x2 - self.x1).length().min((self.x2 - x1.p).length());
        let moved = (x2.p - self.x2).length();
        let j = x2.pdf_fwd / self.pdf;
        if moved <= tolerance && j.is_finite() && j > 0.0 { j } else { 0.0 }
    }
}

/// The Jacobian with which the proposal `new` (its subpaths in `paths`; `None`: not evaluated as
/// one strategy) of a lens step planned as `plan`, or of a film step where the state had no
/// lens step (`plan` `None`), is accepted: for a lens step [`Plan::jacobian`] where the proposal
/// has a lens step too (the step back) and 0 where it has none; for a film step 1 where the
/// proposal has no lens step either and 0 where it has one.
pub fn jacobian(scene: &Scene, plan: Option<&Plan>, new: Option<&Evaluated>, paths: &Paths) -> f32 {
    match (plan, new) {
        (Some(plan), Some(new)) if self::plan(scene, new, paths).is_some() => plan.jacobian(new, paths),
        (Some(_), _) => 0.0,
        (None, new) if new.and_then(|e| self::plan(scene, e, paths)).is_some() => 0.0,
        (None, _) => 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec2;
    use crate::mcmc::evaluate_connection;
    use crate::mcmc::strategy::technique;
    use crate::sampler::PssSampler;

    /// The numbers of a state of depth 2 evaluated by `(s, t) = (1, 3)`: the technique, the
    /// film position, the first camera vertex's three, and the light's three (next-event
    /// estimation at the second camera vertex).
    #[derive(Clone, Copy)]
    struct Numbers {
        film: Vec2,
        v: [f32; 3],
        light: [f32; 3],
    }

    const K: usize = 2;
    const U_TECHNIQUE: f32 = 1.5 / 4.0;

    /// A context whose sampler holds `n` (unread entries drawn fresh, none read here).
    fn context(n: &Numbers) -> EvalContext {
        let mut sampler = PssSampler::new(7, 0, 0.01, 0.0).with_lens_steps(1.0, 0.02);
        sampler.start_jump();
        let camera = [U_TECHNIQUE, n.film.x, n.film.y, n.v[0], n.v[1], n.v[2]];
        for (i, &u) in camera.iter().enumerate() {
            sampler.pin(Stream::Camera, i, u);
        }
        for (i, &u) in n.light.iter().enumerate() {
            sampler.pin(Stream::Connection, i, u);
        }
        EvalContext::new(sampler)
    }

    fn evaluated(scene: &Scene, n: &Numbers) -> (Evaluated, Paths) {
        let mut cx = context(n);
        let mut paths = Paths::default();
        let e = evaluate_connection(scene, K, &mut cx, &mut paths, None);
        (e, paths)
    }

    /// The lens step of the state `n` to the film position `film`: the new first vertex's
    /// direction numbers, the proposal's Jacobian, and the proposal.
    fn step(scene: &Scene, n: &Numbers, film: Vec2) -> Option<([f32; 2], f32, Numbers)> {
        let (e, paths) = evaluated(scene, n);
        let plan = plan(scene, &e, &paths)?;
        let mut cx = context(&Numbers { film, ..*n });
        if !plan.pin(scene, &mut cx, &mut Pcg32::new(1, 2)) {
            return None;
        }
        let v = |i| cx.sampler.value(Stream::Camera, i).expect("pinned");
        let new = Numbers { film, v: [v(3), v(4), v(5)], ..*n };
        let (e, paths) = evaluated(scene, &new);
        let j = plan.jacobian(&e, &paths);
        (j > 0.0).then_some(([new.v[1], new.v[2]], j, new))
    }

    /// A lens step's map of the first camera vertex's direction numbers, at a fixed film offset,
    /// has the Jacobian determinant the step is accepted with (central differences of the map
    /// itself, traced through the scene), and the step from the proposal back to the film
    /// position it came from returns the numbers it started from, with the inverse Jacobian:
    /// on the Cornell box (diffuse) and the default scene (rough gold and glass, GGX lobes
    /// inverted, a lobe's number redrawn in its interval).
    #[test]
    fn a_lens_step_is_an_invertible_map_with_the_jacobian_it_is_accepted_with() {
        let mut default = crate::scenes::default_scene().build().unwrap();
        default.set_resolution(32, 32);
        let cornell = crate::scenes::cornell_box(32, 32).build().unwrap();
        assert_eq!(technique(K, U_TECHNIQUE).0, 1);
        for (name, scene) in [("cornell box", cornell), ("default scene", default)] {
            let mut rng = Pcg32::new(3, 4);
            let (mut tested, mut glossy) = (0, 0);
            for _ in 0..20_000 {
                if tested == 40 {
                    break;
                }
                let mut u = || rng.next_f32();
                let n = Numbers { film: Vec2::new(u(), u()), v: [u(), u(), u()], light: [u(), u(), u()] };
                let film = n.film + Vec2::new(u() - 0.5, u() - 0.5) * 0.02;
                if !(0.0..1.0).contains(&film.x) || !(0.0..1.0).contains(&film.y) {
                    continue;
                }
                let Some((_, j, new)) = step(&scene, &n, film) else { continue };
                // Central differences of the map v → v' at the fixed film offset.
                let h = 2e-3;
                let moved = |dv: Vec2| {
                    let n = Numbers { v: [n.v[0], n.v[1] + dv.x, n.v[2] + dv.y], ..n };
                    step(&scene, &n, film).map(|s| Vec2::from(s.0))
                };
                let (Some(xp), Some(xm), Some(yp), Some(ym)) = (
                    moved(Vec2::new(h, 0.0)),
                    moved(Vec2::new(-h, 0.0)),
                    moved(Vec2::new(0.0, h)),
                    moved(Vec2::new(0.0, -h)),
                ) else {
                    continue;
                };
                let (dx, dy) = ((xp - xm) / (2.0 * h), (yp - ym) / (2.0 * h));
                let det = (dx.x * dy.y - dx.y * dy.x).abs();
                assert!((det / j - 1.0).abs() < 0.05, "{name}: Jacobian {j}, central differences {det}");
                // And back.
                let (back, j_back, _) = step(&scene, &new, n.film).expect("the reverse step exists");
                assert!(
                    (Vec2::from(back) - Vec2::new(n.v[1], n.v[2])).length() < 1e-3,
                    "{name}: {back:?} vs {:?}",
                    n.v
                );
                assert!((j * j_back - 1.0).abs() < 1e-2, "{name}: {j} and back {j_back}");
                let (e, paths) = evaluated(&scene, &n);
                glossy +=
                    usize::from(!matches!(paths.camera[1].bsdf.map(|b| b.bsdf), Some(crate::bsdf::Bsdf::Diffuse(_))));
                assert!(e.connection.is_some());
                tested += 1;
            }
            assert_eq!(tested, 40, "{name}");
            if name == "default scene" {
                assert!(glossy >= 3, "{name}: {glossy} glossy first vertices");
            }
        }
    }
}
