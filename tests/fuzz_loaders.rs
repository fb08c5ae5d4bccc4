//! Fuzzing the scene loaders: the scene TOML, the OBJ and the MTL, glTF (`.gltf` and `.glb`), the texture
//! images (PNG, JPEG, TGA), with arbitrary and mutated-valid inputs.
//!
//! Properties, for every input: loading never panics and ends within [`DEADLINE`]; an error names the file
//! it is about (scene, mesh or material library), and where the loader gives a line, that line exists in that
//! file; a loader error without a line is an I/O error ("cannot read"), never the OBJ or MTL parser's own
//! line-less message (the checking pass must catch everything the parser would reject) or an image that does
//! not decode (it has no lines); a scene that loads
//! has finite triangles, unit normals, a finite camera and valid render parameters.
//!
//! The budget is small and fixed so that CI stays fast and repeatable: a fixed seed and a few hundred cases
//! per property (600 for generated OBJ and MTL lines, 300 for the rest), a second or two in all. Fuzz longer
//! with another seed, e.g. `PROPTEST_CASES=20000 PROPTEST_RNG_SEED=$RANDOM cargo test --release --test
//! fuzz_loaders`.
//! A failure prints the shrunk input; each bug found gets a plain regression test in `tests/scenes.rs`.

mod common;

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use sensorlight::params::{Overrides, RenderParams};
use sensorlight::scene::Scene;
use sensorlight::scene::material::LoadError;

/// Longest a load of these small files may take (they load in well under a millisecond).
const DEADLINE: Duration = Duration::from_secs(10);
const CAMERA: &str = "[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\nvfov_deg = 40\n[image]\nwidth = 16\nheight = 16\n";
const QUAD: &str = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n";

/// A valid file's bytes with `changes` made (each `(at, byte)`, `at` wrapped to the length) and cut to the
/// fraction `cut` of its length.
fn mutate(bytes: &mut Vec<u8>, changes: &[(usize, u8)], cut: Option<f64>) {
    for &(at, byte) in changes {
        let n = bytes.len();
        bytes[at % n] = byte;
    }
    if let Some(f) = cut {
        bytes.truncate((bytes.len() as f64 * f) as usize);
    }
}

/// `cases` per property, a fixed seed; `PROPTEST_CASES` and `PROPTEST_RNG_SEED` override either.
fn config(cases: u32) -> Config {
    let mut config = Config { failure_persistence: None, ..Config::default() };
    if std::env::var_os("PROPTEST_CASES").is_none() {
        config.cases = cases;
    }
    if std::env::var_os("PROPTEST_RNG_SEED").is_none() {
        config.rng_seed = RngSeed::Fixed(0x5e_a5_0f_11_9b_7e);
    }
    config
}

/// The files of one case, in a directory that each case rewrites.
struct Files {
    dir: PathBuf,
    written: Vec<(PathBuf, String)>,
}

impl Files {
    fn new(dir: &Path) -> Self {
        Self { dir: dir.to_owned(), written: Vec::new() }
    }

    fn write(mut self, name: &str, bytes: &[u8]) -> Self {
        let path = self.dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        self.written.push((path, String::from_utf8_lossy(bytes).into_owned()));
        self
    }

    fn scene(self, toml: &str) -> Self {
        self.write("scene.toml", toml.as_bytes())
    }

