//! pbrt-v4 shapes translated into core shapes: triangle meshes (inline and PLY), bilinear
//! patches (two triangles each), spheres and disks (analytic when the transformation is a
//! similarity and the shape is whole, tessellated otherwise), and cylinders (tessellated).

use super::Loader;
use super::directives::string_arg;
use super::lexer::Lexer;
use super::params::ParamSet;
use crate::LoadError;
use crate::common::{analytic_disk, analytic_sphere, grid};
use crate::diagnostics::Loc;
use std::f32::consts::TAU;
use tempera::geometry::{MeshError, Shape, TriangleMesh};
use tempera::math::{Vec2, Vec3};

/// Segments around the axis of tessellated quadrics.
const SEGMENTS: u32 = 96;
const RINGS: u32 = 48;

fn syntax(loc: &Loc, message: impl Into<String>) -> LoadError {
    LoadError::Syntax { loc: loc.clone(), message: message.into() }
}

fn vec3s(v: Vec<Vec<f64>>) -> Vec<Vec3> {
    v.into_iter().map(|p| Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)).collect()
}

fn sphere_mesh(radius: f32, zmin: f32, zmax: f32, phi_max: f32) -> Result<TriangleMesh, MeshError> {
    let (t0, t1) = ((zmin / radius).clamp(-1.0, 1.0).acos(), (zmax / radius).clamp(-1.0, 1.0).acos());
    grid(SEGMENTS, RINGS, |u, v| {
        let (phi, theta) = (u * phi_max, t0 + (t1 - t0) * v);
        let n = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
        (n * radius, n)
    })
}

fn disk_mesh(height: f32, radius: f32, inner: f32, phi_max: f32) -> Result<TriangleMesh, MeshError> {
    grid(SEGMENTS, 4, |u, v| {
        let (phi, r) = (u * phi_max, radius + (inner - radius) * v);
        (Vec3::new(r * phi.cos(), r * phi.sin(), height), Vec3::Z)
    })
}

fn cylinder_mesh(radius: f32, zmin: f32, zmax: f32, phi_max: f32) -> Result<TriangleMesh, MeshError> {
    grid(SEGMENTS, 1, |u, v| {
        let phi = u * phi_max;
        let n = Vec3::new(phi.cos(), phi.sin(), 0.0);
        (n * radius + Vec3::Z * (zmin + (zmax - zmin) * v), n)
    })
}

impl Loader {
    fn mesh(&self, mesh: TriangleMesh) -> Shape {
        let mut mesh = mesh;
        mesh.reverse_orientation = self.state.reverse_orientation;
        mesh.transform(&self.state.ctm);
        Shape::Mesh(mesh)
    }

    fn triangle_mesh(&mut self, params: &ParamSet, at: &Loc) -> Result<Shape, LoadError> {
        let p = vec3s(params.points("P", 3)?.ok_or_else(|| syntax(at, "trianglemesh needs \"point3 P\""))?);
        let indices = match params.ints("indices")? {
            Some(i) => i,
            None if p.len() == 3 => vec![0, 1, 2],
            None => {
                return Err(syntax(
                    at,
                    "trianglemesh needs \"integer indices\" (only a single triangle may omit them)",
                ));
            }
        };
        if indices.len() % 3 != 0 || indices.iter().any(|&i| i < 0 || i > i64::from(u32::MAX)) {
            return Err(syntax(at, "\"indices\" must be non-negative and a multiple of 3"));
        }
        let tris = indices.chunks(3).map(|c| [c[0] as u32, c[1] as u32, c[2] as u32]).collect();
        let n = params.points("N", 3)?.map(vec3s);
        let uv = params
            .points("uv", 2)?
            .or(params.points("st", 2)?)
            .map(|v| v.into_iter().map(|p| Vec2::new(p[0] as f32, p[1] as f32)).collect());
        params.find("S");
        params.find("faceIndices");
        let mesh = TriangleMesh::new(p, tris, n, uv).map_err(|e| syntax(at, format!("trianglemesh: {e}")))?;
        Ok(self.mesh(mesh))
    }

    fn ply_mesh(&mut self, params: &ParamSet, at: &Loc) -> Result<Shape, LoadError> {
        let file =
            params.string("filename")?.ok_or_else(|| syntax(at, "plymesh needs \"string filename\""))?.to_owned();
        let path = self.resolve(at, &file);
        if params.find("displacement").is_some() {
            self.warn_once(
                "ply-displacement",
                Some(at),
                "plymesh displacement is not supported; meshes are used undisplaced",
            )?;
        }
        params.find("edgelength");
        let bytes = std::fs::read(&path).map_err(|e| syntax(at, format!("cannot read {}: {e}", path.display())))?;
        let ply = crate::ply::parse(&bytes).map_err(|e| syntax(at, format!("{}: {e}", path.display())))?;
        if ply.degenerate_faces > 0 {
            self.warn(
                Some(at),
                format!("{}: {} faces with fewer than 3 vertices skipped", path.display(), ply.degenerate_faces),
            )?;
        }
        let mesh = TriangleMesh::new(ply.positions, ply.indices, ply.normals, ply.uvs)
            .map_err(|e| syntax(at, format!("{}: {e}", path.display())))?;
        Ok(self.mesh(mesh))
    }

