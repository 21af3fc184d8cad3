//! The `shikki brdf` input: CSV rows `nx,ny,nz,vx,vy,vz,lx,ly,lz` (header required), at most
//! [`MAX_DIRECTION_ROWS`] of them.

use crate::{Error, Result};
use glam::DVec3;

pub const HEADER: &str = "nx,ny,nz,vx,vy,vz,lx,ly,lz";

/// The most rows evaluated (1 000 000, as many as `shikki fit` reads): the command holds ~360
/// bytes a row (the directions, the values and the output text; 2 million rows took 714 MB).
pub const MAX_DIRECTION_ROWS: usize = 1_000_000;

/// The largest input (256 MiB): a row of nine full-precision numbers is under 230 bytes, so
/// this holds [`MAX_DIRECTION_ROWS`] rows of any spelling. `shikki brdf` refuses a longer file
/// from its length, before reading it (`text::read_text_file`).
pub const MAX_DIRECTIONS_CSV_BYTES: u64 = 256 << 20;

/// Parses the CSV text; every error names the line. Vectors are normalised here. Text above
/// [`MAX_DIRECTIONS_CSV_BYTES`] or with more than [`MAX_DIRECTION_ROWS`] rows is refused.
pub fn parse_directions(text: &str, source: &str) -> Result<Vec<[DVec3; 3]>> {
    if text.len() as u64 > MAX_DIRECTIONS_CSV_BYTES {
        return Err(Error::invalid(
            "directions CSV file",
            format!("{source} ({} bytes)", text.len()),
            format!(
                "at most {MAX_DIRECTIONS_CSV_BYTES} bytes ({MAX_DIRECTION_ROWS} rows) are read; \
                 split the directions into several files"
            ),
        ));
    }
    let mut lines = crate::text::numbered_lines(text).map(|(n, line)| (n - 1, line));
    let header = lines
        .by_ref()
        .find(|(_, l)| !l.trim().is_empty())
        .ok_or_else(|| {
            Error::parse(
                source,
                1,
                format!("empty file; expected the header {HEADER}"),
            )
        })?;
    let got: Vec<String> = header
        .1
        .split(',')
        .map(|s| s.trim().to_lowercase())
        .collect();
    if got.join(",") != HEADER {
        return Err(Error::parse(
            source,
            header.0 + 1,
            format!("header is {:?}; expected exactly {HEADER}", header.1.trim()),
        ));
    }
    let mut rows = Vec::new();
    for (index, line) in lines {
        let line_no = index + 1;
        if line.trim().is_empty() {
            continue;
        }
        if rows.len() == MAX_DIRECTION_ROWS {
            return Err(Error::parse(
                source,
                line_no,
                format!(
                    "more than {MAX_DIRECTION_ROWS} rows; evaluate at most that many directions \
                     at a time: split the file"
                ),
            ));
        }
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != 9 {
            return Err(Error::parse(
                source,
                line_no,
                format!("{} columns; expected 9 ({HEADER})", cells.len()),
            ));
        }
        let mut values = [0.0f64; 9];
        for (i, (slot, cell)) in values.iter_mut().zip(&cells).enumerate() {
            let name = HEADER.split(',').nth(i).unwrap_or("?");
            let x: f64 = cell.parse().map_err(|_| {
                Error::parse(
                    source,
                    line_no,
                    format!("{name} = {cell:?} is not a number"),
                )
            })?;
            if !x.is_finite() {
                return Err(Error::parse(
                    source,
                    line_no,
                    format!("{name} = {cell} must be finite"),
                ));
            }
            *slot = x;
        }
        let mut triple = [DVec3::ZERO; 3];
        for (k, (slot, label)) in triple.iter_mut().zip(["N", "V", "L"]).enumerate() {
            let v = DVec3::new(values[3 * k], values[3 * k + 1], values[3 * k + 2]);
            *slot = unit_vector(v).ok_or_else(|| {
                Error::parse(
                    source,
                    line_no,
                    format!("{label} is the zero vector; give a direction"),
                )
            })?;
        }
        rows.push(triple);
    }
    Ok(rows)
}