    /// Loads `scene.toml` and checks every property (see the module documentation).
    fn check(self) -> Result<(), TestCaseError> {
        let scene = self.dir.join("scene.toml");
        let (send, receive) = mpsc::channel();
        let loader = std::thread::spawn(move || {
            let result = Scene::load(&scene);
            let _ = send.send(());
            result
        });
        if receive.recv_timeout(DEADLINE).is_err() && !loader.is_finished() {
            // The thread is left behind; the test fails.
            return Err(TestCaseError::fail(format!("loading took more than {DEADLINE:?}")));
        }
        match loader.join() {
            Err(panic) => {
                let message = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()));
                Err(TestCaseError::fail(format!("the loader panicked: {message:?}")))
            }
            Ok(Ok(scene)) => loaded_scene_is_sound(&scene),
            Ok(Err(error)) => self.error_is_clear(&error),
        }
    }

    fn error_is_clear(&self, error: &anyhow::Error) -> Result<(), TestCaseError> {
        let message = format!("{error:#}");
        // The files written, and the mesh the scene names (which may be missing or elsewhere).
        let scene = self.dir.join("scene.toml");
        let mesh = sensorlight::scene::file::SceneFile::read(&scene).ok().map(|f| f.mesh_path(&scene));
        let mut files: Vec<PathBuf> = self.written.iter().map(|(p, _)| p.clone()).collect();
        files.extend(mesh);
        let named = files.iter().any(|path| message.contains(&path.display().to_string()));
        prop_assert!(named, "the error names none of the files: {message}");
        if let Some(e) = error.chain().find_map(|c| c.downcast_ref::<LoadError>()) {
            match e.line {
                Some(line) => {
                    let text = self.written.iter().find(|(p, _)| *p == e.file).map(|(_, t)| t.as_str());
                    let lines = text.map_or(usize::MAX, |t| t.lines().count());
                    prop_assert!(line >= 1 && line <= lines, "line {line} of {} lines: {message}", lines);
                }
                // An image has no lines: what is wrong with it (unreadable, too large, empty) is said of
                // the file itself.
                None => prop_assert!(
                    e.message.starts_with("cannot read")
                        || e.message.contains("not a readable image")
                        || is_image(&e.file),
                    "no line given: {message}"
                ),
            }
        }
        if let Some(at) = message.find("at line ") {
            // A parser's own position: toml's in the scene file, or serde_json's in a glTF file it names.
            let line: usize = message[at + 8..].split(|c: char| !c.is_ascii_digit()).next().unwrap().parse().unwrap();
            let gltf = self.written.iter().find(|(p, _)| p.extension().is_some_and(|e| e == "gltf" || e == "glb"));
            // serde_json puts an unexpected end one line past a final newline.
            let (what, text, past) = match gltf.filter(|(p, _)| message.contains(&p.display().to_string())) {
                Some((_, text)) => ("glTF", text, text.ends_with('\n') as usize),
                None => ("TOML", &self.written.iter().find(|(p, _)| p.ends_with("scene.toml")).unwrap().1, 0),
            };
            let lines = text.lines().count() + past;
            prop_assert!(line >= 1 && line <= lines.max(1), "{what} line {line} of {lines}: {message}");
        }
        Ok(())
    }
}

/// Whether a file is an image (a texture or a sky map), which has no lines to name.
fn is_image(path: &std::path::Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| ["png", "jpg", "tga", "exr", "hdr"].contains(&e))
}

fn loaded_scene_is_sound(scene: &Scene) -> Result<(), TestCaseError> {
    let mesh = &scene.mesh;
    prop_assert!(!mesh.triangles.is_empty());
    for t in &mesh.triangles {
        prop_assert!(t.v.iter().all(|v| v.is_finite()), "a vertex is not finite: {t:?}");
        prop_assert!((t.normal.length() - 1.0).abs() < 1e-3, "normal not unit: {t:?}");
        prop_assert!(t.surface >= 1 && t.surface as usize <= mesh.surfaces.len());
    }
    prop_assert!(mesh.bounds.diagonal().is_finite());
    prop_assert!(mesh.materials.iter().all(|m| m.kd.is_finite() && m.ke.is_finite()));
    let c = &scene.camera;
    prop_assert!(c.eye.is_finite() && c.forward.is_finite() && c.right.is_finite() && c.up.is_finite());
    prop_assert!(c.vfov > 0.0 && c.vfov < std::f32::consts::PI);
    prop_assert!(scene.image.width >= 1 && scene.image.height >= 1);
    // The loader keeps `[render]` as written; resolving it either works or names the file and the table.
    let resolved = Overrides::from_scene_table(&scene.path, &scene.render).and_then(|values| {
        RenderParams::resolve(Some((&scene.path, &values)), &Overrides::default()).map_err(anyhow::Error::from)
    });
    if let Err(e) = resolved {
        let message = e.to_string();
        let file = scene.path.file_name().unwrap().to_string_lossy();
        prop_assert!(message.contains(&*file) && message.contains("[render]"), "{message}");
    }
    Ok(())
}

