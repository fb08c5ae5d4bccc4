//! Writes the metrics: for each experiment a CSV, a Markdown table (the paper's values beside ours where
//! the paper gives them) and a plot in SVG and PNG; and `metrics.json` with the device, every parameter
//! and every run.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Result;
use serde::Serialize;

use super::{Experiment, MetricsConfig, PAPER_TABLE1, Run, log_log_slope, variation};
use crate::output::atomic;
use crate::output::plot::{Chart, Series};

/// Where and how the runs were made.
#[derive(Serialize)]
pub struct Header<'a> {
    pub device: &'a str,
    pub driver: &'a str,
    pub config: &'a MetricsConfig,
    pub total_seconds: f64,
}

impl Header<'_> {
    fn markdown(&self) -> String {
        let c = self.config;
        format!(
            "Device: {} ({}). Scene: `{}`. Sensor: {}; tile {}, dradiance {}, ε {}, filter radius {}. Measured by \
             `sensorlight metrics` in {:.0} s in all.\n",
            self.device,
            self.driver,
            c.scene,
            c.sensor,
            c.tile,
            c.dradiance,
            c.epsilon,
            c.filter_radius,
            self.total_seconds
        )
    }
}

/// Writes every output for the experiments in `runs` into `dir`; returns the files written.
pub fn write(dir: &Path, header: &Header<'_>, runs: &[Run]) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir)?;
    let mut out = Out { dir, written: Vec::new() };
    let table1: Vec<&Run> = runs.iter().filter(|r| r.experiment == Experiment::Table1).collect();
    if !table1.is_empty() {
        out.text("table1.csv", &table1_csv(&table1))?;
        out.text("table1.md", &table1_markdown(header, &table1))?;
        out.chart("table1", &table1_chart(&table1))?;
    }
    let figures: Vec<&Run> = runs.iter().filter(|r| r.experiment == Experiment::Figures).collect();
    if !figures.is_empty() {
        out.text("figures.csv", &figures_csv(&figures))?;
        out.text("fig10.md", &fig10_markdown(header, &figures))?;
        out.text("fig11.md", &fig11_markdown(header, &figures))?;
        out.chart("fig10", &fig10_chart(&figures))?;
        out.chart("fig11", &fig11_chart(&figures))?;
    }
    #[derive(Serialize)]
    struct Everything<'a> {
        #[serde(flatten)]
        header: &'a Header<'a>,
        runs: &'a [Run],
    }
    out.text("metrics.json", &crate::output::json_text(&Everything { header, runs })?)?;
    Ok(out.written)
}

/// Files written into one directory, atomically, remembered in order.
struct Out<'a> {
    dir: &'a Path,
    written: Vec<PathBuf>,
}

impl Out<'_> {
    fn text(&mut self, name: &str, text: &str) -> Result<()> {
        let path = self.dir.join(name);
        atomic::write_bytes(&path, text.as_bytes())?;
        self.written.push(path);
        Ok(())
    }

    /// `name.svg` and `name.png`.
    fn chart(&mut self, name: &str, chart: &Chart<'_>) -> Result<()> {
        let (svg, png) = (self.dir.join(format!("{name}.svg")), self.dir.join(format!("{name}.png")));
        chart.write_svg(&svg)?;
        chart.write_png(&png)?;
        self.written.extend([svg, png]);
        Ok(())
    }
}

fn paper_row(width: u32, height: u32) -> Option<(u64, f64)> {
    PAPER_TABLE1.iter().find(|p| p.0 == width && p.1 == height).map(|p| (p.2, p.3))
}

fn table1_csv(runs: &[&Run]) -> String {
    let mut out = String::from(
        "width,height,pixels,sensors,sensor_fraction,total_seconds,sensor_time_ms,strategy,paper_sensors,paper_sensor_time_ms\n",
    );
    for r in runs {
        let s = &r.stats;
        let pixels = s.width as u64 * s.height as u64;
        let paper = paper_row(s.width, s.height);
        writeln!(
            out,
            "{},{},{},{},{:.4},{:.3},{:.4},{},{},{}",
            s.width,
            s.height,
            pixels,
            s.sensors,
            s.sensors as f64 / pixels as f64,
            s.total_seconds,
            s.sensor_time_ms,
            s.strategy,
            paper.map(|p| p.0.to_string()).unwrap_or_default(),
            paper.map(|p| p.1.to_string()).unwrap_or_default()
        )
        .unwrap();
    }
    out
}

