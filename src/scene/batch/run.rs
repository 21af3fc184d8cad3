//! Executes a [`BatchPlan`]: one GPU context and one [`SceneRenderer`] for the whole run; the
//! render thread hands each image to the encoders (a bounded channel; [`super::encoders`]: one
//! thread, or several on a machine with the cores), which encode and write it and make its
//! contact-sheet tile, and a writer thread records the manifest in job order, so encoding
//! overlaps the next render.
//! Before the output directory is even created, [`BatchPlan::check_outputs`] refuses a plan in
//! which two jobs would share a file.
//!
//! A failed job is reported, recorded (`failed: …` in the manifest, a red tile) and leaves no
//! output file; the run continues and [`BatchSummary::failed`] makes the exit code non-zero. That
//! includes a job whose file cannot be written (a full disk, a directory in the way): every file
//! goes through [`super::sink`], atomically.
//!
//! Cancellation ([`BatchOptions::cancel`], set by the CLI's SIGINT handler): the render thread
//! takes no new job, the writer finishes the images already rendered, and the manifest and
//! contact sheet describe what finished, so the same command resumes.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc, Mutex};

use super::encoders::{encode_loop, encoder_count, in_order, message_bytes, InFlight, Written};
use super::manifest::{self, Manifest, ManifestRow, STATUS_OK};
use super::sheet::{contact_sheet_png, Thumbnail, Tile};
use super::sink::{self, FileSystem, OutputSink};
use super::{in_shard, BatchPlan, JobSpec, PreparedJob};
use crate::gpu::GpuContext;
use crate::output::{self, HdrImage, OutputFormat, PngSettings};
use crate::scene::SceneRenderer;
use crate::{Error, Result};

/// Images waiting for an encoder; two keep the GPU busy while the encoders work without holding
/// many full-size images in memory (the encoders' own are bounded in bytes: `encoders::InFlight`).
const WRITER_QUEUE: usize = 2;

/// What `shikki batch` was asked to do.
#[derive(Clone, Debug)]
pub struct BatchOptions {
    pub out_dir: PathBuf,
    /// (I, N): this process renders the jobs with id % N == I.
    pub shard: (usize, usize),
    /// Render every job even if its output and manifest hash match.
    pub force: bool,
    /// Told of the run's progress and of every warning and failed job: the library prints
    /// nothing itself (the CLI draws a progress bar and prints the lines).
    pub observer: Arc<dyn BatchObserver>,
    /// Set it (from any thread or a signal handler) to stop after the image in flight; the run
    /// then returns normally with [`BatchSummary::cancelled`].
    pub cancel: Arc<AtomicBool>,
    /// Where every file is written: [`FileSystem`], unless a caller injects failures.
    pub sink: Arc<dyn OutputSink>,
    /// Threads that encode and write images at once (at least 1): by default as many as the
    /// machine has cores beside the render and writer threads, at most 8
    /// ([`encoder_count`](super::encoders::encoder_count)). The files, manifest and contact
    /// sheet are the same for any count.
    pub encoders: usize,
}

impl BatchOptions {
    /// All jobs into `out_dir`, resuming, no progress bar, not cancelled, real files.
    pub fn new(out_dir: impl Into<PathBuf>) -> Self {
        BatchOptions {
            out_dir: out_dir.into(),
            shard: (0, 1),
            force: false,
            observer: Arc::new(Silent),
            cancel: Arc::new(AtomicBool::new(false)),
            sink: Arc::new(FileSystem),
            encoders: encoder_count(),
        }
    }
}

/// What a run reports while it goes, from the render and the writer thread. Every method has a
/// default that does nothing.
pub trait BatchObserver: Send + Sync + std::fmt::Debug {
    /// Up to `jobs` jobs of this shard are about to run.
    fn start(&self, _jobs: usize) {}
    /// A job is finished: rendered, skipped or failed.
    fn job_done(&self) {}
    /// A line for the user, already worded: `warning: …`, `error: job N: …`, a note.
    fn line(&self, _text: &str) {}
    /// The run is over (also when it failed or was cancelled).
    fn finish(&self) {}
}

/// Reports nothing: the default of [`BatchOptions::new`].
#[derive(Debug)]
pub struct Silent;

impl BatchObserver for Silent {}

/// How a run ended.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BatchSummary {
    pub rendered: usize,
    pub skipped: usize,
    pub failed: usize,
    /// Whether [`BatchOptions::cancel`] stopped the run early.
    pub cancelled: bool,
    /// Jobs of this shard that a cancelled run never started.
    pub not_started: usize,
    pub manifest: PathBuf,
    pub contact_sheet: PathBuf,
}

/// What the render thread tells the encoders.
pub(super) enum Message {
    Render {
        row: ManifestRow,
        path: PathBuf,
        image: HdrImage,
        png: PngSettings,
    },
    Skipped {
        row: ManifestRow,
        path: PathBuf,
    },
    Failed {
        row: ManifestRow,
    },
}

