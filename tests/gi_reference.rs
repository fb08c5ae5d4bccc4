//! The oracle's global illumination (module `reference::path`) against closed forms, its noise estimate,
//! its determinism, and its behaviour where light is never absorbed. CPU only, each test a few seconds at
//! most in release on 2 cores.

mod common;

use glam::{Vec3, Vec4};
use sensorlight::params::{Bounces, EstimatorParams, Indirect};
use sensorlight::reference::integrator::{Integrator, ReferenceImage};
use sensorlight::scene::{Camera, ImageSize, Scene};
use sensorlight::sensors::SensorKind;

const LE: f32 = 1.5;

fn gi(bounces: Bounces) -> EstimatorParams {
    EstimatorParams { sensor: SensorKind::Hemicube, indirect: Indirect::Bounces(bounces), background: Vec3::ZERO }
}

/// The closed cube of `common::furnace` (every face emits `LE` inwards, one-sided), albedo `rho` everywhere,
/// the camera inside: the light leaving every point in every direction is the same, `L = Le + ρ·L`.
fn closed_box(rho: f32) -> Scene {
    let mut scene = common::furnace(LE);
    scene.mesh.materials[0].kd = Vec3::splat(rho);
    scene
}

fn render(scene: &Scene, params: EstimatorParams, samples: u32, seed: u64) -> ReferenceImage {
    Integrator::new(scene, params, samples, seed).unwrap().render(
        scene.image,
        sensorlight::params::Antialiasing::Off,
        &|_| (),
    )
}

/// How an image of constant truth `expected` (grey) agrees with it: the image mean's relative error, the
/// share of pixels within 3 of their own standard errors, and the pooled ratio Σ error² / Σ std_error².
struct Against {
    mean_error: f64,
    within_3: f64,
    pooled: f64,
}

fn against(image: &ReferenceImage, expected: f64) -> Against {
    let noise = image.image_std_error.clone();
    let pixels: Vec<(f64, f64)> = image
        .image
        .iter()
        .zip(&noise)
        .zip(&image.gbuffer.position)
        .filter(|(_, p)| p.w > 0.0)
        .map(|((v, e), _)| (v.x as f64 - expected, e.x as f64))
        .collect();
    assert_eq!(pixels.len(), image.image.len(), "the camera is inside the box: every pixel sees a wall");
    assert!(image.image.iter().all(|v| v.x == v.y && v.y == v.z), "a grey scene stays grey");
    let n = pixels.len() as f64;
    let mean_error = pixels.iter().map(|(d, _)| d).sum::<f64>() / n / expected;
    let within_3 = pixels.iter().filter(|(d, e)| d.abs() <= 3.0 * e).count() as f64 / n;
    let pooled = pixels.iter().map(|(d, _)| d * d).sum::<f64>() / pixels.iter().map(|(_, e)| e * e).sum::<f64>();
    Against { mean_error, within_3, pooled }
}

/// The noise estimate is honest when the errors against the truth are as large as it says. Each pixel's
/// standard error comes from 4 replicates (3 degrees of freedom), so error / std_error follows Student's t
/// with 3 degrees of freedom: 94.2 % of pixels within 3; over 576 pixels the share's own spread is 1 %,
/// so 85 % is 9 spreads of margin against chance and fails a noise estimate too small by a factor 1.6.
/// The pooled ratio Σ error² / Σ std_error² is 1 in expectation (spread ≈ 0.07 over 576 pixels, more
/// with the heavy tail of path lengths); [0.6, 1.6] fails an estimate off by 1.3× in either direction.
fn assert_honest(what: &str, a: &Against) {
    assert!(a.within_3 >= 0.85, "{what}: only {:.1} % of pixels within 3 standard errors", 100.0 * a.within_3);
    assert!((0.6..=1.6).contains(&a.pooled), "{what}: Σ error² / Σ std_error² = {:.3}", a.pooled);
}

