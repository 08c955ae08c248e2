//! Mitsuba's `sunsky` emitter approximated by the Preetham, Shirley & Smits (1999) analytic
//! daylight model: the sky is the Perez distribution of luminance and chromaticity for the given
//! turbidity and sun direction, baked into a latitude–longitude environment map, and the sun is
//! a distant light. Differences from Mitsuba 0.6, which evaluates both spectrally: the sky is
//! computed in CIE xyY and converted to sRGB (Mitsuba 0.6 itself uses the Hosek–Wilkie model);
//! Preetham's luminance in kcd/m² is converted to Mitsuba's radiometric units, spectral
//! radiance in W·m⁻²·sr⁻¹·nm⁻¹ averaged against ȳ, by `1000 / (683 · ∫ȳ)`; the sun is a
//! directional light whose irradiance is `sunScale` with the colour of a 5778 K blackbody
//! (`sunRadiusScale` is ignored); the sky below the horizon is black.

use crate::spectrum::blackbody;
use tempera::math::{Rgb, Vec3};
use tempera::texture::Image;

/// kcd/m² of luminance to W·m⁻²·sr⁻¹·nm⁻¹ averaged against ȳ (683 lm/W, ∫ȳ dλ = 106.857 nm).
const KCD_TO_SPECTRAL_RADIANCE: f32 = 1000.0 / (683.0 * 106.857);

/// Perez coefficients A–E as linear functions of turbidity, for Y, x and y.
fn perez(t: f32) -> [[f32; 5]; 3] {
    [
        [0.1787 * t - 1.4630, -0.3554 * t + 0.4275, -0.0227 * t + 5.3251, 0.1206 * t - 2.5771, -0.0670 * t + 0.3703],
        [-0.0193 * t - 0.2592, -0.0665 * t + 0.0008, -0.0004 * t + 0.2125, -0.0641 * t - 0.8989, -0.0033 * t + 0.0452],
        [-0.0167 * t - 0.2608, -0.0950 * t + 0.0092, -0.0079 * t + 0.2102, -0.0441 * t - 1.6537, -0.0109 * t + 0.0529],
    ]
}

fn perez_f(c: &[f32; 5], cos_theta: f32, gamma: f32) -> f32 {
    let [a, b, cc, d, e] = *c;
    (1.0 + a * (b / cos_theta.max(1e-3)).exp()) * (1.0 + cc * (d * gamma).exp() + e * gamma.cos().powi(2))
}

