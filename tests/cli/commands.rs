//! The `shikki` binary as a user runs it: defaults, determinism, and every kind of bad input
//! giving a clear error, a non-zero exit code and no output file. Validation is on
//! (SHIKKI_VALIDATION=1), and with it any validation message fails the command itself.

use shikki::model::LacquerMaterial;
use shikki::oracle::{self, AnalyticShape, OracleScene};
use shikki::raster::camera::Camera;
use shikki::raster::lights::Light;
use std::path::Path;
use std::process::{Command, Output};

fn shikki(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_shikki"))
        .args(args)
        .current_dir(dir)
        .env("SHIKKI_VALIDATION", "1")
        // Tests must not write a pipeline cache into the user's home; the cache has its own test.
        .env("SHIKKI_PIPELINE_CACHE", "0")
        .output()
        .expect("the shikki binary runs")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn assert_ok(out: &Output) {
    assert!(out.status.success(), "shikki failed: {}", stderr(out));
}

/// Runs a failing command and checks: exit ≠ 0, stderr names every `expected` fragment, and no
/// file was left at `output` (relative to `dir`).
fn assert_fails(dir: &Path, args: &[&str], output: &str, expected: &[&str]) {
    let out = shikki(dir, args);
    let err = stderr(&out);
    assert!(!out.status.success(), "expected failure for {args:?}");
    assert_ne!(out.status.code(), Some(0));
    for fragment in expected {
        assert!(
            err.to_lowercase().contains(&fragment.to_lowercase()),
            "{args:?}: stderr lacks {fragment:?}:\n{err}"
        );
    }
    assert!(!dir.join(output).exists(), "{args:?} left {output}");
}

#[test]
fn no_arguments_renders_the_default_scene_to_shikki_png() {
    let dir = tempfile::tempdir().unwrap();
    let out = shikki(dir.path(), &[]);
    assert_ok(&out);
    let bytes = std::fs::read(dir.path().join("shikki.png")).unwrap();
    let (w, h, pixels) = shikki::output::png::decode_png_rgba8(&bytes).unwrap();
    assert_eq!((w, h), (1024, 1024));
    // Something was drawn: a lit, red object in the middle, over the environment (opaque).
    let centre = pixels[(512 * w + 512) as usize];
    assert_eq!(centre[3], 255);
    assert!(
        centre[0] > centre[1] && centre[0] > centre[2],
        "centre {centre:?} is not red"
    );
    assert_eq!(pixels[0][3], 255);
}

#[test]
fn identical_inputs_give_bit_identical_png_and_exr() {
    let dir = tempfile::tempdir().unwrap();
    for ext in ["png", "exr"] {
        let mut files = Vec::new();
        for run in 0..2 {
            let name = format!("run{run}.{ext}");
            let out = shikki(
                dir.path(),
                &[
                    "render",
                    "-o",
                    &name,
                    "--size",
                    "96x64",
                    "--preset",
                    "rough-red",
                ],
            );
            assert_ok(&out);
            files.push(std::fs::read(dir.path().join(&name)).unwrap());
        }
        assert!(files[0] == files[1], "{ext}: two identical runs differ");
    }
}

#[test]
fn exr_output_is_linear_radiance_with_coverage_alpha() {
    let dir = tempfile::tempdir().unwrap();
    let args = [
        "render",
        "-o",
        "a.exr",
        "--size",
        "64x64",
        "--samples",
        "1",
        "--preset",
        "rough-black",
        "--light",
        "dir:0,0,1:2,2,2",
        "--env",
        "none",
        "--background",
        "transparent",
    ];
    assert_ok(&shikki(dir.path(), &args));
    let image =
        shikki::output::exr::decode_exr(&std::fs::read(dir.path().join("a.exr")).unwrap()).unwrap();
    assert_eq!((image.width, image.height), (64, 64));
    assert_eq!(image.get(0, 0), [0.0; 4], "background is transparent black");
    let centre = image.get(32, 32);
    assert_eq!(centre[3], 1.0);
    // Linear radiance, no exposure or tone curve: the oracle's value at that pixel. Hand check of
    // the order of magnitude face-on: (F(0)·D(1)/4 + k_d·(a+b)·g/π)·E = (0.0414/(4π·0.04) +
    // 0.02·0.97·1.0159/π)·2 ≈ 0.177. 1 % covers the tessellated sphere (see gpu_raster.rs).
    let material = LacquerMaterial::preset("rough-black").unwrap();
    let lights = [Light::parse("dir:0,0,1:2,2,2").unwrap()];
    let camera = Camera::default();
    let scene = OracleScene {
        shape: AnalyticShape::Sphere,
        camera: &camera,
        lights: &lights,
        brdf: &material.brdf_params().unwrap(),
        fresnel: &material.fresnel_table().unwrap(),
    };
    let expected = oracle::render(&scene, 64, 64).get(32, 32);
    for c in 0..3 {
        assert!(
            (centre[c] - expected[c]).abs() <= 0.01 * expected[c],
            "centre {centre:?} vs oracle {expected:?}"
        );
    }
    assert!(
        (0.15..0.19).contains(&centre[0]),
        "centre radiance {centre:?}"
    );
}

#[test]
fn bad_material_values_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let base = ["render", "-o", "x.png", "--size", "32x32"];
    let cases: &[(&[&str], &[&str])] = &[
        (&["--set", "r=7"], &["r", "7", "1", "5.6"]),
        (&["--set", "r=0.5"], &["r", "0.5"]),
        (&["--set", "m=0"], &["m", "(0, 1]"]),
        (&["--set", "m=-0.2"], &["m", "-0.2"]),
        (&["--set", "m=NaN"], &["m", "nan"]),
        (&["--set", "a=inf"], &["a", "inf"]),
        (&["--set", "kd=0.5,2,0.1"], &["kd"]),
        (&["--set", "shininess=3"], &["shininess"]),
        (&["--set", "m"], &["key=value"]),
        (&["--preset", "glossy"], &["glossy", "smooth-red"]),
    ];
    for (extra, expected) in cases {
        let args: Vec<&str> = base.iter().chain(extra.iter()).copied().collect();
        assert_fails(dir.path(), &args, "x.png", expected);
    }
}