// ---- Generators -------------------------------------------------------------------------------------------

fn number() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => (-1000.0f32..1000.0).prop_map(|x| x.to_string()),
        2 => (-5i64..20).prop_map(|i| i.to_string()),
        2 => proptest::sample::select(vec![
            "nan", "NaN", "inf", "-inf", "infinity", "1e30", "-1e30", "3e38", "1e39", "1e-40", "-1e-45", "0", "-0",
            "+1", "1.", ".5", "0x10", "1e", "1_0", "١", "", "--1", "1e-30",
        ])
        .prop_map(str::to_owned),
    ]
}

fn index() -> impl Strategy<Value = String> {
    prop_oneof![
        3 => (-6i64..10).prop_map(|i| i.to_string()),
        2 => "-?[0-9]{0,2}(/-?[0-9]{0,2}){0,3}",
        1 => Just("99999999999999999999".to_owned()),
        1 => Just("-9223372036854775808".to_owned()),
    ]
}

fn name() -> impl Strategy<Value = String> {
    prop_oneof![
        3 => proptest::sample::select(vec![
            "a", "b", "m.mtl", "mesh.obj", "scene.toml", "../m.mtl", "/dev/zero", "/dev/null", ".", "..", "dir/m.mtl",
            "a b", "é", "light",
        ])
        .prop_map(str::to_owned),
        1 => "[a-zA-Z0-9_./é -]{0,12}",
    ]
}

/// Anything: short strings of any characters.
fn garbage() -> impl Strategy<Value = String> {
    "\\PC{0,6}"
}

fn token() -> impl Strategy<Value = String> {
    prop_oneof![4 => number(), 3 => index(), 2 => name(), 1 => garbage()]
}

fn separator() -> impl Strategy<Value = &'static str> {
    proptest::sample::select(vec![" ", " ", " ", "\t", "  ", " \t ", "\u{a0}", "\u{b}", "\u{c}", "\u{3000}"])
}

fn ending() -> impl Strategy<Value = &'static str> {
    proptest::sample::select(vec!["\n", "\n", "\n", "\r\n", "\r", " # comment\n", "#\n", "\\\n"])
}

/// A line: a keyword from `keywords` (or anything), then separated tokens.
fn line(keywords: &'static [&'static str]) -> impl Strategy<Value = String> {
    let keyword = prop_oneof![9 => proptest::sample::select(keywords).prop_map(str::to_owned), 1 => garbage()];
    (
        proptest::sample::select(vec!["", "", "", " ", "\t", "\u{feff}"]),
        keyword,
        proptest::collection::vec((separator(), token()), 0..8),
        ending(),
    )
        .prop_map(|(lead, keyword, args, end)| {
            let args: String = args.into_iter().map(|(s, t)| format!("{s}{t}")).collect();
            format!("{lead}{keyword}{args}{end}")
        })
}

const OBJ_KEYWORDS: &[&str] = &[
    "v", "v", "v", "vt", "vn", "f", "f", "f", "l", "p", "usemtl", "mtllib", "o", "g", "s", "#", "cstype", "deg",
    "curv", "end", "vp", "lod", "V", "F", "vx",
];
const MTL_KEYWORDS: &[&str] = &[
    "newmtl", "newmtl", "Kd", "Kd", "Ke", "Ke", "Ka", "Ks", "Ns", "Ni", "d", "Tr", "Tf", "illum", "map_Kd", "map_Ka",
    "map_Ks", "map_Bump", "map_bump", "bump", "map_d", "map_Ns", "refl", "#",
];

/// Lines of glTF JSON to insert: values that are out of range, of the wrong type, or that loop.
const GLTF_LINES: &[&str] = &[
    "\"mode\": 0,",
    "\"mode\": 5,",
    "\"count\": 99999,",
    "\"byteOffset\": 7,",
    "\"scale\": [0, 0, 0],",
    "\"matrix\": [1e39, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1],",
    "\"children\": [0, 0],",
    "\"indices\": 3,",
    "\"camera\": 0,",
    "\"yfov\": 0,",
    "\"emissiveFactor\": [1e30, 1, 1],",
    "{",
    "}",
    "[",
    "],",
];

