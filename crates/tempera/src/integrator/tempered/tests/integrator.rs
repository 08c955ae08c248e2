//! Tempered MMLT end to end: one replica reproduces MMLT, every swap strategy and hot-replica
//! variant agrees with BDPT and the furnace, the pilot and the swap interval do what they say.

use crate::integrator::tests::{block_stats, classify_furnace_pixels, render_with};
use crate::integrator::*;
use std::sync::atomic::AtomicBool;

fn settings(mpp: u32, seed: u64, threads: usize) -> RenderSettings {
    RenderSettings { budget: Budget::Samples(mpp), seed, threads }
}

#[test]
fn one_replica_reproduces_mmlt_exactly() {
    let mut scene = crate::scenes::default_scene().build().unwrap();
    scene.set_resolution(16, 16);
    let cancel = AtomicBool::new(false);
    let control = RenderControl::new(&cancel, &|_| {});
    // With the same allotment of mutations to depths (tempered MMLT's default is by spread).
    // And with the depths whose bootstrap has fewer than 1500 non-zero values of 5000 sampled
    // independently. And with tempered MMLT's per-pixel shaping, which shapes this scene, and
    // its jumps between techniques, film steps and lens steps.
    for (spread_allocation, independent_below) in [(false, 0), (true, 0), (true, 1500)] {
        let mmlt = MmltIntegrator {
            bootstrap: 5_000,
            chains: 8,
            spread_allocation,
            independent_below,
            importance_pilot: TemperedIntegrator::new(5).importance_pilot,
            jumps: TemperedIntegrator::new(5).jumps,
            film_steps: TemperedIntegrator::new(5).film_steps,
            lens_steps: TemperedIntegrator::new(5).lens_steps,
            ..MmltIntegrator::new(5)
        };
        let tempered = TemperedIntegrator {
            bootstrap: 5_000,
            chains: 8,
            replicas: 1,
            spread_allocation,
            independent_below,
            ensembles_below: 0,
            bdpt_above: None,
            ..TemperedIntegrator::new(5)
        };
        let a = mmlt.render(&scene, &settings(16, 3, 0), &control).unwrap();
        let b = tempered.render(&scene, &settings(16, 3, 0), &control).unwrap();
        assert!(a.image.pixels == b.image.pixels, "replicas = 1 is MMLT bit for bit");
        let shaped = |o: &RenderOutput| o.chains[0].importance_pilot.is_some_and(|c| c.shaped);
        assert!(shaped(&a) && shaped(&b), "the shaping was not tested");
    }
}

/// On a diffuse Cornell box every replica's target equals the main one, so almost every
/// swap is accepted: states change replicas all the time, and the image must not notice.
/// The furnace checks the absolute level.
#[test]
fn every_swap_strategy_agrees_with_bdpt_on_a_cornell_box_and_the_furnace() {
    let cornell = crate::scenes::cornell_box(32, 32).build().unwrap();
    let furnace = crate::scenes::furnace(0.8, 32, 32).build().unwrap();
    let cancel = AtomicBool::new(false);
    let control = RenderControl::new(&cancel, &|_| {});
    let bdpt = render_with(&cornell, &BdptIntegrator::new(5), Budget::Samples(256), 1, 0);
    let mean = |s: &[(f64, f64)]| s.iter().map(|v| v.0).sum::<f64>() / s.len() as f64;
    for swap in [Swap::Neighbor, Swap::EquiEnergy, Swap::Permutation] {
        // Replica 0 alone writes the image here; the default scene below reuses every replica.
        let t = TemperedIntegrator {
            bootstrap: 100_000,
            chains: 16,
            replicas: 3,
            swap,
            reuse_replicas: false,
            ensembles_below: 0,
            bdpt_above: None,
            ..TemperedIntegrator::new(5)
        };
        let out = t.render(&cornell, &settings(512, 2, 0), &control).unwrap();
        let (a, b) = (block_stats(&out.image, 16), block_stats(&bdpt.image, 16));
        assert!((mean(&a) / mean(&b) - 1.0).abs() < 0.01, "{swap:?}: image means {} vs {}", mean(&a), mean(&b));
        for (i, ((ma, _), (mb, sb))) in a.iter().zip(&b).enumerate() {
            assert!((ma - mb).abs() < 4.0 * sb + 0.03 * mb, "{swap:?} block {i}: {ma} vs {mb} ± {sb}");
        }
        let swaps = out.chains[1].swaps.as_ref().unwrap();
        let exchanged: u64 = swaps.accepted.iter().sum::<u64>() + swaps.non_identity;
        assert!(exchanged > swaps.steps / 2, "{swap:?}: states move between replicas: {swaps:?}");
        // Film and lens steps make neighbouring mutations alike; at 128 mutations per pixel the
        // sphere's mean spreads by about 0.01 over seeds, the test's tolerance.
        let out = t.render(&furnace, &settings(512, 3, 0), &control).unwrap();
        let (sphere, sky) = classify_furnace_pixels(&furnace);
        let m = |idx: &[usize]| idx.iter().map(|&i| f64::from(out.image.pixels[i].y)).sum::<f64>() / idx.len() as f64;
        assert!((m(&sphere) - 0.8).abs() < 0.01, "{swap:?}: furnace sphere {}", m(&sphere));
        assert!((m(&sky) - 1.0).abs() < 0.01, "{swap:?}: furnace sky {}", m(&sky));
    }
}

