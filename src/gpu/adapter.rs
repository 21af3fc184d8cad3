//! Choosing the physical device: discrete > integrated > virtual > CPU, or the first whose name
//! contains `SHIKKI_DEVICE`. Only devices with Vulkan 1.3, dynamic rendering, synchronization2 and
//! a graphics+compute queue qualify.
//!
//! This is also the one place that knows drivers apart: [`Quirks`], set here once from the chosen
//! device's driver ID and version, records what each driver does that the renderer works around.

use super::error::{GpuError, VkResultExt};
use ash::vk;

/// What `shikki info` prints and what the renderer checks sizes against.
#[derive(Clone, Debug)]
pub struct AdapterInfo {
    pub name: String,
    pub device_type: String,
    pub driver_name: String,
    pub driver_info: String,
    pub api_version: String,
    pub max_image_dimension_2d: u32,
    pub max_image_dimension_cube: u32,
    pub max_compute_workgroup_invocations: u32,
    pub max_storage_buffer_range: u32,
    pub max_uniform_buffer_range: u32,
    pub max_texel_buffer_elements: u32,
    pub framebuffer_color_sample_counts: Vec<u32>,
    pub timestamp_period_ns: f32,
    pub timestamp_compute_and_graphics: bool,
    /// Double precision in shaders (enabled when present; the prefilter uses it for exact
    /// source coordinates).
    pub shader_float64: bool,
    /// Identity of the driver's pipeline-cache format: (vendorID, deviceID, pipelineCacheUUID).
    pub pipeline_cache_id: (u32, u32, [u8; 16]),
    /// Rays traced from shaders: available and enabled, turned off, or what the device lacks.
    pub ray_query: RayQuery,
    /// What this driver does that the renderer works around.
    pub quirks: Quirks,
}

/// Driver behaviour the renderer works around, one field per quirk, set once when the adapter is
/// chosen (`Quirks::of_driver`). Code and shaders name a quirk by its field (`// quirk
/// ssbo_gather_is_per_lane`) instead of retelling it; `shikki info` lists the active ones.
///
/// Most workarounds are unconditional (the shaders read gathers from texel buffers on every
/// driver): they cost nothing measurable elsewhere, and one set of shaders keeps every driver on
/// the same code and the same bits. The field then records which drivers need it.
/// Supported drivers: lavapipe from Mesa 22.3 (Debian 12's own; no ray queries) and from Mesa ≥
/// 24.1 (the reference device, with ray queries), and GPU drivers. The quirks that cost speed were
/// re-measured on Mesa 25.0 and still pay (BENCHMARKS.md, "Mesa 25").
///
/// To add one: a field saying which drivers and why, its condition in `Quirks::of_driver`, and
/// its name in [`Quirks::NAMES`] and [`Quirks::active`] (same order).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Quirks {
    /// lavapipe, every version: a loop is cut off after [`Quirks::LOOP_ITERATION_LIMIT`]
    /// iterations per invocation (gallivm's loop limiter), silently. Compute shaders keep every
    /// loop's trip count below it: the prefilter visits only the cube faces a lobe can reach, and
    /// `environment/params.rs` bounds the irradiance source at 6·32² texels. Seen on Mesa 22.3;
    /// not probed on 25, as the bound costs nothing.
    pub loop_iteration_limit: bool,
    /// Every driver: GLSL `acos`/`atan` have no useful precision bound in Vulkan (atan's is 4096
    /// ulp), and lavapipe's acos is off by ~1e-4 rad, beyond what the oracle tests allow. Shaders
    /// use `common/math.glsl` instead.
    pub imprecise_inverse_trig: bool,
    /// lavapipe, every version: an SSBO element is loaded lane by lane unless the address is
    /// provably uniform (a loop counter is not), while a `texelFetch` gathers a whole texel per
    /// lane. Gathered reads use texel buffers (`BindingKind::UniformTexelBuffer`), declared
    /// `textureBuffer` (`common/texel_buffer.glsl`; Mesa 25's SPIR-V parser rejects a
    /// `samplerBuffer`).
    pub ssbo_gather_is_per_lane: bool,
    /// lavapipe, every version: a loop's body runs once, masked, even when no lane enters it, and
    /// both sides of every `if` run under a lane mask. Rare expensive work goes to a separate
    /// dispatch over a compacted list (the prefilter's near-edge pass), not behind a condition.
    /// Masked lanes still load through device addresses (a crash seen in the ray-traced pass):
    /// a ray query that misses reports triangle 0 of object 0, and an object without triangles
    /// gets another mesh's addresses, so every such load stays in bounds (visibility.glsl,
    /// `raster/draw/mod.rs` `object_geometry`).
    pub loop_body_runs_when_no_lane_enters: bool,
    /// lavapipe before Mesa 25 (seen on 22.3; 25.0 writes them in place; the versions between
    /// were not measured): after a graphics pass, a timestamp is written at the rasterizer's next
    /// flush, not where it was recorded, so later compute-only timestamps land one pass late. Only
    /// per-pass splits are affected (the wall clock is right): `shikki bench` marks them.
    pub late_timestamps_after_graphics: bool,
    /// lavapipe, every version (seen on Mesa 25.0 with LLVM 15; the others not measured): GLSL
    /// `int(x)` of a float is converted lane by lane, six or seven instructions a lane (a
    /// saturating conversion, scalarised). Where it counts (the Fresnel table, the `brdf` model's
    /// texel taps, per-pixel indices, the light bins' lists, the grid's node counts and the sharp
    /// reads' rows and columns) shaders turn whole numbers into indices with `common/math.glsl`'s
    /// `whole_to_int` (or `signed_whole_to_int`, which may be negative) instead: the same integers
    /// by a vector add and subtract, on every driver.
    pub float_to_int_is_per_lane: bool,
}

