//! Indexed triangle meshes with optional per-vertex normals and texture coordinates; surface
//! data at a hit follows pbrt-v4 §6.5.3 (uv parametrisation, `dpdu`, shading normals).

use super::SurfacePoint;
use crate::math::{Mat4, Vec2, Vec3};

/// An error found while validating mesh data.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MeshError {
    #[error("vertex index {index} out of range (mesh has {count} vertices)")]
    IndexOutOfRange { index: u32, count: usize },
    #[error("{what} has {got} entries but the mesh has {want} vertices")]
    AttributeCount { what: &'static str, got: usize, want: usize },
    #[error("non-finite vertex position")]
    NonFinite,
}

/// A triangle mesh in world space.
#[derive(Clone, Debug, Default)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    pub indices: Vec<[u32; 3]>,
    /// Flip the geometric normal (pbrt's `ReverseOrientation`, Mitsuba's `flipNormals`).
    pub reverse_orientation: bool,
}

impl TriangleMesh {
    /// Builds and validates a mesh.
    pub fn new(
        positions: Vec<Vec3>,
        indices: Vec<[u32; 3]>,
        normals: Option<Vec<Vec3>>,
        uvs: Option<Vec<Vec2>>,
    ) -> Result<Self, MeshError> {
        let count = positions.len();
        if let Some(&index) = indices.iter().flatten().find(|&&i| i as usize >= count) {
            return Err(MeshError::IndexOutOfRange { index, count });
        }
        if positions.iter().any(|p| !p.is_finite()) {
            return Err(MeshError::NonFinite);
        }
        if let Some(n) = &normals
            && n.len() != count
        {
            return Err(MeshError::AttributeCount { what: "normals", got: n.len(), want: count });
        }
        if let Some(uv) = &uvs
            && uv.len() != count
        {
            return Err(MeshError::AttributeCount { what: "uvs", got: uv.len(), want: count });
        }
        Ok(Self { positions, normals, uvs, indices, reverse_orientation: false })
    }

    /// Transforms the mesh in place (normals by the inverse transpose). A transform that swaps
    /// handedness flips the geometric normal, as in pbrt.
    pub fn transform(&mut self, m: &Mat4) {
        for p in &mut self.positions {
            *p = m.transform_point3(*p);
        }
        let normal_m = m.inverse().transpose();
        if let Some(ns) = &mut self.normals {
            for n in ns.iter_mut() {
                *n = normal_m.transform_vector3(*n).normalize_or_zero();
            }
        }
        if m.determinant() < 0.0 {
            self.reverse_orientation = !self.reverse_orientation;
        }
    }

    #[inline]
    pub fn vertices(&self, tri: u32) -> [Vec3; 3] {
        let [a, b, c] = self.indices[tri as usize];
        [self.positions[a as usize], self.positions[b as usize], self.positions[c as usize]]
    }

    pub fn area(&self, tri: u32) -> f32 {
        let [p0, p1, p2] = self.vertices(tri);
        0.5 * (p1 - p0).cross(p2 - p0).length()
    }