/// An OBJ of generated lines, often after a valid quad (so that some load), with a BOM now and then.
fn obj_text() -> impl Strategy<Value = String> {
    (any::<bool>(), any::<bool>(), proptest::collection::vec(line(OBJ_KEYWORDS), 0..24)).prop_map(
        |(bom, quad, lines)| {
            let bom = if bom { "\u{feff}" } else { "" };
            let quad = if quad { QUAD } else { "" };
            format!("{bom}mtllib m.mtl\nusemtl a\n{quad}{}", lines.concat())
        },
    )
}

fn mtl_text() -> impl Strategy<Value = String> {
    (any::<bool>(), proptest::collection::vec(line(MTL_KEYWORDS), 0..24)).prop_map(|(bom, lines)| {
        let bom = if bom { "\u{feff}" } else { "" };
        format!("{bom}newmtl a\n{}", lines.concat())
    })
}

/// One edit of a file's lines.
#[derive(Clone, Debug)]
enum Edit {
    Delete(usize),
    Duplicate(usize),
    Swap(usize, usize),
    Insert(usize, String),
    /// Replace the k-th word of a line.
    Replace(usize, usize, String),
    /// Cut the file at this fraction of its length (on a character boundary).
    Truncate(f64),
}

fn edit(lines: &'static [&'static str]) -> impl Strategy<Value = Edit> {
    let at = 0usize..10_000;
    prop_oneof![
        1 => at.clone().prop_map(Edit::Delete),
        1 => at.clone().prop_map(Edit::Duplicate),
        1 => (at.clone(), at.clone()).prop_map(|(a, b)| Edit::Swap(a, b)),
        1 => (at.clone(), line(lines)).prop_map(|(a, l)| Edit::Insert(a, l)),
        3 => (at, 0usize..8, token()).prop_map(|(a, k, t)| Edit::Replace(a, k, t)),
        1 => (0.0f64..1.0).prop_map(Edit::Truncate),
    ]
}

fn apply(text: &str, edits: &[Edit]) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    let mut cut = None;
    for e in edits {
        let n = lines.len().max(1);
        match e {
            Edit::Delete(i) if !lines.is_empty() => drop(lines.remove(i % n)),
            Edit::Duplicate(i) if !lines.is_empty() => lines.insert(i % n, lines[i % n].clone()),
            Edit::Swap(a, b) if !lines.is_empty() => lines.swap(a % n, b % n),
            Edit::Insert(i, l) => lines.insert(i % (lines.len() + 1), l.trim_end_matches(['\n', '\r']).to_owned()),
            Edit::Replace(i, k, t) if !lines.is_empty() => {
                let mut words: Vec<&str> = lines[i % n].split_whitespace().collect();
                if words.is_empty() {
                    words.push(t);
                } else {
                    let k = k % words.len();
                    words[k] = t;
                }
                lines[i % n] = words.join(" ");
            }
            Edit::Truncate(f) => cut = Some(*f),
            _ => {}
        }
    }
    let mut text = lines.join("\n");
    if let Some(f) = cut {
        let mut at = (text.len() as f64 * f) as usize;
        while !text.is_char_boundary(at) {
            at -= 1;
        }
        text.truncate(at);
    }
    text
}

fn shipped(path: &str) -> String {
    std::fs::read_to_string(common::project(path)).unwrap()
}

fn scratch(name: &str) -> PathBuf {
    common::scratch(&format!("fuzz_{name}"))
}

