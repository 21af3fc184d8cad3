//! `shikki batch` under faults (issue 8): no Vulkan device, an output that cannot be written, a
//! disk that fills up mid-batch, Ctrl-C mid-batch and the resume after it; and the batch path
//! (render thread + writer thread) with a prefilter and a render before it in one process, under
//! synchronisation validation.
//!
//! Invariants checked throughout: every image present decodes completely, no temporary file is
//! left, the manifest says what happened to each job, and the exit code says whether all went
//! well.

use crate::common;
use shikki::environment::EnvironmentLight;

use std::collections::BTreeSet;
use std::fs::File;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use common::{assert_no_validation_messages, validated_gpu};
use shikki::output::HdrImage;
use shikki::scene::batch::manifest::{parse_rows, ManifestRow, STATUS_OK};
use shikki::scene::batch::{run_batch, BatchOptions, BatchPlan, OutputSink};
use shikki::scene::SceneRenderer;

/// 2 × 3 small jobs, `job-0.png` … `job-5.png`.
const SMALL_JOBS: &str = r#"
[scene]
environment = "none"
[scene.output]
size = "32x24"
samples = 1
[[scene.object]]
mesh = "builtin:sphere"
material = { preset = "smooth-red" }
[sweep]
"object.0.material.preset" = ["smooth-red", "rough-red"]
"object.0.material.r" = [1, 2, 3]
"#;

/// The exit code of an interrupted batch (128 + SIGINT).
const EXIT_INTERRUPTED: i32 = 130;

fn shikki(dir: &Path, args: &[&str]) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_shikki"));
    command
        .args(args)
        .current_dir(dir)
        .env("SHIKKI_PIPELINE_CACHE", "0")
        .env("SHIKKI_VALIDATION", "1");
    command
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn file_names(dir: &Path) -> BTreeSet<String> {
    std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default()
}

/// Job images (files, not the contact sheet).
fn job_images(dir: &Path) -> BTreeSet<String> {
    file_names(dir)
        .into_iter()
        .filter(|n| n.starts_with("job-") && n.ends_with(".png") && dir.join(n).is_file())
        .collect()
}

fn manifest(dir: &Path) -> Vec<ManifestRow> {
    parse_rows(&std::fs::read_to_string(dir.join("manifest.csv")).unwrap())
}

/// No temporary file anywhere, every job image decodes completely, and the manifest's `ok` rows
/// are exactly the images present.
fn assert_consistent(out_dir: &Path) -> Vec<ManifestRow> {
    let names = file_names(out_dir);
    let temps: Vec<&String> = names.iter().filter(|n| n.ends_with(".tmp")).collect();
    assert!(temps.is_empty(), "temporary files left: {temps:?}");
    for name in job_images(out_dir) {
        let bytes = std::fs::read(out_dir.join(&name)).unwrap();
        let (w, h, _) = shikki::output::png::decode_png_rgba8(&bytes)
            .unwrap_or_else(|e| panic!("{name} does not decode: {e}"));
        assert_eq!((w, h), (32, 24), "{name}");
    }
    let rows = manifest(out_dir);
    let ok: BTreeSet<String> = rows
        .iter()
        .filter(|r| r.status == STATUS_OK)
        .map(|r| r.output.clone())
        .collect();
    assert_eq!(
        ok,
        job_images(out_dir),
        "manifest ok rows vs images present"
    );
    let sheet = std::fs::read(out_dir.join("contact_sheet.png")).unwrap();
    assert!(shikki::output::png::decode_png_rgba8(&sheet).is_ok());
    rows
}

#[test]
fn batch_without_a_vulkan_device_names_the_packages_to_install() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("jobs.toml"), SMALL_JOBS).unwrap();
    let missing = dir.path().join("no-such-icd.json");
    let out = shikki(dir.path(), &["batch", "jobs.toml", "--out", "out"])
        .env("VK_DRIVER_FILES", &missing)
        .env("VK_ICD_FILENAMES", &missing)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    // The loader (libvulkan1) is there, the driver is not: the error names the driver package.
    assert!(err.contains("apt-get install mesa-vulkan-drivers"), "{err}");
    assert!(job_images(&dir.path().join("out")).is_empty());
}

