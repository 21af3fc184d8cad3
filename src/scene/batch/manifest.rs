//! `manifest.csv`: one row per job (id, every swept value, output file, scene hash, status),
//! rewritten atomically after every job so a killed run leaves a manifest of what is finished.
//!
//! Owns the CSV format and the resume rule; never renders.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::sink::{write_file, OutputSink};
use crate::Result;

/// The status of a job that finished and wrote its output.
pub const STATUS_OK: &str = "ok";

/// One manifest row.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ManifestRow {
    pub job: usize,
    /// Swept values as text, in sweep order.
    pub values: Vec<String>,
    pub output: String,
    pub scene_hash: String,
    /// `ok`, `skipped` is never written (a skipped job keeps `ok`), or `failed: <message>`.
    pub status: String,
}

/// The manifest of one run (or shard): rows by job id.
#[derive(Clone, Debug)]
pub struct Manifest {
    pub path: PathBuf,
    pub columns: Vec<String>,
    pub rows: BTreeMap<usize, ManifestRow>,
}

/// `manifest.csv` for a whole run, `manifest-shard-I-of-N.csv` for a shard: shards of one sweep
/// usually share an output directory, and each must own its file.
pub fn manifest_name(shard: (usize, usize)) -> String {
    match shard {
        (_, 1) => "manifest.csv".into(),
        (i, n) => format!("manifest-shard-{i}-of-{n}.csv"),
    }
}

impl Manifest {
    /// An empty manifest with a column per sweep path.
    pub fn new(path: PathBuf, sweep_paths: &[String]) -> Self {
        Manifest {
            path,
            columns: sweep_paths.to_vec(),
            rows: BTreeMap::new(),
        }
    }

    /// The text: header `job,<sweep paths…>,output,scene_hash,status`, rows by id.
    pub fn to_csv(&self) -> String {
        let mut out = String::from("job");
        for c in &self.columns {
            out.push(',');
            out.push_str(&csv_field(c));
        }
        out.push_str(",output,scene_hash,status\n");
        for row in self.rows.values() {
            out.push_str(&row.job.to_string());
            for v in &row.values {
                out.push(',');
                out.push_str(&csv_field(v));
            }
            out.push_str(&format!(
                ",{},{},{}\n",
                csv_field(&row.output),
                csv_field(&row.scene_hash),
                csv_field(&row.status)
            ));
        }
        out
    }

    /// Writes the CSV atomically through `sink` ([`super::sink`]).
    pub fn save(&self, sink: &dyn OutputSink) -> Result<()> {
        write_file(sink, &self.path, self.to_csv().as_bytes())
    }
}

/// Rows of every `manifest*.csv` in `dir` (a run, or any shard of it), by job id: what a resumed
/// run compares against. Unreadable or foreign files contribute nothing — the worst case is that a
/// job renders again.
pub fn previous_rows(dir: &Path) -> BTreeMap<usize, ManifestRow> {
    let mut rows = BTreeMap::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return rows;
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().to_string();
        if !(name.starts_with("manifest") && name.ends_with(".csv")) {
            continue;
        }
        if let Ok(text) = std::fs::read_to_string(entry.path()) {
            for row in parse_rows(&text) {
                rows.insert(row.job, row);
            }
        }
    }
    rows
}

/// Parses a manifest's rows (the header gives the number of value columns).
pub fn parse_rows(text: &str) -> Vec<ManifestRow> {
    let mut lines = split_records(text).into_iter();
    let Some(header) = lines.next() else {
        return Vec::new();
    };
    let values = header.len().saturating_sub(4);
    lines
        .filter(|fields| fields.len() == values + 4)
        .filter_map(|fields| {
            Some(ManifestRow {
                job: fields[0].parse().ok()?,
                values: fields[1..1 + values].to_vec(),
                output: fields[1 + values].clone(),
                scene_hash: fields[2 + values].clone(),
                status: fields[3 + values].clone(),
            })
        })
        .collect()
}

/// Whether a job may be skipped: its previous row finished with this hash and its output is there.
pub fn is_done(previous: Option<&ManifestRow>, scene_hash: &str, output: &Path) -> bool {
    previous.is_some_and(|row| row.status == STATUS_OK && row.scene_hash == scene_hash)
        && output.is_file()
}

/// RFC 4180 quoting when needed.
fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// RFC 4180 records (quoted fields may hold commas, quotes and newlines).
fn split_records(text: &str) -> Vec<Vec<String>> {
    let mut records = Vec::new();
    let mut record = Vec::new();
    let mut field = String::new();
    let mut quoted = false;
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                field.push('"');
                chars.next();
            }
            (true, '"') => quoted = false,
            (true, c) => field.push(c),
            (false, '"') => quoted = true,
            (false, ',') => record.push(std::mem::take(&mut field)),
            (false, '\n') => {
                record.push(std::mem::take(&mut field));
                records.push(std::mem::take(&mut record));
            }
            (false, '\r') => {}
            (false, c) => field.push(c),
        }
    }
    if !field.is_empty() || !record.is_empty() {
        record.push(field);
        records.push(record);
    }
    records
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_round_trip_through_csv_with_quoting() {
        let mut m = Manifest::new("m.csv".into(), &["a.b".into(), "c".into()]);
        let row = ManifestRow {
            job: 3,
            values: vec!["1.5".into(), "[0, 1, \"x\"]".into()],
            output: "out,3.png".into(),
            scene_hash: "abc".into(),
            status: "failed: line 1\nline 2".into(),
        };
        m.rows.insert(3, row.clone());
        let text = m.to_csv();
        assert!(text.starts_with("job,a.b,c,output,scene_hash,status\n"));
        assert_eq!(parse_rows(&text), vec![row]);
    }

    #[test]
    fn shard_manifests_have_their_own_names() {
        assert_eq!(manifest_name((0, 1)), "manifest.csv");
        assert_eq!(manifest_name((1, 4)), "manifest-shard-1-of-4.csv");
    }
}
