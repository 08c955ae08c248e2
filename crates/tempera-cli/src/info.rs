//! `tempera info`: what a scene file contains once loaded: counts of shapes, triangles,
//! instances, materials and lights by type, textures, the loader's warnings, and timings.

use crate::scene;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;
use tempera::accel::AccelKind;

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// Scene file (.pbrt or .xml); omitted describes the embedded default scene.
    pub scene: Option<PathBuf>,
    /// Treat loader warnings as errors.
    #[arg(long)]
    pub strict: bool,
    /// The accelerator whose build is timed (as `tempera render --accel`).
    #[arg(long, value_enum, default_value_t = AccelKind::Bvh)]
    pub accel: AccelKind,
}

pub fn run(args: InfoArgs) -> Result<()> {
    let loaded = scene::load(args.scene.as_deref(), args.strict, args.accel)?;
    let s = &loaded.scene;
    let name = args.scene.as_ref().map_or_else(|| "embedded default scene".to_owned(), |p| p.display().to_string());
    println!("{name}");
    println!("  film          {}x{}, {:?}", s.film.width, s.film.height, s.film.filter);
    println!("  defaults      {} spp, maxdepth {}", s.defaults.spp, s.defaults.max_depth);
    if let Some(i) = &s.defaults.integrator {
        println!("  integrator    {i}");
    }
    let c = &s.defaults.chain;
    if let Some(mpp) = c.mpp {
        let given = |name: &str, v: Option<String>| v.map(|v| format!(", {name} {v}")).unwrap_or_default();
        println!(
            "  chains        {mpp} mutations/pixel{}{}{}{}",
            given("bootstrap", c.bootstrap.map(|n| n.to_string())),
            given("chains per depth", c.chains.map(|n| n.to_string())),
            given("large step", c.large_step.map(|p| p.to_string())),
            given("sigma", c.sigma.map(|s| s.to_string())),
        );
    }
    if let Some(o) = &s.defaults.output {
        println!("  output        {}", o.display());
    }
    println!("  primitives    {}", s.geometry.prims.len());
    if let Some(info) = &loaded.info {
        println!("  files         {}", info.files);
        println!("  shapes        {} ({} triangles, {} instances)", info.shapes, info.triangles, info.instances);
        println!("  textures      {}", info.textures);
        let list = |m: &std::collections::BTreeMap<String, usize>| {
            m.iter().map(|(k, v)| format!("{k} {v}")).collect::<Vec<_>>().join(", ")
        };
        println!("  materials     {}", list(&info.materials));
        println!("  lights        {}", list(&info.lights));
    }
    let area = s.lights.iter().filter(|l| matches!(l, tempera::light::Light::Area(_))).count();
    println!("  emitters      {} lights in total ({area} area-light primitives)", s.lights.len());
    println!(
        "  load time     {:.3} s (parse and meshes), {:.3} s (scene build, {} accelerator)",
        loaded.load_seconds,
        loaded.build_seconds,
        s.accel_kind()
    );
    println!("  warnings      {}", loaded.warnings.len());
    for w in &loaded.warnings {
        println!("    {w}");
    }
    let ignored = loaded.info.as_ref().map_or(&[][..], |i| i.ignored.as_slice());
    if !ignored.is_empty() {
        println!("  ignored       {} parameters, on purpose:", ignored.len());
        for i in ignored {
            println!("    {i}");
        }
    }
    Ok(())
}
