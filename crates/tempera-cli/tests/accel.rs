//! `--accel`: Embree (with the `embree` feature) renders the default scene to the image the
//! BVH gives, up to noise (the two order the scene's primitives, and so its light table,
//! differently), deterministically at any thread count; without the feature it is a clear error.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tempera-accel-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn render(dir: &Path, accel: &str, threads: &str, out: &str) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tempera"))
        .current_dir(dir)
        .args(["render", "--accel", accel, "--spp", "256", "--resolution", "32x32", "--seed", "3"])
        .args(["--threads", threads, "--quiet", "-o", out])
        .output()
        .unwrap()
}

#[cfg(not(feature = "embree"))]
#[test]
fn embree_without_the_feature_is_a_clear_error() {
    let dir = scratch("missing");
    let out = render(&dir, "embree", "1", "e.exr");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--features embree"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[cfg(feature = "embree")]
#[test]
fn embree_renders_the_bvh_image_up_to_noise_at_any_thread_count() {
    use tempera_image::{ColorEncoding, read_image};
    let dir = scratch("agree");
    for (accel, threads, name) in [("bvh", "2", "b.exr"), ("embree", "1", "e1.exr"), ("embree", "2", "e2.exr")] {
        let out = render(&dir, accel, threads, name);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    let read = |name: &str| read_image(&dir.join(name), ColorEncoding::Linear).unwrap().pixels;
    let (b, e1, e2) = (read("b.exr"), read("e1.exr"), read("e2.exr"));
    assert!(e1 == e2, "Embree's image depends on the thread count");
    // Per 8×8 block, the mean over the block's pixels and channels.
    let blocks = |p: &[tempera::math::Vec3]| -> Vec<f64> {
        (0..16)
            .map(|k| {
                let (bx, by) = (k % 4, k / 4);
                let mut sum = 0.0;
                for y in 8 * by..8 * by + 8 {
                    for x in 8 * bx..8 * bx + 8 {
                        let c = p[y * 32 + x];
                        sum += f64::from(c.x + c.y + c.z);
                    }
                }
                sum / 192.0
            })
            .collect()
    };
    let (bb, be) = (blocks(&b), blocks(&e1));
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    assert!((mean(&be) / mean(&bb) - 1.0).abs() < 0.01, "image means {} and {}", mean(&be), mean(&bb));
    for (k, (x, y)) in bb.iter().zip(&be).enumerate() {
        assert!((x - y).abs() <= 0.05 * x.max(*y) + 1e-3, "block {k}: {x} against {y}");
    }
}
