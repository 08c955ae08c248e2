//! Re-evaluation of an evaluated strategy under a tempered target (Šik & Křivánek 2016, §4):
//! the GGX lobes at the two connection vertices are roughened by `a` ([`Bsdf::roughened`])
//! while every other vertex, the camera and the emitters stay as they are. Nothing is ever
//! sampled *from* a connection vertex, so the same subpaths describe the same path under every
//! tempered target, and the re-evaluation needs no rays: the connection's visibility and
//! geometry are those [`connect`](super::connect()) found, kept in [`Connection::base`].
//!
//! Which vertices are connection vertices: `q_s` and `p_t` for `s, t ≥ 2`; the surface vertex
//! joined to a sampled light (`s = 1`) or camera (`t = 1`) point. A camera path that hits an
//! emitter (`s = 0`) has no connection edge and is unchanged.
//!
//! With `roughen_mis` the MIS weight is recomputed from the roughened BSDFs' reverse densities
//! (the forward densities are those the subpaths were sampled with); without it the weight of
//! the untempered evaluation is kept.
//!
//! [`Bsdf::roughened`]: crate::bsdf::Bsdf::roughened

use super::connect::{Connection, Subpaths};
use super::mis::{Heuristic, ReversePdfs, mis_weight_with, reverse_pdfs};
use super::vertex::{Vertex, VertexKind};
use crate::bsdf::TransportMode;
use crate::math::Rgb;
use crate::scene::Scene;

/// Scratch copies of the subpaths with roughened connection vertices.
#[derive(Default)]
pub struct TemperScratch {
    light: Vec<Vertex>,
    camera: Vec<Vertex>,
}

fn roughened(v: &Vertex, a: f32) -> Vertex {
    let mut v = *v;
    if v.kind == VertexKind::Surface
        && let Some(b) = &mut v.bsdf
    {
        b.bsdf = b.bsdf.roughened(a);
    }
    v
}

/// One tempered target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tempering {
    /// The roughening `a` (0: the scene's BSDFs).
    pub a: f32,
    pub heuristic: Heuristic,
    /// Recompute the MIS weight from the roughened reverse densities.
    pub roughen_mis: bool,
}

