//! Path-tracing throughput on the embedded default scene at 128×128, one sample per pixel per
//! iteration, on one thread and on all threads.

use divan::Bencher;
use divan::counter::ItemsCount;
use std::sync::LazyLock;
use std::sync::atomic::AtomicBool;
use tempera::integrator::{Budget, Integrator, PathIntegrator, RenderControl, RenderSettings};
use tempera::scene::Scene;

const SIZE: u32 = 128;

static SCENE: LazyLock<Scene> = LazyLock::new(|| {
    let mut scene = tempera::scenes::default_scene().build().expect("the default scene builds");
    scene.set_resolution(SIZE, SIZE);
    scene
});

fn render(threads: usize) {
    let cancel = AtomicBool::new(false);
    let control = RenderControl::new(&cancel, &|_| {});
    let settings = RenderSettings { budget: Budget::Samples(1), seed: 1, threads };
    let out = PathIntegrator::new(8).render(&SCENE, &settings, &control).expect("the scene renders");
    divan::black_box(out.image);
}

#[divan::bench(args = [1, 0])]
fn default_scene_samples(bencher: Bencher, threads: usize) {
    LazyLock::force(&SCENE);
    bencher.counter(ItemsCount::new((SIZE * SIZE) as usize)).bench(|| render(threads));
}

fn main() {
    divan::main();
}
