//! `tempera experiment` as a user runs it: a tiny experiment writes its results, images and
//! report, a second invocation reuses every finished run, mistakes in the file are clear
//! errors, and the report loads in a headless browser (when Chromium is installed).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn tempera() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tempera"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tempera-experiment-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

const TINY: &str = r#"
output = "out"
[reference]
method = "bdpt"
spp = 16
[[scene]]
name = "default"
resolution = "24x24"
maxdepth = 4
[[scene]]
name = "absent"
file = "no/such/scene.pbrt"
optional = true
[[method]]
name = "bdpt"
integrator = "bdpt"
[[method]]
name = "mmlt"
integrator = "mmlt"
settings = { bootstrap = 2000, chains = 8 }
[budget]
seconds = [0.4]
snapshots = [0.2]
seeds = [1, 2]
"#;

fn run(dir: &Path, config: &str) -> Output {
    std::fs::write(dir.join("tiny.toml"), config).unwrap();
    tempera().current_dir(dir).args(["experiment", "tiny.toml", "-q"]).output().unwrap()
}

#[test]
fn experiment_writes_results_images_and_report_and_resumes() {
    let dir = scratch("resume");
    let out = run(&dir, TINY);
    assert!(out.status.success(), "{}", stderr(&out));
    let log = stderr(&out);
    assert!(log.contains("scene 'absent'") && log.contains("skipped (optional)"), "{log}");
    assert!(log.contains("rendering the reference") && log.contains("[4/4]"), "{log}");
    let out_dir = dir.join("out");
    let csv = std::fs::read_to_string(out_dir.join("results.csv")).unwrap();
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    for key in ["scene", "method", "seed", "time", "relmse", "flip", "smape", "mean_ratio", "acceptance"] {
        assert!(header.split(',').any(|h| h == key), "{key} missing from {header}");
    }
    // 2 methods × 2 seeds × (1 snapshot + 1 budget).
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 8, "{csv}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("results.json")).unwrap()).unwrap();
    let rows = json.as_array().unwrap();
    assert_eq!(rows.len(), 8);
    for r in rows {
        let relmse = r["relmse"].as_f64().unwrap();
        assert!(relmse.is_finite() && relmse > 0.0, "{r}");
        assert!((r["mean_ratio"].as_f64().unwrap() - 1.0).abs() < 0.5, "{r}");
        assert!(r["seconds"].as_f64().unwrap() >= r["time"].as_f64().unwrap() * 0.99, "taken at or after its time");
        if r["method"] == "mmlt" {
            assert!(r["stats"]["depths"].as_array().is_some_and(|d| !d.is_empty()), "MCMC statistics: {r}");
            assert!(r["acceptance"].as_f64().is_some());
        }
    }
    for file in [
        "report.html",
        "reference/default.exr",
        "reference/default.png",
        "images/default/mmlt/seed-2-0.4s.exr",
        "images/default/mmlt/seed-2-0.4s.png",
        "images/default/mmlt/seed-2-0.4s-relmse.png",
        "images/default/mmlt/seed-2-0.4s-flip.png",
        "spread/default/mmlt-variance.png",
    ] {
        assert!(out_dir.join(file).exists(), "{file} missing");
    }
    let html = std::fs::read_to_string(out_dir.join("report.html")).unwrap();
    assert!(html.contains("Seed spread") && html.contains("<svg") && html.contains("mmlt"));

    // A second invocation renders nothing: the reference and every run are reused.
    let record = out_dir.join("runs/default/mmlt/seed-1.json");
    let before = std::fs::read_to_string(&record).unwrap();
    let again = run(&dir, TINY);
    assert!(again.status.success(), "{}", stderr(&again));
    let log = stderr(&again);
    assert_eq!(log.matches("finished earlier").count(), 4, "{log}");
    assert!(!log.contains("rendering the reference"), "{log}");
    assert_eq!(std::fs::read_to_string(&record).unwrap(), before);

    // Adding a seed renders only the new runs.
    let more = run(&dir, &TINY.replace("seeds = [1, 2]", "seeds = [1, 2, 3]"));
    assert!(more.status.success(), "{}", stderr(&more));
    let log = stderr(&more);
    assert_eq!(log.matches("finished earlier").count(), 4, "{log}");
    assert!(log.contains("[6/6] default · mmlt · seed 3: relMSE"), "{log}");
    let csv = std::fs::read_to_string(out_dir.join("results.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 12);

    // A given reference image, at twice the scene's resolution: box-filtered down, not rendered.
    let reference = out_dir.join("reference/default.exr");
    let image = tempera_image::read_image(&reference, tempera_image::ColorEncoding::Linear).unwrap();
    let big: Vec<_> = (0..48 * 48).map(|i| image.get(i % 48 / 2, i / 48 / 2)).collect();
    let big = tempera::texture::Image::new(48, 48, big);
    tempera_image::write_image(&dir.join("big.exr"), &big, &Default::default()).unwrap();
    let given = TINY
        .replace("output = \"out\"", "output = \"given\"")
        .replace("[reference]\nmethod = \"bdpt\"\nspp = 16\n", "")
        .replace("maxdepth = 4", "maxdepth = 4\nreference = \"big.exr\"");
    let out = run(&dir, &given);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(!stderr(&out).contains("rendering the reference"), "{}", stderr(&out));
    let csv = std::fs::read_to_string(dir.join("given/results.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 8, "{csv}");
}

/// A reference by several seeds is the mean of the single-seed references, pixel by pixel;
/// each seed's render is kept as it finishes, so adding a seed renders only that seed.
#[test]
fn a_reference_by_several_seeds_is_their_mean() {
    let dir = scratch("reference-seeds");
    let config = |output: &str, seeds: &str| {
        TINY.replace("output = \"out\"", &format!("output = \"{output}\""))
            .replace("spp = 16", &format!("spp = 16\n{seeds}"))
            .replace("seeds = [1, 2]", "seeds = [1]")
    };
    let read = |path: &str| tempera_image::read_image(&dir.join(path), tempera_image::ColorEncoding::Linear).unwrap();
    for (output, seeds) in [("mean", "seeds = [7, 8]"), ("seven", "seed = 7"), ("eight", "seed = 8")] {
        let out = run(&dir, &config(output, seeds));
        assert!(out.status.success(), "{}", stderr(&out));
    }
    let (mean, a, b) =
        (read("mean/reference/default.exr"), read("seven/reference/default.exr"), read("eight/reference/default.exr"));
    assert_ne!(a.pixels, b.pixels);
    for ((m, a), b) in mean.pixels.iter().zip(&a.pixels).zip(&b.pixels) {
        let expected = (*a + *b) / 2.0;
        assert!((*m - expected).abs().max_element() <= 1e-6 * expected.max_element().max(1.0), "{m} vs {expected}");
    }
    assert_eq!(read("mean/reference/default.seed-8.exr").pixels, b.pixels);
    let more = run(&dir, &config("mean", "seeds = [7, 8, 9]"));
    assert!(more.status.success(), "{}", stderr(&more));
    let log = stderr(&more);
    assert!(log.contains("seed 9") && !log.contains("seed 7") && !log.contains("seed 8"), "{log}");
}

#[test]
fn mistakes_in_the_experiment_file_are_clear_errors() {
    let dir = scratch("errors");
    for (change, expected) in [
        (("settings = { bootstrap", "settings = { time = 3, bootstrap"), "unknown field `time`"),
        (("settings = { bootstrap", "settings = { maxdepth = 3, bootstrap"), "set `maxdepth` per [[scene]]"),
        (("settings = { bootstrap", "settings = { replicas = 3, bootstrap"), "replicas is not a setting of the mmlt"),
        (("integrator = \"mmlt\"", "integrator = \"nope\""), "unknown variant `nope`"),
        (("optional = true", "optional = false"), "no/such/scene.pbrt does not exist"),
        (("seconds = [0.4]", "seconds = []"), "times in `seconds` or per-pixel counts in `samples`"),
        (("spp = 16", "spp = 16\nimage = \"r.exr\""), "serves a single scene"),
        (("[budget]", "[budget]\nsnapshot = [1]"), "unknown field `snapshot`"),
    ] {
        let out = run(&dir, &TINY.replace(change.0, change.1));
        let err = stderr(&out);
        assert!(!out.status.success(), "{change:?} should fail");
        assert!(err.contains(expected), "{change:?}: expected '{expected}' in {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

fn chromium() -> Option<&'static str> {
    ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|c| Command::new(c).arg("--version").output().is_ok_and(|o| o.status.success()))
}

#[test]
fn report_loads_its_images_and_plots_in_headless_chromium() {
    let Some(browser) = chromium() else {
        eprintln!("skipped: Chromium is not installed (Debian: apt-get install chromium)");
        return;
    };
    let dir = scratch("chromium");
    let out = run(&dir, TINY);
    assert!(out.status.success(), "{}", stderr(&out));
    let report = dir.join("out/report.html");
    let url = format!("file://{}", report.canonicalize().unwrap().display());
    let flags = ["--headless", "--no-sandbox", "--disable-gpu", "--enable-logging=stderr", "--v=0"];
    let shot = dir.join("report.png");
    let screenshot = Command::new(browser)
        .args(flags)
        .args(["--window-size=1280,2000", "--virtual-time-budget=5000"])
        .arg(format!("--screenshot={}", shot.display()))
        .arg(&url)
        .output()
        .unwrap();
    assert!(screenshot.status.success(), "{}", stderr(&screenshot));
    let dom = Command::new(browser)
        .args(flags)
        .args(["--virtual-time-budget=5000", "--dump-dom"])
        .arg(&url)
        .output()
        .unwrap();
    assert!(dom.status.success(), "{}", stderr(&dom));
    // Console messages (errors included) appear on standard error as `CONSOLE` lines.
    for log in [stderr(&screenshot), stderr(&dom)] {
        let console: Vec<&str> = log.lines().filter(|l| l.contains(":CONSOLE")).collect();
        assert!(console.is_empty(), "console output: {console:?}");
    }
    // The page's own check: every image decoded and every plot is an SVG.
    let dom = String::from_utf8_lossy(&dom.stdout);
    let body = dom.split("<body").nth(1).and_then(|b| b.split('>').next()).unwrap_or_default();
    assert!(body.contains("data-status=\"ok\""), "report check failed: <body{body}>");
    assert!(body.contains("data-plots=\"2\""), "{body}");
    let images: usize =
        body.split("data-images=\"").nth(1).and_then(|v| v.split('"').next()).and_then(|v| v.parse().ok()).unwrap_or(0);
    assert!(images >= 10, "{body}");
    // The screenshot shows a page, not a blank window.
    let png = tempera_image::read_image(&shot, tempera_image::ColorEncoding::Srgb).unwrap();
    assert!(png.width >= 1000 && png.height >= 1000);
    let distinct: std::collections::HashSet<[u32; 3]> =
        png.pixels.iter().map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]).collect();
    assert!(distinct.len() > 100, "a blank screenshot ({} colours)", distinct.len());
}

#[cfg(unix)]
#[test]
fn an_interrupted_experiment_keeps_its_finished_runs() {
    let dir = scratch("interrupt");
    let config = TINY.replace("seconds = [0.4]", "seconds = [1.5]").replace("seeds = [1, 2]", "seeds = [1, 2, 3]");
    std::fs::write(dir.join("tiny.toml"), config).unwrap();
    let child = tempera()
        .current_dir(&dir)
        .args(["experiment", "tiny.toml", "-q"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait for the first run's record, then press Ctrl-C during the second run.
    let first = dir.join("out/runs/default/bdpt/seed-1.json");
    let start = std::time::Instant::now();
    while !first.exists() && start.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    assert!(first.exists(), "the first run never finished");
    std::thread::sleep(std::time::Duration::from_millis(300));
    let status = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(status.success());
    let out = child.wait_with_output().unwrap();
    let log = stderr(&out);
    assert!(out.status.success(), "{log}");
    assert!(log.contains("interrupted"), "{log}");
    assert!(!dir.join("out/runs/default/bdpt/seed-2.json").exists(), "the interrupted run is not recorded");
    let csv = std::fs::read_to_string(dir.join("out/results.csv")).unwrap();
    assert_eq!(csv.lines().filter(|l| l.starts_with("default,bdpt,1,")).count(), 2, "{csv}");
    assert!(dir.join("out/report.html").exists());
}

/// Every file under `dir`, recursively.
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let path = entry.path();
        if path.is_dir() {
            out.extend(files(&path));
        } else {
            out.push(path);
        }
    }
    out
}

/// `kill -9` at several moments (while the reference renders, between runs, mid-run), each
/// time followed by nothing else: a re-run finishes the experiment, keeps what was finished,
/// and leaves no truncated file: every record and result parses, every image reads, and the
/// reference (a fixed budget) is byte for byte an uninterrupted experiment's.
#[test]
fn an_experiment_killed_at_any_moment_loses_nothing_finished() {
    let config = TINY.replace("seeds = [1, 2]", "seeds = [1, 2, 3]");
    let whole = scratch("kill-whole");
    assert!(run(&whole, &config).status.success());
    let dir = scratch("kill");
    std::fs::write(dir.join("tiny.toml"), &config).unwrap();
    for delay_ms in [150, 700, 1300, 2100, 2900] {
        let mut child = tempera().current_dir(&dir).args(["experiment", "tiny.toml", "-q"]).spawn().unwrap();
        std::thread::sleep(std::time::Duration::from_millis(delay_ms));
        let _ = child.kill();
        let _ = child.wait();
        let before: Vec<PathBuf> = files(&dir.join("out/runs"));
        for record in &before {
            let text = std::fs::read_to_string(record).unwrap();
            assert!(serde_json::from_str::<serde_json::Value>(&text).is_ok(), "{} is truncated", record.display());
        }
    }
    let out = run(&dir, &config);
    assert!(out.status.success(), "{}", stderr(&out));
    for file in files(&dir.join("out")) {
        let name = file.to_string_lossy().into_owned();
        if name.ends_with(".json") {
            let text = std::fs::read_to_string(&file).unwrap();
            assert!(serde_json::from_str::<serde_json::Value>(&text).is_ok(), "{name} is truncated");
        } else if name.ends_with(".exr") || name.ends_with(".png") {
            let img = tempera_image::read_image(&file, tempera_image::ColorEncoding::Srgb);
            assert!(img.is_ok(), "{name} does not read: {:?}", img.err());
        }
    }
    assert!(partials(&dir).is_empty(), "temporary files are gone: {:?}", partials(&dir));
    let rows = |d: &Path| std::fs::read_to_string(d.join("out/results.csv")).unwrap().lines().count();
    assert_eq!(rows(&dir), rows(&whole), "every run is in the results");
    let reference = |d: &Path| std::fs::read(d.join("out/reference/default.exr")).unwrap();
    assert!(reference(&dir) == reference(&whole), "the reference is an uninterrupted run's");
}

/// Names of the temporary files of interrupted writes under `dir`.
fn partials(dir: &Path) -> Vec<PathBuf> {
    files(dir).into_iter().filter(|f| f.to_string_lossy().contains(".partial-")).collect()
}

/// A folder that cannot be created and a full disk (simulated with a file-size limit, so the
/// writes fail with EFBIG as they would with ENOSPC) are errors naming the path; the finished
/// runs stay as they were, no temporary file is left, and a later run finishes the rest.
/// Temporary files a killed process left are removed when the experiment starts again.
#[cfg(unix)]
#[test]
fn unwritable_folders_and_a_full_disk_are_clear_errors_that_keep_finished_runs() {
    let dir = scratch("full");
    assert!(run(&dir, &TINY.replace("seeds = [1, 2]", "seeds = [1]")).status.success());
    let finished = ["out/runs/default/bdpt/seed-1.json", "out/runs/default/mmlt/seed-1.json"];
    let kept = || finished.map(|f| std::fs::read(dir.join(f)).unwrap());
    let before = kept();
    let second = dir.join("out/runs/default/bdpt/seed-2.json");

    // A file where the images folder should be.
    std::fs::rename(dir.join("out/images"), dir.join("images-saved")).unwrap();
    std::fs::write(dir.join("out/images"), b"not a folder").unwrap();
    let out = run(&dir, TINY);
    let log = stderr(&out);
    assert!(!out.status.success(), "{log}");
    assert!(log.contains("cannot create the folder") && log.contains("out/images/default/bdpt"), "{log}");
    assert!(kept() == before && !second.exists(), "finished runs are kept");
    std::fs::remove_file(dir.join("out/images")).unwrap();
    std::fs::rename(dir.join("images-saved"), dir.join("out/images")).unwrap();

    // Files may grow to 6 KiB: the next run's 7-KB EXR does not fit.
    let out = Command::new("bash")
        .current_dir(&dir)
        .arg("-c")
        .arg(format!("trap '' XFSZ; ulimit -f 6; exec '{}' experiment tiny.toml -q", env!("CARGO_BIN_EXE_tempera")))
        .output()
        .unwrap();
    let log = stderr(&out);
    assert!(!out.status.success(), "{log}");
    assert!(log.contains("File too large") && log.contains("out/images/default/bdpt/seed-2"), "{log}");
    assert!(kept() == before && !second.exists(), "finished runs are kept");
    assert!(partials(&dir).is_empty(), "{:?}", partials(&dir));

    // What a `kill -9` between writing and renaming leaves (a process id that cannot run).
    let stale = dir.join("out/images/default/.seed-2-0.4s.exr.partial-4294967294.exr");
    std::fs::write(&stale, b"half an image").unwrap();
    let out = run(&dir, TINY);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("removed 1 temporary file"), "{}", stderr(&out));
    assert!(kept() == before && second.exists());
    assert!(partials(&dir).is_empty(), "{:?}", partials(&dir));
}
