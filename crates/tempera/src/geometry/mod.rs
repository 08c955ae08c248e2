//! Geometry: rays, shapes (triangle meshes, analytic spheres and disks) and the flat table of
//! primitives the accelerator indexes.

pub mod disk;
pub mod instance;
pub mod mesh;
pub mod packet;
pub mod ray;
pub mod sphere;
pub mod triangle;

pub use disk::Disk;
pub use instance::{Instance, Prototype};
pub use mesh::{MeshError, TriangleMesh};
pub use ray::{Ray, spawn_ray, spawn_ray_to};
pub use sphere::{ShapeSample, Sphere};
pub use triangle::{RayShear, intersect_triangle};

use crate::math::{Vec2, Vec3};
use crate::pages::PageVec;
use crate::texture::Texture;

/// Geometric data of a surface point.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    pub p: Vec3,
    /// Geometric normal (orientation as the shape defines it).
    pub ng: Vec3,
    /// Shading normal (interpolated vertex normals, or `ng`).
    pub ns: Vec3,
    pub uv: Vec2,
    pub dpdu: Vec3,
    pub dpdv: Vec3,
}

/// A shape as stored in the scene.
#[derive(Clone, Debug)]
pub enum Shape {
    Mesh(TriangleMesh),
    Sphere(Sphere),
    Disk(Disk),
}

impl Shape {
    /// Number of primitives the shape contributes to the accelerator.
    pub fn primitive_count(&self) -> usize {
        match self {
            Shape::Mesh(m) => m.indices.len(),
            Shape::Sphere(_) | Shape::Disk(_) => 1,
        }
    }
}

/// One intersectable primitive: a triangle of a mesh, or a whole analytic shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PrimRef {
    pub shape: u32,
    pub index: u32,
}

/// The parameters at which a primitive was hit (barycentrics for triangles).
#[derive(Clone, Copy, Debug)]
pub struct PrimHit {
    pub prim: u32,
    pub t: f32,
    pub b: Vec3,
    /// For an instance, the primitive hit inside its prototype.
    pub inner: u32,
}

/// `PrimRef::shape` of a primitive that is an object instance (`index` is the instance).
pub const INSTANCE: u32 = u32::MAX;

/// A triangle primitive's vertices as the intersection test reads them, or a mark that the
/// primitive is not a triangle (an analytic shape or an instance).
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct CachedTriangle {
    p: [[f32; 3]; 3],
    /// 1 for a triangle, 0 otherwise.
    triangle: u32,
}

impl CachedTriangle {
    #[inline(always)]
    fn get(&self) -> Option<[Vec3; 3]> {
        (self.triangle != 0).then(|| self.p.map(Vec3::from_array))
    }
}

/// All shapes of a scene and the primitive table over them. For an accelerator that tests
/// triangles through [`Geometry::intersect_prim`] (Embree's filter), triangle vertices can be
/// cached per primitive, in primitive order, so that each test reads one contiguous record;
/// the BVH keeps its own copy in its packets and needs no cache.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    pub shapes: Vec<Shape>,
    pub prims: Vec<PrimRef>,
    /// Vertices of triangle primitives, aligned with `prims`, once
    /// [`Geometry::ensure_triangle_cache`] has built them; empty otherwise.
    triangles: PageVec<CachedTriangle>,
    /// Alpha (cut-out) texture per shape; empty when no shape has one.
    alpha: Vec<Option<Texture>>,
    pub prototypes: Vec<Prototype>,
    pub instances: Vec<Instance>,
}

impl Geometry {
    pub fn new(shapes: Vec<Shape>) -> Self {
        let prims = shapes
            .iter()
            .enumerate()
            .flat_map(|(s, shape)| {
                (0..shape.primitive_count() as u32).map(move |index| PrimRef { shape: s as u32, index })
            })
            .collect();
        Self { shapes, prims, ..Self::default() }
    }

