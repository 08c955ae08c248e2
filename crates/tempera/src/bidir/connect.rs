//! Evaluation of one bidirectional strategy `(s, t)`: `s` light-subpath vertices joined to `t`
//! camera-subpath vertices (Veach 1997 §10.2; pbrt-v4 §13.3.4). The result keeps the
//! unweighted contribution, its MIS weight, the raster position for `t = 1`, and the factors of
//! the connection (BSDF values at both connection vertices and the geometry term), so that a
//! caller can evaluate one strategy alone (MMLT) or re-evaluate it with other BSDFs.

use super::mis::{Heuristic, ReversePdfs, mis_weight_with, reverse_pdfs};
use super::vertex::{Vertex, VertexKind};
use crate::bsdf::TransportMode;
use crate::geometry::{Ray, spawn_ray_to};
use crate::math::{Rgb, Vec2, Vec3};
use crate::sampler::{Sampler, Stream};
use crate::scene::Scene;

/// One evaluated strategy.
#[derive(Clone, Copy, Debug)]
pub struct Connection {
    /// Unweighted contribution `f/p` of the path.
    pub l: Rgb,
    pub weight: f32,
    /// Raster position of the path (only for `t = 1`; otherwise the camera ray's pixel).
    pub raster: Option<Vec2>,
    /// BSDF (or emission) value at the light-side connection vertex towards the camera side.
    pub f_light: Rgb,
    /// BSDF value at the camera-side connection vertex towards the light side.
    pub f_camera: Rgb,
    /// Geometry term between the connection vertices (1 when no edge is created).
    pub g: f32,
    /// Reverse densities around the connection that entered the MIS weight.
    pub rev: ReversePdfs,
    /// `l` without the two connection factors: `l = base · f_light · f_camera` up to rounding
    /// (the segment's transmittance through media is part of it).
    pub base: Rgb,
    /// The endpoint sampled anew for `s = 1` (a light vertex) or `t = 1` (a camera vertex).
    pub sampled: Option<Vertex>,
}

/// Geometric coupling `|cos θ₀| |cos θ₁| / d²` with shading normals (zero when nothing
/// passes), and what light keeps between the two vertices.
fn geometry(scene: &Scene, a: &Vertex, b: &Vertex, rays: &mut u64) -> (f32, Rgb) {
    let (w, d2) = a.towards(b);
    if d2 == 0.0 || !d2.is_finite() {
        return (0.0, Rgb::ZERO);
    }
    let mut g = 1.0 / d2;
    if a.is_on_surface() {
        g *= a.ns.dot(w).abs();
    }
    if b.is_on_surface() {
        g *= b.ns.dot(w).abs();
    }
    if g == 0.0 {
        return (0.0, Rgb::ZERO);
    }
    let tr = transmittance(scene, a, b, rays);
    if tr.max_element() > 0.0 { (g, tr) } else { (0.0, Rgb::ZERO) }
}

/// What light keeps between `a` and `b`: one or zero (visibility) in a scene without media;
/// with media, the transmittance of every medium along the segment, through the surfaces that
/// only bound media, and zero when anything else blocks it. Counts the rays it traces.
fn transmittance(scene: &Scene, a: &Vertex, b: &Vertex, rays: &mut u64) -> Rgb {
    if !scene.has_media() {
        *rays += 1;
        return if visible(scene, a, b) { Rgb::ONE } else { Rgb::ZERO };
    }
    let (w, _) = a.towards(b);
    let ng = if a.is_on_surface() { a.ng } else { Vec3::ZERO };
    let (target, to_infinity) = if b.infinite { (w, true) } else { (b.p, false) };
    scene.transmittance(a.p, ng, target, to_infinity, a.medium_towards(w), rays)
}