impl Quirks {
    /// The iterations lavapipe runs of one loop in one invocation (`loop_iteration_limit`).
    pub const LOOP_ITERATION_LIMIT: u32 = 65535;

    /// Every quirk's name, as its field is spelled, in declaration order.
    pub const NAMES: [&'static str; 6] = [
        "loop_iteration_limit",
        "imprecise_inverse_trig",
        "ssbo_gather_is_per_lane",
        "loop_body_runs_when_no_lane_enters",
        "late_timestamps_after_graphics",
        "float_to_int_is_per_lane",
    ];

    /// The quirks of a driver: its Vulkan driver ID and `driverInfo` text (Mesa's reads
    /// "Mesa 25.0.7-2~bpo12+1 (LLVM 15.0.6)").
    pub(crate) fn of_driver(driver_id: vk::DriverId, driver_info: &str) -> Quirks {
        let lavapipe = driver_id == vk::DriverId::MESA_LLVMPIPE;
        let mesa = mesa_version(driver_info);
        Quirks {
            loop_iteration_limit: lavapipe,
            imprecise_inverse_trig: true,
            ssbo_gather_is_per_lane: lavapipe,
            loop_body_runs_when_no_lane_enters: lavapipe,
            // An unreadable version counts as old: a wrong "unreliable" costs less than a wrong
            // split.
            late_timestamps_after_graphics: lavapipe && !matches!(mesa, Some(v) if v >= (25, 0)),
            float_to_int_is_per_lane: lavapipe,
        }
    }

    /// The names of the quirks that are set, in [`Quirks::NAMES`] order.
    pub fn active(&self) -> Vec<&'static str> {
        let set = [
            self.loop_iteration_limit,
            self.imprecise_inverse_trig,
            self.ssbo_gather_is_per_lane,
            self.loop_body_runs_when_no_lane_enters,
            self.late_timestamps_after_graphics,
            self.float_to_int_is_per_lane,
        ];
        Self::NAMES
            .iter()
            .zip(set)
            .filter(|(_, on)| *on)
            .map(|(name, _)| *name)
            .collect()
    }

    /// One line for `shikki info`: the active quirks' names, or "none".
    pub fn summary(&self) -> String {
        let active = self.active();
        if active.is_empty() {
            "none".into()
        } else {
            active.join(", ")
        }
    }
}

/// (major, minor) from a Mesa driver's `driverInfo` ("Mesa 22.3.6 (LLVM 15.0.6)").
pub(crate) fn mesa_version(driver_info: &str) -> Option<(u32, u32)> {
    let rest = driver_info.split("Mesa ").nth(1)?;
    let mut numbers = rest
        .split(|c: char| !c.is_ascii_digit())
        .map(str::parse::<u32>);
    match (numbers.next(), numbers.next()) {
        (Some(Ok(major)), Some(Ok(minor))) => Some((major, minor)),
        _ => None,
    }
}

