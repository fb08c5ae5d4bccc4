//! The first hour with real files (issue 24): what a user sees of a bare mesh's image. A closed room gets a
//! camera inside; a black image says why; the background is seen, with coverage in alpha; the PNG of a mesh
//! is exposed automatically; `--aovs` writes what a denoiser takes.

mod common;

use std::path::{Path, PathBuf};

use sensorlight::output::exr;

/// A closed box 4 × 2.5 × 6 m (walls of Kd 0.7) with a light panel under its ceiling facing down, as
/// `box.obj` + `box.mtl` in `dir`.
fn closed_room(dir: &Path) -> PathBuf {
    let mtl = "newmtl white\nKd 0.7 0.7 0.7\nnewmtl light\nKd 0 0 0\nKe 10 10 10\n";
    std::fs::write(dir.join("box.mtl"), mtl).unwrap();
    // Corners 1–8 of the box; faces wound to face inwards.
    let mut obj = String::from("mtllib box.mtl\n");
    for (x, y, z) in [(-2, 0, -3), (2, 0, -3), (2, 0, 3), (-2, 0, 3)] {
        obj += &format!("v {x} {y} {z}\n");
    }
    for (x, y, z) in [(-2, 2.5, -3), (2, 2.5, -3), (2, 2.5, 3), (-2, 2.5, 3)] {
        obj += &format!("v {x} {y} {z}\n");
    }
    obj += "usemtl white\n";
    obj += "g floor\nf 1 4 3 2\ng ceiling\nf 5 6 7 8\n";
    obj += "g walls\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
    obj += "g light\nusemtl light\nv -0.5 2.4 -0.5\nv 0.5 2.4 -0.5\nv 0.5 2.4 0.5\nv -0.5 2.4 0.5\nf 9 10 11 12\n";
    let path = dir.join("box.obj");
    std::fs::write(&path, obj).unwrap();
    path
}

/// `sensorlight render input -o out` at 16² with small sensors and `extra`; succeeds; returns stderr.
fn render(input: &Path, out: &Path, extra: &[&str]) -> String {
    let mut args = vec!["render", input.to_str().unwrap(), "-o", out.to_str().unwrap()];
    args.extend_from_slice(&["--width", "16", "--height", "16", "--sensor-size", "16"]);
    args.extend_from_slice(extra);
    let run = common::sensorlight(&args);
    let stderr = common::stderr(&run);
    assert!(run.status.success(), "{args:?}: {stderr}");
    stderr
}

fn channels(path: &Path, names: &[&str]) -> Vec<Vec<f32>> {
    exr::read_channels(path, names).unwrap().2
}

#[test]
fn a_closed_room_is_seen_from_inside_and_lit() {
    let dir = common::scratch("first_hour_closed_room");
    let mesh = closed_room(&dir);
    let (out, toml) = (dir.join("room.exr"), dir.join("room.toml"));
    let stderr = render(&mesh, &out, &["--bounces", "0", "--write-scene", toml.to_str().unwrap()]);
    assert!(stderr.contains("the camera is inside, at [0, 1.25, 0]"), "{stderr}");
    assert!(!stderr.contains("the image is black"), "{stderr}");
    let c = channels(&out, &["G", "A"]);
    let lit = c[0].iter().filter(|&&g| g > 0.05).count();
    assert!(lit > 16 * 16 / 2, "most of the room is lit from inside: {lit} of 256 pixels");
    assert!(c[1].iter().all(|&a| a == 1.0), "every pixel sees a wall");
    let scene = sensorlight::scene::Scene::load(&toml).unwrap();
    assert_eq!(scene.camera.eye, glam::Vec3::new(0.0, 1.25, 0.0), "the written scene keeps the inside camera");
}

#[test]
fn a_camera_that_sees_nothing_lit_says_so() {
    let dir = common::scratch("first_hour_black");
    closed_room(&dir);
    // The closed room from outside: its roof, which nothing lights.
    let toml = "mesh = \"box.obj\"\n[camera]\neye = [0, 12, 0.5]\ntarget = [0, 0, 0]\nup = [0, 1, 0]\nvfov_deg = 40\n\
                [image]\nwidth = 16\nheight = 16\n";
    std::fs::write(dir.join("outside.toml"), toml).unwrap();
    let out = dir.join("outside.exr");
    let stderr = render(&dir.join("outside.toml"), &out, &["--bounces", "0"]);
    assert!(
        stderr.contains("warning: the image is black: no lit surface is in view (the camera is at [0, 12, 0.5]"),
        "{stderr}"
    );
    assert!(stderr.contains("move the camera"), "{stderr}");
    assert!(channels(&out, &["R"])[0].iter().all(|&r| r == 0.0));
}

