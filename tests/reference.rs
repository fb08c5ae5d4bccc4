//! The CPU reference integrator against closed forms, its convergence, and its determinism.

mod common;

use std::f64::consts::PI;

use glam::{DVec3, Vec3};
use sensorlight::light::polygon::{self, Domain, Receiver, parallel_rectangle};
use sensorlight::params::{Antialiasing, EstimatorParams, Indirect};
use sensorlight::reference::integrator::Integrator;
use sensorlight::scene::{Camera, ImageSize, Scene};
use sensorlight::sensors::frame::SensorFrame;
use sensorlight::sensors::{SensorKind, frame};

fn params(sensor: SensorKind, epsilon: f32) -> EstimatorParams {
    EstimatorParams { sensor, indirect: Indirect::Epsilon(epsilon), background: Vec3::ZERO }
}

/// The sensor the oracle integrates for at `p` with normal `n`, in f64 for the closed forms.
fn receiver(scene: &Scene, p: Vec3, n: Vec3) -> Receiver {
    let f = SensorFrame::new(p, n, frame::BIAS * scene.mesh.scale());
    Receiver { origin: f.origin.as_dvec3(), t: f.t.as_dvec3(), b: f.b.as_dvec3(), n: f.n.as_dvec3() }
}

/// `R` from an unoccluded polygon of radiance `ke` (module `light::polygon`): `Ke·Ω⊥/π`.
fn exact_r(receiver: &Receiver, domain: Domain, ke: f64, polygon: &[DVec3]) -> f64 {
    ke * polygon::projected_solid_angle(receiver, domain, polygon) / PI
}

/// A rectangle parallel to the floor at height `y`, `[x0, x1] × [z0, z1]`, its front facing down.
fn ceiling_rect(x0: f64, x1: f64, z0: f64, z1: f64, y: f64) -> Vec<DVec3> {
    vec![DVec3::new(x0, y, z0), DVec3::new(x1, y, z0), DVec3::new(x1, y, z1), DVec3::new(x0, y, z1)]
}

fn relative_error(estimate: f64, exact: f64) -> f64 {
    estimate / exact - 1.0
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
        let estimate = integrator.radiance(Vec3::new(x, 0.0, z), Vec3::Y, 11);
        let (r, noise) = (estimate.mean.x as f64, estimate.std_error.x as f64);
        let (x, z) = (x as f64, z as f64);
        let exact = parallel_rectangle(-0.5 - x, 0.5 - x, -0.5 - z, 0.5 - z, height);
        let error = relative_error(r, exact);
        eprintln!(
            "square light at ({x}, {z}): R {r:.6}, exact {exact:.6}, error {:+.4} % (noise ±{:.4} %)",
            100.0 * error,
            100.0 * noise / exact
        );
        assert!(error.abs() < 0.003, "at ({x}, {z}): {r} vs {exact}");
    }
}

