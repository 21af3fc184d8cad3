//! `manifest.csv`: one row per job (id, every swept value, output file, scene hash, status),
//! appended in job order as each job finishes, so a killed run leaves a manifest of what is
//! finished.
//!
//! Owns the CSV format, the journal that writes it ([`ManifestWriter`]) and the resume rule
//! ([`Finished`]); never renders.
//!
//! Why a journal and not a file rewritten after every job: a rewrite costs the whole file, so a
//! run of n jobs wrote O(n²) bytes and fsynced n times; past a few thousand jobs the writer fell
//! behind the renderer and the run slowed as it went (BENCHMARKS.md, "The batch at scale").
//! Appending costs one row; the file is fsynced at most every
//! [`MANIFEST_SYNC_INTERVAL`] and at the end. The first write of a run still replaces the previous
//! run's manifest atomically (temporary file, fsync, rename), so a run killed before its first job
//! finished leaves the old manifest whole.
//!
//! What a killed run leaves: every row appended before the kill (the kernel has them even if the
//! process dies; a power cut may lose the last [`MANIFEST_SYNC_INTERVAL`]), of which the last may
//! be cut short. A cut row never reads as finished: it has too few fields, or its status is a
//! prefix of `ok` or of `failed: …` (statuses are compared whole), so resume renders that job again.
//! A row is appended only after its image is in place, so an `ok` row always names a whole file.

use std::collections::HashSet;
use std::fs::{File, OpenOptions};
use std::io::{self, BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::sink::{write_file, OutputSink};
use crate::scene::doc::Value;
use crate::{Error, Result};

/// The status of a job that finished and wrote its output.
pub const STATUS_OK: &str = "ok";

/// How long appended rows may wait for an fsync: what a power cut (not a kill) can lose, and
/// what keeps a batch of fast jobs from spending its time in fsync (one per job was most of the
/// cost of a failing job).
pub const MANIFEST_SYNC_INTERVAL: Duration = Duration::from_secs(1);

/// One manifest row.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ManifestRow {
    pub job: usize,
    /// Swept values as text ([`value_text`]), in sweep order.
    pub values: Vec<String>,
    pub output: String,
    pub scene_hash: String,
    /// `ok`, `skipped` is never written (a skipped job keeps `ok`), or `failed: <message>`.
    pub status: String,
}

/// `manifest.csv` for a whole run, `manifest-shard-I-of-N.csv` for a shard: shards of one sweep
/// usually share an output directory, and each must own its file.
pub fn manifest_name(shard: (usize, usize)) -> String {
    match shard {
        (_, 1) => "manifest.csv".into(),
        (i, n) => format!("manifest-shard-{i}-of-{n}.csv"),
    }
}

/// A swept value as the manifest shows it. A number, boolean or string alone is its text as file
/// names use it ([`crate::scene::doc::Value::to_text`]: a string bare); inside an array or an
/// inline table every value is written as TOML writes it, so `[0.2, "x"]` stays `[0.2, "x"]`
/// and `["a, b"]` is not `["a", "b"]`.
pub fn value_text(value: &Value) -> String {
    match value {
        Value::Array(_) | Value::Table(_) => toml_text(value),
        scalar => scalar.to_text(),
    }
}

/// `value` in TOML syntax (a datetime, which sweeps cannot use, as `datetime`).
fn toml_text(value: &Value) -> String {
    match value {
        Value::Integer(i) => i.to_string(),
        // Debug keeps the point (`1.0`) and writes exponents TOML reads (`1e-7`).
        Value::Float(f) if f.is_nan() => "nan".into(),
        Value::Float(f) if f.is_infinite() => if *f > 0.0 { "inf" } else { "-inf" }.into(),
        Value::Float(f) => format!("{f:?}"),
        Value::Bool(b) => b.to_string(),
        Value::Str(s) => toml_string(s),
        Value::Array(items) => {
            let parts: Vec<String> = items.iter().map(|n| toml_text(&n.value)).collect();
            format!("[{}]", parts.join(", "))
        }
        Value::Table(entries) => {
            let parts: Vec<String> = entries
                .iter()
                .map(|e| format!("{} = {}", toml_key(&e.key), toml_text(&e.node.value)))
                .collect();
            format!("{{ {} }}", parts.join(", "))
        }
        Value::Datetime => "datetime".into(),
    }
}

