//! Unidirectional path tracing with next-event estimation and BSDF sampling combined by the
//! power heuristic, and Russian roulette after a few bounces (Veach 1997 §9; pbrt-v4 §13.4).
//! `max_depth` counts scattering events as pbrt does: 0 shows emitters only, 1 adds direct light.

use super::tiles::{PixelEstimator, SampleCtx, render_tiles};
use super::{Integrator, RenderControl, RenderOutput, RenderSettings};
use crate::bsdf::{SurfaceBsdf, TransportMode};
use crate::geometry::{Ray, spawn_ray, spawn_ray_to};
use crate::math::{Rgb, Vec3, power_heuristic};
use crate::sampler::{Sampler, Stream};
use crate::scene::{Interaction, Scene};

/// Russian roulette starts after this many scattering events.
const RR_DEPTH: u32 = 3;

#[derive(Clone, Copy, Debug)]
pub struct PathIntegrator {
    pub max_depth: u32,
    /// Sample lights at every vertex (next-event estimation) and weight by MIS. Without it, only
    /// BSDF sampling finds light: an independent estimator used to validate the MIS weights.
    pub next_event: bool,
}

impl PathIntegrator {
    pub fn new(max_depth: u32) -> Self {
        Self { max_depth, next_event: true }
    }
}

impl PathIntegrator {
    /// Direct light at `it` by light sampling, MIS-weighted against BSDF sampling when `mis`
    /// (else the whole of it: where no BSDF sample will look for emitters).
    pub(crate) fn sample_light<S: Sampler>(
        &self,
        scene: &Scene,
        it: &Interaction,
        bsdf: &SurfaceBsdf,
        sampler: &mut S,
        rays: &mut u64,
        mis: bool,
    ) -> Rgb {
        let u_light = sampler.next_1d();
        let u = sampler.next_2d();
        let Some((index, pmf)) = scene.light_sampler.sample(u_light) else {
            return Rgb::ZERO;
        };
        let light = &scene.lights[index];
        let p = it.surface.p;
        let Some(ls) = light.sample_li(&scene.geometry, p, u) else {
            return Rgb::ZERO;
        };
        let f = bsdf.eval(it.wo, ls.wi, TransportMode::Radiance) * ls.wi.dot(bsdf.frame.n).abs();
        if f.max_element() <= 0.0 {
            return Rgb::ZERO;
        }
        *rays += 1;
        let blocked = if ls.dist.is_finite() {
            let (ray, t_max) = spawn_ray_to(p, it.surface.ng, ls.p);
            scene.occluded(&ray, t_max)
        } else {
            scene.occluded(&spawn_ray(p, it.surface.ng, ls.wi), f32::INFINITY)
        };
        if blocked {
            return Rgb::ZERO;
        }
        let light_pdf = pmf * ls.pdf;
        if ls.delta || !mis {
            return f * ls.li / light_pdf;
        }
        let w = power_heuristic(light_pdf, bsdf.pdf(it.wo, ls.wi));
        f * ls.li * (w / light_pdf)
    }
}

impl PathIntegrator {
    /// Direct light at `p` by light sampling through participating media, MIS-weighted against
    /// sampling the scattering function: `scatter(wi)` gives its value times the cosine (one
    /// for a phase function) and its density; `ng` is the surface's normal (zero in a medium)
    /// and `medium_towards(wi)` the medium a ray leaving along `wi` starts in.
    #[allow(clippy::too_many_arguments)]
    fn sample_light_through_media<S: Sampler>(
        &self,
        scene: &Scene,
        p: Vec3,
        ng: Vec3,
        scatter: impl Fn(Vec3) -> (Rgb, f32),
        medium_towards: impl Fn(Vec3) -> Option<u32>,
        sampler: &mut S,
        rays: &mut u64,
    ) -> Rgb {
        let u_light = sampler.next_1d();
        let u = sampler.next_2d();
        let Some((index, pmf)) = scene.light_sampler.sample(u_light) else {
            return Rgb::ZERO;
        };
        let Some(ls) = scene.lights[index].sample_li(&scene.geometry, p, u) else {
            return Rgb::ZERO;
        };
        let (f, scatter_pdf) = scatter(ls.wi);
        if f.max_element() <= 0.0 {
            return Rgb::ZERO;
        }
        let to_infinity = !ls.dist.is_finite();
        let target = if to_infinity { ls.wi } else { ls.p };
        let tr = scene.transmittance(p, ng, target, to_infinity, medium_towards(ls.wi), rays);
        if tr.max_element() <= 0.0 {
            return Rgb::ZERO;
        }
        let light_pdf = pmf * ls.pdf;
        let w = if ls.delta { 1.0 } else { power_heuristic(light_pdf, scatter_pdf) };
        f * tr * ls.li * (w / light_pdf)
    }

