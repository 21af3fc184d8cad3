//! Property tests of the text and measurement parsers: scene TOML, jobs TOML (plan and the first
//! jobs prepared), material TOML, the scene's `--set PATH=VALUE`, the material's `--set KEY=VALUE`,
//! Fresnel CSV, goniometer CSV and MERL. Strategies: arbitrary bytes, mutations of valid files and
//! near-valid text built from the format's own pieces with hostile numbers. Each returns Ok or a
//! well-formed error, never a panic or a hang. Case counts: tests/common/prop.rs.

use crate::common::prop as prop_support;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use prop_support::*;
use proptest::prelude::*;
use shikki::fit::csv::parse_goniometer_csv;
use shikki::fit::merl::{parse_merl, MERL_ENTRIES, MERL_FILE_BYTES};
use shikki::model::material_file::material_from_toml_str;
use shikki::model::{FresnelTable, LacquerMaterial, MATERIAL_KEYS};
use shikki::scene::batch::BatchPlan;
use shikki::scene::SceneDocument;

/// A directory holding one small valid OBJ and Fresnel CSV, so that relative paths in generated
/// scenes sometimes resolve.
fn base() -> &'static Path {
    static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = tempfile::tempdir().expect("temp dir");
        std::fs::write(
            dir.path().join("m.obj"),
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        )
        .unwrap();
        std::fs::write(
            dir.path().join("f.csv"),
            "angle_deg,r,g,b\n0,0.04,0.04,0.04\n90,1,1,1\n",
        )
        .unwrap();
        dir
    })
    .path()
}

fn base_dir() -> PathBuf {
    base().to_path_buf()
}

/// A TOML value as text: numbers (hostile ones included), strings, arrays, inline tables.
fn toml_value() -> impl Strategy<Value = String> {
    let leaf = prop_oneof![
        number_text(),
        prop::sample::select(
            &[
                "\"builtin:bowl\"",
                "\"builtin:sphere\"",
                "\"builtin:cube\"",
                "\"m.obj\"",
                "\"missing.glb\"",
                "\"none\"",
                "\"builtin:studio\"",
                "\"env.hdr\"",
                "\"smooth-red\"",
                "\"64x64\"",
                "\"100000x100000\"",
                "\"0x0\"",
                "\"exr\"",
                "\"png\"",
                "\"env\"",
                "\"transparent\"",
                "\"dir\"",
                "\"point\"",
                "\"f.csv\"",
                "\"aces\"",
                "true",
                "false",
                "\"\"",
                "1979-05-27",
                "\"{job}\"",
                "\"{r}\"",
            ][..]
        )
        .prop_map(str::to_string),
    ];
    leaf.prop_recursive(3, 24, 5, |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 0..5).prop_map(|v| format!("[{}]", v.join(", "))),
            prop::collection::vec(
                (
                    prop::sample::select(&["m", "r", "kd", "preset", "file", "x"][..]),
                    inner
                ),
                0..3
            )
            .prop_map(|kv| {
                let parts: Vec<String> = kv.iter().map(|(k, v)| format!("{k} = {v}")).collect();
                format!("{{ {} }}", parts.join(", "))
            }),
        ]
    })
}

const SCENE_HEADERS: &[&str] = &[
    "[camera]",
    "[[object]]",
    "[[light]]",
    "[environment]",
    "[output]",
    "[object]",
    "[[camera]]",
    "[object.material]",
    "[sweep]",
    "[scene]",
    "[nope]",
];

const SCENE_KEYS: &[&str] = &[
    "eye",
    "target",
    "up",
    "fov_deg",
    "orbit_deg",
    "mesh",
    "translate",
    "rotate_deg",
    "scale",
    "transform",
    "material",
    "kind",
    "to_light",
    "irradiance",
    "position",
    "intensity",
    "source",
    "rotation_deg",
    "size",
    "width",
    "height",
    "samples",
    "exposure",
    "tonemap",
    "format",
    "background",
    "m",
    "r",
    "kd",
    "preset",
    "fresnel",
    "scene",
    "name",
    "\"camera.fov_deg\"",
    "\"object.0.material.r\"",
    "\"output.size\"",
    "bogus",
];

/// Near-valid scene (or jobs) text: section headers and `key = value` lines.
fn scene_text() -> impl Strategy<Value = String> {
    let line = prop_oneof![
        1 => prop::sample::select(SCENE_HEADERS).prop_map(str::to_string),
        4 => (prop::sample::select(SCENE_KEYS), toml_value()).prop_map(|(k, v)| format!("{k} = {v}")),
        1 => "[ -~]{0,16}",
    ];
    prop::collection::vec(line, 0..16).prop_map(|l| l.join("\n"))
}

