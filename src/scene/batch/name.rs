//! A batch job's output file name: the `name` template and the rule that turns a swept value into
//! file-name text.
//!
//! Owns the naming rule, which must never merge two values (issue 14: `-30` and `30` both became
//! `30`, and ten images of the example sweep overwrote ten others):
//!
//! 1. A value's text (as the manifest shows it; inside an array the manifest also quotes
//!    strings) keeps ASCII letters, digits, `.`, `_` and `-`;
//!    every other character becomes `%XX` for each byte of its UTF-8 encoding, `%` itself
//!    included ([`escape_value`]). Decoding the escapes gives the text back, so two values with
//!    different texts never share a name: `-30` → `-30`, `1.5` → `1.5`, `builtin:bowl` →
//!    `builtin%3Abowl`, `a b` → `a%20b`.
//! 2. The template's own text is kept as written; it may not hold `/`, `\` or control
//!    characters (the directory is `--out`'s).
//! 3. `.png` / `.exr` is added from the format unless the template's text already ends with it.
//! 4. A name never starts with `.` (hidden) or `-` (read as an option): such a first character
//!    becomes `%2E` / `%2D`.
//!
//! Different values per placeholder are not yet different names (`{a}{b}` runs values together,
//! a sweep may list one value twice, a case-insensitive disk folds `Red` and `red`): the plan-wide
//! check in `collisions` ([`super::BatchPlan::check_outputs`]) refuses those. Never touches the
//! disk.

use super::Sweep;
use crate::output::OutputFormat;
use crate::scene::doc::Origin;
use crate::Result;

/// The longest file name ext4, APFS and NTFS accept, in bytes (UTF-16 units on NTFS).
pub const MAX_FILE_NAME_BYTES: usize = 255;

/// One piece of a parsed `name` template.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Piece<'a> {
    Text(&'a str),
    /// `{job}`: the id, zero-padded to the width of the largest id.
    Job,
    /// `{path}` or `{last.segment}` of sweep `k`.
    Sweep(usize),
}

/// A parsed `name` template of one plan.
#[derive(Clone, Debug)]
pub(super) struct Template<'a> {
    pieces: Vec<Piece<'a>>,
    job_width: usize,
}

impl<'a> Template<'a> {
    /// Splits `text` into pieces and resolves each placeholder against `sweeps`; errors point at
    /// the `name` line (`at`).
    pub(super) fn parse(
        text: &'a str,
        sweeps: &[Sweep],
        job_count: usize,
        at: &Origin,
    ) -> Result<Self> {
        let mut pieces = Vec::new();
        let mut rest = text;
        while let Some(open) = rest.find('{') {
            pieces.push(Piece::Text(&rest[..open]));
            let Some(close) = rest[open..].find('}') else {
                return Err(at.error("`name` has a `{` without its `}`"));
            };
            let key = &rest[open + 1..open + close];
            pieces.push(match key {
                "job" => Piece::Job,
                _ => Piece::Sweep(placeholder(key, sweeps, at)?),
            });
            rest = &rest[open + close + 1..];
        }
        pieces.push(Piece::Text(rest));
        pieces.retain(|p| *p != Piece::Text(""));
        let literal = pieces.iter().filter_map(|p| match p {
            Piece::Text(t) => Some(*t),
            _ => None,
        });
        for t in literal {
            if let Some(bad) = t.chars().find(|&c| c == '/' || c == '\\' || c.is_control()) {
                return Err(at.error(format!(
                    "`name` = {text:?} holds {bad:?}: it is a file name, not a path; give the \
                     directory with --out"
                )));
            }
        }
        Ok(Template {
            pieces,
            job_width: job_count.saturating_sub(1).to_string().len(),
        })
    }

    /// Whether a placeholder of the template names sweep `k`.
    pub(super) fn uses(&self, k: usize) -> bool {
        self.pieces.contains(&Piece::Sweep(k))
    }

