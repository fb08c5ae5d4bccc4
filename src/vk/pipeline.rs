//! Pipeline layouts and pipelines (compute and graphics), built from the SPIR-V in [`crate::shaders`].

use std::io::Cursor;
use std::sync::Arc;

use anyhow::{Context as _, Result};
use ash::vk;

use super::device::Device;

/// One descriptor set layout and the pipeline layout around it (plus an optional push-constant range).
pub struct PipelineLayout {
    device: Arc<Device>,
    pub set_layout: vk::DescriptorSetLayout,
    pub raw: vk::PipelineLayout,
    pub push_stages: vk::ShaderStageFlags,
}

/// A descriptor binding: (binding number, type, stages that read it).
pub type Binding = (u32, vk::DescriptorType, vk::ShaderStageFlags);

impl PipelineLayout {
    pub fn new(
        device: &Arc<Device>,
        bindings: &[Binding],
        push_bytes: u32,
        push_stages: vk::ShaderStageFlags,
    ) -> Result<Self> {
        let raw_bindings: Vec<_> = bindings
            .iter()
            .map(|&(binding, ty, stages)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(binding)
                    .descriptor_type(ty)
                    .descriptor_count(1)
                    .stage_flags(stages)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&raw_bindings);
        // SAFETY: valid device and create info.
        let set_layout = unsafe { device.raw.create_descriptor_set_layout(&info, None) }?;
        let set_layouts = [set_layout];
        let ranges = [vk::PushConstantRange::default().stage_flags(push_stages).offset(0).size(push_bytes)];
        let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        if push_bytes > 0 {
            info = info.push_constant_ranges(&ranges);
        }
        // SAFETY: as above; on failure the set layout is destroyed.
        let raw = match unsafe { device.raw.create_pipeline_layout(&info, None) } {
            Ok(raw) => raw,
            Err(e) => {
                unsafe { device.raw.destroy_descriptor_set_layout(set_layout, None) };
                return Err(e.into());
            }
        };
        Ok(Self { device: device.clone(), set_layout, raw, push_stages })
    }
}

impl Drop for PipelineLayout {
    fn drop(&mut self) {
        // SAFETY: pipelines using this layout are dropped first by their owning pass.
        unsafe {
            self.device.raw.destroy_pipeline_layout(self.raw, None);
            self.device.raw.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// A shader module that lives only while pipelines are created from it.
struct ShaderModule<'a> {
    device: &'a Device,
    raw: vk::ShaderModule,
}

impl<'a> ShaderModule<'a> {
    fn new(device: &'a Device, spirv: &[u8]) -> Result<Self> {
        let words = ash::util::read_spv(&mut Cursor::new(spirv)).context("invalid SPIR-V")?;
        let info = vk::ShaderModuleCreateInfo::default().code(&words);
        // SAFETY: `words` is SPIR-V produced by shaderc in build.rs.
        let raw = unsafe { device.raw.create_shader_module(&info, None) }?;
        Ok(Self { device, raw })
    }

    fn stage(&self, stage: vk::ShaderStageFlags) -> vk::PipelineShaderStageCreateInfo<'_> {
        vk::PipelineShaderStageCreateInfo::default().stage(stage).module(self.raw).name(c"main")
    }
}

impl Drop for ShaderModule<'_> {
    fn drop(&mut self) {
        // SAFETY: modules are not needed once their pipelines exist.
        unsafe { self.device.raw.destroy_shader_module(self.raw, None) };
    }
}

pub struct Pipeline {
    device: Arc<Device>,
    pub raw: vk::Pipeline,
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        // SAFETY: owners wait for the GPU before dropping what it uses.
        unsafe { self.device.raw.destroy_pipeline(self.raw, None) };
    }
}

