//! `[render] environment_model`: scene files choose SPEC §4's environment model (`paper`, the
//! default, or `brdf`); an unknown name is an error naming file, line, column and the valid
//! names; `--set` and batch sweeps reach it like any other field. No GPU: parsing and planning
//! only.

use std::path::Path;

use shikki::scene::batch::BatchPlan;
use shikki::scene::{load_scene_file, parse_scene_str, EnvironmentModel, SceneDocument};
use shikki::Error;

/// A sphere lit by the default lights, with `render` as the scene's `[render]` table body.
fn scene_text(render: &str) -> String {
    format!("[[object]]\nmesh = \"builtin:sphere\"\n\n[render]\n{render}")
}

#[test]
fn a_scene_file_with_render_brdf_parses_to_the_brdf_model() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("brdf.toml");
    std::fs::write(&path, scene_text("environment_model = \"brdf\"\n")).expect("write scene");
    let scene = load_scene_file(&path).expect("the scene file loads");
    assert_eq!(scene.render.environment_model, EnvironmentModel::Brdf);

    let paper = parse_scene_str(
        &scene_text("environment_model = \"paper\"\n"),
        "paper.toml",
        dir.path(),
    )
    .expect("`paper` parses");
    assert_eq!(paper.render.environment_model, EnvironmentModel::Paper);
}

#[test]
fn without_a_render_table_or_key_the_model_is_paper() {
    let dir = Path::new(".");
    let none = parse_scene_str("[[object]]\nmesh = \"builtin:sphere\"\n", "s.toml", dir)
        .expect("a scene without [render] parses");
    assert_eq!(none.render.environment_model, EnvironmentModel::Paper);
    let empty = parse_scene_str(&scene_text(""), "s.toml", dir).expect("an empty [render]");
    assert_eq!(empty.render.environment_model, EnvironmentModel::Paper);
    assert_eq!(EnvironmentModel::default(), EnvironmentModel::Paper);
}

#[test]
fn an_unknown_model_names_the_file_line_and_the_valid_values() {
    // Line 5 (the object takes lines 1–2, a blank line, `[render]` on 4), column 21: the value.
    let text = scene_text("environment_model = \"phong\"\n");
    let err = parse_scene_str(&text, "scene.toml", Path::new(".")).unwrap_err();
    let message = err.to_string();
    match &err {
        Error::Parse {
            file,
            line,
            message: m,
        } => {
            assert_eq!(file, "scene.toml", "{message}");
            assert_eq!(*line, 5, "{message}");
            assert!(m.starts_with("column 21:"), "{message}");
        }
        other => panic!("not a located error: {other:?}"),
    }
    for word in [
        "scene.toml:5",
        "environment_model",
        "\"phong\"",
        "`paper` or `brdf`",
    ] {
        assert!(message.contains(word), "{message:?} lacks {word:?}");
    }

    // The wrong type and a misspelt key are located errors too.
    let err = parse_scene_str(
        &scene_text("environment_model = 1\n"),
        "scene.toml",
        Path::new("."),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("scene.toml:5") && err.contains("environment_model"),
        "{err}"
    );
    let err = parse_scene_str(
        &scene_text("environment_modle = \"brdf\"\n"),
        "scene.toml",
        Path::new("."),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("scene.toml:5") && err.contains("did you mean `environment_model`"),
        "{err}"
    );
}

#[test]
fn set_overrides_the_model_and_a_bad_override_names_the_set() {
    let dir = Path::new(".");
    let mut doc = SceneDocument::parse(
        &scene_text("environment_model = \"paper\"\n"),
        "s.toml",
        dir,
    )
    .expect("scene parses");
    doc.set("render.environment_model=brdf", dir)
        .expect("the path exists");
    let scene = doc.build().expect("the overridden scene builds");
    assert_eq!(scene.render.environment_model, EnvironmentModel::Brdf);

    // Without a [render] table in the file.
    let mut doc = SceneDocument::parse("[[object]]\nmesh = \"builtin:sphere\"\n", "s.toml", dir)
        .expect("scene parses");
    doc.set("render.environment_model=brdf", dir)
        .expect("the path exists");
    let scene = doc.build().expect("the overridden scene builds");
    assert_eq!(scene.render.environment_model, EnvironmentModel::Brdf);

    doc.set("render.environment_model=phong", dir)
        .expect("the path exists");
    let message = doc.build().unwrap_err().to_string();
    assert!(
        message.contains("--set render.environment_model") && message.contains("`paper` or `brdf`"),
        "{message}"
    );
}

const JOBS: &str = r#"name = "sphere-{environment_model}"

[scene]
[[scene.object]]
mesh = "builtin:sphere"
[scene.output]
size = "32x32"
samples = 1

[sweep]
"render.environment_model" = ["paper", "brdf"]
"#;

#[test]
fn a_batch_sweeping_the_model_plans_one_job_per_model() {
    let plan = BatchPlan::parse(JOBS, "jobs.toml", Path::new(".")).expect("the jobs file parses");
    assert_eq!(plan.job_count(), 2);
    let jobs: Vec<_> = plan
        .jobs()
        .iter()
        .map(|job| plan.prepare(job).expect("the job prepares"))
        .collect();
    let models: Vec<EnvironmentModel> = jobs
        .iter()
        .map(|job| job.scene.render.environment_model)
        .collect();
    assert_eq!(models, [EnvironmentModel::Paper, EnvironmentModel::Brdf]);
    let names: Vec<&str> = jobs.iter().map(|job| job.file_name.as_str()).collect();
    assert_eq!(names, ["sphere-paper.png", "sphere-brdf.png"]);
    // The model is part of a job's identity: resuming never takes one model's image for the
    // other's.
    assert_ne!(jobs[0].scene_hash, jobs[1].scene_hash);
    // Everything else is the same scene.
    let mut paper = jobs[0].scene.clone();
    paper.render.environment_model = EnvironmentModel::Brdf;
    assert_eq!(format!("{paper:?}"), format!("{:?}", jobs[1].scene));
}

#[test]
fn a_batch_sweeping_an_unknown_model_fails_that_job_naming_the_sweep_line() {
    let jobs = JOBS.replace(r#"["paper", "brdf"]"#, r#"["brdf", "phong"]"#);
    let plan = BatchPlan::parse(&jobs, "jobs.toml", Path::new(".")).expect("the jobs file parses");
    assert_eq!(plan.job_count(), 2);
    let first = plan.prepare(&plan.job(0)).expect("`brdf` prepares");
    assert_eq!(first.scene.render.environment_model, EnvironmentModel::Brdf);
    // The sweep's value is located in the jobs file (line 11: the sweep).
    let message = plan.prepare(&plan.job(1)).unwrap_err().to_string();
    for word in ["jobs.toml:11", "\"phong\"", "`paper` or `brdf`"] {
        assert!(message.contains(word), "{message:?} lacks {word:?}");
    }
}
