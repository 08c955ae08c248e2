//! `report.html`: per scene an image viewer (methods and reference flipped with keys or clicks,
//! zoomed with the wheel, error maps), error-versus-time plots, a metrics table, Markov-chain
//! and swap statistics, and the seed-spread panel (per-seed images, the spread of their means
//! and the per-pixel variance across seeds). Images lie beside the page; the plots are inline
//! SVG; nothing is fetched from the network.

use super::config::Config;
use super::plot::{Series, error_vs_time};
use super::runs::{Record, Row, image_stem};
use super::scenes::PreparedScene;
use anyhow::{Context, Result};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;
use tempera::math::luminance;
use tempera_image::metrics::{EPSILON, value_map};
use tempera_image::{ColorEncoding, WriteOptions, read_image, write_image};

const TEMPLATE: &str = include_str!("report.html.j2");

#[derive(Serialize)]
struct ViewerImage {
    time: String,
    kind: &'static str,
    src: String,
}

#[derive(Serialize)]
struct ViewerEntry {
    label: String,
    images: Vec<ViewerImage>,
}

#[derive(Serialize)]
struct TableRow {
    method: String,
    time: f64,
    seeds: usize,
    relmse: f64,
    relmse_min: f64,
    relmse_max: f64,
    flip: f64,
    smape: f64,
    mean_ratio: f64,
    samples_per_pixel: f64,
}

#[derive(Serialize)]
struct DepthRow {
    depth: String,
    b: f64,
    acceptance: f64,
    neighbor: Option<f64>,
    ladder: String,
    extra: String,
}

#[derive(Serialize)]
struct ChainRow {
    method: String,
    acceptance: Option<f64>,
    neighbor_acceptance: Option<f64>,
    seed: u64,
    depths: Vec<DepthRow>,
}

#[derive(Serialize)]
struct SpreadRow {
    method: String,
    colour: String,
    seeds: Vec<(u64, String, f64)>,
    mean_ratio_min: f64,
    mean_ratio_max: f64,
    /// Standard deviation of the image means over seeds, relative to the reference mean.
    mean_spread: f64,
    /// Mean over pixels of the variance across seeds divided by R² + ε.
    cross_seed_relvar: f64,
    /// relMSE of the average image over seeds (what averaging the seeds leaves).
    mean_image_relmse: f64,
    map: String,
}

#[derive(Serialize)]
struct SceneReport {
    name: String,
    width: usize,
    height: usize,
    budgets: Vec<String>,
    viewer: Vec<ViewerEntry>,
    plots: Vec<String>,
    table: Vec<TableRow>,
    chains: Vec<ChainRow>,
    spread: Vec<SpreadRow>,
    spread_time: String,
    viewer_seed: u64,
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

fn min_max(v: &[f64]) -> (f64, f64) {
    v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| (lo.min(x), hi.max(x)))
}

/// Rows of one scene grouped by method (in the file's order) and time.
fn grouped<'a>(config: &Config, rows: &[&'a Row], scene: &str) -> Vec<(String, BTreeMap<u64, Vec<&'a Row>>)> {
    config
        .methods
        .iter()
        .map(|m| {
            let mut by_time: BTreeMap<u64, Vec<&Row>> = BTreeMap::new();
            for r in rows.iter().filter(|r| r.scene == scene && r.method == m.name) {
                by_time.entry(r.time.to_bits()).or_default().push(r);
            }
            (m.name.clone(), by_time)
        })
        .filter(|(_, t)| !t.is_empty())
        .collect()
}

fn plots(config: &Config, scene: &str, groups: &[(String, BTreeMap<u64, Vec<&Row>>)]) -> Vec<String> {
    let metric = |name: &str, get: fn(&Row) -> f64| {
        let series: Vec<Series> = groups
            .iter()
            .map(|(method, by_time)| Series {
                name: method.clone(),
                points: by_time
                    .iter()
                    .map(|(t, rows)| {
                        let v: Vec<f64> = rows.iter().map(|r| get(r)).collect();
                        let (lo, hi) = min_max(&v);
                        (f64::from_bits(*t), mean(&v), lo, hi)
                    })
                    .collect(),
            })
            .collect();
        let (against, x_desc) =
            if config.fixed() { ("samples", "samples or mutations per pixel") } else { ("time", "time (s)") };
        error_vs_time(&format!("{scene}: {name} against {against}"), name, x_desc, &series)
            .unwrap_or_else(|e| format!("<p class=\"note\">{e}</p>"))
    };
    vec![metric("relMSE", |r| r.relmse), metric("FLIP", |r| r.flip)]
}

