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
    /// A tile of a larger image: the image's size and where the data's top-left pixel lies in it (the
    /// data window; the display window is the whole image).
    window: Option<Window>,
    /// Text attributes in the header (sorted by name when written).
    attributes: Vec<(String, String)>,
}

/// Where a tile's pixels lie in the whole image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Window {
    pub width: usize,
    pub height: usize,
    pub x: usize,
    pub y: usize,
}

impl ExrImage {
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width: width as usize,
            height: height as usize,
            channels: Vec::new(),
            window: None,
            attributes: Vec::new(),
        }
    }

    /// Only rows `y0..y1` of the image, written as a tile of it: the data window says where they belong.
    pub fn rows(mut self, y0: usize, y1: usize) -> Self {
        assert!(y0 < y1 && y1 <= self.height && self.window.is_none(), "rows {y0}..{y1} of {}", self.height);
        let w = self.width;
        for (_, data) in &mut self.channels {
            *data = data[y0 * w..y1 * w].to_vec();
        }
        self.window = Some(Window { width: w, height: self.height, x: 0, y: y0 });
        self.height = y1 - y0;
        self
    }

    /// A text attribute in the header.
    pub fn attribute(mut self, name: &str, value: &str) -> Self {
        self.attributes.push((name.to_owned(), value.to_owned()));
        self
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
        let mut image = Image::from_encoded_channels((self.width, self.height), encoding, AnyChannels::sort(channels));
        if let Some(window) = self.window {
            image.layer_data.attributes.layer_position = Vec2(window.x as i32, window.y as i32);
            image.attributes.display_window = IntegerBounds::new((0, 0), (window.width, window.height));
        }
        let mut attributes = self.attributes;
        attributes.sort();
        for (name, value) in attributes {
            image.attributes.other.insert(Text::from(name.as_str()), AttributeValue::Text(Text::from(value.as_str())));
        }
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
    let image = read_flat(path)?;
    let layer = first_layer(&image, path)?;
    Ok((layer.size.width(), layer.size.height(), channels_of(layer)))
}

/// Every layer of the EXR at `path`, its channels as flat samples.
fn read_flat(path: &Path) -> Result<FlatImage> {
    read_all_flat_layers_from_file(path).map_err(|e| anyhow::anyhow!("cannot read {}: {e}", path.display()))
}

fn first_layer<'a>(image: &'a FlatImage, path: &Path) -> Result<&'a Layer<AnyChannels<FlatSamples>>> {
    image.layer_data.first().ok_or_else(|| anyhow::anyhow!("{}: no layers", path.display()))
}

/// A layer's channels by name, as `f32`.
fn channels_of(layer: &Layer<AnyChannels<FlatSamples>>) -> NamedChannels {
    layer.channel_data.list.iter().map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect())).collect()
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

/// A tile as [`ExrImage::rows`] wrote it: where it lies, its text attributes and its channels.
pub struct Tile {
    pub window: Window,
    /// Its data's size.
    pub width: usize,
    pub height: usize,
    pub attributes: std::collections::BTreeMap<String, String>,
    pub channels: NamedChannels,
}

/// Reads an EXR as a tile of an image (a whole image is its own one tile).
pub fn read_tile(path: &Path) -> Result<Tile> {
    let image = read_flat(path)?;
    let layer = first_layer(&image, path)?;
    let (width, height) = (layer.size.width(), layer.size.height());
    let display = image.attributes.display_window;
    let position = layer.attributes.layer_position - display.position;
    ensure!(
        position.x() >= 0 && position.y() >= 0,
        "{}: its data window starts outside its display window",
        path.display()
    );
    let window = Window {
        width: display.size.width(),
        height: display.size.height(),
        x: position.x() as usize,
        y: position.y() as usize,
    };
    // Attributes the crate does not know are kept with the layer when read (a single part's header is both).
    let attributes = (image.attributes.other.iter().chain(&layer.attributes.other))
        .filter_map(|(name, value)| match value {
            AttributeValue::Text(text) => Some((name.to_string(), text.to_string())),
            _ => None,
        })
        .collect();
    Ok(Tile { window, width, height, attributes, channels: channels_of(layer) })
}
