//! Shared by the corpus tests (`environment::corpus`, `raster::mesh_io::corpus`,
//! `scene::corpus`): running the CLI on a bad input and checking it failed cleanly, and matching
//! the exact `shikki::Error` kind. The cases are listed in `corpus.md` beside this file.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use shikki::Error;

/// Runs the `shikki` binary in `dir` (validation on, no pipeline cache in the home directory).
pub fn shikki(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_shikki"))
        .args(args)
        .current_dir(dir)
        .env("SHIKKI_VALIDATION", "1")
        .env("SHIKKI_PIPELINE_CACHE", "0")
        .output()
        .expect("the shikki binary runs")
}

/// Runs `shikki` under `ulimit -v` (address space in KiB): an allocation from an untrusted size
/// that was not checked first would abort the process instead of giving the expected error.
pub fn shikki_limited(dir: &Path, args: &[&str], address_space_kib: u64) -> Output {
    let mut script = format!("ulimit -v {address_space_kib} && exec \"$0\"");
    for k in 0..args.len() {
        script.push_str(&format!(" \"${}\"", k + 1));
    }
    Command::new("sh")
        .arg("-c")
        .arg(script)
        .arg(env!("CARGO_BIN_EXE_shikki"))
        .args(args)
        .current_dir(dir)
        .env("SHIKKI_VALIDATION", "1")
        .env("SHIKKI_PIPELINE_CACHE", "0")
        .output()
        .expect("sh runs")
}

/// A fresh working directory with an empty `out/` for the command's outputs.
pub struct Workspace {
    pub dir: tempfile::TempDir,
}

impl Workspace {
    pub fn new() -> Self {
        let dir = tempfile::tempdir().expect("temp dir");
        std::fs::create_dir(dir.path().join("out")).expect("out/");
        Workspace { dir }
    }

    pub fn path(&self) -> &Path {
        self.dir.path()
    }

    /// Writes `bytes` to `name` in the workspace and returns its absolute path.
    pub fn file(&self, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
        let path = self.dir.path().join(name);
        std::fs::write(&path, bytes).expect("write corpus file");
        path
    }

    /// The files the command left in `out/` (outputs and temporaries alike).
    pub fn outputs(&self) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(self.dir.path().join("out"))
            .expect("out/")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }
}

/// The CLI failed as a user should see it: exit code 1 (an error; 101 would be a panic, `None` a
/// signal such as an abort on a failed allocation), stderr names every fragment (case-insensitive)
/// and nothing — neither output nor temporary file — was left in `out/`.
pub fn assert_cli_fails(ws: &Workspace, args: &[&str], fragments: &[&str]) -> String {
    let out = shikki(ws.path(), args);
    check_failure(ws, args, &out, fragments)
}

/// [`assert_cli_fails`] for an output that was already captured.
pub fn check_failure(ws: &Workspace, args: &[&str], out: &Output, fragments: &[&str]) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(
        out.status.code(),
        Some(1),
        "{args:?}: expected exit code 1 (an error), got {:?}:\n{stderr}",
        out.status
    );
    assert!(!stderr.contains("panicked"), "{args:?} panicked:\n{stderr}");
    for fragment in fragments {
        assert!(
            stderr.to_lowercase().contains(&fragment.to_lowercase()),
            "{args:?}: stderr lacks {fragment:?}:\n{stderr}"
        );
    }
    assert_eq!(
        ws.outputs(),
        Vec::<String>::new(),
        "{args:?} left files in out/"
    );
    stderr
}

/// Runs `f` and fails if it takes longer than `limit`: the loaders answer a hostile header from
/// the header alone. The bound is two orders of magnitude above the expected time, so it only
/// catches a loader that reads, allocates or loops according to the claimed size (a hang), never
/// a slow machine.
pub fn quickly<T>(what: &str, limit: Duration, f: impl FnOnce() -> T) -> T {
    let start = Instant::now();
    let value = f();
    let elapsed = start.elapsed();
    assert!(
        elapsed < limit,
        "{what} took {elapsed:?}: the loader must refuse the claimed size before reading it"
    );
    value
}

/// The error is `Error::Parse` for a file whose name contains `file`, at `line`; returns the
/// message.
pub fn expect_parse<T: std::fmt::Debug>(
    result: shikki::Result<T>,
    file: &str,
    line: usize,
) -> String {
    match result {
        Err(Error::Parse {
            file: f,
            line: l,
            message,
        }) => {
            assert!(f.contains(file), "error names {f:?}, expected {file:?}");
            assert_eq!(l, line, "wrong line in {f}:{l}: {message}");
            assert!(!message.trim().is_empty());
            message
        }
        other => panic!("expected Error::Parse at {file}:{line}, got {other:?}"),
    }
}

/// The error is `Error::InvalidParameter` with this `field`; returns the whole message.
pub fn expect_invalid<T: std::fmt::Debug>(result: shikki::Result<T>, field: &str) -> String {
    match result {
        Err(e @ Error::InvalidParameter { .. }) => {
            let Error::InvalidParameter {
                field: f, reason, ..
            } = &e
            else {
                unreachable!()
            };
            assert_eq!(f, field, "{e}");
            assert!(!reason.trim().is_empty(), "{e}");
            e.to_string()
        }
        other => panic!("expected Error::InvalidParameter {{ field: {field:?} }}, got {other:?}"),
    }
}

/// The error is `Error::Read` of `path`; returns the whole message (the cause included).
pub fn expect_read<T: std::fmt::Debug>(result: shikki::Result<T>, path: &Path) -> String {
    match result {
        Err(e @ Error::Read { .. }) => {
            let Error::Read { path: p, source } = &e else {
                unreachable!()
            };
            assert_eq!(p, path, "{e}");
            format!("{e}: {source}")
        }
        other => panic!("expected Error::Read of {}, got {other:?}", path.display()),
    }
}

/// Asserts `message` contains every fragment (case-insensitive): what is wrong, where, the fix.
pub fn assert_names(message: &str, fragments: &[&str]) {
    for fragment in fragments {
        assert!(
            message.to_lowercase().contains(&fragment.to_lowercase()),
            "message lacks {fragment:?}: {message}"
        );
    }
}

/// A sparse file of `len` bytes (no disk blocks): a "terabyte" input that costs nothing.
pub fn sparse_file(path: &Path, head: &[u8], len: u64) {
    let file = std::fs::File::create(path).expect("create sparse file");
    std::io::Write::write_all(&mut &file, head).expect("head");
    file.set_len(len).expect("set_len");
}
