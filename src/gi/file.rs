//! The radiance cache as a file (`sensorlight cache`, `render --cache`): its solved values, what they were
//! solved for, and how solving went, so that tiles, frames and machines share one cache instead of each
//! solving it again. The cache's points and table are not stored: they follow from the scene and the
//! settings, which the file's [`Fingerprint`] records and a reader checks.
//!
//! Layout (little-endian): the magic `SENSORLIGHT-CACHE\n`, the format version (`u32`), the header's
//! length (`u64`) and the header (JSON: fingerprint, statistics, the count of values), the values (four
//! `f32` each), then a CRC-32 of everything before it, so that a truncated or damaged file is refused.

use std::collections::BTreeMap;

use glam::{Vec3, Vec4};
use serde::{Deserialize, Serialize};

use crate::params::{Param, RenderParams};
use crate::scene::Scene;

const MAGIC: &[u8] = b"SENSORLIGHT-CACHE\n";
/// The format written; a reader refuses a newer one.
pub const FORMAT: u32 = 1;

/// What a cache's values depend on: the scene's parts as hashes, and the settings by flag.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Fingerprint {
    /// The triangles, their shading normals and texture coordinates, and their surfaces.
    pub geometry: String,
    /// The materials and the textures they read.
    pub materials: String,
    /// The sun, or none.
    pub sun: String,
    /// The sky map, its strength and turn, or none.
    pub sky: String,
    /// Each setting the cache depends on, by flag, as the flag takes it.
    pub settings: BTreeMap<String, String>,
}

/// The parameters a cache's values depend on (the others act on the camera's pixels only).
const CACHE_PARAMS: [Param; 6] =
    [Param::Estimator, Param::Sensor, Param::Fov, Param::SensorSize, Param::CacheResolution, Param::CacheSensorSize];

impl Fingerprint {
    /// The fingerprint of `scene` rendered with `params`.
    pub fn of(scene: &Scene, params: &RenderParams) -> Self {
        let mesh = &scene.mesh;
        let mut geometry = Fnv::new();
        for t in &mesh.triangles {
            geometry.floats(t.v.iter().flat_map(|v| v.to_array()));
            geometry.bytes(&t.surface.to_le_bytes());
        }
        mesh.shading.iter().for_each(|n| geometry.floats(n.iter().flat_map(|v| v.to_array())));
        mesh.uvs.iter().for_each(|uv| geometry.floats(uv.iter().flat_map(|v| v.to_array())));
        geometry.text(&format!("{:?}", mesh.surfaces));
        let mut materials = Fnv::new();
        materials.text(&format!(
            "{:?}",
            mesh.materials.iter().map(|m| (m.kd, m.ke, m.kd_map, m.ke_map)).collect::<Vec<_>>()
        ));
        materials.text(&format!("{:?}", mesh.materials.iter().map(|m| &m.cutout).collect::<Vec<_>>()));
        for texture in mesh.textures.iter() {
            for level in &texture.levels {
                materials.bytes(&[level.width, level.height].map(u32::to_le_bytes).concat());
                level.texels.iter().for_each(|t| materials.bytes(&t.to_le_bytes()));
            }
        }
        let mut sun = Fnv::new();
        sun.text(&format!("{:?}", scene.sun));
        let mut sky = Fnv::new();
        if let Some(map) = &scene.sky {
            sky.floats([map.strength, map.rotation_deg]);
            let level = &map.levels[0];
            sky.bytes(&[level.width, level.height].map(u32::to_le_bytes).concat());
            sky.floats(level.texels.iter().flat_map(|t| t.to_array()));
        }
        let mut settings: BTreeMap<String, String> =
            CACHE_PARAMS.iter().map(|&p| (p.flag().to_owned(), params.values.show(p))).collect();
        let Vec3 { x, y, z } = params.estimator.background;
        settings.insert("--background".into(), format!("{x},{y},{z}"));
        settings.insert("light".into(), params.estimator.indirect.to_string());
        Self { geometry: geometry.hex(), materials: materials.hex(), sun: sun.hex(), sky: sky.hex(), settings }
    }

