//! `shikki synth` and `shikki fit` as a user runs them: synthetic data → fit → a material TOML
//! (with its Fresnel CSV beside it) that loads, and a report with readable PNGs; determinism of
//! synth; and bad input giving a clear error, exit code 1 and no output file.

use shikki::model::material_file::load_material_file;
use shikki::model::LacquerMaterial;
use std::path::Path;
use std::process::{Command, Output};

fn shikki(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_shikki"))
        .env("SHIKKI_PIPELINE_CACHE", "0")
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the shikki binary runs")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn assert_ok(out: &Output) {
    assert!(out.status.success(), "shikki failed: {}", stderr(out));
}

/// Exit code 1, `expected` in stderr, nothing at `output`.
fn assert_fails(dir: &Path, args: &[&str], output: &str, expected: &str) {
    let out = shikki(dir, args);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
    assert!(
        err.contains(expected),
        "{args:?}: stderr lacks {expected:?}:\n{err}"
    );
    assert!(!dir.join(output).exists(), "{args:?} left {output}");
}

#[test]
fn synth_then_fit_writes_a_loadable_material_and_a_report() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    assert_ok(&shikki(
        d,
        &[
            "synth",
            "--preset",
            "rough-red",
            "-o",
            "boards.csv",
            "--noise",
            "0.02",
            "--seed",
            "7",
        ],
    ));
    // Like `render`, fit does not create the output's directory; the report's it does.
    std::fs::create_dir(d.join("out")).unwrap();
    assert_ok(&shikki(
        d,
        &[
            "fit",
            "boards.csv",
            "-o",
            "out/lacquer.toml",
            "--report",
            "report",
            "--normalise-like",
            "rough-red",
        ],
    ));
    // The TOML names the Fresnel table beside it, relative, and loads from anywhere.
    let toml = std::fs::read_to_string(d.join("out/lacquer.toml")).unwrap();
    assert!(toml.contains("fresnel = \"lacquer.fresnel.csv\""), "{toml}");
    let material = load_material_file(&d.join("out/lacquer.toml")).unwrap();
    let truth = LacquerMaterial::preset("rough-red").unwrap();
    // 2 % noise: the bounds (m within 5 %, a and b within 0.02).
    assert!((material.beckmann_m / truth.beckmann_m - 1.0).abs() < 0.05);
    assert!((material.diffuse_a - truth.diffuse_a).abs() < 0.02);
    assert!((material.diffuse_b - truth.diffuse_b).abs() < 0.02);
    assert_eq!(
        material.fresnel_file,
        Some(d.join("out/lacquer.fresnel.csv"))
    );
    material.fresnel_table().unwrap();

    for name in [
        "report.md",
        "residuals.csv",
        "boards.csv",
        "fresnel.csv",
        "m_search.csv",
    ] {
        assert!(d.join("report").join(name).is_file(), "missing {name}");
    }
    for name in [
        "fig1_polar_total.png",
        "fig2_polar_diffuse.png",
        "fig3_polar_specular.png",
        "fig4_beckmann.png",
        "fig5_fresnel.png",
        "fig6_f_nv.png",
        "fig8_g_r.png",
    ] {
        let bytes = std::fs::read(d.join("report").join(name)).unwrap();
        let (w, h, pixels) = shikki::output::png::decode_png_rgba8(&bytes).unwrap();
        assert!(w >= 800 && h >= 500, "{name}: {w}x{h}");
        // Drawn on: a good share of the pixels is not the white background.
        let inked = pixels.iter().filter(|p| p[..3] != [255, 255, 255]).count();
        assert!(
            inked * 50 > pixels.len(),
            "{name}: only {inked} non-white pixels"
        );
    }
    let residuals = std::fs::read_to_string(d.join("report/residuals.csv")).unwrap();
    assert!(residuals.starts_with("term,sample,count,rms_relative,max_abs_relative\n"));
    assert!(residuals.contains("\ntotal,board-5,"));
}

#[test]
fn synth_is_deterministic_per_seed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (name, seed) in [("a.csv", "3"), ("b.csv", "3"), ("c.csv", "4")] {
        assert_ok(&shikki(
            d,
            &[
                "synth", "--preset", "smooth", "-o", name, "--noise", "0.02", "--seed", seed,
                "--ratios", "1,3",
            ],
        ));
    }
    let read = |n: &str| std::fs::read(d.join(n)).unwrap();
    assert_eq!(read("a.csv"), read("b.csv"));
    assert_ne!(read("a.csv"), read("c.csv"));
    let text = String::from_utf8(read("a.csv")).unwrap();
    assert!(text.starts_with("# synthetic measurements from shikki synth: preset smooth"));
    assert!(text.contains("\nsample,r,theta_i_deg,theta_o_deg,phi_deg,R,G,B\nboard-1,1,0,-85,0,"));
}

#[test]
fn merl_output_fits_back() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("m.toml"), "preset = \"rough\"\nm = 0.15\n").unwrap();
    assert_ok(&shikki(d, &["synth", "m.toml", "-o", "m.binary"]));
    assert_eq!(
        std::fs::metadata(d.join("m.binary")).unwrap().len(),
        shikki::fit::merl::MERL_FILE_BYTES as u64
    );
    assert_ok(&shikki(d, &["fit", "m.binary", "-o", "fitted.toml"]));
    let fitted = load_material_file(&d.join("fitted.toml")).unwrap();
    assert!(
        (fitted.beckmann_m - 0.15).abs() < 1e-3,
        "{}",
        fitted.beckmann_m
    );
}

