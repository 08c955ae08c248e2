//! Stochastic progressive photon mapping (Hachisuka & Jensen 2009, "Stochastic progressive
//! photon mapping"; pbrt-v3 §16.2 and pbrt-v4's `sppm`, whose parameters it takes: `radius`,
//! `photonsperiteration`, `maxdepth`). Each iteration:
//!
//! 1. **Camera pass.** Every pixel traces one camera path (its film position drawn from the
//!    pixel filter) through specular and glossy surfaces to the first surface with a diffuse
//!    component, its *visible point*: emission seen directly or through specular bounces and
//!    direct light sampled at the non-specular vertices are added to the pixel's direct
//!    estimate (MIS between light and BSDF sampling at glossy vertices the path continues
//!    from; light sampling alone at the visible point, whose indirect light the photons carry).
//! 2. **Photon pass.** Photons leave the lights (chosen in proportion to power) and scatter by
//!    BSDF sampling with Russian roulette; at every surface after the first they add
//!    `β·f(ω_o, ω_i)` to each visible point within its radius (found through a hashed grid).
//! 3. **Update.** Per pixel with `M` new photons: `N' = N + γM` (`γ = 2/3`),
//!    `R' = R·sqrt(N'/(N + M))`, `τ' = (τ + β_vp·Φ)·R'²/R²`.
//!
//! The image is `L_direct / iterations + τ / (N_photons·π·R²)`. Every random number comes from a
//! hash of (seed, iteration, pixel or photon), and photon contributions add up in fixed point
//! ([`SharedSplats`]), so the image is the same at any thread count.

use super::path::PathIntegrator;
use super::render_loop::RenderLoop;
use super::{Budget, Integrator, RenderControl, RenderOutput, RenderSettings, RenderStats};
use crate::bidir::vertex::scene_sphere;
use crate::bsdf::{Bsdf, LayeredBase, SurfaceBsdf, TransportMode};
use crate::film::{Filter, SharedSplats};
use crate::geometry::{Ray, spawn_ray};
use crate::math::rng::hash;
use crate::math::{Rgb, Vec2, Vec3};
use crate::sampler::{IndependentSampler, Sampler, Stream};
use crate::scene::Scene;
use crate::texture::Image;
use grid::Grid;
use photon_chains::PhotonChains;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

mod grid;
mod photon_chains;

/// The fraction of new photons kept per iteration (Hachisuka & Jensen's α).
const GAMMA: f64 = 2.0 / 3.0;

/// How photon paths are sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum PhotonSampler {
    /// Independent photons from the lights (pbrt-v4's SPPM).
    #[default]
    Uniform,
    /// Markov chains whose target is the photon path's visibility, exchanging states with
    /// uniform photons.
    Mcmc,
}

/// Markov chains of the MCMC photon sampler (a fixed number, so that the image does not depend
/// on the thread count).
const PHOTON_CHAINS: usize = 64;

#[derive(Clone, Copy, Debug)]
pub struct SppmIntegrator {
    pub max_depth: u32,
    /// Photons per iteration (0: one per pixel, pbrt-v4's default).
    pub photons: u64,
    /// The initial search radius of every visible point, in scene units.
    pub radius: f32,
    pub photon_sampler: PhotonSampler,
}

impl SppmIntegrator {
    pub fn new(max_depth: u32) -> Self {
        Self { max_depth, photons: 0, radius: 1.0, photon_sampler: PhotonSampler::Uniform }
    }

    fn photons_per_iteration(&self, scene: &Scene) -> u64 {
        if self.photons > 0 { self.photons } else { u64::from(scene.film.width) * u64::from(scene.film.height) }
    }
}

/// Where a camera path ended on a surface with a diffuse component.
#[derive(Clone, Copy, Debug)]
struct VisiblePoint {
    p: Vec3,
    wo: Vec3,
    bsdf: SurfaceBsdf,
    beta: Rgb,
}

/// A pixel's progressive state.
#[derive(Clone, Copy, Debug)]
struct PixelState {
    /// Sum of the direct estimates over iterations.
    direct: [f64; 3],
    /// Accumulated flux, already scaled to the current radius.
    tau: [f64; 3],
    /// Photon count `N` (fractional).
    n: f64,
    radius: f64,
}

