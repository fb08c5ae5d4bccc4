//! Sensor-map batching strategies: every strategy that passes its self-check agrees with `per-sensor`, one
//! named test per (strategy, sensor kind, map size) so that one failure hides no other; one that fails
//! (multiview on lavapipe 22.3) or cannot run is refused when asked for by name; `auto` never picks a
//! strategy that failed its check.

mod common;

use std::sync::Arc;

use glam::{Vec3, Vec4};
use sensorlight::params::{Bounces, EstimatorKind, FrameParams, Overrides};
use sensorlight::passes::sensor_maps::{EmitterFronts, StrategyDesc, unsupported};
use sensorlight::renderer::{self, Renderer, probe_pixels};
use sensorlight::scene::ImageSize;
use sensorlight::sensors::SensorKind;
use sensorlight::sensors::layout::SensorLayout;
use sensorlight::strategy::{self, Cache, CheckResult, Event, StrategyKind, StrategyRequest, relative_difference};
use sensorlight::vk::Device;

const HEMICUBE: SensorKind = SensorKind::Hemicube;
const FRUSTUM: SensorKind = SensorKind::Frustum { fov_deg: 135.0 };
const EXACT: EstimatorKind = EstimatorKind::Exact;
const PAPER: EstimatorKind = EstimatorKind::Paper;

/// `compute` against per-sensor on the probe: its coverage is floating point, not the hardware's snapped
/// fixed point, so where an edge passes within the snapping's reach of a texel centre (1/512 of a texel)
/// the two may decide that texel differently, one texel of a light being up to ~8 % of a sensor's R at rd
/// 16. So: at most [`COMPUTE_MOVED`] of the probe's light moved between sensors, and at most one sensor in
/// [`COMPUTE_SENSORS_PER_DIFFERENCE`] off by more than 1e-4 of its R.
const COMPUTE_MOVED: f32 = 5e-3;
const COMPUTE_SENSORS_PER_DIFFERENCE: usize = 10;

/// 40 sensors on the built-in lightbox, in batches of 7 (full and partial batches), sensed by `kind`.
fn probe(
    device: &Arc<Device>,
    kind: StrategyKind,
    (sensor, estimator): (SensorKind, EstimatorKind),
    rd: u32,
) -> Vec<Vec4> {
    let size = ImageSize { width: 32, height: 32 };
    let scene = common::lightbox((size.width, size.height));
    let mut renderer = Renderer::builder(device, &scene, sensor, rd)
        .estimator(estimator)
        .max_batch(Some(7))
        .build_unchecked(kind)
        .unwrap();
    let pixels = probe_pixels(&renderer.gbuffer(size).unwrap().surface, 40);
    let frame = FrameParams::every_pixel(sensorlight::params::Indirect::Epsilon(0.1), Vec3::splat(0.02));
    renderer.sense_at(size, &pixels, &frame).unwrap().0
}

/// A strategy that passes its self-check gives per-sensor's R within float tolerance (`compute`, whose
/// coverage is not the hardware's fixed point, as [`COMPUTE_MOVED`] says, and it must pass: it needs no
/// graphics feature a driver may get wrong); one that fails it or cannot run is refused when asked for by
/// name, with the reason.
fn agrees_with_per_sensor(kind: StrategyKind, sensor: SensorKind, estimator: EstimatorKind, rd: u32) {
    common::gpu(|device| {
        let reference = probe(device, StrategyKind::PerSensor, (sensor, estimator), rd);
        assert!(reference.iter().all(|r| r.w == 1.0 && r.x > 0.0), "every probe sensor is sensed and lit");
        let scene = common::lightbox((8, 8));
        let named = Renderer::builder(device, &scene, sensor, rd)
            .estimator(estimator)
            .strategy(StrategyRequest::Fixed(kind))
            .build();
        let groups = if estimator == EXACT { 1 } else { 0 }; // the lightbox has one light
        let fronts = if estimator == EXACT { EmitterFronts::Group } else { EmitterFronts::Emission };
        let layout = SensorLayout { kind: sensor, groups };
        let desc = StrategyDesc { layout, fronts, rd, budget: 1 << 24, cull_triangles: true };
        if let Some(why) = unsupported(kind, device, &desc) {
            let message = named.err().map(|e| e.to_string()).unwrap_or_default();
            assert!(message.contains("cannot run") && message.contains(&why), "{kind}: {message}");
            return;
        }
        let check = renderer::self_check(device, sensor, estimator, kind).unwrap();
        assert!(
            check.passed || kind != StrategyKind::Compute,
            "{sensor}, {estimator}: compute fails its check: {check:?}"
        );
        if !check.passed {
            let message = named.err().map(|e| e.to_string()).unwrap_or_default();
            assert!(message.contains("disagrees with per-sensor"), "{kind}: {message}");
            return;
        }
        assert_eq!(named.unwrap().strategy(), kind, "a strategy that passes is used when asked for");
        let r = probe(device, kind, (sensor, estimator), rd);
        if kind == StrategyKind::Compute {
            let total = |v: &[Vec4]| v.iter().map(|r| r.truncate().element_sum()).sum::<f32>();
            let diffs: Vec<Vec3> = r.iter().zip(&reference).map(|(a, b)| (*a - *b).truncate().abs()).collect();
            let moved = diffs.iter().map(|d| d.element_sum()).sum::<f32>() / total(&reference);
            let off = diffs.iter().zip(&reference).filter(|(d, b)| d.max_element() > 1e-4 * b.max_element()).count();
            assert!(
                moved <= COMPUTE_MOVED && off * COMPUTE_SENSORS_PER_DIFFERENCE <= r.len(),
                "compute, {sensor}, {estimator}, rd {rd}: {moved:.2e} of the light moved, {off} of {} sensors off",
                r.len()
            );
            return;
        }
        let difference = relative_difference(&r, &reference);
        assert!(
            difference <= 1e-5,
            "{kind}, {sensor}, {estimator}, rd {rd}: differs from per-sensor by {difference:.2e}"
        );
    });
}