#[test]
fn an_output_that_cannot_be_written_fails_that_job_and_the_batch_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("jobs.toml"), SMALL_JOBS).unwrap();
    let out_dir = dir.path().join("out");
    // A directory where job 2's image must go: no file can be created there, whoever we run as
    // (tests run as root, for whom permission bits do not stop anything).
    std::fs::create_dir_all(out_dir.join("job-2.png")).unwrap();
    std::fs::write(out_dir.join("job-2.png").join("keep"), b"k").unwrap();
    let out = shikki(dir.path(), &["batch", "jobs.toml", "--out", "out"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains("job 2") && err.contains("is a directory"),
        "{err}"
    );
    assert!(
        err.contains("5 rendered") && err.contains("1 failed"),
        "{err}"
    );
    let rows = assert_consistent(&out_dir);
    assert_eq!(rows.len(), 6);
    assert!(rows[2].status.contains("is a directory"), "{:?}", rows[2]);
    assert!(out_dir.join("job-2.png").join("keep").is_file());

    // --out naming a regular file: the whole batch stops before rendering, saying so.
    std::fs::write(dir.path().join("plain"), b"x").unwrap();
    let out = shikki(dir.path(), &["batch", "jobs.toml", "--out", "plain/out"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("plain"), "{}", stderr(&out));
}

/// A disk that fills up while job `full_at`'s image is written (after `bytes` bytes of it) and
/// stays full until the next image: that image and the manifest save after it fail with ENOSPC.
#[derive(Debug)]
struct FillingDisk {
    full_at: String,
    bytes: usize,
    full: AtomicBool,
}

impl OutputSink for FillingDisk {
    fn write_bytes(&self, target: &Path, file: &mut File, bytes: &[u8]) -> io::Result<()> {
        let name = target.file_name().unwrap().to_string_lossy();
        if name.starts_with("job-") {
            self.full.store(name == self.full_at, Ordering::SeqCst);
        }
        if self.full.load(Ordering::SeqCst) {
            file.write_all(&bytes[..self.bytes.min(bytes.len())])?;
            return Err(io::Error::from_raw_os_error(28)); // ENOSPC
        }
        file.write_all(bytes)
    }
}

#[test]
fn a_full_disk_mid_batch_fails_that_job_only_and_leaves_no_partial_file() {
    let dir = tempfile::tempdir().unwrap();
    let gpu = validated_gpu();
    let plan = BatchPlan::parse(SMALL_JOBS, "jobs.toml", dir.path()).unwrap();
    let out_dir = dir.path().join("out");
    let mut options = BatchOptions::new(&out_dir);
    options.sink = Arc::new(FillingDisk {
        full_at: "job-3.png".into(),
        bytes: 100,
        full: AtomicBool::new(false),
    });
    // The disk fills at one image and empties at the next one written: a sequence of writes,
    // which one encoder keeps (several write images at once).
    options.encoders = 1;
    let summary = run_batch(&gpu, &plan, &options).unwrap();
    assert_eq!(
        (summary.rendered, summary.failed, summary.cancelled),
        (5, 1, false),
        "{summary:?}"
    );
    assert_no_validation_messages(&gpu);
    let rows = assert_consistent(&out_dir);
    assert_eq!(rows.len(), 6);
    assert!(!out_dir.join("job-3.png").exists());
    assert!(
        rows[3].status.starts_with("failed") && rows[3].status.contains("No space left"),
        "{:?}",
        rows[3]
    );
    assert!(rows
        .iter()
        .filter(|r| r.job != 3)
        .all(|r| r.status == STATUS_OK));

    // The disk has room again: the same batch renders only the failed job.
    let summary = run_batch(&gpu, &plan, &BatchOptions::new(&out_dir)).unwrap();
    assert_eq!(
        (summary.rendered, summary.skipped, summary.failed),
        (1, 5, 0)
    );
    assert_eq!(assert_consistent(&out_dir).len(), 6);
}

/// Several encoders write the same files, manifest and contact sheet as one: images finish out of
/// order, the writer puts them back in job order.
#[test]
fn any_number_of_encoders_writes_the_same_files() {
    let gpu = validated_gpu();
    let jobs = format!("{SMALL_JOBS}\"object.0.material.m\" = [0.05, 0.1, 0.2, 0.3]\n");
    let mut outputs = Vec::new();
    for encoders in [1, 4] {
        let dir = tempfile::tempdir().unwrap();
        let plan = BatchPlan::parse(&jobs, "jobs.toml", dir.path()).unwrap();
        let out_dir = dir.path().join("out");
        let options = BatchOptions {
            encoders,
            ..BatchOptions::new(&out_dir)
        };
        let summary = run_batch(&gpu, &plan, &options).unwrap();
        assert_eq!((summary.rendered, summary.failed), (24, 0), "{summary:?}");
        assert_consistent(&out_dir);
        let files: Vec<(String, Vec<u8>)> = file_names(&out_dir)
            .into_iter()
            .map(|name| {
                let bytes = std::fs::read(out_dir.join(&name)).unwrap();
                (name, bytes)
            })
            .collect();
        outputs.push(files);
    }
    assert_no_validation_messages(&gpu);
    assert_eq!(
        outputs[0].len(),
        24 + 2,
        "24 images, the manifest, the contact sheet"
    );
    for ((name, one), (_, four)) in outputs[0].iter().zip(&outputs[1]) {
        assert!(one == four, "{name} differs between 1 and 4 encoders");
    }
}

#[test]
fn cancelling_stops_taking_jobs_and_keeps_what_finished() {
    let dir = tempfile::tempdir().unwrap();
    let gpu = validated_gpu();
    let plan = BatchPlan::parse(SMALL_JOBS, "jobs.toml", dir.path()).unwrap();
    let out_dir = dir.path().join("out");
    let options = BatchOptions::new(&out_dir);
    options.cancel.store(true, Ordering::SeqCst);
    let summary = run_batch(&gpu, &plan, &options).unwrap();
    assert_eq!(
        (summary.rendered, summary.not_started, summary.cancelled),
        (0, 6, true)
    );
    assert!(assert_consistent(&out_dir).is_empty());
}

/// 40 jobs at 32 × 24: long enough to interrupt, short enough for CI.
fn forty_jobs() -> String {
    let orbits: Vec<String> = (0..40).map(|k| (k * 9).to_string()).collect();
    SMALL_JOBS.replace(
        "\"object.0.material.preset\" = [\"smooth-red\", \"rough-red\"]\n\"object.0.material.r\" = [1, 2, 3]",
        &format!("\"camera.orbit_deg\" = [{}]", orbits.join(", ")),
    )
}

#[test]
fn sigint_stops_after_the_image_in_flight_and_the_same_command_resumes() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("jobs.toml"), forty_jobs()).unwrap();
    let out_dir = dir.path().join("out");
    let mut child = shikki(dir.path(), &["batch", "jobs.toml", "--out", "out"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(120);
    while job_images(&out_dir).len() < 2 {
        assert!(Instant::now() < deadline, "no output after 120 s");
        assert!(child.try_wait().unwrap().is_none(), "batch ended early");
        std::thread::sleep(Duration::from_millis(10));
    }
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let out = child.wait_with_output().unwrap();
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(EXIT_INTERRUPTED), "{err}");
    assert!(
        err.contains("run the same command again to resume"),
        "{err}"
    );
    let rows = assert_consistent(&out_dir);
    let done = job_images(&out_dir).len();
    assert!(
        (2..40).contains(&done),
        "{done} of 40 done when interrupted"
    );
    assert_eq!(
        rows.len(),
        done,
        "the manifest lists exactly the finished jobs"
    );

    let out = shikki(
        dir.path(),
        &["batch", "jobs.toml", "--out", "out", "--quiet"],
    )
    .output()
    .unwrap();
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains(&format!("{} rendered, {done} skipped", 40 - done)),
        "{err}"
    );
    let rows = assert_consistent(&out_dir);
    assert_eq!(rows.len(), 40);
    assert_eq!(job_images(&out_dir).len(), 40);
}

