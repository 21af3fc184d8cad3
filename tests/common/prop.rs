//! Shared by the property tests (`environment::properties`, `raster::mesh_io::properties`,
//! `scene::properties`): the case budget, the "well-formed error" property, a watchdog against
//! hangs and byte mutations of valid files.
#![allow(dead_code)]

use std::sync::mpsc;
use std::time::Duration;

use proptest::prelude::*;
use proptest::test_runner::Config;

/// Cases per property: `default` (sized so that every property test together stays well under
/// 90 s in the dev profile), or `SHIKKI_PROPTEST_CASES` for a longer run.
pub fn config(default: u32) -> Config {
    let cases = std::env::var("SHIKKI_PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default);
    Config {
        cases,
        // Regressions are kept as explicit tests (tests/*/corpus.rs), not proptest-regressions/
        // files, so nothing is written into the source tree.
        failure_persistence: None,
        ..Config::default()
    }
}

/// [`config`] for a property whose cases are expensive (a 35 MB MERL file each): `default`, or
/// `SHIKKI_PROPTEST_CASES` / 20.
pub fn heavy_config(default: u32) -> Config {
    let mut config = config(default);
    if std::env::var("SHIKKI_PROPTEST_CASES").is_ok() {
        config.cases = (config.cases / 20).max(1);
    }
    config
}

/// How long one parse may take before it counts as a hang: inputs are at most a few KiB (or one
/// MERL file), parsed in micro- to milliseconds, so 20 s is orders of magnitude above normal and
/// only an infinite loop or a size-driven blow-up reaches it.
pub const HANG: Duration = Duration::from_secs(20);

/// Runs `f` on a thread and waits at most [`HANG`]; a panic inside is reported as a panic here
/// (so proptest shrinks it), a timeout as a hang.
pub fn within<T: Send + 'static>(what: &str, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (send, receive) = mpsc::channel();
    let handle = std::thread::spawn(move || {
        let _ = send.send(f());
    });
    match receive.recv_timeout(HANG) {
        Ok(value) => {
            let _ = handle.join();
            value
        }
        Err(mpsc::RecvTimeoutError::Disconnected) => {
            let panic = handle.join().err();
            let text = panic
                .as_ref()
                .and_then(|p| {
                    p.downcast_ref::<String>()
                        .cloned()
                        .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                })
                .unwrap_or_default();
            panic!("{what} panicked: {text}")
        }
        Err(mpsc::RecvTimeoutError::Timeout) => panic!("{what} did not return within {HANG:?}"),
    }
}

/// The property every parser must have: Ok, or an error whose message is non-empty, and for a
/// parse error a file name and a 1-based line.
pub fn well_formed<T>(result: &shikki::Result<T>) -> Result<(), TestCaseError> {
    if let Err(e) = result {
        let message = e.to_string();
        prop_assert!(!message.trim().is_empty(), "empty error message: {e:?}");
        if let shikki::Error::Parse {
            file,
            line,
            message,
        } = e
        {
            prop_assert!(!file.is_empty(), "parse error without a file: {e:?}");
            prop_assert!(*line >= 1, "parse error at line 0: {e:?}");
            prop_assert!(
                !message.trim().is_empty(),
                "parse error without a message: {e:?}"
            );
        }
        if let shikki::Error::InvalidParameter { field, reason, .. } = e {
            prop_assert!(!field.is_empty() && !reason.trim().is_empty(), "{e:?}");
        }
    }
    Ok(())
}

/// One edit of a byte string.
#[derive(Clone, Debug)]
pub enum Mutation {
    /// Keep the first `fraction` of the bytes.
    Truncate(f64),
    /// XOR the byte at `fraction` of the length with a non-zero mask.
    Flip(f64, u8),
    /// Overwrite the byte at `fraction` with `value` (interesting bytes for text formats).
    Set(f64, u8),
    /// Insert `bytes` at `fraction`.
    Insert(f64, Vec<u8>),
    /// Remove `len` bytes at `fraction`.
    Remove(f64, usize),
    /// Copy `len` bytes from `from` to `to` (fractions): splices the file into itself.
    Splice(f64, f64, usize),
}

