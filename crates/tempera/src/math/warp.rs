//! Warps from the unit square to disks, hemispheres, spheres, cones and triangles, with their
//! densities (pbrt-v4 §A.5; Shirley & Chiu 1997 for the concentric disk; Clarberg 2008, "Fast
//! Equal-Area Mapping of the (Hemi)Sphere using SIMD", for the octahedral equal-area map).

use super::{Vec2, Vec3, safe_sqrt};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, PI};

/// Uniform point on the unit disk, low distortion (Shirley & Chiu concentric map).
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) =
        if o.x.abs() > o.y.abs() { (o.x, FRAC_PI_4 * (o.y / o.x)) } else { (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y)) };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Uniform point on the unit disk by polar coordinates.
pub fn polar_disk(u: Vec2) -> Vec2 {
    let r = u.x.sqrt();
    let theta = 2.0 * PI * u.y;
    Vec2::new(r * theta.cos(), r * theta.sin())
}

/// Cosine-weighted direction on the +z hemisphere.
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    let z = safe_sqrt(1.0 - d.length_squared());
    Vec3::new(d.x, d.y, z)
}

#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// Uniform direction on the unit sphere.
pub fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = safe_sqrt(1.0 - z * z);
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

pub const UNIFORM_SPHERE_PDF: f32 = 1.0 / (4.0 * PI);

/// Uniform direction in the cone of half-angle `acos(cos_max)` around +z.
pub fn uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let cos_theta = (1.0 - u.x) + u.x * cos_max;
    let sin_theta = safe_sqrt(1.0 - cos_theta * cos_theta);
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
}

#[inline]
pub fn uniform_cone_pdf(cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * (1.0 - cos_max))
}

/// Uniform barycentrics `(b0, b1, b2)` on a triangle (pbrt-v4's low-distortion warp).
pub fn uniform_triangle(u: Vec2) -> Vec3 {
    let (b0, b1) = if u.x < u.y {
        let b0 = u.x / 2.0;
        (b0, u.y - b0)
    } else {
        let b1 = u.y / 2.0;
        (u.x - b1, b1)
    };
    Vec3::new(b0, b1, 1.0 - b0 - b1)
}

/// The sample `u` that [`concentric_disk`] maps to the disk point `d` (`|d| ≤ 1`).
pub fn concentric_disk_inverse(d: Vec2) -> Vec2 {
    let r = d.length();
    if r == 0.0 {
        return Vec2::splat(0.5);
    }
    let mut phi = d.y.atan2(d.x);
    if phi < -FRAC_PI_4 {
        phi += 2.0 * PI;
    }
    // The square's point `o` in `[-1, 1]²`: `r` on the axis whose quadrant holds `phi`, the
    // other coordinate linear in the angle from that axis.
    let o = if phi < FRAC_PI_4 {
        Vec2::new(r, r * phi / FRAC_PI_4)
    } else if phi < 3.0 * FRAC_PI_4 {
        Vec2::new(r * (FRAC_PI_2 - phi) / FRAC_PI_4, r)
    } else if phi < 5.0 * FRAC_PI_4 {
        Vec2::new(-r, -r * (phi - PI) / FRAC_PI_4)
    } else {
        Vec2::new(-r * (3.0 * FRAC_PI_2 - phi) / FRAC_PI_4, -r)
    };
    unit_square((o + Vec2::ONE) * 0.5)
}

/// The sample `u` that [`polar_disk`] maps to the disk point `d`.
pub fn polar_disk_inverse(d: Vec2) -> Vec2 {
    let phi = spherical_phi(Vec3::new(d.x, d.y, 0.0));
    unit_square(Vec2::new(d.length_squared(), phi / (2.0 * PI)))
}

/// The sample `u` that [`cosine_hemisphere`] maps to the direction `w` (`w.z ≥ 0`).
pub fn cosine_hemisphere_inverse(w: Vec3) -> Vec2 {
    concentric_disk_inverse(Vec2::new(w.x, w.y))
}

/// The sample `u` that [`uniform_sphere`] maps to the unit direction `w`.
pub fn uniform_sphere_inverse(w: Vec3) -> Vec2 {
    unit_square(Vec2::new((1.0 - w.z) * 0.5, spherical_phi(w) / (2.0 * PI)))
}

/// The sample `u` that [`uniform_cone`] maps to the unit direction `w` inside the cone.
pub fn uniform_cone_inverse(w: Vec3, cos_max: f32) -> Vec2 {
    let x = if cos_max < 1.0 { (1.0 - w.z) / (1.0 - cos_max) } else { 0.0 };
    unit_square(Vec2::new(x, spherical_phi(w) / (2.0 * PI)))
}

/// The sample `u` that [`uniform_triangle`] maps to the barycentrics `b` (its first two;
/// inverting the two branches of the warp, `b0 < b1` and `b0 ≥ b1`).
pub fn uniform_triangle_inverse(b: Vec3) -> Vec2 {
    let u = if b.x < b.y { Vec2::new(2.0 * b.x, b.y + b.x) } else { Vec2::new(b.x + b.y, 2.0 * b.y) };
    unit_square(u)
}

/// `u` with each coordinate kept in `[0, 1)`.
fn unit_square(u: Vec2) -> Vec2 {
    let below_one = 1.0 - f32::EPSILON / 2.0;
    Vec2::new(u.x.clamp(0.0, below_one), u.y.clamp(0.0, below_one))
}

