//! The tile driver for per-pixel estimators: the film is cut into tiles rendered in parallel
//! (rayon), each into its own `f64` buffer, merged in tile order after each pass, so the image
//! depends only on the seed and the number of samples, never on the thread count. Passes double
//! in size (1, 1, 2, 4, … samples per pixel) so that time budgets and Ctrl-C stop between
//! passes or, within a pass, between rows.

use super::{Budget, RenderControl, RenderOutput, RenderSettings, RenderStats};
use crate::camera::Camera;
use crate::film::{Film, Tile, TileBuffer};
use crate::geometry::Ray;
use crate::math::{Rgb, Vec2};
use crate::sampler::{IndependentSampler, Sampler, Stream};
use crate::scene::Scene;
use rayon::prelude::*;
use std::sync::atomic::Ordering;
use std::time::Instant;

const TILE_SIZE: u32 = 16;

/// Estimates the radiance arriving along a camera ray.
pub trait PixelEstimator: Sync {
    /// Radiance along `ray`; adds the rays it traces to `rays`.
    fn li<S: Sampler>(&self, scene: &Scene, ray: Ray, sampler: &mut S, rays: &mut u64) -> Rgb;
}

struct TileResult {
    buffer: TileBuffer,
    rays: u64,
    samples: u64,
    stopped: bool,
}

struct Pass<'a> {
    scene: &'a Scene,
    seed: u64,
    samples: std::ops::Range<u32>,
    /// Stop at this instant (never during the first pass, so every pixel gets a sample).
    deadline: Option<Instant>,
    control: &'a RenderControl<'a>,
}

impl Pass<'_> {
    fn should_stop(&self) -> bool {
        self.control.cancel.load(Ordering::Relaxed) || self.deadline.is_some_and(|d| Instant::now() >= d)
    }

    fn render_tile<E: PixelEstimator>(&self, estimator: &E, tile: Tile) -> TileResult {
        let film = &self.scene.film;
        let camera: &Camera = &self.scene.camera;
        let mut buffer = TileBuffer::new(film, tile);
        let (mut rays, mut samples, mut stopped) = (0u64, 0u64, false);
        for y in tile.y0..tile.y1 {
            if self.should_stop() {
                stopped = true;
                break;
            }
            for x in tile.x0..tile.x1 {
                let pixel = u64::from(y) * u64::from(film.width) + u64::from(x);
                for s in self.samples.clone() {
                    let mut sampler = IndependentSampler::for_pixel_sample(self.seed, pixel, u64::from(s));
                    sampler.start_stream(Stream::Camera);
                    let film_u = sampler.next_2d();
                    let lens_u = sampler.next_2d();
                    let raster = Vec2::new(x as f32 + film_u.x, y as f32 + film_u.y);
                    let ray = camera.generate_ray(raster, lens_u);
                    let l = estimator.li(self.scene, ray, &mut sampler, &mut rays);
                    buffer.add_sample(raster, l);
                    samples += 1;
                }
            }
            (self.control.on_progress)(u64::from(tile.x1 - tile.x0) * self.samples.len() as u64);
        }
        TileResult { buffer, rays, samples, stopped }
    }
}

/// Renders `scene` with `estimator` under `settings`.
pub fn render_tiles<E: PixelEstimator>(
    estimator: &E,
    scene: &Scene,
    settings: &RenderSettings,
    control: &RenderControl,
) -> RenderOutput {
    let start = Instant::now();
    let tiles = scene.film.tiles(TILE_SIZE);
    let mut film = Film::new(scene.film);
    let mut stats = RenderStats::default();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(settings.threads)
        .build()
        .expect("a rayon thread pool can be created");
    let (max_spp, deadline) = match settings.budget {
        Budget::Samples(n) => (n, None),
        Budget::Time(d) => (u32::MAX, Some(start + d)),
    };
    let mut done = 0u32;
    while done < max_spp {
        let size = done.max(1).min(max_spp - done);
        let pass = Pass {
            scene,
            seed: settings.seed,
            samples: done..done + size,
            deadline: if done == 0 { None } else { deadline },
            control,
        };
        if control.cancel.load(Ordering::Relaxed) || pass.deadline.is_some_and(|d| Instant::now() >= d) {
            break;
        }
        let results: Vec<TileResult> =
            pool.install(|| tiles.par_iter().map(|&t| pass.render_tile(estimator, t)).collect());
        let mut stopped = false;
        for r in &results {
            film.merge(&r.buffer);
            stats.rays += r.rays;
            stats.pixel_samples += r.samples;
            stopped |= r.stopped;
        }
        if stopped {
            break;
        }
        done += size;
    }
    stats.spp_completed = done;
    stats.invalid_samples = film.invalid_samples;
    stats.cancelled = control.cancel.load(Ordering::Relaxed);
    stats.seconds = start.elapsed().as_secs_f64();
    RenderOutput { image: film.develop(), stats }
}
