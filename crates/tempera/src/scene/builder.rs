//! The scene-building API: loaders and built-in scenes add shapes, materials, lights and a
//! camera; [`SceneBuilder::build`] validates them, builds the accelerator and the light tables.

use super::{NO_LIGHT, Scene};
use crate::accel::{AccelKind, SceneAccel};
use crate::camera::{Camera, CameraDesc};
use crate::film::FilmDesc;
use crate::geometry::{Geometry, Instance, Prototype, Shape};
use crate::light::{AreaLight, Light, LightSampler};
use crate::material::Material;
use crate::math::Mat4;
use crate::medium::{Medium, MediumInterface};
use crate::texture::Texture;

/// Handle of a material added to a builder.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MaterialId(pub u32);

/// Handle of a prototype (instanced geometry) added to a builder.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PrototypeId(pub u32);

/// A shape of a prototype: geometry, material and optional alpha texture.
pub type PrototypeShape = (Shape, MaterialId, Option<Texture>);

/// Emission of an area light attached to a shape.
#[derive(Clone, Debug)]
pub struct AreaEmission {
    pub radiance: Texture,
    pub scale: f32,
    pub two_sided: bool,
}

/// Render settings a scene suggests (pbrt's `Sampler`/`Integrator` directives).
#[derive(Clone, Debug, PartialEq)]
pub struct RenderDefaults {
    pub spp: u32,
    pub max_depth: u32,
    /// The integrator the scene asks for, when Tempera has it (the loader's information keeps
    /// the name as written).
    pub integrator: Option<crate::integrator::IntegratorKind>,
    /// The output file the scene asks for.
    pub output: Option<std::path::PathBuf>,
    /// SPPM's photons per iteration, when the scene says.
    pub photons: Option<u64>,
    /// SPPM's initial search radius, when the scene says.
    pub radius: Option<f32>,
    /// The Markov-chain integrators' parameters, where the scene gives them.
    pub chain: ChainDefaults,
}

impl RenderDefaults {
    /// The samples (for the Markov-chain integrators, mutations) per pixel of a render by
    /// `kind` that names no budget: the scene's mutations per pixel where it gives them and
    /// `kind` is a Markov-chain integrator, else its samples per pixel.
    pub fn per_pixel(&self, kind: crate::integrator::IntegratorKind) -> u32 {
        match self.chain.mpp {
            Some(mpp) if kind.is_chain() => mpp,
            _ => self.spp,
        }
    }
}

/// The Markov-chain integrators' parameters a scene may give (pbrt-v4's `mlt` integrator):
/// each `None` leaves Tempera's default.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ChainDefaults {
    /// Mutations per pixel, the budget when none is given.
    pub mpp: Option<u32>,
    /// Bootstrap samples per path depth.
    pub bootstrap: Option<usize>,
    /// Chains per path depth.
    pub chains: Option<usize>,
    /// The probability of a large step.
    pub large_step: Option<f32>,
    /// The standard deviation of a small step.
    pub sigma: Option<f32>,
}

