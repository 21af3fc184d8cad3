//! The `shikki brdf` input: CSV rows `nx,ny,nz,vx,vy,vz,lx,ly,lz` (header required).

use crate::{Error, Result};
use glam::DVec3;

pub const HEADER: &str = "nx,ny,nz,vx,vy,vz,lx,ly,lz";

/// Parses the CSV text; every error names the line. Vectors are normalised here.
pub fn parse_directions(text: &str, source: &str) -> Result<Vec<[DVec3; 3]>> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text.lines().enumerate();
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
            let len = v.length();
            if !(len > 0.0 && len.is_finite()) {
                return Err(Error::parse(
                    source,
                    line_no,
                    format!("{label} is the zero vector; give a direction"),
                ));
            }
            *slot = v / len;
        }
        rows.push(triple);
    }
    Ok(rows)
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
    fn rows_have_at_least_nine_significant_digits() {
        let row = format_row(&[DVec3::Z, DVec3::Z, DVec3::Z], [0.123456789123, 1.0, 0.0]);
        assert!(row.contains("1.234567891e-1"), "{row}");
    }
}
