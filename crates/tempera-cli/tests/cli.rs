//! End-to-end tests of the `tempera` binary: outputs, clear errors without panics, and Ctrl-C
//! writing the image rendered so far.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn tempera() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tempera"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tempera-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn render_writes_every_requested_format() {
    let dir = scratch("formats");
    let out = tempera()
        .current_dir(&dir)
        .args(["render", "--spp", "2", "--resolution", "24x16", "-o", "a.exr", "-o", "a.pfm", "-o", "a.png"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    for name in ["a.exr", "a.pfm", "a.png"] {
        let img = tempera_image::read_image(&dir.join(name), tempera_image::ColorEncoding::Srgb).unwrap();
        assert_eq!((img.width, img.height), (24, 16), "{name}");
        assert!(img.pixels.iter().any(|p| p.max_element() > 0.0), "{name} is black");
    }
    assert!(stderr(&out).contains("Mrays/s"), "one-line summary expected: {}", stderr(&out));
}

#[test]
fn default_outputs_are_tempera_exr_and_png_in_the_current_folder() {
    let dir = scratch("defaults");
    let out =
        tempera().current_dir(&dir).args(["render", "--spp", "1", "--resolution", "8x8", "--quiet"]).output().unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(dir.join("tempera.exr").is_file() && dir.join("tempera.png").is_file());
    assert!(out.stderr.is_empty(), "--quiet prints nothing: {}", stderr(&out));
}

fn assert_clean_error(args: &[&str], needle: &str) {
    let out = tempera().current_dir(scratch("errors")).args(args).output().unwrap();
    let err = stderr(&out);
    assert!(!out.status.success(), "{args:?} must fail");
    assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
    assert!(err.contains(needle), "{args:?}: expected '{needle}' in: {err}");
}

#[test]
fn bad_input_is_a_clear_error_not_a_panic() {
    assert_clean_error(&["render", "/no/such/scene.pbrt"], "/no/such/scene.pbrt");
    assert_clean_error(&["render", "--resolution", "0x10"], "resolution");
    assert_clean_error(&["render", "--resolution", "abc"], "WIDTHxHEIGHT");
    assert_clean_error(&["render", "--spp", "0"], "spp");
    assert_clean_error(&["render", "--time", "-3"], "seconds");
    assert_clean_error(&["render", "--integrator", "magic"], "magic");
    assert_clean_error(&["render", "-o", "image.bmp"], "unsupported output format");
    assert_clean_error(&["render", "-o", "/no/such/folder/x.exr"], "does not exist");
}

/// A film larger than memory allows is refused before anything is allocated, naming the
/// figure and the flag, for every integrator (a 60000² film with MMLT aborted in the allocator).
#[test]
fn renders_larger_than_memory_are_refused_before_allocating() {
    let dir = scratch("memory");
    let scene = dir.join("huge.pbrt");
    std::fs::write(
        &scene,
        "Film \"rgb\" \"integer xresolution\" [60000] \"integer yresolution\" [60000]\n\
         Camera \"perspective\"\nWorldBegin\nLightSource \"point\" \"point3 from\" [0 0 2]\n\
         Shape \"sphere\" \"float radius\" 1\n",
    )
    .unwrap();
    let scene = scene.to_str().unwrap();
    for integrator in ["path", "bdpt", "mmlt", "pssmlt", "tempered"] {
        let args = ["render", scene, "--integrator", integrator, "--mpp", "1", "-q", "--max-memory", "8"];
        let args = if integrator == "path" || integrator == "bdpt" {
            ["render", scene, "--integrator", integrator, "--spp", "1", "-q", "--max-memory", "8"]
        } else {
            args
        };
        assert_clean_error(&args, "8.0 GiB");
        assert_clean_error(&args, "--max-memory");
    }
    // Without a limit the machine's available memory is the limit: 60000² pixels with a buffer
    // per depth is far beyond any machine this runs on.
    assert_clean_error(&["render", scene, "--integrator", "mmlt", "--mpp", "1", "-q"], "needs about");
    assert_clean_error(&["render", "--max-memory", "0"], "GiB");
}

#[test]
fn ctrl_c_stops_and_writes_the_image_so_far() {
    let dir = scratch("interrupt");
    let out_path = dir.join("partial.exr");
    let mut child = tempera()
        .current_dir(&dir)
        .args(["render", "--spp", "100000", "--resolution", "64x64", "-o"])
        .arg(&out_path)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    let status = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(status.success());
    let start = Instant::now();
    let out = loop {
        if let Some(_status) = child.try_wait().unwrap() {
            break child.wait_with_output().unwrap();
        }
        assert!(start.elapsed() < Duration::from_secs(30), "render did not stop after Ctrl-C");
        std::thread::sleep(Duration::from_millis(50));
    };
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("interrupted"), "{}", stderr(&out));
    let img = tempera_image::read_image(Path::new(&out_path), tempera_image::ColorEncoding::Linear).unwrap();
    assert!(img.pixels.iter().filter(|p| p.max_element() > 0.0).count() > 2000, "the partial image is kept");
    assert!(img.pixels.iter().all(|p| p.is_finite()));
}