/// Bytes that steer text parsers into their interesting branches.
const INTERESTING: &[u8] = b"0123456789-+.eE,;:[]{}()\"'=# \n\r\t\\/xXnaif\0\xff";

pub fn mutation() -> impl Strategy<Value = Mutation> {
    let fraction = 0.0..1.0f64;
    prop_oneof![
        fraction.clone().prop_map(Mutation::Truncate),
        (fraction.clone(), 1..=255u8).prop_map(|(f, m)| Mutation::Flip(f, m)),
        (fraction.clone(), prop::sample::select(INTERESTING))
            .prop_map(|(f, b)| Mutation::Set(f, b)),
        (fraction.clone(), prop::collection::vec(any::<u8>(), 1..8))
            .prop_map(|(f, b)| Mutation::Insert(f, b)),
        (fraction.clone(), 1..16usize).prop_map(|(f, n)| Mutation::Remove(f, n)),
        (fraction.clone(), fraction, 1..64usize).prop_map(|(a, b, n)| Mutation::Splice(a, b, n)),
    ]
}

/// 1 to 6 mutations.
pub fn mutations() -> impl Strategy<Value = Vec<Mutation>> {
    prop::collection::vec(mutation(), 1..6)
}

pub fn apply(original: &[u8], mutations: &[Mutation]) -> Vec<u8> {
    let mut bytes = original.to_vec();
    let at = |f: f64, len: usize| ((f * len as f64) as usize).min(len);
    for m in mutations {
        let len = bytes.len();
        match m {
            Mutation::Truncate(f) => bytes.truncate(at(*f, len)),
            Mutation::Flip(f, mask) if len > 0 => {
                let i = at(*f, len - 1);
                bytes[i] ^= mask;
            }
            Mutation::Set(f, value) if len > 0 => {
                let i = at(*f, len - 1);
                bytes[i] = *value;
            }
            Mutation::Insert(f, new) => {
                let i = at(*f, len);
                bytes.splice(i..i, new.iter().copied());
            }
            Mutation::Remove(f, n) => {
                let i = at(*f, len);
                let end = (i + n).min(len);
                bytes.drain(i..end);
            }
            Mutation::Splice(from, to, n) => {
                let (i, j) = (at(*from, len), at(*to, len));
                let piece: Vec<u8> = bytes[i..(i + n).min(len)].to_vec();
                bytes.splice(j..j, piece);
            }
            _ => {}
        }
    }
    bytes
}

/// Text lines drawn from `pieces` (near-valid fragments of a format) and a few arbitrary words.
pub fn lines_from(
    pieces: &'static [&'static str],
    lines: std::ops::Range<usize>,
) -> impl Strategy<Value = String> {
    let line = prop_oneof![
        4 => prop::sample::select(pieces).prop_map(str::to_string),
        1 => "[ -~]{0,24}",
    ];
    prop::collection::vec(line, lines).prop_map(|l| l.join("\n"))
}

/// A number as text, biased to the values parsers trip on.
pub fn number_text() -> impl Strategy<Value = String> {
    prop_oneof![
        prop::sample::select(
            &[
                "0",
                "-0",
                "1",
                "-1",
                "0.5",
                "90",
                "89.999",
                "1e308",
                "-1e308",
                "1e-320",
                "nan",
                "NaN",
                "inf",
                "-inf",
                "+inf",
                "4294967296",
                "18446744073709551616",
                "9e999",
                "",
                "1.",
                ".5",
                "0x10",
                "1_0",
                "1e",
                "--1",
            ][..]
        )
        .prop_map(str::to_string),
        any::<f64>().prop_map(|v| v.to_string()),
        any::<i64>().prop_map(|v| v.to_string()),
        (0..200u32).prop_map(|v| v.to_string()),
    ]
}