/// A penumbra with a closed form: a 1 × 1 light at height 2 and, at height 1, a large occluder parallel to it
/// whose edge `x = 0` crosses under it. From a point on the floor the occluder hides the part of the light
/// left of the edge's central projection onto the light's plane, so the visible part is a rectangle.
#[test]
fn a_penumbra_matches_the_visible_rectangle_of_the_light() {
    let (light_h, occluder_h, ke) = (2.0f64, 1.0f64, 5.0f64);
    let light = common::rect(Vec3::new(0.0, light_h as f32, 0.0), Vec3::X * 0.5, Vec3::Z * 0.5, -Vec3::Y);
    let occluder = common::rect(Vec3::new(-2.5, occluder_h as f32, 0.0), Vec3::X * 2.5, Vec3::Z * 5.0, Vec3::Y);
    let floor = common::rect(Vec3::ZERO, Vec3::X * 5.0, Vec3::Z * 5.0, Vec3::Y);
    let camera = Camera::look_at(Vec3::new(0.0, 3.0, 3.0), Vec3::ZERO, Vec3::Y, 60.0).unwrap();
    let scene = common::scene(
        vec![("light", 0, light), ("occluder", 1, occluder), ("floor", 1, floor)],
        vec![common::material("light", 0.0, ke as f32), common::material("grey", 0.5, 0.0)],
        camera,
        (8, 8),
    );
    let integrator = Integrator::new(&scene, params(SensorKind::Hemicube, 0.0), 65536, 5).unwrap();
    for (x, z) in [(-0.35, 0.0), (-0.2, 0.4), (0.0, -0.3), (0.15, 0.8), (0.4, -1.0)] {
        let p = Vec3::new(x, 0.0, z);
        let at = receiver(&scene, p, Vec3::Y);
        let o = at.origin;
        // The edge x = 0 at the occluder's height, projected from o onto the light's plane.
        let cut = o.x + (0.0 - o.x) * (light_h - o.y) / (occluder_h - o.y);
        assert!(-0.5 < cut && cut < 0.5, "({x}, {z}) is in the penumbra");
        let visible = ceiling_rect(cut, 0.5, -0.5, 0.5, light_h);
        let exact = exact_r(&at, Domain::Hemisphere, ke, &visible);
        // The same rectangle by Howell's form factor: the two closed forms agree.
        let howell = ke * parallel_rectangle(cut - o.x, 0.5 - o.x, -0.5 - o.z, 0.5 - o.z, light_h - o.y);
        assert!((exact - howell).abs() < 1e-9 * exact, "{exact} vs {howell}");
        let estimate = integrator.radiance(p, Vec3::Y, 3);
        let (r, noise) = (estimate.mean.x as f64, estimate.std_error.x as f64);
        let error = relative_error(r, exact);
        eprintln!(
            "penumbra at ({x}, {z}): light visible from x = {cut:.3}, R {r:.6}, exact {exact:.6}, error {:+.4} % \
             (noise ±{:.4} %)",
            100.0 * error,
            100.0 * noise / exact
        );
        assert!(error.abs() < 0.003, "at ({x}, {z}): {r} vs {exact}");
    }
}

/// A small bright light (0.1 m at 2 m, Ke 2000) over an occluder: the case a cosine-only oracle cannot check
/// (from right below, 1 cosine direction in 1250 hits the light). With light samples it converges in seconds.
#[test]
fn a_small_light_over_an_occluder_converges_to_half_a_percent() {
    let scene = common::small_light((64, 64));
    let samples = 256;
    let integrator = Integrator::new(&scene, params(SensorKind::Hemicube, 0.1), samples, 1).unwrap();
    let start = std::time::Instant::now();
    let image = integrator.render(scene.image, sensorlight::params::Antialiasing::Off, &|_| ());
    let seconds = start.elapsed().as_secs_f64();
    let noise = image.relative_noise();
    eprintln!(
        "small light, {} samples per pixel: mean relative standard error {:.3} % in {seconds:.2} s ({:.1} M rays)",
        samples,
        100.0 * noise,
        image.rays as f64 * 1e-6
    );
    assert!(noise <= 0.005, "noise {:.3} %", 100.0 * noise);
    // Not vacuous: the occluder's shadow is in the picture (some floor pixels see none of the light).
    let dark = image.radiance.iter().filter(|r| r.w > 0.0 && r.x < 0.05).count();
    let lit = image.radiance.iter().filter(|r| r.x > 0.5).count();
    assert!(dark > 10 && lit > 100, "{dark} pixels in the umbra, {lit} lit");
}