/// A small sky (64 × 32 EXR) for the environment prefilter.
fn write_sky(dir: &Path) -> PathBuf {
    let mut image = HdrImage::new(64, 32);
    for (i, p) in image.pixels.iter_mut().enumerate() {
        let sky = 1.0 - (i / 64) as f32 / 32.0;
        *p = [sky, 0.5 * sky + 0.2, 0.3, 1.0];
    }
    let path = dir.join("sky.exr");
    std::fs::write(&path, shikki::output::exr::encode_exr(&image).unwrap()).unwrap();
    path
}

/// Issue 8 part 5: a standalone prefilter, a render with an environment and a batch (its writer
/// thread beside the render thread, with a cancelled second batch) in one process, all under the
/// validation layer with its synchronisation checks: not one message, during the work or when the
/// device is destroyed.
#[test]
fn prefilter_render_and_batch_in_one_process_are_silent_under_sync_validation() {
    use shikki::environment::gpu::GpuPrefilter;
    use shikki::environment::{load_environment, PrefilterParams};
    let dir = tempfile::tempdir().unwrap();
    let sky = write_sky(dir.path()).display().to_string();
    let gpu = validated_gpu();
    let log = gpu.validation_log();

    let loaded = load_environment(&sky).unwrap();
    let prefilter = GpuPrefilter::new(&gpu).unwrap();
    let params = PrefilterParams::for_source_width(loaded.image.width);
    drop(
        prefilter
            .run(
                &gpu,
                &loaded.image,
                &params,
                EnvironmentLight::new(1.0, 30.0),
            )
            .unwrap(),
    );
    drop(prefilter);
    assert_no_validation_messages(&gpu);

    let jobs = SMALL_JOBS.replace("environment = \"none\"", &format!("environment = {sky:?}"));
    let plan = BatchPlan::parse(&jobs, "jobs.toml", dir.path()).unwrap();
    let mut renderer = SceneRenderer::new(&gpu).unwrap();
    let scene = plan.prepare(&plan.job(4)).unwrap().scene;
    renderer.render(&gpu, &scene).unwrap();
    drop(renderer);
    assert_no_validation_messages(&gpu);

    let summary = run_batch(&gpu, &plan, &BatchOptions::new(dir.path().join("out"))).unwrap();
    assert_eq!((summary.rendered, summary.failed), (6, 0), "{summary:?}");
    assert_no_validation_messages(&gpu);
    drop(gpu);
    let at_shutdown = log.take();
    assert!(at_shutdown.is_empty(), "{}", at_shutdown.join("\n"));
}