#[test]
fn malformed_fresnel_csv_fails_with_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "unsorted.csv",
            "angle_deg,r,g,b\n0,0.04,0.04,0.04\n50,0.1,0.1,0.1\n40,0.2,0.2,0.2\n90,1,1,1\n",
            "4",
        ),
        (
            "no_zero.csv",
            "angle_deg,r,g,b\n5,0.04,0.04,0.04\n90,1,1,1\n",
            "2",
        ),
        (
            "no_ninety.csv",
            "angle_deg,r,g,b\n0,0.04,0.04,0.04\n80,1,1,1\n",
            "3",
        ),
        (
            "range.csv",
            "angle_deg,r,g,b\n0,0.04,1.5,0.04\n90,1,1,1\n",
            "2",
        ),
        (
            "header.csv",
            "theta,red,green,blue\n0,0.04,0.04,0.04\n90,1,1,1\n",
            "1",
        ),
    ];
    for (name, text, line) in cases {
        std::fs::write(dir.path().join(name), text).unwrap();
        let set = format!("fresnel={name}");
        let args = ["render", "-o", "x.png", "--size", "32x32", "--set", &set];
        assert_fails(dir.path(), &args, "x.png", &[&format!("{name}:{line}")]);
    }
}

#[test]
fn unwritable_output_fails_before_rendering_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    assert_fails(
        dir.path(),
        &["render", "-o", "missing/dir/x.png", "--size", "32x32"],
        "missing/dir/x.png",
        &["missing/dir"],
    );
    assert_fails(
        dir.path(),
        &["render", "-o", "x.jpg", "--size", "32x32"],
        "x.jpg",
        &["x.jpg", ".png", ".exr"],
    );
}

#[test]
fn a_failed_run_removes_a_stale_output_file() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("x.png"), b"old image").unwrap();
    assert_fails(
        dir.path(),
        &["render", "-o", "x.png", "--size", "32x32", "--set", "m=2"],
        "x.png",
        &["m"],
    );
}

