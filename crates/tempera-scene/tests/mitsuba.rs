//! Mitsuba 0.6 loader tests on the project's own fixtures: document features, shapes of every
//! kind, BSDFs, emitters, camera conventions, diagnostics with file and line, strict mode, and
//! robustness against truncated and mutated input.

mod common;

use std::path::{Path, PathBuf};
use tempera::geometry::Shape;
use tempera::math::{Vec2, Vec3};
use tempera_scene::{LoadError, LoadOptions, load, load_mitsuba_str};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/mitsuba").join(name)
}

fn load_text(text: &str) -> Result<tempera_scene::LoadedScene, LoadError> {
    load_mitsuba_str(text, &fixture("mem.xml"), &LoadOptions::default())
}

fn wrap(body: &str) -> String {
    format!("<scene version=\"0.6.0\">\n<sensor type=\"perspective\"/>\n{body}\n</scene>")
}

fn error(text: &str) -> String {
    match load_text(text) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn full_fixture_loads_every_feature() {
    let loaded = load(&fixture("full.xml"), &LoadOptions::default()).unwrap();
    assert!(loaded.warnings.is_empty(), "{:#?}", loaded.warnings);
    let info = &loaded.info;
    assert_eq!(info.files, 2, "the include counts");
    assert_eq!((info.shapes, info.instances), (10, 2), "nine scene shapes plus the group's disk, placed twice");
    for (light, n) in [("area", 1), ("constant", 1), ("point", 1), ("directional", 1)] {
        assert_eq!(info.lights.get(light), Some(&n), "{light}");
    }
    let scene = loaded.builder.build().unwrap();
    assert_eq!((scene.film.width, scene.film.height, scene.defaults.spp), (64, 48, 8), "$spp substituted");
    assert_eq!(scene.defaults.max_depth, 5, "Mitsuba's maxDepth 6 is 5 scattering events");
    assert_eq!(scene.film.filter, tempera::film::Filter::Box { radius: 0.5 });
    assert_eq!((scene.geometry.prototypes.len(), scene.geometry.instances.len()), (1, 2));

    // Camera: looks down -z from (0, 1, 5); the fov spans x; world +x appears on the right.
    let center = scene.camera.generate_ray(Vec2::new(32.0, 24.0), Vec2::splat(0.5));
    assert!((center.o - Vec3::new(0.0, 1.0, 5.0)).length() < 1e-5 && (center.d + Vec3::Z).length() < 1e-5);
    let left = scene.camera.generate_ray(Vec2::new(0.0, 24.0), Vec2::splat(0.5));
    assert!(left.d.x < 0.0, "raster left is world -x");
    assert!((left.d.dot(-Vec3::Z).acos().to_degrees() - 22.5).abs() < 1e-3, "fov 45 spans x");

    // $radius substituted into an analytic sphere; the non-uniformly scaled one is tessellated.
    let spheres: Vec<_> =
        scene.geometry.shapes.iter().filter_map(|s| if let Shape::Sphere(s) = s { Some(*s) } else { None }).collect();
    assert_eq!(spheres.len(), 1);
    assert!((spheres[0].center - Vec3::new(-1.0, 0.5, 0.0)).length() < 1e-6 && spheres[0].radius == 0.5);
    // The rotated floor faces up, the light rectangle down; the serialized mesh is index 1.
    let mesh_with = |pred: &dyn Fn(&tempera::geometry::TriangleMesh) -> bool| {
        scene.geometry.shapes.iter().any(|s| matches!(s, Shape::Mesh(m) if pred(m)))
    };
    assert!(mesh_with(
        &|m| m.positions.iter().all(|p| p.y.abs() < 1e-5) && m.surface(0, Vec3::splat(1.0 / 3.0)).ng.y > 0.99
    ));
    assert!(mesh_with(
        &|m| m.positions.iter().all(|p| (p.y - 3.0).abs() < 1e-5) && m.surface(0, Vec3::splat(1.0 / 3.0)).ng.y < -0.99
    ));
    assert!(mesh_with(&|m| m.positions.len() == 3 && m.positions.iter().all(|p| p.z == 3.0)));
    use tempera::material::Material;
    let count = |f: &dyn Fn(&Material) -> bool| scene.materials.iter().filter(|m| f(m)).count();
    assert_eq!(count(&|m| matches!(m, Material::Conductor(_))), 1, "gold is shared by the sphere and the OBJ");
    assert_eq!(count(&|m| matches!(m, Material::Dielectric(d) if (d.eta - 1.5046).abs() < 1e-4)), 1);
    assert_eq!(count(&|m| matches!(m, Material::Plastic(_))), 1);
}

#[test]
fn transforms_compose_in_document_order_and_matrices_are_row_major() {
    let text = wrap(
        "<shape type=\"sphere\"><transform name=\"toWorld\"><translate x=\"1\"/><scale value=\"2\"/></transform><bsdf type=\"diffuse\"/></shape>\n\
         <shape type=\"sphere\"><transform name=\"toWorld\"><matrix value=\"1 0 0 5  0 1 0 6  0 0 1 7  0 0 0 1\"/></transform><bsdf type=\"diffuse\"/></shape>",
    );
    let scene = load_text(&text).unwrap().builder.build().unwrap();
    let spheres: Vec<_> =
        scene.geometry.shapes.iter().filter_map(|s| if let Shape::Sphere(s) = s { Some(*s) } else { None }).collect();
    assert_eq!(spheres[0].center, Vec3::new(2.0, 0.0, 0.0), "translate, then scale");
    assert_eq!(spheres[0].radius, 2.0);
    assert_eq!(spheres[1].center, Vec3::new(5.0, 6.0, 7.0));
}

#[test]
fn errors_name_file_and_line() {
    let cases = [
        ("<scene version=\"0.6.0\">\n<shape type=\"sphere\">\n</scene>", "mem.xml:3:1: malformed XML"),
        (&wrap("<shape type=\"teapot\"/>") as &str, "mem.xml:3:1"),
        (&wrap("<shape type=\"obj\"><string name=\"filename\" value=\"nothere.obj\"/></shape>"), "nothere.obj"),
        (&wrap("<shape type=\"sphere\"><ref id=\"nope\"/></shape>"), "mem.xml:3:22: unknown BSDF \"nope\""),
        (
            &wrap("<bsdf type=\"diffuse\" id=\"a\"><ref name=\"reflectance\" id=\"tex\"/></bsdf>"),
            "unknown texture \"tex\"",
        ),
        (
            &wrap("<shape type=\"sphere\"><float name=\"radius\" value=\"$r\"/></shape>"),
            "\"$r\" has no <default> value",
        ),
        (
            &wrap("<bsdf type=\"conductor\" id=\"c\"><string name=\"material\" value=\"Unobtainium\"/></bsdf>"),
            "unknown conductor material",
        ),
        (&wrap("<medium type=\"homogeneous\" id=\"m\"/>"), "needs sigmaA and sigmaS"),
        (&wrap("<medium type=\"heterogeneous\" id=\"m\"/>"), "medium \"heterogeneous\" is not supported"),
        (&wrap("<shape type=\"sphere\"><ref name=\"interior\" id=\"nope\"/></shape>"), "unknown medium \"nope\""),
        ("<scene version=\"3.0.0\"/>", "Mitsuba 3 scenes"),
        ("<notascene/>", "expected <scene>"),
        (&wrap("<include filename=\"missing.xml\"/>"), "missing.xml"),
    ];
    for (text, want) in cases {
        let err = error(text);
        assert!(err.contains(want), "for {text:?}\n  got:  {err}\n  want: {want}");
    }
}

#[test]
fn unused_properties_and_approximations_warn_or_fail_in_strict_mode() {
    let text = wrap(
        "<shape type=\"sphere\"><float name=\"radius\" value=\"1\"/><float name=\"bogus\" value=\"2\"/>\n\
         <bsdf type=\"roughconductor\"><string name=\"distribution\" value=\"beckmann\"/></bsdf></shape>",
    );
    let loaded = load_text(&text).unwrap();
    let w: Vec<String> = loaded.warnings.iter().map(ToString::to_string).collect();
    assert_eq!(w.len(), 2, "{w:#?}");
    assert!(w.iter().any(|m| m.contains("beckmann")), "{w:#?}");
    assert!(w.iter().any(|m| m.contains("mem.xml:3:") && m.contains("unused property \"bogus\"")), "{w:#?}");
    let strict = load_mitsuba_str(&text, &fixture("mem.xml"), &LoadOptions { strict: true }).unwrap_err();
    assert!(strict.to_string().contains("mem.xml:"), "{strict}");
}

#[test]
fn one_sided_bsdfs_and_twosided_wrappers() {
    let text = wrap(
        "<shape type=\"rectangle\"><bsdf type=\"diffuse\"/></shape>\n\
         <shape type=\"rectangle\"><transform name=\"toWorld\"><translate z=\"-1\"/></transform><bsdf type=\"twosided\"><bsdf type=\"diffuse\"/></bsdf></shape>",
    );
    let scene = load_text(&text).unwrap().builder.build().unwrap();
    let f = |z0: f32, dz: f32| {
        let ray = tempera::geometry::Ray::new(Vec3::new(0.2, 0.1, z0), Vec3::new(0.0, 0.0, dz));
        let it = scene.intersect(&ray).unwrap();
        scene.bsdf(&it).eval(it.wo, it.wo, tempera::bsdf::TransportMode::Radiance).x
    };
    assert!(f(1.0, -1.0) > 0.0, "front of the one-sided rectangle");
    assert_eq!(f(-0.5, 1.0), 0.0, "back of the one-sided rectangle is black");
    assert!(f(-2.0, 1.0) > 0.0, "back of the two-sided rectangle reflects");
}

#[test]
fn truncated_and_mutated_input_never_panics() {
    let path = fixture("full.xml");
    let text = std::fs::read_to_string(&path).unwrap();
    common::load_truncated_and_mutated(
        &text,
        5,
        (7, 3),
        &['<', '>', '"', '/', '=', '-', '0', '9', '.', ' ', 'x', '$', '#'],
        |s| load_mitsuba_str(s, &path, &LoadOptions::default()),
    );
}

#[test]
fn unknown_plugins_are_errors_and_unsupported_ones_warnings() {
    assert!(error(&wrap("<texture type=\"noise\" id=\"t\"/>")).contains("unknown texture plugin \"noise\""));
    assert!(error(&wrap("<bsdf type=\"velvet\" id=\"b\"/>")).contains("unknown bsdf plugin \"velvet\""));
    let loaded = load_text(&wrap("<texture type=\"wireframe\" id=\"t\"/><bsdf type=\"ward\" id=\"b\"/>")).unwrap();
    assert_eq!(loaded.warnings.len(), 2, "{:?}", loaded.warnings);
}

#[test]
fn envmap_follows_mitsubas_latitude_longitude_orientation() {
    // A 16×8 map, black but for one texel at u ≈ 0.281, v ≈ 0.3125.
    let (w, h, tx, ty) = (16usize, 8usize, 4usize, 2usize);
    let mut px = vec![tempera::math::Rgb::ZERO; w * h];
    px[ty * w + tx] = tempera::math::Rgb::ONE;
    let dir = std::env::temp_dir().join(format!("tempera-envmap-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    tempera_image::write_image(&dir.join("env.pfm"), &tempera::texture::Image::new(w, h, px), &Default::default())
        .unwrap();
    let text = wrap(
        "<emitter type=\"envmap\"><string name=\"filename\" value=\"env.pfm\"/><float name=\"scale\" value=\"2\"/></emitter>",
    );
    let loaded = load_mitsuba_str(&text, &dir.join("scene.xml"), &LoadOptions::default()).unwrap();
    let scene = loaded.builder.build().unwrap();
    let light = &scene.lights[0];
    let (u, v) = ((tx as f32 + 0.5) / w as f32, (ty as f32 + 0.5) / h as f32);
    let (phi, theta) = (u * std::f32::consts::TAU, v * std::f32::consts::PI);
    let d = Vec3::new(phi.sin() * theta.sin(), theta.cos(), -phi.cos() * theta.sin());
    assert_eq!(light.le(d), tempera::math::Rgb::splat(2.0), "Mitsuba's direction for the texel");
    assert_eq!(light.le(Vec3::new(-d.x, d.y, d.z)), tempera::math::Rgb::ZERO, "not mirrored");
    assert_eq!(light.le(-d), tempera::math::Rgb::ZERO);
}

#[test]
fn sunsky_places_the_sun_from_date_and_location() {
    let text = wrap(
        "<emitter type=\"sunsky\"><float name=\"hour\" value=\"12\"/><float name=\"latitude\" value=\"0\"/>\
        <float name=\"longitude\" value=\"0\"/><float name=\"timezone\" value=\"0\"/><integer name=\"month\" value=\"3\"/>\
        <integer name=\"day\" value=\"20\"/></emitter>",
    );
    let scene = load_text(&text).unwrap().builder.build().unwrap();
    let sun = scene
        .lights
        .iter()
        .find_map(|l| if let tempera::light::Light::Distant(d) = l { Some(d.clone()) } else { None })
        .unwrap();
    assert!(sun.to_light.y > 0.995, "equinox noon on the equator: the sun is overhead ({})", sun.to_light);
    assert!(scene.lights.iter().any(|l| l.is_infinite()), "and the sky is an environment light");
}

#[test]
fn deliberately_ignored_properties_are_listed_with_their_reason_not_warned() {
    let text = wrap(
        "<integrator type=\"path\">\n<integer name=\"rrDepth\" value=\"5\"/>\n<integer name=\"bogus\" value=\"1\"/>\n</integrator>",
    );
    let loaded = load_text(&text).unwrap();
    assert_eq!(loaded.info.ignored.len(), 1, "{:?}", loaded.info.ignored);
    let ignored = &loaded.info.ignored[0];
    assert!(
        ignored.contains("mem.xml:4:") && ignored.contains("\"rrDepth\"") && ignored.contains("sample"),
        "{ignored}"
    );
    assert_eq!(loaded.warnings.len(), 1, "the unknown property still warns: {:?}", loaded.warnings);
    assert!(loaded.warnings[0].message.contains("\"bogus\""), "{:?}", loaded.warnings);
}

/// Mitsuba's homogeneous media: `sigmaA`/`sigmaS` or `sigmaT`/`albedo` times `scale`, the `hg`
/// phase function's `g`, a shape's `interior`/`exterior` by reference or nested, a boundary
/// without a BSDF made index-matched, and the sensor's medium.
#[test]
fn homogeneous_media_load_with_shapes_and_the_sensor() {
    let text = format!(
        "<scene version=\"0.6.0\">\n{}\n</scene>",
        "<medium type=\"homogeneous\" id=\"fog\"><rgb name=\"sigmaA\" value=\"0.1, 0.2, 0.3\"/>\
         <rgb name=\"sigmaS\" value=\"1, 1, 1\"/><float name=\"scale\" value=\"2\"/>\
         <phase type=\"hg\"><float name=\"g\" value=\"0.5\"/></phase></medium>\n\
         <sensor type=\"perspective\"><ref id=\"fog\"/></sensor>\n\
         <shape type=\"sphere\"><ref name=\"exterior\" id=\"fog\"/>\
         <medium name=\"interior\" type=\"homogeneous\"><rgb name=\"sigmaT\" value=\"4, 4, 4\"/>\
         <rgb name=\"albedo\" value=\"0.25, 0.5, 1\"/></medium></shape>"
    );
    let loaded = load_mitsuba_str(&text, Path::new("mem.xml"), &LoadOptions::default()).unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let scene = loaded.builder.build().unwrap();
    assert_eq!(scene.media.len(), 2);
    assert!((scene.media[0].sigma_a.z - 0.6).abs() < 1e-6 && (scene.media[0].g - 0.5).abs() < 1e-6);
    assert!((scene.media[1].sigma_s - tempera::math::Vec3::new(1.0, 2.0, 4.0)).length() < 1e-6);
    assert!((scene.media[1].sigma_a.x - 3.0).abs() < 1e-6);
    assert_eq!(scene.camera_medium, Some(0));
    assert!(matches!(scene.materials[0], tempera::material::Material::Interface), "{:?}", scene.materials);
}

/// Mitsuba's `sppm` selects Tempera's with its photon count and initial radius; the automatic
/// radius (0) is reported.
#[test]
fn the_sppm_integrator_keeps_its_photon_count_and_radius() {
    let text = wrap(
        "<integrator type=\"sppm\"><integer name=\"photonCount\" value=\"4000\"/>\
         <float name=\"initialRadius\" value=\"0.02\"/><integer name=\"maxDepth\" value=\"6\"/></integrator>",
    );
    let loaded = load_text(&text).unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let d = loaded.builder.build().unwrap().defaults;
    assert_eq!(d.integrator, Some(tempera::integrator::IntegratorKind::Sppm));
    assert_eq!((d.photons, d.radius, d.max_depth), (Some(4000), Some(0.02), 5));
    let auto = load_text(&wrap("<integrator type=\"sppm\"/>")).unwrap();
    assert!(auto.warnings.iter().any(|w| w.message.contains("automatic initial radius")), "{:?}", auto.warnings);
}

/// Mitsuba's `pssmlt` renders by Tempera's PSSMLT with its `luminanceSamples` as the bootstrap
/// and `pLarge` as the large-step probability (Mitsuba's defaults 100,000 and 0.3 where absent);
/// a probability out of range is an error.
#[test]
fn the_pssmlt_integrator_keeps_its_bootstrap_and_large_step_probability() {
    let text = wrap(
        "<integrator type=\"pssmlt\"><integer name=\"luminanceSamples\" value=\"5000\"/>\
         <float name=\"pLarge\" value=\"0.2\"/></integrator>",
    );
    let loaded = load_text(&text).unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let d = loaded.builder.build().unwrap().defaults;
    assert_eq!(d.integrator, Some(tempera::integrator::IntegratorKind::Pssmlt));
    assert_eq!((d.chain.bootstrap, d.chain.large_step, d.chain.mpp), (Some(5000), Some(0.2), None));
    let plain = load_text(&wrap("<integrator type=\"pssmlt\"/>")).unwrap().builder.build().unwrap().defaults;
    assert_eq!((plain.chain.bootstrap, plain.chain.large_step), (Some(100_000), Some(0.3)));
    let bad = load_text(&wrap("<integrator type=\"pssmlt\"><float name=\"pLarge\" value=\"0\"/></integrator>"));
    assert!(bad.err().unwrap().to_string().contains("pLarge must lie in (0, 1]"));
}
