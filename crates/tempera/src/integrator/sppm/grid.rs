//! The hashed uniform grid over SPPM's visible points (pbrt-v3 §16.2.4).

use super::{PixelState, VisiblePoint};
use crate::math::Vec3;
use crate::math::rng::hash;
use rayon::prelude::*;

/// A hashed uniform grid over the visible points (pbrt-v3 §16.2.4): each point is entered in
/// every cell its search sphere overlaps; cells hash into as many buckets as there are points.
pub(super) struct Grid {
    lo: Vec3,
    cell: Vec3,
    res: [i64; 3],
    /// Bucket `b`'s points are `entries[offsets[b]..offsets[b + 1]]`.
    offsets: Vec<u32>,
    entries: Vec<u32>,
}

impl Grid {
    pub(super) fn build(points: &[Option<VisiblePoint>], pixels: &[PixelState]) -> Option<Grid> {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        let mut max_r = 0.0f32;
        let mut count = 0usize;
        for (vp, px) in points.iter().zip(pixels) {
            let Some(vp) = vp else { continue };
            let r = px.radius as f32;
            lo = lo.min(vp.p - Vec3::splat(r));
            hi = hi.max(vp.p + Vec3::splat(r));
            max_r = max_r.max(r);
            count += 1;
        }
        if count == 0 || !lo.is_finite() || !hi.is_finite() || max_r <= 0.0 {
            return None;
        }
        let diag = (hi - lo).max(Vec3::splat(1e-6));
        let max_diag = diag.max_element();
        // About one cell per search diameter along the longest side, at most 2^20 per axis.
        let base = (f64::from(max_diag) / f64::from(max_r)).clamp(1.0, f64::from(1u32 << 20));
        let res = [0, 1, 2].map(|i| ((base * f64::from(diag[i] / max_diag)) as i64).max(1));
        let cell = diag / Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32);
        let grid = Grid { lo, cell, res, offsets: Vec::new(), entries: Vec::new() };
        let buckets = count as u64;
        let mut pairs: Vec<(u32, u32)> = points
            .par_iter()
            .zip(pixels)
            .enumerate()
            .flat_map_iter(|(i, (vp, px))| {
                let mut out = Vec::new();
                if let Some(vp) = vp {
                    let r = px.radius as f32;
                    let (a, b) = (grid.cell_of(vp.p - Vec3::splat(r)), grid.cell_of(vp.p + Vec3::splat(r)));
                    for z in a[2]..=b[2] {
                        for y in a[1]..=b[1] {
                            for x in a[0]..=b[0] {
                                out.push((Grid::bucket([x, y, z], buckets), i as u32));
                            }
                        }
                    }
                }
                out
            })
            .collect();
        pairs.par_sort_unstable();
        // A point whose cells share a bucket is entered once.
        pairs.dedup();
        let mut offsets = vec![0u32; count + 1];
        for &(b, _) in &pairs {
            offsets[b as usize + 1] += 1;
        }
        for b in 0..count {
            offsets[b + 1] += offsets[b];
        }
        let entries = pairs.into_iter().map(|(_, i)| i).collect();
        Some(Grid { offsets, entries, ..grid })
    }

    fn cell_of(&self, p: Vec3) -> [i64; 3] {
        let c = (p - self.lo) / self.cell;
        [0, 1, 2].map(|i| (c[i].floor() as i64).clamp(0, self.res[i] - 1))
    }

    fn bucket(c: [i64; 3], buckets: u64) -> u32 {
        (hash(&[c[0] as u64, c[1] as u64, c[2] as u64]) % buckets) as u32
    }

    /// The visible points whose cells might hold `p`.
    pub(super) fn near(&self, p: Vec3) -> &[u32] {
        let buckets = (self.offsets.len() - 1) as u64;
        let b = Grid::bucket(self.cell_of(p), buckets) as usize;
        &self.entries[self.offsets[b] as usize..self.offsets[b + 1] as usize]
    }
}