fn table1_markdown(header: &Header<'_>, runs: &[&Run]) -> String {
    let rd = runs.first().map_or(0, |r| r.stats.sensor_size);
    let mut out =
        format!("# Table I: sensor time against screen resolution ({rd}² sensor maps)\n\n{}\n", header.markdown());
    out.push_str(
        "| screen resolution | sensors | sensors (paper) | time/sensor ms | time/sensor ms (paper) | total s |\n",
    );
    out.push_str("|---|---:|---:|---:|---:|---:|\n");
    let mut ours = Vec::new();
    let mut paper = Vec::new();
    for r in runs {
        let s = &r.stats;
        let p = paper_row(s.width, s.height);
        ours.push(s.sensor_time_ms);
        if let Some(p) = p {
            paper.push(p.1);
        }
        writeln!(
            out,
            "| {}x{} | {} | {} | {:.3} | {} | {:.1} |",
            s.width,
            s.height,
            s.sensors,
            p.map(|p| p.0.to_string()).unwrap_or_else(|| "–".into()),
            s.sensor_time_ms,
            p.map(|p| format!("{:.3}", p.1)).unwrap_or_else(|| "–".into()),
            s.total_seconds
        )
        .unwrap();
    }
    write!(
        out,
        "\nSpread of the sensor time over resolutions (standard deviation / mean): ours {:.1} %",
        100.0 * variation(&ours)
    )
    .unwrap();
    if !paper.is_empty() {
        write!(out, ", the paper's {:.1} %", 100.0 * variation(&paper)).unwrap();
    }
    out.push_str(".\n");
    out
}

fn table1_chart(runs: &[&Run]) -> Chart<'static> {
    let ours =
        runs.iter().map(|r| (r.stats.width as f64 * r.stats.height as f64 / 1e3, r.stats.sensor_time_ms)).collect();
    let mut series = vec![Series { name: "ours".into(), points: ours, dashed: false }];
    let paper: Vec<(f64, f64)> = runs
        .iter()
        .filter_map(|r| {
            paper_row(r.stats.width, r.stats.height).map(|p| (r.stats.width as f64 * r.stats.height as f64 / 1e3, p.1))
        })
        .collect();
    if !paper.is_empty() {
        series.push(Series { name: "paper (GTX 660, DX9)".into(), points: paper, dashed: true });
    }
    Chart {
        title: "Table I: sensor time against screen resolution",
        x_label: "screen resolution (thousands of pixels)",
        y_label: "sensor time (ms)",
        log_x: false,
        log_y: false,
        series,
    }
}

fn figures_csv(runs: &[&Run]) -> String {
    let mut out = String::from("sensor_size,width,height,sensors,total_seconds,sensor_time_ms,strategy\n");
    for r in runs {
        let s = &r.stats;
        writeln!(
            out,
            "{},{},{},{},{:.3},{:.4},{}",
            s.sensor_size, s.width, s.height, s.sensors, s.total_seconds, s.sensor_time_ms, s.strategy
        )
        .unwrap();
    }
    out
}

/// Runs grouped by resolution, each sorted by map size.
fn by_resolution<'a>(runs: &[&'a Run]) -> Vec<(String, Vec<&'a Run>)> {
    let mut groups: Vec<(String, Vec<&Run>)> = Vec::new();
    for r in runs {
        match groups.iter_mut().find(|g| g.0 == r.resolution()) {
            Some(g) => g.1.push(r),
            None => groups.push((r.resolution(), vec![r])),
        }
    }
    for g in &mut groups {
        g.1.sort_by_key(|r| r.stats.sensor_size);
    }
    groups
}

