//! `shikki bench --json --quick` as a CI smoke run: every stage runs at tiny sizes and the JSON
//! report has every field. Not a timed test: no figure is compared with anything (speed is
//! measured by `cargo run --release -- bench`, BENCHMARKS.md), only the report's shape and that
//! each figure is a finite, positive measurement.

use std::process::Command;

fn field<'a>(value: &'a serde_json::Value, path: &str) -> &'a serde_json::Value {
    path.split('.').fold(value, |v, key| match v.get(key) {
        Some(next) => next,
        None => panic!("the bench report has no `{path}` (missing `{key}`):\n{value:#}"),
    })
}

fn positive_median(report: &serde_json::Value, path: &str) {
    let median = field(report, &format!("{path}.median"))
        .as_f64()
        .unwrap_or_else(|| panic!("{path}.median is not a number"));
    assert!(
        median.is_finite() && median > 0.0,
        "{path}.median = {median}: a measurement must be finite and positive"
    );
    let samples = field(report, &format!("{path}.samples"))
        .as_array()
        .unwrap_or_else(|| panic!("{path}.samples is not an array"));
    assert!(!samples.is_empty(), "{path} has no samples");
}

#[test]
fn quick_bench_reports_every_stage_as_json() {
    let scratch = tempfile::tempdir().unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_shikki"))
        .args([
            "bench",
            "--json",
            "--quick",
            "--runs",
            "1",
            "--render-size",
            "32",
            "--face-size",
            "16",
            "--layers",
            "2",
            "--batch-jobs",
            "2",
            "--batch-size",
            "32",
            "--startup-size",
            "32",
        ])
        // Caches in a temp dir, never the home directory (the children get their own).
        .env(
            "SHIKKI_PIPELINE_CACHE",
            scratch.path().join("pipelines.bin"),
        )
        .env("SHIKKI_VALIDATION", "1")
        .current_dir(scratch.path())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "shikki bench failed:\n{stderr}");
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap_or_else(|e| {
        panic!(
            "stdout is not JSON ({e}):\n{}",
            String::from_utf8_lossy(&output.stdout)
        )
    });
    for path in [
        "shikki_version",
        "build_profile",
        "config.runs",
        "machine.cpu_model",
        "machine.cores",
        "driver.device",
        "driver.driver_info",
        "render.triangles",
        "render.ratio",
        "prefilter.speedup",
        "prefilter.gpu_pass_breakdown",
        "batch.images_per_second",
        "batch.gpu_ceiling",
        "batch.efficiency",
        "startup.warm_over_cold",
        "memory.cold_peak_mib",
        "memory.warm_peak_mib",
    ] {
        field(&report, path);
    }
    for path in [
        "render.lacquer_gpu",
        "render.trivial_gpu",
        "render.lacquer_wall",
        "prefilter.gpu_wall",
        "render.models.paper_gpu",
        "render.models.brdf_gpu",
        "prefilter.gpu_passes",
        "prefilter.cpu_oracle",
        "batch.run_wall",
        "batch.images_per_second",
        "batch.gpu_per_image",
        "startup.cold",
        "startup.driver_cache_only",
        "startup.warm",
        "memory.cold_peak_mib",
        "memory.warm_peak_mib",
    ] {
        positive_median(&report, path);
    }
    assert!(
        field(&report, "render.triangles").as_u64() > Some(50_000),
        "the render benchmark draws the ~100k-triangle bowl"
    );
    // The `rays` stage runs where the device has ray queries (issue 17's two targets).
    let traced = !report["rays"].is_null();
    assert_eq!(
        traced,
        crate::common::validated_gpu().info().ray_query.is_enabled(),
        "the rays stage runs exactly where the device has ray queries"
    );
    if traced {
        for path in [
            "rays.off_gpu",
            "rays.on_gpu",
            "rays.sphere_on_board_process",
        ] {
            positive_median(&report, path);
        }
        field(&report, "rays.bottom_level");
        field(&report, "batch.ray_traced_images_per_second");
    }
    let targets = field(&report, "targets").as_array().unwrap();
    assert_eq!(
        targets.len(),
        if traced { 9 } else { 7 },
        "one verdict per target of issue 7, issue 16's brdf/paper ratio and issue 17's two"
    );
    for target in targets {
        for key in ["description", "value", "limit", "met"] {
            assert!(
                target.get(key).is_some(),
                "a target lacks `{key}`: {target}"
            );
        }
    }
    assert!(
        !stderr.contains("warning: ignoring the environment cache"),
        "the warm runs must find a valid cache file:\n{stderr}"
    );
}
