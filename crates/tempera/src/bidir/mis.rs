//! Multiple importance sampling weights over all strategies that could have produced a path,
//! from the ratios of reverse to forward densities along both subpaths (Veach 1997 §10.3;
//! pbrt-v4 §13.3.5), with the power (β = 2) or balance heuristic. Delta vertices contribute
//! no strategy of their own.

use super::vertex::Vertex;
use crate::scene::Scene;

/// The MIS heuristic (Veach 1997 §9.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Heuristic {
    #[default]
    Power,
    Balance,
}

#[inline]
fn remap0(x: f32) -> f32 {
    if x != 0.0 { x } else { 1.0 }
}

/// The reverse densities MIS needs around a connection: of the camera-side endpoint `pt` and
/// its predecessor, and of the light-side endpoint `qs` and its predecessor, each as if sampled
/// from the other side through the connection. They depend on the BSDFs at the two connection
/// vertices, so re-evaluating a path with other BSDFs there means recomputing them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ReversePdfs {
    pub pt: f32,
    pub pt_minus: f32,
    pub qs: f32,
    pub qs_minus: f32,
}

/// The connection endpoints of strategy `(s, t)`, with the freshly sampled one substituted.
struct Endpoints<'a> {
    qs: Option<&'a Vertex>,
    pt: Option<&'a Vertex>,
    qs_minus: Option<&'a Vertex>,
    pt_minus: Option<&'a Vertex>,
}

fn endpoints<'a>(
    light: &'a [Vertex],
    camera: &'a [Vertex],
    sampled: Option<&'a Vertex>,
    s: usize,
    t: usize,
) -> Endpoints<'a> {
    Endpoints {
        qs: (s > 0).then(|| if s == 1 { sampled.unwrap_or_else(|| &light[0]) } else { &light[s - 1] }),
        pt: (t > 0).then(|| if t == 1 { sampled.unwrap_or_else(|| &camera[0]) } else { &camera[t - 1] }),
        qs_minus: (s > 1).then(|| &light[s - 2]),
        pt_minus: (t > 1).then(|| &camera[t - 2]),
    }
}

/// The reverse densities of strategy `(s, t)`.
pub fn reverse_pdfs(
    scene: &Scene,
    light: &[Vertex],
    camera: &[Vertex],
    sampled: Option<&Vertex>,
    s: usize,
    t: usize,
) -> ReversePdfs {
    let Endpoints { qs, pt, qs_minus, pt_minus } = endpoints(light, camera, sampled, s, t);
    let pt_rev = pt.map_or(0.0, |pt| match (&qs, &pt_minus) {
        (Some(q), _) => q.pdf(scene, qs_minus, pt),
        (None, Some(pm)) => pt.pdf_light_origin(scene, pm),
        (None, None) => 0.0,
    });
    let pt_minus_rev = match (&pt, &pt_minus) {
        (Some(p), Some(pm)) => match &qs {
            Some(q) => p.pdf(scene, Some(q), pm),
            None => p.pdf_light(scene, pm),
        },
        _ => 0.0,
    };
    let qs_rev = match (&qs, &pt) {
        (Some(q), Some(p)) => p.pdf(scene, pt_minus, q),
        _ => 0.0,
    };
    let qs_minus_rev = match (&qs, &qs_minus) {
        (Some(q), Some(qm)) => q.pdf(scene, pt, qm),
        _ => 0.0,
    };
    ReversePdfs { pt: pt_rev, pt_minus: pt_minus_rev, qs: qs_rev, qs_minus: qs_minus_rev }
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
    let rev = reverse_pdfs(scene, light, camera, sampled, s, t);
    mis_weight_with(scene, light, camera, sampled, (s, t), &rev, heuristic)
}

/// The MIS weight of strategy `(s, t)` from given reverse densities around the connection.
pub fn mis_weight_with(
    scene: &Scene,
    light: &[Vertex],
    camera: &[Vertex],
    sampled: Option<&Vertex>,
    (s, t): (usize, usize),
    rev: &ReversePdfs,
    heuristic: Heuristic,
) -> f32 {
    if s + t == 2 {
        return 1.0;
    }
    let power = |r: f32| match heuristic {
        Heuristic::Power => r * r,
        Heuristic::Balance => r,
    };
    let Endpoints { qs, pt, .. } = endpoints(light, camera, sampled, s, t);
    let cam_rev = |i: usize| {
        if i + 1 == t {
            rev.pt
        } else if i + 2 == t {
            rev.pt_minus
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
            rev.qs
        } else if i + 2 == s {
            rev.qs_minus
        } else {
            light[i].pdf_rev
        }
    };
    let light_fwd = |i: usize| if i + 1 == s { qs.map_or(0.0, |q| q.pdf_fwd) } else { light[i].pdf_fwd };
    let light_delta = |i: usize| if i + 1 == s { false } else { light[i].delta };
    let first = if s == 1 { qs } else { light.first() };
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
