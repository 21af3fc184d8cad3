//! Wavefront OBJ through `tobj`, behind a line filter that checks every line first.
//!
//! `tobj` reports errors without line numbers and can overflow on hostile face indices, so each
//! line passes [`ObjFilter`] before `tobj` sees it: the filter checks numbers and index ranges
//! (naming the line), counts triangles against the limit while streaming (before `tobj`
//! allocates more), and hands `tobj` a canonical file of `v x y z`, `vn x y z` and
//! `f v[//vn] …` lines with absolute indices. Texture coordinates, groups, materials, points and
//! lines are dropped (points and lines noted), so vertices are shared exactly as the file's `v`
//! indices share them, and `tobj` only triangulates (fans) and builds the single index.
//! Owns nothing else; the clean-up is `MeshBuilder`'s.

use std::collections::HashMap;
use std::fs::File;
use std::io::{self, BufRead, BufReader, Read};
use std::path::Path;

use super::{content_error, LoadReport, MeshBuilder, Part, MAX_TRIANGLES, MAX_VERTICES};
use crate::raster::mesh::Mesh;
use crate::{Error, Result};

/// Longer lines are refused rather than buffered: no real OBJ line is a megabyte.
const MAX_LINE_BYTES: u64 = 1 << 20;

pub(super) fn load(path: &Path) -> Result<(Mesh, LoadReport)> {
    let file = File::open(path).map_err(|source| Error::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let mut filter = ObjFilter::new(BufReader::new(file), path);
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    // The filter drops `mtllib`, so the material loader is never called.
    let loaded = tobj::load_obj_buf(&mut filter, &options, |_| Ok((Vec::new(), HashMap::new())));
    if let Some(error) = filter.error.take() {
        return Err(error);
    }
    let models = match loaded {
        Ok((models, _)) => models,
        Err(e) => {
            return Err(Error::parse(
                path.display().to_string(),
                filter.line.max(1),
                format!("tobj: {e}"),
            ))
        }
    };

    let mut builder = MeshBuilder::new(path);
    let counts = &filter.counts;
    if counts.points_or_lines > 0 {
        builder.report.skipped.push(format!(
            "skipped {} point/line element(s) (only faces are drawn)",
            counts.points_or_lines
        ));
    }
    // Some face corners with a normal and some without: tobj's normal array no longer lines up
    // with its vertices, so every normal is generated instead.
    let file_has_normals = counts.corners_with_normal > 0 && counts.corners_without_normal == 0;
    if counts.corners_with_normal > 0 && counts.corners_without_normal > 0 {
        builder.report.skipped.push(format!(
            "ignored the file's normals: {} face corner(s) have none",
            counts.corners_without_normal
        ));
    }
    for model in models {
        let mesh = model.mesh;
        let positions = triples(&mesh.positions);
        let normals = triples(&mesh.normals);
        let normals = (file_has_normals && normals.len() == positions.len()).then_some(normals);
        if mesh.indices.iter().any(|&i| i as usize >= positions.len()) {
            return Err(content_error(
                path,
                "internal: tobj produced an out-of-range index",
            ));
        }
        builder.add(Part {
            positions,
            normals,
            indices: mesh.indices,
        })?;
    }
    builder.finish()
}

fn triples(flat: &[f32]) -> Vec<[f32; 3]> {
    flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
}

#[derive(Default)]
struct Counts {
    positions: usize,
    normals: usize,
    texcoords: usize,
    triangles: usize,
    points_or_lines: usize,
    corners_with_normal: usize,
    corners_without_normal: usize,
}

/// A `BufRead` that yields the canonical form of each checked line, or stops with an I/O error
/// after storing the real [`Error`] in `error`.
struct ObjFilter<'a, R> {
    inner: R,
    file: &'a Path,
    /// 1-based number of the last line read.
    line: usize,
    raw: Vec<u8>,
    /// The lines so far of a statement continued by a trailing `\` (the OBJ format's line
    /// continuation), joined by spaces.
    continued: String,
    out: Vec<u8>,
    out_pos: usize,
    counts: Counts,
    error: Option<Error>,
}

impl<'a, R: BufRead> ObjFilter<'a, R> {
    fn new(inner: R, file: &'a Path) -> Self {
        ObjFilter {
            inner,
            file,
            line: 0,
            raw: Vec::new(),
            continued: String::new(),
            out: Vec::new(),
            out_pos: 0,
            counts: Counts::default(),
            error: None,
        }
    }

    fn parse_error(&self, message: impl Into<String>) -> Error {
        Error::parse(self.file.display().to_string(), self.line, message)
    }

