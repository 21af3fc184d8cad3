//! Scene errors: wrong type, unknown key, missing file, bad mesh, bad value, bad syntax — each a
//! message with file:line and column, exit code ≠ 0 from the CLI, and no output written.

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
        &["no-such.hdr", "does not exist"],
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
        1,
        1,
        &["eye"],
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
        match &err {
            Error::Parse {
                file,
                line: l,
                message: m,
            } => {
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
}
