//! Image agreement: how far one radiance image is from another (e.g. a render from its CPU reference).
//!
//! Two figures, each with everything below: the **whole image** (the headline: every lit pixel, nothing
//! masked, edges, emitters and background included, as a person sees it) and the **interior** (silhouettes,
//! emitters and the background masked as described below: the lighting alone).
//!
//! The figure is the **per-pixel relative RMSE on lit pixels**, on luminance:
//! `sqrt(mean over lit pixels of ((Ya − Yb) / Yb)²)`, `Y = 0.2126 R + 0.7152 G + 0.0722 B` (Rec. 709, the
//! renderer's linear RGB). Every lit pixel weighs the same, so a dim wall counts as much as the light
//! source. Luminance rather than each channel: a saturated pixel (a red wall's blue channel) would otherwise
//! divide by a near-zero reference.
//!
//! - **Lit** means the reference's luminance exceeds [`LIT_FRACTION`] (1 %) of its mean luminance over the
//!   compared pixels; darker pixels would divide by noise. The threshold is reported.
//!
//! Masked in the interior figure only:
//!
//! - **Silhouettes** are masked where either image has a `surface_id` channel: a pixel whose 3 × 3
//!   neighbourhood holds another id there. Renderers filter pixels differently along an edge, which is not
//!   what a comparison of lighting should measure. The masked pixels are counted and reported.
//! - **Emitters** are left out where either image has an `emission` layer (`emission.R/G/B`: what the pixel
//!   itself emits, as `render --aovs` and the Mitsuba peer write): their `Le` is given, not estimated, and
//!   would dilute the figure.
//! - **The background** (a `surface_id` of 0 in either image) is left out where the reference shows it lit:
//!   its radiance is given (`--background`), both images show it exactly, and it would dilute the figure.
//! - **Leaks**: pixels the reference leaves black (luminance 0) that the image lights above the lit
//!   threshold. A figure over lit pixels cannot see light where there should be none; this count does.
//! - Also reported: the mean absolute relative error (per pixel, luminance), the bias
//!   `(ΣYa − ΣYb) / ΣYb`, and the former headline, the L2 ratio `sqrt(Σ|a − b|² / Σ|b|²)` over the RGB of
//!   the lit pixels, which the brightest pixels dominate.
//! - **The reference's own noise**, where it carries its standard error (the CPU reference writes
//!   `std_error.*` for its image and `radiance_std_error.*` for R): the RMS of its relative standard error over
//!   the same lit pixels, and the image's own error with that noise removed, `sqrt(max(0, RMSE² − noise²))`
//!   (independent errors add in quadrature).
//! - An image holding NaN or infinite values, images of different sizes and a reference with no lit pixel
//!   are errors, with the counts of NaN and infinite pixels of each image.

use std::path::Path;

use anyhow::{Context as _, Result, bail, ensure};

pub use super::picture::{NonFinite, Picture};

/// A pixel is lit where the reference's luminance exceeds this fraction of its mean luminance.
pub const LIT_FRACTION: f64 = 0.01;
/// Rec. 709 luminance weights of linear R, G, B.
pub const LUMINANCE: [f64; 3] = [0.2126, 0.7152, 0.0722];

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Agreement {
    /// The headline: sqrt(mean over lit pixels of ((Ya − Yb) / Yb)²).
    pub relative_rmse: f64,
    /// Mean over lit pixels of |Ya − Yb| / Yb.
    pub mean_abs_relative_error: f64,
    /// (ΣYa − ΣYb) / ΣYb over lit pixels.
    pub relative_bias: f64,
    /// sqrt(Σ|a − b|² / Σ|b|²) over the RGB of lit pixels.
    pub l2_ratio: f64,
    /// All pixels of the image.
    pub pixels: usize,
    /// Pixels compared: lit and not masked.
    pub lit_pixels: usize,
    /// Pixels left out: silhouettes (`surface_id` changes in their 3 × 3 neighbourhood), emitters and a lit
    /// background.
    pub masked_pixels: usize,
    /// Whether a `surface_id` channel was found (in either image) to mask silhouettes with.
    pub surface_ids: bool,
    /// Reference luminance above which a pixel is lit: [`LIT_FRACTION`] of its mean over unmasked pixels.
    pub lit_threshold: f64,
    /// The reference's own noise: RMS over the lit pixels of its relative standard error (where it has one).
    pub reference_noise: Option<f64>,
    /// The image's own error, the reference's noise removed: `sqrt(max(0, RMSE² − noise²))`.
    pub own_error: Option<f64>,
    /// Emitter pixels left out (an `emission` layer in either image).
    pub emitter_pixels: usize,
    /// Background pixels left out (`surface_id` 0 where the reference is not black there).
    pub background_pixels: usize,
    /// Pixels black in the reference that the image lights above the lit threshold.
    pub leaked_pixels: usize,
}

