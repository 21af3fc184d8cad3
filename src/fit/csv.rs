//! The goniophotometer CSV (documented in docs/measurements.md): header
//! `sample,r,theta_i_deg,theta_o_deg,phi_deg,` then `R,G,B` or wavelengths in nm covering
//! 380–780; one row per measured value, reflectance factors π·f_r.
//!
//! Owns reading (every bad cell is an [`Error::Parse`] naming the line) and writing. A file is
//! read line by line, never held whole, and at most [`MAX_GONIOMETER_ROWS`] rows. The separator
//! (`,`, `;` or tab), quoted cells and decimal commas are [`crate::text`]'s; header names are
//! read in any case, and columns the fit does not use are left out with a note. Spectral rows are
//! converted to linear RGB by SPEC §3's spectral path on reading; the fit never sees spectra
//! (every term of the model is linear in the spectral quantities, so this is exact: see the doc).

use std::borrow::Cow;
use std::collections::HashMap;
use std::path::Path;

use super::data::{light_direction, view_direction, Measurement, Measurements, Sample};
use crate::model::fresnel::wavelength_nm;
use crate::model::spectral::reflectance_to_rgb;
use crate::text::{detect_separator, for_each_line, numbered_lines, parse_number, split_cells};
use crate::{Error, Result};

/// The geometry columns, in the order they are written.
pub const GEOMETRY_COLUMNS: [&str; 5] = ["sample", "r", "theta_i_deg", "theta_o_deg", "phi_deg"];

/// The RGB value columns.
pub const RGB_COLUMNS: [&str; 3] = ["R", "G", "B"];

const HEADER_HELP: &str = "the header must name sample, r, theta_i_deg, theta_o_deg, phi_deg \
    and then R,G,B or wavelengths in nm covering 380–780 (e.g. 380,390,…,780)";

/// The largest goniometer CSV read (1 GiB), refused from its length before reading: ~650 000
/// spectral rows of 81 wavelengths. The rows are capped by [`MAX_GONIOMETER_ROWS`] too.
pub const MAX_GONIOMETER_CSV_BYTES: u64 = 1 << 30;

/// The most rows read (1 000 000). A goniophotometer measurement is thousands to hundreds of
/// thousands of rows; the fit holds ~500 bytes a row (0.5 GB here, ~12 s), so the 12 million
/// rows a 1 GiB RGB file can hold took 6.2 GB and 143 s.
pub const MAX_GONIOMETER_ROWS: usize = 1_000_000;

/// Reads a goniometer CSV file line by line (at most [`MAX_GONIOMETER_CSV_BYTES`] and
/// [`MAX_GONIOMETER_ROWS`] rows).
pub fn read_goniometer_csv(path: &Path) -> Result<Measurements> {
    let mut reader = Reader::new(&path.display().to_string());
    for_each_line(
        path,
        MAX_GONIOMETER_CSV_BYTES,
        "goniometer CSV",
        |number, line| reader.line(number, line),
    )?;
    reader.finish()
}

/// Parses goniometer CSV text; `source` names it in errors. A UTF-8 BOM, any line end (LF, CRLF,
/// CR), whitespace around cells, blank lines and `#` comment lines are accepted.
pub fn parse_goniometer_csv(text: &str, source: &str) -> Result<Measurements> {
    let mut reader = Reader::new(source);
    for (number, line) in numbered_lines(text) {
        reader.line(number, line)?;
    }
    reader.finish()
}

/// Writes rows as an RGB goniometer CSV, with `comment` lines (prefixed `# `) first. `angles`
/// holds each row's (θ_i, θ_o, φ) in degrees, in row order (the vectors alone would print as
/// 29.999999999999996); numbers are written with Rust's shortest round-trip `{}`.
pub fn goniometer_csv(data: &Measurements, angles: &[[f64; 3]], comment: &str) -> String {
    let mut csv = String::with_capacity(data.rows.len() * 64);
    for line in comment.lines() {
        csv.push_str(&format!("# {line}\n"));
    }
    csv.push_str(&GEOMETRY_COLUMNS.join(","));
    csv.push(',');
    csv.push_str(&RGB_COLUMNS.join(","));
    csv.push('\n');
    for (row, [ti, to, phi]) in data.rows.iter().zip(angles) {
        let sample = &data.samples[row.sample];
        let [r, g, b] = row.reflectance;
        csv.push_str(&format!(
            "{},{},{ti},{to},{phi},{r},{g},{b}\n",
            sample.name, sample.lacquer_ratio
        ));
    }
    csv
}

