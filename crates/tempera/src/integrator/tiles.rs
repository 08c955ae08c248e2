//! The tile driver for per-pixel estimators: the film is cut into tiles rendered in parallel
//! (rayon), each into its own `f64` buffer, merged in tile order after each pass; contributions
//! that land on other pixels (light tracing) go to per-thread fixed-point splat buffers whose
//! merge is order-independent. The image therefore depends only on the seed and the number of
//! samples, never on the thread count. Passes double in size (1, 1, 2, 4, … samples per pixel)
//! so that time budgets and Ctrl-C stop between passes or, within a pass, between rows. A pass
//! stopped for a snapshot resumes where each tile stopped.

use super::render_loop::RenderLoop;
use super::{Budget, RenderControl, RenderOutput, RenderSettings, RenderStats};
use crate::bidir::Paths;
use crate::camera::Camera;
use crate::cluster::{Cluster, Reader, Wire};
use crate::film::{Film, SplatBuffer, Tile, TileBuffer};
use crate::geometry::Ray;
use crate::math::{Rgb, Vec2};
use crate::sampler::{IndependentSampler, Sampler, Stream};
use crate::scene::Scene;
use crate::texture::Image;
use rayon::prelude::*;
use std::sync::Mutex;
use std::time::Instant;

const TILE_SIZE: u32 = 16;

/// Per-thread state a sample may use: ray counting, a splat buffer and extra image layers.
pub struct SampleCtx<'a> {
    pub rays: u64,
    /// Raster position of the sample's camera ray.
    pub raster: Vec2,
    /// Contributions to other pixels; scaled by 1/spp when the image is developed.
    pub splats: &'a mut SplatBuffer,
    /// Extra images (for example one per BDPT strategy), developed like the splats.
    pub layers: &'a mut [SplatBuffer],
    /// Subpath storage reused from sample to sample (bidirectional estimators).
    pub paths: &'a mut Paths,
}

/// A worker thread's splat buffer, extra layers and subpath storage.
struct ThreadBuffers {
    splats: SplatBuffer,
    layers: Vec<SplatBuffer>,
    paths: Paths,
}

type Size = (u32, u32);

impl ThreadBuffers {
    fn new(splats: &SplatBuffer, layers: usize, (fw, fh): Size) -> Self {
        let layers = (0..layers).map(|_| SplatBuffer::new(fw, fh)).collect();
        ThreadBuffers { splats: splats.cleared(), layers, paths: Paths::default() }
    }

    /// One set of buffers per worker thread: splats like `splats` (empty for estimators that
    /// do not splat) and `layers` film-size layers.
    fn per_thread(threads: usize, splats: &SplatBuffer, layers: usize, film: Size) -> Vec<Mutex<ThreadBuffers>> {
        (0..threads).map(|_| Mutex::new(Self::new(splats, layers, film))).collect()
    }

    /// The threads' buffers summed (fixed point: in any order).
    fn merged(all: Vec<Mutex<ThreadBuffers>>, splats: &SplatBuffer, layers: usize, film: Size) -> ThreadBuffers {
        let mut total = Self::new(splats, layers, film);
        for buffers in all {
            let buffers = buffers.into_inner().unwrap_or_else(std::sync::PoisonError::into_inner);
            total.splats.merge(&buffers.splats);
            for (sum, layer) in total.layers.iter_mut().zip(&buffers.layers) {
                sum.merge(layer);
            }
        }
        total
    }
}

/// Estimates the radiance arriving along a camera ray.
pub trait PixelEstimator: Sync {
    /// True when the estimator splats onto other pixels (a full-size splat buffer per thread).
    const SPLATS: bool = false;
    /// Number of extra image layers the estimator fills (each a full-size buffer per thread).
    fn layers(&self) -> usize {
        0
    }
    /// Radiance along `ray` through raster position `raster`.
    fn li<S: Sampler>(&self, scene: &Scene, ray: Ray, sampler: &mut S, ctx: &mut SampleCtx) -> Rgb;
}

struct TileResult {
    buffer: TileBuffer,
    samples: u64,
    rays: u64,
    /// The first row of the tile this pass has not rendered (the tile's end when it is done).
    next_row: u32,
}

struct Pass<'a> {
    scene: &'a Scene,
    seed: u64,
    samples: std::ops::Range<u32>,
    /// Stop at this instant (never during the first pass, so every pixel gets a sample).
    stop_at: Option<Instant>,
    render: &'a RenderLoop<'a>,
    /// Per tile, the row this pass starts at (after a snapshot interrupted it).
    resume: &'a [u32],
}

