//! The default accelerator: a binary tree built by PLOC with reinsertion and SAH leaf
//! collapsing (the `obvhs` crate), collapsed into the four-wide tree of [`super::wide`] that
//! rays traverse. The geometry's primitive table is reordered to the tree's leaf order, and each
//! leaf's primitives are copied into [`Packet`]s of four whose triangles are tested together;
//! the tree's leaves index the packets.

use super::Accel;
use super::wide::Wide;
use crate::geometry::packet::{LANES, Packet};
use crate::geometry::{Geometry, PrimHit, Ray, RayShear};
use crate::math::Vec3;
use crate::pages::PageVec;
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use rayon::prelude::*;
use std::time::Duration;

struct Bounds(Aabb);

impl obvhs::Boundable for Bounds {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

/// Stack for the binary tree's build, which runs on a thread of its own: primitives with
/// identical bounds (coincident copies, shapes scaled to a point) make a chain as deep as their
/// count, and a pass of the builder that recursed over the tree would go that deep. (The
/// collapse into the wide tree is iterative.)
fn build_stack_bytes(primitives: usize) -> usize {
    (32 << 20) + primitives.saturating_mul(2 << 10)
}

/// The most primitives a leaf holds.
const LEAF_PRIMS: u32 = 8;
/// The cost of a node visit relative to a primitive test in the surface-area heuristic that
/// decides which subtrees become leaves (obvhs's default is 3). Lower makes smaller leaves:
/// Tempera's watertight triangle test is dearer than the box test of four children.
const TRAVERSAL_COST: f32 = 2.0;

/// Builds the binary tree on a thread whose stack fits the deepest tree `bounds` can make (the
/// stack is address space, taken only as deep as the recursion goes), or here when no such
/// thread can be made.
fn build_tree(bounds: &[Bounds]) -> Bvh2 {
    let params = obvhs::BvhBuildParams {
        max_prims_per_leaf: LEAF_PRIMS,
        collapse_traversal_cost: TRAVERSAL_COST,
        ..obvhs::BvhBuildParams::medium_build()
    };
    let build = || obvhs::bvh2::builder::build_bvh2(bounds, params, &mut Duration::default());
    std::thread::scope(|scope| {
        let thread = std::thread::Builder::new().name("bvh-build".into()).stack_size(build_stack_bytes(bounds.len()));
        match thread.spawn_scoped(scope, build) {
            Ok(handle) => handle.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic)),
            Err(_) => build(),
        }
    })
}

/// The default accelerator.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    tree: Wide,
    packets: PageVec<Packet>,
}

impl Bvh {
    /// Builds over `geometry` and reorders its primitive table to the tree's leaf order.
    pub fn build(geometry: &mut Geometry) -> Self {
        if geometry.prims.is_empty() {
            return Self::default();
        }
        let bounds: Vec<Bounds> = (0..geometry.prims.len())
            .into_par_iter()
            .map(|i| {
                let (lo, hi) = geometry.bounds(i);
                // Pad flat boxes (axis-aligned quads) so that slab tests stay robust.
                let pad = (hi - lo).max_element().max(1e-6) * 1e-5;
                Bounds(Aabb::new((lo - Vec3::splat(pad)).into(), (hi + Vec3::splat(pad)).into()))
            })
            .collect();
        let bvh2 = build_tree(&bounds);
        geometry.reorder(&bvh2.primitive_indices);
        let mut tree = Wide::collapse(&bvh2);
        // Each packet's primitives: `(first, count)`, the packets of a leaf consecutive.
        let mut ranges: Vec<(u32, u32)> = Vec::new();
        tree.remap_leaves(|first, count| {
            let start = ranges.len() as u32;
            let lanes = LANES as u32;
            ranges.extend((first..first + count).step_by(LANES).map(|p| (p, (first + count - p).min(lanes))));
            (start, ranges.len() as u32 - start)
        });
        let mut packets = PageVec::zeroed(ranges.len());
        packets.par_iter_mut().zip(ranges.par_iter()).for_each(|(packet, &(first, n))| {
            *packet = Packet::new(geometry, first, n);
        });
        Self { tree, packets }
    }
}

