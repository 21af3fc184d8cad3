//! `shikki render` flags a user hits first: `--light none` and the built-in meshes `--help`
//! names. Validation is on (SHIKKI_VALIDATION=1), so any validation message fails the render.

use std::path::Path;
use std::process::{Command, Output};

use shikki::raster::mesh::BuiltinMesh;

fn shikki(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_shikki"))
        .args(args)
        .current_dir(dir)
        .env("SHIKKI_VALIDATION", "1")
        // Tests must not write a pipeline cache into the user's home.
        .env("SHIKKI_PIPELINE_CACHE", "0")
        .output()
        .expect("the shikki binary runs")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn light_none_renders_with_no_lights() {
    let dir = tempfile::tempdir().unwrap();
    let render = |lights: &[&str]| {
        let mut args = vec![
            "render",
            "-o",
            "dark.exr",
            "--size",
            "16x16",
            "--samples",
            "1",
            "--env",
            "none",
            "--background",
            "transparent",
        ];
        args.extend_from_slice(lights);
        let out = shikki(dir.path(), &args);
        assert!(out.status.success(), "{args:?}: {}", stderr(&out));
        let bytes = std::fs::read(dir.path().join("dark.exr")).unwrap();
        shikki::output::exr::decode_exr(&bytes).unwrap()
    };
    // No environment and no lights: the sphere covers the centre (alpha 1) but nothing lights it,
    // so every pixel's radiance is exactly 0.
    let dark = render(&["--light", "none"]);
    assert_eq!(dark.get(8, 8)[3], 1.0, "the sphere is drawn");
    for y in 0..16 {
        for x in 0..16 {
            let [r, g, b, _] = dark.get(x, y);
            assert_eq!([r, g, b], [0.0; 3], "pixel ({x}, {y})");
        }
    }
    // The same view with one light is lit: the zeros above come from `none`, not the view.
    let lit = render(&["--light", "dir:0,0,1:3,3,3"]);
    assert!(lit.get(8, 8)[0] > 0.0);
}

#[test]
fn light_none_with_another_light_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    for lights in [
        ["--light", "none", "--light", "dir:0,0,1:1,1,1"],
        ["--light", "point:0,2,2:5,5,5", "--light", "NONE"],
    ] {
        let mut args = vec!["render", "-o", "x.png", "--size", "16x16"];
        args.extend_from_slice(&lights);
        let out = shikki(dir.path(), &args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains("--light") && err.contains("cannot be combined"),
            "{args:?}: {err}"
        );
        assert!(!dir.path().join("x.png").exists());
    }
    // A misspelt light says `none` exists.
    let out = shikki(dir.path(), &["render", "-o", "x.png", "--light", "off"]);
    assert!(stderr(&out).contains("--light none"), "{}", stderr(&out));
}

#[test]
fn render_help_lists_every_builtin_mesh_and_light_none() {
    let dir = tempfile::tempdir().unwrap();
    let out = shikki(dir.path(), &["render", "--help"]);
    assert!(out.status.success());
    let help = String::from_utf8_lossy(&out.stdout);
    for builtin in BuiltinMesh::ALL {
        assert!(
            help.contains(&builtin.spec()),
            "help lacks {}:\n{help}",
            builtin.spec()
        );
    }
    assert!(help.contains("`none`"), "{help}");
}
