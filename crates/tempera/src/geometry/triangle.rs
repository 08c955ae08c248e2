//! Watertight ray–triangle intersection (Woop, Benthin & Wald 2013, "Watertight Ray/Triangle
//! Intersection", JCGT 2(1)); pbrt-v4 §6.5.3 follows the same construction.

use super::Ray;
use crate::math::Vec3;

/// Per-ray constants of the watertight test: the axis permutation and the shear.
#[derive(Clone, Copy, Debug)]
pub struct RayShear {
    pub(super) kz: usize,
    /// The ray origin, permuted.
    pub(super) o: Vec3,
    pub(super) sx: f32,
    pub(super) sy: f32,
    pub(super) sz: f32,
}

impl RayShear {
    pub fn new(ray: &Ray) -> Self {
        let a = ray.d.abs();
        let kz = if a.x > a.y {
            if a.x > a.z { 0 } else { 2 }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let kx = (kz + 1) % 3;
        let ky = (kx + 1) % 3;
        let d = ray.d;
        let o = Vec3::new(ray.o[kx], ray.o[ky], ray.o[kz]);
        Self { kz, o, sx: -d[kx] / d[kz], sy: -d[ky] / d[kz], sz: 1.0 / d[kz] }
    }

    /// `v` with its axes in the order `(kx, ky, kz)`: the largest direction axis last. The
    /// permutation is a rotation, picked by `kz` alone.
    #[inline(always)]
    fn permute(&self, v: Vec3) -> Vec3 {
        match self.kz {
            0 => Vec3::new(v.y, v.z, v.x),
            1 => Vec3::new(v.z, v.x, v.y),
            _ => v,
        }
    }
}

/// Hit distance and barycentrics `(b0, b1, b2)` weighting the vertices `p0, p1, p2`.
#[derive(Clone, Copy, Debug)]
pub struct TriangleHit {
    pub t: f32,
    pub b: Vec3,
}

/// Intersects `ray` with triangle `(p0, p1, p2)` for `0 < t < t_max`.
#[inline]
pub fn intersect_triangle(ray: &Ray, shear: &RayShear, p: [Vec3; 3], t_max: f32) -> Option<TriangleHit> {
    let RayShear { sx, sy, sz, o, .. } = *shear;
    debug_assert_eq!(o, shear.permute(ray.o));
    // Permuting first and subtracting the permuted origin is the same arithmetic, per
    // component, as subtracting first.
    let mut q = p.map(|v| shear.permute(v) - o);
    for v in q.iter_mut() {
        v.x += sx * v.z;
        v.y += sy * v.z;
    }
    let mut e0 = q[1].x * q[2].y - q[1].y * q[2].x;
    let mut e1 = q[2].x * q[0].y - q[2].y * q[0].x;
    let mut e2 = q[0].x * q[1].y - q[0].y * q[1].x;
    if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
        let f = |a: Vec3, b: Vec3| (f64::from(a.x) * f64::from(b.y) - f64::from(a.y) * f64::from(b.x)) as f32;
        e0 = f(q[1], q[2]);
        e1 = f(q[2], q[0]);
        e2 = f(q[0], q[1]);
    }
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return None;
    }
    let det = e0 + e1 + e2;
    if det == 0.0 {
        return None;
    }
    let z = [q[0].z * sz, q[1].z * sz, q[2].z * sz];
    let t_scaled = e0 * z[0] + e1 * z[1] + e2 * z[2];
    let (t, inv_det) = distance(det, t_scaled, t_max)?;
    Some(TriangleHit { t, b: Vec3::new(e0, e1, e2) * inv_det })
}

/// The last step of the test, the only one that depends on `t_max`: from the determinant
/// `det` (non-zero) and the scaled distance `t_scaled`, the hit distance and `1 / det` when
/// `0 < t < t_max`.
#[inline(always)]
pub(super) fn distance(det: f32, t_scaled: f32, t_max: f32) -> Option<(f32, f32)> {
    if det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_max * det) {
        return None;
    }
    if det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_max * det) {
        return None;
    }
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    (t > 0.0 && t < t_max).then_some((t, inv_det))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::Pcg32;

    #[test]
    fn hits_inside_and_misses_outside() {
        let tri = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        let ray = Ray::new(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z);
        let h = intersect_triangle(&ray, &RayShear::new(&ray), tri, f32::INFINITY).unwrap();
        assert!((h.t - 1.0).abs() < 1e-6);
        assert!((h.b - Vec3::new(0.5, 0.25, 0.25)).length() < 1e-6);
        let ray = Ray::new(Vec3::new(0.75, 0.75, 1.0), -Vec3::Z);
        assert!(intersect_triangle(&ray, &RayShear::new(&ray), tri, f32::INFINITY).is_none());
        let ray = Ray::new(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z);
        assert!(intersect_triangle(&ray, &RayShear::new(&ray), tri, 0.5).is_none());
    }

    #[test]
    fn shared_edges_are_watertight() {
        // Two triangles sharing a diagonal: rays through the diagonal must hit at least one.
        let a = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0)];
        let b = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        let mut rng = Pcg32::new(11, 0);
        for _ in 0..20_000 {
            let s = rng.next_f32();
            let target = Vec3::new(s, s, 0.0);
            let o = Vec3::new(rng.next_f32() * 4.0 - 2.0, rng.next_f32() * 4.0 - 2.0, 3.0);
            let ray = Ray::new(o, (target - o).normalize());
            let sh = RayShear::new(&ray);
            let hit = intersect_triangle(&ray, &sh, a, f32::INFINITY).is_some()
                || intersect_triangle(&ray, &sh, b, f32::INFINITY).is_some();
            assert!(hit, "ray through the shared edge leaked at s = {s}");
        }
    }
}