impl Pass<'_> {
    /// Renders every tile in parallel. One splat buffer per worker thread, locked once per
    /// tile (never per sample); the fixed-point sums make the merge order irrelevant.
    fn run<E: PixelEstimator>(
        &self,
        estimator: &E,
        tiles: &[Tile],
        buffers: &[Mutex<ThreadBuffers>],
        cluster: &dyn Cluster,
    ) -> Vec<(usize, TileResult)> {
        tiles
            .par_iter()
            .copied()
            .enumerate()
            .filter(|(i, _)| cluster.owns(*i))
            .map(|t| {
                let index = rayon::current_thread_index().unwrap_or(0) % buffers.len();
                let mut buffers = buffers[index].lock().unwrap_or_else(std::sync::PoisonError::into_inner);
                (t.0, self.render_tile(estimator, t, &mut buffers))
            })
            .collect()
    }

    fn should_stop(&self) -> bool {
        self.render.cancelled() || self.stop_at.is_some_and(|d| Instant::now() >= d)
    }

    fn render_tile<E: PixelEstimator>(
        &self,
        estimator: &E,
        (index, tile): (usize, Tile),
        buffers: &mut ThreadBuffers,
    ) -> TileResult {
        let film = &self.scene.film;
        let camera: &Camera = &self.scene.camera;
        let mut buffer = TileBuffer::new(film, tile);
        let mut samples = 0u64;
        let ThreadBuffers { splats, layers, paths } = buffers;
        let mut ctx = SampleCtx { rays: 0, raster: Vec2::ZERO, splats, layers, paths };
        let first_row = self.resume[index];
        let mut next_row = first_row;
        for y in first_row..tile.y1 {
            if self.should_stop() {
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
                    ctx.rays += 1;
                    ctx.raster = raster;
                    let l = estimator.li(self.scene, ray, &mut sampler, &mut ctx);
                    buffer.add_sample(raster, l);
                    samples += 1;
                }
            }
            self.render.progress(u64::from(tile.x1 - tile.x0) * self.samples.len() as u64);
            next_row = y + 1;
        }
        TileResult { buffer, samples, rays: ctx.rays, next_row }
    }
}

/// Every rank's tile results at rank 0, in tile order; the other ranks keep their own.
fn exchange_tiles(
    cluster: &dyn Cluster,
    film: &crate::film::FilmDesc,
    own: Vec<(usize, TileResult)>,
) -> Vec<(usize, TileResult)> {
    let mut w = Wire::default();
    w.u64(own.len() as u64);
    for (i, r) in &own {
        w.u64(*i as u64).u64(r.samples).u64(r.rays).u64(u64::from(r.next_row));
        r.buffer.encode(&mut w);
    }
    let all = cluster.gather(w.bytes);
    if !cluster.is_root() {
        return own;
    }
    let mut results: Vec<(usize, TileResult)> = Vec::new();
    for bytes in &all {
        let mut r = Reader::new(bytes);
        for _ in 0..r.u64() {
            let (i, samples, rays, next_row) = (r.u64() as usize, r.u64(), r.u64(), r.u64() as u32);
            let buffer = TileBuffer::decode(film, &mut r);
            results.push((i, TileResult { buffer, samples, rays, next_row }));
        }
    }
    results.sort_by_key(|(i, _)| *i);
    results
}

/// The threads' light-tracing splats so far, summed over the ranks at rank 0.
fn merged_splats(cluster: &dyn Cluster, buffers: &[Mutex<ThreadBuffers>], empty: &SplatBuffer) -> SplatBuffer {
    let mut splats = empty.cleared();
    for buffers in buffers {
        splats.merge(&buffers.lock().unwrap_or_else(std::sync::PoisonError::into_inner).splats);
    }
    sum_at_root(cluster, std::slice::from_mut(&mut splats));
    splats
}

/// Adds every other rank's `buffers` to rank 0's (fixed point: exact in any order).
fn sum_at_root(cluster: &dyn Cluster, buffers: &mut [SplatBuffer]) {
    if !cluster.is_distributed() {
        return;
    }
    let mut w = Wire::default();
    for b in buffers.iter() {
        b.encode(&mut w);
    }
    for bytes in cluster.gather(w.bytes).iter().skip(1) {
        let mut r = Reader::new(bytes);
        for b in buffers.iter_mut() {
            b.merge_encoded(&mut r);
        }
    }
}

