//! # gpu — the only place with Vulkan and `unsafe`
//!
//! A thin backend in the manner of kajiya and wgpu-hal: it owns the device, memory, buffers,
//! images, pipelines and command submission; the renderer above speaks in [`BufferDesc`],
//! [`ImageDesc`], [`Access`] and [`Recorder`] methods and never sees a raw handle.
//!
//! * **Lifetimes.** `DeviceShared` (instance, messenger, device, allocator) is reference-counted;
//!   every resource holds an `Arc` to it and frees itself in `Drop`, so the device is destroyed
//!   last, after everything made from it, in reverse creation order.
//! * **Memory.** All through gpu-allocator. Upload and readback buffers are host-visible,
//!   coherent and persistently mapped; images are device-local.
//! * **Synchronisation.** One queue; [`GpuContext::submit_and_wait`] records one command buffer,
//!   submits it and waits on a fence. Inside it, hazards are resolved with synchronization2
//!   barriers named by the two [`Access`]es; images carry explicit layout transitions. The fence
//!   wait plus a barrier to `Access::HostRead` makes device writes visible to the host.
//! * **Validation.** With [`ContextOptions::validation`], VK_LAYER_KHRONOS_validation is enabled
//!   and every warning/error message is collected; tests fail on any (`check_validation`).
//! * **Driver quirks.** What a driver does that shikki works around is data: [`Quirks`], one field
//!   per quirk with the drivers that have it and why, set once when the adapter is chosen
//!   (`adapter.rs`) and read from [`AdapterInfo::quirks`]. Code and shaders name the field
//!   (`loop_iteration_limit`, `imprecise_inverse_trig`, `ssbo_gather_is_per_lane`,
//!   `loop_body_runs_when_no_lane_enters`, `late_timestamps_after_graphics`,
//!   `float_to_int_is_per_lane`); `shikki info` lists the active ones.

mod accel;
mod adapter;
mod buffer;
mod command;
mod context;
mod conv;
mod debug;
mod device;
mod error;
mod image;
mod instance;
mod pipeline;
mod query;
mod ray_pipeline;
pub mod shaders;

pub use accel::{AccelerationStructure, Instance, TriangleGeometry};
pub use adapter::{AdapterInfo, Quirks, RayQuery, RayTracingChoice};
pub use buffer::{Buffer, BufferDesc, BufferUsage, MemoryUse};
pub use command::{ImageUse, Recorder, RenderTargets};
pub use context::{ContextOptions, GpuContext};
pub use conv::{Access, DepthCompare, DepthTest, Format, Layout};
pub use debug::ValidationLog;
pub use error::GpuError;
pub use image::{Image, ImageDesc, ImageUsage, Sampler};
pub use pipeline::{
    Binding, BindingKind, ComputePipeline, DescriptorSet, GraphicsPipeline, GraphicsPipelineDesc,
    PipelineLayout, Resource, VertexAttribute,
};
pub use query::TimestampPool;
pub use ray_pipeline::{RayTracingPipeline, RayTracingPipelineDesc};
