//! Spectra in scene files reduced to linear sRGB: RGB values pass through; blackbody
//! temperatures and sampled spectra are integrated against the CIE 1931 colour-matching
//! functions (the analytic multi-lobe fit of Wyman, Sloan & Shirley 2013, JCGT 2(2)) and
//! converted with the XYZ→sRGB matrix of IEC 61966-2-1. Emission spectra are normalised to unit
//! luminance, as pbrt-v4 does for lights; reflectance spectra are white-balanced so that a
//! constant spectrum maps to a grey of the same value. pbrt-v4's named metal spectra are
//! replaced by their RGB equivalents, named glasses by their index at 587.6 nm.

use tempera::math::Rgb;

fn lobe(l: f64, mu: f64, s1: f64, s2: f64) -> f64 {
    let t = (l - mu) / if l < mu { s1 } else { s2 };
    (-0.5 * t * t).exp()
}

/// CIE 1931 2° colour-matching functions at wavelength `l` (nm).
pub fn cie_xyz(l: f64) -> [f64; 3] {
    [
        1.056 * lobe(l, 599.8, 37.9, 31.0) + 0.362 * lobe(l, 442.0, 16.0, 26.7) - 0.065 * lobe(l, 501.1, 20.4, 26.2),
        0.821 * lobe(l, 568.8, 46.9, 40.5) + 0.286 * lobe(l, 530.9, 16.3, 31.1),
        1.217 * lobe(l, 437.0, 11.8, 36.0) + 0.681 * lobe(l, 459.0, 26.0, 13.8),
    ]
}

fn xyz_to_srgb(xyz: [f64; 3]) -> Rgb {
    let [x, y, z] = xyz;
    Rgb::new(
        (3.240_454_2 * x - 1.537_138_5 * y - 0.498_531_4 * z) as f32,
        (-0.969_266 * x + 1.876_010_8 * y + 0.041_556 * z) as f32,
        (0.055_643_4 * x - 0.204_025_9 * y + 1.057_225_2 * z) as f32,
    )
}

fn integrate(f: impl Fn(f64) -> f64) -> [f64; 3] {
    let mut xyz = [0.0; 3];
    for l in 360..=830 {
        let (l, v) = (f64::from(l), f(f64::from(l)));
        let c = cie_xyz(l);
        for i in 0..3 {
            xyz[i] += v * c[i];
        }
    }
    xyz
}

/// Planck's law: spectral radiance of a blackbody at `t` kelvin, wavelength `l` nm.
fn planck(l: f64, t: f64) -> f64 {
    let (c, h, kb) = (299_792_458.0, 6.626_070_15e-34, 1.380_649e-23);
    let l = l * 1e-9;
    2.0 * h * c * c / (l.powi(5) * ((h * c / (l * kb * t)).exp() - 1.0))
}

/// RGB of an emitter with the given spectrum, normalised to unit luminance.
fn emission_rgb(f: impl Fn(f64) -> f64) -> Rgb {
    let xyz = integrate(f);
    if xyz[1] <= 0.0 {
        return Rgb::ZERO;
    }
    xyz_to_srgb([xyz[0] / xyz[1], 1.0, xyz[2] / xyz[1]]).max(Rgb::ZERO)
}

/// A blackbody emitter of temperature `kelvin` with unit luminance.
pub fn blackbody(kelvin: f64) -> Rgb {
    if kelvin.is_nan() || kelvin <= 0.0 {
        return Rgb::ZERO;
    }
    emission_rgb(|l| planck(l, kelvin))
}

/// Piecewise-linear interpolation of `(wavelength, value)` pairs, constant beyond the ends.
fn piecewise(pairs: &[f64]) -> impl Fn(f64) -> f64 + '_ {
    move |l| {
        let n = pairs.len() / 2;
        let (l0, v0) = (pairs[0], pairs[1]);
        let (ln, vn) = (pairs[2 * (n - 1)], pairs[2 * (n - 1) + 1]);
        if l <= l0 {
            return v0;
        }
        if l >= ln {
            return vn;
        }
        for i in 0..n - 1 {
            let (a, va, b, vb) = (pairs[2 * i], pairs[2 * i + 1], pairs[2 * i + 2], pairs[2 * i + 3]);
            if l >= a && l <= b {
                return if b > a { va + (vb - va) * (l - a) / (b - a) } else { va };
            }
        }
        vn
    }
}

