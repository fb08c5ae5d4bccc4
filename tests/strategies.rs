//! Sensor-map batching strategies: the ones that pass the self-check agree with `per-sensor`; `auto` never
//! picks one that fails; a strategy the device gets wrong is refused when asked for by name.

mod common;

use sensorlight::passes::sensor_maps::{StrategyDesc, StrategyKind, unsupported};
use sensorlight::sensors::SensorKind;
use sensorlight::strategy::{self, Cache, CheckResult, Probe, relative_difference};

const FRUSTUM: SensorKind = SensorKind::Frustum { fov_deg: 135.0 };

/// On a fixed scene (the built-in lightbox, 40 sensors in batches of 7), every strategy that passes the
/// self-check gives per-sensor's R within float tolerance, for both sensor kinds and at two map sizes.
#[test]
fn strategies_that_pass_agree_with_per_sensor() {
    let probe = Probe::new(40);
    common::gpu(|device| {
        for sensor in [SensorKind::Hemicube, FRUSTUM] {
            for rd in [16, 48] {
                let budget = 7 * sensor.layers() as u64 * (rd as u64).pow(2) * 12;
                let (reference, _) = probe.run(device, sensor, rd, Some(budget), StrategyKind::PerSensor).unwrap();
                assert!(reference.iter().all(|r| r.w == 1.0 && r.x > 0.0), "every probe sensor is sensed and lit");
                for kind in StrategyKind::ALL {
                    let desc = StrategyDesc { sensor, rd, budget, near: 0.0 };
                    if unsupported(kind, device, &desc).is_some()
                        || !strategy::self_check(device, sensor, kind).unwrap().passed
                    {
                        continue;
                    }
                    let (r, _) = probe.run(device, sensor, rd, Some(budget), kind).unwrap();
                    let difference = relative_difference(&r, &reference);
                    assert!(
                        difference <= 1e-5,
                        "{kind}, {sensor}, rd {rd}: differs from per-sensor by {difference:.2e}"
                    );
                }
            }
        }
    });
}

/// `auto` skips a strategy whose self-check failed, even where it would be the fastest.
#[test]
fn auto_never_picks_a_strategy_that_failed_its_check() {
    common::gpu(|device| {
        for failing in [StrategyKind::Layered, StrategyKind::Atlas] {
            let mut cache = Cache::in_memory();
            // Every other strategy fails too, except per-sensor and `failing`'s complement.
            for kind in StrategyKind::ALL {
                let passed = kind == StrategyKind::PerSensor || (kind != failing && kind != StrategyKind::Multiview);
                cache.record_check(device, SensorKind::Hemicube, kind, CheckResult { max_difference: 0.0, passed });
            }
            let mut log = Vec::new();
            let choice =
                strategy::choose(device, SensorKind::Hemicube, 16, 1 << 22, None, &mut cache, &mut |l| log.push(l))
                    .unwrap();
            assert_ne!(choice.strategy, failing, "auto picked a strategy that failed its self-check");
            assert_ne!(choice.strategy, StrategyKind::Multiview);
            assert!(log.iter().any(|l| l.contains("auto: per sensor")), "auto says what it measured: {log:?}");
        }
    });
}

/// Asking for a strategy by name runs its self-check; one that fails on this device is refused with a
/// clear message (on lavapipe 22.3 that is multiview, see docs/BENCHMARKS.md), one that passes is used.
#[test]
fn a_named_strategy_is_checked_before_use() {
    common::gpu(|device| {
        for kind in StrategyKind::ALL {
            let mut cache = Cache::in_memory();
            let desc = StrategyDesc { sensor: SensorKind::Hemicube, rd: 16, budget: 1 << 22, near: 0.0 };
            let result =
                strategy::choose(device, SensorKind::Hemicube, 16, 1 << 22, Some(kind), &mut cache, &mut |_| ());
            match (
                unsupported(kind, device, &desc),
                strategy::self_check(device, SensorKind::Hemicube, kind).unwrap().passed,
            ) {
                (Some(_), _) => assert!(result.unwrap_err().to_string().contains("cannot run")),
                (None, true) => assert_eq!(result.unwrap().strategy, kind),
                (None, false) => {
                    let message = result.err().map(|e| e.to_string()).unwrap_or_default();
                    assert!(message.contains("disagrees with per-sensor"), "{kind}: {message}");
                }
            }
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