impl Pipeline {
    pub fn compute(device: &Arc<Device>, layout: &PipelineLayout, spirv: &[u8]) -> Result<Self> {
        let module = ShaderModule::new(device, spirv)?;
        let info = [vk::ComputePipelineCreateInfo::default()
            .stage(module.stage(vk::ShaderStageFlags::COMPUTE))
            .layout(layout.raw)];
        // SAFETY: valid module and layout.
        let raw = unsafe { device.raw.create_compute_pipelines(vk::PipelineCache::null(), &info, None) }
            .map_err(|(_, e)| e)
            .context("create compute pipeline")?[0];
        Ok(Self { device: device.clone(), raw })
    }

    pub fn graphics(device: &Arc<Device>, layout: &PipelineLayout, desc: &GraphicsDesc<'_>) -> Result<Self> {
        let vertex = ShaderModule::new(device, desc.vertex)?;
        let fragment = ShaderModule::new(device, desc.fragment)?;
        // Constant i of the vertex shader is `vertex_constants[i]` (4 bytes each: a uint or a bool).
        let entries: Vec<_> = (0..desc.vertex_constants.len() as u32)
            .map(|i| vk::SpecializationMapEntry::default().constant_id(i).offset(4 * i).size(4))
            .collect();
        let specialization =
            vk::SpecializationInfo::default().map_entries(&entries).data(bytemuck::cast_slice(desc.vertex_constants));
        let stages = [
            vertex.stage(vk::ShaderStageFlags::VERTEX).specialization_info(&specialization),
            fragment.stage(vk::ShaderStageFlags::FRAGMENT),
        ];
        let bindings = [vk::VertexInputBindingDescription::default()
            .binding(0)
            .stride(desc.vertex_stride)
            .input_rate(vk::VertexInputRate::VERTEX)];
        let attributes: Vec<_> = desc
            .vertex_attributes
            .iter()
            .map(|&(location, format, offset)| {
                vk::VertexInputAttributeDescription::default()
                    .binding(0)
                    .location(location)
                    .format(format)
                    .offset(offset)
            })
            .collect();
        let vertex_input = if desc.vertex_stride == 0 {
            vk::PipelineVertexInputStateCreateInfo::default()
        } else {
            vk::PipelineVertexInputStateCreateInfo::default()
                .vertex_binding_descriptions(&bindings)
                .vertex_attribute_descriptions(&attributes)
        };
        let assembly =
            vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::NONE)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample =
            vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(desc.depth_compare.is_some())
            .depth_write_enable(desc.depth_compare.is_some())
            .depth_compare_op(desc.depth_compare.unwrap_or(vk::CompareOp::ALWAYS));
        let blend: Vec<_> = (0..desc.color_attachments)
            .map(|_| vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA))
            .collect();
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend);
        let dynamic = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic);
        let info = [vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(layout.raw)
            .render_pass(desc.render_pass)
            .subpass(0)];
        // SAFETY: every state struct above outlives the call.
        let raw = unsafe { device.raw.create_graphics_pipelines(vk::PipelineCache::null(), &info, None) }
            .map_err(|(_, e)| e)
            .context("create graphics pipeline")?[0];
        Ok(Self { device: device.clone(), raw })
    }
}

/// What differs between the graphics pipelines here. Culling is always off: ordinary surfaces are two-sided
/// and emitters decide their side in the fragment shader from `gl_FrontFacing` (CCW = front).
pub struct GraphicsDesc<'a> {
    pub vertex: &'a [u8],
    /// The vertex shader's specialization constants, by `constant_id` from 0 (empty for none).
    pub vertex_constants: &'a [u32],
    pub fragment: &'a [u8],
    pub render_pass: vk::RenderPass,
    pub color_attachments: u32,
    /// 0 for no vertex buffer.
    pub vertex_stride: u32,
    /// (location, format, byte offset) in binding 0.
    pub vertex_attributes: &'a [(u32, vk::Format, u32)],
    /// `None` disables the depth test.
    pub depth_compare: Option<vk::CompareOp>,
}