/// The image of `film` plus the splats so far, which estimate the image per sample.
fn develop(film: &Film, splats: &SplatBuffer, splatting: bool, pixel_samples: u64) -> Image {
    let mut image = film.develop();
    let (fw, fh) = (film.desc.width, film.desc.height);
    let per_sample = f64::from(fw) * f64::from(fh) / (pixel_samples.max(1) as f64);
    if splatting && pixel_samples > 0 {
        let splat = splats.image(per_sample);
        for (p, s) in image.pixels.iter_mut().zip(&splat.pixels) {
            *p += *s;
        }
    }
    image
}

/// Renders `scene` with `estimator` under `settings`.
pub fn render_tiles<E: PixelEstimator>(
    estimator: &E,
    scene: &Scene,
    settings: &RenderSettings,
    control: &RenderControl,
) -> RenderOutput {
    let render = RenderLoop::new(settings, control);
    let cluster = control.cluster;
    let tiles = scene.film.tiles(TILE_SIZE);
    let mut film = Film::new(scene.film);
    // Light-tracing splats go through the film's filter, as the camera samples do.
    let empty_splats = if E::SPLATS {
        SplatBuffer::filtered(&crate::film::Footprint::of(&scene.film))
    } else {
        SplatBuffer::new(0, 0)
    };
    let mut stats = RenderStats::default();
    let layer_count = estimator.layers();
    let (fw, fh) = (scene.film.width, scene.film.height);
    let thread_buffers = ThreadBuffers::per_thread(render.threads().max(1), &empty_splats, layer_count, (fw, fh));
    let max_spp = match settings.budget {
        Budget::Samples(n) => n,
        Budget::Time(_) => u32::MAX,
    };
    let mut snapshots = render.snapshots(settings.budget);
    let mut resume: Vec<u32> = tiles.iter().map(|t| t.y0).collect();
    let mut done = 0u32;
    while done < max_spp {
        let size = done.max(1).min(max_spp - done);
        // Later passes stop at the deadline or at the next snapshot, whichever comes first.
        let stop_at = match (render.deadline, snapshots.next_due()) {
            (Some(d), Some(s)) => Some(d.min(s)),
            (d, s) => d.or(s),
        };
        let pass = Pass {
            scene,
            seed: settings.seed,
            samples: done..done + size,
            stop_at: if done == 0 { None } else { stop_at },
            render: &render,
            resume: &resume,
        };
        // Rank 0 decides for every rank (a single process decides alone).
        if cluster.broadcast(render.cancelled() || (done > 0 && render.past_deadline())) {
            break;
        }
        let results = render.install(|| pass.run(estimator, &tiles, &thread_buffers, cluster));
        // Rank 0 merges every rank's tiles in tile order, as a single process merges its own.
        let results = if cluster.is_distributed() { exchange_tiles(cluster, &scene.film, results) } else { results };
        let mut finished = true;
        for (i, r) in &results {
            if cluster.is_root() {
                film.merge(&r.buffer);
                stats.pixel_samples += r.samples;
                stats.rays += r.rays;
            }
            finished &= r.next_row == tiles[*i].y1;
            resume[*i] = r.next_row;
        }
        let finished = cluster.broadcast(finished);
        if cluster.broadcast(snapshots.is_due(&render)) {
            let splats = merged_splats(cluster, &thread_buffers, &empty_splats);
            snapshots.take(&render, |seconds| RenderOutput {
                image: develop(&film, &splats, E::SPLATS, stats.pixel_samples),
                stats: RenderStats { spp_completed: done, seconds, ..stats.clone() },
                layers: Vec::new(),
                chains: Vec::new(),
            });
        }
        if finished {
            done += size;
            for (row, tile) in resume.iter_mut().zip(&tiles) {
                *row = tile.y0;
            }
        } else if cluster.broadcast(render.should_stop()) {
            break;
        }
    }
    let ThreadBuffers { splats, layers, .. } =
        ThreadBuffers::merged(thread_buffers, &empty_splats, layer_count, (fw, fh));
    let mut all: Vec<SplatBuffer> = std::iter::once(splats).chain(layers).collect();
    sum_at_root(cluster, &mut all);
    let layers = all.split_off(1);
    let splats = all.pop().expect("the splat buffer");
    stats.spp_completed = done;
    stats.invalid_samples = film.invalid_samples + splats.invalid;
    render.finish(&mut stats);
    let image = develop(&film, &splats, E::SPLATS, stats.pixel_samples);
    let per_sample = f64::from(fw) * f64::from(fh) / (stats.pixel_samples.max(1) as f64);
    let layers = layers.iter().map(|l| l.image(per_sample)).collect();
    RenderOutput { image, stats, layers, chains: Vec::new() }
}
