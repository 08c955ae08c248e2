//! A Markov chain in primary sample space with expected-value splatting (Veach 1997 §11.5;
//! pbrt-v4 §13.4.3): each proposal `y` from the current state `x` is accepted with
//! `a = min(1, f(y)/f(x))`, and both are splatted as `C/f` with weights `a` and `1 − a`. Values
//! that are NaN, infinite or negative count as zero. The chain keeps its state between calls, so
//! time-budgeted renders can advance all chains in rounds.

use super::{Contribution, DepthStats, Paths};
use crate::film::SplatBuffer;
use crate::math::rng::Pcg32;
use crate::sampler::PssSampler;

/// Evaluates the sampler's current state; the flag reports an invalid value.
pub trait Target {
    fn evaluate(&self, sampler: &mut PssSampler, paths: &mut Paths, rays: &mut u64) -> (Contribution, bool);
}

pub struct Chain {
    sampler: PssSampler,
    rng: Pcg32,
    current: Contribution,
    paths: Paths,
    pub stats: DepthStats,
    /// Sum, sum of squares and count of the large-step proposals' values.
    pub large: (f64, f64, u64),
    pub rays: u64,
}

impl Chain {
    /// Starts from the state `sampler` holds (its first, large step), evaluated and accepted.
    pub fn start(target: &impl Target, mut sampler: PssSampler, rng: Pcg32, depth: usize) -> Self {
        let mut paths = Paths::default();
        let mut rays = 0;
        let (current, _) = target.evaluate(&mut sampler, &mut paths, &mut rays);
        sampler.accept();
        Self {
            sampler,
            rng,
            current,
            paths,
            stats: DepthStats { depth, ..DepthStats::default() },
            large: (0.0, 0.0, 0),
            rays,
        }
    }

    /// Makes up to `mutations` mutations, checking `stop` every 256; returns how many were made.
    pub fn run(
        &mut self,
        target: &impl Target,
        mutations: u64,
        splats: &mut SplatBuffer,
        stop: &dyn Fn() -> bool,
    ) -> u64 {
        let start = std::time::Instant::now();
        let splat = |splats: &mut SplatBuffer, c: &Contribution, weight: f32| {
            if weight > 0.0 && c.f > 0.0 {
                splats.add(c.raster, c.l * (weight / c.f));
            }
        };
        let mut done = 0;
        while done < mutations {
            if done % 256 == 0 && stop() {
                break;
            }
            self.sampler.start_iteration();
            let large = self.sampler.is_large_step();
            let (proposal, invalid) = target.evaluate(&mut self.sampler, &mut self.paths, &mut self.rays);
            let s = &mut self.stats;
            s.invalid += u64::from(invalid);
            if large {
                let f = f64::from(proposal.f);
                self.large = (self.large.0 + f, self.large.1 + f * f, self.large.2 + 1);
                s.large_steps_proposed += 1;
            } else {
                s.small_steps_proposed += 1;
            }
            let a = if self.current.f > 0.0 { (proposal.f / self.current.f).min(1.0) } else { 1.0 };
            splat(splats, &proposal, a);
            splat(splats, &self.current, 1.0 - a);
            s.mutations += 1;
            done += 1;
            if self.rng.next_f32() < a {
                if proposal.technique != self.current.technique {
                    s.technique_changes += 1;
                }
                if large {
                    s.large_steps_accepted += 1;
                } else {
                    s.small_steps_accepted += 1;
                }
                self.current = proposal;
                self.sampler.accept();
            } else {
                self.sampler.reject();
            }
        }
        self.stats.seconds += start.elapsed().as_secs_f64();
        done
    }
}