fn visible(scene: &Scene, a: &Vertex, b: &Vertex) -> bool {
    let origin_normal = if a.is_on_surface() { a.ng } else { Vec3::ZERO };
    let (ray, t_max) = if origin_normal == Vec3::ZERO {
        let (w, d2) = a.towards(b);
        (Ray::new(a.p, w), d2.sqrt() * (1.0 - 1e-4))
    } else {
        spawn_ray_to(a.p, origin_normal, b.p)
    };
    let t_max = if b.infinite { f32::INFINITY } else { t_max - if b.is_on_surface() { 1e-4 } else { 0.0 } };
    !scene.occluded(&ray, t_max)
}

/// A light and a camera subpath.
#[derive(Clone, Copy, Debug)]
pub struct Subpaths<'a> {
    pub light: &'a [Vertex],
    pub camera: &'a [Vertex],
}

/// What joining the two subpaths of one strategy gives, before MIS: the unweighted value and
/// the pieces a tempered target re-evaluates.
struct Joined {
    l: Rgb,
    /// The vertex the strategy sampled (the camera for `t = 1`, the light for `s = 1`).
    sampled: Option<Vertex>,
    raster: Option<Vec2>,
    f_light: Rgb,
    f_camera: Rgb,
    g: f32,
    base: Rgb,
}

impl Joined {
    fn new(l: Rgb, base: Rgb) -> Self {
        Self { l, sampled: None, raster: None, f_light: Rgb::ONE, f_camera: Rgb::ONE, g: 1.0, base }
    }
}

/// `s = 0`: the camera subpath's last vertex is on an emitter.
fn hit_emitter(scene: &Scene, camera: &[Vertex], t: usize) -> Option<Joined> {
    let pt = &camera[t - 1];
    if !pt.is_light() {
        return None;
    }
    let f_light = pt.le(scene, &camera[t - 2]);
    Some(Joined { f_light, ..Joined::new(f_light * pt.beta, pt.beta) })
}

/// The value of joining subpath vertex `p` (BSDF value `f` towards the sampled endpoint `v`,
/// which lies along `w`) to `v`, and its part without the BSDF (`base`); `None` when occluded
/// (a shadow ray is traced only for a nonzero value).
fn reach(scene: &Scene, p: &Vertex, f: Rgb, v: &Vertex, w: Vec3, rays: &mut u64) -> Option<(Rgb, Rgb)> {
    let cos = if p.is_on_surface() { p.ns.dot(w).abs() } else { 1.0 };
    let mut base = p.beta * v.beta * cos;
    let mut l = p.beta * f * v.beta;
    if p.is_on_surface() {
        l *= cos;
    }
    if l.max_element() > 0.0 {
        let tr = transmittance(scene, p, v, rays);
        if tr.max_element() <= 0.0 {
            return None;
        }
        if scene.has_media() {
            l *= tr;
            base *= tr;
        }
    }
    Some((l, base))
}

/// `t = 1`: the light subpath's last vertex is connected to a point sampled on the lens.
fn reach_camera<S: Sampler>(scene: &Scene, qs: &Vertex, sampler: &mut S, rays: &mut u64) -> Option<Joined> {
    if !qs.connectible(scene) {
        return None;
    }
    sampler.start_stream(Stream::Connection);
    let u = scene.camera.lens_sample(sampler);
    let cs = scene.camera.sample_wi(qs.p, u)?;
    if cs.pdf.is_nan() || cs.pdf <= 0.0 || cs.importance.max_element() <= 0.0 {
        return None;
    }
    let mut v = Vertex::camera(cs.p_lens, cs.importance / cs.pdf);
    v.pdf_fwd = 0.0;
    let f_light = qs.f(scene, &v, TransportMode::Importance);
    let (l, base) = reach(scene, qs, f_light, &v, cs.wi, rays)?;
    Some(Joined { sampled: Some(v), raster: Some(cs.raster), f_light, ..Joined::new(l, base) })
}

