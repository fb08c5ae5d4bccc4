//! Scene loading: the real third-party files with their quirks, and every kind of malformed input, which
//! must end in a clear message and a non-zero exit without a panic or a half-written output.

mod common;

use std::path::{Path, PathBuf};

use glam::Vec3;
use sensorlight::params::{Overrides, RenderParams};
use sensorlight::scene::Scene;

const CAMERA: &str = "[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\nvfov_deg = 40\n[image]\nwidth = 16\nheight = 16\n";
const QUAD: &str = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n";

/// Writes `scene.toml` (with `toml_body`, or a default one naming `mesh.obj`) and `mesh.obj` into `dir`.
fn write_scene(dir: &Path, obj: Option<&str>, toml_body: Option<&str>) -> PathBuf {
    if let Some(obj) = obj {
        std::fs::write(dir.join("mesh.obj"), obj).unwrap();
    }
    let toml = toml_body.map(str::to_owned).unwrap_or_else(|| format!("mesh = \"mesh.obj\"\n{CAMERA}"));
    let path = dir.join("scene.toml");
    std::fs::write(&path, toml).unwrap();
    path
}

/// Loading fails with a message containing every piece of `expected`; the CLI exits non-zero with the same
/// message, without panicking, and leaves no output behind.
fn rejects(name: &str, obj: Option<&str>, toml_body: Option<&str>, expected: &[&str]) {
    rejects_with(name, obj, toml_body, &[], expected);
}

/// [`rejects`] with `extra` files (name, contents) beside the scene.
fn rejects_with(name: &str, obj: Option<&str>, toml_body: Option<&str>, extra: &[(&str, &str)], expected: &[&str]) {
    let dir = common::scratch(name);
    for (file, contents) in extra {
        std::fs::write(dir.join(file), contents).unwrap();
    }
    let scene = write_scene(&dir, obj, toml_body);
    let message = format!("{:#}", Scene::load(&scene).err().unwrap_or_else(|| panic!("{name}: loaded")));
    for piece in expected {
        assert!(message.contains(piece), "{name}: message {message:?} lacks {piece:?}");
    }
    let out = dir.join("out.exr");
    common::expect_failure(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()], expected[0]);
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert!(!out.exists() && !dir.join("out.png").exists(), "{name}: output written: {left:?}");
    assert!(left.iter().all(|f| !f.to_string_lossy().contains("tmp")), "{name}: temporary left: {left:?}");
}

#[test]
fn bad_toml_names_file_and_line() {
    rejects("bad_toml", Some(QUAD), Some("mesh = \"mesh.obj\"\n[camera\neye = [0, 0, 5]\n"), &["scene.toml", "line 2"]);
}

#[test]
fn unknown_toml_key_is_an_error() {
    let body = format!("mesh = \"mesh.obj\"\nsamples = 4\n{CAMERA}");
    rejects("unknown_key", Some(QUAD), Some(&body), &["scene.toml", "samples"]);
}

/// The scene loader keeps `[render]` as written (it knows no render parameter); resolving the parameters
/// names the file and the key, in the library and on the command line, and a flag does not hide it.
#[test]
fn bad_render_table_names_the_file_and_key() {
    let dir = common::scratch("bad_render_table");
    let body = format!("mesh = \"mesh.obj\"\n{CAMERA}[render]\ntile = 12\n");
    let path = write_scene(&dir, Some(QUAD), Some(&body));
    let scene = Scene::load(&path).unwrap();
    let values = Overrides::from_scene_table(&path, &scene.render).unwrap();
    let error = RenderParams::resolve(Some((&path, &values)), &Overrides::default()).unwrap_err().to_string();
    assert!(error.contains("scene.toml: [render] tile must be a power of two") && error.contains("got 12"), "{error}");
    let out = dir.join("out.exr");
    for flags in [&[][..], &["--tile", "8"]] {
        let mut args = vec!["render", path.to_str().unwrap(), "-o", out.to_str().unwrap()];
        args.extend_from_slice(flags);
        common::expect_failure(&args, "scene.toml: [render] tile must be a power of two");
        assert!(!out.exists());
    }
    let body = format!("mesh = \"mesh.obj\"\n{CAMERA}[render]\nsensor = \"fisheye\"\n");
    let path = write_scene(&dir, Some(QUAD), Some(&body));
    let args = ["render", path.to_str().unwrap(), "-o", out.to_str().unwrap()];
    let stderr = common::expect_failure(&args, "scene.toml: [render]");
    assert!(stderr.contains("fisheye") && stderr.contains("hemicube"), "{stderr}");
}

#[test]
fn camera_looking_along_up_is_an_error() {
    let body = "mesh = \"mesh.obj\"\n[camera]\neye = [0, 5, 0]\ntarget = [0, 0, 0]\nvfov_deg = 40\n[image]\nwidth = 8\nheight = 8\n";
    rejects("camera_up", Some(QUAD), Some(body), &["scene.toml", "up is parallel"]);
}

#[test]
fn missing_obj_is_an_error() {
    rejects("missing_obj", None, None, &["mesh.obj", "cannot read mesh"]);
}

#[test]
fn garbage_line_names_its_line() {
    rejects("garbage", Some(&format!("{QUAD}this is not obj\n")), None, &["mesh.obj:6", "unknown statement 'this'"]);
}

#[test]
fn non_numeric_vertex_names_its_line() {
    rejects("bad_number", Some("v 1 2 three\n"), None, &["mesh.obj:1", "not a number: 'three'"]);
}

#[test]
fn nan_vertex_names_its_line() {
    rejects("nan_vertex", Some("v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n"), None, &["mesh.obj:3", "not finite"]);
}