fn luminance(p: &[f32; 3]) -> f64 {
    (0..3).map(|c| LUMINANCE[c] * p[c] as f64).sum()
}

/// Pixels whose 3 × 3 neighbourhood (within the image) holds another id.
pub fn silhouettes(width: usize, height: usize, ids: &[f32]) -> Vec<bool> {
    let mut mask = vec![false; width * height];
    for y in 0..height {
        for x in 0..width {
            let id = ids[y * width + x];
            let ys = y.saturating_sub(1)..(y + 2).min(height);
            mask[y * width + x] =
                ys.into_iter().any(|v| (x.saturating_sub(1)..(x + 2).min(width)).any(|u| ids[v * width + u] != id));
        }
    }
    mask
}

/// Which pixels a figure leaves out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Masking {
    /// None: the whole image.
    Nothing,
    /// Silhouettes, emitters and the lit background (see the module documentation).
    Interior,
}

/// Both figures of `a` against the reference `b`: the whole image, and its interior.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Comparison {
    pub whole: Agreement,
    pub interior: Agreement,
}

/// Compares `a` against the reference `b` over the whole image and over its interior.
pub fn compare(a: &Picture, b: &Picture) -> Result<Comparison> {
    Ok(Comparison { whole: agreement_with(a, b, Masking::Nothing)?, interior: agreement(a, b)? })
}

/// Compares `a` against the reference `b` over the interior (see the module documentation).
pub fn agreement(a: &Picture, b: &Picture) -> Result<Agreement> {
    agreement_with(a, b, Masking::Interior)
}

/// Compares `a` against the reference `b`, leaving out what `masking` says.
pub fn agreement_with(a: &Picture, b: &Picture, masking: Masking) -> Result<Agreement> {
    ensure!(
        (a.width, a.height) == (b.width, b.height),
        "{} is {}x{} but {} is {}x{}; only images of one size can be compared",
        a.name,
        a.width,
        a.height,
        b.name,
        b.width,
        b.height
    );
    let (na, nb) = (a.non_finite(), b.non_finite());
    if na.first.is_some() || nb.first.is_some() {
        bail!("cannot compare images holding NaN or infinite values: {}: {na}; {}: {nb}", a.name, b.name);
    }
    let n = a.rgb.len();
    let mut masked = vec![false; n];
    let interior = masking == Masking::Interior;
    for ids in [&a.surface_id, &b.surface_id].into_iter().flatten().filter(|_| interior) {
        for (m, s) in masked.iter_mut().zip(silhouettes(a.width, a.height, ids)) {
            *m |= s;
        }
    }
    let mut emitter_pixels = 0;
    for i in (0..n).filter(|_| interior) {
        if [&a.emitter, &b.emitter].into_iter().flatten().any(|e| e[i]) {
            emitter_pixels += !masked[i] as usize;
            masked[i] = true;
        }
    }
    let mut background_pixels = 0;
    for ids in [&a.surface_id, &b.surface_id].into_iter().flatten().filter(|_| interior) {
        for i in 0..n {
            if ids[i] == 0.0 && !masked[i] && luminance(&b.rgb[i]) > 0.0 {
                background_pixels += 1;
                masked[i] = true;
            }
        }
    }
    let unmasked = masked.iter().filter(|&&m| !m).count();
    let mean = b.rgb.iter().zip(&masked).filter(|(_, m)| !**m).map(|(p, _)| luminance(p)).sum::<f64>()
        / unmasked.max(1) as f64;
    let threshold = LIT_FRACTION * mean;
    let (mut rel2, mut rel_abs, mut sum_a, mut sum_b, mut err2, mut ref2, mut lit) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0);
    let (mut noise2, mut leaked_pixels) = (0.0, 0);
    for i in (0..n).filter(|&i| !masked[i]) {
        let (ya, yb) = (luminance(&a.rgb[i]), luminance(&b.rgb[i]));
        if yb == 0.0 && ya > threshold {
            leaked_pixels += 1;
        }
        if yb <= threshold || yb <= 0.0 {
            continue;
        }
        lit += 1;
        let relative = (ya - yb) / yb;
        rel2 += relative * relative;
        if let Some(e) = &b.std_error {
            noise2 += (luminance(&e[i]) / yb).powi(2);
        }
        rel_abs += relative.abs();
        sum_a += ya;
        sum_b += yb;
        for c in 0..3 {
            let (x, y) = (a.rgb[i][c] as f64, b.rgb[i][c] as f64);
            err2 += (x - y) * (x - y);
            ref2 += y * y;
        }
    }
    if lit == 0 {
        bail!(
            "{} has no lit pixel to compare against ({} of {} pixels masked as silhouettes, mean luminance {mean})",
            b.name,
            n - unmasked,
            n
        );
    }
    let reference_noise = b.std_error.as_ref().map(|_| (noise2 / lit as f64).sqrt());
    Ok(Agreement {
        own_error: reference_noise.map(|noise| (rel2 / lit as f64 - noise * noise).max(0.0).sqrt()),
        reference_noise,
        emitter_pixels,
        background_pixels,
        leaked_pixels,
        relative_rmse: (rel2 / lit as f64).sqrt(),
        mean_abs_relative_error: rel_abs / lit as f64,
        relative_bias: (sum_a - sum_b) / sum_b,
        l2_ratio: (err2 / ref2).sqrt(),
        pixels: n,
        lit_pixels: lit,
        masked_pixels: n - unmasked,
        surface_ids: interior && (a.surface_id.is_some() || b.surface_id.is_some()),
        lit_threshold: threshold,
    })
}

