//! glTF 2.0 scenes (`scene::gltf`): node transforms, normals, materials, the camera, against the same scene
//! written as an OBJ, and rendered against the oracle; what is refused and what is said.

mod common;

use glam::{Quat, Vec3};
use sensorlight::scene::{ImageSize, Scene};

const SIZE: ImageSize = ImageSize { width: 96, height: 72 };

/// The `.glb`, the `.gltf` + `.bin` and the OBJ of one scene load to the same triangles (to float rounding),
/// corner normals, materials and surfaces; the glTF's camera is its camera node's.
#[test]
fn a_gltf_scene_is_the_same_scene_as_its_obj() {
    let dir = common::scratch("gltf-same");
    let obj = Scene::from_mesh(&common::gltf::write_obj(&dir, "scene"), SIZE).unwrap();
    for path in [common::gltf::write_glb(&dir, "scene", &[]), common::gltf::write_gltf(&dir, "scene")] {
        let scene = Scene::from_mesh(&path, SIZE).unwrap();
        let (a, b) = (&scene.mesh, &obj.mesh);
        assert_eq!(a.triangles.len(), b.triangles.len(), "{}", path.display());
        for (k, (ta, tb)) in a.triangles.iter().zip(&b.triangles).enumerate() {
            let close = (0..3).all(|c| (ta.v[c] - tb.v[c]).abs().max_element() < 1e-5);
            assert!(close, "{}: triangle {k}: {:?} against the OBJ's {:?}", path.display(), ta.v, tb.v);
            assert!(ta.normal.dot(tb.normal) > 0.9999, "triangle {k}: front {} against {}", ta.normal, tb.normal);
            let (ma, mb) = (a.material_of(ta.surface), b.material_of(tb.surface));
            assert!((ma.kd - mb.kd).abs().max_element() < 1e-6 && ma.ke == mb.ke, "triangle {k}: {ma:?} {mb:?}");
        }
        assert_eq!(a.surfaces.len(), b.surfaces.len());
        assert_eq!(a.shading.len(), b.shading.len(), "the quads' normals are read");
        for (na, nb) in a.shading.iter().zip(&b.shading) {
            assert!((0..3).all(|c| na[c].dot(nb[c]) > 0.9999), "{na:?} against {nb:?}");
        }
        // The camera node: at its translation, looking along −z turned by its pitch, 0.8 rad tall.
        let c = &scene.camera;
        let forward = Quat::from_rotation_x(common::gltf::CAMERA_PITCH) * -Vec3::Z;
        assert!((c.eye - common::gltf::CAMERA_EYE).length() < 1e-5, "eye {}", c.eye);
        assert!(c.forward.dot(forward) > 0.99999, "forward {}", c.forward);
        assert!((c.vfov - 0.8).abs() < 1e-5, "vfov {}", c.vfov);
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    }
}

/// The `.glb` rendered at the defaults (direct light) against the oracle over pixel squares, which reads the
/// same file: within 2 % inside, 3 % over the whole image.
#[test]
fn a_glb_renders_within_two_percent_of_the_oracle() {
    let dir = common::scratch("gltf-oracle");
    let scene = Scene::from_mesh(&common::gltf::write_glb(&dir, "scene", &[]), SIZE).unwrap();
    let [on, _] = common::against_the_area_oracle(&scene, 0.0, 1024);
    assert!(on.interior.own_error.unwrap() <= 0.02, "interior {:?}", on.interior);
    assert!(on.whole.own_error.unwrap() <= 0.03, "whole image {:?}", on.whole);
}

/// `render model.glb` works as `render mesh.obj` does; a file that requires an extension sensorlight lacks
/// is refused naming it; a scene file (TOML) may name a glTF mesh.
#[test]
fn the_cli_renders_a_glb_and_refuses_an_unsupported_extension() {
    let dir = common::scratch("gltf-cli");
    let glb = common::gltf::write_glb(&dir, "scene", &[]);
    let out = dir.join("out.exr");
    let run = common::sensorlight(&["render", glb.to_str().unwrap(), "-o", out.to_str().unwrap(), "--bounces", "0"]);
    assert!(run.status.success(), "{}", common::stderr(&run));
    assert!(out.exists() && dir.join("out.png").exists());

    let toml = dir.join("scene.toml");
    std::fs::write(
        &toml,
        "mesh = \"scene.glb\"\n[camera]\neye = [0, 1.3, 3.4]\ntarget = [0, 0.5, 0]\nvfov_deg = 45\n[image]\nwidth = 32\nheight = 24\n",
    )
    .unwrap();
    let scene = Scene::load(&toml).unwrap();
    assert_eq!(scene.mesh.triangles.len(), 2 * 2 + 2 * 12 + 2, "floor, wall, two boxes, light");

    let bad = common::gltf::write_glb(&dir, "draco", &["KHR_draco_mesh_compression"]);
    let message = common::expect_failure(&["render", bad.to_str().unwrap(), "-o", out.to_str().unwrap()], "KHR_draco");
    assert!(message.contains("draco.glb") && message.contains("does not support"), "{message}");
    let corrupt = dir.join("corrupt.glb");
    let mut bytes = std::fs::read(&glb).unwrap();
    bytes.truncate(bytes.len() / 2);
    std::fs::write(&corrupt, bytes).unwrap();
    let message =
        common::expect_failure(&["render", corrupt.to_str().unwrap(), "-o", out.to_str().unwrap()], "corrupt.glb");
    assert!(message.contains("glTF"), "{message}");
}