/// The paper's frustum: a light straddling the edge of the 135° square view counts only inside it, as the
/// polygon clipped to the frustum's planes says.
#[test]
fn a_light_straddling_the_frustum_edge_matches_the_clipped_polygon() {
    let fov_deg = 135.0f32;
    let s = (fov_deg.to_radians() * 0.5).tan();
    let floor = common::rect(Vec3::ZERO, Vec3::X * 5.0, Vec3::Z * 5.0, Vec3::Y);
    // Where the sensor's tangents point: the frustum's square turns with them.
    let f = SensorFrame::new(Vec3::ZERO, Vec3::Y, 0.0);
    let ke = 3.0;
    // At height 1, the frustum's edge is at t = s = 2.414: the light spans t ∈ [1.9, 2.9], b ∈ [-0.3, 0.3].
    let light = common::rect(f.n + f.t * 2.4, f.t * 0.5, f.b * 0.3, -f.n);
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    let polygon: Vec<DVec3> =
        corners.iter().map(|&(u, v)| (f.n + f.t * (2.4 + 0.5 * u) + f.b * (0.3 * v)).as_dvec3()).collect();
    let camera = Camera::look_at(Vec3::new(0.0, 3.0, 3.0), Vec3::ZERO, Vec3::Y, 60.0).unwrap();
    let scene = common::scene(
        vec![("light", 0, light), ("floor", 1, floor)],
        vec![common::material("light", 0.0, ke), common::material("grey", 0.5, 0.0)],
        camera,
        (8, 8),
    );
    let sensor = SensorKind::Frustum { fov_deg };
    let integrator = Integrator::new(&scene, params(sensor, 0.0), 65536, 9).unwrap();
    for (dt, db) in [(0.0, 0.0), (0.1, 0.2), (-0.15, -0.1)] {
        let p = f.t * dt + f.b * db;
        let at = receiver(&scene, p, Vec3::Y);
        // The polygon is wound counter-clockwise seen from below (t × b = n): reverse it to face down.
        let light_polygon: Vec<DVec3> = polygon.iter().rev().copied().collect();
        let exact = exact_r(&at, Domain::Frustum { half_width: s as f64 }, ke as f64, &light_polygon);
        let whole = exact_r(&at, Domain::Hemisphere, ke as f64, &light_polygon);
        assert!(exact < 0.8 * whole && exact > 0.2 * whole, "the frustum's edge cuts the light: {exact} of {whole}");
        let estimate = integrator.radiance(p, Vec3::Y, 17);
        let (r, noise) = (estimate.mean.x as f64, estimate.std_error.x as f64);
        let error = relative_error(r, exact);
        eprintln!(
            "frustum edge at ({dt}, {db}): R {r:.6}, clipped exact {exact:.6} (whole light {whole:.6}), error {:+.4} % \
             (noise ±{:.4} %)",
            100.0 * error,
            100.0 * noise / exact
        );
        assert!(error.abs() < 0.003, "at ({dt}, {db}): {r} vs {exact}");
    }
}

/// The hemisphere's edge: a wall light beside a tilted receiver, partly below its horizon, counts only above
/// it (nothing else in the scene, so the part below is not hidden by a floor but by the domain alone).
#[test]
fn a_light_straddling_the_horizon_matches_the_clipped_polygon() {
    let ke = 2.0;
    let n = Vec3::new(0.3, 1.0, 0.2).normalize();
    let light = common::rect(Vec3::new(1.0, 0.1, 0.0), Vec3::Y * 0.7, Vec3::Z * 0.5, -Vec3::X);
    // Its corners, counter-clockwise seen from −x (the front).
    let polygon: Vec<DVec3> = [(-1.0, 1.0), (1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)]
        .iter()
        .map(|&(u, v)| DVec3::new(1.0, 0.1 + 0.7 * u, 0.5 * v))
        .collect();
    assert!(polygon::front_normal(&polygon).dot(DVec3::NEG_X) > 0.99);
    let camera = Camera::look_at(Vec3::new(0.0, 3.0, 3.0), Vec3::ZERO, Vec3::Y, 60.0).unwrap();
    let scene = common::scene(vec![("light", 0, light)], vec![common::material("light", 0.0, ke)], camera, (8, 8));
    let integrator = Integrator::new(&scene, params(SensorKind::Hemicube, 0.0), 65536, 4).unwrap();
    for p in [Vec3::ZERO, Vec3::new(0.2, 0.1, -0.3), Vec3::new(0.3, 0.4, 0.2)] {
        let at = receiver(&scene, p, n);
        let exact = exact_r(&at, Domain::Hemisphere, ke as f64, &polygon);
        let unclipped =
            ke as f64 * polygon::lambert(&polygon.iter().map(|&v| v - at.origin).collect::<Vec<_>>(), at.n) / PI;
        assert!(unclipped < 0.95 * exact, "the horizon cuts the light: {unclipped} unclipped, {exact} clipped");
        let estimate = integrator.radiance(p, n, 23);
        let (r, noise) = (estimate.mean.x as f64, estimate.std_error.x as f64);
        let error = relative_error(r, exact);
        eprintln!(
            "horizon at {p}: R {r:.6}, clipped exact {exact:.6} (unclipped {unclipped:.6}), error {:+.4} % \
             (noise ±{:.4} %)",
            100.0 * error,
            100.0 * noise / exact
        );
        assert!(error.abs() < 0.003, "at {p}: {r} vs {exact}");
    }
}

