//! `sensorlight metrics`: the quick run's outputs, their consistency, and how sensor counts respond to
//! the refinement threshold.

mod common;

use std::path::Path;

fn metrics(name: &str, flags: &[&str]) -> (std::path::PathBuf, serde_json::Value) {
    let dir = common::scratch(name);
    let mut args = vec!["metrics", "--quick", "-o", dir.to_str().unwrap()];
    args.extend_from_slice(flags);
    let run = common::sensorlight(&args);
    assert!(run.status.success(), "{}", common::stderr(&run));
    let json = serde_json::from_slice(&std::fs::read(dir.join("metrics.json")).unwrap()).unwrap();
    (dir, json)
}

fn csv_rows(path: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(path).unwrap().lines().skip(1).map(|l| l.split(',').map(str::to_owned).collect()).collect()
}

#[test]
fn quick_metrics_write_every_output_consistently() {
    let (dir, json) = metrics("metrics_quick", &[]);
    for file in ["table1.csv", "table1.md", "figures.csv", "fig10.md", "fig11.md"] {
        assert!(dir.join(file).exists(), "{file}");
    }
    for plot in ["table1", "fig10", "fig11"] {
        let svg = std::fs::read_to_string(dir.join(format!("{plot}.svg"))).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("<text"), "{plot}.svg has text");
        let png = std::fs::read(dir.join(format!("{plot}.png"))).unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{plot}.png");
    }
    assert_eq!(json["device"].as_str().map(|s| !s.is_empty()), Some(true), "the device is recorded");
    assert!(
        json["config"]["dradiance"].as_f64().is_some() && json["config"]["tile"].as_u64().is_some(),
        "parameters recorded"
    );
    let runs = json["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 3 + 9, "3 Table I renders, 3 resolutions × 3 sizes for the figures");
    for run in runs {
        let s = &run["stats"];
        let sensors = s["sensors"].as_u64().unwrap();
        let per_round: u64 = s["sensors_per_round"].as_array().unwrap().iter().map(|v| v.as_u64().unwrap()).sum();
        assert_eq!(sensors, per_round, "sensors counted = sensors rendered round by round");
        let pixels = s["width"].as_u64().unwrap() * s["height"].as_u64().unwrap();
        assert!(sensors > 0 && sensors <= pixels);
        let (total, sensor_time) = (s["total_seconds"].as_f64().unwrap(), s["sensor_time_ms"].as_f64().unwrap());
        assert!(
            (sensor_time * sensors as f64 - 1e3 * total).abs() < 1e-6 * total.max(1.0) * 1e3,
            "sensor time = total / sensors"
        );
    }
    // The CSVs say what the JSON says.
    let table1 = csv_rows(&dir.join("table1.csv"));
    assert_eq!(table1.len(), 3);
    for (row, run) in table1.iter().zip(runs.iter().filter(|r| r["experiment"] == "table1")) {
        assert_eq!(row[3].parse::<u64>().unwrap(), run["stats"]["sensors"].as_u64().unwrap());
    }
    // Table I at the paper's resolutions: its values beside ours on every row, none missing ("–").
    let markdown = std::fs::read_to_string(dir.join("table1.md")).unwrap();
    assert!(["200x200", "300x200", "400x300"].iter().all(|r| markdown.contains(r)), "{markdown}");
    assert!(markdown.contains("15240") && !markdown.contains("–"), "{markdown}");
    assert_eq!(csv_rows(&dir.join("figures.csv")).len(), 9);
    let fig11 = std::fs::read_to_string(dir.join("fig11.md")).unwrap();
    assert!(["80x60", "120x90", "160x120"].iter().all(|r| fig11.contains(r)));
}

