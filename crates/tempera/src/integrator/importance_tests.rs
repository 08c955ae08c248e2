//! Markov-chain renders whose targets are shaped per pixel (`importance_pilot`): a chain on
//! `g = f/ψ(pixel)` splatting `C/g`, normalised by `E[g]`, renders the image a chain on `f`
//! does.

use super::tests::{block_stats, render_with};
use super::*;
use crate::math::Vec2;
use crate::mcmc::Moments;
use crate::mcmc::all_strategies::all_strategies;
use crate::mcmc::importance::ImportanceMap;

/// With a pilot of 4 samples per pixel, MMLT (the full shape, power 1) and tempered MMLT
/// (ensembles at every depth, replica reuse, never BDPT alone; power 1/2) agree with BDPT on a
/// Cornell box block by block; the shaping did bite (every depth's `b` is the shaped target's,
/// far from MMLT's, and power 1/2's ratio to MMLT's is about the square root of power 1's); a
/// shaped render is the same at any thread count, and one without a pilot is MMLT's, bit for
/// bit.
#[test]
fn shaped_chains_agree_with_bdpt() {
    let scene = crate::scenes::cornell_box(32, 32).build().unwrap();
    let bdpt = render_with(&scene, &BdptIntegrator::new(5), Budget::Samples(256), 1, 0);
    let b = block_stats(&bdpt.image, 16);
    let mean = |s: &[(f64, f64)]| s.iter().map(|v| v.0).sum::<f64>() / s.len() as f64;
    let plain = MmltIntegrator { bootstrap: 100_000, ..MmltIntegrator::new(5) };
    // Shaped whatever the map predicts.
    let shaped = MmltIntegrator { importance_pilot: 4, importance_below: 1000.0, importance_power: 1.0, ..plain };
    let tempered = TemperedIntegrator {
        bootstrap: 100_000,
        importance_pilot: 4,
        importance_below: 1000.0,
        importance_power: 0.5,
        ensembles_below: 0,
        bdpt_above: None,
        ..TemperedIntegrator::new(5)
    };
    let integrators: [(&str, &dyn Integrator, u32); 2] = [("mmlt", &shaped, 2048), ("tempered", &tempered, 1024)];
    for (name, integrator, mpp) in integrators {
        let out = render_with(&scene, integrator, Budget::Samples(mpp), 2, 0);
        let a = block_stats(&out.image, 16);
        assert!((mean(&a) / mean(&b) - 1.0).abs() < 0.01, "{name}: image means {} vs {}", mean(&a), mean(&b));
        for (i, ((ma, _), (mb, sb))) in a.iter().zip(&b).enumerate() {
            assert!((ma - mb).abs() < 4.0 * sb + 0.03 * mb, "{name}, block {i}: {ma} vs bdpt {mb} ± {sb}");
        }
    }
    let unshaped = render_with(&scene, &plain, Budget::Samples(64), 2, 0);
    let one = render_with(&scene, &shaped, Budget::Samples(64), 2, 1);
    let ratios: Vec<f64> = one.chains.iter().zip(&unshaped.chains).skip(1).map(|(s, u)| s.b / u.b).collect();
    assert!(ratios.iter().all(|&r| (r - 1.0).abs() > 0.2), "shaped b / b: {ratios:?}");
    let soft = render_with(&scene, &MmltIntegrator { importance_power: 0.5, ..shaped }, Budget::Samples(64), 2, 1);
    // Where `ψ` varies little over a depth's light, as on this box, `E[f/ψ^γ] ≈ E[f]/ψ̄^γ`:
    // power 1/2 gives about the square root of the full shape's ratio.
    for (k, ((s, u), r)) in soft.chains.iter().zip(&unshaped.chains).skip(1).zip(&ratios).enumerate() {
        let (soft, full) = ((s.b / u.b).ln(), r.ln());
        assert!((soft - 0.5 * full).abs() < 0.1 * full, "depth {}: power 1/2 {soft} vs power 1 {full} (logs)", k + 1);
    }
    let two = render_with(&scene, &shaped, Budget::Samples(64), 2, 2);
    assert!(one.image.pixels == two.image.pixels, "a shaped render differs between thread counts");
    let none = render_with(&scene, &MmltIntegrator { importance_pilot: 0, ..shaped }, Budget::Samples(64), 2, 0);
    assert!(none.image.pixels == unshaped.image.pixels, "no pilot is not MMLT");
    // The pilot's choice is recorded; where its map predicts less gain than asked for, the
    // chains are MMLT's, bit for bit.
    let chose = one.chains[0].importance_pilot.expect("the pilot's choice");
    assert!(chose.shaped && chose.spp == 4 && chose.predicted_ratio > 0.0, "{chose:?}");
    let declined = MmltIntegrator { importance_below: chose.predicted_ratio * 0.999, ..shaped };
    let declined = render_with(&scene, &declined, Budget::Samples(64), 2, 0);
    let choice = declined.chains[0].importance_pilot.expect("the pilot's choice");
    assert!(!choice.shaped, "{choice:?}");
    assert!(declined.image.pixels == unshaped.image.pixels, "a declined shaping is not MMLT");
    // Where even the first passes predict too little gain, the pilot stops there.
    let hopeless = MmltIntegrator { importance_below: 1e-9, ..shaped };
    let hopeless = render_with(&scene, &hopeless, Budget::Samples(64), 2, 0);
    let choice = hopeless.chains[0].importance_pilot.expect("the pilot's choice");
    assert!(!choice.shaped && choice.spp == importance_pilot::DECIDE_AFTER, "{choice:?}");
    assert!(hopeless.image.pixels == unshaped.image.pixels, "a declined shaping is not MMLT");
}