/// Surfaces where the camera path stops and density estimation takes over (pbrt's "diffuse"
/// flag): any BSDF with a diffuse lobe. Smooth and rough conductors and dielectrics are
/// specular or glossy: the path continues through them.
fn has_diffuse_lobe(bsdf: &Bsdf) -> bool {
    match bsdf {
        Bsdf::Diffuse(_) | Bsdf::DiffuseTransmission(_) | Bsdf::Plastic(_) => true,
        Bsdf::Layered(l) => matches!(l.base, LayeredBase::Diffuse(_)),
        Bsdf::Conductor(_) | Bsdf::Dielectric(_) => false,
    }
}

/// A film offset from the pixel centre distributed as the filter (rejection from its square;
/// every filter here peaks at the centre), so that a pixel's samples need no weights.
fn sample_filter<S: Sampler>(filter: &Filter, sampler: &mut S) -> Vec2 {
    let r = filter.radius();
    let peak = filter.eval(0.0, 0.0);
    for _ in 0..64 {
        let d = (sampler.next_2d() * 2.0 - Vec2::ONE) * r;
        if sampler.next_1d() * peak < filter.eval(d.x, d.y) {
            return d;
        }
    }
    Vec2::ZERO
}

impl SppmIntegrator {
    /// The camera pass of one pixel: its direct estimate, its visible point (if the path found
    /// one) and the rays traced.
    fn camera_path(&self, scene: &Scene, x: u32, y: u32, sampler: &mut IndependentSampler) -> CameraPath {
        let path = PathIntegrator::new(self.max_depth);
        let offset = sample_filter(&scene.film.filter, sampler);
        let raster = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) + offset;
        let mut ray = scene.camera.generate_ray(raster, sampler.next_2d());
        let mut out = CameraPath { direct: Rgb::ZERO, vp: None, rays: 1 };
        let mut beta = Rgb::ONE;
        let mut prev = path.first_vertex(ray.o);
        for depth in 0..=self.max_depth {
            if depth > 0 {
                out.rays += 1;
            }
            let Some(it) = scene.intersect(&ray) else {
                path.add_escaped(scene, ray.d, &prev, beta, &mut out.direct);
                break;
            };
            if let Some((le, w)) = path.emission(scene, &it, &prev) {
                out.direct += beta * le * w;
            }
            if depth == self.max_depth {
                break;
            }
            let bsdf = scene.bsdf(&it);
            let diffuse = has_diffuse_lobe(&bsdf.bsdf);
            let last = depth + 1 == self.max_depth;
            // Where the path stops (a diffuse lobe, or a glossy surface at the last bounce)
            // light sampling alone gives the direct light; elsewhere it shares with the BSDF
            // sample that continues the path.
            let stop = !bsdf.is_delta() && (diffuse || last);
            if !bsdf.is_delta() {
                out.direct += beta * path.sample_light(scene, &it, &bsdf, sampler, &mut out.rays, !stop);
            }
            if stop {
                out.vp = Some(VisiblePoint { p: it.surface.p, wo: it.wo, bsdf, beta });
                break;
            }
            let Some((wi, next)) = PathIntegrator::sample_bsdf(&it, &bsdf, sampler, &mut beta) else {
                break;
            };
            prev = next;
            ray = spawn_ray(it.surface.p, it.surface.ng, wi);
        }
        out
    }

    /// The uniform photon pass: photon `j` of iteration `iteration` from its own hashed
    /// numbers, straight into the sums. Returns the rays traced.
    fn uniform_photons(
        &self,
        scene: &Scene,
        targets: &Targets,
        sums: &PhotonSums,
        seed: u64,
        (iteration, photons): (u64, u64),
        owns: &(dyn Fn(usize) -> bool + Sync),
    ) -> u64 {
        (0..photons)
            .into_par_iter()
            .filter(|&j| owns(j as usize))
            .map(|j| {
                let mut sampler = IndependentSampler::new(hash(&[seed, 0x9407, iteration, j]), 0x9407);
                trace_photon(scene, self.max_depth, targets, &mut sampler, &mut |i, v| sums.add(i, v)).0
            })
            .sum()
    }
}

