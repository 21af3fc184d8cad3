//! `shikki batch` end to end (validated Vulkan): a 2 × 3 sweep gives 6 images, a manifest and a
//! contact sheet; shards are disjoint and cover the sweep; a resumed run renders only what is
//! missing; a failing job is recorded and makes the exit code non-zero; the example sweep writes
//! 30 distinct images, and jobs that would share a file are refused before anything is written.

use std::collections::BTreeSet;
use std::path::Path;
use std::process::{Command, Output};

const JOBS: &str = r#"
name = "{preset}-r{r}"
[scene]
environment = "none"
[scene.output]
size = "48x32"
samples = 1
[[scene.object]]
mesh = "builtin:sphere"
material = { preset = "smooth-red" }
[[scene.light]]
kind = "dir"
to_light = [0, 0, 1]
irradiance = 2

[sweep]
"object.0.material.preset" = ["smooth-red", "rough-red"]
"object.0.material.r" = [1, 2, 3]
"#;

fn shikki(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_shikki"))
        .env("SHIKKI_PIPELINE_CACHE", "0")
        .args(args)
        .current_dir(dir)
        .env("SHIKKI_VALIDATION", "1")
        .output()
        .unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn pngs(dir: &Path) -> BTreeSet<String> {
    std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .flatten()
                .map(|e| e.file_name().to_string_lossy().to_string())
                .filter(|n| n.ends_with(".png") && !n.starts_with("contact_sheet"))
                .collect()
        })
        .unwrap_or_default()
}

fn all_names() -> BTreeSet<String> {
    ["smooth-red", "rough-red"]
        .iter()
        .flat_map(|p| (1..=3).map(move |r| format!("{p}-r{r}.png")))
        .collect()
}

fn manifest_rows(path: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

#[test]
fn two_by_three_sweep_gives_six_images_a_manifest_and_a_contact_sheet() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("jobs.toml"), JOBS).unwrap();
    let out = shikki(dir.path(), &["batch", "jobs.toml", "--out", "out"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let out_dir = dir.path().join("out");
    assert_eq!(pngs(&out_dir), all_names());
    let text = std::fs::read_to_string(out_dir.join("manifest.csv")).unwrap();
    assert!(text.starts_with(
        "job,object.0.material.preset,object.0.material.r,output,scene_hash,status\n"
    ));
    let rows = manifest_rows(&out_dir.join("manifest.csv"));
    assert_eq!(rows.len(), 6);
    // Job 4 is (rough-red, r = 2): first sweep slowest.
    assert_eq!(rows[4][..4], ["4", "rough-red", "2", "rough-red-r2.png"]);
    let hashes: BTreeSet<&String> = rows.iter().map(|r| &r[4]).collect();
    assert_eq!(
        hashes.len(),
        6,
        "every job's scene differs, so must its hash"
    );
    assert!(rows.iter().all(|r| r[5] == "ok"));
    // The contact sheet: 6 tiles → 3 columns × 2 rows of (192 + 8) plus the margin.
    let sheet = std::fs::read(out_dir.join("contact_sheet.png")).unwrap();
    let (w, _, pixels) = shikki::output::png::decode_png_rgba8(&sheet).unwrap();
    assert_eq!(w, 3 * 200 + 8);
    assert!(
        pixels.iter().any(|p| p[0] > 100 && p[1] < 60),
        "no red tile pixels on the contact sheet"
    );

    // The images differ as the sweep says: rough (m = 0.2) has a dimmer, wider highlight than
    // smooth, so the brightest pixel of smooth-red-r1 is brighter than rough-red-r1's.
    let peak = |name: &str| {
        let bytes = std::fs::read(out_dir.join(name)).unwrap();
        let (_, _, px) = shikki::output::png::decode_png_rgba8(&bytes).unwrap();
        px.iter().map(|p| u32::from(p[1])).max().unwrap()
    };
    assert!(peak("smooth-red-r1.png") > peak("rough-red-r1.png"));
}

#[test]
fn shards_are_disjoint_and_cover_the_sweep() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("jobs.toml"), JOBS).unwrap();
    let mut seen = Vec::new();
    for shard in ["0/2", "1/2"] {
        let out_dir = format!("out-{}", &shard[..1]);
        let out = shikki(
            dir.path(),
            &["batch", "jobs.toml", "--out", &out_dir, "--shard", shard],
        );
        assert!(out.status.success(), "{}", stderr(&out));
        let names = pngs(&dir.path().join(&out_dir));
        assert_eq!(names.len(), 3, "shard {shard}: {names:?}");
        let manifest = format!("manifest-shard-{}-of-2.csv", &shard[..1]);
        assert_eq!(
            manifest_rows(&dir.path().join(&out_dir).join(manifest)).len(),
            3
        );
        seen.push(names);
    }
    assert!(seen[0].is_disjoint(&seen[1]));
    let union: BTreeSet<String> = seen[0].union(&seen[1]).cloned().collect();
    assert_eq!(union, all_names());
}

