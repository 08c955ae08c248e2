"""The Python module as a notebook user drives it: load, render, compare, experiment; the
same pixels as the command line; errors as Python exceptions; Ctrl-C and the GIL."""

import os
import pathlib
import signal
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest

import tempera

ROOT = pathlib.Path(__file__).resolve().parents[3]
FIXTURES = ROOT / "crates" / "tempera-scene" / "tests" / "fixtures"


def cli() -> pathlib.Path:
    """The command-line binary built from the same sources (`cargo build --release`)."""
    path = pathlib.Path(os.environ.get("TEMPERA_BIN", ROOT / "target" / "release" / "tempera"))
    if not path.exists():
        pytest.fail(f"{path} is missing: run `cargo build --release` first (or set TEMPERA_BIN)")
    return path


def test_default_scene_renders_finite_linear_rgb():
    scene = tempera.default_scene()
    info = scene.info()
    assert info["resolution"] == (512, 512) and info["primitives"] > 0 and info["warnings"] == []
    result = tempera.render(scene, "bdpt", spp=2, resolution=(40, 30), seed=1, progress=False)
    image = result.image
    assert image.shape == (30, 40, 3) and image.dtype == np.float32
    assert np.isfinite(image).all() and image.mean() > 0.01
    assert result.stats["integrator"] == "bdpt" and result.stats["samples"] == 40 * 30 * 2
    assert not result.interrupted
    # The scene keeps its own resolution after a render at another one.
    assert scene.info()["resolution"] == (512, 512)


def test_loaded_scene_reports_its_contents_and_warnings():
    scene = tempera.load(FIXTURES / "pbrt" / "full.pbrt")
    info = scene.info()
    assert info["resolution"] == (64, 48)
    assert info["lights"] and info["materials"] and info["files"] >= 2
    assert all(isinstance(w, str) for w in info["warnings"])


def test_a_pbrt_mlt_file_sets_the_mutations_per_pixel(tmp_path):
    path = tmp_path / "mlt.pbrt"
    path.write_text(
        'Integrator "mlt" "integer mutationsperpixel" 3 "integer maxdepth" 3\n'
        'Film "rgb" "integer xresolution" 16 "integer yresolution" 16\nCamera "perspective"\n'
        'WorldBegin\nLightSource "point" "rgb I" [1 1 1]\nShape "sphere"\n'
    )
    scene = tempera.load(path)
    assert scene.info()["mpp"] == 3 and scene.info()["integrator"] == "mmlt"
    result = tempera.render(scene, seed=1, progress=False)
    # MMLT rounds each depth's share of the budget to whole rounds of its chains.
    assert result.stats["integrator"] == "mmlt" and abs(result.stats["samples"] / (16 * 16) - 3) < 0.05


@pytest.mark.parametrize(
    "integrator,flags,kwargs",
    [
        ("path", ["--spp", "3"], {"spp": 3}),
        ("bdpt", ["--spp", "2"], {"spp": 2}),
        ("mmlt", ["--mpp", "2", "--bootstrap", "3000"], {"mpp": 2, "bootstrap": 3000}),
        (
            "mmlt",
            ["--mpp", "2", "--bootstrap", "3000", "--importance-pilot", "2", "--importance-floor", "0.3"]
            + ["--importance-power", "0.7"],
            {"mpp": 2, "bootstrap": 3000, "importance_pilot": 2, "importance_floor": 0.3, "importance_power": 0.7},
        ),
        (
            "tempered",
            ["--mpp", "2", "--bootstrap", "3000", "--replicas", "3", "--swap", "equi-energy"],
            {"mpp": 2, "bootstrap": 3000, "replicas": 3, "swap": "equi-energy"},
        ),
        (
            "sppm",
            ["--spp", "2", "--photons", "2000", "--radius", "0.1", "--photon-sampler", "mcmc"],
            {"spp": 2, "photons": 2000, "radius": 0.1, "photon_sampler": "mcmc"},
        ),
    ],
)
def test_same_pixels_as_the_command_line(tmp_path, integrator, flags, kwargs):
    out = tmp_path / "cli.exr"
    common = ["--resolution", "36x24", "--seed", "5", "--threads", "2"]
    subprocess.run([cli(), "render", "--integrator", integrator, *flags, *common, "-q", "-o", out], check=True)
    result = tempera.render(
        tempera.default_scene(), integrator, seed=5, threads=2, resolution=(36, 24), progress=False, **kwargs
    )
    assert np.array_equal(tempera.read(out), result.image)