#[test]
fn bad_cli_values_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let base = ["render", "-o", "x.png"];
    let cases: &[(&[&str], &[&str])] = &[
        (&["--size", "0x10"], &["size"]),
        (&["--size", "10"], &["size"]),
        (&["--samples", "3"], &["samples", "1", "4"]),
        (&["--light", "spot:0,0,1:1,1,1"], &["spot"]),
        (&["--light", "dir:0,0,0:1,1,1"], &["light"]),
        (&["--light", "dir:0,0,1:1,-1,1"], &["light"]),
        (&["--eye", "0,0,0", "--target", "0,0,0"], &["eye"]),
        (&["--fov", "180"], &["fov"]),
        (&["--mesh", "builtin:teapot"], &["teapot"]),
        (&["--tonemap", "filmic"], &["filmic"]),
    ];
    for (extra, expected) in cases {
        let args: Vec<&str> = base.iter().chain(extra.iter()).copied().collect();
        assert_fails(dir.path(), &args, "x.png", expected);
    }
}

/// An error that quotes its cause (`cannot read PATH: CAUSE`) says the cause once, not again as
/// a `caused by:` line.
#[test]
fn a_missing_environment_names_its_cause_once() {
    let dir = tempfile::tempdir().unwrap();
    let args = [
        "render",
        "-o",
        "x.png",
        "--size",
        "8x8",
        "--env",
        "absent.hdr",
    ];
    assert_fails(dir.path(), &args, "x.png", &["absent.hdr"]);
    let err = stderr(&shikki(dir.path(), &args));
    assert!(!err.contains("caused by"), "{err}");
    assert_eq!(err.matches("os error").count(), 1, "{err}");
}

#[test]
fn brdf_command_cpu_and_gpu_agree_and_print_nine_digits() {
    let dir = tempfile::tempdir().unwrap();
    let input = "nx,ny,nz,vx,vy,vz,lx,ly,lz\n\
                 0,0,1,0,0,1,0,0,1\n\
                 0,0,2,1,0,1,-1,0,1\n\
                 0,1,0,0.3,1,0,-0.2,1,0.1\n\
                 0,0,1,1,0,0.01,-1,0,0.02\n\
                 0,0,1,0,0,-1,0,0,1\n";
    std::fs::write(dir.path().join("dirs.csv"), input).unwrap();
    let mut tables = Vec::new();
    for backend in ["cpu", "gpu"] {
        let out = shikki(
            dir.path(),
            &[
                "brdf",
                "--preset",
                "rough-red",
                "--input",
                "dirs.csv",
                "--backend",
                backend,
            ],
        );
        assert_ok(&out);
        let text = String::from_utf8(out.stdout).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("nx,ny,nz,vx,vy,vz,lx,ly,lz,r,g,b"));
        let rows: Vec<Vec<f64>> = lines
            .map(|l| {
                for cell in l.split(',') {
                    let digits = cell
                        .split(['e', 'E'])
                        .next()
                        .unwrap()
                        .replace(['-', '.'], "");
                    assert!(
                        digits.len() >= 9,
                        "{cell} has fewer than 9 significant digits"
                    );
                }
                l.split(',').map(|c| c.parse().unwrap()).collect()
            })
            .collect();
        assert_eq!(rows.len(), 5);
        // Vectors are printed normalised.
        assert!((rows[1][5] - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-9);
        // Below the horizon: exactly zero.
        assert_eq!(&rows[4][9..], &[0.0, 0.0, 0.0]);
        tables.push(rows);
    }
    for (cpu, gpu) in tables[0].iter().zip(&tables[1]) {
        for c in 9..12 {
            let rel = (cpu[c] - gpu[c]).abs() / cpu[c].abs().max(1e-6);
            assert!(rel <= 1e-4, "cpu {} vs gpu {}", cpu[c], gpu[c]);
        }
    }
}

