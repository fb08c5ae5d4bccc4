//! Submissions: one-off work recorded, submitted and waited for (uploads, read-backs, the G-buffer), and
//! the queue submission every command buffer goes through. Work kept in flight uses a
//! [`super::CommandSlot`] instead.

use std::time::{Duration, Instant};

use anyhow::{Context as _, Result};
use ash::vk;

use super::device::Device;
use super::encoder::Encoder;

impl Device {
    /// Records `record` into a command buffer, submits it and waits: for one-off work (uploads,
    /// read-backs). Returns the host time from submission to the fence.
    pub fn submit_and_wait(&self, record: impl FnOnce(&Encoder<'_>) -> Result<()>) -> Result<Duration> {
        let submitter = self.submitter.lock().unwrap();
        let cmd = submitter.cmd;
        // SAFETY: the command buffer is only used under the mutex and is idle (its fence was waited on).
        unsafe {
            self.raw.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty())?;
            let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            self.raw.begin_command_buffer(cmd, &begin)?;
        }
        let recorded = record(&Encoder::new(self, cmd));
        // SAFETY: as above; the buffer is ended even when recording failed so that it can be reset later.
        unsafe { self.raw.end_command_buffer(cmd)? };
        recorded?;
        let start = Instant::now();
        self.submit(cmd, submitter.fence)?;
        // SAFETY: the fence is owned by this submitter and was just submitted.
        unsafe {
            self.raw.wait_for_fences(&[submitter.fence], true, u64::MAX).context("vkWaitForFences")?;
            self.raw.reset_fences(&[submitter.fence])?;
        }
        Ok(start.elapsed())
    }

    /// Submits one recorded command buffer that signals `fence` (unsignalled) when done.
    pub(crate) fn submit(&self, cmd: vk::CommandBuffer, fence: vk::Fence) -> Result<()> {
        self.submit_between(cmd, fence, None, &[])
    }

    /// Like [`Device::submit`], starting its `stage` only once `wait.0` is signalled and signalling `signal`
    /// when done (a swapchain image acquired, then presented).
    pub(crate) fn submit_between(
        &self,
        cmd: vk::CommandBuffer,
        fence: vk::Fence,
        wait: Option<(vk::Semaphore, vk::PipelineStageFlags)>,
        signal: &[vk::Semaphore],
    ) -> Result<()> {
        let cmds = [cmd];
        let (waits, stages): (Vec<_>, Vec<_>) = wait.into_iter().unzip();
        let submit = [vk::SubmitInfo::default()
            .command_buffers(&cmds)
            .wait_semaphores(&waits)
            .wait_dst_stage_mask(&stages)
            .signal_semaphores(signal)];
        let queue = self.queue.lock().unwrap();
        // SAFETY: the queue is used under its mutex; the command buffer is recorded and the fence unsignalled.
        unsafe { self.raw.queue_submit(*queue, &submit, fence) }.context("vkQueueSubmit")
    }
}
