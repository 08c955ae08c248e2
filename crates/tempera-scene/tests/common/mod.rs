//! Helpers shared by the loader tests.

use tempera_scene::{LoadError, LoadedScene};

/// Feeds a loader every `step`-th prefix of `text`, then 1500 copies of it with one to four
/// characters replaced from `alphabet`; mutated copies that load are also built. Any panic fails
/// the calling test.
pub fn load_truncated_and_mutated(
    text: &str,
    step: usize,
    (seed, stream): (u64, u64),
    alphabet: &[char],
    load: impl Fn(&str) -> Result<LoadedScene, LoadError>,
) {
    let chars: Vec<char> = text.chars().collect();
    for cut in (0..chars.len()).step_by(step) {
        let prefix: String = chars[..cut].iter().collect();
        let _ = load(&prefix);
    }
    let mut rng = tempera::math::rng::Pcg32::new(seed, stream);
    for _ in 0..1500 {
        let mut mutated = chars.clone();
        for _ in 0..1 + rng.next_u32() % 4 {
            let i = rng.next_u32() as usize % mutated.len();
            mutated[i] = alphabet[rng.next_u32() as usize % alphabet.len()];
        }
        let s: String = mutated.into_iter().collect();
        if let Ok(loaded) = load(&s) {
            let _ = loaded.builder.build();
        }
    }
}
