//! R at points that are not an image's pixels: a lightmap's texels (`lightmap`, `sensorlight bake`). Each
//! point is sensed by its own sensor, as a render senses the pixels it does not interpolate, after the
//! radiance cache is solved for the frame: the light a point's sensor reduces is what a pixel at that point
//! would show (paper §III-E, §III-F), so a baked surface and a rendered one agree wherever both sensed.

use anyhow::Result;
use glam::Vec4;

use super::batch::{Sensed, SensedMaps};
use super::{GiStats, Phase, Progress, Renderer};
use crate::gbuffer::GBufferData;
use crate::params::FrameParams;
use crate::scene::NO_SURFACE;

impl Renderer {
    /// R at every point of `g` that shows a surface (zero elsewhere), with the radiance cache solved for
    /// `frame` first (or kept, see [`Renderer::keep_cache`]). `g` is a G-buffer of arbitrary points: its
    /// normals must face the side to sense (w = 1 for a front). Progress counts points; `progress` may stop
    /// it between batches.
    pub fn sense_points(
        &mut self,
        g: &GBufferData,
        frame: &FrameParams,
        progress: &dyn Progress,
    ) -> Result<(Vec<Vec4>, Option<GiStats>)> {
        let gi = self.cache_for(frame, progress)?;
        progress.phase(Phase::Sensing);
        self.runner.bind(&SensedMaps::new(&self.device, g.size)?)?;
        let pixels: Vec<u32> = (0..g.surface.len() as u32).filter(|&i| g.surface[i as usize] != NO_SURFACE).collect();
        progress.queued(pixels.len() as u64);
        let mut r = vec![Vec4::ZERO; g.surface.len()];
        let mut deliver = |b: &Sensed<'_>| {
            b.pixels.iter().zip(b.results).for_each(|(&i, f)| r[i as usize] = f.r);
            progress.done(b.pixels.len() as u64);
        };
        let ck = self.ck(frame);
        self.runner.sense_or_stop(g, &pixels, ck, &mut deliver, &|| progress.cancelled())?;
        self.runner.drain(&mut deliver)?;
        Ok((r, gi))
    }
}
