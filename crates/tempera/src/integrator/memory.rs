//! Memory a render will take, checked before it is taken: every integrator estimates the
//! buffers it allocates per pixel (film, splat buffers per thread or per path depth, replica
//! layers), and a render whose estimate exceeds the memory available refuses to start with a
//! message that names the figure and what lowers it, instead of aborting in the allocator.

use crate::scene::Scene;

/// Bytes per pixel of the tile driver's film (four `f64` sums) and of the developed image.
pub const FILM_BYTES: u64 = 32 + 12;
/// Bytes per pixel of a per-thread splat buffer (three 64.64 fixed-point sums).
pub const SPLAT_BYTES: u64 = 48;
/// Bytes per pixel of a splat buffer shared by the threads (three atomic 40.24 sums), plus
/// the image it develops into.
pub const SHARED_SPLAT_BYTES: u64 = 24 + 12;

/// The film's pixel count.
pub fn pixels(scene: &Scene) -> u64 {
    u64::from(scene.film.width) * u64::from(scene.film.height)
}

/// The memory this machine can still give, from `/proc/meminfo` (`MemAvailable`); `None`
/// where that is not known.
pub fn available() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib.saturating_mul(1024))
}

fn gib(bytes: u64) -> String {
    format!("{:.1} GiB", bytes as f64 / (1u64 << 30) as f64)
}

/// `Ok` when `needed` bytes fit in `limit` (or, without one, in the available memory), else
/// a message naming both figures and what lowers the need.
pub fn check(needed: u64, limit: Option<u64>, what: &str) -> Result<(), String> {
    let Some(limit) = limit.or_else(available) else { return Ok(()) };
    if needed <= limit {
        return Ok(());
    }
    Err(format!(
        "this render needs about {} ({what}) but {} {} available; lower --resolution (or --maxdepth), \
         or set --max-memory to allow more",
        gib(needed),
        gib(limit),
        if limit == 0 { "is" } else { "are" },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_render_larger_than_the_limit_is_refused_with_its_figures() {
        assert!(check(1 << 20, Some(1 << 30), "film").is_ok());
        let e = check(48 << 30, Some(2 << 30), "film and splat buffers").unwrap_err();
        assert!(e.contains("48.0 GiB") && e.contains("2.0 GiB") && e.contains("--max-memory"), "{e}");
        assert!(available().is_none_or(|a| a > 0));
    }
}
