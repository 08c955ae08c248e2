//! Independent uniform sampling from PCG32, seeded by hashing `(seed, pixel, sample)` so that a
//! sample's numbers never depend on which thread draws them.

use super::{Sampler, Stream};
use crate::math::rng::{Pcg32, hash};

#[derive(Clone, Debug)]
pub struct IndependentSampler {
    rng: Pcg32,
}

impl IndependentSampler {
    pub fn new(seed: u64, stream: u64) -> Self {
        Self { rng: Pcg32::new(seed, stream) }
    }

    /// The sampler of sample `sample` of pixel `pixel` in a render seeded with `seed`.
    pub fn for_pixel_sample(seed: u64, pixel: u64, sample: u64) -> Self {
        Self::new(hash(&[seed, pixel, sample]), hash(&[seed]))
    }
}

impl Sampler for IndependentSampler {
    /// All streams share one generator: independent numbers need no separation.
    fn start_stream(&mut self, _stream: Stream) {}

    #[inline]
    fn next_1d(&mut self) -> f32 {
        self.rng.next_f32()
    }
}