fn sizes_header(groups: &[(String, Vec<&Run>)]) -> (String, Vec<u32>) {
    let sizes: Vec<u32> = groups.first().map(|g| g.1.iter().map(|r| r.stats.sensor_size).collect()).unwrap_or_default();
    let mut out = String::from("| resolution |");
    for rd in &sizes {
        write!(out, " rd {rd} |").unwrap();
    }
    out.push_str("\n|---|");
    out.push_str(&"---:|".repeat(sizes.len()));
    out.push('\n');
    (out, sizes)
}

fn fig10_markdown(header: &Header<'_>, runs: &[&Run]) -> String {
    let groups = by_resolution(runs);
    let (table_header, _) = sizes_header(&groups);
    let mut out =
        format!("# Fig. 10: sensor time (ms) against sensor map size\n\n{}\n{table_header}", header.markdown());
    for (resolution, rs) in &groups {
        write!(out, "| {resolution} |").unwrap();
        for r in rs {
            write!(out, " {:.4} |", r.stats.sensor_time_ms).unwrap();
        }
        out.push('\n');
    }
    out.push_str("\nGrowth exponent (slope of log time against log rd; 2 is quadratic):\n\n");
    for (resolution, rs) in &groups {
        let points: Vec<(f64, f64)> = rs.iter().map(|r| (r.stats.sensor_size as f64, r.stats.sensor_time_ms)).collect();
        let tail = &points[points.len().saturating_sub(2)..];
        writeln!(
            out,
            "- {resolution}: {:.2} over all sizes, {:.2} between the two largest",
            log_log_slope(&points),
            log_log_slope(tail)
        )
        .unwrap();
    }
    out
}

fn fig11_markdown(header: &Header<'_>, runs: &[&Run]) -> String {
    let groups = by_resolution(runs);
    let (table_header, _) = sizes_header(&groups);
    let mut out =
        format!("# Fig. 11: number of sensors against sensor map size\n\n{}\n{table_header}", header.markdown());
    for (resolution, rs) in &groups {
        write!(out, "| {resolution} |").unwrap();
        for r in rs {
            write!(out, " {} |", r.stats.sensors).unwrap();
        }
        out.push('\n');
    }
    out.push_str("\nChange in the number of sensors from each size to the next:\n\n");
    for (resolution, rs) in &groups {
        let steps: Vec<String> = rs
            .windows(2)
            .map(|w| {
                let change = w[1].stats.sensors as f64 / w[0].stats.sensors.max(1) as f64 - 1.0;
                format!("{}→{}: {:+.0} %", w[0].stats.sensor_size, w[1].stats.sensor_size, 100.0 * change)
            })
            .collect();
        writeln!(out, "- {resolution}: {}", steps.join(", ")).unwrap();
    }
    out
}

/// One line per resolution: `value` of each run against its map size.
fn series_by_resolution(runs: &[&Run], value: fn(&Run) -> f64) -> Vec<Series> {
    by_resolution(runs)
        .into_iter()
        .map(|(resolution, rs)| Series {
            name: resolution,
            points: rs.iter().map(|r| (r.stats.sensor_size as f64, value(r))).collect(),
            dashed: false,
        })
        .collect()
}

fn fig10_chart(runs: &[&Run]) -> Chart<'static> {
    let mut series = series_by_resolution(runs, |r| r.stats.sensor_time_ms);
    // A quadratic through the largest resolution's largest size, for reference.
    if let Some(&(x, y)) = series.last().and_then(|s| s.points.last()) {
        let xs: Vec<f64> = series[0].points.iter().map(|p| p.0).collect();
        series.push(Series {
            name: "∝ rd²".into(),
            points: xs.iter().map(|&v| (v, y * (v / x).powi(2))).collect(),
            dashed: true,
        });
    }
    Chart {
        title: "Fig. 10: sensor time against sensor map size",
        x_label: "sensor map size rd (texels per side)",
        y_label: "sensor time (ms)",
        log_x: true,
        log_y: true,
        series,
    }
}

fn fig11_chart(runs: &[&Run]) -> Chart<'static> {
    let series = series_by_resolution(runs, |r| r.stats.sensors as f64);
    Chart {
        title: "Fig. 11: number of sensors against sensor map size",
        x_label: "sensor map size rd (texels per side)",
        y_label: "sensors",
        log_x: true,
        log_y: false,
        series,
    }
}
