//! The goniophotometer CSV (documented in docs/measurements.md): header
//! `sample,r,theta_i_deg,theta_o_deg,phi_deg,` then `R,G,B` or wavelengths in nm covering
//! 380–780; one row per measured value, reflectance factors π·f_r.
//!
//! Owns reading (every bad cell is an [`Error::Parse`] naming the line) and writing. Spectral rows
//! are converted to linear RGB by SPEC §3's spectral path on reading; the fit never sees spectra
//! (every term of the model is linear in the spectral quantities, so this is exact: see the doc).

use std::collections::HashMap;
use std::path::Path;

use super::data::{light_direction, view_direction, Measurement, Measurements, Sample};
use crate::model::spectral::reflectance_to_rgb;
use crate::text::read_text_file;
use crate::{Error, Result};

/// The geometry columns, in the order they are written.
pub const GEOMETRY_COLUMNS: [&str; 5] = ["sample", "r", "theta_i_deg", "theta_o_deg", "phi_deg"];

/// The RGB value columns.
pub const RGB_COLUMNS: [&str; 3] = ["R", "G", "B"];

const HEADER_HELP: &str = "the header must name sample, r, theta_i_deg, theta_o_deg, phi_deg \
    and then R,G,B or wavelengths in nm covering 380–780 (e.g. 380,390,…,780)";

/// The largest goniometer CSV read (1 GiB): a dense measurement of a few million rows.
pub const MAX_GONIOMETER_CSV_BYTES: u64 = 1 << 30;

/// Reads a goniometer CSV file (at most [`MAX_GONIOMETER_CSV_BYTES`]).
pub fn read_goniometer_csv(path: &Path) -> Result<Measurements> {
    let text = read_text_file(path, MAX_GONIOMETER_CSV_BYTES, "goniometer CSV")?;
    parse_goniometer_csv(&text, &path.display().to_string())
}

/// Parses goniometer CSV text; `source` names it in errors. A UTF-8 BOM, CRLF line ends,
/// whitespace around cells, blank lines and `#` comment lines are accepted.
pub fn parse_goniometer_csv(text: &str, source: &str) -> Result<Measurements> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, line)| (i + 1, line.trim()))
        .filter(|(_, line)| !line.is_empty() && !line.starts_with('#'));
    let Some((header_line, header_text)) = lines.next() else {
        return Err(Error::parse(
            source,
            1,
            format!("empty file; {HEADER_HELP}"),
        ));
    };
    let header = Header::parse(header_text).map_err(|m| Error::parse(source, header_line, m))?;
    let mut data = Measurements {
        source: source.to_string(),
        samples: Vec::new(),
        rows: Vec::new(),
    };
    // Sample name → (index, line that first gave its r).
    let mut sample_index: HashMap<String, (usize, usize)> = HashMap::new();
    for (line, text) in lines {
        let fail = |message: String| Error::parse(source, line, message);
        let row = header.parse_row(text).map_err(fail)?;
        let index = match sample_index.get(&row.sample) {
            Some(&(index, first_line)) => {
                let r = data.samples[index].lacquer_ratio;
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
                let index = data.samples.len();
                sample_index.insert(row.sample.clone(), (index, line));
                data.samples.push(Sample {
                    name: row.sample,
                    lacquer_ratio: row.lacquer_ratio,
                });
                index
            }
        };
        data.rows.push(Measurement {
            sample: index,
            light: light_direction(row.angles[0]),
            view: view_direction(row.angles[1], row.angles[2]),
            reflectance: row.rgb,
            line,
        });
    }
    if data.rows.is_empty() {
        return Err(Error::parse(
            source,
            header_line,
            "the header has no data rows after it; add one row per measured value",
        ));
    }
    Ok(data)
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

/// The value columns of a header.
enum Values {
    Rgb,
    /// Wavelengths [nm], strictly increasing, covering 380–780.
    Spectral(Vec<f64>),
}

/// Where each column is.
struct Header {
    /// Column index of each of [`GEOMETRY_COLUMNS`].
    geometry: [usize; 5],
    /// Column indices of the values, in wavelength (or R, G, B) order.
    value_columns: Vec<usize>,
    values: Values,
    names: Vec<String>,
}

/// One parsed row.
struct Row {
    sample: String,
    lacquer_ratio: f64,
    /// θ_i, θ_o, φ in degrees.
    angles: [f64; 3],
    rgb: [f64; 3],
}