def test_bad_input_raises_python_exceptions(tmp_path):
    broken = tmp_path / "broken.pbrt"
    broken.write_text('Camera "perspective"\nWorldBegin\nShape "sphere" "float radius" [ 1\n')
    with pytest.raises(tempera.SceneError, match="broken.pbrt:3"):
        tempera.load(broken)
    with pytest.raises(tempera.SceneError, match="no-such-file.pbrt"):
        tempera.load(tmp_path / "no-such-file.pbrt")
    scene = tempera.default_scene()
    for kwargs, message in [
        ({"spp": 1, "mpp": 1}, "at most one"),
        ({"spp": 0}, "at least 1"),
        ({"time": -1.0}, "positive"),
        ({"resolution": (0, 10)}, "resolution"),
        ({"replicas": 3}, "replicas"),
        ({"bogus": 1}, "bogus"),
        ({"large_step": "a lot"}, "large_step"),
    ]:
        with pytest.raises(ValueError, match=message):
            tempera.render(scene, "mmlt", progress=False, **kwargs)
    with pytest.raises(ValueError, match="unknown integrator"):
        tempera.render(scene, "photon", spp=1)
    with pytest.raises(ValueError, match="shape"):
        tempera.compare(np.zeros((4, 4)), np.zeros((4, 4)))
    with pytest.raises(ValueError, match="metric"):
        tempera.compare(np.zeros((4, 4, 3)), np.zeros((4, 4, 3)), metrics=["psnr"])


def test_compare_error_map_save_and_read_take_numpy_arrays(tmp_path):
    rng = np.random.default_rng(1)
    reference = rng.uniform(0.2, 1.0, size=(12, 16, 3))
    image = reference * 1.1
    c = tempera.compare(image, reference)
    # By hand, in float32 as the renderer stores images: luminance-based relMSE with ε = 0.01.
    x, r = image.astype(np.float32).astype(np.float64), reference.astype(np.float32).astype(np.float64)
    lum = lambda a: a @ np.array([0.2126, 0.7152, 0.0722])  # noqa: E731
    assert c["mse"] == pytest.approx(((x - r) ** 2).mean(), rel=1e-6)
    assert c["rmse"] == pytest.approx(np.sqrt(((x - r) ** 2).mean()), rel=1e-6)
    assert c["relmse"] == pytest.approx(((lum(x) - lum(r)) ** 2 / (lum(r) ** 2 + 0.01)).mean(), rel=1e-5)
    assert c["smape"] == pytest.approx((abs(x - r) / (abs(x) + abs(r) + 0.01)).mean(), rel=1e-6)
    assert c["mean_ratio"] == pytest.approx(lum(x).sum() / lum(r).sum(), rel=1e-6)
    assert tempera.compare(reference, reference)["flip"] == 0.0 and 0.0 < c["flip"] < 0.2
    assert set(tempera.compare(image, reference, metrics=("relmse", "flip"))) == {"relmse", "flip"}
    relmse = tempera.error_map(image, reference)
    assert relmse.shape == (12, 16) and relmse.mean() == pytest.approx(c["relmse"], rel=1e-5)
    flip = tempera.error_map(image, reference, "flip")
    assert flip.shape == (12, 16) and flip.mean() == pytest.approx(c["flip"], rel=1e-4)
    picture = tempera.error_map(image, reference, colour=True)
    assert picture.shape[1:] == (16, 3) and picture.shape[0] > 12
    tempera.save(image, tmp_path / "a.exr")
    assert np.array_equal(tempera.read(tmp_path / "a.exr"), image.astype(np.float32))
    tempera.save(image, tmp_path / "a.png", exposure=-1.0)
    assert (tmp_path / "a.png").stat().st_size > 0


