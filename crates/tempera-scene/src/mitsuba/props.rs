//! Properties of Mitsuba 0.6 plugin elements (`<float name=… value=…/>`, `<rgb …/>`,
//! `<transform …>`, nested objects and `<ref>`), read with `$name` default substitution and
//! tracked so that unused properties can be reported (Mitsuba 0.6 documentation, ch. 6).

use super::Ctx;
use crate::LoadError;
use crate::diagnostics::Loc;
use crate::spectrum;
use roxmltree::Node;
use std::cell::Cell;
use tempera::math::{Mat4, Rgb, Vec3};

/// The property children and nested objects of one plugin element.
pub(super) struct Props<'a, 'i> {
    pub node: Node<'a, 'i>,
    pub loc: Loc,
    entries: Vec<(Node<'a, 'i>, Cell<bool>)>,
}

/// Tags that are nested objects rather than values.
const OBJECTS: &[&str] =
    &["bsdf", "texture", "emitter", "sampler", "film", "rfilter", "ref", "shape", "medium", "phase", "subsurface"];

fn parse_floats(s: &str) -> Option<Vec<f64>> {
    s.split(|c: char| c == ',' || c.is_whitespace()).filter(|w| !w.is_empty()).map(|w| w.parse().ok()).collect()
}

impl<'a, 'i> Props<'a, 'i> {
    pub fn new(ctx: &Ctx, node: Node<'a, 'i>) -> Self {
        let entries = node.children().filter(Node::is_element).map(|n| (n, Cell::new(false))).collect();
        Self { node, loc: ctx.loc(node), entries }
    }

    /// The plugin's `type` attribute.
    pub fn ty(&self, ctx: &Ctx) -> Result<String, LoadError> {
        match self.node.attribute("type") {
            Some(t) => ctx.subst(t, &self.loc),
            None => Err(ctx.err(&self.loc, format!("<{}> needs a \"type\" attribute", self.node.tag_name().name()))),
        }
    }

    fn find(&self, name: &str) -> Option<Node<'a, 'i>> {
        let (n, used) = self.entries.iter().find(|(n, _)| n.attribute("name") == Some(name))?;
        used.set(true);
        Some(*n)
    }

    /// Nested objects with tag `tag` (and no `name`, or any name when `named` is true).
    pub fn objects(&self, tag: &str) -> Vec<Node<'a, 'i>> {
        self.entries
            .iter()
            .filter(|(n, _)| n.tag_name().name() == tag)
            .map(|(n, used)| {
                used.set(true);
                *n
            })
            .collect()
    }

    pub fn object(&self, tag: &str) -> Option<Node<'a, 'i>> {
        self.objects(tag).into_iter().next()
    }

    /// A nested object given by name (`<texture name="reflectance" …>` or `<ref name=… id=…>`).
    pub fn named_object(&self, name: &str) -> Option<Node<'a, 'i>> {
        self.find(name).filter(|n| OBJECTS.contains(&n.tag_name().name()))
    }

    fn value(&self, ctx: &Ctx, n: Node) -> Result<String, LoadError> {
        let loc = ctx.loc(n);
        match n.attribute("value") {
            Some(v) => ctx.subst(v, &loc),
            None => Err(ctx.err(&loc, format!("<{}> needs a \"value\" attribute", n.tag_name().name()))),
        }
    }

    fn wrong(ctx: &Ctx, n: Node, want: &str) -> LoadError {
        ctx.err(&ctx.loc(n), format!("property \"{}\" must be {want}", n.attribute("name").unwrap_or("")))
    }

