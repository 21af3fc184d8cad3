//! Bad-input corpus, scene / jobs / material TOML, Fresnel and goniometer CSV, MERL binaries, the
//! CLI's `--set` values and image sizes (tests/common/corpus.md lists every case). Each case
//! asserts the exact error kind (Parse with file and line, InvalidParameter with its field, Read
//! of the path), that the message says what, where and the fix, and through the CLI exit code 1
//! (2 for clap's usage errors) with nothing written.

use crate::common::corpus as support;

use std::path::Path;
use std::time::Duration;

use shikki::fit::csv::{parse_goniometer_csv, read_goniometer_csv, MAX_GONIOMETER_CSV_BYTES};
use shikki::fit::merl::{parse_merl, read_merl, MERL_FILE_BYTES};
use shikki::model::fresnel::{FresnelTable, MAX_FRESNEL_CSV_BYTES};
use shikki::model::material_file::{load_material_file, material_from_toml_str};
use shikki::model::LacquerMaterial;
use shikki::scene::batch::BatchPlan;
use shikki::scene::parse::MAX_SCENE_FILE_BYTES;
use shikki::scene::{load_scene_file, parse_scene_str, SceneDocument};
use shikki::Error;
use support::*;

const HEADER_ONLY: Duration = Duration::from_secs(2);

fn scene(text: &str) -> shikki::Result<shikki::scene::Scene> {
    parse_scene_str(text, "s.toml", Path::new("."))
}

// ---- scene TOML -----------------------------------------------------------------------------

#[test]
fn empty_scene_file_is_the_documented_defaults_not_an_error() {
    // docs/scene.md: every section is optional; an empty scene shows the environment alone.
    let scene = scene("").unwrap();
    assert!(scene.objects.is_empty());
}

#[test]
fn truncated_scene_names_the_line_and_column() {
    let ws = Workspace::new();
    let path = ws.file(
        "cut.toml",
        "[camera]\nfov_deg = 30\n\n[[object]]\nmesh = \"builtin:bo",
    );
    let message = expect_parse(load_scene_file(&path), "cut.toml", 5);
    assert_names(&message, &["column"]);
    assert_cli_fails(
        &ws,
        &["render", "cut.toml", "-o", "out/r.png"],
        &["cut.toml:5"],
    );
}

#[test]
fn scene_with_binary_garbage_names_the_line_of_the_first_bad_byte() {
    let ws = Workspace::new();
    let path = ws.file("binary.toml", b"[camera]\nfov_deg = 30\x00\xff\xfe\n");
    let message = expect_parse(load_scene_file(&path), "binary.toml", 2);
    // "fov_deg = 30" is 12 bytes, NUL is valid UTF-8 (and a TOML error later), 0xFF is byte 14.
    assert_names(
        &message,
        &["byte 14", "not UTF-8", "save the scene file as UTF-8"],
    );
    assert_cli_fails(
        &ws,
        &["render", "binary.toml", "-o", "out/r.png"],
        &["binary.toml:2", "UTF-8"],
    );
}

#[test]
fn scene_nan_inf_and_negative_values_name_the_key() {
    for (text, line, fragments) in [
        (
            "[camera]\nfov_deg = nan\n",
            2,
            vec!["`fov_deg` must be finite"],
        ),
        (
            "[camera]\neye = [0, inf, 1]\n",
            2,
            vec!["`eye` must be three finite numbers", "inf"],
        ),
        (
            "[[object]]\nmesh = \"builtin:bowl\"\nscale = -1\n",
            3,
            vec!["`scale` must be positive"],
        ),
        (
            "[[object]]\nmesh = \"builtin:bowl\"\nmaterial = { m = -0.1 }\n",
            3,
            vec!["invalid m = -0.1", "[0.001, 1]"],
        ),
        (
            "[environment]\nsource = \"none\"\nintensity = -1\n",
            3,
            vec!["`intensity` must be ≥ 0"],
        ),
        (
            "[[light]]\nkind = \"dir\"\nto_light = [0, 0, 0]\nirradiance = 1\n",
            3,
            vec!["`to_light` must not be the zero vector"],
        ),
        (
            "[output]\nexposure = -inf\n",
            2,
            vec!["`exposure` must be finite"],
        ),
        (
            "[output]\nbackground = [-1, 0, 0]\n",
            2,
            vec!["`background` colour components must be ≥ 0"],
        ),
    ] {
        let message = expect_parse(scene(text), "s.toml", line);
        assert_names(&message, &fragments);
    }
}

