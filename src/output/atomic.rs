//! Atomic file replacement: a run either leaves its complete output at the path or nothing at
//! all — never a partial file, a leftover temporary, or the previous run's file posing as this
//! run's. Owns the temporary-file naming, the write → fsync → rename sequence and the stale-file
//! policy; it knows nothing about image formats.
//!
//! Stale-file policy: when this run fails to write `path`, a file already at `path` (from an
//! earlier run) is removed and the error says so. A batch user re-running a scene must not find
//! yesterday's image and take it for today's (the same reasoning as make's `.DELETE_ON_ERROR`).
//! A directory at `path` is never removed.

use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::{Error, Result};

/// Writes bytes to `path` through a temporary file in the same directory + fsync + rename, so a
/// failed run never leaves a partial or stale file; the temp file is removed on any error.
///
/// On failure, a pre-existing file at `path` is removed too (see the module doc) and the error
/// message says whether that happened.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomically_with(path, bytes, |file, bytes| file.write_all(bytes))
}

/// [`write_atomically`] with the step that puts the bytes into the temporary file supplied by the
/// caller (the batch's output sink, which tests replace with one that fails like a full disk).
pub(crate) fn write_atomically_with(
    path: &Path,
    bytes: &[u8],
    write: impl FnOnce(&mut File, &[u8]) -> io::Result<()>,
) -> Result<()> {
    replace_via_temp(path, bytes, write).map_err(|cause| failed_write(path, &cause))
}

/// Removes a previous run's file at `path` so it cannot be mistaken for the output of a run that
/// failed. Returns whether a file was removed. Only a regular file is removed: a directory, a
/// symbolic link, a device (`-o /dev/null` removed the device node) or a pipe is left alone and
/// reported as `false`; a missing file is not an error.
///
/// The CLI calls this when a run fails before reaching [`write_atomically`] (e.g. a GPU error
/// after [`preflight_output`](super::preflight_output)).
pub fn discard_stale_output(path: &Path) -> io::Result<bool> {
    match fs::symlink_metadata(path) {
        Ok(meta) if meta.file_type().is_file() => fs::remove_file(path).map(|()| true),
        Ok(_) => Ok(false),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(false),
        Err(e) => Err(e),
    }
}

/// Builds the [`Error::Write`] for a failed write of `path`, applying the stale-file policy and
/// saying in the message what became of any previous file.
pub(crate) fn failed_write(path: &Path, cause: &str) -> Error {
    Error::Write {
        path: path.to_path_buf(),
        message: format!("{cause}; nothing was written{}", discard_stale_saying(path)),
    }
}

/// [`discard_stale_output`] for a failed run's message: what became of a previous file at
/// `path`, as a clause to append ("; the previous … was removed …"), or "" where there was none.
pub fn discard_stale_saying(path: &Path) -> String {
    match discard_stale_output(path) {
        Ok(true) => format!(
            "; the previous {} was removed so it cannot be mistaken for this run's output",
            path.display()
        ),
        Ok(false) => String::new(),
        Err(e) => format!(
            "; WARNING: the previous {} could not be removed ({e}) and is NOT this run's output",
            path.display()
        ),
    }
}

/// Checks that a file can be created in `path`'s directory by creating and deleting a temporary
/// file there. The message names the directory and the fix.
pub(crate) fn probe_directory(path: &Path) -> std::result::Result<(), String> {
    let file_name = file_name_of(path)?;
    if path.is_dir() {
        return Err(is_a_directory(path));
    }
    // Checked here, before the work: the temporary file's name is bounded, so a name over the
    // limit passed the probe and failed only at the rename, after the render.
    let length = file_name.as_encoded_bytes().len();
    if length > MAX_FILE_NAME_BYTES {
        return Err(format!(
            "the file name of {} is {length} bytes; file systems take at most \
             {MAX_FILE_NAME_BYTES}: choose a shorter name",
            path.display()
        ));
    }
    if let Ok(meta) = fs::symlink_metadata(path) {
        let kind = meta.file_type();
        if !(kind.is_file() || kind.is_symlink()) {
            return Err(format!(
                "{} exists and is not a regular file (a device, pipe or socket); the image \
                 would replace it: choose a file path",
                path.display()
            ));
        }
    }
    TempFile::create_in(directory_of(path), file_name).map(drop)
}