    pub fn float(&self, ctx: &Ctx, name: &str, default: f64) -> Result<f64, LoadError> {
        let Some(n) = self.find(name) else { return Ok(default) };
        if !matches!(n.tag_name().name(), "float" | "integer") {
            return Err(Self::wrong(ctx, n, "a <float>"));
        }
        let v = self.value(ctx, n)?;
        match v.trim().parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(ctx.err(&ctx.loc(n), format!("expected a number, found \"{v}\""))),
        }
    }

    pub fn int(&self, ctx: &Ctx, name: &str, default: i64) -> Result<i64, LoadError> {
        let v = self.float(ctx, name, default as f64)?;
        if v.fract() != 0.0 {
            return Err(ctx.err(&self.loc, format!("property \"{name}\" must be a whole number")));
        }
        Ok(v as i64)
    }

    pub fn bool(&self, ctx: &Ctx, name: &str, default: bool) -> Result<bool, LoadError> {
        let Some(n) = self.find(name) else { return Ok(default) };
        match self.value(ctx, n)?.trim() {
            "true" => Ok(true),
            "false" => Ok(false),
            other => Err(ctx.err(&ctx.loc(n), format!("expected true or false, found \"{other}\""))),
        }
    }

    pub fn string(&self, ctx: &Ctx, name: &str) -> Result<Option<String>, LoadError> {
        let Some(n) = self.find(name) else { return Ok(None) };
        if n.tag_name().name() != "string" {
            return Err(Self::wrong(ctx, n, "a <string>"));
        }
        Ok(Some(self.value(ctx, n)?))
    }

    /// `<point>`/`<vector>`: `x y z` attributes or a `value` list.
    pub fn vec3(&self, ctx: &Ctx, name: &str) -> Result<Option<Vec3>, LoadError> {
        let Some(n) = self.find(name) else { return Ok(None) };
        let loc = ctx.loc(n);
        if let Some(v) = n.attribute("value") {
            let v = parse_floats(&ctx.subst(v, &loc)?)
                .filter(|v| v.len() == 3)
                .ok_or_else(|| ctx.err(&loc, "expected three numbers"))?;
            return Ok(Some(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)));
        }
        let c = |a: &str| -> Result<f32, LoadError> {
            match n.attribute(a) {
                None => Ok(0.0),
                Some(s) => ctx
                    .subst(s, &loc)?
                    .trim()
                    .parse::<f32>()
                    .map_err(|_| ctx.err(&loc, format!("\"{a}\" must be a number"))),
            }
        };
        Ok(Some(Vec3::new(c("x")?, c("y")?, c("z")?)))
    }

    /// A colour property (`rgb`, `srgb`, `spectrum`, `blackbody` or `float`) as linear RGB.
    /// `emission` normalises spectra to unit luminance.
    pub fn color(&self, ctx: &Ctx, name: &str, emission: bool) -> Result<Option<Rgb>, LoadError> {
        let Some(n) = self.find(name) else { return Ok(None) };
        color_of(ctx, n, emission).map(Some)
    }

    /// `<transform name=…>` composed in document order.
    pub fn transform(&self, ctx: &Ctx, name: &str) -> Result<Option<Mat4>, LoadError> {
        match self.find(name) {
            None => Ok(None),
            Some(n) if n.tag_name().name() == "transform" => transform_of(ctx, n).map(Some),
            Some(n) => Err(Self::wrong(ctx, n, "a <transform>")),
        }
    }

    /// The element tag of property `name`, without marking it read.
    pub fn tag_of(&self, name: &str) -> Option<&'a str> {
        self.entries.iter().find(|(n, _)| n.attribute("name") == Some(name)).map(|(n, _)| n.tag_name().name())
    }

    /// Marks a property as read and tells whether it exists.
    pub fn named_value_present(&self, name: &str) -> bool {
        self.find(name).is_some()
    }

    /// Marks the properties `names` as read; returns those present.
    pub fn take(&self, names: &[&str]) -> Vec<Node<'a, 'i>> {
        names.iter().filter_map(|name| self.find(name)).collect()
    }

    /// Every unused child, for warnings.
    pub fn unused(&self) -> Vec<Node<'a, 'i>> {
        self.entries.iter().filter(|(_, used)| !used.get()).map(|(n, _)| *n).collect()
    }
}

/// Linear RGB of a colour element.
pub(super) fn color_of(ctx: &Ctx, n: Node, emission: bool) -> Result<Rgb, LoadError> {
    let loc = ctx.loc(n);
    let tag = n.tag_name().name();
    if tag == "blackbody" {
        let t = n.attribute("temperature").ok_or_else(|| ctx.err(&loc, "<blackbody> needs \"temperature\""))?;
        let t = ctx.subst(t, &loc)?;
        let k: f64 = t.trim().trim_end_matches(['k', 'K']).parse().map_err(|_| ctx.err(&loc, "bad temperature"))?;
        let scale: f64 = n.attribute("scale").map(|s| s.parse().unwrap_or(1.0)).unwrap_or(1.0);
        return Ok(spectrum::blackbody(k) * scale as f32);
    }
    let raw = n.attribute("value").ok_or_else(|| ctx.err(&loc, format!("<{tag}> needs a \"value\"")))?;
    let value = ctx.subst(raw, &loc)?;
    let bad = || ctx.err(&loc, format!("cannot read colour \"{value}\""));
    let rgb = match tag {
        "rgb" | "srgb" => {
            let c = if let Some(hex) = value.trim().strip_prefix('#') {
                let v = u32::from_str_radix(hex, 16).map_err(|_| bad())?;
                let f = |s: u32| ((v >> s) & 0xff) as f32 / 255.0;
                Rgb::new(f(16), f(8), f(0))
            } else {
                let v = parse_floats(&value).ok_or_else(bad)?;
                match v.as_slice() {
                    [g] => Rgb::splat(*g as f32),
                    [r, g, b] => Rgb::new(*r as f32, *g as f32, *b as f32),
                    _ => return Err(bad()),
                }
            };
            if tag == "srgb" || value.trim().starts_with('#') {
                Rgb::new(
                    tempera_image::srgb_to_linear(c.x),
                    tempera_image::srgb_to_linear(c.y),
                    tempera_image::srgb_to_linear(c.z),
                )
            } else {
                c
            }
        }
        "float" => Rgb::splat(value.trim().parse::<f32>().map_err(|_| bad())?),
        "spectrum" => {
            if value.contains(':') {
                let mut pairs = Vec::new();
                for entry in value.split(',') {
                    let (l, v) = entry.trim().split_once(':').ok_or_else(bad)?;
                    pairs.push(l.trim().parse::<f64>().map_err(|_| bad())?);
                    pairs.push(v.trim().parse::<f64>().map_err(|_| bad())?);
                }
                if emission { spectrum::sampled_emission(&pairs) } else { spectrum::sampled_reflectance(&pairs) }
            } else {
                Rgb::splat(value.trim().parse::<f32>().map_err(|_| bad())?)
            }
        }
        _ => return Err(ctx.err(&loc, format!("<{tag}> is not a colour"))),
    };
    if !rgb.is_finite() {
        return Err(bad());
    }
    Ok(rgb)
}