/// The default scene at 24² and its 512-spp BDPT render.
fn default_scene_and_bdpt() -> (crate::scene::Scene, RenderOutput) {
    let mut scene = crate::scenes::default_scene().build().unwrap();
    scene.set_resolution(24, 24);
    let bdpt = render_with(&scene, &BdptIntegrator::new(5), Budget::Samples(512), 1, 0);
    (scene, bdpt)
}

/// `image` agrees with the BDPT render: image means within 3 %, 2×2 blocks within four
/// standard errors (plus 10 %).
pub(super) fn assert_agrees(name: &str, image: &crate::texture::Image, bdpt: &crate::texture::Image) {
    let mean =
        |img: &crate::texture::Image| img.pixels.iter().map(|p| f64::from(p.y)).sum::<f64>() / img.pixels.len() as f64;
    let ratio = mean(image) / mean(bdpt);
    assert!((ratio - 1.0).abs() < 0.03, "{name}: image mean ratio {ratio}");
    let (a, b) = (block_stats(image, 12), block_stats(bdpt, 12));
    for (i, ((ma, _), (mb, sb))) in a.iter().zip(&b).enumerate() {
        assert!((ma - mb).abs() < 4.0 * sb + 0.1 * mb, "{name} block {i}: {ma} vs {mb} ± {sb}");
    }
}

