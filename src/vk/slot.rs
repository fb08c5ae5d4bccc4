//! A command slot: one command buffer with its own pool and fence, for work that is submitted without
//! waiting ("in flight"), so that the host can prepare the next batch while the device runs this one.
//!
//! Whatever such work uses must outlive it. A slot therefore keeps a deferred-release list (kajiya's model,
//! here per fence): objects handed to [`CommandSlot::retire`] are dropped only once the slot's submission
//! has completed, the next time the slot is waited on or reused.
//!
//! ```text
//!   record ─► submit ─► (device runs it; host records other slots) ─► wait ─► drop retired ─► record …
//! ```

use std::any::Any;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context as _, Result};
use ash::vk;

use super::device::Device;
use super::encoder::Encoder;

pub struct CommandSlot {
    device: Arc<Device>,
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    /// Submitted and not yet waited on.
    pending: bool,
    retired: Vec<Box<dyn Any>>,
}

impl CommandSlot {
    pub fn new(device: &Arc<Device>) -> Result<Self> {
        let raw = &device.raw;
        let info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(device.queue_family)
            .flags(vk::CommandPoolCreateFlags::TRANSIENT);
        // SAFETY: plain object creation; on failure what was created is destroyed.
        unsafe {
            let pool = raw.create_command_pool(&info, None)?;
            let alloc = vk::CommandBufferAllocateInfo::default()
                .command_pool(pool)
                .level(vk::CommandBufferLevel::PRIMARY)
                .command_buffer_count(1);
            let cmd = match raw.allocate_command_buffers(&alloc) {
                Ok(c) => c[0],
                Err(e) => {
                    raw.destroy_command_pool(pool, None);
                    return Err(e.into());
                }
            };
            let fence = match raw.create_fence(&vk::FenceCreateInfo::default(), None) {
                Ok(f) => f,
                Err(e) => {
                    raw.destroy_command_pool(pool, None);
                    return Err(e.into());
                }
            };
            Ok(Self { device: device.clone(), pool, cmd, fence, pending: false, retired: Vec::new() })
        }
    }

    /// Whether work was submitted that has not been waited on.
    pub fn is_pending(&self) -> bool {
        self.pending
    }

    /// Waits for the slot's submission, if any, and drops what was retired with it. Returns the time spent
    /// waiting.
    pub fn wait(&mut self) -> Result<Duration> {
        let start = Instant::now();
        if self.pending {
            // SAFETY: the fence belongs to this slot and was submitted with its command buffer.
            unsafe {
                self.device.raw.wait_for_fences(&[self.fence], true, u64::MAX).context("vkWaitForFences")?;
                self.device.raw.reset_fences(&[self.fence])?;
            }
            self.pending = false;
        }
        self.retired.clear();
        Ok(start.elapsed())
    }

    /// Waits for the previous submission, then records a new one with `record`. On a recording error the
    /// slot stays idle and the command buffer is reset at the next recording.
    pub fn record(&mut self, record: impl FnOnce(&Encoder<'_>) -> Result<()>) -> Result<()> {
        self.wait()?;
        // SAFETY: the slot is idle (waited above), so its pool's buffers are not in use.
        unsafe {
            self.device.raw.reset_command_pool(self.pool, vk::CommandPoolResetFlags::empty())?;
            let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            self.device.raw.begin_command_buffer(self.cmd, &begin)?;
        }
        let recorded = record(&Encoder::new(&self.device, self.cmd));
        // SAFETY: begun above; ended even when recording failed.
        unsafe { self.device.raw.end_command_buffer(self.cmd)? };
        recorded
    }

    /// Submits what [`CommandSlot::record`] recorded, without waiting.
    pub fn submit(&mut self) -> Result<()> {
        self.device.submit(self.cmd, self.fence)?;
        self.pending = true;
        Ok(())
    }

    /// Like [`CommandSlot::submit`], waiting for `wait` before its `stage` and signalling `signal` when done.
    pub fn submit_between(
        &mut self,
        wait: (vk::Semaphore, vk::PipelineStageFlags),
        signal: vk::Semaphore,
    ) -> Result<()> {
        self.device.submit_between(self.cmd, self.fence, Some(wait), &[signal])?;
        self.pending = true;
        Ok(())
    }

    /// Keeps `object` alive until this slot's current (or, if idle, next) submission completes.
    pub fn retire(&mut self, object: impl Any) {
        self.retired.push(Box::new(object));
    }
}

impl Drop for CommandSlot {
    fn drop(&mut self) {
        // An error here means the device is lost; nothing is in flight any more then.
        let _ = self.wait();
        // SAFETY: idle (waited above); the command buffer is freed with its pool.
        unsafe {
            self.device.raw.destroy_fence(self.fence, None);
            self.device.raw.destroy_command_pool(self.pool, None);
        }
    }
}