#[test]
fn scene_image_sizes_beyond_the_limits_name_the_range() {
    for (text, fragment) in [
        (
            "[output]\nsize = \"100000x100000\"\n",
            "whole numbers in 1..=16384",
        ),
        (
            "[output]\nsize = [0, 10]\n",
            "`size` must be a whole number in 1..=16384",
        ),
        (
            "[output]\nwidth = 4294967296\n",
            "`width` must be a whole number in 1..=16384",
        ),
        (
            "[output]\nheight = -5\n",
            "`height` must be a whole number in 1..=16384",
        ),
        ("[output]\nsamples = 3\n", "`samples` must be one of [1, 4]"),
    ] {
        let message = expect_parse(scene(text), "s.toml", 2);
        assert_names(&message, &[fragment]);
    }
}

#[test]
fn deeply_nested_toml_is_refused_without_overflowing_the_stack() {
    let ws = Workspace::new();
    // 100 000 nested arrays: a recursive parser without a depth limit would overflow its stack.
    let text = format!("x = {}{}\n", "[".repeat(100_000), "]".repeat(100_000));
    let path = ws.file("deep.toml", &text);
    let message = expect_parse(load_scene_file(&path), "deep.toml", 1);
    assert!(!message.is_empty());
    let message = expect_parse(
        material_from_toml_str(&text, Path::new("."), "deep-material.toml"),
        "deep-material.toml",
        1,
    );
    assert!(!message.is_empty());
    assert_cli_fails(
        &ws,
        &["render", "deep.toml", "-o", "out/r.png"],
        &["deep.toml:1"],
    );
}

#[test]
fn scene_file_larger_than_the_limit_is_refused_before_reading() {
    let ws = Workspace::new();
    let path = ws.path().join("huge.toml");
    sparse_file(&path, b"[camera]\n# ", 1 << 40);
    let message = quickly("huge.toml", HEADER_ONLY, || {
        expect_invalid(load_scene_file(&path), "scene file")
    });
    assert_names(
        &message,
        &[
            "huge.toml",
            &format!("at most {MAX_SCENE_FILE_BYTES} bytes"),
        ],
    );
    assert_cli_fails(
        &ws,
        &["render", "huge.toml", "-o", "out/r.png"],
        &["scene file"],
    );
}

#[test]
fn missing_scene_file_is_a_read_error() {
    let ws = Workspace::new();
    let missing = ws.path().join("nope.toml");
    assert_names(
        &expect_read(load_scene_file(&missing), &missing),
        &["no such file"],
    );
    assert_cli_fails(
        &ws,
        &["render", "nope.toml", "-o", "out/r.png"],
        &["cannot read", "nope.toml"],
    );
}

// ---- --set values ----------------------------------------------------------------------------

#[test]
fn scene_set_values_that_are_nan_or_malformed_name_the_override() {
    let base = "[camera]\nfov_deg = 30\n\n[[object]]\nmesh = \"builtin:bowl\"\n";
    for (assignment, field, fragment) in [
        (
            "camera.fov_deg=nan",
            "--set camera.fov_deg",
            "`fov_deg` must be finite",
        ),
        (
            "camera.fov_deg=inf",
            "--set camera.fov_deg",
            "must be finite",
        ),
        (
            "object.0.scale=-2",
            "--set object.0.scale",
            "`scale` must be positive",
        ),
        (
            "object.0.material.m=nan",
            "--set object.0.material.m",
            "finite",
        ),
        (
            "output.size=100000x100000",
            "--set output.size",
            "1..=16384",
        ),
        ("output.width=1e30", "--set output.width", "1..=16384"),
    ] {
        let mut document = SceneDocument::parse(base, "s.toml", Path::new(".")).unwrap();
        document.set(assignment, Path::new(".")).unwrap();
        let message = expect_invalid(document.build(), field);
        assert_names(&message, &[fragment]);
    }
    for (assignment, field, fragment) in [
        ("camera.fov_deg", "--set", "expected PATH=VALUE"),
        (
            "object.7.mesh=builtin:bowl",
            "--set object.7.mesh",
            "(0..1)",
        ),
        ("object..mesh=x", "--set object..mesh", "not a field path"),
        (
            "camera.fov_deg.x=1",
            "--set camera.fov_deg.x",
            "cannot go into `fov_deg`",
        ),
    ] {
        let mut document = SceneDocument::parse(base, "s.toml", Path::new(".")).unwrap();
        let message = expect_invalid(document.set(assignment, Path::new(".")), field);
        assert_names(&message, &[fragment]);
    }
    let ws = Workspace::new();
    ws.file("s.toml", base);
    assert_cli_fails(
        &ws,
        &[
            "render",
            "s.toml",
            "--set",
            "camera.fov_deg=nan",
            "-o",
            "out/r.png",
        ],
        &["--set camera.fov_deg", "finite"],
    );
}