/// `L = Le / (1 − ρ)`: the whole Neumann series, by paths ended with Russian roulette. ρ = 0.9 is the
/// hard one: the light has bounced 10 times on average, and roulette's path lengths leave 90 % noise per
/// sample. The mean over 576 pixels must be within 0.5 % (its noise: 0.08 % at ρ = 0.5, 0.11 % at 0.9;
/// roulette's rare long paths skew it, so it errs low more often than high). The near distance at the
/// seams leaks a little light out of the box (a vertex closer than `NEAR` to the next wall does not see it):
/// −0.05 ± 0.04 % at ρ = 0.9 with 8 192 samples, within the tolerance by far.
#[test]
fn a_closed_box_converges_to_le_over_one_minus_albedo() {
    for (rho, samples) in [(0.5, 256), (0.9, 1024)] {
        let scene = closed_box(rho);
        let image = render(&scene, gi(Bounces::Converged), samples, 7);
        let expected = LE as f64 / (1.0 - rho as f64);
        let a = against(&image, expected);
        eprintln!(
            "closed box ρ {rho}, {samples} samples: mean {:+.4} %, {:.1} % of pixels within 3 σ, pooled {:.3}, \
             relative noise {:.3} %, {:.1} rays per sample",
            100.0 * a.mean_error,
            100.0 * a.within_3,
            a.pooled,
            100.0 * image.relative_noise(),
            image.rays as f64 / (image.image.len() as f64 * samples as f64)
        );
        assert!(a.mean_error.abs() < 0.005, "ρ {rho}: the mean is {:+.3} % off {expected}", 100.0 * a.mean_error);
        assert_honest(&format!("ρ {rho}"), &a);
    }
}

/// `Bounces::Fixed(N)`: `L = Le·(1 + ρ + … + ρ^(N+1))`: the emitter seen, its direct light, and N bounces.
/// The counts differ by ρ^(N+1) ≥ 6 % at ρ = 0.5, N ≤ 2 (25 % at 0.9), so an off-by-one fails by far.
#[test]
fn a_fixed_count_of_bounces_sums_that_many_terms_of_the_series() {
    for rho in [0.5f32, 0.9] {
        let scene = closed_box(rho);
        for n in 0..=2u32 {
            let image = render(&scene, gi(Bounces::Fixed(n)), 128, 3);
            let expected: f64 = (0..=n + 1).map(|k| LE as f64 * (rho as f64).powi(k as i32)).sum();
            let a = against(&image, expected);
            eprintln!(
                "closed box ρ {rho}, {n} bounce(s): mean {:+.4} %, {:.1} % within 3 σ, pooled {:.3}",
                100.0 * a.mean_error,
                100.0 * a.within_3,
                a.pooled
            );
            assert!(a.mean_error.abs() < 0.005, "ρ {rho}, N {n}: {:+.3} % off {expected}", 100.0 * a.mean_error);
            assert_honest(&format!("ρ {rho}, N {n}"), &a);
        }
    }
}

/// `--bounces 0` is the same estimator as `--epsilon 0`, bit for bit (the same code): R, its noise, the
/// image and the rays cast, with a background and with the frustum's domain.
#[test]
fn no_indirect_bounce_is_the_direct_light_bit_for_bit() {
    let scene = common::lightbox((20, 16));
    for sensor in [SensorKind::Hemicube, SensorKind::Frustum { fov_deg: 120.0 }] {
        let background = Vec3::new(0.2, 0.3, 0.4);
        let direct = EstimatorParams { sensor, indirect: Indirect::Epsilon(0.0), background };
        let none = EstimatorParams { indirect: Indirect::Bounces(Bounces::Fixed(0)), ..direct };
        let (a, b) = (render(&scene, direct, 64, 2), render(&scene, none, 64, 2));
        assert!(a.radiance == b.radiance && a.std_error == b.std_error && a.image == b.image, "{sensor}");
        assert_eq!(a.rays, b.rays, "{sensor}");
        // …and one bounce is not: the test can tell them apart.
        let one = render(&scene, EstimatorParams { indirect: Indirect::Bounces(Bounces::Fixed(1)), ..direct }, 64, 2);
        let brighter = one.radiance.iter().zip(&a.radiance).filter(|(o, d)| o.x > d.x).count();
        assert!(brighter > a.radiance.len() / 2, "{sensor}: one bounce adds light ({brighter} pixels brighter)");
        assert!(one.rays > a.rays, "{sensor}");
    }
}