#[test]
fn bad_input_fails_with_a_clear_message_and_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("bad.csv"),
        "sample,r,theta_i_deg,theta_o_deg,phi_deg,R,G,B\nA,1,30,30,0,0.1,0.2,0.3\nA,1,30,x,0,1,1,1\n",
    )
    .unwrap();
    assert_fails(
        d,
        &["fit", "bad.csv", "-o", "m.toml"],
        "m.toml",
        "error: bad.csv:3: `theta_o_deg` = `x` is not a number",
    );
    assert!(!d.join("m.fresnel.csv").exists());
    assert_fails(
        d,
        &["fit", "bad.csv", "-o", "m.txt"],
        "m.txt",
        "the material file must end in .toml",
    );
    assert_fails(
        d,
        &["fit", "data.json", "-o", "m.toml"],
        "m.toml",
        "the extension must be .csv (goniophotometer CSV) or .binary (MERL BRDF)",
    );
    assert_fails(
        d,
        &[
            "fit",
            "bad.csv",
            "-o",
            "m.toml",
            "--normalise-like",
            "glossy",
        ],
        "m.toml",
        "invalid --normalise-like = glossy: is neither a preset",
    );
    assert_fails(
        d,
        &[
            "synth", "--preset", "smooth", "-o", "d.csv", "--ratios", "1,7",
        ],
        "d.csv",
        "invalid r = 7",
    );
    assert_fails(
        d,
        &[
            "synth", "--preset", "smooth", "-o", "d.binary", "--ratios", "1,2",
        ],
        "d.binary",
        "a MERL file holds one board",
    );
    assert_fails(
        d,
        &[
            "synth", "--preset", "smooth", "-o", "d.csv", "--noise", "0.7",
        ],
        "d.csv",
        "the relative noise σ must be in [0, 0.5)",
    );
}

/// `fit boards.csv -o lacquer.toml --report .` replaced the measurements with the report's
/// per-board table, and `fit a.fresnel.csv -o a.toml` replaced them with the fitted Fresnel
/// table: every output that is an input (by any name: `./x`, a hard link) is refused before
/// anything is written or removed.
#[test]
fn outputs_never_overwrite_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    assert_ok(&shikki(
        d,
        &[
            "synth",
            "--preset",
            "smooth",
            "-o",
            "boards.csv",
            "--ratios",
            "1",
        ],
    ));
    let original = std::fs::read(d.join("boards.csv")).unwrap();
    std::fs::copy(d.join("boards.csv"), d.join("a.fresnel.csv")).unwrap();
    std::fs::create_dir(d.join("out")).unwrap();
    std::fs::hard_link(d.join("boards.csv"), d.join("out/linked.fresnel.csv")).unwrap();
    std::fs::write(d.join("ref.toml"), "preset = \"smooth\"\n").unwrap();
    let cases: [(&[&str], &str, &str); 5] = [
        (
            &["fit", "boards.csv", "-o", "lacquer.toml", "--report", "."],
            "lacquer.toml",
            "invalid --report = .: the report file ./boards.csv is the input boards.csv (the same \
             file)",
        ),
        (
            &["fit", "./boards.csv", "-o", "lacquer.toml", "--report", "."],
            "lacquer.toml",
            "choose another --report folder",
        ),
        (
            &["fit", "a.fresnel.csv", "-o", "a.toml"],
            "a.toml",
            "invalid -o = a.toml: the material's Fresnel table (written beside it) \
             a.fresnel.csv is the input a.fresnel.csv (the same file); writing it would replace \
             the input, so nothing was written: choose another -o name",
        ),
        (
            &["fit", "boards.csv", "-o", "out/linked.toml"],
            "out/linked.toml",
            "choose another -o name",
        ),
        (
            &[
                "fit",
                "boards.csv",
                "-o",
                "ref.toml",
                "--normalise-like",
                "ref.toml",
            ],
            "ref.fresnel.csv",
            "is the input ref.toml",
        ),
    ];
    for (args, output, expected) in cases {
        assert_fails(d, args, output, expected);
        assert!(
            !d.join("residuals.csv").exists(),
            "{args:?} wrote the report"
        );
    }
    assert_eq!(std::fs::read(d.join("boards.csv")).unwrap(), original);
    assert_eq!(std::fs::read(d.join("a.fresnel.csv")).unwrap(), original);
    assert_eq!(
        std::fs::read_to_string(d.join("ref.toml")).unwrap(),
        "preset = \"smooth\"\n"
    );

    // synth must not write over the material it reads or the Fresnel table that names.
    std::fs::write(
        d.join("lab.fresnel.csv"),
        "angle_deg,r,g,b\n0,0.04,0.04,0.04\n90,1,1,1\n",
    )
    .unwrap();
    std::fs::write(
        d.join("lab.toml"),
        "preset = \"smooth\"\nfresnel = \"lab.fresnel.csv\"\n",
    )
    .unwrap();
    let out = shikki(d, &["synth", "lab.toml", "-o", "lab.fresnel.csv"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("is the input lab.fresnel.csv"),
        "{}",
        stderr(&out)
    );
    assert!(std::fs::read_to_string(d.join("lab.fresnel.csv"))
        .unwrap()
        .starts_with("angle_deg,r,g,b\n0,0.04"));
}