/// The reading state: the header once found, the data so far and each sample's first line.
struct Reader {
    header: Option<(usize, Header)>,
    data: Measurements,
    /// Sample name → (index, line that first gave its r).
    sample_index: HashMap<String, (usize, usize)>,
}

impl Reader {
    fn new(source: &str) -> Self {
        Reader {
            header: None,
            data: Measurements {
                source: source.to_string(),
                samples: Vec::new(),
                rows: Vec::new(),
                notes: Vec::new(),
            },
            sample_index: HashMap::new(),
        }
    }

    /// One line of the file: skipped when blank or a comment, else the header or a row.
    fn line(&mut self, number: usize, text: &str) -> Result<()> {
        let text = text.trim();
        if text.is_empty() || text.starts_with('#') {
            return Ok(());
        }
        let source = &self.data.source;
        let fail = |message: String| Error::parse(source, number, message);
        let Some((_, header)) = &self.header else {
            let header = Header::parse(text).map_err(fail)?;
            if !header.ignored.is_empty() {
                self.data.notes.push(header.ignored_note(source, number));
            }
            self.header = Some((number, header));
            return Ok(());
        };
        if self.data.rows.len() == MAX_GONIOMETER_ROWS {
            return Err(fail(format!(
                "more than {MAX_GONIOMETER_ROWS} data rows; a goniophotometer measurement is \
                 thousands to hundreds of thousands of rows, and the fit holds ~500 bytes a \
                 row: thin the data (e.g. every other φ or θ_o) or fit each board on its own"
            )));
        }
        let row = header.parse_row(text).map_err(fail)?;
        let index = match self.sample_index.get(row.sample.as_ref()) {
            Some(&(index, first_line)) => {
                let r = self.data.samples[index].lacquer_ratio;
                if r != row.lacquer_ratio {
                    return Err(fail(format!(
                        "sample `{}` has r = {} here but r = {r} on line {first_line}; a sample is \
                         one board with one lacquer ratio",
                        row.sample, row.lacquer_ratio
                    )));
                }
                index
            }
            None => {
                let index = self.data.samples.len();
                let name = row.sample.into_owned();
                self.sample_index.insert(name.clone(), (index, number));
                self.data.samples.push(Sample {
                    name,
                    lacquer_ratio: row.lacquer_ratio,
                });
                index
            }
        };
        self.data.rows.push(Measurement {
            sample: index,
            light: light_direction(row.angles[0]),
            view: view_direction(row.angles[1], row.angles[2]),
            reflectance: row.rgb,
            line: number,
        });
        Ok(())
    }

    fn finish(self) -> Result<Measurements> {
        let Some((header_line, _)) = self.header else {
            return Err(Error::parse(
                &self.data.source,
                1,
                format!("empty file; {HEADER_HELP}"),
            ));
        };
        if self.data.rows.is_empty() {
            return Err(Error::parse(
                &self.data.source,
                header_line,
                "the header has no data rows after it; add one row per measured value",
            ));
        }
        Ok(self.data)
    }
}

/// The value columns of a header.
enum Values {
    Rgb,
    /// Wavelengths [nm], strictly increasing, covering 380–780.
    Spectral(Vec<f64>),
}

/// Where each column is.
struct Header {
    separator: char,
    /// Column index of each of [`GEOMETRY_COLUMNS`].
    geometry: [usize; 5],
    /// Column indices of the values, in wavelength (or R, G, B) order.
    value_columns: Vec<usize>,
    values: Values,
    /// The names as written (for messages).
    names: Vec<String>,
    /// A trailing separator left an unnamed last column: rows may have that empty cell or not.
    trailing_empty: bool,
    /// Columns the fit does not use (left out, with a note).
    ignored: Vec<usize>,
}

/// One parsed row.
struct Row<'a> {
    sample: Cow<'a, str>,
    lacquer_ratio: f64,
    /// θ_i, θ_o, φ in degrees.
    angles: [f64; 3],
    rgb: [f64; 3],
}

