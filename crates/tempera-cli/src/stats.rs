//! Render statistics for people and programs: a short per-depth table of Markov-chain statistics
//! on the terminal, and `--stats FILE.json` ([`RunStats`], keys documented in the README).

use anyhow::{Context, Result};
use std::path::Path;
use tempera::integrator::RunStats;

pub fn write(path: &Path, stats: &RunStats) -> Result<()> {
    let text = serde_json::to_string_pretty(stats).expect("statistics serialise");
    tempera_image::write_file_atomically(path, text.as_bytes())
        .with_context(|| format!("cannot write {}", path.display()))
}

/// A per-depth table of chain statistics on standard error.
pub fn print_table(stats: &RunStats) {
    if let Some(c) = stats.depths.first().and_then(|d| d.hybrid_pilot) {
        let chose = if c.bdpt_alone() {
            "BDPT alone".to_owned()
        } else if c.chains_alone() {
            "the chains alone".to_owned()
        } else {
            format!("the samples {:.0} % of the work", 100.0 * c.work_share)
        };
        eprintln!(
            "pilot ({:.1} s): BDPT's relative variance per unit of work {:.3} times the chains': {chose}",
            c.seconds, c.variance_ratio
        );
    }
    if let Some(p) = stats.depths.first().and_then(|d| d.importance_pilot) {
        let chose = if p.shaped { "targets shaped per pixel" } else { "MMLT's targets" };
        eprintln!(
            "importance pilot ({} samples per pixel, {:.1} s): predicted relMSE ratio {:.3} (--importance-below): {chose}",
            p.spp, p.seconds, p.predicted_ratio
        );
    }
    let no_chains = stats.depths.iter().all(|d| d.mutations == 0);
    if let Some(a) = stats.depths.first().and_then(|d| d.independent_acceptance) {
        let chose = if no_chains { "BDPT alone" } else { "the chains" };
        eprintln!("bootstrap: independent acceptance {a:.4} (--bdpt-above): {chose}");
    }
    // No chains ran (BDPT alone by the pilot's or the bootstrap's choice): nothing to tabulate.
    if no_chains {
        return;
    }
    let tempered = stats.depths.iter().any(|d| d.swaps.is_some());
    let swap_header = if tempered { "  swap.nbr" } else { "" };
    eprintln!("depth          b   rel.se   mutations  acc.large  acc.small  technique{swap_header}");
    for d in &stats.depths {
        eprintln!(
            "{:>5} {:10.4e} {:7.2}% {:11} {:10.3} {:10.3} {:10.3}{}",
            d.depth.to_string(),
            d.b,
            100.0 * d.b_rel_se,
            d.mutations,
            d.acceptance.large_step,
            d.acceptance.small_step,
            d.acceptance.technique_change,
            if tempered {
                d.swaps.as_ref().map_or("         -".to_owned(), |s| format!(" {:9.3}", s.neighbor_acceptance))
            } else {
                String::new()
            },
        );
    }
}
