//! What the window shows: the image or one of its AOVs, as 8-bit sRGB bytes made exactly as the PNG that
//! `render` writes (`output::png::tone_map`), so that the viewer and a render of the same camera show the
//! same pixels.

use ash::vk;
use glam::Vec4;

use crate::gpu_types::radiance_state;
use crate::output::png::tone_map;
use crate::renderer::RenderOutput;
use crate::scene::NO_SURFACE;

/// What the window shows of a render (keys 1 to 5). The AOVs are a finished render's; while one is in
/// progress the window shows its image so far.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Show {
    /// `Le + albedo·R`, tone-mapped at the exposure.
    Image,
    /// R, the light arriving at each pixel, at the exposure.
    Radiance,
    /// White where a sensor sensed, grey where R was interpolated, black elsewhere.
    Sensors,
    /// Each surface id in a colour of its own.
    Surfaces,
    /// `Le` of what each pixel sees, at the exposure.
    Emission,
}

impl Show {
    pub const ALL: [Show; 5] = [Show::Image, Show::Radiance, Show::Sensors, Show::Surfaces, Show::Emission];

    pub fn word(self) -> &'static str {
        match self {
            Show::Image => "image",
            Show::Radiance => "radiance",
            Show::Sensors => "sensors",
            Show::Surfaces => "surfaces",
            Show::Emission => "emission",
        }
    }

    pub fn from_word(word: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.word() == word)
    }

    /// The number key that shows it: its place in [`Show::ALL`], from 1.
    pub fn key(self) -> char {
        let i = Self::ALL.iter().position(|&s| s == self).unwrap_or(0);
        char::from(b'1' + i as u8)
    }
}

/// RGB bytes of what `show` shows of the finished render `out`.
pub fn picture(show: Show, out: &RenderOutput, exposure: f32) -> Vec<u8> {
    match show {
        Show::Image => tone_map(&out.image, exposure),
        Show::Radiance => tone_map(&out.radiance, exposure),
        Show::Emission => tone_map(&out.gbuffer.emission, exposure),
        Show::Sensors => out
            .radiance
            .iter()
            .flat_map(|r| {
                let v = match r.w {
                    w if w == radiance_state::SENSED => 255,
                    w if w == radiance_state::INTERPOLATED => 128,
                    _ => 0,
                };
                [v; 3]
            })
            .collect(),
        Show::Surfaces => out.gbuffer.surface.iter().flat_map(|&id| surface_colour(id)).collect(),
    }
}

/// RGB bytes of an image so far (a snapshot's).
pub fn preview(image: &[Vec4], exposure: f32) -> Vec<u8> {
    tone_map(image, exposure)
}

/// A colour per surface id, neighbours far apart (a multiplicative hash); black for no surface.
fn surface_colour(id: u32) -> [u8; 3] {
    if id == NO_SURFACE {
        return [0; 3];
    }
    let h = id.wrapping_mul(0x9e37_79b1);
    [(h >> 24) as u8 | 0x30, (h >> 16) as u8 | 0x30, (h >> 8) as u8 | 0x30]
}

/// `rgb` as texels of `format` (one of `vk::swapchain::FORMATS`), alpha opaque.
pub fn texels(rgb: &[u8], format: vk::Format) -> Vec<u8> {
    let bgra = format == vk::Format::B8G8R8A8_UNORM;
    rgb.chunks_exact(3).flat_map(|p| if bgra { [p[2], p[1], p[0], 255] } else { [p[0], p[1], p[2], 255] }).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_and_keys_name_each_view_once() {
        for (i, show) in Show::ALL.into_iter().enumerate() {
            assert_eq!(Show::from_word(show.word()), Some(show));
            assert_eq!(show.key(), char::from(b'1' + i as u8));
        }
        assert_eq!(Show::from_word("depth"), None);
    }

    #[test]
    fn texels_keep_the_bytes_in_the_formats_order() {
        let rgb = [10, 20, 30, 40, 50, 60];
        assert_eq!(texels(&rgb, vk::Format::B8G8R8A8_UNORM), [30, 20, 10, 255, 60, 50, 40, 255]);
        assert_eq!(texels(&rgb, vk::Format::R8G8B8A8_UNORM), [10, 20, 30, 255, 40, 50, 60, 255]);
        assert_eq!(surface_colour(NO_SURFACE), [0; 3]);
        assert_ne!(surface_colour(1), surface_colour(2));
    }
}