/// `s = 1`: the camera subpath's last vertex is connected to a point sampled on a light.
fn reach_light<S: Sampler>(scene: &Scene, pt: &Vertex, sampler: &mut S, rays: &mut u64) -> Option<Joined> {
    if !pt.connectible(scene) {
        return None;
    }
    sampler.start_stream(Stream::Connection);
    let u_light = sampler.next_1d();
    let u = sampler.next_2d();
    let (index, pmf) = scene.light_sampler.sample(u_light)?;
    let light_ref = &scene.lights[index];
    let ls = light_ref.sample_li(&scene.geometry, pt.p, u)?;
    let infinite = light_ref.is_infinite() || light_ref.is_delta_direction();
    let mut v = Vertex::light(
        index as u32,
        ls.p,
        if infinite { Vec3::ZERO } else { ls.n },
        ls.li / (ls.pdf * pmf),
        0.0,
        infinite,
    );
    v.pdf_fwd = v.pdf_light_origin(scene, pt);
    let f_camera = pt.f(scene, &v, TransportMode::Radiance);
    let (l, base) = reach(scene, pt, f_camera, &v, ls.wi, rays)?;
    Some(Joined { sampled: Some(v), f_camera, ..Joined::new(l, base) })
}

/// `s, t > 1`: the two subpaths' last vertices are joined by a shadow ray.
fn join(scene: &Scene, qs: &Vertex, pt: &Vertex, rays: &mut u64) -> Option<Joined> {
    if !qs.connectible(scene) || !pt.connectible(scene) {
        return None;
    }
    let f_light = qs.f(scene, pt, TransportMode::Importance);
    let f_camera = pt.f(scene, qs, TransportMode::Radiance);
    let l = qs.beta * f_light * f_camera * pt.beta;
    if l.max_element() <= 0.0 {
        return None;
    }
    let (g, tr) = geometry(scene, qs, pt, rays);
    if !scene.has_media() {
        let base = qs.beta * pt.beta * g;
        return Some(Joined { f_light, f_camera, g, ..Joined::new(l * g, base) });
    }
    // The transmittance is part of the connection's base: roughening never changes it.
    let base = qs.beta * pt.beta * g * tr;
    Some(Joined { f_light, f_camera, g, ..Joined::new(l * g * tr, base) })
}

/// Evaluates strategy `(s, t)`. Numbers for sampling a new endpoint (`s = 1`, `t = 1`) come
/// from [`Stream::Connection`].
pub fn connect<S: Sampler>(
    scene: &Scene,
    paths: Subpaths,
    (s, t): (usize, usize),
    sampler: &mut S,
    heuristic: Heuristic,
    rays: &mut u64,
) -> Option<Connection> {
    let Subpaths { light, camera } = paths;
    // (1, 1) would see the light directly through light tracing: never a strategy here.
    if (s == 1 && t == 1) || t == 0 || (s > 1 && light.len() < s) || (t > 1 && camera.len() < t) || (s == 0 && t < 2) {
        return None;
    }
    if t > 1 && s != 0 && camera[t - 1].kind == VertexKind::Light {
        return None;
    }
    let joined = if s == 0 {
        hit_emitter(scene, camera, t)
    } else if t == 1 {
        reach_camera(scene, &light[s - 1], sampler, rays)
    } else if s == 1 {
        reach_light(scene, &camera[t - 1], sampler, rays)
    } else {
        join(scene, &light[s - 1], &camera[t - 1], rays)
    };
    let Joined { l, sampled, raster, f_light, f_camera, g, base } = joined?;
    if !l.is_finite() || l.max_element() <= 0.0 {
        return None;
    }
    let rev =
        if s + t == 2 { ReversePdfs::default() } else { reverse_pdfs(scene, light, camera, sampled.as_ref(), s, t) };
    let weight = mis_weight_with(scene, light, camera, sampled.as_ref(), (s, t), &rev, heuristic);
    Some(Connection { l, weight, raster, f_light, f_camera, g, rev, base, sampled })
}