/// Same seed, same image, whatever the number of threads; `radiance(p, n, key)` is the pixel's R; another
/// seed gives other noise, as large as both estimates say.
#[test]
fn global_illumination_is_bit_reproducible_and_its_noise_is_honest() {
    let scene = common::lightbox((24, 18));
    let params = gi(Bounces::Converged);
    let a = render(&scene, params, 64, 11);
    let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let b = one_thread.install(|| render(&scene, params, 64, 11));
    assert!(a.radiance == b.radiance && a.std_error == b.std_error && a.image == b.image && a.rays == b.rays);
    let integrator = Integrator::new(&scene, params, 64, 11).unwrap();
    let seen: Vec<usize> = (0..a.radiance.len()).filter(|&i| a.gbuffer.position[i].w > 0.0).collect();
    assert!(seen.len() > a.radiance.len() / 2);
    for i in seen.iter().copied().step_by(seen.len() / 5) {
        let (p, n) = (a.gbuffer.position[i], a.gbuffer.normal[i]);
        let r = integrator.radiance(p.truncate(), n.truncate(), i as u64);
        assert_eq!(r.mean.extend(1.0), a.radiance[i], "pixel {i}");
    }
    // Another seed: the difference of two independent estimates has variance σa² + σb².
    let c = render(&scene, params, 64, 12);
    assert!(a.radiance != c.radiance);
    let lit = |v: &Vec4| v.w > 0.0 && v.truncate().max_element() > 0.0;
    let (mut d2, mut s2, mut within) = (0.0f64, 0.0f64, 0usize);
    let pixels: Vec<usize> = (0..a.radiance.len()).filter(|&i| lit(&a.radiance[i])).collect();
    for &i in &pixels {
        let d = (a.radiance[i] - c.radiance[i]).truncate().as_dvec3();
        let s = (a.std_error[i].truncate().as_dvec3().powf(2.0) + c.std_error[i].truncate().as_dvec3().powf(2.0))
            .map(f64::sqrt);
        d2 += d.length_squared();
        s2 += s.length_squared();
        within += usize::from((d.x.abs() <= 3.0 * s.x) as u8 + (d.y.abs() <= 3.0 * s.y) as u8 == 2);
    }
    let (pooled, share) = (d2 / s2, within as f64 / pixels.len() as f64);
    eprintln!("two seeds: Σ d² / Σ (σa² + σb²) = {pooled:.3}, {:.1} % within 3 σ (R, G)", 100.0 * share);
    // With 6 degrees of freedom per pixel: 97 % within 3 σ in expectation (both channels ~94 %).
    assert!((0.6..=1.6).contains(&pooled), "the noise estimate is off: pooled ratio {pooled:.3}");
    assert!(share >= 0.85, "only {:.1} % within 3 σ", 100.0 * share);
}

/// No emitters and a black background: nothing to bounce, exactly black. A white sky over an open room:
/// finite everywhere, and brighter than the sky's direct light alone (the walls light each other).
/// A lone plane under the sky sees only the sky, whatever the bounces: `R = sky` to rounding.
#[test]
fn without_emitters_the_light_is_the_sky_s() {
    let dark = closed_box(0.9);
    let mut dark = dark;
    dark.mesh.materials[0].ke = Vec3::ZERO;
    let image = render(&dark, gi(Bounces::Converged), 64, 1);
    assert!(image.image.iter().all(|p| p.truncate() == Vec3::ZERO));
    assert!(image.std_error.iter().all(|p| p.truncate() == Vec3::ZERO));

    let mut room = common::lightbox((20, 16));
    room.mesh.materials[3].ke = Vec3::ZERO;
    let sky = |indirect| EstimatorParams { sensor: SensorKind::Hemicube, indirect, background: Vec3::ONE };
    let bounced = render(&room, sky(Indirect::Bounces(Bounces::Converged)), 64, 1);
    let direct = render(&room, sky(Indirect::Epsilon(0.0)), 64, 1);
    assert!(bounced.image.iter().chain(&bounced.std_error).chain(&bounced.radiance).all(|v| v.is_finite()));
    let total = |i: &ReferenceImage| i.radiance.iter().map(|r| r.truncate().element_sum() as f64).sum::<f64>();
    assert!(total(&bounced) > 1.05 * total(&direct), "{} vs {}", total(&bounced), total(&direct));

    let plane = common::scene(
        vec![("floor", 0, common::rect(Vec3::ZERO, Vec3::X, Vec3::Z, Vec3::Y))],
        vec![common::material("grey", 0.5, 0.0)],
        Camera::look_at(Vec3::new(0.0, 2.0, 0.5), Vec3::ZERO, Vec3::Y, 40.0).unwrap(),
        (8, 8),
    );
    let image = render(&plane, sky(Indirect::Bounces(Bounces::Converged)), 64, 1);
    for (r, p) in image.radiance.iter().zip(&image.gbuffer.position).filter(|(_, p)| p.w > 0.0) {
        assert!((r.truncate() - Vec3::ONE).abs().max_element() < 1e-6, "{r} at {p}");
    }
}

