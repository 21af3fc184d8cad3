//! Text inputs shared by every loader (material, scene, jobs, Fresnel and goniometer CSV): a file
//! read whole with a size limit and UTF-8 errors at their line, or line by line (a measurement
//! file is never held whole); the lexing every delimited table shares (line ends, the separator,
//! quoted cells, decimal commas); and the nearest valid name for a "did you mean" hint. Owns no
//! format: each loader gives its columns their meaning itself.

use std::borrow::Cow;
use std::io::{BufRead, BufReader};
use std::path::Path;

use crate::{Error, Result};

/// The longest line [`for_each_line`] reads (1 MiB): a spectral row at every 0.1 nm is ~80 kB,
/// so a longer line is not a table row (a binary file, or a file without line ends).
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// The separators a delimited table may use: `,`; `;` (Excel in locales whose decimal mark is a
/// comma); a tab (tab-separated values, a spreadsheet's copy).
pub const SEPARATORS: [char; 3] = [',', ';', '\t'];

/// Reads a text input (material, scene, CSV) whole: refused from its length above `max_bytes`
/// (before anything is read), and a byte that is not UTF-8 is a parse error at its line. Shared
/// by every text loader; `kind` names the file in messages ("scene", "Fresnel CSV").
pub fn read_text_file(path: &Path, max_bytes: u64, kind: &str) -> Result<String> {
    check_file_size(path, max_bytes, kind)?;
    let bytes = std::fs::read(path).map_err(|source| read_error(path, source))?;
    String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = valid.iter().filter(|&&b| b == b'\n').count() + 1;
        let column = valid.len() - valid.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        not_utf8(path, line, column, kind)
    })
}

/// Calls `each` with every line of a text file (1-based number, text without its line end) as
/// [`numbered_lines`] splits them, reading the file in pieces: only one line is held at a time.
/// The file is refused from its length above `max_bytes` (before anything is read), a line
/// longer than [`MAX_LINE_BYTES`] and a byte that is not UTF-8 are errors at their line, and a
/// UTF-16 file is named as such. `each`'s first error stops the reading and is returned.
pub fn for_each_line(
    path: &Path,
    max_bytes: u64,
    kind: &str,
    mut each: impl FnMut(usize, &str) -> Result<()>,
) -> Result<()> {
    check_file_size(path, max_bytes, kind)?;
    let file = std::fs::File::open(path).map_err(|source| read_error(path, source))?;
    let mut reader = BufReader::with_capacity(1 << 16, file);
    let mut line: Vec<u8> = Vec::new();
    let mut number = 0;
    // The last piece ended in `\r`: a `\n` that starts the next belongs to that line end.
    let mut after_cr = false;
    let mut emit = |number: usize, bytes: &[u8]| -> Result<()> {
        let bytes = if number == 1 {
            first_line_bytes(bytes, path, kind)?
        } else {
            bytes
        };
        match std::str::from_utf8(bytes) {
            Ok(text) => each(number, text),
            Err(e) => Err(not_utf8(path, number, e.valid_up_to(), kind)),
        }
    };
    loop {
        let piece = reader
            .fill_buf()
            .map_err(|source| read_error(path, source))?;
        let length = piece.len();
        if length == 0 {
            break;
        }
        let mut start = usize::from(after_cr && piece[0] == b'\n');
        after_cr = false;
        while let Some(offset) = piece[start..]
            .iter()
            .position(|&b| b == b'\n' || b == b'\r')
        {
            let end = start + offset;
            line.extend_from_slice(&piece[start..end]);
            number += 1;
            emit(number, &line)?;
            line.clear();
            start = end + 1;
            if piece[end] == b'\r' {
                match piece.get(start) {
                    Some(b'\n') => start += 1,
                    Some(_) => {}
                    None => after_cr = true,
                }
            }
        }
        line.extend_from_slice(&piece[start..]);
        if line.len() > MAX_LINE_BYTES {
            return Err(Error::parse(
                path.display().to_string(),
                number + 1,
                format!(
                    "the line is longer than {MAX_LINE_BYTES} bytes; this is not a {kind} (a \
                     binary file, or one without line ends?): check that this is the right file"
                ),
            ));
        }
        reader.consume(length);
    }
    if !line.is_empty() {
        emit(number + 1, &line)?;
    }
    Ok(())
}