/// Reads channel group `layer` (`""` for the main R, G, B) of two EXR files and compares them.
pub fn compare_files(a: &Path, b: &Path, layer: &str) -> Result<Comparison> {
    let (a, b) = (Picture::read(a, layer)?, Picture::read(b, layer)?);
    compare(&a, &b)
}

impl Comparison {
    /// The figures as a person reads them: the whole image's headline first, then the interior's.
    pub fn summary(&self) -> Vec<String> {
        let whole = self.whole.summary();
        let mut lines = vec![format!("whole image (nothing masked): {}", whole[0])];
        lines.extend(whole[1..whole.len() - 1].iter().map(|l| format!("  {l}")));
        lines.push(format!("interior: {}", self.interior.summary()[0]));
        lines.extend(self.interior.summary()[1..].iter().map(|l| format!("  {l}")));
        lines
    }

    /// The figures as JSON, with the files they compare: `whole` and `interior`, each an [`Agreement`].
    pub fn to_json(&self, image: &Path, reference: &Path, layer: &str) -> Result<Vec<u8>> {
        #[derive(serde::Serialize)]
        struct Report<'a> {
            image: String,
            reference: String,
            layer: &'a str,
            whole: &'a Agreement,
            interior: &'a Agreement,
            lit_fraction: f64,
        }
        let report = Report {
            image: image.display().to_string(),
            reference: reference.display().to_string(),
            layer,
            whole: &self.whole,
            interior: &self.interior,
            lit_fraction: LIT_FRACTION,
        };
        let mut json = serde_json::to_vec_pretty(&report).context("comparison to JSON")?;
        json.push(b'\n');
        Ok(json)
    }
}

