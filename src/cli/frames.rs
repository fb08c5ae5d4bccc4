//! The frames of a scene's camera path on the command line: `--frames A..B`, and the numbered names of
//! their outputs (`OUT.####.exr`).

use std::path::{Path, PathBuf};

use anyhow::Result;
use sensorlight::scene::Scene;

/// `A..B`: frames A to B, both included.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    pub first: u32,
    pub last: u32,
}

impl std::str::FromStr for FrameRange {
    type Err = String;
    fn from_str(text: &str) -> Result<Self, String> {
        match super::args::two_numbers(text, "..").map(|(first, last)| Self { first, last }) {
            Some(r) if r.first <= r.last => Ok(r),
            Some(r) => Err(format!("{}..{}: the first frame comes after the last", r.first, r.last)),
            None => Err(format!("expected A..B (frames A to B, both included), got '{text}'")),
        }
    }
}

/// `OUT.exr` for frame `k`: `OUT.####.exr` (four digits at least), its PNG beside it as for any output.
pub fn numbered(output: &Path, k: u32) -> PathBuf {
    let ext = output.extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_default();
    output.with_extension(format!("{k:04}.{ext}"))
}

/// The scene's camera path where frames are asked for (`numbers` holds none or only `None` else), each
/// within it.
pub fn path_of(scene: &Scene, numbers: &[Option<u32>]) -> Result<Option<sensorlight::scene::CameraPath>> {
    if numbers.iter().all(Option::is_none) {
        return Ok(None);
    }
    let Some(path) = &scene.camera_path else {
        anyhow::bail!(
            "--frame and --frames need a camera path: {} has no [path] (keyframes with times; docs/USAGE.md, \
             \"Frames\")",
            scene.path.display()
        );
    };
    let last = path.last_frame();
    if let Some(k) = numbers.iter().flatten().find(|&&k| k > last) {
        anyhow::bail!("frame {k} is after the path's end: its last key is frame {last} (at {} fps)", path.fps);
    }
    Ok(Some(path.clone()))
}