/// A mesh without emitters, under its white sky: the sky shows where the camera sees no surface, alpha 0
/// there and 1 on the mesh; the PNG shows the sky white.
#[test]
fn the_sky_is_seen_around_a_mesh_and_alpha_is_coverage() {
    let dir = common::scratch("first_hour_sky");
    // A tent: a floor quad and one triangle standing on it; framed from −z, the sky shows around it.
    std::fs::write(dir.join("tent.obj"), "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nv 0 1 0\nf 1 4 3 2\nf 1 2 5\n")
        .unwrap();
    let out = dir.join("tent.exr");
    render(&dir.join("tent.obj"), &out, &["--bounces", "0", "--exposure", "0"]);
    let c = channels(&out, &["R", "G", "B", "A"]);
    let sky: Vec<usize> = (0..256).filter(|&i| c[3][i] == 0.0).collect();
    assert!(!sky.is_empty() && sky.len() < 256, "{} sky pixels", sky.len());
    for &i in &sky {
        assert_eq!([c[0][i], c[1][i], c[2][i]], [1.0; 3], "sky pixel {i}");
    }
    // Alpha is coverage: 0 on the sky, 1 inside the mesh, the share of the square on the mesh at its edges.
    assert!((0..256).all(|i| (0.0..=1.0).contains(&c[3][i])), "alpha is coverage");
    let edges = (0..256).filter(|&i| c[3][i] > 0.0 && c[3][i] < 1.0).count();
    assert!(edges > 0 && edges < 256 - sky.len(), "{edges} pixels partly covered");
    let png = std::fs::read(out.with_extension("png")).unwrap();
    assert!(!png.is_empty());
}

/// A mesh with its own light keeps a black background, as before: its background pixels are 0, alpha 0.
#[test]
fn a_black_background_stays_black() {
    let dir = common::scratch("first_hour_black_background");
    let out = dir.join("cornell.exr");
    render(&common::project("scenes/cornell/cornell.obj"), &out, &["--bounces", "0", "--aovs"]);
    let c = channels(&out, &["R", "G", "B", "A", "surface_id"]);
    let background = (0..256).filter(|&i| c[4][i] == 0.0).count();
    assert!(background > 0, "the framed box leaves background around it");
    for (i, &id) in c[4].iter().enumerate() {
        // Alpha is coverage; a pixel's id is what most of it shows.
        let alpha = c[3][i];
        assert!(
            if id == 0.0 { alpha <= 0.5 } else { alpha > 0.0 && alpha <= 1.0 },
            "pixel {i}: alpha {alpha}, id {id}"
        );
        if alpha == 0.0 {
            assert_eq!([c[0][i], c[1][i], c[2][i]], [0.0; 3], "pixel {i}");
        }
    }
}

/// The mean 8-bit value of a PNG's RGB.
fn png_mean(path: &Path) -> f64 {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let bytes = &buf[..info.buffer_size()];
    bytes.iter().map(|&b| b as f64).sum::<f64>() / bytes.len() as f64
}

/// A dim mesh (under a sky of 0.02) gets an automatic exposure that brightens its PNG, said in the summary
/// and written into `--write-scene`'s file; `--exposure` overrides it.
#[test]
fn a_dim_mesh_is_exposed_automatically_and_the_flag_wins() {
    let dir = common::scratch("first_hour_exposure");
    std::fs::write(dir.join("tent.obj"), "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nv 0 1 0\nf 1 4 3 2\nf 1 2 5\n")
        .unwrap();
    let mesh = dir.join("tent.obj");
    let dim = ["--bounces", "0", "--background", "0.02"];
    let (auto, toml) = (dir.join("auto.exr"), dir.join("auto.toml"));
    let stderr = render(&mesh, &auto, &[&dim[..], &["--write-scene", toml.to_str().unwrap()]].concat());
    let said = stderr.lines().find(|l| l.starts_with("exposure ")).unwrap_or_else(|| panic!("{stderr}"));
    assert!(said.contains("(auto: 99th percentile of lit pixels"), "{said}");
    let stops: f32 = said["exposure ".len()..].split(' ').next().unwrap().parse().unwrap();
    assert!(stops > 4.0, "a sky of 0.02 is brightened by more than 4 stops: {said}");
    let fixed = dir.join("fixed.exr");
    let stderr = render(&mesh, &fixed, &[&dim[..], &["--exposure", "0"]].concat());
    assert!(!stderr.contains("(auto:"), "{stderr}");
    let (bright, plain) = (png_mean(&auto.with_extension("png")), png_mean(&fixed.with_extension("png")));
    assert!(bright > 3.0 * plain && bright > 100.0, "auto {bright} vs --exposure 0 {plain}");
    let written = std::fs::read_to_string(&toml).unwrap();
    assert!(written.contains(&format!("exposure = {stops:.1}")), "{written}");
}

