//! Timestamp queries: GPU time measured by the GPU, so that what a batch cost the device can be told apart
//! from what the host spent recording and waiting (kajiya's profiler does the same per pass).

use std::sync::Arc;

use anyhow::Result;
use ash::vk;

use super::device::Device;

/// Timestamp `i` lives at query `i · stride`. A timestamp written inside a multiview pass fills one query
/// per view, and Mesa 25's lavapipe keeps doing so after the pass has ended (it reads its last view mask;
/// without the gaps the pool overflows and the driver crashes), so each timestamp gets room for as many
/// views as the device allows.
pub struct TimestampQueries {
    device: Arc<Device>,
    pub raw: vk::QueryPool,
    /// Timestamps (not queries).
    pub count: u32,
    /// Queries per timestamp.
    pub stride: u32,
    /// Nanoseconds per tick.
    period_ns: f64,
    /// Bits of a timestamp that carry time (the rest is undefined).
    valid_mask: u64,
}

impl TimestampQueries {
    /// A pool of `count` timestamps, or `None` where the device's queue cannot write timestamps.
    pub fn new(device: &Arc<Device>, count: u32) -> Result<Option<Self>> {
        let bits = device.adapter.timestamp_valid_bits;
        if bits == 0 || device.adapter.limits.timestamp_period <= 0.0 {
            return Ok(None);
        }
        let stride =
            if device.adapter.features.multiview { device.adapter.limits.max_multiview_view_count.max(1) } else { 1 };
        let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(count * stride);
        // SAFETY: valid device and create info.
        let raw = unsafe { device.raw.create_query_pool(&info, None) }?;
        let valid_mask = if bits >= 64 { u64::MAX } else { (1u64 << bits) - 1 };
        Ok(Some(Self {
            device: device.clone(),
            raw,
            count,
            stride,
            period_ns: device.adapter.limits.timestamp_period as f64,
            valid_mask,
        }))
    }

    /// The `count` timestamps in seconds (on the device's clock), once the submission that wrote all of
    /// them has completed. `None` if any was not written.
    pub fn read_seconds(&self) -> Result<Option<Vec<f64>>> {
        // Value and availability word per query.
        let mut data = vec![[0u64; 2]; (self.count * self.stride) as usize];
        let flags = vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WITH_AVAILABILITY;
        // SAFETY: the pool holds `count` queries; the caller waited for the submission that wrote them.
        let result = unsafe { self.device.raw.get_query_pool_results(self.raw, 0, &mut data, flags) };
        match result {
            Ok(()) | Err(vk::Result::NOT_READY) => {}
            Err(e) => return Err(e.into()),
        }
        let stamps = data.iter().step_by(self.stride as usize);
        if stamps.clone().any(|[_, available]| *available == 0) {
            return Ok(None);
        }
        Ok(Some(stamps.map(|[ticks, _]| (ticks & self.valid_mask) as f64 * self.period_ns * 1e-9).collect()))
    }
}

impl Drop for TimestampQueries {
    fn drop(&mut self) {
        // SAFETY: the owner (a command slot) waits for its submission before dropping the pool.
        unsafe { self.device.raw.destroy_query_pool(self.raw, None) };
    }
}
