//! `[render]` keys of light between objects (SPEC §6): `ray_tracing`, `shadows`, `bounces`,
//! `rays`, `seed`, `denoise` — their defaults, range errors naming file, line and the valid range, `--set`
//! overrides and batch sweeps. No GPU: parsing and planning only.

use std::path::Path;

use shikki::scene::batch::BatchPlan;
use shikki::scene::{parse_scene_str, RenderSpec, SceneDocument, DEFAULT_RAYS};

fn scene_text(render: &str) -> String {
    format!("[[object]]\nmesh = \"builtin:sphere\"\n\n[render]\n{render}")
}

fn parse(render: &str) -> shikki::Result<shikki::scene::Scene> {
    parse_scene_str(&scene_text(render), "scene.toml", Path::new("."))
}

#[test]
fn defaults_are_ray_traced_shadows_one_bounce_and_the_default_rays() {
    let scene = parse("").expect("an empty [render]");
    assert_eq!(scene.render, RenderSpec::default());
    let RenderSpec {
        shadows,
        ray_tracing,
        bounces,
        rays,
        seed,
        denoise,
        ..
    } = scene.render;
    assert!(shadows && ray_tracing && denoise);
    assert_eq!((bounces, rays, seed), (1, DEFAULT_RAYS, 0));
}

#[test]
fn every_key_reaches_the_scene() {
    let keys = "ray_tracing = false\nshadows = false\nbounces = 3\nrays = 64\nseed = 77\n";
    let scene = parse(&format!("{keys}denoise = false\n")).expect("the keys parse");
    let r = scene.render;
    assert!(!r.ray_tracing && !r.shadows && !r.denoise);
    assert_eq!((r.bounces, r.rays, r.seed), (3, 64, 77));
}

#[test]
fn out_of_range_and_wrong_types_name_the_line_and_the_range() {
    for (render, words) in [
        ("bounces = 5\n", &["scene.toml:5", "`bounces`", "0..=4"][..]),
        ("rays = 0\n", &["scene.toml:5", "`rays`", "1..=4096"][..]),
        ("rays = 5000\n", &["scene.toml:5", "`rays`", "1..=4096"][..]),
        ("seed = -1\n", &["scene.toml:5", "`seed`"][..]),
        (
            "shadows = \"yes\"\n",
            &["scene.toml:5", "`shadows`", "true or false"][..],
        ),
        (
            "ray_tracing = 1\n",
            &["scene.toml:5", "`ray_tracing`", "true or false"][..],
        ),
        (
            "denoise = \"on\"\n",
            &["scene.toml:5", "`denoise`", "true or false"][..],
        ),
        (
            "bounce = 2\n",
            &["scene.toml:5", "did you mean `bounces`"][..],
        ),
    ] {
        let message = parse(render).unwrap_err().to_string();
        for word in words {
            assert!(
                message.contains(word),
                "{render:?}: {message:?} lacks {word:?}"
            );
        }
    }
}

#[test]
fn set_overrides_the_keys() {
    let dir = Path::new(".");
    let mut doc = SceneDocument::parse("[[object]]\nmesh = \"builtin:sphere\"\n", "s.toml", dir)
        .expect("scene parses");
    for set in [
        "render.bounces=2",
        "render.rays=9",
        "render.shadows=false",
        "render.denoise=false",
    ] {
        doc.set(set, dir).expect("the path exists");
    }
    let scene = doc.build().expect("the overridden scene builds");
    assert_eq!((scene.render.bounces, scene.render.rays), (2, 9));
    assert!(!scene.render.shadows && !scene.render.denoise);
    doc.set("render.bounces=7", dir).expect("the path exists");
    let message = doc.build().unwrap_err().to_string();
    assert!(
        message.contains("--set render.bounces") && message.contains("0..=4"),
        "{message}"
    );
}

#[test]
fn a_batch_sweeps_bounces_and_rays_and_each_is_its_own_job() {
    let jobs = r#"name = "b{bounces}-r{rays}"

[scene]
[[scene.object]]
mesh = "builtin:sphere"

[sweep]
"render.bounces" = [0, 2]
"render.rays" = [1, 16]
"#;
    let plan = BatchPlan::parse(jobs, "jobs.toml", Path::new(".")).expect("the jobs file parses");
    assert_eq!(plan.job_count(), 4);
    let prepared: Vec<_> = plan
        .jobs()
        .iter()
        .map(|job| plan.prepare(job).expect("the job prepares"))
        .collect();
    let settings: Vec<(u32, u32)> = prepared
        .iter()
        .map(|j| (j.scene.render.bounces, j.scene.render.rays))
        .collect();
    for want in [(0, 1), (0, 16), (2, 1), (2, 16)] {
        assert!(settings.contains(&want), "{settings:?} lacks {want:?}");
    }
    let mut hashes: Vec<&str> = prepared.iter().map(|j| j.scene_hash.as_str()).collect();
    hashes.sort_unstable();
    hashes.dedup();
    assert_eq!(hashes.len(), 4, "each setting is its own job identity");
}
