//! The primary-sample-space sampler of Kelemen et al. 2002 ("A Simple and Robust Mutation
//! Strategy for the Metropolis Light Transport Algorithm") with lazy mutation, as in pbrt-v4
//! §13.4.1: a state of uniforms grown on demand, each entry with its value, the iteration that
//! last modified it, and a backup for rejection. Small steps perturb by a wrapped Gaussian of
//! width `sigma`, applied lazily as `sigma·√n` for the `n` iterations an entry was skipped; large
//! steps draw fresh uniforms. Three streams (camera, light, connection) are interleaved by index
//! (`stream + 3·i`) and restart at their first entry, so a change of technique does not shift
//! another stream's numbers. An entry first touched after the chain started is drawn as a fresh
//! uniform (the stationary distribution of an unused component), and forgotten again if the
//! proposal that drew it is rejected. A sampler may hold a counter-based first state
//! ([`PssSampler::with_first_state`]): its entries' first values are then a hash of the state's
//! seed and the entry's index, whatever order they are touched in, so that evaluating the state
//! as paths of different lengths reads the same numbers wherever their entries coincide.

use super::{Sampler, Stream};
use crate::math::rng::Pcg32;
use std::f32::consts::SQRT_2;

const STREAMS: usize = 3;
/// Stamp of an entry no state has used yet.
const UNTOUCHED: u64 = u64::MAX;

#[derive(Clone, Copy, Debug, PartialEq)]
struct Entry {
    value: f32,
    modified: u64,
    backup_value: f32,
    backup_modified: u64,
}

impl Entry {
    const NEW: Entry = Entry { value: 0.0, modified: UNTOUCHED, backup_value: 0.0, backup_modified: UNTOUCHED };
}

/// Inverse error function (Giles 2012, "Approximating the erfinv function", single-precision
/// coefficients, evaluated in double precision).
fn erf_inv(x: f32) -> f32 {
    let x = f64::from(x.clamp(-0.999_999, 0.999_999));
    let mut w = -((1.0 - x) * (1.0 + x)).ln();
    let p = if w < 5.0 {
        w -= 2.5;
        let mut p = 2.810_226_36e-08;
        for c in [
            3.432_739_39e-07,
            -3.523_387_7e-06,
            -4.391_506_54e-06,
            0.000_218_580_87,
            -0.001_253_725_03,
            -0.004_177_681_64,
            0.246_640_727,
            1.501_409_41,
        ] {
            p = c + p * w;
        }
        p
    } else {
        w = w.sqrt() - 3.0;
        let mut p = -0.000_200_214_257;
        for c in [
            0.000_100_950_558,
            0.001_349_343_22,
            -0.003_673_428_44,
            0.005_739_507_73,
            -0.007_622_461_3,
            0.009_438_870_47,
            1.001_674_06,
            2.832_976_82,
        ] {
            p = c + p * w;
        }
        p
    };
    (p * x) as f32
}

/// A Markov chain's position in primary sample space.
#[derive(Clone, Debug)]
pub struct PssSampler {
    rng: Pcg32,
    entries: Vec<Entry>,
    sigma: f32,
    large_step_probability: f32,
    iteration: u64,
    last_large_step: u64,
    large_step: bool,
    stream: usize,
    stream_index: usize,
    /// The seed of the counter-based first state, if the sampler has one.
    first_state: Option<u64>,
    /// The probability that a chain on this sampler proposes a reversible jump instead of a
    /// mutation ([`crate::mcmc::jump`]).
    jump_probability: f32,
    /// The probability that a small step is a film step ([`Self::with_film_steps`]).
    film_step_probability: f32,
    /// The width of a film step.
    film_sigma: f32,
    /// Whether the current proposal is a film step.
    film_step: bool,
    /// The probability that a small step is a lens step ([`Self::with_lens_steps`]).
    lens_step_probability: f32,
    /// Whether the current proposal is a lens step.
    lens_step: bool,
}

/// The indices of the entries that choose the film position in MMLT's states
/// ([`crate::mcmc::strategy::evaluate_connection`]): the camera stream's second and third.
const FILM: [usize; 2] = [STREAMS, 2 * STREAMS];

/// The width of a film step ([`PssSampler::with_film_steps`]) in primary sample space: 2 % of
/// the film's width and height, twice the small step's (measured against 5 %, whose larger
/// moves left more renders blotched; README, "Film steps").
pub const FILM_STEP_WIDTH: f32 = 0.02;

fn stream_id(stream: Stream) -> usize {
    match stream {
        Stream::Camera => 0,
        Stream::Light => 1,
        Stream::Connection => 2,
    }
}

/// The first value of entry `index` of the counter-based first state seeded by `seed`.
fn first_value(seed: u64, index: usize) -> f32 {
    (crate::math::rng::hash(&[seed, index as u64]) >> 40) as f32 * (1.0 / 16_777_216.0)
}