/// Albedo 1 in a closed emitting box has no finite answer, and albedo 2 (which the loader accepts, with a
/// warning) gains energy at every bounce: the paths must still end (roulette's survival is capped at
/// 0.95, so ~20 more vertices after the 3rd; albedo 2 also meets the throughput cap) and every value be
/// finite. The oracle says so once; albedo 0.9 gives no such warning.
#[test]
fn albedo_of_one_and_above_terminates_with_finite_values() {
    let size = ImageSize { width: 8, height: 8 };
    for rho in [1.0f32, 2.0] {
        let scene = closed_box(rho);
        let integrator = Integrator::new(&scene, gi(Bounces::Converged), 64, 5).unwrap();
        let image = integrator.render(size, sensorlight::params::Antialiasing::Off, &|_| ());
        assert!(image.image.iter().chain(&image.std_error).all(|v| v.is_finite()), "albedo {rho}");
        assert!(image.image.iter().all(|v| v.x >= LE * 2.0), "albedo {rho}: at least Le and its direct light");
        let per_sample = image.rays as f64 / (64.0 * 64.0);
        eprintln!("albedo {rho}: {per_sample:.1} rays per sample, mean image {}", image.image[0]);
        // 2 rays per vertex, ≈ 1 + 3 + 20 vertices with the cap: far below the 1024-bounce bound's 2 000.
        assert!(per_sample < 100.0, "albedo {rho}: {per_sample} rays per sample: paths did not end by roulette");
        let warnings = integrator.warnings();
        assert!(warnings.len() == 1 && warnings[0].contains("'glow'"), "{warnings:?}");
    }
    // Ke at the loader's limit (1e18) with albedo 2: values of 1e24, whose squares leave f32 (the noise
    // estimate then squares in f64).
    let mut extreme = closed_box(2.0);
    extreme.mesh.materials[0].ke = Vec3::splat(1e18);
    let image = render(&extreme, gi(Bounces::Converged), 16, 5);
    assert!(image.image.iter().chain(&image.std_error).all(|v| v.is_finite()), "Ke 1e18, albedo 2");
    assert!(image.std_error.iter().any(|e| e.x > 1e20), "the test reaches the f64 noise path (σ² > f32::MAX)");
    let fine = closed_box(0.9);
    assert!(Integrator::new(&fine, gi(Bounces::Converged), 4, 1).unwrap().warnings().is_empty());
    assert!(Integrator::new(&closed_box(1.0), gi(Bounces::Fixed(0)), 4, 1).unwrap().warnings().is_empty());
}

