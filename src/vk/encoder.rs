//! Recording commands. An [`Encoder`] is a command buffer in the recording state together with the device
//! that records into it, so passes record through it without a `device` argument beside it; a
//! [`RenderPassScope`] is an open render pass that ends itself when dropped, so a pass cannot be left open
//! on an early return.

use ash::vk;

use super::buffer::Buffer;
use super::device::Device;
use super::pipeline::{Pipeline, PipelineLayout};
use super::query::TimestampQueries;
use super::render_pass::{Framebuffer, RenderPass};

pub struct Encoder<'a> {
    device: &'a Device,
    raw: vk::CommandBuffer,
}

impl<'a> Encoder<'a> {
    /// Wraps `raw`, which must be in the recording state and stay there while this encoder lives.
    pub(crate) fn new(device: &'a Device, raw: vk::CommandBuffer) -> Self {
        Self { device, raw }
    }

    pub fn device(&self) -> &'a Device {
        self.device
    }

    pub fn raw(&self) -> vk::CommandBuffer {
        self.raw
    }

    /// Binds `pipeline` at `bind_point` with `set` as set 0 of `layout`.
    pub fn bind(
        &self,
        bind_point: vk::PipelineBindPoint,
        pipeline: &Pipeline,
        layout: &PipelineLayout,
        set: vk::DescriptorSet,
    ) {
        // SAFETY: recording state; owners keep the pipeline, layout and set alive until the GPU is done.
        unsafe {
            self.device.raw.cmd_bind_pipeline(self.raw, bind_point, pipeline.raw);
            self.device.raw.cmd_bind_descriptor_sets(self.raw, bind_point, layout.raw, 0, &[set], &[]);
        }
    }

    /// Records `vkCmdPushConstants` with the bytes of `value` for the stages `layout` declared.
    pub fn push<T: bytemuck::Pod>(&self, layout: &PipelineLayout, value: &T) {
        // SAFETY: the layout's range holds at least `size_of::<T>()` bytes (its owner declared it for `T`).
        unsafe {
            self.device.raw.cmd_push_constants(self.raw, layout.raw, layout.push_stages, 0, bytemuck::bytes_of(value))
        };
    }

    pub fn dispatch(&self, groups: [u32; 3]) {
        // SAFETY: recording state, a compute pipeline bound by the caller.
        unsafe { self.device.raw.cmd_dispatch(self.raw, groups[0], groups[1], groups[2]) };
    }

    /// Dispatches the workgroup counts found at `offset` in `buffer` (a `VkDispatchIndirectCommand`).
    pub fn dispatch_indirect(&self, buffer: &Buffer, offset: u64) {
        // SAFETY: recording state, a compute pipeline bound by the caller; the buffer (indirect usage)
        // outlives the submission and holds 12 bytes at `offset`.
        unsafe { self.device.raw.cmd_dispatch_indirect(self.raw, buffer.raw, offset) };
    }

    /// Writes `words` at the start of `buffer` (inline in the command buffer: at most 64 KiB).
    pub fn update(&self, buffer: &Buffer, words: &[u32]) {
        assert!(words.len() * 4 <= 65536, "vkCmdUpdateBuffer writes at most 64 KiB");
        // SAFETY: recording state; the buffer (transfer destination) outlives the submission and holds the
        // words (its owner sized it for them).
        unsafe { self.device.raw.cmd_update_buffer(self.raw, buffer.raw, 0, bytemuck::cast_slice(words)) };
    }

    /// Fills a whole buffer with the 32-bit word `value`.
    pub fn fill(&self, buffer: &Buffer, value: u32) {
        // SAFETY: recording state; the buffer outlives the submission.
        unsafe { self.device.raw.cmd_fill_buffer(self.raw, buffer.raw, 0, vk::WHOLE_SIZE, value) };
    }

    /// Copies the first `bytes` of `src` to the start of `dst`.
    pub fn copy(&self, src: &Buffer, dst: &Buffer, bytes: u64) {
        let region = [vk::BufferCopy::default().size(bytes)];
        // SAFETY: recording state; both buffers outlive the submission and hold `bytes` (checked by callers).
        unsafe { self.device.raw.cmd_copy_buffer(self.raw, src.raw, dst.raw, &region) };
    }

    /// Resets `queries` (before any timestamp of this submission is written).
    pub fn reset_queries(&self, queries: &TimestampQueries) {
        // SAFETY: recording state, outside a render pass.
        unsafe { self.device.raw.cmd_reset_query_pool(self.raw, queries.raw, 0, queries.count * queries.stride) };
    }

    /// Writes timestamp `index` of `queries` once all earlier commands have finished `stage`.
    pub fn timestamp(&self, queries: &TimestampQueries, index: u32, stage: vk::PipelineStageFlags) {
        // SAFETY: recording state; the query was reset earlier in this command buffer.
        unsafe { self.device.raw.cmd_write_timestamp(self.raw, stage, queries.raw, index * queries.stride) };
    }

    /// Begins `pass` on `framebuffer`, clearing `clears` over `area` (the top-left corner of the
    /// framebuffer; `None`: all of it). The viewport covers the whole framebuffer, so clip space keeps
    /// mapping onto all of it, and the scissor is `area`.
    pub fn begin_render_pass(
        &self,
        pass: &RenderPass,
        framebuffer: &Framebuffer,
        clears: &[vk::ClearValue],
        area: Option<vk::Extent2D>,
    ) -> RenderPassScope<'_, 'a> {
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent: area.unwrap_or(framebuffer.extent) };
        let info = vk::RenderPassBeginInfo::default()
            .render_pass(pass.raw)
            .framebuffer(framebuffer.raw)
            .render_area(area)
            .clear_values(clears);
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: framebuffer.extent.width as f32,
            height: framebuffer.extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        // SAFETY: recording state, outside a render pass; the framebuffer was made for `pass`.
        unsafe {
            self.device.raw.cmd_begin_render_pass(self.raw, &info, vk::SubpassContents::INLINE);
            self.device.raw.cmd_set_viewport(self.raw, 0, &[viewport]);
            self.device.raw.cmd_set_scissor(self.raw, 0, &[area]);
        }
        RenderPassScope { encoder: self }
    }
}