#[test]
fn face_index_out_of_range_names_its_line() {
    rejects("bad_index", Some("v 0 0 0\nv 1 0 0\nf 1 2 7\n"), None, &["mesh.obj:3", "index 7"]);
}

/// Every MTL statement the parser would reject is reported with its line, never taken for "no materials".
#[test]
fn bad_mtl_lines_name_their_line() {
    let obj = format!("mtllib m.mtl\nusemtl a\n{QUAD}");
    for (name, bad, expected) in [
        ("mtl_kd_short", "Kd 1 1", "'Kd' needs 3"),
        ("mtl_ns", "Ns shiny", "'Ns' needs a number"),
        ("mtl_illum", "illum two", "'illum' needs"),
        ("mtl_newmtl", "newmtl", "'newmtl' needs a material name"),
        ("mtl_map", "map_Kd", "'map_Kd' needs a file name"),
    ] {
        let mtl = format!("# materials\nnewmtl a\n{bad}\nKd 0.5 0.5 0.5\n");
        rejects_with(name, Some(&obj), None, &[("m.mtl", &mtl)], &["m.mtl:3", expected]);
    }
}

#[test]
fn empty_mesh_is_an_error() {
    rejects("empty_mesh", Some("# nothing here\nv 0 0 0\n"), None, &["mesh.obj", "no triangles"]);
}

#[test]
fn only_degenerate_triangles_is_an_empty_mesh() {
    rejects("degenerate", Some("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"), None, &["mesh.obj", "(1 degenerate)"]);
}

/// Two small triangles 6e19 apart: each is fine, but the scene's diagonal overflows f32.
#[test]
fn mesh_too_large_for_f32_is_an_error() {
    let obj = "v -3e19 0 0\nv -3e19 1 0\nv -3e19 0 1\nv 3e19 0 0\nv 3e19 1 0\nv 3e19 0 1\nf 1 2 3\nf 4 5 6\n";
    rejects("too_large", Some(obj), None, &["mesh.obj", "too large for 32-bit floats"]);
}

#[test]
fn mcguire_box_loads_with_its_quirks() {
    let scene = Scene::load(&common::project("scenes/cornell-mcguire/cornell-mcguire.toml")).unwrap();
    let mesh = &scene.mesh;
    assert_eq!(mesh.triangles.len(), 36, "18 quads, fan-triangulated");
    assert!(scene.warnings.iter().any(|w| w.contains("found by file name")), "{:?}", scene.warnings);
    let light = mesh.materials.iter().find(|m| m.name == "light").expect("light material");
    assert_eq!(light.ke, Vec3::new(17.0, 12.0, 4.0));
    assert_eq!(mesh.materials.iter().find(|m| m.name == "leftWall").unwrap().kd, Vec3::new(0.63, 0.065, 0.05));
    let light_tris: Vec<_> = mesh.triangles.iter().filter(|t| mesh.material_of(t.surface).name == "light").collect();
    assert_eq!(light_tris.len(), 2);
    assert!(light_tris.iter().all(|t| t.normal.y < -0.99), "the light faces down");
    // Walls, floor, ceiling, light: one surface each; the boxes one per face.
    assert!(mesh.surfaces.len() >= 5 + 1 + 2 * 5, "{} surfaces", mesh.surfaces.len());
    for t in &mesh.triangles {
        let same: Vec<_> = mesh.triangles.iter().filter(|u| u.surface == t.surface).collect();
        assert!(
            same.iter().all(|u| u.normal.dot(t.normal) > 0.86),
            "surface {} bends more than the crease angle",
            t.surface
        );
    }
}

#[test]
fn undefined_material_is_grey_with_a_warning() {
    let dir = common::scratch("undefined_material");
    let scene = write_scene(&dir, Some(&format!("mtllib nowhere.mtl\nusemtl chalk\n{QUAD}")), None);
    let scene = Scene::load(&scene).unwrap();
    let m = scene.mesh.material_of(scene.mesh.triangles[0].surface);
    assert_eq!((m.kd, m.ke), (Vec3::splat(0.8), Vec3::ZERO));
    assert!(scene.warnings.iter().any(|w| w.contains("'chalk'") && w.contains("mesh.obj:2")), "{:?}", scene.warnings);
    assert!(scene.warnings.iter().any(|w| w.contains("nowhere.mtl")), "{:?}", scene.warnings);
}

#[test]
fn polygons_are_fan_triangulated_with_their_winding() {
    let dir = common::scratch("pentagon");
    let obj = "v 0 0 0\nv 2 0 0\nv 3 1 0\nv 1 2 0\nv -1 1 0\nf 1 2 3 4 5\n";
    let scene = Scene::load(&write_scene(&dir, Some(obj), None)).unwrap();
    let tris = &scene.mesh.triangles;
    assert_eq!(tris.len(), 3);
    assert!(tris.iter().all(|t| t.v[0] == Vec3::ZERO && (t.normal - Vec3::Z).length() < 1e-6));
    assert!(tris.iter().all(|t| t.surface == tris[0].surface), "a flat polygon is one surface");
}

#[test]
fn comments_and_ignored_statements_are_tolerated() {
    let dir = common::scratch("comments");
    let obj = format!("# header\nv -1 -1 0 # trailing comment\n{}\ncstype bspline\ndeg 3\n", &QUAD[10..]);
    let scene = Scene::load(&write_scene(&dir, Some(&obj), None)).unwrap();
    assert_eq!(scene.mesh.triangles.len(), 2);
    assert!(scene.warnings.iter().any(|w| w.contains("cstype")), "{:?}", scene.warnings);
}