/// Thousands of emissive triangles of two brightnesses (a 64 × 64 checkerboard of Ke 1 and 4, 8192
/// triangles): the light table picks by power and the result is the sum of the cells' exact values.
#[test]
fn thousands_of_emissive_triangles_sum_to_the_exact_value() {
    let (cells, h) = (64, 1.0f32);
    let mut groups = Vec::new();
    let mut cell_polygons = Vec::new();
    let size = 1.0 / cells as f32;
    for i in 0..cells {
        for j in 0..cells {
            let center = Vec3::new(-0.5 + (i as f32 + 0.5) * size, h, -0.5 + (j as f32 + 0.5) * size);
            let material = (i + j) % 2;
            groups.push(("cell", material, common::rect(center, Vec3::X * size * 0.5, Vec3::Z * size * 0.5, -Vec3::Y)));
            let (x0, x1) = ((center.x - size * 0.5) as f64, (center.x + size * 0.5) as f64);
            let (z0, z1) = ((center.z - size * 0.5) as f64, (center.z + size * 0.5) as f64);
            cell_polygons.push((material, ceiling_rect(x0, x1, z0, z1, h as f64)));
        }
    }
    groups.push(("floor", 2, common::rect(Vec3::ZERO, Vec3::X * 5.0, Vec3::Z * 5.0, Vec3::Y)));
    let ke = [1.0, 4.0];
    let camera = Camera::look_at(Vec3::new(0.0, 3.0, 3.0), Vec3::ZERO, Vec3::Y, 60.0).unwrap();
    let scene = common::scene(
        groups,
        vec![
            common::material("dim", 0.0, ke[0]),
            common::material("bright", 0.0, ke[1]),
            common::material("floor", 0.5, 0.0),
        ],
        camera,
        (8, 8),
    );
    let integrator = Integrator::new(&scene, params(SensorKind::Hemicube, 0.0), 65536, 2).unwrap();
    assert_eq!(integrator.emitters(), cells * cells * 2);
    for (x, z) in [(0.0, 0.0), (0.4, -0.3), (1.2, 0.5)] {
        let p = Vec3::new(x, 0.0, z);
        let at = receiver(&scene, p, Vec3::Y);
        let exact: f64 =
            cell_polygons.iter().map(|(m, poly)| exact_r(&at, Domain::Hemisphere, ke[*m] as f64, poly)).sum();
        let estimate = integrator.radiance(p, Vec3::Y, 5);
        let (r, noise) = (estimate.mean.x as f64, estimate.std_error.x as f64);
        let error = relative_error(r, exact);
        eprintln!(
            "checkerboard light at ({x}, {z}): R {r:.6}, exact {exact:.6}, error {:+.4} % (noise ±{:.4} %)",
            100.0 * error,
            100.0 * noise / exact
        );
        assert!(error.abs() < 0.003, "at ({x}, {z}): {r} vs {exact}");
    }
}