/// The scene TOML: a valid one with its values replaced, keys added or removed, or anything at all.
fn toml_value() -> impl Strategy<Value = String> {
    prop_oneof![
        number(),
        proptest::sample::select(vec![
            "[0, 0, 5]",
            "[0, 0, 0]",
            "[0, 1, 0]",
            "[nan, 0, 0]",
            "[inf, 0, 0]",
            "[3e38, 0, 0]",
            "[-3e38, 0, 0]",
            "[1e39, 0, 0]",
            "[0, 0]",
            "[0, 0, 0, 0]",
            "[\"a\", 0, 0]",
            "[]",
            "4294967295",
            "4294967296",
            "-1",
            "0",
            "1e300",
            "\"mesh.obj\"",
            "\"\"",
            "\"/dev/zero\"",
            "\".\"",
            "\"nowhere.obj\"",
            "\"hemicube\"",
            "\"frustum\"",
            "\"fisheye\"",
            "true",
            "{ a = 1 }",
            "1979-05-27",
            "'''x'''",
        ])
        .prop_map(str::to_owned),
    ]
}

const TOML_KEYS: &[&str] = &[
    "mesh",
    "eye",
    "target",
    "up",
    "vfov_deg",
    "width",
    "height",
    "sensor",
    "fov_deg",
    "sensor_size",
    "tile",
    "dradiance",
    "epsilon",
    "filter_radius",
    "exposure",
    "background",
    "samples",
];

fn scene_toml() -> impl Strategy<Value = String> {
    let edits = proptest::collection::vec(
        (
            proptest::sample::select(TOML_KEYS),
            toml_value(),
            proptest::sample::select(vec!["", "[camera]", "[image]", "[render]", "[other]"]),
        ),
        0..5,
    );
    prop_oneof![
        6 => edits.prop_map(|edits| {
            let mut camera = vec![
                ("eye", "[0, 0, 5]".to_owned()),
                ("target", "[0, 0, 0]".to_owned()),
                ("up", "[0, 1, 0]".to_owned()),
                ("vfov_deg", "40".to_owned()),
            ];
            let mut image = vec![("width", "16".to_owned()), ("height", "16".to_owned())];
            let mut top = vec![("mesh", "\"mesh.obj\"".to_owned())];
            let mut render: Vec<(&str, String)> = Vec::new();
            let mut other: Vec<(&str, String)> = Vec::new();
            for (key, value, table) in edits {
                let section = match table {
                    "[camera]" => &mut camera,
                    "[image]" => &mut image,
                    "[render]" => &mut render,
                    "[other]" => &mut other,
                    _ => &mut top,
                };
                match section.iter_mut().find(|(k, _)| *k == key) {
                    Some(entry) => entry.1 = value,
                    None => section.push((key, value)),
                }
            }
            let body = |entries: &[(&str, String)]| entries.iter().map(|(k, v)| format!("{k} = {v}\n")).collect::<String>();
            let mut text = body(&top);
            for (name, entries) in [("camera", &camera), ("image", &image), ("render", &render), ("other", &other)] {
                if !entries.is_empty() {
                    text.push_str(&format!("[{name}]\n{}", body(entries)));
                }
            }
            text
        }),
        1 => (0.0f64..1.0).prop_map(|f| {
            let text = format!("mesh = \"mesh.obj\"\n{CAMERA}");
            text[..(text.len() as f64 * f) as usize].to_owned()
        }),
        1 => "\\PC{0,80}",
    ]
}

// ---- Properties -------------------------------------------------------------------------------------------

proptest! {
    #![proptest_config(config(600))]

    /// Generated OBJ lines, after a valid quad or not, with the material library they name.
    #[test]
    fn generated_obj(obj in obj_text()) {
        let dir = scratch("obj");
        Files::new(&dir).write("m.mtl", b"newmtl a\nKd 0.5 0.5 0.5\nKe 1 1 1\n").write("mesh.obj", obj.as_bytes())
            .scene(&format!("mesh = \"mesh.obj\"\n{CAMERA}")).check()?;
    }

    /// Generated MTL lines, for an OBJ that uses materials `a` and `b`.
    #[test]
    fn generated_mtl(mtl in mtl_text()) {
        let dir = scratch("mtl");
        let obj = format!("mtllib m.mtl\nusemtl a\n{QUAD}usemtl b\nv 0 0 1\nf 1 2 5\n");
        Files::new(&dir).write("m.mtl", mtl.as_bytes()).write("mesh.obj", obj.as_bytes())
            .scene(&format!("mesh = \"mesh.obj\"\n{CAMERA}")).check()?;
    }
}

