//! Ray queries on and off: the device reports them, `SHIKKI_RAY_QUERY=0` takes the path of a device
//! without them, and that path renders what shikki renders today and says so once on stderr.
//! Validation (with its synchronisation checks) is on in every run here.

use crate::common;

use shikki::gpu::{ContextOptions, GpuContext, RayQuery, RayTracingChoice};
use std::path::Path;
use std::process::{Command, Output};

fn shikki(dir: &Path, ray_query: bool, args: &[&str]) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_shikki"));
    command
        .args(args)
        .current_dir(dir)
        .env("SHIKKI_VALIDATION", "1")
        .env("SHIKKI_SYNC_VALIDATION", "1")
        .env("SHIKKI_PIPELINE_CACHE", "0");
    // With rays on, the child traces as this process's contexts do (`SHIKKI_RAY_QUERY` inherited:
    // unset, or `pipeline`).
    if !ray_query {
        command.env("SHIKKI_RAY_QUERY", "0");
    }
    let out = command.output().expect("the shikki binary runs");
    assert!(
        out.status.success(),
        "shikki {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn context(no_ray_query: bool) -> GpuContext {
    GpuContext::new(&ContextOptions {
        validation: true,
        synchronization_validation: true,
        device_name: std::env::var("SHIKKI_DEVICE").ok(),
        ray_tracing: match no_ray_query {
            true => RayTracingChoice::Off,
            false => ContextOptions::ray_tracing_by_env(),
        },
        ..ContextOptions::default()
    })
    .expect("a validated Vulkan context")
}

/// Mesa's lavapipe has ray queries from 24.1 on (the reference device, which `scripts/setup`
/// installs); an older one must report them missing, never enabled.
fn lavapipe_mesa_version(info: &shikki::gpu::AdapterInfo) -> Option<(u32, u32)> {
    info.name
        .starts_with("llvmpipe")
        .then(|| info.mesa_version())
        .flatten()
}

#[test]
fn device_reports_ray_queries_and_the_option_turns_them_off() {
    let on = context(false);
    let off = context(true);
    common::assert_no_validation_messages(&on);
    common::assert_no_validation_messages(&off);
    match lavapipe_mesa_version(on.info()) {
        Some(version) if version >= (24, 1) => {
            // Mesa 25's lavapipe has ray-tracing pipelines too: `SHIKKI_RAY_QUERY=pipeline`
            // takes NVIDIA's H100/H200 path.
            let expected = match ContextOptions::ray_tracing_by_env() {
                RayTracingChoice::Pipeline => RayQuery::Pipeline,
                _ => RayQuery::Enabled,
            };
            assert_eq!(on.info().ray_query, expected, "{}", on.info().driver_info);
            assert_eq!(off.info().ray_query, RayQuery::Disabled);
        }
        Some(_) => assert!(matches!(on.info().ray_query, RayQuery::Missing(_))),
        None => {}
    }
    // Off is never on, whatever the device.
    assert!(!off.info().ray_query.is_enabled());
    if on.info().ray_query.is_enabled() {
        assert_eq!(off.info().ray_query, RayQuery::Disabled);
    }
    // The warning a program shows: none when enabled; otherwise it names what is missing.
    assert_eq!(
        on.info().ray_query.warning("dev").is_none(),
        on.info().ray_query.is_enabled()
    );
    let warning = off
        .info()
        .ray_query
        .warning("dev")
        .expect("a warning when off");
    assert!(warning.contains("SHIKKI_RAY_QUERY=0") || warning.contains("VK_KHR_ray_query"));
}

#[test]
fn missing_ray_queries_name_the_extensions_and_what_to_install() {
    let missing = RayQuery::Missing("no VK_KHR_acceleration_structure, VK_KHR_ray_query".into());
    let warning = missing.warning("old GPU").unwrap();
    for fragment in [
        "old GPU",
        "VK_KHR_acceleration_structure",
        "Mesa >= 24.1",
        "scripts/setup",
    ] {
        assert!(warning.contains(fragment), "{warning}");
    }
    assert!(missing.summary().starts_with("no ("));
}

#[test]
fn info_prints_whether_ray_queries_are_available() {
    let dir = tempfile::tempdir().unwrap();
    let gpu = context(false);
    let on = shikki(dir.path(), true, &["info"]);
    let text = String::from_utf8_lossy(&on.stdout).into_owned();
    let line = text
        .lines()
        .find(|l| l.starts_with("ray queries:"))
        .unwrap_or_else(|| panic!("no ray-query line in:\n{text}"));
    assert!(
        line.ends_with(&gpu.info().ray_query.summary()),
        "{line:?} vs {:?}",
        gpu.info().ray_query
    );
    let off = shikki(dir.path(), false, &["info"]);
    let text = String::from_utf8_lossy(&off.stdout).into_owned();
    assert!(
        text.contains("ray queries:          available, turned off")
            || text.contains("ray queries:          no ("),
        "{text}"
    );
}

/// Without ray queries the image is that of ray tracing turned off (every object alone), byte
/// for byte, and stderr says why once.
#[test]
fn render_without_ray_queries_is_the_same_image_and_says_so_once() {
    let dir = tempfile::tempdir().unwrap();
    let on = shikki(
        dir.path(),
        true,
        &[
            "render",
            "--size",
            "96x96",
            "-o",
            "on.png",
            "--no-ray-tracing",
        ],
    );
    let off = shikki(
        dir.path(),
        false,
        &["render", "--size", "96x96", "-o", "off.png"],
    );
    let read = |name: &str| std::fs::read(dir.path().join(name)).unwrap();
    assert_eq!(read("on.png"), read("off.png"));
    let on_err = String::from_utf8_lossy(&on.stderr).into_owned();
    let off_err = String::from_utf8_lossy(&off.stderr).into_owned();
    if context(false).info().ray_query.is_enabled() {
        assert!(!on_err.contains("ray queries"), "{on_err}");
    }
    assert_eq!(
        off_err.matches("warning:").count(),
        1,
        "one warning expected:\n{off_err}"
    );
    assert!(off_err.contains("SHIKKI_RAY_QUERY=0") || off_err.contains("no ray queries"));
}
