//! The Fresnel table's CSV format (SPEC §3; docs/measurements.md): reading a table, RGB or
//! spectral, with the dialects of [`crate::text`]. Writing is [`FresnelTable::to_csv`]'s.
//! Owns the header and row rules; the table's own checks are [`FresnelTable`]'s.

use super::{FresnelTable, SPECTRAL_COVER_NM};
use crate::model::spectral::reflectance_to_rgb;
use crate::text::{detect_separator, numbered_lines, parse_number, separator_name, split_cells};
use crate::{Error, Result};

/// The table in `text` (see [`FresnelTable::from_csv_str`]).
pub(super) fn parse_table(text: &str, source: &str) -> Result<FresnelTable> {
    let mut lines = numbered_lines(text)
        .map(|(number, line)| (number, line.trim()))
        .filter(|(_, line)| !line.starts_with('#'));
    let Some((header_line, header_text)) = lines.by_ref().find(|(_, l)| !l.is_empty()) else {
        return Err(Error::parse(
            source,
            1,
            format!("empty file; {EXPECTED_HEADER}"),
        ));
    };
    let header = parse_header(header_text).map_err(|m| Error::parse(source, header_line, m))?;
    let mut rows: Vec<(usize, &str)> = lines.collect();
    let Some(last) = rows.iter().rposition(|(_, l)| !l.is_empty()) else {
        return Err(Error::parse(source, header_line, NO_ROWS));
    };
    rows.truncate(last + 1);
    let mut angles_deg: Vec<f64> = Vec::new();
    let mut values: Vec<Vec<f64>> = Vec::new();
    for &(number, line) in &rows {
        let fail = |message: String| Error::parse(source, number, message);
        let mut row = parse_row(line, &header).map_err(fail)?;
        check_next_angle(row[0], angles_deg.last().copied()).map_err(fail)?;
        angles_deg.push(row[0]);
        values.push(row.split_off(1));
    }
    let last_line = rows[last].0;
    match angles_deg.last() {
        Some(&angle) if angle != 90.0 => Err(Error::parse(
            source,
            last_line,
            format!("the last angle must be 90 (the table spans 0..90 degrees), found {angle}"),
        )),
        _ => {
            let rgb = match &header.channels {
                Channels::Rgb => values.iter().map(|v| [v[0], v[1], v[2]]).collect(),
                Channels::Spectral(nm) => {
                    values.iter().map(|v| reflectance_to_rgb(nm, v)).collect()
                }
            };
            // The spectral path does not clamp (SPEC §3 says nothing of it), so a converted
            // spectral table may leave [0, 1] slightly; only its structure is re-checked.
            FresnelTable::checked(angles_deg, rgb, false)
        }
    }
}

/// The value columns of a CSV header.
enum Channels {
    Rgb,
    /// Wavelengths [nm], strictly increasing, covering 380–780.
    Spectral(Vec<f64>),
}

/// A CSV header: its value columns and how its rows are written.
struct Header {
    channels: Channels,
    separator: char,
}

impl Header {
    fn channel_count(&self) -> usize {
        match &self.channels {
            Channels::Rgb => 3,
            Channels::Spectral(nm) => nm.len(),
        }
    }

    fn column_name(&self, column: usize) -> String {
        match (&self.channels, column) {
            (_, 0) => "angle_deg".into(),
            (Channels::Rgb, c) => ["r", "g", "b"][(c - 1).min(2)].into(),
            (Channels::Spectral(nm), c) => format!("{} nm", nm[c - 1]),
        }
    }
}

/// A header cell as a wavelength in nm: a number, optionally followed by `nm` (`380`, `380.0`,
/// `380nm`, `380 nm`, in any case); `None` if it is not a finite number. Shared by the Fresnel
/// and the goniometer CSV, whose callers refuse a wavelength that is not > 0.
pub fn wavelength_nm(name: &str) -> Option<f64> {
    let name = name.trim();
    let number = match name.len().checked_sub(2).and_then(|at| name.get(at..)) {
        Some(unit) if unit.eq_ignore_ascii_case("nm") => name[..name.len() - 2].trim_end(),
        _ => name,
    };
    number.parse::<f64>().ok().filter(|v| v.is_finite())
}