impl PssSampler {
    /// A chain seeded from `(seed, chain)`. Its first iteration is a large step, so the first
    /// evaluated state consists of independent uniforms.
    pub fn new(seed: u64, chain: u64, sigma: f32, large_step_probability: f32) -> Self {
        Self {
            rng: Pcg32::new(crate::math::rng::hash(&[seed, chain]), crate::math::rng::hash(&[chain, 0x5ca1ab1e])),
            entries: Vec::new(),
            sigma,
            large_step_probability,
            iteration: 0,
            last_large_step: 0,
            large_step: true,
            stream: 0,
            stream_index: 0,
            first_state: None,
            jump_probability: 0.0,
            film_step_probability: 0.0,
            film_sigma: 0.0,
            film_step: false,
            lens_step_probability: 0.0,
            lens_step: false,
        }
    }

    /// The sampler with a counter-based first state seeded by `seed`: the entries its first
    /// evaluation touches take values that depend on `seed` and their index alone (not on
    /// the order they are touched in, nor on the seed of the sampler's own numbers). Entries
    /// first touched later are drawn from the sampler's numbers as usual.
    pub fn with_first_state(mut self, seed: u64) -> Self {
        self.first_state = Some(seed);
        self
    }

    /// Takes over the storage of `old`'s entries (emptied) if this sampler has none yet: a
    /// bootstrap evaluates many fresh samplers one after another, and each would otherwise
    /// allocate and grow its own. The state is unchanged (a fresh sampler holds no entries).
    pub fn reuse_storage(&mut self, old: PssSampler) {
        if self.entries.is_empty() {
            let mut entries = old.entries;
            entries.clear();
            self.entries = entries;
        }
    }

    /// Begins a proposal: decides between a large and a small step.
    pub fn start_iteration(&mut self) {
        self.iteration += 1;
        self.large_step = self.rng.next_f32() < self.large_step_probability;
        (self.film_step, self.lens_step) = (false, false);
        let (film, lens) = (self.film_step_probability, self.lens_step_probability);
        if !self.large_step && (film > 0.0 || lens > 0.0) {
            let r = self.rng.next_f32();
            self.film_step = r < film;
            self.lens_step = !self.film_step && r < film + lens;
        }
    }

    /// The sampler with film steps: with probability `p` a small step moves the film position
    /// alone, by a wrapped Gaussian of width `sigma`, and keeps every other number. A primary
    /// sample space counterpart of Veach & Guibas' lens perturbation ("Metropolis Light
    /// Transport", 1997): every other number keeps its value, so each vertex the path meets
    /// next scatters by the same local direction and the light subpath stays as it is, where
    /// a small step moves every number of the path at once and breaks a path that reaches the
    /// light through a gap more often than it moves its pixel. Perturbing a subset of the
    /// numbers by a symmetric kernel is itself symmetric, so a film step is accepted with
    /// `min(1, f(y)/f(x))` as a small step is. The states must lay the film position out as
    /// MMLT's do (the camera stream's second and third numbers).
    pub fn with_film_steps(mut self, p: f32, sigma: f32) -> Self {
        self.film_step_probability = p;
        self.film_sigma = sigma;
        self
    }

    /// The sampler with lens steps: with probability `p` a small step moves the film position
    /// as a film step does ([`Self::with_film_steps`], width `sigma`) and its chain then sets
    /// the first camera vertex's scattering numbers so that the path keeps its second vertex
    /// ([`crate::mcmc::lens`]); the sampler moves the film numbers and keeps every other one,
    /// and the chain pins the rest ([`Self::pin`]). Film and lens steps share their width.
    pub fn with_lens_steps(mut self, p: f32, sigma: f32) -> Self {
        self.lens_step_probability = p;
        self.film_sigma = sigma;
        self
    }

    /// Whether the current proposal is a lens step ([`Self::with_lens_steps`]).
    pub fn is_lens_step(&self) -> bool {
        self.lens_step
    }

    /// The probability that a small step is a lens step.
    pub fn lens_step_probability(&self) -> f32 {
        self.lens_step_probability
    }

    /// Begins a proposal of the kind asked for: a large step (independent uniforms) or a
    /// small one.
    pub fn start_iteration_as(&mut self, large: bool) {
        self.iteration += 1;
        self.large_step = large;
        (self.film_step, self.lens_step) = (false, false);
    }

    /// Begins a proposal whose entries the caller sets where it chooses ([`Self::pin`]) and
    /// that draws fresh uniforms for every other entry, as a large step does: the proposal of a
    /// reversible jump (Bitterli et al. 2017), which keeps the path and changes its technique.
    pub fn start_jump(&mut self) {
        self.iteration += 1;
        self.large_step = true;
        (self.film_step, self.lens_step) = (false, false);
    }

