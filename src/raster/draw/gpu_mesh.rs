//! [`GpuMesh`]: a mesh's interleaved vertex buffer and index buffer on the device, uploaded once
//! and drawn by any number of renders (the scene renderer caches them per `Arc<Mesh>`).

use crate::gpu::shaders::interface::{VERTEX_NORMAL_LOCATION, VERTEX_POSITION_LOCATION};
use crate::gpu::{Buffer, BufferDesc, BufferUsage, GpuContext, VertexAttribute};
use crate::raster::mesh::Mesh;
use crate::Result;
use std::mem::{offset_of, size_of};

/// One vertex of the interleaved buffer mesh.vert reads.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Vertex {
    position: [f32; 3],
    normal: [f32; 3],
}

pub(crate) const VERTEX_STRIDE: u32 = size_of::<Vertex>() as u32;
pub(crate) const VERTEX_ATTRIBUTES: [VertexAttribute; 2] = [
    VertexAttribute {
        location: VERTEX_POSITION_LOCATION,
        offset: offset_of!(Vertex, position) as u32,
        components: 3,
    },
    VertexAttribute {
        location: VERTEX_NORMAL_LOCATION,
        offset: offset_of!(Vertex, normal) as u32,
        components: 3,
    },
];

/// The device copy of one [`Mesh`]. Immutable after upload: reading it from many submits needs
/// no barrier (queue submission makes the host writes visible).
pub struct GpuMesh {
    pub(crate) vertices: Buffer,
    pub(crate) indices: Buffer,
    pub(crate) index_count: u32,
}

impl GpuMesh {
    /// Uploads `mesh` (interleaving positions and normals). An empty mesh gets one-element
    /// buffers (Vulkan has no zero-sized buffers) and draws nothing.
    pub fn upload(gpu: &GpuContext, mesh: &Mesh) -> Result<Self> {
        let vertices: Vec<Vertex> = mesh
            .positions
            .iter()
            .zip(&mesh.normals)
            .map(|(&position, &normal)| Vertex { position, normal })
            .collect();
        Ok(GpuMesh {
            vertices: upload(gpu, "mesh vertices", &vertices, BufferUsage::VERTEX)?,
            indices: upload(gpu, "mesh indices", &mesh.indices, BufferUsage::INDEX)?,
            index_count: mesh.indices.len() as u32,
        })
    }

    /// Bytes of device memory the mesh holds.
    pub fn byte_size(&self) -> u64 {
        self.vertices.size() + self.indices.size()
    }
}

/// A mapped buffer holding `data` (at least 16 bytes).
pub(crate) fn upload<T: bytemuck::Pod>(
    gpu: &GpuContext,
    name: &str,
    data: &[T],
    usage: BufferUsage,
) -> Result<Buffer> {
    let size = (std::mem::size_of_val(data) as u64).max(16);
    let mut buffer = gpu.create_buffer(BufferDesc::upload(name, size, usage))?;
    buffer.write(data)?;
    Ok(buffer)
}