def test_experiment_returns_the_results_table(tmp_path):
    config = tmp_path / "tiny.toml"
    config.write_text(
        textwrap.dedent(
            """
            output = "out"
            [reference]
            method = "bdpt"
            spp = 8
            [[scene]]
            name = "default"
            resolution = "16x16"
            maxdepth = 3
            [[method]]
            name = "bdpt"
            integrator = "bdpt"
            [[method]]
            name = "mmlt"
            integrator = "mmlt"
            settings = { bootstrap = 1000, chains = 4 }
            [budget]
            seconds = [0.2]
            seeds = [1, 2]
            """
        )
    )
    table = tempera.experiment(config)
    rows = table.to_dict("records") if hasattr(table, "to_dict") else table
    assert len(rows) == 4
    assert {r["method"] for r in rows} == {"bdpt", "mmlt"}
    assert all(r["relmse"] >= 0 for r in rows)
    assert (tmp_path / "out" / "report.html").exists() and (tmp_path / "out" / "results.csv").exists()
    # A second call reuses every finished run.
    again = tempera.experiment(config)
    again = again.to_dict("records") if hasattr(again, "to_dict") else again
    assert [r["relmse"] for r in again] == [r["relmse"] for r in rows]


def test_renders_release_the_gil():
    scene = tempera.default_scene()
    done = threading.Event()

    def work():
        tempera.render(scene, "path", time=1.0, resolution=(64, 64), threads=1, progress=False)
        done.set()

    thread = threading.Thread(target=work)
    thread.start()
    time.sleep(0.1)
    count = 0
    while not done.is_set():
        count += 1
        time.sleep(0.001)
    thread.join()
    assert count > 100, f"the main thread ran {count} times during a 1-s render"


def test_ctrl_c_returns_the_image_so_far():
    script = textwrap.dedent(
        """
        import signal, sys, time, tempera
        # As in an interactive session, even when this test runs where SIGINT is ignored (a
        # background job of a shell without job control).
        signal.signal(signal.SIGINT, signal.default_int_handler)
        scene = tempera.default_scene()
        print("ready", flush=True)
        start = time.time()
        r = tempera.render(scene, "path", time=60, resolution=(64, 64), threads=1, progress=False)
        print("interrupted", r.interrupted, "after", round(time.time() - start), "mean", float(r.image.mean()) > 0, flush=True)
        """
    )
    child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == "ready"
    time.sleep(1.5)
    child.send_signal(signal.SIGINT)
    out, _ = child.communicate(timeout=30)
    assert child.returncode == 0, out
    words = out.split()
    assert words[:2] == ["interrupted", "True"] and int(words[3]) < 30 and words[5] == "True", out


def test_an_interrupt_from_a_timer_thread_returns_a_partial_image():
    import _thread

    # interrupt_main does nothing where SIGINT is ignored (a background job of a shell without
    # job control): handle it as an interactive session does, for this test.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(1.0, _thread.interrupt_main)
    timer.start()
    start = time.time()
    try:
        result = tempera.render(tempera.default_scene(), "path", time=60, resolution=(48, 48), threads=1, progress=False)
    finally:
        timer.join()
        signal.signal(signal.SIGINT, previous)
    assert result.interrupted and time.time() - start < 20
    assert result.stats["cancelled"] and 0 < result.stats["samples"]
    assert np.isfinite(result.image).all() and result.image.mean() > 0


def test_progress_bar_with_tqdm():
    pytest.importorskip("tqdm")
    script = "import tempera; tempera.render(tempera.default_scene(), 'path', spp=4, resolution=(32, 32))"
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    # A bar over 32 × 32 pixels × 4 samples (cleared when done: leave=False).
    assert "/4096" in out.stderr and "sample/s" in out.stderr, out.stderr