#[test]
fn fresnel_command_prints_every_whole_degree() {
    let dir = tempfile::tempdir().unwrap();
    let out = shikki(dir.path(), &["fresnel", "--preset", "smooth"]);
    assert_ok(&out);
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "angle_deg,r,g,b");
    assert_eq!(lines.len(), 92);
    let first: Vec<f64> = lines[1].split(',').map(|c| c.parse().unwrap()).collect();
    // ((n-1)/(n+1))² for n ≈ 1.51 at normal incidence.
    assert_eq!(first[0], 0.0);
    assert!((first[1] - 0.0414).abs() < 2e-3, "{first:?}");
    let last: Vec<f64> = lines[91].split(',').map(|c| c.parse().unwrap()).collect();
    assert_eq!(last, vec![90.0, 1.0, 1.0, 1.0]);
}

#[test]
fn info_names_the_device() {
    let dir = tempfile::tempdir().unwrap();
    let out = shikki(dir.path(), &["info"]);
    assert_ok(&out);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("device:") && text.contains("Vulkan:"),
        "{text}"
    );
}

#[test]
fn missing_vulkan_driver_gives_install_hint() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_shikki"))
        .args(["render", "-o", "x.png", "--size", "8x8"])
        .current_dir(dir.path())
        .env("VK_DRIVER_FILES", dir.path().join("no-such-icd.json"))
        .env("VK_ICD_FILENAMES", dir.path().join("no-such-icd.json"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(err.contains("mesa-vulkan-drivers"), "{err}");
    assert!(!dir.path().join("x.png").exists());
}

#[test]
fn prefilter_writes_every_layer_irradiance_and_a_preview() {
    let dir = tempfile::tempdir().unwrap();
    let args = [
        "prefilter",
        "builtin:studio",
        "-o",
        "pf",
        "--face-size",
        "32",
    ];
    assert_ok(&shikki(
        dir.path(),
        &[&args[..], &["--layers", "4"]].concat(),
    ));
    for k in 0..4 {
        let bytes = std::fs::read(dir.path().join(format!("pf/layer_{k}.exr"))).unwrap();
        let image = shikki::output::exr::decode_exr(&bytes).unwrap();
        // A horizontal strip of the six faces: width 6N, height N (layer 0 at N = 32).
        assert_eq!(image.width, 6 * image.height, "layer {k}");
        if k == 0 {
            assert_eq!(image.height, 32);
        }
        assert!(image.pixels.iter().flatten().all(|v| v.is_finite()));
    }
    let irradiance = shikki::output::exr::decode_exr(
        &std::fs::read(dir.path().join("pf/irradiance.exr")).unwrap(),
    )
    .unwrap();
    assert_eq!(irradiance.width, 6 * irradiance.height);
    let preview = std::fs::read(dir.path().join("pf/preview.png")).unwrap();
    assert!(shikki::output::png::decode_png_rgba8(&preview).is_ok());
    // Again with fewer layers: the earlier run's layers past them would pass for this run's.
    assert_ok(&shikki(
        dir.path(),
        &[&args[..], &["--layers", "2"]].concat(),
    ));
    let layers = |dir: &std::path::Path| {
        let mut names: Vec<String> = std::fs::read_dir(dir.join("pf"))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with("layer_"))
            .collect();
        names.sort();
        names
    };
    assert_eq!(layers(dir.path()), ["layer_0.exr", "layer_1.exr"]);
    // A failed run leaves none of its files, as a failed render leaves no image.
    let out = shikki(dir.path(), &[&args[..], &["--beta-min", "0"]].concat());
    assert!(!out.status.success());
    assert!(layers(dir.path()).is_empty());
    assert!(!dir.path().join("pf/irradiance.exr").exists());
    assert!(!dir.path().join("pf/preview.png").exists());
}

