//! Ray-tracing throughput of the accelerators, the same rays for each, in one run: Tempera's
//! BVH and (built with `--features embree`) Embree. Rows:
//!
//! - `mesh`: random rays (from a sphere of radius 3 towards points inside radius 0.9) against a
//!   procedurally displaced sphere of about 1.41 million triangles;
//! - `default`, `classroom`: rays recorded from a scene — per pixel a camera ray, and at its
//!   hit a shadow ray towards a point sampled on a light and one cosine-distributed bounce
//!   (classroom from `../shared/scenes` when present, else skipped with a message);
//!
//! each as closest hit and any hit (shadow rays up to their light sample, the others unbounded),
//! on 1 and 2 threads (rays split in fixed chunks; the counter is all rays, so the throughput is
//! the whole machine's). `build` times the construction over that mesh.
//!
//! `cargo bench -p tempera-cli --bench accel [--features embree]`

use divan::Bencher;
use divan::counter::ItemsCount;
use rayon::prelude::*;
use std::path::Path;
use std::sync::LazyLock;
use tempera::accel::{Accel, AccelKind, SceneAccel};
use tempera::geometry::{Geometry, Ray, Shape, TriangleMesh, spawn_ray, spawn_ray_to};
use tempera::math::frame::Frame;
use tempera::math::rng::Pcg32;
use tempera::math::warp::{cosine_hemisphere, uniform_sphere};
use tempera::math::{Vec2, Vec3};
use tempera::scene::Scene;

const RINGS: u32 = 840;
const SEGMENTS: u32 = 840;
const RANDOM_RAYS: usize = 20_000;
/// Rays per chunk handed to a thread.
const CHUNK: usize = 256;

/// A bumpy sphere: 2 · RINGS · SEGMENTS ≈ 1.41M triangles.
fn bumpy_sphere() -> TriangleMesh {
    let mut positions = Vec::with_capacity(((RINGS + 1) * (SEGMENTS + 1)) as usize);
    for i in 0..=RINGS {
        let theta = std::f32::consts::PI * i as f32 / RINGS as f32;
        for j in 0..=SEGMENTS {
            let phi = std::f32::consts::TAU * j as f32 / SEGMENTS as f32;
            let r = 1.0 + 0.05 * (7.0 * theta).sin() * (11.0 * phi).cos();
            positions.push(r * Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()));
        }
    }
    let mut indices = Vec::with_capacity((2 * RINGS * SEGMENTS) as usize);
    for i in 0..RINGS {
        for j in 0..SEGMENTS {
            let a = i * (SEGMENTS + 1) + j;
            let b = a + SEGMENTS + 1;
            indices.push([a, b, a + 1]);
            indices.push([a + 1, b, b + 1]);
        }
    }
    TriangleMesh::new(positions, indices, None, None).expect("valid mesh")
}

/// Rays with their closest-hit and any-hit distances.
struct Rays {
    rays: Vec<(Ray, f32)>,
}

/// Geometry with every accelerator this build has, over the same primitives.
struct Setup {
    geometry: Geometry,
    accels: Vec<(AccelKind, SceneAccel)>,
    rays: Rays,
}

fn accels(geometry: &mut Geometry) -> Vec<(AccelKind, SceneAccel)> {
    // The BVH reorders the primitive table; Embree keeps whatever order it finds.
    let mut out = vec![(AccelKind::Bvh, SceneAccel::build(AccelKind::Bvh, geometry).expect("a BVH"))];
    if AccelKind::Embree.available() {
        out.push((AccelKind::Embree, SceneAccel::build(AccelKind::Embree, geometry).expect("Embree")));
    }
    out
}

static MESH: LazyLock<Setup> = LazyLock::new(|| {
    let mut geometry = Geometry::new(vec![Shape::Mesh(bumpy_sphere())]);
    let accels = accels(&mut geometry);
    let mut rng = Pcg32::new(1, 1);
    let mut u2 = || Vec2::new(rng.next_f32(), rng.next_f32());
    let rays = (0..RANDOM_RAYS)
        .map(|_| {
            let o = 3.0 * uniform_sphere(u2());
            let target = 0.9 * uniform_sphere(u2());
            (Ray::new(o, (target - o).normalize()), f32::INFINITY)
        })
        .collect();
    Setup { geometry, accels, rays: Rays { rays } }
});