/// The all-strategy normaliser of a shaped target estimates the shaped target's mean: at
/// depths 1–3 of the default scene, under a map that weighs the film's left half ten times its
/// right, it agrees with the mean of the shaped target over MMLT's own samples (within four
/// standard errors) and differs from the unshaped mean by more than ten; depth 0's target is
/// never shaped.
#[test]
fn the_shaped_normaliser_estimates_the_shaped_mean() {
    let mut scene = crate::scenes::default_scene().build().unwrap();
    scene.set_resolution(16, 16);
    let pilot: Vec<f32> = (0..256).map(|j| if j % 16 < 8 { 0.1 } else { 1.0 }).collect();
    let map = ImportanceMap::from_pilot(16, 16, &pilot, 16, 0.01, 1.0).unwrap();
    assert!(map.factor(Vec2::new(2.5, 3.5)) > 9.0 * map.factor(Vec2::new(13.5, 3.5)));
    let n = 200_000;
    for k in 1..=3 {
        let mut shaped = Moments::default();
        crate::testing::shaped_target_values(&scene, k, 9, n, Some(&map)).iter().for_each(|&v| shaped.push(v));
        let (all, _) = all_strategies(&scene, k, 9, n, (f32::INFINITY, Some(&map)));
        crate::testing::assert_same_mean(&format!("depth {k}"), &shaped, &all.moments);
        let (unshaped, _) = all_strategies(&scene, k, 9, n, (f32::INFINITY, None));
        let (ms, es) = all.moments.mean_and_rel_se();
        let (mu, eu) = unshaped.moments.mean_and_rel_se();
        let sigma = ((ms * es).powi(2) + (mu * eu).powi(2)).sqrt();
        assert!((ms - mu).abs() > 10.0 * sigma, "depth {k}: the shaping changed little: {ms} vs {mu} ± {sigma}");
        // The same samples' unshaped estimates are the unshaped normaliser's, bit for bit.
        assert_eq!(all.plain, Some(unshaped.moments), "depth {k}");
        assert_eq!(unshaped.plain, None);
    }
    let depth0 = crate::testing::shaped_target_values(&scene, 0, 9, 20_000, Some(&map));
    assert!(depth0 == crate::testing::mmlt_target_values(&scene, 0, 9, 20_000));
}