    fn cache_triangles(&mut self) {
        use rayon::prelude::*;
        let mut triangles = PageVec::zeroed(self.prims.len());
        triangles.par_iter_mut().zip(self.prims.par_iter()).for_each(|(t, r)| {
            if let Some(Shape::Mesh(m)) = self.shapes.get(r.shape as usize) {
                *t = CachedTriangle { p: m.vertices(r.index).map(|v| v.to_array()), triangle: 1 };
            }
        });
        self.triangles = triangles;
    }

    /// Builds the triangle cache unless it is there (for an accelerator that reads it).
    pub fn ensure_triangle_cache(&mut self) {
        if self.triangles.len() != self.prims.len() {
            self.cache_triangles();
        }
    }

    /// Adds instances of prototypes as primitives.
    pub fn add_instances(&mut self, prototypes: Vec<Prototype>, instances: Vec<Instance>) {
        let first = self.instances.len() as u32;
        self.prims.extend((0..instances.len() as u32).map(|k| PrimRef { shape: INSTANCE, index: first + k }));
        self.prototypes.extend(prototypes);
        self.instances.extend(instances);
        self.triangles = PageVec::default();
    }

    /// The instance primitive `i` places, if it is one.
    #[inline]
    pub fn instance(&self, i: u32) -> Option<(&Instance, &Prototype)> {
        let r = self.prims[i as usize];
        (r.shape == INSTANCE).then(|| {
            let inst = &self.instances[r.index as usize];
            (inst, &self.prototypes[inst.prototype as usize])
        })
    }

    /// Axis-aligned bounds of primitive `i`.
    pub fn bounds(&self, i: usize) -> (Vec3, Vec3) {
        if let Some((inst, proto)) = self.instance(i as u32) {
            return inst.bounds(proto);
        }
        let r = self.prims[i];
        match &self.shapes[r.shape as usize] {
            Shape::Mesh(m) => {
                let [a, b, c] = m.vertices(r.index);
                (a.min(b).min(c), a.max(b).max(c))
            }
            Shape::Sphere(s) => (s.center - Vec3::splat(s.radius), s.center + Vec3::splat(s.radius)),
            Shape::Disk(d) => {
                let n = d.frame.n;
                let ext = Vec3::new(
                    (1.0 - n.x * n.x).max(0.0).sqrt(),
                    (1.0 - n.y * n.y).max(0.0).sqrt(),
                    (1.0 - n.z * n.z).max(0.0).sqrt(),
                ) * d.radius;
                (d.center - ext, d.center + ext)
            }
        }
    }

    /// Gives shape `shape` an alpha texture: hits where it is 0 are ignored, where it is
    /// between 0 and 1 they are kept with that probability (decided by a hash of the ray, so
    /// every ray sees a consistent surface), as pbrt-v4 does.
    pub fn set_alpha(&mut self, shape: usize, alpha: Texture) {
        if self.alpha.is_empty() {
            self.alpha = vec![None; self.shapes.len()];
        }
        self.alpha[shape] = Some(alpha);
    }

    /// The vertices of primitive `i` when it is a triangle outside instances.
    #[inline(always)]
    pub fn triangle(&self, i: u32) -> Option<[Vec3; 3]> {
        match self.triangles.get(i as usize) {
            Some(cached) => cached.get(),
            None => self.mesh_triangle(i),
        }
    }

    /// [`Self::triangle`] without the cache, from the mesh.
    #[inline(never)]
    fn mesh_triangle(&self, i: u32) -> Option<[Vec3; 3]> {
        let r = self.prims[i as usize];
        match self.shapes.get(r.shape as usize) {
            Some(Shape::Mesh(m)) => Some(m.vertices(r.index)),
            Some(Shape::Sphere(_) | Shape::Disk(_)) | None => None,
        }
    }

    /// Whether primitive `i` belongs to a shape with an alpha (cut-out) texture.
    pub fn has_alpha(&self, i: u32) -> bool {
        !self.alpha.is_empty() && self.alpha[self.prims[i as usize].shape as usize].is_some()
    }

