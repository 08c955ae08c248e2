//! Camera and light subpaths by random walks (Veach 1997 §10.2; pbrt-v4 §13.3.3), generic over
//! the sampler so that BDPT and the primary-sample-space MCMC integrators share them. The camera
//! subpath continues the camera stream its caller started (after the film and lens samples); the
//! light subpath starts [`Stream::Light`].

use super::vertex::{Vertex, VertexKind, infinite_light_density, scene_sphere};
use crate::bsdf::TransportMode;
use crate::geometry::{Ray, spawn_ray};
use crate::math::Rgb;
use crate::medium::Flight;
use crate::sampler::{Sampler, Stream};
use crate::scene::Scene;

/// The start of a random walk: throughput, direction density, length limit and the medium
/// the first ray travels in.
struct Walk {
    beta: Rgb,
    pdf_dir: f32,
    bounces: usize,
    mode: TransportMode,
    medium: Option<u32>,
}

/// Surfaces that only bound media a walk may cross between two vertices (a guard against
/// degenerate geometry).
const MAX_CROSSINGS: u32 = 4096;

/// Extends `path` from its last vertex along `ray` for at most `walk.bounces` more vertices.
/// In a medium each ray's free flight is sampled first (two numbers, only there): a scattering
/// point becomes a medium vertex whose phase function is sampled exactly; a flight that gets
/// through reaches the surface with the flight's weight. Surfaces that only bound media are
/// crossed without a vertex, as pbrt-v4 skips them.
fn random_walk<S: Sampler>(
    scene: &Scene,
    mut ray: Ray,
    sampler: &mut S,
    walk: Walk,
    path: &mut Vec<Vertex>,
    rays: &mut u64,
) {
    let Walk { mut beta, pdf_dir, bounces, mode, mut medium } = walk;
    let mut pdf_fwd = pdf_dir;
    let (mut made, mut crossings) = (0, 0u32);
    while made < bounces {
        *rays += 1;
        // The previous vertex, by index: a vertex is large, so it is not copied.
        let prev = path.len().checked_sub(1).expect("a subpath starts at an endpoint");
        let hit = scene.intersect(&ray);
        if let Some(m) = medium {
            let t_max = hit.as_ref().map_or(f32::INFINITY, |it| it.t);
            let med = &scene.media[m as usize];
            match med.sample_flight(sampler.next_1d(), sampler.next_1d(), t_max) {
                Flight::Scatter { t, weight } => {
                    beta *= weight;
                    if !beta.is_finite() || beta.max_element() <= 0.0 {
                        return;
                    }
                    let p = ray.o + ray.d * t;
                    let mut v = Vertex::in_medium(p, -ray.d, m, beta);
                    v.pdf_fwd = path[prev].convert_density(pdf_fwd, &v);
                    path.push(v);
                    made += 1;
                    if made == bounces {
                        // The last vertex: a direction sampled here would go unused.
                        return;
                    }
                    // The phase function is sampled exactly (weight one) and is symmetric.
                    let (wi, pdf) = med.sample_phase(-ray.d, sampler.next_2d());
                    pdf_fwd = pdf;
                    let n = path.len();
                    path[n - 2].pdf_rev = path[n - 1].convert_density(pdf, &path[n - 2]);
                    ray = Ray::new(p, wi);
                    continue;
                }
                Flight::Through { weight } => {
                    beta *= weight;
                    if !beta.is_finite() || beta.max_element() <= 0.0 {
                        return;
                    }
                }
            }
        }
        let Some(it) = hit else {
            if mode == TransportMode::Radiance && !scene.infinite_lights.is_empty() {
                path.push(Vertex::escaped(&ray, scene, beta, pdf_fwd));
            }
            return;
        };
        if scene.has_media() && scene.is_interface(&it) {
            crossings += 1;
            if crossings > MAX_CROSSINGS {
                return;
            }
            medium = scene.medium_after(&it, ray.d, medium);
            ray = spawn_ray(it.surface.p, it.surface.ng, ray.d);
            continue;
        }
        let bsdf = scene.bsdf(&it);
        let s = it.surface;
        let mut v = Vertex {
            kind: VertexKind::Surface,
            p: s.p,
            ng: s.ng,
            ns: bsdf.frame.n,
            surface: Some(s),
            bsdf: Some(bsdf),
            wo: it.wo,
            beta,
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
            delta: false,
            light: scene.area_light(it.prim).map(|(i, _)| i),
            infinite: false,
            medium,
            interface: scene.medium_interface(&it),
        };
        v.pdf_fwd = path[prev].convert_density(pdf_fwd, &v);
        path.push(v);
        made += 1;
        if made == bounces {
            // The subpath is complete. A direction sampled at its last vertex would only set
            // the previous vertex's reverse density and this one's delta flag, and a connection
            // recomputes both at its endpoints (`mis::reverse_pdfs`), as pbrt-v4's walk, which
            // stops here too, does.
            return;
        }
        let uc = sampler.next_1d();
        let u = sampler.next_2d();
        let Some(bs) = bsdf.sample(it.wo, uc, u, mode) else { return };
        let cos = bs.wi.dot(bsdf.frame.n).abs();
        beta *= bs.f * (cos / bs.pdf);
        if mode == TransportMode::Importance {
            beta *= shading_normal_correction(it.wo, bs.wi, s.ng, bsdf.frame.n);
        }
        let mut pdf_rev = bsdf.pdf(bs.wi, it.wo);
        pdf_fwd = if bs.proportional { bsdf.pdf(it.wo, bs.wi) } else { bs.pdf };
        let n = path.len();
        if bs.delta {
            path[n - 1].delta = true;
            pdf_fwd = 0.0;
            pdf_rev = 0.0;
        }
        path[n - 2].pdf_rev = path[n - 1].convert_density(pdf_rev, &path[n - 2]);
        if !beta.is_finite() || beta.max_element() <= 0.0 {
            return;
        }
        medium = v.medium_towards(bs.wi);
        ray = spawn_ray(s.p, s.ng, bs.wi);
    }
}