    /// The file name of job `id`, whose sweep `k` has the escaped text `values[k]`
    /// ([`escape_value`]); steps 3 and 4 of the module doc.
    pub(super) fn compose(&self, id: usize, values: &[&str], format: OutputFormat) -> String {
        let mut name = String::new();
        for piece in &self.pieces {
            match *piece {
                Piece::Text(t) => name.push_str(t),
                Piece::Job => name.push_str(&format!("{id:0width$}", width = self.job_width)),
                Piece::Sweep(k) => name.push_str(values[k]),
            }
        }
        let extension = extension(format);
        // Only the template's own text counts: a value ending in `.png` still gets `.png` added,
        // or `a` and `a.png` would both be `a.png`.
        let literal_extension = matches!(self.pieces.last(), Some(Piece::Text(t))
            if t.to_ascii_lowercase().ends_with(extension));
        let suffix = if literal_extension {
            name.split_off(name.len() - extension.len())
        } else {
            extension.to_string()
        };
        let escaped_first = match name.chars().next() {
            Some('.') => Some("%2E"),
            Some('-') => Some("%2D"),
            _ => None,
        };
        if let Some(escape) = escaped_first {
            name.replace_range(..1, escape);
        }
        name + &suffix
    }
}

/// `.png` or `.exr`.
pub(super) fn extension(format: OutputFormat) -> &'static str {
    match format {
        OutputFormat::Png => ".png",
        OutputFormat::Exr => ".exr",
    }
}

/// Step 1 of the module doc: keeps `[A-Za-z0-9._-]`, writes every other character as `%XX` per
/// UTF-8 byte (uppercase hex). Injective: `%` only ever starts an escape.
pub fn escape_value(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-') {
            out.push(c);
        } else {
            let mut bytes = [0; 4];
            for b in c.encode_utf8(&mut bytes).bytes() {
                out.push_str(&format!("%{b:02X}"));
            }
        }
    }
    out
}

/// The sweep a placeholder names: its full path, or its last segment if no other sweep's last
/// segment is the same.
fn placeholder(key: &str, sweeps: &[Sweep], at: &Origin) -> Result<usize> {
    if let Some(k) = sweeps.iter().position(|s| s.path == key) {
        return Ok(k);
    }
    let matches: Vec<usize> = (0..sweeps.len())
        .filter(|&k| last_segment(&sweeps[k].path) == key)
        .collect();
    match matches[..] {
        [k] => Ok(k),
        _ => {
            let valid: Vec<String> = std::iter::once("{job}".to_string())
                .chain(sweeps.iter().map(|s| format!("{{{}}}", s.path)))
                .collect();
            Err(at.error(format!(
                "`name` placeholder {{{key}}} names no sweep{}; valid: {}",
                if matches.len() > 1 {
                    " unambiguously"
                } else {
                    ""
                },
                valid.join(", ")
            )))
        }
    }
}

/// The shortest placeholder that names sweep `k`: its last segment where that is unambiguous.
pub(super) fn shortest_placeholder(k: usize, sweeps: &[Sweep]) -> String {
    let last = last_segment(&sweeps[k].path);
    let unique = sweeps
        .iter()
        .filter(|s| last_segment(&s.path) == last)
        .count()
        == 1;
    let key = if unique && last != "job" {
        last
    } else {
        &sweeps[k].path
    };
    format!("{{{key}}}")
}