/// How shaders trace rays against the draw's acceleration structures
/// (`VK_KHR_acceleration_structure`), which light between objects (SPEC §6) needs: ray queries
/// from the shading pass's fragment shader (`VK_KHR_ray_query`), or, on a device without them
/// that has ray-tracing pipelines (`VK_KHR_ray_tracing_pipeline`: NVIDIA's H100 and H200), the
/// same shading as a ray generation shader (shade_rt*.rgen). Without either shikki renders every
/// object as if alone.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RayQuery {
    /// Ray queries: the extensions and features are present and enabled on the device.
    Enabled,
    /// A ray-tracing pipeline traces instead: the device has no ray queries, or
    /// `SHIKKI_RAY_QUERY=pipeline` asked for this path.
    Pipeline,
    /// Present, but turned off (`SHIKKI_RAY_QUERY=0`, [`ContextOptions`](super::ContextOptions)).
    Disabled,
    /// Not available on this device: what it lacks.
    Missing(String),
}

impl RayQuery {
    /// Rays are traced, by ray queries or by a ray-tracing pipeline.
    pub fn is_enabled(&self) -> bool {
        matches!(self, RayQuery::Enabled | RayQuery::Pipeline)
    }

    /// Rays are traced by a ray-tracing pipeline (shade_rt*.rgen), not by ray queries.
    pub fn uses_pipeline(&self) -> bool {
        *self == RayQuery::Pipeline
    }

    /// One line for `shikki info`.
    pub fn summary(&self) -> String {
        match self {
            RayQuery::Enabled => "yes".into(),
            RayQuery::Pipeline => {
                "rays traced by a ray-tracing pipeline instead (VK_KHR_ray_tracing_pipeline)".into()
            }
            RayQuery::Disabled => "available, turned off (SHIKKI_RAY_QUERY=0)".into(),
            RayQuery::Missing(what) => format!("no ({what})"),
        }
    }

    /// What a program shows its user once when rays are off: which feature is missing and what
    /// to install. `None` when ray queries are enabled.
    pub fn warning(&self, device: &str) -> Option<String> {
        match self {
            RayQuery::Enabled | RayQuery::Pipeline => None,
            RayQuery::Disabled => Some(format!(
                "ray queries turned off by SHIKKI_RAY_QUERY=0 on {device}: objects are shaded \
                 without light between them (no shadows or inter-reflections)"
            )),
            RayQuery::Missing(what) => Some(format!(
                "{device} has no ray tracing ({what}): objects are shaded without light between \
                 them (no shadows or inter-reflections); install Mesa >= 24.1 lavapipe \
                 (./scripts/setup does) or a GPU driver with VK_KHR_ray_query or \
                 VK_KHR_ray_tracing_pipeline"
            )),
        }
    }
}

/// The device extensions ray queries need, in the order they are enabled.
pub(crate) const RAY_QUERY_EXTENSIONS: [&std::ffi::CStr; 3] = [
    ash::khr::deferred_host_operations::NAME,
    ash::khr::acceleration_structure::NAME,
    ash::khr::ray_query::NAME,
];

/// The device extensions the ray-tracing pipeline path needs, in the order they are enabled.
pub(crate) const RAY_PIPELINE_EXTENSIONS: [&std::ffi::CStr; 3] = [
    ash::khr::deferred_host_operations::NAME,
    ash::khr::acceleration_structure::NAME,
    ash::khr::ray_tracing_pipeline::NAME,
];

/// Which way of tracing rays a context may use (`SHIKKI_RAY_QUERY`, [`ContextOptions`]).
///
/// [`ContextOptions`]: super::ContextOptions
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RayTracingChoice {
    /// Ray queries where the device has them, else a ray-tracing pipeline where it has one.
    #[default]
    Auto,
    /// The ray-tracing pipeline even where ray queries exist (`SHIKKI_RAY_QUERY=pipeline`): the
    /// path of NVIDIA's H100/H200, which tests keep covered on lavapipe.
    Pipeline,
    /// No ray tracing (`SHIKKI_RAY_QUERY=0`).
    Off,
}

