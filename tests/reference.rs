//! The CPU reference integrator against closed forms, its convergence, and its determinism.

mod common;

use std::f64::consts::PI;

use glam::Vec3;
use sensorlight::params::EstimatorParams;
use sensorlight::reference::integrator::Integrator;
use sensorlight::scene::{Camera, ImageSize};
use sensorlight::sensors::{SensorKind, frame};

fn params(sensor: SensorKind, epsilon: f32) -> EstimatorParams {
    EstimatorParams { sensor, epsilon, background: Vec3::ZERO }
}

/// Irradiance/π from a rectangle parallel to the receiver: the form factor from a differential area to a
/// corner-aligned a × b rectangle at height h (Howell's catalogue, C-11), combined with signs.
fn parallel_rectangle(x0: f64, x1: f64, y0: f64, y1: f64, h: f64) -> f64 {
    let corner = |a: f64, b: f64| {
        let (a, b) = (a / h, b / h);
        let (sa, sb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
        (a / sa * (b / sa).atan() + b / sb * (a / sb).atan()) / (2.0 * PI)
    };
    corner(x1, y1) - corner(x0, y1) - corner(x1, y0) + corner(x0, y0)
}

#[test]
fn point_under_a_square_light_matches_the_closed_form() {
    let h = 1.0f32;
    let light = common::rect(Vec3::new(0.0, h, 0.0), Vec3::X * 0.5, Vec3::Z * 0.5, -Vec3::Y);
    let floor = common::rect(Vec3::ZERO, Vec3::X * 10.0, Vec3::Z * 10.0, Vec3::Y);
    let camera = Camera::look_at(Vec3::new(0.0, 3.0, 3.0), Vec3::ZERO, Vec3::Y, 60.0).unwrap();
    let scene = common::scene(
        vec![("light", 0, light), ("floor", 1, floor)],
        vec![common::material("light", 0.0, 1.0), common::material("floor", 0.5, 0.0)],
        camera,
        (8, 8),
    );
    let integrator = Integrator::new(&scene, params(SensorKind::Hemicube, 0.0), 65536, 7).unwrap();
    // The rays leave from the sensor origin, lifted by the bias: that is the point the closed form is for.
    let height = (h - frame::BIAS * scene.mesh.scale()) as f64;
    for (x, z) in [(0.0, 0.0), (0.3, 0.2), (0.5, 0.5), (1.0, 0.7), (-0.2, -1.5)] {
        let estimate = integrator.radiance(Vec3::new(x, 0.0, z), Vec3::Y, 11).mean.x as f64;
        let (x, z) = (x as f64, z as f64);
        let exact = parallel_rectangle(-0.5 - x, 0.5 - x, -0.5 - z, 0.5 - z, height);
        eprintln!(
            "square light at ({x}, {z}): R {estimate:.6}, exact {exact:.6}, error {:+.3} %",
            100.0 * (estimate / exact - 1.0)
        );
        assert!((estimate - exact).abs() < 0.005 * exact, "at ({x}, {z}): {estimate} vs {exact}");
    }
}

#[test]
fn white_furnace_gives_one_for_the_hemisphere_and_0_8774_for_the_135_degree_frustum() {
    let scene = common::furnace(1.0);
    let size = ImageSize { width: 12, height: 12 };
    for (sensor, expected) in [(SensorKind::Hemicube, 1.0), (SensorKind::Frustum { fov_deg: 135.0 }, 0.8774)] {
        let image = Integrator::new(&scene, params(sensor, 0.3), 4096, 3).unwrap().render(size, &|_| ());
        let lit: Vec<f32> = image.radiance.iter().filter(|r| r.w > 0.0).map(|r| r.x).collect();
        assert_eq!(lit.len(), 144, "the camera is inside the box");
        let mean = lit.iter().sum::<f32>() / lit.len() as f32;
        eprintln!("furnace, {sensor}: mean R {mean:.5} (expected {expected})");
        assert!((mean - expected).abs() < 0.005 * expected, "{sensor}: mean R {mean}, expected {expected}");
        assert!(lit.iter().all(|r| (r - expected).abs() < 0.02), "{sensor}: a pixel is far off");
    }
}

#[test]
fn no_emitters_and_zero_epsilon_is_exactly_black() {
    let mut scene = common::furnace(0.0);
    scene.mesh.materials[0].kd = Vec3::splat(0.9);
    let image = Integrator::new(&scene, params(SensorKind::Hemicube, 0.0), 64, 1).unwrap().render(scene.image, &|_| ());
    assert!(image.image.iter().all(|p| p.truncate() == Vec3::ZERO));
    // …while ε > 0 makes it glow Kd·ε: the test above is not vacuous.
    let image = Integrator::new(&scene, params(SensorKind::Hemicube, 0.5), 64, 1).unwrap().render(scene.image, &|_| ());
    let r = image.radiance[0].x;
    assert!((r - 0.45).abs() < 1e-5, "{r}");
}

#[test]
fn error_falls_at_least_like_one_over_sqrt_n() {
    let scene = sensorlight::scene::Scene::load(&common::project("scenes/cornell/cornell.toml")).unwrap();
    let size = ImageSize { width: 20, height: 20 };
    let p = params(SensorKind::Hemicube, 0.1);
    let truth = Integrator::new(&scene, p, 16384, 99).unwrap().render(size, &|_| ()).radiance;
    let rms = |n: u32| {
        let r = Integrator::new(&scene, p, n, 5).unwrap().render(size, &|_| ()).radiance;
        let sum: f64 = r.iter().zip(&truth).map(|(a, b)| (*a - *b).truncate().length_squared() as f64).sum();
        (sum / r.len() as f64).sqrt()
    };
    let ns = [16u32, 64, 256, 1024];
    let errors: Vec<f64> = ns.iter().map(|&n| rms(n)).collect();
    // Least-squares slope of log(error) against log(N).
    let xs: Vec<f64> = ns.iter().map(|&n| (n as f64).ln()).collect();
    let ys: Vec<f64> = errors.iter().map(|e| e.ln()).collect();
    let (mx, my) = (xs.iter().sum::<f64>() / 4.0, ys.iter().sum::<f64>() / 4.0);
    let slope = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum::<f64>()
        / xs.iter().map(|x| (x - mx) * (x - mx)).sum::<f64>();
    eprintln!("RMS error {errors:?} at N {ns:?}: slope {slope:.3}");
    assert!(slope <= -0.45, "error {errors:?} at N {ns:?}: slope {slope:.3}, expected ≤ −0.5");
    assert!(errors.windows(2).all(|w| w[1] < w[0]), "error does not fall monotonically: {errors:?}");
}

#[test]
fn same_command_twice_writes_identical_files() {
    let dir = common::scratch("reference_determinism");
    let scene = common::project("scenes/cornell/cornell.toml");
    let mut outputs = Vec::new();
    for run in ["a", "b"] {
        let out = dir.join(format!("{run}.exr"));
        let args = [
            "reference",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--width",
            "24",
            "--height",
            "16",
            "--samples",
            "64",
        ];
        let result = common::sensorlight(&args);
        assert!(result.status.success(), "{}", common::stderr(&result));
        assert!(common::stderr(&result).contains("rays/s"), "reports its speed");
        outputs.push((std::fs::read(&out).unwrap(), std::fs::read(out.with_extension("png")).unwrap()));
    }
    assert!(outputs[0] == outputs[1], "two runs wrote different files");
}

#[test]
fn bad_reference_parameters_are_clear_errors() {
    let scene = common::project("scenes/cornell/cornell.toml");
    for (flags, expected) in [
        (&["--samples", "6"][..], "multiple of 4"),
        (&["--sensor", "frustum", "--fov", "180"], "--fov"),
        (&["--epsilon", "-1"], "--epsilon"),
        (&["--background", "1,2"], "R,G,B"),
    ] {
        let out = common::scratch("reference_bad").join("x.exr");
        let mut args = vec!["reference", scene.to_str().unwrap(), "-o", out.to_str().unwrap()];
        args.extend_from_slice(flags);
        common::expect_failure(&args, expected);
        assert!(!out.exists());
    }
}
