//! A BVH leaf's primitives in packets of four, their triangles stored as structure of arrays
//! so that the watertight test of [`super::triangle`] runs on all four lanes at once (the lane
//! loops compile to packed SSE arithmetic). Every lane performs exactly the scalar test's
//! floating-point operations in the scalar test's order, so a packet finds the same hits with
//! the same distances and barycentrics bit for bit; only the part of the test that depends on
//! `t_max` runs per lane, in the primitives' order, so that the nearest of equally distant hits
//! is the one the scalar loop would keep. A lane whose edge functions hit zero takes the scalar
//! test (its double-precision fallback); a triangle with an alpha texture is kept or dropped by
//! the texture as in [`Geometry::intersect_prim`], and lanes holding other primitives (spheres,
//! disks, instances) go to [`Geometry::intersect_other`]. The packets hold the only copy of the BVH's triangles in the
//! tree's order: the geometry's own triangle cache is freed once they are built.

use super::triangle::{RayShear, distance, intersect_triangle};
use super::{Geometry, PrimHit, Ray};
use crate::math::Vec3;

/// Lanes per packet.
pub const LANES: usize = 4;

/// Up to four consecutive primitives of one leaf.
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C, align(16))]
pub struct Packet {
    /// Triangle vertices, `p[vertex][axis][lane]`.
    p: [[[f32; LANES]; 3]; 3],
    /// The primitive in each lane.
    prim: [u32; LANES],
    /// Lanes in use (the low `n` bits).
    used: u32,
    /// Lanes in use that hold a triangle tested here.
    tri: u32,
    /// Triangle lanes whose shape has an alpha texture, which decides each of their hits.
    alpha: u32,
    _pad: u32,
}

/// The per-lane values of the test that do not depend on `t_max`.
struct Lanes {
    e: [[f32; LANES]; 3],
    det: [f32; LANES],
    t_scaled: [f32; LANES],
    /// Triangle lanes still hit before the distance test.
    pass: u32,
    /// Triangle lanes with an edge function of zero, for the scalar test.
    exact: u32,
}

impl Packet {
    /// The packet of the `n` (at most [`LANES`]) primitives `first..first + n` of `geometry`.
    pub fn new(geometry: &Geometry, first: u32, n: u32) -> Packet {
        debug_assert!(n as usize <= LANES);
        let mut packet = Packet { p: [[[0.0; LANES]; 3]; 3], prim: [0; LANES], used: 0, tri: 0, alpha: 0, _pad: 0 };
        for lane in 0..n as usize {
            let prim = first + lane as u32;
            packet.prim[lane] = prim;
            packet.used |= 1 << lane;
            if let Some(tri) = geometry.triangle(prim) {
                packet.tri |= 1 << lane;
                if geometry.has_alpha(prim) {
                    packet.alpha |= 1 << lane;
                }
                for (v, p) in tri.iter().enumerate() {
                    for a in 0..3 {
                        packet.p[v][a][lane] = p[a];
                    }
                }
            }
        }
        packet
    }

    /// The vertices of triangle lane `lane`.
    fn vertices(&self, lane: usize) -> [Vec3; 3] {
        [0, 1, 2].map(|v| Vec3::new(self.p[v][0][lane], self.p[v][1][lane], self.p[v][2][lane]))
    }

