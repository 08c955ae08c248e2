//! Markov-chain throughput on the embedded default scene at 128×128: MMLT, PSSMLT and tempered
//! MMLT (5 replicas, neighbour swaps, fixed ladder; main-chain mutations) mutations per second
//! (8 mutations per pixel per iteration, after a bootstrap of 1000 samples per depth, which the
//! figure includes), on one thread and on all threads.

use divan::Bencher;
use divan::counter::ItemsCount;
use std::sync::LazyLock;
use std::sync::atomic::AtomicBool;
use tempera::integrator::{
    Budget, Integrator, MmltIntegrator, PssmltIntegrator, RenderControl, RenderSettings, TemperedIntegrator,
};
use tempera::scene::Scene;

const SIZE: u32 = 128;
const MPP: u32 = 8;

static SCENE: LazyLock<Scene> = LazyLock::new(|| {
    let mut scene = tempera::scenes::default_scene().build().expect("the default scene builds");
    scene.set_resolution(SIZE, SIZE);
    scene
});

fn render(integrator: &dyn Integrator, threads: usize) {
    let cancel = AtomicBool::new(false);
    let control = RenderControl::new(&cancel, &|_| {});
    let settings = RenderSettings { budget: Budget::Samples(MPP), seed: 1, threads };
    let out = integrator.render(&SCENE, &settings, &control).expect("the scene renders");
    divan::black_box(out.image);
}

#[divan::bench(args = [1, 0], sample_count = 10)]
fn mmlt_mutations(bencher: Bencher, threads: usize) {
    LazyLock::force(&SCENE);
    let m = MmltIntegrator { bootstrap: 1000, ..MmltIntegrator::new(8) };
    bencher.counter(ItemsCount::new((SIZE * SIZE * MPP) as usize)).bench(|| render(&m, threads));
}

#[divan::bench(args = [1, 0], sample_count = 10)]
fn pssmlt_mutations(bencher: Bencher, threads: usize) {
    LazyLock::force(&SCENE);
    let m = PssmltIntegrator { bootstrap: 9000, ..PssmltIntegrator::new(8) };
    bencher.counter(ItemsCount::new((SIZE * SIZE * MPP) as usize)).bench(|| render(&m, threads));
}

#[divan::bench(args = [1, 0], sample_count = 10)]
fn tempered_mutations(bencher: Bencher, threads: usize) {
    LazyLock::force(&SCENE);
    let ladder = TemperedIntegrator::default_ladder(5);
    let m = TemperedIntegrator {
        bootstrap: 1000,
        replicas: 5,
        ladder,
        ensembles_below: 0,
        bdpt_above: None,
        ..TemperedIntegrator::new(8)
    };
    bencher.counter(ItemsCount::new((SIZE * SIZE * MPP) as usize)).bench(|| render(&m, threads));
}

fn main() {
    divan::main();
}
