//! A render split into tiles (`render --image-tile I/N`) and joined again (`sensorlight assemble`): the joined
//! image, AOVs and PNG equal the single process's render bit for bit.
//!
//! Tile I of N is the band of rows `(I − 1)·H/N .. I·H/N` (rounded down): bands keep each process's share
//! of the image even and its margin one-dimensional. A tile renders the whole image's first sensor grid
//! (whose brightest R sets the refinement's dark floor) and then refines only the quads that meet its band
//! grown by the filters' and the supersampling's reach (`renderer::REGION_MARGIN`), so that every pixel of
//! the band is what the whole render gives it; it writes only its band, every AOV included, in an EXR
//! whose data window says where the band lies, with in its header which tile it is, a hash of everything
//! the image depends on, and how the PNG's exposure is to be chosen.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context as _, Result, bail, ensure};
use clap::Args;
use glam::{Vec3, Vec4};
use sensorlight::gi::file::{Fingerprint, Fnv};
use sensorlight::output::exr::{self, ExrImage};
use sensorlight::output::{atomic, png};
use sensorlight::params::{Param, Region, RenderParams};
use sensorlight::scene::{ImageSize, NO_SURFACE, Scene};

use super::ExposureRule;

/// The header attributes of a tile.
const TILE: &str = "sensorlight.tile";
const RENDER: &str = "sensorlight.render";
const EXPOSURE: &str = "sensorlight.exposure";
const AOVS: &str = "sensorlight.aovs";

/// Tile `index` (from 1) of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileSpec {
    pub index: u32,
    pub count: u32,
}

impl std::fmt::Display for TileSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl std::str::FromStr for TileSpec {
    type Err = String;
    fn from_str(text: &str) -> Result<Self, String> {
        match super::args::two_numbers(text, "/").map(|(index, count)| Self { index, count }) {
            Some(t) if t.count >= 1 && (1..=t.count).contains(&t.index) => Ok(t),
            Some(t) => Err(format!("tile {t}: the tile's number runs from 1 to its count")),
            None => Err(format!("expected I/N (tile I of N, from 1), got '{text}'")),
        }
    }
}

impl TileSpec {
    /// Its band of rows in an image of `size`.
    pub fn rows(self, size: ImageSize) -> Result<(u32, u32)> {
        ensure!(
            self.count <= size.height,
            "--image-tile {self}: {} tiles of rows need an image at least {} pixels high (it is {})",
            self.count,
            self.count,
            size.height
        );
        let row = |k: u32| (k as u64 * size.height as u64 / self.count as u64) as u32;
        Ok((row(self.index - 1), row(self.index)))
    }

    /// The region its render must get right.
    pub fn region(self, size: ImageSize) -> Result<Region> {
        let (y0, y1) = self.rows(size)?;
        Ok(Region { x0: 0, y0, x1: size.width, y1 })
    }
}

/// A hash of everything a render's pixels depend on: the scene (as the radiance cache's fingerprint has
/// it), every parameter, the size and the camera. Tiles of one render share it.
pub fn render_id(scene: &Scene, params: &RenderParams, size: ImageSize) -> String {
    let mut h = Fnv::new();
    h.text(&serde_json::to_string(&Fingerprint::of(scene, params)).unwrap_or_default());
    for &p in Param::ALL {
        h.text(&format!("{}={};", p.key(), params.values.show(p)));
    }
    h.text(&format!("{size:?} {:?}", scene.camera));
    h.hex()
}

/// The tile `tile` of `exr` (the whole image, every AOV in it) with its header.
pub fn tile_exr(
    exr: ExrImage,
    tile: TileSpec,
    size: ImageSize,
    header: (&str, ExposureRule, bool),
) -> Result<ExrImage> {
    let (id, exposure, aovs) = header;
    let (y0, y1) = tile.rows(size)?;
    Ok(exr
        .rows(y0 as usize, y1 as usize)
        .attribute(TILE, &tile.to_string())
        .attribute(RENDER, id)
        .attribute(EXPOSURE, &exposure.text())
        .attribute(AOVS, if aovs { "yes" } else { "no" }))
}

#[derive(Args)]
pub struct AssembleArgs {
    /// The tiles, each an EXR that `render --image-tile I/N` wrote, in any order
    #[arg(required = true, value_name = "TILE.exr")]
    tiles: Vec<PathBuf>,
    /// The joined image: F.exr (with the AOVs where the tiles were rendered with --aovs) and F.png beside it
    #[arg(short, long, value_name = "F.exr")]
    output: PathBuf,
    /// Do not write the PNG
    #[arg(long)]
    no_png: bool,
}

/// A tile as read, with what its header says.
struct Read {
    path: PathBuf,
    tile: TileSpec,
    render: String,
    exposure: ExposureRule,
    aovs: bool,
    exr: exr::Tile,
}