fn check_scene(text: String) -> Result<(), TestCaseError> {
    let result = within("scene", move || {
        SceneDocument::parse(&text, "p.toml", &base_dir()).and_then(|d| d.build())
    });
    well_formed(&result)
}

fn check_jobs(text: String) -> Result<(), TestCaseError> {
    let result = within("jobs", move || {
        let plan = BatchPlan::parse(&text, "j.toml", &base_dir())?;
        // The first few jobs prepared (each a scene build with the sweep values set).
        for id in 0..plan.job_count().min(4) {
            plan.prepare(&plan.job(id))?;
        }
        Ok(())
    });
    well_formed(&result)
}

const MATERIAL_LINES: &[&str] = &[
    "preset = \"smooth-red\"",
    "preset = \"rough\"",
    "preset = \"smoth\"",
    "m = 0.1",
    "kd = [0.5, 0.06, 0.03]",
    "extrapolate_g = true",
    "fresnel = \"f.csv\"",
    "fresnel = \"\"",
    "r = 3",
    "c0 = 1.1",
];

fn material_text() -> impl Strategy<Value = String> {
    let keys: Vec<&'static str> = MATERIAL_KEYS
        .iter()
        .copied()
        .chain(["preset", "mm", "kd.x"])
        .collect();
    let line = prop_oneof![
        2 => prop::sample::select(MATERIAL_LINES).prop_map(str::to_string),
        3 => (prop::sample::select(keys), toml_value()).prop_map(|(k, v)| format!("{k} = {v}")),
        1 => "[ -~]{0,16}",
    ];
    prop::collection::vec(line, 0..10).prop_map(|l| l.join("\n"))
}

fn check_material(text: String) -> Result<(), TestCaseError> {
    let result = within("material", move || {
        material_from_toml_str(&text, &base_dir(), "p.toml")
    });
    well_formed(&result)?;
    if let Ok(material) = &result {
        prop_assert!(material.validate().is_ok(), "{material:?}");
    }
    Ok(())
}

const VALID_SCENE: &str =
    "[camera]\neye = [0, 1, 4]\nfov_deg = 35\n\n[[object]]\nmesh = \"m.obj\"\n\
    scale = 0.5\nmaterial = { preset = \"smooth-red\", r = 2, kd = [0.5, 0.1, 0.1] }\n\n\
    [[light]]\nkind = \"point\"\nposition = [1, 2, 3]\nintensity = 5\n\n[environment]\n\
    source = \"none\"\n\n[output]\nsize = \"64x48\"\nsamples = 1\nbackground = [0.1, 0.1, 0.1]\n";

const VALID_JOBS: &str =
    "name = \"{job}-{r}\"\n[scene]\n[[scene.object]]\nmesh = \"builtin:bowl\"\n\
    [sweep]\n\"object.0.material.r\" = [1, 2]\n\"camera.orbit_deg\" = [0, 90]\n";

// ---- CSVs -----------------------------------------------------------------------------------

fn csv_rows(columns: std::ops::Range<usize>) -> impl Strategy<Value = Vec<String>> {
    prop::collection::vec(
        prop::collection::vec(number_text(), columns).prop_map(|c| c.join(",")),
        0..8,
    )
}

fn fresnel_text() -> impl Strategy<Value = String> {
    let header = prop::sample::select(
        &[
            "angle_deg,r,g,b",
            "angle_deg,380,580,780",
            "angle_deg,400,500",
            "angle_deg,780,380",
            "angle,r,g,b",
            "\u{feff}angle_deg,r,g,b",
            "0,0,0,0",
            "",
        ][..],
    );
    (header, csv_rows(3..6), any::<bool>()).prop_map(|(h, rows, crlf)| {
        let end = if crlf { "\r\n" } else { "\n" };
        format!("{h}{end}{}", rows.join(end))
    })
}

