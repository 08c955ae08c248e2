//! Statistical tests of every BSDF: chi-square goodness of fit of sampling against `pdf`,
//! agreement of sampled values with `eval`/`pdf`, reciprocity and energy bounds.

use super::plastic::PlasticCoat;
use super::*;
use crate::math::rng::Pcg32;
use crate::testing::chi2_sphere;

const MODES: [TransportMode; 2] = [TransportMode::Radiance, TransportMode::Importance];

fn dir(theta_deg: f32, phi_deg: f32) -> Vec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

fn rough_bsdfs() -> Vec<(&'static str, Bsdf)> {
    let coat = PlasticCoat::new(1.5, false);
    vec![
        ("diffuse", Bsdf::Diffuse(Diffuse { reflectance: Rgb::new(0.8, 0.5, 0.2) })),
        (
            "diffuse transmission",
            Bsdf::DiffuseTransmission(DiffuseTransmission {
                reflectance: Rgb::new(0.3, 0.4, 0.5),
                transmittance: Rgb::new(0.6, 0.2, 0.1),
            }),
        ),
        (
            "conductor 0.2",
            Bsdf::Conductor(Conductor {
                distribution: Ggx::isotropic(0.2),
                eta: Rgb::new(0.2, 0.9, 1.1),
                k: Rgb::new(3.9, 2.4, 2.2),
                tint: Rgb::ONE,
            }),
        ),
        (
            "conductor aniso",
            Bsdf::Conductor(Conductor {
                distribution: Ggx::new(0.15, 0.5),
                eta: Rgb::splat(1.5),
                k: Rgb::splat(3.0),
                tint: Rgb::new(0.9, 0.7, 1.0),
            }),
        ),
        ("dielectric 0.2", Bsdf::Dielectric(Dielectric { distribution: Ggx::isotropic(0.2), eta: 1.5 })),
        ("dielectric 0.5", Bsdf::Dielectric(Dielectric { distribution: Ggx::isotropic(0.5), eta: 1.33 })),
        ("dielectric aniso", Bsdf::Dielectric(Dielectric { distribution: Ggx::new(0.3, 0.1), eta: 1.7 })),
        ("plastic 0.25", Bsdf::Plastic(Plastic::new(Ggx::isotropic(0.25), &coat, Rgb::new(0.7, 0.3, 0.1), 1.0))),
        ("plastic smooth", Bsdf::Plastic(Plastic::new(Ggx::isotropic(0.0), &coat, Rgb::splat(0.5), 1.0))),
    ]
}

fn outgoing() -> [Vec3; 3] {
    [dir(10.0, 30.0), dir(60.0, 200.0), dir(130.0, 80.0)]
}

#[test]
fn sampling_matches_pdf_chi_square() {
    for (name, bsdf) in rough_bsdfs() {
        for (k, wo) in outgoing().into_iter().enumerate() {
            let r = chi2_sphere(
                400_000,
                k as u64 + 1,
                |u, uc| bsdf.sample(wo, uc, u, TransportMode::Radiance).filter(|s| !s.delta).map(|s| s.wi),
                |wi| f64::from(bsdf.pdf(wo, wi)),
            );
            assert!(r.p_value > 1e-4, "{name}, wo #{k}: chi-square p = {:e}", r.p_value);
            // The density of the non-delta lobes integrates to the fraction of non-delta samples.
            assert!(
                (r.pdf_integral - r.sampled_fraction).abs() < 0.01,
                "{name}, wo #{k}: ∫pdf = {} but {} of samples succeeded",
                r.pdf_integral,
                r.sampled_fraction
            );
        }
    }
}

#[test]
fn sampled_values_agree_with_eval_and_pdf() {
    let mut rng = Pcg32::new(3, 3);
    for (name, bsdf) in rough_bsdfs() {
        for wo in outgoing() {
            for mode in MODES {
                for _ in 0..2000 {
                    let u = Vec2::new(rng.next_f32(), rng.next_f32());
                    let Some(s) = bsdf.sample(wo, rng.next_f32(), u, mode) else {
                        continue;
                    };
                    if s.delta {
                        continue;
                    }
                    let f = bsdf.eval(wo, s.wi, mode);
                    let pdf = bsdf.pdf(wo, s.wi);
                    let tol = |a: f32| 2e-3 * a.abs().max(1e-3);
                    assert!((f - s.f).abs().max_element() <= tol(s.f.max_element()), "{name}: f {f} vs {}", s.f);
                    assert!((pdf - s.pdf).abs() <= tol(s.pdf), "{name}: pdf {pdf} vs {}", s.pdf);
                }
            }
        }
    }
}