/// Temperatures past the roughness cap (powers `f^{1/τ}` of the fully roughened target),
/// depths collapsed to plain MMLT chains, hot replicas that mutate every fourth sweep and
/// power-flattened replicas (with small steps, or with independent proposals only) leave
/// the image unbiased; the lazy ones trace fewer rays for the same main-chain mutations.
#[test]
fn hot_replicas_and_collapsed_depths_agree_with_bdpt() {
    let (scene, bdpt) = default_scene_and_bdpt();
    let cancel = AtomicBool::new(false);
    let control = RenderControl::new(&cancel, &|_| {});
    let base = TemperedIntegrator {
        bootstrap: 50_000,
        chains: 16,
        ensembles_below: 0,
        bdpt_above: None,
        ..TemperedIntegrator::new(5)
    };
    let hot = TemperedIntegrator { ladder: vec![0.3, 1.0, 8.0], replicas: 4, ..base.clone() };
    let collapsed = TemperedIntegrator { collapse_above: Some(0.01), max_temperature: 50.0, ..base.clone() };
    let lazy = TemperedIntegrator { hot_every: 4, ..base.clone() };
    // Every depth's estimated acceptance lies below 0.999: all collapse.
    let below = TemperedIntegrator { collapse_below: Some(0.999), ..base.clone() };
    // Powers of the scene's own value, tuned from the bootstrap: a hotter target than any
    // roughening (the uniform one at τ = 1), reused with the balance heuristic.
    let power = TemperedIntegrator { flattening: Flattening::Power, replicas: 3, ..base.clone() };
    // Hot replicas that propose only large steps (independent uniform samples).
    let independent = TemperedIntegrator { hot_large_step: Some(1.0), ..power.clone() };
    // Two cold replicas sharing one hot one (a ladder with a repeated zero).
    let shared = TemperedIntegrator { ladder: vec![0.0, 1.0], replicas: 3, ..base.clone() };
    let every_sweep = base.render(&scene, &settings(256, 2, 0), &control).unwrap().stats.rays;
    let cases = [
        ("hot", hot),
        ("collapsed", collapsed),
        ("collapsed below", below),
        ("lazy", lazy),
        ("power", power),
        ("independent", independent),
        ("shared", shared),
    ];
    for (name, t) in cases {
        let out = t.render(&scene, &settings(256, 2, 0), &control).unwrap();
        assert_agrees(name, &out.image, &bdpt.image);
        if name == "lazy" {
            // Two replicas: the hot one's mutations fall to a quarter (the bootstrap, the
            // same for both, holds most of the rays of so short a render).
            let ratio = out.stats.rays as f64 / every_sweep as f64;
            assert!(ratio < 0.95, "hot replicas mutating every 4th sweep traced {ratio} of the rays");
            continue;
        }
        for d in out.chains.iter().filter(|d| d.depth > 0 && d.mutations > 0) {
            match name {
                "hot" => {
                    let expected = [0.0, 0.3, 1.0, 8.0];
                    let same = d.ladder.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-4);
                    assert!(d.ladder.len() == 4 && same, "depth {}: ladder {:?}", d.depth, d.ladder);
                    assert!(d.prepare_seconds > 0.0, "depth {}: the calibration takes time", d.depth);
                }
                "shared" => {
                    assert_eq!(d.ladder, vec![0.0, 0.0, 1.0], "depth {}", d.depth);
                    // Exchanges between the two cold replicas are always accepted.
                    let swaps = d.swaps.as_ref().expect("an ensemble's swaps");
                    assert!(swaps.attempts[1] > 0 && swaps.accepted[1] == swaps.attempts[1], "{swaps:?}");
                    assert!(swaps.accepted[5] < swaps.attempts[5], "depth {}: {swaps:?}", d.depth);
                }
                "power" | "independent" => {
                    let ladder = &d.ladder;
                    assert!(ladder.len() == 3 && ladder[2] > ladder[1], "depth {}: {ladder:?}", d.depth);
                    let ratios = &d.replica_b_ratios;
                    assert!(ratios.len() == 3 && ratios.iter().all(|r| r.is_finite() && *r > 0.0), "{ratios:?}");
                }
                _ => assert!(d.ladder == vec![0.0] && d.swaps.is_none(), "depth {} not collapsed: {d:?}", d.depth),
            }
        }
    }
}

#[test]
fn every_swap_strategy_agrees_with_bdpt_and_is_deterministic() {
    let (scene, bdpt) = default_scene_and_bdpt();
    let cancel = AtomicBool::new(false);
    let control = RenderControl::new(&cancel, &|_| {});
    for swap in [Swap::Neighbor, Swap::EquiEnergy, Swap::Permutation] {
        let t = TemperedIntegrator {
            bootstrap: 50_000,
            chains: 16,
            replicas: 4,
            swap,
            ensembles_below: 0,
            bdpt_above: None,
            ..TemperedIntegrator::new(5)
        };
        let out = t.render(&scene, &settings(256, 2, 0), &control).unwrap();
        assert_agrees(&format!("{swap:?}"), &out.image, &bdpt.image);
        let swaps = out.chains[2].swaps.as_ref().expect("depth 2 has an ensemble");
        let accepted: u64 = swaps.accepted.iter().sum();
        assert!(swaps.steps > 0 && accepted + swaps.non_identity > 0, "{swap:?}: {swaps:?}");
        assert_eq!(out.chains[2].ladder.len(), 4);
        let small = TemperedIntegrator {
            bootstrap: 2_000,
            chains: 4,
            replicas: 3,
            swap,
            ensembles_below: 0,
            bdpt_above: None,
            ..TemperedIntegrator::new(4)
        };
        let run = |threads| small.render(&scene, &settings(4, 7, threads), &control).unwrap().image.pixels;
        assert!(run(1) == run(2), "{swap:?}: same image at any thread count");
    }
}

