//! Markov chains combined with bidirectional path tracing (`hybrid`, [`crate::mcmc::hybrid`]):
//! the combination renders BDPT's image whatever the weights lean on, with the chains' target
//! clamped too, and it is the same image at any thread count.

use super::tests::{block_stats, render_with};
use super::*;
use crate::texture::Image;

fn mean(img: &Image) -> f64 {
    img.pixels.iter().map(|p| f64::from(p.y)).sum::<f64>() / img.pixels.len() as f64
}

/// Agreement with BDPT on a Cornell box, block by block, with the weights leaning on the
/// independent samples (a mutation worth a thousandth of a sample), balanced (1), and on the
/// chains (100), and with weights that give the samples 5 % and 95 % of each depth's light
/// ([`crate::mcmc::hybrid::HybridDepth::with_share`]): the chains' and the samples' weights sum to one at every point only if both
/// value it alike (the chains' `f` is the strategy's luminance times the depth's `n`
/// strategies, and depth 0 has one), so a mismatch shows as a bias wherever both carry light.
#[test]
fn hybrid_mmlt_agrees_with_bdpt_on_a_cornell_box() {
    let scene = crate::scenes::cornell_box(32, 32).build().unwrap();
    let bdpt = render_with(&scene, &BdptIntegrator::new(5), Budget::Samples(256), 1, 0);
    let b = block_stats(&bdpt.image, 16);
    let weights = [(1e-3, None), (1.0, None), (100.0, None), (1.0, Some(0.05)), (1.0, Some(0.95))];
    for (efficiency, sample_share) in weights {
        let m = MmltIntegrator {
            bootstrap: 100_000,
            hybrid: 0.25,
            chain_efficiency: efficiency,
            sample_share,
            ..MmltIntegrator::new(5)
        };
        let out = render_with(&scene, &m, Budget::Samples(1024), 2, 0);
        let a = block_stats(&out.image, 16);
        let mean = |s: &[(f64, f64)]| s.iter().map(|v| v.0).sum::<f64>() / s.len() as f64;
        assert!(
            (mean(&a) / mean(&b) - 1.0).abs() < 0.01,
            "{efficiency} {sample_share:?}: image means {} vs {}",
            mean(&a),
            mean(&b)
        );
        for (i, ((ma, _), (mb, sb))) in a.iter().zip(&b).enumerate() {
            assert!(
                (ma - mb).abs() < 4.0 * sb + 0.03 * mb,
                "{efficiency} {sample_share:?}, block {i}: hybrid {ma} vs bdpt {mb} ± {sb}"
            );
        }
        // A quarter of a sample per mutation, counted in depth 0's row.
        let samples: u64 = out.chains.iter().map(|d| d.hybrid_samples).sum();
        assert_eq!(samples, out.chains[0].hybrid_samples);
        assert_eq!(samples, (1024 * 32 * 32) / 4, "{:?}", out.chains);
    }
}

/// On the default scene (caustics through glass, seen in a glossy mirror), with the chains'
/// target clamped, and with tempered MMLT's ensembles (replica 0 writing the image), the
/// combination keeps BDPT's image mean; with every replica writing it, it is refused.
#[test]
fn hybrid_keeps_the_image_with_clamped_targets_and_tempered_ensembles() {
    let mut scene = crate::scenes::default_scene().build().unwrap();
    scene.set_resolution(24, 24);
    let bdpt = render_with(&scene, &BdptIntegrator::new(5), Budget::Samples(512), 1, 0);
    let clamped = MmltIntegrator {
        bootstrap: 50_000,
        chains: 16,
        target_clamp: 4.0,
        hybrid: 0.2,
        chain_efficiency: 1.0,
        ..MmltIntegrator::new(5)
    };
    let out = render_with(&scene, &clamped, Budget::Samples(1024), 3, 0);
    assert!((mean(&out.image) / mean(&bdpt.image) - 1.0).abs() < 0.03, "{} vs {}", mean(&out.image), mean(&bdpt.image));
    let tempered = TemperedIntegrator {
        bootstrap: 50_000,
        chains: 16,
        reuse_replicas: false,
        hybrid: 0.2,
        chain_efficiency: 1.0,
        ensembles_below: 0,
        bdpt_above: None,
        importance_pilot: 0,
        ..TemperedIntegrator::new(5)
    };
    let out = render_with(&scene, &tempered, Budget::Samples(512), 4, 0);
    assert!((mean(&out.image) / mean(&bdpt.image) - 1.0).abs() < 0.03, "{} vs {}", mean(&out.image), mean(&bdpt.image));
    let reused = TemperedIntegrator { reuse_replicas: true, ..tempered };
    let cancel = std::sync::atomic::AtomicBool::new(false);
    let control = RenderControl::new(&cancel, &|_| {});
    let settings = RenderSettings { budget: Budget::Samples(4), seed: 1, threads: 0 };
    let err = reused.render(&scene, &settings, &control).err().expect("refused");
    assert!(err.contains("replica 0"), "{err}");
}