macro_rules! strategy_matrix {
    ($($name:ident: $kind:ident, $sensor:expr, $estimator:expr, $rd:expr;)*) => {
        $(
            #[test]
            fn $name() {
                agrees_with_per_sensor(StrategyKind::$kind, $sensor, $estimator, $rd);
            }
        )*
    };
}

strategy_matrix! {
    single_cb_hemicube_exact_rd16: SingleCb, HEMICUBE, EXACT, 16;
    single_cb_hemicube_exact_rd48: SingleCb, HEMICUBE, EXACT, 48;
    single_cb_frustum_exact_rd16: SingleCb, FRUSTUM, EXACT, 16;
    single_cb_frustum_exact_rd48: SingleCb, FRUSTUM, EXACT, 48;
    single_cb_hemicube_paper_rd16: SingleCb, HEMICUBE, PAPER, 16;
    single_cb_frustum_paper_rd16: SingleCb, FRUSTUM, PAPER, 16;
    multiview_hemicube_exact_rd16: Multiview, HEMICUBE, EXACT, 16;
    multiview_hemicube_exact_rd48: Multiview, HEMICUBE, EXACT, 48;
    multiview_frustum_exact_rd16: Multiview, FRUSTUM, EXACT, 16;
    multiview_frustum_exact_rd48: Multiview, FRUSTUM, EXACT, 48;
    multiview_hemicube_paper_rd16: Multiview, HEMICUBE, PAPER, 16;
    multiview_frustum_paper_rd16: Multiview, FRUSTUM, PAPER, 16;
    layered_hemicube_exact_rd16: Layered, HEMICUBE, EXACT, 16;
    layered_hemicube_exact_rd48: Layered, HEMICUBE, EXACT, 48;
    layered_frustum_exact_rd16: Layered, FRUSTUM, EXACT, 16;
    layered_frustum_exact_rd48: Layered, FRUSTUM, EXACT, 48;
    layered_hemicube_paper_rd16: Layered, HEMICUBE, PAPER, 16;
    layered_frustum_paper_rd16: Layered, FRUSTUM, PAPER, 16;
    atlas_hemicube_exact_rd16: Atlas, HEMICUBE, EXACT, 16;
    atlas_hemicube_exact_rd48: Atlas, HEMICUBE, EXACT, 48;
    atlas_frustum_exact_rd16: Atlas, FRUSTUM, EXACT, 16;
    atlas_frustum_exact_rd48: Atlas, FRUSTUM, EXACT, 48;
    atlas_hemicube_paper_rd16: Atlas, HEMICUBE, PAPER, 16;
    atlas_frustum_paper_rd16: Atlas, FRUSTUM, PAPER, 16;
    compute_hemicube_exact_rd16: Compute, HEMICUBE, EXACT, 16;
    compute_hemicube_exact_rd32: Compute, HEMICUBE, EXACT, 32;
    compute_hemicube_exact_rd48: Compute, HEMICUBE, EXACT, 48;
    compute_frustum_exact_rd16: Compute, FRUSTUM, EXACT, 16;
    compute_frustum_exact_rd48: Compute, FRUSTUM, EXACT, 48;
    compute_hemicube_paper_rd16: Compute, HEMICUBE, PAPER, 16;
    compute_frustum_paper_rd16: Compute, FRUSTUM, PAPER, 16;
}

