//! Linear HDR output: one OpenEXR part with the main image as `R`, `G`, `B` and any AOVs as named channel
//! groups (`albedo.R`, …, `surface_id`), the convention viewers such as tev and Nuke show as layers.

use std::io::{Seek, Write};
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

    /// Adds the rgb of `pixels` as [`ExrImage::rgb`] does and their w as `A` (or `layer.A`): the image's
    /// coverage, 1 where a surface is seen and 0 on the background, so that it composites over another.
    pub fn rgba(self, layer: &str, pixels: &[Vec4]) -> Self {
        let alpha = if layer.is_empty() { "A".to_owned() } else { format!("{layer}.A") };
        self.rgb(layer, pixels).scalar(&alpha, pixels.iter().map(|p| p.w).collect())
    }

    /// Adds vectors as `layer.X`, `layer.Y`, `layer.Z` (normals).
    pub fn xyz(mut self, layer: &str, values: &[[f32; 3]]) -> Self {
        assert_eq!(values.len(), self.width * self.height, "{layer}: wrong pixel count");
        for (c, name) in ["X", "Y", "Z"].iter().enumerate() {
            self.channels.push((format!("{layer}.{name}"), values.iter().map(|v| v[c]).collect()));
        }
        self
    }

    /// Adds a single channel.
    pub fn scalar(mut self, name: &str, values: Vec<f32>) -> Self {
        assert_eq!(values.len(), self.width * self.height, "{name}: wrong pixel count");
        self.channels.push((name.to_owned(), values));
        self
    }

    /// Encodes the image into `w`. The file is the same, byte for byte, for the same image: scan-line blocks
    /// are stored in increasing order (the `exr` crate's default, "unspecified", writes them in the order its
    /// threads finish compressing them).
    pub fn encode(self, w: &mut (impl Write + Seek)) -> Result<()> {
        ensure!(!self.channels.is_empty(), "an EXR needs at least one channel");
        let channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = self
            .channels
            .into_iter()
            .map(|(name, data)| AnyChannel::new(name.as_str(), FlatSamples::F32(data)))
            .collect();
        let encoding = Encoding { line_order: LineOrder::Increasing, ..Encoding::FAST_LOSSLESS };
        let image = Image::from_encoded_channels((self.width, self.height), encoding, AnyChannels::sort(channels));
        image.write().to_buffered(w)?;
        Ok(())
    }

    /// Writes the file atomically (temporary name, then rename).
    pub fn write(self, path: &Path) -> Result<()> {
        atomic::write_file(path, |w| self.encode(w))
    }

    /// Stages the file among `outputs` (written with the others, or not at all).
    pub fn stage(self, outputs: &mut atomic::Outputs, path: &Path) -> Result<()> {
        outputs.stage(path, |w| self.encode(w))
    }
}

/// Channels by name, each with its samples in row-major order from the top.
pub type NamedChannels = Vec<(String, Vec<f32>)>;

/// Every channel of the first layer of an EXR: (width, height, channels).
pub fn read_all(path: &Path) -> Result<(usize, usize, NamedChannels)> {
    let image =
        read_all_flat_layers_from_file(path).map_err(|e| anyhow::anyhow!("cannot read {}: {e}", path.display()))?;
    let layer = image.layer_data.first().ok_or_else(|| anyhow::anyhow!("{}: no layers", path.display()))?;
    let (w, h) = (layer.size.width(), layer.size.height());
    let channels =
        layer.channel_data.list.iter().map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect())).collect();
    Ok((w, h, channels))
}

/// Reads the named channels of an EXR written by [`ExrImage::write`] (for tests and tools).
pub fn read_channels(path: &Path, names: &[&str]) -> Result<(usize, usize, Vec<Vec<f32>>)> {
    let (w, h, mut channels) = read_all(path)?;
    let mut out = Vec::new();
    for name in names {
        let Some(i) = channels.iter().position(|(n, _)| n == name) else {
            let present: Vec<&str> = channels.iter().map(|(n, _)| n.as_str()).collect();
            anyhow::bail!("{}: no channel {name} (it has {})", path.display(), present.join(", "));
        };
        out.push(std::mem::take(&mut channels[i].1));
    }
    Ok((w, h, out))
}
