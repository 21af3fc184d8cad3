//! Scene errors: wrong type, unknown key, missing file, bad mesh, bad value, bad syntax — each a
//! message with file:line and column, exit code ≠ 0 from the CLI, and no output written.

use crate::common;

use std::path::Path;
use std::process::Command;

use shikki::scene::{parse_scene_str, SceneDocument};
use shikki::Error;

/// (scene text, line, column, words the message must contain). Line/column hand-counted.
const CASES: &[(&str, usize, usize, &[&str])] = &[
    // wrong type
    (
        "[camera]\nfov_deg = \"wide\"\n",
        2,
        11,
        &["fov_deg", "number", "string"],
    ),
    // unknown key, with the nearest valid one suggested
    (
        "[camera]\neye = [0, 0, 4]\nfov_dg = 30\n",
        3,
        1,
        &["fov_dg", "did you mean `fov_deg`"],
    ),
    (
        "[[object]]\nmesh = \"builtin:sphere\"\nmaterial = { preset = \"smooth\", rr = 2 }\n",
        3,
        33,
        &["rr", "did you mean `r`"],
    ),
    // a value a check of the whole section refuses, at that value's line (it was the section's)
    (
        "[camera]\neye = [0, 0, 4]\n\nfov_deg = 0\n",
        4,
        11,
        &["camera.fov_deg", "180"],
    ),
    (
        "[[light]]\nkind = \"dir\"\nto_light = [0, 1, 0]\nirradiance = [1, -1, 1]\n",
        4,
        14,
        &["light.irradiance", "1e20"],
    ),
    (
        "[environment]\nsource = \"builtin:studio\"\nintensity = -1\n",
        3,
        13,
        &["intensity", "≥ 0"],
    ),
    // a placement the renderer's f32 cannot draw, at the key that placed it
    (
        "[[object]]\nmesh = \"builtin:sphere\"\nscale = [1, 1, 1e-30]\n",
        3,
        1,
        &["placement", "[1e-12, 1e12]"],
    ),
    // a key written twice, named
    (
        "[camera]\nfov_deg = 30\nfov_deg = 40\n",
        3,
        1,
        &["duplicate key `fov_deg`"],
    ),
    // missing files: mesh, material, environment
    (
        "[[object]]\nmesh = \"no-such.obj\"\n",
        2,
        8,
        &["no-such.obj"],
    ),
    (
        "[[object]]\nmesh = \"builtin:sphere\"\nmaterial = \"no-such.toml\"\n",
        3,
        12,
        &["no-such.toml"],
    ),
    (
        "[environment]\nsource = \"no-such.hdr\"\n",
        2,
        10,
        &["cannot read", "no-such.hdr", "does not exist"],
    ),
    // bad mesh: an unknown built-in, and a file that is not a mesh
    (
        "[[object]]\nmesh = \"builtin:teapot\"\n",
        2,
        8,
        &["teapot", "builtin:bowl"],
    ),
    ("[[object]]\nmesh = \"bad.obj\"\n", 2, 8, &["bad.obj"]),
    // bad values
    (
        "[[object]]\nmesh = \"builtin:sphere\"\nmaterial = { preset = \"smooth-red\", r = 7 }\n",
        3,
        41,
        &["r", "7", "5.6"],
    ),
    ("[output]\nsamples = 3\n", 2, 11, &["samples", "[1, 4]"]),
    (
        "[camera]\neye = [0, 0, 0]\ntarget = [0, 0, 0]\n",
        3,
        10,
        &["eye", "camera.target"],
    ),
    // syntax
    ("[camera\nfov_deg = 30\n", 1, 8, &[]),
];

fn write_files(dir: &Path) {
    std::fs::write(dir.join("bad.obj"), "v 0 0 0\nf 1 2 3\n").unwrap();
}

#[test]
fn every_error_kind_names_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    write_files(dir.path());
    for (text, line, column, words) in CASES {
        let err = parse_scene_str(text, "scene.toml", dir.path()).unwrap_err();
        let message = err.to_string();
        // A file that cannot be read is an I/O failure at its line; everything else a parse
        // error there. Both are located alike.
        let missing_file = text.contains("no-such");
        match &err {
            Error::Parse {
                file,
                line: l,
                message: m,
            }
            | Error::ReadNamedAt {
                file,
                line: l,
                message: m,
                ..
            } => {
                assert_eq!(
                    matches!(err, Error::ReadNamedAt { .. }),
                    missing_file,
                    "{text:?}: {err:?}"
                );
                assert_eq!(file, "scene.toml", "{text:?}");
                assert_eq!(
                    (*l, m.split(':').next()),
                    (*line, Some(format!("column {column}").as_str())),
                    "{text:?}: {message}"
                );
            }
            other => panic!("{text:?}: not a located error: {other:?}"),
        }
        for word in *words {
            assert!(
                message.contains(word),
                "{text:?}: {message:?} lacks {word:?}"
            );
        }
    }
}

#[test]
fn set_override_errors_name_the_override() {
    let mut doc =
        SceneDocument::parse("[camera]\nfov_deg = 30\n", "s.toml", Path::new(".")).unwrap();
    doc.set("camera.fov_deg=\"wide\"", Path::new(".")).unwrap();
    let message = doc.build().unwrap_err().to_string();
    assert!(message.contains("--set camera.fov_deg"), "{message}");
    let mut doc = SceneDocument::parse("", "s.toml", Path::new(".")).unwrap();
    assert!(doc
        .set("object.0.mesh=builtin:bowl", Path::new("."))
        .is_err());
}

