//! Where a batch's files go: the [`OutputSink`] seam between the writer thread and the disk.
//!
//! Every file a batch writes (images, contact sheet, the manifest's first write) goes through
//! [`write_file`]: a temporary file next to the target → the sink writes the bytes into it →
//! fsync → rename. On any error the temporary file is removed, no file is left at the target (the
//! stale-file policy of `output::atomic` applies) and the error names the file and the cause.
//! The manifest's later rows are appended through the same sink.
//!
//! The default sink, [`FileSystem`], simply writes the bytes. A library user (in practice a test)
//! may hand [`super::BatchOptions`] a sink that fails, e.g. with ENOSPC after N bytes, to check
//! that a full disk fails one job and not the batch. The sequence is
//! `output::atomic::write_atomically_with`'s, so [`remove_leftover_temps`] knows its temporary
//! names.

use std::collections::HashSet;
use std::fs::{self, File};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use crate::output::atomic::write_atomically_with;
use crate::Result;

/// Writes the bytes of one batch file into the temporary file that becomes the target.
pub trait OutputSink: Send + Sync + std::fmt::Debug {
    /// Writes all of `bytes` into `file`: the freshly created temporary file that is renamed to
    /// `target` once complete (an error leaves nothing at `target`), or the manifest `target`
    /// itself, open for appending rows (an error is cut back off it:
    /// [`super::manifest::ManifestWriter`]).
    fn write_bytes(&self, target: &Path, file: &mut File, bytes: &[u8]) -> io::Result<()> {
        let _ = target;
        file.write_all(bytes)
    }
}

/// The real file system: every byte is written.
#[derive(Clone, Copy, Debug, Default)]
pub struct FileSystem;

impl OutputSink for FileSystem {}

/// Writes `bytes` to `path` atomically through `sink` (see the module doc).
pub fn write_file(sink: &dyn OutputSink, path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomically_with(path, bytes, |file, bytes| {
        sink.write_bytes(path, file, bytes)
    })
}

/// Removes temporary files that a killed run (SIGKILL, a second Ctrl-C, a power cut) left next to
/// the files named in `names`; returns how many. Only this run's names are touched, so shards
/// writing into the same directory keep their own temporaries. `names` is read only if the
/// directory holds a temporary file at all: a run of a million jobs names two million files.
pub fn remove_leftover_temps(dir: &Path, names: impl IntoIterator<Item = String>) -> usize {
    let Ok(entries) = fs::read_dir(dir) else {
        return 0;
    };
    // `.<stem>.<pid>-<n>.tmp`: the stem may hold dots, the `<pid>-<n>` part has none.
    let temps: Vec<(PathBuf, String)> = entries
        .flatten()
        .filter(|entry| entry.file_type().is_ok_and(|t| t.is_file()))
        .filter_map(|entry| {
            let name = entry.file_name().to_string_lossy().into_owned();
            let stem = name
                .strip_prefix('.')
                .and_then(|rest| rest.strip_suffix(".tmp"))
                .and_then(|rest| rest.rsplit_once('.'))
                .map(|(stem, _)| stem.to_string())?;
            Some((entry.path(), stem))
        })
        .collect();
    if temps.is_empty() {
        return 0;
    }
    let mut stems: HashSet<&str> = temps.iter().map(|(_, stem)| stem.as_str()).collect();
    let mut ours = HashSet::new();
    for name in names {
        if stems.is_empty() {
            break;
        }
        if let Some(stem) = stems.take(temp_stem(&name).as_str()) {
            ours.insert(stem);
        }
    }
    temps
        .iter()
        .filter(|(_, stem)| ours.contains(stem.as_str()))
        .filter(|(path, _)| fs::remove_file(path).is_ok())
        .count()
}

/// Bounded so that a target name near the 255-byte limit still has a valid temporary name.
fn temp_stem(file_name: &str) -> String {
    file_name.chars().take(64).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    /// Writes `limit` bytes, then fails as a full disk does.
    #[derive(Debug)]
    struct FullAfter(usize);

    impl OutputSink for FullAfter {
        fn write_bytes(&self, _: &Path, file: &mut File, bytes: &[u8]) -> io::Result<()> {
            file.write_all(&bytes[..self.0.min(bytes.len())])?;
            file.sync_all()?;
            Err(io::Error::other("No space left on device"))
        }
    }

    #[test]
    fn a_failing_sink_leaves_neither_temp_nor_target_and_removes_a_stale_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.png");
        fs::write(&path, b"yesterday").unwrap();
        let message = write_file(&FullAfter(3), &path, b"0123456789")
            .unwrap_err()
            .to_string();
        assert!(message.contains("No space left"), "{message}");
        assert!(message.contains("was removed"), "{message}");
        assert!(entries(dir.path()).is_empty(), "{:?}", entries(dir.path()));
        write_file(&FileSystem, &path, b"today").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"today");
        assert_eq!(entries(dir.path()), vec!["out.png"]);
    }

    #[test]
    fn leftover_temps_of_this_runs_names_are_removed_others_kept() {
        let dir = tempfile::tempdir().unwrap();
        for name in [
            ".a.png.7-b0.tmp",
            ".a.png.8-3.tmp",
            ".b.png.7-b1.tmp",
            "a.png",
        ] {
            fs::write(dir.path().join(name), b"x").unwrap();
        }
        let removed = remove_leftover_temps(dir.path(), ["a.png".to_string()]);
        assert_eq!(removed, 2);
        assert_eq!(entries(dir.path()), vec![".b.png.7-b1.tmp", "a.png"]);
    }
}