/// `auto` skips a strategy whose self-check failed, even where it would be the fastest, and says what it
/// measured.
#[test]
fn auto_never_picks_a_strategy_that_failed_its_check() {
    common::gpu(|device| {
        let scene = common::lightbox((8, 8));
        let key = strategy::device_key(&device.adapter);
        for failing in [StrategyKind::Layered, StrategyKind::Atlas] {
            let mut cache = Cache::in_memory();
            // Every strategy fails but per-sensor and `failing`'s complement.
            for kind in StrategyKind::ALL {
                let passed = kind == StrategyKind::PerSensor || (kind != failing && kind != StrategyKind::Multiview);
                cache.record_check(
                    &key,
                    HEMICUBE,
                    EXACT,
                    kind,
                    CheckResult { max_difference: 0.0, passed, identical: passed },
                );
            }
            let mut events = Vec::new();
            let mut record = |e: Event| events.push(e);
            let renderer = Renderer::builder(device, &scene, HEMICUBE, 16)
                .memory_budget(Some(1 << 22))
                .cache(&mut cache)
                .on_strategy_event(&mut record)
                .build()
                .unwrap();
            assert_ne!(renderer.strategy(), failing, "auto picked a strategy that failed its self-check");
            assert_ne!(renderer.strategy(), StrategyKind::Multiview);
            assert!(events.iter().any(|e| matches!(e, Event::Measured { .. })), "auto says what it measured");
        }
    });
}

