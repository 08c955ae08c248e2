//! Mitsuba 0.6's `homogeneous` medium (`sigmaA` and `sigmaS`, or `sigmaT` and `albedo`, times
//! `scale`; an `isotropic` or `hg` phase function) and the media of shapes (`interior`,
//! `exterior`) and of the sensor. A shape that bounds a medium but has no BSDF is an
//! index-matched boundary, as Mitsuba makes it. Named material presets (`material`) and
//! heterogeneous media are refused with a clear message.

use super::props::Props;
use super::{Ctx, Loader};
use crate::LoadError;
use roxmltree::Node;
use tempera::math::Rgb;
use tempera::medium::{Medium, MediumInterface};

impl Loader {
    /// A `<medium>` element: its index in the scene (added once per `id`).
    pub(super) fn medium(&mut self, ctx: &Ctx, n: Node) -> Result<u32, LoadError> {
        if n.tag_name().name() == "ref" {
            let id = n.attribute("id").ok_or_else(|| ctx.err(&ctx.loc(n), "<ref> needs an \"id\""))?;
            return self.media.get(id).copied().ok_or_else(|| ctx.err(&ctx.loc(n), format!("unknown medium \"{id}\"")));
        }
        let props = Props::new(ctx, n);
        let ty = props.ty(ctx)?;
        if ty != "homogeneous" {
            return Err(ctx.err(&props.loc, format!("medium \"{ty}\" is not supported (only \"homogeneous\")")));
        }
        if let Some(preset) = props.string(ctx, "material")? {
            return Err(ctx.err(
                &props.loc,
                format!("medium material preset \"{preset}\" is not supported; give sigmaA and sigmaS"),
            ));
        }
        let scale = props.float(ctx, "scale", 1.0)? as f32;
        // Without coefficients Mitsuba uses a measured preset, which Tempera does not have.
        let pair = |a: &str, b: &str| -> Result<Option<(Rgb, Rgb)>, LoadError> {
            Ok(match (props.color(ctx, a, false)?, props.color(ctx, b, false)?) {
                (Some(x), Some(y)) => Some((x, y)),
                (None, None) => None,
                _ => return Err(ctx.err(&props.loc, format!("\"{a}\" and \"{b}\" go together"))),
            })
        };
        let (sigma_a, sigma_s) = match (pair("sigmaA", "sigmaS")?, pair("sigmaT", "albedo")?) {
            (Some(ab), None) => ab,
            (None, Some((t, albedo))) => (t * (Rgb::ONE - albedo), t * albedo),
            _ => {
                return Err(ctx.err(
                    &props.loc,
                    "a homogeneous medium needs sigmaA and sigmaS, or sigmaT and albedo (presets are not supported)",
                ));
            }
        };
        let g = match props.object("phase") {
            None => 0.0,
            Some(p) => {
                let phase = Props::new(ctx, p);
                let g = match phase.ty(ctx)?.as_str() {
                    "isotropic" => 0.0,
                    "hg" => phase.float(ctx, "g", 0.8)? as f32,
                    other => return Err(ctx.err(&phase.loc, format!("phase function \"{other}\" is not supported"))),
                };
                self.report_unused(ctx, &phase, "phase")?;
                g
            }
        };
        let medium = Medium { sigma_a: sigma_a * scale, sigma_s: sigma_s * scale, g };
        let valid = |c: Rgb| c.is_finite() && c.min_element() >= 0.0;
        if !valid(medium.sigma_a) || !valid(medium.sigma_s) || g.is_nan() || g.abs() >= 1.0 {
            return Err(ctx.err(&props.loc, "medium coefficients must be non-negative and |g| below 1"));
        }
        self.report_unused(ctx, &props, "medium \"homogeneous\"")?;
        *self.cx.info.materials.entry("medium homogeneous".to_owned()).or_default() += 1;
        let index = self.cx.builder.add_medium(medium);
        if let Some(id) = n.attribute("id") {
            self.media.insert(id.to_owned(), index);
        }
        Ok(index)
    }

    /// The media a shape's `interior` and `exterior` name, if any.
    pub(super) fn shape_media(&mut self, ctx: &Ctx, props: &Props) -> Result<Option<MediumInterface>, LoadError> {
        let mut side = |name: &str| -> Result<Option<u32>, LoadError> {
            match props.named_object(name) {
                Some(n) if matches!(n.tag_name().name(), "medium" | "ref") => {
                    props.take(&[name]);
                    self.medium(ctx, n).map(Some)
                }
                _ => Ok(None),
            }
        };
        let (inside, outside) = (side("interior")?, side("exterior")?);
        Ok((inside.is_some() || outside.is_some()).then_some(MediumInterface { inside, outside }))
    }
}
