//! The reference of each scene: a given image, or a render by a named method with a long
//! budget, cached in `reference/SCENE.exr` beside a description of how it was made
//! (`reference/SCENE.json`): a changed description renders it again.

use super::config::Config;
use super::scenes::PreparedScene;
use crate::run::Job;
use anyhow::{Context, Result, bail};
use std::path::PathBuf;
use std::time::Duration;
use tempera::cluster::Cluster;
use tempera::integrator::{Budget, IntegratorKind, RenderSettings};
use tempera::texture::Image;
use tempera_image::{ColorEncoding, WriteOptions, read_image, write_image};

/// Samples per pixel of a rendered reference when the file gives no budget.
pub const DEFAULT_SPP: u32 = 1024;
/// Seed of a rendered reference when the file gives none (apart from the runs' small seeds).
pub const DEFAULT_SEED: u64 = 1000;

pub struct Reference {
    pub image: Image,
    /// How the reference was made (part of every run's key).
    pub key: serde_json::Value,
}

fn paths(config: &Config, scene: &PreparedScene) -> (PathBuf, PathBuf, PathBuf) {
    let dir = config.output.join("reference");
    let name = &scene.entry.name;
    (dir.join(format!("{name}.exr")), dir.join(format!("{name}.json")), dir.join(format!("{name}.png")))
}

/// The image file given for `scene`, if any.
fn given(config: &Config, scene: &PreparedScene) -> Option<PathBuf> {
    scene.entry.reference.clone().or_else(|| config.reference.image.clone())
}

fn key(config: &Config, scene: &PreparedScene) -> serde_json::Value {
    let film = &scene.scene.film;
    if let Some(image) = given(config, scene) {
        let modified = std::fs::metadata(&image)
            .and_then(|m| m.modified())
            .ok()
            .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
            .map(|d| d.as_secs());
        return serde_json::json!({ "image": image.display().to_string(), "modified": modified });
    }
    let r = &config.reference;
    let mut key = serde_json::json!({
        "method": r.method.unwrap_or(IntegratorKind::Bdpt),
        "settings": r.settings,
        "spp": if r.seconds.is_none() { Some(r.spp.unwrap_or(DEFAULT_SPP)) } else { None },
        "seconds": r.seconds,
        "seed": r.seed.unwrap_or(DEFAULT_SEED),
        "scene_file": scene.entry.file.as_ref().map(|p| p.display().to_string()),
        "resolution": [film.width, film.height],
        "maxdepth": scene.scene.defaults.max_depth,
    });
    if let Some(seeds) = &r.seeds {
        let fields = key.as_object_mut().expect("the key is an object");
        fields.remove("seed");
        fields.insert("seeds".into(), serde_json::json!(seeds));
    }
    key
}

/// The key of the render with `seed` among a reference's `seeds`: a single render's.
fn seed_key(config: &Config, scene: &PreparedScene, seed: u64) -> serde_json::Value {
    let mut key = key(config, scene);
    let fields = key.as_object_mut().expect("the key is an object");
    fields.remove("seeds");
    fields.insert("seed".into(), serde_json::json!(seed));
    key
}

/// Where the render with `seed` among a reference's `seeds` is cached, and its key.
fn seed_paths(config: &Config, scene: &PreparedScene, seed: u64) -> (PathBuf, PathBuf) {
    let dir = config.output.join("reference");
    let name = &scene.entry.name;
    (dir.join(format!("{name}.seed-{seed}.exr")), dir.join(format!("{name}.seed-{seed}.json")))
}

/// The image at `exr` if the key beside it (`json`) is `key`.
fn read_if_same(exr: &std::path::Path, json: &std::path::Path, key: &serde_json::Value) -> Option<Image> {
    let same = std::fs::read_to_string(json)
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .is_some_and(|k| &k == key);
    if same { read(exr).ok() } else { None }
}

/// Writes `image` to `exr` and `key` beside it (`json`).
fn write_cached(exr: &std::path::Path, json: &std::path::Path, image: &Image, key: &serde_json::Value) -> Result<()> {
    super::create_folder(exr.parent().expect("reference paths have a folder"))?;
    write_image(exr, image, &WriteOptions::default())?;
    tempera_image::write_file_atomically(json, serde_json::to_string_pretty(key).expect("keys serialise").as_bytes())
        .with_context(|| format!("cannot write {}", json.display()))
}

fn read(path: &std::path::Path) -> Result<Image> {
    read_image(path, ColorEncoding::Linear).with_context(|| format!("cannot read the reference {}", path.display()))
}

/// The reference already at hand: a given image or a cached render that still matches.
pub fn cached(config: &Config, scene: &PreparedScene) -> Result<Option<Reference>> {
    let key = key(config, scene);
    if let Some(path) = given(config, scene) {
        let mut image = read(&path)?;
        // NaN or infinite pixels would make every metric NaN: they count as black, with a warning.
        let bad = image.pixels.iter().filter(|p| !p.is_finite()).count();
        if bad > 0 {
            eprintln!("warning: {}: {bad} NaN or infinite pixels read as black", path.display());
            for p in image.pixels.iter_mut().filter(|p| !p.is_finite()) {
                *p = tempera::math::Rgb::ZERO;
            }
        }
        let film = &scene.scene.film;
        let (w, h) = (film.width as usize, film.height as usize);
        // A reference at an integer multiple of the scene's resolution is box-filtered down.
        let factor = image.width / w.max(1);
        let image = if (image.width, image.height) != (w, h) && factor > 1 && image.height == h * factor {
            image.downsample(factor).unwrap_or(image)
        } else {
            image
        };
        if (image.width, image.height) != (w, h) {
            bail!(
                "scene '{}': the reference {} is {}x{} but the scene renders at {}x{} (set `resolution`, or a size that divides the reference's)",
                scene.entry.name,
                path.display(),
                image.width,
                image.height,
                film.width,
                film.height
            );
        }
        return Ok(Some(Reference { image, key }));
    }
    let (exr, json, _) = paths(config, scene);
    Ok(read_if_same(&exr, &json, &key).map(|image| Reference { image, key }))
}

