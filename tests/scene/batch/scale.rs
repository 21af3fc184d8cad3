//! `shikki batch` at scale: thousands of jobs that fail at once (no image to render, so only the
//! runner's own costs remain). The contact sheet stays bounded, each manifest row is written
//! once, the render thread stays a bounded number of jobs ahead of the writer, and the first
//! Ctrl-C stops such a batch in moments.

use crate::common;

use std::fs::File;
use std::io::{self, Write};
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use common::{assert_no_validation_messages, validated_gpu};
use shikki::scene::batch::encoders::MAX_UNWRITTEN;
use shikki::scene::batch::manifest::parse_rows;
use shikki::scene::batch::{run_batch, BatchObserver, BatchOptions, BatchPlan, OutputSink};

/// A 1 × 1 scene whose jobs all fail when prepared: r = 100 and up is outside g's domain
/// [1, 5.63], so no job reaches the GPU.
fn failing_jobs(r_values: usize, extra_sweeps: &str) -> String {
    let rs: Vec<String> = (0..r_values).map(|k| (100 + k).to_string()).collect();
    format!(
        "name = \"{{job}}\"\n[scene]\nenvironment = \"none\"\n[scene.output]\nsize = \"1x1\"\n\
         samples = 1\n[[scene.object]]\nmesh = \"builtin:sphere\"\n[sweep]\n\
         \"object.0.material.r\" = [{}]\n{extra_sweeps}",
        rs.join(", ")
    )
}

/// Width and height from a PNG's header.
fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    let (w, h, _) = shikki::output::png::decode_png_rgba8(&bytes).unwrap();
    (w, h)
}

/// The tester's case: 4,300 jobs with 131 sweeps (130 of one value each, so every label is 131
/// lines). The sheet of every tile was 13,208 × 145,406 pixels, whose byte count wrapped `u32`:
/// plotters panicked and the batch wrote no sheet and no summary.
#[test]
fn thousands_of_jobs_with_long_labels_write_a_bounded_contact_sheet() {
    let dir = tempfile::tempdir().unwrap();
    let extra: String = (0..130)
        .map(|k| format!("\"camera.unused_{k}\" = [0.05]\n"))
        .collect();
    let plan = BatchPlan::parse(&failing_jobs(4_300, &extra), "jobs.toml", dir.path()).unwrap();
    assert_eq!(plan.job_count(), 4_300);
    let gpu = validated_gpu();
    let out_dir = dir.path().join("out");
    let summary = run_batch(&gpu, &plan, &BatchOptions::new(&out_dir)).unwrap();
    assert_eq!((summary.failed, summary.rendered), (4_300, 0));
    assert_no_validation_messages(&gpu);
    let rows = parse_rows(&std::fs::read_to_string(&summary.manifest).unwrap());
    assert_eq!(rows.len(), 4_300);
    assert!(rows.iter().enumerate().all(|(k, r)| r.job == k));
    // At most 16 × 16 tiles of 8 label lines (`sheet::SheetLayout`) and a footer.
    let (w, h) = png_size(&summary.contact_sheet);
    assert!(w <= 3_208 && h <= 5_279, "{w} × {h}");
}

/// Counts the bytes written to the manifest (through its temporary file or appended).
#[derive(Debug, Default)]
struct CountingSink {
    manifest_bytes: AtomicU64,
}

impl OutputSink for CountingSink {
    fn write_bytes(&self, target: &Path, file: &mut File, bytes: &[u8]) -> io::Result<()> {
        if target.ends_with("manifest.csv") {
            self.manifest_bytes
                .fetch_add(bytes.len() as u64, Ordering::SeqCst);
        }
        file.write_all(bytes)
    }
}

/// The manifest was rewritten whole after every job: 2,000 jobs wrote it 2,000 times (Σ of its
/// sizes, ~200 MB here) and the run slowed as it grew. Now each row is written once: the bytes
/// written are exactly the file's.
#[test]
fn each_manifest_row_is_written_once() {
    let dir = tempfile::tempdir().unwrap();
    let plan = BatchPlan::parse(&failing_jobs(2_000, ""), "jobs.toml", dir.path()).unwrap();
    let gpu = validated_gpu();
    let sink = Arc::new(CountingSink::default());
    let options = BatchOptions {
        sink: sink.clone(),
        ..BatchOptions::new(dir.path().join("out"))
    };
    let summary = run_batch(&gpu, &plan, &options).unwrap();
    assert_eq!(summary.failed, 2_000);
    let on_disk = std::fs::metadata(&summary.manifest).unwrap().len();
    assert_eq!(sink.manifest_bytes.load(Ordering::SeqCst), on_disk);
    assert_eq!(
        parse_rows(&std::fs::read_to_string(&summary.manifest).unwrap()).len(),
        2_000
    );
}