impl Accel for Bvh {
    fn intersect(&self, geometry: &Geometry, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        let shear = RayShear::new(ray);
        let packets: &[Packet] = &self.packets;
        self.tree.closest(ray.o, ray.d, t_max, |p, t_max| {
            packets[p as usize].closest(geometry, ray, &shear, t_max).map(|hit| (hit.t, hit))
        })
    }

    fn occluded(&self, geometry: &Geometry, ray: &Ray, t_max: f32) -> bool {
        let shear = RayShear::new(ray);
        let packets: &[Packet] = &self.packets;
        self.tree.any(ray.o, ray.d, t_max, |p| packets[p as usize].any(geometry, ray, &shear, t_max))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::BruteForce;
    use crate::geometry::{Disk, Shape, Sphere, TriangleMesh};
    use crate::math::rng::Pcg32;

    fn random_geometry(rng: &mut Pcg32) -> Geometry {
        let mut r3 = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE;
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for t in 0..2000u32 {
            let c = r3();
            positions.extend([c, c + r3() * 0.1, c + r3() * 0.1]);
            indices.push([3 * t, 3 * t + 1, 3 * t + 2]);
        }
        let mut shapes = vec![Shape::Mesh(TriangleMesh::new(positions, indices, None, None).unwrap())];
        for _ in 0..20 {
            shapes.push(Shape::Sphere(Sphere { center: r3(), radius: 0.05, reverse_orientation: false }));
            let n = r3().normalize();
            shapes.push(Shape::Disk(Disk::new(r3(), n, 0.08)));
        }
        Geometry::new(shapes)
    }

    #[test]
    fn bvh_agrees_with_brute_force() {
        let mut rng = Pcg32::new(42, 0);
        let mut geometry = random_geometry(&mut rng);
        let bvh = Bvh::build(&mut geometry);
        let mut hits = 0;
        for i in 0..20_000 {
            let o = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 3.0 - Vec3::splat(1.5);
            let d = crate::math::warp::uniform_sphere(crate::math::Vec2::new(rng.next_f32(), rng.next_f32()));
            let ray = Ray::new(o, d);
            let t_max = if i % 3 == 0 { 0.7 } else { f32::INFINITY };
            let a = bvh.intersect(&geometry, &ray, t_max);
            let b = BruteForce.intersect(&geometry, &ray, t_max);
            match (a, b) {
                (Some(a), Some(b)) => {
                    hits += 1;
                    assert!((a.t - b.t).abs() <= 1e-6 * b.t.max(1.0), "t differs: {} vs {}", a.t, b.t);
                    assert!(a.prim == b.prim || (a.t - b.t).abs() == 0.0, "primitive differs");
                }
                (None, None) => {}
                _ => panic!("bvh and brute force disagree on ray {i}: {a:?} vs {b:?}"),
            }
            assert_eq!(bvh.occluded(&geometry, &ray, t_max), b.is_some());
        }
        assert!(hits > 2000, "too few hits ({hits}) for a meaningful test");
    }

    #[test]
    fn axis_aligned_rays_with_negative_zero_components_hit() {
        let quad = TriangleMesh::new(
            vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(2.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
            None,
            None,
        )
        .unwrap();
        let mut g = Geometry::new(vec![Shape::Mesh(quad)]);
        let bvh = Bvh::build(&mut g);
        for d in [-Vec3::Z, Vec3::Z, Vec3::new(-0.0, 0.0, -1.0), Vec3::new(0.0, -0.0, 1.0)] {
            let ray = Ray::new(Vec3::new(1.3, 0.4, 0.0) - d, d);
            assert!(bvh.intersect(&g, &ray, f32::INFINITY).is_some(), "direction {d:?}");
            assert!(bvh.occluded(&g, &ray, f32::INFINITY), "direction {d:?}");
        }
    }

    /// Triangles collapsed to one point (a tessellated sphere of radius 1e-39 in a scene file)
    /// have identical, empty bounds; the build then makes a chain as deep as their count, which
    /// overflowed the stack of the thread that built it (an abort). 12,000 of them, and one
    /// ordinary triangle behind them that rays must still find.
    #[test]
    fn triangles_collapsed_to_a_point_build_without_overflowing_the_stack() {
        let count = 12_000u32;
        let mut positions = vec![Vec3::new(1.0, 0.5, 0.0); 3 * count as usize];
        let mut indices: Vec<[u32; 3]> = (0..count).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        positions.extend([Vec3::new(0.0, 0.0, -1.0), Vec3::new(2.0, 0.0, -1.0), Vec3::new(0.0, 2.0, -1.0)]);
        indices.push([3 * count, 3 * count + 1, 3 * count + 2]);
        let mut g = Geometry::new(vec![Shape::Mesh(TriangleMesh::new(positions, indices, None, None).unwrap())]);
        let bvh = Bvh::build(&mut g);
        let ray = Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z);
        assert!((bvh.intersect(&g, &ray, f32::INFINITY).expect("a hit").t - 2.0).abs() < 1e-6);
        assert!(bvh.occluded(&g, &ray, f32::INFINITY));
        assert!(!bvh.occluded(&g, &Ray::new(Vec3::new(3.0, 3.0, 1.0), -Vec3::Z), f32::INFINITY));
    }

    /// 4,000 coincident triangles under the ray: every child of every node is entered, and
    /// every entry pushed must come back. The ray finds the plane, and, from below and stopping
    /// short of it, the one triangle behind.
    #[test]
    fn coincident_triangles_deeper_than_the_stack_are_all_traversed() {
        let count = 4000u32;
        let tri = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0)];
        let mut positions: Vec<Vec3> = (0..count).flat_map(|_| tri).collect();
        let mut indices: Vec<[u32; 3]> = (0..count).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        positions.extend(tri.map(|p| p - Vec3::Z));
        indices.push([3 * count, 3 * count + 1, 3 * count + 2]);
        let mut g = Geometry::new(vec![Shape::Mesh(TriangleMesh::new(positions, indices, None, None).unwrap())]);
        let bvh = Bvh::build(&mut g);
        let ray = Ray::new(Vec3::new(0.3, 0.3, 1.0), -Vec3::Z);
        let hit = bvh.intersect(&g, &ray, f32::INFINITY).expect("a hit");
        assert!((hit.t - 1.0).abs() < 1e-6);
        assert!(g.prims[hit.prim as usize].index < count);
        assert!(bvh.occluded(&g, &ray, f32::INFINITY));
        // From below the plane, upwards, stopping short of it: only the far triangle remains.
        let up = Ray::new(Vec3::new(0.3, 0.3, -3.0), Vec3::Z);
        let hit = bvh.intersect(&g, &up, 2.5).expect("the triangle at z = -1");
        assert!((hit.t - 2.0).abs() < 1e-6);
        assert_eq!(g.prims[hit.prim as usize].index, count);
        assert!(!bvh.occluded(&g, &up, 1.5));
    }

    /// A ray whose direction is not finite (a scene file's 1e39 made it so) would enter every
    /// box, the unused child slots included; it hits nothing.
    #[test]
    fn rays_with_non_finite_directions_do_not_panic() {
        let tri = TriangleMesh::new(
            vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)],
            vec![[0, 1, 2]],
            None,
            None,
        )
        .unwrap();
        let mut g = Geometry::new(vec![
            Shape::Mesh(tri),
            Shape::Sphere(Sphere { center: Vec3::splat(3.0), radius: 0.5, reverse_orientation: false }),
        ]);
        let bvh = Bvh::build(&mut g);
        for d in [Vec3::new(f32::NAN, 0.0, 0.0), Vec3::new(f32::INFINITY, 1.0, 0.0), Vec3::splat(f32::NEG_INFINITY)] {
            let ray = Ray { o: Vec3::new(0.2, 0.2, 1.0), d };
            assert!(bvh.intersect(&g, &ray, f32::INFINITY).is_none());
            assert!(!bvh.occluded(&g, &ray, f32::INFINITY));
        }
    }

    #[test]
    fn empty_scene_never_hits() {
        let mut g = Geometry::default();
        let bvh = Bvh::build(&mut g);
        let ray = Ray::new(Vec3::ZERO, Vec3::Z);
        assert!(bvh.intersect(&g, &ray, f32::INFINITY).is_none());
        assert!(!bvh.occluded(&g, &ray, f32::INFINITY));
    }
}