#[test]
fn cli_scene_errors_exit_nonzero_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    write_files(dir.path());
    for (k, (text, line, _, _)) in CASES.iter().enumerate() {
        let name = format!("s{k}.toml");
        std::fs::write(dir.path().join(&name), text).unwrap();
        // An output from an earlier run must not survive a failed one either.
        std::fs::write(dir.path().join("x.png"), b"old").unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_shikki"))
            .env("SHIKKI_PIPELINE_CACHE", "0")
            .args(["render", &name, "-o", "x.png"])
            .current_dir(dir.path())
            .env("SHIKKI_VALIDATION", "1")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{text:?}");
        assert!(
            err.contains(&format!("{name}:{line}: column")),
            "{text:?}: {err}"
        );
        assert!(!dir.path().join("x.png").exists(), "{text:?} left x.png");
    }
    // In scene mode --set paths are scene paths; a bad one is an error naming it.
    std::fs::write(dir.path().join("ok.toml"), "environment = \"none\"\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_shikki"))
        .env("SHIKKI_PIPELINE_CACHE", "0")
        .args([
            "render",
            "ok.toml",
            "-o",
            "y.png",
            "--set",
            "camera.fov_deg=500",
        ])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--set camera.fov_deg"));
    assert!(!dir.path().join("y.png").exists());
    // A value a check of the whole section refuses names the override that set it.
    let mut doc =
        SceneDocument::parse("[camera]\nfov_deg = 30\n", "s.toml", Path::new(".")).unwrap();
    doc.set("camera.fov_deg=0", Path::new(".")).unwrap();
    let message = doc.build().unwrap_err().to_string();
    assert!(message.contains("--set camera.fov_deg"), "{message}");
}

/// A failed render removes an earlier image at its output path, and nothing else: a path it would
/// not write (another extension: `-o notes.txt` removed the user's notes, `-o /dev/null` the
/// device node), and never the environment map it reads, which an `.exr` output can name (it was
/// overwritten by a good render and removed by a failed one). Found by a probe, 2026-12-06.
#[test]
fn a_render_never_removes_or_overwrites_what_it_does_not_write() {
    let dir = tempfile::tempdir().unwrap();
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_shikki"))
            .env("SHIKKI_PIPELINE_CACHE", "0")
            .args(args)
            .current_dir(dir.path())
            .output()
            .unwrap()
    };
    let path = |name: &str| dir.path().join(name);
    // Another extension: refused, and the file left as it was (flags and scene file alike).
    std::fs::write(path("notes.txt"), b"precious").unwrap();
    std::fs::write(path("bad.toml"), "[camera]\nfov_deg = 500\n").unwrap();
    for args in [
        &["render", "-o", "notes.txt", "--size", "8x8"][..],
        &["render", "bad.toml", "-o", "notes.txt"][..],
        &["render", "missing.toml", "-o", "notes.txt"][..],
    ] {
        let out = run(args);
        assert!(!out.status.success(), "{args:?}");
        assert_eq!(
            std::fs::read(path("notes.txt")).unwrap(),
            b"precious",
            "{args:?}"
        );
        assert!(!path("notes.exr").exists(), "{args:?}");
    }
    // The environment map as the output: refused before rendering, the map untouched, whether
    // the render would have succeeded or failed.
    let map = common::synthetic_environment(16, 8);
    let pixels: Vec<[f32; 4]> = map.pixels.iter().map(|p| [p[0], p[1], p[2], 1.0]).collect();
    let image = shikki::output::HdrImage {
        width: 16,
        height: 8,
        pixels,
    };
    let bytes = shikki::output::exr::encode_exr(&image).unwrap();
    std::fs::write(path("map.exr"), &bytes).unwrap();
    std::fs::write(
        path("env.toml"),
        "[[object]]\nmesh = \"builtin:sphere\"\n\n[environment]\nsource = \"map.exr\"\n\n\
         [output]\nsize = \"8x8\"\n",
    )
    .unwrap();
    for args in [
        &[
            "render", "--env", "map.exr", "--size", "8x8", "-o", "map.exr",
        ][..],
        &[
            "render", "--env", "map.exr", "--set", "m=5", "-o", "map.exr",
        ][..],
        &["render", "env.toml", "-o", "./map.exr"][..],
        &[
            "render",
            "env.toml",
            "--set",
            "camera.fov_deg=500",
            "-o",
            "map.exr",
        ][..],
    ] {
        let out = run(args);
        assert!(!out.status.success(), "{args:?}");
        assert_eq!(std::fs::read(path("map.exr")).unwrap(), bytes, "{args:?}");
    }
    let out = run(&[
        "render", "--env", "map.exr", "--size", "8x8", "-o", "map.exr",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("environment map this render reads"), "{err}");
    // A file name longer than file systems take: refused before rendering, nothing written.
    let long = format!("{}.png", "x".repeat(252));
    let out = run(&["render", "--size", "8x8", "-o", &long]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("256 bytes") && err.contains("nothing was rendered"),
        "{err}"
    );
    assert!(!err.contains("WARNING"), "{err}");
}