#[test]
fn bench_writes_its_report_table_csv_and_plot() {
    let dir = common::scratch("bench");
    let (json, csv, svg) = (dir.join("b.json"), dir.join("b.csv"), dir.join("b.svg"));
    let run = common::sensorlight(&[
        "bench",
        "--sizes",
        "8,16",
        "--sensors",
        "12",
        "--repeat",
        "2",
        "--strategies",
        "per-sensor,layered,atlas",
        "--json",
        json.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{}", common::stderr(&run));
    assert!(stdout.contains("| 16 | layered |") && stdout.contains("raw fill"), "{stdout}");
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let rows = report["measurements"].as_array().unwrap();
    assert_eq!(rows.len(), 6, "3 strategies × 2 sizes");
    for row in rows {
        assert_eq!(row["seconds"].as_array().unwrap().len(), 2, "one time per repeat");
        let (per_second, median) =
            (row["sensors_per_second"].as_f64().unwrap(), row["median_seconds"].as_f64().unwrap());
        assert!((per_second * median - 12.0).abs() < 1e-6, "sensors/s is sensors / median time");
        if row["strategy"] == "per-sensor" {
            assert!((row["vs_per_sensor"].as_f64().unwrap() - 1.0).abs() < 1e-12);
        }
    }
    assert_eq!(std::fs::read_to_string(&csv).unwrap().lines().count(), 7, "header + 6 rows");
    let plot = std::fs::read_to_string(&svg).unwrap();
    assert!(plot.starts_with("<svg") && plot.contains("layered") && plot.contains("raw fill"));
}

#[test]
fn bad_bench_arguments_are_clear_errors() {
    let dir = common::scratch("bench_bad");
    let (png, missing) = (dir.join("plot.png"), dir.join("missing/b.json"));
    for (flags, expected) in [
        (&["--plot", png.to_str().unwrap()][..], "expected a .svg file name"),
        (&["--json", missing.to_str().unwrap()], "does not exist"),
        (&["--sizes", "0"], "--sensor-size"),
        (&["--sensors", "0"], "--sensors"),
        (&["--strategies", "warp"], "warp"),
    ] {
        let mut args = vec!["bench", "--repeat", "1"];
        args.extend_from_slice(flags);
        common::expect_failure(&args, expected);
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "{flags:?} wrote a file");
    }
}

/// Every strategy renders the shipped Cornell box alike (see [`every_strategy_renders_alike`]).
#[test]
fn every_strategy_renders_the_shipped_cornell_box_alike() {
    every_strategy_renders_alike("scenes/cornell/cornell.toml");
}

/// Every strategy renders the third-party Cornell box with its two spheres alike.
#[test]
fn every_strategy_renders_the_third_party_cornell_box_alike() {
    every_strategy_renders_alike("scenes/cornell-mcguire/cornell-mcguire.toml");
}

/// Every strategy renders `file` at its defaults but for two cache bounces (96 × 96, global illumination
/// included, so the radiance cache's sensors too): R is per-sensor's bit for bit, the same sensors sensed,
/// for each strategy `auto` may take (identical on the probe, rasterizing as per-sensor does), and within
/// 1e-3 relative RMSE for the atlas (whose tiles' offsets round window coordinates differently). A strategy
/// that fails its check is refused (`agrees_with_per_sensor`). One test per scene, so that the two run side
/// by side.
fn every_strategy_renders_alike(file: &str) {
    let path = common::project(file);
    let scene = sensorlight::scene::Scene::load(&path).unwrap();
    let defaults = Overrides::from_scene_table(&path, &scene.render).unwrap();
    // Two bounces take the cache's sensors through both of its map sizes (rd 32, then rd 16), as the first
    // two of the default's do; its later bounces would only repeat them.
    let flags = Overrides { bounces: Some(Bounces::Fixed(2)), ..Default::default() };
    let params = sensorlight::params::RenderParams::resolve(Some((&path, &defaults)), &flags).unwrap();
    let size = ImageSize { width: 96, height: 96 };
    common::gpu(|device| {
        let render = |kind| {
            let mut renderer = Renderer::builder(device, &scene, params.estimator.sensor, params.values.sensor_size)
                .estimator(params.values.estimator)
                .radiance_cache(renderer::CacheConfig::for_params(&params))
                .build_unchecked(kind)
                .unwrap();
            let out = renderer.render(size, &params.frame(), &renderer::Quiet).unwrap();
            (out.radiance, out.stats.sensors)
        };
        let (reference, sensors) = render(StrategyKind::PerSensor);
        let mut compared = Vec::new();
        for kind in StrategyKind::ALL.into_iter().filter(|&k| k != StrategyKind::PerSensor) {
            // Unsupported or failing its check: refused by name and by auto (`agrees_with_per_sensor`).
            let Ok(check) = renderer::self_check(device, params.estimator.sensor, params.values.estimator, kind) else {
                continue;
            };
            if !check.passed {
                continue;
            }
            compared.push(kind);
            let (r, n) = render(kind);
            let bits = |v: &[Vec4]| v.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
            if check.identical && kind.rasterizes_like_per_sensor() {
                assert_eq!(n, sensors, "{file}: {kind} senses other pixels than per-sensor");
                let differing = bits(&r).chunks(4).zip(bits(&reference).chunks(4)).filter(|(a, b)| a != b).count();
                assert_eq!(differing, 0, "{file}: {kind}: {differing} pixels differ from per-sensor");
            } else {
                let rmse = (r.iter().zip(&reference).filter(|(_, b)| b.x + b.y + b.z > 0.0).map(|(a, b)| {
                    let (ya, yb) = (a.x + a.y + a.z, b.x + b.y + b.z);
                    ((ya - yb) / yb).powi(2) as f64
                }))
                .fold((0.0, 0usize), |(s, n), e| (s + e, n + 1));
                let rmse = (rmse.0 / rmse.1.max(1) as f64).sqrt();
                assert!(rmse <= 1e-3, "{file}: {kind}: relative RMSE {rmse:.2e} from per-sensor");
            }
        }
        // The strategies core Vulkan gives every driver were compared, not skipped as refused.
        for kind in [StrategyKind::SingleCb, StrategyKind::Layered] {
            assert!(compared.contains(&kind), "{file}: {kind} was not compared (compared: {compared:?})");
        }
    });
}

/// Multiview is verified where a driver does it right: Mesa 25's lavapipe (CI runs the tests on it) must
/// pass the self-check bit for bit. Stable Debian's lavapipe (Mesa 22.3) renders view i into layer i + 1
/// and is refused there (`agrees_with_per_sensor`); on other drivers this asserts nothing.
#[test]
fn multiview_is_verified_on_mesa_25_lavapipe() {
    common::gpu(|device| {
        let driver = &device.adapter.driver;
        let mesa_major = driver.split("Mesa ").nth(1).and_then(|v| v.split('.').next()?.parse::<u32>().ok());
        if !(driver.contains("llvmpipe") && mesa_major.is_some_and(|m| m >= 25)) {
            eprintln!("not Mesa ≥ 25 lavapipe ({driver}): nothing to verify");
            return;
        }
        for (sensor, estimator) in [(HEMICUBE, EXACT), (HEMICUBE, PAPER), (FRUSTUM, EXACT)] {
            let check = renderer::self_check(device, sensor, estimator, StrategyKind::Multiview).unwrap();
            assert!(check.passed && check.identical, "{driver}: multiview, {sensor}, {estimator}: {check:?}");
        }
    });
}
