//! Mitsuba emitters outside shapes: `point`, `spot`, `directional`, `constant`, `envmap`
//! (latitude–longitude with Mitsuba's y-up orientation) and `sunsky`.

use super::props::Props;
use super::{Ctx, Loader, sky};
use crate::LoadError;
use roxmltree::Node;
use std::sync::Arc;
use tempera::light::{DistantLight, EnvironmentMap, InfiniteLight, Light, PointLight, SpotLight};
use tempera::math::{Mat3, Mat4, Rgb, Vec3};
use tempera_image::ColorEncoding;

/// Maps Tempera's environment frame (+z up, φ from +x towards +y) to Mitsuba's (+y up,
/// u = atan2(x, −z)/2π): local (x, y, z) ↦ Mitsuba (y, z, −x)… as columns.
fn mitsuba_envmap_frame() -> Mat3 {
    Mat3::from_cols(Vec3::new(0.0, 0.0, -1.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0))
}

impl Loader {
    pub(super) fn emitter(&mut self, ctx: &Ctx, n: Node) -> Result<(), LoadError> {
        let props = Props::new(ctx, n);
        let ty = props.ty(ctx)?;
        let to_world = props.transform(ctx, "toWorld")?.unwrap_or(Mat4::IDENTITY);
        props.float(ctx, "samplingWeight", 1.0)?;
        let scale = props.float(ctx, "scale", 1.0)? as f32;
        let lights: Vec<Light> = match ty.as_str() {
            "point" => {
                let position = props.vec3(ctx, "position")?.unwrap_or_else(|| to_world.transform_point3(Vec3::ZERO));
                let intensity = props.color(ctx, "intensity", false)?.unwrap_or(Rgb::ONE) * scale;
                vec![Light::Point(PointLight { position, intensity })]
            }
            "spot" => {
                self.warn_once("spot-falloff", Some(&props.loc), "spot lights use pbrt's smoothstep falloff between beamWidth and cutoffAngle, not Mitsuba's linear one")?;
                let intensity = props.color(ctx, "intensity", false)?.unwrap_or(Rgb::ONE) * scale;
                let cutoff = props.float(ctx, "cutoffAngle", 20.0)? as f32;
                let beam = props.float(ctx, "beamWidth", f64::from(cutoff) * 0.75)? as f32;
                let from = to_world.transform_point3(Vec3::ZERO);
                let to = to_world.transform_point3(Vec3::Z);
                vec![Light::Spot(SpotLight::new(from, to, intensity, cutoff, (cutoff - beam).max(0.0)))]
            }
            "directional" => {
                let dir = props.vec3(ctx, "direction")?.unwrap_or_else(|| to_world.transform_vector3(Vec3::Z));
                let to_light = (-dir)
                    .try_normalize()
                    .ok_or_else(|| ctx.err(&props.loc, "directional light with a zero direction"))?;
                let irradiance = props.color(ctx, "irradiance", false)?.unwrap_or(Rgb::ONE) * scale;
                vec![Light::Distant(DistantLight { to_light, radiance: irradiance })]
            }
            "constant" => {
                let radiance = props.color(ctx, "radiance", false)?.unwrap_or(Rgb::ONE) * scale;
                vec![Light::Infinite(InfiniteLight::uniform(radiance))]
            }
            "envmap" => {
                let file =
                    props.string(ctx, "filename")?.ok_or_else(|| ctx.err(&props.loc, "envmap needs \"filename\""))?;
                let gamma = props.float(ctx, "gamma", 0.0)?;
                let encoding = if gamma > 0.0 { ColorEncoding::Gamma(gamma as f32) } else { ColorEncoding::Srgb };
                let image = self.image(ctx, &file, encoding, &props.loc)?;
                let rotation = tempera::math::Mat3::from_mat4(to_world) * mitsuba_envmap_frame();
                self.ignore(ctx, &props, &["cache"], "a loading hint of Mitsuba's");
                vec![Light::Infinite(InfiniteLight::image(image, EnvironmentMap::LatLong, rotation, Rgb::splat(scale)))]
            }
            "sunsky" | "sky" | "sun" => self.sunsky(ctx, &props, &ty, &to_world)?,
            "area" => return Err(ctx.err(&props.loc, "an area emitter must be nested in a <shape>")),
            other => return Err(ctx.err(&props.loc, format!("emitter \"{other}\" is not supported"))),
        };
        self.report_unused(ctx, &props, &format!("emitter \"{ty}\""))?;
        *self.cx.info.lights.entry(ty).or_default() += lights.len();
        for l in lights {
            self.cx.builder.add_light(l);
        }
        Ok(())
    }

    fn sunsky(&mut self, ctx: &Ctx, props: &Props, ty: &str, to_world: &Mat4) -> Result<Vec<Light>, LoadError> {
        self.warn_once(
            "sunsky",
            Some(&props.loc),
            "sunsky is approximated by the Preetham sky in RGB and a directional sun (see the loader's documentation)",
        )?;
        let turbidity = props.float(ctx, "turbidity", 3.0)? as f32;
        if !(1.0..=30.0).contains(&turbidity) {
            return Err(ctx.err(&props.loc, format!("turbidity {turbidity} is outside [1, 30]")));
        }
        // The sun in the emitter's frame: `sunDirection` is given in world space.
        let sun = match props.vec3(ctx, "sunDirection")? {
            Some(d) => {
                let local = to_world.inverse().transform_vector3(d);
                local.try_normalize().ok_or_else(|| ctx.err(&props.loc, "zero sunDirection"))?
            }
            None => {
                let time = sky::SunTime {
                    latitude: props.float(ctx, "latitude", 35.6894)?,
                    longitude: props.float(ctx, "longitude", 139.6917)?,
                    timezone: props.float(ctx, "timezone", 9.0)?,
                    year: props.int(ctx, "year", 2010)?,
                    month: props.int(ctx, "month", 7)?,
                    day: props.int(ctx, "day", 10)?,
                    hour: props.float(ctx, "hour", 15.0)?,
                    minute: props.float(ctx, "minute", 0.0)?,
                    second: props.float(ctx, "second", 0.0)?,
                };
                if !(1..=12).contains(&time.month) || !(1..=31).contains(&time.day) {
                    return Err(ctx.err(&props.loc, "month or day out of range"));
                }
                sky::sun_direction(&time)
            }
        };
        let sky_scale = props.float(ctx, "skyScale", 1.0)? as f32;
        let sun_scale = props.float(ctx, "sunScale", 1.0)? as f32;
        let model = ["sunRadiusScale", "stretch", "albedo", "resolution", "extend"];
        self.ignore(ctx, props, &model, "the sky and sun are approximated (see the warning)");
        let mut out = Vec::new();
        if ty != "sun" {
            let image = Arc::new(sky::sky_image(turbidity, sun, 512, 256));
            let up_y = Mat3::from_cols(Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0));
            let rotation = Mat3::from_mat4(*to_world) * up_y;
            out.push(Light::Infinite(InfiniteLight::image(
                image,
                EnvironmentMap::LatLong,
                rotation,
                Rgb::splat(sky_scale),
            )));
        }
        if ty != "sky" && sun.y > 0.0 {
            let to_light = to_world.transform_vector3(sun).normalize();
            out.push(Light::Distant(DistantLight { to_light, radiance: sky::sun_color() * sun_scale }));
        }
        Ok(out)
    }
}