impl Header {
    fn parse(line: &str) -> std::result::Result<Self, String> {
        let separator = detect_separator(line);
        let names: Vec<String> = split_cells(line, separator)?
            .into_iter()
            .map(Cow::into_owned)
            .collect();
        if names
            .first()
            .is_some_and(|c| parse_number(c, separator).is_some())
        {
            return Err(format!(
                "missing header: the first line is data; {HEADER_HELP}"
            ));
        }
        if names.len() == 1 {
            return Err(format!(
                "the header `{line}` is one column: separate the columns with `,`, `;` or tabs; \
                 {HEADER_HELP}"
            ));
        }
        let trailing_empty = names.last().is_some_and(String::is_empty);
        let named = names.len() - usize::from(trailing_empty);
        if let Some(i) = (0..named).find(|&i| names[i].is_empty()) {
            return Err(format!(
                "column {} of the header has no name (two separators in a row?); name the \
                 column or remove it; {HEADER_HELP}",
                i + 1
            ));
        }
        let lower: Vec<String> = names[..named].iter().map(|n| n.to_lowercase()).collect();
        let find = |wanted: &str| -> std::result::Result<Option<usize>, String> {
            let found: Vec<usize> = (0..named).filter(|&i| lower[i] == wanted).collect();
            match found[..] {
                [] => Ok(None),
                [one] => Ok(Some(one)),
                [a, b, ..] => Err(format!(
                    "column `{wanted}` appears twice (columns {} and {}); keep one",
                    a + 1,
                    b + 1
                )),
            }
        };
        let (ratio, red) = ratio_and_red(&names, &lower)?;
        let green = find("g")?;
        let blue = find("b")?;
        let mut geometry = [0; 5];
        for (slot, wanted) in geometry.iter_mut().zip(GEOMETRY_COLUMNS) {
            let found = if wanted == "r" { ratio } else { find(wanted)? };
            *slot = found.ok_or_else(|| format!("missing column `{wanted}`; {HEADER_HELP}"))?;
        }
        let rgb = [red, green, blue];
        let rest: Vec<usize> = (0..named)
            .filter(|i| !geometry.contains(i) && !rgb.contains(&Some(*i)))
            .collect();
        let mut header = Header {
            separator,
            geometry,
            value_columns: Vec::new(),
            values: Values::Rgb,
            names,
            trailing_empty,
            ignored: Vec::new(),
        };
        if rgb.iter().any(Option::is_some) {
            if let Some(&i) = rest.iter().find(|&&i| wavelength_nm(&lower[i]).is_some()) {
                return Err(format!(
                    "the header has R,G,B and the wavelength column `{}`: keep one kind of \
                     value columns",
                    header.names[i]
                ));
            }
            header.value_columns = rgb
                .iter()
                .zip(RGB_COLUMNS)
                .map(|(c, name)| c.ok_or_else(|| format!("missing column `{name}`; {HEADER_HELP}")))
                .collect::<std::result::Result<Vec<_>, _>>()?;
            header.ignored = rest;
            return Ok(header);
        }
        header.spectral(rest)?;
        Ok(header)
    }

    /// The remaining columns named by a wavelength are the values: increasing, covering
    /// 380–780 nm; the others are left out.
    fn spectral(&mut self, rest: Vec<usize>) -> std::result::Result<(), String> {
        let mut nm = Vec::with_capacity(rest.len());
        for i in rest {
            match wavelength_nm(&self.names[i]) {
                // A wavelength is > 0 nm: `-380` passed as one and bent the resampling.
                Some(v) if v > 0.0 => {
                    nm.push(v);
                    self.value_columns.push(i);
                }
                Some(_) => {
                    return Err(format!(
                        "column `{}` is not a wavelength: wavelengths are in nm, greater than 0; \
                         {HEADER_HELP}",
                        self.names[i]
                    ))
                }
                None => self.ignored.push(i),
            }
        }
        if nm.is_empty() {
            let ignored: Vec<&str> = self.ignored.iter().map(|&i| &*self.names[i]).collect();
            return Err(format!(
                "missing the value columns: no R, G, B or wavelength column (the others are \
                 `{}`); {HEADER_HELP}",
                ignored.join("`, `")
            ));
        }
        if let Some(i) = (1..nm.len()).find(|&i| nm[i] <= nm[i - 1]) {
            return Err(format!(
                "wavelength {} nm is not greater than {} nm before it; wavelengths must strictly \
                 increase",
                nm[i],
                nm[i - 1]
            ));
        }
        let (first, last) = (nm[0], nm[nm.len() - 1]);
        if first > 380.0 || last < 780.0 {
            return Err(format!(
                "wavelengths {first}–{last} nm do not cover 380–780 nm; add columns down to 380 \
                 nm and up to 780 nm"
            ));
        }
        self.values = Values::Spectral(nm);
        Ok(())
    }

