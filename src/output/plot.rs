//! Line charts for benchmarks and the paper's figures: SVG (text stays text) and PNG (text rasterised with
//! the embedded DejaVu Sans, so no system font is needed).

use std::path::Path;

use anyhow::{Result, anyhow};
use plotters::prelude::*;

use super::atomic;

/// One line: a name for the legend, its points, and whether it is drawn dashed (a bound, not a measurement).
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    pub dashed: bool,
}

pub struct Chart<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    /// Logarithmic axes (base 2 on x, base 10 on y).
    pub log_x: bool,
    pub log_y: bool,
    pub series: Vec<Series>,
}

/// An axis label: whole numbers from 100 up, below that three significant digits with trailing zeros
/// dropped. Ticks are sums of f64 steps: printed as they are, 0.03 reads "0.030000000000000002" and does
/// not fit the label area.
fn tick(v: &f64) -> String {
    let v = *v;
    if !v.is_finite() || v == 0.0 {
        return if v == 0.0 { "0".into() } else { format!("{v}") };
    }
    if v.abs() >= 100.0 {
        return format!("{v:.0}");
    }
    let decimals = (2 - v.abs().log10().floor() as i32).clamp(0, 12) as usize;
    let text = format!("{v:.decimals$}");
    let text = if text.contains('.') { text.trim_end_matches('0').trim_end_matches('.') } else { &text };
    if text == "-0" { "0".into() } else { text.into() }
}

/// Makes the embedded DejaVu Sans plotters' "sans-serif" (once).
fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let font: &'static [u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
        // The font is known to parse; a failure would surface as FontUnavailable when drawing.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, font);
    });
}

const COLORS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

impl Chart<'_> {
    /// The chart as an SVG document.
    pub fn svg(&self) -> Result<String> {
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (800, 500)).into_drawing_area();
            self.draw(&root)?;
            root.present().map_err(|e| anyhow!("plot: {e}"))?;
        }
        Ok(svg)
    }

    pub fn write_svg(&self, path: &Path) -> Result<()> {
        atomic::write_bytes(path, self.svg()?.as_bytes())
    }

    /// The chart as an 8-bit RGB PNG.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        let (w, h) = (1000u32, 625u32);
        let mut rgb = vec![0u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
            self.draw(&root)?;
            root.present().map_err(|e| anyhow!("plot: {e}"))?;
        }
        super::png::write_rgb8(path, w, h, &rgb)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, plotters::coord::Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        // Both backends lay text out with the registered font.
        register_font();
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("plot: {e:?}");
        root.fill(&WHITE).map_err(err)?;
        let points = self.series.iter().flat_map(|s| s.points.iter());
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for &(x, y) in points {
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
        }
        if x0 > x1 {
            return Err(anyhow!("plot '{}': no points", self.title));
        }
        let pad = |lo: f64, hi: f64, log: bool| {
            if log { (lo / 1.5, hi * 1.5) } else { (lo - 0.05 * (hi - lo).max(1e-9), hi + 0.05 * (hi - lo).max(1e-9)) }
        };
        let (x0, x1) = pad(x0, x1, self.log_x);
        let (y0, y1) = pad(y0.min(if self.log_y { y0 } else { 0.0 }), y1, self.log_y);
        let mut builder = ChartBuilder::on(root);
        builder.caption(self.title, ("sans-serif", 22)).margin(15).x_label_area_size(50).y_label_area_size(85);
        macro_rules! finish {
            ($chart:expr) => {{
                let mut chart = $chart;
                // Integers on a log-2 axis (16, 32, …); no ".0" on large round values.
                let integer = |v: &f64| format!("{v:.0}");
                let x_format: &dyn Fn(&f64) -> String = if self.log_x { &integer } else { &tick };
                chart
                    .configure_mesh()
                    .x_label_formatter(x_format)
                    .y_label_formatter(&tick)
                    .x_desc(self.x_label)
                    .y_desc(self.y_label)
                    .label_style(("sans-serif", 14))
                    .draw()
                    .map_err(err)?;
                for (i, s) in self.series.iter().enumerate() {
                    let color = COLORS[i % COLORS.len()];
                    let style = ShapeStyle { color: color.to_rgba(), filled: false, stroke_width: 2 };
                    let drawn = if s.dashed {
                        chart.draw_series(DashedLineSeries::new(s.points.iter().copied(), 6, 4, style)).map_err(err)?
                    } else {
                        chart.draw_series(LineSeries::new(s.points.iter().copied(), style)).map_err(err)?
                    };
                    drawn
                        .label(s.name.clone())
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
                    if !s.dashed {
                        chart.draw_series(s.points.iter().map(|&p| Circle::new(p, 3, color.filled()))).map_err(err)?;
                    }
                }
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.8))
                    .border_style(BLACK)
                    .position(SeriesLabelPosition::UpperRight)
                    .draw()
                    .map_err(err)?;
            }};
        }
        match (self.log_x, self.log_y) {
            (true, true) => {
                let y = (y0..y1).log_scale().with_key_points(log_ticks(y0, y1));
                finish!(builder.build_cartesian_2d((x0..x1).log_scale().base(2.0), y).map_err(err)?)
            }
            (true, false) => finish!(builder.build_cartesian_2d((x0..x1).log_scale().base(2.0), y0..y1).map_err(err)?),
            (false, true) => {
                let y = (y0..y1).log_scale().with_key_points(log_ticks(y0, y1));
                finish!(builder.build_cartesian_2d(x0..x1, y).map_err(err)?)
            }
            (false, false) => finish!(builder.build_cartesian_2d(x0..x1, y0..y1).map_err(err)?),
        }
        Ok(())
    }
}