    fn bilinear_mesh(&mut self, params: &ParamSet, at: &Loc) -> Result<Shape, LoadError> {
        let p = vec3s(params.points("P", 3)?.ok_or_else(|| syntax(at, "bilinearmesh needs \"point3 P\""))?);
        let indices = match params.ints("indices")? {
            Some(i) => i,
            None if p.len() == 4 => vec![0, 1, 2, 3],
            None => return Err(syntax(at, "bilinearmesh needs \"integer indices\"")),
        };
        if indices.len() % 4 != 0 || indices.iter().any(|&i| i < 0 || i > i64::from(u32::MAX)) {
            return Err(syntax(at, "bilinearmesh \"indices\" must be non-negative and a multiple of 4"));
        }
        // Patch vertices are p00, p10, p01, p11.
        let tris = indices
            .chunks(4)
            .flat_map(|c| {
                let [a, b, c0, d] = [c[0] as u32, c[1] as u32, c[2] as u32, c[3] as u32];
                [[a, b, d], [a, d, c0]]
            })
            .collect();
        let n = params.points("N", 3)?.map(vec3s);
        let uv = params.points("uv", 2)?.map(|v| v.into_iter().map(|p| Vec2::new(p[0] as f32, p[1] as f32)).collect());
        let mesh = TriangleMesh::new(p, tris, n, uv).map_err(|e| syntax(at, format!("bilinearmesh: {e}")))?;
        Ok(self.mesh(mesh))
    }

    fn quadric(&mut self, ty: &str, params: &ParamSet, at: &Loc) -> Result<Shape, LoadError> {
        let radius = params.float("radius", 1.0)? as f32;
        if !radius.is_finite() || radius <= 0.0 {
            return Err(syntax(at, format!("{ty} radius must be positive and finite, got {radius}")));
        }
        let phi_max = (params.float("phimax", 360.0)? as f32).clamp(0.0, 360.0).to_radians();
        let ctm = self.state.ctm;
        let reverse = self.state.reverse_orientation;
        let whole = (phi_max - TAU).abs() < 1e-6;
        let mesh = match ty {
            "sphere" => {
                let zmin = (params.float("zmin", -f64::from(radius))? as f32).clamp(-radius, radius);
                let zmax = (params.float("zmax", f64::from(radius))? as f32).clamp(-radius, radius);
                if whole
                    && zmin <= -radius
                    && zmax >= radius
                    && let Some(sphere) = analytic_sphere(&ctm, Vec3::ZERO, radius, reverse)
                {
                    return Ok(sphere);
                }
                sphere_mesh(radius, zmin.min(zmax), zmin.max(zmax), phi_max)
            }
            "disk" => {
                let height = params.float("height", 0.0)? as f32;
                let inner = params.float("innerradius", 0.0)? as f32;
                if whole
                    && inner <= 0.0
                    && let Some(disk) = analytic_disk(&ctm, Vec3::new(0.0, 0.0, height), radius, reverse)
                {
                    return Ok(disk);
                }
                disk_mesh(height, radius, inner.clamp(0.0, radius), phi_max)
            }
            _ => {
                let (zmin, zmax) = (params.float("zmin", -1.0)? as f32, params.float("zmax", 1.0)? as f32);
                cylinder_mesh(radius, zmin.min(zmax), zmin.max(zmax), phi_max)
            }
        };
        Ok(self.mesh(mesh.map_err(|e| syntax(at, format!("{ty}: {e}")))?))
    }

    pub(super) fn shape_directive(&mut self, lx: &mut Lexer) -> Result<(), LoadError> {
        let (ty, at) = string_arg(lx, "shape type")?;
        let params = ParamSet::parse(lx)?;
        let shape = match ty.as_str() {
            "trianglemesh" => Some(self.triangle_mesh(&params, &at)?),
            "plymesh" => Some(self.ply_mesh(&params, &at)?),
            "bilinearmesh" => Some(self.bilinear_mesh(&params, &at)?),
            "sphere" | "disk" | "cylinder" => Some(self.quadric(&ty, &params, &at)?),
            "loopsubdiv" => {
                self.warn_once("loopsubdiv", Some(&at), "loopsubdiv is not subdivided; its control mesh is rendered")?;
                params.find("levels");
                Some(self.triangle_mesh(&params, &at)?)
            }
            _ => {
                for p in &params.params {
                    p.mark_used();
                }
                self.warn(Some(&at), format!("shape \"{ty}\" is not supported and is skipped"))?;
                None
            }
        };
        let alpha = self.float_param(&params, "alpha", 1.0)?;
        let alpha = if alpha.as_constant().is_some_and(|a| a.x >= 1.0) { None } else { Some(alpha) };
        self.report_unused(&params, &format!("Shape \"{ty}\""))?;
        if let Some(shape) = shape {
            let material = self.state.material.clone();
            let emission = self.state.area_light.clone();
            self.add_shape(shape, &material, emission, alpha, &at)?;
        }
        Ok(())
    }
}
