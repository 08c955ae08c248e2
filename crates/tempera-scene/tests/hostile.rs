//! Hostile scene input, kind by kind: every number of the pbrt-v4 and Mitsuba fixtures
//! replaced by NaN, infinities, overflowing, negative, zero and giant values; cyclic includes;
//! broken object instancing and material references; missing files; files of the wrong type;
//! deep nesting. Each case must load or fail with an error (never panic, never abort), errors
//! must say what is wrong, and what loads must build and render finite pixels with the path
//! tracer and BDPT. The test prints a table of cases and outcomes per kind, which the README's
//! reliability table quotes.

use std::collections::BTreeMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use tempera::integrator::{BdptIntegrator, Budget, Integrator, PathIntegrator, RenderControl, RenderSettings};
use tempera_scene::{LoadOptions, load, load_mitsuba_str, load_pbrt_str};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

/// What a case did.
enum Outcome {
    Error(String),
    Rendered,
}

/// Builds and renders a loaded scene small: finite pixels or a build error.
fn render(loaded: tempera_scene::LoadedScene) -> Outcome {
    let mut scene = match loaded.builder.build() {
        Ok(scene) => scene,
        Err(e) => return Outcome::Error(e.to_string()),
    };
    scene.set_resolution(8, 6);
    let cancel = AtomicBool::new(false);
    let control = RenderControl::new(&cancel, &|_| {});
    let settings = RenderSettings { budget: Budget::Samples(1), seed: 1, threads: 1 };
    let integrators: [Box<dyn Integrator>; 2] = [Box::new(PathIntegrator::new(4)), Box::new(BdptIntegrator::new(4))];
    for integrator in integrators {
        match integrator.render(&scene, &settings, &control) {
            Ok(out) => assert!(out.image.pixels.iter().all(|p| p.is_finite()), "a non-finite pixel"),
            Err(e) => return Outcome::Error(e.to_string()),
        }
    }
    Outcome::Rendered
}

/// Runs one case, turning a panic into a test failure that names the case.
fn attempt(label: &str, case: impl FnOnce() -> Outcome) -> Outcome {
    match catch_unwind(AssertUnwindSafe(case)) {
        Ok(outcome) => {
            if let Outcome::Error(e) = &outcome {
                assert!(!e.trim().is_empty(), "{label}: an empty error message");
            }
            outcome
        }
        Err(_) => panic!("{label}: panicked"),
    }
}

/// Counts per kind of input: cases, errors, renders.
#[derive(Default)]
struct Tally(BTreeMap<String, [usize; 3]>);

impl Tally {
    fn add(&mut self, kind: &str, outcome: &Outcome) {
        let row = self.0.entry(kind.to_owned()).or_default();
        row[0] += 1;
        row[if matches!(outcome, Outcome::Error(_)) { 1 } else { 2 }] += 1;
    }

    fn print(&self) {
        eprintln!("| kind | cases | errors | loaded and rendered |");
        for (kind, [cases, errors, rendered]) in &self.0 {
            eprintln!("| {kind} | {cases} | {errors} | {rendered} |");
        }
    }
}

/// Byte ranges of the numbers in `text` outside strings and comments (`#` for pbrt-v4; for
/// XML, only inside attribute values).
fn number_spans(text: &str, xml: bool) -> Vec<(usize, usize)> {
    let bytes = text.as_bytes();
    let (mut spans, mut i, mut quoted, mut comment) = (Vec::new(), 0, false, false);
    while i < bytes.len() {
        let c = bytes[i];
        if comment {
            comment = c != b'\n';
        } else if c == b'"' {
            quoted = !quoted;
        } else if !xml && !quoted && c == b'#' {
            comment = true;
        } else if quoted == xml && (c.is_ascii_digit() || c == b'-' || c == b'.') {
            let prev = if i > 0 { bytes[i - 1] } else { b' ' };
            if !prev.is_ascii_alphanumeric() && prev != b'_' && prev != b'-' && prev != b'.' {
                let mut end = i + 1;
                while end < bytes.len() && (bytes[end].is_ascii_digit() || b".eE".contains(&bytes[end])) {
                    end += 1;
                }
                if text[i..end].parse::<f64>().is_ok() {
                    spans.push((i, end));
                    i = end;
                    continue;
                }
            }
        }
        i += 1;
    }
    spans
}

/// What every number is replaced by, by kind.
const BAD_NUMBERS: [(&str, &[&str]); 4] = [
    ("NaN and infinite numbers", &["nan", "inf", "-inf", "1e39", "-1e39"]),
    ("negative numbers", &["-1", "-1e9"]),
    ("zero and denormal numbers", &["0", "-0", "1e-39"]),
    ("giant numbers and counts", &["4294967296", "1e300", "99999999999999999999"]),
];