/// The pilot that decides whether a depth's ensembles pay: with no swaps and replica 0
/// alone writing the image, an ensemble's main chain is a plain MMLT chain and its hot
/// replica traces as many rays again for nothing, so every depth must collapse (a pilot
/// that ignored the rays' cost keeps depth 1's ensembles). The image stays BDPT's, and the
/// same at any thread count.
#[test]
fn the_pilot_collapses_depths_whose_ensembles_do_not_pay() {
    let cornell = crate::scenes::cornell_box(32, 32).build().unwrap();
    let cancel = AtomicBool::new(false);
    let control = RenderControl::new(&cancel, &|_| {});
    let t = TemperedIntegrator {
        bootstrap: 20_000,
        chains: 16,
        replicas: 2,
        reuse_replicas: false,
        swap_every: 1_000_000_000,
        pilot: 256,
        ensembles_below: 0,
        bdpt_above: None,
        ..TemperedIntegrator::new(5)
    };
    let out = t.render(&cornell, &settings(512, 2, 0), &control).unwrap();
    for d in out.chains.iter().filter(|d| d.depth > 0 && d.mutations > 0) {
        assert!(d.ladder == vec![0.0] && d.swaps.is_none(), "depth {} kept its ensembles: {:?}", d.depth, d.ladder);
    }
    let bdpt = render_with(&cornell, &BdptIntegrator::new(5), Budget::Samples(256), 1, 0);
    let (a, b) = (block_stats(&out.image, 16), block_stats(&bdpt.image, 16));
    for (i, ((ma, _), (mb, sb))) in a.iter().zip(&b).enumerate() {
        assert!((ma - mb).abs() < 4.0 * sb + 0.03 * mb, "block {i}: {ma} vs {mb} ± {sb}");
    }
    let small = TemperedIntegrator { pilot: 64, ..t };
    let run = |threads| small.render(&cornell, &settings(256, 7, threads), &control).unwrap().image.pixels;
    assert!(run(1) == run(2), "same image at any thread count");
}

/// `ensembles_below`: ensembles exactly at the depths whose bootstrap holds fewer non-zero
/// values than the threshold, plain MMLT chains elsewhere. With every depth plain the render is
/// MMLT's bit for bit (by spread, and with `spread_only_sparse` by `b_k`, as MMLT allots, which
/// the defaults do); a mixed render agrees with BDPT and is the same at any thread count.
#[test]
fn ensembles_only_where_the_bootstrap_is_sparse() {
    let (scene, bdpt) = default_scene_and_bdpt();
    let cancel = AtomicBool::new(false);
    let control = RenderControl::new(&cancel, &|_| {});
    // Shaped as tempered MMLT's defaults shape (where the pilot chooses to), jumping and
    // moving the film position as they do.
    let TemperedIntegrator { importance_pilot, jumps, film_steps, lens_steps, .. } = TemperedIntegrator::new(5);
    let mmlt = MmltIntegrator {
        bootstrap: 20_000,
        chains: 16,
        importance_pilot,
        jumps,
        film_steps,
        lens_steps,
        ..MmltIntegrator::new(5)
    };
    let t = TemperedIntegrator {
        bootstrap: 20_000,
        chains: 16,
        replicas: 2,
        ensembles_below: 0,
        bdpt_above: None,
        ..TemperedIntegrator::new(5)
    };
    for spread in [true, false] {
        let a = MmltIntegrator { spread_allocation: spread, ..mmlt }.render(&scene, &settings(16, 3, 0), &control);
        let plain = TemperedIntegrator { ensembles_below: 1, spread_only_sparse: !spread, ..t.clone() };
        let b = plain.render(&scene, &settings(16, 3, 0), &control).unwrap();
        assert!(a.unwrap().image.pixels == b.image.pixels, "every depth plain is MMLT bit for bit ({spread})");
    }
    // With its defaults tempered MMLT renders a scene without sparse depths as MMLT does.
    let a = mmlt.render(&scene, &settings(4, 3, 0), &control).unwrap();
    assert!(a.chains.iter().all(|d| d.depth == 0 || d.bootstrap_nonzero >= 128), "no sparse depth");
    let defaults = TemperedIntegrator { bootstrap: 20_000, chains: 16, bdpt_above: None, ..TemperedIntegrator::new(5) };
    let b = defaults.render(&scene, &settings(4, 3, 0), &control).unwrap();
    assert!(a.image.pixels == b.image.pixels, "the defaults are MMLT's where no depth is sparse");
    // A threshold between the depths' counts of non-zero bootstrap values.
    let counts: Vec<(usize, u64)> =
        a.chains.iter().filter(|d| d.depth > 0 && d.mutations > 0).map(|d| (d.depth, d.bootstrap_nonzero)).collect();
    let mut sorted: Vec<u64> = counts.iter().map(|c| c.1).collect();
    sorted.sort_unstable();
    let below = sorted[sorted.len() / 2] as usize;
    assert!(sorted[0] < below as u64, "the depths' counts differ: {counts:?}");
    let mixed = TemperedIntegrator { ensembles_below: below, spread_only_sparse: true, ..t };
    let out = mixed.render(&scene, &settings(256, 2, 0), &control).unwrap();
    for (depth, nonzero) in counts {
        let d = out.chains.iter().find(|d| d.depth == depth).unwrap();
        let ensembles = (nonzero as usize) < below;
        assert_eq!(d.ladder.len(), if ensembles { 2 } else { 1 }, "depth {depth}, {nonzero} non-zero: {:?}", d.ladder);
        assert_eq!(d.swaps.is_some(), ensembles, "depth {depth}");
    }
    assert_agrees("sparse", &out.image, &bdpt.image);
    let run = |threads| mixed.render(&scene, &settings(8, 7, threads), &control).unwrap().image.pixels;
    assert!(run(1) == run(2), "same image at any thread count");
}