#[test]
fn table1_puts_the_papers_values_beside_ours() {
    let (dir, _) = metrics("metrics_paper", &["--table1", "--resolutions", "200x200,300x200", "--sensor-size", "16"]);
    let markdown = std::fs::read_to_string(dir.join("table1.md")).unwrap();
    assert!(markdown.contains("| 200x200 |") && markdown.contains("15240") && markdown.contains("4.455"), "{markdown}");
    assert!(markdown.contains("23762") && markdown.contains("the paper's"), "{markdown}");
    let rows = csv_rows(&dir.join("table1.csv"));
    assert_eq!(rows[0][8], "15240");
}

#[test]
fn sensor_counts_fall_as_dradiance_rises() {
    let sensors = |json: &serde_json::Value| -> Vec<u64> {
        json["runs"].as_array().unwrap().iter().map(|r| r["stats"]["sensors"].as_u64().unwrap()).collect()
    };
    let (_, strict) = metrics("metrics_strict", &["--table1", "--dradiance", "0.05"]);
    let (_, loose) = metrics("metrics_loose", &["--table1", "--dradiance", "1.0"]);
    let (strict, loose) = (sensors(&strict), sensors(&loose));
    assert!(strict.iter().zip(&loose).all(|(s, l)| l <= s), "strict {strict:?}, loose {loose:?}");
    assert!(loose.iter().sum::<u64>() < strict.iter().sum::<u64>(), "strict {strict:?}, loose {loose:?}");
}

#[test]
fn bad_metrics_arguments_are_clear_errors() {
    for (flags, expected) in [
        (&["--resolutions", "200by200"][..], "WIDTHxHEIGHT"),
        (&["--scene", "/nonexistent/scene.toml"], "cannot read scene file"),
        (&["--strategy", "warp"], "invalid value 'warp'"),
    ] {
        let dir = common::scratch("metrics_bad");
        let mut args = vec!["metrics", "--quick", "-o", dir.to_str().unwrap()];
        args.extend_from_slice(flags);
        common::expect_failure(&args, expected);
        assert!(!dir.join("metrics.json").exists());
    }
    let file = common::scratch("metrics_bad_file").join("not-a-dir");
    std::fs::write(&file, "x").unwrap();
    common::expect_failure(&["metrics", "--quick", "-o", file.to_str().unwrap()], "is not a directory");
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "x");
}

/// From any directory: the default scene comes from the source tree the binary was built from; text outputs
/// end with a newline.
#[test]
fn metrics_run_from_another_directory_and_end_lines() {
    let dir = common::scratch("metrics_elsewhere");
    let run = common::command()
        .current_dir(&dir)
        .args(["metrics", "--table1", "--resolutions", "40x30", "--sensor-size", "16", "-o", "out"])
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", common::stderr(&run));
    let json = std::fs::read_to_string(dir.join("out/metrics.json")).unwrap();
    assert!(json.ends_with("}\n"), "metrics.json ends with a newline");
    let json: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(json["config"]["scene"], "scenes/cornell/cornell.toml", "the default scene, named as in the tree");
    for file in ["table1.csv", "table1.md"] {
        assert!(std::fs::read_to_string(dir.join("out").join(file)).unwrap().ends_with('\n'), "{file}");
    }
}

/// `metrics --help` says `render`'s shared flags as they act in `metrics` (issue 42, item 11): ε defaults to
/// the paper's 0.1, not to global illumination; no bare mesh is lit by a white sky; the filter's default
/// is the paper's estimator's.
#[test]
fn metrics_help_speaks_of_metrics() {
    let run = common::sensorlight(&["metrics", "--help"]);
    let help = String::from_utf8_lossy(&run.stdout).into_owned();
    assert!(run.status.success(), "{help}");
    for render_words in ["default: global illumination", "given to render or reference", "paper's estimator: 2)"] {
        assert!(!help.contains(render_words), "{render_words:?} in {help}");
    }
    assert!(help.contains("Kd·ε (≥ 0; 0 = direct light only) [default: 0.1]"), "{help}");
    assert!(help.contains("[default: 2 with the paper's estimator, 0 with --estimator exact]"), "{help}");
}
