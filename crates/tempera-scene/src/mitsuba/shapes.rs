//! Mitsuba shapes: `obj` (via `tobj`), `ply`, `serialized`, `rectangle`, `cube`, `sphere`,
//! `disk`, `cylinder`, and `shapegroup` + `instance` (shared geometry). Spheres and disks stay
//! analytic under similarity transforms. OBJ texture coordinates follow Mitsuba's default
//! `flipTexCoords`; PLY and serialized ones are flipped to Tempera's bottom-up `v`.

use super::props::Props;
use super::{Ctx, Loader};
use crate::LoadError;
use crate::common::{analytic_disk, analytic_sphere, grid};
use roxmltree::Node;
use tempera::geometry::{Shape, TriangleMesh};
use tempera::math::frame::Frame;
use tempera::math::{Mat4, Rgb, Vec2, Vec3};
use tempera::scene::{AreaEmission, PrototypeShape};
use tempera::texture::Texture;

const SEGMENTS: u32 = 96;

fn mesh(
    positions: Vec<Vec3>,
    indices: Vec<[u32; 3]>,
    normals: Option<Vec<Vec3>>,
    uvs: Option<Vec<Vec2>>,
) -> TriangleMesh {
    TriangleMesh::new(positions, indices, normals, uvs).expect("built-in meshes are valid")
}

/// Mitsuba's `rectangle`: [-1, 1]² in the z = 0 plane, facing +z.
fn rectangle() -> TriangleMesh {
    let p = vec![
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    let uv = vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)];
    mesh(p, vec![[0, 1, 2], [0, 2, 3]], None, Some(uv))
}

/// Mitsuba's `cube`: [-1, 1]³ with outward faces.
fn cube() -> TriangleMesh {
    let (mut p, mut uv, mut idx) = (Vec::new(), Vec::new(), Vec::new());
    for n in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
        let f = Frame::from_z(n);
        let base = p.len() as u32;
        for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            p.push(n + f.s * a + f.t * b);
            uv.push(Vec2::new(0.5 * (a + 1.0), 0.5 * (b + 1.0)));
        }
        idx.push([base, base + 1, base + 2]);
        idx.push([base, base + 2, base + 3]);
    }
    mesh(p, idx, None, Some(uv))
}

fn flip_v(uvs: Option<Vec<Vec2>>) -> Option<Vec<Vec2>> {
    uvs.map(|v| v.into_iter().map(|t| Vec2::new(t.x, 1.0 - t.y)).collect())
}

impl Loader {
    fn obj(&mut self, ctx: &Ctx, props: &Props, file: &str) -> Result<TriangleMesh, LoadError> {
        let path = ctx.resolve(file);
        let bytes =
            std::fs::read(&path).map_err(|e| ctx.err(&props.loc, format!("cannot read {}: {e}", path.display())))?;
        let m = crate::obj::parse(&bytes).map_err(|e| ctx.err(&props.loc, format!("{}: {e}", path.display())))?;
        let flip = props.bool(ctx, "flipTexCoords", true)?;
        let uvs = m.uvs.map(|uv| uv.into_iter().map(|t| Vec2::new(t.x, if flip { t.y } else { 1.0 - t.y })).collect());
        TriangleMesh::new(m.positions, m.indices, m.normals, uvs)
            .map_err(|e| ctx.err(&props.loc, format!("{}: {e}", path.display())))
    }

    fn file_mesh(&mut self, ctx: &Ctx, props: &Props, ty: &str) -> Result<TriangleMesh, LoadError> {
        let file =
            props.string(ctx, "filename")?.ok_or_else(|| ctx.err(&props.loc, format!("{ty} needs \"filename\"")))?;
        let mut m = match ty {
            "obj" => self.obj(ctx, props, &file)?,
            _ => {
                let path = ctx.resolve(&file);
                let bytes = std::fs::read(&path)
                    .map_err(|e| ctx.err(&props.loc, format!("cannot read {}: {e}", path.display())))?;
                let fail = |e: String| ctx.err(&props.loc, format!("{}: {e}", path.display()));
                let (p, idx, n, uv) = if ty == "ply" {
                    let m = crate::ply::parse(&bytes).map_err(fail)?;
                    (m.positions, m.indices, m.normals, m.uvs)
                } else {
                    let index = props.int(ctx, "shapeIndex", 0)?;
                    let m = crate::serialized::parse(&bytes, index.max(0) as usize).map_err(fail)?;
                    (m.positions, m.indices, m.normals, m.uvs)
                };
                TriangleMesh::new(p, idx, n, flip_v(uv))
                    .map_err(|e| ctx.err(&props.loc, format!("{}: {e}", path.display())))?
            }
        };
        if props.bool(ctx, "faceNormals", false)? {
            m.normals = None;
        }
        if props.named_value_present("maxSmoothAngle") {
            self.warn_once("maxSmoothAngle", Some(&props.loc), "maxSmoothAngle is ignored")?;
        }
        Ok(m)
    }

