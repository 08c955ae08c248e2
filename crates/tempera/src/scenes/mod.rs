//! Scenes built in code with the builder API: the embedded default scene that `tempera render`
//! shows without arguments, and small analytic scenes for tests and benchmarks.

mod cornell;
mod default;

pub use cornell::{cornell_box, furnace};
pub use default::default_scene;

use crate::geometry::{Shape, TriangleMesh};
use crate::math::Vec3;

/// A quad `a, b, c, d` (counter-clockwise seen from the side its normal points to) as two
/// triangles.
pub fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> Shape {
    let mesh =
        TriangleMesh::new(vec![a, b, c, d], vec![[0, 1, 2], [0, 2, 3]], None, None).expect("four vertices, in range");
    Shape::Mesh(mesh)
}

/// A quad centred at `center` with unit normal `normal`, extending `half_u` along `u` (which
/// must be perpendicular to `normal`) and `half_v` along `normal × u`.
pub fn oriented_quad(center: Vec3, normal: Vec3, u: Vec3, half_u: f32, half_v: f32) -> Shape {
    let n = normal.normalize();
    let u = u.normalize() * half_u;
    let v = n.cross(u.normalize()) * half_v;
    quad(center - u - v, center + u - v, center + u + v, center - u + v)
}