/// What a photon pass sees of the visible points: the grid over them, the points, and the
/// pixels' radii.
struct Targets<'a> {
    grid: &'a Grid,
    points: &'a [Option<VisiblePoint>],
    pixels: &'a [PixelState],
}

/// Traces one photon path with numbers from `sampler` (from its light stream), handing every
/// contribution `β·f` to a visible point within its radius to `deposit(pixel, value)`, at each
/// surface after the first. Returns the rays traced and whether the path reached any visible
/// point (its *visibility*, Hachisuka & Jensen 2011).
fn trace_photon<S: Sampler>(
    scene: &Scene,
    max_depth: u32,
    targets: &Targets,
    sampler: &mut S,
    deposit: &mut dyn FnMut(usize, Rgb),
) -> (u64, bool) {
    sampler.start_stream(Stream::Light);
    let Some((index, pmf)) = scene.light_sampler.sample(sampler.next_1d()) else { return (0, false) };
    let (u_pos, u_dir) = (sampler.next_2d(), sampler.next_2d());
    let light = &scene.lights[index];
    let Some(e) = light.sample_le(&scene.geometry, scene_sphere(scene), u_pos, u_dir) else { return (0, false) };
    let infinite = light.is_infinite() || light.is_delta_direction();
    let cos = if e.n == Vec3::ZERO || infinite { 1.0 } else { e.n.dot(e.ray.d).abs() };
    let denom = pmf * e.pdf_pos * e.pdf_dir;
    if denom.is_nan() || denom <= 0.0 {
        return (0, false);
    }
    let mut beta = e.le * (cos / denom);
    let mut ray: Ray = e.ray;
    let (mut rays, mut visible) = (0, false);
    for depth in 0..max_depth {
        if !beta.is_finite() || beta.max_element() <= 0.0 {
            break;
        }
        rays += 1;
        let Some(it) = scene.intersect(&ray) else { break };
        let p = it.surface.p;
        if depth > 0 {
            let wi = -ray.d;
            for &i in targets.grid.near(p) {
                let i = i as usize;
                let (Some(vp), px) = (&targets.points[i], &targets.pixels[i]) else { continue };
                let r = px.radius as f32;
                if (vp.p - p).length_squared() > r * r {
                    continue;
                }
                visible = true;
                deposit(i, beta * vp.bsdf.eval(vp.wo, wi, TransportMode::Radiance));
            }
        }
        let bsdf = scene.bsdf(&it);
        let (uc, u) = (sampler.next_1d(), sampler.next_2d());
        let Some(bs) = bsdf.sample(it.wo, uc, u, TransportMode::Importance) else { break };
        let correction = crate::bidir::subpath::shading_normal_correction(it.wo, bs.wi, it.surface.ng, bsdf.frame.n);
        let next = beta * bs.f * (bs.wi.dot(bsdf.frame.n).abs() / bs.pdf * correction);
        // Russian roulette on the throughput's change (pbrt-v4's photon pass).
        let survive = (next.max_element() / beta.max_element()).min(1.0);
        if survive.is_nan() || survive <= 0.0 || sampler.next_1d() >= survive {
            break;
        }
        beta = next / survive;
        ray = spawn_ray(p, it.surface.ng, bs.wi);
    }
    (rays, visible)
}

/// Photon sums of one iteration: `Φ` per pixel in fixed point and the photon count `M`.
struct PhotonSums {
    phi: SharedSplats,
    counts: Vec<AtomicU64>,
    width: usize,
}

impl PhotonSums {
    fn new(w: u32, h: u32) -> Self {
        let n = w as usize * h as usize;
        Self { phi: SharedSplats::new(w, h), counts: (0..n).map(|_| AtomicU64::new(0)).collect(), width: w as usize }
    }