fn table(groups: &[(String, BTreeMap<u64, Vec<&Row>>)], budgets: &[f64]) -> Vec<TableRow> {
    let mut out = Vec::new();
    for (method, by_time) in groups {
        for &t in budgets {
            let Some(rows) = by_time.get(&t.to_bits()) else { continue };
            let get = |f: fn(&Row) -> f64| rows.iter().map(|r| f(r)).collect::<Vec<f64>>();
            let relmse = get(|r| r.relmse);
            let (lo, hi) = min_max(&relmse);
            out.push(TableRow {
                method: method.clone(),
                time: t,
                seeds: rows.len(),
                relmse: mean(&relmse),
                relmse_min: lo,
                relmse_max: hi,
                flip: mean(&get(|r| r.flip)),
                smape: mean(&get(|r| r.smape)),
                mean_ratio: mean(&get(|r| r.mean_ratio)),
                samples_per_pixel: mean(&get(|r| r.samples_per_pixel)),
            });
        }
    }
    out
}

fn chains(groups: &[(String, BTreeMap<u64, Vec<&Row>>)], last: f64) -> Vec<ChainRow> {
    let mut out = Vec::new();
    for (method, by_time) in groups {
        let Some(rows) = by_time.get(&last.to_bits()) else { continue };
        let acc: Vec<f64> = rows.iter().filter_map(|r| r.acceptance).collect();
        if acc.is_empty() {
            continue;
        }
        let nbr: Vec<f64> = rows.iter().filter_map(|r| r.neighbor_acceptance).collect();
        let first = rows[0];
        let depths = first
            .stats
            .depths
            .iter()
            .filter(|d| d.mutations > 0)
            .map(|d| DepthRow {
                depth: d.depth.to_string(),
                b: d.b,
                acceptance: d.acceptance.total,
                neighbor: d.swaps.as_ref().map(|s| s.neighbor_acceptance),
                ladder: d.ladder.iter().map(|v| format!("{v:.3}")).collect::<Vec<_>>().join(", "),
                extra: d.swaps.as_ref().map_or_else(String::new, |s| {
                    format!(
                        "no pair {:.3}, non-identity {:.3}, main changed {:.3}",
                        s.no_pair_rate, s.non_identity_rate, s.main_changed_rate
                    )
                }),
            })
            .collect();
        out.push(ChainRow {
            method: method.clone(),
            acceptance: Some(mean(&acc)),
            neighbor_acceptance: (!nbr.is_empty()).then(|| mean(&nbr)),
            seed: first.seed,
            depths,
        });
    }
    out
}