const EXPECTED_HEADER: &str = "expected the header `angle_deg,r,g,b` (RGB) or \
    `angle_deg,<wavelength_nm>,<wavelength_nm>,…` (spectral, covering 380–780 nm), then one row \
    per angle from 0 to 90 degrees";

const NO_ROWS: &str =
    "the header has no data rows after it; add rows for 0..90 degrees (at least 0 and 90)";

/// The header: RGB, or spectral with valid wavelengths; or why not.
fn parse_header(line: &str) -> std::result::Result<Header, String> {
    let separator = detect_separator(line);
    let mut cells = split_cells(line, separator)?;
    // A trailing separator leaves an unnamed last column; the rows may have it or not.
    if cells.len() > 1 && cells.last().is_some_and(|c| c.is_empty()) {
        cells.pop();
    }
    if !cells[0].eq_ignore_ascii_case("angle_deg") {
        if parse_number(&cells[0], separator).is_some() {
            return Err(format!(
                "missing header: the first line is data; {EXPECTED_HEADER}"
            ));
        }
        return Err(format!("wrong header `{line}`; {EXPECTED_HEADER}"));
    }
    let header = |channels| Header {
        channels,
        separator,
    };
    let rgb = ["r", "g", "b"];
    if cells.len() == 4
        && cells[1..]
            .iter()
            .zip(rgb)
            .all(|(c, n)| c.eq_ignore_ascii_case(n))
    {
        return Ok(header(Channels::Rgb));
    }
    let mut nm = Vec::with_capacity(cells.len() - 1);
    for (column, cell) in cells.iter().enumerate().skip(1) {
        let n = column + 1;
        match wavelength_nm(cell) {
            Some(v) if v > 0.0 => nm.push(v),
            // A wavelength of 0 or less has no light; -380 used to pass as covering 380 nm.
            Some(_) => {
                return Err(format!(
                    "wrong header: column {n} `{cell}` is not a wavelength: wavelengths are \
                     lengths in nm, greater than 0 (the table covers {lo}–{hi} nm)",
                    lo = SPECTRAL_COVER_NM.0,
                    hi = SPECTRAL_COVER_NM.1
                ));
            }
            None => {
                return Err(format!(
                    "wrong header: column {n} `{cell}` is not a wavelength in nm; {EXPECTED_HEADER}"
                ));
            }
        }
    }
    if nm.len() < 2 {
        return Err(format!("wrong header `{line}`; {EXPECTED_HEADER}"));
    }
    if let Some(i) = (1..nm.len()).find(|&i| nm[i] <= nm[i - 1]) {
        let (here, before) = (nm[i], nm[i - 1]);
        return Err(format!(
            "wavelength {here} nm is not greater than {before} nm before it; \
             wavelengths must strictly increase"
        ));
    }
    let (lo, hi) = SPECTRAL_COVER_NM;
    let (first, last) = (nm[0], nm[nm.len() - 1]);
    if first > lo || last < hi {
        return Err(format!(
            "wavelengths {first}–{last} nm do not cover {lo}–{hi} nm; \
             add columns down to {lo} nm and up to {hi} nm"
        ));
    }
    Ok(header(Channels::Spectral(nm)))
}