proptest! {
    #![proptest_config(config(300))]

    /// Any bytes as the OBJ, and as the MTL.
    #[test]
    fn arbitrary_bytes(obj in proptest::collection::vec(any::<u8>(), 0..300), mtl in proptest::collection::vec(any::<u8>(), 0..300)) {
        let dir = scratch("bytes");
        let mut obj_bytes = b"mtllib m.mtl\n".to_vec();
        obj_bytes.extend(&obj);
        Files::new(&dir).write("m.mtl", &mtl).write("mesh.obj", &obj_bytes)
            .scene(&format!("mesh = \"mesh.obj\"\n{CAMERA}")).check()?;
    }

    /// The shipped Cornell box (OBJ and MTL) with a few edits each.
    #[test]
    fn mutated_cornell_box(
        obj_edits in proptest::collection::vec(edit(OBJ_KEYWORDS), 0..4),
        mtl_edits in proptest::collection::vec(edit(MTL_KEYWORDS), 0..3),
    ) {
        let dir = scratch("cornell");
        let obj = apply(&shipped("scenes/cornell/cornell.obj"), &obj_edits);
        let mtl = apply(&shipped("scenes/cornell/cornell.mtl"), &mtl_edits);
        Files::new(&dir).write("cornell.mtl", mtl.as_bytes()).write("cornell.obj", obj.as_bytes())
            .scene(&shipped("scenes/cornell/cornell.toml")).check()?;
    }

    /// The real third-party box (indented MTL, an mtllib path from elsewhere) with a few edits each.
    #[test]
    fn mutated_mcguire_box(
        obj_edits in proptest::collection::vec(edit(OBJ_KEYWORDS), 0..4),
        mtl_edits in proptest::collection::vec(edit(MTL_KEYWORDS), 0..3),
    ) {
        let dir = scratch("mcguire");
        let obj = apply(&shipped("scenes/cornell-mcguire/CornellBox-Original.obj"), &obj_edits);
        let mtl = apply(&shipped("scenes/cornell-mcguire/CornellBox-Original.mtl"), &mtl_edits);
        Files::new(&dir).write("CornellBox-Original.mtl", mtl.as_bytes())
            .write("CornellBox-Original.obj", obj.as_bytes())
            .scene(&shipped("scenes/cornell-mcguire/cornell-mcguire.toml")).check()?;
    }

    /// The glTF test asset (`.gltf` JSON, one value per line, and its `.bin`) with a few edits of its lines.
    #[test]
    fn mutated_gltf(edits in proptest::collection::vec(edit(GLTF_LINES), 1..4)) {
        let dir = scratch("gltf");
        let text = apply(&std::fs::read_to_string(common::gltf::write_gltf(&dir, "mesh")).unwrap(), &edits);
        Files::new(&dir).write("mesh.gltf", text.as_bytes()).scene(&format!("mesh = \"mesh.gltf\"\n{CAMERA}")).check()?;
    }

    /// The `.glb` with bytes changed, and cut short now and then.
    #[test]
    fn mutated_glb(
        changes in proptest::collection::vec((0usize..100_000, any::<u8>()), 0..6),
        cut in proptest::option::of(0.0f64..1.0),
    ) {
        let dir = scratch("glb");
        let mut bytes = std::fs::read(common::gltf::write_glb(&dir, "mesh", &[])).unwrap();
        mutate(&mut bytes, &changes, cut);
        Files::new(&dir).write("mesh.glb", &bytes).scene(&format!("mesh = \"mesh.glb\"\n{CAMERA}")).check()?;
    }

    /// A textured quad's `map_Kd` image (a valid PNG, JPEG or TGA) with bytes changed or cut short.
    #[test]
    fn mutated_texture(
        format in prop_oneof![Just("png"), Just("jpg"), Just("tga")],
        changes in proptest::collection::vec((0usize..100_000, any::<u8>()), 0..6),
        cut in proptest::option::of(0.0f64..1.0),
    ) {
        let dir = scratch("texture");
        let name = format!("t.{format}");
        let image = image::RgbImage::from_fn(8, 8, |x, y| image::Rgb([(x * 32) as u8, (y * 32) as u8, 128]));
        image.save(dir.join(&name)).unwrap();
        let mut bytes = std::fs::read(dir.join(&name)).unwrap();
        mutate(&mut bytes, &changes, cut);
        let obj = "mtllib m.mtl\nusemtl a\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
                   f 1/1 2/2 3/3 4/4\n";
        Files::new(&dir).write(&name, &bytes).write("mesh.obj", obj.as_bytes())
            .write("m.mtl", format!("newmtl a\nKe 1 1 1\nmap_Kd {name}\n").as_bytes())
            .scene(&format!("mesh = \"mesh.obj\"\n{CAMERA}")).check()?;
    }

    /// A scene's `[sky]` map (a valid OpenEXR or Radiance HDR image) with bytes changed or cut short.
    #[test]
    fn mutated_sky_map(
        format in prop_oneof![Just("exr"), Just("hdr")],
        changes in proptest::collection::vec((0usize..100_000, any::<u8>()), 0..6),
        cut in proptest::option::of(0.0f64..1.0),
    ) {
        let dir = scratch("sky");
        let name = format!("sky.{format}");
        let image = image::Rgb32FImage::from_fn(16, 8, |x, y| image::Rgb([x as f32 * 0.1, y as f32 * 0.2, 1.0]));
        match format {
            "exr" => {
                let texels: Vec<glam::Vec4> = image.pixels().map(|p| glam::Vec4::new(p[0], p[1], p[2], 1.0)).collect();
                sensorlight::output::exr::ExrImage::new(16, 8).rgb("", &texels).write(&dir.join(&name)).unwrap();
            }
            _ => image::DynamicImage::ImageRgb32F(image).save(dir.join(&name)).unwrap(),
        }
        let mut bytes = std::fs::read(dir.join(&name)).unwrap();
        mutate(&mut bytes, &changes, cut);
        Files::new(&dir).write(&name, &bytes).write("mesh.obj", format!("mtllib m.mtl\nusemtl a\n{QUAD}").as_bytes())
            .write("m.mtl", b"newmtl a\nKd 0.5 0.5 0.5\n")
            .scene(&format!("mesh = \"mesh.obj\"\n{CAMERA}\n[sky]\nmap = \"{name}\"\n")).check()?;
    }

    /// Scene files: valid ones with values replaced or keys added, cut short, or anything.
    #[test]
    fn generated_scene_toml(toml in scene_toml()) {
        let dir = scratch("toml");
        Files::new(&dir).write("mesh.obj", format!("mtllib m.mtl\nusemtl a\n{QUAD}").as_bytes())
            .write("m.mtl", b"newmtl a\nKe 1 1 1\n").scene(&toml).check()?;
    }
}