#[test]
fn reciprocity() {
    let mut rng = Pcg32::new(5, 1);
    for (name, bsdf) in rough_bsdfs() {
        for _ in 0..5000 {
            let a = crate::math::warp::uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32()));
            let b = crate::math::warp::uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32()));
            // f(a, b) in radiance mode is the adjoint of f(b, a) in importance mode; without
            // refraction both modes agree and this is plain symmetry.
            let f_ab = bsdf.eval(a, b, TransportMode::Radiance);
            let f_ba = bsdf.eval(b, a, TransportMode::Importance);
            let scale = f_ab.max_element().max(f_ba.max_element()).max(1e-3);
            assert!((f_ab - f_ba).abs().max_element() <= 2e-3 * scale, "{name}: {f_ab} vs {f_ba} for {a} {b}");
        }
    }
}

/// Directional albedo `∫ f |cos| dωi` by importance sampling, with its standard error.
fn albedo(bsdf: &Bsdf, wo: Vec3, mode: TransportMode, n: usize) -> (f64, f64) {
    let mut rng = Pcg32::new(17, 2);
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let u = Vec2::new(rng.next_f32(), rng.next_f32());
        let v = bsdf
            .sample(wo, rng.next_f32(), u, mode)
            .map_or(0.0, |s| f64::from(crate::math::luminance(s.f) * s.wi.z.abs() / s.pdf));
        sum += v;
        sum2 += v * v;
    }
    let mean = sum / n as f64;
    (mean, ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt())
}

#[test]
fn white_furnace_energy_is_at_most_one() {
    let coat = PlasticCoat::new(1.5, false);
    let (eta, k) = fresnel::conductor_from_reflectance(Rgb::ONE);
    let white: Vec<(&str, Bsdf, f64)> = vec![
        ("diffuse", Bsdf::Diffuse(Diffuse { reflectance: Rgb::ONE }), 0.999),
        (
            "diffuse transmission",
            Bsdf::DiffuseTransmission(DiffuseTransmission {
                reflectance: Rgb::splat(0.5),
                transmittance: Rgb::splat(0.5),
            }),
            0.999,
        ),
        (
            "conductor smooth",
            Bsdf::Conductor(Conductor { distribution: Ggx::isotropic(0.0), eta, k, tint: Rgb::ONE }),
            0.99,
        ),
        (
            "conductor rough",
            Bsdf::Conductor(Conductor { distribution: Ggx::isotropic(0.3), eta, k, tint: Rgb::ONE }),
            0.8,
        ),
        ("dielectric smooth", Bsdf::Dielectric(Dielectric { distribution: Ggx::isotropic(0.0), eta: 1.5 }), 0.999),
        ("dielectric rough", Bsdf::Dielectric(Dielectric { distribution: Ggx::isotropic(0.3), eta: 1.5 }), 0.85),
        ("plastic smooth", Bsdf::Plastic(Plastic::new(Ggx::isotropic(0.0), &coat, Rgb::ONE, 1.0)), 0.95),
        ("plastic rough", Bsdf::Plastic(Plastic::new(Ggx::isotropic(0.3), &coat, Rgb::ONE, 1.0)), 0.9),
    ];
    // Lower bounds guard against lost energy: single-scattering GGX at alpha 0.3 loses about a
    // tenth at normal incidence (normals beyond 45° reflect below the horizon).
    for (name, bsdf, lower) in white {
        for wo in [dir(0.0, 0.0), dir(45.0, 10.0), dir(80.0, 100.0), dir(150.0, 40.0)] {
            // Importance mode: no 1/η² radiance scaling, so energy conservation reads ≤ 1.
            let (mean, se) = albedo(&bsdf, wo, TransportMode::Importance, 200_000);
            assert!(mean <= 1.0 + 4.0 * se + 1e-3, "{name}: albedo {mean} ± {se} exceeds one at {wo}");
            if wo.z.abs() > 0.5 {
                assert!(mean >= lower, "{name}: albedo {mean} implausibly low at {wo}");
            }
        }
    }
}