/// A shaped depth's brightness, estimated twice: by its chains as `b·w̄` (the shaped
/// normalisation times their mean splat weight, the luminance a splat carries per unit of
/// shaped target) and by its normaliser samples' unshaped values (`b_plain`). MMLT shaped on a
/// Cornell box (box filter: every splat lands on one pixel), seeds 1–8 at 64 mutations per
/// pixel: the image's mean luminance is the sum of the chains' estimates (so the splat weight
/// counts what the chains splatted), the shaped depths' two estimates agree, and over the seeds
/// the plain estimates spread less than the chains' here (no caustic; the README's twin
/// caustics are the counter-example); an unshaped render's splat weight is one per mutation
/// and it has no plain estimate.
#[test]
fn a_shaped_depths_chains_and_plain_normaliser_estimate_its_brightness_alike() {
    let scene = crate::scenes::cornell_box(32, 32).build().unwrap();
    let plain = MmltIntegrator { bootstrap: 20_000, ..MmltIntegrator::new(5) };
    let shaped = MmltIntegrator { importance_pilot: 4, importance_below: 1000.0, importance_power: 1.0, ..plain };
    let (mut plains, mut chains) = (Moments::default(), Moments::default());
    for seed in 1..=8 {
        let out = render_with(&scene, &shaped, Budget::Samples(64), seed, 2);
        let (mut own, mut independent) = (0.0, 0.0);
        for d in out.chains.iter().filter(|d| d.mutations > 0 && d.depth > 0) {
            assert!(d.b_plain > 0.0, "seed {seed}, depth {}: no plain normalisation", d.depth);
            own += d.b * d.splat_weight / d.mutations as f64;
            independent += d.b_plain;
        }
        let depth0 = &out.chains[0];
        let w0 = depth0.splat_weight / depth0.mutations as f64;
        assert!(depth0.b_plain == 0.0 && (w0 - 1.0).abs() < 1e-5, "depth 0: {} {w0}", depth0.b_plain);
        let mean = out.image.pixels.iter().map(|&p| f64::from(crate::math::luminance(p))).sum::<f64>()
            / out.image.pixels.len() as f64;
        let total = own + depth0.b;
        assert!((mean / total - 1.0).abs() < 1e-3, "seed {seed}: image mean {mean}, chains' estimate {total}");
        assert!((own / independent - 1.0).abs() < 0.1, "seed {seed}: chains {own} vs plain {independent}");
        plains.push(independent);
        chains.push(own);
    }
    let sd = |m: &Moments| (m.sum2 / m.n as f64 - (m.sum / m.n as f64).powi(2)).max(0.0).sqrt();
    assert!(sd(&plains) < sd(&chains), "spread over seeds: plain {} vs chains {}", sd(&plains), sd(&chains));
    let unshaped = render_with(&scene, &plain, Budget::Samples(64), 1, 2);
    for d in unshaped.chains.iter().filter(|d| d.mutations > 0) {
        let w = d.splat_weight / d.mutations as f64;
        assert!(d.b_plain == 0.0 && (w - 1.0).abs() < 1e-5, "unshaped depth {}: {} {w}", d.depth, d.b_plain);
    }
}

/// A shaped render cannot be combined with BDPT samples (their weights are the unshaped
/// target's), nor measure its chains' efficiency (against the unshaped target's independent
/// samples): an error, not a wrong image or figure.
#[test]
fn shaping_is_refused_with_the_hybrid_and_the_efficiency_measurement() {
    let mut scene = crate::scenes::cornell_box(8, 8).build().unwrap();
    scene.set_resolution(8, 8);
    let cancel = std::sync::atomic::AtomicBool::new(false);
    let control = RenderControl::new(&cancel, &|_| {});
    let settings = RenderSettings { budget: Budget::Samples(2), seed: 1, threads: 1 };
    let mmlt = MmltIntegrator { importance_pilot: 2, hybrid: 0.15, ..MmltIntegrator::new(3) };
    let tempered = TemperedIntegrator { importance_pilot: 2, hybrid_auto: true, ..TemperedIntegrator::new(3) };
    for integrator in [&mmlt as &dyn Integrator, &tempered] {
        let err = integrator.render(&scene, &settings, &control).err().unwrap_or_default();
        assert!(err.contains("--importance-pilot cannot be combined with --hybrid"), "{err}");
    }
    let measured = MmltIntegrator { importance_pilot: 2, measure_efficiency: true, ..MmltIntegrator::new(3) };
    let err = measured.render(&scene, &settings, &control).err().unwrap_or_default();
    assert!(err.contains("cannot be combined with --measure-efficiency"), "{err}");
}