    /// [`PixelEstimator::li`] in a scene with homogeneous participating media (pbrt-v4's
    /// `volpath` for them): free flights sampled per channel ([`crate::medium::Medium::sample_flight`]),
    /// scattering in media counted as a bounce, next-event estimation through media and
    /// interface surfaces (their transmittance), and surfaces that only bound media crossed
    /// without a bounce.
    fn li_media<S: Sampler>(&self, scene: &Scene, mut ray: Ray, sampler: &mut S, rays: &mut u64) -> Rgb {
        use crate::medium::Flight;
        let mut l = Rgb::ZERO;
        let mut beta = Rgb::ONE;
        let mut prev = PrevVertex { p: ray.o, bsdf_pdf: 0.0, specular: true };
        let mut depth = 0u32;
        let mut medium = scene.camera_medium;
        let mut crossings = 0u32;
        loop {
            *rays += 1;
            let hit = scene.intersect(&ray);
            if let Some(m) = medium {
                let t_max = hit.as_ref().map_or(f32::INFINITY, |it| it.t);
                let med = &scene.media[m as usize];
                match med.sample_flight(sampler.next_1d(), sampler.next_1d(), t_max) {
                    Flight::Scatter { t, weight } => {
                        beta *= weight;
                        if !beta.is_finite() || beta.max_element() <= 0.0 || depth == self.max_depth {
                            break;
                        }
                        depth += 1;
                        let p = ray.o + ray.d * t;
                        let wo = -ray.d;
                        if self.next_event {
                            let phase = |wi: Vec3| {
                                let f = med.phase(wo, wi);
                                (Rgb::splat(f), f)
                            };
                            l += beta
                                * self.sample_light_through_media(
                                    scene,
                                    p,
                                    Vec3::ZERO,
                                    phase,
                                    |_| medium,
                                    sampler,
                                    rays,
                                );
                        }
                        // The phase function is sampled exactly: its weight is one.
                        let (wi, pdf) = med.sample_phase(wo, sampler.next_2d());
                        prev = PrevVertex { p, bsdf_pdf: pdf, specular: false };
                        ray = Ray::new(p, wi);
                        if !self.roulette(&mut beta, depth, sampler) {
                            break;
                        }
                        continue;
                    }
                    Flight::Through { weight } => {
                        beta *= weight;
                        if !beta.is_finite() || beta.max_element() <= 0.0 {
                            break;
                        }
                    }
                }
            }
            let Some(it) = hit else {
                self.add_escaped(scene, ray.d, &prev, beta, &mut l);
                break;
            };
            if scene.is_interface(&it) {
                crossings += 1;
                if crossings > 4096 {
                    break;
                }
                medium = scene.medium_after(&it, ray.d, medium);
                ray = spawn_ray(it.surface.p, it.surface.ng, ray.d);
                continue;
            }
            if let Some((le, w)) = self.emission(scene, &it, &prev) {
                l += beta * le * w;
            }
            if depth == self.max_depth {
                break;
            }
            depth += 1;
            let bsdf = scene.bsdf(&it);
            if self.next_event && !bsdf.is_delta() {
                let surface = |wi: Vec3| {
                    let f = bsdf.eval(it.wo, wi, TransportMode::Radiance) * wi.dot(bsdf.frame.n).abs();
                    (f, bsdf.pdf(it.wo, wi))
                };
                let towards = |wi: Vec3| scene.medium_after(&it, wi, medium);
                l += beta
                    * self.sample_light_through_media(
                        scene,
                        it.surface.p,
                        it.surface.ng,
                        surface,
                        towards,
                        sampler,
                        rays,
                    );
            }
            let Some((wi, next)) = Self::sample_bsdf(&it, &bsdf, sampler, &mut beta) else {
                break;
            };
            prev = next;
            medium = scene.medium_after(&it, wi, medium);
            ray = spawn_ray(it.surface.p, it.surface.ng, wi);
            if !self.roulette(&mut beta, depth, sampler) {
                break;
            }
        }
        l
    }

    /// Adds the environment lights seen along `d` by a path that escaped, MIS-weighted against
    /// having sampled them from the previous vertex (which next-event estimation did only when
    /// it is on and that vertex was not specular).
    pub(crate) fn add_escaped(&self, scene: &Scene, d: Vec3, prev: &PrevVertex, beta: Rgb, l: &mut Rgb) {
        for &i in &scene.infinite_lights {
            let light = &scene.lights[i as usize];
            let w = if prev.specular || !self.next_event {
                1.0
            } else {
                power_heuristic(prev.bsdf_pdf, scene.light_sampler.pmf(i as usize) * light.pdf_li_dir(d))
            };
            *l += beta * light.le(d) * w;
        }
    }