#[test]
fn white_furnace_gives_one_for_the_hemisphere_and_0_8774_for_the_135_degree_frustum() {
    let scene = common::furnace(1.0);
    let size = ImageSize { width: 12, height: 12 };
    for (sensor, expected) in [(SensorKind::Hemicube, 1.0), (SensorKind::Frustum { fov_deg: 135.0 }, 0.8774)] {
        let image = Integrator::new(&scene, params(sensor, 0.3), 4096, 3).unwrap().render(
            size,
            sensorlight::params::Antialiasing::Off,
            &|_| (),
        );
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
    let image = Integrator::new(&scene, params(SensorKind::Hemicube, 0.0), 64, 1).unwrap().render(
        scene.image,
        sensorlight::params::Antialiasing::Off,
        &|_| (),
    );
    assert!(image.image.iter().all(|p| p.truncate() == Vec3::ZERO));
    // …while ε > 0 makes it glow Kd·ε: the test above is not vacuous.
    let image = Integrator::new(&scene, params(SensorKind::Hemicube, 0.5), 64, 1).unwrap().render(
        scene.image,
        sensorlight::params::Antialiasing::Off,
        &|_| (),
    );
    let r = image.radiance[0].x;
    assert!((r - 0.45).abs() < 1e-5, "{r}");
}

#[test]
fn error_falls_at_least_like_one_over_sqrt_n() {
    let scene = sensorlight::scene::Scene::load(&common::project("scenes/cornell/cornell.toml")).unwrap();
    let size = ImageSize { width: 20, height: 20 };
    let p = params(SensorKind::Hemicube, 0.1);
    let truth = Integrator::new(&scene, p, 16384, 99)
        .unwrap()
        .render(size, sensorlight::params::Antialiasing::Off, &|_| ())
        .radiance;
    let rms = |n: u32| {
        let r = Integrator::new(&scene, p, n, 5)
            .unwrap()
            .render(size, sensorlight::params::Antialiasing::Off, &|_| ())
            .radiance;
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

/// A pixel integrated over its square (`--aa on`) against an independent quadrature of the same integral:
/// a 32 × 32 grid of camera rays across the pixel, R estimated at each hit point with independent samples.
/// The pixels straddle the Cornell box's ceiling edge (under half covered) and a block's silhouette, where
/// which samples meet a surface must not bias the directions they take (it once did: the same Sobol index
/// in two scrambles made the ceiling's edge up to five times too dark).
#[test]
fn a_pixel_over_an_edge_is_the_mean_over_its_square() {
    let mut scene = Scene::load(&common::project("scenes/cornell/cornell.toml")).unwrap();
    let size = ImageSize { width: 32, height: 32 };
    scene.image = size;
    let p = params(SensorKind::Hemicube, 0.1);
    let area = Integrator::new(&scene, p, 4096, 11).unwrap().render(size, Antialiasing::On, &|_| ());
    let integrator = Integrator::new(&scene, p, 256, 12).unwrap();
    let bvh = sensorlight::scene::bvh::Bvh::build(&scene.mesh.triangles);
    // Two pixels on the ceiling's front edge, and the first pixel below the middle whose right neighbour's
    // centre shows another surface (a block's silhouette or a crease).
    let g = &area.gbuffer;
    let w = size.width;
    let silhouette = (16 * w..31 * w).find(|&i| i % w < w - 1 && g.surface[i as usize] != g.surface[i as usize + 1]);
    let silhouette = silhouette.expect("an edge below the middle");
    for (x, y) in [(16u32, 0u32), (20, 0), (silhouette % w, silhouette / w)] {
        let mut sum = Vec3::ZERO;
        let (mut hits, mut surfaces, grid) = (0, std::collections::BTreeSet::new(), 32);
        for k in 0..grid * grid {
            let (u, v) = ((k % grid) as f32 + 0.5, (k / grid) as f32 + 0.5);
            let ray = scene.camera.ray(x as f32 + u / grid as f32, y as f32 + v / grid as f32, size.width, size.height);
            let Some(hit) = sensorlight::gbuffer::cast::first_surface(&scene, &bvh, &ray) else { continue };
            let r = integrator.radiance(hit.position.truncate(), hit.normal.truncate(), k as u64 + 1000 * x as u64);
            sum += hit.emission.truncate() + hit.albedo.truncate() * r.mean;
            hits += 1;
            surfaces.insert(hit.surface);
        }
        let quadrature = sum / (grid * grid) as f32;
        let i = (y * size.width + x) as usize;
        let got = area.image[i].truncate();
        let lum = |c: Vec3| c.dot(Vec3::new(0.2126, 0.7152, 0.0722));
        let error = (lum(got) - lum(quadrature)).abs() / lum(quadrature);
        eprintln!(
            "pixel ({x}, {y}): {hits} of 1024 rays meet a surface; area {got}, quadrature {quadrature}, {error:.4}"
        );
        assert!(hits > 0 && (hits < 1024 || surfaces.len() > 1), "pixel ({x}, {y}) straddles an edge");
        assert!(error < 0.03, "pixel ({x}, {y}): the square's mean {got} against {quadrature}");
    }
}