#[test]
fn resume_renders_only_the_missing_jobs() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("jobs.toml"), JOBS).unwrap();
    let out_dir = dir.path().join("out");
    assert!(shikki(dir.path(), &["batch", "jobs.toml", "--out", "out"])
        .status
        .success());
    let mtime = |n: &str| {
        std::fs::metadata(out_dir.join(n))
            .unwrap()
            .modified()
            .unwrap()
    };
    let before = mtime("smooth-red-r1.png");
    // A run killed half-way: two images missing, one row missing from the manifest (its image
    // is there but unrecorded, so it cannot be trusted), the rest finished.
    std::fs::remove_file(out_dir.join("rough-red-r2.png")).unwrap();
    std::fs::remove_file(out_dir.join("rough-red-r3.png")).unwrap();
    let manifest = out_dir.join("manifest.csv");
    let text = std::fs::read_to_string(&manifest).unwrap();
    let kept: Vec<&str> = text.lines().filter(|l| !l.starts_with("1,")).collect();
    std::fs::write(&manifest, kept.join("\n") + "\n").unwrap();

    let out = shikki(
        dir.path(),
        &["batch", "jobs.toml", "--out", "out", "--quiet"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains("3 rendered, 3 skipped"),
        "expected jobs 1, 4, 5 rendered and 0, 2, 3 skipped: {err}"
    );
    assert_eq!(pngs(&out_dir), all_names());
    assert_eq!(
        mtime("smooth-red-r1.png"),
        before,
        "a finished job was redone"
    );
    assert_eq!(manifest_rows(&manifest).len(), 6);

    let out = shikki(
        dir.path(),
        &["batch", "jobs.toml", "--out", "out", "--force"],
    );
    assert!(
        stderr(&out).contains("6 rendered, 0 skipped"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn a_failing_job_is_recorded_the_others_finish_and_the_exit_code_is_nonzero() {
    let dir = tempfile::tempdir().unwrap();
    // r = 7 is outside g's domain [1, 5.63]: that job fails, the other two render.
    let jobs = JOBS.replace("[1, 2, 3]", "[1, 7, 3]");
    std::fs::write(dir.path().join("jobs.toml"), jobs).unwrap();
    let out = shikki(dir.path(), &["batch", "jobs.toml", "--out", "out"]);
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(err.contains("job 1") && err.contains("5.6"), "{err}");
    let out_dir = dir.path().join("out");
    assert_eq!(pngs(&out_dir).len(), 4);
    assert!(!out_dir.join("smooth-red-r7.png").exists());
    let rows = manifest_rows(&out_dir.join("manifest.csv"));
    assert_eq!(rows.len(), 6);
    assert!(
        rows[1].last().unwrap().starts_with("failed")
            || rows[1].iter().any(|f| f.contains("failed"))
    );
    assert!(out_dir.join("contact_sheet.png").exists());
}

/// The example batch (its `name` template and sweeps, as shipped) with a tiny inline scene in
/// place of `default.toml`, so its 30 jobs render in seconds.
fn small_example() -> String {
    let example = include_str!("../../../examples/ratio-sweep.jobs.toml");
    let mut text: String = example
        .lines()
        .filter(|l| !l.starts_with("scene ="))
        .map(|l| format!("{l}\n"))
        .collect();
    text.push_str(
        "[scene]\nenvironment = \"none\"\n[scene.output]\nsize = \"16x16\"\nsamples = 1\n\
         [[scene.object]]\nmesh = \"builtin:sphere\"\n",
    );
    text
}

#[test]
fn the_example_sweep_writes_thirty_images_and_thirty_manifest_rows() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("jobs.toml"), small_example()).unwrap();
    let out = shikki(dir.path(), &["batch", "jobs.toml", "--out", "out"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let out_dir = dir.path().join("out");
    assert_eq!(pngs(&out_dir).len(), 30, "{:?}", pngs(&out_dir));
    let rows = manifest_rows(&out_dir.join("manifest.csv"));
    assert_eq!(rows.len(), 30);
    // job, three sweep columns, output, scene_hash, status.
    assert!(
        rows.iter().all(|r| r.len() == 7 && r[6] == "ok"),
        "{rows:?}"
    );
    let outputs: BTreeSet<&String> = rows.iter().map(|r| &r[4]).collect();
    assert_eq!(outputs.len(), 30, "two rows name one file: {rows:?}");
    assert!(outputs.iter().all(|o| out_dir.join(o).is_file()));
}

#[test]
fn jobs_that_share_a_file_are_refused_before_anything_is_written() {
    // Without {orbit_deg}, the three view angles of each (preset, r) write one file.
    let dir = tempfile::tempdir().unwrap();
    let jobs = small_example().replace("{preset}-r{r}-orbit{orbit_deg}", "{preset}-r{r}");
    std::fs::write(dir.path().join("jobs.toml"), jobs).unwrap();
    for shard in [None, Some("1/2")] {
        let mut args = vec!["batch", "jobs.toml", "--out", "out"];
        args.extend(shard.iter().flat_map(|s| ["--shard", *s]));
        let out = shikki(dir.path(), &args);
        assert!(!out.status.success(), "shard {shard:?}");
        let err = stderr(&out);
        for fragment in [
            "jobs.toml:",
            "job 0 (object.0.material.preset = smooth-red, object.0.material.r = 1, \
             camera.orbit_deg = -30)",
            "job 1 (object.0.material.preset = smooth-red, object.0.material.r = 1, \
             camera.orbit_deg = 0)",
            "would both write smooth-red-r1.png",
            "add {orbit_deg}, the sweep that tells them apart, to `name`",
        ] {
            assert!(err.contains(fragment), "{fragment:?} not in: {err}");
        }
        assert!(
            !dir.path().join("out").exists(),
            "shard {shard:?} wrote files"
        );
    }
}