#[test]
fn bdpt_writes_strategy_images() {
    let dir = scratch("strategies");
    let out = tempera()
        .current_dir(&dir)
        .args(["render", "--integrator", "bdpt", "--spp", "2", "--maxdepth", "2", "--resolution", "16x16", "--quiet"])
        .args(["-o", "img.exr", "--strategy-images", "strategies"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    for name in ["s0_t2", "s0_t3", "s1_t2", "s2_t1", "s0_t4", "s1_t3", "s2_t2", "s3_t1"] {
        assert!(dir.join("strategies").join(format!("{name}.exr")).is_file(), "{name}");
    }
    assert!(!dir.join("strategies/s1_t1.exr").exists());
    assert_clean_error(&["render", "--strategy-images", "x"], "--strategy-images needs --integrator bdpt");
}

#[test]
fn mmlt_writes_depth_images() {
    let dir = scratch("depths");
    let out = tempera()
        .current_dir(&dir)
        .args(["render", "--integrator", "mmlt", "--mpp", "2", "--maxdepth", "2", "--resolution", "16x16", "--quiet"])
        .args(["--bootstrap", "2000", "-o", "img.exr", "--depth-images", "depths"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    for name in ["depth0", "depth1", "depth2"] {
        assert!(dir.join("depths").join(format!("{name}.exr")).is_file(), "{name}");
    }
    assert!(!dir.join("depths/depth3.exr").exists());
    assert_clean_error(
        &["render", "--integrator", "bdpt", "--depth-images", "x"],
        "--depth-images needs --integrator mmlt or tempered",
    );
}

/// `--independent-below N` samples the sparse depths independently: the statistics say which
/// (here every depth `k ≥ 1`, with the threshold above the bootstrap's size) and count each
/// depth's non-zero bootstrap values; integrators without chains refuse it.
#[test]
fn mmlt_samples_sparse_depths_independently() {
    let dir = scratch("independent");
    let out = tempera()
        .current_dir(&dir)
        .args(["render", "--integrator", "mmlt", "--mpp", "2", "--maxdepth", "2", "--resolution", "16x16", "--quiet"])
        .args(["--bootstrap", "2000", "--independent-below", "100000", "-o", "img.exr", "--stats", "s.json"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let stats: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
    let depths = stats["depths"].as_array().unwrap();
    assert_eq!(depths.len(), 3);
    for d in depths {
        let k = d["depth"].as_u64().unwrap();
        assert_eq!(d["independent"].as_bool().unwrap_or(false), k >= 1, "depth {k}");
        let nonzero = d["bootstrap_nonzero"].as_u64().unwrap();
        assert!(nonzero > 0 && nonzero <= 2000, "depth {k}: {nonzero}");
    }
    assert_clean_error(
        &["render", "--integrator", "bdpt", "--independent-below", "10"],
        "independent_below is not a setting of the bdpt integrator",
    );
}

#[test]
fn mmlt_renders_with_a_mutation_budget() {
    let dir = scratch("mmlt");
    let out = tempera()
        .current_dir(&dir)
        .args([
            "render",
            "--integrator",
            "mmlt",
            "--mpp",
            "4",
            "--bootstrap",
            "2000",
            "--chains",
            "8",
            "--resolution",
            "16x16",
            "-o",
            "m.exr",
        ])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let img = tempera_image::read_image(&dir.join("m.exr"), tempera_image::ColorEncoding::Linear).unwrap();
    assert!(img.pixels.iter().any(|p| p.max_element() > 0.0));
    assert_clean_error(&["render", "--integrator", "mmlt", "--large-step", "2"], "probability");
    assert_clean_error(&["render", "--mpp", "4", "--spp", "4"], "cannot be used with");
}

/// A pbrt-v4 file's `mlt` integrator renders with its mutations per pixel and prints its
/// parameters in `tempera info`; another integrator asked for on the command line keeps the
/// sampler's samples per pixel.
#[test]
fn pbrt_v4s_mlt_parameters_set_the_render() {
    let dir = scratch("mlt-file");
    std::fs::write(
        dir.join("mlt.pbrt"),
        "Integrator \"mlt\" \"integer mutationsperpixel\" 3 \"float sigma\" 0.02 \"integer maxdepth\" 3\n\
         Sampler \"independent\" \"integer pixelsamples\" 2\n\
         Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\nCamera \"perspective\"\n\
         WorldBegin\nLightSource \"point\" \"rgb I\" [1 1 1]\nShape \"sphere\"\n",
    )
    .unwrap();
    let run = |args: &[&str]| {
        let out = tempera().current_dir(&dir).args(args).output().unwrap();
        assert!(out.status.success(), "{}", stderr(&out));
        format!("{}{}", String::from_utf8_lossy(&out.stdout), stderr(&out))
    };
    let info = run(&["info", "mlt.pbrt"]);
    assert!(info.contains("3 mutations/pixel") && info.contains("sigma 0.02"), "{info}");
    let mlt = run(&["render", "mlt.pbrt", "-o", "m.exr"]);
    assert!(mlt.contains("with mmlt: 3.0 mutations/pixel"), "{mlt}");
    let bdpt = run(&["render", "mlt.pbrt", "--integrator", "bdpt", "-o", "b.exr"]);
    assert!(bdpt.contains("with bdpt: 2.0 spp"), "{bdpt}");
}

#[test]
fn stats_json_reports_every_depth() {
    let dir = scratch("stats");
    let out = tempera()
        .current_dir(&dir)
        .args([
            "render",
            "--integrator",
            "mmlt",
            "--mpp",
            "4",
            "--maxdepth",
            "3",
            "--bootstrap",
            "2000",
            "--resolution",
            "16x16",
        ])
        .args(["-o", "m.exr", "--stats", "s.json"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(dir.join("s.json")).unwrap();
    for key in [
        "\"depths\"",
        "\"b_rel_se\"",
        "\"large_step\"",
        "\"small_step\"",
        "\"technique_change\"",
        "\"mutations_per_second\"",
    ] {
        assert!(text.contains(key), "{key} missing from {text}");
    }
    assert_eq!(text.matches("\"depth\":").count(), 4, "depths 0..=3");
    assert!(stderr(&out).contains("acc.small"), "terminal table expected");
}

#[test]
fn pssmlt_renders_and_reports_one_row_for_all_depths() {
    let dir = scratch("pssmlt");
    let out = tempera()
        .current_dir(&dir)
        .args(["render", "--integrator", "pssmlt", "--mpp", "2", "--bootstrap", "2000", "--resolution", "16x16"])
        .args(["-o", "p.exr", "--stats", "p.json"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let text = std::fs::read_to_string(dir.join("p.json")).unwrap();
    assert!(text.contains("\"integrator\": \"pssmlt\""), "{text}");
    assert_eq!(text.matches("\"depth\": \"all\"").count(), 1, "{text}");
    assert!(dir.join("p.exr").exists());
}

#[test]
fn tempered_renders_with_every_swap_strategy_and_reports_swaps() {
    let dir = scratch("tempered");
    for swap in ["neighbor", "equi-energy", "permutation"] {
        let json = format!("{swap}.json");
        let out = tempera()
            .current_dir(&dir)
            .args(["render", "--integrator", "tempered", "--mpp", "2", "--bootstrap", "2000", "--maxdepth", "3"])
            .args([
                "--bdpt-above",
                "inf",
                "--ensembles-below",
                "0",
                "--resolution",
                "16x16",
                "--swap",
                swap,
                "--ladder",
                "0.05,0.2",
                "-o",
                "t.exr",
                "--stats",
                &json,
            ])
            .output()
            .unwrap();
        assert!(out.status.success(), "{swap}: {}", stderr(&out));
        let text = std::fs::read_to_string(dir.join(&json)).unwrap();
        assert!(text.contains("\"ladder\": [\n        0.0,\n        0.05,\n        0.2\n      ]"), "{text}");
        assert!(text.contains("\"swap_pairs\"") && text.contains("\"non_identity_rate\""), "{text}");
        assert!(stderr(&out).contains("swap.nbr"), "{}", stderr(&out));
    }
    let bad = tempera()
        .current_dir(&dir)
        .args(["render", "--integrator", "tempered", "--replicas", "4", "--ladder", "0.1,0.05", "--mpp", "1"])
        .output()
        .unwrap();
    assert!(!bad.status.success() && stderr(&bad).contains("must increase"), "{}", stderr(&bad));
    let mismatch = tempera()
        .current_dir(&dir)
        .args(["render", "--integrator", "tempered", "--replicas", "4", "--ladder", "0.05,0.1", "--mpp", "1"])
        .output()
        .unwrap();
    assert!(!mismatch.status.success() && stderr(&mismatch).contains("replicas must be 3"), "{}", stderr(&mismatch));
    let foreign =
        tempera().current_dir(&dir).args(["render", "--integrator", "mmlt", "--replicas", "3"]).output().unwrap();
    let err = stderr(&foreign);
    assert!(!foreign.status.success() && err.contains("replicas is not a setting of the mmlt"), "{err}");
}

#[test]
fn compare_prints_metrics_and_writes_an_error_map() {
    let dir = scratch("compare");
    for (name, spp, res) in [("a.exr", "2", "16x16"), ("r.pfm", "32", "16x16"), ("small.exr", "1", "8x8")] {
        let out = tempera()
            .current_dir(&dir)
            .args(["render", "--spp", spp, "--resolution", res, "--maxdepth", "3", "-q", "-o", name])
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", stderr(&out));
    }
    let out = tempera().current_dir(&dir).args(["compare", "a.exr", "r.pfm", "--error-map", "e.png"]).output().unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    for key in ["mse", "rmse", "relmse", "smape", "flip", "mean ratio"] {
        assert!(text.contains(key), "{key} missing: {text}");
    }
    assert!(dir.join("e.png").exists());
    let flip = tempera()
        .current_dir(&dir)
        .args(["compare", "a.exr", "r.pfm", "--metric", "flip", "--error-map", "f.png"])
        .output()
        .unwrap();
    assert!(flip.status.success(), "{}", stderr(&flip));
    let value: f64 = String::from_utf8_lossy(&flip.stdout)
        .lines()
        .find_map(|l| l.strip_prefix("flip"))
        .and_then(|v| v.trim().parse().ok())
        .expect("a FLIP value");
    assert!(value > 0.0 && value < 1.0, "{value}");
    assert!(dir.join("f.png").exists());
    let same = tempera().current_dir(&dir).args(["compare", "r.pfm", "r.pfm", "--metric", "relmse"]).output().unwrap();
    let text = String::from_utf8_lossy(&same.stdout);
    assert!(text.contains("relmse  0.000000e0") && text.contains("mean ratio 1.000000"), "{text}");
    assert!(!text.contains("smape"), "only the requested metric: {text}");
    let mismatch = tempera().current_dir(&dir).args(["compare", "a.exr", "small.exr"]).output().unwrap();
    assert!(!mismatch.status.success() && stderr(&mismatch).contains("16x16 but the reference is 8x8"));
}