    /// Reads lines until one produces output or the file ends (then `out` stays empty).
    fn refill(&mut self) -> Result<()> {
        self.out.clear();
        self.out_pos = 0;
        while self.out.is_empty() {
            self.raw.clear();
            let read = (&mut self.inner)
                .take(MAX_LINE_BYTES + 1)
                .read_until(b'\n', &mut self.raw)
                .map_err(|source| Error::Read {
                    path: self.file.to_path_buf(),
                    source,
                })?;
            if read == 0 {
                // A file whose last line ends in `\`: the statement ends with the file.
                if !self.continued.is_empty() {
                    let statement = std::mem::take(&mut self.continued);
                    self.emit(&statement)?;
                }
                return Ok(());
            }
            self.line += 1;
            if read as u64 > MAX_LINE_BYTES {
                return Err(self.parse_error(format!(
                    "line is longer than {MAX_LINE_BYTES} bytes; is this an OBJ text file?"
                )));
            }
            let raw = std::mem::take(&mut self.raw);
            let text = std::str::from_utf8(&raw)
                .map_err(|_| self.parse_error("line is not valid UTF-8 text"))?;
            // Editors on Windows start UTF-8 files with a byte-order mark. Left in, it glues onto
            // the first keyword ("\u{feff}v"), which no keyword matches: the first vertex was
            // dropped and every face index after it pointed one vertex off.
            let text = match self.line {
                1 => text.strip_prefix('\u{feff}').unwrap_or(text),
                _ => text,
            };
            // A line ending in `\` continues on the next (a valid OBJ was refused as "a vertex
            // needs three numbers ... found \"0 \\\"").
            let content = text.split('#').next().unwrap_or("").trim_end();
            if let Some(head) = content.strip_suffix('\\') {
                self.continued.push_str(head);
                self.continued.push(' ');
                self.raw = raw;
                if self.continued.len() as u64 > MAX_LINE_BYTES {
                    return Err(self.parse_error(format!(
                        "a statement continued with `\\` runs past {MAX_LINE_BYTES} bytes"
                    )));
                }
                continue;
            }
            match self.continued.is_empty() {
                true => self.emit(text)?,
                false => {
                    let statement = std::mem::take(&mut self.continued) + text;
                    self.emit(&statement)?;
                }
            }
            self.raw = raw;
        }
        Ok(())
    }

    /// Checks one statement and queues its canonical line, if it has one.
    fn emit(&mut self, statement: &str) -> Result<()> {
        if let Some(canonical) = self.check_line(statement)? {
            self.out.extend_from_slice(canonical.as_bytes());
            self.out.push(b'\n');
        }
        Ok(())
    }

    /// The canonical line tobj should see, or `None` to drop the line.
    fn check_line(&mut self, text: &str) -> Result<Option<String>> {
        let text = text.split('#').next().unwrap_or("");
        let mut words = text.split_whitespace();
        let Some(keyword) = words.next() else {
            return Ok(None);
        };
        let values: Vec<&str> = words.collect();
        match keyword {
            "v" => self.vertex(&values).map(Some),
            "vn" => {
                let [x, y, z] = self.numbers(&values, "a normal needs three numbers: vn x y z")?;
                self.counts.normals += 1;
                // Zero or non-finite normals are kept: the builder regenerates those vertices.
                Ok(Some(format!("vn {x} {y} {z}")))
            }
            "vt" => {
                self.counts.texcoords += 1;
                Ok(None)
            }
            "f" => self.face(&values),
            "l" | "p" => {
                self.counts.points_or_lines += 1;
                Ok(None)
            }
            _ => Ok(None),
        }
    }

    fn numbers(&self, values: &[&str], usage: &str) -> Result<[f32; 3]> {
        let parse = |k: usize| values.get(k).and_then(|v| v.parse::<f32>().ok());
        match (parse(0), parse(1), parse(2)) {
            (Some(x), Some(y), Some(z)) => Ok([x, y, z]),
            _ => Err(self.parse_error(format!("{usage}; found {:?}", values.join(" ")))),
        }
    }

    /// `v x y z [w]` or `v x y z r g b`: the homogeneous w divides; colours are ignored.
    fn vertex(&mut self, values: &[&str]) -> Result<String> {
        let [x, y, z] = self.numbers(values, "a vertex needs three numbers: v x y z")?;
        let w = match values.len() {
            4 => values[3].parse::<f32>().map_err(|_| {
                self.parse_error(format!(
                    "the vertex weight w {:?} is not a number",
                    values[3]
                ))
            })?,
            _ => 1.0,
        };
        let p = [x / w, y / w, z / w];
        if !p.iter().all(|c| c.is_finite()) {
            return Err(self.parse_error(format!(
                "vertex {} = ({x}, {y}, {z}) / w {w} is not finite; every coordinate must be a finite number",
                self.counts.positions + 1
            )));
        }
        self.counts.positions += 1;
        if self.counts.positions > MAX_VERTICES {
            return Err(self.parse_error(format!(
                "more than {MAX_VERTICES} vertices, shikki's limit for one mesh; split or decimate it"
            )));
        }
        Ok(format!("v {} {} {}", p[0], p[1], p[2]))
    }

