//! One render across MPI ranks (with the `mpi` feature): `mpirun -np 2` and `-np 3` give the
//! same image, byte for byte, as a single process for every integrator at a fixed budget; a
//! scene that fails to load stops every rank with one clear error. Skipped, with a message,
//! when `mpirun` is missing.
#![cfg(feature = "mpi")]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tempera-mpi-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Held by each test while it runs `mpirun`: every job oversubscribes the machine's cores, and
/// two at once (the test harness runs tests in parallel) can delay a job's start past what a
/// test waits for. `None` (the test skips) when `mpirun` is missing.
fn mpirun_alone() -> Option<std::sync::MutexGuard<'static, ()>> {
    static MPIRUN: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let found = Command::new("mpirun").arg("--version").output().is_ok_and(|o| o.status.success());
    if !found {
        eprintln!("skipped: mpirun not found (install openmpi-bin)");
        return None;
    }
    Some(MPIRUN.lock().unwrap_or_else(std::sync::PoisonError::into_inner))
}

/// `tempera ARGS` in one process, or under `mpirun -np ranks`.
fn tempera(dir: &Path, ranks: Option<usize>, args: &[&str]) -> Output {
    let bin = env!("CARGO_BIN_EXE_tempera");
    let mut cmd = match ranks {
        None => Command::new(bin),
        Some(n) => {
            let mut c = Command::new("mpirun");
            c.args(["--allow-run-as-root", "--oversubscribe", "-np", &n.to_string(), bin]);
            c
        }
    };
    cmd.current_dir(dir).args(args).output().unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn ranks_render_the_single_process_image_byte_for_byte() {
    let Some(_alone) = mpirun_alone() else { return };
    let dir = scratch("identical");
    let common = ["--resolution", "40x30", "--seed", "5", "--threads", "1", "--quiet"];
    let runs: [(&str, &[&str]); 9] = [
        ("path", &["--spp", "6"]),
        ("bdpt", &["--spp", "3"]),
        ("mmlt", &["--mpp", "4", "--bootstrap", "4000"]),
        ("mmlt", &["--mpp", "4", "--bootstrap", "4000", "--hybrid", "0.5", "--measure-efficiency"]),
        ("pssmlt", &["--mpp", "4", "--bootstrap", "4000"]),
        // Targets shaped by a BDPT pilot drawn across the ranks, its map from rank 0's image.
        ("mmlt", &["--mpp", "3", "--bootstrap", "4000", "--importance-pilot", "3", "--importance-below", "1000"]),
        ("tempered", &["--mpp", "3", "--bootstrap", "4000", "--ensembles-below", "0", "--bdpt-above", "inf"]),
        // The default scene's bootstrap chooses BDPT alone, at the same samples on every rank.
        ("tempered", &["--mpp", "3", "--bootstrap", "4000"]),
        ("sppm", &["--spp", "3", "--photons", "3000", "--radius", "0.1"]),
    ];
    for (integrator, budget) in runs {
        let (mut images, mut efficiencies) = (Vec::new(), Vec::new());
        for ranks in [None, Some(2), Some(3)] {
            let name = format!("{integrator}-{}.exr", ranks.unwrap_or(1));
            let mut args = vec!["render", "--integrator", integrator, "-o", &name, "--stats", "stats.json"];
            args.extend_from_slice(budget);
            args.extend_from_slice(&common);
            let out = tempera(&dir, ranks, &args);
            assert!(out.status.success(), "{integrator} on {ranks:?} ranks: {}", stderr(&out));
            images.push(std::fs::read(dir.join(&name)).unwrap());
            let stats: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(dir.join("stats.json")).unwrap()).unwrap();
            assert_eq!(stats["ranks"].as_u64().unwrap_or(1), ranks.unwrap_or(1) as u64, "{integrator}: {stats}");
            let depths = stats["depths"].as_array().unwrap();
            efficiencies.push(depths.iter().map(|d| d["measured_efficiency"].as_f64()).collect::<Vec<_>>());
        }
        // Measured from the halves summed over the ranks, the same everywhere.
        assert!(efficiencies.iter().all(|e| *e == efficiencies[0]), "{integrator}: {efficiencies:?}");
        if budget.contains(&"--measure-efficiency") {
            assert!(efficiencies[0].iter().any(Option::is_some), "{integrator}: nothing measured");
        }
        assert!(images[0] == images[1], "{integrator}: 2 ranks differ from one process");
        assert!(images[0] == images[2], "{integrator}: 3 ranks differ from one process");
    }
}