/// Veach's correction for shading normals in adjoint transport (Veach 1997, §5.3).
pub(crate) fn shading_normal_correction(
    wo: crate::math::Vec3,
    wi: crate::math::Vec3,
    ng: crate::math::Vec3,
    ns: crate::math::Vec3,
) -> f32 {
    let denom = wo.dot(ng).abs() * wi.dot(ns).abs();
    if denom == 0.0 { 0.0 } else { wo.dot(ns).abs() * wi.dot(ng).abs() / denom }
}

/// The camera subpath through `ray` (at most `max_depth + 2` vertices, the camera included).
/// Numbers continue the camera stream the caller started (after the film and lens samples).
pub fn camera_subpath<S: Sampler>(
    scene: &Scene,
    ray: Ray,
    sampler: &mut S,
    max_depth: u32,
    path: &mut Vec<Vertex>,
    rays: &mut u64,
) {
    camera_subpath_vertices(scene, ray, sampler, max_depth as usize + 2, path, rays);
}

/// A camera subpath of at most `vertices` vertices (the camera included).
pub fn camera_subpath_vertices<S: Sampler>(
    scene: &Scene,
    ray: Ray,
    sampler: &mut S,
    vertices: usize,
    path: &mut Vec<Vertex>,
    rays: &mut u64,
) {
    path.clear();
    if vertices == 0 {
        return;
    }
    let (_, pdf_dir) = scene.camera.pdf_we(&ray);
    path.push(Vertex { medium: scene.camera_medium, ..Vertex::camera(ray.o, Rgb::ONE) });
    if pdf_dir > 0.0 && vertices > 1 {
        let walk = Walk {
            beta: Rgb::ONE,
            pdf_dir,
            bounces: vertices - 1,
            mode: TransportMode::Radiance,
            medium: scene.camera_medium,
        };
        random_walk(scene, ray, sampler, walk, path, rays);
    }
}

/// A light subpath (at most `max_depth + 1` vertices, the light included), from the light
/// stream.
pub fn light_subpath<S: Sampler>(
    scene: &Scene,
    sampler: &mut S,
    max_depth: u32,
    path: &mut Vec<Vertex>,
    rays: &mut u64,
) {
    light_subpath_vertices(scene, sampler, max_depth as usize + 1, path, rays);
}

/// A light subpath of at most `vertices` vertices (the light included), from the light stream.
pub fn light_subpath_vertices<S: Sampler>(
    scene: &Scene,
    sampler: &mut S,
    vertices: usize,
    path: &mut Vec<Vertex>,
    rays: &mut u64,
) {
    path.clear();
    if vertices == 0 {
        return;
    }
    sampler.start_stream(Stream::Light);
    let u_light = sampler.next_1d();
    let u_pos = sampler.next_2d();
    let u_dir = sampler.next_2d();
    let Some((index, pmf)) = scene.light_sampler.sample(u_light) else { return };
    let light = &scene.lights[index];
    let Some(e) = light.sample_le(&scene.geometry, scene_sphere(scene), u_pos, u_dir) else { return };
    let infinite = light.is_infinite() || light.is_delta_direction();
    let mut v0 = Vertex::light(
        index as u32,
        e.ray.o,
        if infinite { crate::math::Vec3::ZERO } else { e.n },
        e.le,
        pmf * e.pdf_pos,
        infinite,
    );
    if light.is_infinite() {
        v0.pdf_fwd = infinite_light_density(scene, e.ray.d);
    }
    v0.medium = scene.light_medium(index, e.n, e.ray.d);
    path.push(v0);
    let cos = if e.n == crate::math::Vec3::ZERO || infinite { 1.0 } else { e.n.dot(e.ray.d).abs() };
    let beta = e.le * (cos / (pmf * e.pdf_pos * e.pdf_dir));
    let walk =
        Walk { beta, pdf_dir: e.pdf_dir, bounces: vertices - 1, mode: TransportMode::Importance, medium: v0.medium };
    random_walk(scene, e.ray, sampler, walk, path, rays);
    // Positions on the emitting disk of an infinite light are planar: the first surface vertex's
    // density is the disk's, projected (pbrt-v4 §13.3.3).
    if infinite && path.len() > 1 {
        let w = e.ray.d;
        let v1 = &mut path[1];
        v1.pdf_fwd = e.pdf_pos * if v1.is_on_surface() { v1.ng.dot(w).abs() } else { 1.0 };
    }
}
