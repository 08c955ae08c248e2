//! Multiple importance sampling weights over all strategies that could have produced a path,
//! from the ratios of reverse to forward densities along both subpaths (Veach 1997 §10.3;
//! pbrt-v4 §13.3.5), with the power (β = 2) or balance heuristic. Delta vertices contribute
//! no strategy of their own.

use super::vertex::Vertex;
use crate::scene::Scene;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Heuristic {
    #[default]
    Power,
    Balance,
}

#[inline]
fn remap0(x: f32) -> f32 {
    if x != 0.0 { x } else { 1.0 }
}

/// The MIS weight of strategy `(s, t)`; `sampled` replaces the connecting endpoint when it was
/// sampled anew (`s = 1` or `t = 1`).
pub fn mis_weight(
    scene: &Scene,
    light: &[Vertex],
    camera: &[Vertex],
    sampled: Option<&Vertex>,
    s: usize,
    t: usize,
    heuristic: Heuristic,
) -> f32 {
    if s + t == 2 {
        return 1.0;
    }
    let power = |r: f32| match heuristic {
        Heuristic::Power => r * r,
        Heuristic::Balance => r,
    };
    // The connection endpoints, with the freshly sampled one substituted.
    let qs = (s > 0).then(|| if s == 1 { sampled.copied().unwrap_or(light[0]) } else { light[s - 1] });
    let pt = (t > 0).then(|| if t == 1 { sampled.copied().unwrap_or(camera[0]) } else { camera[t - 1] });
    let qs_minus = (s > 1).then(|| light[s - 2]);
    let pt_minus = (t > 1).then(|| camera[t - 2]);

    // Reverse densities of the four vertices around the connection.
    let pt_rev = pt.map(|pt| match (&qs, &pt_minus) {
        (Some(q), _) => q.pdf(scene, qs_minus.as_ref(), &pt),
        (None, Some(pm)) => pt.pdf_light_origin(scene, pm),
        (None, None) => 0.0,
    });
    let pt_minus_rev = match (&pt, &pt_minus) {
        (Some(p), Some(pm)) => Some(match &qs {
            Some(q) => p.pdf(scene, Some(q), pm),
            None => p.pdf_light(scene, pm),
        }),
        _ => None,
    };
    let qs_rev = match (&qs, &pt) {
        (Some(q), Some(p)) => Some(p.pdf(scene, pt_minus.as_ref(), q)),
        _ => None,
    };
    let qs_minus_rev = match (&qs, &qs_minus) {
        (Some(q), Some(qm)) => Some(q.pdf(scene, pt.as_ref(), qm)),
        _ => None,
    };

    let cam_rev = |i: usize| {
        if i + 1 == t {
            pt_rev.unwrap_or(0.0)
        } else if i + 2 == t {
            pt_minus_rev.unwrap_or(0.0)
        } else {
            camera[i].pdf_rev
        }
    };
    let cam_fwd = |i: usize| if i + 1 == t { pt.map_or(0.0, |p| p.pdf_fwd) } else { camera[i].pdf_fwd };
    let cam_delta = |i: usize| if i + 1 == t { false } else { camera[i].delta };
    let mut sum = 0.0f32;
    let mut ri = 1.0f32;
    for i in (1..t).rev() {
        ri *= remap0(cam_rev(i)) / remap0(cam_fwd(i));
        if !cam_delta(i) && !cam_delta(i - 1) {
            sum += power(ri);
        }
    }

    let light_rev = |i: usize| {
        if i + 1 == s {
            qs_rev.unwrap_or(0.0)
        } else if i + 2 == s {
            qs_minus_rev.unwrap_or(0.0)
        } else {
            light[i].pdf_rev
        }
    };
    let light_fwd = |i: usize| if i + 1 == s { qs.map_or(0.0, |q| q.pdf_fwd) } else { light[i].pdf_fwd };
    let light_delta = |i: usize| if i + 1 == s { false } else { light[i].delta };
    let first = if s == 1 { qs } else { light.first().copied() };
    ri = 1.0;
    for i in (0..s).rev() {
        ri *= remap0(light_rev(i)) / remap0(light_fwd(i));
        let delta_before = if i > 0 { light_delta(i - 1) } else { first.is_some_and(|v| v.is_delta_light(scene)) };
        if !light_delta(i) && !delta_before {
            sum += power(ri);
        }
    }
    let w = 1.0 / (1.0 + sum);
    if w.is_finite() { w } else { 0.0 }
}