fn last_segment(path: &str) -> &str {
    path.rsplit('.').next().unwrap_or(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The inverse of [`escape_value`], to show that it loses nothing.
    fn unescape(text: &str) -> String {
        let mut bytes = Vec::new();
        let mut rest = text.as_bytes();
        while let Some((&b, tail)) = rest.split_first() {
            if b == b'%' {
                let hex = std::str::from_utf8(&tail[..2]).unwrap();
                bytes.push(u8::from_str_radix(hex, 16).unwrap());
                rest = &tail[2..];
            } else {
                bytes.push(b);
                rest = tail;
            }
        }
        String::from_utf8(bytes).unwrap()
    }

    #[test]
    fn escaping_keeps_signs_and_points_and_round_trips() {
        for (text, escaped) in [
            ("-30", "-30"),
            ("30", "30"),
            ("1.5", "1.5"),
            ("15", "15"),
            ("smooth-red", "smooth-red"),
            ("builtin:bowl", "builtin%3Abowl"),
            ("a b", "a%20b"),
            ("100%", "100%25"),
            ("%25", "%2525"),
            ("meshes/bowl.obj", "meshes%2Fbowl.obj"),
            ("[0, 1]", "%5B0%2C%201%5D"),
            ("漆", "%E6%BC%86"),
            ("", ""),
        ] {
            assert_eq!(escape_value(text), escaped, "{text:?}");
            assert_eq!(unescape(escaped), text);
        }
    }

    #[test]
    fn distinct_texts_get_distinct_escapes() {
        let texts = [
            "-30", "30", "+30", "m30", "1.5", "15", "1_5", "1-5", "1 5", "1%205", "a:b", "a-b",
            "a/b", "a%2Fb", "A", "a", "", "-", ".", "..", "%", "%25",
        ];
        let escaped: std::collections::BTreeSet<String> =
            texts.iter().map(|t| escape_value(t)).collect();
        assert_eq!(escaped.len(), texts.len(), "{escaped:?}");
    }

    fn sweeps(paths: &[&str]) -> Vec<Sweep> {
        paths
            .iter()
            .map(|p| Sweep {
                path: p.to_string(),
                values: Vec::new(),
            })
            .collect()
    }

    fn at() -> Origin {
        Origin::Override {
            what: "name".into(),
            text: "".into(),
            base_dir: std::path::Path::new(".").into(),
        }
    }

    #[test]
    fn names_never_start_with_a_dot_or_dash_and_keep_one_extension() {
        let s = sweeps(&["camera.orbit_deg"]);
        let bare = Template::parse("{orbit_deg}", &s, 3, &at()).unwrap();
        assert_eq!(bare.compose(0, &["-30"], OutputFormat::Png), "%2D30.png");
        assert_eq!(bare.compose(0, &[".."], OutputFormat::Png), "%2E..png");
        assert_eq!(bare.compose(0, &["a.png"], OutputFormat::Png), "a.png.png");
        assert_eq!(bare.compose(0, &["a"], OutputFormat::Exr), "a.exr");
        let suffixed = Template::parse("o{orbit_deg}.PNG", &s, 3, &at()).unwrap();
        assert_eq!(suffixed.compose(0, &["-30"], OutputFormat::Png), "o-30.PNG");
        assert_eq!(
            suffixed.compose(0, &["-30"], OutputFormat::Exr),
            "o-30.PNG.exr"
        );
        let job = Template::parse("{job}", &s, 1000, &at()).unwrap();
        assert_eq!(job.compose(7, &["x"], OutputFormat::Png), "007.png");
    }

    #[test]
    fn a_template_with_a_path_separator_is_refused() {
        let s = sweeps(&["camera.orbit_deg"]);
        for text in ["out/{orbit_deg}", "..\\{orbit_deg}", "a\t{orbit_deg}"] {
            let err = Template::parse(text, &s, 3, &at()).unwrap_err();
            assert!(err.to_string().contains("not a path"), "{err}");
        }
    }

    #[test]
    fn the_shortest_placeholder_is_the_last_segment_when_unique() {
        let s = sweeps(&["object.0.material.r", "object.1.material.r", "camera.job"]);
        assert_eq!(shortest_placeholder(0, &s), "{object.0.material.r}");
        assert_eq!(shortest_placeholder(2, &s), "{camera.job}");
        let s = sweeps(&["object.0.material.r", "camera.orbit_deg"]);
        assert_eq!(shortest_placeholder(1, &s), "{orbit_deg}");
    }
}
