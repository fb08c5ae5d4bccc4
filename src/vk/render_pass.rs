//! Render passes and framebuffers: one subpass, cleared attachments, results kept for compute or copies.

use std::sync::Arc;

use anyhow::{Context as _, Result};
use ash::vk;

use super::device::Device;
use super::image::ImageView;

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
        // SAFETY: no pending command buffer uses it (its owner waits for the GPU first); framebuffers and
        // pipelines made from it may outlive it.
        unsafe { self.device.raw.destroy_render_pass(self.raw, None) };
    }
}

/// A framebuffer and the views it draws into (which keep their images alive).
pub struct Framebuffer {
    device: Arc<Device>,
    pub raw: vk::Framebuffer,
    pub extent: vk::Extent2D,
    _attachments: Vec<ImageView>,
}

impl Framebuffer {
    /// A framebuffer of `pass` over `attachments` (in the pass's order; their images' extent); `layers` > 1
    /// for layered rendering (`gl_Layer`), 1 for single-layer and multiview passes.
    pub fn new(device: &Arc<Device>, pass: &RenderPass, attachments: Vec<ImageView>, layers: u32) -> Result<Self> {
        let extent = attachments.first().map(|a| a.image().extent()).context("a framebuffer needs attachments")?;
        let views: Vec<vk::ImageView> = attachments.iter().map(|a| a.raw).collect();
        let info = vk::FramebufferCreateInfo::default()
            .render_pass(pass.raw)
            .attachments(&views)
            .width(extent.width)
            .height(extent.height)
            .layers(layers);
        // SAFETY: the views are alive (owned below) and match the pass's attachments.
        let raw = unsafe { device.raw.create_framebuffer(&info, None) }?;
        Ok(Self { device: device.clone(), raw, extent, _attachments: attachments })
    }
}

impl Drop for Framebuffer {
    fn drop(&mut self) {
        // SAFETY: owners wait for the GPU before dropping what it uses; the views are dropped after this.
        unsafe { self.device.raw.destroy_framebuffer(self.raw, None) };
    }
}
