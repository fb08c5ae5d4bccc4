//! Image agreement: how far one radiance image is from another (e.g. a render from its CPU reference).

use std::path::Path;

use anyhow::{Result, ensure};

use super::exr;

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Agreement {
    /// sqrt(Σ|a − b|² / Σ|b|²) over the pixels compared (rgb).
    pub relative_rmse: f64,
    /// Σ|a − b| / Σ|b|: the mean absolute error relative to the mean.
    pub relative_mean_abs: f64,
    /// (Σa − Σb) / Σb: the overall bias.
    pub relative_bias: f64,
    pub pixels: usize,
}

/// Compares rgb images `a` against `b` (the reference) over pixels where `b` is not black.
pub fn agreement(a: &[[f32; 3]], b: &[[f32; 3]]) -> Agreement {
    assert_eq!(a.len(), b.len());
    let (mut err2, mut ref2, mut abs, mut refabs, mut sum_a, mut sum_b, mut n) = (0.0f64, 0.0, 0.0, 0.0, 0.0, 0.0, 0);
    for (pa, pb) in a.iter().zip(b) {
        if pb.iter().all(|&v| v == 0.0) {
            continue;
        }
        n += 1;
        for c in 0..3 {
            let (x, y) = (pa[c] as f64, pb[c] as f64);
            err2 += (x - y) * (x - y);
            ref2 += y * y;
            abs += (x - y).abs();
            refabs += y.abs();
            sum_a += x;
            sum_b += y;
        }
    }
    let ratio = |num: f64, den: f64| if den > 0.0 { num / den } else { 0.0 };
    Agreement {
        relative_rmse: ratio(err2, ref2).sqrt(),
        relative_mean_abs: ratio(abs, refabs),
        relative_bias: ratio(sum_a - sum_b, sum_b),
        pixels: n,
    }
}

/// Reads channel group `layer` (`""` for the main R, G, B) of two EXR files and compares them.
pub fn compare_files(a: &Path, b: &Path, layer: &str) -> Result<Agreement> {
    let names: Vec<String> =
        ["R", "G", "B"].iter().map(|c| if layer.is_empty() { c.to_string() } else { format!("{layer}.{c}") }).collect();
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    let (wa, ha, ca) = exr::read_channels(a, &names)?;
    let (wb, hb, cb) = exr::read_channels(b, &names)?;
    ensure!((wa, ha) == (wb, hb), "{} is {wa}x{ha} but {} is {wb}x{hb}", a.display(), b.display());
    let rgb = |c: &[Vec<f32>]| (0..wa * ha).map(|i| [c[0][i], c[1][i], c[2][i]]).collect::<Vec<_>>();
    Ok(agreement(&rgb(&ca), &rgb(&cb)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn agreement_of_a_scaled_image() {
        let b = vec![[1.0, 2.0, 3.0], [0.0; 3], [2.0, 2.0, 2.0]];
        let a: Vec<[f32; 3]> = b.iter().map(|p| p.map(|v| v * 1.1)).collect();
        let r = agreement(&a, &b);
        assert_eq!(r.pixels, 2, "black reference pixels are skipped");
        assert!((r.relative_rmse - 0.1).abs() < 1e-6 && (r.relative_bias - 0.1).abs() < 1e-6);
        assert!((r.relative_mean_abs - 0.1).abs() < 1e-6);
    }
}
