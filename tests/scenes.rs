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
        ("mtl_ke_huge", "Ke 1e30 1e30 1e30", "'Ke' 1000000000000000000000000000000 exceeds 1e18"),
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
    // Its `mtllib scenes/CornellBox-Original.mtl`, kept verbatim, names a directory of the repository it came
    // from; the MTL beside it is found by its file name, and that is the only warning.
    assert_eq!(scene.warnings.len(), 1, "{:?}", scene.warnings);
    assert!(scene.warnings[0].contains("found by file name"), "{:?}", scene.warnings);
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

/// The box as it is usually copied, the MTL beside the OBJ: `mtllib scenes/…` does not resolve as written,
/// and the MTL is found by its file name, with a warning.
#[test]
fn mtllib_from_elsewhere_is_found_by_file_name_with_a_warning() {
    let dir = common::scratch("mcguire_flat");
    let shipped = common::project("scenes/cornell-mcguire");
    std::fs::copy(shipped.join("CornellBox-Original.obj"), dir.join("CornellBox-Original.obj")).unwrap();
    std::fs::copy(shipped.join("CornellBox-Original.mtl"), dir.join("CornellBox-Original.mtl")).unwrap();
    std::fs::copy(shipped.join("cornell-mcguire.toml"), dir.join("scene.toml")).unwrap();
    let scene = Scene::load(&dir.join("scene.toml")).unwrap();
    assert!(scene.warnings.iter().any(|w| w.contains("found by file name")), "{:?}", scene.warnings);
    assert_eq!(scene.mesh.materials.iter().find(|m| m.name == "light").map(|m| m.ke), Some(Vec3::new(17.0, 12.0, 4.0)));
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

/// Loads `obj` (and `extra` files beside it) as the mesh of a default scene.
fn load_with(name: &str, obj: &str, extra: &[(&str, &str)]) -> Scene {
    let dir = common::scratch(name);
    for (file, contents) in extra {
        std::fs::write(dir.join(file), contents).unwrap();
    }
    Scene::load(&write_scene(&dir, Some(obj), None)).unwrap_or_else(|e| panic!("{name}: {e:#}"))
}

fn kd_of_first_triangle(scene: &Scene) -> Vec3 {
    scene.mesh.material_of(scene.mesh.triangles[0].surface).kd
}

/// Files saved by Windows editors start with a UTF-8 byte order mark; it is not part of the first statement.
#[test]
fn a_byte_order_mark_is_accepted_in_obj_and_mtl() {
    let obj = format!("\u{feff}mtllib m.mtl\nusemtl a\n{QUAD}");
    let scene = load_with("bom", &obj, &[("m.mtl", "\u{feff}newmtl a\nKd 0.2 0.3 0.4\nKe 1 1 1\n")]);
    assert_eq!(kd_of_first_triangle(&scene), Vec3::new(0.2, 0.3, 0.4), "{:?}", scene.warnings);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
}

/// Any whitespace separates a statement from its arguments, tabs included.
#[test]
fn tabs_separate_statements_from_names() {
    let obj = format!("mtllib\tm.mtl\nusemtl \t a\ng\twall\n{}", QUAD.replace(' ', "\t"));
    let scene = load_with("tabs", &obj, &[("m.mtl", "newmtl\ta\nKd\t0.2 \t0.3\t0.4\nKe\t1\t1\t1\n")]);
    assert_eq!(kd_of_first_triangle(&scene), Vec3::new(0.2, 0.3, 0.4), "{:?}", scene.warnings);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(scene.mesh.surfaces[0].name, "wall/a");
}

/// Coordinates of 1e30 are finite, but the triangle's area is not: that is said, not "degenerate".
#[test]
fn a_triangle_whose_area_overflows_f32_is_an_error() {
    let obj = "v 0 0 0\nv 1e30 0 0\nv 0 1e30 0\nf 1 2 3\n";
    rejects("area_overflow", Some(obj), None, &["mesh.obj", "too large for 32-bit floats", "area"]);
    let dir = common::scratch("area_overflow_message");
    let message = format!("{:#}", Scene::load(&write_scene(&dir, Some(obj), None)).unwrap_err());
    assert!(!message.contains("degenerate"), "{message}");
}

/// A polyline of three points is a line, not a triangle; a point is not geometry either.
#[test]
fn lines_and_points_are_not_triangles() {
    let scene = load_with("polyline", &format!("{QUAD}v 0 0 1\nl 1 2 5\np 1 2 5\nl 2 5\n"), &[]);
    assert_eq!(scene.mesh.triangles.len(), 2, "only the quad");
}

/// `vt u` (v defaults to 0 in the OBJ format) is accepted; `vn` needs three values, said with the line.
#[test]
fn texture_coordinates_and_normals_take_their_arities() {
    let scene = load_with("vt_one", &format!("vt 0.5\n{QUAD}"), &[]);
    assert_eq!(scene.mesh.triangles.len(), 2);
    rejects("vn_two", Some(&format!("{QUAD}vn 0 1\n")), None, &["mesh.obj:6", "'vn' takes 3"]);
    rejects("vt_four", Some(&format!("{QUAD}vt 0 1 0 1\n")), None, &["mesh.obj:6", "'vt' takes 1 to 3"]);
}

/// A weight w divides the coordinates: one that makes them overflow is refused with the line.
#[test]
fn a_vertex_weight_that_overflows_is_an_error() {
    rejects("tiny_w", Some(&format!("{QUAD}v 1 1 1 1e-40\n")), None, &["mesh.obj:6", "not finite"]);
}

#[test]
fn a_scene_without_emitters_is_warned_about() {
    let scene = load_with("no_emitters", QUAD, &[]);
    let warning = scene.warnings.iter().find(|w| w.contains("emits")).unwrap_or_else(|| panic!("{:?}", scene.warnings));
    assert!(warning.contains("ε = 0"), "{warning}");
    let lit =
        load_with("emitters", &format!("mtllib m.mtl\nusemtl glow\n{QUAD}"), &[("m.mtl", "newmtl glow\nKe 1 1 1\n")]);
    assert!(lit.warnings.is_empty(), "{:?}", lit.warnings);
}

#[test]
fn an_albedo_above_one_is_warned_about_by_name() {
    let mtl = "newmtl hot\nKd 1.2 0.5 0.5\nnewmtl fine\nKd 1 1 1\nKe 1 1 1\nnewmtl unused\nKd 3 3 3\n";
    let obj = format!("mtllib m.mtl\nusemtl hot\n{QUAD}usemtl fine\nv 0 0 1\nf 1 2 5\n");
    let scene = load_with("kd_above_one", &obj, &[("m.mtl", mtl)]);
    let gains: Vec<&String> = scene.warnings.iter().filter(|w| w.contains("Kd")).collect();
    assert_eq!(gains.len(), 1, "only 'hot' (used, above 1): {:?}", scene.warnings);
    assert!(gains[0].contains("'hot'") && gains[0].contains("1.2") && gains[0].contains("energy"), "{}", gains[0]);
}

/// A mesh that is a device or a directory is refused at once: reading /dev/zero would never end.
#[test]
fn a_mesh_that_is_not_a_regular_file_is_refused() {
    let body = format!("mesh = \"/dev/zero\"\n{CAMERA}");
    rejects("mesh_device", None, Some(&body), &["/dev/zero", "not a regular file"]);
    let body = format!("mesh = \".\"\n{CAMERA}");
    rejects("mesh_directory", None, Some(&body), &["cannot read mesh: it is a directory"]);
}

/// Found by the fuzz harness: the index -9223372036854775808 (i64::MIN) has no positive counterpart in an
/// i64; negating it wrapped around and passed the check, and tobj then failed without a line.
#[test]
fn the_most_negative_face_index_names_its_line() {
    let obj = format!("{QUAD}f 1 -9223372036854775808 2\n");
    rejects("index_min", Some(&obj), None, &["mesh.obj:6", "index -9223372036854775808"]);
}

/// Vectors that are finite but whose length overflows f32 were "coinciding" or "parallel"; say what it is,
/// and accept a long `up`, whose length does not matter.
#[test]
fn huge_camera_vectors_are_told_apart() {
    let camera = |eye: &str, target: &str, up: &str| {
        format!(
            "mesh = \"mesh.obj\"\n[camera]\neye = {eye}\ntarget = {target}\nup = {up}\nvfov_deg = 40\n[image]\nwidth = 8\nheight = 8\n"
        )
    };
    let far = camera("[3e38, 0, 5]", "[-3e38, 0, 0]", "[0, 1, 0]");
    rejects("camera_far", Some(QUAD), Some(&far), &["scene.toml: [camera]", "too far apart for 32-bit floats"]);
    let dir = common::scratch("camera_long_up");
    let scene = Scene::load(&write_scene(&dir, Some(QUAD), Some(&camera("[0, 0, 5]", "[0, 0, 0]", "[0, 3e38, 0]"))));
    let scene = scene.unwrap_or_else(|e| panic!("{e:#}"));
    assert!((scene.camera.up - Vec3::Y).length() < 1e-6, "{:?}", scene.camera);
    let dir = common::scratch("camera_long_view");
    let scene = Scene::load(&write_scene(&dir, Some(QUAD), Some(&camera("[0, 0, 2e38]", "[0, 0, 0]", "[0, 1, 0]"))));
    assert!((scene.unwrap_or_else(|e| panic!("{e:#}")).camera.forward + Vec3::Z).length() < 1e-6);
}

/// Found by the fuzz harness: vertex colours (`v x y z r g b`) on some vertices and not on others made tobj
/// fail without a line when a face used an uncoloured one. This renderer does not use vertex colours.
#[test]
fn vertex_colours_on_some_vertices_are_ignored() {
    let scene = load_with("vertex_colours", &format!("v 0 0 0 1 0 0\n{QUAD}"), &[]);
    assert_eq!(scene.mesh.triangles.len(), 2);
}