/// The longest file name (one path component) Linux's file systems and most others take.
const MAX_FILE_NAME_BYTES: usize = 255;

/// The write → fsync → rename sequence. Any early return drops the [`TempFile`], deleting it.
fn replace_via_temp(
    path: &Path,
    bytes: &[u8],
    write: impl FnOnce(&mut File, &[u8]) -> io::Result<()>,
) -> std::result::Result<(), String> {
    let file_name = file_name_of(path)?;
    let directory = directory_of(path);
    let mut temp = TempFile::create_in(directory, file_name)?;
    let temp_name = temp.path.display().to_string();
    let describe =
        |what: &str, e: io::Error| format!("{what} the temporary file {temp_name} failed ({e})");
    write(&mut temp.file, bytes).map_err(|e| describe("writing", e))?;
    // fsync before rename: otherwise a crash can leave the new name pointing at an empty file.
    temp.file.sync_all().map_err(|e| describe("syncing", e))?;
    fs::rename(&temp.path, path).map_err(|e| {
        if path.is_dir() {
            is_a_directory(path)
        } else {
            format!(
                "renaming the temporary file to {} failed ({e})",
                path.display()
            )
        }
    })?;
    temp.persisted = true;
    sync_directory(directory);
    Ok(())
}

/// Makes the rename itself durable. Best effort: the new file is already complete and in place,
/// and some platforms and file systems cannot open or sync a directory at all.
#[cfg(unix)]
fn sync_directory(directory: &Path) {
    if let Ok(dir) = File::open(directory) {
        let _ = dir.sync_all();
    }
}

#[cfg(not(unix))]
fn sync_directory(_directory: &Path) {}

fn file_name_of(path: &Path) -> std::result::Result<&std::ffi::OsStr, String> {
    path.file_name().ok_or_else(|| {
        format!(
            "{} has no file name; give a file such as renders/bowl.png",
            path.display()
        )
    })
}

/// The directory a relative bare file name lives in is the current one.
fn directory_of(path: &Path) -> &Path {
    match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    }
}

fn is_a_directory(path: &Path) -> String {
    format!(
        "{} is a directory; give a file name inside it, such as {}",
        path.display(),
        path.join("render.png").display()
    )
}

/// A temporary file next to the target; deleted on drop unless `persisted` (renamed away).
struct TempFile {
    path: PathBuf,
    file: File,
    persisted: bool,
}

impl TempFile {
    /// Creates `.<name>.<pid>-<n>.tmp` in `directory` with `create_new`, so two runs (or two
    /// threads) writing the same output never share a temporary file.
    fn create_in(
        directory: &Path,
        file_name: &std::ffi::OsStr,
    ) -> std::result::Result<Self, String> {
        static COUNTER: AtomicU64 = AtomicU64::new(0);
        // Bounded so that a target name near the 255-byte limit still has a valid temp name.
        let stem: String = file_name.to_string_lossy().chars().take(64).collect();
        loop {
            let n = COUNTER.fetch_add(1, Ordering::Relaxed);
            let path = directory.join(format!(".{stem}.{}-{n}.tmp", std::process::id()));
            match OpenOptions::new().write(true).create_new(true).open(&path) {
                Ok(file) => {
                    return Ok(TempFile {
                        path,
                        file,
                        persisted: false,
                    })
                }
                // Left behind by a killed process with our pid and counter: try the next name.
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(describe_create_error(directory, e)),
            }
        }
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if !self.persisted {
            // Nothing more can be done if this fails; the error already being returned is the
            // one the user needs.
            let _ = fs::remove_file(&self.path);
        }
    }
}

