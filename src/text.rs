//! Text inputs shared by every loader (material, scene, jobs, Fresnel and goniometer CSV): a file
//! read whole with a size limit and UTF-8 errors at their line, and the nearest valid name for a
//! "did you mean" hint. Owns no format: each loader parses the text itself.

use std::path::Path;

use crate::{Error, Result};

/// Reads a text input (material, scene, CSV) whole: refused from its length above `max_bytes`
/// (before anything is read), and a byte that is not UTF-8 is a parse error at its line. Shared
/// by every text loader; `kind` names the file in messages ("scene", "Fresnel CSV").
pub fn read_text_file(path: &Path, max_bytes: u64, kind: &str) -> Result<String> {
    let read_error = |source| Error::Read {
        path: path.to_path_buf(),
        source,
    };
    let length = std::fs::metadata(path).map_err(read_error)?.len();
    if length > max_bytes {
        return Err(Error::invalid(
            format!("{kind} file"),
            format!("{} ({length} bytes)", path.display()),
            format!("at most {max_bytes} bytes are read; check that this is the right file"),
        ));
    }
    let bytes = std::fs::read(path).map_err(read_error)?;
    String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = valid.iter().filter(|&&b| b == b'\n').count() + 1;
        let column = valid.len() - valid.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        Error::parse(
            path.display().to_string(),
            line,
            format!(
                "byte {} of the line is not UTF-8 text; save the {kind} file as UTF-8",
                column + 1
            ),
        )
    })
}

/// Levenshtein distance (for "did you mean"); shared by material and scene files.
pub fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let substitute = diagonal + usize::from(ca != *cb);
            diagonal = row[j + 1];
            row[j + 1] = substitute.min(row[j] + 1).min(diagonal + 1);
        }
    }
    row[b.len()]
}

/// The candidate nearest to `got` by [`edit_distance`] (the first of equals), for "did you mean
/// `x`?"; `None` only when there are no candidates.
pub fn nearest<'a>(candidates: &[&'a str], got: &str) -> Option<&'a str> {
    candidates
        .iter()
        .copied()
        .min_by_key(|candidate| edit_distance(candidate, got))
}

/// `spec` after its `builtin:` prefix, or `None` where it has none. Names (built-ins, presets,
/// models, light kinds, tone curves, formats, `none`) are read without regard to ASCII case in
/// every input; paths are not names.
pub fn builtin_name(spec: &str) -> Option<&str> {
    const PREFIX: &str = "builtin:";
    let head = spec.get(..PREFIX.len())?;
    head.eq_ignore_ascii_case(PREFIX)
        .then(|| &spec[PREFIX.len()..])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edit_distance_spot_values() {
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("m", "m"), 0);
        assert_eq!(edit_distance("", "ab"), 2);
    }

    #[test]
    fn nearest_takes_the_first_of_equally_near_candidates() {
        assert_eq!(nearest(&["smooth", "rough"], "smoth"), Some("smooth"));
        assert_eq!(nearest(&["ab", "ba"], "aa"), Some("ab"));
        assert_eq!(nearest(&[], "x"), None);
    }
}