/// The seed-spread panel of one method at time `t`: the seeds' images, their means and the
/// per-pixel variance across seeds (written as a false-colour map).
fn spread(
    config: &Config,
    scene: &str,
    (index, method): (usize, &str),
    rows: &[&Row],
    reference: &tempera::texture::Image,
) -> Result<Option<SpreadRow>> {
    let mut images = Vec::new();
    for r in rows {
        let Some(stem) = &r.image else { continue };
        let path = config.output.join(format!("{stem}.exr"));
        let image =
            read_image(&path, ColorEncoding::Linear).with_context(|| format!("cannot read {}", path.display()))?;
        images.push((r.seed, format!("{stem}.png"), image));
    }
    if images.len() < 2 {
        return Ok(None);
    }
    let n = images.len() as f64;
    let ref_mean = mean(&reference.pixels.iter().map(|&p| f64::from(luminance(p))).collect::<Vec<_>>());
    let image_mean =
        |img: &tempera::texture::Image| mean(&img.pixels.iter().map(|&p| f64::from(luminance(p))).collect::<Vec<_>>());
    let ratios: Vec<f64> = images.iter().map(|(_, _, img)| image_mean(img) / ref_mean).collect();
    let (lo, hi) = min_max(&ratios);
    let mean_ratio = mean(&ratios);
    let ratio_sd = (ratios.iter().map(|r| (r - mean_ratio).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let pixels = reference.pixels.len();
    let (mut relvar, mut sum_relvar, mut bias) = (vec![0.0; pixels], 0.0, 0.0);
    for (p, relvar) in relvar.iter_mut().enumerate() {
        let v: Vec<f64> = images.iter().map(|(_, _, img)| f64::from(luminance(img.pixels[p]))).collect();
        let m = mean(&v);
        let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
        let r = f64::from(luminance(reference.pixels[p]));
        *relvar = var / (r * r + EPSILON);
        sum_relvar += *relvar;
        bias += (m - r).powi(2) / (r * r + EPSILON);
    }
    let map_name = format!("spread/{scene}/{method}-variance.png");
    let path: PathBuf = config.output.join(&map_name);
    super::create_folder(path.parent().expect("a folder"))?;
    write_image(&path, &value_map(&relvar, reference.width, reference.height), &WriteOptions::default())?;
    let c = super::plot::colour(index);
    Ok(Some(SpreadRow {
        method: method.to_owned(),
        colour: format!("#{:02x}{:02x}{:02x}", c.0, c.1, c.2),
        seeds: images.iter().zip(&ratios).map(|((s, png, _), &r)| (*s, png.clone(), r)).collect(),
        mean_ratio_min: lo,
        mean_ratio_max: hi,
        mean_spread: ratio_sd,
        cross_seed_relvar: sum_relvar / pixels.max(1) as f64,
        mean_image_relmse: bias / pixels.max(1) as f64,
        map: map_name,
    }))
}

fn scene_report(
    config: &Config,
    scene: &PreparedScene,
    rows: &[&Row],
    reference: &tempera::texture::Image,
) -> Result<SceneReport> {
    let name = &scene.entry.name;
    let groups = grouped(config, rows, name);
    let budgets = config.budgets();
    let last = *budgets.last().expect("a budget exists");
    let viewer_seed = config.budget.seeds[0];
    let reference_png = super::reference::png_name(name);
    let mut viewer = vec![ViewerEntry {
        label: "reference".into(),
        images: budgets
            .iter()
            .map(|t| ViewerImage { time: super::runs::time_label(*t), kind: "image", src: reference_png.clone() })
            .collect(),
    }];
    for (method, by_time) in &groups {
        let mut images = Vec::new();
        for t in &budgets {
            if by_time.get(&t.to_bits()).is_some_and(|rs| rs.iter().any(|r| r.seed == viewer_seed)) {
                let stem = image_stem(config, name, method, viewer_seed, *t);
                for (kind, suffix) in [("image", ".png"), ("relmse", "-relmse.png"), ("flip", "-flip.png")] {
                    images.push(ViewerImage {
                        time: super::runs::time_label(*t),
                        kind,
                        src: format!("{stem}{suffix}"),
                    });
                }
            }
        }
        viewer.push(ViewerEntry { label: method.clone(), images });
    }
    let mut spread_rows = Vec::new();
    for (i, (method, by_time)) in groups.iter().enumerate() {
        if let Some(rows) = by_time.get(&last.to_bits())
            && let Some(row) = spread(config, name, (i, method), rows, reference)?
        {
            spread_rows.push(row);
        }
    }
    Ok(SceneReport {
        name: name.clone(),
        width: scene.scene.film.width as usize,
        height: scene.scene.film.height as usize,
        budgets: budgets.iter().map(|t| super::runs::time_label(*t)).collect(),
        viewer,
        plots: plots(config, name, &groups),
        table: table(&groups, &budgets),
        chains: chains(&groups, last),
        spread: spread_rows,
        spread_time: super::runs::time_label(last),
        viewer_seed,
    })
}

/// Writes `report.html` for the finished runs; returns its path.
/// `references` holds each scene's reference image as the runs were compared with it.
pub fn write(
    config: &Config,
    scenes: &[PreparedScene],
    records: &[Record],
    references: &[(String, tempera::texture::Image)],
) -> Result<PathBuf> {
    let rows: Vec<&Row> = records.iter().flat_map(|r| &r.rows).collect();
    let mut reports = Vec::new();
    for scene in scenes {
        let reference = references.iter().find(|(name, _)| *name == scene.entry.name);
        if let Some((_, reference)) = reference
            && rows.iter().any(|r| r.scene == scene.entry.name)
        {
            reports.push(scene_report(config, scene, &rows, reference)?);
        }
    }
    let mut env = minijinja::Environment::new();
    env.add_template("report.html", TEMPLATE).context("report template")?;
    let seeds: Vec<String> = config.budget.seeds.iter().map(u64::to_string).collect();
    let methods: Vec<serde_json::Value> = config
        .methods
        .iter()
        .map(|m| serde_json::json!({"name": m.name, "integrator": m.integrator, "args": m.describe()}))
        .collect();
    let html = env
        .get_template("report.html")
        .and_then(|t| {
            t.render(minijinja::context! {
                scenes => minijinja::Value::from(minijinja::value::Serde(&reports)),
                seeds => seeds.join(", "),
                unit => if config.fixed() { " per pixel" } else { " s" },
                methods => minijinja::Value::from(minijinja::value::Serde(&methods)),
            })
        })
        .context("rendering report.html")?;
    let path = config.output.join("report.html");
    tempera_image::write_file_atomically(&path, html.as_bytes())
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(path)
}