    /// The core shape for a plugin, in world space.
    fn geometry(
        &mut self,
        ctx: &Ctx,
        props: &Props,
        ty: &str,
        to_world: Mat4,
        flip: bool,
    ) -> Result<Option<Shape>, LoadError> {
        let mut m = match ty {
            "obj" | "ply" | "serialized" => self.file_mesh(ctx, props, ty)?,
            "rectangle" => rectangle(),
            "cube" => cube(),
            "sphere" => {
                let center = props.vec3(ctx, "center")?.unwrap_or(Vec3::ZERO);
                let radius = props.float(ctx, "radius", 1.0)? as f32;
                if !radius.is_finite() || radius <= 0.0 {
                    return Err(ctx.err(&props.loc, "sphere radius must be positive and finite"));
                }
                if let Some(sphere) = analytic_sphere(&to_world, center, radius, flip) {
                    return Ok(Some(sphere));
                }
                grid(SEGMENTS, SEGMENTS / 2, |u, v| {
                    let (phi, theta) = (u * std::f32::consts::TAU, v * std::f32::consts::PI);
                    let n = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
                    (center + n * radius, n)
                })
                .map_err(|e| ctx.err(&props.loc, format!("{ty}: {e}")))?
            }
            "disk" => {
                if let Some(disk) = analytic_disk(&to_world, Vec3::ZERO, 1.0, flip) {
                    return Ok(Some(disk));
                }
                grid(SEGMENTS, 4, |u, v| {
                    let (phi, r) = (u * std::f32::consts::TAU, 1.0 - v);
                    (Vec3::new(r * phi.cos(), r * phi.sin(), 0.0), Vec3::Z)
                })
                .map_err(|e| ctx.err(&props.loc, format!("{ty}: {e}")))?
            }
            "cylinder" => {
                let p0 = props.vec3(ctx, "p0")?.unwrap_or(Vec3::ZERO);
                let p1 = props.vec3(ctx, "p1")?.unwrap_or(Vec3::Z);
                let r = props.float(ctx, "radius", 1.0)? as f32;
                let axis = p1 - p0;
                let f =
                    Frame::from_z(axis.try_normalize().ok_or_else(|| ctx.err(&props.loc, "cylinder with p0 = p1"))?);
                grid(SEGMENTS, 1, |u, v| {
                    let phi = u * std::f32::consts::TAU;
                    let n = f.s * phi.cos() + f.t * phi.sin();
                    (p0 + axis * v + n * r, n)
                })
                .map_err(|e| ctx.err(&props.loc, format!("{ty}: {e}")))?
            }
            "hair" | "heightfield" => {
                let unused = props.unused();
                let names: Vec<&str> = unused.iter().filter_map(|n| n.attribute("name")).collect();
                self.ignore(ctx, props, &names, "the unsupported shape is skipped");
                self.warn(Some(&props.loc), format!("shape \"{ty}\" is not supported and is skipped"))?;
                return Ok(None);
            }
            other => return Err(ctx.err(&props.loc, format!("unknown shape plugin \"{other}\""))),
        };
        if flip {
            m.reverse_orientation = true;
            if let Some(n) = &mut m.normals {
                n.iter_mut().for_each(|v| *v = -*v);
            }
        }
        m.transform(&to_world);
        Ok(Some(Shape::Mesh(m)))
    }

