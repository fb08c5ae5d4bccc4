//! Render passes and framebuffers: one subpass, cleared attachments, results kept for compute or copies.

use std::sync::Arc;

use anyhow::Result;
use ash::vk;

use super::device::Device;

pub struct RenderPass {
    device: Arc<Device>,
    pub raw: vk::RenderPass,
}

impl RenderPass {
    /// Colour attachments of `colors` formats and an optional depth attachment, all cleared on load and stored.
    /// Colour attachments end in `GENERAL` (read by compute passes and copies). `view_mask != 0` makes it a
    /// multiview pass: the subpass runs once per set bit, `gl_ViewIndex` telling which, each into its layer.
    pub fn new(device: &Arc<Device>, colors: &[vk::Format], depth: Option<vk::Format>, view_mask: u32) -> Result<Self> {
        let mut attachments: Vec<_> = colors
            .iter()
            .map(|&format| {
                vk::AttachmentDescription::default()
                    .format(format)
                    .samples(vk::SampleCountFlags::TYPE_1)
                    .load_op(vk::AttachmentLoadOp::CLEAR)
                    .store_op(vk::AttachmentStoreOp::STORE)
                    .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
                    .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
                    .initial_layout(vk::ImageLayout::UNDEFINED)
                    .final_layout(vk::ImageLayout::GENERAL)
            })
            .collect();
        let color_refs: Vec<_> = (0..colors.len() as u32)
            .map(|i| vk::AttachmentReference::default().attachment(i).layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL))
            .collect();
        let depth_ref = vk::AttachmentReference::default()
            .attachment(colors.len() as u32)
            .layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL);
        if let Some(format) = depth {
            attachments.push(
                vk::AttachmentDescription::default()
                    .format(format)
                    .samples(vk::SampleCountFlags::TYPE_1)
                    .load_op(vk::AttachmentLoadOp::CLEAR)
                    // Depth is scratch: nothing reads it after the pass.
                    .store_op(vk::AttachmentStoreOp::DONT_CARE)
                    .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
                    .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
                    .initial_layout(vk::ImageLayout::UNDEFINED)
                    .final_layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL),
            );
        }
        let mut subpass = vk::SubpassDescription::default()
            .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
            .color_attachments(&color_refs);
        if depth.is_some() {
            subpass = subpass.depth_stencil_attachment(&depth_ref);
        }
        let attachment_stages = vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT
            | vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS
            | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS;
        let attachment_writes =
            vk::AccessFlags::COLOR_ATTACHMENT_WRITE | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE;
        let readers = vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER;
        let dependencies = [
            // Earlier readers (a previous batch's reduction or copy) finish before the attachments are rewritten.
            vk::SubpassDependency::default()
                .src_subpass(vk::SUBPASS_EXTERNAL)
                .dst_subpass(0)
                .src_stage_mask(readers | attachment_stages)
                .src_access_mask(attachment_writes)
                .dst_stage_mask(attachment_stages)
                .dst_access_mask(attachment_writes | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_READ),
            // The attachments' contents are visible to compute shaders and copies after the pass.
            vk::SubpassDependency::default()
                .src_subpass(0)
                .dst_subpass(vk::SUBPASS_EXTERNAL)
                .src_stage_mask(attachment_stages)
                .src_access_mask(attachment_writes)
                .dst_stage_mask(readers)
                .dst_access_mask(vk::AccessFlags::SHADER_READ | vk::AccessFlags::TRANSFER_READ),
        ];
        let subpasses = [subpass];
        let view_masks = [view_mask];
        let mut multiview =
            vk::RenderPassMultiviewCreateInfo::default().view_masks(&view_masks).correlation_masks(&view_masks);
        let mut info = vk::RenderPassCreateInfo::default()
            .attachments(&attachments)
            .subpasses(&subpasses)
            .dependencies(&dependencies);
        if view_mask != 0 {
            info = info.push_next(&mut multiview);
        }
        // SAFETY: every array above outlives the call.
        let raw = unsafe { device.raw.create_render_pass(&info, None) }?;
        Ok(Self { device: device.clone(), raw })
    }
}

impl Drop for RenderPass {
    fn drop(&mut self) {
        // SAFETY: framebuffers and pipelines made from it are owned by the same pass and dropped first.
        unsafe { self.device.raw.destroy_render_pass(self.raw, None) };
    }
}

pub struct Framebuffer {
    device: Arc<Device>,
    pub raw: vk::Framebuffer,
    pub extent: vk::Extent2D,
}

impl Framebuffer {
    /// `layers` > 1 for layered rendering (`gl_Layer`); 1 for single-layer and multiview passes.
    pub fn new(
        device: &Arc<Device>,
        pass: &RenderPass,
        views: &[vk::ImageView],
        extent: vk::Extent2D,
        layers: u32,
    ) -> Result<Self> {
        let info = vk::FramebufferCreateInfo::default()
            .render_pass(pass.raw)
            .attachments(views)
            .width(extent.width)
            .height(extent.height)
            .layers(layers);
        // SAFETY: the views are alive and match the pass's attachments.
        let raw = unsafe { device.raw.create_framebuffer(&info, None) }?;
        Ok(Self { device: device.clone(), raw, extent })
    }

    /// Begins `pass` on this framebuffer with the given clear values and sets the full viewport and scissor.
    pub fn begin(&self, cmd: vk::CommandBuffer, pass: &RenderPass, clears: &[vk::ClearValue]) {
        self.begin_area(cmd, pass, clears, self.extent);
    }

    /// Like [`Framebuffer::begin`], but clears and draws only the top-left `area` (the viewport stays whole,
    /// so clip space keeps mapping to the full framebuffer).
    pub fn begin_area(&self, cmd: vk::CommandBuffer, pass: &RenderPass, clears: &[vk::ClearValue], area: vk::Extent2D) {
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent: area };
        let info = vk::RenderPassBeginInfo::default()
            .render_pass(pass.raw)
            .framebuffer(self.raw)
            .render_area(area)
            .clear_values(clears);
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: self.extent.width as f32,
            height: self.extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        // SAFETY: recording into a command buffer in the recording state.
        unsafe {
            self.device.raw.cmd_begin_render_pass(cmd, &info, vk::SubpassContents::INLINE);
            self.device.raw.cmd_set_viewport(cmd, 0, &[viewport]);
            self.device.raw.cmd_set_scissor(cmd, 0, &[area]);
        }
    }
}

impl Drop for Framebuffer {
    fn drop(&mut self) {
        // SAFETY: owners wait for the GPU before dropping what it uses.
        unsafe { self.device.raw.destroy_framebuffer(self.raw, None) };
    }
}
