//! Layered BSDFs as pbrt-v4 defines `coateddiffuse` and `coatedconductor` (pbrt-v4 §14.3,
//! after Guo, Hašan & Zhao 2018, "Position-Free Monte Carlo Simulation for Arbitrary Layered
//! BSDFs"): a dielectric interface on top of a reflecting base (Lambertian or conductor), with
//! a slab of thickness `thickness` between them that may hold a homogeneous medium of albedo
//! `albedo` and Henyey–Greenstein asymmetry `g` (unit extinction per unit thickness). Light
//! that enters the coat is followed by a random walk between the two interfaces of at most
//! `max_depth` scattering events, with Russian roulette after the third.
//!
//! The BSDF's value, sampling density and samples are Monte Carlo estimates, each the average
//! of `samples` walks:
//!
//! - `eval(wo, wi)`: the top interface's own reflection, plus walks that enter through the top
//!   towards `wo` (transmission sampled), bounce between the interfaces and, at every vertex,
//!   connect to the exit towards `wi` (a transmission through the top sampled from `wi`, as in
//!   next-event estimation) and continue by sampling the vertex, each connection weighted
//!   against the walk reaching the exit by itself (power heuristic). Both weights compare the
//!   densities of the same inside direction (the exit's from `wi`'s side, the vertex's from the
//!   walk's), so they sum to one and values agree with samples (tested);
//! - `pdf(wo, wi)`: an estimate of the density of `sample`: the top's reflection, plus, weighted
//!   by the probability of entering, transmission–reflection–transmission through the base,
//!   mixed 9:1 with the uniform density so that it is never zero where the BSDF is not. It only
//!   weights strategies (MIS), so an approximate density costs variance, never bias;
//! - `sample(wo)`: one walk from `wo` until it leaves through the top; its weight `f·cos/pdf`
//!   is exact, its `pdf` only proportional to the true density, so MIS uses `pdf()` instead.
//!
//! At the depth limit the two differ by the truncated paths: a value connects to the exit from
//! the last event of its walk, which a sample would leave by one step more.
//!
//! Their random numbers come from a generator seeded by a hash of the directions (and, for
//! samples, of the sample's own numbers), so every estimate is a pure function of its inputs:
//! a Markov chain re-evaluating a state gets the same value. The BSDF is two-sided, as pbrt-v4
//! makes its coated materials: below the surface it mirrors the upper side.

use super::dielectric::Lobes;
use super::{BsdfSample, Conductor, Dielectric, Diffuse, TransportMode, fresnel};
use crate::math::rng::{Pcg32, hash};
use crate::math::{Rgb, Vec2, Vec3, power_heuristic};
use crate::medium::{hg, sample_hg};
use std::f32::consts::PI;

/// The base of a layered BSDF: reflection only.
#[derive(Clone, Copy, Debug)]
pub enum Base {
    Diffuse(Diffuse),
    Conductor(Conductor),
}

impl Base {
    fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        match self {
            Base::Diffuse(b) => b.eval(wo, wi),
            Base::Conductor(b) => b.eval(wo, wi),
        }
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Base::Diffuse(b) => b.pdf(wo, wi),
            Base::Conductor(b) => b.pdf(wo, wi),
        }
    }

    fn sample(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        match self {
            Base::Diffuse(b) => b.sample(wo, u),
            Base::Conductor(b) => b.sample(wo, u),
        }
        .filter(|s| s.pdf > 0.0 && s.wi.z != 0.0)
    }

    fn is_delta(&self) -> bool {
        match self {
            Base::Diffuse(_) => false,
            Base::Conductor(b) => b.distribution.effectively_smooth(),
        }
    }
}

/// A dielectric coat over a reflecting base.
#[derive(Clone, Copy, Debug)]
pub struct Layered {
    pub top: Dielectric,
    pub base: Base,
    pub thickness: f32,
    /// Single-scattering albedo of the medium between the interfaces, whose extinction is one
    /// per unit thickness (zero: the slab only absorbs).
    pub albedo: Rgb,
    /// Henyey–Greenstein asymmetry of that medium.
    pub g: f32,
    pub max_depth: u32,
    pub samples: u32,
}

/// The transmittance through a slab of thickness `dz` along `w` (unit extinction).
fn tr(dz: f32, w: Vec3) -> f32 {
    if dz.abs() <= f32::MIN_POSITIVE { 1.0 } else { (-(dz / w.z).abs()).exp() }
}