/// Runs the jobs of `plan` in this shard (see the module doc).
pub fn run_batch(
    gpu: &GpuContext,
    plan: &BatchPlan,
    options: &BatchOptions,
) -> Result<BatchSummary> {
    // Every job's name, not only this shard's: shards share directories. `parse` checked this
    // already; the plan's fields are public, so it is checked again before a file is written.
    plan.check_outputs()?;
    std::fs::create_dir_all(&options.out_dir).map_err(|e| Error::Write {
        path: options.out_dir.clone(),
        message: format!("cannot create the output directory: {e}"),
    })?;
    let jobs: Vec<JobSpec> = (0..plan.job_count())
        .filter(|&id| in_shard(id, options.shard))
        .map(|id| plan.job(id))
        .collect();
    let previous = if options.force {
        BTreeMap::new()
    } else {
        manifest::previous_rows(&options.out_dir)
    };
    let sweep_paths: Vec<String> = plan.sweeps.iter().map(|s| s.path.clone()).collect();
    let manifest_path = options.out_dir.join(manifest::manifest_name(options.shard));
    let sheet_name = match options.shard {
        (_, 1) => "contact_sheet.png".to_string(),
        (i, n) => format!("contact_sheet-shard-{i}-of-{n}.png"),
    };
    remove_leftover_temps(
        plan,
        &jobs,
        options,
        [&manifest_path, Path::new(&sheet_name)],
    );
    let mut renderer = SceneRenderer::new(gpu)?;
    let observer = options.observer.as_ref();
    observer.start(jobs.len());

    let (sender, receiver) = mpsc::sync_channel::<(usize, Message)>(WRITER_QUEUE);
    let (done, written) = mpsc::channel();
    let receiver = Mutex::new(receiver);
    let encoder_count = options.encoders.max(1);
    let in_flight = InFlight::new(encoder_count);
    let writer_manifest = Manifest::new(manifest_path.clone(), &sweep_paths);
    let sink: &dyn OutputSink = options.sink.as_ref();
    let mut started = 0;
    let result = std::thread::scope(|scope| {
        let encoders: Vec<_> = (0..encoder_count)
            .map(|_| {
                let done = done.clone();
                let (receiver, in_flight) = (&receiver, &in_flight);
                scope.spawn(move || encode_loop(receiver, done, in_flight, sink))
            })
            .collect();
        drop(done);
        let writer = scope.spawn(move || write_loop(written, writer_manifest, observer, sink));
        for job in &jobs {
            if options.cancel.load(Ordering::SeqCst) {
                break;
            }
            started += 1;
            let message = render_job(gpu, &mut renderer, plan, job, &options.out_dir, &previous);
            for warning in renderer.take_warnings() {
                observer.line(&format!("warning: {warning}"));
            }
            if let Message::Failed { row } = &message {
                observer.line(&format!("error: job {}: {}", row.job, row.status));
            }
            in_flight.acquire(message_bytes(&message));
            if sender.send((started - 1, message)).is_err() {
                break; // The encoders stopped: the writer's error is returned below.
            }
        }
        drop(sender);
        let panicked = |what| Error::invalid("batch", what, "panicked; please report");
        for encoder in encoders {
            encoder.join().map_err(|_| panicked("encoder thread"))?;
        }
        writer.join().map_err(|_| panicked("writer thread"))?
    });
    observer.finish();
    let (manifest, tiles, counts) = result?;
    let sheet_path = options.out_dir.join(sheet_name);
    let labelled: Vec<Tile> = tiles.into_values().collect();
    sink::write_file(sink, &sheet_path, &contact_sheet_png(&labelled)?)?;
    Ok(BatchSummary {
        rendered: counts.0,
        skipped: counts.1,
        failed: counts.2,
        cancelled: started < jobs.len(),
        not_started: jobs.len() - started,
        manifest: manifest.path,
        contact_sheet: sheet_path,
    })
}

/// Temporary files a killed run left next to this shard's outputs (either format), its manifest
/// and its contact sheet.
fn remove_leftover_temps(
    plan: &BatchPlan,
    jobs: &[JobSpec],
    options: &BatchOptions,
    own: [&Path; 2],
) {
    let mut names: Vec<String> = own
        .iter()
        .filter_map(|p| p.file_name())
        .map(|n| n.to_string_lossy().into_owned())
        .collect();
    for job in jobs {
        for format in [OutputFormat::Png, OutputFormat::Exr] {
            names.extend(plan.file_name(job, format));
        }
    }
    let removed = sink::remove_leftover_temps(&options.out_dir, &names);
    if removed > 0 {
        options.observer.line(&format!(
            "removed {removed} temporary file(s) an interrupted run left in {}",
            options.out_dir.display()
        ));
    }
}

