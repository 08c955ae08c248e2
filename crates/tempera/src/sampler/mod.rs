//! Samplers: where every random number of a light-transport sample comes from. Integrators are
//! generic over [`Sampler`], so the same path code serves independent sampling and (later) the
//! primary-sample-space sampler of MCMC integrators. Numbers are requested per [`Stream`] so
//! that a sampler can keep the camera, light and connection dimensions apart.

pub mod independent;
pub mod pss;

pub use independent::IndependentSampler;
pub use pss::PssSampler;

use crate::math::Vec2;

/// The stream a group of random numbers belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stream {
    Camera,
    Light,
    Connection,
}

pub trait Sampler {
    /// Starts (or restarts) drawing from `stream`.
    fn start_stream(&mut self, stream: Stream);
    fn next_1d(&mut self) -> f32;
    fn next_2d(&mut self) -> Vec2 {
        let x = self.next_1d();
        Vec2::new(x, self.next_1d())
    }
}
