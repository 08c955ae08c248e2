//! Intel Embree 3 as an accelerator (cargo feature `embree`; Debian's `libembree-dev`), through
//! the `embree` crate's bindings to its C API (the Embree 3 API reference: `rtcIntersect1`,
//! `rtcOccluded1`, user geometries, extended intersect contexts).
//!
//! The scene's triangles outside instances form one native Embree triangle geometry, traversed
//! and intersected by Embree. Everything else is one user geometry whose primitives Embree
//! bounds and traverses and Tempera intersects: analytic spheres and disks (kept analytic, not
//! tessellated), instances (each intersected through its prototype's own BVH), and triangles of
//! shapes with an alpha texture (so cut-outs and stochastic alpha behave exactly as with the
//! default BVH, with no filter function needed). A filter function passes each native triangle
//! hit through Tempera's watertight test: hits that test misses are rejected, and the kept one
//! carries Tempera's distance and barycentrics, the ones the default BVH gives for the same
//! primitive. Both accelerators then report the same nearest hit, up to which of two
//! primitives hit at the same distance is reported.
//!
//! The geometry is handed to the callbacks through the intersect context (a `#[repr(C)]`
//! extension of `RTCIntersectContext`), not stored in Embree, so the scene may move.

use super::Accel;
use crate::geometry::{Geometry, PrimHit, Ray, RayShear};
use embree::sys;
use std::cell::Cell;
use std::os::raw::{c_uint, c_void};

const INVALID: c_uint = u32::MAX;

/// Embree's device and committed scene, with the map from its primitives to Tempera's.
pub struct EmbreeAccel {
    device: sys::RTCDevice,
    scene: sys::RTCScene,
    /// Tempera's primitive of each native triangle.
    triangles: Vec<u32>,
    /// Tempera's primitive of each user primitive.
    users: Vec<u32>,
    user_geometry: c_uint,
}

// Embree's committed scenes are safe to query from any number of threads at once; the handles
// are only released in `drop`.
unsafe impl Send for EmbreeAccel {}
unsafe impl Sync for EmbreeAccel {}

/// The intersect context with what the callbacks need. Embree passes the pointer to its
/// leading `RTCIntersectContext` back to them unchanged.
#[repr(C)]
struct Context<'a> {
    base: sys::RTCIntersectContext,
    geometry: &'a Geometry,
    triangles: &'a [u32],
    users: &'a [u32],
    ray: Ray,
    shear: RayShear,
    /// The nearest hit accepted so far, by the user geometry's intersection or the triangles'
    /// filter (its primitive is the one Embree reports last, and so finally).
    hit: Cell<Option<PrimHit>>,
}

impl<'a> Context<'a> {
    fn new(geometry: &'a Geometry, accel: &'a EmbreeAccel, ray: &Ray) -> Self {
        let base =
            sys::RTCIntersectContext { flags: sys::RTCIntersectContextFlags(0), filter: None, instID: [INVALID; 1] };
        Self {
            base,
            geometry,
            triangles: &accel.triangles,
            users: &accel.users,
            ray: *ray,
            shear: RayShear::new(ray),
            hit: Cell::new(None),
        }
    }
}