impl Default for RenderDefaults {
    fn default() -> Self {
        Self {
            spp: 16,
            max_depth: 5,
            integrator: None,
            output: None,
            photons: None,
            radius: None,
            chain: ChainDefaults::default(),
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SceneError {
    #[error("the scene has no camera")]
    NoCamera,
    #[error("shape {shape} uses material {material}, but only {count} materials exist")]
    UnknownMaterial { shape: usize, material: u32, count: usize },
    #[error("film resolution {0}x{1} is empty")]
    EmptyFilm(u32, u32),
    #[error("invalid shape {shape}: {reason}")]
    InvalidShape { shape: usize, reason: String },
    #[error("invalid instance: {0}")]
    InvalidInstance(String),
    #[error("invalid medium: {0}")]
    InvalidMedium(String),
    #[error("accelerator: {0}")]
    Accel(String),
}

#[derive(Debug, Default)]
pub struct SceneBuilder {
    accel: AccelKind,
    shapes: Vec<Shape>,
    shape_material: Vec<u32>,
    shape_emission: Vec<Option<AreaEmission>>,
    materials: Vec<Material>,
    displacement: Vec<Option<Texture>>,
    one_sided: Vec<bool>,
    shape_alpha: Vec<Option<Texture>>,
    shape_medium: Vec<Option<MediumInterface>>,
    media: Vec<Medium>,
    camera_medium: Option<u32>,
    /// Per non-area light, the medium it sits in.
    light_media: Vec<Option<u32>>,
    prototypes: Vec<Vec<PrototypeShape>>,
    instances: Vec<(u32, Mat4)>,
    lights: Vec<Light>,
    camera: Option<CameraDesc>,
    film: FilmDesc,
    defaults: RenderDefaults,
}

impl SceneBuilder {
    pub fn new() -> Self {
        Self::default()
    }

    /// The accelerator [`Self::build`] makes (default: Tempera's BVH).
    pub fn set_accel(&mut self, kind: AccelKind) {
        self.accel = kind;
    }

    pub fn add_material(&mut self, material: Material) -> MaterialId {
        self.materials.push(material);
        self.displacement.push(None);
        self.one_sided.push(false);
        MaterialId(self.materials.len() as u32 - 1)
    }

    /// Bump-maps a material with a float displacement texture.
    pub fn set_displacement(&mut self, material: MaterialId, displacement: Texture) {
        if let Some(d) = self.displacement.get_mut(material.0 as usize) {
            *d = Some(displacement);
        }
    }

    /// Makes a material black when seen from behind the geometric normal (Mitsuba BSDFs that
    /// are not wrapped in `twosided`).
    pub fn set_one_sided(&mut self, material: MaterialId) {
        if let Some(flag) = self.one_sided.get_mut(material.0 as usize) {
            *flag = true;
        }
    }

    /// Adds a shape with a material and, optionally, area emission.
    pub fn add_shape(&mut self, shape: Shape, material: MaterialId, emission: Option<AreaEmission>) {
        self.add_shape_with_alpha(shape, material, emission, None);
    }

    /// Adds a shape whose float texture `alpha` cuts it out where it is below one
    /// (stochastically between zero and one).
    pub fn add_shape_with_alpha(
        &mut self,
        shape: Shape,
        material: MaterialId,
        emission: Option<AreaEmission>,
        alpha: Option<Texture>,
    ) {
        self.shapes.push(shape);
        self.shape_material.push(material.0);
        self.shape_emission.push(emission);
        self.shape_alpha.push(alpha);
        self.shape_medium.push(None);
    }

    /// The shapes added so far.
    pub fn shape_count(&self) -> usize {
        self.shapes.len()
    }

    /// Adds a homogeneous medium; returns its index for [`MediumInterface`]s.
    pub fn add_medium(&mut self, medium: Medium) -> u32 {
        self.media.push(medium);
        self.media.len() as u32 - 1
    }

    /// Makes shape `shape` (an index below [`Self::shape_count`]) the boundary between the
    /// media of `interface`.
    pub fn set_shape_medium(&mut self, shape: usize, interface: MediumInterface) {
        if let Some(slot) = self.shape_medium.get_mut(shape) {
            *slot = Some(interface);
        }
    }

    /// The medium the camera sits in.
    pub fn set_camera_medium(&mut self, medium: Option<u32>) {
        self.camera_medium = medium;
    }

    /// Adds geometry to be placed by instances; it is stored once however often it is placed.
    pub fn add_prototype(&mut self, shapes: Vec<PrototypeShape>) -> PrototypeId {
        self.prototypes.push(shapes);
        PrototypeId(self.prototypes.len() as u32 - 1)
    }

    /// Places a prototype with the transformation `to_world`.
    pub fn add_instance(&mut self, prototype: PrototypeId, to_world: Mat4) {
        self.instances.push((prototype.0, to_world));
    }

    /// Adds a non-area light (point, spot, distant, infinite) in vacuum.
    pub fn add_light(&mut self, light: Light) {
        self.add_light_in(light, None);
    }

    /// Adds a non-area light that sits in `medium` (its emitted light starts there).
    pub fn add_light_in(&mut self, light: Light, medium: Option<u32>) {
        self.lights.push(light);
        self.light_media.push(medium);
    }

    pub fn set_camera(&mut self, camera: CameraDesc) {
        self.camera = Some(camera);
    }

    pub fn set_film(&mut self, film: FilmDesc) {
        self.film = film;
    }

    pub fn set_defaults(&mut self, defaults: RenderDefaults) {
        self.defaults = defaults;
    }

    fn validate(&self) -> Result<(), SceneError> {
        if self.film.width == 0 || self.film.height == 0 {
            return Err(SceneError::EmptyFilm(self.film.width, self.film.height));
        }
        for (shape, &material) in self.shape_material.iter().enumerate() {
            if material as usize >= self.materials.len() {
                return Err(SceneError::UnknownMaterial { shape, material, count: self.materials.len() });
            }
        }
        for (shape, (_, material, _)) in self.prototypes.iter().flatten().enumerate() {
            if material.0 as usize >= self.materials.len() {
                return Err(SceneError::UnknownMaterial { shape, material: material.0, count: self.materials.len() });
            }
        }
        for &(p, m) in &self.instances {
            if p as usize >= self.prototypes.len() {
                return Err(SceneError::InvalidInstance(format!("prototype {p} does not exist")));
            }
            if !m.is_finite() || m.determinant().abs() < 1e-20 {
                return Err(SceneError::InvalidInstance("the transformation is not invertible".into()));
            }
        }
        for m in &self.materials {
            if let Material::Mix(mix) = m
                && let Some(&bad) = mix.materials.iter().find(|&&i| i as usize >= self.materials.len())
            {
                return Err(SceneError::UnknownMaterial {
                    shape: usize::MAX,
                    material: bad,
                    count: self.materials.len(),
                });
            }
        }
        let known = |m: Option<u32>| m.is_none_or(|m| (m as usize) < self.media.len());
        let interfaces = self.shape_medium.iter().flatten();
        if !known(self.camera_medium)
            || interfaces.clone().any(|i| !known(i.inside) || !known(i.outside))
            || !self.light_media.iter().all(|&m| known(m))
        {
            return Err(SceneError::InvalidMedium("a medium interface names a medium that does not exist".into()));
        }
        for m in &self.media {
            let coefficients = [m.sigma_a, m.sigma_s];
            if coefficients.iter().any(|c| !c.is_finite() || c.min_element() < 0.0) || m.g.is_nan() || m.g.abs() >= 1.0
            {
                return Err(SceneError::InvalidMedium(format!(
                    "coefficients must be finite and non-negative and |g| below 1: {m:?}"
                )));
            }
        }
        for (i, shape) in self.shapes.iter().enumerate() {
            let bad = match shape {
                Shape::Sphere(s) => !(s.radius > 0.0 && s.radius.is_finite() && s.center.is_finite()),
                Shape::Disk(d) => !(d.radius > 0.0 && d.radius.is_finite() && d.center.is_finite()),
                Shape::Mesh(m) => m.positions.iter().any(|p| !p.is_finite()),
            };
            if bad {
                return Err(SceneError::InvalidShape { shape: i, reason: "non-finite or non-positive size".into() });
            }
        }
        Ok(())
    }

    pub fn build(self) -> Result<Scene, SceneError> {
        self.validate()?;
        let camera_desc = self.camera.ok_or(SceneError::NoCamera)?;
        let mut geometry = Geometry::new(self.shapes);
        for (shape, alpha) in self.shape_alpha.into_iter().enumerate() {
            if let Some(alpha) = alpha {
                geometry.set_alpha(shape, alpha);
            }
        }
        let prototypes = self.prototypes.into_iter().map(build_prototype).collect();
        let instances = self
            .instances
            .iter()
            .map(|&(p, m)| {
                Instance::new(p, m)
                    .ok_or_else(|| SceneError::InvalidInstance("the transformation is not invertible".into()))
            })
            .collect::<Result<Vec<_>, _>>()?;
        geometry.add_instances(prototypes, instances);
        let accel = SceneAccel::build(self.accel, &mut geometry).map_err(SceneError::Accel)?;
        let bounds = geometry.world_bounds();

        let mut lights = self.lights;
        let mut prim_light = vec![NO_LIGHT; geometry.prims.len()];
        // Area lights in the scene's order (shape, then triangle), not the accelerator's
        // primitive order: light sampling, and so the image, does not depend on the tree.
        let mut emitters: Vec<(usize, &AreaEmission)> = (0..geometry.prims.len())
            .filter_map(|prim| {
                let emission = self.shape_emission.get(geometry.prims[prim].shape as usize);
                emission.and_then(Option::as_ref).map(|e| (prim, e))
            })
            .collect();
        emitters.sort_unstable_by_key(|&(prim, _)| (geometry.prims[prim].shape, geometry.prims[prim].index));
        for (prim, e) in emitters {
            prim_light[prim] = lights.len() as u32;
            lights.push(Light::Area(AreaLight {
                prim: prim as u32,
                radiance: e.radiance.clone(),
                scale: e.scale,
                two_sided: e.two_sided,
            }));
        }
        let radius = if bounds.0.is_finite() { 0.5 * (bounds.1 - bounds.0).length() } else { 1.0 };
        let powers: Vec<f32> = lights.iter().map(|l| l.power(&geometry, radius)).collect();
        let infinite_lights =
            lights.iter().enumerate().filter(|(_, l)| l.is_infinite()).map(|(i, _)| i as u32).collect();
        Ok(Scene {
            geometry,
            accel,
            materials: self.materials,
            displacement: self.displacement,
            one_sided: self.one_sided,
            shape_material: self.shape_material,
            shape_medium: self.shape_medium,
            media: self.media,
            camera_medium: self.camera_medium,
            light_media: self.light_media,
            prim_light,
            light_sampler: LightSampler::new(&powers),
            lights,
            infinite_lights,
            camera: Camera::Perspective(camera_desc.build(self.film.width, self.film.height)),
            camera_desc,
            film: self.film,
            defaults: self.defaults,
            bounds,
        })
    }
}

fn build_prototype(shapes: Vec<PrototypeShape>) -> Prototype {
    let mut materials = Vec::with_capacity(shapes.len());
    let mut alphas = Vec::with_capacity(shapes.len());
    let mut geometry_shapes = Vec::with_capacity(shapes.len());
    for (shape, material, alpha) in shapes {
        geometry_shapes.push(shape);
        materials.push(material.0);
        alphas.push(alpha);
    }
    let mut geometry = Geometry::new(geometry_shapes);
    for (shape, alpha) in alphas.into_iter().enumerate() {
        if let Some(alpha) = alpha {
            geometry.set_alpha(shape, alpha);
        }
    }
    Prototype::new(geometry, materials)
}