impl AdapterInfo {
    /// (major, minor) of the Mesa release in the driver's info string, for Mesa drivers.
    pub fn mesa_version(&self) -> Option<(u32, u32)> {
        mesa_version(&self.driver_info)
    }
}

pub(crate) struct ChosenAdapter {
    pub physical_device: vk::PhysicalDevice,
    pub queue_family: u32,
    pub info: AdapterInfo,
}

pub(crate) fn choose_adapter(
    instance: &ash::Instance,
    wanted: Option<&str>,
    choice: RayTracingChoice,
) -> Result<ChosenAdapter, GpuError> {
    // SAFETY: a plain query on a valid instance.
    let devices =
        unsafe { instance.enumerate_physical_devices() }.during("vkEnumeratePhysicalDevices")?;
    let mut candidates = Vec::new();
    let mut rejected = Vec::new();
    for physical_device in devices {
        let info = describe(instance, physical_device, choice)?;
        match suitability(instance, physical_device) {
            Ok(queue_family) => candidates.push(ChosenAdapter {
                physical_device,
                queue_family,
                info,
            }),
            Err(why) => rejected.push(format!("{} ({why})", info.name)),
        }
    }
    if let Some(wanted) = wanted {
        let needle = wanted.to_lowercase();
        let available: Vec<String> = candidates.iter().map(|c| c.info.name.clone()).collect();
        return candidates
            .into_iter()
            .find(|c| c.info.name.to_lowercase().contains(&needle))
            .ok_or_else(|| GpuError::DeviceNotFound {
                wanted: wanted.to_string(),
                available: if available.is_empty() {
                    "none".to_string()
                } else {
                    available.join(", ")
                },
            });
    }
    candidates.sort_by_key(|c| type_rank(&c.info.device_type));
    candidates
        .into_iter()
        .next()
        .ok_or_else(|| GpuError::NoDevice {
            detail: if rejected.is_empty() {
                String::new()
            } else {
                format!(" (unsuitable: {})", rejected.join("; "))
            },
        })
}

fn type_rank(device_type: &str) -> u8 {
    match device_type {
        "discrete GPU" => 0,
        "integrated GPU" => 1,
        "virtual GPU" => 2,
        "CPU" => 3,
        _ => 4,
    }
}

/// The queue family to use, or why this device cannot be used.
fn suitability(instance: &ash::Instance, device: vk::PhysicalDevice) -> Result<u32, String> {
    // SAFETY: plain queries on a valid physical device.
    let props = unsafe { instance.get_physical_device_properties(device) };
    if props.api_version < vk::API_VERSION_1_3 {
        return Err("Vulkan 1.3 required".into());
    }
    let mut features13 = vk::PhysicalDeviceVulkan13Features::default();
    let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut features13);
    // SAFETY: as above; `features` chains only structs that live on this stack frame.
    unsafe { instance.get_physical_device_features2(device, &mut features) };
    if features13.dynamic_rendering == vk::FALSE || features13.synchronization2 == vk::FALSE {
        return Err("dynamicRendering and synchronization2 required".into());
    }
    // SAFETY: as above.
    let families = unsafe { instance.get_physical_device_queue_family_properties(device) };
    let wanted = vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE;
    families
        .iter()
        .position(|f| f.queue_flags.contains(wanted) && f.queue_count > 0)
        .map(|i| i as u32)
        .ok_or_else(|| "no graphics+compute queue".to_string())
}