/// Per pixel: the camera ray, and at its hit a shadow ray and a diffuse bounce.
fn record(scene: &Scene) -> Rays {
    let mut rng = Pcg32::new(7, 3);
    let mut rays = Vec::new();
    for y in 0..scene.film.height {
        for x in 0..scene.film.width {
            let raster = Vec2::new(x as f32 + rng.next_f32(), y as f32 + rng.next_f32());
            let ray = scene.camera.generate_ray(raster, Vec2::new(rng.next_f32(), rng.next_f32()));
            rays.push((ray, f32::INFINITY));
            let Some(it) = scene.intersect(&ray) else { continue };
            let s = &it.surface;
            if let Some((light, _)) = scene.light_sampler.sample(rng.next_f32()) {
                let u = Vec2::new(rng.next_f32(), rng.next_f32());
                if let Some(ls) = scene.lights[light].sample_li(&scene.geometry, s.p, u) {
                    rays.push(spawn_ray_to(s.p, s.ng, ls.p));
                }
            }
            let n = if s.ng.dot(it.wo) < 0.0 { -s.ng } else { s.ng };
            let w = Frame::from_z(n).to_world(cosine_hemisphere(Vec2::new(rng.next_f32(), rng.next_f32())));
            rays.push((spawn_ray(s.p, s.ng, w), f32::INFINITY));
        }
    }
    Rays { rays }
}

fn scene_setup(scene: Scene) -> Setup {
    let rays = record(&scene);
    let mut geometry = scene.geometry.clone();
    let accels = accels(&mut geometry);
    Setup { geometry, accels, rays }
}

static DEFAULT: LazyLock<Setup> = LazyLock::new(|| {
    let mut builder = tempera::scenes::default_scene();
    builder.set_accel(AccelKind::Bvh);
    let mut scene = builder.build().expect("the default scene");
    scene.set_resolution(256, 256);
    scene_setup(scene)
});

const CLASSROOM: &str = "../../../shared/scenes/classroom/pbrt-v4/scene-v4.pbrt";

static CLASSROOM_SETUP: LazyLock<Option<Setup>> = LazyLock::new(|| {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(CLASSROOM);
    if !path.exists() {
        eprintln!("classroom rows skipped: {} not found", path.display());
        return None;
    }
    let loaded = tempera_scene::load(&path, &tempera_scene::LoadOptions::default()).expect("classroom loads");
    let mut scene = loaded.builder.build().expect("classroom builds");
    scene.set_resolution(320, 240);
    Some(scene_setup(scene))
});

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a thread pool")
}

/// Traces every ray of `s` with accelerator `which` on `threads` threads.
fn trace(bencher: Bencher, s: &Setup, which: AccelKind, threads: usize, closest: bool) {
    let Some((_, accel)) = s.accels.iter().find(|(k, _)| *k == which) else {
        eprintln!("{which:?} is not in this build (cargo bench --features embree)");
        return;
    };
    let pool = pool(threads);
    let rays = &s.rays.rays;
    bencher.counter(ItemsCount::new(rays.len())).bench(|| {
        pool.install(|| {
            rays.par_chunks(CHUNK)
                .map(|chunk| {
                    chunk
                        .iter()
                        .filter(|(r, t)| {
                            if closest {
                                accel.intersect(&s.geometry, r, *t).is_some()
                            } else {
                                accel.occluded(&s.geometry, r, *t)
                            }
                        })
                        .count()
                })
                .sum::<usize>()
        })
    });
}

const KINDS: [AccelKind; 2] = [AccelKind::Bvh, AccelKind::Embree];

#[divan::bench(args = KINDS, consts = [1, 2])]
fn mesh_closest<const T: usize>(bencher: Bencher, kind: AccelKind) {
    trace(bencher, &MESH, kind, T, true);
}

#[divan::bench(args = KINDS, consts = [1, 2])]
fn mesh_any<const T: usize>(bencher: Bencher, kind: AccelKind) {
    trace(bencher, &MESH, kind, T, false);
}

#[divan::bench(args = KINDS, consts = [1, 2])]
fn default_closest<const T: usize>(bencher: Bencher, kind: AccelKind) {
    trace(bencher, &DEFAULT, kind, T, true);
}

#[divan::bench(args = KINDS, consts = [1, 2])]
fn default_any<const T: usize>(bencher: Bencher, kind: AccelKind) {
    trace(bencher, &DEFAULT, kind, T, false);
}

#[divan::bench(args = KINDS, consts = [1, 2])]
fn classroom_closest<const T: usize>(bencher: Bencher, kind: AccelKind) {
    if let Some(s) = CLASSROOM_SETUP.as_ref() {
        trace(bencher, s, kind, T, true);
    }
}

#[divan::bench(args = KINDS, consts = [1, 2])]
fn classroom_any<const T: usize>(bencher: Bencher, kind: AccelKind) {
    if let Some(s) = CLASSROOM_SETUP.as_ref() {
        trace(bencher, s, kind, T, false);
    }
}

/// The build over the 1.41M-triangle mesh, on all threads.
#[divan::bench(args = KINDS, sample_count = 5, sample_size = 1)]
fn build(bencher: Bencher, kind: AccelKind) {
    if !kind.available() {
        return;
    }
    let geometry = Geometry::new(vec![Shape::Mesh(bumpy_sphere())]);
    bencher
        .with_inputs(|| geometry.clone())
        .bench_local_values(|mut g| SceneAccel::build(kind, &mut g).map(|a| a.kind()).expect("built"));
}

fn main() {
    println!("mesh: {} triangles, {} rays", 2 * RINGS * SEGMENTS, RANDOM_RAYS);
    divan::main();
}