/// RGB of a sampled emission spectrum (wavelength–value pairs), unit luminance.
pub fn sampled_emission(pairs: &[f64]) -> Rgb {
    emission_rgb(piecewise(pairs))
}

/// RGB of a sampled reflectance (or other unitless) spectrum, white-balanced per channel.
pub fn sampled_reflectance(pairs: &[f64]) -> Rgb {
    let white = xyz_to_srgb(integrate(|_| 1.0));
    let c = xyz_to_srgb(integrate(piecewise(pairs)));
    c / white
}

/// Named spectra of pbrt-v4 reduced to RGB (complex IOR of metals at about 650/550/450 nm,
/// from refractiveindex.info tabulations) or, for glasses, a constant index.
pub fn named(name: &str) -> Option<Rgb> {
    let rgb = |r, g, b| Some(Rgb::new(r, g, b));
    match name {
        "metal-Ag-eta" => rgb(0.155, 0.117, 0.138),
        "metal-Ag-k" => rgb(4.828, 3.122, 2.147),
        "metal-Al-eta" => rgb(1.657, 0.880, 0.521),
        "metal-Al-k" => rgb(9.224, 6.270, 4.837),
        "metal-Au-eta" => rgb(0.143, 0.374, 1.442),
        "metal-Au-k" => rgb(3.983, 2.385, 1.603),
        "metal-Cu-eta" => rgb(0.200, 0.924, 1.102),
        "metal-Cu-k" => rgb(3.912, 2.452, 2.142),
        "metal-CuZn-eta" => rgb(0.444, 0.527, 1.094),
        "metal-CuZn-k" => rgb(3.695, 2.765, 1.829),
        "metal-MgO-eta" => rgb(1.732, 1.736, 1.746),
        "metal-MgO-k" => rgb(0.0, 0.0, 0.0),
        "metal-TiO2-eta" => rgb(2.745, 2.875, 3.112),
        "metal-TiO2-k" => rgb(0.0, 0.0, 0.0),
        "glass-BK7" => Some(Rgb::splat(1.5168)),
        "glass-BAF10" => Some(Rgb::splat(1.6700)),
        "glass-FK51A" => Some(Rgb::splat(1.4866)),
        "glass-LASF9" => Some(Rgb::splat(1.8503)),
        "glass-F5" => Some(Rgb::splat(1.6034)),
        "glass-F10" => Some(Rgb::splat(1.6200)),
        "glass-F11" => Some(Rgb::splat(1.6209)),
        "stdillum-D65" | "stdillum-D50" | "illum-acesD60" => Some(Rgb::ONE),
        "stdillum-A" => Some(blackbody(2856.0)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blackbody_colours_are_plausible() {
        let warm = blackbody(2700.0);
        let d65ish = blackbody(6504.0);
        assert!(warm.x > warm.y && warm.y > warm.z, "incandescent is reddish: {warm}");
        assert!((d65ish.x - d65ish.z).abs() < 0.12 && (d65ish.y - 1.0).abs() < 0.1, "≈ white: {d65ish}");
        let lum = |c: Rgb| tempera::math::luminance(c);
        assert!((lum(warm) - 1.0).abs() < 0.02 && (lum(d65ish) - 1.0).abs() < 0.02);
    }

    #[test]
    fn constant_reflectance_spectrum_is_grey() {
        let c = sampled_reflectance(&[400.0, 0.5, 700.0, 0.5]);
        assert!((c - Rgb::splat(0.5)).abs().max_element() < 1e-4, "{c}");
        let red = sampled_reflectance(&[400.0, 0.0, 580.0, 0.0, 620.0, 1.0, 700.0, 1.0]);
        assert!(red.x > 0.5 && red.z < 0.1, "{red}");
    }

    #[test]
    fn named_metals_and_glasses() {
        assert!(named("metal-Au-eta").unwrap().z > 1.0);
        assert_eq!(named("glass-BK7").unwrap().x, 1.5168);
        assert!(named("metal-unobtainium-eta").is_none());
    }
}