/// `v` scaled to length 1, or `None` for the zero vector. Divided by its largest component first,
/// so that any finite non-zero vector works: the length of (1e200, 1e200, 1e200) overflows to
/// infinity and that of (1e-170, …) underflows to 0, and both were called the zero vector.
fn unit_vector(v: DVec3) -> Option<DVec3> {
    let largest = v.abs().max_element();
    if !(largest > 0.0 && largest.is_finite()) {
        return None;
    }
    let scaled = v / largest;
    Some(scaled / scaled.length())
}

/// One output row: the normalised vectors and f_r, every value with 10 significant digits.
pub fn format_row(triple: &[DVec3; 3], rgb: [f64; 3]) -> String {
    let mut cells: Vec<String> = Vec::with_capacity(12);
    for v in triple {
        cells.extend(v.to_array().iter().map(|x| format!("{x:.9e}")));
    }
    cells.extend(rgb.iter().map(|x| format!("{x:.9e}")));
    cells.join(",")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_normalises_rows() {
        let rows =
            parse_directions("nx,ny,nz,vx,vy,vz,lx,ly,lz\n0,0,2,0,1,1,1,0,1\n", "t").unwrap();
        assert_eq!(rows.len(), 1);
        assert!((rows[0][1].length() - 1.0).abs() < 1e-15);
        assert!((rows[0][1].y - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-15);
    }

    #[test]
    fn errors_name_the_line() {
        let err = parse_directions(
            "nx,ny,nz,vx,vy,vz,lx,ly,lz\n0,0,1,0,0,1,0,0,1\n0,0,1,x,0,1,0,0,1\n",
            "d.csv",
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("d.csv:3") && err.contains("vx"), "{err}");
        let err = parse_directions("a,b\n", "d.csv").unwrap_err().to_string();
        assert!(err.contains("d.csv:1") && err.contains("header"), "{err}");
        let err = parse_directions("nx,ny,nz,vx,vy,vz,lx,ly,lz\n0,0,0,0,0,1,0,0,1\n", "d.csv")
            .unwrap_err()
            .to_string();
        assert!(err.contains("zero vector"), "{err}");
    }

    #[test]
    fn huge_and_tiny_vectors_normalise() {
        // (1e200, …) overflowed the length and (1e-170, …) underflowed it: "N is the zero
        // vector". Scaled first, both are (1, 1, 1)/√3 to rounding (1e-15); 5e-324 is the
        // smallest subnormal.
        let text =
            "nx,ny,nz,vx,vy,vz,lx,ly,lz\n1e200,1e200,1e200,1e-170,1e-170,1e-170,0,0,5e-324\n";
        let rows = parse_directions(text, "t").unwrap();
        let diagonal = DVec3::ONE / 3f64.sqrt();
        for v in &rows[0][..2] {
            assert!((*v - diagonal).length() < 1e-15, "{v}");
        }
        assert_eq!(rows[0][2], DVec3::Z);
        // CR-only line ends read as line ends.
        let rows = parse_directions("nx,ny,nz,vx,vy,vz,lx,ly,lz\r0,0,1,0,0,1,0,0,1\r", "t");
        assert_eq!(rows.unwrap().len(), 1);
    }

    #[test]
    fn too_many_rows_are_refused_at_the_first_extra_row() {
        let mut text = String::from("nx,ny,nz,vx,vy,vz,lx,ly,lz\n");
        text.push_str(&"0,0,1,0,0,1,0,0,1\n".repeat(MAX_DIRECTION_ROWS + 1));
        let err = parse_directions(&text, "d.csv").unwrap_err().to_string();
        assert!(
            err.starts_with(&format!(
                "d.csv:{}: more than 1000000 rows",
                MAX_DIRECTION_ROWS + 2
            )),
            "{err}"
        );
    }

    #[test]
    fn rows_have_at_least_nine_significant_digits() {
        let row = format_row(&[DVec3::Z, DVec3::Z, DVec3::Z], [0.123456789123, 1.0, 0.0]);
        assert!(row.contains("1.234567891e-1"), "{row}");
    }
}