#[test]
fn material_set_values_that_are_nan_or_malformed_name_the_field() {
    for (key, value, fragment) in [
        ("m", "nan", "finite number"),
        ("m", "2", "(0, 1]"),
        ("r", "inf", "finite number"),
        ("kd", "1,2", "kd"),
        ("kd", "-1,0,0", "kd"),
        ("extrapolate_g", "maybe", "`true` or `false`"),
        ("ior_a", "0.5", "ior"),
        ("c0", "1e999", "finite number"),
    ] {
        let mut material = LacquerMaterial::default();
        let result = material.set(key, value);
        let message = match &result {
            Err(shikki::Error::InvalidParameter { field, .. }) => {
                assert!(field.contains(key), "{key}: field {field}");
                result.unwrap_err().to_string()
            }
            other => panic!("{key}={value}: {other:?}"),
        };
        assert_names(&message, &[fragment]);
    }
    let ws = Workspace::new();
    assert_cli_fails(
        &ws,
        &[
            "render",
            "--set",
            "m=nan",
            "--size",
            "16x16",
            "-o",
            "out/r.png",
        ],
        &["invalid m = nan", "finite"],
    );
    assert_cli_fails(
        &ws,
        &[
            "render",
            "--set",
            "nokey",
            "--size",
            "16x16",
            "-o",
            "out/r.png",
        ],
        &["KEY=VALUE"],
    );
}

