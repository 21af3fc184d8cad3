//! What each subcommand does, in terms of the library.

use super::args::{
    Backend, BrdfArgs, Cli, Command, EnvironmentArgs, MaterialArgs, PrefilterArgs, RenderArgs,
};
use super::directions;
use super::scene_cmd;
use crate::compute::BrdfEvaluator;
use crate::environment::gpu::{default_params, GpuPrefilter};
use crate::environment::load::{environment_file, load_environment, LoadedEnvironment};
use crate::environment::{EnvironmentLight, EnvironmentSource, PrefilterParams};
use crate::model::{lacquer_brdf, LacquerMaterial};
use crate::output::{self, PngSettings};
use crate::raster::camera::Camera;
use crate::raster::lights::{default_lights, Light, MAX_LIGHTS};
use crate::raster::mesh::BuiltinMesh;
use crate::scene::{EnvironmentSpec, MeshSource, OutputSpec, RenderSpec, Scene, SceneObject};
use crate::{Error, Result, Warning};
use glam::{DMat4, DVec3};
use std::io::Write;

pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        None => scene_cmd::render_default(&RenderArgs::default()),
        Some(Command::Render(args)) => match &args.scene {
            Some(path) => {
                // --env-model, --no-shadows and --no-ray-tracing are `[render]` scene paths.
                let mut sets = args.material.set.clone();
                sets.extend(args.render_overrides());
                scene_cmd::render_scene_file(path, &sets, &args.output)
            }
            None if scene_cmd::wants_default_scene(&args) => scene_cmd::render_default(&args),
            None => render(args),
        },
        Some(Command::Batch(args)) => scene_cmd::run_batch(args),
        Some(Command::Bench(args)) => super::bench::run_bench(args),
        Some(Command::Brdf(args)) => brdf(args),
        Some(Command::Fresnel(args)) => fresnel(args),
        Some(Command::Info) => info(),
        Some(Command::Prefilter(args)) => prefilter(args),
        Some(Command::Fit(args)) => super::fit::run_fit(args),
        Some(Command::Synth(args)) => super::fit::run_synth(args),
        Some(Command::Mesh(args)) => super::mesh_cmd::run_mesh(args),
    }
}

/// The preset, then every `--set KEY=VALUE` in order, then full validation.
pub fn build_material(args: &MaterialArgs) -> Result<LacquerMaterial> {
    let mut material = match &args.material {
        Some(path) => crate::model::material_file::load_material_file(path)?,
        None => LacquerMaterial::preset(&args.preset)?,
    };
    for assignment in &args.set {
        let (key, value) = assignment.split_once('=').ok_or_else(|| {
            Error::invalid(
                "--set",
                assignment,
                "expected KEY=VALUE, e.g. --set m=0.1 or --set kd=0.5,0.06,0.03",
            )
        })?;
        material.set(key.trim(), value.trim())?;
    }
    material.validate()?;
    Ok(material)
}

/// A camera that frames the chosen built-in mesh, with the user's overrides applied.
fn camera_for(mesh: BuiltinMesh, args: &RenderArgs) -> Result<Camera> {
    let mut camera = Camera::default();
    match mesh {
        // The board lies in the XZ plane: look down at it at 45° rather than edge-on.
        BuiltinMesh::Board => camera.eye = DVec3::new(0.0, 3.0, 3.0),
        // Bowl and plate stand on y = 0: look slightly down into them.
        BuiltinMesh::Bowl | BuiltinMesh::Plate => {
            camera.eye = DVec3::new(0.0, 2.2, 3.2);
            camera.target = DVec3::new(0.0, 0.3, 0.0);
            camera.fov_deg = 30.0;
        }
        BuiltinMesh::Sphere => {}
    }
    if let Some(eye) = args.eye {
        camera.eye = eye;
    }
    if let Some(target) = args.target {
        camera.target = target;
    }
    if let Some(fov) = args.fov {
        camera.fov_deg = fov;
    }
    camera.validate()?;
    Ok(camera)
}

/// The `--light` values: none given → the default rig; `none` alone → no lights; otherwise each
/// parsed.
fn lights_from(specs: &[String]) -> Result<Vec<Light>> {
    if specs.is_empty() {
        return Ok(default_lights());
    }
    let is_none = |s: &String| s.trim().eq_ignore_ascii_case("none");
    if specs.iter().any(is_none) {
        if specs.len() > 1 {
            return Err(Error::invalid(
                "--light",
                specs.join(" "),
                "`none` turns every light off and cannot be combined with other --light values; \
                 give either --light none or only dir:/point: lights",
            ));
        }
        return Ok(Vec::new());
    }
    if specs.len() > MAX_LIGHTS {
        return Err(Error::invalid(
            "--light",
            format!("{} lights", specs.len()),
            format!("at most {MAX_LIGHTS} lights"),
        ));
    }
    specs
        .iter()
        .map(|s| {
            Light::parse(s).map_err(|e| match e {
                Error::InvalidParameter {
                    field,
                    value,
                    reason,
                } => Error::InvalidParameter {
                    field,
                    value,
                    reason: format!("{reason}; or `--light none` (alone) for no lights"),
                },
                other => other,
            })
        })
        .collect()
}