/// The lines of `text`, numbered from 1, split at `\n`, `\r\n` or a lone `\r` (classic Mac OS
/// files end lines with `\r` alone, and a reader that split at `\n` saw one line); a leading
/// UTF-8 byte-order mark is removed. As with [`str::lines`], a final line end adds no empty line.
pub fn numbered_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let mut rest = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut number = 0;
    std::iter::from_fn(move || {
        if rest.is_empty() {
            return None;
        }
        number += 1;
        let Some(end) = rest.find(['\n', '\r']) else {
            return Some((number, std::mem::take(&mut rest)));
        };
        let line = &rest[..end];
        let skip = if rest[end..].starts_with("\r\n") {
            2
        } else {
            1
        };
        rest = &rest[end + skip..];
        Some((number, line))
    })
}

/// The separator of a delimited table, from its header line: whichever of [`SEPARATORS`] occurs
/// most often outside double quotes (the first listed on a tie), `,` if none does (one column).
/// Counting, not just finding, keeps a `;`-separated header with a decimal comma in a wavelength
/// (`380,5`) a `;` header.
pub fn detect_separator(header: &str) -> char {
    let mut counts = [0usize; SEPARATORS.len()];
    let mut quoted = false;
    for c in header.chars() {
        if c == '"' {
            quoted = !quoted;
        } else if let Some(i) = SEPARATORS.iter().position(|&s| s == c).filter(|_| !quoted) {
            counts[i] += 1;
        }
    }
    let mut best = 0;
    for i in 1..SEPARATORS.len() {
        if counts[i] > counts[best] {
            best = i;
        }
    }
    SEPARATORS[best]
}

/// How a separator is named in messages.
pub fn separator_name(separator: char) -> &'static str {
    match separator {
        ';' => "`;`",
        '\t' => "tabs",
        _ => "`,`",
    }
}

/// Splits a table line at `separator` into cells with the spaces around them trimmed. A cell in
/// double quotes (as spreadsheets write text) may hold the separator, and `""` inside it is one
/// quote; the quotes are removed. A quote left open, or text after a closing quote, is an error
/// (cells do not span lines).
pub fn split_cells(line: &str, separator: char) -> std::result::Result<Vec<Cow<'_, str>>, String> {
    if !line.contains('"') {
        return Ok(line
            .split(separator)
            .map(|cell| Cow::Borrowed(cell.trim()))
            .collect());
    }
    let mut cells = Vec::new();
    let mut rest = line;
    loop {
        let trimmed = rest.trim_start();
        let Some(quoted) = trimmed.strip_prefix('"') else {
            match rest.find(separator) {
                Some(end) => {
                    cells.push(Cow::Borrowed(rest[..end].trim()));
                    rest = &rest[end + separator.len_utf8()..];
                    continue;
                }
                None => {
                    cells.push(Cow::Borrowed(rest.trim()));
                    return Ok(cells);
                }
            }
        };
        let mut text = String::new();
        let mut chars = quoted.char_indices();
        let after = loop {
            match chars.next() {
                Some((i, '"')) if quoted[i + 1..].starts_with('"') => {
                    text.push('"');
                    chars.next();
                }
                Some((i, '"')) => break &quoted[i + 1..],
                Some((_, c)) => text.push(c),
                None => {
                    return Err(format!(
                        "cell {} opens a quote that the line does not close; close it with `\"` \
                         (a cell cannot span lines)",
                        cells.len() + 1
                    ))
                }
            }
        };
        cells.push(Cow::Owned(text));
        let after = after.trim_start();
        if after.is_empty() {
            return Ok(cells);
        }
        match after.strip_prefix(separator) {
            Some(next) => rest = next,
            None => {
                return Err(format!(
                    "cell {} has text after its closing quote; put the whole cell in quotes",
                    cells.len()
                ))
            }
        }
    }
}

/// A number cell: Rust's f64 syntax, or, in a table not separated by `,`, the same with a
/// decimal comma (`0,25`, as Excel writes numbers where the decimal mark is a comma).
pub fn parse_number(cell: &str, separator: char) -> Option<f64> {
    match cell.parse::<f64>() {
        Ok(v) => Some(v),
        Err(_) if separator != ',' && cell.matches(',').count() == 1 && !cell.contains('.') => {
            cell.replacen(',', ".", 1).parse().ok()
        }
        Err(_) => None,
    }
}

fn read_error(path: &Path, source: std::io::Error) -> Error {
    Error::Read {
        path: path.to_path_buf(),
        source,
    }
}