    fn uvs_of(&self, tri: u32) -> [Vec2; 3] {
        match &self.uvs {
            Some(uv) => self.indices[tri as usize].map(|i| uv[i as usize]),
            None => [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0)],
        }
    }

    /// Surface data at barycentrics `b` of triangle `tri`.
    pub fn surface(&self, tri: u32, b: Vec3) -> SurfacePoint {
        let [p0, p1, p2] = self.vertices(tri);
        let uv = self.uvs_of(tri);
        let p = b.x * p0 + b.y * p1 + b.z * p2;
        let uv_hit = b.x * uv[0] + b.y * uv[1] + b.z * uv[2];
        let mut ng = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        if ng == Vec3::ZERO {
            ng = Vec3::Z;
        }
        let (duv02, duv12) = (uv[0] - uv[2], uv[1] - uv[2]);
        let (dp02, dp12) = (p0 - p2, p1 - p2);
        let det = duv02.x * duv12.y - duv02.y * duv12.x;
        let (mut dpdu, mut dpdv) = if det.abs() < 1e-12 {
            (Vec3::ZERO, Vec3::ZERO)
        } else {
            ((duv12.y * dp02 - duv02.y * dp12) / det, (duv02.x * dp12 - duv12.x * dp02) / det)
        };
        if !dpdu.is_finite() || !dpdv.is_finite() {
            (dpdu, dpdv) = (Vec3::ZERO, Vec3::ZERO);
        }
        let ns = match &self.normals {
            Some(n) => {
                let [a, bb, c] = self.indices[tri as usize];
                let ns = b.x * n[a as usize] + b.y * n[bb as usize] + b.z * n[c as usize];
                let ns = ns.normalize_or_zero();
                if ns == Vec3::ZERO { None } else { Some(ns) }
            }
            None => None,
        };
        let (ng, ns) = match ns {
            Some(ns) => (if ng.dot(ns) < 0.0 { -ng } else { ng }, ns),
            None => {
                let ng = if self.reverse_orientation { -ng } else { ng };
                (ng, ng)
            }
        };
        SurfacePoint { p, ng, ns, uv: uv_hit, dpdu, dpdv }
    }

    /// Texture coordinates at barycentrics `b` of triangle `tri`.
    pub fn uv_at(&self, tri: u32, b: Vec3) -> Vec2 {
        let uv = self.uvs_of(tri);
        b.x * uv[0] + b.y * uv[1] + b.z * uv[2]
    }

    /// Uniform area sample on triangle `tri`: the surface point and the area density.
    pub fn sample(&self, tri: u32, u: Vec2) -> (SurfacePoint, f32) {
        let b = crate::math::warp::uniform_triangle(u);
        (self.surface(tri, b), 1.0 / self.area(tri))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> TriangleMesh {
        let p = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(2.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let uv = vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)];
        TriangleMesh::new(p, vec![[0, 1, 2], [0, 2, 3]], None, Some(uv)).unwrap()
    }

    #[test]
    fn surface_interpolates_uvs_and_orients_normals() {
        let mut m = quad();
        let s = m.surface(0, Vec3::new(0.25, 0.5, 0.25));
        assert!((s.p - Vec3::new(1.5, 0.25, 0.0)).length() < 1e-6);
        assert!((s.uv - Vec2::new(0.75, 0.25)).length() < 1e-6);
        assert_eq!(s.ng, Vec3::Z, "counter-clockwise faces +z");
        assert!((s.dpdu - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-5, "dp/du follows the uv layout");
        assert!((s.dpdv - Vec3::new(0.0, 1.0, 0.0)).length() < 1e-5, "dp/dv follows the uv layout");
        m.reverse_orientation = true;
        assert_eq!(m.surface(0, Vec3::splat(1.0 / 3.0)).ng, -Vec3::Z);
        // Shading normals win over the winding: the geometric normal is flipped towards them.
        let mut n = quad();
        n.normals = Some(vec![Vec3::new(0.0, 0.6, -0.8); 4]);
        let s = n.surface(1, Vec3::splat(1.0 / 3.0));
        assert_eq!(s.ng, -Vec3::Z);
        assert!((s.ns - Vec3::new(0.0, 0.6, -0.8)).length() < 1e-6);
    }

    #[test]
    fn mirroring_transforms_flip_orientation_and_area_sampling_is_uniform_density() {
        let mut m = quad();
        m.transform(&Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)));
        assert_eq!(m.surface(0, Vec3::splat(1.0 / 3.0)).ng, Vec3::Z, "the mirrored winding is compensated");
        assert!((m.area(0) - 1.0).abs() < 1e-6);
        let (s, pdf) = m.sample(1, Vec2::new(0.3, 0.8));
        assert_eq!(pdf, 1.0);
        assert!(s.p.x <= 0.0 && s.p.x >= -2.0 && s.p.y >= 0.0 && s.p.y <= 1.0);
    }

    #[test]
    fn invalid_meshes_are_rejected() {
        let p = vec![Vec3::ZERO; 3];
        assert_eq!(
            TriangleMesh::new(p.clone(), vec![[0, 1, 3]], None, None).unwrap_err(),
            MeshError::IndexOutOfRange { index: 3, count: 3 }
        );
        assert!(TriangleMesh::new(p.clone(), vec![[0, 1, 2]], Some(vec![Vec3::Z; 2]), None).is_err());
        assert!(TriangleMesh::new(vec![Vec3::splat(f32::NAN); 3], vec![[0, 1, 2]], None, None).is_err());
    }
}