#[test]
fn cli_image_size_beyond_what_the_argument_accepts_is_a_usage_error() {
    let ws = Workspace::new();
    let out = shikki(
        ws.path(),
        &["render", "--size", "100000x100000", "-o", "out/r.png"],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    // clap's usage errors exit with 2.
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert_names(&stderr, &["--size", "100000x100000", "WxH", "1..=65535"]);
    assert!(ws.outputs().is_empty());
}

#[test]
fn cli_image_size_beyond_the_device_limit_names_the_device_limit() {
    // One pixel past the device's maxImageDimension2D (lavapipe 16384, NVIDIA 32768) passes
    // `--size` (1..=65535), and the draw refuses it (after opening the GPU, before allocating any
    // image). The CLI picks the same device as this context (SHIKKI_DEVICE).
    let limit = crate::common::validated_gpu().info().max_image_dimension_2d;
    let width = limit + 1;
    assert!(
        width <= 65535,
        "a device limit of {limit} leaves nothing for --size to pass"
    );
    let size = format!("{width}x16");
    let ws = Workspace::new();
    assert_cli_fails(
        &ws,
        &[
            "render",
            "--size",
            &size,
            "--samples",
            "1",
            "-o",
            "out/r.png",
        ],
        &[
            &format!("invalid width = {width}"),
            &format!("1..={limit} pixels on this device"),
        ],
    );
}

// ---- jobs TOML --------------------------------------------------------------------------------

fn jobs(text: &str) -> shikki::Result<BatchPlan> {
    BatchPlan::parse(text, "jobs.toml", Path::new("."))
}

#[test]
fn jobs_file_errors_name_the_line() {
    for (text, line, fragment) in [
        ("", 1, "needs `scene`"),
        ("scene = 3\n", 1, "`scene` must be a path or a table"),
        (
            "scene = \"s.toml\"\nnmae = \"x\"\n",
            2,
            "did you mean `name`?",
        ),
        (
            "[scene]\n[sweep]\n\"camera.fov_deg\" = []\n",
            3,
            "non-empty array",
        ),
        (
            "name = \"{nope}\"\n[scene]\n",
            1,
            "placeholder {nope} names no sweep",
        ),
        ("name = \"a{\"\n[scene]\n", 1, "without its `}`"),
        (
            "name = \"same\"\n[scene]\n[sweep]\n\"camera.fov_deg\" = [20, 30]\n",
            1,
            "no placeholder",
        ),
        ("[scene]\n[sweep\n", 2, "column"),
    ] {
        let message = expect_parse(jobs(text), "jobs.toml", line);
        assert_names(&message, &[fragment]);
    }
    let ws = Workspace::new();
    ws.file("jobs.toml", "scene = \"missing.toml\"\n");
    assert_cli_fails(
        &ws,
        &["batch", "jobs.toml", "--out", "out/b"],
        &["jobs.toml:1", "missing.toml"],
    );
}

#[test]
fn jobs_sweep_value_errors_fail_the_job_with_the_sweep_named() {
    let plan = jobs("[scene]\n[sweep]\n\"camera.fov_deg\" = [30, nan]\n").unwrap();
    let all = plan.jobs();
    assert!(plan.prepare(&all[0]).is_ok());
    let message = expect_parse(plan.prepare(&all[1]), "jobs.toml", 3);
    assert_names(&message, &["`fov_deg` must be finite"]);
}

#[test]
fn jobs_with_a_sweep_product_of_10_pow_12_are_refused_quickly() {
    // Four sweeps of 1000 values: 10^12 jobs from a 16 KB file. The plan must refuse the product
    // (or handle it lazily) instead of materialising every job.
    let values: Vec<String> = (0..1000).map(|v| v.to_string()).collect();
    let list = values.join(", ");
    let text = format!(
        "[scene]\nname = \"{{job}}\"\n[sweep]\n\"camera.fov_deg\" = [{list}]\n\
         \"camera.orbit_deg\" = [{list}]\n\"output.exposure\" = [{list}]\n\
         \"environment.intensity\" = [{list}]\n"
    );
    let result = quickly("10^12 jobs", HEADER_ONLY, || jobs(&text));
    let message = expect_parse(result, "jobs.toml", 3);
    assert_names(&message, &["jobs"]);
}

// ---- material TOML ---------------------------------------------------------------------------

#[test]
fn material_file_errors_name_line_key_and_valid_values() {
    let ws = Workspace::new();
    for (name, text, line, fragment) in [
        ("cut.toml", "m = 0.1\nkd = [0.5, 0.0", 2, "column"),
        ("nan.toml", "m = nan\n", 1, "invalid m = NaN"),
        ("neg.toml", "kd = [0.5, -0.1, 0.2]\n", 1, "kd"),
        ("inf.toml", "a = 0.2\nr = inf\n", 2, "finite"),
        (
            "type.toml",
            "m = \"0.1\"\n",
            1,
            "`m` must be a number, found a string",
        ),
        (
            "key.toml",
            "bta_normal = 0.2\n",
            1,
            "did you mean `beta_normal`?",
        ),
        ("binary.toml", "m = 0.1\n\u{0}\n", 2, "column"),
    ] {
        let path = ws.file(name, text);
        let message = expect_parse(load_material_file(&path), name, line);
        assert_names(&message, &[fragment]);
    }
    // A table that cannot be read is a read failure at the line that names it, not a parse
    // error (the C API's IO_ERROR).
    let path = ws.file("fresnel.toml", "fresnel = \"missing.csv\"\n");
    match load_material_file(&path) {
        Err(Error::ReadNamedAt {
            file,
            line,
            message,
            ..
        }) => {
            assert!(file.ends_with("fresnel.toml") && line == 1, "{file}:{line}");
            assert_names(&message, &["column 11", "cannot read", "missing.csv"]);
        }
        other => panic!("expected a read failure at fresnel.toml:1, got {other:?}"),
    }
    let path = ws.file("latin1.toml", b"m = 0.1\n# caf\xe9\n");
    let message = expect_parse(load_material_file(&path), "latin1.toml", 2);
    assert_names(
        &message,
        &["byte 6", "not UTF-8", "save the material file as UTF-8"],
    );
    // An empty material file is the default material (every key is optional).
    assert_eq!(
        load_material_file(&ws.file("empty.toml", "")).unwrap(),
        LacquerMaterial::default()
    );
    assert_cli_fails(
        &ws,
        &[
            "render",
            "--material",
            "nan.toml",
            "--size",
            "16x16",
            "-o",
            "out/r.png",
        ],
        &["nan.toml:1", "invalid m"],
    );
}

#[test]
fn material_file_larger_than_the_limit_is_refused_before_reading() {
    let ws = Workspace::new();
    let path = ws.path().join("huge.toml");
    sparse_file(&path, b"m = 0.1\n#", 1 << 40);
    let message = quickly("huge material", HEADER_ONLY, || {
        expect_invalid(load_material_file(&path), "material file")
    });
    assert_names(&message, &["huge.toml", "bytes are read"]);
}

// ---- Fresnel CSV -----------------------------------------------------------------------------

#[test]
fn fresnel_csv_errors_name_line_and_fix() {
    let ws = Workspace::new();
    for (name, text, line, fragment) in [
        ("empty.csv", "", 1, "empty file"),
        ("header.csv", "angle,r,g,b\n0,0,0,0\n", 1, "wrong header"),
        (
            "cut.csv",
            "angle_deg,r,g,b\n0,0.04,0.04,0.04\n45,0.05,0.0",
            3,
            "expected 4",
        ),
        (
            "nan.csv",
            "angle_deg,r,g,b\n0,nan,0.04,0.04\n90,1,1,1\n",
            2,
            "not finite",
        ),
        (
            "inf.csv",
            "angle_deg,r,g,b\n0,0.04,0.04,0.04\ninf,1,1,1\n",
            3,
            "not finite",
        ),
        (
            "neg.csv",
            "angle_deg,r,g,b\n0,-0.1,0.04,0.04\n90,1,1,1\n",
            2,
            "outside [0, 1]",
        ),
        (
            "order.csv",
            "angle_deg,r,g,b\n0,0,0,0\n50,0,0,0\n40,0,0,0\n90,1,1,1\n",
            4,
            "strictly increase",
        ),
        (
            "last.csv",
            "angle_deg,r,g,b\n0,0,0,0\n80,1,1,1\n",
            3,
            "last angle must be 90",
        ),
        ("rows.csv", "angle_deg,r,g,b\n", 1, "no data rows"),
        (
            "spectral.csv",
            "angle_deg,400,700\n0,0,0\n90,1,1\n",
            1,
            "do not cover 380–780",
        ),
    ] {
        let path = ws.file(name, text);
        let message = expect_parse(FresnelTable::from_csv_file(&path), name, line);
        assert_names(&message, &[fragment]);
    }
    let path = ws.file("binary.csv", b"angle_deg,r,g,b\n0,0,0,0\n\xff\n");
    let message = expect_parse(FresnelTable::from_csv_file(&path), "binary.csv", 3);
    assert_names(&message, &["not UTF-8"]);
    assert_cli_fails(
        &ws,
        &[
            "render",
            "--set",
            "fresnel=nan.csv",
            "--size",
            "16x16",
            "-o",
            "out/r.png",
        ],
        &["nan.csv:2", "not finite"],
    );
}

#[test]
fn fresnel_csv_larger_than_the_limit_is_refused_before_reading() {
    let ws = Workspace::new();
    let path = ws.path().join("huge.csv");
    sparse_file(&path, b"angle_deg,r,g,b\n", 1 << 40);
    let message = quickly("huge fresnel", HEADER_ONLY, || {
        expect_invalid(FresnelTable::from_csv_file(&path), "Fresnel CSV file")
    });
    assert_names(
        &message,
        &[&format!("at most {MAX_FRESNEL_CSV_BYTES} bytes")],
    );
}

// ---- goniometer CSV --------------------------------------------------------------------------

const GONIO_HEADER: &str = "sample,r,theta_i_deg,theta_o_deg,phi_deg,R,G,B\n";

/// `shikki fit DATA -o out/m.toml` fails and writes neither the material nor its Fresnel table.
fn fit_refuses(ws: &Workspace, data: &str, fragments: &[&str]) {
    assert_cli_fails(ws, &["fit", data, "-o", "out/m.toml"], fragments);
}

#[test]
fn goniometer_csv_errors_name_line_and_fix() {
    let ws = Workspace::new();
    for (name, body, line, fragment) in [
        ("empty.csv", String::new(), 1, "empty file"),
        ("rows.csv", GONIO_HEADER.to_string(), 1, "no data rows"),
        (
            "cut.csv",
            format!("{GONIO_HEADER}A,1,30,30,0,0.1,0.1"),
            2,
            "expected 8",
        ),
        (
            "nan.csv",
            format!("{GONIO_HEADER}A,1,30,30,0,nan,0.1,0.1\n"),
            2,
            "`R` = `nan` is not a finite number",
        ),
        (
            "inf.csv",
            format!("{GONIO_HEADER}A,1,inf,30,0,0.1,0.1,0.1\n"),
            2,
            "not a finite number",
        ),
        (
            "neg.csv",
            format!("{GONIO_HEADER}A,1,30,30,0,0.1,-0.5,0.1\n"),
            2,
            "is negative",
        ),
        (
            "ratio.csv",
            format!("{GONIO_HEADER}A,0.5,30,30,0,0.1,0.1,0.1\n"),
            2,
            "is below 1",
        ),
        (
            "angle.csv",
            format!("{GONIO_HEADER}A,1,95,30,0,0.1,0.1,0.1\n"),
            2,
            "outside [0, 90)",
        ),
        (
            "header.csv",
            "sample,r,theta_i_deg,phi_deg,R,G,B\n".to_string(),
            1,
            "missing column `theta_o_deg`",
        ),
        (
            "empty_cell.csv",
            format!("{GONIO_HEADER}A,1,30,,0,0.1,0.1,0.1\n"),
            2,
            "is empty",
        ),
    ] {
        let path = ws.file(name, body);
        let message = expect_parse(read_goniometer_csv(&path), name, line);
        assert_names(&message, &[fragment]);
    }
    let path = ws.file(
        "binary.csv",
        [GONIO_HEADER.as_bytes(), b"A,1,30,30,0,\xff\n"].concat(),
    );
    assert_names(
        &expect_parse(read_goniometer_csv(&path), "binary.csv", 2),
        &["byte 13", "save the goniometer CSV file as UTF-8"],
    );
    fit_refuses(&ws, "nan.csv", &["nan.csv:2", "not a finite number"]);
    fit_refuses(&ws, "empty.csv", &["empty.csv:1"]);
}

#[test]
fn goniometer_csv_with_a_million_columns_is_bounded() {
    // A 2 MB header of a million wavelength columns: refused by the header check, quickly.
    let mut header = "sample,r,theta_i_deg,theta_o_deg,phi_deg".to_string();
    for k in 0..1_000_000 {
        header.push_str(&format!(",{}", 400 + k % 10));
    }
    let message = quickly("1e6 columns", Duration::from_secs(10), || {
        expect_parse(parse_goniometer_csv(&header, "wide.csv"), "wide.csv", 1)
    });
    assert_names(&message, &["strictly increase"]);
}

#[test]
fn goniometer_csv_larger_than_the_limit_is_refused_before_reading() {
    let ws = Workspace::new();
    let path = ws.path().join("huge.csv");
    sparse_file(&path, GONIO_HEADER.as_bytes(), 1 << 40);
    let message = quickly("huge goniometer", HEADER_ONLY, || {
        expect_invalid(read_goniometer_csv(&path), "goniometer CSV file")
    });
    assert_names(
        &message,
        &[&format!("at most {MAX_GONIOMETER_CSV_BYTES} bytes")],
    );
    fit_refuses(&ws, "huge.csv", &["goniometer CSV file"]);
}

// ---- MERL ------------------------------------------------------------------------------------

fn merl_header(dims: [i32; 3]) -> Vec<u8> {
    dims.iter().flat_map(|d| d.to_le_bytes()).collect()
}

#[test]
fn merl_errors_name_the_file_and_the_expected_layout() {
    let ws = Workspace::new();
    let field = |name: &str| format!("MERL file {}", ws.path().join(name).display());
    // Zero-size, truncated, foreign header, huge dims, negative dims.
    for (name, bytes, fragment) in [
        ("empty.binary", Vec::new(), "0 bytes"),
        (
            "cut.binary",
            [merl_header([90, 90, 180]), vec![0; 800]].concat(),
            "812 bytes",
        ),
        (
            "huge.binary",
            merl_header([1 << 30, 1 << 30, 1 << 30]),
            "header 1073741824 × 1073741824",
        ),
        (
            "neg.binary",
            merl_header([-1, 90, 180]),
            "header -1 × 90 × 180",
        ),
        ("short.binary", vec![90, 0], "2 bytes"),
    ] {
        let path = ws.file(name, &bytes);
        let message = quickly(name, HEADER_ONLY, || {
            expect_invalid(read_merl(&path), &field(name))
        });
        assert_names(&message, &[fragment, "MERL"]);
    }
    fit_refuses(&ws, "huge.binary", &["header 1073741824"]);
    fit_refuses(
        &ws,
        "cut.binary",
        &["812 bytes", &format!("exactly {MERL_FILE_BYTES} bytes")],
    );
}

#[test]
fn merl_of_a_terabyte_is_refused_from_its_length() {
    let ws = Workspace::new();
    let path = ws.path().join("tera.binary");
    sparse_file(&path, &merl_header([90, 90, 180]), 1 << 40);
    let field = format!("MERL file {}", path.display());
    let message = quickly("tera.binary", HEADER_ONLY, || {
        expect_invalid(read_merl(&path), &field)
    });
    assert_names(
        &message,
        &["1099511627776 bytes", "truncated or not a MERL"],
    );
    let args = ["fit", "tera.binary", "-o", "out/m.toml"];
    let out = shikki_limited(ws.path(), &args, 512 * 1024);
    check_failure(&ws, &args, &out, &["1099511627776 bytes"]);
}

#[test]
fn merl_nan_inf_and_negative_entries_are_skipped_as_not_measured() {
    // MERL marks unmeasured entries with negative values; NaN and Inf are treated the same.
    let mut bytes = merl_header([90, 90, 180]);
    bytes.resize(MERL_FILE_BYTES, 0);
    let values = [f64::NAN, f64::INFINITY, -1.0];
    for (k, v) in values.iter().enumerate() {
        // Entry (i = 10, j = 10, φ_d index 0): well above the horizon, read at any stride.
        let at = 12 + (k * 1_458_000 + (10 * 90 + 10) * 180) * 8;
        bytes[at..at + 8].copy_from_slice(&v.to_le_bytes());
    }
    let data = parse_merl(&bytes, "m.binary", 10).unwrap();
    assert!(data
        .rows
        .iter()
        .all(|r| r.reflectance.iter().all(|c| c.is_finite() && *c >= 0.0)));
    let all = parse_merl(
        &{
            let mut b = merl_header([90, 90, 180]);
            b.resize(MERL_FILE_BYTES, 0);
            b
        },
        "z.binary",
        10,
    )
    .unwrap();
    assert_eq!(
        all.rows.len(),
        data.rows.len() + 1,
        "exactly the one poisoned entry is skipped"
    );
}

#[test]
fn merl_entry_near_f64_max_is_skipped_not_turned_into_infinity() {
    // Regression (found by proptest_text's merl_full_size_with_hostile_values): f64::MAX times
    // π·scale overflowed to an infinite reflectance that reached the fit.
    let mut bytes = merl_header([90, 90, 180]);
    bytes.resize(MERL_FILE_BYTES, 0);
    bytes[12..20].copy_from_slice(&f64::MAX.to_le_bytes());
    let at = 12 + ((10 * 90 + 10) * 180) * 8;
    bytes[at..at + 8].copy_from_slice(&f64::MAX.to_le_bytes());
    let data = parse_merl(&bytes, "max.binary", 10).unwrap();
    assert!(data
        .rows
        .iter()
        .all(|r| r.reflectance.iter().all(|c| c.is_finite())));
}