/// Explains why no file can be created in `directory`, with the fix.
fn describe_create_error(directory: &Path, e: io::Error) -> String {
    let shown = directory.display();
    if !directory.exists() {
        format!("the directory {shown} does not exist; create it first (mkdir -p {shown}) or choose another output path")
    } else if !directory.is_dir() {
        format!("{shown} is not a directory, so no file can be created inside it; choose another output path")
    } else if e.kind() == io::ErrorKind::PermissionDenied {
        format!("no permission to create files in the directory {shown} ({e}); make it writable or choose another output path")
    } else {
        format!("cannot create a file in the directory {shown} ({e}); choose another output path")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh empty directory for one test, removed when the test ends.
    struct Scratch(PathBuf);

    impl std::ops::Deref for Scratch {
        type Target = Path;
        fn deref(&self) -> &Path {
            &self.0
        }
    }

    impl Drop for Scratch {
        fn drop(&mut self) {
            let _ = fs::remove_dir_all(&self.0);
        }
    }

    fn scratch_dir(name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!(
            "shikki-output-atomic-{}-{name}",
            std::process::id()
        ));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn write_creates_and_replaces_the_file_leaving_no_temp() {
        let dir = scratch_dir("replace");
        let path = dir.join("out.png");
        write_atomically(&path, b"first").unwrap();
        write_atomically(&path, b"second").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"second");
        assert_eq!(entries(&dir), vec!["out.png"]);
    }

    #[test]
    fn write_into_a_missing_directory_fails_clearly_and_leaves_nothing() {
        let dir = scratch_dir("missing");
        let path = dir.join("no-such-dir").join("out.exr");
        let message = write_atomically(&path, b"data").unwrap_err().to_string();
        assert!(message.contains("does not exist"), "{message}");
        assert!(message.contains("mkdir -p"), "{message}");
        assert!(message.contains("out.exr"), "{message}");
        assert!(entries(&dir).is_empty());
    }

    #[test]
    fn write_below_a_regular_file_fails_clearly_and_leaves_nothing() {
        let dir = scratch_dir("below-file");
        fs::write(dir.join("plain"), b"x").unwrap();
        let path = dir.join("plain").join("out.png");
        let message = write_atomically(&path, b"data").unwrap_err().to_string();
        assert!(message.contains("is not a directory"), "{message}");
        assert_eq!(entries(&dir), vec!["plain"]);
    }

    #[test]
    fn failure_after_the_temp_file_was_written_removes_it() {
        // A non-empty directory at the target makes the final rename fail (EISDIR/ENOTEMPTY),
        // i.e. after the temporary file was created, filled and synced.
        let dir = scratch_dir("late-failure");
        let target = dir.join("out.png");
        fs::create_dir(&target).unwrap();
        fs::write(target.join("keep"), b"k").unwrap();
        let message = write_atomically(&target, b"data").unwrap_err().to_string();
        assert!(message.contains("is a directory"), "{message}");
        assert_eq!(entries(&dir), vec!["out.png"]);
        assert_eq!(
            entries(&target),
            vec!["keep"],
            "a directory is never removed"
        );
    }

    #[test]
    fn dropping_an_unpersisted_temp_file_deletes_it() {
        let dir = scratch_dir("temp-drop");
        let temp = TempFile::create_in(&dir, "x.png".as_ref()).unwrap();
        let temp_path = temp.path.clone();
        assert!(temp_path.exists());
        assert!(temp_path
            .file_name()
            .unwrap()
            .to_string_lossy()
            .starts_with(".x.png."));
        drop(temp);
        assert!(!temp_path.exists());
    }

    #[cfg(unix)]
    #[test]
    fn unwritable_directory_fails_clearly_and_leaves_nothing() {
        use std::os::unix::fs::PermissionsExt;
        let dir = scratch_dir("read-only");
        let locked = dir.join("locked");
        fs::create_dir(&locked).unwrap();
        fs::set_permissions(&locked, fs::Permissions::from_mode(0o555)).unwrap();
        // Root (as in many containers) ignores directory permissions; the check is then
        // meaningless, so the test only asserts where the lock actually holds.
        let privileged = File::create(locked.join("probe")).is_ok();
        if !privileged {
            fs::set_permissions(&locked, fs::Permissions::from_mode(0o755)).unwrap();
            fs::write(locked.join("out.png"), b"old").unwrap();
            fs::set_permissions(&locked, fs::Permissions::from_mode(0o555)).unwrap();
            let message = write_atomically(&locked.join("out.png"), b"new")
                .unwrap_err()
                .to_string();
            assert!(message.contains("no permission"), "{message}");
            // The old file cannot be removed from a read-only directory either: the message must
            // say it is not this run's output.
            assert!(message.contains("NOT this run's output"), "{message}");
            assert_eq!(entries(&locked), vec!["out.png"]);
        }
        fs::set_permissions(&locked, fs::Permissions::from_mode(0o755)).unwrap();
    }

    #[test]
    fn failed_write_removes_a_previous_file_and_says_so() {
        let dir = scratch_dir("stale");
        let path = dir.join("out.png");
        fs::write(&path, b"yesterday").unwrap();
        let message = failed_write(&path, "the render failed").to_string();
        assert!(message.contains("the render failed"), "{message}");
        assert!(message.contains("previous"), "{message}");
        assert!(message.contains("was removed"), "{message}");
        assert!(!path.exists());
        // With nothing there, the message does not claim a removal.
        let message = failed_write(&path, "again").to_string();
        assert!(!message.contains("removed"), "{message}");
    }

    #[test]
    fn discard_leaves_directories_and_missing_paths_alone() {
        let dir = scratch_dir("discard");
        assert!(!discard_stale_output(&dir.join("absent")).unwrap());
        fs::create_dir(dir.join("sub")).unwrap();
        assert!(!discard_stale_output(&dir.join("sub")).unwrap());
        assert!(dir.join("sub").is_dir());
    }

    #[test]
    fn probe_creates_nothing_that_survives() {
        let dir = scratch_dir("probe");
        probe_directory(&dir.join("out.exr")).unwrap();
        assert!(entries(&dir).is_empty());
        let message = probe_directory(&dir).unwrap_err();
        assert!(message.contains("is a directory"), "{message}");
    }

    #[test]
    fn a_long_file_name_still_gets_a_valid_temp_name() {
        // 250 bytes is a legal name on common file systems (limit 255); the temp name must not
        // exceed the limit by prefixing and suffixing it.
        let dir = scratch_dir("long-name");
        let path = dir.join(format!("{}.png", "a".repeat(246)));
        write_atomically(&path, b"data").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"data");
    }

    /// Only a regular file is ever removed as stale: `-o /dev/null` removed the device node
    /// (a probe, 2026-12-06). A link is left too (its target is not this run's to judge).
    #[cfg(unix)]
    #[test]
    fn only_a_regular_file_is_removed_as_stale() {
        let dir = scratch_dir("stale-kinds");
        let target = dir.join("target.png");
        fs::write(&target, b"keep").unwrap();
        let link = dir.join("link.png");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        assert!(!discard_stale_output(&link).unwrap());
        assert!(fs::symlink_metadata(&link).is_ok());
        assert!(!discard_stale_output(Path::new("/dev/null")).unwrap());
        assert!(Path::new("/dev/null").exists());
        assert!(discard_stale_output(&target).unwrap());
        assert!(!target.exists());
    }

    /// A name over 255 bytes, or a device at the path, is refused before any work; the name
    /// was refused only at the rename, after the render, with a false warning.
    #[test]
    fn the_probe_refuses_long_names_and_devices() {
        let dir = scratch_dir("probe-refuses");
        let long = dir.join(format!("{}.png", "x".repeat(252)));
        let message = probe_directory(&long).unwrap_err();
        assert!(
            message.contains("256 bytes") && message.contains("255"),
            "{message}"
        );
        probe_directory(&dir.join(format!("{}.png", "x".repeat(251)))).unwrap();
        #[cfg(unix)]
        {
            let message = probe_directory(Path::new("/dev/null")).unwrap_err();
            assert!(message.contains("not a regular file"), "{message}");
        }
    }
}
