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
use crate::sampler::{IndependentSampler, Sampler};
use crate::scene::Scene;
use crate::texture::Image;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// The fraction of new photons kept per iteration (Hachisuka & Jensen's α).
const GAMMA: f64 = 2.0 / 3.0;

#[derive(Clone, Copy, Debug)]
pub struct SppmIntegrator {
    pub max_depth: u32,
    /// Photons per iteration (0: one per pixel, pbrt-v4's default).
    pub photons: u64,
    /// The initial search radius of every visible point, in scene units.
    pub radius: f32,
}

impl SppmIntegrator {
    pub fn new(max_depth: u32) -> Self {
        Self { max_depth, photons: 0, radius: 1.0 }
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

/// A hashed uniform grid over the visible points (pbrt-v3 §16.2.4): each point is entered in
/// every cell its search sphere overlaps; cells hash into as many buckets as there are points.
struct Grid {
    lo: Vec3,
    cell: Vec3,
    res: [i64; 3],
    /// Bucket `b`'s points are `entries[offsets[b]..offsets[b + 1]]`.
    offsets: Vec<u32>,
    entries: Vec<u32>,
}

impl Grid {
    fn build(points: &[Option<VisiblePoint>], pixels: &[PixelState]) -> Option<Grid> {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        let mut max_r = 0.0f32;
        let mut count = 0usize;
        for (vp, px) in points.iter().zip(pixels) {
            let Some(vp) = vp else { continue };
            let r = px.radius as f32;
            lo = lo.min(vp.p - Vec3::splat(r));
            hi = hi.max(vp.p + Vec3::splat(r));
            max_r = max_r.max(r);
            count += 1;
        }
        if count == 0 || !lo.is_finite() || !hi.is_finite() || max_r <= 0.0 {
            return None;
        }
        let diag = (hi - lo).max(Vec3::splat(1e-6));
        let max_diag = diag.max_element();
        // About one cell per search diameter along the longest side, at most 2^20 per axis.
        let base = (f64::from(max_diag) / f64::from(max_r)).clamp(1.0, f64::from(1u32 << 20));
        let res = [0, 1, 2].map(|i| ((base * f64::from(diag[i] / max_diag)) as i64).max(1));
        let cell = diag / Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32);
        let grid = Grid { lo, cell, res, offsets: Vec::new(), entries: Vec::new() };
        let buckets = count as u64;
        let mut pairs: Vec<(u32, u32)> = points
            .par_iter()
            .zip(pixels)
            .enumerate()
            .flat_map_iter(|(i, (vp, px))| {
                let mut out = Vec::new();
                if let Some(vp) = vp {
                    let r = px.radius as f32;
                    let (a, b) = (grid.cell_of(vp.p - Vec3::splat(r)), grid.cell_of(vp.p + Vec3::splat(r)));
                    for z in a[2]..=b[2] {
                        for y in a[1]..=b[1] {
                            for x in a[0]..=b[0] {
                                out.push((Grid::bucket([x, y, z], buckets), i as u32));
                            }
                        }
                    }
                }
                out
            })
            .collect();
        pairs.par_sort_unstable();
        // A point whose cells share a bucket is entered once.
        pairs.dedup();
        let mut offsets = vec![0u32; count + 1];
        for &(b, _) in &pairs {
            offsets[b as usize + 1] += 1;
        }
        for b in 0..count {
            offsets[b + 1] += offsets[b];
        }
        let entries = pairs.into_iter().map(|(_, i)| i).collect();
        Some(Grid { offsets, entries, ..grid })
    }

    fn cell_of(&self, p: Vec3) -> [i64; 3] {
        let c = (p - self.lo) / self.cell;
        [0, 1, 2].map(|i| (c[i].floor() as i64).clamp(0, self.res[i] - 1))
    }

    fn bucket(c: [i64; 3], buckets: u64) -> u32 {
        (hash(&[c[0] as u64, c[1] as u64, c[2] as u64]) % buckets) as u32
    }

    /// The visible points whose cells might hold `p`.
    fn near(&self, p: Vec3) -> &[u32] {
        let buckets = (self.offsets.len() - 1) as u64;
        let b = Grid::bucket(self.cell_of(p), buckets) as usize;
        &self.entries[self.offsets[b] as usize..self.offsets[b + 1] as usize]
    }
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

    /// Traces photon `j` of iteration `iteration`, adding to the visible points near each
    /// surface it reaches after the first; returns the rays traced.
    #[allow(clippy::too_many_arguments)]
    fn photon(
        &self,
        scene: &Scene,
        grid: &Grid,
        points: &[Option<VisiblePoint>],
        pixels: &[PixelState],
        (phi, counts): (&SharedSplats, &[AtomicU64]),
        seed: u64,
        (iteration, j): (u64, u64),
    ) -> u64 {
        let mut sampler = IndependentSampler::new(hash(&[seed, 0x9407, iteration, j]), 0x9407);
        let Some((index, pmf)) = scene.light_sampler.sample(sampler.next_1d()) else { return 0 };
        let (u_pos, u_dir) = (sampler.next_2d(), sampler.next_2d());
        let light = &scene.lights[index];
        let Some(e) = light.sample_le(&scene.geometry, scene_sphere(scene), u_pos, u_dir) else { return 0 };
        let infinite = light.is_infinite() || light.is_delta_direction();
        let cos = if e.n == Vec3::ZERO || infinite { 1.0 } else { e.n.dot(e.ray.d).abs() };
        let denom = pmf * e.pdf_pos * e.pdf_dir;
        if denom.is_nan() || denom <= 0.0 {
            return 0;
        }
        let mut beta = e.le * (cos / denom);
        let mut ray: Ray = e.ray;
        let width = scene.film.width as usize;
        let mut rays = 0;
        for depth in 0..self.max_depth {
            if !beta.is_finite() || beta.max_element() <= 0.0 {
                break;
            }
            rays += 1;
            let Some(it) = scene.intersect(&ray) else { break };
            let p = it.surface.p;
            if depth > 0 {
                let wi = -ray.d;
                for &i in grid.near(p) {
                    let i = i as usize;
                    let (Some(vp), px) = (&points[i], &pixels[i]) else { continue };
                    let r = px.radius as f32;
                    if (vp.p - p).length_squared() > r * r {
                        continue;
                    }
                    let f = vp.bsdf.eval(vp.wo, wi, TransportMode::Radiance);
                    let contribution = beta * f;
                    if contribution.max_element() > 0.0 {
                        let raster = Vec2::new((i % width) as f32 + 0.5, (i / width) as f32 + 0.5);
                        phi.add(raster, contribution);
                    }
                    counts[i].fetch_add(1, Ordering::Relaxed);
                }
            }
            let bsdf = scene.bsdf(&it);
            let (uc, u) = (sampler.next_1d(), sampler.next_2d());
            let Some(bs) = bsdf.sample(it.wo, uc, u, TransportMode::Importance) else { break };
            let correction =
                crate::bidir::subpath::shading_normal_correction(it.wo, bs.wi, it.surface.ng, bsdf.frame.n);
            let next = beta * bs.f * (bs.wi.dot(bsdf.frame.n).abs() / bs.pdf * correction);
            // Russian roulette on the throughput's change (pbrt-v4's photon pass).
            let survive = (next.max_element() / beta.max_element()).min(1.0);
            if survive.is_nan() || survive <= 0.0 || sampler.next_1d() >= survive {
                break;
            }
            beta = next / survive;
            ray = spawn_ray(p, it.surface.ng, bs.wi);
        }
        rays
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
        while iteration < max_iterations && !(iteration > 0 && render.should_stop()) && !render.cancelled() {
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
            let phi = SharedSplats::new(w, h);
            let counts: Vec<AtomicU64> = (0..n).map(|_| AtomicU64::new(0)).collect();
            let photon_rays: u64 = match Grid::build(&points, &pixels) {
                Some(grid) => (0..photons)
                    .into_par_iter()
                    .map(|j| self.photon(scene, &grid, &points, &pixels, (&phi, &counts), seed, (iteration, j)))
                    .sum(),
                None => 0,
            };
            // Progressive update.
            let phi = phi.image(1.0);
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
            snapshots.take(render, |seconds| RenderOutput {
                image: develop(&pixels, (w, h), iteration, photons),
                stats: RenderStats { spp_completed: iteration as u32, seconds, ..stats.clone() },
                layers: Vec::new(),
                chains: Vec::new(),
            });
        }
        stats.spp_completed = iteration.min(u64::from(u32::MAX)) as u32;
        render.finish(&mut stats);
        RenderOutput {
            image: develop(&pixels, (w, h), iteration, photons),
            stats,
            layers: Vec::new(),
            chains: Vec::new(),
        }
    }
}

#[cfg(test)]
#[path = "sppm_tests.rs"]
mod tests;