/// Panics when the manifest is written: the writer thread dies at the first row.
#[derive(Debug)]
struct PanickingManifest;

impl OutputSink for PanickingManifest {
    fn write_bytes(&self, target: &Path, file: &mut File, bytes: &[u8]) -> io::Result<()> {
        assert!(!target.ends_with("manifest.csv"), "a sink that panics");
        file.write_all(bytes)
    }
}

/// A writer that panics (here in a library user's sink) fails the run with an error naming it.
/// The render thread used to wait for ever: the encoders stopped when the writer went, but the
/// queue they read from stayed open and filled up.
#[test]
fn a_panicking_writer_fails_the_batch_instead_of_hanging() {
    let (result, finished) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let dir = tempfile::tempdir().unwrap();
        // 2 × 100 jobs that fail when prepared (r = 7 is outside [1, 5.63]): more than the queues
        // hold, so the render thread must see that the encoders are gone.
        let sevens = format!("[{}]", ["7"; 100].join(", "));
        let plan = BatchPlan::parse(
            &SMALL_JOBS.replace("[1, 2, 3]", &sevens),
            "jobs.toml",
            dir.path(),
        )
        .unwrap();
        let gpu = validated_gpu();
        let mut options = BatchOptions::new(dir.path().join("out"));
        options.sink = Arc::new(PanickingManifest);
        let _ = result.send(run_batch(&gpu, &plan, &options).map_err(|e| e.to_string()));
    });
    // Failing jobs finish in milliseconds; the margin is for a loaded CI machine.
    let outcome = match finished.recv_timeout(Duration::from_secs(60)) {
        Ok(outcome) => outcome,
        Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
            panic!("the batch hung after its writer panicked")
        }
        Err(e) => panic!("the test's thread failed before run_batch returned ({e})"),
    };
    let message = outcome.unwrap_err();
    assert!(message.contains("writer thread"), "{message}");
}

/// Panics at the first failed job's error line, which the render thread reports.
#[derive(Debug)]
struct PanickingObserver;

impl shikki::scene::batch::BatchObserver for PanickingObserver {
    fn line(&self, text: &str) {
        assert!(!text.starts_with("error: job"), "an observer that panics");
    }
}

/// A panic on the render thread (here in a library user's observer) is the run's error, after
/// the jobs before it are written; it used to unwind through `run_batch` into the caller.
#[test]
fn a_panic_on_the_render_thread_is_an_error_not_an_unwind() {
    let dir = tempfile::tempdir().unwrap();
    // Job 2 (smooth-red, r = 7) fails when prepared; jobs 0 and 1 render first.
    let plan = BatchPlan::parse(
        &SMALL_JOBS.replace("[1, 2, 3]", "[1, 2, 7]"),
        "jobs.toml",
        dir.path(),
    )
    .unwrap();
    let gpu = validated_gpu();
    let out_dir = dir.path().join("out");
    let mut options = BatchOptions::new(&out_dir);
    options.observer = Arc::new(PanickingObserver);
    let message = run_batch(&gpu, &plan, &options).unwrap_err().to_string();
    assert!(message.contains("render thread"), "{message}");
    assert_no_validation_messages(&gpu);
    let rows = assert_consistent(&out_dir);
    assert_eq!(rows.iter().map(|r| r.job).collect::<Vec<_>>(), [0, 1]);
}
