//! Tests of the primary-sample-space sampler: restore on reject, small and large steps, lazy
//! mutation of skipped entries, fresh uniforms for late components, stream separation, replay and jumps.

use super::*;
use crate::testing::chi2_p_value;

fn draw(s: &mut PssSampler, stream: Stream, n: usize) -> Vec<f32> {
    s.start_stream(stream);
    (0..n).map(|_| s.next_1d()).collect()
}

fn warm(seed: u64) -> PssSampler {
    let mut s = PssSampler::new(seed, 1, 0.01, 0.3);
    draw(&mut s, Stream::Camera, 4);
    draw(&mut s, Stream::Light, 4);
    s.accept();
    s
}

#[test]
fn reject_restores_values_and_stamps_exactly() {
    let mut s = warm(1);
    for _ in 0..50 {
        let before = (s.entries.clone(), s.iteration, s.last_large_step);
        s.start_iteration();
        draw(&mut s, Stream::Camera, 6);
        draw(&mut s, Stream::Connection, 2);
        s.reject();
        assert_eq!(
            (s.entries.iter().filter(|e| e.modified != UNTOUCHED).count(), s.iteration),
            (before.0.iter().filter(|e| e.modified != UNTOUCHED).count(), before.1)
        );
        for (a, b) in s.entries.iter().zip(&before.0) {
            assert_eq!((a.value, a.modified), (b.value, b.modified), "value and stamp restored");
        }
        s.start_iteration();
        draw(&mut s, Stream::Camera, 4);
        s.accept();
    }
}

#[test]
fn small_steps_are_wrapped_gaussians_and_lazy_for_skipped_iterations() {
    for skipped in [1u64, 16] {
        let mut offsets = Vec::new();
        for seed in 0..4000 {
            let mut s = PssSampler::new(seed, 7, 0.01, 0.0);
            let x0 = draw(&mut s, Stream::Camera, 1)[0];
            s.accept();
            for _ in 0..skipped - 1 {
                s.start_iteration();
                draw(&mut s, Stream::Light, 1);
                s.accept();
            }
            s.start_iteration();
            assert!(!s.is_large_step());
            let x1 = draw(&mut s, Stream::Camera, 1)[0];
            let mut d = x1 - x0;
            d -= d.round();
            offsets.push(f64::from(d));
        }
        let n = offsets.len() as f64;
        let mean = offsets.iter().sum::<f64>() / n;
        let std = (offsets.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / n).sqrt();
        let want = 0.01 * (skipped as f64).sqrt();
        assert!(mean.abs() < 4.0 * want / n.sqrt(), "mean offset {mean}");
        assert!((std / want - 1.0).abs() < 0.06, "{skipped} skipped: std {std} vs {want}");
    }
}

fn uniform_p_value(values: &[f32]) -> f64 {
    let bins = 20;
    let mut counts = vec![0u64; bins];
    for &v in values {
        assert!((0.0..1.0).contains(&v));
        counts[((v * bins as f32) as usize).min(bins - 1)] += 1;
    }
    chi2_p_value(&counts, &vec![values.len() as f64 / bins as f64; bins])
}

#[test]
fn large_steps_and_late_components_are_fresh_uniforms() {
    let mut large = Vec::new();
    let mut late = Vec::new();
    for seed in 0..5000 {
        // Large steps replace values entirely.
        let mut l = PssSampler::new(seed, 2, 0.01, 1.0);
        draw(&mut l, Stream::Camera, 1);
        l.accept();
        l.start_iteration();
        large.push(draw(&mut l, Stream::Camera, 1)[0]);
        // A component first touched after 30 small steps behaves as a uniform.
        let mut small = PssSampler::new(seed, 3, 0.01, 0.0);
        draw(&mut small, Stream::Camera, 1);
        small.accept();
        for _ in 0..30 {
            small.start_iteration();
            draw(&mut small, Stream::Camera, 1);
            small.accept();
        }
        small.start_iteration();
        late.push(draw(&mut small, Stream::Camera, 5)[4]);
    }
    assert!(uniform_p_value(&large) > 1e-3);
    assert!(uniform_p_value(&late) > 1e-3);
}

#[test]
fn rejected_fresh_components_are_forgotten() {
    let mut s = warm(3);
    s.start_iteration();
    draw(&mut s, Stream::Connection, 3);
    let fresh = [2, 5, 8];
    assert!(fresh.iter().all(|&i| s.entries[i].modified == s.iteration));
    s.reject();
    assert!(fresh.iter().all(|&i| s.entries[i].modified == UNTOUCHED), "no state ever used them");
}

#[test]
fn streams_do_not_shift_each_other() {
    // Light-stream entries sit at fixed indices whatever the camera stream's length.
    let mut s = PssSampler::new(11, 4, 0.01, 0.3);
    draw(&mut s, Stream::Camera, 2);
    draw(&mut s, Stream::Light, 3);
    assert!(
        s.entries[1].modified != UNTOUCHED && s.entries[4].modified != UNTOUCHED && s.entries[7].modified != UNTOUCHED
    );
    assert_eq!(s.entries[2].modified, UNTOUCHED, "connection stream untouched");
    s.accept();
    // After a small step that uses more camera numbers, the light values move only by the
    // small-step perturbation.
    let before: Vec<f32> = [1, 4, 7].iter().map(|&i| s.entries[i].value).collect();
    s.start_iteration();
    if !s.is_large_step() {
        draw(&mut s, Stream::Camera, 9);
        let after = draw(&mut s, Stream::Light, 3);
        for (a, b) in after.iter().zip(&before) {
            let mut d = a - b;
            d -= d.round();
            assert!(d.abs() < 0.1, "light value jumped by {d}");
        }
    }
}