    /// Loads a `<shape>`; inside a `shapegroup`, shapes go to `group` instead of the scene.
    pub(super) fn shape(
        &mut self,
        ctx: &Ctx,
        n: Node,
        group: Option<&mut Vec<PrototypeShape>>,
    ) -> Result<(), LoadError> {
        let props = Props::new(ctx, n);
        let ty = props.ty(ctx)?;
        match ty.as_str() {
            "shapegroup" => return self.shape_group(ctx, &props, group.is_some()),
            "instance" => return self.instance(ctx, &props),
            _ => {}
        }
        let to_world = props.transform(ctx, "toWorld")?.unwrap_or(Mat4::IDENTITY);
        let flip = props.bool(ctx, "flipNormals", false)?;
        let shape = self.geometry(ctx, &props, &ty, to_world, flip)?;
        let media = self.shape_media(ctx, &props)?;
        let bsdf_ref =
            props.objects("ref").into_iter().find(|r| !matches!(r.attribute("name"), Some("interior" | "exterior")));
        let bsdf_node = props.object("bsdf").or(bsdf_ref);
        let mut desc = match bsdf_node {
            Some(b) => self.bsdf(ctx, b)?,
            // Mitsuba makes a medium boundary without a BSDF index-matched.
            None if media.is_some() => super::bsdfs::BsdfDesc {
                material: Some(tempera::material::Material::Interface),
                one_sided: false,
                displacement: None,
                opacity: None,
                id: None,
            },
            None => super::bsdfs::BsdfDesc {
                material: Some(tempera::material::Material::diffuse(Rgb::splat(0.5))),
                one_sided: true,
                displacement: None,
                opacity: None,
                id: None,
            },
        };
        let emission = match props.object("emitter") {
            Some(e) => Some(self.area_emitter(ctx, e)?),
            None => None,
        };
        // A null BSDF hides the surface; an emitter on it still needs a (black) surface.
        if desc.material.is_none() && emission.is_some() {
            desc.material = Some(tempera::material::Material::diffuse(Rgb::ZERO));
        }
        let alpha = desc.opacity.clone().map(|o| Texture::Scale(Box::new((o, 1.0.into()))));
        self.report_unused(ctx, &props, &format!("shape \"{ty}\""))?;
        let (Some(shape), Some(material)) = (shape, self.register(&mut desc)) else { return Ok(()) };
        // Shapes referring to the same named BSDF share one material.
        if let Some(b) = bsdf_node.filter(|b| b.tag_name().name() == "ref").and_then(|b| b.attribute("id")) {
            self.bsdfs.insert(b.to_owned(), desc);
        }
        let count = |s: &Shape| if let Shape::Mesh(m) = s { m.indices.len() } else { 0 };
        self.cx.info.shapes += 1;
        self.cx.info.triangles += count(&shape);
        match group {
            Some(list) => {
                if emission.is_some() {
                    self.warn_once(
                        "group-emitter",
                        Some(&props.loc),
                        "area emitters inside shape groups are not supported; their emission is dropped",
                    )?;
                }
                list.push((shape, material, alpha));
            }
            None => {
                if emission.is_some() {
                    *self.cx.info.lights.entry("area".to_owned()).or_default() += 1;
                }
                self.cx.builder.add_shape_with_alpha(shape, material, emission, alpha);
                if let Some(interface) = media {
                    self.cx.builder.set_shape_medium(self.cx.builder.shape_count() - 1, interface);
                }
            }
        }
        Ok(())
    }

    fn shape_group(&mut self, ctx: &Ctx, props: &Props, nested: bool) -> Result<(), LoadError> {
        if nested {
            return Err(ctx.err(&props.loc, "shape groups cannot be nested"));
        }
        let id = props.node.attribute("id").ok_or_else(|| ctx.err(&props.loc, "shapegroup needs an \"id\""))?;
        let mut shapes = Vec::new();
        for child in props.objects("shape") {
            self.shape(ctx, child, Some(&mut shapes))?;
        }
        let prototype = (!shapes.is_empty()).then(|| self.cx.builder.add_prototype(shapes));
        self.groups.insert(id.to_owned(), prototype);
        self.report_unused(ctx, props, "shapegroup")
    }

    fn instance(&mut self, ctx: &Ctx, props: &Props) -> Result<(), LoadError> {
        let r = props.object("ref").ok_or_else(|| ctx.err(&props.loc, "instance needs a <ref> to a shapegroup"))?;
        let id = r.attribute("id").unwrap_or("");
        let prototype =
            *self.groups.get(id).ok_or_else(|| ctx.err(&ctx.loc(r), format!("unknown shapegroup \"{id}\"")))?;
        let to_world = props.transform(ctx, "toWorld")?.unwrap_or(Mat4::IDENTITY);
        if !to_world.is_finite() || to_world.determinant().abs() < 1e-20 {
            return Err(ctx.err(&props.loc, "instance with a singular transformation"));
        }
        self.cx.info.instances += 1;
        if let Some(p) = prototype {
            self.cx.builder.add_instance(p, to_world);
        }
        self.report_unused(ctx, props, "instance")
    }

    /// An area emitter nested in a shape.
    fn area_emitter(&mut self, ctx: &Ctx, n: Node) -> Result<AreaEmission, LoadError> {
        let props = Props::new(ctx, n);
        let ty = props.ty(ctx)?;
        if ty != "area" {
            return Err(ctx.err(&props.loc, format!("emitter \"{ty}\" cannot be attached to a shape (only \"area\")")));
        }
        let radiance = self.color_or_texture(ctx, &props, "radiance", Some(Rgb::ONE))?.expect("default");
        let scale = props.float(ctx, "scale", 1.0)? as f32;
        props.float(ctx, "samplingWeight", 1.0)?;
        self.report_unused(ctx, &props, "emitter \"area\"")?;
        Ok(AreaEmission { radiance, scale, two_sided: false })
    }
}
