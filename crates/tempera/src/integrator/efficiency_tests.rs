//! The chains' efficiency measured from two halves of each depth's walkers
//! ([`crate::mcmc::efficiency`]): it tells well-mixing chains from slow ones, leaves the image
//! as it was, and is the same at any thread count.

use super::tests::render_with;
use super::*;

/// Chains that mostly make large steps (independent proposals) are worth more independent
/// samples per mutation than chains that mostly make small ones, at every depth, and several
/// times more on the short paths, where most independent proposals are accepted; every
/// measurement lies in `(0, 1]`.
#[test]
fn large_steps_measure_more_efficient_than_small_ones() {
    let scene = crate::scenes::cornell_box(24, 24).build().unwrap();
    let measure = |large_step_probability: f32| {
        let m = MmltIntegrator {
            bootstrap: 20_000,
            chains: 16,
            large_step_probability,
            measure_efficiency: true,
            ..MmltIntegrator::new(4)
        };
        let out = render_with(&scene, &m, Budget::Samples(256), 3, 0);
        out.chains.iter().map(|d| d.measured_efficiency).collect::<Vec<f64>>()
    };
    let (large, small) = (measure(0.9), measure(0.02));
    for (k, (l, s)) in large.iter().zip(&small).enumerate() {
        assert!(*l > 0.0 && *l <= 1.0 && *s > 0.0 && *s <= 1.0, "depth {k}: {l}, {s}");
        assert!(l > s, "depth {k}: large steps {l} against small steps {s}");
    }
    // Where most large steps are accepted (the short paths), several times more.
    assert!(large[1] > 2.0 * small[1] && large[2] > 2.0 * small[2], "{large:?} against {small:?}");
}

/// Splatting in halves changes only the order of the sums: the image is the one rendered
/// without, to rounding, and bit-identical at one, two and three threads, with tempered
/// ensembles too.
#[test]
fn measuring_keeps_the_image_at_any_thread_count() {
    let scene = crate::scenes::cornell_box(16, 16).build().unwrap();
    let plain = MmltIntegrator { bootstrap: 5_000, chains: 8, hybrid: 0.5, ..MmltIntegrator::new(4) };
    let measured = MmltIntegrator { measure_efficiency: true, ..plain };
    let tempered = TemperedIntegrator {
        bootstrap: 5_000,
        chains: 8,
        reuse_replicas: false,
        measure_efficiency: true,
        ensembles_below: 0,
        bdpt_above: None,
        importance_pilot: 0,
        ..TemperedIntegrator::new(4)
    };
    let reference = render_with(&scene, &plain, Budget::Samples(16), 9, 1);
    let one = render_with(&scene, &measured, Budget::Samples(16), 9, 1);
    for (a, b) in one.image.pixels.iter().zip(&reference.image.pixels) {
        assert!((a.y - b.y).abs() <= 1e-5 * b.y.abs() + 1e-7, "{} vs {}", a.y, b.y);
    }
    assert!(one.chains.iter().skip(1).all(|d| d.measured_efficiency > 0.0), "{:?}", one.chains);
    assert!(reference.chains.iter().all(|d| d.measured_efficiency == 0.0));
    for threads in [2, 3] {
        assert!(render_with(&scene, &measured, Budget::Samples(16), 9, threads).image.pixels == one.image.pixels);
    }
    let run = |threads| render_with(&scene, &tempered, Budget::Samples(8), 4, threads);
    let (a, b) = (run(1), run(3));
    assert!(a.image.pixels == b.image.pixels);
    assert!(a.chains.iter().skip(1).any(|d| d.measured_efficiency > 0.0), "{:?}", a.chains);
}
