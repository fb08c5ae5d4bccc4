//! Sensors sensed again at a finer rd where a slit made their maps unreliable (docs/DESIGN.md §3 step 5).
//!
//! A bright surface seen through a gap narrower than a texel (the lit room through the door ajar's 1 cm
//! clearances and its wedge) falls on whole texels or on none, as their centres fall: at rd 32 one floor
//! pixel of the dark room took twice the light a ray gather over the same cache finds, its neighbour half.
//! The reduction measures the share of each sensor's main-layer light that such one-texel-wide bright
//! features hold (`glsl/reduce.comp`, in `GpuSensorResult::rest.w`). Where it is at least [`THIN_SHARE`],
//! that sensor and every sensed pixel within [`THIN_REACH`] of it (the slit fell between their texels: as
//! wrong the other way, and nothing in their maps says so) are sensed again by a runner at [`FINE_FACTOR`]
//! times the rd, before the refinement reads them.

use crate::scene::ImageSize;

/// A sensor is sensed again where thin bright texels hold at least this share of its main layers' light.
/// On the door ajar at rd 32 the floor pixels that see the lit room through the gaps hold 10–40 %. At 5 %
/// the small light (160 × 120) had 696 of its 4 440 sensors sensed again, 1.25× its time, at 10 % 27 of
/// them, and the door ajar's error is the same (4.77 % inside the edges).
pub const THIN_SHARE: f32 = 0.1;

/// Sensed pixels within this many pixels (a square) of one whose share is [`THIN_SHARE`] are sensed again
/// too. On the door ajar 1 and 5 give the same error (5.14 %), 3 as well (5.12 %), for 1 720, 2 518 and
/// 2 201 sensors sensed again; on `tests/slits.rs` 1 gives 8.4 % per pixel, 3 8.8 %.
pub const THIN_REACH: i32 = 1;

/// The finer sensors' rd over the render's.
pub const FINE_FACTOR: u32 = 2;

/// The finer runner is built only up to this rd of the render's. At rd 64 the door ajar's slits alias half
/// as much, and sensing 2 152 of its 2 935 sensors again at rd 128 took 2.1× the render's time for
/// 4.42 % → 4.18 % against the path tracer.
pub const FINE_MAX_RD: u32 = 32;

/// Which sensed pixels are to be sensed again at the finer rd, as the rounds deliver them.
pub(super) struct Slits {
    width: i32,
    height: i32,
    /// Per pixel: the share its last sensor measured, −1 where none was sensed.
    share: Vec<f32>,
    /// Within [`THIN_REACH`] of a pixel whose share is [`THIN_SHARE`].
    near: Vec<bool>,
    /// Sensed at the finer rd already.
    fine: Vec<bool>,
}

impl Slits {
    pub(super) fn new(size: ImageSize) -> Self {
        let n = size.width as usize * size.height as usize;
        Self {
            width: size.width as i32,
            height: size.height as i32,
            share: vec![-1.0; n],
            near: vec![false; n],
            fine: vec![false; n],
        }
    }

    /// What the sensor at `pixel` measured.
    pub(super) fn record(&mut self, pixel: u32, share: f32) {
        self.share[pixel as usize] = share;
        if share >= THIN_SHARE {
            let (x, y) = (pixel as i32 % self.width, pixel as i32 / self.width);
            for v in (y - THIN_REACH).max(0)..=(y + THIN_REACH).min(self.height - 1) {
                for u in (x - THIN_REACH).max(0)..=(x + THIN_REACH).min(self.width - 1) {
                    self.near[(v * self.width + u) as usize] = true;
                }
            }
        }
    }

    /// The sensed pixels near a slit not yet sensed at the finer rd, marked as sensed so.
    pub(super) fn take(&mut self) -> Vec<u32> {
        let again: Vec<u32> = (0..self.share.len())
            .filter(|&i| self.share[i] >= 0.0 && self.near[i] && !self.fine[i])
            .map(|i| i as u32)
            .collect();
        again.iter().for_each(|&i| self.fine[i as usize] = true);
        again
    }

    /// How many pixels were sensed at the finer rd.
    pub(super) fn count(&self) -> u64 {
        self.fine.iter().filter(|&&f| f).count() as u64
    }
}

/// The runner of the finer sensors, where the render's rd allows one.
pub(super) fn fine_rd(rd: u32) -> Option<u32> {
    (rd <= FINE_MAX_RD).then_some(rd * FINE_FACTOR)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_slit_takes_its_sensed_neighbours_within_reach_once() {
        let (width, height) = (16, 8);
        let mut s = Slits::new(ImageSize { width, height });
        // Sensed every other pixel; the one at (8, 4) saw a slit.
        for y in 0..height {
            for x in (0..width).step_by(2) {
                s.record(y * width + x, if (x, y) == (8, 4) { 0.2 } else { 0.0 });
            }
        }
        let near = |x: u32, y: u32| x.abs_diff(8) as i32 <= THIN_REACH && y.abs_diff(4) as i32 <= THIN_REACH;
        let expected: Vec<u32> = (0..height)
            .flat_map(|y| (0..width).step_by(2).filter(move |&x| near(x, y)).map(move |x| y * width + x))
            .collect();
        assert!(expected.len() > 1, "the slit's pixel and some of its neighbours");
        assert_eq!(s.take(), expected);
        assert!(s.take().is_empty(), "each pixel is sensed finer once");
        // A pixel sensed later within reach is taken then; one out of reach is not.
        let (inside, outside) = (4 * width + 8 + THIN_REACH as u32, 4 * width + 8 + THIN_REACH as u32 + 1);
        s.record(outside, 0.0);
        s.record(inside, 0.0);
        assert_eq!(s.take(), vec![inside]);
        assert_eq!(s.count(), expected.len() as u64 + 1);
    }
}