    /// The note for the columns left out.
    fn ignored_note(&self, source: &str, line: usize) -> String {
        let shown: Vec<String> = self
            .ignored
            .iter()
            .map(|&i| format!("`{}` (column {})", self.names[i], i + 1))
            .collect();
        format!(
            "{source}:{line}: column(s) {} are not read: the fit reads sample, r, theta_i_deg, \
             theta_o_deg, phi_deg and R,G,B or wavelengths in nm",
            shown.join(", ")
        )
    }

    fn parse_row<'a>(&self, line: &'a str) -> std::result::Result<Row<'a>, String> {
        let mut cells = split_cells(line, self.separator)?;
        let columns = self.names.len();
        // A trailing separator on the rows and not the header, or on the header and not the
        // rows, is the same table.
        if cells.len() == columns + 1 && cells.last().is_some_and(|c| c.is_empty()) {
            cells.pop();
        } else if self.trailing_empty && cells.len() + 1 == columns {
            cells.push(Cow::Borrowed(""));
        }
        if cells.len() != columns {
            return Err(format!(
                "expected {columns} cells separated by {} as in the header, found {}",
                crate::text::separator_name(self.separator),
                cells.len()
            ));
        }
        let sample = std::mem::take(&mut cells[self.geometry[0]]);
        if sample.is_empty() {
            return Err("`sample` is empty; name the board this row was measured on".into());
        }
        let lacquer_ratio = self.number(&cells, self.geometry[1])?;
        if lacquer_ratio < 1.0 {
            return Err(format!(
                "`r` = {lacquer_ratio} is below 1; r is the lacquer ratio relative to the \
                 least-lacquer sample, which has r = 1"
            ));
        }
        let theta_i = self.angle(&cells, 2, |a| (0.0..90.0).contains(&a), "[0, 90)")?;
        let theta_o = self.angle(&cells, 3, |a| a.abs() < 90.0, "(-90, 90)")?;
        let phi = self.angle(&cells, 4, |a| a.abs() <= 360.0, "[-360, 360]")?;
        let values = self
            .value_columns
            .iter()
            .map(|&i| {
                let v = self.number(&cells, i)?;
                if v < 0.0 {
                    return Err(format!(
                        "`{}` = {v} is negative; reflectance factors (π·f_r) are >= 0",
                        self.names[i]
                    ));
                }
                Ok(v)
            })
            .collect::<std::result::Result<Vec<f64>, String>>()?;
        let rgb = match &self.values {
            Values::Rgb => [values[0], values[1], values[2]],
            Values::Spectral(nm) => reflectance_to_rgb(nm, &values),
        };
        Ok(Row {
            sample,
            lacquer_ratio,
            angles: [theta_i, theta_o, phi],
            rgb,
        })
    }

    /// A finite number in column `i`, or why not.
    fn number(&self, cells: &[Cow<str>], i: usize) -> std::result::Result<f64, String> {
        let (name, cell) = (&self.names[i], &*cells[i]);
        match parse_number(cell, self.separator) {
            Some(v) if v.is_finite() => Ok(v),
            Some(_) => Err(format!("`{name}` = `{cell}` is not a finite number")),
            None if cell.is_empty() => Err(format!("`{name}` is empty; put a number there")),
            None => Err(format!("`{name}` = `{cell}` is not a number")),
        }
    }

    /// Geometry column `g` (2..=4) as an angle for which `valid` holds (the range is written
    /// `shown` in the message).
    fn angle(
        &self,
        cells: &[Cow<str>],
        g: usize,
        valid: impl Fn(f64) -> bool,
        shown: &str,
    ) -> std::result::Result<f64, String> {
        let i = self.geometry[g];
        let v = self.number(cells, i)?;
        if valid(v) {
            Ok(v)
        } else {
            Err(format!("`{}` = {v} is outside {shown}", self.names[i]))
        }
    }
}

