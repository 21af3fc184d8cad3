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
//! contact sheet describe what finished, so the same command resumes. The render thread is at
//! most [`MAX_UNWRITTEN`](super::encoders::MAX_UNWRITTEN) jobs ahead of the writer, so that takes
//! moments whatever the batch.
//!
//! Memory does not grow with the batch beyond a few bytes a job: jobs are made from their ids as
//! they run, resume keeps a hash per finished job ([`manifest::Finished`]), manifest rows go to
//! the file as they finish and the contact sheet is bounded ([`super::sheet`]).

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc, Mutex};

use super::encoders::{
    encode_loop, encoder_count, in_order, message_bytes, InFlight, Unwritten, Writing, Written,
};
use super::manifest::{self, Finished, ManifestRow, ManifestWriter, STATUS_OK};
use super::sheet::{label, ContactSheet, SheetLayout, Thumbnail, Tile};
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
        /// Whether the contact sheet shows this job (its thumbnail is made).
        tile: bool,
    },
    Skipped {
        row: ManifestRow,
        path: PathBuf,
        tile: bool,
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
    let shard = options.shard;
    let ids = || (0..plan.job_count()).filter(move |&id| in_shard(id, shard));
    let total = ids().count();
    let previous = if options.force {
        Finished::default()
    } else {
        Finished::read(&options.out_dir)
    };
    let sweep_paths: Vec<String> = plan.sweeps.iter().map(|s| s.path.clone()).collect();
    let manifest_path = options.out_dir.join(manifest::manifest_name(options.shard));
    let sheet_name = match options.shard {
        (_, 1) => "contact_sheet.png".to_string(),
        (i, n) => format!("contact_sheet-shard-{i}-of-{n}.png"),
    };
    remove_leftover_temps(
        plan,
        ids(),
        options,
        [&manifest_path, Path::new(&sheet_name)],
    );
    let mut renderer = SceneRenderer::new(gpu)?;
    let observer = options.observer.as_ref();
    observer.start(total);

    let (sender, receiver) = mpsc::sync_channel::<(usize, Message)>(WRITER_QUEUE);
    let (done, written) = mpsc::channel();
    let receiver = Mutex::new(Some(receiver));
    let encoder_count = options.encoders.max(1);
    let in_flight = InFlight::new(encoder_count);
    let unwritten = Unwritten::new();
    let layout = SheetLayout::new(total, sweep_paths.len());
    let writer = Writer {
        manifest: ManifestWriter::new(manifest_path, &sweep_paths),
        sheet: ContactSheet::new(layout.clone()),
        columns: sweep_paths,
        counts: Counts::default(),
    };
    let sink: &dyn OutputSink = options.sink.as_ref();
    let mut started = 0;
    let mut render_panicked = false;
    let result = std::thread::scope(|scope| {
        let encoders: Vec<_> = (0..encoder_count)
            .map(|_| {
                let done = done.clone();
                let (receiver, in_flight) = (&receiver, &in_flight);
                scope.spawn(move || encode_loop(receiver, done, in_flight, sink))
            })
            .collect();
        drop(done);
        let unwritten = &unwritten;
        let writer = scope.spawn(move || writer.run(written, unwritten, observer, sink));
        for id in ids() {
            if options.cancel.load(Ordering::SeqCst) {
                break;
            }
            let place = started;
            started += 1;
            // A panic here (a bug, or a library user's observer) ends the run with an error once
            // the jobs before it are written, rather than unwinding through the caller.
            let step = catch_unwind(AssertUnwindSafe(|| {
                let job = plan.job(id);
                let tile = layout.shows(place);
                let message = render_job(gpu, &mut renderer, plan, &job, options, &previous, tile);
                for warning in renderer.take_warnings() {
                    observer.line(&format!("warning: {warning}"));
                }
                if let Message::Failed { row } = &message {
                    observer.line(&format!("error: job {}: {}", row.job, row.status));
                }
                message
            }));
            let Ok(message) = step else {
                render_panicked = true;
                break;
            };
            // Bounded in count (failed jobs carry no image) and in image bytes.
            unwritten.acquire();
            in_flight.acquire(message_bytes(&message));
            if sender.send((place, message)).is_err() {
                break; // The encoders are gone: the writer's error is returned below.
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
    let (manifest_path, sheet, counts) = result?;
    let sheet_path = options.out_dir.join(sheet_name);
    sink::write_file(sink, &sheet_path, &sheet.finish()?)?;
    if render_panicked {
        return Err(Error::invalid(
            "batch",
            "render thread",
            "panicked; please report (the manifest lists the jobs before it)",
        ));
    }
    Ok(BatchSummary {
        rendered: counts.rendered,
        skipped: counts.skipped,
        failed: counts.failed,
        cancelled: started < total,
        not_started: total - started,
        manifest: manifest_path,
        contact_sheet: sheet_path,
    })
}

/// Temporary files a killed run left next to this shard's outputs (either format), its manifest
/// and its contact sheet. The names are made only if the directory holds a temporary file.
fn remove_leftover_temps(
    plan: &BatchPlan,
    ids: impl Iterator<Item = usize>,
    options: &BatchOptions,
    own: [&Path; 2],
) {
    let own = own
        .into_iter()
        .filter_map(|p| p.file_name())
        .map(|n| n.to_string_lossy().into_owned());
    let outputs = ids.flat_map(|id| {
        let job = plan.job(id);
        [OutputFormat::Png, OutputFormat::Exr]
            .into_iter()
            .filter_map(move |format| plan.file_name(&job, format).ok())
    });
    let removed = sink::remove_leftover_temps(&options.out_dir, own.chain(outputs));
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
    options: &BatchOptions,
    previous: &Finished,
    tile: bool,
) -> Message {
    let mut row = ManifestRow {
        job: job.id,
        values: job
            .values
            .iter()
            .map(|(_, v)| manifest::value_text(&v.value))
            .collect(),
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
    let path = options.out_dir.join(&prepared.file_name);
    row.output = prepared.file_name.clone();
    row.scene_hash = prepared.scene_hash.clone();
    if previous.is_done(job.id, &prepared.scene_hash, &path) {
        return Message::Skipped { row, path, tile };
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
            tile,
        },
        Err(e) => {
            // A file from an earlier run would pass for this job's output.
            let _ = output::atomic::discard_stale_output(&path);
            row.status = format!("failed: {e}");
            Message::Failed { row }
        }
    }
}

/// Jobs rendered, skipped and failed.
#[derive(Default)]
struct Counts {
    rendered: usize,
    skipped: usize,
    failed: usize,
}

/// The writer thread's state: what it records of each job the encoders finished.
struct Writer {
    manifest: ManifestWriter,
    sheet: ContactSheet,
    /// The sweep paths, for tile labels.
    columns: Vec<String>,
    counts: Counts,
}

impl Writer {
    /// In job order: the manifest row (appended at once, so a killed run can resume), the tile
    /// and the progress of each job. A row that cannot be written (a full disk) is retried with
    /// the next one and must be written at the end; so must the contact sheet's tiles.
    fn run(
        mut self,
        receiver: mpsc::Receiver<(usize, Written)>,
        unwritten: &Unwritten,
        observer: &dyn BatchObserver,
        sink: &dyn OutputSink,
    ) -> Result<(PathBuf, ContactSheet, Counts)> {
        let _writing = Writing(unwritten);
        let mut manifest_warned = false;
        let mut sheet_error = None;
        let mut place = 0;
        in_order(receiver, |written| {
            let (row, image) = self.record(written, observer);
            if let Err(e) = self.manifest.append(&row, sink) {
                if !manifest_warned {
                    observer.line(&format!("warning: {e}; retrying after the next job"));
                    manifest_warned = true;
                }
            }
            unwritten.release();
            if sheet_error.is_none() {
                let tile = Tile {
                    lines: label(&row, &self.columns),
                    failed: row.status != STATUS_OK,
                    image,
                };
                sheet_error = self.sheet.add(place, tile).err();
            }
            place += 1;
            observer.job_done();
        });
        self.manifest.finish(sink)?;
        match sheet_error {
            Some(e) => Err(e),
            None => Ok((self.manifest.path, self.sheet, self.counts)),
        }
    }

    /// Counts the job and gives its manifest row and tile image.
    fn record(
        &mut self,
        written: Written,
        observer: &dyn BatchObserver,
    ) -> (ManifestRow, Option<Thumbnail>) {
        let (mut row, image) = match written {
            Written::Rendered { row, result } => match result {
                Ok(thumbnail) => {
                    self.counts.rendered += 1;
                    (row, thumbnail)
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
                self.counts.skipped += 1;
                (row, thumbnail)
            }
            Written::Failed { row } => (row, None),
        };
        if row.status != STATUS_OK {
            self.counts.failed += 1;
            row.output.clear();
        }
        (row, image)
    }
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