    /// Whether the alpha texture of primitive `i`'s shape, if it has one, keeps the hit at
    /// distance `t` with barycentrics `b`.
    pub(crate) fn alpha_keeps(&self, i: u32, ray: &Ray, t: f32, b: Vec3) -> bool {
        let r = self.prims[i as usize];
        let Some(alpha) = &self.alpha[r.shape as usize] else { return true };
        let uv = match &self.shapes[r.shape as usize] {
            Shape::Mesh(m) => m.uv_at(r.index, b),
            Shape::Sphere(s) => s.surface(ray.at(t)).uv,
            Shape::Disk(d) => d.surface(ray.at(t)).uv,
        };
        let a = alpha.eval_float(uv);
        if a >= 1.0 {
            return true;
        }
        if a.is_nan() || a <= 0.0 {
            return false;
        }
        let bits =
            |v: Vec3| (u64::from(v.x.to_bits()) << 32) ^ (u64::from(v.y.to_bits()) << 16) ^ u64::from(v.z.to_bits());
        let u = (crate::math::rng::hash(&[bits(ray.o), bits(ray.d)]) >> 40) as f32 / (1u64 << 24) as f32;
        u < a
    }

    /// Intersects primitive `i`, returning the distance and hit parameters.
    #[inline]
    pub fn intersect_prim(&self, i: u32, ray: &Ray, shear: &RayShear, t_max: f32) -> Option<PrimHit> {
        let Some(tri) = self.triangle(i) else {
            return self.intersect_other(i, ray, t_max);
        };
        let h = intersect_triangle(ray, shear, tri, t_max)?;
        self.keep(i, ray, h.t, h.b)
    }

    /// Intersects primitive `i`, which is not a triangle: an instance, a sphere or a disk.
    pub fn intersect_other(&self, i: u32, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        let r = self.prims[i as usize];
        if r.shape == INSTANCE {
            let (inst, proto) = self.instance(i)?;
            return inst.intersect(proto, ray, t_max).map(|h| PrimHit { prim: i, ..h });
        }
        let t = match &self.shapes[r.shape as usize] {
            Shape::Sphere(s) => s.intersect(ray, t_max),
            Shape::Disk(d) => d.intersect(ray, t_max),
            Shape::Mesh(_) => None,
        }?;
        self.keep(i, ray, t, Vec3::ZERO)
    }

    /// The hit of primitive `i` at distance `t`, unless its alpha texture drops it.
    #[inline(always)]
    fn keep(&self, i: u32, ray: &Ray, t: f32, b: Vec3) -> Option<PrimHit> {
        if !self.alpha.is_empty() && !self.alpha_keeps(i, ray, t, b) {
            return None;
        }
        Some(PrimHit { prim: i, t, b, inner: 0 })
    }

    /// Surface data at a hit found by an accelerator.
    pub fn surface(&self, ray: &Ray, hit: &PrimHit) -> SurfacePoint {
        if let Some((inst, proto)) = self.instance(hit.prim) {
            return inst.surface(proto, ray, hit);
        }
        let r = self.prims[hit.prim as usize];
        match &self.shapes[r.shape as usize] {
            Shape::Mesh(m) => m.surface(r.index, hit.b),
            Shape::Sphere(s) => s.surface(ray.at(hit.t)),
            Shape::Disk(d) => d.surface(ray.at(hit.t)),
        }
    }

    /// Surface area of primitive `i` (instances, which never emit, report zero).
    pub fn area(&self, i: u32) -> f32 {
        let r = self.prims[i as usize];
        if r.shape == INSTANCE {
            return 0.0;
        }
        match &self.shapes[r.shape as usize] {
            Shape::Mesh(m) => m.area(r.index),
            Shape::Sphere(s) => s.area(),
            Shape::Disk(d) => d.area(),
        }
    }