fn rtc_ray(ray: &Ray, t_max: f32) -> sys::RTCRay {
    sys::RTCRay {
        org_x: ray.o.x,
        org_y: ray.o.y,
        org_z: ray.o.z,
        tnear: 0.0,
        dir_x: ray.d.x,
        dir_y: ray.d.y,
        dir_z: ray.d.z,
        time: 0.0,
        tfar: t_max,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

unsafe extern "C" fn user_bounds(args: *const sys::RTCBoundsFunctionArguments) {
    // SAFETY: Embree passes valid arguments; the user pointer is the accelerator's build data,
    // alive during the commit that calls this.
    unsafe {
        let args = &*args;
        let (geometry, users) = &*(args.geometryUserPtr as *const (&Geometry, &[u32]));
        let (lo, hi) = geometry.bounds(users[args.primID as usize] as usize);
        *args.bounds_o = sys::RTCBounds {
            lower_x: lo.x,
            lower_y: lo.y,
            lower_z: lo.z,
            align0: 0.0,
            upper_x: hi.x,
            upper_y: hi.y,
            upper_z: hi.z,
            align1: 0.0,
        };
    }
}

unsafe extern "C" fn user_intersect(args: *const sys::RTCIntersectFunctionNArguments) {
    // SAFETY: queries are single rays (`rtcIntersect1`: N = 1, the ray-hit an `RTCRayHit`), and
    // the context is the `Context` the query was started with.
    unsafe {
        let args = &*args;
        if args.N != 1 || *args.valid == 0 {
            return;
        }
        let cx = &*(args.context as *const Context);
        let rayhit = &mut *(args.rayhit as *mut sys::RTCRayHit);
        let prim = cx.users[args.primID as usize];
        if let Some(hit) = cx.geometry.intersect_prim(prim, &cx.ray, &cx.shear, rayhit.ray.tfar) {
            rayhit.ray.tfar = hit.t;
            rayhit.hit.geomID = args.geomID;
            rayhit.hit.primID = args.primID;
            rayhit.hit.u = 0.0;
            rayhit.hit.v = 0.0;
            rayhit.hit.instID = [INVALID; 1];
            cx.hit.set(Some(hit));
        }
    }
}

unsafe extern "C" fn user_occluded(args: *const sys::RTCOccludedFunctionNArguments) {
    // SAFETY: as in `user_intersect`, with an `RTCRay`.
    unsafe {
        let args = &*args;
        if args.N != 1 || *args.valid == 0 {
            return;
        }
        let cx = &*(args.context as *const Context);
        let ray = &mut *(args.ray as *mut sys::RTCRay);
        let prim = cx.users[args.primID as usize];
        if cx.geometry.intersect_prim(prim, &cx.ray, &cx.shear, ray.tfar).is_some() {
            ray.tfar = f32::NEG_INFINITY;
        }
    }
}

/// Keeps a native triangle hit only where Tempera's watertight test also hits that triangle
/// (both queries): the hits Embree reports are then the ones the default BVH can report.
unsafe extern "C" fn triangle_filter(args: *const sys::RTCFilterFunctionNArguments) {
    // SAFETY: single-ray queries (N = 1: an `RTCRay` and an `RTCHit`) started with a `Context`.
    unsafe {
        let args = &*args;
        if args.N != 1 || *args.valid == 0 {
            return;
        }
        let cx = &*(args.context as *const Context);
        let hit = &*(args.hit as *const sys::RTCHit);
        let prim = cx.triangles[hit.primID as usize];
        // Tempera's distance and barycentrics for the triangle, kept for `intersect`.
        match cx.geometry.intersect_prim(prim, &cx.ray, &cx.shear, f32::INFINITY) {
            Some(tempera_hit) => cx.hit.set(Some(tempera_hit)),
            None => *args.valid = 0,
        }
    }
}

impl EmbreeAccel {
    /// Builds Embree's scene over `geometry` (whose primitive order it leaves as it is).
    pub fn build(geometry: &Geometry) -> Result<Self, String> {
        let mut triangles = Vec::new();
        let mut users = Vec::new();
        for i in 0..geometry.prims.len() as u32 {
            if geometry.triangle(i).is_some() && !geometry.has_alpha(i) {
                triangles.push(i);
            } else {
                users.push(i);
            }
        }
        // SAFETY: the calls follow the Embree 3 API; every buffer Embree allocates is filled to
        // its declared size before the commit, and the bounds callback's user data outlives it.
        unsafe {
            let device = sys::rtcNewDevice(std::ptr::null());
            if device.is_null() {
                return Err("Embree could not create a device".into());
            }
            let scene = sys::rtcNewScene(device);
            sys::rtcSetSceneBuildQuality(scene, sys::RTCBuildQuality::HIGH);
            // Watertight traversal and triangle tests (no cracks between triangles).
            sys::rtcSetSceneFlags(scene, sys::RTCSceneFlags::ROBUST);
            let mut accel = Self { device, scene, triangles, users, user_geometry: INVALID };
            if !accel.triangles.is_empty() {
                let g = sys::rtcNewGeometry(device, sys::RTCGeometryType::TRIANGLE);
                let n = accel.triangles.len();
                let vertices =
                    sys::rtcSetNewGeometryBuffer(g, sys::RTCBufferType::VERTEX, 0, sys::RTCFormat::FLOAT3, 12, 3 * n)
                        as *mut [f32; 3];
                let indices =
                    sys::rtcSetNewGeometryBuffer(g, sys::RTCBufferType::INDEX, 0, sys::RTCFormat::UINT3, 12, n)
                        as *mut [u32; 3];
                if vertices.is_null() || indices.is_null() {
                    sys::rtcReleaseGeometry(g);
                    return Err("Embree could not allocate the triangle buffers".into());
                }
                let vertices = std::slice::from_raw_parts_mut(vertices, 3 * n);
                let indices = std::slice::from_raw_parts_mut(indices, n);
                for (t, &prim) in accel.triangles.iter().enumerate() {
                    let tri = geometry.triangle(prim).expect("a triangle");
                    for (k, p) in tri.iter().enumerate() {
                        vertices[3 * t + k] = [p.x, p.y, p.z];
                    }
                    let first = 3 * t as u32;
                    indices[t] = [first, first + 1, first + 2];
                }
                sys::rtcSetGeometryIntersectFilterFunction(g, Some(triangle_filter));
                sys::rtcSetGeometryOccludedFilterFunction(g, Some(triangle_filter));
                sys::rtcCommitGeometry(g);
                sys::rtcAttachGeometry(scene, g);
                sys::rtcReleaseGeometry(g);
            }
            let data: (&Geometry, &[u32]) = (geometry, &accel.users);
            if !accel.users.is_empty() {
                let g = sys::rtcNewGeometry(device, sys::RTCGeometryType::USER);
                sys::rtcSetGeometryUserPrimitiveCount(g, accel.users.len() as c_uint);
                // The bounds callback reads the geometry's user data (only during the commit
                // below; the queries find the geometry in their context instead).
                let data = &data as *const _ as *mut c_void;
                sys::rtcSetGeometryUserData(g, data);
                sys::rtcSetGeometryBoundsFunction(g, Some(user_bounds), data);
                sys::rtcSetGeometryIntersectFunction(g, Some(user_intersect));
                sys::rtcSetGeometryOccludedFunction(g, Some(user_occluded));
                sys::rtcCommitGeometry(g);
                accel.user_geometry = sys::rtcAttachGeometry(scene, g);
                sys::rtcReleaseGeometry(g);
            }
            sys::rtcCommitScene(scene);
            if accel.user_geometry != INVALID {
                sys::rtcSetGeometryUserData(sys::rtcGetGeometry(scene, accel.user_geometry), std::ptr::null_mut());
            }
            let error = sys::rtcGetDeviceError(device);
            if error != sys::RTCError::NONE {
                return Err(format!("Embree could not build the scene ({error:?})"));
            }
            Ok(accel)
        }
    }
}

impl Drop for EmbreeAccel {
    fn drop(&mut self) {
        // SAFETY: the handles were made by `build` and are released once.
        unsafe {
            sys::rtcReleaseScene(self.scene);
            sys::rtcReleaseDevice(self.device);
        }
    }
}

impl Accel for EmbreeAccel {
    fn intersect(&self, geometry: &Geometry, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        let mut cx = Context::new(geometry, self, ray);
        let mut rayhit = sys::RTCRayHit {
            ray: rtc_ray(ray, t_max),
            hit: sys::RTCHit {
                Ng_x: 0.0,
                Ng_y: 0.0,
                Ng_z: 0.0,
                u: 0.0,
                v: 0.0,
                primID: INVALID,
                geomID: INVALID,
                instID: [INVALID; 1],
            },
        };
        // SAFETY: the context starts with the `RTCIntersectContext` Embree expects and lives
        // through the query.
        unsafe { sys::rtcIntersect1(self.scene, &mut cx.base, &mut rayhit) };
        // Every hit Embree commits went through `hit` (the user geometry's intersection or the
        // triangles' filter); the last one committed is the nearest.
        if rayhit.hit.geomID == INVALID { None } else { cx.hit.get() }
    }

    fn occluded(&self, geometry: &Geometry, ray: &Ray, t_max: f32) -> bool {
        let mut cx = Context::new(geometry, self, ray);
        let mut r = rtc_ray(ray, t_max);
        // SAFETY: as in `intersect`.
        unsafe { sys::rtcOccluded1(self.scene, &mut cx.base, &mut r) };
        r.tfar == f32::NEG_INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::BruteForce;
    use crate::geometry::{Disk, Instance, Prototype, Shape, Sphere, TriangleMesh};
    use crate::math::rng::Pcg32;
    use crate::math::{Mat4, Vec3};

    fn soup(rng: &mut Pcg32, count: u32, size: f32) -> TriangleMesh {
        let mut r3 = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE;
        let (mut positions, mut indices) = (Vec::new(), Vec::new());
        for t in 0..count {
            let c = r3();
            positions.extend([c, c + r3() * size, c + r3() * size]);
            indices.push([3 * t, 3 * t + 1, 3 * t + 2]);
        }
        TriangleMesh::new(positions, indices, None, None).unwrap()
    }

    /// Triangles, a closed grid of shared-edge triangles, spheres, disks, a shape with a
    /// stochastic alpha of 0.5, and instances of a prototype.
    fn scene(rng: &mut Pcg32) -> Geometry {
        let mut shapes = vec![Shape::Mesh(soup(rng, 2000, 0.1)), Shape::Mesh(soup(rng, 300, 0.2))];
        // A grid of quads sharing edges and vertices: rays through them must not slip through.
        let n = 20u32;
        let positions: Vec<Vec3> = (0..=n)
            .flat_map(|i| {
                (0..=n).map(move |j| Vec3::new(i as f32 / n as f32 * 2.0 - 1.0, j as f32 / n as f32 * 2.0 - 1.0, 0.3))
            })
            .collect();
        let mut indices = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let v = |a: u32, b: u32| a * (n + 1) + b;
                indices.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
                indices.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
            }
        }
        shapes.push(Shape::Mesh(TriangleMesh::new(positions, indices, None, None).unwrap()));
        for _ in 0..20 {
            let c = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE;
            shapes.push(Shape::Sphere(Sphere { center: c, radius: 0.05, reverse_orientation: false }));
            let d = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - Vec3::splat(0.5);
            shapes.push(Shape::Disk(Disk::new(c + Vec3::splat(0.1), d.normalize(), 0.08)));
        }
        let mut geometry = Geometry::new(shapes);
        geometry.set_alpha(1, 0.5.into());
        let prototype = Prototype::new(Geometry::new(vec![Shape::Mesh(soup(rng, 200, 0.3))]), vec![0]);
        let instances = (0..4)
            .map(|k| {
                let m =
                    Mat4::from_translation(Vec3::new(0.3 * k as f32, -0.2, 0.1)) * Mat4::from_scale(Vec3::splat(0.4));
                Instance::new(0, m).unwrap()
            })
            .collect();
        geometry.add_instances(vec![prototype], instances);
        geometry
    }

    /// The accelerator agreement test: Embree finds the brute-force nearest hit (primitive,
    /// distance and barycentrics) and the same occlusion for every ray.
    #[test]
    fn embree_agrees_with_brute_force() {
        let mut rng = Pcg32::new(7, 0);
        let geometry = scene(&mut rng);
        let embree = EmbreeAccel::build(&geometry).unwrap();
        let (mut hits, mut users) = (0, 0);
        for i in 0..20_000 {
            let o = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 3.0 - Vec3::splat(1.5);
            let d = crate::math::warp::uniform_sphere(crate::math::Vec2::new(rng.next_f32(), rng.next_f32()));
            let ray = Ray::new(o, d);
            let t_max = if i % 3 == 0 { 0.7 } else { f32::INFINITY };
            let a = embree.intersect(&geometry, &ray, t_max);
            let b = BruteForce.intersect(&geometry, &ray, t_max);
            match (a, b) {
                (Some(a), Some(b)) => {
                    hits += 1;
                    users += usize::from(geometry.triangle(b.prim).is_none() || geometry.has_alpha(b.prim));
                    assert_eq!(a.t, b.t, "ray {i}: distance");
                    assert!(a.prim == b.prim && a.b == b.b && a.inner == b.inner, "ray {i}: {a:?} vs {b:?}");
                }
                (None, None) => {}
                _ => panic!("Embree and brute force disagree on ray {i}: {a:?} vs {b:?}"),
            }
            assert_eq!(embree.occluded(&geometry, &ray, t_max), b.is_some(), "ray {i}: occlusion");
        }
        assert!(hits > 4000 && users > 300, "too few hits ({hits}, {users} on user primitives)");
    }

    #[test]
    fn an_empty_scene_never_hits() {
        let g = Geometry::default();
        let embree = EmbreeAccel::build(&g).unwrap();
        let ray = Ray::new(Vec3::ZERO, Vec3::Z);
        assert!(embree.intersect(&g, &ray, f32::INFINITY).is_none());
        assert!(!embree.occluded(&g, &ray, f32::INFINITY));
    }
}