/// Found by fuzzing: a primitive whose `POSITION` names no accessor made the `gltf` crate's own validation
/// index out of bounds (a panic); it is a clear error naming the file, and nothing panics on stderr.
#[test]
fn a_position_naming_no_accessor_is_an_error_not_a_panic() {
    let dir = common::scratch("gltf-bad-accessor");
    let path = common::gltf::write_gltf(&dir, "scene");
    let text = std::fs::read_to_string(&path).unwrap().replacen("\"POSITION\": 0", "\"POSITION\": 99", 1);
    assert!(text.contains("\"POSITION\": 99"));
    std::fs::write(&path, text).unwrap();
    let out = dir.join("out.exr");
    let message =
        common::expect_failure(&["render", path.to_str().unwrap(), "-o", out.to_str().unwrap()], "scene.gltf");
    assert!(message.contains("not a valid glTF"), "{message}");
    assert!(!out.exists());
}

/// An accessor whose count runs past its buffer view (here 2³¹ positions) is a malformed file, refused naming
/// the accessor: the glTF reader answered no positions for it, and the mesh was skipped with a warning.
#[test]
fn an_accessor_past_its_buffer_view_is_refused_naming_it() {
    let dir = common::scratch("gltf-accessor-count");
    let path = common::gltf::write_gltf_edited(&dir, "scene", |doc| doc["accessors"][0]["count"] = (1u64 << 31).into());
    let out = dir.join("out.exr");
    let message =
        common::expect_failure(&["render", path.to_str().unwrap(), "-o", out.to_str().unwrap()], "scene.gltf");
    assert!(message.contains("malformed: accessor 0 (Positions: 2147483648 elements"), "{message}");
    assert!(message.contains("buffer view"), "{message}");
    assert!(!out.exists());
}

/// `KHR_lights_punctual`: a point light becomes a small emitting sphere whose irradiance on the floor is
/// the light's, `I·cosθ/d²`, within 3 % (the lights' closed form on its facets); a spot light lights all
/// around (said); the directional light is the sun, along its node's +z, its intensity the irradiance.
#[test]
fn a_point_light_lights_the_floor_as_its_intensity_says() {
    let dir = common::scratch("gltf-lights");
    let (intensity, at) = (40.0f32, Vec3::new(0.2, 1.5, 0.1));
    let path = common::gltf::write_gltf_edited(&dir, "scene", |doc| {
        doc["extensionsUsed"] = serde_json::json!(["KHR_materials_emissive_strength", "KHR_lights_punctual"]);
        doc["extensions"] = serde_json::json!({ "KHR_lights_punctual": { "lights": [
            { "name": "bulb", "type": "point", "color": [1.0, 0.5, 0.25], "intensity": intensity },
            { "name": "spot", "type": "spot", "intensity": 1.0, "spot": { "outerConeAngle": 0.5 } },
            { "name": "sun", "type": "directional", "intensity": 3.0 },
        ] } });
        let nodes = doc["nodes"].as_array_mut().unwrap();
        for (light, translation) in [(0, at), (1, Vec3::new(-1.0, 1.0, 0.0)), (2, Vec3::ZERO)] {
            let name = ["bulb", "spot", "sun"][light];
            nodes.push(serde_json::json!({
                "name": name,
                "translation": translation.to_array(),
                "extensions": { "KHR_lights_punctual": { "light": light } },
            }));
        }
        let count = nodes.len();
        let roots = doc["scenes"][0]["nodes"].as_array_mut().unwrap();
        roots.extend([count - 3, count - 2, count - 1].map(|n| serde_json::json!(n)));
    });
    let scene = Scene::from_mesh(&path, SIZE).unwrap();
    let said = |what: &str| scene.warnings.iter().any(|w| w.contains(what));
    assert!(said("'spot'") && said("cone"), "{:?}", scene.warnings);
    let sun = scene.sun.expect("the directional light is the sun");
    assert!((sun.direction - Vec3::Z).length() < 1e-6 && sun.irradiance == Vec3::splat(3.0), "{sun:?}");
    assert_eq!(scene.mesh.surfaces.last().unwrap().name, "sun/sun");
    let lights = sensorlight::light::groups::Lights::new(&scene.mesh);
    let bulb = scene.mesh.surfaces.iter().position(|s| s.name.contains("'bulb'")).unwrap() as u32 + 1;
    let group = lights.surface_group[&bulb] as usize;
    for floor in [Vec3::new(0.2, 0.0, 0.1), Vec3::new(1.2, 0.0, -0.6)] {
        let d = at - floor;
        let expected = Vec3::new(1.0, 0.5, 0.25) * intensity * (d.normalize().y) / d.length_squared();
        let e = lights.unoccluded(floor, Vec3::Y)[group];
        assert!(((e - expected) / expected).abs().max_element() < 0.03, "at {floor}: {e} against {expected}");
    }
}

