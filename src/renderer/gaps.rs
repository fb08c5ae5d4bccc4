//! A light seen through a gap (docs/DESIGN.md §3, step 5): a sensor's zoom view counts the share of a light
//! group it sees in texels, and through a gap a few texels wide (the door ajar's, a centimetre seen from a
//! metre or two) that count is tens of percent off: the wedge of light it throws on the wall was +67 % to
//! −5 % from pixel to pixel. So where a sensor saw a little of a group (or none of it, but its light hints
//! see some), shadow rays to every one of the supersampling's points on the group (`supersample::SHADOW_RAYS` ×
//! `SAMPLES`, 1 024) measure the share instead, and the pixel's R moves by the group's unoccluded light
//! times the difference. The door ajar's direct light at 160 × 120, against the path tracer through the
//! same pixel centres: 6.5 % per pixel, now 2.5 %. With the radiance cache's 256 points it was 11 %: at a
//! penumbra's dim end the gap shows a sliver of the light that 256 points hit two or three times.

use std::f32::consts::PI;

use glam::Vec3;

use crate::gpu_types::MAX_GROUPS;
use crate::light::groups::Lights;
use crate::scene::bvh::Bvh;
use crate::sensors::refine::Visibility;
use crate::supersample::ShadowPoints;

/// A sensor's share of a group is none below this: the reduction's sums round.
const NONE: f32 = 1e-3;

/// The shadow rays measure a group where the sensor saw less of it than this: a gap, or the dim end of a
/// penumbra, where the zoom view's texels that see the light are few. Wider penumbrae are resolved by the
/// zoom view (on the 40 000-triangle hall, the rays changed nothing that the oracle can tell, for 4 % of the
/// render's time when measuring every share under 1).
const FEW: f32 = 0.25;

/// What the shadow rays need: the scene's BVH, the points on the lights, the lights themselves (their
/// unoccluded light in closed form), each group's light hint bits, and the sensors' lift and near distance.
pub(super) struct Gaps<'a> {
    pub(super) bvh: &'a Bvh,
    pub(super) points: &'a ShadowPoints,
    pub(super) lights: &'a Lights,
    pub(super) bits: &'a [u64],
    pub(super) offsets: (f32, f32),
}

impl Gaps<'_> {
    /// A sensed pixel at `p` facing `n`, with its light `hint`: each group its sensor saw a little of (`v`
    /// between [`NONE`] and [`FEW`]), or none of where the hint sees some, measured again by shadow rays in
    /// `v`. Returns how much that moves the pixel's R.
    pub(super) fn measure(&self, (p, n): (Vec3, Vec3), hint: u64, v: &mut Visibility) -> Vec3 {
        let mut unoccluded = None;
        let mut change = Vec3::ZERO;
        for group in 0..self.lights.groups.len().min(MAX_GROUPS) {
            let sensed = v[group];
            let part = sensed > NONE && sensed < FEW;
            let missed = (0.0..=NONE).contains(&sensed) && hint & self.bits[group] != 0;
            if !(part || missed) {
                continue;
            }
            let Some(share) = self.points.share(self.bvh, (p, n), self.offsets, group) else { continue };
            let e = unoccluded.get_or_insert_with(|| self.lights.unoccluded(p + n * self.offsets.0, n));
            change += e[group] * (share - sensed) / PI;
            v[group] = share;
        }
        change
    }
}
