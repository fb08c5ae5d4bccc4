//! An image as `compare` reads it from an EXR: its RGB (or a named layer's), and where the file has them,
//! its noise estimate and surface ids; a NaN or infinite pixel refused with where it is.

use std::path::Path;

use anyhow::{Context as _, Result, bail};

use crate::output::exr;

/// One image's channels as compared: R, G, B of a layer and the `surface_id` AOV where it has one.
#[derive(Clone, Debug)]
pub struct Picture {
    /// For messages: usually the file name.
    pub name: String,
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<[f32; 3]>,
    pub surface_id: Option<Vec<f32>>,
    /// The standard error of `rgb` where the image is an estimate that knows its own noise (the CPU
    /// reference).
    pub std_error: Option<Vec<[f32; 3]>>,
    /// Whether each pixel shows an emitter's front (its `emission` layer is not black), where known.
    pub emitter: Option<Vec<bool>>,
}

impl Picture {
    /// Reads channel group `layer` (`""` for the main R, G, B) of an EXR, and its `surface_id` if present.
    pub fn read(path: &Path, layer: &str) -> Result<Self> {
        let (width, height, mut channels) = exr::read_all(path)?;
        let prefix = if layer.is_empty() { String::new() } else { format!("{layer}.") };
        let found = ["R", "G", "B"].iter().all(|c| channels.iter().any(|(n, _)| *n == format!("{prefix}{c}")));
        if !found {
            bail!("{}", missing_layer(path, layer, &channels));
        }
        let mut take = |name: &str| channels.iter_mut().find(|(n, _)| n == name).map(|(_, v)| std::mem::take(v));
        let mut rgb = Vec::new();
        for c in ["R", "G", "B"] {
            let name = format!("{prefix}{c}");
            rgb.push(take(&name).with_context(|| format!("{}: no channel {name}", path.display()))?);
        }
        let surface_id = take("surface_id");
        let rgb = (0..width * height).map(|i| [rgb[0][i], rgb[1][i], rgb[2][i]]).collect();
        // The layer's standard error, where the image knows it: `std_error` for the main layer,
        // `<layer>_std_error` for another.
        let noise = if layer.is_empty() { "std_error".to_owned() } else { format!("{layer}_std_error") };
        let error: Option<Vec<Vec<f32>>> = ["R", "G", "B"].iter().map(|c| take(&format!("{noise}.{c}"))).collect();
        let std_error = error.map(|e| (0..width * height).map(|i| [e[0][i], e[1][i], e[2][i]]).collect());
        let emission: Option<Vec<Vec<f32>>> = ["R", "G", "B"].iter().map(|c| take(&format!("emission.{c}"))).collect();
        let emitter = emission.map(|e| (0..width * height).map(|i| e.iter().any(|c| c[i] > 0.0)).collect());
        Ok(Self { name: path.display().to_string(), width, height, rgb, surface_id, std_error, emitter })
    }

    /// NaN and infinite pixels (any channel), and the first one's (x, y).
    pub fn non_finite(&self) -> NonFinite {
        let mut count = NonFinite::default();
        for (i, p) in self.rgb.iter().enumerate() {
            let nan = p.iter().any(|v| v.is_nan());
            let inf = !nan && p.iter().any(|v| v.is_infinite());
            count.nan += nan as usize;
            count.infinite += inf as usize;
            if (nan || inf) && count.first.is_none() {
                count.first = Some((i % self.width, i / self.width));
            }
        }
        count
    }
}

/// Why `layer` cannot be compared in the image at `path` holding `channels`: the layers it has, and for a
/// render's AOV layer, how to get it (`render --aovs`).
pub(super) fn missing_layer(path: &Path, layer: &str, channels: &[(String, Vec<f32>)]) -> String {
    let mut layers: Vec<String> = Vec::new();
    for (name, _) in channels {
        let group = match name.rsplit_once('.') {
            Some((group, "R" | "G" | "B")) => format!("'{group}'"),
            None if ["R", "G", "B"].contains(&name.as_str()) => "the main R, G, B".to_owned(),
            _ => continue,
        };
        if !layers.contains(&group) {
            layers.push(group);
        }
    }
    let has =
        if layers.is_empty() { "no R, G, B layer at all".to_owned() } else { format!("only {}", layers.join(", ")) };
    let asked = if layer.is_empty() { "no main R, G, B layer".to_owned() } else { format!("no layer '{layer}'") };
    let hint = match layer {
        "radiance" | "emission" => {
            format!("; render with --aovs to write '{layer}' (`sensorlight reference` always writes it)")
        }
        _ => String::new(),
    };
    format!("{} has {asked} to compare (it has {has}){hint}", path.display())
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NonFinite {
    pub nan: usize,
    pub infinite: usize,
    pub first: Option<(usize, usize)>,
}

impl std::fmt::Display for NonFinite {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.first {
            None => write!(f, "no NaN or infinite pixel"),
            Some((x, y)) => {
                write!(f, "{} NaN and {} infinite pixel(s), the first at x {x}, y {y}", self.nan, self.infinite)
            }
        }
    }
}
