//! Tempera core: geometry, acceleration, textures, BSDFs, materials, lights, camera, samplers,
//! film and the light-transport integrators. The core knows no scene format and no command
//! line; loaders build scenes through [`scene::SceneBuilder`].

pub mod accel;
pub mod bidir;
pub mod bsdf;
pub mod geometry;
pub mod math;
pub mod mcmc;
pub mod pages;
pub mod texture;

pub mod camera;
pub mod cluster;
pub mod film;
pub mod integrator;
pub mod light;
pub mod material;
pub mod medium;
pub mod sampler;
pub mod scene;
pub mod scenes;
#[cfg(test)]
pub(crate) mod testing;