/// The same seed and budget give the same image at one, two and three threads, with and
/// without per-depth images (whose sum is the image).
#[test]
fn hybrid_mmlt_is_bit_identical_at_any_thread_count() {
    let scene = crate::scenes::cornell_box(16, 16).build().unwrap();
    for depth_images in [false, true] {
        let m = MmltIntegrator { bootstrap: 5_000, chains: 8, hybrid: 0.5, depth_images, ..MmltIntegrator::new(4) };
        let run = |threads| render_with(&scene, &m, Budget::Samples(16), 9, threads);
        let one = run(1);
        assert!(one.image.pixels == run(2).image.pixels && one.image.pixels == run(3).image.pixels);
        if depth_images {
            assert_eq!(one.layers.len(), 5);
            for (i, p) in one.image.pixels.iter().enumerate() {
                let sum: f32 = one.layers.iter().map(|l| l.pixels[i].y).sum();
                assert!((sum - p.y).abs() <= 1e-4 * p.y.abs() + 1e-6, "pixel {i}: {sum} vs {}", p.y);
            }
        }
    }
}

/// `--hybrid auto` under a fixed budget: on a diffuse Cornell box, where BDPT beats the chains
/// by far, the pilot has BDPT render alone, with as many samples per pixel as it made in the
/// rays of the budget's mutations; the image agrees with BDPT's, is the same at one and three
/// threads (the pilot measures work in rays), and the statistics carry the choice in a row of
/// its own. Tempered MMLT chooses so too.
#[test]
fn hybrid_auto_chooses_by_a_pilot_and_keeps_the_image() {
    let scene = crate::scenes::cornell_box(24, 24).build().unwrap();
    let bdpt = render_with(&scene, &BdptIntegrator::new(5), Budget::Samples(256), 1, 0);
    let m = MmltIntegrator { bootstrap: 20_000, chains: 16, hybrid_auto: true, ..MmltIntegrator::new(5) };
    let one = render_with(&scene, &m, Budget::Samples(256), 5, 1);
    let choice = one.chains[0].hybrid_choice.expect("the pilot's choice is reported");
    assert!(choice.variance_ratio < 0.7 && choice.bdpt_alone(), "{choice:?}");
    assert_eq!(one.chains.len(), 1);
    assert_eq!((one.chains[0].mutations, one.chains[0].hybrid_samples), (0, 0));
    let spp = (256.0 * choice.samples_per_mutation).round() as u64;
    assert!(spp >= 8 && one.stats.pixel_samples == spp * 24 * 24, "{spp} spp, {:?}", one.stats);
    assert!((mean(&one.image) / mean(&bdpt.image) - 1.0).abs() < 0.02, "{} vs {}", mean(&one.image), mean(&bdpt.image));
    assert!(one.image.pixels == render_with(&scene, &m, Budget::Samples(256), 5, 3).image.pixels);
    let tempered = TemperedIntegrator {
        bootstrap: 20_000,
        chains: 16,
        hybrid_auto: true,
        ensembles_below: 0,
        bdpt_above: None,
        importance_pilot: 0,
        ..TemperedIntegrator::new(5)
    };
    let out = render_with(&scene, &tempered, Budget::Samples(128), 6, 0);
    assert!(out.chains[0].hybrid_choice.is_some_and(|c| c.bdpt_alone()), "{:?}", out.chains[0]);
    assert!((mean(&out.image) / mean(&bdpt.image) - 1.0).abs() < 0.02, "{} vs {}", mean(&out.image), mean(&bdpt.image));
}