/// `swap_every` spaces the swap steps: one per `n` sweeps of each ensemble.
#[test]
fn swap_steps_follow_the_swap_interval() {
    let mut scene = crate::scenes::default_scene().build().unwrap();
    scene.set_resolution(16, 16);
    let cancel = AtomicBool::new(false);
    let control = RenderControl::new(&cancel, &|_| {});
    for every in [1, 4] {
        let t = TemperedIntegrator {
            bootstrap: 5_000,
            chains: 8,
            replicas: 3,
            swap_every: every,
            ensembles_below: 0,
            bdpt_above: None,
            ..TemperedIntegrator::new(4)
        };
        let out = t.render(&scene, &settings(32, 1, 0), &control).unwrap();
        for d in out.chains.iter().filter(|d| d.depth > 0 && d.mutations > 0) {
            let steps = d.swaps.as_ref().unwrap().steps;
            // Each of the depth's 8 ensembles rounds its own count down.
            assert!(steps * every <= d.mutations && steps * every + 8 * every > d.mutations, "every {every}: {d:?}");
        }
    }
}

/// `bdpt_above`: on the default scene (light found by independent samples about as often as
/// by chains: independent acceptance above the default threshold) tempered MMLT with its
/// defaults renders by BDPT alone, exactly BDPT's image at the samples per pixel it chose,
/// fewer than the mutations per pixel asked for (a BDPT sample traces more rays than a
/// mutation); on the glossy corner (light on narrow highlights) it runs its chains, exactly
/// as without the choice, and says which in depth 0's row.
#[test]
fn bdpt_alone_where_the_bootstrap_says_the_chains_cannot_pay() {
    let mut scene = crate::scenes::default_scene().build().unwrap();
    scene.set_resolution(24, 24);
    let render = |i: &dyn Integrator, scene, mpp, threads| render_with(scene, i, Budget::Samples(mpp), 3, threads);
    let t = TemperedIntegrator { bootstrap: 20_000, chains: 16, ..TemperedIntegrator::new(5) };
    let out = render(&t, &scene, 64, 0);
    let a = out.chains[0].independent_acceptance.expect("the choice is reported");
    assert!(a > crate::integrator::tempered::DEFAULT_BDPT_ABOVE, "{a}");
    assert!(out.chains.iter().all(|d| d.mutations == 0), "no chains ran");
    let spp = out.stats.spp_completed;
    assert!((1..64).contains(&spp), "{spp} samples per pixel");
    let bdpt = render(&BdptIntegrator::new(5), &scene, spp, 0);
    assert!(out.image.pixels == bdpt.image.pixels, "BDPT's image");
    let again = render(&t, &scene, 64, 1);
    assert!(again.image.pixels == out.image.pixels, "the same image at any thread count");

    let glossy = super::tuning::glossy_corner(0.02);
    let t = TemperedIntegrator { bootstrap: 20_000, chains: 8, ..TemperedIntegrator::new(3) };
    let chosen = render(&t, &glossy, 16, 0);
    let a = chosen.chains[0].independent_acceptance.expect("the choice is reported");
    assert!(a < crate::integrator::tempered::DEFAULT_BDPT_ABOVE, "{a}");
    assert!(chosen.chains.iter().any(|d| d.mutations > 0), "the chains ran");
    let never = render(&TemperedIntegrator { bdpt_above: None, ..t }, &glossy, 16, 0);
    assert!(chosen.image.pixels == never.image.pixels, "the chains' image, bootstrapped once");
    assert!(never.chains[0].independent_acceptance.is_none());
}
