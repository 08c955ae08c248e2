//! pbrt-v4 loader tests on the project's own fixtures: syntax, graphics state, every supported
//! directive family, diagnostics with file/line/column, strict mode, and robustness against
//! truncated and mutated input.

mod common;

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use tempera::geometry::Shape;
use tempera::integrator::{Budget, Integrator, PathIntegrator, RenderControl, RenderSettings};
use tempera::math::{Vec2, Vec3};
use tempera_scene::{LoadError, LoadOptions, load, load_pbrt_str};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/pbrt").join(name)
}

fn load_text(text: &str) -> Result<tempera_scene::LoadedScene, LoadError> {
    load_pbrt_str(text, &fixture("mem.pbrt"), &LoadOptions::default())
}

fn error(text: &str) -> String {
    match load_text(text) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn full_fixture_loads_every_directive_family() {
    let loaded = load(&fixture("full.pbrt"), &LoadOptions::default()).unwrap();
    let messages: Vec<String> = loaded.warnings.iter().map(ToString::to_string).collect();
    assert!(messages.is_empty(), "everything in the fixture is supported exactly: {messages:#?}");

    let info = &loaded.info;
    assert_eq!(info.files, 2, "the include counts");
    // The object's quad is stored once and placed twice.
    assert_eq!((info.shapes, info.instances, info.textures), (7, 2, 3));
    assert_eq!(info.materials.get("conductor"), Some(&2));
    assert_eq!(info.materials.get("dielectric"), Some(&1));
    for light in ["infinite", "distant", "point", "spot"] {
        assert_eq!(info.lights.get(light), Some(&1), "{light}");
    }

    let scene = loaded.builder.build().unwrap();
    assert_eq!((scene.geometry.prototypes.len(), scene.geometry.instances.len()), (1, 2), "instances share geometry");
    assert_eq!((scene.film.width, scene.film.height), (64, 48));
    assert_eq!((scene.defaults.spp, scene.defaults.max_depth), (8, 7));
    assert_eq!(scene.defaults.output.as_deref(), Some(std::path::Path::new("fixture.exr")));
    assert_eq!(scene.defaults.integrator, Some(tempera::integrator::IntegratorKind::Path));

    // LookAt: the image centre looks down -z from (0, 1, 5).
    let ray = scene.camera.generate_ray(Vec2::new(32.0, 24.0), Vec2::splat(0.5));
    assert!((ray.o - Vec3::new(0.0, 1.0, 5.0)).length() < 1e-5);
    assert!((ray.d - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-5, "{}", ray.d);

    // Whole spheres under a similarity stay analytic; the disk light faces down after Rotate.
    let gold = scene.geometry.shapes.iter().find_map(|s| match s {
        Shape::Sphere(s) if (s.center - Vec3::new(-1.0, 0.5, 0.0)).length() < 1e-5 => Some(*s),
        _ => None,
    });
    assert_eq!(gold.map(|s| s.radius), Some(0.5));
    let disk = scene.geometry.shapes.iter().find_map(|s| if let Shape::Disk(d) = s { Some(*d) } else { None }).unwrap();
    assert!((disk.center - Vec3::new(0.0, 3.0, 0.0)).length() < 1e-5);
    assert!((disk.frame.n - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-5, "{}", disk.frame.n);
    // Emitters: the disk (one area light) plus the four light sources.
    assert_eq!(scene.lights.len(), 5);

    let cancel = AtomicBool::new(false);
    let control = RenderControl::new(&cancel, &|_| {});
    let mut scene = scene;
    scene.set_resolution(16, 12);
    let out = PathIntegrator::new(5)
        .render(&scene, &RenderSettings { budget: Budget::Samples(2), seed: 1, threads: 1 }, &control)
        .expect("the scene renders");
    assert!(out.image.pixels.iter().all(|p| p.is_finite()));
    assert!(out.image.pixels.iter().any(|p| p.max_element() > 0.0));
}

#[test]
fn transforms_compose_like_pbrt() {
    let text = "Translate 1 0 0\nScale 2 2 2\nTransformBegin\nTranslate 0 1 0\nTransformEnd\n\
                Camera \"perspective\"\nWorldBegin\nConcatTransform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 3 1]\n\
                CoordinateSystem \"here\"\nIdentity\nCoordSysTransform \"here\"\nShape \"sphere\"\n\
                Transform 1 0 0 0 0 1 0 0 0 0 1 0 5 0 0 1\nShape \"sphere\"";
    let scene = load_text(text).unwrap().builder.build().unwrap();
    let centers: Vec<Vec3> = scene
        .geometry
        .shapes
        .iter()
        .filter_map(|s| if let Shape::Sphere(s) = s { Some(s.center) } else { None })
        .collect();
    assert_eq!(centers, vec![Vec3::new(0.0, 0.0, 3.0), Vec3::new(5.0, 0.0, 0.0)]);
    // The camera sees through the CTM at Camera: translate then scale (TransformEnd restored it).
    let ray = scene.camera.generate_ray(Vec2::new(640.0, 360.0), Vec2::splat(0.5));
    assert!((ray.o - Vec3::new(-0.5, 0.0, 0.0)).length() < 1e-5, "{}", ray.o);
}

#[test]
fn syntax_errors_name_file_line_and_column() {
    let cases = [
        ("Shape \"sphere\" \"float radius\" [ 1", "mem.pbrt:1:16: unterminated '['"),
        ("Translate 1 2", "mem.pbrt:1:1"),
        ("\nShape \"sphere\" \"flaot radius\" 1", "mem.pbrt:2:16: unknown parameter type 'flaot'"),
        ("NamedMaterial \"nope\"", "mem.pbrt:1:15: unknown material \"nope\""),
        ("AttributeEnd", "mem.pbrt:1:1: AttributeEnd without AttributeBegin"),
        ("AttributeBegin\nShape \"sphere\"", "mem.pbrt:1:1: AttributeBegin without a matching end"),
        ("Shape \"sphere\" \"float radius\" \"abc\"", "\"float\" parameter cannot hold strings"),
        ("Camera \"orthographic\"", "camera \"orthographic\" is not supported"),
        ("MakeNamedMedium \"fog\" \"string type\" \"cloud\"", "mem.pbrt:1:17: heterogeneous medium \"fog\""),
        ("\"float fov\" 30", "mem.pbrt:1:1: expected a directive, found string"),
        (
            "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 5]",
            "vertex index 5 out of range",
        ),
        ("Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"nothere.png\"", "nothere.png"),
        ("Shape \"plymesh\" \"string filename\" \"nothere.ply\"", "nothere.ply"),
        ("Translate 1 2 3x", "mem.pbrt:1:15: expected a number, found '3x'"),
        ("LightSource \"goniometric\"", "\"goniometric\" lights are not supported"),
    ];
    for (text, want) in cases {
        let err = error(text);
        assert!(err.contains(want), "for {text:?}\n  got:  {err}\n  want: {want}");
    }
    let err = error("WorldBegin\n  Include \"missing.pbrt\"");
    assert!(err.contains("mem.pbrt:2:11") && err.contains("missing.pbrt"), "{err}");
}

#[test]
fn unknown_directives_and_unused_parameters_warn_or_fail_in_strict_mode() {
    let text =
        "Frobnicate 1 2 \"x\" [ 3 ]\nCamera \"perspective\"\nShape \"sphere\" \"float radius\" 1 \"float bogus\" 2";
    let loaded = load_text(text).unwrap();
    let w: Vec<String> = loaded.warnings.iter().map(ToString::to_string).collect();
    assert_eq!(w.len(), 2, "{w:#?}");
    assert!(w[0].contains("mem.pbrt:1:1: unknown directive 'Frobnicate'"), "{}", w[0]);
    assert!(w[1].contains("mem.pbrt:3:33: unused parameter \"float bogus\" in Shape \"sphere\""), "{}", w[1]);
    assert_eq!(loaded.info.shapes, 1, "loading continued after the unknown directive");
    let strict = load_pbrt_str(text, &fixture("mem.pbrt"), &LoadOptions { strict: true }).unwrap_err();
    assert!(strict.to_string().contains("mem.pbrt:1:1: unknown directive"), "{strict}");
}

#[test]
fn emission_follows_pbrt_units() {
    let text = "Camera \"perspective\"\nWorldBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 2 3] \"float scale\" 2 \"bool twosided\" true\n\
                Shape \"sphere\"\nLightSource \"point\" \"blackbody I\" 3000\n";
    let scene = load_text(text).unwrap().builder.build().unwrap();
    let area = scene
        .lights
        .iter()
        .find_map(|l| if let tempera::light::Light::Area(a) = l { Some(a.clone()) } else { None })
        .unwrap();
    assert_eq!(area.radiance.as_constant(), Some(Vec3::new(1.0, 2.0, 3.0)), "RGB emission is used as given");
    assert_eq!(area.scale, 2.0);
    assert!(area.two_sided);
    let point = scene
        .lights
        .iter()
        .find_map(|l| if let tempera::light::Light::Point(p) = l { Some(p.clone()) } else { None })
        .unwrap();
    assert!((tempera::math::luminance(point.intensity) - 1.0).abs() < 0.02, "blackbody has unit luminance");
    assert!(point.intensity.x > point.intensity.z, "3000 K is warm");
}

#[test]
fn truncated_and_mutated_input_never_panics() {
    let path = fixture("full.pbrt");
    let text = std::fs::read_to_string(&path).unwrap();
    common::load_truncated_and_mutated(
        &text,
        3,
        (99, 1),
        &['[', ']', '"', '#', '-', '0', '9', '.', 'e', ' ', '\n', 'x', '\\'],
        |s| load_pbrt_str(s, &path, &LoadOptions::default()),
    );
}

#[test]
fn mix_diffusetransmission_bump_and_alpha_load_without_approximation() {
    let text = "Camera \"perspective\"\nWorldBegin\n\
        Texture \"bumps\" \"float\" \"checkerboard\" \"float tex1\" 0 \"float tex2\" 0.01\n\
        MakeNamedMaterial \"a\" \"string type\" \"diffuse\"\n\
        MakeNamedMaterial \"b\" \"string type\" \"conductor\" \"spectrum reflectance\" [ 400 0.9 700 0.9 ]\n\
        MakeNamedMaterial \"m\" \"string type\" \"mix\" \"string materials\" [ \"a\" \"b\" ] \"float amount\" 0.3\n\
        Material \"diffusetransmission\" \"rgb transmittance\" [ 0.5 0.4 0.3 ] \"texture displacement\" \"bumps\"\n\
        Shape \"sphere\" \"float alpha\" 0.5\n\
        NamedMaterial \"m\"\nShape \"disk\"\n";
    let loaded = load_text(text).unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let scene = loaded.builder.build().unwrap();
    use tempera::material::{ConductorFresnel, Material};
    let mix =
        scene.materials.iter().find_map(|m| if let Material::Mix(m) = m { Some(m.clone()) } else { None }).unwrap();
    assert_eq!(mix.amount.as_constant(), Some(Vec3::splat(0.3)));
    assert!(matches!(&scene.materials[mix.materials[0] as usize], Material::Diffuse(_)));
    match &scene.materials[mix.materials[1] as usize] {
        Material::Conductor(c) => match &c.fresnel {
            ConductorFresnel::Reflectance(r) => {
                assert!((r.as_constant().unwrap() - Vec3::splat(0.9)).abs().max_element() < 1e-3)
            }
            other => panic!("expected the reflectance parametrisation, got {other:?}"),
        },
        other => panic!("expected a conductor, got {other:?}"),
    }
    assert!(scene.materials.iter().any(|m| matches!(m, Material::DiffuseTransmission(d)
        if d.transmittance.as_constant() == Some(Vec3::new(0.5, 0.4, 0.3)))));
}

#[test]
fn spectrum_files_are_read_relative_to_the_scene() {
    let text = "Camera \"perspective\"\nWorldBegin\nMaterial \"diffuse\" \"spectrum reflectance\" \"flat.spd\"\nShape \"sphere\"";
    let scene = load_text(text).unwrap().builder.build().unwrap();
    let Some(tempera::material::Material::Diffuse(d)) = scene.materials.last() else { panic!("diffuse expected") };
    let c = d.reflectance.as_constant().unwrap();
    assert!((c - Vec3::splat(0.25)).abs().max_element() < 1e-3, "{c}");
    let err = error("Material \"diffuse\" \"spectrum reflectance\" \"nothing.spd\"");
    assert!(err.contains("neither a named spectrum nor a readable spectrum file"), "{err}");
}

/// pbrt-v4's layered materials keep every parameter pbrt-v4 reads: the coat's roughness
/// (remapped unless told otherwise) and index, the slab's thickness, albedo and `g`, the walk's
/// depth and samples; `coatedconductor`'s conductor is taken relative to the coat's index, and
/// `reflectance` replaces its `eta`/`k`. Nonsense values are errors naming the line.
#[test]
fn layered_materials_keep_every_parameter() {
    use tempera::bsdf::{Bsdf, LayeredBase};
    let scene = |material: &str| {
        let text = format!(
            "Camera \"perspective\"\nWorldBegin\n{material}\n\
             Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n"
        );
        let scene = load_text(&text).unwrap().builder.build().unwrap();
        assert!(matches!(scene.materials[0], tempera::material::Material::Layered(_)), "{material}");
        match scene.materials[0].bsdf(Vec2::splat(0.5)) {
            Bsdf::Layered(b) => b,
            other => panic!("{material}: {other:?}"),
        }
    };
    let d = scene(
        "Material \"coateddiffuse\" \"rgb reflectance\" [0.2 0.4 0.6] \"float roughness\" 0.25 \
         \"float thickness\" 0.05 \"rgb albedo\" [0.5 0.5 0.5] \"float g\" 0.3 \"integer maxdepth\" 7 \
         \"integer nsamples\" 4 \"float eta\" 1.33",
    );
    let LayeredBase::Diffuse(base) = d.base else { panic!("{:?}", d.base) };
    assert!((base.reflectance.z - 0.6).abs() < 1e-6);
    assert!((d.top.eta - 1.33).abs() < 1e-6 && (d.top.distribution.alpha_x - 0.5).abs() < 1e-6, "{:?}", d.top);
    assert!((d.thickness - 0.05).abs() < 1e-6 && (d.albedo.x - 0.5).abs() < 1e-6 && (d.g - 0.3).abs() < 1e-6);
    assert_eq!((d.max_depth, d.samples), (7, 4));
    // pbrt-v4's defaults: thickness 0.01, no medium, 10 events, one sample, index 1.5, smooth.
    let d = scene("Material \"coateddiffuse\"");
    assert!((d.thickness - 0.01).abs() < 1e-6 && d.albedo.max_element() == 0.0 && (d.top.eta - 1.5).abs() < 1e-6);
    assert_eq!((d.max_depth, d.samples), (10, 1));

    let c = scene(
        "Material \"coatedconductor\" \"float interface.eta\" 2 \"float interface.roughness\" 0.01 \
         \"float conductor.uroughness\" 0.2 \"float conductor.vroughness\" 0.3 \"bool remaproughness\" false \
         \"rgb conductor.eta\" [0.2 0.4 0.8] \"rgb conductor.k\" [3 4 5]",
    );
    let LayeredBase::Conductor(base) = c.base else { panic!("{:?}", c.base) };
    assert!((c.top.eta - 2.0).abs() < 1e-6 && (c.top.distribution.alpha_x - 0.01).abs() < 1e-6);
    assert!((base.distribution.alpha_x - 0.2).abs() < 1e-6 && (base.distribution.alpha_y - 0.3).abs() < 1e-6);
    assert!((base.eta.z - 0.4).abs() < 1e-6 && (base.k.x - 1.5).abs() < 1e-6, "relative to the coat: {base:?}");
    let c = scene("Material \"coatedconductor\" \"rgb reflectance\" [0.5 0.5 0.5]");
    let LayeredBase::Conductor(base) = c.base else { panic!("{:?}", c.base) };
    let k = 2.0 * 0.5f32.sqrt() / 0.5f32.sqrt() / 1.5;
    assert!((base.eta.x - 1.0 / 1.5).abs() < 1e-5 && (base.k.x - k).abs() < 1e-4, "{base:?}");

    for (material, expect) in [
        ("\"coateddiffuse\" \"integer maxdepth\" 0", "maxdepth"),
        ("\"coateddiffuse\" \"integer nsamples\" -2", "nsamples"),
        ("\"coatedconductor\" \"rgb reflectance\" [0.5 0.5 0.5] \"rgb conductor.k\" [1 1 1]", "not both"),
    ] {
        let e = error(&format!("WorldBegin\nMaterial {material}\n"));
        assert!(e.contains("mem.pbrt:2:") && e.contains(expect), "{e}");
    }
}

/// pbrt-v4's homogeneous media: `MakeNamedMedium` with its coefficients, `scale` and `g`; the
/// camera in the outside medium current at `Camera` (defined later in the file); an
/// `interface` shape bounding a medium; glass with a medium inside. Heterogeneous media,
/// presets and unknown names are errors naming the line.
#[test]
fn homogeneous_media_load_with_their_interfaces() {
    let text = "MediumInterface \"\" \"fog\"\nCamera \"perspective\"\n\
        MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.1 0.2 0.3] \
        \"rgb sigma_s\" [1 2 3] \"float scale\" 2 \"float g\" 0.4\n\
        MakeNamedMedium \"ink\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [5 5 5] \"rgb sigma_s\" [0 0 0]\n\
        WorldBegin\n\
        AttributeBegin\n MediumInterface \"ink\" \"fog\"\n Material \"interface\"\n Shape \"sphere\"\nAttributeEnd\n\
        AttributeBegin\n MediumInterface \"ink\" \"fog\"\n Material \"dielectric\"\n Translate 3 0 0\n Shape \"sphere\"\nAttributeEnd\n\
        AttributeBegin\n MediumInterface \"\" \"fog\"\n LightSource \"point\"\nAttributeEnd\n\
        MediumInterface \"\" \"\"\nMaterial \"interface\"\n Shape \"sphere\" \"float radius\" 9\n\
        LightSource \"point\" \"point3 from\" [0 5 0]\n";
    let loaded = load_text(text).unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let scene = loaded.builder.build().unwrap();
    assert_eq!(scene.media.len(), 2);
    let fog = scene.media[0];
    assert!((fog.sigma_a - Vec3::new(0.2, 0.4, 0.6)).length() < 1e-6 && (fog.sigma_s.z - 6.0).abs() < 1e-6);
    assert!((fog.g - 0.4).abs() < 1e-6);
    assert_eq!(scene.camera_medium, Some(0));
    // The interface sphere and the glass sphere bound media; the last interface sphere bounds
    // none (the MediumInterface before it names none) and is dropped: pbrt-v4 makes it invisible.
    assert_eq!(scene.geometry.shapes.len(), 2);
    let ray = tempera::geometry::Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, -1.0));
    let hit = scene.intersect(&ray).unwrap();
    assert!(scene.is_interface(&hit));
    assert_eq!(scene.medium_after(&hit, ray.d, Some(0)), Some(1), "entering the sphere enters the ink");
    let glass = scene.intersect(&tempera::geometry::Ray::new(Vec3::new(3.0, 0.0, 5.0), ray.d)).unwrap();
    assert!(!scene.is_interface(&glass));
    assert_eq!(scene.medium_after(&glass, -ray.d, Some(1)), Some(0), "leaving the glass enters the fog");
    // Lights sit in the outside medium current where they are defined.
    assert_eq!(scene.light_medium(0, Vec3::Z, Vec3::Z), Some(0), "the first light is in the fog");
    assert_eq!(scene.light_medium(1, Vec3::Z, Vec3::Z), None, "the second one in vacuum");

    for (bad, expect) in [
        ("MakeNamedMedium \"a\" \"string type\" \"uniformgrid\"", "heterogeneous medium \"a\""),
        ("MakeNamedMedium \"a\" \"string type\" \"homogeneous\" \"string preset\" \"Wholemilk\"", "preset"),
        ("MakeNamedMedium \"a\" \"string type\" \"homogeneous\" \"float g\" 1", "\"g\""),
        ("MediumInterface \"nope\" \"\"\nShape \"sphere\"", "mem.pbrt:3:7: unknown medium \"nope\""),
    ] {
        let e = error(&format!("WorldBegin\n{bad}\n"));
        assert!(e.contains("mem.pbrt:") && e.contains(expect), "{bad}: {e}");
    }
}

/// pbrt-v4's `sppm` integrator selects Tempera's with its photons per iteration and radius;
/// without them, one photon per pixel and radius 1 (pbrt-v4's defaults).
#[test]
fn the_sppm_integrator_keeps_its_photons_and_radius() {
    let loaded = load_text(
        "Integrator \"sppm\" \"float radius\" 0.05 \"integer photonsperiteration\" 5000 \"integer maxdepth\" 7 \
         \"integer seed\" 3\nCamera \"perspective\"\nWorldBegin\nShape \"sphere\"\n",
    )
    .unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let d = loaded.builder.build().unwrap().defaults;
    assert_eq!(d.integrator, Some(tempera::integrator::IntegratorKind::Sppm));
    assert_eq!((d.photons, d.radius, d.max_depth), (Some(5000), Some(0.05), 7));
    let plain = load_text("Integrator \"sppm\"\nCamera \"perspective\"\nWorldBegin\nShape \"sphere\"\n").unwrap();
    let d = plain.builder.build().unwrap().defaults;
    assert_eq!((d.photons, d.radius), (None, Some(1.0)));
    let bad = load_text("Integrator \"sppm\" \"float radius\" -1\nCamera \"perspective\"\nWorldBegin\n");
    assert!(bad.err().unwrap().to_string().contains("positive radius"));
}

/// pbrt-v4's `mlt` integrator selects MMLT with its parameters: mutations per pixel (pbrt-v4's
/// 100 where none is given), bootstrap samples, `chains` over all depths as Tempera's chains
/// per depth (rounded up), the large-step probability and `sigma`; `regularize`, which
/// Tempera does not have, is warned about, and values out of range are errors at their line.
#[test]
fn the_mlt_integrator_keeps_its_parameters() {
    let loaded = load_text(
        "Integrator \"mlt\" \"integer mutationsperpixel\" 256 \"integer bootstrapsamples\" 5000 \
         \"integer chains\" 100 \"float largestepprobability\" 0.2 \"float sigma\" 0.02 \"integer maxdepth\" 4\n\
         Camera \"perspective\"\nWorldBegin\nShape \"sphere\"\n",
    )
    .unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let d = loaded.builder.build().unwrap().defaults;
    assert_eq!(d.integrator, Some(tempera::integrator::IntegratorKind::Mmlt));
    let c = &d.chain;
    assert_eq!(
        (c.mpp, c.bootstrap, c.chains, c.large_step, c.sigma),
        (Some(256), Some(5000), Some(20), Some(0.2), Some(0.02))
    );
    let plain = load_text("Integrator \"mlt\" \"bool regularize\" true\nCamera \"perspective\"\nWorldBegin\n").unwrap();
    assert!(plain.warnings.iter().any(|w| w.to_string().contains("regularize")), "{:?}", plain.warnings);
    let c = plain.builder.build().unwrap().defaults.chain;
    assert_eq!((c.mpp, c.bootstrap, c.chains, c.large_step, c.sigma), (Some(100), None, None, None, None));
    let other = load_text("Integrator \"bdpt\"\nCamera \"perspective\"\nWorldBegin\n").unwrap();
    assert_eq!(other.builder.build().unwrap().defaults.chain, tempera::scene::ChainDefaults::default());
    for (params, needle) in [
        ("\"float sigma\" 0", "sigma 0 must lie in (0, 1]"),
        ("\"float largestepprobability\" 1.5", "largestepprobability 1.5"),
        ("\"integer chains\" 0", "chains 0 is out of range"),
        ("\"integer mutationsperpixel\" -3", "mutationsperpixel -3 is out of range"),
    ] {
        let e = error(&format!("Integrator \"mlt\" {params}\nCamera \"perspective\"\nWorldBegin\n"));
        assert!(e.contains(needle) && e.contains(":1:"), "{params}: {e}");
    }
}