    /// The watertight test's steps up to the distance test, on every lane.
    #[inline(always)]
    fn lanes(&self, shear: &RayShear) -> Lanes {
        let RayShear { kz, o, sx, sy, sz } = *shear;
        // The rotation that puts the largest direction axis last, as `RayShear::permute`.
        let (ax, ay, az) = match kz {
            0 => (1, 2, 0),
            1 => (2, 0, 1),
            _ => (0, 1, 2),
        };
        let mut x = [[0.0f32; LANES]; 3];
        let mut y = [[0.0f32; LANES]; 3];
        let mut z = [[0.0f32; LANES]; 3];
        for v in 0..3 {
            let (px, py, pz) = (&self.p[v][ax], &self.p[v][ay], &self.p[v][az]);
            for i in 0..LANES {
                z[v][i] = pz[i] - o.z;
            }
            for i in 0..LANES {
                x[v][i] = (px[i] - o.x) + sx * z[v][i];
                y[v][i] = (py[i] - o.y) + sy * z[v][i];
            }
        }
        let mut e = [[0.0f32; LANES]; 3];
        for (k, (a, b)) in [(1, 2), (2, 0), (0, 1)].into_iter().enumerate() {
            for i in 0..LANES {
                e[k][i] = x[a][i] * y[b][i] - y[a][i] * x[b][i];
            }
        }
        let mut det = [0.0f32; LANES];
        let mut t_scaled = [0.0f32; LANES];
        for i in 0..LANES {
            det[i] = e[0][i] + e[1][i] + e[2][i];
            t_scaled[i] = e[0][i] * (z[0][i] * sz) + e[1][i] * (z[1][i] * sz) + e[2][i] * (z[2][i] * sz);
        }
        fn mask(f: impl Fn(usize) -> bool) -> u32 {
            (0..LANES).fold(0, |m, i| m | (u32::from(f(i)) << i))
        }
        let zero = mask(|i| e[0][i] == 0.0 || e[1][i] == 0.0 || e[2][i] == 0.0);
        let neg = mask(|i| e[0][i] < 0.0 || e[1][i] < 0.0 || e[2][i] < 0.0);
        let pos = mask(|i| e[0][i] > 0.0 || e[1][i] > 0.0 || e[2][i] > 0.0);
        let flat = mask(|i| det[i] == 0.0);
        let (exact, pass) = (zero, !zero & !(neg & pos) & !flat);
        Lanes { e, det, t_scaled, pass: pass & self.tri, exact: exact & self.tri }
    }

    /// Triangle lane `i`'s hit closer than `t_max`, alpha texture included.
    #[inline(always)]
    fn triangle_hit(
        &self,
        l: &Lanes,
        i: usize,
        geometry: &Geometry,
        ray: &Ray,
        shear: &RayShear,
        t_max: f32,
    ) -> Option<PrimHit> {
        let bit = 1 << i;
        let prim = self.prim[i];
        let hit = if l.pass & bit != 0 {
            let (t, inv_det) = distance(l.det[i], l.t_scaled[i], t_max)?;
            PrimHit { prim, t, b: Vec3::new(l.e[0][i], l.e[1][i], l.e[2][i]) * inv_det, inner: 0 }
        } else if l.exact & bit != 0 {
            let h = intersect_triangle(ray, shear, self.vertices(i), t_max)?;
            PrimHit { prim, t: h.t, b: h.b, inner: 0 }
        } else {
            return None;
        };
        if self.alpha & bit != 0 && !geometry.alpha_keeps(prim, ray, hit.t, hit.b) {
            return None;
        }
        Some(hit)
    }

    /// The nearest hit closer than `t_max` among the packet's primitives.
    #[inline]
    pub fn closest(&self, geometry: &Geometry, ray: &Ray, shear: &RayShear, mut t_max: f32) -> Option<PrimHit> {
        let l = self.lanes(shear);
        let mut best = None;
        let mut lanes = (l.pass | l.exact) | (self.used & !self.tri);
        while lanes != 0 {
            let i = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let hit = if self.tri & (1 << i) != 0 {
                self.triangle_hit(&l, i, geometry, ray, shear, t_max)
            } else {
                geometry.intersect_other(self.prim[i], ray, t_max)
            };
            if let Some(hit) = hit {
                t_max = hit.t;
                best = Some(hit);
            }
        }
        best
    }

