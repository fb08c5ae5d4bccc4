//! Pipeline barriers described by what the work on each side does, in the manner of vk-sync and kajiya: an
//! [`Access`] names a pipeline stage and the memory access made there; a barrier between two lists of
//! accesses waits for the stages of the first and makes its writes visible to the second. Callers never
//! spell out stage and access masks, so a barrier reads like the dependency it expresses.

use ash::vk;

use super::encoder::Encoder;
use super::image::Image;

/// One kind of use of a resource by the GPU or the host.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// No earlier use: nothing to wait for (e.g. contents about to be discarded).
    Nothing,
    /// Storage buffers or images read by a compute shader.
    ComputeRead,
    /// Storage buffers or images written (or read and written) by a compute shader.
    ComputeWrite,
    /// Storage buffers read by a vertex shader (sensor views, surfaces).
    VertexShaderRead,
    /// Colour attachments written by a render pass (cleared and drawn).
    ColorAttachmentWrite,
    /// Depth attachments tested and written by a render pass.
    DepthAttachment,
    /// Indirect draw or dispatch arguments.
    IndirectRead,
    /// Index buffers read by indexed draws.
    IndexRead,
    TransferRead,
    TransferWrite,
    HostRead,
    HostWrite,
    /// A swapchain image just acquired: the submission waits for its semaphore at the transfer stage, so a
    /// layout change must wait there too, not at the top of the pipe (before the image is ours).
    Acquired,
    /// A swapchain image handed to the presentation engine, which waits for the submission's semaphore.
    Present,
    /// Anything, by any stage: the coarse dependency around one-off copies and uploads.
    Any,
}

impl Access {
    fn stage(self) -> vk::PipelineStageFlags {
        use vk::PipelineStageFlags as S;
        match self {
            Self::Nothing => S::TOP_OF_PIPE,
            Self::ComputeRead | Self::ComputeWrite => S::COMPUTE_SHADER,
            Self::VertexShaderRead => S::VERTEX_SHADER,
            Self::ColorAttachmentWrite => S::COLOR_ATTACHMENT_OUTPUT,
            Self::DepthAttachment => S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
            Self::IndirectRead => S::DRAW_INDIRECT,
            Self::IndexRead => S::VERTEX_INPUT,
            Self::TransferRead | Self::TransferWrite | Self::Acquired => S::TRANSFER,
            Self::HostRead | Self::HostWrite => S::HOST,
            Self::Present => S::BOTTOM_OF_PIPE,
            Self::Any => S::ALL_COMMANDS,
        }
    }

    fn access(self) -> vk::AccessFlags {
        use vk::AccessFlags as A;
        match self {
            Self::Nothing | Self::Acquired | Self::Present => A::empty(),
            Self::ComputeRead | Self::VertexShaderRead => A::SHADER_READ,
            Self::ComputeWrite => A::SHADER_READ | A::SHADER_WRITE,
            Self::ColorAttachmentWrite => A::COLOR_ATTACHMENT_READ | A::COLOR_ATTACHMENT_WRITE,
            Self::DepthAttachment => A::DEPTH_STENCIL_ATTACHMENT_READ | A::DEPTH_STENCIL_ATTACHMENT_WRITE,
            Self::IndirectRead => A::INDIRECT_COMMAND_READ,
            Self::IndexRead => A::INDEX_READ,
            Self::TransferRead => A::TRANSFER_READ,
            Self::TransferWrite => A::TRANSFER_WRITE,
            Self::HostRead => A::HOST_READ,
            Self::HostWrite => A::HOST_WRITE,
            Self::Any => A::MEMORY_READ | A::MEMORY_WRITE,
        }
    }

    /// The writes of this access (reads need only an execution dependency, not a flush).
    fn writes(self) -> vk::AccessFlags {
        use vk::AccessFlags as A;
        self.access()
            & (A::SHADER_WRITE
                | A::COLOR_ATTACHMENT_WRITE
                | A::DEPTH_STENCIL_ATTACHMENT_WRITE
                | A::TRANSFER_WRITE
                | A::HOST_WRITE
                | A::MEMORY_WRITE)
    }
}

