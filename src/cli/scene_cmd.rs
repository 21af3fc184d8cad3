//! `shikki render` in every form (flags, a scene file, the default scene) and `shikki batch`:
//! argument handling only. Every render form builds a `Scene` and goes through
//! [`render_built_scene`]; the scene schema, renderer and batch runner live in `crate::scene`.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::args::{BatchArgs, RenderArgs};
use super::fit::same_file;
use crate::environment::load;
use crate::environment::EnvironmentSource;
use crate::output::{self, OutputFormat, PngSettings};
use crate::scene::batch::{self, BatchOptions, BatchPlan};
use crate::scene::{default_scene, EnvironmentSpec, Scene, SceneDocument, SceneRenderer};
use crate::{Error, Result};

/// Whether `shikki render` was given no scene and nothing that describes one (mesh, preset,
/// material file, camera, lights, environment, background): then it renders [`default_scene`]. Output flags
/// (-o, --size, --samples, --exposure, --tonemap) and the `[render]` flags (--env-model,
/// --no-shadows, --no-ray-tracing) still apply.
pub fn wants_default_scene(args: &RenderArgs) -> bool {
    let d = RenderArgs::default();
    args.scene.is_none()
        && args.mesh == d.mesh
        && args.material.preset == d.material.preset
        && args.material.material.is_none()
        && args.material.set.is_empty()
        && args.eye.is_none()
        && args.target.is_none()
        && args.fov.is_none()
        && args.lights.is_empty()
        && args.environment.env == d.environment.env
        && args.environment.intensity == d.environment.intensity
        && args.environment.rotation_deg == d.environment.rotation_deg
        && args.background == d.background
}

/// The default scene at the size, samples, exposure and tone curve of `args`, to `args.output`.
pub fn render_default(args: &RenderArgs) -> Result<()> {
    let mut scene = default_scene();
    scene.output.width = args.size.0;
    scene.output.height = args.size.1;
    scene.output.samples = args.samples;
    scene.output.exposure_ev = args.exposure;
    scene.output.tone_curve = args.tonemap;
    args.apply_render_overrides(&mut scene.render);
    render_built_scene(Ok(scene), &args.output, &[], scene_summary)
}

/// `shikki render SCENE.toml [--set path=value]… [-o FILE]`. `--set` paths are scene paths
/// (`camera.fov_deg=30`, `object.0.material.r=2`, `material.preset=rough-red` for every object);
/// with `[output] format = "exr"` and no `-o`, the file is shikki.exr.
pub fn render_scene_file(scene_path: &Path, sets: &[String], output_path: &Path) -> Result<()> {
    // The map the scene reads, known from the file even if the scene does not build.
    let document = SceneDocument::load(scene_path);
    let inputs: Vec<PathBuf> = document
        .as_ref()
        .ok()
        .and_then(|d| d.environment_file())
        .into_iter()
        .collect();
    let built = document.and_then(|document| scene_and_path(document, sets, output_path));
    match built {
        Ok((scene, path)) => render_built_scene(Ok(scene), &path, &inputs, scene_summary),
        Err(error) => {
            // The scene failed before its output path (and format) was known: with no `-o` an
            // `[output] format = "exr"` scene writes shikki.exr.
            let mut stale = vec![output_path.to_path_buf()];
            if output_path == Path::new(DEFAULT_OUTPUT) {
                stale.push(output_path.with_extension("exr"));
            }
            for path in stale {
                discard_stale(&path, &inputs);
            }
            Err(error)
        }
    }
}

/// `-o`'s default.
const DEFAULT_OUTPUT: &str = "shikki.png";

fn scene_and_path(
    mut document: SceneDocument,
    sets: &[String],
    output_path: &Path,
) -> Result<(Scene, PathBuf)> {
    for assignment in sets {
        document.set(assignment, Path::new(""))?;
    }
    let scene = document.build()?;
    let format = document.output_format()?;
    let mut path = output_path.to_path_buf();
    if format == OutputFormat::Exr && path == Path::new(DEFAULT_OUTPUT) {
        path.set_extension("exr");
    }
    Ok((scene, path))
}

/// What `wrote PATH (…)` says of a scene, given the device's name.
fn scene_summary(scene: &Scene, device: &str) -> String {
    format!(
        "{}x{}, {} object(s), {} sample(s) on {device}",
        scene.output.width,
        scene.output.height,
        scene.objects.len(),
        scene.output.samples
    )
}

/// Renders `scene` (or reports why it could not be built) to `path`, format by extension, then
/// prints `wrote PATH (summary)`. A failure leaves no file at `path`: a file there from an
/// earlier run would pass for this run's result (batch users check for existence), so it is
/// removed, and the CLI says so. `inputs` are files the render reads (its environment map): one
/// named as the output is refused before anything is rendered, and never removed.
pub fn render_built_scene(
    scene: Result<Scene>,
    path: &Path,
    inputs: &[PathBuf],
    summary: impl FnOnce(&Scene, &str) -> String,
) -> Result<()> {
    let inputs = match &scene {
        Ok(scene) => [inputs.to_vec(), map_file(scene).into_iter().collect()].concat(),
        Err(_) => inputs.to_vec(),
    };
    if let Some(input) = inputs.iter().find(|input| same_file(path, input)) {
        return Err(Error::invalid(
            "output path",
            path.display(),
            format!(
                "it is the environment map this render reads ({}); write the image to \
                 another file",
                input.display()
            ),
        ));
    }
    let result = scene.and_then(|scene| render_and_write(&scene, path, summary));
    if result.is_err() {
        discard_stale(path, &inputs);
    }
    result
}