fn goniometer_text() -> impl Strategy<Value = String> {
    let header = prop::sample::select(
        &[
            "sample,r,theta_i_deg,theta_o_deg,phi_deg,R,G,B",
            "sample,r,theta_i_deg,theta_o_deg,phi_deg,380,580,780",
            "r,sample,phi_deg,theta_o_deg,theta_i_deg,B,G,R",
            "sample,r,theta_i_deg,theta_o_deg,phi_deg,R,G",
            "sample,r,theta_i_deg,theta_o_deg,phi_deg,R,G,B,X",
            "sample,r,theta_i_deg,theta_o_deg,phi_deg",
            "# comment",
        ][..],
    );
    let row = (
        prop::sample::select(&["A", "B", "", "A,B"][..]),
        prop::collection::vec(number_text(), 4..9),
    )
        .prop_map(|(s, cells)| format!("{s},{}", cells.join(",")));
    (header, prop::collection::vec(row, 0..8))
        .prop_map(|(h, rows)| format!("{h}\n{}", rows.join("\n")))
}

const VALID_FRESNEL: &str = "angle_deg,r,g,b\n0,0.04,0.04,0.04\n45,0.05,0.05,0.05\n90,1,1,1\n";
const VALID_GONIOMETER: &str = "sample,r,theta_i_deg,theta_o_deg,phi_deg,R,G,B\n\
    A,1,30,30,0,0.5,0.2,0.1\nA,1,30,40,90,0.3,0.2,0.1\nB,2,10,-20,180,0.2,0.2,0.2\n";

// ---- --set ----------------------------------------------------------------------------------

fn set_path() -> impl Strategy<Value = String> {
    let segment = prop::sample::select(
        &[
            "camera",
            "fov_deg",
            "eye",
            "object",
            "0",
            "1",
            "99999999999999999999",
            "material",
            "m",
            "kd",
            "preset",
            "file",
            "output",
            "size",
            "samples",
            "light",
            "environment",
            "source",
            "intensity",
            "mesh",
            "scale",
            "transform",
            "",
            " ",
            "x",
        ][..],
    );
    prop::collection::vec(segment, 1..5).prop_map(|s| s.join("."))
}

fn set_value() -> impl Strategy<Value = String> {
    prop_oneof![
        toml_value(),
        prop::sample::select(
            &["[", "{a=", "\"open", "=", "a=b=c", "[1,", "]]", "\u{0}", "1 2"][..]
        )
        .prop_map(str::to_string),
        "[ -~]{0,12}",
    ]
}

// ---- the properties ---------------------------------------------------------------------------

proptest! {
    #![proptest_config(config(1024))]

    #[test]
    fn scene_near_valid_text(text in scene_text()) {
        check_scene(text)?;
    }

    #[test]
    fn scene_mutations_of_a_valid_file(edits in mutations()) {
        let text = String::from_utf8_lossy(&apply(VALID_SCENE.as_bytes(), &edits)).into_owned();
        check_scene(text)?;
    }

    #[test]
    fn scene_arbitrary_text(text in "\\PC{0,200}") {
        check_scene(text)?;
    }

    #[test]
    fn jobs_near_valid_text(text in scene_text()) {
        check_jobs(text)?;
    }

    #[test]
    fn jobs_mutations_of_a_valid_file(edits in mutations()) {
        let text = String::from_utf8_lossy(&apply(VALID_JOBS.as_bytes(), &edits)).into_owned();
        check_jobs(text)?;
    }

    #[test]
    fn material_near_valid_text(text in material_text()) {
        check_material(text)?;
    }

    #[test]
    fn material_arbitrary_text(text in "\\PC{0,120}") {
        check_material(text)?;
    }

    #[test]
    fn scene_set_assignments(
        path in set_path(),
        value in set_value(),
        separator in prop::sample::select(&["=", " = ", "", "=="][..]),
    ) {
        let assignment = format!("{path}{separator}{value}");
        let result = within("--set", move || {
            let mut document = SceneDocument::parse(VALID_SCENE, "v.toml", &base_dir())?;
            document.set(&assignment, &base_dir())?;
            document.build().map(|_| ())
        });
        well_formed(&result)?;
    }

    #[test]
    fn material_set_values(
        key in prop::sample::select(
            MATERIAL_KEYS.iter().copied().chain(["", "M", "kd ", "beta"]).collect::<Vec<_>>()
        ),
        value in prop_oneof![number_text(), set_value(),
            (number_text(), number_text(), number_text()).prop_map(|(a, b, c)| format!("{a},{b},{c}"))],
    ) {
        let result = within("material set", move || {
            let mut material = LacquerMaterial::default();
            material.set(key, &value)?;
            material.validate()
        });
        well_formed(&result)?;
    }

    #[test]
    fn fresnel_near_valid_csv(text in fresnel_text()) {
        let result = within("fresnel", move || FresnelTable::from_csv_str(&text, "p.csv"));
        well_formed(&result)?;
        if let Ok(table) = &result {
            // A loaded table evaluates to finite values everywhere.
            for theta in [0.0, 33.3, 90.0, -5.0, f64::NAN] {
                prop_assert!(table.eval(theta).iter().all(|c| c.is_finite()));
            }
        }
    }

    #[test]
    fn fresnel_mutations_of_a_valid_csv(edits in mutations()) {
        let text = String::from_utf8_lossy(&apply(VALID_FRESNEL.as_bytes(), &edits)).into_owned();
        let result = within("fresnel", move || FresnelTable::from_csv_str(&text, "p.csv"));
        well_formed(&result)?;
    }

    #[test]
    fn goniometer_near_valid_csv(text in goniometer_text()) {
        let result = within("goniometer", move || parse_goniometer_csv(&text, "p.csv"));
        well_formed(&result)?;
        if let Ok(data) = &result {
            prop_assert!(data.rows.iter().all(|r| r.reflectance.iter().all(|c| c.is_finite())));
            prop_assert!(data.rows.iter().all(|r| r.sample < data.samples.len()));
        }
    }

    #[test]
    fn goniometer_mutations_of_a_valid_csv(edits in mutations()) {
        let text = String::from_utf8_lossy(&apply(VALID_GONIOMETER.as_bytes(), &edits)).into_owned();
        let result = within("goniometer", move || parse_goniometer_csv(&text, "p.csv"));
        well_formed(&result)?;
    }

    #[test]
    fn merl_arbitrary_bytes(bytes in prop::collection::vec(any::<u8>(), 0..256), stride in 0usize..200) {
        let result = within("merl", move || parse_merl(&bytes, "p.binary", stride));
        well_formed(&result)?;
    }
}

