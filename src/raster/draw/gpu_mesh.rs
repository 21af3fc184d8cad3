//! [`GpuMesh`]: a mesh's interleaved vertex buffer and index buffer on the device, uploaded once
//! and drawn by any number of renders (the scene renderer caches them per `Arc<Mesh>`).

use crate::gpu::shaders::interface::{VERTEX_NORMAL_LOCATION, VERTEX_POSITION_LOCATION};
use crate::gpu::{
    AccelerationStructure, Buffer, BufferDesc, BufferUsage, GpuContext, TriangleGeometry,
    VertexAttribute,
};
use crate::raster::mesh::Mesh;
use crate::raster::SelfHits;
use crate::Result;
use std::mem::{offset_of, size_of};
use std::sync::OnceLock;

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
    vertex_count: u32,
    /// Its bottom-level acceleration structure, built by the first ray-traced draw and kept as
    /// long as the mesh: [`GpuMesh::bottom_level`].
    bottom_level: OnceLock<AccelerationStructure>,
    /// Which rays leaving it can meet it again (on a device without ray queries: any).
    pub(crate) self_hits: SelfHits,
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
        // With ray queries the buffers are also an acceleration-structure build's input.
        let usage = |usage| match gpu.info().ray_query.is_enabled() {
            true => usage | BufferUsage::ACCELERATION_INPUT,
            false => usage,
        };
        Ok(GpuMesh {
            vertices: upload(gpu, "mesh vertices", &vertices, usage(BufferUsage::VERTEX))?,
            indices: upload(
                gpu,
                "mesh indices",
                &mesh.indices,
                usage(BufferUsage::INDEX),
            )?,
            index_count: mesh.indices.len() as u32,
            vertex_count: vertices.len() as u32,
            bottom_level: OnceLock::new(),
            self_hits: match gpu.info().ray_query.is_enabled() {
                true => SelfHits::of(mesh),
                false => SelfHits::ANY,
            },
        })
    }

    /// Triangles of the mesh.
    pub fn triangle_count(&self) -> u32 {
        self.index_count / 3
    }

    /// Bytes of device memory the mesh holds (with its acceleration structure, once built).
    pub fn byte_size(&self) -> u64 {
        self.vertices.size()
            + self.indices.size()
            + self.bottom_level.get().map_or(0, |b| b.byte_size())
    }

    /// The vertex and index buffers' device addresses as (low, high) u32 pairs, for shaders
    /// that read the triangles (a device with ray queries only).
    pub(crate) fn addresses(&self) -> Result<[u32; 4]> {
        let vertices = self.vertices.device_address()?;
        let indices = self.indices.device_address()?;
        Ok([
            vertices as u32,
            (vertices >> 32) as u32,
            indices as u32,
            (indices >> 32) as u32,
        ])
    }

    /// The mesh's bottom-level acceleration structure, built on first use (a device with ray
    /// queries only) and kept with the mesh, so a batch that draws the same mesh many times
    /// builds it once.
    pub fn bottom_level(&self, gpu: &GpuContext) -> Result<&AccelerationStructure> {
        if let Some(built) = self.bottom_level.get() {
            return Ok(built);
        }
        let built = gpu.build_bottom_level(
            "mesh bottom-level structure",
            &TriangleGeometry {
                vertices: &self.vertices,
                vertex_count: self.vertex_count,
                vertex_stride: VERTEX_STRIDE,
                indices: &self.indices,
                triangle_count: self.triangle_count(),
            },
        )?;
        Ok(self.bottom_level.get_or_init(|| built))
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