/// One data row: `1 + channels` finite numbers, reflectances in [0, 1]; or why not.
fn parse_row(line: &str, header: &Header) -> std::result::Result<Vec<f64>, String> {
    if line.is_empty() {
        return Err(
            "blank line inside the table; remove it (blank lines are allowed only at the end)"
                .into(),
        );
    }
    let mut cells = split_cells(line, header.separator)?;
    let columns = 1 + header.channel_count();
    // A trailing separator on the rows, with or without one on the header, is the same table.
    if cells.len() == columns + 1 && cells.last().is_some_and(|c| c.is_empty()) {
        cells.pop();
    }
    if cells.len() != columns {
        let found = cells.len();
        return Err(format!(
            "expected {columns} columns separated by {} as in the header, found {found}",
            separator_name(header.separator)
        ));
    }
    let mut row = Vec::with_capacity(columns);
    for (column, cell) in cells.iter().enumerate() {
        let name = header.column_name(column);
        let v = match parse_number(cell, header.separator) {
            Some(v) if v.is_finite() => v,
            Some(_) => {
                return Err(format!(
                    "`{name}` = `{cell}` is not finite; use a finite number"
                ))
            }
            None if cell.is_empty() => {
                return Err(format!("`{name}` is empty; put a number there"))
            }
            None => return Err(format!("`{name}` = `{cell}` is not a number")),
        };
        if column > 0 && !(0.0..=1.0).contains(&v) {
            return Err(format!(
                "`{name}` = {v} is outside [0, 1]; reflectance values must be in [0, 1]"
            ));
        }
        row.push(v);
    }
    Ok(row)
}