/// A scene file without `[camera]` takes its glTF mesh's camera; naming an OBJ (which has none), it is an
/// error that says so.
#[test]
fn a_scene_file_without_a_camera_takes_the_gltfs() {
    let dir = common::scratch("gltf-camera");
    common::gltf::write_glb(&dir, "scene", &[]);
    common::gltf::write_obj(&dir, "scene");
    let image = "[image]\nwidth = 32\nheight = 24\n";
    std::fs::write(dir.join("glb.toml"), format!("mesh = \"scene.glb\"\n{image}")).unwrap();
    let scene = Scene::load(&dir.join("glb.toml")).unwrap();
    assert!((scene.camera.eye - common::gltf::CAMERA_EYE).length() < 1e-5, "eye {}", scene.camera.eye);
    assert_eq!((scene.image.width, scene.image.height), (32, 24));
    std::fs::write(dir.join("obj.toml"), format!("mesh = \"scene.obj\"\n{image}")).unwrap();
    let e = format!("{:#}", Scene::load(&dir.join("obj.toml")).err().unwrap());
    assert!(e.contains("obj.toml") && e.contains("no [camera]") && e.contains("scene.obj"), "{e}");
}

/// Messages in glTF's words, about what is used (issue 42, item 9): the default material (white) is said
/// to have a base colour of 1, not `Kd`; a used material's metalness is named as not used, an unused
/// material's is not; a position that is not a number is said as such, not as a mesh too large for floats;
/// a `.glb` with a wrong magic is called an invalid glTF file, not a binary file.
#[test]
fn gltf_messages_use_its_words_and_speak_of_what_is_used() {
    let dir = common::scratch("gltf-messages");
    let path = common::gltf::write_gltf_edited(&dir, "words", |doc| {
        doc["meshes"][2]["primitives"][0].as_object_mut().unwrap().remove("material");
        doc["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] = 1.0.into();
        let chrome = serde_json::json!({ "name": "chrome", "pbrMetallicRoughness": { "metallicFactor": 1.0 } });
        doc["materials"].as_array_mut().unwrap().push(chrome);
    });
    let scene = Scene::from_mesh(&path, SIZE).unwrap();
    let grey = scene.warnings.iter().filter(|w| w.contains("material 'grey': metalness (treated as diffuse)"));
    assert_eq!(grey.count(), 1, "{:?}", scene.warnings);
    assert!(!scene.warnings.iter().any(|w| w.contains("chrome")), "{:?}", scene.warnings);
    let albedo = sensorlight::gi::albedo_warnings(&scene.mesh);
    assert!(albedo.iter().any(|w| w.contains("material '(glTF default, white)' has base colour 1 1 1")), "{albedo:?}");
    assert!(!albedo.iter().any(|w| w.contains("Kd")), "{albedo:?}");

    let nan = common::gltf::write_gltf(&dir, "nan");
    let mut bin = std::fs::read(dir.join("nan.bin")).unwrap();
    bin[0..4].copy_from_slice(&f32::NAN.to_le_bytes()); // the first quad corner's x
    std::fs::write(dir.join("nan.bin"), bin).unwrap();
    let error = format!("{:#}", Scene::from_mesh(&nan, SIZE).unwrap_err());
    assert!(error.contains("with a corner that is not a finite number"), "{error}");
    assert!(!error.contains("too large"), "{error}");

    let glb = common::gltf::write_glb(&dir, "magic", &[]);
    let mut bytes = std::fs::read(&glb).unwrap();
    bytes[0..4].copy_from_slice(b"gLtF");
    std::fs::write(&glb, bytes).unwrap();
    let out = dir.join("out.exr");
    let stderr = common::expect_failure(&["render", glb.to_str().unwrap(), "-o", out.to_str().unwrap()], "magic.glb");
    assert!(stderr.contains("not a valid glTF 2.0 file") && !stderr.contains("binary file"), "{stderr}");
}