/// Zenith luminance (kcd/m²) and chromaticity for turbidity `t` and sun zenith angle `ts`.
fn zenith(t: f32, ts: f32) -> [f32; 3] {
    let chi = (4.0 / 9.0 - t / 120.0) * (std::f32::consts::PI - 2.0 * ts);
    let y = (4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192;
    let poly = |m: [[f32; 4]; 3]| {
        let th = [ts * ts * ts, ts * ts, ts, 1.0];
        let row = |r: [f32; 4]| r.iter().zip(th).map(|(a, b)| a * b).sum::<f32>();
        t * t * row(m[0]) + t * row(m[1]) + row(m[2])
    };
    let x = poly([
        [0.00166, -0.00375, 0.00209, 0.0],
        [-0.02903, 0.06377, -0.03202, 0.00394],
        [0.11693, -0.21196, 0.06052, 0.25886],
    ]);
    let yy = poly([
        [0.00275, -0.00610, 0.00317, 0.0],
        [-0.04214, 0.08970, -0.04153, 0.00516],
        [0.15346, -0.26756, 0.06670, 0.26688],
    ]);
    [y.max(0.0), x, yy]
}

fn xyy_to_rgb(x: f32, y: f32, lum: f32) -> Rgb {
    if y <= 0.0 {
        return Rgb::ZERO;
    }
    let (cx, cz) = (x / y * lum, (1.0 - x - y) / y * lum);
    Rgb::new(
        3.240_454_2 * cx - 1.537_138_5 * lum - 0.498_531_4 * cz,
        -0.969_266 * cx + 1.876_010_8 * lum + 0.041_556 * cz,
        0.055_643_4 * cx - 0.204_025_9 * lum + 1.057_225_2 * cz,
    )
    .max(Rgb::ZERO)
}

/// Sky radiance towards `d` (unit, y up) for a sun in direction `sun` (unit, y up).
pub fn sky_radiance(turbidity: f32, sun: Vec3, d: Vec3) -> Rgb {
    if d.y <= 0.0 {
        return Rgb::ZERO;
    }
    let ts = sun.y.clamp(-1.0, 1.0).acos().min(std::f32::consts::FRAC_PI_2);
    let gamma = d.dot(sun).clamp(-1.0, 1.0).acos();
    let [c_y, c_x, c_yy] = perez(turbidity);
    let [zy, zx, zyy] = zenith(turbidity, ts);
    let ratio = |c: &[f32; 5]| perez_f(c, d.y, gamma) / perez_f(c, 1.0, ts);
    xyy_to_rgb(zx * ratio(&c_x), zyy * ratio(&c_yy), zy * ratio(&c_y)) * KCD_TO_SPECTRAL_RADIANCE
}

/// The sky as a latitude–longitude image in Tempera's environment frame (+z up): the caller
/// places it with a rotation taking +z to the scene's up (+y).
pub fn sky_image(turbidity: f32, sun: Vec3, width: usize, height: usize) -> Image {
    let mut pixels = Vec::with_capacity(width * height);
    for j in 0..height {
        let theta = (j as f32 + 0.5) / height as f32 * std::f32::consts::PI;
        for i in 0..width {
            let phi = (i as f32 + 0.5) / width as f32 * std::f32::consts::TAU;
            // Local (x, y, z) with z up maps to the y-up sky frame as (y, z, x).
            let local = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
            let d = Vec3::new(local.y, local.z, local.x);
            pixels.push(sky_radiance(turbidity, sun, d));
        }
    }
    Image::new(width, height, pixels)
}

/// Date, time and place of an observer, as Mitsuba's `sunsky` takes them.
#[derive(Clone, Copy, Debug)]
pub struct SunTime {
    pub latitude: f64,
    pub longitude: f64,
    /// Hours ahead of UTC.
    pub timezone: f64,
    pub year: i64,
    pub month: i64,
    pub day: i64,
    pub hour: f64,
    pub minute: f64,
    pub second: f64,
}

/// Unit direction towards the sun (y up, azimuth 0 towards −z, 90° towards +x) by the PSA
/// algorithm (Blanco-Muriel et al. 2001, "Computing the Solar Vector", Solar Energy 70(5)).
pub fn sun_direction(t: &SunTime) -> Vec3 {
    use std::f64::consts::TAU;
    let hours = t.hour - t.timezone + (t.minute + t.second / 60.0) / 60.0;
    let a1 = (t.month - 14) / 12;
    let jd = (1461 * (t.year + 4800 + a1)) / 4 + (367 * (t.month - 2 - 12 * a1)) / 12
        - (3 * ((t.year + 4900 + a1) / 100)) / 4
        + t.day
        - 32075;
    let n = jd as f64 - 0.5 + hours / 24.0 - 2_451_545.0;
    let omega = 2.1429 - 0.001_039_459_4 * n;
    let mean_longitude = 4.895_063 + 0.017_202_791_698 * n;
    let anomaly = 6.240_06 + 0.017_201_969_9 * n;
    let ecl_longitude = mean_longitude + 0.033_416_07 * anomaly.sin() + 0.000_348_94 * (2.0 * anomaly).sin()
        - 0.000_113_4
        - 0.000_020_3 * omega.sin();
    let obliquity = 0.409_092_8 - 6.214e-9 * n + 0.000_039_6 * omega.cos();
    let mut ra = (obliquity.cos() * ecl_longitude.sin()).atan2(ecl_longitude.cos());
    if ra < 0.0 {
        ra += TAU;
    }
    let declination = (obliquity.sin() * ecl_longitude.sin()).asin();
    let gmst = 6.697_424_324_2 + 0.065_709_828_3 * n + hours;
    let lmst = (gmst * 15.0 + t.longitude).to_radians();
    let lat = t.latitude.to_radians();
    let hour_angle = lmst - ra;
    let mut zenith =
        (lat.cos() * hour_angle.cos() * declination.cos() + declination.sin() * lat.sin()).clamp(-1.0, 1.0).acos();
    let mut azimuth = (-hour_angle.sin()).atan2(declination.tan() * lat.cos() - lat.sin() * hour_angle.cos());
    if azimuth < 0.0 {
        azimuth += TAU;
    }
    zenith += 6371.01 / 149_597_890.0 * zenith.sin();
    let (st, ct) = zenith.sin_cos();
    Vec3::new((azimuth.sin() * st) as f32, ct as f32, (-azimuth.cos() * st) as f32)
}

/// The colour of the sun, with unit luminance.
pub fn sun_color() -> Rgb {
    blackbody(5778.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sky_is_brighter_near_the_sun_and_bluer_away_from_it() {
        let sun = Vec3::new(0.3, 0.5, 0.2).normalize();
        let near = sky_radiance(3.0, sun, (sun + Vec3::new(0.05, 0.0, 0.0)).normalize());
        let far = sky_radiance(3.0, sun, Vec3::new(-0.6, 0.4, -0.2).normalize());
        assert!(tempera::math::luminance(near) > tempera::math::luminance(far));
        assert!(far.z > far.x, "the sky away from the sun is blue: {far}");
        assert_eq!(sky_radiance(3.0, sun, Vec3::new(0.0, -0.5, 1.0).normalize()), Rgb::ZERO);
    }

    #[test]
    fn solar_position_is_plausible() {
        // Equator, equinox noon (UTC): the sun is almost overhead.
        let equinox = SunTime {
            latitude: 0.0,
            longitude: 0.0,
            timezone: 0.0,
            year: 2010,
            month: 3,
            day: 20,
            hour: 12.0,
            minute: 0.0,
            second: 0.0,
        };
        assert!(sun_direction(&equinox).y > 0.995, "{}", sun_direction(&equinox));
        // Mitsuba's default: Tokyo, 10 July 2010, 15:00 local time: a western afternoon sun
        // about 40° above the horizon.
        let tokyo = SunTime {
            latitude: 35.6894,
            longitude: 139.6917,
            timezone: 9.0,
            year: 2010,
            month: 7,
            day: 10,
            hour: 15.0,
            minute: 0.0,
            second: 0.0,
        };
        let d = sun_direction(&tokyo);
        let elevation = d.y.asin().to_degrees();
        assert!((30.0..50.0).contains(&elevation), "elevation {elevation}");
        assert!(d.x < 0.0, "the afternoon sun is in the west (-x): {d}");
        // Midnight: below the horizon.
        assert!(sun_direction(&SunTime { hour: 0.0, ..tokyo }).y < 0.0);
    }
}
