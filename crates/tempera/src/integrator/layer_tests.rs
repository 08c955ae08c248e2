//! Extra images of a render: BDPT's per-strategy images and the Markov-chain integrators'
//! per-depth images.

use super::tests::render_with;
use super::*;
use crate::math::Rgb;

#[test]
fn strategy_images_sum_to_the_bdpt_image() {
    let scene = crate::scenes::cornell_box(16, 16).build().unwrap();
    let integrator = BdptIntegrator { strategy_images: true, ..BdptIntegrator::new(3) };
    let out = render_with(&scene, &integrator, Budget::Samples(8), 4, 0);
    let names = integrator.layer_names();
    assert_eq!(names.len(), out.layers.len());
    assert_eq!(names.len(), 2 + 3 + 4 + 5 - 1);
    assert!(names.contains(&"s2_t1".to_owned()) && names.contains(&"s0_t5".to_owned()));
    for (i, p) in out.image.pixels.iter().enumerate() {
        let sum: Rgb = out.layers.iter().map(|l| l.pixels[i]).sum();
        assert!((sum - *p).abs().max_element() <= 1e-4 * p.max_element().max(1.0), "pixel {i}: {sum} vs {p}");
    }
    let light_tracing = &out.layers[names.iter().position(|n| n == "s2_t1").unwrap()];
    assert!(light_tracing.pixels.iter().any(|p| p.max_element() > 0.0), "light tracing contributes");
}

/// An image's total luminance.
fn total(image: &Image) -> f64 {
    image.pixels.iter().map(|p| f64::from(crate::math::luminance(*p))).sum()
}

/// The total luminance of each depth `k = s + t − 2` (maxdepth 3) in a 1024-spp BDPT render of
/// `scene`, from its per-strategy images.
fn bdpt_totals_per_depth(scene: &Scene) -> [f64; 4] {
    let bdpt = BdptIntegrator { strategy_images: true, ..BdptIntegrator::new(3) };
    let reference = render_with(scene, &bdpt, Budget::Samples(1024), 4, 0);
    let mut per_depth = [0.0f64; 4];
    for (name, layer) in bdpt.layer_names().iter().zip(&reference.layers) {
        let (s, t) = name.trim_start_matches('s').split_once("_t").unwrap();
        per_depth[s.parse::<usize>().unwrap() + t.parse::<usize>().unwrap() - 2] += total(layer);
    }
    per_depth
}

/// MMLT's and tempered MMLT's per-depth images: asking for them leaves the image bit for bit
/// as it was, they sum to it, and each depth's total agrees with BDPT's strategies of that
/// depth (`s + t − 2 = k`) summed.
#[test]
fn depth_images_sum_to_the_image_and_agree_with_bdpts_strategies_per_depth() {
    let scene = crate::scenes::cornell_box(16, 16).build().unwrap();
    let per_depth = bdpt_totals_per_depth(&scene);
    let mmlt = MmltIntegrator { bootstrap: 50_000, chains: 16, ..MmltIntegrator::new(3) };
    let tempered = TemperedIntegrator {
        bootstrap: 50_000,
        chains: 16,
        ensembles_below: 0,
        bdpt_above: None,
        ..TemperedIntegrator::new(3)
    };
    let cases: [(&dyn Integrator, &dyn Integrator); 2] = [
        (&mmlt, &MmltIntegrator { depth_images: true, ..mmlt }),
        (&tempered, &TemperedIntegrator { depth_images: true, ..tempered.clone() }),
    ];
    for (plain, with_images) in cases {
        let a = render_with(&scene, plain, Budget::Samples(1024), 5, 0);
        let b = render_with(&scene, with_images, Budget::Samples(1024), 5, 0);
        let name = plain.name();
        assert!(a.layers.is_empty() && plain.layer_names().is_empty());
        assert_eq!(a.image.pixels, b.image.pixels, "{name}: the image does not change");
        assert_eq!(with_images.layer_names(), ["depth0", "depth1", "depth2", "depth3"]);
        assert_eq!(b.layers.len(), 4);
        for (i, p) in b.image.pixels.iter().enumerate() {
            let sum: Rgb = b.layers.iter().map(|l| l.pixels[i]).sum();
            assert!((sum - *p).abs().max_element() <= 1e-5 * p.max_element().max(1.0), "{name} pixel {i}");
        }
        for (k, layer) in b.layers.iter().enumerate() {
            let (got, want) = (total(layer), per_depth[k]);
            assert!(want > 0.0, "depth {k} carries light");
            assert!((got / want - 1.0).abs() < 0.05, "{name} depth {k}: {got} against BDPT's {want}");
        }
    }
}