fn read(path: &Path) -> Result<Read> {
    let exr = exr::read_tile(path)?;
    let attribute = |name: &str| {
        exr.attributes.get(name).cloned().with_context(|| {
            format!("{}: not a tile of `render --image-tile` (its header has no {name})", path.display())
        })
    };
    let tile: TileSpec = attribute(TILE)?.parse().map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let exposure = ExposureRule::parse(&attribute(EXPOSURE)?)
        .with_context(|| format!("{}: its {EXPOSURE} cannot be read", path.display()))?;
    let (render, aovs) = (attribute(RENDER)?, attribute(AOVS)? == "yes");
    Ok(Read { path: path.to_owned(), tile, render, exposure, aovs, exr })
}

pub fn run(args: AssembleArgs) -> Result<ExitCode> {
    let outputs = super::ImageOutputs::new(&args.output, !args.no_png)?;
    ensure!(
        outputs.exr.is_some(),
        "-o {}: assemble writes an EXR (and its PNG); name an .exr file",
        args.output.display()
    );
    outputs.check(&[], &args.tiles.iter().map(PathBuf::as_path).collect::<Vec<_>>())?;
    let tiles = args.tiles.iter().map(|p| read(p)).collect::<Result<Vec<_>>>()?;
    let first = &tiles[0];
    for t in &tiles[1..] {
        let same = (&t.render, t.tile.count, t.aovs, t.exposure)
            == (&first.render, first.tile.count, first.aovs, first.exposure);
        if !same {
            bail!(
                "{} and {} are tiles of different renders (another scene, settings, size, count of tiles, --aovs or \
                 exposure); render every tile with the same command but its --image-tile",
                first.path.display(),
                t.path.display()
            );
        }
    }
    let count = first.tile.count;
    let mut by_index: BTreeMap<u32, &Read> = BTreeMap::new();
    for t in &tiles {
        if let Some(other) = by_index.insert(t.tile.index, t) {
            bail!("tile {} is given twice: {} and {}", t.tile, other.path.display(), t.path.display());
        }
    }
    let missing: Vec<String> =
        (1..=count).filter(|i| !by_index.contains_key(i)).map(|i| format!("{i}/{count}")).collect();
    ensure!(missing.is_empty(), "missing tile(s) {} of the {count}", missing.join(", "));
    let (width, height) = (first.exr.window.width, first.exr.window.height);
    let size = ImageSize { width: width as u32, height: height as u32 };
    let names: Vec<&String> = first.exr.channels.iter().map(|(n, _)| n).collect();
    let mut channels: BTreeMap<&str, Vec<f32>> =
        names.iter().map(|n| (n.as_str(), vec![0.0; width * height])).collect();
    for t in by_index.values() {
        let (y0, y1) = t.tile.rows(size)?;
        let w = &t.exr.window;
        ensure!(
            (w.width, w.height, w.x, w.y) == (width, height, 0, y0 as usize)
                && (t.exr.width, t.exr.height) == (width, (y1 - y0) as usize),
            "{}: its pixels (rows {}..{} of {}×{}) are not tile {}'s (rows {y0}..{y1}): it overlaps another",
            t.path.display(),
            w.y,
            w.y + t.exr.height,
            w.width,
            w.height,
            t.tile
        );
        let mine: Vec<&String> = t.exr.channels.iter().map(|(n, _)| n).collect();
        ensure!(mine == names, "{} has other channels than {}", t.path.display(), first.path.display());
        for (name, data) in &t.exr.channels {
            channels.get_mut(name.as_str()).expect("same channels")[y0 as usize * width..y1 as usize * width]
                .copy_from_slice(data);
        }
    }
    let take = |name: &str| channels.get(name).cloned().with_context(|| format!("the tiles have no channel {name}"));
    let rgba = |prefix: &str| -> Result<Vec<Vec4>> {
        let c: Vec<Vec<f32>> = ["R", "G", "B"].iter().map(|n| take(&format!("{prefix}{n}"))).collect::<Result<_>>()?;
        Ok((0..width * height).map(|i| Vec4::new(c[0][i], c[1][i], c[2][i], 0.0)).collect())
    };
    let image = rgba("")?;
    let mut files = atomic::Outputs::new();
    if let Some(path) = &outputs.exr {
        let mut exr = ExrImage::new(size.width, size.height);
        for (name, data) in &channels {
            if first.aovs || ["R", "G", "B", "A"].contains(name) {
                exr = exr.scalar(name, data.clone());
            }
        }
        exr.stage(&mut files, path)?;
    }
    if let Some(path) = &outputs.png {
        let (surface, emission) = (take("surface_id")?, rgba("emission.")?);
        let lit = |i: usize| surface[i] as u32 != NO_SURFACE && emission[i].truncate() == Vec3::ZERO;
        let (exposure, auto) = first.exposure.choose(&image, lit);
        if let Some(text) = auto {
            say!("{text}");
        }
        png::stage(&mut files, path, (size.width, size.height), &image, exposure)?;
    }
    files.commit()?;
    for path in outputs.paths() {
        say!("wrote {}", path.display());
    }
    Ok(ExitCode::SUCCESS)
}