/// A manifest on a slow disk: every write to it takes 20 ms.
#[derive(Debug)]
struct SlowManifest;

impl OutputSink for SlowManifest {
    fn write_bytes(&self, target: &Path, file: &mut File, bytes: &[u8]) -> io::Result<()> {
        if target.ends_with("manifest.csv") {
            std::thread::sleep(Duration::from_millis(20));
        }
        file.write_all(bytes)
    }
}

/// Cancels the run when the first job is written.
#[derive(Debug)]
struct CancelAtFirstJob(Arc<AtomicBool>);

impl BatchObserver for CancelAtFirstJob {
    fn job_done(&self) {
        self.0.store(true, Ordering::SeqCst);
    }
}

/// Failed jobs carry no image, so the queue bounded in image bytes let the render thread run
/// through a whole batch of them while a slow writer lagged, and a cancel came too late to stop
/// anything. Now it is at most MAX_UNWRITTEN jobs ahead.
#[test]
fn the_render_thread_stays_a_bounded_number_of_jobs_ahead_of_the_writer() {
    let dir = tempfile::tempdir().unwrap();
    let plan = BatchPlan::parse(&failing_jobs(2_000, ""), "jobs.toml", dir.path()).unwrap();
    let gpu = validated_gpu();
    let mut options = BatchOptions::new(dir.path().join("out"));
    options.sink = Arc::new(SlowManifest);
    options.observer = Arc::new(CancelAtFirstJob(Arc::clone(&options.cancel)));
    let summary = run_batch(&gpu, &plan, &options).unwrap();
    let started = 2_000 - summary.not_started;
    // When the first job is written the render thread holds at most MAX_UNWRITTEN unwritten jobs
    // plus the one freed by that write, and may be preparing one more before it sees the cancel.
    // (Unbounded, it prepared hundreds in the first write's 20 ms.)
    assert!(summary.cancelled);
    assert!(started <= MAX_UNWRITTEN + 2, "{started} jobs started");
    let rows = parse_rows(&std::fs::read_to_string(&summary.manifest).unwrap());
    assert_eq!(rows.len(), started, "the manifest lists every started job");
}

/// The tester's case through the CLI: a SIGINT 8 s into 15,000 failing jobs was still waiting
/// 60 s later. 90,000 failing jobs (two sweeps, so the jobs file stays small) run for seconds
/// here; the SIGINT comes with the first manifest row, and the batch must exit with 130 within
/// 10 s (it takes well under one; the margin is for a loaded CI machine), leaving a manifest of
/// consecutive jobs, no temporary file and a contact sheet.
#[test]
fn the_first_sigint_stops_a_batch_of_failing_jobs_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let orbits: Vec<String> = (0..300).map(|k| k.to_string()).collect();
    let jobs = failing_jobs(
        300,
        &format!("\"camera.orbit_deg\" = [{}]\n", orbits.join(", ")),
    );
    std::fs::write(dir.path().join("jobs.toml"), jobs).unwrap();
    let out_dir = dir.path().join("out");
    let mut child = Command::new(env!("CARGO_BIN_EXE_shikki"))
        .args(["batch", "jobs.toml", "--out", "out", "--quiet"])
        .current_dir(dir.path())
        .env("SHIKKI_PIPELINE_CACHE", "0")
        .env("SHIKKI_VALIDATION", "1")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let manifest = out_dir.join("manifest.csv");
    let deadline = Instant::now() + Duration::from_secs(120);
    while !manifest.is_file() {
        assert!(Instant::now() < deadline, "no manifest after 120 s");
        assert!(child.try_wait().unwrap().is_none(), "batch ended early");
        std::thread::sleep(Duration::from_millis(5));
    }
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let interrupted = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if interrupted.elapsed() > Duration::from_secs(10) {
            let _ = child.kill();
            panic!("still running 10 s after the first SIGINT");
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    assert_eq!(status.code(), Some(130));
    let rows = parse_rows(&std::fs::read_to_string(&manifest).unwrap());
    assert!(rows.len() < 90_000, "all {} jobs ran", rows.len());
    assert!(rows.iter().enumerate().all(|(k, r)| r.job == k));
    assert!(rows.iter().all(|r| r.status.starts_with("failed")));
    let names: Vec<String> = std::fs::read_dir(&out_dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(!names.iter().any(|n| n.ends_with(".tmp")), "{names:?}");
    png_size(&out_dir.join("contact_sheet.png"));
}
