//! The experiment file (`tempera experiment CONFIG.toml`): scenes × methods × time budgets ×
//! seeds, and how the reference is obtained. Keys are documented in the README; unknown keys
//! are errors (a misspelt key would otherwise be silently ignored).

use anyhow::{Context, Result, bail};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use tempera::integrator::{IntegratorKind, IntegratorSettings};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Config {
    /// Folder for everything the run writes (relative to the experiment file).
    pub output: PathBuf,
    /// Worker threads of every render (0: all cores).
    #[serde(default)]
    pub threads: usize,
    #[serde(default)]
    pub reference: Reference,
    #[serde(rename = "scene")]
    pub scenes: Vec<SceneEntry>,
    #[serde(rename = "method")]
    pub methods: Vec<Method>,
    pub budget: BudgetEntry,
}

/// Either a given image or a method rendered once with a long budget (and cached).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Reference {
    /// A reference image (EXR or PFM); only with a single scene (else per scene).
    pub image: Option<PathBuf>,
    /// Integrator of the rendered reference (default bdpt).
    pub method: Option<IntegratorKind>,
    /// Its settings (the keys of a method's `settings`).
    #[serde(default)]
    pub settings: IntegratorSettings,
    pub spp: Option<u32>,
    pub seconds: Option<f64>,
    /// Seed of the reference render (default 1000, apart from the runs' seeds).
    pub seed: Option<u64>,
    /// Seeds of several reference renders with that budget whose mean is the reference (a
    /// Markov-chain method's renders, each with its own normalisation, average out); instead
    /// of `seed`.
    pub seeds: Option<Vec<u64>>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneEntry {
    pub name: String,
    /// Scene file (relative to the experiment file); omitted: the embedded default scene.
    pub file: Option<PathBuf>,
    /// WIDTHxHEIGHT override.
    pub resolution: Option<String>,
    /// Maximum path depth override for every method and the reference.
    pub maxdepth: Option<u32>,
    /// This scene's reference image (overrides `[reference]`).
    pub reference: Option<PathBuf>,
    /// Skip the scene with a message when its file is missing (instead of failing).
    #[serde(default)]
    pub optional: bool,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Method {
    pub name: String,
    pub integrator: IntegratorKind,
    /// The integrator's settings, as `tempera render` flags set them (`maxdepth` is set per
    /// [[scene]], budgets, seeds and threads by the experiment).
    #[serde(default)]
    pub settings: IntegratorSettings,
}

impl Method {
    /// The method's settings in one line, `key = value, …` (empty for the defaults).
    pub fn describe(&self) -> String {
        let value = serde_json::to_value(&self.settings).unwrap_or_default();
        let entries = value.as_object().into_iter().flatten().filter(|(_, v)| !v.is_null());
        entries.map(|(k, v)| format!("{k} = {v}")).collect::<Vec<_>>().join(", ")
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BudgetEntry {
    /// Equal-time budgets in seconds.
    #[serde(default)]
    pub seconds: Vec<f64>,
    /// Fixed budgets instead of times: samples (path tracing, BDPT, SPPM iterations) or
    /// main-chain mutations (MCMC) per pixel; each is its own render, deterministic for its
    /// seed whatever the machine, threads or ranks.
    #[serde(default)]
    pub samples: Vec<u32>,
    /// Extra times (seconds) at which each run records its image for convergence curves.
    #[serde(default)]
    pub snapshots: Vec<f64>,
    #[serde(default = "default_seeds")]
    pub seeds: Vec<u64>,
}

fn default_seeds() -> Vec<u64> {
    vec![1]
}

/// Names become folder and file names: keep them to letters, digits, `-`, `_` and `.`.
fn check_name(kind: &str, name: &str) -> Result<()> {
    let ok = !name.is_empty()
        && !name.starts_with('.')
        && name.chars().all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.' | '+'));
    if !ok {
        bail!("{kind} name '{name}' must be made of letters, digits, '-', '_', '+' and '.'");
    }
    Ok(())
}

/// A method's settings must suit its integrator and leave `maxdepth` to the scenes.
fn check_settings(what: &str, kind: IntegratorKind, settings: &IntegratorSettings) -> Result<()> {
    if settings.maxdepth.is_some() {
        bail!("{what}: set `maxdepth` per [[scene]], not per method");
    }
    settings.validate(kind).map_err(|e| anyhow::anyhow!("{what}: {e}"))
}

impl Config {
    /// Reads and checks `path`; relative paths inside become relative to its folder.
    pub fn load(path: &Path) -> Result<Config> {
        let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
        Self::parse(&text, path)
    }

    /// Parses and checks the text of the experiment file `path`.
    pub fn parse(text: &str, path: &Path) -> Result<Config> {
        let mut config: Config = toml::from_str(text).map_err(|e| {
            // toml's messages carry the line and column; prefix the file like the scene loaders.
            anyhow::anyhow!("{}: {e}", path.display())
        })?;
        let base = path.parent().unwrap_or(Path::new(""));
        let resolve = |p: &mut PathBuf| {
            if p.is_relative() {
                *p = base.join(&*p);
            }
        };
        resolve(&mut config.output);
        if let Some(image) = config.reference.image.as_mut() {
            resolve(image);
        }
        for scene in &mut config.scenes {
            scene.file.as_mut().map(resolve);
            scene.reference.as_mut().map(resolve);
        }
        config.check().with_context(|| format!("{}: invalid experiment", path.display()))?;
        Ok(config)
    }

    fn check(&self) -> Result<()> {
        if self.scenes.is_empty() || self.methods.is_empty() {
            bail!("needs at least one [[scene]] and one [[method]]");
        }
        let b = &self.budget;
        if b.seconds.is_empty() == b.samples.is_empty() || b.seeds.is_empty() {
            bail!(
                "[budget] needs times in `seconds` or per-pixel counts in `samples` (one of the two), and one seed in `seeds`"
            );
        }
        if !b.samples.is_empty() && !b.snapshots.is_empty() {
            bail!("[budget] `snapshots` are times: they go with `seconds`, not `samples`");
        }
        if b.samples.contains(&0) {
            bail!("[budget] `samples` must be positive");
        }
        if b.seconds.iter().chain(&b.snapshots).any(|t| !t.is_finite() || *t <= 0.0) {
            bail!("[budget] times must be positive numbers of seconds");
        }
        for (i, s) in self.scenes.iter().enumerate() {
            check_name("scene", &s.name)?;
            if self.scenes[..i].iter().any(|o| o.name == s.name) {
                bail!("two scenes are called '{}'", s.name);
            }
            if let Some(r) = &s.resolution {
                crate::flags::parse_resolution(r).map_err(|e| anyhow::anyhow!("scene '{}': {e}", s.name))?;
            }
        }
        for (i, m) in self.methods.iter().enumerate() {
            check_name("method", &m.name)?;
            if self.methods[..i].iter().any(|o| o.name == m.name) {
                bail!("two methods are called '{}'", m.name);
            }
            check_settings(&format!("method '{}'", m.name), m.integrator, &m.settings)?;
        }
        let r = &self.reference;
        if r.image.is_some() && self.scenes.len() > 1 {
            bail!("[reference] image serves a single scene; give each [[scene]] its own `reference`");
        }
        if r.image.is_some() && (r.method.is_some() || r.spp.is_some() || r.seconds.is_some()) {
            bail!("[reference] is either an image or a method with a budget, not both");
        }
        check_settings("[reference]", r.method.unwrap_or(IntegratorKind::Bdpt), &r.settings)?;
        if r.spp.is_some() && r.seconds.is_some() {
            bail!("[reference] takes `spp` or `seconds`, not both");
        }
        if r.seconds.is_some_and(|t| !t.is_finite() || t <= 0.0) || r.spp == Some(0) {
            bail!("[reference] budget must be positive");
        }
        if let Some(seeds) = &r.seeds {
            if r.seed.is_some() || r.image.is_some() {
                bail!("[reference] takes `seeds` or `seed` (or an image), not both");
            }
            if seeds.is_empty() || seeds.iter().enumerate().any(|(i, s)| seeds[..i].contains(s)) {
                bail!("[reference] `seeds` needs at least one seed, none twice");
            }
        }
        Ok(())
    }

    /// Whether the budgets are per-pixel counts (`samples`) rather than times.
    pub fn fixed(&self) -> bool {
        !self.budget.samples.is_empty()
    }

    /// The unit of a budget in labels: seconds or per-pixel counts.
    pub fn unit(&self) -> &'static str {
        if self.fixed() { "pp" } else { "s" }
    }

    /// The budgets (times or per-pixel counts), sorted, without repeats.
    pub fn budgets(&self) -> Vec<f64> {
        let mut budgets: Vec<f64> = self.budget.seconds.clone();
        budgets.extend(self.budget.samples.iter().map(|&n| f64::from(n)));
        budgets.sort_by(f64::total_cmp);
        budgets.dedup();
        budgets
    }

    /// Every time a run records: the snapshots and the budgets, sorted, without repeats; the
    /// run lasts the longest. With `samples`, the per-pixel counts (one render each).
    pub fn times(&self) -> Vec<f64> {
        if self.fixed() {
            return self.budgets();
        }
        let mut times: Vec<f64> = self.budget.seconds.iter().chain(&self.budget.snapshots).copied().collect();
        times.sort_by(f64::total_cmp);
        times.dedup();
        let longest = self.budget.seconds.iter().copied().fold(0.0, f64::max);
        times.retain(|&t| t <= longest);
        times
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Config> {
        let dir = std::env::temp_dir().join(format!("tempera-config-{}", std::process::id()));
        std::fs::create_dir_all(&dir)?;
        let path = dir.join(format!("c{}.toml", text.len()));
        std::fs::write(&path, text)?;
        Config::load(&path)
    }

    const BASE: &str = r#"
output = "out"
[reference]
method = "bdpt"
spp = 64
[[scene]]
name = "default"
resolution = "32x32"
[[method]]
name = "mmlt"
integrator = "mmlt"
[budget]
seconds = [2, 1]
snapshots = [0.5, 1, 4]
seeds = [1, 2]
"#;

    #[test]
    fn the_documented_shape_loads() {
        let typed = BASE.replace(
            "integrator = \"mmlt\"",
            "integrator = \"tempered\"\nsettings = { replicas = 3, swap = \"equi-energy\", reuse_replicas = false }",
        );
        let m = &parse(&typed).unwrap().methods[0];
        assert_eq!(m.settings.swap, Some(tempera::integrator::Swap::EquiEnergy));
        assert_eq!(m.describe(), "replicas = 3, reuse_replicas = false, swap = \"equi-energy\"");
        let c = parse(BASE).unwrap();
        assert!(c.output.ends_with("out") && c.output.components().count() > 1, "relative to the file");
        assert_eq!(c.times(), vec![0.5, 1.0, 2.0], "snapshots past the longest budget are dropped");
        assert_eq!(c.budget.seeds, vec![1, 2]);
        assert_eq!(c.reference.spp, Some(64));
    }

    #[test]
    fn mistakes_are_errors_naming_the_problem() {
        let typo = parse(&BASE.replace("snapshots", "snapshot")).unwrap_err();
        assert!(format!("{typo:#}").contains("unknown field `snapshot`"), "{typo:#}");
        let line = parse(&BASE.replace("spp = 64", "spp = \"many\"")).unwrap_err();
        assert!(format!("{line:#}").contains("line 5"), "{line:#}");
        let both = parse(&BASE.replace("spp = 64", "spp = 64\nseconds = 3")).unwrap_err();
        assert!(format!("{both:#}").contains("not both"), "{both:#}");
        let name = parse(&BASE.replace("name = \"mmlt\"", "name = \"a/b\"")).unwrap_err();
        assert!(format!("{name:#}").contains("method name 'a/b'"), "{name:#}");
        let both_budgets = parse(&BASE.replace("seconds = [2, 1]", "seconds = [2, 1]\nsamples = [4]")).unwrap_err();
        assert!(format!("{both_budgets:#}").contains("one of the two"), "{both_budgets:#}");
        let snapshots = parse(&BASE.replace("seconds = [2, 1]", "samples = [4]")).unwrap_err();
        assert!(format!("{snapshots:#}").contains("not `samples`"), "{snapshots:#}");
        let fixed =
            parse(&BASE.replace("seconds = [2, 1]", "samples = [16, 4]").replace("snapshots = [0.5, 1, 4]\n", ""));
        let fixed = fixed.unwrap();
        assert!(fixed.fixed() && fixed.unit() == "pp");
        assert_eq!(fixed.times(), vec![4.0, 16.0]);
        let res = parse(&BASE.replace("32x32", "32")).unwrap_err();
        assert!(format!("{res:#}").contains("WIDTHxHEIGHT"), "{res:#}");
        let seeds = parse(&BASE.replace("spp = 64", "spp = 64\nseed = 3\nseeds = [4, 5]")).unwrap_err();
        assert!(format!("{seeds:#}").contains("`seeds` or `seed`"), "{seeds:#}");
        let twice = parse(&BASE.replace("spp = 64", "spp = 64\nseeds = [4, 4]")).unwrap_err();
        assert!(format!("{twice:#}").contains("none twice"), "{twice:#}");
        let kind = parse(&BASE.replace("integrator = \"mmlt\"", "integrator = \"vcm\"")).unwrap_err();
        assert!(format!("{kind:#}").contains("unknown variant `vcm`"), "{kind:#}");
        let foreign =
            parse(&BASE.replace("integrator = \"mmlt\"", "integrator = \"mmlt\"\nsettings = { replicas = 2 }"))
                .unwrap_err();
        assert!(format!("{foreign:#}").contains("method 'mmlt': replicas is not a setting"), "{foreign:#}");
        let key = parse(&BASE.replace("integrator = \"mmlt\"", "integrator = \"mmlt\"\nsettings = { chain = 2 }"))
            .unwrap_err();
        assert!(format!("{key:#}").contains("unknown field `chain`"), "{key:#}");
    }
}
