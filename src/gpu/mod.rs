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
//! * **Driver quirks.** Supported drivers: lavapipe from Mesa 22.3 (Debian 12's own; no ray
//!   queries) and from Mesa ≥ 24.1 (the reference device, with ray queries), and GPU drivers.
//!   The two that cost speed were re-measured on Mesa 25.0 and still pay (BENCHMARKS.md, "Mesa 25").
//!   - lavapipe: a loop is cut off after 65535 iterations per invocation (the gallivm loop
//!     limiter), silently. Compute shaders keep every loop's trip count below that: the prefilter
//!     visits only the cube faces a lobe can reach, and `params.rs` bounds the irradiance source
//!     at 6·32² texels. Correctness on Mesa 22.3 (not probed on 25: the bound costs nothing).
//!   - GLSL `acos`/`atan` have no useful precision guarantee in Vulkan and lavapipe's acos is off by
//!     ~1e-4 rad: shaders use `common/math.glsl` instead. Correctness on any driver.
//!   - lavapipe loads an SSBO element lane by lane unless the address is provably uniform (a loop
//!     counter is not): gathered reads use texel buffers (`BindingKind::UniformTexelBuffer`),
//!     declared `textureBuffer` (`common/texel_buffer.glsl`: Mesa 25's SPIR-V parser rejects a
//!     `samplerBuffer`).
//!   - lavapipe runs a loop's body once, masked, even when no lane enters it, and both sides of
//!     every `if`: rare expensive work goes to a separate dispatch over a compacted list (the
//!     prefilter's near-edge pass), not behind a condition.
//!   - Mesa 22.3's lavapipe, after a graphics pass, writes a timestamp at the rasterizer's next
//!     flush, not where it was recorded, so later compute-only timestamps land one pass late.
//!     Only the benchmark's per-pass split is affected; Mesa 25 writes them in place.

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
pub mod shaders;

pub use adapter::{AdapterInfo, RayQuery};
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