/// Angles start at 0, strictly increase and stay ≤ 90 (the last-is-90 rule is checked at the end).
fn check_next_angle(angle: f64, previous: Option<f64>) -> std::result::Result<(), String> {
    match previous {
        None if angle != 0.0 => Err(format!(
            "the first angle must be 0 (the table spans 0..90 degrees), found {angle}"
        )),
        Some(previous) if angle <= previous => Err(format!(
            "angle {angle} is not greater than the previous angle {previous}; \
             angles must strictly increase"
        )),
        _ if angle > 90.0 => Err(format!(
            "angle {angle} is above 90; the table spans 0..90 degrees and must end at 90"
        )),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn assert_close(got: f64, want: f64, tolerance: f64, what: &str) {
        assert!((got - want).abs() < tolerance, "{what}: {got} vs {want}");
    }

    /// The line number and message of a CSV that must fail to parse.
    fn csv_error(text: &str) -> (usize, String) {
        match FresnelTable::from_csv_str(text, "test.csv") {
            Err(Error::Parse {
                file,
                line,
                message,
            }) => {
                assert_eq!(file, "test.csv");
                (line, message)
            }
            other => panic!("expected a parse error for {text:?}, got {other:?}"),
        }
    }

    #[test]
    fn spectral_header_refuses_wavelengths_not_above_zero() {
        // -380 < 580 < 780 used to pass as covering 380–780 nm.
        for (header, column, cell) in [
            ("angle_deg,-380,580,780", 2, "-380"),
            ("angle_deg,0,580,780", 2, "0"),
            ("angle_deg,-0,580,780", 2, "-0"),
            ("angle_deg,-800,-400,380,780", 2, "-800"),
        ] {
            let text = format!("{header}\n0,0,0,0\n90,1,1,1\n");
            let (line, message) = csv_error(&text);
            assert_eq!(line, 1, "{header}: {message}");
            assert!(
                message.contains(&format!("column {column} `{cell}` is not a wavelength"))
                    && message.contains("greater than 0"),
                "{header}: {message}"
            );
        }
        for header in ["angle_deg,380,inf,780", "angle_deg,NaN,580,780"] {
            let text = format!("{header}\n0,0,0,0\n90,1,1,1\n");
            let (line, message) = csv_error(&text);
            assert_eq!(line, 1, "{header}: {message}");
            assert!(
                message.contains("is not a wavelength in nm"),
                "{header}: {message}"
            );
        }
    }

    #[test]
    fn rgb_csv_parses_with_bom_crlf_whitespace_and_trailing_blank_lines() {
        let text = "\u{feff}angle_deg,r,g,b\r\n 0 , 0.04,0.05 ,0.06\r\n45,0.1,0.1,0.1\r\n\
                    90,1,1,1\r\n\r\n  \n";
        let table = FresnelTable::from_csv_str(text, "t").unwrap();
        assert_eq!(table.angles_deg(), &[0.0, 45.0, 90.0]);
        assert_eq!(
            table.rgb(),
            &[[0.04, 0.05, 0.06], [0.1, 0.1, 0.1], [1.0, 1.0, 1.0]]
        );
    }

    #[test]
    fn rgb_csv_reads_any_case_trailing_separators_comments_and_other_dialects() {
        // Each said "column 2 `R` is not a wavelength" or "wrong header"; all are this table.
        let plain =
            FresnelTable::from_csv_str("angle_deg,r,g,b\n0,0.04,0.05,0.06\n90,1,1,1\n", "t")
                .unwrap();
        for text in [
            "ANGLE_DEG,R,G,B\n0,0.04,0.05,0.06\n90,1,1,1\n",
            "angle_deg,r,g,b,\n0,0.04,0.05,0.06,\n90,1,1,1,\n",
            "angle_deg,r,g,b,\n0,0.04,0.05,0.06\n90,1,1,1\n",
            "# measured 2024\n\nangle_deg,r,g,b\n0,0.04,0.05,0.06\n# lamp changed\n90,1,1,1\n",
            "angle_deg,r,g,b\r0,0.04,0.05,0.06\r90,1,1,1\r",
            "angle_deg;r;g;b\n0;0,04;0,05;0,06\n90;1;1;1\n",
            "angle_deg\tr\tg\tb\n0\t0.04\t0.05\t0.06\n90\t1\t1\t1\n",
            "\"angle_deg\",\"r\",\"g\",\"b\"\n\"0\",\"0.04\",\"0.05\",\"0.06\"\n90,1,1,1\n",
        ] {
            let table =
                FresnelTable::from_csv_str(text, "t").unwrap_or_else(|e| panic!("{text:?}: {e}"));
            assert_eq!(table, plain, "{text:?}");
        }
    }

    #[test]
    fn spectral_headers_may_carry_their_unit() {
        let plain =
            FresnelTable::from_csv_str("angle_deg,380,580,780\n0,0.5,0.5,0.5\n90,1,1,1\n", "t")
                .unwrap();
        for header in [
            "angle_deg,380nm,580 nm,780.0",
            "Angle_Deg,380 NM,580.0nm,780",
        ] {
            let text = format!("{header}\n0,0.5,0.5,0.5\n90,1,1,1\n");
            assert_eq!(
                FresnelTable::from_csv_str(&text, "t").unwrap(),
                plain,
                "{header}"
            );
        }
        assert_eq!(wavelength_nm(" 380 nm "), Some(380.0));
        assert_eq!(wavelength_nm("nm"), None);
        assert_eq!(wavelength_nm("inf"), None);
    }

    #[test]
    fn spectral_csv_goes_through_the_spectral_path() {
        // Flat spectra map to grey exactly (flat 1 → 1 by construction, flat 0.5 to rounding).
        let text = "angle_deg,370,500,790\n0,0.5,0.5,0.5\n90,1,1,1\n";
        let table = FresnelTable::from_csv_str(text, "t").unwrap();
        assert_eq!(table.rgb()[1], [1.0; 3]);
        for c in table.rgb()[0] {
            assert_close(c, 0.5, 1e-15, "flat 0.5");
        }
        // A table rising in the blue at grazing angles (the paper's observation) is bluer there.
        let text = "angle_deg,380,500,600,780\n0,0.04,0.04,0.04,0.04\n90,0.9,0.2,0.1,0.1\n";
        let blue = FresnelTable::from_csv_str(text, "t").unwrap().eval(90.0);
        assert!(blue[2] > blue[1] && blue[2] > blue[0], "{blue:?}");
    }

    #[test]
    fn every_csv_error_names_its_line() {
        #[rustfmt::skip]
        let cases: [(&str, usize, &str); 21] = [
            ("", 1, "empty file"),
            ("\u{feff}\n  \n", 1, "empty file"),
            ("0,0,0,0\n90,1,1,1\n", 1, "missing header"),
            ("angle,r,g,b\n0,0,0,0\n90,1,1,1\n", 1, "wrong header"),
            ("angle_deg,r,g\n0,0,0\n90,1,1\n", 1, "wrong header"),
            ("angle_deg,r,g,b\n", 1, "no data rows"),
            ("angle_deg,r,g,b\n0,0,0\n90,1,1,1\n", 2, "expected 4"),
            ("angle_deg,r,g,b\n0,0,0,0\n90,1,1,1,1\n", 3, "expected 4"),
            ("angle_deg,r,g,b\n0,0,x,0\n90,1,1,1\n", 2, "not a number"),
            ("angle_deg,r,g,b\n0,0,,0\n90,1,1,1\n", 2, "empty"),
            ("angle_deg,r,g,b\n0,0,NaN,0\n90,1,1,1\n", 2, "not finite"),
            ("angle_deg,r,g,b\n0,0,0,0\n90,inf,1,1\n", 3, "not finite"),
            ("angle_deg,r,g,b\n5,0,0,0\n90,1,1,1\n", 2, "first angle must be 0"),
            ("angle_deg,r,g,b\n0,0,0,0\n40,0,0,0\n30,0,0,0\n90,1,1,1\n", 4, "strictly increase"),
            ("angle_deg,r,g,b\n0,0,0,0\n80,1,1,1\n\n", 3, "last angle must be 90"),
            ("angle_deg,r,g,b\n0,0,0,0\n95,1,1,1\n", 3, "above 90"),
            ("angle_deg,r,g,b\n0,0,0,0\n\n90,1,1,1\n", 3, "blank line"),
            ("angle_deg,r,g,b\n0,0,0,0\n90,1,1.2,1\n", 3, "outside [0, 1]"),
            ("angle_deg,380,600,500,780\n0,0,0,0,0\n90,1,1,1,1\n", 1, "strictly increase"),
            ("angle_deg,400,780\n0,0,0\n90,1,1\n", 1, "do not cover"),
            ("angle_deg,380,780\n0,0,-0.1\n90,1,1\n", 2, "outside [0, 1]"),
        ];
        for (text, line, needle) in cases {
            let (got_line, message) = csv_error(text);
            assert_eq!(got_line, line, "{text:?}: {message}");
            assert!(
                message.contains(needle),
                "{text:?}: `{message}` lacks `{needle}`"
            );
        }
    }

    #[test]
    fn csv_round_trip_is_exact() {
        let table = FresnelTable::dielectric(1.5, 0.0045).unwrap();
        let csv = table.to_csv();
        assert!(csv.starts_with("angle_deg,r,g,b\n0,"));
        assert_eq!(csv.lines().count(), 92);
        assert_eq!(
            FresnelTable::from_csv_str(&csv, "round trip").unwrap(),
            table
        );
    }

    #[test]
    fn csv_file_errors_name_the_file() {
        let missing = Path::new("/nonexistent/shikki/fresnel.csv");
        assert!(matches!(
            FresnelTable::from_csv_file(missing),
            Err(Error::Read { .. })
        ));
        let path =
            std::env::temp_dir().join(format!("shikki-fresnel-test-{}.csv", std::process::id()));
        std::fs::write(&path, "angle_deg,r,g,b\n0,0,0,0\n").unwrap();
        let result = FresnelTable::from_csv_file(&path);
        std::fs::remove_file(&path).unwrap();
        match result {
            Err(Error::Parse { file, line, .. }) => {
                assert_eq!(file, path.display().to_string());
                assert_eq!(line, 2);
            }
            other => panic!("{other:?}"),
        }
    }
}