/// The flag form of `shikki render`: the scene the flags describe, rendered like any other.
fn render(args: RenderArgs) -> Result<()> {
    let scene = scene_from_flags(&args);
    let preset = &args.material.preset;
    // The map `--env` names, even if the scene fails to build: never written over or removed.
    let inputs: Vec<_> = environment_file(&args.environment.env)
        .map(std::path::Path::to_path_buf)
        .into_iter()
        .collect();
    scene_cmd::render_built_scene(scene, &args.output, &inputs, |scene, device| {
        let out = &scene.output;
        format!(
            "{}x{}, {} sample(s), {preset} on {device}",
            out.width, out.height, out.samples
        )
    })
}

/// The [`Scene`] of `shikki render --mesh … --preset … --light … --env …`: one object (the
/// built-in mesh, unmoved, with the material of the flags), the camera that frames it, the
/// lights, the environment and the output settings.
fn scene_from_flags(args: &RenderArgs) -> Result<Scene> {
    let material = build_material(&args.material)?;
    // Checked now, before the GPU is opened, as every other flag is.
    material.brdf_params()?;
    material.fresnel_table()?;
    let builtin = BuiltinMesh::parse(&args.mesh)?;
    let camera = camera_for(builtin, args)?;
    let lights = lights_from(&args.lights)?;
    if !args.exposure.is_finite() {
        return Err(Error::invalid(
            "--exposure",
            args.exposure,
            "must be a finite number of EV",
        ));
    }
    Ok(Scene {
        camera,
        objects: vec![SceneObject {
            mesh: MeshSource::Builtin(builtin),
            transform: DMat4::IDENTITY,
            material,
        }],
        lights,
        environment: environment_from_flags(&args.environment),
        render: {
            let mut spec = RenderSpec::default();
            args.apply_render_overrides(&mut spec);
            spec
        },
        output: OutputSpec {
            width: args.size.0,
            height: args.size.1,
            samples: args.samples,
            exposure_ev: args.exposure,
            tone_curve: args.tonemap,
            background: args.background,
        },
    })
}

/// `--env none` or a map with `--env-intensity` and `--env-rotation`; the map is loaded (and
/// its errors reported) when the renderer prepares it.
fn environment_from_flags(args: &EnvironmentArgs) -> EnvironmentSpec {
    if args.env.trim().eq_ignore_ascii_case("none") {
        return EnvironmentSpec::None;
    }
    EnvironmentSpec::Map {
        source: EnvironmentSource::Named(args.env.clone()),
        light: EnvironmentLight {
            intensity: args.intensity,
            rotation_deg: args.rotation_deg,
        },
    }
}

fn warn_replaced(loaded: &LoadedEnvironment) {
    if loaded.replaced_pixels > 0 {
        super::print_warnings([Warning::ReplacedPixels {
            environment: loaded.source.clone(),
            count: loaded.replaced_pixels,
        }]);
    }
}

/// `shikki prefilter`: its files in the output directory are this run's alone. A run that fails
/// removes those of an earlier run (they would pass for its output), and one that succeeds the
/// layers past its own K (a run at K = 17 then at K = 2 left layer_2 … layer_16 beside the new
/// ones; found by a probe, 2026-12-06).
fn prefilter(args: PrefilterArgs) -> Result<()> {
    let result = prefilter_into(&args);
    let keep = match &result {
        Ok(layers) => *layers,
        Err(_) => 0,
    };
    let mut stale = stale_prefilter_files(&args.output, keep);
    if result.is_err() {
        stale.extend(["irradiance.exr", "preview.png"].map(|f| args.output.join(f)));
    }
    for path in stale {
        super::remove_earlier_output(&path);
    }
    result.map(|_| ())
}

/// `layer_K.exr` files in `dir` with K ≥ `keep`.
fn stale_prefilter_files(dir: &std::path::Path, keep: usize) -> Vec<std::path::PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    entries
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|path| {
            let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
            let layer = name
                .strip_prefix("layer_")
                .and_then(|rest| rest.strip_suffix(".exr"))
                .and_then(|k| k.parse::<usize>().ok());
            layer.is_some_and(|k| k >= keep)
        })
        .collect()
}