impl Agreement {
    /// The figures as a person reads them, one line each; the headline first.
    pub fn summary(&self) -> Vec<String> {
        let masked = if self.surface_ids {
            format!(
                "{} silhouette pixel(s) masked (surface_id)",
                self.masked_pixels - self.emitter_pixels - self.background_pixels
            )
        } else {
            "no surface_id channel, so no silhouette masked".to_owned()
        };
        let emitters = match self.emitter_pixels {
            0 => String::new(),
            n => format!(", {n} emitter pixel(s) left out"),
        };
        let emitters = match self.background_pixels {
            0 => emitters,
            n => format!("{emitters}, {n} background pixel(s) left out"),
        };
        let mut lines = vec![format!(
            "relative RMSE {:.4} (per pixel, luminance, over {} lit pixels of {})",
            self.relative_rmse, self.lit_pixels, self.pixels
        )];
        if let (Some(noise), Some(own)) = (self.reference_noise, self.own_error) {
            lines.push(format!(
                "reference noise {noise:.4} (RMS of its relative standard error); the image's own error {own:.4}"
            ));
        }
        lines.extend([
            format!(
                "mean absolute relative error {:.4}, bias {:+.4}, L2 ratio {:.4} (sqrt(Σ|a−b|²/Σ|b|²), RGB)",
                self.mean_abs_relative_error, self.relative_bias, self.l2_ratio
            ),
            format!(
                "lit: reference luminance > {:.4e} ({} % of its mean); {masked}{emitters}; {} pixel(s) lit where the \
                 reference is black; no NaN or infinite pixel in either image",
                self.lit_threshold,
                LIT_FRACTION * 100.0,
                self.leaked_pixels
            ),
        ]);
        lines
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::picture::missing_layer;

    fn picture(name: &str, width: usize, rgb: Vec<[f32; 3]>, ids: Option<Vec<f32>>) -> Picture {
        let height = rgb.len() / width;
        Picture { name: name.into(), width, height, rgb, surface_id: ids, std_error: None, emitter: None }
    }

    /// A layer the file lacks is named with the layers it has; a render's AOV layer says how to get it.
    #[test]
    fn a_missing_layer_names_what_the_file_has_and_how_to_get_it() {
        let channels = |names: &[&str]| names.iter().map(|n| (n.to_string(), Vec::new())).collect::<Vec<_>>();
        let plain = channels(&["B", "G", "R"]);
        let path = Path::new("a.exr");
        assert_eq!(
            missing_layer(path, "radiance", &plain),
            "a.exr has no layer 'radiance' to compare (it has only the main R, G, B); render with --aovs to write \
             'radiance' (`sensorlight reference` always writes it)"
        );
        let aovs = channels(&["radiance.B", "radiance.G", "radiance.R", "surface_id"]);
        assert_eq!(
            missing_layer(path, "", &aovs),
            "a.exr has no main R, G, B layer to compare (it has only 'radiance')"
        );
        assert!(missing_layer(path, "x", &[]).ends_with("(it has no R, G, B layer at all)"));
    }

    /// A reference that knows its noise: the image's own error is what the noise does not explain.
    #[test]
    fn the_reference_noise_is_taken_out_in_quadrature() {
        let b = vec![[1.0; 3]; 4];
        let a: Vec<[f32; 3]> = [1.05f32, 0.95, 1.05, 0.95].iter().map(|&v| [v; 3]).collect();
        let mut reference = picture("ref", 2, b, None);
        let image = picture("img", 2, a, None);
        let without = agreement(&image, &reference).unwrap();
        assert!(without.reference_noise.is_none() && without.own_error.is_none());
        reference.std_error = Some(vec![[0.03; 3]; 4]);
        let with = agreement(&image, &reference).unwrap();
        assert!((with.relative_rmse - 0.05).abs() < 1e-6);
        assert!((with.reference_noise.unwrap() - 0.03).abs() < 1e-6);
        assert!((with.own_error.unwrap() - 0.04).abs() < 1e-6, "sqrt(0.05² − 0.03²) = 0.04");
        reference.std_error = Some(vec![[0.2; 3]; 4]);
        assert_eq!(agreement(&image, &reference).unwrap().own_error, Some(0.0), "noise explains all of it");
    }

    /// A bright emitter and a dim wall: 10 % error on the wall, none on the emitter. The per-pixel headline
    /// sees the wall's error on half the pixels; the old L2 ratio hardly sees it.
    #[test]
    fn the_headline_weighs_every_lit_pixel_alike() {
        let mut b = vec![[100.0f32; 3]; 4];
        b.extend(vec![[1.0f32; 3]; 4]);
        let a: Vec<[f32; 3]> = b.iter().map(|p| if p[0] > 1.0 { *p } else { p.map(|v| v * 1.1) }).collect();
        let r = agreement(&picture("a", 4, a, None), &picture("b", 4, b, None)).unwrap();
        assert_eq!((r.pixels, r.lit_pixels, r.masked_pixels), (8, 8, 0));
        let expected = (0.5f64 * 0.01).sqrt(); // sqrt(mean of four 0 and four 0.1²)
        assert!((r.relative_rmse - expected).abs() < 1e-6, "{r:?}");
        assert!((r.mean_abs_relative_error - 0.05).abs() < 1e-6, "{r:?}");
        assert!(r.l2_ratio < 0.002, "the L2 ratio is dominated by the emitter: {r:?}");
        let bias = (4.0 * 1.1 - 4.0) / (4.0 * 100.0 + 4.0);
        assert!((r.relative_bias - bias).abs() < 1e-6, "{r:?}");
    }

    #[test]
    fn dark_reference_pixels_are_not_lit() {
        // Mean luminance ≈ 0.5: the threshold ≈ 0.005; 0.001 and 0 are left out, whatever `a` holds there.
        let b = vec![[0.998f32; 3], [0.001; 3], [0.0; 3], [1.0; 3]];
        let a = vec![[0.998f32; 3], [5.0; 3], [7.0; 3], [1.0; 3]];
        let r = agreement(&picture("a", 2, a, None), &picture("b", 2, b, None)).unwrap();
        assert_eq!(r.lit_pixels, 2);
        assert!((r.lit_threshold - 0.005).abs() < 1e-5 && r.relative_rmse < 1e-6, "{r:?}");
    }

    /// An emitter pixel (known from either image's `emission` layer) is left out however wrong it is, and a
    /// pixel lit where the reference is black is counted as a leak, though no lit-pixel figure can see it.
    #[test]
    fn emitters_are_left_out_and_leaks_counted() {
        let b = vec![[50.0f32; 3], [1.0; 3], [1.0; 3], [0.0; 3]];
        let a = vec![[20.0f32; 3], [1.0; 3], [1.0; 3], [0.5; 3]];
        let plain = agreement(&picture("a", 2, a.clone(), None), &picture("b", 2, b.clone(), None)).unwrap();
        assert_eq!((plain.emitter_pixels, plain.leaked_pixels, plain.lit_pixels), (0, 1, 3));
        assert!(plain.relative_rmse > 0.3, "the emitter's 60 % error counts: {plain:?}");
        let emitter = Some(vec![true, false, false, false]);
        let mut reference = picture("b", 2, b, None);
        reference.emitter = emitter.clone();
        let r = agreement(&picture("a", 2, a.clone(), None), &reference).unwrap();
        assert_eq!((r.emitter_pixels, r.masked_pixels, r.lit_pixels, r.leaked_pixels), (1, 1, 2, 1));
        assert!(r.relative_rmse < 1e-9, "{r:?}");
        reference.emitter = None;
        let mut image = picture("a", 2, a, None);
        image.emitter = emitter;
        assert_eq!(agreement(&image, &reference).unwrap().emitter_pixels, 1, "either image's layer counts");
    }

    #[test]
    fn nan_and_inf_are_errors_counted_per_image() {
        let b = vec![[f32::NAN; 3]; 4];
        let a = vec![[1.0f32; 3], [f32::INFINITY, 0.0, 0.0], [1.0; 3], [1.0; 3]];
        let message = agreement(&picture("a.exr", 2, a, None), &picture("b.exr", 2, b, None)).unwrap_err().to_string();
        assert!(message.contains("a.exr: 0 NaN and 1 infinite pixel(s), the first at x 1, y 0"), "{message}");
        assert!(message.contains("b.exr: 4 NaN and 0 infinite"), "{message}");
        let fine = vec![[1.0f32; 3]; 4];
        let message =
            agreement(&picture("a.exr", 2, fine.clone(), None), &picture("b.exr", 4, fine, None)).unwrap_err();
        assert!(message.to_string().contains("a.exr is 2x2 but b.exr is 4x1"), "{message}");
    }

    #[test]
    fn an_all_black_reference_is_an_error() {
        let black = vec![[0.0f32; 3]; 4];
        let message = agreement(&picture("a", 2, black.clone(), None), &picture("b", 2, black, None)).unwrap_err();
        assert!(message.to_string().contains("b has no lit pixel"), "{message}");
    }

    /// Two surfaces side by side, 4 × 3: the columns on either side of the edge are masked, and a large
    /// error there does not count.
    #[test]
    fn silhouettes_are_masked_where_either_image_has_surface_ids() {
        let ids: Vec<f32> = (0..12).map(|i| if i % 4 < 2 { 1.0 } else { 2.0 }).collect();
        let mask = silhouettes(4, 3, &ids);
        assert_eq!(mask.iter().filter(|&&m| m).count(), 6);
        assert!((0..3).all(|y| mask[y * 4 + 1] && mask[y * 4 + 2] && !mask[y * 4] && !mask[y * 4 + 3]));
        let b = vec![[1.0f32; 3]; 12];
        let a: Vec<[f32; 3]> = (0..12).map(|i| if mask[i] { [3.0; 3] } else { [1.0; 3] }).collect();
        for (ia, ib) in [(Some(ids.clone()), None), (None, Some(ids.clone()))] {
            let r = agreement(&picture("a", 4, a.clone(), ia), &picture("b", 4, b.clone(), ib)).unwrap();
            assert_eq!((r.masked_pixels, r.lit_pixels), (6, 6));
            assert!(r.relative_rmse < 1e-9 && r.surface_ids, "{r:?}");
        }
        let r = agreement(&picture("a", 4, a, None), &picture("b", 4, b, None)).unwrap();
        assert_eq!(r.masked_pixels, 0);
        assert!((r.relative_rmse - 2.0f64.sqrt()).abs() < 1e-6, "unmasked, the edge counts: {r:?}");
    }
}