    /// What differs from `now`, said for a user: the scene's parts, then each setting with both values.
    pub fn differences(&self, now: &Fingerprint) -> Vec<String> {
        let mut out = Vec::new();
        for (part, a, b) in [
            ("the geometry", &self.geometry, &now.geometry),
            ("the materials or their textures", &self.materials, &now.materials),
            ("the sun", &self.sun, &now.sun),
            ("the sky map", &self.sky, &now.sky),
        ] {
            if a != b {
                out.push(part.to_owned());
            }
        }
        let keys: std::collections::BTreeSet<&String> = self.settings.keys().chain(now.settings.keys()).collect();
        for key in keys {
            let (a, b) = (self.settings.get(key), now.settings.get(key));
            if a != b {
                let show = |v: Option<&String>| v.map_or("unset".to_owned(), |v| v.clone());
                out.push(format!("{key} (the cache's: {}, this render's: {})", show(a), show(b)));
            }
        }
        out
    }
}

/// A solved radiance cache as written and read.
#[derive(Clone, Debug, PartialEq)]
pub struct CacheFile {
    pub fingerprint: Fingerprint,
    /// How solving went (the renderer's statistics of the cache, as JSON).
    pub stats: serde_json::Value,
    /// The values buffer as the sensor maps read it: one per entry, then each surface side's fallback.
    pub values: Vec<Vec4>,
}

#[derive(Serialize, Deserialize)]
struct Header {
    fingerprint: Fingerprint,
    stats: serde_json::Value,
    values: u64,
}

impl CacheFile {
    pub fn to_bytes(&self) -> Vec<u8> {
        let header = Header {
            fingerprint: self.fingerprint.clone(),
            stats: self.stats.clone(),
            values: self.values.len() as u64,
        };
        let header = serde_json::to_vec(&header).expect("a header serialises");
        let mut out = Vec::with_capacity(MAGIC.len() + 16 + header.len() + 16 * self.values.len() + 4);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&FORMAT.to_le_bytes());
        out.extend_from_slice(&(header.len() as u64).to_le_bytes());
        out.extend_from_slice(&header);
        for v in &self.values {
            v.to_array().iter().for_each(|f| out.extend_from_slice(&f.to_le_bytes()));
        }
        let crc = crc32fast::hash(&out);
        out.extend_from_slice(&crc.to_le_bytes());
        out
    }

    /// Reads a file's bytes; the error says what is wrong with it (the caller names the file).
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, String> {
        if !bytes.starts_with(MAGIC) {
            return Err("is not a sensorlight radiance cache (write one with `sensorlight cache`)".into());
        }
        let truncated = || "is truncated or damaged (its checksum does not match): write it again".to_owned();
        let rest = &bytes[MAGIC.len()..];
        let format = u32::from_le_bytes(rest.get(..4).ok_or_else(truncated)?.try_into().unwrap());
        if format > FORMAT {
            return Err(format!(
                "was written by a newer sensorlight (cache format {format}; this one reads up to {FORMAT})"
            ));
        }
        if bytes.len() < MAGIC.len() + 16 {
            return Err(truncated());
        }
        let (body, crc) = bytes.split_at(bytes.len() - 4);
        if crc32fast::hash(body) != u32::from_le_bytes(crc.try_into().unwrap()) {
            return Err(truncated());
        }
        let length = u64::from_le_bytes(rest[4..12].try_into().unwrap()) as usize;
        let header_end = (MAGIC.len() + 12).checked_add(length).filter(|&e| e <= body.len()).ok_or_else(truncated)?;
        let header: Header = serde_json::from_slice(&body[MAGIC.len() + 12..header_end])
            .map_err(|e| format!("has a header that cannot be read ({e})"))?;
        let data = &body[header_end..];
        if data.len() as u64 != header.values * 16 {
            return Err(truncated());
        }
        let values = data
            .chunks_exact(16)
            .map(|c| {
                Vec4::from_array(std::array::from_fn(|i| f32::from_le_bytes(c[4 * i..4 * i + 4].try_into().unwrap())))
            })
            .collect();
        Ok(Self { fingerprint: header.fingerprint, stats: header.stats, values })
    }
}