impl Header {
    fn parse(line: &str) -> std::result::Result<Self, String> {
        let names: Vec<String> = line.split(',').map(|c| c.trim().to_string()).collect();
        if names.first().is_some_and(|c| c.parse::<f64>().is_ok()) {
            return Err(format!(
                "missing header: the first line is data; {HEADER_HELP}"
            ));
        }
        let mut geometry = [0; 5];
        for (slot, wanted) in geometry.iter_mut().zip(GEOMETRY_COLUMNS) {
            *slot = names
                .iter()
                .position(|n| n == wanted)
                .ok_or_else(|| format!("missing column `{wanted}`; {HEADER_HELP}"))?;
        }
        let rest: Vec<usize> = (0..names.len()).filter(|i| !geometry.contains(i)).collect();
        if rest.is_empty() {
            return Err(format!("missing the value columns; {HEADER_HELP}"));
        }
        let rgb: Vec<Option<usize>> = RGB_COLUMNS
            .iter()
            .map(|c| {
                rest.iter()
                    .copied()
                    .find(|&i| names[i].eq_ignore_ascii_case(c))
            })
            .collect();
        if rgb.iter().any(Option::is_some) {
            if let Some(&extra) = rest.iter().find(|i| !rgb.contains(&Some(**i))) {
                return Err(format!("unknown column `{}`; {HEADER_HELP}", names[extra]));
            }
            let value_columns = rgb
                .iter()
                .zip(RGB_COLUMNS)
                .map(|(c, name)| c.ok_or_else(|| format!("missing column `{name}`; {HEADER_HELP}")))
                .collect::<std::result::Result<Vec<_>, _>>()?;
            return Ok(Header {
                geometry,
                value_columns,
                values: Values::Rgb,
                names,
            });
        }
        Self::spectral(geometry, rest, names)
    }

    /// Every remaining column is a wavelength: increasing, covering 380–780 nm.
    fn spectral(
        geometry: [usize; 5],
        value_columns: Vec<usize>,
        names: Vec<String>,
    ) -> std::result::Result<Self, String> {
        let mut nm = Vec::with_capacity(value_columns.len());
        for &i in &value_columns {
            match names[i].parse::<f64>() {
                // A wavelength is > 0 nm: `-380` passed as one and bent the resampling.
                Ok(v) if v.is_finite() && v > 0.0 => nm.push(v),
                _ => return Err(format!("unknown column `{}`; {HEADER_HELP}", names[i])),
            }
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
        Ok(Header {
            geometry,
            value_columns,
            values: Values::Spectral(nm),
            names,
        })
    }

    fn parse_row(&self, line: &str) -> std::result::Result<Row, String> {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != self.names.len() {
            return Err(format!(
                "expected {} comma-separated cells as in the header, found {}",
                self.names.len(),
                cells.len()
            ));
        }
        let sample = cells[self.geometry[0]];
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
            sample: sample.to_string(),
            lacquer_ratio,
            angles: [theta_i, theta_o, phi],
            rgb,
        })
    }

    /// A finite number in column `i`, or why not.
    fn number(&self, cells: &[&str], i: usize) -> std::result::Result<f64, String> {
        let (name, cell) = (&self.names[i], cells[i]);
        match cell.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(format!("`{name}` = `{cell}` is not a finite number")),
            Err(_) if cell.is_empty() => Err(format!("`{name}` is empty; put a number there")),
            Err(_) => Err(format!("`{name}` = `{cell}` is not a number")),
        }
    }

    /// Geometry column `g` (2..=4) as an angle for which `valid` holds (the range is written
    /// `shown` in the message).
    fn angle(
        &self,
        cells: &[&str],
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
        let (_, m) = parse_error("sample,r,theta_i_deg,theta_o_deg,phi_deg,R,G,B,X\n");
        assert!(m.starts_with("unknown column `X`"), "{m}");
        // Not a wavelength: it covered 380 nm and bent the resampling.
        let (_, m) = parse_error("sample,r,theta_i_deg,theta_o_deg,phi_deg,-380,580,780\n");
        assert!(m.starts_with("unknown column `-380`"), "{m}");
        let (line, m) = parse_error(HEADER);
        assert_eq!(line, 1);
        assert!(m.starts_with("the header has no data rows"), "{m}");
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