/// A TOML basic string: quotes, backslashes and control characters escaped.
fn toml_string(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            '\r' => out.push_str("\\r"),
            c if c.is_control() => out.push_str(&format!("\\u{:04X}", u32::from(c))),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A bare key when TOML allows one, else a quoted key.
fn toml_key(key: &str) -> String {
    let bare = !key.is_empty()
        && key
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if bare {
        key.to_string()
    } else {
        toml_string(key)
    }
}

/// The header line: `job,<sweep paths…>,output,scene_hash,status`.
fn header_text(columns: &[String]) -> String {
    let mut out = String::from("job");
    for c in columns {
        out.push(',');
        out.push_str(&csv_field(c));
    }
    out.push_str(",output,scene_hash,status\n");
    out
}

/// One row as a CSV line.
fn row_text(row: &ManifestRow) -> String {
    let mut out = row.job.to_string();
    for v in &row.values {
        out.push(',');
        out.push_str(&csv_field(v));
    }
    for field in [&row.output, &row.scene_hash, &row.status] {
        out.push(',');
        out.push_str(&csv_field(field));
    }
    out.push('\n');
    out
}

/// Writes one run's (or shard's) manifest as a journal (see the module doc). Rows must come in
/// job order; a row that cannot be written (a full disk) waits and goes with the next one.
pub struct ManifestWriter {
    pub path: PathBuf,
    /// Open for appending once the first write replaced the previous manifest.
    file: Option<File>,
    /// Text not yet in the file: the header until the first write, then rows a failure held back.
    pending: Vec<u8>,
    /// Bytes in the file: where a failed append is cut back to.
    written: u64,
    last_sync: Instant,
    unsynced: bool,
    /// Why the file can no longer be appended to (a failed append could not be cut back).
    broken: Option<String>,
}

impl ManifestWriter {
    /// A manifest with a column per sweep path; nothing is written before the first row (or
    /// [`ManifestWriter::finish`]).
    pub fn new(path: PathBuf, sweep_paths: &[String]) -> Self {
        ManifestWriter {
            path,
            file: None,
            pending: header_text(sweep_paths).into_bytes(),
            written: 0,
            last_sync: Instant::now(),
            unsynced: false,
            broken: None,
        }
    }

    /// Appends `row` (and any row a failure held back); fsyncs if the last fsync is
    /// [`MANIFEST_SYNC_INTERVAL`] old. On error the rows are kept for the next call.
    pub fn append(&mut self, row: &ManifestRow, sink: &dyn OutputSink) -> Result<()> {
        self.pending.extend_from_slice(row_text(row).as_bytes());
        self.write_pending(sink)?;
        if self.unsynced && self.last_sync.elapsed() >= MANIFEST_SYNC_INTERVAL {
            self.sync()?;
        }
        Ok(())
    }

    /// Writes what is held back and fsyncs: after this the manifest is whole and durable.
    pub fn finish(&mut self, sink: &dyn OutputSink) -> Result<()> {
        self.write_pending(sink)?;
        if self.unsynced {
            self.sync()?;
        }
        Ok(())
    }

    fn write_pending(&mut self, sink: &dyn OutputSink) -> Result<()> {
        if let Some(why) = &self.broken {
            return Err(self.error(why.clone()));
        }
        let Some(file) = &mut self.file else {
            // The run's first write replaces the previous manifest whole; it stays in `pending`
            // until the file is open, so a failure to open it is retried by rewriting it.
            write_file(sink, &self.path, &self.pending)?;
            let file = OpenOptions::new()
                .append(true)
                .open(&self.path)
                .map_err(|e| self.error(format!("cannot open it to append rows ({e})")))?;
            self.written = self.pending.len() as u64;
            self.pending.clear();
            self.file = Some(file);
            self.last_sync = Instant::now();
            return Ok(());
        };
        if self.pending.is_empty() {
            return Ok(());
        }
        match sink.write_bytes(&self.path, file, &self.pending) {
            Ok(()) => {
                self.written += self.pending.len() as u64;
                self.pending.clear();
                self.unsynced = true;
                Ok(())
            }
            Err(e) => {
                // A partial row would run into the next one: cut it off.
                if let Err(cut) = file.set_len(self.written) {
                    self.broken = Some(format!(
                        "an append failed ({e}) and the partial row could not be cut off ({cut}); \
                         its rows before that are valid, later jobs render again when the same \
                         command is run again"
                    ));
                }
                Err(self.error(format!("appending a row failed ({e})")))
            }
        }
    }

    fn sync(&mut self) -> Result<()> {
        if let Some(file) = &self.file {
            file.sync_data()
                .map_err(|e| self.error(format!("fsync failed ({e})")))?;
        }
        self.unsynced = false;
        self.last_sync = Instant::now();
        Ok(())
    }

    fn error(&self, message: String) -> Error {
        Error::Write {
            path: self.path.clone(),
            message: format!("manifest: {message}"),
        }
    }
}

/// The jobs earlier runs finished: (id, scene hash) of every `ok` row of every `manifest*.csv` in
/// the output directory (this run's or any shard's). About 50 bytes a row (40 and the table's
/// own), where the rows themselves were hundreds: a resumed million-job run holds tens of
/// megabytes, not gigabytes.
#[derive(Debug, Default)]
pub struct Finished(HashSet<(usize, [u8; 32])>);

impl Finished {
    /// Reads the manifests in `dir`. Unreadable or foreign files and rows contribute nothing —
    /// the worst case is that a job renders again.
    pub fn read(dir: &Path) -> Self {
        let mut finished = HashSet::new();
        let Ok(entries) = std::fs::read_dir(dir) else {
            return Finished(finished);
        };
        for entry in entries.flatten() {
            let name = entry.file_name().to_string_lossy().to_string();
            if !(name.starts_with("manifest") && name.ends_with(".csv")) {
                continue;
            }
            if let Ok(file) = File::open(entry.path()) {
                // A read error part-way keeps the rows before it.
                let _ = each_row(BufReader::new(file), |row| {
                    if let Some(hash) = hash_bytes(&row.scene_hash) {
                        if row.status == STATUS_OK {
                            finished.insert((row.job, hash));
                        }
                    }
                });
            }
        }
        Finished(finished)
    }

    /// Whether job `id` may be skipped: a row finished it with this scene hash and its output is
    /// there.
    pub fn is_done(&self, id: usize, scene_hash: &str, output: &Path) -> bool {
        hash_bytes(scene_hash).is_some_and(|hash| self.0.contains(&(id, hash))) && output.is_file()
    }
}

/// A SHA-256 written as 64 hex digits; anything else is no hash this code wrote.
fn hash_bytes(hex: &str) -> Option<[u8; 32]> {
    let digits = hex.as_bytes();
    if digits.len() != 64 {
        return None;
    }
    let mut out = [0u8; 32];
    for (byte, pair) in out.iter_mut().zip(digits.chunks_exact(2)) {
        let text = std::str::from_utf8(pair).ok()?;
        *byte = u8::from_str_radix(text, 16).ok()?;
    }
    Some(out)
}

/// Parses a manifest's rows (the header gives the number of value columns).
pub fn parse_rows(text: &str) -> Vec<ManifestRow> {
    let mut rows = Vec::new();
    // Reading from memory cannot fail.
    let _ = each_row(text.as_bytes(), |row| rows.push(row));
    rows
}

/// Calls `each` with every well-formed row of the manifest `reader` reads, one at a time: a
/// manifest of a million rows is never held whole.
fn each_row(reader: impl BufRead, mut each: impl FnMut(ManifestRow)) -> io::Result<()> {
    let mut columns = None;
    each_record(reader, |fields| {
        let Some(columns) = columns else {
            columns = Some(fields.len());
            return;
        };
        if columns < 4 || fields.len() != columns {
            return;
        }
        let values = columns - 4;
        let Ok(job) = fields[0].parse() else { return };
        each(ManifestRow {
            job,
            values: fields[1..1 + values].to_vec(),
            output: fields[1 + values].clone(),
            scene_hash: fields[2 + values].clone(),
            status: fields[3 + values].clone(),
        });
    })
}

/// RFC 4180 quoting when needed.
fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// RFC 4180 records (quoted fields may hold commas, quotes and newlines), one at a time. The
/// delimiters are ASCII, so the bytes are split first and each field decoded as UTF-8 after.
fn each_record(mut reader: impl BufRead, mut each: impl FnMut(&[String])) -> io::Result<()> {
    let mut record: Vec<String> = Vec::new();
    let mut field: Vec<u8> = Vec::new();
    let mut quoted = false;
    // A quote inside a quoted field: the next byte says whether it was `""` or the closing one.
    let mut quote_pending = false;
    let take = |field: &mut Vec<u8>| String::from_utf8_lossy(&std::mem::take(field)).into_owned();
    loop {
        let chunk = reader.fill_buf()?;
        if chunk.is_empty() {
            break;
        }
        for &byte in chunk {
            if quote_pending {
                quote_pending = false;
                if byte == b'"' {
                    field.push(b'"');
                    continue;
                }
                quoted = false;
            }
            match (quoted, byte) {
                (true, b'"') => quote_pending = true,
                (true, b) => field.push(b),
                (false, b'"') => quoted = true,
                (false, b',') => record.push(take(&mut field)),
                (false, b'\n') => {
                    record.push(take(&mut field));
                    each(&record);
                    record.clear();
                }
                (false, b'\r') => {}
                (false, b) => field.push(b),
            }
        }
        let used = chunk.len();
        reader.consume(used);
    }
    if !field.is_empty() || !record.is_empty() {
        record.push(take(&mut field));
        each(&record);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(job: usize, status: &str) -> ManifestRow {
        ManifestRow {
            job,
            values: vec!["1.5".into(), "[0, 1, \"x\"]".into()],
            output: format!("out,{job}.png"),
            scene_hash: format!("{job:064x}"),
            status: status.into(),
        }
    }

    #[test]
    fn rows_round_trip_through_csv_with_quoting() {
        let row = row(3, "failed: line 1\nline 2");
        let text = header_text(&["a.b".into(), "c".into()]) + &row_text(&row);
        assert!(text.starts_with("job,a.b,c,output,scene_hash,status\n"));
        assert_eq!(parse_rows(&text), vec![row]);
    }

    #[test]
    fn shard_manifests_have_their_own_names() {
        assert_eq!(manifest_name((0, 1)), "manifest.csv");
        assert_eq!(manifest_name((1, 4)), "manifest-shard-1-of-4.csv");
    }

    /// Strings inside arrays and tables keep their quotes (they were dropped: `[0.2, 0.2, x]`);
    /// a value alone is written as file names write it.
    #[test]
    fn nested_values_are_written_as_toml() {
        let doc = crate::scene::doc::parse_document(
            "a = [0.2, 0.2, \"x\"]\nb = \"rough-red\"\nc = 2.0\n\
             d = [[1.0, -0.5e-7], { k = \"q\\\"\", \"odd key\" = true }]\n",
            "t.toml",
            Path::new("."),
        )
        .unwrap();
        let Value::Table(entries) = &doc.value else {
            unreachable!("the document is a table")
        };
        let texts: Vec<String> = entries.iter().map(|e| value_text(&e.node.value)).collect();
        assert_eq!(
            texts,
            [
                "[0.2, 0.2, \"x\"]",
                "rough-red",
                "2",
                "[[1.0, -5e-8], { k = \"q\\\"\", \"odd key\" = true }]"
            ]
        );
    }

    /// Every prefix of a manifest — what a kill can leave of the last row — reads as the rows
    /// before the cut plus, at most, the cut row whole (cut after its last byte but the newline):
    /// never as a finished row that was not written whole.
    #[test]
    fn a_cut_row_never_reads_as_finished() {
        let rows = [
            row(0, STATUS_OK),
            row(1, "failed: a\nb, \"c\""),
            row(2, STATUS_OK),
        ];
        let text =
            header_text(&["a".into(), "b".into()]) + &rows.iter().map(row_text).collect::<String>();
        for cut in 0..=text.len() {
            let parsed = parse_rows(&text[..cut]);
            for (k, r) in parsed.iter().enumerate() {
                assert_eq!(r.job, k, "cut at {cut}");
                let whole = &rows[k];
                if r.status == STATUS_OK {
                    assert_eq!(r, whole, "cut at {cut}: a cut row reads as finished");
                }
            }
        }
    }

    /// A failed append (a full disk that took part of the row) is cut back, held, and written
    /// with the next row: the file then holds every row whole, once.
    #[test]
    fn a_failed_append_is_cut_back_and_retried() {
        #[derive(Debug)]
        struct FullOnce(std::sync::atomic::AtomicUsize);
        impl OutputSink for FullOnce {
            fn write_bytes(&self, _: &Path, file: &mut File, bytes: &[u8]) -> io::Result<()> {
                use std::io::Write;
                let call = self.0.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                if call == 2 {
                    file.write_all(&bytes[..7])?;
                    return Err(io::Error::from_raw_os_error(28));
                }
                file.write_all(bytes)
            }
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("manifest.csv");
        std::fs::write(&path, "yesterday's manifest\n").unwrap();
        let sink = FullOnce(Default::default());
        let mut writer = ManifestWriter::new(path.clone(), &["a".into(), "b".into()]);
        let rows: Vec<ManifestRow> = (0..4).map(|k| row(k, STATUS_OK)).collect();
        // Call 0 writes the header and row 0 through a temporary file, 1 appends row 1, 2 fails.
        writer.append(&rows[0], &sink).unwrap();
        writer.append(&rows[1], &sink).unwrap();
        assert!(writer.append(&rows[2], &sink).is_err());
        writer.append(&rows[3], &sink).unwrap();
        writer.finish(&sink).unwrap();
        assert_eq!(parse_rows(&std::fs::read_to_string(&path).unwrap()), rows);

        let finished = Finished::read(dir.path());
        let output = dir.path().join("manifest.csv");
        assert!(finished.is_done(2, &rows[2].scene_hash, &output));
        assert!(!finished.is_done(2, &rows[1].scene_hash, &output));
        assert!(!finished.is_done(2, &rows[2].scene_hash, &dir.path().join("missing.png")));
    }
}