/// A generator for one estimate, seeded by the directions (and `extra`).
fn rng_for(a: Vec3, b: Vec3, extra: u64) -> Pcg32 {
    let bits = |v: Vec3| (u64::from(v.x.to_bits()) << 32) ^ (u64::from(v.y.to_bits()) << 16) ^ u64::from(v.z.to_bits());
    Pcg32::new(hash(&[0x1a7e, bits(a), bits(b), extra]), 5)
}

fn next2(rng: &mut Pcg32) -> Vec2 {
    let x = rng.next_f32();
    Vec2::new(x, rng.next_f32())
}

impl Layered {
    /// Whether the walk needs the medium (a non-zero albedo).
    fn has_medium(&self) -> bool {
        self.albedo.max_element() > 0.0
    }

    /// The side of `wo` mirrored to the top: the BSDF is two-sided.
    fn upper(wo: Vec3, wi: Vec3) -> (Vec3, Vec3) {
        if wo.z < 0.0 { (-wo, -wi) } else { (wo, wi) }
    }

    pub fn is_delta(&self) -> bool {
        self.top.is_delta() && self.base.is_delta() && !self.has_medium()
    }

    pub fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Rgb {
        let (wo, wi) = Self::upper(wo, wi);
        // Only reflection: the base lets nothing through.
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let n = self.samples.max(1);
        let mut f = self.top.eval(wo, wi, mode) * n as f32;
        let mut rng = rng_for(wo, wi, 0);
        let exit_z = self.thickness;
        for _ in 0..n {
            // Into the coat towards wo, and the exit towards wi (sampled the other way).
            let Some(wos) = self.top.sample_lobes(wo, rng.next_f32(), next2(&mut rng), mode, Lobes::TRANSMISSION)
            else {
                continue;
            };
            let other = match mode {
                TransportMode::Radiance => TransportMode::Importance,
                TransportMode::Importance => TransportMode::Radiance,
            };
            let Some(wis) = self.top.sample_lobes(wi, rng.next_f32(), next2(&mut rng), other, Lobes::TRANSMISSION)
            else {
                continue;
            };
            if !(wos.pdf > 0.0 && wis.pdf > 0.0 && wos.wi.z != 0.0 && wis.wi.z != 0.0) {
                continue;
            }
            let mut beta = wos.f * (wos.wi.z.abs() / wos.pdf);
            let mut z = self.thickness;
            let mut w = wos.wi;
            let exit_specular = self.top.is_delta();
            for depth in 0..self.max_depth {
                if depth > 3 && beta.max_element() < 0.25 {
                    let q = (1.0 - beta.max_element()).max(0.0);
                    if rng.next_f32() < q {
                        break;
                    }
                    beta /= 1.0 - q;
                }
                if w.z == 0.0 {
                    break;
                }
                if self.has_medium() {
                    let dz = -(1.0 - rng.next_f32()).ln() * w.z.abs();
                    let zp = if w.z > 0.0 { z + dz } else { z - dz };
                    if zp == z {
                        break;
                    }
                    if 0.0 < zp && zp < self.thickness {
                        // Scattering in the medium: connect to the exit, then sample the phase
                        // function (and weigh the exit reached by that direction).
                        let wt = if exit_specular { 1.0 } else { power_heuristic(wis.pdf, hg(-w, -wis.wi, self.g)) };
                        f += beta
                            * self.albedo
                            * (hg(-w, -wis.wi, self.g) * wt * tr(zp - exit_z, wis.wi) / wis.pdf)
                            * wis.f;
                        let (wi_p, p) = sample_hg(-w, self.g, next2(&mut rng));
                        if p <= 0.0 || wi_p.z == 0.0 {
                            break;
                        }
                        beta *= self.albedo;
                        w = wi_p;
                        z = zp;
                        if z < exit_z && w.z > 0.0 && !exit_specular {
                            let f_exit = self.top.eval(-w, wi, mode);
                            if f_exit.max_element() > 0.0 {
                                let exit_pdf = self.top.pdf_lobes(wi, -w, Lobes::TRANSMISSION);
                                let wt = power_heuristic(p, exit_pdf);
                                f += beta * f_exit * (tr(zp - exit_z, w) * wt);
                            }
                        }
                        continue;
                    }
                    z = zp.clamp(0.0, self.thickness);
                } else {
                    z = if z == self.thickness { 0.0 } else { self.thickness };
                    beta *= tr(self.thickness, w);
                }
                if z == exit_z {
                    // At the top from inside: reflect back into the coat.
                    let Some(bs) = self.top.sample_lobes(-w, rng.next_f32(), next2(&mut rng), mode, Lobes::REFLECTION)
                    else {
                        break;
                    };
                    if bs.pdf.is_nan() || bs.pdf <= 0.0 || bs.wi.z == 0.0 {
                        break;
                    }
                    beta *= bs.f * (bs.wi.z.abs() / bs.pdf);
                    w = bs.wi;
                } else {
                    // At the base: connect to the exit, then sample the base.
                    if !self.base.is_delta() {
                        let wt = if exit_specular { 1.0 } else { power_heuristic(wis.pdf, self.base.pdf(-w, -wis.wi)) };
                        f += beta
                            * self.base.eval(-w, -wis.wi)
                            * (wis.wi.z.abs() * wt * tr(self.thickness, wis.wi) / wis.pdf)
                            * wis.f;
                    }
                    let Some(bs) = self.base.sample(-w, next2(&mut rng)) else { break };
                    beta *= bs.f * (bs.wi.z.abs() / bs.pdf);
                    w = bs.wi;
                    if !exit_specular {
                        let f_exit = self.top.eval(-w, wi, mode);
                        if f_exit.max_element() > 0.0 {
                            let wt = if bs.delta {
                                1.0
                            } else {
                                power_heuristic(bs.pdf, self.top.pdf_lobes(wi, -w, Lobes::TRANSMISSION))
                            };
                            f += beta * f_exit * (tr(self.thickness, bs.wi) * wt);
                        }
                    }
                }
            }
        }
        let f = f / n as f32;
        if f.is_finite() { f } else { Rgb::ZERO }
    }