/// Depths sampled independently instead of by chains (`independent_below` above the
/// bootstrap size: every depth `k ≥ 1`): each depth's total agrees with BDPT's strategies of
/// that depth, the statistics say which depths were sampled so, and the image is the same at
/// one and at four threads.
#[test]
fn independently_sampled_depths_agree_with_bdpt_per_depth() {
    let scene = crate::scenes::cornell_box(16, 16).build().unwrap();
    let per_depth = bdpt_totals_per_depth(&scene);
    let mmlt = MmltIntegrator {
        bootstrap: 20_000,
        chains: 16,
        independent_below: 1_000_000,
        depth_images: true,
        ..MmltIntegrator::new(3)
    };
    let tempered = TemperedIntegrator {
        bootstrap: 20_000,
        chains: 16,
        independent_below: 1_000_000,
        depth_images: true,
        ensembles_below: 0,
        bdpt_above: None,
        ..TemperedIntegrator::new(3)
    };
    for integrator in [&mmlt as &dyn Integrator, &tempered] {
        let name = integrator.name();
        let out = render_with(&scene, integrator, Budget::Samples(512), 5, 4);
        let one = render_with(&scene, integrator, Budget::Samples(512), 5, 1);
        assert_eq!(out.image.pixels, one.image.pixels, "{name}: the same image at 1 and 4 threads");
        for d in &out.chains {
            assert_eq!(d.independent, d.depth >= 1, "{name} depth {}: sampled independently", d.depth);
            assert!(d.bootstrap_nonzero > 0 && d.bootstrap_nonzero <= d.bootstrap_samples);
        }
        for (k, layer) in out.layers.iter().enumerate() {
            let (got, want) = (total(layer), per_depth[k]);
            assert!((got / want - 1.0).abs() < 0.05, "{name} depth {k}: {got} against BDPT's {want}");
        }
    }
}

/// A depth whose bootstrap found no light has no state to start a chain from, but where its
/// normaliser saw light and the depth is sampled independently, it gets independent samples
/// all the same: with 8 bootstrap samples per depth, the first seed (of 1–40) at which some
/// depth's values are all zero while its `b` is positive still renders that depth, and its
/// total agrees with BDPT's. Without them the depth would be dark.
#[test]
fn an_independent_depth_needs_no_bootstrap_light() {
    let scene = crate::scenes::cornell_box(16, 16).build().unwrap();
    let per_depth = bdpt_totals_per_depth(&scene);
    let mmlt =
        MmltIntegrator { bootstrap: 8, chains: 4, independent_below: 1, depth_images: true, ..MmltIntegrator::new(3) };
    let found = (1..=40).find_map(|seed| {
        let out = render_with(&scene, &mmlt, Budget::Samples(512), seed, 0);
        let k = out.chains.iter().position(|d| d.depth >= 1 && d.bootstrap_nonzero == 0 && d.b > 0.0)?;
        Some((seed, k, out))
    });
    let (seed, k, out) = found.expect("a seed with a depth whose bootstrap found no light");
    let d = &out.chains[k];
    assert!(d.independent && d.mutations > 0, "seed {seed} depth {}: sampled independently", d.depth);
    let (got, want) = (total(&out.layers[d.depth]), per_depth[d.depth]);
    assert!((got / want - 1.0).abs() < 0.05, "seed {seed} depth {}: {got} against BDPT's {want}", d.depth);
}