/// A full-size MERL file of zeros with the right header (built once).
fn merl_zeros() -> &'static [u8] {
    static BYTES: OnceLock<Vec<u8>> = OnceLock::new();
    BYTES.get_or_init(|| {
        let mut bytes: Vec<u8> = [90i32, 90, 180]
            .iter()
            .flat_map(|d| d.to_le_bytes())
            .collect();
        bytes.resize(MERL_FILE_BYTES, 0);
        bytes
    })
}

proptest! {
    // Each case parses a 35 MB file: few cases.
    #![proptest_config(heavy_config(24))]

    #[test]
    fn merl_full_size_with_hostile_values(
        header in prop::option::of([any::<i32>(), any::<i32>(), any::<i32>()]),
        values in prop::collection::vec((0..3 * MERL_ENTRIES, prop_oneof![
            any::<f64>(), Just(f64::NAN), Just(f64::INFINITY), Just(-1.0), Just(f64::MAX), Just(1e-310)
        ]), 0..64),
        stride in prop_oneof![Just(10usize), Just(0), Just(1000)],
    ) {
        let mut bytes = merl_zeros().to_vec();
        if let Some(dims) = header {
            for (k, d) in dims.iter().enumerate() {
                bytes[4 * k..4 * k + 4].copy_from_slice(&d.to_le_bytes());
            }
        }
        for (entry, value) in values {
            let at = 12 + entry * 8;
            bytes[at..at + 8].copy_from_slice(&value.to_le_bytes());
        }
        let result = within("merl", move || parse_merl(&bytes, "p.binary", stride));
        well_formed(&result)?;
        if let Ok(data) = &result {
            prop_assert!(data.rows.iter().all(|r| r.reflectance.iter().all(|c| c.is_finite() && *c >= 0.0)));
        }
    }
}

#[test]
fn the_originals_parse() {
    let document = SceneDocument::parse(VALID_SCENE, "v.toml", base()).unwrap();
    assert_eq!(document.build().unwrap().objects.len(), 1);
    let plan = BatchPlan::parse(VALID_JOBS, "j.toml", base()).unwrap();
    assert_eq!(plan.job_count(), 4);
    assert!(plan.prepare(&plan.job(3)).is_ok());
    assert!(FresnelTable::from_csv_str(VALID_FRESNEL, "f.csv").is_ok());
    assert_eq!(
        parse_goniometer_csv(VALID_GONIOMETER, "g.csv")
            .unwrap()
            .rows
            .len(),
        3
    );
    assert!(parse_merl(merl_zeros(), "z.binary", 10).is_ok());
}