/// Octahedral equal-area map from the unit square to the unit sphere (Clarberg 2008).
pub fn equal_area_square_to_sphere(p: Vec2) -> Vec3 {
    let u = 2.0 * p.x - 1.0;
    let v = 2.0 * p.y - 1.0;
    let (up, vp) = (u.abs(), v.abs());
    let signed_distance = 1.0 - (up + vp);
    let d = signed_distance.abs();
    let r = 1.0 - d;
    let phi = if r == 0.0 { 1.0 } else { (vp - up) / r + 1.0 } * FRAC_PI_4;
    let z = (1.0 - r * r).copysign(signed_distance);
    let cos_phi = phi.cos().copysign(u);
    let sin_phi = phi.sin().copysign(v);
    let s = r * safe_sqrt(2.0 - r * r);
    Vec3::new(cos_phi * s, sin_phi * s, z)
}

/// Inverse of [`equal_area_square_to_sphere`].
pub fn equal_area_sphere_to_square(d: Vec3) -> Vec2 {
    let (x, y, z) = (d.x.abs(), d.y.abs(), d.z.abs());
    let r = safe_sqrt(1.0 - z);
    let a = x.max(y);
    let b = if a == 0.0 { 0.0 } else { x.min(y) / a };
    let mut phi = b.atan() * 2.0 / PI;
    if x < y {
        phi = 1.0 - phi;
    }
    let mut v = phi * r;
    let mut u = r - v;
    if d.z < 0.0 {
        std::mem::swap(&mut u, &mut v);
        u = 1.0 - u;
        v = 1.0 - v;
    }
    u = u.copysign(d.x);
    v = v.copysign(d.y);
    Vec2::new((u + 1.0) * 0.5, (v + 1.0) * 0.5)
}

/// Direction from spherical angles, z up.
#[inline]
pub fn spherical_direction(sin_theta: f32, cos_theta: f32, phi: f32) -> Vec3 {
    Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
}

/// Polar angle of a unit vector measured from +z.
#[inline]
pub fn spherical_theta(v: Vec3) -> f32 {
    v.z.clamp(-1.0, 1.0).acos()
}

/// Azimuth of a vector in `[0, 2π)`.
#[inline]
pub fn spherical_phi(v: Vec3) -> f32 {
    let p = v.y.atan2(v.x);
    if p < 0.0 { p + 2.0 * PI } else { p }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::Pcg32;

    #[test]
    fn equal_area_map_round_trips_and_is_unit() {
        let mut rng = Pcg32::new(1, 0);
        for _ in 0..10_000 {
            let p = Vec2::new(rng.next_f32(), rng.next_f32());
            let d = equal_area_square_to_sphere(p);
            assert!((d.length() - 1.0).abs() < 1e-4);
            let q = equal_area_sphere_to_square(d);
            assert!((p - q).length() < 2e-3, "{p} -> {d} -> {q}");
        }
    }

    #[test]
    fn equal_area_map_preserves_area() {
        // Fraction of square samples landing in the upper cap z > 0.5 must be the cap's area
        // fraction (1 - 0.5) / 2 = 0.25.
        let mut rng = Pcg32::new(2, 0);
        let n = 200_000;
        let hits = (0..n)
            .filter(|_| {
                let d = equal_area_square_to_sphere(Vec2::new(rng.next_f32(), rng.next_f32()));
                d.z > 0.5
            })
            .count();
        let frac = hits as f64 / f64::from(n);
        assert!((frac - 0.25).abs() < 0.005, "{frac}");
    }

    #[test]
    fn inverse_warps_round_trip() {
        let mut rng = Pcg32::new(4, 0);
        let close = |a: Vec3, b: Vec3| (a - b).length() < 2e-4;
        for _ in 0..20_000 {
            let u = Vec2::new(rng.next_f32(), rng.next_f32());
            let d = concentric_disk(u);
            assert!((concentric_disk_inverse(d) - u).length() < 2e-4, "{u} -> {d}");
            let d = polar_disk(u);
            let back = polar_disk(polar_disk_inverse(d));
            assert!((back - d).length() < 2e-4, "{u} -> {d} -> {back}");
            let w = cosine_hemisphere(u);
            assert!(close(cosine_hemisphere(cosine_hemisphere_inverse(w)), w));
            let w = uniform_sphere(u);
            assert!(close(uniform_sphere(uniform_sphere_inverse(w)), w));
            let w = uniform_cone(u, 0.8);
            assert!(close(uniform_cone(uniform_cone_inverse(w, 0.8), 0.8), w));
            let b = uniform_triangle(u);
            assert!(close(uniform_triangle(uniform_triangle_inverse(b)), b), "{u} -> {b}");
            let q = uniform_triangle_inverse(b);
            assert!(q.min_element() >= 0.0 && q.max_element() < 1.0);
        }
    }

    #[test]
    fn disks_and_triangles_stay_in_domain() {
        let mut rng = Pcg32::new(3, 0);
        for _ in 0..10_000 {
            let u = Vec2::new(rng.next_f32(), rng.next_f32());
            assert!(concentric_disk(u).length() <= 1.0 + 1e-6);
            assert!(polar_disk(u).length() <= 1.0 + 1e-6);
            let b = uniform_triangle(u);
            assert!(b.min_element() >= -1e-6 && (b.x + b.y + b.z - 1.0).abs() < 1e-5);
            assert!(cosine_hemisphere(u).z >= 0.0);
            assert!(uniform_cone(u, 0.9).z >= 0.9 - 1e-6);
        }
    }
}