/// What the device lacks of the extensions and features ray queries (`pipeline` false) or the
/// ray-tracing pipeline path (`pipeline` true) need; `None` when nothing.
fn ray_tracing_lack(
    instance: &ash::Instance,
    device: vk::PhysicalDevice,
    pipeline: bool,
) -> Result<Option<String>, GpuError> {
    // SAFETY: plain query on a valid physical device.
    let extensions = unsafe { instance.enumerate_device_extension_properties(device) }
        .during("vkEnumerateDeviceExtensionProperties")?;
    let has = |name: &std::ffi::CStr| {
        extensions
            .iter()
            .any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == name))
    };
    let wanted = match pipeline {
        true => RAY_PIPELINE_EXTENSIONS,
        false => RAY_QUERY_EXTENSIONS,
    };
    let missing: Vec<String> = wanted
        .iter()
        .filter(|name| !has(name))
        .map(|name| name.to_string_lossy().into_owned())
        .collect();
    if !missing.is_empty() {
        return Ok(Some(format!("no {}", missing.join(", "))));
    }
    let mut features12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut acceleration = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default();
    let mut ray_query = vk::PhysicalDeviceRayQueryFeaturesKHR::default();
    let mut ray_pipeline = vk::PhysicalDeviceRayTracingPipelineFeaturesKHR::default();
    let mut features = vk::PhysicalDeviceFeatures2::default()
        .push_next(&mut features12)
        .push_next(&mut acceleration);
    features = match pipeline {
        true => features.push_next(&mut ray_pipeline),
        false => features.push_next(&mut ray_query),
    };
    // SAFETY: the chained structs live on this stack frame; their extensions are supported.
    unsafe { instance.get_physical_device_features2(device, &mut features) };
    let (geometry_shader, independent_blend) = (
        features.features.geometry_shader,
        features.features.independent_blend,
    );
    let lacking: Vec<&str> = [
        (features12.buffer_device_address, "bufferDeviceAddress"),
        (acceleration.acceleration_structure, "accelerationStructure"),
        match pipeline {
            true => (ray_pipeline.ray_tracing_pipeline, "rayTracingPipeline"),
            false => (ray_query.ray_query, "rayQuery"),
        },
        // The ray-traced G-buffer pass reads gl_PrimitiveID in its fragment shader.
        (geometry_shader, "geometryShader"),
        // The ray-traced shading pass has a second colour target (the integral image) that its
        // coverage draw leaves alone while writing the first.
        (independent_blend, "independentBlend"),
    ]
    .iter()
    .filter(|(value, _)| *value == vk::FALSE)
    .map(|(_, name)| *name)
    .collect();
    Ok((!lacking.is_empty()).then(|| format!("feature {} not supported", lacking.join(", "))))
}

/// How a device traces rays, given the choice and what it lacks for ray queries and for the
/// ray-tracing pipeline path (`None`: nothing).
fn ray_tracing_of(
    choice: RayTracingChoice,
    queries: Option<String>,
    pipeline: Option<String>,
) -> RayQuery {
    match (choice, queries, pipeline) {
        (RayTracingChoice::Auto, None, _) => RayQuery::Enabled,
        (RayTracingChoice::Auto | RayTracingChoice::Pipeline, _, None) => RayQuery::Pipeline,
        (RayTracingChoice::Off, None, _) | (RayTracingChoice::Off, _, None) => RayQuery::Disabled,
        // Asked for the pipeline on a device with ray queries only: say what it lacks.
        (RayTracingChoice::Pipeline, _, Some(what)) => RayQuery::Missing(what),
        (_, Some(what), Some(_)) => RayQuery::Missing(what),
    }
}

