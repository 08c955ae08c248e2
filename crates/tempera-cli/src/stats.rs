//! Render statistics for people and programs: a short per-depth table of Markov-chain statistics
//! on the terminal, and `--stats FILE.json` (keys documented in the README).

use anyhow::{Context, Result};
use serde_json::{Value, json};
use std::path::Path;
use tempera::integrator::RenderOutput;
use tempera::mcmc::{DepthStats, SwapStats};

fn rate(accepted: u64, proposed: u64) -> f64 {
    if proposed == 0 { 0.0 } else { accepted as f64 / proposed as f64 }
}

fn swaps_json(s: &SwapStats) -> Value {
    let k = s.replicas;
    let mut pairs = Vec::new();
    for i in 0..k {
        for j in i + 1..k {
            let (attempts, accepted) = (s.attempts[i * k + j], s.accepted[i * k + j]);
            if attempts > 0 || j == i + 1 {
                pairs.push(json!({ "pair": [i, j], "attempts": attempts, "accepted": accepted }));
            }
        }
    }
    json!({
        "steps": s.steps,
        "swap_pairs": pairs,
        "neighbor_acceptance": s.neighbor_acceptance(),
        "no_pair_rate": rate(s.no_pair, s.steps),
        "non_identity_rate": rate(s.non_identity, s.steps),
        "main_changed_rate": rate(s.main_changed, s.steps),
    })
}

/// The shortest decimal form of each `f32` (0.02, not 0.019999999552965164).
fn shortest(values: &[f32]) -> Vec<f64> {
    values.iter().map(|a| a.to_string().parse().unwrap_or(f64::from(*a))).collect()
}

fn depth_json(d: &DepthStats) -> Value {
    let proposed = d.large_steps_proposed + d.small_steps_proposed;
    let mut v = json!({
        "depth": if d.all_depths { json!("all") } else { json!(d.depth) },
        "b": d.b,
        "b_rel_se": d.b_rel_se,
        "bootstrap_samples": d.bootstrap_samples,
        "large_step_samples": d.large_step_samples,
        "mutations": d.mutations,
        "acceptance": {
            "total": d.acceptance(),
            "large_step": rate(d.large_steps_accepted, d.large_steps_proposed),
            "small_step": rate(d.small_steps_accepted, d.small_steps_proposed),
            "technique_change": rate(d.technique_changes, proposed),
        },
        "invalid": d.invalid,
        "seconds": d.seconds,
    });
    if !d.ladder.is_empty() {
        v["ladder"] = json!(shortest(&d.ladder));
    }
    if !d.replica_b_ratios.is_empty() {
        v["replica_b_ratios"] = json!(shortest(&d.replica_b_ratios));
    }
    if !d.replica_b.is_empty() {
        v["replica_b"] = json!(d.replica_b);
    }
    if let Some(swaps) = &d.swaps {
        v["swaps"] = swaps_json(swaps);
    }
    v
}

/// The statistics of a render as JSON.
pub fn to_json(integrator: &str, out: &RenderOutput) -> Value {
    let s = &out.stats;
    let mutations: u64 = out.chains.iter().map(|d| d.mutations).sum();
    json!({
        "integrator": integrator,
        "seconds": s.seconds,
        "samples": s.pixel_samples,
        "rays": s.rays,
        "rays_per_second": s.rays as f64 / s.seconds.max(1e-9),
        "invalid_samples": s.invalid_samples,
        "cancelled": s.cancelled,
        "mutations": mutations,
        "mutations_per_second": mutations as f64 / s.seconds.max(1e-9),
        "depths": out.chains.iter().map(depth_json).collect::<Vec<_>>(),
    })
}

pub fn write(path: &Path, integrator: &str, out: &RenderOutput) -> Result<()> {
    let text = serde_json::to_string_pretty(&to_json(integrator, out)).expect("JSON values serialise");
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
}

/// A per-depth table of chain statistics on standard error.
pub fn print_table(out: &RenderOutput) {
    if out.chains.is_empty() {
        return;
    }
    let tempered = out.chains.iter().any(|d| d.swaps.is_some());
    let swap_header = if tempered { "  swap.nbr" } else { "" };
    eprintln!("depth          b   rel.se   mutations  acc.large  acc.small  technique{swap_header}");
    for d in &out.chains {
        let proposed = d.large_steps_proposed + d.small_steps_proposed;
        eprintln!(
            "{:>5} {:10.4e} {:7.2}% {:11} {:10.3} {:10.3} {:10.3}{}",
            if d.all_depths { "all".to_owned() } else { d.depth.to_string() },
            d.b,
            100.0 * d.b_rel_se,
            d.mutations,
            rate(d.large_steps_accepted, d.large_steps_proposed),
            rate(d.small_steps_accepted, d.small_steps_proposed),
            rate(d.technique_changes, proposed),
            if tempered {
                d.swaps.as_ref().map_or("         -".to_owned(), |s| format!(" {:9.3}", s.neighbor_acceptance()))
            } else {
                String::new()
            },
        );
    }
}