    /// Samples the BSDF to continue the path: multiplies `beta` by the sample's weight and
    /// returns the new direction with what MIS needs of this vertex, or `None` when the path
    /// ends (no sample, or no throughput left).
    pub(crate) fn sample_bsdf<S: Sampler>(
        it: &Interaction,
        bsdf: &SurfaceBsdf,
        sampler: &mut S,
        beta: &mut Rgb,
    ) -> Option<(Vec3, PrevVertex)> {
        let uc = sampler.next_1d();
        let u = sampler.next_2d();
        let bs = bsdf.sample(it.wo, uc, u, TransportMode::Radiance)?;
        *beta *= bs.f * (bs.wi.dot(bsdf.frame.n).abs() / bs.pdf);
        if !beta.is_finite() || beta.max_element() <= 0.0 {
            return None;
        }
        let bsdf_pdf = if bs.proportional { bsdf.pdf(it.wo, bs.wi) } else { bs.pdf };
        Some((bs.wi, PrevVertex { p: it.surface.p, bsdf_pdf, specular: bs.delta }))
    }

    /// Russian roulette after [`RR_DEPTH`] bounces: false when the path ends, else the
    /// throughput is divided by the survival probability.
    fn roulette<S: Sampler>(&self, beta: &mut Rgb, depth: u32, sampler: &mut S) -> bool {
        if depth > RR_DEPTH {
            let q = (1.0 - beta.max_element()).max(0.0);
            if sampler.next_1d() < q {
                return false;
            }
            *beta /= 1.0 - q;
        }
        true
    }
}

impl PathIntegrator {
    /// Emission of the hit surface towards the path and its MIS weight against having
    /// sampled the light from the previous vertex; `None` where the surface does not emit.
    pub(crate) fn emission(&self, scene: &Scene, it: &Interaction, prev: &PrevVertex) -> Option<(Rgb, f32)> {
        let (index, light) = scene.area_light(it.prim)?;
        let le = scene.emitted(it);
        if le.max_element() <= 0.0 {
            return None;
        }
        let w = if prev.specular || !self.next_event {
            1.0
        } else {
            let light_pdf =
                scene.light_sampler.pmf(index as usize) * light.pdf_li_area(&scene.geometry, prev.p, &it.surface);
            power_heuristic(prev.bsdf_pdf, light_pdf)
        };
        Some((le, w))
    }
}

/// State carried from one vertex to the next for MIS of emission found by BSDF sampling.
pub(crate) struct PrevVertex {
    p: Vec3,
    bsdf_pdf: f32,
    specular: bool,
}

impl PathIntegrator {
    /// What MIS needs of the camera before the first bounce (emission seen directly counts
    /// whole).
    pub(crate) fn first_vertex(&self, p: Vec3) -> PrevVertex {
        PrevVertex { p, bsdf_pdf: 0.0, specular: true }
    }
}

impl PixelEstimator for PathIntegrator {
    fn li<S: Sampler>(&self, scene: &Scene, mut ray: Ray, sampler: &mut S, ctx: &mut SampleCtx) -> Rgb {
        let rays = &mut ctx.rays;
        sampler.start_stream(Stream::Camera);
        if scene.has_media() {
            return self.li_media(scene, ray, sampler, rays);
        }
        let mut l = Rgb::ZERO;
        let mut beta = Rgb::ONE;
        let mut prev = PrevVertex { p: ray.o, bsdf_pdf: 0.0, specular: true };
        let mut depth = 0u32;
        loop {
            if depth > 0 {
                *rays += 1;
            }
            let Some(it) = scene.intersect(&ray) else {
                self.add_escaped(scene, ray.d, &prev, beta, &mut l);
                break;
            };
            if let Some((le, w)) = self.emission(scene, &it, &prev) {
                l += beta * le * w;
            }
            if depth == self.max_depth {
                break;
            }
            depth += 1;
            let bsdf = scene.bsdf(&it);
            if self.next_event && !bsdf.is_delta() {
                l += beta * self.sample_light(scene, &it, &bsdf, sampler, rays, true);
            }
            let Some((wi, next)) = Self::sample_bsdf(&it, &bsdf, sampler, &mut beta) else {
                break;
            };
            prev = next;
            ray = spawn_ray(it.surface.p, it.surface.ng, wi);
            if !self.roulette(&mut beta, depth, sampler) {
                break;
            }
        }
        l
    }
}

impl Integrator for PathIntegrator {
    fn name(&self) -> &'static str {
        "path"
    }

    fn render(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
    ) -> Result<RenderOutput, String> {
        control.check_memory(self.memory_estimate(scene, settings.threads), "the film")?;
        Ok(render_tiles(self, scene, settings, control))
    }

    fn memory_estimate(&self, scene: &Scene, _threads: usize) -> u64 {
        super::memory::pixels(scene).saturating_mul(super::memory::FILM_BYTES)
    }
}
