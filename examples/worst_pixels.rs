//! Where an image's error against a reference lies: the per-pixel relative error of luminance over the
//! reference's lit pixels (as `sensorlight compare` counts them), split between supersampled pixels and
//! pixel centres (the image's `supersampled` AOV, from `render --aovs`), how much of the squared error the
//! worst pixels hold, and the worst pixels themselves with their surfaces. The reference's noise is left
//! in. With a fourth argument, a PNG map of the signed error: red where the image is brighter, blue where
//! darker, full at ±50 %, grey where the reference is unlit.
//! `cargo run --release --example worst_pixels -- IMAGE.exr REFERENCE.exr [N, default 20] [MAP.png]`; with
//! `INTERIOR=1`, silhouettes masked as `compare` masks them.
use std::path::Path;

use anyhow::{Context as _, Result};
use sensorlight::output::exr::read_all;

type Channels = Vec<(String, Vec<f32>)>;

fn channel<'a>(c: &'a Channels, name: &str) -> Option<&'a [f32]> {
    c.iter().find(|(k, _)| k == name).map(|(_, v)| v.as_slice())
}

fn luminance(c: &Channels) -> Result<Vec<f32>> {
    let [r, g, b] = ["R", "G", "B"].map(|n| channel(c, n));
    let (r, g, b) = (r.context("no R")?, g.context("no G")?, b.context("no B")?);
    Ok((0..r.len()).map(|i| 0.2126 * r[i] + 0.7152 * g[i] + 0.0722 * b[i]).collect())
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: worst_pixels IMAGE.exr REFERENCE.exr [N] [MAP.png]";
    let (w, h, image) = read_all(Path::new(args.get(1).context(usage)?))?;
    let (rw, rh, reference) = read_all(Path::new(args.get(2).context(usage)?))?;
    anyhow::ensure!((w, h) == (rw, rh), "the image is {w} × {h}, the reference {rw} × {rh}");
    let n: usize = args.get(3).map_or(Ok(20), |s| s.parse())?;
    let (a, b) = (luminance(&image)?, luminance(&reference)?);
    let supersampled = channel(&image, "supersampled");
    let surface = channel(&image, "surface_id");
    let mean = b.iter().sum::<f32>() / b.len() as f32;
    // (relative error, pixel) over the reference's lit pixels.
    // INTERIOR=1: silhouettes masked as `compare` masks them (its "interior").
    let masked = match (std::env::var_os("INTERIOR"), surface) {
        (Some(_), Some(ids)) => sensorlight::metrics::compare::silhouettes(w, h, ids),
        _ => vec![false; w * h],
    };
    let mut errors: Vec<(f64, usize)> =
        (0..w * h).filter(|&i| b[i] > 0.01 * mean && !masked[i]).map(|i| (((a[i] - b[i]) / b[i]) as f64, i)).collect();
    let total: f64 = errors.iter().map(|(e, _)| e * e).sum();
    let count = errors.len() as f64;
    println!("{} lit pixels: relative RMSE {:.4} (the reference's noise in)", errors.len(), (total / count).sqrt());
    if let Some(s) = supersampled {
        for (name, kept) in [("supersampled", true), ("centres", false)] {
            let part: Vec<f64> = errors.iter().filter(|(_, i)| (s[*i] > 0.5) == kept).map(|(e, _)| e * e).collect();
            let rms = (part.iter().sum::<f64>() / part.len().max(1) as f64).sqrt();
            let share = part.iter().sum::<f64>() / total;
            println!("  {name}: {} pixels, RMSE {rms:.4}, {:.0} % of the squared error", part.len(), 100.0 * share);
        }
    }
    if let Some(map) = args.get(4) {
        write_map(Path::new(map), w, h, &errors)?;
    }
    errors.sort_by(|x, y| y.0.abs().total_cmp(&x.0.abs()));
    for k in [10, 20, 50, 100] {
        let rest: f64 = errors.iter().skip(k).map(|(e, _)| e * e).sum();
        println!(
            "  without the worst {k}: RMSE {:.4} ({:.0} % of the squared error left)",
            (rest / count).sqrt(),
            100.0 * rest / total
        );
    }
    for &(e, i) in errors.iter().take(n) {
        let id = surface.map_or(String::new(), |s| format!(", surface {}", s[i]));
        let ss =
            supersampled.map_or(String::new(), |s| if s[i] > 0.5 { ", supersampled".into() } else { String::new() });
        println!("  ({}, {}): {:+.3}, reference {:.4}, image {:.4}{id}{ss}", i % w, i / w, e, b[i], a[i]);
    }
    Ok(())
}

/// The signed relative error as colour: grey where unlit, towards red (too bright) or blue (too dark).
fn write_map(path: &Path, w: usize, h: usize, errors: &[(f64, usize)]) -> Result<()> {
    let mut rgb = vec![64u8; w * h * 3];
    for &(e, i) in errors {
        let t = (e.abs() / 0.5).min(1.0);
        let (hot, cold) = ((255.0 * t) as u8, 0u8);
        let px = if e > 0.0 { [255, 255 - hot, 255 - hot] } else { [255 - hot, 255 - hot, 255 - cold] };
        rgb[3 * i..3 * i + 3].copy_from_slice(&px);
    }
    image::save_buffer(path, &rgb, w as u32, h as u32, image::ColorType::Rgb8).context("writing the map")
}
