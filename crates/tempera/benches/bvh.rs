//! BVH throughput: random rays against a procedurally displaced sphere of about one million
//! triangles (closest hit and any hit).

use divan::Bencher;
use divan::counter::ItemsCount;
use std::sync::LazyLock;
use tempera::accel::{Accel, Bvh};
use tempera::geometry::{Geometry, Ray, Shape, TriangleMesh};
use tempera::math::rng::Pcg32;
use tempera::math::warp::uniform_sphere;
use tempera::math::{Vec2, Vec3};

const RINGS: u32 = 708;
const SEGMENTS: u32 = 708;
const RAYS: usize = 10_000;

/// A bumpy sphere: 2 · RINGS · SEGMENTS ≈ 1.0M triangles.
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

struct Setup {
    geometry: Geometry,
    bvh: Bvh,
    rays: Vec<Ray>,
}

static SETUP: LazyLock<Setup> = LazyLock::new(|| {
    let mut geometry = Geometry::new(vec![Shape::Mesh(bumpy_sphere())]);
    let bvh = Bvh::build(&mut geometry);
    let mut rng = Pcg32::new(1, 1);
    let mut u2 = || Vec2::new(rng.next_f32(), rng.next_f32());
    let rays = (0..RAYS)
        .map(|_| {
            let o = 3.0 * uniform_sphere(u2());
            let target = 0.9 * uniform_sphere(u2());
            Ray::new(o, (target - o).normalize())
        })
        .collect();
    Setup { geometry, bvh, rays }
});

#[divan::bench]
fn closest_hit(bencher: Bencher) {
    let s = &*SETUP;
    bencher
        .counter(ItemsCount::new(RAYS))
        .bench(|| s.rays.iter().filter(|r| s.bvh.intersect(&s.geometry, r, f32::INFINITY).is_some()).count());
}

#[divan::bench]
fn any_hit(bencher: Bencher) {
    let s = &*SETUP;
    bencher
        .counter(ItemsCount::new(RAYS))
        .bench(|| s.rays.iter().filter(|r| s.bvh.occluded(&s.geometry, r, f32::INFINITY)).count());
}

fn main() {
    println!("triangles: {}", 2 * RINGS * SEGMENTS);
    divan::main();
}