/// An open render pass; drawing happens through it, and dropping it ends the pass.
pub struct RenderPassScope<'e, 'a> {
    encoder: &'e Encoder<'a>,
}

impl<'a> RenderPassScope<'_, 'a> {
    pub fn encoder(&self) -> &Encoder<'a> {
        self.encoder
    }

    /// Binds a graphics pipeline and its set 0.
    pub fn bind(&self, pipeline: &Pipeline, layout: &PipelineLayout, set: vk::DescriptorSet) {
        self.encoder.bind(vk::PipelineBindPoint::GRAPHICS, pipeline, layout, set);
    }

    /// Binds a graphics pipeline that reads no descriptors.
    pub fn bind_pipeline(&self, pipeline: &Pipeline) {
        // SAFETY: recording state; the owner keeps the pipeline alive until the GPU is done.
        unsafe {
            self.encoder.device.raw.cmd_bind_pipeline(self.encoder.raw, vk::PipelineBindPoint::GRAPHICS, pipeline.raw)
        };
    }

    pub fn push<T: bytemuck::Pod>(&self, layout: &PipelineLayout, value: &T) {
        self.encoder.push(layout, value);
    }

    /// Binds `buffer` as vertex buffer 0.
    pub fn bind_vertices(&self, buffer: &Buffer) {
        // SAFETY: recording state; the buffer outlives the submission.
        unsafe { self.encoder.device.raw.cmd_bind_vertex_buffers(self.encoder.raw, 0, &[buffer.raw], &[0]) };
    }

    /// Binds `buffer` as the index buffer (32-bit indices).
    pub fn bind_indices(&self, buffer: &Buffer) {
        // SAFETY: recording state; the buffer outlives the submission.
        unsafe {
            self.encoder.device.raw.cmd_bind_index_buffer(self.encoder.raw, buffer.raw, 0, vk::IndexType::UINT32)
        };
    }

    /// Draws the `VkDrawIndexedIndirectCommand`s at byte `offset` of `commands`: as many as the `u32` at
    /// byte `count_offset` of `counts` says, at most `max` (`count` `None`: exactly `max`, which needs
    /// `multiDrawIndirect` when above 1). `count` `Some` needs `drawIndirectCount`.
    pub fn draw_indexed_indirect(&self, commands: &Buffer, offset: u64, count: Option<(&Buffer, u64)>, max: u32) {
        let stride = size_of::<vk::DrawIndexedIndirectCommand>() as u32;
        let (device, raw) = (&self.encoder.device.raw, self.encoder.raw);
        // SAFETY: inside a render pass with a graphics pipeline, vertex and index buffers bound by the caller;
        // the buffers hold `max` commands from `offset` and a count at `count_offset` (checked by callers).
        unsafe {
            match count {
                Some((counts, count_offset)) => device.cmd_draw_indexed_indirect_count(
                    raw,
                    commands.raw,
                    offset,
                    counts.raw,
                    count_offset,
                    max,
                    stride,
                ),
                None => device.cmd_draw_indexed_indirect(raw, commands.raw, offset, max, stride),
            }
        }
    }

    /// Points viewport and scissor at `rect` of the framebuffer (a tile of an atlas, say).
    pub fn set_viewport_scissor(&self, rect: vk::Rect2D) {
        let viewport = vk::Viewport {
            x: rect.offset.x as f32,
            y: rect.offset.y as f32,
            width: rect.extent.width as f32,
            height: rect.extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        // SAFETY: recording state inside a render pass; both states are dynamic in every pipeline here.
        unsafe {
            self.encoder.device.raw.cmd_set_viewport(self.encoder.raw, 0, &[viewport]);
            self.encoder.device.raw.cmd_set_scissor(self.encoder.raw, 0, &[rect]);
        }
    }

    pub fn draw(&self, vertices: u32, instances: u32, first_vertex: u32, first_instance: u32) {
        // SAFETY: inside a render pass with a graphics pipeline bound by the caller.
        unsafe {
            self.encoder.device.raw.cmd_draw(self.encoder.raw, vertices, instances, first_vertex, first_instance)
        };
    }
}

impl Drop for RenderPassScope<'_, '_> {
    fn drop(&mut self) {
        // SAFETY: this scope began the pass on this command buffer.
        unsafe { self.encoder.device.raw.cmd_end_render_pass(self.encoder.raw) };
    }
}
