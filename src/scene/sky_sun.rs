//! A sun painted into a sky map, taken out of it and drawn as a [`Sun`] disc.
//!
//! A clear-sky HDRI holds the sun as a few texels 10⁴–10⁵ times brighter than the sky. The sensors read the
//! map on the level whose texels are as large as theirs (several degrees at rd 32), where the sun is one
//! bright texel that a sensor texel's direction meets or misses: neighbouring sensors disagree by the sun's
//! whole light. On a courtyard under such a map the defaults were 34 % off the oracle, in a moiré of light
//! and shadow. The sun's light needs the exact estimator's closed form and zoom view, as a [`Sun`] has.
//!
//! What is taken out: the connected texels (8-neighbours, wrapping in u) around the brightest one whose
//! luminance exceeds [`SUN_CONTRAST`] times the map's mean over the sphere, if they subtend no more than
//! a disc of [`Sun::MAX_DIAMETER_DEG`]. They become a sun whose irradiance is their light above the sky
//! around them (`Σ (L − L_ring)·Ω` per channel, Ω each texel's solid angle), along their luminance-weighted
//! mean direction, as wide as a disc of their solid angle; in the map they take the mean of the texels
//! around them (`L_ring`), so nothing is counted twice.

use std::f32::consts::PI;

use anyhow::Result;
use glam::Vec3;

use super::Sun;
use super::sky::{SkyLevel, SkyMap, uv_to_direction};

/// A texel brighter than this many times the map's mean radiance over the sphere belongs to a sun. A clear
/// sky's sun is 10⁴ times its sky; sunlit clouds a few times.
pub const SUN_CONTRAST: f32 = 50.0;

/// Rec. 709 luminance.
fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

impl SkyMap {
    /// The map with its sun taken out (module docs; [`SkyMap::taken_sun`] says which), or the map unchanged
    /// where it holds none.
    pub fn without_sun(self) -> Result<SkyMap> {
        let Some((sun, cleaned)) = self.painted_sun()? else { return Ok(self) };
        let mut map = SkyMap::new(&self.name, cleaned, 1.0)?.turned(self.rotation_deg)?;
        map.strength = self.strength;
        map.taken_sun = Some(sun);
        Ok(map)
    }