/// Composes the children of a `<transform>`: each applies after the previous ones.
pub(super) fn transform_of(ctx: &Ctx, node: Node) -> Result<Mat4, LoadError> {
    let mut m = Mat4::IDENTITY;
    for c in node.children().filter(Node::is_element) {
        let loc = ctx.loc(c);
        let attr = |a: &str, default: f32| -> Result<f32, LoadError> {
            match c.attribute(a) {
                None => Ok(default),
                Some(s) => ctx
                    .subst(s, &loc)?
                    .trim()
                    .parse::<f32>()
                    .map_err(|_| ctx.err(&loc, format!("\"{a}\" must be a number"))),
            }
        };
        // A vector as `x y z` attributes (missing ones default) or a `value` list (Mitsuba's
        // later exporters write `<translate value="x, y, z"/>`).
        let xyz = |default: f32| -> Result<Vec3, LoadError> {
            if let Some(v) = c.attribute("value") {
                let v = parse_floats(&ctx.subst(v, &loc)?)
                    .filter(|v| v.len() == 3)
                    .ok_or_else(|| ctx.err(&loc, "\"value\" needs three numbers"))?;
                return Ok(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32));
            }
            Ok(Vec3::new(attr("x", default)?, attr("y", default)?, attr("z", default)?))
        };
        let vec = |a: &str| -> Result<Vec3, LoadError> {
            let s = c.attribute(a).ok_or_else(|| ctx.err(&loc, format!("<{}> needs \"{a}\"", c.tag_name().name())))?;
            let v = parse_floats(&ctx.subst(s, &loc)?)
                .filter(|v| v.len() == 3)
                .ok_or_else(|| ctx.err(&loc, format!("\"{a}\" needs three numbers")))?;
            Ok(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32))
        };
        let op = match c.tag_name().name() {
            "translate" => Mat4::from_translation(xyz(0.0)?),
            "scale" => {
                match c.attribute("value").map(|v| ctx.subst(v, &loc)).transpose()?.as_deref().and_then(parse_floats) {
                    Some(v) if v.len() == 1 => Mat4::from_scale(Vec3::splat(v[0] as f32)),
                    _ => Mat4::from_scale(xyz(1.0)?),
                }
            }
            "rotate" => {
                let axis = xyz(0.0)?;
                let axis = axis.try_normalize().ok_or_else(|| ctx.err(&loc, "rotation about a zero axis"))?;
                Mat4::from_axis_angle(axis, attr("angle", 0.0)?.to_radians())
            }
            "matrix" => {
                let s = c.attribute("value").ok_or_else(|| ctx.err(&loc, "<matrix> needs \"value\""))?;
                let v = parse_floats(&ctx.subst(s, &loc)?)
                    .ok_or_else(|| ctx.err(&loc, "<matrix> values must be numbers"))?;
                let v: Vec<f32> = v.into_iter().map(|x| x as f32).collect();
                match v.len() {
                    16 => Mat4::from_cols_slice(&v).transpose(),
                    9 => Mat4::from_mat3(tempera::math::Mat3::from_cols_slice(&v).transpose()),
                    n => return Err(ctx.err(&loc, format!("<matrix> needs 16 (or 9) values, found {n}"))),
                }
            }
            "lookat" => {
                let (origin, target) = (vec("origin")?, vec("target")?);
                let up = if c.attribute("up").is_some() { vec("up")? } else { Vec3::Y };
                let dir =
                    (target - origin).try_normalize().ok_or_else(|| ctx.err(&loc, "lookat with origin = target"))?;
                let left = up
                    .cross(dir)
                    .try_normalize()
                    .ok_or_else(|| ctx.err(&loc, "lookat with up parallel to the view"))?;
                let new_up = dir.cross(left);
                Mat4::from_cols(left.extend(0.0), new_up.extend(0.0), dir.extend(0.0), origin.extend(1.0))
            }
            other => return Err(ctx.err(&loc, format!("unknown transformation <{other}>"))),
        };
        m = op * m;
    }
    if !m.is_finite() {
        return Err(ctx.err(&ctx.loc(node), "transformation is not finite"));
    }
    Ok(m)
}
