//! One chain on the mixture of the replicas' targets (`Swap::Mixture`): unbiased at any weight
//! of the hotter targets (the depth's splats normalised by `b_m = Σ_l b_l/ρ_l`; by `b_0` alone
//! the image would be `1 + w(K − 1)` times too dark), as deterministic as the ensembles, and
//! at the cost of one chain: its hotter replicas never mutate.

use crate::integrator::tests::{classify_furnace_pixels, render_with};
use crate::integrator::*;
use std::sync::atomic::AtomicBool;

fn settings(mpp: u32, seed: u64, threads: usize) -> RenderSettings {
    RenderSettings { budget: Budget::Samples(mpp), seed, threads }
}

#[test]
fn the_mixture_chain_agrees_with_bdpt_and_the_furnace_at_the_cost_of_one_chain() {
    let mut scene = crate::scenes::default_scene().build().unwrap();
    scene.set_resolution(24, 24);
    let cancel = AtomicBool::new(false);
    let control = RenderControl::new(&cancel, &|_| {});
    let bdpt = render_with(&scene, &BdptIntegrator::new(5), Budget::Samples(512), 1, 0);
    let base = TemperedIntegrator {
        bootstrap: 50_000,
        chains: 16,
        swap: Swap::Mixture,
        ensembles_below: 0,
        bdpt_above: None,
        ..TemperedIntegrator::new(5)
    };
    let cases = [
        ("two targets", base.clone()),
        ("three targets, hot weight 0.25", TemperedIntegrator { replicas: 3, hot_weight: 0.25, ..base.clone() }),
        ("fixed power ladder", TemperedIntegrator { ladder: vec![0.9], flattening: Flattening::Power, ..base.clone() }),
    ];
    for (name, t) in cases {
        let out = t.render(&scene, &settings(256, 2, 0), &control).unwrap();
        super::integrator::assert_agrees(name, &out.image, &bdpt.image);
        for d in out.chains.iter().filter(|d| d.depth > 0 && d.mutations > 0) {
            assert!(d.swaps.is_none(), "{name}, depth {}: a mixture chain does not swap", d.depth);
            assert_eq!(d.ladder.len(), t.replicas, "{name}, depth {}: {:?}", d.depth, d.ladder);
            let ratios = &d.replica_b_ratios;
            assert!(ratios.len() == t.replicas && ratios.iter().all(|r| r.is_finite() && *r > 0.0), "{ratios:?}");
        }
    }
    // The same mutations of the main chains as two-replica ensembles, with a fraction of the
    // rays: the bootstrap and calibration trace the same for both, the mutations once, not
    // twice.
    let cheap = TemperedIntegrator { bootstrap: 5_000, ..base.clone() };
    let ensembles = TemperedIntegrator { swap: Swap::Neighbor, ..cheap.clone() };
    let (a, b) = (
        cheap.render(&scene, &settings(512, 2, 0), &control).unwrap(),
        ensembles.render(&scene, &settings(512, 2, 0), &control).unwrap(),
    );
    assert_eq!(a.stats.pixel_samples, b.stats.pixel_samples);
    let ratio = a.stats.rays as f64 / b.stats.rays as f64;
    assert!(ratio < 0.8, "the mixture traced {ratio} of the ensembles' rays");
    let run = |threads| base.render(&scene, &settings(4, 7, threads), &control).unwrap().image.pixels;
    assert!(run(1) == run(2), "same image at any thread count");

    // The furnace over four seeds: one seed's sphere mean spreads by nearly the bound here.
    let furnace = crate::scenes::furnace(0.8, 32, 32).build().unwrap();
    let (sphere, sky) = classify_furnace_pixels(&furnace);
    let seeds = [3, 4, 5, 6];
    let (mut sphere_mean, mut sky_mean) = (0.0, 0.0);
    for seed in seeds {
        let out = TemperedIntegrator { bootstrap: 100_000, replicas: 3, ..base.clone() }
            .render(&furnace, &settings(128, seed, 0), &control)
            .unwrap();
        let m = |idx: &[usize]| idx.iter().map(|&i| f64::from(out.image.pixels[i].y)).sum::<f64>() / idx.len() as f64;
        sphere_mean += m(&sphere) / seeds.len() as f64;
        sky_mean += m(&sky) / seeds.len() as f64;
    }
    assert!((sphere_mean - 0.8).abs() < 0.01, "furnace sphere {sphere_mean}");
    assert!((sky_mean - 1.0).abs() < 0.01, "furnace sky {sky_mean}");
}

#[test]
fn mixture_settings_are_checked() {
    let mixture = IntegratorSettings { swap: Some(Swap::Mixture), ..Default::default() };
    let no_reuse = IntegratorSettings { reuse_replicas: Some(false), ..mixture.clone() };
    assert!(no_reuse.validate(IntegratorKind::Tempered).unwrap_err().contains("reuses every replica"));
    let weight = IntegratorSettings { hot_weight: Some(0.5), ..Default::default() };
    assert!(weight.validate(IntegratorKind::Tempered).unwrap_err().contains("needs swap = mixture"));
    let weight = IntegratorSettings { hot_weight: Some(1.5), ..mixture.clone() };
    assert!(weight.validate(IntegratorKind::Tempered).is_err());
    assert!(IntegratorSettings { hot_weight: Some(0.5), ..mixture }.validate(IntegratorKind::Tempered).is_ok());
}