    /// The sun painted into the map and level 0 without it (module docs), if it holds one.
    pub fn painted_sun(&self) -> Result<Option<(Sun, SkyLevel)>> {
        let level = &self.levels[0];
        let (w, h) = (level.width as usize, level.height as usize);
        // Each row's texel solid angle: 2π/w of longitude times the band's (cos θ0 − cos θ1).
        let omega: Vec<f32> = (0..h)
            .map(|j| {
                let (t0, t1) = (PI * j as f32 / h as f32, PI * (j + 1) as f32 / h as f32);
                2.0 * PI / w as f32 * (t0.cos() - t1.cos())
            })
            .collect();
        let power: f32 = (0..w * h).map(|i| luminance(level.texels[i]) * omega[i / w]).sum();
        let threshold = SUN_CONTRAST * power / (4.0 * PI);
        let lum = |i: usize| luminance(level.texels[i]);
        let Some(brightest) = (0..w * h).max_by(|&a, &b| lum(a).total_cmp(&lum(b))) else {
            return Ok(None);
        };
        if !(threshold > 0.0 && lum(brightest) > threshold) {
            return Ok(None);
        }
        let neighbours = |i: usize| {
            let (x, y) = ((i % w) as i64, (i / w) as i64);
            (-1..=1i64).flat_map(move |dy| (-1..=1i64).map(move |dx| (dx, dy))).filter_map(move |(dx, dy)| {
                let ny = y + dy;
                ((dx, dy) != (0, 0) && (0..h as i64).contains(&ny))
                    .then(|| (ny as usize) * w + (x + dx).rem_euclid(w as i64) as usize)
            })
        };
        // The bright texels connected to the brightest.
        let mut inside = vec![false; w * h];
        let (mut sun, mut stack) = (Vec::new(), vec![brightest]);
        inside[brightest] = true;
        while let Some(i) = stack.pop() {
            sun.push(i);
            for n in neighbours(i) {
                if !inside[n] && lum(n) > threshold {
                    inside[n] = true;
                    stack.push(n);
                }
            }
        }
        let solid_angle: f32 = sun.iter().map(|&i| omega[i / w]).sum();
        let diameter_deg = 2.0 * (1.0 - solid_angle / (2.0 * PI)).clamp(-1.0, 1.0).acos().to_degrees();
        if diameter_deg > Sun::MAX_DIAMETER_DEG {
            return Ok(None); // a bright region, not a sun: it stays in the map
        }
        // The sky around it: the mean of the texels that touch it.
        let mut ring: Vec<usize> = sun.iter().flat_map(|&i| neighbours(i)).filter(|&n| !inside[n]).collect();
        ring.sort_unstable();
        ring.dedup();
        let around = match ring.len() {
            0 => Vec3::ZERO,
            n => ring.iter().map(|&i| level.texels[i]).sum::<Vec3>() / n as f32,
        };
        let mut irradiance = Vec3::ZERO;
        let mut towards = Vec3::ZERO;
        for &i in &sun {
            let (x, y) = (i % w, i / w);
            let uv = glam::Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
            let above = (level.texels[i] - around).max(Vec3::ZERO);
            irradiance += above * omega[y];
            towards += uv_to_direction(uv) * luminance(above) * omega[y];
        }
        let mut texels = level.texels.clone();
        sun.iter().for_each(|&i| texels[i] = around);
        let cleaned = SkyLevel { width: level.width, height: level.height, texels };
        // A texel of a huge map is still a disc the zoom views can frame.
        let diameter = diameter_deg.max(0.01);
        Ok(Some((Sun::new(self.to_world(towards), diameter, irradiance)?, cleaned)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::sky::direction_to_uv;

    /// A dim sky of 0.3 above the horizon with a sun of irradiance `e` in one texel along `d`.
    fn sky_with_sun(d: Vec3, e: f32, (w, h): (u32, u32)) -> SkyLevel {
        let mut texels: Vec<Vec3> =
            (0..w * h).map(|i| if (i / w) < h / 2 { Vec3::splat(0.3) } else { Vec3::ZERO }).collect();
        let uv = direction_to_uv(d);
        let (x, y) = ((uv.x * w as f32) as u32, (uv.y * h as f32) as u32);
        let (t0, t1) = (PI * y as f32 / h as f32, PI * (y + 1) as f32 / h as f32);
        let omega = 2.0 * PI / w as f32 * (t0.cos() - t1.cos());
        texels[(y * w + x) as usize] = Vec3::new(0.3 + e / omega, 0.3 + 0.9 * e / omega, 0.3 + 0.8 * e / omega);
        SkyLevel { width: w, height: h, texels }
    }

    /// The sun's light above the sky becomes the disc's irradiance, along its texel's direction (turned with
    /// the map), as wide as the texel; the map keeps the sky, and its total light drops by the sun's.
    #[test]
    fn a_painted_sun_becomes_a_disc_of_its_light() {
        let d = Vec3::new(0.5, 1.0, 0.3).normalize();
        let map = SkyMap::new("sky", sky_with_sun(d, 3.0, (512, 256)), 1.0).unwrap().turned(90.0).unwrap();
        let cleaned = map.without_sun().unwrap();
        let sun = cleaned.taken_sun.expect("a sun 10⁴ times the sky is found");
        assert!((sun.irradiance - Vec3::new(3.0, 2.7, 2.4)).abs().max_element() < 1e-3 * 3.0, "{}", sun.irradiance);
        // The texel's centre is within half a texel (0.35°) of `d`, turned 90° about +y as the map is.
        let turned = Vec3::new(d.z, d.y, -d.x);
        assert!(sun.direction.angle_between(turned).to_degrees() < 0.5, "{} vs {turned}", sun.direction);
        assert!((0.5..0.9).contains(&sun.angular_diameter_deg), "{}°", sun.angular_diameter_deg);
        assert!(cleaned.levels[0].texels.iter().all(|t| t.max_element() <= 0.3 + 1e-6), "the sky alone is left");
        assert_eq!((cleaned.rotation_deg, cleaned.strength), (90.0, 1.0));
    }

    /// A map without a sun, and one whose bright region is wider than a sun, keep their light.
    #[test]
    fn skies_without_a_sun_are_left_alone() {
        let plain = SkyLevel {
            width: 64,
            height: 32,
            texels: (0..64 * 32).map(|i| Vec3::splat(1.0 + (i % 7) as f32)).collect(),
        };
        assert!(SkyMap::new("plain", plain, 1.0).unwrap().without_sun().unwrap().taken_sun.is_none());
        // 12 × 12 texels of 1.4° by the horizon, 10⁴ times brighter: past the threshold, but 19° wide.
        let wide = SkyLevel {
            width: 256,
            height: 128,
            texels: (0..256 * 128)
                .map(|i| if i % 256 < 12 && (52..64).contains(&(i / 256)) { Vec3::splat(1e4) } else { Vec3::ONE })
                .collect(),
        };
        let map = SkyMap::new("wide", wide.clone(), 1.0).unwrap().without_sun().unwrap();
        assert!(map.taken_sun.is_none());
        assert_eq!(map.levels[0], wide);
    }
}