    /// `f a b c …` with corners `v`, `v/vt`, `v//vn` or `v/vt/vn`, 1-based or negative
    /// (relative to the elements defined so far), all referring to elements already defined.
    fn face(&mut self, corners: &[&str]) -> Result<Option<String>> {
        if corners.len() < 3 {
            if corners.is_empty() {
                return Err(self.parse_error("a face needs at least three vertices"));
            }
            self.counts.points_or_lines += 1;
            return Ok(None);
        }
        let mut canonical = String::from("f");
        let mut with_normal = 0;
        for corner in corners {
            let parts: Vec<&str> = corner.split('/').collect();
            if parts.len() > 3 || parts[0].is_empty() {
                return Err(self.parse_error(format!(
                    "face corner {corner:?} is not v, v/vt, v//vn or v/vt/vn"
                )));
            }
            let v = self.resolve(parts[0], self.counts.positions, "vertex")?;
            if let Some(vt) = parts.get(1).filter(|s| !s.is_empty()) {
                self.resolve(vt, self.counts.texcoords, "texture coordinate")?;
            }
            match parts.get(2).filter(|s| !s.is_empty()) {
                Some(vn) => {
                    let vn = self.resolve(vn, self.counts.normals, "normal")?;
                    canonical += &format!(" {v}//{vn}");
                    with_normal += 1;
                }
                None => canonical += &format!(" {v}"),
            }
        }
        self.counts.corners_with_normal += with_normal;
        self.counts.corners_without_normal += corners.len() - with_normal;
        self.counts.triangles += corners.len() - 2;
        if self.counts.triangles > MAX_TRIANGLES {
            return Err(self.parse_error(format!(
                "more than {MAX_TRIANGLES} triangles, shikki's limit for one mesh; split or decimate it"
            )));
        }
        Ok(Some(canonical))
    }

    /// The absolute 1-based index of an OBJ reference to one of `defined` elements.
    fn resolve(&self, text: &str, defined: usize, what: &str) -> Result<usize> {
        let index: i64 = text
            .parse()
            .map_err(|_| self.parse_error(format!("{what} index {text:?} is not an integer")))?;
        let defined_i64 = defined as i64;
        let absolute = if index < 0 {
            defined_i64 + 1 + index
        } else {
            index
        };
        if index == 0 || absolute < 1 || absolute > defined_i64 {
            return Err(self.parse_error(format!(
                "{what} index {index} is out of range: {defined} {what}(s) are defined before \
                 this line (indices are 1..={defined}, or -1..=-{defined} counting back)"
            )));
        }
        Ok(absolute as usize)
    }
}

impl<R: BufRead> Read for ObjFilter<'_, R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let available = self.fill_buf()?;
        let n = available.len().min(buf.len());
        buf[..n].copy_from_slice(&available[..n]);
        self.consume(n);
        Ok(n)
    }
}

impl<R: BufRead> BufRead for ObjFilter<'_, R> {
    fn fill_buf(&mut self) -> io::Result<&[u8]> {
        if self.error.is_some() {
            return Err(io::Error::other("the OBJ line filter stopped at an error"));
        }
        if self.out_pos >= self.out.len() {
            if let Err(e) = self.refill() {
                self.error = Some(e);
                return Err(io::Error::other("the OBJ line filter stopped at an error"));
            }
        }
        Ok(&self.out[self.out_pos..])
    }

    fn consume(&mut self, amount: usize) {
        self.out_pos = (self.out_pos + amount).min(self.out.len());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Loads `text` as an OBJ file written to a temporary directory.
    fn load_text(text: &str) -> Result<(Mesh, LoadReport)> {
        let dir = tempfile::tempdir().expect("a temporary directory");
        let path = dir.path().join("bom.obj");
        std::fs::write(&path, text).expect("the test file is written");
        load(&path)
    }

    #[test]
    fn leading_utf8_bom_keeps_the_first_vertex() {
        let (mesh, _) = load_text("\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
            .expect("an OBJ file with a BOM loads");
        assert_eq!(mesh.indices.len(), 3);
        let mut positions = mesh.positions.clone();
        positions.sort_by(|a, b| a.partial_cmp(b).expect("finite positions"));
        assert_eq!(
            positions,
            vec![[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]
        );
    }

    #[test]
    fn bom_on_a_later_line_is_not_a_keyword() {
        // Only the file's first bytes may be a BOM; elsewhere U+FEFF is content, so the vertex
        // it starts is not one and face index 3 is out of range.
        let error = load_text("v 0 0 0\nv 1 0 0\n\u{feff}v 0 1 0\nf 1 2 3\n")
            .expect_err("a BOM inside the file is not skipped")
            .to_string();
        assert!(error.contains("bom.obj:4: "), "{error}");
        assert!(error.contains("vertex index 3 is out of range"), "{error}");
    }

    #[test]
    fn a_trailing_backslash_continues_the_statement() {
        let joined = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\n";
        let continued = "v 0 \\\n 0 0\nv 1 0 0 \\\r\n\nv 0 1 0\nv 0 0 1\nf 1 2 \\\n3\nf 1 3 4 \\";
        let (a, _) = load_text(joined).expect("plain lines");
        let (b, _) = load_text(continued).expect("continued lines");
        assert_eq!((a.positions, a.indices), (b.positions, b.indices));
    }
}