/// Ticks of a log axis over `[lo, hi]`: 1, 2 and 5 times each power of ten within it, and every digit's
/// where that gives fewer than four (plotters' own labelled only a few values of the range, e.g. 0.1 to 0.3
/// of an axis running from 0.04 to 3).
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let within = |digits: &[f64]| -> Vec<f64> {
        let (first, last) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        (first..=last)
            // Divided by an exact power of ten below 1, so that 3 · 0.1 is 0.3 as written.
            .flat_map(|e| digits.iter().map(move |d| if e >= 0 { d * 10f64.powi(e) } else { d / 10f64.powi(-e) }))
            .filter(|v| (lo..=hi).contains(v))
            .collect()
    };
    let ticks = within(&[1.0, 2.0, 5.0]);
    if ticks.len() >= 4 { ticks } else { within(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_are_short_and_exact_enough() {
        assert_eq!(tick(&0.030000000000000002), "0.03");
        assert_eq!(tick(&(0.1 + 0.2)), "0.3");
        assert_eq!(tick(&0.00012345), "0.000123");
        assert_eq!(tick(&1.5), "1.5");
        assert_eq!(tick(&2.0), "2");
        assert_eq!(tick(&12.345), "12.3");
        assert_eq!(tick(&1234.4), "1234");
        assert_eq!(tick(&0.0), "0");
        assert_eq!(tick(&-0.25), "-0.25");
    }

    #[test]
    fn a_log_axis_is_labelled_over_its_whole_range() {
        assert_eq!(log_ticks(0.04, 3.0), [0.05, 0.1, 0.2, 0.5, 1.0, 2.0]);
        assert_eq!(log_ticks(0.12, 0.45), [0.2, 0.3, 0.4]);
        let points = vec![(16.0, 0.05), (64.0, 0.4), (256.0, 2.5)];
        let chart = Chart {
            title: "t",
            x_label: "x",
            y_label: "y",
            log_x: true,
            log_y: true,
            series: vec![Series { name: "s".into(), points, dashed: false }],
        };
        let svg = chart.svg().unwrap();
        let labels: Vec<&str> = svg.split('>').filter_map(|t| t.split('<').next()).map(str::trim).collect();
        for label in ["0.05", "0.1", "0.5", "1", "2"] {
            assert!(labels.contains(&label), "no tick {label}: {labels:?}");
        }
    }

    #[test]
    fn svg_axis_labels_carry_no_float_noise() {
        let points = (0..8).map(|i| (i as f64, 0.01 * i as f64)).collect();
        let chart = Chart {
            title: "t",
            x_label: "x",
            y_label: "y",
            log_x: false,
            log_y: false,
            series: vec![Series { name: "s".into(), points, dashed: false }],
        };
        let svg = chart.svg().unwrap();
        let labels: Vec<&str> = svg
            .split('>')
            .filter_map(|t| t.split('<').next())
            .map(str::trim)
            .filter(|t| t.parse::<f64>().is_ok())
            .collect();
        assert!(labels.iter().any(|l| l.starts_with("0.0")), "fractional ticks: {labels:?}");
        assert!(labels.iter().all(|l| l.len() <= 6), "no label carries float noise: {labels:?}");
    }
}