/// The prefilter's work; the number of layers written.
fn prefilter_into(args: &PrefilterArgs) -> Result<usize> {
    let loaded = load_environment(&args.env)?;
    warn_replaced(&loaded);
    let mut params = PrefilterParams::for_source_width(loaded.image.width);
    if let Some(face) = args.face_size {
        params.face_size = face;
    }
    params.layers = args.layers;
    params.beta_min = args.beta_min;
    params.beta_max = args.beta_max;
    params.validate()?;
    let light = EnvironmentLight::new(args.intensity, args.rotation_deg);
    light.check_levels(&loaded.image, &args.env)?;
    std::fs::create_dir_all(&args.output).map_err(|e| Error::Write {
        path: args.output.clone(),
        message: format!("cannot create the output directory: {e}"),
    })?;
    let gpu = super::open_gpu_tracing(false)?;
    if args.face_size.is_none() {
        params.face_size = default_params(&gpu, loaded.image.width).face_size;
    }
    let env = GpuPrefilter::new(&gpu)?.run(&gpu, &loaded.image, &params, light)?;
    let cubes = env.read_back(&gpu)?;
    gpu.check_validation()?;
    let linear = PngSettings::default();
    for (k, layer) in cubes.layers.iter().enumerate() {
        let path = args.output.join(format!("layer_{k}.exr"));
        output::write_image(&path, &layer.to_strip(), &linear)?;
    }
    output::write_image(
        &args.output.join("irradiance.exr"),
        &cubes.irradiance.to_strip(),
        &linear,
    )?;
    let preview = crate::environment::preview::preview_image(&cubes)?;
    output::atomic::write_atomically(&args.output.join("preview.png"), &preview)?;
    eprintln!(
        "wrote {} layers (face {}), irradiance and preview.png to {}",
        cubes.layers.len(),
        params.face_size,
        args.output.display()
    );
    Ok(cubes.layers.len())
}

fn brdf(args: BrdfArgs) -> Result<()> {
    let material = build_material(&args.material)?;
    let params = material.brdf_params()?;
    let fresnel = material.fresnel_table()?;
    let text = crate::text::read_text_file(
        &args.input,
        directions::MAX_DIRECTIONS_CSV_BYTES,
        "directions CSV",
    )?;
    let rows = directions::parse_directions(&text, &args.input.display().to_string())?;
    let values: Vec<[f64; 3]> = match args.backend {
        Backend::Cpu => rows
            .iter()
            .map(|[n, v, l]| lacquer_brdf(&params, &fresnel, *n, *v, *l))
            .collect(),
        Backend::Gpu => {
            let gpu = super::open_gpu_tracing(false)?;
            let evaluator = BrdfEvaluator::new(&gpu)?;
            let values = evaluator.evaluate(&gpu, &params, &fresnel, &rows)?;
            gpu.check_validation()?;
            values.iter().map(|v| v.map(f64::from)).collect()
        }
    };
    let mut out = String::with_capacity(rows.len() * 200);
    out.push_str(directions::HEADER);
    out.push_str(",r,g,b\n");
    for (triple, rgb) in rows.iter().zip(values) {
        out.push_str(&directions::format_row(triple, rgb));
        out.push('\n');
    }
    write_stdout(&out)
}

fn fresnel(args: MaterialArgs) -> Result<()> {
    let material = build_material(&args)?;
    write_stdout(&material.fresnel_table()?.to_csv())
}

fn info() -> Result<()> {
    let gpu = super::open_gpu()?;
    let i = gpu.info();
    let text = format!(
        "device:               {}\n\
         type:                 {}\n\
         driver:               {} ({})\n\
         Vulkan:               {}\n\
         validation:           {}\n\
         max image 2D:         {}\n\
         max image cube:       {}\n\
         max compute threads:  {}\n\
         max storage buffer:   {} bytes\n\
         max uniform buffer:   {} bytes\n\
         max texel buffer:     {} texels\n\
         MSAA sample counts:   {:?}\n\
         timestamps:           {} (period {} ns)\n\
         ray queries:          {}\n\
         driver quirks:        {}\n",
        i.name,
        i.device_type,
        i.driver_name,
        i.driver_info,
        i.api_version,
        if gpu.validation_enabled() {
            "on"
        } else {
            "off (SHIKKI_VALIDATION=1 to enable)"
        },
        i.max_image_dimension_2d,
        i.max_image_dimension_cube,
        i.max_compute_workgroup_invocations,
        i.max_storage_buffer_range,
        i.max_uniform_buffer_range,
        i.max_texel_buffer_elements,
        i.framebuffer_color_sample_counts,
        if i.timestamp_compute_and_graphics {
            "yes"
        } else {
            "no"
        },
        i.timestamp_period_ns,
        i.ray_query.summary(),
        i.quirks.summary(),
    );
    write_stdout(&text)
}

/// Writes to stdout; a closed pipe (`shikki brdf … | head`) is not an error worth a panic.
pub(super) fn write_stdout(text: &str) -> Result<()> {
    let mut stdout = std::io::stdout().lock();
    match stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
    {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => Err(Error::Write {
            path: "stdout".into(),
            message: e.to_string(),
        }),
    }
}
