//! The pbrt-v4 graphics state: current transformation, orientation, material, area light, and
//! the named objects (materials, textures, coordinate systems, object instances) the directives
//! refer to (pbrt-v4 file format reference, "Attributes" and "Transformations").

use std::collections::HashMap;
use tempera::geometry::Shape;
use tempera::math::{Mat4, Vec3};
use tempera::scene::{AreaEmission, MaterialId, PrototypeId};
use tempera::texture::Texture;

/// The material a shape receives.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialSlot {
    /// The scene's default (diffuse, reflectance 0.5), created on first use.
    Default,
    Id(MaterialId),
    /// pbrt's `interface`: the surface only bounds a medium and is invisible.
    Interface,
}

#[derive(Clone, Debug)]
pub struct GraphicsState {
    pub ctm: Mat4,
    pub reverse_orientation: bool,
    pub material: MaterialSlot,
    pub area_light: Option<AreaEmission>,
    /// The current `MediumInterface`: inside and outside medium names ("" is vacuum).
    pub media: (String, String),
}

impl Default for GraphicsState {
    fn default() -> Self {
        Self {
            ctm: Mat4::IDENTITY,
            reverse_orientation: false,
            material: MaterialSlot::Default,
            area_light: None,
            media: (String::new(), String::new()),
        }
    }
}

/// A shape recorded inside `ObjectBegin`/`ObjectEnd`, placed by `ObjectInstance`.
#[derive(Clone, Debug)]
pub struct ObjectShape {
    pub shape: Shape,
    pub material: MaterialSlot,
    pub emission: Option<AreaEmission>,
    pub alpha: Option<Texture>,
}

#[derive(Default)]
pub struct Named {
    pub materials: HashMap<String, MaterialSlot>,
    pub float_textures: HashMap<String, Texture>,
    pub spectrum_textures: HashMap<String, Texture>,
    pub coord_systems: HashMap<String, Mat4>,
    /// Named media, by their index in the scene.
    pub media: HashMap<String, u32>,
    /// The medium the camera was declared in (the outside of the `MediumInterface` then
    /// current), resolved when the file ends.
    pub camera_medium: Option<(String, crate::diagnostics::Loc)>,
    /// The interface material shared by surfaces that only bound media.
    pub interface_material: Option<MaterialId>,
    /// Object definitions; `None` for objects with nothing visible in them.
    pub objects: HashMap<String, Option<PrototypeId>>,
}

/// pbrt's `Rotate`: `angle` degrees about `axis`.
pub fn rotation(angle_degrees: f32, axis: Vec3) -> Option<Mat4> {
    let axis = axis.try_normalize()?;
    Some(Mat4::from_axis_angle(axis, angle_degrees.to_radians()))
}

/// pbrt's `LookAt` matrix (world to camera).
pub fn look_at(eye: Vec3, target: Vec3, up: Vec3) -> Option<Mat4> {
    let dir = (target - eye).try_normalize()?;
    let right = up.try_normalize()?.cross(dir).try_normalize()?;
    let new_up = dir.cross(right);
    let camera_to_world = Mat4::from_cols(right.extend(0.0), new_up.extend(0.0), dir.extend(0.0), eye.extend(1.0));
    Some(camera_to_world.inverse())
}
