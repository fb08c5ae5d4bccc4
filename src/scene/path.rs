//! A camera path: keyframes with times, interpolated, for the frames of a fly-through (`render --frame K`,
//! `--frames A..B`). Frame K is the camera at time K / fps.
//!
//! ```toml
//! [path]
//! fps = 24
//! [[path.key]]
//! time = 0                      # seconds, increasing from key to key
//! eye = [278, 273, -800]
//! target = [278, 273, 0]
//! # up = [0, 1, 0]              # optional, as vfov_deg: the [camera]'s where not given
//! [[path.key]]
//! time = 2
//! eye = [400, 273, -700]
//! target = [278, 273, 0]
//! ```
//!
//! Between two keys the eye, the target, the up vector and the field of view move linearly in time (the
//! camera is then made as `[camera]` makes it); before the first key and after the last, the path stands at
//! them. Linear keeps what the keys say exactly at their times and never overshoots them, which a spline
//! would.

use anyhow::{Result, bail, ensure};
use glam::Vec3;
use serde::Deserialize;

use super::Camera;

/// The `[path]` table as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PathSection {
    pub fps: f32,
    pub key: Vec<KeySection>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeySection {
    pub time: f32,
    pub eye: [f32; 3],
    pub target: [f32; 3],
    pub up: Option<[f32; 3]>,
    pub vfov_deg: Option<f32>,
}

/// One keyframe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key {
    pub time: f32,
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    pub vfov_deg: f32,
}

/// The keyframes and their rate.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraPath {
    pub fps: f32,
    pub keys: Vec<Key>,
}

impl CameraPath {
    /// The path `section` gives, whose keys take `camera`'s up and field of view where they give none.
    /// Errors name the key (from 1).
    pub fn new(section: &PathSection, camera: &Camera) -> Result<Self> {
        ensure!(section.fps.is_finite() && section.fps > 0.0, "fps must be a number above 0, got {}", section.fps);
        ensure!(!section.key.is_empty(), "a path needs at least one [[path.key]]");
        let mut keys = Vec::with_capacity(section.key.len());
        for (n, k) in section.key.iter().enumerate() {
            let key = Key {
                time: k.time,
                eye: k.eye.into(),
                target: k.target.into(),
                up: k.up.map_or(camera.up, Vec3::from),
                vfov_deg: k.vfov_deg.unwrap_or(camera.vfov.to_degrees()),
            };
            if !key.time.is_finite() || keys.last().is_some_and(|p: &Key| key.time <= p.time) {
                bail!("[[path.key]] {}: time {} must be finite and after the key before it", n + 1, key.time);
            }
            Camera::look_at(key.eye, key.target, key.up, key.vfov_deg)
                .map_err(|e| anyhow::anyhow!("[[path.key]] {}: {e}", n + 1))?;
            keys.push(key);
        }
        Ok(Self { fps: section.fps, keys })
    }

    /// The last frame: the one at (or just before) the last key's time.
    pub fn last_frame(&self) -> u32 {
        let last = self.keys.last().map_or(0.0, |k| k.time);
        (last * self.fps + 1e-4).floor().max(0.0) as u32
    }

    /// The camera of frame `frame` (at time frame / fps).
    pub fn camera(&self, frame: u32) -> Result<Camera> {
        let t = frame as f32 / self.fps;
        let k = &self.keys;
        let next = k.iter().position(|key| key.time > t).unwrap_or(k.len());
        let key = match next {
            0 => k[0],
            n if n == k.len() => k[n - 1],
            n => {
                let (a, b) = (k[n - 1], k[n]);
                let s = (t - a.time) / (b.time - a.time);
                Key {
                    time: t,
                    eye: a.eye.lerp(b.eye, s),
                    target: a.target.lerp(b.target, s),
                    up: a.up.lerp(b.up, s),
                    vfov_deg: a.vfov_deg + (b.vfov_deg - a.vfov_deg) * s,
                }
            }
        };
        Camera::look_at(key.eye, key.target, key.up, key.vfov_deg)
            .map_err(|e| anyhow::anyhow!("frame {frame} (time {t} s) of the path: {e}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path(text: &str) -> Result<CameraPath> {
        let section: PathSection = toml::from_str(text).unwrap();
        let camera = Camera::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 60.0).unwrap();
        CameraPath::new(&section, &camera)
    }

    #[test]
    fn frames_move_linearly_between_keys_and_stand_at_the_ends() {
        let p = path(
            "fps = 10\n[[key]]\ntime = 0\neye = [0, 0, 0]\ntarget = [0, 0, 1]\n[[key]]\ntime = 2\neye = [4, 0, 0]\n\
             target = [4, 0, 1]\nvfov_deg = 40",
        )
        .unwrap();
        assert_eq!(p.last_frame(), 20);
        let c = p.camera(5).unwrap();
        assert!((c.eye - Vec3::new(1.0, 0.0, 0.0)).length() < 1e-6, "{:?}", c.eye);
        assert!((c.vfov.to_degrees() - 55.0).abs() < 1e-4, "the [camera]'s 60° to the key's 40°");
        assert_eq!(p.camera(20).unwrap().eye, Vec3::new(4.0, 0.0, 0.0));
        assert_eq!(p.camera(30).unwrap().eye, Vec3::new(4.0, 0.0, 0.0), "after the last key: the last key");
    }

    #[test]
    fn bad_paths_are_refused_naming_the_key() {
        let key = |t: &str| format!("[[key]]\ntime = {t}\neye = [0, 0, 0]\ntarget = [0, 0, 1]\n");
        let e = path(&format!("fps = 24\n{}{}", key("1"), key("1"))).unwrap_err().to_string();
        assert!(e.contains("[[path.key]] 2: time 1 must be finite and after"), "{e}");
        let e = path(&format!("fps = 0\n{}", key("0"))).unwrap_err().to_string();
        assert!(e.contains("fps must be a number above 0"), "{e}");
        let e = path("fps = 24\n[[key]]\ntime = 0\neye = [0, 0, 0]\ntarget = [0, 0, 0]\n").unwrap_err().to_string();
        assert!(e.contains("[[path.key]] 1: camera eye and target coincide"), "{e}");
    }
}
