//! The scene as the GPU passes read it: a vertex buffer (triangle soup), per-triangle normals and the
//! per-surface materials. Uploaded once per renderer and shared (hence `Arc`) by the G-buffer and sensor
//! passes, each of which keeps what it draws with alive.

use std::sync::Arc;

use anyhow::Result;
use ash::vk;
use glam::Vec4;

use crate::gpu_types::{GpuSurface, Vertex};
use crate::scene::{Mesh, Scene};
use crate::vk::{Buffer, Device, transfer};

pub struct GpuScene {
    pub vertices: Arc<Buffer>,
    pub vertex_count: u32,
    /// One `vec4` per triangle: the front normal.
    pub normals: Arc<Buffer>,
    /// `GpuSurface` per surface id (entry 0 unused).
    pub surfaces: Arc<Buffer>,
}

impl GpuScene {
    pub fn upload(device: &Arc<Device>, scene: &Scene) -> Result<Self> {
        let mesh = &scene.mesh;
        let vertices = vertices(mesh);
        let normals: Vec<Vec4> = mesh.triangles.iter().map(|t| t.normal.extend(0.0)).collect();
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        Ok(Self {
            vertex_count: vertices.len() as u32,
            vertices: Arc::new(transfer::upload(
                device,
                "vertices",
                &vertices,
                vk::BufferUsageFlags::VERTEX_BUFFER | storage,
            )?),
            normals: Arc::new(transfer::upload(device, "triangle normals", &normals, storage)?),
            surfaces: Arc::new(transfer::upload(device, "surfaces", &surfaces(mesh), storage)?),
        })
    }
}

/// The triangle soup: three vertices per triangle, each carrying its triangle's surface id.
pub fn vertices(mesh: &Mesh) -> Vec<Vertex> {
    mesh.triangles.iter().flat_map(|t| t.v.map(|p| Vertex { position: p.to_array(), surface: t.surface })).collect()
}

/// The material table indexed by surface id (entry 0: no surface).
pub fn surfaces(mesh: &Mesh) -> Vec<GpuSurface> {
    std::iter::once(GpuSurface::default())
        .chain((1..=mesh.surfaces.len() as u32).map(|id| {
            let m = mesh.material_of(id);
            GpuSurface { kd: m.kd.extend(0.0), ke: m.ke.extend(if m.is_emitter() { 1.0 } else { 0.0 }) }
        }))
        .collect()
}