#[test]
fn smooth_dielectric_chooses_lobes_by_fresnel() {
    let bsdf = Bsdf::Dielectric(Dielectric { distribution: Ggx::isotropic(0.0), eta: 1.5 });
    let wo = dir(50.0, 0.0);
    let want = fresnel::dielectric(wo.z, 1.5);
    let mut rng = Pcg32::new(8, 8);
    let n = 100_000;
    let mut reflected = 0;
    for _ in 0..n {
        let s = bsdf.sample(wo, rng.next_f32(), Vec2::ZERO, TransportMode::Radiance).unwrap();
        assert!(s.delta);
        if !s.transmission {
            reflected += 1;
            assert!((s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-5);
        } else {
            // Snell's law and radiance scaling by 1/η².
            assert!((wo.x.hypot(wo.y) - 1.5 * s.wi.x.hypot(s.wi.y)).abs() < 1e-4);
            let ft = s.f.x * s.wi.z.abs() / s.pdf;
            assert!((ft - 1.0 / 2.25).abs() < 1e-4, "{ft}");
        }
    }
    let frac = reflected as f32 / n as f32;
    assert!((frac - want).abs() < 0.005, "{frac} vs {want}");
    assert!(bsdf.is_delta() && bsdf.eval(wo, -wo, TransportMode::Radiance) == Rgb::ZERO);
}

#[test]
fn roughening_is_the_identity_at_zero_and_widens_glossy_lobes() {
    let g = Ggx::new(0.02, 0.3);
    assert_eq!(g.roughened(0.0), g);
    let r = g.roughened(0.1);
    assert!((r.alpha_x - 0.02f32.hypot(0.1)).abs() < 1e-7 && (r.alpha_y - 0.3f32.hypot(0.1)).abs() < 1e-7);
    assert_eq!(Ggx::isotropic(0.9).roughened(0.8), Ggx::isotropic(1.0), "alpha is capped at 1");
    assert_eq!(Ggx::isotropic(1.5).roughened(0.3), Ggx::isotropic(1.5), "roughening never sharpens");
    for (name, bsdf) in rough_bsdfs() {
        let same = bsdf.roughened(0.0);
        let (wo, wi) = (dir(30.0, 10.0), dir(35.0, 195.0));
        assert_eq!(same.eval(wo, wi, TransportMode::Radiance), bsdf.eval(wo, wi, TransportMode::Radiance), "{name}");
        assert_eq!(bsdf.roughened(0.5).is_delta(), bsdf.is_delta(), "{name}");
    }
    // Delta lobes stay delta.
    let mirror = Bsdf::Conductor(Conductor {
        distribution: Ggx::isotropic(0.0),
        eta: Rgb::splat(0.2),
        k: Rgb::splat(3.0),
        tint: Rgb::ONE,
    });
    assert!(mirror.roughened(0.5).is_delta());
    let glass = Bsdf::Dielectric(Dielectric { distribution: Ggx::isotropic(0.0), eta: 1.5 });
    assert!(glass.roughened(0.5).is_delta());
    // A sharp glossy lobe gets flatter: lower at the mirror direction, higher away from it.
    let glossy = Bsdf::Conductor(Conductor {
        distribution: Ggx::isotropic(0.02),
        eta: Rgb::splat(0.2),
        k: Rgb::splat(3.0),
        tint: Rgb::ONE,
    });
    let wo = dir(40.0, 0.0);
    let (peak, off) = (dir(40.0, 180.0), dir(20.0, 180.0));
    let rough = glossy.roughened(0.2);
    let m = TransportMode::Radiance;
    assert!(rough.eval(wo, peak, m).x < 0.1 * glossy.eval(wo, peak, m).x);
    assert!(rough.eval(wo, off, m).x > 10.0 * glossy.eval(wo, off, m).x);
    assert!(rough.pdf(wo, off) > 10.0 * glossy.pdf(wo, off));
}

/// Inverting a sample gives numbers that sample the same direction again: for every invertible
/// BSDF (rough, near-smooth and smooth; reflection and transmission, from either side), a
/// direction sampled from `(uc, u)` is sampled again from any `uc` in the inverse's interval and
/// its `u`.
#[test]
fn sample_inverse_resamples_the_direction() {
    let mut bsdfs: Vec<(&str, Bsdf)> = rough_bsdfs().into_iter().filter(|(_, b)| b.invertible()).collect();
    bsdfs.push(("dielectric 0.02", Bsdf::Dielectric(Dielectric { distribution: Ggx::isotropic(0.02), eta: 1.5 })));
    bsdfs.push(("smooth dielectric", Bsdf::Dielectric(Dielectric { distribution: Ggx::isotropic(0.0), eta: 1.5 })));
    bsdfs.push((
        "smooth conductor",
        Bsdf::Conductor(Conductor { distribution: Ggx::isotropic(0.0), eta: Rgb::ONE, k: Rgb::ONE, tint: Rgb::ONE }),
    ));
    assert_eq!(bsdfs.len(), 9);
    let mut rng = Pcg32::new(11, 0);
    for (name, bsdf) in bsdfs {
        let mut lobes = [0usize; 2];
        for wo in outgoing() {
            for _ in 0..4000 {
                let (uc, u) = (rng.next_f32(), Vec2::new(rng.next_f32(), rng.next_f32()));
                let Some(s) = bsdf.sample(wo, uc, u, TransportMode::Radiance) else { continue };
                let inv = bsdf.sample_inverse(wo, s.wi).unwrap_or_else(|| panic!("{name}: {wo} -> {}", s.wi));
                let uc2 = inv.uc.map_or(rng.next_f32(), |(lo, hi)| lo + (hi - lo) * rng.next_f32());
                let u2 = inv.u.unwrap_or(Vec2::new(rng.next_f32(), rng.next_f32()));
                let again = bsdf.sample(wo, uc2, u2, TransportMode::Radiance).expect("resampled");
                assert!((again.wi - s.wi).length() < 2e-3, "{name}: {wo}: {} -> {}", s.wi, again.wi);
                assert_eq!(again.delta, s.delta);
                lobes[usize::from(s.transmission)] += 1;
            }
        }
        // Dielectrics were inverted through both lobes.
        if name.starts_with("dielectric") || name.starts_with("smooth dielectric") {
            assert!(lobes.iter().all(|&n| n > 100), "{name}: {lobes:?}");
        }
    }
}