fn replace_every_number(
    tally: &mut Tally,
    format: &str,
    text: &str,
    xml: bool,
    load_text: &dyn Fn(&str) -> Result<tempera_scene::LoadedScene, tempera_scene::LoadError>,
) {
    let spans = number_spans(text, xml);
    assert!(spans.len() > 40, "{format}: only {} numbers found", spans.len());
    for (kind, values) in BAD_NUMBERS {
        for &(start, end) in &spans {
            for value in values {
                let mutated = format!("{}{value}{}", &text[..start], &text[end..]);
                let label = format!("{format}: {:?} → {value} at byte {start}", &text[start..end]);
                // An abort (stack overflow) cannot be caught and named like a panic:
                // `HOSTILE_TRACE=1` prints each case before it runs, to find the one.
                if std::env::var_os("HOSTILE_TRACE").is_some() {
                    eprintln!("{label}");
                }
                let outcome = attempt(&label, || match load_text(&mutated) {
                    Ok(loaded) => render(loaded),
                    Err(e) => Outcome::Error(e.to_string()),
                });
                tally.add(&format!("{format}: {kind}"), &outcome);
            }
        }
    }
}

#[test]
fn every_number_replaced_by_a_hostile_value_loads_or_fails_cleanly() {
    let mut tally = Tally::default();
    let pbrt = fixtures().join("pbrt/full.pbrt");
    let text = std::fs::read_to_string(&pbrt).unwrap();
    replace_every_number(&mut tally, "pbrt-v4", &text, false, &|t| load_pbrt_str(t, &pbrt, &LoadOptions::default()));
    let xml = fixtures().join("mitsuba/full.xml");
    let text = std::fs::read_to_string(&xml).unwrap();
    replace_every_number(&mut tally, "Mitsuba", &text, true, &|t| load_mitsuba_str(t, &xml, &LoadOptions::default()));
    tally.print();
    // Some replacements must be refused: NaN and infinity never pass silently everywhere.
    for (kind, [cases, errors, _]) in &tally.0 {
        if kind.contains("NaN") {
            assert!(*errors > cases / 2, "{kind}: only {errors} of {cases} refused");
        }
    }
}

/// A folder of files for one structural case; the first file is the scene loaded.
fn scratch(case: &str, files: &[(&str, &[u8])]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tempera-hostile-{}-{case}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    for (name, contents) in files {
        let path = dir.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, contents).unwrap();
    }
    dir.join(files[0].0)
}

const PBRT_HEAD: &str = "Camera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 6\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n";
const XML_HEAD: &str = "<scene version=\"0.6.0\"><sensor type=\"perspective\"><film type=\"hdrfilm\"><integer name=\"width\" value=\"8\"/><integer name=\"height\" value=\"6\"/></film></sensor><emitter type=\"constant\"/>";