/// A scene file that sets no exposure, lit so brightly that most of its PNG would clip white at the default
/// (issue 42, item 8: veach's door ajar, 67 % of its pixels white, without a word): the PNG takes the
/// automatic exposure, and the summary says why; a scene file that sets `exposure` keeps it, clipped as
/// asked.
#[test]
fn a_scene_file_that_would_clip_is_exposed_automatically_and_says_so() {
    let dir = common::scratch("first_hour_clipping");
    std::fs::write(dir.join("tent.obj"), "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nv 0 1 0\nf 1 4 3 2\nf 1 2 5\n")
        .unwrap();
    let camera = "[camera]\neye = [0, 1.5, 4]\ntarget = [0, 0.3, 0]\nvfov_deg = 40\n[image]\nwidth = 16\nheight = 16\n";
    let scene = |name: &str, render: &str| {
        let path = dir.join(name);
        std::fs::write(
            &path,
            format!("mesh = \"tent.obj\"\n{camera}[render]\nbackground = [20, 20, 20]\nbounces = 0\n{render}"),
        )
        .unwrap();
        path
    };
    let (bright, set) = (scene("bright.toml", ""), scene("set.toml", "exposure = 0\n"));
    let (auto, fixed) = (dir.join("auto.exr"), dir.join("fixed.exr"));
    let stderr = render(&bright, &auto, &[]);
    let said = stderr.lines().find(|l| l.starts_with("exposure ")).unwrap_or_else(|| panic!("{stderr}"));
    assert!(said.contains("(auto: at the default 0, 100 % of lit pixels would clip white; 99th percentile"), "{said}");
    let stops: f32 = said["exposure ".len()..].split(' ').next().unwrap().parse().unwrap();
    assert!(stops < -3.0, "a sky of 20 is darkened by more than 3 stops: {said}");
    let stderr = render(&set, &fixed, &[]);
    assert!(!stderr.contains("(auto:"), "{stderr}");
    let (exposed, clipped) = (png_mean(&auto.with_extension("png")), png_mean(&fixed.with_extension("png")));
    // The sky (20) stays white either way; the tent does not.
    assert!(clipped > 254.0 && exposed < 245.0, "auto {exposed} vs the scene file's exposure 0: {clipped}");
}

/// `--aovs` writes what Open Image Denoise takes beside the beauty pass, right on the Cornell box: each
/// pixel's albedo is its material's Kd (the red wall's among them), normals are unit and face the camera,
/// depth is the distance along the pixel's ray to what it sees (against a CPU ray cast through the BVH).
#[test]
fn aovs_hold_albedo_normal_and_depth_for_a_denoiser() {
    use glam::Vec3;
    use sensorlight::scene::{Scene, bvh::Bvh};
    let dir = common::scratch("first_hour_aovs");
    let out = dir.join("cornell.exr");
    let toml = common::project("scenes/cornell/cornell.toml");
    let (w, h) = (24, 20);
    let mut args = vec!["render", toml.to_str().unwrap(), "-o", out.to_str().unwrap(), "--aovs"];
    args.extend_from_slice(&["--width", "24", "--height", "20", "--sensor-size", "16", "--bounces", "0"]);
    let run = common::sensorlight(&args);
    assert!(run.status.success(), "{}", common::stderr(&run));
    let names = ["surface_id", "albedo.R", "albedo.G", "albedo.B", "normal.X", "normal.Y", "normal.Z", "depth.Z"];
    let c = channels(&out, &names);
    let scene = Scene::load(&toml).unwrap();
    let bvh = Bvh::build(&scene.mesh.triangles);
    let red = Vec3::new(0.63, 0.065, 0.05);
    let (mut on_red, mut surfaces) = (0, 0);
    for i in 0..w * h {
        let (x, y) = (i % w, i / w);
        let id = c[0][i] as u32;
        let albedo = Vec3::new(c[1][i], c[2][i], c[3][i]);
        let normal = Vec3::new(c[4][i], c[5][i], c[6][i]);
        if id == 0 {
            assert_eq!((albedo, normal, c[7][i]), (Vec3::ZERO, Vec3::ZERO, 0.0), "background pixel {i}");
            continue;
        }
        surfaces += 1;
        assert_eq!(albedo, scene.mesh.material_of(id).kd, "pixel ({x}, {y}): albedo is its material's Kd");
        on_red += (albedo == red) as usize;
        assert!((normal.length() - 1.0).abs() < 1e-4, "pixel ({x}, {y}): |n| = {}", normal.length());
        let ray = scene.camera.ray(x as f32 + 0.5, y as f32 + 0.5, w as u32, h as u32);
        assert!(normal.dot(ray.dir) < 0.0, "pixel ({x}, {y}): the normal faces the camera");
        // Away from silhouettes the raster and the ray see the same point.
        let edge = (x.saturating_sub(1)..(x + 2).min(w))
            .any(|u| (y.saturating_sub(1)..(y + 2).min(h)).any(|v| c[0][v * w + u] != c[0][i]));
        if !edge {
            let t = bvh.intersect(&ray, 0.0, f32::INFINITY).expect("the ray sees what the pixel does").t;
            assert!((c[7][i] - t).abs() <= 1e-3 * t, "pixel ({x}, {y}): depth {} vs ray {t}", c[7][i]);
        }
    }
    assert!(surfaces > 0 && on_red > 0, "{on_red} pixels on the red wall of {surfaces}");
}