    /// Samples a point uniformly by area on primitive `i`; the density is per unit area.
    pub fn sample_area(&self, i: u32, u: Vec2) -> Option<ShapeSample> {
        let r = self.prims[i as usize];
        if r.shape == INSTANCE {
            return None;
        }
        Some(match &self.shapes[r.shape as usize] {
            Shape::Mesh(m) => {
                let (point, pdf) = m.sample(r.index, u);
                ShapeSample { point, pdf }
            }
            Shape::Sphere(s) => s.sample_area(u),
            Shape::Disk(d) => d.sample_area(u),
        })
    }

    /// The sample `u` with which [`Self::sample_area`] (and [`Self::sample_from`]) produce the
    /// point `p` of primitive `i`, for a triangle (its barycentrics, inverted through the
    /// triangle warp); `None` for other shapes.
    pub fn sample_area_inverse(&self, i: u32, p: Vec3) -> Option<Vec2> {
        let r = self.prims.get(i as usize)?;
        let Some(Shape::Mesh(m)) = self.shapes.get(r.shape as usize) else { return None };
        let [p0, p1, p2] = m.vertices(r.index);
        let n = (p1 - p0).cross(p2 - p0);
        let n2 = n.length_squared();
        if n2.is_nan() || n2 <= 0.0 {
            return None;
        }
        let b1 = (p - p0).cross(p2 - p0).dot(n) / n2;
        let b2 = (p1 - p0).cross(p - p0).dot(n) / n2;
        let b = Vec3::new(1.0 - b1 - b2, b1, b2);
        Some(crate::math::warp::uniform_triangle_inverse(b.max(Vec3::ZERO)))
    }

    /// Samples a point on primitive `i` as seen from `reference`; the density is per unit solid
    /// angle at `reference`.
    pub fn sample_from(&self, i: u32, reference: Vec3, u: Vec2) -> Option<ShapeSample> {
        let r = self.prims[i as usize];
        if r.shape == INSTANCE {
            return None;
        }
        let area_sample = match &self.shapes[r.shape as usize] {
            Shape::Sphere(s) => return s.sample_from(reference, u),
            Shape::Mesh(m) => {
                let (point, pdf) = m.sample(r.index, u);
                ShapeSample { point, pdf }
            }
            Shape::Disk(d) => d.sample_area(u),
        };
        let w = area_sample.point.p - reference;
        let d2 = w.length_squared();
        let cos = area_sample.point.ng.dot(w).abs() / d2.sqrt();
        if d2 == 0.0 || cos.is_nan() || cos <= 0.0 {
            return None;
        }
        Some(ShapeSample { point: area_sample.point, pdf: area_sample.pdf * d2 / cos })
    }

    /// Solid-angle density of [`Self::sample_from`] for the point `hit` on primitive `i`.
    pub fn pdf_from(&self, i: u32, reference: Vec3, hit: &SurfacePoint) -> f32 {
        let r = self.prims[i as usize];
        if r.shape == INSTANCE {
            return 0.0;
        }
        if let Shape::Sphere(s) = &self.shapes[r.shape as usize] {
            return s.pdf_from(reference, hit);
        }
        let w = hit.p - reference;
        let d2 = w.length_squared();
        let cos = hit.ng.dot(w).abs() / d2.sqrt();
        if cos.is_nan() || cos <= 0.0 {
            return 0.0;
        }
        d2 / (cos * self.area(i))
    }

    /// Bounding box of everything.
    pub fn world_bounds(&self) -> (Vec3, Vec3) {
        (0..self.prims.len()).fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), i| {
            let (a, b) = self.bounds(i);
            (lo.min(a), hi.max(b))
        })
    }

    /// Reorders the primitive table (the accelerator stores primitives in its own order). A
    /// triangle cache is dropped, not reordered: the BVH, the one caller, keeps its own copy
    /// ([`Self::ensure_triangle_cache`] rebuilds it).
    pub fn reorder(&mut self, order: &[u32]) {
        self.prims = order.iter().map(|&i| self.prims[i as usize]).collect();
        self.triangles = PageVec::default();
    }
}