/// FNV-1a, 64 bits: a hash that is the same on every run and machine (std's is not promised to be).
pub struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Self::new()
    }
}

impl Fnv {
    pub fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }

    pub fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0100_0000_01b3);
        }
    }

    pub fn floats(&mut self, floats: impl IntoIterator<Item = f32>) {
        floats.into_iter().for_each(|f| self.bytes(&f.to_bits().to_le_bytes()));
    }

    pub fn text(&mut self, text: &str) {
        self.bytes(text.as_bytes());
    }

    pub fn hex(&self) -> String {
        format!("{:016x}", self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Overrides;
    use crate::scene::{ImageSize, builtin};

    fn file() -> CacheFile {
        let scene = builtin::lightbox(ImageSize { width: 8, height: 8 });
        let params = RenderParams::resolve(None, &Overrides::default()).unwrap();
        let values = vec![Vec4::new(0.25, 0.5, 1.0, 0.0), Vec4::splat(f32::MIN_POSITIVE)];
        CacheFile { fingerprint: Fingerprint::of(&scene, &params), stats: serde_json::json!({"bounces": 3}), values }
    }

    #[test]
    fn a_file_reads_back_as_written() {
        let f = file();
        assert_eq!(CacheFile::from_bytes(&f.to_bytes()).unwrap(), f);
    }

    /// Truncated anywhere, one bit flipped anywhere, another file, a newer format: each refused as such.
    #[test]
    fn damaged_foreign_and_newer_files_are_refused() {
        let bytes = file().to_bytes();
        for cut in [0, 5, MAGIC.len() + 3, bytes.len() / 2, bytes.len() - 1] {
            let e = CacheFile::from_bytes(&bytes[..cut]).unwrap_err();
            assert!(e.contains("truncated") || e.contains("not a sensorlight radiance cache"), "{cut}: {e}");
        }
        for at in [MAGIC.len() + 8, MAGIC.len() + 20, bytes.len() - 10] {
            let mut flipped = bytes.clone();
            flipped[at] ^= 0x10;
            assert!(CacheFile::from_bytes(&flipped).unwrap_err().contains("truncated or damaged"), "{at}");
        }
        let mut newer = bytes.clone();
        newer[MAGIC.len()..MAGIC.len() + 4].copy_from_slice(&(FORMAT + 1).to_le_bytes());
        assert!(CacheFile::from_bytes(&newer).unwrap_err().contains("newer sensorlight"));
        assert!(CacheFile::from_bytes(b"P6 an image").unwrap_err().contains("not a sensorlight radiance cache"));
    }

    /// Another scene, material, sun or setting is named; the camera's own settings are not part of it.
    #[test]
    fn a_fingerprint_names_what_differs() {
        let scene = builtin::lightbox(ImageSize { width: 8, height: 8 });
        let params = |o: Overrides| RenderParams::resolve(None, &o).unwrap();
        let base = Fingerprint::of(&scene, &params(Overrides::default()));
        let camera_only = Overrides { tile: Some(4), dradiance: Some(0.5), exposure: Some(2.0), ..Default::default() };
        assert!(base.differences(&Fingerprint::of(&scene, &params(camera_only))).is_empty());
        let finer = Overrides { cache_resolution: Some(32), ..Default::default() };
        let d = base.differences(&Fingerprint::of(&scene, &params(finer)));
        assert_eq!(d, ["--cache-resolution (the cache's: 16, this render's: 32)"]);
        let mut other = scene.clone();
        other.mesh.materials[0].kd *= 0.5;
        other.mesh.triangles[0].v[0].x += 1e-3;
        let d = base.differences(&Fingerprint::of(&other, &params(Overrides::default())));
        assert_eq!(d, ["the geometry", "the materials or their textures"]);
    }
}