    /// These sums added up over the ranks of `cluster` (integer sums: exact).
    fn summed(self, cluster: &dyn crate::cluster::Cluster) -> Self {
        let mut values = self.phi.values();
        let n = values.len();
        values.extend(self.counts.iter().map(|c| c.load(Ordering::Relaxed) as i64));
        cluster.sum(&mut values);
        let phi = SharedSplats::from_values(self.phi.width, self.phi.height, &values[..n]);
        let counts = values[n..].iter().map(|&c| AtomicU64::new(c as u64)).collect();
        Self { phi, counts, width: self.width }
    }

    /// Adds one photon's contribution to pixel `i`'s visible point.
    fn add(&self, i: usize, value: Rgb) {
        if value.max_element() > 0.0 {
            let raster = Vec2::new((i % self.width) as f32 + 0.5, (i / self.width) as f32 + 0.5);
            self.phi.add(raster, value);
        }
        self.counts[i].fetch_add(1, Ordering::Relaxed);
    }
}

struct CameraPath {
    direct: Rgb,
    vp: Option<VisiblePoint>,
    rays: u64,
}

/// The image of `iterations` finished iterations of `photons` photons each.
fn develop(pixels: &[PixelState], (w, h): (u32, u32), iterations: u64, photons: u64) -> Image {
    let its = iterations.max(1) as f64;
    let np = (iterations * photons).max(1) as f64;
    let values = pixels
        .iter()
        .map(|px| {
            let area = std::f64::consts::PI * px.radius * px.radius;
            let c = |k: usize| (px.direct[k] / its + if area > 0.0 { px.tau[k] / (np * area) } else { 0.0 }) as f32;
            Rgb::new(c(0), c(1), c(2))
        })
        .collect();
    Image::new(w as usize, h as usize, values)
}

impl Integrator for SppmIntegrator {
    fn name(&self) -> &'static str {
        "sppm"
    }

    fn render(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
    ) -> Result<RenderOutput, String> {
        if scene.has_media() {
            return Err("sppm does not render participating media; the path tracer and bdpt do".into());
        }
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return Err(format!("the SPPM radius must be positive, not {}", self.radius));
        }
        control.check_memory(self.memory_estimate(scene, settings.threads), "visible points and photon sums")?;
        let render = RenderLoop::new(settings, control);
        Ok(render.install(|| self.render_in_pool(&render, scene, settings)))
    }

    fn memory_estimate(&self, scene: &Scene, _threads: usize) -> u64 {
        let per_pixel = (std::mem::size_of::<VisiblePoint>()
            + std::mem::size_of::<PixelState>()
            + 8
            + super::memory::SHARED_SPLAT_BYTES as usize
            + 27 * 8) as u64;
        super::memory::pixels(scene).saturating_mul(per_pixel)
    }
}