/// An unknown `SHIKKI_RAY_QUERY` is an error naming the valid values: `off` was taken for
/// "auto" and traced rays without a word.
#[test]
fn an_unknown_ray_query_setting_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_shikki"))
        .env("SHIKKI_RAY_QUERY", "off")
        .env("SHIKKI_PIPELINE_CACHE", "0")
        .args(["render", "--size", "8x8", "-o", "x.png"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(
        err.contains("SHIKKI_RAY_QUERY") && err.contains("pipeline"),
        "{err}"
    );
    assert!(!dir.path().join("x.png").exists());
}

#[test]
fn prefilter_rejects_bad_parameters() {
    let dir = tempfile::tempdir().unwrap();
    let out = shikki(
        dir.path(),
        &[
            "prefilter",
            "builtin:studio",
            "-o",
            "pf",
            "--face-size",
            "100",
        ],
    );
    assert!(!out.status.success());
    assert!(stderr(&out).contains("power of two"), "{}", stderr(&out));
    let out = shikki(dir.path(), &["prefilter", "nothing.hdr", "-o", "pf"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("nothing.hdr"), "{}", stderr(&out));
}

/// A CC0 HDRI shipped in the repository (`assets/env/`, licence beside the files).
fn asset_env(name: &str) -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/env")
        .join(name);
    assert!(path.exists(), "{} is missing", path.display());
    path.display().to_string()
}

#[test]
fn real_hdris_load_and_render() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["studio_piz.exr", "studio.hdr"] {
        let env = asset_env(name);
        let args = [
            "render",
            "-o",
            "x.exr",
            "--size",
            "48x48",
            "--samples",
            "1",
            "--env",
            &env,
        ];
        assert_ok(&shikki(dir.path(), &args));
        let image =
            shikki::output::exr::decode_exr(&std::fs::read(dir.path().join("x.exr")).unwrap())
                .unwrap();
        // Background is the environment: opaque everywhere, finite, not black.
        assert!(image
            .pixels
            .iter()
            .all(|p| p[3] == 1.0 && p.iter().all(|v| v.is_finite())));
        let mean: f32 = image.pixels.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>()
            / image.pixels.len() as f32;
        assert!(mean > 1e-3, "{name}: mean radiance {mean}");
    }
}

#[test]
fn background_modes() {
    let dir = tempfile::tempdir().unwrap();
    let corner = |background: &str| -> [f32; 4] {
        let args = [
            "render",
            "-o",
            "b.exr",
            "--size",
            "32x32",
            "--samples",
            "1",
            "--background",
            background,
        ];
        assert_ok(&shikki(dir.path(), &args));
        shikki::output::exr::decode_exr(&std::fs::read(dir.path().join("b.exr")).unwrap())
            .unwrap()
            .get(0, 0)
    };
    assert_eq!(corner("transparent"), [0.0; 4]);
    assert_eq!(corner("0.25,0.5,1"), [0.25, 0.5, 1.0, 1.0]);
    let env = corner("env");
    assert_eq!(env[3], 1.0);
    let out = shikki(
        dir.path(),
        &["render", "-o", "b.png", "--background", "purple"],
    );
    assert!(!out.status.success());
    assert!(stderr(&out).contains("purple"));
}

#[test]
fn pipeline_cache_is_saved_reused_and_survives_corruption() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache/pipelines.bin");
    let run = || {
        Command::new(env!("CARGO_BIN_EXE_shikki"))
            .args(["render", "-o", "x.png", "--size", "16x16", "--env", "none"])
            .current_dir(dir.path())
            .env("SHIKKI_VALIDATION", "1")
            .env("SHIKKI_PIPELINE_CACHE", &cache)
            .output()
            .unwrap()
    };
    assert_ok(&run());
    let data = std::fs::read(&cache).expect("the cache file is written");
    // VkPipelineCacheHeaderVersionOne: header length 32, version 1.
    assert!(data.len() >= 32);
    assert_eq!(u32::from_le_bytes(data[0..4].try_into().unwrap()), 32);
    assert_eq!(u32::from_le_bytes(data[4..8].try_into().unwrap()), 1);
    // A warm start reads it back (validation on: zero messages).
    assert_ok(&run());
    // A corrupted or foreign cache is ignored, not trusted.
    std::fs::write(
        &cache,
        b"not a pipeline cache at all, but long enough to look like one",
    )
    .unwrap();
    assert_ok(&run());
}