    /// Whether any of the packet's primitives is hit closer than `t_max`.
    #[inline]
    pub fn any(&self, geometry: &Geometry, ray: &Ray, shear: &RayShear, t_max: f32) -> bool {
        let l = self.lanes(shear);
        let mut lanes = l.pass | l.exact;
        while lanes != 0 {
            let i = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            if self.triangle_hit(&l, i, geometry, ray, shear, t_max).is_some() {
                return true;
            }
        }
        let mut lanes = self.used & !self.tri;
        while lanes != 0 {
            let i = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            if geometry.intersect_other(self.prim[i], ray, t_max).is_some() {
                return true;
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Shape, Sphere, TriangleMesh};
    use crate::math::rng::Pcg32;

    /// The scalar loop a packet replaces: the primitives in order, each within the distance of
    /// the nearest hit so far.
    fn scalar_closest(g: &Geometry, prims: std::ops::Range<u32>, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        let shear = RayShear::new(ray);
        let mut t_max = t_max;
        let mut best = None;
        for prim in prims {
            if let Some(hit) = g.intersect_prim(prim, ray, &shear, t_max) {
                t_max = hit.t;
                best = Some(hit);
            }
        }
        best
    }

    /// Packets find the scalar test's hits bit for bit — the same primitive, distance and
    /// barycentrics — and the same occlusion, on triangles mixed with spheres, on coincident
    /// triangles (ties), and on rays through shared edges and vertices of a grid at integer
    /// coordinates, whose edge functions are exactly zero.
    #[test]
    fn packets_agree_with_the_scalar_test_bit_for_bit() {
        let mut rng = Pcg32::new(11, 4);
        let r3 = |rng: &mut Pcg32| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE;
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for t in 0..60u32 {
            let c = r3(&mut rng) * 0.5;
            positions.extend([c, c + r3(&mut rng) * 0.6, c + r3(&mut rng) * 0.6]);
            indices.push([3 * t, 3 * t + 1, 3 * t + 2]);
        }
        // A copy of the first triangle: equal distances, the first in order must win.
        positions.extend_from_within(0..3);
        indices.push([180, 181, 182]);
        // A grid of unit squares at z = 0.25, two triangles each.
        let base = positions.len() as u32;
        for y in 0..4 {
            for x in 0..4 {
                positions.push(Vec3::new(x as f32 - 2.0, y as f32 - 2.0, 0.25));
            }
        }
        for y in 0..3 {
            for x in 0..3 {
                let a = base + y * 4 + x;
                indices.push([a, a + 1, a + 5]);
                indices.push([a, a + 5, a + 4]);
            }
        }
        let mesh = TriangleMesh::new(positions, indices, None, None).unwrap();
        let mut shapes = vec![Shape::Mesh(mesh)];
        for _ in 0..6 {
            shapes.push(Shape::Sphere(Sphere { center: r3(&mut rng) * 0.5, radius: 0.15, reverse_orientation: false }));
        }
        // Cut-out triangles: an alpha of one half keeps about half of their hits.
        let mut cut = Vec::new();
        for _ in 0..20 {
            let c = r3(&mut rng) * 0.5;
            cut.extend([c, c + r3(&mut rng) * 0.6, c + r3(&mut rng) * 0.6]);
        }
        let cut_indices = (0..20u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        shapes.push(Shape::Mesh(TriangleMesh::new(cut, cut_indices, None, None).unwrap()));
        let mut g = Geometry::new(shapes);
        g.set_alpha(g.shapes.len() - 1, 0.5.into());
        let n = g.prims.len() as u32;
        let packets: Vec<Packet> =
            (0..n).step_by(LANES).map(|first| Packet::new(&g, first, (n - first).min(LANES as u32))).collect();
        assert!(packets.iter().any(|p| p.tri != p.used), "no lane of another primitive");
        assert!(packets.iter().any(|p| p.alpha != 0), "no cut-out lane");
        let mut hits = 0;
        for i in 0..20_000 {
            let ray = if i % 4 == 0 {
                // Straight down through grid vertices and edges.
                let o =
                    Vec3::new((rng.next_u32() % 7) as f32 * 0.5 - 1.5, (rng.next_u32() % 7) as f32 * 0.5 - 1.5, 2.0);
                Ray::new(o, -Vec3::Z)
            } else {
                let o = r3(&mut rng) * 2.5;
                Ray::new(o, (r3(&mut rng) * 0.5 - o).normalize())
            };
            let t_max = if i % 3 == 0 { 1.5 } else { f32::INFINITY };
            let shear = RayShear::new(&ray);
            let mut t = t_max;
            let mut best = None;
            let mut occluded = false;
            for p in &packets {
                if let Some(hit) = p.closest(&g, &ray, &shear, t) {
                    t = hit.t;
                    best = Some(hit);
                }
                occluded |= p.any(&g, &ray, &shear, t_max);
            }
            let scalar = scalar_closest(&g, 0..n, &ray, t_max);
            match (best, scalar) {
                (Some(a), Some(b)) => {
                    hits += 1;
                    assert_eq!(a.prim, b.prim, "ray {i}");
                    assert_eq!(a.t.to_bits(), b.t.to_bits(), "ray {i}");
                    assert_eq!(a.b.to_array().map(f32::to_bits), b.b.to_array().map(f32::to_bits), "ray {i}");
                }
                (None, None) => {}
                (a, b) => panic!("ray {i}: packets {a:?}, scalar {b:?}"),
            }
            assert_eq!(occluded, scalar.is_some(), "ray {i}");
        }
        assert!(hits > 5000, "too few hits ({hits}) to mean anything");
    }
}
