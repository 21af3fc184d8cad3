//! Goniometer CSV as spreadsheets and instruments write it: `;` with decimal commas, tabs, quoted
//! cells, upper-case headers, trailing separators, CR-only line ends and extra columns all read
//! as the plain file does (each said "missing column `sample`" or named a column that is not
//! there); the row cap; and fit messages that name the real problem (angles in radians, the
//! signed viewing angle).

use shikki::fit::csv::MAX_GONIOMETER_ROWS;
use shikki::fit::csv::{goniometer_csv, parse_goniometer_csv, read_goniometer_csv};
use shikki::fit::synth::{synthesize, Noise};
use shikki::fit::{fit_measurements, FitOptions, Measurements};
use shikki::model::LacquerMaterial;

const PLAIN: &str = "sample,r,theta_i_deg,theta_o_deg,phi_deg,R,G,B
board-1,1,0,-85,0,0.031245797505106605,0.0037,0.0018
board-1,1,30,30.5,0,3.91,3.93,3.95
board 2,2,30,30,90,0.5,0.25,0.125
";

/// `PLAIN` with every line passed through `line` and ended by `end`.
fn variant(line: impl Fn(usize, &str) -> String, end: &str) -> String {
    PLAIN
        .lines()
        .enumerate()
        .map(|(i, l)| line(i, l) + end)
        .collect()
}

fn parse(text: &str) -> Measurements {
    parse_goniometer_csv(text, "t.csv").unwrap_or_else(|e| panic!("{text:?}: {e}"))
}

#[test]
fn spreadsheet_dialects_read_like_the_plain_file() {
    let plain = parse(PLAIN);
    fn separated(separator: &'static str) -> impl Fn(usize, &str) -> String {
        move |_, l| l.replace(',', separator)
    }
    let cases: Vec<(&str, String)> = vec![
        (
            "`;` with decimal commas",
            variant(|_, l| l.replace(',', ";").replace('.', ","), "\n"),
        ),
        ("`;` with decimal points", variant(separated(";"), "\n")),
        ("tabs", variant(separated("\t"), "\n")),
        (
            "tabs with decimal commas",
            variant(|_, l| l.replace(',', "\t").replace('.', ","), "\n"),
        ),
        (
            "every cell quoted",
            variant(
                |_, l| {
                    let quoted: Vec<String> = l.split(',').map(|c| format!("\"{c}\"")).collect();
                    quoted.join(",")
                },
                "\n",
            ),
        ),
        (
            "upper-case header",
            variant(
                |i, l| if i == 0 { l.to_uppercase() } else { l.into() },
                "\n",
            ),
        ),
        ("trailing separators", variant(|_, l| format!("{l},"), "\n")),
        (
            "a trailing separator on the header only",
            variant(|i, l| if i == 0 { format!("{l},") } else { l.into() }, "\n"),
        ),
        (
            "trailing separators on the rows only",
            variant(|i, l| if i == 0 { l.into() } else { format!("{l},") }, "\n"),
        ),
        ("CR-only line ends", variant(|_, l| l.into(), "\r")),
        ("CRLF line ends", variant(|_, l| l.into(), "\r\n")),
    ];
    for (what, text) in &cases {
        let data = parse(text);
        assert_eq!(data.samples, plain.samples, "{what}");
        assert_eq!(data.rows, plain.rows, "{what}");
        assert!(data.notes.is_empty(), "{what}: {:?}", data.notes);
    }

    // An extra column is read past, with a note the fit passes on.
    let text = variant(
        |i, l| format!("{l},{}", if i == 0 { "operator" } else { "bob" }),
        "\n",
    );
    let data = parse(&text);
    assert_eq!(data.rows, plain.rows);
    assert_eq!(data.notes.len(), 1);
    assert!(data.notes[0].contains("`operator` (column 9) are not read"));

    // A quoted sample name may hold the separator.
    let data = parse(&PLAIN.replace("board 2,", "\"Board, 2\","));
    assert_eq!(data.samples[1].name, "Board, 2");

    // The file is read line by line: the same rows, CR-only line ends included.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mac.csv");
    std::fs::write(&path, variant(|_, l| l.into(), "\r")).unwrap();
    let data = read_goniometer_csv(&path).unwrap();
    assert_eq!(data.rows, plain.rows);
}

#[test]
fn more_rows_than_the_cap_are_refused_at_the_first_extra_row() {
    let mut text = String::from("sample,r,theta_i_deg,theta_o_deg,phi_deg,R,G,B\n");
    text.push_str(&"A,1,30,30,0,1,1,1\n".repeat(MAX_GONIOMETER_ROWS + 1));
    let err = parse_goniometer_csv(&text, "big.csv")
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with(&format!(
            "big.csv:{}: more than 1000000 data rows; a goniophotometer measurement is \
             thousands to hundreds of thousands of rows",
            MAX_GONIOMETER_ROWS + 2
        )),
        "{err}"
    );
}

#[test]
fn the_one_viewing_angle_is_shown_signed() {
    // θ_o = −85 is on the light's side; it was shown as 85.0°.
    let data = parse("sample,r,theta_i_deg,theta_o_deg,phi_deg,R,G,B\nA,1,0,-85,0,1,1,1\n");
    let err = fit_measurements(&data, &FitOptions::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("1 viewing angle(s) (-85.0°)"), "{err}");
}

#[test]
fn angles_in_radians_get_a_hint() {
    // The synth grid with its angles written in radians: every θ is within π/2 of 0, read as
    // degrees. The fit fails (on the diffuse luminance) and now says why the data look wrong.
    let material = LacquerMaterial::preset("rough-red").unwrap();
    let clean = Noise {
        relative: 0.0,
        seed: 0,
    };
    let (data, angles) = synthesize(&material, &[1.0, 3.0, 5.0], clean).unwrap();
    let radians: Vec<[f64; 3]> = angles.iter().map(|a| a.map(f64::to_radians)).collect();
    let text = goniometer_csv(&data, &radians, "");
    let err = fit_measurements(&parse(&text), &FitOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains(
            "Hint: every θ_i and θ_o is within π/2 ≈ 1.5708 of 0, so the angles look like radians"
        ),
        "{err}"
    );
    // Degrees fit, with the reader's notes passed on.
    let mut degrees = data;
    degrees.notes.push("a note from reading".into());
    let fit = fit_measurements(&degrees, &FitOptions::default()).unwrap();
    assert!(fit.notes.iter().any(|n| n == "a note from reading"));
    assert!(!fit.notes.iter().any(|n| n.contains("radians")));
}
