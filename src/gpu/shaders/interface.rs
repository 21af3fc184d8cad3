// The one declaration of everything the host and the shaders share: limits, workgroup sizes,
// binding numbers, specialization-constant ids and the layout of every buffer, push-constant and
// texel block. build.rs expands it into the GLSL header `interface.glsl` that the shaders
// `#include`; `gpu/shaders.rs` expands it into the Rust constants and `#[repr(C)]` structs below.
// build.rs refuses a struct whose Rust layout differs from its GLSL layout (std140/std430), and
// the tests in `gpu/shaders.rs` hold each block against the offsets in the compiled SPIR-V.
//
// The field types are GLSL's (float, int, uint, vec3, vec4, ivec4, uvec4, mat4, [T; N], or a
// struct declared above); each maps to one Rust type (f32, i32, u32, [f32; 3], …). Constants are
// integers, written into the header as `#define NAME value`.
//
// (No `//!` here: build.rs `include!`s this file.)

shader_interface! {
    constants {
        /// The most punctual lights one draw takes (the length of `Frame::light_vector`).
        MAX_LIGHTS: usize = 16;
        /// The most environment layers K a prefilter makes and a draw samples.
        MAX_ENV_LAYERS: usize = 20;
        /// The most bright parts of a map the `brdf` model takes out as directional lights
        /// (environment/bright.rs; `Frame::env_light_direction`).
        MAX_ENV_LIGHTS: usize = 16;
        /// The most lights of the rough split (environment/bright.rs `split_bright_rough`;
        /// `Frame::env_rough_light_*`). 128: a studio's light boxes at 1k in 71 blocks of 8 px
        /// (2.8°), which their spread keeps accurate down to m = 0.033; at 256 (199 blocks of
        /// 4 px) the default scene's lobes visit ~2.5× as many lights, +0.1 on its `brdf`/`paper`
        /// ratio (BENCHMARKS.md).
        ROUGH_MAX_ENV_LIGHTS: usize = 128;
        /// A bright light whose half vector has tan²θ_H > BRIGHT_LOBE_CULL·m² is skipped: D there
        /// is below e^-9 (1.2e-4) of its peak, and the lobe's share of slopes out there is e^-9
        /// of the whole (brdf_environment.glsl `bright_light`, its twin brdf_quadrature.rs
        /// `bright_specular`).
        BRIGHT_LOBE_CULL: u32 = 9;
        /// The rough split's lights are binned by direction on the cube, in cells of
        /// ENV_LIGHT_BIN_CELLS² per face (environment/light_bins.rs).
        ENV_LIGHT_BIN_CELLS: usize = 32;
        /// The `brdf` model's layer texels are stored two to an RGBA32UI texel, each channel in
        /// LAYER_CODE_BITS bits: an f32 less its sign and its 31 − LAYER_CODE_BITS lowest
        /// mantissa bits, rounded to nearest even (relative error ≤ 2⁻¹⁴), so that a bilinear
        /// lookup reads two texels, not four (shaders/common/layer_pair.glsl, its twin
        /// environment/layer_pair.rs; measured in BENCHMARKS.md). 21 is the most that fits: the
        /// second texel's three codes less the bits beside the first's must share one word.
        LAYER_CODE_BITS: u32 = 21;
        /// Knots of the specular directional albedo A(nv) the `brdf` model normalises by, at
        /// nv = (k/(ALBEDO_KNOTS − 1))² (environment/brdf_quadrature.rs `albedo_knots`).
        ALBEDO_KNOTS: usize = 65;
        /// The most MSAA samples per pixel the shading pass reads from the G-buffer.
        MAX_SAMPLES: u32 = 4;
        /// Lobe samples of filtered importance sampling in `paper`'s control variate of the light
        /// between objects (lacquer_shade.glsl `integral_environment`): the `brdf` model's
        /// quadrature as it was at 128 samples, the camera's configuration otherwise. The `brdf`
        /// model's own 1,024 (`BRDF_SAMPLES` then; 2,048 now) took a ray-traced `paper` render of a 512² m = 0.5
        /// sphere from 1.8 to 7.1 s on lavapipe.
        ENV_VARIATE_SAMPLES: u32 = 128;
        /// The golden fraction (√5 − 1)/2 in 32-bit fixed point: point i of the Fibonacci
        /// lattice of the `brdf` model's filtered importance sampling has the azimuth fraction
        /// given by the top 24 bits of i·FIBONACCI_STEP mod 2³², exact in f32 and f64 alike
        /// (brdf_quadrature.rs `fibonacci_point`). fract(i·0.618…) in f32 is off by up to 3e-5
        /// of a turn at i ≈ 1000, which put the shader 2e-4 from its twin at 1,024 samples.
        FIBONACCI_STEP: u32 = 2_654_435_769;
        /// Newton steps of the visible-normal sampler's slope inversion (visible_normals.glsl,
        /// oracle/visible_normals.rs): from its fitted first guess the CDF's residual is 1.8e-7
        /// after 4 (measured there); 10 leaves room for the steps that bisect.
        VISIBLE_SLOPE_STEPS: u32 = 10;

        /// `local_size_x` = `local_size_y` of every prefilter step (one workgroup: an 8 × 8 tile
        /// of one cube face).
        PREFILTER_WORKGROUP: u32 = 8;
        /// The most sub-samples a side step 1 takes per cube texel (params.rs
        /// `equirect_supersample`): its near pass keeps one bit per sub-sample, S² ≤ 256.
        MAX_STEP_ONE_SUPERSAMPLE: u32 = 16;
        /// `local_size_x` of brdf_eval.comp (one invocation per direction triple).
        BRDF_EVAL_WORKGROUP: u32 = 64;
        /// `local_size_x` = `local_size_y` of the denoise's steps (denoise_guide.comp,
        /// denoise_filter.comp: one invocation per pixel, 8 × 8 tiles).
        DENOISE_WORKGROUP: u32 = 8;

        /// The draw's set 0: the `Frame` uniform block.
        FRAME_BINDING: u32 = 0;
        /// The concatenated Fresnel tables, (angle_deg, r, g, b) per RGBA32F texel; the binding of
        /// `fresnel_knots` in every pipeline that includes lacquer_brdf.glsl.
        FRESNEL_KNOTS_BINDING: u32 = 1;
        /// The draw's environment layers (a sampler array of `MAX_ENV_LAYERS`).
        ENV_LAYERS_BINDING: u32 = 2;
        /// The draw's irradiance cube.
        ENV_IRRADIANCE_BINDING: u32 = 3;
        /// Every object's `ObjectMaterial`, `OBJECT_MATERIAL_TEXELS` RGBA32F texels each.
        OBJECT_MATERIAL_BINDING: u32 = 4;
        /// The G-buffer as the shading pass samples it: position + object, normal.
        GBUFFER_POSITION_BINDING: u32 = 5;
        GBUFFER_NORMAL_BINDING: u32 = 6;
        /// Every environment layer's cube texels, concatenated (layer k from
        /// `Frame::layer_first_texel[k]`), RGBA32F: what the `brdf` model's lobe samples read
        /// (brdf_environment.glsl).
        ENV_LAYER_TEXELS_BINDING: u32 = 7;
        /// The ray-traced shading pass (shade_rt*.frag): the draw's top-level acceleration
        /// structure, for SPEC §6's visibility.
        SCENE_TLAS_BINDING: u32 = 11;
        /// ... and per object an `ObjectGeometry` (ray_surface.glsl).
        OBJECT_GEOMETRY_BINDING: u32 = 12;
        /// Instance masks of the top-level structure (raster/self_hits.rs): a ray that cannot
        /// meet its own mesh again leaves that object's bit out of TRACE_MASK_ALL. Objects
        /// without a bit of their own (all but the first seven a ray can leave out) share
        /// TRACE_MASK_SHARED, which no ray leaves out.
        TRACE_MASK_ALL: u32 = 255;
        TRACE_MASK_SHARED: u32 = 128;
        /// `ObjectGeometry::clear_sides` bits (raster/self_hits.rs `SelfHits`): a ray leaving a
        /// face along its winding normal (front) or against it (back) never meets the mesh
        /// again.
        SELF_HITS_FRONT_CLEAR: u32 = 1;
        SELF_HITS_BACK_CLEAR: u32 = 2;
        /// The ray-tracing pipeline's shading (shade_rt*.rgen, where the device has no ray
        /// queries): the image and the integral image it writes as storage images, where the
        /// fragment shading pass writes colour attachments.
        SHADED_IMAGE_BINDING: u32 = 13;
        SHADED_INTEGRAL_BINDING: u32 = 14;

        /// A prefilter step's set 0: the cube (or, for step 1, the equirect) it reads as a texel
        /// buffer, the cube it writes, and step 1's near-edge list (`NearHeader`, then texels).
        PREFILTER_SOURCE_BINDING: u32 = 0;
        PREFILTER_DEST_BINDING: u32 = 1;
        NEAR_TEXELS_BINDING: u32 = 2;

        /// brdf_eval.comp's set 0 (its Fresnel table is at `FRESNEL_KNOTS_BINDING`).
        BRDF_EVAL_PARAMS_BINDING: u32 = 0;
        BRDF_EVAL_DIRECTIONS_BINDING: u32 = 2;
        BRDF_EVAL_VALUES_BINDING: u32 = 3;
        /// The denoise's set 0 (raster/draw/denoise.rs): the draw's image (read, then filtered
        /// in place), its integral image, and the guide the first step writes for the second.
        DENOISE_IMAGE_BINDING: u32 = 0;
        DENOISE_INTEGRAL_BINDING: u32 = 1;
        DENOISE_GUIDE_BINDING: u32 = 2;
        /// brdf_environment_eval.comp's set 0, beside the draw's frame (`FRAME_BINDING`), Fresnel
        /// knots (`FRESNEL_KNOTS_BINDING`) and layer texels (`ENV_LAYER_TEXELS_BINDING`).
        ENV_EVAL_PARAMS_BINDING: u32 = 8;
        ENV_EVAL_DIRECTIONS_BINDING: u32 = 9;
        ENV_EVAL_VALUES_BINDING: u32 = 10;

        /// mesh.vert's vertex attributes (`GpuMesh`'s interleaved vertex buffer).
        VERTEX_POSITION_LOCATION: u32 = 0;
        VERTEX_NORMAL_LOCATION: u32 = 1;

        /// The values of the `background_kind` specialization constant: what pixels no mesh
        /// covers show.
        BACKGROUND_COLOR: u32 = 0;
        BACKGROUND_ENVIRONMENT: u32 = 1;

    }

    specialization_constants {
        /// The fragment shaders' specialization constants, one 32-bit value each; a field's
        /// position is its `constant_id`, named `<FIELD>_ID` in the header.
        struct DrawConstants {
            /// K, the bound environment's layer count (`ENV_LAYER_COUNT`).
            env_layer_count,
            /// The G-buffer's samples per pixel (`SAMPLE_COUNT`).
            sample_count,
            /// `BACKGROUND_COLOR` or `BACKGROUND_ENVIRONMENT` (`BACKGROUND_KIND`).
            background_kind,
            /// Every Fresnel table of the draw has its knots on a power-of-two grid
            /// (`FRESNEL_POW2_GRID`, a VkBool32).
            fresnel_pow2_grid,
            /// The `brdf` model's lobe samples per point the camera sees (`ENV_SAMPLES`).
            env_samples,
            /// The same at the hits of the light between objects' paths (`ENV_HIT_SAMPLES`).
            env_hit_samples,
            /// The ray-traced shading pass traces shadow rays to the lights (`SHADOWS`, a
            /// VkBool32; SPEC §6's vis, else 1).
            shadows,
            /// ... and estimates SPEC §6's integral (`INTEGRAL`, a VkBool32: bounces ≥ 1), so a
            /// shadows-only pipeline keeps none of its code (llvmpipe runs a branch no lane takes).
            integral,
        }
    }

    blocks {
        /// One object's lacquer material (SPEC §2–4) as the shaders read it: `OBJECT_MATERIAL_TEXELS`
        /// RGBA32F texels per object in the draw's material buffer, and a member of brdf_eval.comp's
        /// uniform block. lacquer_brdf.glsl's `lacquer_params` is the one place that unpacks it.
        struct ObjectMaterial: texels std140 {
            /// Beckmann m of the lacquer's specular lobe.
            beckmann_m: float,
            /// a and b of the view factor f(nv) = a + b·nv, rounded to f32; the remainders are
            /// `diffuse_a_lo` and `diffuse_b_lo` (the shader evaluates a + b·nv compensated).
            diffuse_a: float,
            diffuse_b: float,
            /// g(r), evaluated on the host.
            lacquer_g: float,
            /// k_d.
            albedo: vec3,
            /// Knots in the object's Fresnel table (exact as a float: tables are short).
            fresnel_count: float,
            diffuse_a_lo: float,
            diffuse_b_lo: float,
            /// Index of the table's first knot among the draw's concatenated knots (exact as a
            /// float below 2^24, which the renderer checks).
            fresnel_first: float,
            /// Index of the first of the object's `ALBEDO_KNOTS` directional-albedo knots
            /// (nv, A_r, A_g, A_b) among the draw's knots (the `brdf` model; 0 in `paper`).
            albedo_first: float,
            /// SPEC §4's β(nv) = β_grazing + (β_normal − β_grazing)·nv^p.
            beta_normal: float,
            beta_grazing: float,
            beta_power: float,
            pad1: float,
        }

        /// brdf_eval.comp's uniform block.
        struct BrdfEvalParams: std140 {
            material: ObjectMaterial,
            /// x: the number of direction triples.
            row_count: uvec4,
        }

        /// What every object of a draw shares (frame.glsl's `frame`), std140.
        struct Frame: std140 {
            view_projection: mat4,
            /// xyz: the camera position.
            eye: vec4,
            /// x: the number of lights.
            light_count: ivec4,
            /// w = 0: directional, xyz towards the light; w = 1: point, xyz its position.
            light_vector: [vec4; MAX_LIGHTS],
            /// rgb: irradiance E (directional) or intensity I (point).
            light_color: [vec4; MAX_LIGHTS],
            /// x: 1 if an environment lights the scene; y: its number of layers K; z: its bright
            /// lights (the `brdf` model's, `env_light_*`).
            environment: ivec4,
            /// β_k, four per vec4.
            layer_beta: [vec4; MAX_ENV_LAYERS / 4],
            /// ln β_k for k ≥ 1 (0 where β_k ≤ 0): the shader interpolates layers linearly in ln β.
            layer_log_beta: [vec4; MAX_ENV_LAYERS / 4],
            /// Face size of layer k, and the index of its first texel at `ENV_LAYER_TEXELS_BINDING`
            /// (the `brdf` model's lookups), four per ivec4.
            layer_face_size: [ivec4; MAX_ENV_LAYERS / 4],
            layer_first_texel: [ivec4; MAX_ENV_LAYERS / 4],
            /// The layers' geometric run (SPEC §4: β_k = β_min·(β_max/β_min)^(…) from layer 1 on;
            /// the `brdf` model's fine layers continue it below β_min): x = ln β_1, y = 1/Δ with Δ
            /// the run's step in ln β, z = 1 where the β above are that run (raster/draw/frame.rs
            /// `geometric_run`), 0 otherwise; w unused. The `brdf` model's lookups find their
            /// layers from it without a search (frame.glsl `layer_pair_of_run`).
            layer_run: vec4,
            /// What the `brdf` model's blend in variance needs of the layers, packed once a draw
            /// (frame.rs `set_environment_layers`): x = layer 0's variance, its texels' read
            /// (params.rs `texel_read_variance`); y = e^(2Δ) − 1, the run's ratio of variances
            /// between neighbours less one; z, w unused.
            layer_variance: vec4,
            /// The camera basis (world), for the background's primary rays; `camera_back` is the
            /// negated view direction.
            camera_right: vec4,
            camera_up: vec4,
            camera_back: vec4,
            /// tan(fov/2), aspect W/H, width, height.
            camera_params: vec4,
            /// y: the image row of the render target's row 0 (tall images render in strips).
            strip_offset: vec4,
            /// x: object index + 1 in the G-buffer pass (0 elsewhere).
            draw_info: ivec4,
            /// The constant background (linear rgba; transparent is all 0).
            background_color: vec4,
            /// SPEC §6's integral in the ray-traced shading pass: x = rays per shaded point,
            /// y = bounces (0: none), z = the seed of the sample sequence.
            light_transport: ivec4,
            /// The `brdf` model's bright lights (environment/bright.rs), world frame: xyz towards
            /// the light and w its spread σ² (rad², `BrightLight::spread`); rgb its irradiance.
            /// The rough split's, `env_rough_light_*`, alike.
            env_light_direction: [vec4; MAX_ENV_LIGHTS],
            env_light_irradiance: [vec4; MAX_ENV_LIGHTS],
            /// The `brdf` model's plane-of-incidence lattice (environment/brdf_lattice.rs
            /// `LATTICE_*`, the taper brdf_quadrature.rs `LATTICE_TAPER`): spacing, reach, taper,
            /// most nodes on each side; the roughness bands (m_lo, m_hi) over which it hands over
            /// to the grid, and the grid to filtered importance sampling (`LATTICE_M_*`,
            /// `FIS_M_*`); and the deconvolved slope grid (`GRID`, and `VARIATE_GRID` for
            /// `paper`'s control variate): blur share t, spacing, reach, most nodes on each side
            /// along the plane.
            env_lattice: vec4,
            env_lattice_band: vec4,
            env_grid: vec4,
            env_variate_grid: vec4,
            /// The grids' blur share towards grazing (`GRID_GRAZING`): at least x up to nv = y,
            /// no floor from nv = z, a smoothstep between; w unused.
            env_grid_grazing: vec4,
            /// x: the lattice's blur share t (`LATTICE_BLUR_SHARE`); y: the least m whose lattice
            /// reads the rough split where the camera looks (brdf_quadrature.rs
            /// `rough_lattice_m`); z: the largest m the rough lights' direction bins serve (the
            /// draw's largest up to `LATTICE_M_LO`); w: the lattice's widest node step in σ_p
            /// (`LATTICE_MAX_STEP`).
            env_lattice_share: vec4,
            /// x: the share of the lobe's across-the-plane spread whose mean reflection each
            /// lattice node reads (brdf_lattice.rs `LATTICE_ACROSS_MEAN`); y: the least share of
            /// the lattice's β a node's own blur takes (`LATTICE_NODE_BLUR_FLOOR`); z, w: the nv
            /// band over which the nodes' own widths fade out (`LATTICE_OWN_WIDTHS`).
            env_lattice_across: vec4,
            /// The rough materials' bright split (environment/bright.rs `split_bright_rough`),
            /// which the grid and filtered importance sampling read where the camera looks (and
            /// the lattice, from env_lattice_share.y up): x the
            /// index of its residual's first texel at `ENV_LAYER_TEXELS_BINDING` (its layers are
            /// laid out as the residual's, after them), y its number of lights, z the first texel
            /// of its lights' direction bins at `FRESNEL_KNOTS_BINDING` (environment/
            /// light_bins.rs).
            env_rough: ivec4,
            /// The lattice's sharp reads of the residuals' own pixels (environment/
            /// sharp_source.rs): x the first texel of the residual's pixels at
            /// `ENV_LAYER_TEXELS_BINDING` (after every layer), y the rough residual's (−1: none,
            /// the layers alone), z the map's width, w its height.
            env_sharp: ivec4,
            /// x `SHARP_SIGMA`, y `SHARP_REACH`, z and w `SHARP_NODES`; the environment's rotation
            /// is `env_sharp_rotation` (cos ρ, sin ρ).
            env_sharp_read: vec4,
            env_sharp_rotation: vec4,
            env_rough_light_direction: [vec4; ROUGH_MAX_ENV_LIGHTS],
            env_rough_light_irradiance: [vec4; ROUGH_MAX_ENV_LIGHTS],
        }

        /// Step 1's push constants (equirect_to_cube*.comp).
        struct EquirectToCubeParams: push_constant {
            src_width: uint,
            src_height: uint,
            face_size: uint,
            intensity: float,
            /// cos ρ and sin ρ of the environment's rotation ρ about +Y.
            rotation_cos: float,
            rotation_sin: float,
            /// S: each cube texel averages S × S sub-samples (`params::equirect_supersample`).
            supersample: uint,
        }

        /// The head of step 1's near-edge list: how many texels it holds, then the near pass's
        /// indirect dispatch (groups of `PREFILTER_WORKGROUP`² texels); the texel indices follow.
        struct NearHeader: std430 {
            count: uint,
            dispatch_x: uint,
            dispatch_y: uint,
            dispatch_z: uint,
        }

        /// Per object of a ray-traced draw (`OBJECT_GEOMETRY_BINDING`, ray_surface.glsl).
        struct ObjectGeometry: std430 {
            /// Its mesh's vertex and index buffer addresses: (vertices low, high, indices low,
            /// high) words.
            addresses: uvec4,
            /// `SELF_HITS_FRONT_CLEAR` | `SELF_HITS_BACK_CLEAR` of its mesh, or 0.
            clear_sides: uint,
            /// Its instance mask bit that its own rays leave out where its mesh is convex on
            /// their side; 0 where none.
            own_mask: uint,
            unused0: uint,
            unused1: uint,
        }

        /// The apron pass's push constants (layer_apron.comp): one layer of face size M, read
        /// from the unpadded texels at `source_first`, written with its apron at `dest_first`.
        struct LayerApronParams: push_constant {
            face_size: uint,
            source_first: uint,
            dest_first: uint,
        }

        /// Step 2's push constants (downsample.comp).
        struct DownsampleParams: push_constant {
            /// The face size written (half the one read).
            dst_face_size: uint,
        }

        /// The denoise's push constants (raster/draw/denoise.rs `DenoiseParams::new`, the host
        /// filter's constants).
        struct DenoiseParams: push_constant {
            /// Width, height, the filter's radius in pixels, 0.
            size: uvec4,
            /// 1/(2σ²) of the spatial Gaussian; 1/(2·tolerance²) of the guide; 2·k² of the
            /// estimate's edge test; the largest −ln w a neighbour keeps.
            weights: vec4,
        }

        /// Step 3's push constants (prefilter_layers.comp).
        struct BlurLayerParams: push_constant {
            face_size: uint,
            beta: float,
            /// `params::LOBE_CUTOFF`: texels with q > cutoff·β² are skipped.
            cutoff: float,
        }

        /// The ray-tracing pipeline's shading (shade_rt*.rgen): the target texel of launch (0, 0),
        /// the corner of the strip's shaded rectangle.
        struct TraceOrigin: push_constant {
            origin_x: int,
            origin_y: int,
        }

        /// Step 4's push constants (irradiance.comp).
        struct IrradianceParams: push_constant {
            face_size: uint,
        }
    }
}
