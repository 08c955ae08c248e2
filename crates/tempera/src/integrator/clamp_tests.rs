//! MMLT with a clamped target (`target_clamp`): a chain on `g = min(f, c)` splatting `C/g`,
//! normalised by `E[g]`, renders the image a chain on `f` does.

use super::tests::{block_stats, render_with};
use super::*;
use crate::mcmc::Moments;
use crate::mcmc::all_strategies::all_strategies;

/// Clamped at twice the mean of the non-zero bootstrap values (far below what the option is
/// for, so that the clamp lowers every depth's `b`), MMLT still agrees with BDPT
/// on a Cornell box, block by block, and on the default scene (caustics), in the mean; the
/// clamp did bite (every clamped depth's `b` is well below the unclamped one), and the
/// clamped render is the same at any thread count.
#[test]
fn clamped_mmlt_agrees_with_bdpt() {
    let scene = crate::scenes::cornell_box(32, 32).build().unwrap();
    let bdpt = render_with(&scene, &BdptIntegrator::new(5), Budget::Samples(256), 1, 0);
    let plain = MmltIntegrator { bootstrap: 200_000, ..MmltIntegrator::new(5) };
    let clamped = MmltIntegrator { target_clamp: 2.0, ..plain };
    let out = render_with(&scene, &clamped, Budget::Samples(2048), 2, 0);
    let (a, b) = (block_stats(&out.image, 16), block_stats(&bdpt.image, 16));
    let mean = |s: &[(f64, f64)]| s.iter().map(|v| v.0).sum::<f64>() / s.len() as f64;
    assert!((mean(&a) / mean(&b) - 1.0).abs() < 0.01, "image means {} vs {}", mean(&a), mean(&b));
    for (i, ((ma, _), (mb, sb))) in a.iter().zip(&b).enumerate() {
        assert!((ma - mb).abs() < 4.0 * sb + 0.03 * mb, "block {i}: clamped mmlt {ma} vs bdpt {mb} ± {sb}");
    }
    let unclamped = render_with(&scene, &plain, Budget::Samples(64), 2, 0);
    let ratios: Vec<f64> = out.chains.iter().zip(&unclamped.chains).skip(1).map(|(c, u)| c.b / u.b).collect();
    assert!(ratios.iter().all(|&r| r < 0.99) && ratios.iter().any(|&r| r < 0.9), "clamped b / b: {ratios:?}");

    let mut scene = crate::scenes::default_scene().build().unwrap();
    scene.set_resolution(24, 24);
    let m = MmltIntegrator { bootstrap: 50_000, chains: 16, target_clamp: 4.0, ..MmltIntegrator::new(5) };
    let out = render_with(&scene, &m, Budget::Samples(1024), 3, 0);
    let bdpt = render_with(&scene, &BdptIntegrator::new(5), Budget::Samples(512), 1, 0);
    let mean =
        |img: &crate::texture::Image| img.pixels.iter().map(|p| f64::from(p.y)).sum::<f64>() / img.pixels.len() as f64;
    assert!((mean(&out.image) / mean(&bdpt.image) - 1.0).abs() < 0.03, "{} vs {}", mean(&out.image), mean(&bdpt.image));

    scene.set_resolution(16, 12);
    let one = render_with(&scene, &m, Budget::Samples(16), 5, 1);
    let two = render_with(&scene, &m, Budget::Samples(16), 5, 2);
    assert!(one.image.pixels == two.image.pixels, "a clamped render differs between thread counts");
}

/// The all-strategy normaliser of a clamped target estimates the clamped target's mean: at
/// depths 1–3 of the default scene, clamped at 1.5 times the mean non-zero value, it agrees
/// with the mean of `min(f, c)` over MMLT's own samples (within four standard errors) and
/// differs from the unclamped mean by more than ten.
#[test]
fn the_clamped_normaliser_estimates_the_clamped_mean() {
    let mut scene = crate::scenes::default_scene().build().unwrap();
    scene.set_resolution(16, 16);
    for k in 1..=3 {
        let n = 200_000;
        let values = crate::testing::mmlt_target_values(&scene, k, 9, n);
        let nonzero: Vec<f64> = values.iter().copied().filter(|&v| v > 0.0).collect();
        let c = 1.5 * nonzero.iter().sum::<f64>() / nonzero.len() as f64;
        let mut clamped = Moments::default();
        values.iter().for_each(|&v| clamped.push(v.min(c)));
        let (all, _) = all_strategies(&scene, k, 9, n, (c as f32, None));
        crate::testing::assert_same_mean(&format!("depth {k}"), &clamped, &all.moments);
        let (unclamped, _) = all_strategies(&scene, k, 9, n, (f32::INFINITY, None));
        let (mc, ec) = all.moments.mean_and_rel_se();
        let (mu, eu) = unclamped.moments.mean_and_rel_se();
        let sigma = ((mc * ec).powi(2) + (mu * eu).powi(2)).sqrt();
        assert!(mu - mc > 10.0 * sigma, "depth {k}: the clamp changed little: {mc} vs {mu} ± {sigma}");
    }
}