impl SppmIntegrator {
    fn render_in_pool(&self, render: &RenderLoop, scene: &Scene, settings: &RenderSettings) -> RenderOutput {
        let (w, h) = (scene.film.width, scene.film.height);
        let n = w as usize * h as usize;
        let photons = self.photons_per_iteration(scene);
        let initial = PixelState { direct: [0.0; 3], tau: [0.0; 3], n: 0.0, radius: f64::from(self.radius) };
        let mut pixels = vec![initial; n];
        let mut points: Vec<Option<VisiblePoint>> = vec![None; n];
        let max_iterations = match settings.budget {
            Budget::Samples(s) => u64::from(s),
            Budget::Time(_) => u64::MAX,
        };
        let seed = settings.seed;
        let mut stats = RenderStats::default();
        let mut snapshots = render.snapshots(settings.budget);
        let mut iteration = 0u64;
        let mut visible_sum = 0.0;
        let mut chains = (self.photon_sampler == PhotonSampler::Mcmc)
            .then(|| PhotonChains::new(seed, PHOTON_CHAINS.min(photons.max(1) as usize)));
        let cluster = render.control.cluster;
        while iteration < max_iterations
            && !cluster.broadcast((iteration > 0 && render.should_stop()) || render.cancelled())
        {
            // Camera pass.
            let camera_rays: u64 = points
                .par_iter_mut()
                .zip(pixels.par_iter_mut())
                .enumerate()
                .map(|(i, (vp, px))| {
                    let (x, y) = ((i % w as usize) as u32, (i / w as usize) as u32);
                    let mut sampler = IndependentSampler::for_pixel_sample(seed ^ 0x5bb5, i as u64, iteration);
                    let cam = self.camera_path(scene, x, y, &mut sampler);
                    for (k, d) in px.direct.iter_mut().enumerate() {
                        *d += f64::from(cam.direct[k].max(0.0));
                    }
                    *vp = cam.vp;
                    cam.rays
                })
                .sum();
            // Photon pass.
            let sums = PhotonSums::new(w, h);
            // Every rank makes the same visible points and traces its share of the photons
            // (or runs its share of the chains); the sums are added up over the ranks.
            let owns = |j: usize| cluster.owns(j);
            let (photon_rays, visible, recorded) = match Grid::build(&points, &pixels) {
                Some(grid) => {
                    let targets = Targets { grid: &grid, points: &points, pixels: &pixels };
                    match &mut chains {
                        None => (self.uniform_photons(scene, &targets, &sums, seed, (iteration, photons), &owns), 0, 0),
                        Some(chains) => chains.run(scene, self.max_depth, (&targets, &sums), photons, &owns),
                    }
                }
                None => (0, 0, 0),
            };
            let sums = if cluster.is_distributed() { sums.summed(cluster) } else { sums };
            let mut counts = [visible as i64, recorded as i64];
            cluster.sum(&mut counts);
            // Uniform photons count whole; the chains' recorded photons are scaled to as many
            // uniform photons (`photons·V̄/recorded`, `V̄` the uniform photons' visible fraction).
            let scale = if chains.is_some() { counts[0] as f64 / counts[1].max(1) as f64 } else { 1.0 };
            visible_sum += counts[0] as f64 / photons.max(1) as f64;
            // Progressive update; the photon sums scaled to photons per iteration.
            let PhotonSums { phi, counts, .. } = sums;
            let phi = phi.image(scale);
            pixels.par_iter_mut().zip(&points).zip(&counts).zip(&phi.pixels).for_each(|(((px, vp), m), phi)| {
                let m = m.load(Ordering::Relaxed) as f64;
                let Some(vp) = vp else { return };
                if m <= 0.0 {
                    return;
                }
                let n_new = px.n + GAMMA * m;
                let r_new = px.radius * (n_new / (px.n + m)).sqrt();
                let shrink = (r_new * r_new) / (px.radius * px.radius);
                let flux = vp.beta * *phi;
                for k in 0..3 {
                    px.tau[k] = (px.tau[k] + f64::from(flux[k])) * shrink;
                }
                px.n = n_new;
                px.radius = r_new;
            });
            iteration += 1;
            stats.rays += camera_rays + photon_rays;
            stats.pixel_samples += n as u64;
            render.progress(n as u64);
            // Every rank holds the same pixel states: no exchange is needed for a snapshot.
            snapshots.take(render, |seconds| RenderOutput {
                image: develop(&pixels, (w, h), iteration, photons),
                stats: RenderStats { spp_completed: iteration as u32, seconds, ..stats.clone() },
                layers: Vec::new(),
                chains: Vec::new(),
            });
        }
        stats.spp_completed = iteration.min(u64::from(u32::MAX)) as u32;
        let mut rays = [stats.rays as i64];
        cluster.sum(&mut rays);
        stats.rays = rays[0] as u64;
        render.finish(&mut stats);
        // The chains' counts, added up over the ranks that ran them.
        let chains = chains
            .map(|c| {
                let mut d = c.stats(visible_sum / iteration.max(1) as f64);
                let mut counts = [
                    d.mutations,
                    d.large_steps_proposed,
                    d.large_steps_accepted,
                    d.small_steps_proposed,
                    d.small_steps_accepted,
                ]
                .map(|v| v as i64);
                cluster.sum(&mut counts);
                [
                    d.mutations,
                    d.large_steps_proposed,
                    d.large_steps_accepted,
                    d.small_steps_proposed,
                    d.small_steps_accepted,
                ] = counts.map(|v| v as u64);
                vec![d]
            })
            .unwrap_or_default();
        RenderOutput { image: develop(&pixels, (w, h), iteration, photons), stats, layers: Vec::new(), chains }
    }
}

#[cfg(test)]
mod tests;