#[test]
fn a_scene_no_rank_can_load_stops_every_rank_with_one_error() {
    let Some(_alone) = mpirun_alone() else { return };
    let dir = scratch("missing");
    let out = tempera(&dir, Some(2), &["render", "no-such-scene.pbrt", "--quiet"]);
    assert!(!out.status.success());
    let err = stderr(&out);
    assert_eq!(err.matches("no-such-scene.pbrt").count(), 1, "one message, from rank 0: {err}");
}

#[test]
fn other_commands_refuse_to_run_across_ranks() {
    let Some(_alone) = mpirun_alone() else { return };
    let dir = scratch("info");
    let out = tempera(&dir, Some(2), &["info"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("only `tempera render` and `tempera experiment`"), "{}", stderr(&out));
}

/// An experiment across 2 ranks: the reference (a fixed budget) is rendered by both ranks and
/// is the single process's byte for byte; every run is done once, by one rank; with fixed
/// budgets rank 0 writes the single process's rows (every figure but the wall time) and images,
/// and a second invocation finds every run finished.
#[test]
fn an_experiment_across_ranks_renders_its_reference_together_and_deals_its_runs() {
    let Some(_alone) = mpirun_alone() else { return };
    let config = r#"
output = "out"
threads = 1
[reference]
method = "bdpt"
spp = 8
[[scene]]
name = "default"
resolution = "24x24"
maxdepth = 4
[[method]]
name = "path"
integrator = "path"
[[method]]
name = "mmlt"
integrator = "mmlt"
settings = { bootstrap = 2000, chains = 8 }
[budget]
samples = [2, 5]
seeds = [1, 2, 3]
"#;
    let (one, two) = (scratch("experiment-1"), scratch("experiment-2"));
    for dir in [&one, &two] {
        std::fs::write(dir.join("e.toml"), config).unwrap();
    }
    let single = tempera(&one, None, &["experiment", "e.toml", "-q"]);
    assert!(single.status.success(), "{}", stderr(&single));
    let ranks = tempera(&two, Some(2), &["experiment", "e.toml", "-q"]);
    assert!(ranks.status.success(), "{}", stderr(&ranks));
    let reference = |d: &Path| std::fs::read(d.join("out/reference/default.exr")).unwrap();
    assert!(reference(&one) == reference(&two), "the reference differs from one process's");
    let rows = |d: &Path| {
        let text = std::fs::read_to_string(d.join("out/results.csv")).unwrap();
        // Every column but `seconds` (the wall time).
        let mut keys: Vec<String> = text
            .lines()
            .skip(1)
            .map(|l| l.split(',').enumerate().filter(|(i, _)| *i != 4).map(|(_, f)| f).collect::<Vec<_>>().join(","))
            .collect();
        keys.sort();
        keys
    };
    assert_eq!(rows(&one), rows(&two));
    assert_eq!(rows(&two).len(), 12);
    let image = |d: &Path| std::fs::read(d.join("out/images/default/mmlt/seed-2-5pp.exr")).unwrap();
    assert!(image(&one) == image(&two), "a run's image differs from one process's");
    let claims = std::fs::read_dir(two.join("out")).unwrap().flatten();
    assert!(!claims.into_iter().any(|e| e.file_name().to_string_lossy().starts_with(".claims")), "claims left over");
    let again = tempera(&two, Some(2), &["experiment", "e.toml", "-q"]);
    assert!(again.status.success(), "{}", stderr(&again));
    assert_eq!(stderr(&again).matches("finished earlier").count(), 6, "{}", stderr(&again));
}

/// Ctrl-C on `mpirun` (which passes it on to the ranks as a termination signal) writes the
/// image rendered so far, as a single process does.
#[test]
fn interrupting_mpirun_writes_the_image_so_far() {
    let Some(_alone) = mpirun_alone() else { return };
    use std::os::unix::process::CommandExt;
    let dir = scratch("interrupt");
    let bin = env!("CARGO_BIN_EXE_tempera");
    // In a process group of its own: what mpirun signals on an interrupt must not reach the
    // other tests' processes.
    let child = Command::new("mpirun")
        .process_group(0)
        .args(["--allow-run-as-root", "--oversubscribe", "-np", "2", bin, "render", "--integrator", "mmlt"])
        .args(["--time", "60", "--resolution", "32x32", "--threads", "1", "--quiet", "-o", "so-far.exr"])
        .current_dir(&dir)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_secs(5));
    let start = std::time::Instant::now();
    Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(start.elapsed().as_secs() < 30, "mpirun stopped long after the interrupt");
    let image = tempera_image::read_image(&dir.join("so-far.exr"), tempera_image::ColorEncoding::Linear)
        .unwrap_or_else(|e| panic!("no image after the interrupt ({e}): {}", stderr(&out)));
    assert!(image.pixels.iter().any(|p| p.max_element() > 0.0), "the image so far is black");
}