/// `sensorlight reference --bounces N` says which model it renders and what a sample is.
#[test]
fn the_reference_command_names_its_model() {
    let dir = common::scratch("gi_reference_cli");
    let scene = common::project("scenes/cornell/cornell.toml");
    let out = dir.join("gi.exr");
    let args = ["reference", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--width", "16", "--height", "16"];
    for (flags, model) in [
        (&["--bounces", "2"][..], "global illumination, 2 indirect bounces"),
        (&[], "global illumination until converged"),
        (&["--epsilon", "0"], "the paper's ε 0"),
    ] {
        let mut all = args.to_vec();
        all.extend_from_slice(&["--samples", "8", "--no-png"]);
        all.extend_from_slice(flags);
        let run = common::sensorlight(&all);
        let stderr = common::stderr(&run);
        assert!(run.status.success(), "{stderr}");
        assert!(stderr.contains(model), "{flags:?}: {stderr}");
        let sample = if flags.first() == Some(&"--epsilon") { "a direction + a point" } else { "a path" };
        assert!(stderr.contains(sample), "{flags:?}: {stderr}");
    }
}

/// One bounce is, by definition, the direct light of the surfaces a point sees: `R₁(p) = R₀(p) +
/// (1/π) ∫ Kd(q)·R₀(q) cosθ dω`, with `q` the first hit along ω. Estimated here the long way, on the shipped
/// Cornell box (a small light, occluders, colour): 16 384 independent cosine directions from `p`, each hit's
/// direct `R₀(q)` from the direct-light oracle (itself checked against closed forms in `tests/reference.rs`),
/// against the path tracer's `Fixed(1)`. The nested estimate's standard error comes from its 16 384 terms
/// (well determined); the two oracles' own, at 65 536 samples, are a fraction of it. 4 standard errors per channel
/// at 4 points (12 checks): chance alone fails it with probability < 1e-3; the tolerance it gives is
/// 5–7 % of the bounce, so a wrong normal side, a light point seen through an occluder or a missing MIS
/// weight at the vertex fails it.
#[test]
fn one_bounce_is_the_direct_light_of_the_surfaces_a_point_sees() {
    use sensorlight::reference::sampling::{HashedStream, cosine_hemisphere};
    use sensorlight::scene::Ray;
    use sensorlight::scene::bvh::Bvh;
    use sensorlight::sensors::frame::{self, SensorFrame};

    let scene = Scene::load(&common::project("scenes/cornell/cornell.toml")).unwrap();
    let direct =
        EstimatorParams { sensor: SensorKind::Hemicube, indirect: Indirect::Epsilon(0.0), background: Vec3::ZERO };
    let inner = Integrator::new(&scene, direct, 32, 1).unwrap();
    let r0 = Integrator::new(&scene, direct, 65536, 2).unwrap();
    let r1 = Integrator::new(&scene, gi(Bounces::Fixed(1)), 65536, 3).unwrap();
    let bvh = Bvh::build(&scene.mesh.triangles);
    let (bias, near) = (frame::BIAS * scene.mesh.scale(), frame::NEAR * scene.mesh.scale());
    let points = [
        ("ceiling", Vec3::new(100.0, 548.8, 400.0), -Vec3::Y),
        ("floor", Vec3::new(420.0, 0.0, 450.0), Vec3::Y),
        ("red wall", Vec3::new(556.0, 200.0, 400.0), -Vec3::X),
        ("short block's top", Vec3::new(185.0, 165.0, 170.0), Vec3::Y),
    ];
    let m = 16384u32;
    for (name, p, n) in points {
        let sensor = SensorFrame::new(p, n, bias);
        // Independent directions, not a net: then the terms' spread is the estimate's true error.
        let directions = HashedStream::new(77);
        let (mut sum, mut sum2) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
        for j in 0..m {
            let dir = sensor.to_world(cosine_hemisphere(directions.vertex(j, 0).direction));
            let Some(hit) = bvh.intersect(&Ray::new(sensor.origin, dir), near, f32::INFINITY) else { continue };
            let tri = &scene.mesh.triangles[hit.triangle as usize];
            let normal = if dir.dot(tri.normal) < 0.0 { tri.normal } else { -tri.normal };
            let q = sensor.origin + dir * hit.t;
            let term = (scene.mesh.material_of(tri.surface).kd * inner.radiance(q, normal, j as u64).mean).as_dvec3();
            sum += term;
            sum2 += term * term;
        }
        let bounce = sum / m as f64;
        let bounce_error = ((sum2 / m as f64 - bounce * bounce) / (m - 1) as f64).map(f64::sqrt);
        let (a, b) = (r0.radiance(p, n, 5), r1.radiance(p, n, 6));
        let difference = b.mean.as_dvec3() - a.mean.as_dvec3() - bounce;
        let sigma = (bounce_error.powf(2.0) + a.std_error.as_dvec3().powf(2.0) + b.std_error.as_dvec3().powf(2.0))
            .map(f64::sqrt);
        eprintln!(
            "{name}: direct {:.4}, bounce {bounce:.4} ± {bounce_error:.4}, Fixed(1) {:.4} ± {:.4}: {:.2} σ",
            a.mean,
            b.mean,
            b.std_error,
            (difference / sigma).abs().max_element()
        );
        assert!(bounce.cmpgt(10.0 * bounce_error).all(), "{name}: the bounce is measurable");
        assert!((difference / sigma).abs().max_element() <= 4.0, "{name}: {difference} against σ {sigma}");
    }
}

/// Light beyond 32-bit floats (a background of 1e38, summed over samples) is an error that names the
/// pixel, not an EXR of infinities. (At the pixel centres, where a pixel sums every sample's R at one point;
/// over its square, 16 samples' images stay below f32's limit here.)
#[test]
fn a_reference_beyond_f32_is_a_clear_error() {
    let scene = common::project("scenes/cornell/cornell.toml");
    let out = common::scratch("gi_reference_overflow").join("x.exr");
    let args = ["reference", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--width", "8", "--height", "8"];
    let mut all = args.to_vec();
    all.extend_from_slice(&["--samples", "16", "--background", "1e38,1e38,1e38", "--aa", "off"]);
    common::expect_failure(&all, "is not finite");
    assert!(!out.exists());
}