/// A texture whose header claims a side past the limit (a case the mutation found): refused naming the
/// file and its size, with no line, as an image has none.
#[test]
fn texture_header_past_the_limit() {
    let dir = scratch("texture_limit");
    let image = image::RgbImage::from_fn(8, 8, |x, y| image::Rgb([(x * 32) as u8, (y * 32) as u8, 128]));
    image.save(dir.join("t.tga")).unwrap();
    let mut bytes = std::fs::read(dir.join("t.tga")).unwrap();
    bytes[13] = 64; // TGA's width, little-endian at bytes 12..14: 8 + 64 · 256 = 16 392
    let obj = "mtllib m.mtl\nusemtl a\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
               f 1/1 2/2 3/3 4/4\n";
    let files = Files::new(&dir).write("t.tga", &bytes).write("mesh.obj", obj.as_bytes());
    let files =
        files.write("m.mtl", b"newmtl a\nKe 1 1 1\nmap_Kd t.tga\n").scene(&format!("mesh = \"mesh.obj\"\n{CAMERA}"));
    let error = Scene::load(&dir.join("scene.toml")).expect_err("a 16 392-texel side is refused");
    let message = format!("{error:#}");
    assert!(message.contains("16392 × 8 texels"), "{message}");
    // The path once (issue 42, item 9: it was printed twice).
    assert_eq!(message.matches(&dir.join("t.tga").display().to_string()).count(), 1, "{message}");
    files.check().unwrap();
}