/// A rank killed in the middle of an experiment ends the job (no hang) with a non-zero exit;
/// every run finished before keeps its record, and the same command then finishes the rest,
/// skipping them.
#[test]
fn a_rank_that_dies_loses_no_finished_run() {
    let Some(_alone) = mpirun_alone() else { return };
    use std::os::unix::process::CommandExt;
    let dir = scratch("death");
    let config = r#"
output = "out"
threads = 1
[reference]
method = "bdpt"
spp = 4
[[scene]]
name = "default"
resolution = "24x24"
maxdepth = 4
[[method]]
name = "path"
integrator = "path"
[budget]
seconds = [0.5]
seeds = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10]
"#;
    std::fs::write(dir.join("e.toml"), config).unwrap();
    let bin = env!("CARGO_BIN_EXE_tempera");
    let child = Command::new("mpirun")
        .process_group(0)
        .args(["--allow-run-as-root", "--oversubscribe", "-np", "2", bin, "experiment", "e.toml", "-q"])
        .current_dir(&dir)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let runs = dir.join("out/runs/default/path");
    let finished = || std::fs::read_dir(&runs).map_or(0, |d| d.flatten().count());
    let start = std::time::Instant::now();
    while finished() < 2 && start.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    // The ranks are mpirun's children; kill one outright.
    let ranks = Command::new("pgrep").args(["-P", &child.id().to_string()]).output().unwrap();
    let rank = String::from_utf8_lossy(&ranks.stdout).lines().last().map(str::to_owned).expect("a rank process");
    let kept: Vec<String> =
        std::fs::read_dir(&runs).unwrap().flatten().map(|e| e.file_name().to_string_lossy().into()).collect();
    Command::new("kill").args(["-KILL", &rank]).status().unwrap();
    let killed = std::time::Instant::now();
    let out = child.wait_with_output().unwrap();
    assert!(killed.elapsed().as_secs() < 30, "the job went on long after a rank died");
    assert!(!out.status.success(), "a job that lost a rank reported success: {}", stderr(&out));
    for name in &kept {
        let text = std::fs::read_to_string(runs.join(name)).unwrap();
        assert!(text.contains("\"relmse\""), "{name} lost or damaged: {text}");
    }
    let again = tempera(&dir, Some(2), &["experiment", "e.toml", "-q"]);
    assert!(again.status.success(), "{}", stderr(&again));
    assert!(stderr(&again).matches("finished earlier").count() >= kept.len(), "{}", stderr(&again));
    let csv = std::fs::read_to_string(dir.join("out/results.csv")).unwrap();
    assert_eq!(csv.lines().count(), 11, "{csv}");
}