#[test]
fn replay_reproduces_a_chain_exactly() {
    let run = |seed: u64| {
        let mut s = PssSampler::new(seed, 9, 0.02, 0.3);
        let mut recorded = Vec::new();
        let mut current = draw(&mut s, Stream::Camera, 3);
        s.accept();
        for i in 0..500 {
            s.start_iteration();
            let proposal = draw(&mut s, Stream::Camera, 3 + i % 2);
            // A deterministic acceptance rule standing in for the Metropolis test.
            if proposal[0] > current[0] - 0.05 {
                s.accept();
                current = proposal;
            } else {
                s.reject();
            }
            recorded.push(current[0].to_bits());
        }
        recorded
    };
    assert_eq!(run(5), run(5));
    assert_ne!(run(5), run(6));
}

/// A jump proposal keeps the pinned entries, draws every other entry it reads as a fresh
/// uniform, and is restored exactly on rejection.
#[test]
fn jumps_pin_entries_draw_the_rest_fresh_and_are_restored_on_rejection() {
    let mut s = warm(7);
    s.start_iteration();
    let camera = draw(&mut s, Stream::Camera, 4);
    s.accept();
    let state = |s: &PssSampler| (s.entries.iter().map(|e| (e.value, e.modified)).collect::<Vec<_>>(), s.iteration);
    let before = state(&s);
    let mut unpinned = Vec::new();
    for _ in 0..2000 {
        s.start_jump();
        s.pin(Stream::Camera, 1, 0.25);
        s.pin(Stream::Light, 6, 0.75);
        let c = draw(&mut s, Stream::Camera, 3);
        let l = draw(&mut s, Stream::Light, 7);
        assert_eq!((c[1], l[6]), (0.25, 0.75));
        unpinned.push(c[2]);
        s.reject();
        let (entries, iteration) = state(&s);
        assert_eq!((entries[..before.0.len()].to_vec(), iteration), before, "restored");
    }
    // Not a small step of the current state: uniform over [0, 1).
    assert!(uniform_p_value(&unpinned) > 1e-3);
    s.start_jump();
    s.pin(Stream::Camera, 0, 0.5);
    s.accept();
    // Entries the accepted jump did not read are fresh at their next use, not the old state's.
    s.start_iteration_as(false);
    s.set_sigma(0.0);
    assert_ne!(draw(&mut s, Stream::Camera, 4)[3], camera[3]);
}

/// A film step moves the film position (the camera stream's second and third entries) by a
/// wrapped Gaussian of its own width, and keeps every other entry; entries skipped before it
/// catch up by the small steps' width alone.
#[test]
fn film_steps_move_the_film_position_alone() {
    let (sigma, width) = (0.01, 0.05);
    let mut s = PssSampler::new(9, 1, sigma, 0.0).with_film_steps(1.0, width);
    s.start_iteration_as(true);
    let camera = draw(&mut s, Stream::Camera, 5);
    let light = draw(&mut s, Stream::Light, 3);
    s.accept();
    let mut offsets = Vec::new();
    for _ in 0..4000 {
        s.start_iteration();
        assert!(s.is_film_step() && !s.is_large_step());
        let c = draw(&mut s, Stream::Camera, 5);
        assert_eq!((c[0], &c[3..], draw(&mut s, Stream::Light, 3)), (camera[0], &camera[3..], light.clone()));
        for i in [1, 2] {
            let d = c[i] - camera[i];
            offsets.push(f64::from(d - d.round()));
        }
        s.reject();
    }
    let var = offsets.iter().map(|d| d * d).sum::<f64>() / offsets.len() as f64;
    assert!((var.sqrt() / f64::from(width) - 1.0).abs() < 0.05, "film step width {}", var.sqrt());
    // A light entry skipped for three iterations, then read in a film step, moves by the
    // small steps' width over the two iterations before it: σ·√2.
    let mut moves = Vec::new();
    for seed in 0..4000 {
        let mut s = PssSampler::new(seed, 2, sigma, 0.0).with_film_steps(0.0, width);
        s.start_iteration_as(true);
        let x0 = draw(&mut s, Stream::Light, 1)[0];
        s.accept();
        for _ in 0..2 {
            s.start_iteration();
            draw(&mut s, Stream::Camera, 1);
            s.accept();
        }
        s.film_step_probability = 1.0;
        s.start_iteration();
        let d = draw(&mut s, Stream::Light, 1)[0] - x0;
        moves.push(f64::from(d - d.round()));
    }
    let sd = (moves.iter().map(|d| d * d).sum::<f64>() / moves.len() as f64).sqrt();
    assert!((sd / (f64::from(sigma) * 2f64.sqrt()) - 1.0).abs() < 0.05, "catch-up width {sd}");
}