/// The unweighted contribution and MIS weight of strategy `(s, t)`, evaluated by
/// [`connect`](super::connect) as `c`, under the target `temper`. `a = 0` returns `c`'s own
/// values exactly.
pub fn tempered(
    scene: &Scene,
    paths: Subpaths,
    (s, t): (usize, usize),
    c: &Connection,
    temper: &Tempering,
    scratch: &mut TemperScratch,
) -> (Rgb, f32) {
    let Tempering { a, heuristic, roughen_mis } = *temper;
    if a <= 0.0 || s == 0 {
        return (c.l, c.weight);
    }
    let Subpaths { light, camera } = paths;
    // The surface-side connection vertices, roughened.
    let qs = (s >= 2 || t == 1).then(|| roughened(&light[s - 1], a));
    let pt = (t >= 2).then(|| roughened(&camera[t - 1], a));
    let (f_light, f_camera) = match (s, t, &qs, &pt) {
        (_, 1, Some(qs), _) => {
            let Some(v) = &c.sampled else { return (c.l, c.weight) };
            (qs.f(scene, v, TransportMode::Importance), c.f_camera)
        }
        (1, _, _, Some(pt)) => {
            let Some(v) = &c.sampled else { return (c.l, c.weight) };
            (c.f_light, pt.f(scene, v, TransportMode::Radiance))
        }
        (_, _, Some(qs), Some(pt)) => {
            (qs.f(scene, pt, TransportMode::Importance), pt.f(scene, qs, TransportMode::Radiance))
        }
        _ => return (c.l, c.weight),
    };
    let l = c.base * f_light * f_camera;
    if !roughen_mis {
        return (l, c.weight);
    }
    // The MIS weight from the roughened densities: copies of the subpaths with the roughened
    // connection vertices in place.
    scratch.light.clear();
    scratch.light.extend_from_slice(&light[..s.min(light.len())]);
    scratch.camera.clear();
    scratch.camera.extend_from_slice(&camera[..t.min(camera.len())]);
    if let Some(qs) = qs {
        scratch.light[s - 1] = qs;
    }
    if let Some(pt) = pt {
        scratch.camera[t - 1] = pt;
    }
    let (light, camera) = (&scratch.light[..], &scratch.camera[..]);
    let rev =
        if s + t == 2 { ReversePdfs::default() } else { reverse_pdfs(scene, light, camera, c.sampled.as_ref(), s, t) };
    (l, mis_weight_with(scene, light, camera, c.sampled.as_ref(), (s, t), &rev, heuristic))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bidir::{camera_subpath, connect, light_subpath};
    use crate::sampler::{PssSampler, Sampler, Stream};

    /// Re-evaluating without rays agrees with evaluating the same subpaths from scratch with
    /// roughened connection vertices (new shadow rays, new reverse densities), for every kind of
    /// strategy, on the default scene's glossy metal and rough glass.
    #[test]
    fn tempered_re_evaluation_matches_a_full_evaluation_with_roughened_vertices() {
        let mut scene = crate::scenes::default_scene().build().unwrap();
        scene.set_resolution(32, 32);
        check_re_evaluation(&scene);
    }

    /// The same in a scattering medium filling the default scene: connections carry the
    /// medium's transmittance (in the connection's base, unchanged by roughening), and medium
    /// vertices, which tempering leaves as they are, are connection vertices too.
    #[test]
    fn tempered_re_evaluation_matches_a_full_evaluation_in_a_medium() {
        use crate::medium::{Medium, MediumInterface};
        let mut b = crate::scenes::default_scene();
        let m = b.add_medium(Medium { sigma_a: Rgb::splat(0.02), sigma_s: Rgb::new(0.08, 0.06, 0.04), g: 0.3 });
        for shape in 0..b.shape_count() {
            b.set_shape_medium(shape, MediumInterface { inside: Some(m), outside: Some(m) });
        }
        b.set_camera_medium(Some(m));
        let mut scene = b.build().unwrap();
        scene.set_resolution(32, 32);
        let medium_connections = check_re_evaluation(&scene);
        assert!(medium_connections > 100, "{medium_connections} connections at a medium vertex");
    }

    /// Checks every strategy of 3000 sample paths; returns how many connections had a medium
    /// vertex at either end.
    fn check_re_evaluation(scene: &Scene) -> usize {
        let mut medium_connections = 0;
        let (mut camera, mut light, mut rays) = (Vec::new(), Vec::new(), 0);
        let mut scratch = TemperScratch::default();
        let (mut checked, mut changed, mut light_tracing, mut light_sampling) = (0, 0, 0, 0);
        let a = 0.3;
        let at = |a, roughen_mis| Tempering { a, heuristic: Heuristic::Power, roughen_mis };
        for i in 0..3000u64 {
            let mut sampler = PssSampler::new(i, 0, 0.01, 0.3);
            sampler.start_stream(Stream::Camera);
            let film = sampler.next_2d();
            let ray = scene.camera.generate_ray(film * 32.0, sampler.next_2d());
            camera_subpath(scene, ray, &mut sampler, 5, &mut camera, &mut rays);
            light_subpath(scene, &mut sampler, 5, &mut light, &mut rays);
            for t in 1..=camera.len() {
                for s in 1..=light.len() {
                    let paths = Subpaths { light: &light, camera: &camera };
                    let Some(c) = connect(scene, paths, (s, t), &mut sampler, Heuristic::Power, &mut rays) else {
                        continue;
                    };
                    let (l0, w0) = tempered(scene, paths, (s, t), &c, &at(0.0, true), &mut scratch);
                    assert!(l0 == c.l && w0 == c.weight, "a = 0 is the untempered target exactly");
                    let (l, w) = tempered(scene, paths, (s, t), &c, &at(a, true), &mut scratch);
                    let (_, w_kept) = tempered(scene, paths, (s, t), &c, &at(a, false), &mut scratch);
                    assert_eq!(w_kept, c.weight);
                    // From scratch: roughened copies of the connection vertices, connected anew
                    // with the same connection numbers.
                    let mut light2 = light.clone();
                    let mut camera2 = camera.clone();
                    if s >= 2 {
                        light2[s - 1] = roughened(&light[s - 1], a);
                    }
                    if t >= 2 {
                        camera2[t - 1] = roughened(&camera[t - 1], a);
                    }
                    let paths2 = Subpaths { light: &light2, camera: &camera2 };
                    let full = connect(scene, paths2, (s, t), &mut sampler, Heuristic::Power, &mut rays);
                    let Some(full) = full else {
                        assert!(l.max_element() <= 1e-6 * c.l.max_element(), "({s},{t}): {l} but none");
                        continue;
                    };
                    let tol = 1e-4 * full.l.max_element().max(c.l.max_element());
                    assert!((l - full.l).abs().max_element() <= tol, "({s},{t}): {l} vs {}", full.l);
                    assert!((w - full.weight).abs() <= 1e-4, "({s},{t}): weight {w} vs {}", full.weight);
                    checked += 1;
                    let at_medium = |v: Option<&Vertex>| v.is_some_and(|v| v.kind == VertexKind::Medium);
                    medium_connections +=
                        usize::from(at_medium(light.get(s - 1)) || (t >= 2 && at_medium(camera.get(t - 1))));
                    changed += usize::from((l - c.l).abs().max_element() > 1e-3 * c.l.max_element());
                    light_tracing += usize::from(t == 1);
                    light_sampling += usize::from(s == 1);
                }
            }
        }
        assert!(checked > 1000 && changed > 100, "{checked} checked, {changed} changed by roughening");
        assert!(light_tracing > 50 && light_sampling > 50, "{light_tracing} t = 1, {light_sampling} s = 1");
        medium_connections
    }
}