/// One structural case: its kind, a name, its files (the first is loaded), and what its error
/// must mention (`None`: it may load).
type Case = (&'static str, &'static str, Vec<(&'static str, Vec<u8>)>, Option<&'static str>);

fn pbrt(body: &str) -> Vec<u8> {
    format!("{PBRT_HEAD}{body}\n").into_bytes()
}

fn xml(body: &str) -> Vec<u8> {
    format!("{XML_HEAD}{body}</scene>\n").into_bytes()
}

fn png() -> Vec<u8> {
    let dir = std::env::temp_dir().join(format!("tempera-hostile-{}-png", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("a.png");
    let image = tempera::texture::Image::filled(2, 2, tempera::math::Rgb::splat(0.5));
    tempera_image::write_image(&path, &image, &tempera_image::WriteOptions::default()).unwrap();
    std::fs::read(path).unwrap()
}

fn structural_cases() -> Vec<Case> {
    let quad = std::fs::read(fixtures().join("pbrt/quad.ply")).unwrap();
    let deep_pbrt =
        format!("{}Shape \"sphere\"\n{}", "AttributeBegin\n".repeat(20_000), "AttributeEnd\n".repeat(20_000));
    let deep_xml = format!("{}{}", "<shape type=\"sphere\">".repeat(100_000), "</shape>".repeat(100_000));
    let garbage: Vec<u8> = (0..4096u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8).collect();
    vec![
        ("cyclic includes", "includes itself", vec![("a.pbrt", pbrt("Include \"a.pbrt\""))], Some("cycle")),
        (
            "cyclic includes",
            "two files include each other",
            vec![("a.pbrt", pbrt("Include \"b.pbrt\"")), ("b.pbrt", b"Include \"a.pbrt\"\n".to_vec())],
            Some("cycle"),
        ),
        ("cyclic includes", "imports itself", vec![("a.pbrt", pbrt("Import \"a.pbrt\""))], Some("cycle")),
        (
            "cyclic includes",
            "Mitsuba includes itself",
            vec![("a.xml", xml("<include filename=\"a.xml\"/>"))],
            Some("a.xml"),
        ),
        (
            "object instancing and references",
            "instance of an undefined object",
            vec![("a.pbrt", pbrt("ObjectInstance \"nothing\""))],
            Some("nothing"),
        ),
        (
            "object instancing and references",
            "object defined inside an object",
            vec![("a.pbrt", pbrt("ObjectBegin \"a\"\nObjectBegin \"b\"\nObjectEnd\nObjectEnd"))],
            Some("ObjectBegin"),
        ),
        ("object instancing and references", "ObjectEnd alone", vec![("a.pbrt", pbrt("ObjectEnd"))], Some("ObjectEnd")),
        (
            "object instancing and references",
            "object never ended",
            vec![("a.pbrt", pbrt("ObjectBegin \"a\"\nShape \"sphere\""))],
            Some("ObjectBegin"),
        ),
        (
            "object instancing and references",
            "object instancing itself",
            vec![("a.pbrt", pbrt("ObjectBegin \"a\"\nObjectInstance \"a\"\nObjectEnd\nObjectInstance \"a\""))],
            Some("ObjectInstance"),
        ),
        (
            "object instancing and references",
            "AttributeEnd without AttributeBegin",
            vec![("a.pbrt", pbrt("AttributeEnd\nShape \"sphere\""))],
            Some("AttributeEnd"),
        ),
        (
            "object instancing and references",
            "a mix material made of itself",
            vec![(
                "a.pbrt",
                pbrt(
                    "MakeNamedMaterial \"m\" \"string type\" \"mix\" \"string materials\" [\"m\" \"m\"]\nNamedMaterial \"m\"\nShape \"sphere\"",
                ),
            )],
            Some("\"m\""),
        ),
        (
            "object instancing and references",
            "an undefined named material",
            vec![("a.pbrt", pbrt("NamedMaterial \"nothing\"\nShape \"sphere\""))],
            Some("nothing"),
        ),
        (
            "object instancing and references",
            "an undefined texture",
            vec![("a.pbrt", pbrt("Material \"diffuse\" \"texture reflectance\" \"nothing\"\nShape \"sphere\""))],
            Some("nothing"),
        ),
        (
            "object instancing and references",
            "Mitsuba: a reference to an undefined id",
            vec![("a.xml", xml("<shape type=\"sphere\"><ref id=\"nothing\"/></shape>"))],
            Some("nothing"),
        ),
        (
            "object instancing and references",
            "Mitsuba: a BSDF containing a reference to itself",
            vec![(
                "a.xml",
                xml(
                    "<bsdf type=\"twosided\" id=\"a\"><ref id=\"a\"/></bsdf><shape type=\"sphere\"><ref id=\"a\"/></shape>",
                ),
            )],
            Some("\"a\""),
        ),
        ("missing files", "Include", vec![("a.pbrt", pbrt("Include \"gone.pbrt\""))], Some("gone.pbrt")),
        (
            "missing files",
            "plymesh",
            vec![("a.pbrt", pbrt("Shape \"plymesh\" \"string filename\" \"gone.ply\""))],
            Some("gone.ply"),
        ),
        (
            "missing files",
            "imagemap",
            vec![("a.pbrt", pbrt("Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"gone.png\""))],
            Some("gone.png"),
        ),
        (
            "missing files",
            "infinite light map",
            vec![("a.pbrt", pbrt("LightSource \"infinite\" \"string filename\" \"gone.exr\""))],
            Some("gone.exr"),
        ),
        (
            "missing files",
            "spectrum file",
            vec![("a.pbrt", pbrt("Material \"conductor\" \"spectrum eta\" \"gone.spd\"\nShape \"sphere\""))],
            Some("gone.spd"),
        ),
        (
            "missing files",
            "Mitsuba include",
            vec![("a.xml", xml("<include filename=\"gone.xml\"/>"))],
            Some("gone.xml"),
        ),
        (
            "missing files",
            "Mitsuba obj",
            vec![("a.xml", xml("<shape type=\"obj\"><string name=\"filename\" value=\"gone.obj\"/></shape>"))],
            Some("gone.obj"),
        ),
        (
            "missing files",
            "Mitsuba serialized",
            vec![(
                "a.xml",
                xml("<shape type=\"serialized\"><string name=\"filename\" value=\"gone.serialized\"/></shape>"),
            )],
            Some("gone.serialized"),
        ),
        (
            "missing files",
            "Mitsuba envmap",
            vec![("a.xml", xml("<emitter type=\"envmap\"><string name=\"filename\" value=\"gone.exr\"/></emitter>"))],
            Some("gone.exr"),
        ),
        (
            "wrong file types",
            "a PNG as a PLY mesh",
            vec![("a.pbrt", pbrt("Shape \"plymesh\" \"string filename\" \"m.ply\"")), ("m.ply", png())],
            Some("m.ply"),
        ),
        (
            "wrong file types",
            "a PLY as an image",
            vec![
                ("a.pbrt", pbrt("Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"m.png\"")),
                ("m.png", quad.clone()),
            ],
            Some("m.png"),
        ),
        (
            "wrong file types",
            "text as an EXR",
            vec![
                ("a.pbrt", pbrt("LightSource \"infinite\" \"string filename\" \"m.exr\"")),
                ("m.exr", b"not an image".to_vec()),
            ],
            Some("m.exr"),
        ),
        (
            "wrong file types",
            "an image extension the readers do not know",
            vec![
                ("a.pbrt", pbrt("Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"m.bmp\"")),
                ("m.bmp", png()),
            ],
            Some("m.bmp"),
        ),
        (
            "wrong file types",
            "a PNG included as pbrt-v4 text",
            vec![("a.pbrt", pbrt("Include \"m.pbrt\"")), ("m.pbrt", png())],
            Some("m.pbrt"),
        ),
        (
            "wrong file types",
            "a PLY as a Mitsuba obj",
            vec![
                ("a.xml", xml("<shape type=\"obj\"><string name=\"filename\" value=\"m.obj\"/></shape>")),
                ("m.obj", quad.clone()),
            ],
            Some("m.obj"),
        ),
        (
            "wrong file types",
            "text as a Mitsuba serialized mesh",
            vec![
                ("a.xml", xml("<shape type=\"serialized\"><string name=\"filename\" value=\"m.serialized\"/></shape>")),
                ("m.serialized", b"not a mesh".to_vec()),
            ],
            Some("m.serialized"),
        ),
        ("wrong file types", "pbrt-v4 text in a .xml file", vec![("a.xml", pbrt("Shape \"sphere\""))], Some("a.xml")),
        ("wrong file types", "XML in a .pbrt file", vec![("a.pbrt", xml(""))], Some("a.pbrt")),
        ("wrong file types", "random bytes as pbrt-v4", vec![("a.pbrt", garbage.clone())], Some("a.pbrt")),
        ("wrong file types", "random bytes as Mitsuba XML", vec![("a.xml", garbage)], Some("a.xml")),
        ("wrong file types", "an empty pbrt-v4 file", vec![("a.pbrt", Vec::new())], None),
        ("wrong file types", "an empty Mitsuba file", vec![("a.xml", Vec::new())], Some("a.xml")),
        ("wrong file types", "an unknown extension", vec![("a.scene", pbrt(""))], Some("a.scene")),
        ("deep nesting", "20,000 nested AttributeBegin", vec![("a.pbrt", pbrt(&deep_pbrt))], None),
        ("deep nesting", "100,000 nested Mitsuba shapes", vec![("a.xml", xml(&deep_xml))], None),
    ]
}

#[test]
fn cycles_references_missing_and_wrong_files_are_clear_errors() {
    let mut tally = Tally::default();
    let mut failures = Vec::new();
    for (i, (kind, name, files, mention)) in structural_cases().into_iter().enumerate() {
        let files: Vec<(&str, &[u8])> = files.iter().map(|(n, c)| (*n, c.as_slice())).collect();
        let path = scratch(&i.to_string(), &files);
        let outcome = attempt(name, || match load(&path, &LoadOptions::default()) {
            Ok(loaded) => render(loaded),
            Err(e) => Outcome::Error(e.to_string()),
        });
        match (&outcome, mention) {
            (Outcome::Error(e), Some(m)) if !e.contains(m) => {
                failures.push(format!("{name}: {e:?} does not mention {m}"))
            }
            (Outcome::Rendered, Some(m)) => failures.push(format!("{name}: loaded; expected an error mentioning {m}")),
            (Outcome::Error(e), _) => eprintln!("{name}: {e}"),
            (Outcome::Rendered, None) => eprintln!("{name}: rendered"),
        }
        tally.add(kind, &outcome);
    }
    tally.print();
    assert!(failures.is_empty(), "{failures:#?}");
}