/// Refuses a file from its length, before anything is read.
fn check_file_size(path: &Path, max_bytes: u64, kind: &str) -> Result<()> {
    let length = std::fs::metadata(path)
        .map_err(|source| read_error(path, source))?
        .len();
    if length > max_bytes {
        return Err(Error::invalid(
            format!("{kind} file"),
            format!("{} ({length} bytes)", path.display()),
            format!("at most {max_bytes} bytes are read; check that this is the right file"),
        ));
    }
    Ok(())
}

/// The first line without its UTF-8 byte-order mark; a UTF-16 one is an error that says so
/// (every other byte of such a file is 0, which read as "not UTF-8" without the reason).
fn first_line_bytes<'a>(bytes: &'a [u8], path: &Path, kind: &str) -> Result<&'a [u8]> {
    if bytes.starts_with(&[0xff, 0xfe]) || bytes.starts_with(&[0xfe, 0xff]) {
        return Err(Error::parse(
            path.display().to_string(),
            1,
            format!("the file is UTF-16 text; save the {kind} file as UTF-8 (in Excel: CSV UTF-8)"),
        ));
    }
    Ok(bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(bytes))
}

/// A byte that is not UTF-8 at `line`, `column` bytes into it (0-based).
fn not_utf8(path: &Path, line: usize, column: usize, kind: &str) -> Error {
    Error::parse(
        path.display().to_string(),
        line,
        format!(
            "byte {} of the line is not UTF-8 text; save the {kind} file as UTF-8",
            column + 1
        ),
    )
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
    fn lines_end_at_lf_crlf_or_a_lone_cr() {
        let lines: Vec<_> = numbered_lines("\u{feff}a\r\nb\rc\n\nd").collect();
        assert_eq!(lines, [(1, "a"), (2, "b"), (3, "c"), (4, ""), (5, "d")]);
        assert_eq!(numbered_lines("a\n").count(), 1);
        assert_eq!(numbered_lines("").count(), 0);
    }

    #[test]
    fn file_lines_match_text_lines_across_piece_boundaries() {
        // Lines around the reader's 64 KiB pieces, with `\r\n` split between two pieces.
        let long = "x".repeat((1 << 16) - 3);
        let text = format!("\u{feff}h\r{long}\r\nb\rc\n\nd\r");
        let path = std::env::temp_dir().join(format!("shikki-lines-{}.csv", std::process::id()));
        std::fs::write(&path, &text).unwrap();
        let mut read = Vec::new();
        let result = for_each_line(&path, 1 << 20, "test", |n, l| {
            read.push((n, l.to_string()));
            Ok(())
        });
        std::fs::remove_file(&path).unwrap();
        result.unwrap();
        let expected: Vec<_> = numbered_lines(&text)
            .map(|(n, l)| (n, l.to_string()))
            .collect();
        assert_eq!(read, expected);
        assert_eq!(read.len(), 6);
    }

    #[test]
    fn separators_quotes_and_decimal_commas() {
        assert_eq!(detect_separator("sample,r,theta_i_deg"), ',');
        assert_eq!(detect_separator("sample;r;380,5;781"), ';');
        assert_eq!(detect_separator("sample\tr\ttheta"), '\t');
        assert_eq!(detect_separator("\"a,b\";c"), ';');
        assert_eq!(detect_separator("sample"), ',');
        let cells = split_cells(" \"Board, 1\" ,1, \"say \"\"hi\"\"\",", ',').unwrap();
        assert_eq!(cells, ["Board, 1", "1", "say \"hi\"", ""]);
        assert_eq!(split_cells("a; b ;c", ';').unwrap(), ["a", "b", "c"]);
        assert!(split_cells("\"a,b", ',')
            .unwrap_err()
            .contains("cell 1 opens a quote"));
        assert!(split_cells("\"a\"b,c", ',')
            .unwrap_err()
            .contains("after its closing"));
        assert_eq!(parse_number("0,25", ';'), Some(0.25));
        assert_eq!(parse_number("0,25", ','), None);
        assert_eq!(parse_number("1.5,2", ';'), None);
        assert_eq!(parse_number("-1e-3", '\t'), Some(-1e-3));
    }

    #[test]
    fn nearest_takes_the_first_of_equally_near_candidates() {
        assert_eq!(nearest(&["smooth", "rough"], "smoth"), Some("smooth"));
        assert_eq!(nearest(&["ab", "ba"], "aa"), Some("ab"));
        assert_eq!(nearest(&[], "x"), None);
    }
}