    /// The value entry `index` of `stream` holds (`None` where no state has touched it yet).
    pub fn value(&self, stream: Stream, index: usize) -> Option<f32> {
        let e = self.entries.get(stream_id(stream) + STREAMS * index)?;
        (e.modified != UNTOUCHED).then_some(e.value)
    }

    /// Sets entry `index` of `stream` to `value` in the proposal [`Self::start_jump`] began
    /// (given back if the proposal is rejected).
    pub fn pin(&mut self, stream: Stream, index: usize, value: f32) {
        let index = stream_id(stream) + STREAMS * index;
        if index >= self.entries.len() {
            self.entries.resize(index + 1, Entry::NEW);
        }
        let e = &mut self.entries[index];
        if e.modified != self.iteration {
            e.backup_value = e.value;
            e.backup_modified = e.modified;
        }
        e.value = value;
        e.modified = self.iteration;
    }

    /// The probability that a chain on this sampler proposes a reversible jump
    /// ([`crate::mcmc::jump`]) instead of a mutation.
    pub fn jump_probability(&self) -> f32 {
        self.jump_probability
    }

    /// The sampler with jump probability `p`.
    pub fn with_jumps(mut self, p: f32) -> Self {
        self.jump_probability = p;
        self
    }

    /// The probability that a proposal is a large step.
    pub fn large_step_probability(&self) -> f32 {
        self.large_step_probability
    }

    /// Changes the probability that a proposal is a large step.
    pub fn set_large_step_probability(&mut self, p: f32) {
        self.large_step_probability = p;
    }

    /// Changes the width of small steps (an adaptive chain's mutation size); zero re-proposes
    /// the current state.
    pub fn set_sigma(&mut self, sigma: f32) {
        self.sigma = sigma;
    }

    pub fn is_large_step(&self) -> bool {
        self.large_step
    }

    /// Whether the current proposal is a film step ([`Self::with_film_steps`]).
    pub fn is_film_step(&self) -> bool {
        self.film_step
    }

    /// Keeps the proposal as the chain's new state.
    pub fn accept(&mut self) {
        if self.large_step {
            self.last_large_step = self.iteration;
        }
    }

    /// Discards the proposal: every entry it modified gets its value and stamp back.
    pub fn reject(&mut self) {
        for e in &mut self.entries {
            if e.modified == self.iteration {
                e.value = e.backup_value;
                e.modified = e.backup_modified;
            }
        }
        self.iteration -= 1;
    }

    fn ensure_ready(&mut self, index: usize) {
        if index >= self.entries.len() {
            self.entries.resize(index + 1, Entry::NEW);
        }
        let (iteration, last_large, large) = (self.iteration, self.last_large_step, self.large_step);
        let e = &mut self.entries[index];
        if e.modified == iteration {
            return;
        }
        e.backup_value = e.value;
        e.backup_modified = e.modified;
        if let (UNTOUCHED, 0, Some(seed)) = (e.modified, iteration, self.first_state) {
            e.value = first_value(seed, index);
        } else if e.modified == UNTOUCHED || large {
            e.value = self.rng.next_f32();
        } else {
            // Entries not touched since the last accepted large step were replaced by it.
            if e.modified < last_large {
                e.value = self.rng.next_f32();
                e.modified = last_large;
            }
            let skipped = (iteration - e.modified) as f32;
            // A film or lens step moves the film position by its own width and every other
            // entry by none; the iterations skipped before it by the small steps' width.
            let width = match (self.film_step || self.lens_step, FILM.contains(&index)) {
                (false, _) => self.sigma * skipped.sqrt(),
                (true, film) => {
                    let own = if film { self.film_sigma } else { 0.0 };
                    (self.sigma * self.sigma * (skipped - 1.0) + own * own).sqrt()
                }
            };
            let normal = SQRT_2 * erf_inv(2.0 * self.rng.next_f32() - 1.0);
            e.value += normal * width;
            e.value -= e.value.floor();
            if e.value >= 1.0 {
                e.value = 0.0;
            }
        }
        e.modified = iteration;
    }

    /// The number of primary-sample-space dimensions touched so far.
    pub fn dimensions(&self) -> usize {
        self.entries.len()
    }
}

impl Sampler for PssSampler {
    fn start_stream(&mut self, stream: Stream) {
        self.stream = stream_id(stream);
        self.stream_index = 0;
    }

    fn next_1d(&mut self) -> f32 {
        let index = self.stream + STREAMS * self.stream_index;
        self.stream_index += 1;
        self.ensure_ready(index);
        self.entries[index].value
    }
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod erf_tests {
    #[test]
    fn erf_inv_inverts_erf() {
        // erf(0.5) = 0.520499877813; erf(1.5) = 0.966105146475.
        assert!((super::erf_inv(0.520_499_9) - 0.5).abs() < 1e-5);
        assert!((super::erf_inv(0.966_105_1) - 1.5).abs() < 1e-4);
        assert_eq!(super::erf_inv(0.0), 0.0);
    }
}