/// The lacquer ratio `r` and the red channel `R` are one name in any case. Written `r` and `R`
/// they are told apart by case; written alike (an upper-cased header: `SAMPLE,R,…,R,G,B`), the
/// first is the ratio and the second red, the order the header is documented in. One such
/// column is red only when written `R` beside G or B columns.
fn ratio_and_red(
    names: &[String],
    lower: &[String],
) -> std::result::Result<(Option<usize>, Option<usize>), String> {
    let found: Vec<usize> = (0..lower.len()).filter(|&i| lower[i] == "r").collect();
    let beside_green_or_blue = lower.iter().any(|n| n == "g" || n == "b");
    match found[..] {
        [] => Ok((None, None)),
        [one] if names[one] == "R" && beside_green_or_blue => Ok((None, Some(one))),
        [one] => Ok((Some(one), None)),
        [a, b] if names[a] == "R" && names[b] == "r" => Ok((Some(b), Some(a))),
        [a, b] => Ok((Some(a), Some(b))),
        [a, b, c, ..] => Err(format!(
            "columns {}, {} and {} are all named `r`/`R`; name the lacquer ratio `r` once and \
             red `R` once",
            a + 1,
            b + 1,
            c + 1
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "sample,r,theta_i_deg,theta_o_deg,phi_deg,R,G,B\n";

    fn parse_error(text: &str) -> (usize, String) {
        match parse_goniometer_csv(text, "t.csv") {
            Err(Error::Parse { line, message, .. }) => (line, message),
            other => panic!("expected a parse error, got {other:?}"),
        }
    }

    #[test]
    fn reads_rgb_rows_with_comments_and_any_column_order() {
        let text = "\u{feff}# measured 2024\nr,sample,theta_i_deg,phi_deg,theta_o_deg,B,G,R\r\n\
                    1,A,30,0,30,0.3,0.2,0.1\n\n2,B,0,90,45,0.6,0.5,0.4\n";
        let data = parse_goniometer_csv(text, "t.csv").unwrap();
        assert_eq!(data.samples.len(), 2);
        assert_eq!(
            data.samples[1],
            Sample {
                name: "B".into(),
                lacquer_ratio: 2.0
            }
        );
        assert_eq!(data.rows[0].reflectance, [0.1, 0.2, 0.3]);
        assert_eq!((data.rows[0].line, data.rows[1].line), (3, 5));
        // θ_o = 45 at φ = 90: V = (0, sin 45°, cos 45°) (hand value; 1e-15 rounding).
        let v = data.rows[1].view;
        let s = 0.5f64.sqrt();
        assert!(v.x.abs() < 1e-15 && (v.y - s).abs() < 1e-15 && (v.z - s).abs() < 1e-15);
    }

    #[test]
    fn spectral_rows_go_through_the_spectral_path() {
        // A flat spectrum of 0.25 is RGB (0.25, 0.25, 0.25) (SPEC §3: flat 1 → exactly white;
        // the path is linear, so 1e-15 of rounding).
        let text =
            "sample,r,theta_i_deg,theta_o_deg,phi_deg,380,580,780\nA,1,10,20,0,0.25,0.25,0.25\n";
        let data = parse_goniometer_csv(text, "t.csv").unwrap();
        for c in data.rows[0].reflectance {
            assert!((c - 0.25).abs() < 1e-15, "{c}");
        }
    }

    #[test]
    fn header_errors_name_line_and_fix() {
        let (line, m) = parse_error("# c\nsample,r,theta_i_deg,phi_deg,R,G,B\n");
        assert_eq!(line, 2);
        assert!(
            m.starts_with("missing column `theta_o_deg`; the header must name"),
            "{m}"
        );
        let (_, m) = parse_error("sample,r,theta_i_deg,theta_o_deg,phi_deg,R,G\n");
        assert!(m.starts_with("missing column `B`"), "{m}");
        let (_, m) = parse_error("sample,r,theta_i_deg,theta_o_deg,phi_deg,400,700\n");
        assert!(
            m.starts_with("wavelengths 400–700 nm do not cover 380–780 nm"),
            "{m}"
        );
        // Not a wavelength: it covered 380 nm and bent the resampling.
        let (_, m) = parse_error("sample,r,theta_i_deg,theta_o_deg,phi_deg,-380,580,780\n");
        assert!(m.starts_with("column `-380` is not a wavelength"), "{m}");
        let (_, m) = parse_error("sample,r,theta_i_deg,theta_o_deg,phi_deg,R,G,B,380\n");
        assert!(m.contains("R,G,B and the wavelength column `380`"), "{m}");
        let (_, m) = parse_error("sample,r,theta_i_deg,,theta_o_deg,phi_deg,R,G,B\n");
        assert!(m.starts_with("column 4 of the header has no name"), "{m}");
        let (_, m) = parse_error("sample,r,theta_i_deg,theta_o_deg,phi_deg,red,green,blue\n");
        assert!(
            m.starts_with(
                "missing the value columns: no R, G, B or wavelength column (the others are \
                 `red`, `green`, `blue`)"
            ),
            "{m}"
        );
        let (_, m) = parse_error("sample|r|theta_i_deg|theta_o_deg|phi_deg|R|G|B\n");
        assert!(
            m.contains("is one column: separate the columns with"),
            "{m}"
        );
        let (line, m) = parse_error(HEADER);
        assert_eq!(line, 1);
        assert!(m.starts_with("the header has no data rows"), "{m}");
    }

    #[test]
    fn unread_columns_are_noted_and_spectral_names_may_carry_nm() {
        let text = "B,G,R,phi_deg,theta_o_deg,theta_i_deg,r,sample,operator\n\
                    0.3,0.2,0.1,0,30,30,1,A,bob\n";
        let data = parse_goniometer_csv(text, "t.csv").unwrap();
        assert_eq!(data.rows[0].reflectance, [0.1, 0.2, 0.3]);
        assert_eq!(
            data.notes,
            [
                "t.csv:1: column(s) `operator` (column 9) are not read: the fit reads sample, r, \
              theta_i_deg, theta_o_deg, phi_deg and R,G,B or wavelengths in nm"
            ]
        );
        let text = "sample,r,theta_i_deg,theta_o_deg,phi_deg,380 nm,580nm,780.0\n\
                    A,1,10,20,0,0.25,0.25,0.25\n";
        let data = parse_goniometer_csv(text, "t.csv").unwrap();
        assert!(data.notes.is_empty());
        // Flat 0.25 is grey 0.25 (see spectral_rows_go_through_the_spectral_path).
        assert!((data.rows[0].reflectance[1] - 0.25).abs() < 1e-15);
    }

    #[test]
    fn upper_case_headers_tell_the_ratio_from_red() {
        // Upper-cased, `r` and `R` are both `R`: the first is the ratio, as documented.
        let text = "SAMPLE,R,THETA_I_DEG,THETA_O_DEG,PHI_DEG,R,G,B\nA,2,30,30,0,0.1,0.2,0.3\n";
        let data = parse_goniometer_csv(text, "t.csv").unwrap();
        assert_eq!(data.samples[0].lacquer_ratio, 2.0);
        assert_eq!(data.rows[0].reflectance, [0.1, 0.2, 0.3]);
        // Written `R` then `r`, case tells them apart whatever the order.
        let text = "R,G,B,sample,r,theta_i_deg,theta_o_deg,phi_deg\n0.1,0.2,0.3,A,2,30,30,0\n";
        let data = parse_goniometer_csv(text, "t.csv").unwrap();
        assert_eq!(data.samples[0].lacquer_ratio, 2.0);
        assert_eq!(data.rows[0].reflectance, [0.1, 0.2, 0.3]);
        let (_, m) = parse_error("sample,theta_i_deg,theta_o_deg,phi_deg,R,G,B\n");
        assert!(m.starts_with("missing column `r`"), "{m}");
        let (_, m) = parse_error("sample,r,theta_i_deg,theta_o_deg,phi_deg,Theta_O_deg,R,G,B\n");
        assert!(
            m.starts_with("column `theta_o_deg` appears twice (columns 4 and 6)"),
            "{m}"
        );
    }

    #[test]
    fn sample_with_two_ratios_is_an_error() {
        let text = format!("{HEADER}A,1,30,30,0,1,1,1\nA,2,30,40,0,1,1,1\n");
        let (line, m) = parse_error(&text);
        assert_eq!(line, 3);
        assert_eq!(
            m,
            "sample `A` has r = 2 here but r = 1 on line 2; a sample is one board with one \
             lacquer ratio"
        );
    }

    #[test]
    fn write_then_read_is_exact() {
        let text = format!("{HEADER}A,1,30,-40,0,0.1,0.2,0.30000000000000004\n");
        let data = parse_goniometer_csv(&text, "t.csv").unwrap();
        let out = goniometer_csv(&data, &[[30.0, -40.0, 0.0]], "synthetic");
        assert!(out.starts_with("# synthetic\nsample,r,theta_i_deg"));
        assert_eq!(parse_goniometer_csv(&out, "t.csv").unwrap().rows, {
            let mut rows = data.rows.clone();
            rows[0].line = 3;
            rows
        });
    }
}