/// The reference of `scene`, rendering (and caching) it when needed: by every rank of
/// `cluster` together, rank 0 writing it; the other ranks then read what rank 0 wrote.
pub fn obtain(config: &Config, scene: &PreparedScene, quiet: bool, cluster: &dyn Cluster) -> Result<Reference> {
    let found = cached(config, scene)?;
    // Rank 0 decides whether the reference is to be rendered.
    let reference = if cluster.broadcast(found.is_none()) {
        let rendered = render(config, scene, quiet, cluster)?;
        // Rank 0 has written it.
        cluster.broadcast(true);
        if cluster.is_root() { Some(rendered) } else { cached(config, scene)? }
    } else {
        found
    };
    let Some(reference) = reference else {
        bail!(
            "scene '{}': the reference rank 0 has is not readable here (experiments across ranks need \
             a file system all ranks share)",
            scene.entry.name
        );
    };
    if cluster.is_root() {
        let (_, _, png) = paths(config, scene);
        super::create_folder(png.parent().expect("reference paths have a folder"))?;
        write_image(&png, &reference.image, &WriteOptions::default())?;
    }
    Ok(reference)
}

/// Renders the reference: one render, or the mean of one render per seed of `seeds`, each
/// cached as it finishes so that an interrupted experiment keeps them.
fn render(config: &Config, scene: &PreparedScene, quiet: bool, cluster: &dyn Cluster) -> Result<Reference> {
    let r = &config.reference;
    let root = cluster.is_root();
    let image = match &r.seeds {
        None => render_seed(config, scene, quiet, cluster, r.seed.unwrap_or(DEFAULT_SEED))?,
        Some(seeds) => {
            let mut sum: Option<Image> = None;
            for &seed in seeds {
                let (exr, json) = seed_paths(config, scene, seed);
                let key = seed_key(config, scene, seed);
                let found = if root { read_if_same(&exr, &json, &key) } else { None };
                let image = if cluster.broadcast(found.is_none()) {
                    let image = render_seed(config, scene, quiet, cluster, seed)?;
                    if root {
                        write_cached(&exr, &json, &image, &key)?;
                    }
                    image
                } else if let Some(image) = found {
                    image
                } else {
                    read(&exr)?
                };
                match sum.as_mut() {
                    None => sum = Some(image),
                    Some(s) => s.pixels.iter_mut().zip(&image.pixels).for_each(|(a, b)| *a += *b),
                }
            }
            let mut mean = sum.expect("seeds are not empty");
            let n = seeds.len() as f32;
            mean.pixels.iter_mut().for_each(|p| *p /= n);
            mean
        }
    };
    let key = key(config, scene);
    if root {
        let (exr, json, _) = paths(config, scene);
        write_cached(&exr, &json, &image, &key)?;
    }
    Ok(Reference { image, key })
}

/// One render of the reference's method and budget with `seed`.
fn render_seed(config: &Config, scene: &PreparedScene, quiet: bool, cluster: &dyn Cluster, seed: u64) -> Result<Image> {
    let r = &config.reference;
    let method = r.method.unwrap_or(IntegratorKind::Bdpt);
    let integrator = tempera::integrator::create(method, &r.settings, &scene.scene.defaults)
        .map_err(|e| anyhow::anyhow!("[reference]: {e}"))?;
    let budget = match r.seconds {
        Some(t) => Budget::Time(Duration::from_secs_f64(t)),
        None => Budget::Samples(r.spp.unwrap_or(DEFAULT_SPP)),
    };
    let label = format!("reference for {}", scene.entry.name);
    let what = match budget {
        Budget::Samples(spp) => format!("{spp} spp"),
        Budget::Time(d) => format!("{} s", d.as_secs_f64()),
    };
    let root = cluster.is_root();
    if root {
        eprintln!("scene '{}': rendering the reference with {method}, {what}, seed {seed}", scene.entry.name);
    }
    let settings = RenderSettings { budget, seed, threads: config.threads };
    let out = Job { label: Some(&label), cluster, ..Job::new(&scene.scene, integrator.as_ref(), settings, quiet) }
        .run()
        .with_context(|| format!("scene '{}': reference", scene.entry.name))?;
    if out.stats.cancelled {
        bail!("interrupted while rendering the reference of '{}' (this render is not cached)", scene.entry.name);
    }
    if root {
        eprintln!("scene '{}': reference rendered in {:.1} s", scene.entry.name, out.stats.seconds);
    }
    Ok(out.image)
}

/// The reference image of `scene` relative to the output folder (for the report).
pub fn png_name(scene: &str) -> String {
    format!("reference/{scene}.png")
}