    /// An estimate of the density of [`Self::sample`] (see the module documentation).
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let (wo, wi) = Self::upper(wo, wi);
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let n = self.samples.max(1);
        // The walk enters the coat with about the probability that the coat transmits.
        let enter = 1.0 - fresnel::dielectric(wo.z, self.top.eta);
        let mut reflected = n as f32 * self.top.pdf(wo, wi);
        let mut sum = 0.0;
        let mut rng = rng_for(wi, wo, 1);
        for _ in 0..n {
            let t = |w: Vec3, mode, rng: &mut Pcg32| {
                self.top.sample_lobes(w, rng.next_f32(), next2(rng), mode, Lobes::TRANSMISSION)
            };
            let (Some(wos), Some(wis)) =
                (t(wo, TransportMode::Radiance, &mut rng), t(wi, TransportMode::Importance, &mut rng))
            else {
                continue;
            };
            if !(wos.pdf > 0.0 && wis.pdf > 0.0 && wos.wi.z != 0.0 && wis.wi.z != 0.0) {
                continue;
            }
            if self.top.is_delta() {
                sum += self.base.pdf(-wos.wi, -wis.wi);
                continue;
            }
            let Some(rs) = self.base.sample(-wos.wi, next2(&mut rng)) else { continue };
            if rs.delta {
                sum += self.top.pdf(-rs.wi, wi);
            } else {
                let r_pdf = self.base.pdf(-wos.wi, -wis.wi);
                sum += power_heuristic(wis.pdf, r_pdf) * r_pdf;
                let t_pdf = self.top.pdf(-rs.wi, wi);
                sum += power_heuristic(rs.pdf, t_pdf) * t_pdf;
            }
        }
        reflected += enter * sum;
        let pdf = 0.1 / (4.0 * PI) + 0.9 * reflected / n as f32;
        if pdf.is_finite() { pdf } else { 0.0 }
    }

    /// One random walk from `wo`, its numbers seeded by `wo`, `uc` and `u`.
    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        let flip = wo.z < 0.0;
        let wo = if flip { -wo } else { wo };
        let out = |mut s: BsdfSample| {
            if flip {
                s.wi = -s.wi;
            }
            s
        };
        let bs = self.top.sample(wo, uc, u, mode)?;
        if !bs.transmission {
            // The coat's own reflection: its density is the coat's alone, not the BSDF's.
            return Some(out(BsdfSample { proportional: !bs.delta, ..bs }));
        }
        let mut rng = rng_for(wo, Vec3::new(uc, u.x, u.y), 2);
        let mut w = bs.wi;
        let mut delta = bs.delta;
        let mut f = bs.f * bs.wi.z.abs();
        let mut pdf = bs.pdf;
        let mut z = self.thickness;
        for depth in 0..self.max_depth {
            let rr = f.max_element() / pdf;
            if depth > 3 && rr < 0.25 {
                let q = (1.0 - rr).max(0.0);
                if rng.next_f32() < q {
                    return None;
                }
                pdf *= 1.0 - q;
            }
            if w.z == 0.0 {
                return None;
            }
            if self.has_medium() {
                let dz = -(1.0 - rng.next_f32()).ln() * w.z.abs();
                let zp = if w.z > 0.0 { z + dz } else { z - dz };
                if zp == z {
                    return None;
                }
                if 0.0 < zp && zp < self.thickness {
                    let (wi_p, p) = sample_hg(-w, self.g, next2(&mut rng));
                    if p <= 0.0 || wi_p.z == 0.0 {
                        return None;
                    }
                    f *= self.albedo * p;
                    pdf *= p;
                    delta = false;
                    w = wi_p;
                    z = zp;
                    continue;
                }
                z = zp.clamp(0.0, self.thickness);
            } else {
                z = if z == self.thickness { 0.0 } else { self.thickness };
                f *= tr(self.thickness, w);
            }
            let bs = if z == 0.0 {
                self.base.sample(-w, next2(&mut rng))?
            } else {
                self.top.sample(-w, rng.next_f32(), next2(&mut rng), mode)?
            };
            if bs.pdf.is_nan() || bs.pdf <= 0.0 || bs.wi.z == 0.0 {
                return None;
            }
            f *= bs.f;
            pdf *= bs.pdf;
            delta &= bs.delta;
            w = bs.wi;
            if bs.transmission {
                // Out through the top.
                let s = BsdfSample { f, wi: w, pdf, delta, transmission: false, proportional: !delta };
                return (s.f.is_finite() && s.pdf.is_finite()).then(|| out(s));
            }
            f *= bs.wi.z.abs();
        }
        None
    }

    /// The coat and the base with their GGX lobes roughened by `a`.
    pub fn roughened(&self, a: f32) -> Layered {
        let mut out = *self;
        out.top.distribution = out.top.distribution.roughened(a);
        if let Base::Conductor(c) = &mut out.base {
            c.distribution = c.distribution.roughened(a);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::Ggx;
    use crate::math::warp::{cosine_hemisphere, cosine_hemisphere_pdf};

    fn coated_diffuse(reflectance: f32, roughness: f32, albedo: f32) -> Layered {
        Layered {
            top: Dielectric { distribution: Ggx::isotropic(roughness), eta: 1.5 },
            base: Base::Diffuse(Diffuse { reflectance: Rgb::splat(reflectance) }),
            thickness: 0.01,
            albedo: Rgb::splat(albedo),
            g: 0.0,
            max_depth: 10,
            samples: 1,
        }
    }

    /// The directional albedo `∫ f cos dwi` by cosine-distributed directions and by the BSDF's
    /// own samples, for `wo` at `cos_o`.
    fn albedos(b: &Layered, cos_o: f32) -> (f64, f64) {
        let wo = Vec3::new((1.0 - cos_o * cos_o).sqrt(), 0.0, cos_o);
        let mut rng = Pcg32::new(7, 1);
        let n = 200_000;
        let (mut by_eval, mut by_sample) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let wi = cosine_hemisphere(next2(&mut rng));
            by_eval += f64::from(b.eval(wo, wi, TransportMode::Radiance).y * wi.z / cosine_hemisphere_pdf(wi.z));
            if let Some(s) = b.sample(wo, rng.next_f32(), next2(&mut rng), TransportMode::Radiance) {
                by_sample += f64::from(s.f.y * s.wi.z.abs() / s.pdf);
            }
        }
        (by_eval / n as f64, by_sample / n as f64)
    }

    /// Values and samples estimate the same BSDF: the albedo `∫ f cos dwi` from values at
    /// cosine-distributed directions equals the mean weight of the BSDF's samples,
    /// which for a smooth coat also hold its mirror reflection (the Fresnel term, a delta lobe
    /// values leave out). A white base under a thin smooth clear coat conserves energy once the
    /// walk may go deep (Russian roulette ends it without bias); in a thick slab, the more of
    /// the extinction scatters, the brighter the BSDF, with values and samples still agreeing.
    #[test]
    fn values_and_samples_agree_and_a_white_coated_base_conserves_energy() {
        for cos_o in [0.9f32, 0.5, 0.2] {
            let mirror = f64::from(fresnel::dielectric(cos_o, 1.5));
            let (e, s) = albedos(&coated_diffuse(1.0, 0.0, 0.0), cos_o);
            assert!((e + mirror - s).abs() < 0.02, "smooth, cos {cos_o}: values {e} + {mirror}, samples {s}");
            let (e, s) = albedos(&coated_diffuse(0.8, 0.3, 0.0), cos_o);
            assert!((e - s).abs() < 0.01 && e > 0.3, "rough, cos {cos_o}: values {e}, samples {s}");
            // The slab attenuates with unit extinction even without scattering (albedo 0):
            // a thin one and a deep walk lose nothing.
            let deep = Layered { max_depth: 500, thickness: 1e-6, ..coated_diffuse(1.0, 0.0, 0.0) };
            let (e, s) = albedos(&deep, cos_o);
            assert!((s - 1.0).abs() < 0.02 && (e + mirror - 1.0).abs() < 0.02, "deep, cos {cos_o}: {e} {s}");
        }
        // A thick slab: the more of its extinction scatters, the brighter the BSDF. (A deep walk:
        // at the depth limit values connect to the exit from the last scattering event, which a
        // sample would leave by one more step, so the two differ by the truncated paths.)
        let slab =
            |albedo| albedos(&Layered { thickness: 0.5, max_depth: 100, ..coated_diffuse(1.0, 0.3, albedo) }, 0.7);
        let (absorbing, half, mostly) = (slab(0.0), slab(0.5), slab(0.9));
        assert!(absorbing.0 + 0.03 < half.0 && half.0 + 0.03 < mostly.0, "{absorbing:?} {half:?} {mostly:?}");
        assert!((half.0 - half.1).abs() < 0.01 && (mostly.0 - mostly.1).abs() < 0.01, "{half:?} {mostly:?}");
    }

    /// Values and densities are pure functions of their directions; the density, an estimate,
    /// integrates to between 0.8 and 1.5 over the upper hemisphere; the BSDF mirrors below.
    #[test]
    fn estimates_are_deterministic_two_sided_and_normalised() {
        let b = coated_diffuse(0.5, 0.2, 0.3);
        let (wo, wi) = (Vec3::new(0.3, 0.1, 0.95).normalize(), Vec3::new(-0.5, 0.2, 0.8).normalize());
        let m = TransportMode::Radiance;
        assert_eq!(b.eval(wo, wi, m), b.eval(wo, wi, m));
        assert_eq!(b.pdf(wo, wi).to_bits(), b.pdf(wo, wi).to_bits());
        assert_eq!(b.eval(-wo, -wi, m), b.eval(wo, wi, m));
        assert_eq!(b.eval(wo, -wi, m), Rgb::ZERO);
        let mut rng = Pcg32::new(3, 2);
        let n = 100_000;
        let total: f64 = (0..n)
            .map(|_| {
                let w = cosine_hemisphere(next2(&mut rng));
                f64::from(b.pdf(wo, w) / cosine_hemisphere_pdf(w.z))
            })
            .sum::<f64>()
            / n as f64;
        assert!(total > 0.8 && total < 1.5, "density integrates to {total}");
    }

    /// A smooth clear coat over a Lambertian base of reflectance `R` has a closed form
    /// (the coat's internal reflections summed as a geometric series):
    /// `F(θo) + (1 − F(θo))·R·(1 − F̄i)/(1 − R·F̄i)`, with `F̄i` the cosine-weighted mean
    /// internal Fresnel reflectance (total internal reflection included). Values and samples
    /// both reach it; at `R = 1` any internal reflectance would conserve energy, so grey bases
    /// are what test the walk's internal bounces.
    #[test]
    fn a_smooth_coat_over_a_grey_base_matches_the_closed_form() {
        let n = 100_000;
        let internal: f64 = (0..n)
            .map(|i| {
                let cos = (i as f32 + 0.5) / n as f32;
                2.0 * f64::from(fresnel::dielectric(cos, 1.0 / 1.5) * cos) / n as f64
            })
            .sum();
        for r in [0.38f32, 0.58] {
            let b = Layered { thickness: 1e-6, max_depth: 100, ..coated_diffuse(r, 0.0, 0.0) };
            for cos_o in [0.9f32, 0.5] {
                let f = f64::from(fresnel::dielectric(cos_o, 1.5));
                let r = f64::from(r);
                let expected = (1.0 - f) * r * (1.0 - internal) / (1.0 - r * internal);
                let (values, samples) = albedos(&b, cos_o);
                assert!((values - expected).abs() < 0.003, "R {r}, cos {cos_o}: values {values}, expected {expected}");
                let samples = samples - f;
                assert!(
                    (samples - expected).abs() < 0.003,
                    "R {r}, cos {cos_o}: samples {samples}, expected {expected}"
                );
            }
        }
    }
}