/// Stage and access masks of the two sides of a dependency.
fn masks(
    before: &[Access],
    after: &[Access],
) -> (vk::PipelineStageFlags, vk::AccessFlags, vk::PipelineStageFlags, vk::AccessFlags) {
    let src_stage = before.iter().fold(vk::PipelineStageFlags::empty(), |m, a| m | a.stage());
    let src_access = before.iter().fold(vk::AccessFlags::empty(), |m, a| m | a.writes());
    let dst_stage = after.iter().fold(vk::PipelineStageFlags::empty(), |m, a| m | a.stage());
    let dst_access = after.iter().fold(vk::AccessFlags::empty(), |m, a| m | a.access());
    let or_top = |s: vk::PipelineStageFlags| if s.is_empty() { vk::PipelineStageFlags::TOP_OF_PIPE } else { s };
    let or_bottom = |s: vk::PipelineStageFlags| if s.is_empty() { vk::PipelineStageFlags::BOTTOM_OF_PIPE } else { s };
    (or_top(src_stage), src_access, or_bottom(dst_stage), dst_access)
}

/// Makes every `before` access happen before every `after` access (a global memory barrier).
pub fn global(enc: &Encoder<'_>, before: &[Access], after: &[Access]) {
    let (src_stage, src_access, dst_stage, dst_access) = masks(before, after);
    let barrier = [vk::MemoryBarrier::default().src_access_mask(src_access).dst_access_mask(dst_access)];
    // SAFETY: recording into a command buffer in the recording state.
    unsafe {
        enc.device().raw.cmd_pipeline_barrier(
            enc.raw(),
            src_stage,
            dst_stage,
            vk::DependencyFlags::empty(),
            &barrier,
            &[],
            &[],
        )
    };
}

/// Like [`global`] for the layers `range` of `image`, changing their layout from `old` to `new`
/// (`UNDEFINED` discards the contents).
pub fn image(
    enc: &Encoder<'_>,
    image: &Image,
    range: vk::ImageSubresourceRange,
    before: (&[Access], vk::ImageLayout),
    after: (&[Access], vk::ImageLayout),
) {
    raw_image(enc, image.raw, range, before, after);
}

/// [`image`] for an image this program does not own (a swapchain's); its owner keeps it alive.
pub fn raw_image(
    enc: &Encoder<'_>,
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    (before, old): (&[Access], vk::ImageLayout),
    (after, new): (&[Access], vk::ImageLayout),
) {
    let (src_stage, src_access, dst_stage, dst_access) = masks(before, after);
    let barrier = [vk::ImageMemoryBarrier::default()
        .src_access_mask(src_access)
        .dst_access_mask(dst_access)
        .old_layout(old)
        .new_layout(new)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(range)];
    // SAFETY: recording into a command buffer in the recording state; the image outlives the submission
    // (its owner waits for the GPU before dropping it).
    unsafe {
        enc.device().raw.cmd_pipeline_barrier(
            enc.raw(),
            src_stage,
            dst_stage,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &barrier,
        )
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_wait_without_flushing_and_empty_sides_become_top_and_bottom() {
        let (src, src_access, dst, dst_access) = masks(&[Access::ComputeRead], &[Access::ColorAttachmentWrite]);
        assert_eq!(src, vk::PipelineStageFlags::COMPUTE_SHADER);
        assert!(src_access.is_empty(), "a read has nothing to make visible");
        assert_eq!(dst, vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT);
        assert!(dst_access.contains(vk::AccessFlags::COLOR_ATTACHMENT_WRITE));
        let (src, _, dst, _) = masks(&[], &[]);
        assert_eq!((src, dst), (vk::PipelineStageFlags::TOP_OF_PIPE, vk::PipelineStageFlags::BOTTOM_OF_PIPE));
        let (_, src_access, _, _) = masks(&[Access::ComputeWrite, Access::TransferWrite], &[Access::HostRead]);
        assert_eq!(src_access, vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE);
    }
}
