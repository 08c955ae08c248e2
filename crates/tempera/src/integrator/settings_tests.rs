//! The integrator settings: what is serialised, how they are checked against the integrator
//! and each other, and the names of the integrators.

use super::settings::*;
use crate::bidir::Heuristic;
use crate::scene::RenderDefaults;

/// Only the settings given are serialised, so records of them (cache keys) do not change
/// when a setting is added; they read back as they were.
#[test]
fn absent_settings_are_left_out_when_serialised() {
    let given = IntegratorSettings {
        replicas: Some(2),
        tuning: Some(LadderTuning::BurnIn),
        burn_in: Some(40),
        ..Default::default()
    };
    let json = serde_json::to_string(&given).unwrap();
    assert_eq!(json, r#"{"replicas":2,"tuning":"burn-in","burn_in":40}"#);
    assert_eq!(serde_json::from_str::<IntegratorSettings>(&json).unwrap(), given);
    assert_eq!(serde_json::to_string(&IntegratorSettings::default()).unwrap(), "{}");
}

#[test]
fn settings_are_checked_against_the_integrator_and_each_other() {
    let ok = IntegratorSettings { replicas: Some(3), ladder: Some(vec![0.1, 0.3]), ..Default::default() };
    assert!(create(IntegratorKind::Tempered, &ok, &RenderDefaults::default()).is_ok());
    // Cold replicas: only zeros may repeat.
    let cold = IntegratorSettings { replicas: Some(4), ladder: Some(vec![0.0, 0.0, 0.3]), ..Default::default() };
    assert!(create(IntegratorKind::Tempered, &cold, &RenderDefaults::default()).is_ok());
    let cases = [
        (IntegratorKind::Mmlt, IntegratorSettings { replicas: Some(3), ..Default::default() }, "replicas is not"),
        (IntegratorKind::Path, IntegratorSettings { mis: Some(Heuristic::Balance), ..Default::default() }, "mis"),
        (IntegratorKind::Tempered, IntegratorSettings { replicas: Some(4), ..ok.clone() }, "must be 3"),
        (IntegratorKind::Tempered, IntegratorSettings { ladder: Some(vec![0.3, 0.1]), ..ok.clone() }, "increase"),
        (IntegratorKind::Tempered, IntegratorSettings { ladder: Some(vec![0.3, 0.3]), ..ok.clone() }, "increase"),
        (IntegratorKind::Tempered, IntegratorSettings { ladder: Some(vec![-0.1, 0.3]), ..ok.clone() }, "[0, 1000]"),
        (IntegratorKind::Mmlt, IntegratorSettings { large_step: Some(0.0), ..Default::default() }, "probability"),
        (IntegratorKind::Mmlt, IntegratorSettings { chains: Some(0), ..Default::default() }, "chains must lie"),
        (IntegratorKind::Mmlt, IntegratorSettings { sigma: Some(0.0), ..Default::default() }, "sigma must lie"),
        (IntegratorKind::Pssmlt, IntegratorSettings { sigma: Some(f32::NAN), ..Default::default() }, "sigma must lie"),
        (IntegratorKind::Bdpt, IntegratorSettings { sigma: Some(0.02), ..Default::default() }, "sigma is not"),
        (IntegratorKind::Pssmlt, IntegratorSettings { jumps: Some(0.1), ..Default::default() }, "jumps is not"),
        (IntegratorKind::Mmlt, IntegratorSettings { jumps: Some(1.5), ..Default::default() }, "jumps must be"),
        (IntegratorKind::Tempered, IntegratorSettings { jumps: Some(f32::NAN), ..Default::default() }, "jumps must be"),
        (
            IntegratorKind::Pssmlt,
            IntegratorSettings { film_steps: Some(0.1), ..Default::default() },
            "film_steps is not",
        ),
        (
            IntegratorKind::Mmlt,
            IntegratorSettings { film_steps: Some(-0.5), ..Default::default() },
            "film_steps must be",
        ),
        (
            IntegratorKind::Tempered,
            IntegratorSettings { film_steps: Some(0.3), paper: Some(true), ..Default::default() },
            "fixes film_steps",
        ),
        (
            IntegratorKind::Tempered,
            IntegratorSettings { jumps: Some(0.0), paper: Some(true), ..Default::default() },
            "fixes jumps",
        ),
        (IntegratorKind::Bdpt, IntegratorSettings { lens_steps: Some(0.1), ..Default::default() }, "lens_steps is not"),
        (
            IntegratorKind::Tempered,
            IntegratorSettings { lens_steps: Some(1.01), ..Default::default() },
            "lens_steps must be",
        ),
        (
            IntegratorKind::Tempered,
            IntegratorSettings { lens_steps: Some(0.3), paper: Some(true), ..Default::default() },
            "fixes lens_steps",
        ),
        (
            IntegratorKind::Mmlt,
            IntegratorSettings { importance_pilot: Some(2000), ..Default::default() },
            "importance_pilot",
        ),
        (
            IntegratorKind::Tempered,
            IntegratorSettings { importance_floor: Some(0.0), ..Default::default() },
            "floor must",
        ),
        (
            IntegratorKind::Mmlt,
            IntegratorSettings { importance_power: Some(2.5), ..Default::default() },
            "importance_power must",
        ),
        (
            IntegratorKind::Path,
            IntegratorSettings { importance_power: Some(0.5), ..Default::default() },
            "importance_power is not",
        ),
        (
            IntegratorKind::Tempered,
            IntegratorSettings { reallot_at: Some(1.5), ..Default::default() },
            "reallot_at must",
        ),
        (
            IntegratorKind::Bdpt,
            IntegratorSettings { reallot_at: Some(0.25), ..Default::default() },
            "reallot_at is not",
        ),
        (
            IntegratorKind::Mmlt,
            IntegratorSettings { importance_share: Some(0.9), ..Default::default() },
            "importance_share must",
        ),
        (
            IntegratorKind::Bdpt,
            IntegratorSettings { importance_share: Some(0.1), ..Default::default() },
            "importance_share is not",
        ),
        (
            IntegratorKind::Pssmlt,
            IntegratorSettings { importance_pilot: Some(4), ..Default::default() },
            "importance_pilot is not",
        ),
        (
            IntegratorKind::Tempered,
            IntegratorSettings { max_temperature: Some(0.5), ..Default::default() },
            "max_temperature must lie",
        ),
        (
            IntegratorKind::Tempered,
            IntegratorSettings { collapse_above: Some(0.0), ..Default::default() },
            "collapse_above must be a probability",
        ),
        (IntegratorKind::Mmlt, IntegratorSettings { photons: Some(10), ..Default::default() }, "photons is not"),
        (
            IntegratorKind::Mmlt,
            IntegratorSettings { hybrid: Some(Hybrid::Ratio(-0.1)), ..Default::default() },
            "hybrid must be",
        ),
        (
            IntegratorKind::Mmlt,
            IntegratorSettings { hybrid: Some(Hybrid::Ratio(f64::NAN)), ..Default::default() },
            "hybrid must be",
        ),
        (
            IntegratorKind::Tempered,
            IntegratorSettings { chain_efficiency: Some(0.0), ..Default::default() },
            "chain_efficiency must be",
        ),
        (
            IntegratorKind::Pssmlt,
            IntegratorSettings { hybrid: Some(Hybrid::Ratio(0.1)), ..Default::default() },
            "hybrid is not",
        ),
        (
            IntegratorKind::Mmlt,
            IntegratorSettings { hybrid_share: Some(1.0), ..Default::default() },
            "hybrid_share must",
        ),
        (
            IntegratorKind::Pssmlt,
            IntegratorSettings { hybrid_share: Some(0.5), ..Default::default() },
            "hybrid_share is not",
        ),
        (
            IntegratorKind::Mmlt,
            IntegratorSettings { bridge_above: Some(-0.1), ..Default::default() },
            "bridge_above must lie",
        ),
        (
            IntegratorKind::Tempered,
            IntegratorSettings { bridge_above: Some(f64::NAN), ..Default::default() },
            "bridge_above must lie",
        ),
        (IntegratorKind::Path, IntegratorSettings { bridge_above: Some(0.1), ..Default::default() }, "not a setting"),
        (IntegratorKind::Sppm, IntegratorSettings { radius: Some(-1.0), ..Default::default() }, "radius must be"),
        (IntegratorKind::Sppm, IntegratorSettings { photons: Some(0), ..Default::default() }, "photons must lie"),
        (IntegratorKind::Mmlt, IntegratorSettings { collapse_above: Some(0.5), ..Default::default() }, "not a setting"),
        (IntegratorKind::Mmlt, IntegratorSettings { ensembles_below: Some(64), ..Default::default() }, "not a setting"),
        (
            IntegratorKind::Mmlt,
            IntegratorSettings { allocation: Some(Allocation::Sparse), ..Default::default() },
            "follows tempered MMLT's ensembles_below",
        ),
        (
            IntegratorKind::Tempered,
            IntegratorSettings { tuning: Some(LadderTuning::Bootstrap), burn_in: Some(100), ..Default::default() },
            "needs tuning = burn-in",
        ),
        (
            IntegratorKind::Tempered,
            IntegratorSettings { swap: Some(Swap::Permutation), replicas: Some(9), ..Default::default() },
            "at most 8",
        ),
    ];
    for (kind, settings, needle) in cases {
        let err = create(kind, &settings, &RenderDefaults { max_depth: 5, ..RenderDefaults::default() })
            .err()
            .unwrap_or_default();
        assert!(err.contains(needle), "{kind} {settings:?}: {err:?}");
    }
}

#[test]
fn names_round_trip() {
    for kind in IntegratorKind::ALL {
        assert_eq!(IntegratorKind::from_name(kind.name()), Some(kind));
    }
    assert_eq!(IntegratorKind::from_name("sppm"), Some(IntegratorKind::Sppm));
    assert_eq!(IntegratorKind::from_name("vcm"), None);
}

/// `hybrid` is a ratio or the word `auto`, on the command line and in settings files.
#[test]
fn hybrid_is_a_ratio_or_auto() {
    assert_eq!("0.25".parse::<Hybrid>(), Ok(Hybrid::Ratio(0.25)));
    assert!("Auto".parse::<Hybrid>().is_ok_and(Hybrid::is_auto));
    assert!("often".parse::<Hybrid>().unwrap_err().contains("`auto`"));
    let parsed: IntegratorSettings = serde_json::from_str(r#"{"hybrid": "auto"}"#).unwrap();
    assert!(parsed.hybrid.is_some_and(Hybrid::is_auto));
    let parsed: IntegratorSettings = serde_json::from_str(r#"{"hybrid": 0.5}"#).unwrap();
    assert_eq!(parsed.hybrid, Some(Hybrid::Ratio(0.5)));
    assert!(serde_json::from_str::<IntegratorSettings>(r#"{"hybrid": "sometimes"}"#).is_err());
}

/// A scene's Markov-chain parameters (pbrt-v4's `mlt` integrator) reach every Markov-chain
/// integrator as the settings would: with the scene's `sigma`, large-step probability and
/// chains the image is bit for bit the one those settings give, and another than without
/// them; settings given override the scene's. Its mutations per pixel are the budget of a
/// Markov-chain render that names none, and not of other integrators.
#[test]
fn the_scenes_chain_parameters_act_as_settings() {
    use super::tests::render_with;
    use super::{Budget, IntegratorKind::*};
    use crate::scene::ChainDefaults;
    let scene = crate::scenes::cornell_box(8, 8).build().unwrap();
    let plain = RenderDefaults { max_depth: 3, ..RenderDefaults::default() };
    let chain =
        ChainDefaults { mpp: Some(7), bootstrap: Some(500), chains: Some(3), large_step: Some(0.5), sigma: Some(0.05) };
    let given = RenderDefaults { chain: chain.clone(), ..plain.clone() };
    let as_settings = IntegratorSettings {
        bootstrap: Some(500),
        chains: Some(3),
        large_step: Some(0.5),
        sigma: Some(0.05),
        ..Default::default()
    };
    let pixels = |kind, settings: &IntegratorSettings, defaults: &RenderDefaults| {
        let integrator = create(kind, settings, defaults).unwrap();
        render_with(&scene, integrator.as_ref(), Budget::Samples(4), 5, 1).image.pixels
    };
    for kind in [Mmlt, Pssmlt, Tempered] {
        // Tempered MMLT keeps its chains on this box (BDPT alone otherwise).
        let none = IntegratorSettings { bdpt_above: (kind == Tempered).then_some(f64::INFINITY), ..Default::default() };
        let as_settings = IntegratorSettings { bdpt_above: none.bdpt_above, ..as_settings.clone() };
        let from_scene = pixels(kind, &none, &given);
        assert_eq!(from_scene, pixels(kind, &as_settings, &plain), "{kind}");
        assert_ne!(from_scene, pixels(kind, &none, &plain), "{kind}");
        let overridden = IntegratorSettings { sigma: Some(0.01), ..as_settings.clone() };
        assert_eq!(pixels(kind, &overridden, &given), pixels(kind, &overridden, &plain), "{kind}");
        assert_eq!(given.per_pixel(kind), 7);
    }
    assert_eq!((given.per_pixel(Bdpt), plain.per_pixel(Mmlt)), (16, 16));
}