fn describe(
    instance: &ash::Instance,
    device: vk::PhysicalDevice,
    choice: RayTracingChoice,
) -> Result<AdapterInfo, GpuError> {
    let mut driver = vk::PhysicalDeviceDriverProperties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
    // SAFETY: plain query; the chained struct lives on this stack frame.
    unsafe { instance.get_physical_device_properties2(device, &mut props2) };
    let props = props2.properties;
    let limits = props.limits;
    let name = props
        .device_name_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|_| "(unnamed)".into());
    let driver_name = driver
        .driver_name_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let driver_info = driver
        .driver_info_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let v = props.api_version;
    let ray_query = ray_tracing_of(
        choice,
        ray_tracing_lack(instance, device, false)?,
        ray_tracing_lack(instance, device, true)?,
    );
    let quirks = Quirks::of_driver(driver.driver_id, &driver_info);
    Ok(AdapterInfo {
        name,
        device_type: super::conv::device_type_name(props.device_type).to_string(),
        driver_name,
        driver_info,
        api_version: format!(
            "{}.{}.{}",
            vk::api_version_major(v),
            vk::api_version_minor(v),
            vk::api_version_patch(v)
        ),
        max_image_dimension_2d: limits.max_image_dimension2_d,
        max_image_dimension_cube: limits.max_image_dimension_cube,
        max_compute_workgroup_invocations: limits.max_compute_work_group_invocations,
        max_storage_buffer_range: limits.max_storage_buffer_range,
        max_uniform_buffer_range: limits.max_uniform_buffer_range,
        max_texel_buffer_elements: limits.max_texel_buffer_elements,
        framebuffer_color_sample_counts: super::conv::sample_counts(
            limits.framebuffer_color_sample_counts & limits.framebuffer_depth_sample_counts,
        ),
        timestamp_period_ns: limits.timestamp_period,
        timestamp_compute_and_graphics: limits.timestamp_compute_and_graphics == vk::TRUE,
        pipeline_cache_id: (props.vendor_id, props.device_id, props.pipeline_cache_uuid),
        shader_float64: {
            // SAFETY: plain query on a valid physical device.
            let features = unsafe { instance.get_physical_device_features(device) };
            features.shader_float64 == vk::TRUE
        },
        ray_query,
        quirks,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ray queries first, the ray-tracing pipeline where they are missing (or asked for), off
    /// only when asked; what is missing names the ray queries' lack unless the pipeline was
    /// asked for.
    #[test]
    fn ray_tracing_prefers_queries_then_the_pipeline() {
        use RayTracingChoice::{Auto, Off, Pipeline};
        let lack = |what: &str| Some(what.to_string());
        let cases = [
            (Auto, None, None, RayQuery::Enabled),
            (Auto, None, lack("p"), RayQuery::Enabled),
            (Auto, lack("q"), None, RayQuery::Pipeline),
            (Auto, lack("q"), lack("p"), RayQuery::Missing("q".into())),
            (Pipeline, None, None, RayQuery::Pipeline),
            (Pipeline, lack("q"), None, RayQuery::Pipeline),
            (Pipeline, None, lack("p"), RayQuery::Missing("p".into())),
            (
                Pipeline,
                lack("q"),
                lack("p"),
                RayQuery::Missing("p".into()),
            ),
            (Off, None, lack("p"), RayQuery::Disabled),
            (Off, lack("q"), None, RayQuery::Disabled),
            (Off, lack("q"), lack("p"), RayQuery::Missing("q".into())),
        ];
        for (choice, queries, pipeline, expected) in cases {
            let got = ray_tracing_of(choice, queries.clone(), pipeline.clone());
            let traced = matches!(expected, RayQuery::Enabled | RayQuery::Pipeline);
            assert_eq!(got.is_enabled(), traced);
            assert_eq!(got, expected, "{choice:?} {queries:?} {pipeline:?}");
        }
    }

    const MESA_22: &str = "Mesa 22.3.6 (LLVM 15.0.6)";
    const MESA_25: &str = "Mesa 25.0.7-2~bpo12+1 (LLVM 15.0.6)";

    #[test]
    fn mesa_versions_are_read_from_driver_info() {
        assert_eq!(mesa_version(MESA_22), Some((22, 3)));
        assert_eq!(mesa_version(MESA_25), Some((25, 0)));
        assert_eq!(mesa_version("570.86.16"), None);
        assert_eq!(mesa_version("Mesa x"), None);
    }

    #[test]
    fn lavapipe_has_every_quirk_and_late_timestamps_only_before_mesa_25() {
        let old = Quirks::of_driver(vk::DriverId::MESA_LLVMPIPE, MESA_22);
        assert_eq!(old.active(), Quirks::NAMES);
        let new = Quirks::of_driver(vk::DriverId::MESA_LLVMPIPE, MESA_25);
        assert!(!new.late_timestamps_after_graphics);
        let all_but_timestamps: Vec<&str> = Quirks::NAMES
            .into_iter()
            .filter(|name| *name != "late_timestamps_after_graphics")
            .collect();
        assert_eq!(new.active(), all_but_timestamps);
    }

    #[test]
    fn other_drivers_keep_only_the_inverse_trig_quirk() {
        let gpu = Quirks::of_driver(vk::DriverId::NVIDIA_PROPRIETARY, "570.86.16");
        assert_eq!(gpu.summary(), "imprecise_inverse_trig");
        assert_eq!(Quirks::default().summary(), "none");
    }
}