/// Prepares and renders one job (or decides to skip it); never fails the run.
fn render_job(
    gpu: &GpuContext,
    renderer: &mut SceneRenderer,
    plan: &BatchPlan,
    job: &JobSpec,
    out_dir: &Path,
    previous: &BTreeMap<usize, ManifestRow>,
) -> Message {
    let mut row = ManifestRow {
        job: job.id,
        values: job.values.iter().map(|(_, v)| v.value.to_text()).collect(),
        output: String::new(),
        scene_hash: String::new(),
        status: STATUS_OK.into(),
    };
    let prepared: Result<PreparedJob> = plan.prepare(job);
    let prepared = match prepared {
        Ok(p) => p,
        Err(e) => {
            row.status = format!("failed: {e}");
            return Message::Failed { row };
        }
    };
    let path = out_dir.join(&prepared.file_name);
    row.output = prepared.file_name.clone();
    row.scene_hash = prepared.scene_hash.clone();
    if manifest::is_done(previous.get(&job.id), &prepared.scene_hash, &path) {
        return Message::Skipped { row, path };
    }
    let png = PngSettings {
        exposure_ev: prepared.scene.output.exposure_ev,
        tone_curve: prepared.scene.output.tone_curve,
    };
    let rendered =
        output::preflight_output(&path).and_then(|_| renderer.render(gpu, &prepared.scene));
    match rendered {
        Ok(image) => Message::Render {
            row,
            path,
            image,
            png,
        },
        Err(e) => {
            // A file from an earlier run would pass for this job's output.
            let _ = output::atomic::discard_stale_output(&path);
            row.status = format!("failed: {e}");
            Message::Failed { row }
        }
    }
}

type WriterResult = (Manifest, BTreeMap<usize, Tile>, (usize, usize, usize));

/// The writer thread: in job order, the manifest row, the tile and the progress of each job the
/// encoders finished; the manifest is saved after every job so a killed run can resume. A
/// manifest that cannot be saved (a full disk) is retried after the next job and must be saved
/// at the end.
fn write_loop(
    receiver: mpsc::Receiver<(usize, Written)>,
    mut manifest: Manifest,
    observer: &dyn BatchObserver,
    sink: &dyn OutputSink,
) -> Result<WriterResult> {
    let mut tiles = BTreeMap::new();
    let (mut rendered, mut skipped, mut failed) = (0, 0, 0);
    let mut manifest_warned = false;
    in_order(receiver, |written| {
        let (mut row, image) = match written {
            Written::Rendered { row, result } => match result {
                Ok(thumbnail) => {
                    rendered += 1;
                    (row, Some(thumbnail))
                }
                Err(e) => {
                    observer.line(&format!("error: job {}: {e}", row.job));
                    let row = ManifestRow {
                        status: format!("failed: {e}"),
                        ..row
                    };
                    (row, None)
                }
            },
            Written::Skipped { row, thumbnail } => {
                skipped += 1;
                (row, thumbnail)
            }
            Written::Failed { row } => (row, None),
        };
        if row.status != STATUS_OK {
            failed += 1;
            if image.is_none() && !row.output.is_empty() {
                row.output.clear();
            }
        }
        let mut lines = vec![format!("#{}", row.job)];
        lines.extend(
            manifest
                .columns
                .iter()
                .zip(&row.values)
                .map(|(path, value)| format!("{} = {value}", short_path(path))),
        );
        if row.status != STATUS_OK {
            lines.push("FAILED (see manifest)".into());
        }
        tiles.insert(row.job, Tile { image, lines });
        manifest.rows.insert(row.job, row);
        if let Err(e) = manifest.save(sink) {
            if !manifest_warned {
                observer.line(&format!("warning: {e}; retrying after the next job"));
                manifest_warned = true;
            }
        }
        observer.job_done();
    });
    manifest.save(sink)?;
    Ok((manifest, tiles, (rendered, skipped, failed)))
}

/// Encodes in memory (format by extension), then writes atomically through `sink`.
pub(super) fn write_image(
    sink: &dyn OutputSink,
    path: &Path,
    image: &HdrImage,
    png: &PngSettings,
) -> Result<()> {
    let encoded = OutputFormat::from_path(path).and_then(|format| match format {
        OutputFormat::Png => output::png::encode_png(image, png),
        OutputFormat::Exr => output::exr::encode_exr(image),
    });
    match encoded {
        Ok(bytes) => sink::write_file(sink, path, &bytes),
        Err(cause) => Err(output::atomic::failed_write(path, &cause.to_string())),
    }
}

/// `object.0.material.r` → `0.material.r`: enough to tell sweeps apart on a 192-pixel tile.
fn short_path(path: &str) -> &str {
    path.strip_prefix("object.").unwrap_or(path)
}

/// The tile of a job skipped on resume, read back from its output.
pub(super) fn thumbnail_from_file(path: &Path) -> Option<Thumbnail> {
    let bytes = std::fs::read(path).ok()?;
    match OutputFormat::from_path(path).ok()? {
        OutputFormat::Png => {
            let (w, h, pixels) = output::png::decode_png_rgba8(&bytes).ok()?;
            Some(Thumbnail::from_rgba8(w, h, &pixels))
        }
        OutputFormat::Exr => {
            let image = output::exr::decode_exr(&bytes).ok()?;
            Some(Thumbnail::from_hdr(&image, &PngSettings::default()))
        }
    }
}