/// The environment map `scene` reads from a file, if it reads one.
fn map_file(scene: &Scene) -> Option<PathBuf> {
    match &scene.environment {
        EnvironmentSpec::Map {
            source: EnvironmentSource::Named(name),
            ..
        } => load::environment_file(name).map(Path::to_path_buf),
        _ => None,
    }
}

/// Removes an earlier run's image at `path` after a failure, and says so. Only what this command
/// writes is ever removed: a path without a .png or .exr extension was refused, not written, and
/// is left alone, as is an input of the render (an .exr environment map).
fn discard_stale(path: &Path, inputs: &[PathBuf]) {
    if OutputFormat::from_path(path).is_ok() && !inputs.iter().any(|i| same_file(path, i)) {
        super::remove_earlier_output(path);
    }
}

/// Renders and writes. The renderer's warnings are printed whether or not the render succeeded
/// (one may explain the failure).
fn render_and_write(
    scene: &Scene,
    path: &Path,
    summary: impl FnOnce(&Scene, &str) -> String,
) -> Result<()> {
    output::preflight_output(path)?;
    let png = PngSettings {
        exposure_ev: scene.output.exposure_ev,
        tone_curve: scene.output.tone_curve,
    };
    png.validate()?;
    let gpu = super::open_gpu_tracing(scene.render.ray_tracing_asked().is_some())?;
    let mut renderer = SceneRenderer::new(&gpu)?;
    // One render in this process: its pipelines build while the environment is prepared.
    renderer.set_pipelines_on_a_thread(true);
    let image = renderer.render(&gpu, scene);
    super::print_warnings(renderer.take_warnings());
    output::write_image(path, &image?, &png)?;
    eprintln!(
        "wrote {} ({})",
        path.display(),
        summary(scene, &gpu.info().name)
    );
    Ok(())
}

/// The exit code of a batch stopped by Ctrl-C (SIGINT): 128 + 2, the shell's convention.
pub const EXIT_INTERRUPTED: i32 = 130;

/// `shikki batch`: exit code ≠ 0 if any job failed (after all others ran). The first SIGINT stops
/// the batch after the image in flight (manifest and contact sheet written, exit
/// [`EXIT_INTERRUPTED`]); a second one exits at once (outputs are atomic: no partial file).
pub fn run_batch(args: BatchArgs) -> Result<()> {
    let plan = BatchPlan::load(&args.jobs)?;
    let shard = args.shard.unwrap_or((0, 1));
    let gpu = super::open_gpu_tracing(plan.may_trace())?;
    let mut options = BatchOptions::new(args.out.clone());
    options.shard = shard;
    options.force = args.force;
    options.observer = Arc::new(TerminalProgress::new(!args.quiet));
    watch_interrupts(&options.cancel);
    let summary = batch::run_batch(&gpu, &plan, &options)?;
    eprintln!(
        "batch: {} rendered, {} skipped (already done), {} failed; {} and {}",
        summary.rendered,
        summary.skipped,
        summary.failed,
        summary.manifest.display(),
        summary.contact_sheet.display()
    );
    if summary.cancelled {
        eprintln!(
            "interrupted: {} job(s) not started; run the same command again to resume (finished \
             jobs are skipped)",
            summary.not_started
        );
        // Saves the pipeline cache: process::exit runs no destructors.
        drop(gpu);
        // The CLI maps every error to exit code 1; a script must be able to tell an interrupted
        // batch from a failed one.
        std::process::exit(EXIT_INTERRUPTED);
    }
    if summary.failed > 0 {
        return Err(Error::invalid(
            "batch",
            format!("{} failed job(s)", summary.failed),
            "each failure is printed above and recorded in the manifest's status column; fix \
             the jobs file and run the same command again (finished jobs are skipped)",
        ));
    }
    Ok(())
}

/// SIGINT sets `cancel`; a second SIGINT (cancel already set) exits with [`EXIT_INTERRUPTED`] at
/// once. Without a handler, Ctrl-C still kills the batch with nothing partial left behind.
fn watch_interrupts(cancel: &Arc<AtomicBool>) {
    use signal_hook::consts::SIGINT;
    // Registered first, so it sees the flag as it was before this signal set it.
    let second = signal_hook::flag::register_conditional_shutdown(
        SIGINT,
        EXIT_INTERRUPTED,
        Arc::clone(cancel),
    );
    let first = signal_hook::flag::register(SIGINT, Arc::clone(cancel));
    if let Err(e) = second.and(first) {
        eprintln!("warning: cannot handle Ctrl-C ({e}); it will stop the batch at once");
    }
}

/// The batch's progress on stderr: a bar (when asked for and stderr is a terminal) with the run's
/// warning and error lines printed above it.
#[derive(Debug)]
struct TerminalProgress {
    bar: ProgressBar,
}

impl TerminalProgress {
    fn new(wanted: bool) -> Self {
        let bar = if wanted && std::io::stderr().is_terminal() {
            let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
            if let Ok(style) = ProgressStyle::with_template(
                "{bar:40} {pos}/{len} jobs  {per_sec}  ETA {eta}  {msg}",
            ) {
                bar.set_style(style);
            }
            bar
        } else {
            ProgressBar::hidden()
        };
        Self { bar }
    }
}

impl batch::BatchObserver for TerminalProgress {
    fn start(&self, jobs: usize) {
        self.bar.set_length(jobs as u64);
    }
    fn job_done(&self) {
        self.bar.inc(1);
    }
    fn line(&self, text: &str) {
        self.bar.suspend(|| eprintln!("{text}"));
    }
    fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
