//! Linear HDR output: one OpenEXR part with the main image as `R`, `G`, `B` and any AOVs as named channel
//! groups (`albedo.R`, …, `surface_id`), the convention viewers such as tev and Nuke show as layers.

use std::path::Path;

use anyhow::{Result, ensure};
use exr::prelude::*;
use glam::Vec4;

use super::atomic;

pub struct ExrImage {
    width: usize,
    height: usize,
    channels: Vec<(String, Vec<f32>)>,
}

impl ExrImage {
    pub fn new(width: u32, height: u32) -> Self {
        Self { width: width as usize, height: height as usize, channels: Vec::new() }
    }

    /// Adds the rgb of `pixels` as `R`, `G`, `B` (empty `layer`) or `layer.R`, `layer.G`, `layer.B`.
    pub fn rgb(mut self, layer: &str, pixels: &[Vec4]) -> Self {
        assert_eq!(pixels.len(), self.width * self.height, "{layer}: wrong pixel count");
        let prefix = if layer.is_empty() { String::new() } else { format!("{layer}.") };
        for (c, name) in ["R", "G", "B"].iter().enumerate() {
            self.channels.push((format!("{prefix}{name}"), pixels.iter().map(|p| p[c]).collect()));
        }
        self
    }

    /// Adds a single channel.
    pub fn scalar(mut self, name: &str, values: Vec<f32>) -> Self {
        assert_eq!(values.len(), self.width * self.height, "{name}: wrong pixel count");
        self.channels.push((name.to_owned(), values));
        self
    }

    /// Writes the file atomically (temporary name, then rename).
    pub fn write(self, path: &Path) -> Result<()> {
        ensure!(!self.channels.is_empty(), "an EXR needs at least one channel");
        let channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = self
            .channels
            .into_iter()
            .map(|(name, data)| AnyChannel::new(name.as_str(), FlatSamples::F32(data)))
            .collect();
        // Blocks stored in increasing order: the same image is then the same file, byte for byte (the exr
        // crate's default, "unspecified", stores them in the order its threads finish compressing them).
        let encoding = Encoding { line_order: LineOrder::Increasing, ..Encoding::FAST_LOSSLESS };
        let image = Image::from_encoded_channels((self.width, self.height), encoding, AnyChannels::sort(channels));
        atomic::write_file(path, |w| Ok(image.write().to_buffered(w)?))
    }
}

/// Reads the named channels of an EXR written by [`ExrImage::write`] (for tests and tools).
pub fn read_channels(path: &Path, names: &[&str]) -> Result<(usize, usize, Vec<Vec<f32>>)> {
    let image =
        read_all_flat_layers_from_file(path).map_err(|e| anyhow::anyhow!("cannot read {}: {e}", path.display()))?;
    let layer = image.layer_data.first().ok_or_else(|| anyhow::anyhow!("{}: no layers", path.display()))?;
    let (w, h) = (layer.size.width(), layer.size.height());
    let mut out = Vec::new();
    for name in names {
        let channel = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == *name)
            .ok_or_else(|| anyhow::anyhow!("{}: no channel {name}", path.display()))?;
        out.push(channel.sample_data.values_as_f32().collect());
    }
    Ok((w, h, out))
}
