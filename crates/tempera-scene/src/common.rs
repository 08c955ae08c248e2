//! Geometry helpers shared by the loaders: analytic spheres and disks where the transform
//! allows (a similarity), and parametric grid meshes for shapes built from triangles.

use tempera::geometry::{Disk, MeshError, Shape, Sphere, TriangleMesh};
use tempera::math::{Mat4, Vec2, Vec3};

/// For a similarity transform (rotation, uniform scale, translation, possibly mirrored), its
/// scale factor; `None` for shears and non-uniform scales.
pub fn uniform_scale(m: &Mat4) -> Option<f32> {
    let c = [m.x_axis.truncate(), m.y_axis.truncate(), m.z_axis.truncate()];
    let s = c[0].length();
    let ok = s > 0.0
        && c.iter().all(|v| (v.length() - s).abs() <= 1e-4 * s)
        && c[0].dot(c[1]).abs() <= 1e-4 * s * s
        && c[0].dot(c[2]).abs() <= 1e-4 * s * s
        && c[1].dot(c[2]).abs() <= 1e-4 * s * s
        && m.row(3) == tempera::math::Vec4::W;
    ok.then_some(s)
}

/// An analytic sphere of `radius` around `center` (object space) placed by `to_world`, when
/// `to_world` is a similarity; `None` otherwise (the caller tessellates). `reverse`: the file
/// flips the orientation (a mirroring transform flips it again).
pub fn analytic_sphere(to_world: &Mat4, center: Vec3, radius: f32, reverse: bool) -> Option<Shape> {
    let k = uniform_scale(to_world)?;
    let flips = to_world.determinant() < 0.0;
    let center = to_world.transform_point3(center);
    Some(Shape::Sphere(Sphere { center, radius: radius * k, reverse_orientation: reverse ^ flips }))
}

/// An analytic disk of `radius` around `center` facing +z (object space) placed by
/// `to_world`, when `to_world` is a similarity; `None` otherwise. `reverse` as for
/// [`analytic_sphere`].
pub fn analytic_disk(to_world: &Mat4, center: Vec3, radius: f32, reverse: bool) -> Option<Shape> {
    let k = uniform_scale(to_world)?;
    let flips = to_world.determinant() < 0.0;
    let normal = to_world.inverse().transpose().transform_vector3(Vec3::Z);
    let mut disk = Disk::new(to_world.transform_point3(center), normal, radius * k);
    disk.reverse_orientation = reverse ^ flips;
    Some(Shape::Disk(disk))
}

/// A grid mesh over `(u, v) ∈ [0,1]²` mapped through `f` to a position and normal; an error
/// when a parameter made a position non-finite.
pub fn grid(nu: u32, nv: u32, f: impl Fn(f32, f32) -> (Vec3, Vec3)) -> Result<TriangleMesh, MeshError> {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    for j in 0..=nv {
        for i in 0..=nu {
            let (u, v) = (i as f32 / nu as f32, j as f32 / nv as f32);
            let (p, n) = f(u, v);
            positions.push(p);
            normals.push(n);
            uvs.push(Vec2::new(u, v));
        }
    }
    let mut indices = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            let a = j * (nu + 1) + i;
            let b = a + nu + 1;
            indices.push([a, a + 1, b + 1]);
            indices.push([a, b + 1, b]);
        }
    }
    TriangleMesh::new(positions, indices, Some(normals), Some(uvs))
}
