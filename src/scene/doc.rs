//! The scene document: a TOML tree in which every value remembers where it came from (file, line,
//! column and the directory its relative paths resolve against, or the `--set`/sweep override that
//! put it there). Owns reading TOML with spans, overriding a value by a dotted path
//! (`object.0.material.r`) and located error messages. It knows nothing of what the keys mean:
//! that is [`super::parse`].

use std::cell::Cell;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use toml::de::{DeTable, DeValue};

use crate::{Error, Result};

/// Where a value came from.
#[derive(Clone, Debug, PartialEq)]
pub enum Origin {
    /// A span of a file: 1-based line and column (in characters).
    File {
        source: Arc<str>,
        line: usize,
        column: usize,
        base_dir: Arc<Path>,
    },
    /// A command-line `--set`; `what` names it (`--set camera.fov_deg`), `text` is the value
    /// as typed.
    Override {
        what: Arc<str>,
        text: Arc<str>,
        base_dir: Arc<Path>,
    },
}

impl Origin {
    /// The directory a relative path written here resolves against.
    pub fn base_dir(&self) -> &Path {
        match self {
            Origin::File { base_dir, .. } | Origin::Override { base_dir, .. } => base_dir,
        }
    }

    /// An error at this place: `file:line: column c: message`, or naming the override.
    pub fn error(&self, message: impl std::fmt::Display) -> Error {
        match self {
            Origin::File {
                source,
                line,
                column,
                ..
            } => Error::parse(
                source.as_ref(),
                *line,
                format!("column {column}: {message}"),
            ),
            Origin::Override { what, text, .. } => {
                Error::invalid(what.as_ref(), text.as_ref(), message.to_string())
            }
        }
    }

    /// `error` located here, as [`error`](Self::error) does, except that a file that could not
    /// be read stays a read failure ([`Error::located_at`]).
    pub fn locate(&self, error: Error) -> Error {
        match self {
            Origin::File {
                source,
                line,
                column,
                ..
            } => error.located_at(source, *line, &format!("column {column}: ")),
            Origin::Override { .. } => self.error(error),
        }
    }

    /// A short human form for listings: `file:line:col` or the override's name.
    pub fn describe(&self) -> String {
        match self {
            Origin::File {
                source,
                line,
                column,
                ..
            } => format!("{source}:{line}:{column}"),
            Origin::Override { what, .. } => what.to_string(),
        }
    }
}

/// A TOML value with its origin.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    pub value: Value,
    pub at: Origin,
}

/// A table entry: the key keeps its own origin so "unknown key" points at the key.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    pub key: String,
    pub key_at: Origin,
    pub node: Node,
}

/// TOML's value kinds (datetimes are kept only as a type name for errors).
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Integer(i64),
    Float(f64),
    Bool(bool),
    Str(String),
    Array(Vec<Node>),
    Table(Vec<Entry>),
    Datetime,
}

impl Value {
    /// "a number", "an array", …: for "expected …, found …".
    pub fn type_name(&self) -> &'static str {
        match self {
            Value::Integer(_) => "an integer",
            Value::Float(_) => "a float",
            Value::Bool(_) => "a boolean",
            Value::Str(_) => "a string",
            Value::Array(_) => "an array",
            Value::Table(_) => "a table",
            Value::Datetime => "a datetime",
        }
    }

    /// The value as TOML text, for manifests, labels and material `set`.
    pub fn to_text(&self) -> String {
        match self {
            Value::Integer(i) => i.to_string(),
            Value::Float(f) => format!("{f}"),
            Value::Bool(b) => b.to_string(),
            Value::Str(s) => s.clone(),
            Value::Array(items) => {
                let parts: Vec<String> = items.iter().map(|n| n.value.to_text()).collect();
                format!("[{}]", parts.join(", "))
            }
            Value::Table(entries) => {
                let parts: Vec<String> = entries
                    .iter()
                    .map(|e| format!("{} = {}", e.key, e.node.value.to_text()))
                    .collect();
                format!("{{{}}}", parts.join(", "))
            }
            Value::Datetime => "datetime".into(),
        }
    }
}

/// Parses TOML `text` into a located tree; a syntax error names `source:line` and the column.
pub fn parse_document(text: &str, source: &str, base_dir: &Path) -> Result<Node> {
    let located = Locator::new(text, source, base_dir);
    let table = DeTable::parse(text).map_err(|e| {
        let span = e.span().unwrap_or(0..0);
        let message = e.message().trim_end();
        // The parser's "duplicate key" names no key: the span holds it (a key or a table header).
        let message = match (message, text.get(span.clone())) {
            ("duplicate key", Some(key)) if !key.trim().is_empty() => format!(
                "duplicate key `{}`: a key (or table) may be written once; remove one",
                key.trim()
            ),
            _ => message.to_string(),
        };
        located.origin(span).error(message)
    })?;
    Ok(Node {
        value: located.table(table.get_ref()),
        at: located.origin(0..0),
    })
}

/// Turns byte spans into [`Origin`]s of one file.
/// Finds the line and column of a span. Counting from the start of the text for every value was
/// quadratic in the file's length (a 200,000-value sweep of 1.3 MB took 21 s to parse, a probe
/// of the batch runner, 2026-12-06): the lines' starts are found once, and a column is counted
/// on from the last one asked for when it lies earlier on the same line, as the values of one
/// long array do.
struct Locator<'a> {
    text: &'a str,
    source: Arc<str>,
    base_dir: Arc<Path>,
    /// The byte offset of each line's first character; the first is 0.
    line_starts: Vec<usize>,
    /// The offset and column of the last span located.
    last: Cell<(usize, usize)>,
}

impl<'a> Locator<'a> {
    fn new(text: &'a str, source: &str, base_dir: &Path) -> Self {
        Locator {
            text,
            source: Arc::from(source),
            base_dir: Arc::from(base_dir),
            line_starts: std::iter::once(0)
                .chain(text.match_indices('\n').map(|(i, _)| i + 1))
                .collect(),
            last: Cell::new((0, 1)),
        }
    }

    fn origin(&self, span: Range<usize>) -> Origin {
        let offset = span.start.min(self.text.len());
        let line = self.line_starts.partition_point(|&start| start <= offset);
        let line_start = self.line_starts[line.saturating_sub(1)];
        let chars = |from: usize| self.text.get(from..offset).map_or(0, |s| s.chars().count());
        let (last_offset, last_column) = self.last.get();
        let column = if (line_start..=offset).contains(&last_offset) {
            last_column + chars(last_offset)
        } else {
            1 + chars(line_start)
        };
        self.last.set((offset, column));
        Origin::File {
            source: self.source.clone(),
            line,
            column,
            base_dir: self.base_dir.clone(),
        }
    }

    /// Entries in the order they appear in the file (the map itself is sorted by key).
    fn table(&self, table: &DeTable) -> Value {
        let mut entries: Vec<(usize, Entry)> = table
            .iter()
            .map(|(key, value)| {
                (
                    key.span().start,
                    Entry {
                        key: key.get_ref().to_string(),
                        key_at: self.origin(key.span()),
                        node: self.node(value.get_ref(), value.span()),
                    },
                )
            })
            .collect();
        entries.sort_by_key(|(start, _)| *start);
        Value::Table(entries.into_iter().map(|(_, e)| e).collect())
    }

    fn node(&self, value: &DeValue, span: Range<usize>) -> Node {
        let at = self.origin(span);
        let value = match value {
            DeValue::Integer(i) => match i64::from_str_radix(i.as_str(), i.radix()) {
                Ok(v) => Value::Integer(v),
                Err(_) => Value::Float(i.as_str().parse().unwrap_or(f64::NAN)),
            },
            DeValue::Float(f) => Value::Float(parse_toml_float(f.as_str())),
            DeValue::Boolean(b) => Value::Bool(*b),
            DeValue::String(s) => Value::Str(s.to_string()),
            DeValue::Array(items) => Value::Array(
                items
                    .iter()
                    .map(|v| self.node(v.get_ref(), v.span()))
                    .collect(),
            ),
            DeValue::Table(table) => self.table(table),
            DeValue::Datetime(_) => Value::Datetime,
        };
        Node { value, at }
    }
}

/// TOML floats include `inf`, `nan` and `_` separators; Rust's parser takes neither spelling.
fn parse_toml_float(text: &str) -> f64 {
    let clean: String = text.chars().filter(|c| *c != '_').collect();
    match clean.trim_start_matches(['+', '-']) {
        "inf" if clean.starts_with('-') => f64::NEG_INFINITY,
        "inf" => f64::INFINITY,
        "nan" => f64::NAN,
        _ => clean.parse().unwrap_or(f64::NAN),
    }
}

/// Parses the text of a `--set` value as a TOML value (`2`, `[0, 1, 4]`, `"x"`, `true`); text that
/// is not TOML (`builtin:plate`, `smooth-red`) is taken as a string.
pub fn parse_override_value(text: &str, what: &str, base_dir: &Path) -> Node {
    let at = Origin::Override {
        what: Arc::from(what),
        text: Arc::from(text.trim()),
        base_dir: Arc::from(base_dir),
    };
    // `0x64` on a command line is a size (`--set output.size=0x64`), not TOML's hexadecimal 100:
    // hexadecimal, octal and binary integers are taken as the text typed.
    let unsigned = text.trim().trim_start_matches(['+', '-']);
    let radix_integer = ["0x", "0o", "0b"].iter().any(|p| unsigned.starts_with(p));
    let parsed = (!radix_integer)
        .then(|| parse_document(&format!("v = {text}"), what, base_dir).ok())
        .flatten()
        .and_then(|doc| match doc.value {
            Value::Table(mut entries) if entries.len() == 1 => entries.pop().map(|e| e.node.value),
            _ => None,
        });
    let value = parsed.unwrap_or_else(|| Value::Str(text.trim().to_string()));
    relocate(Node { value, at })
}

/// Gives every nested node the origin of the root (an override has one place: its own name).
fn relocate(node: Node) -> Node {
    let at = node.at.clone();
    let value = match node.value {
        Value::Array(items) => Value::Array(
            items
                .into_iter()
                .map(|n| {
                    relocate(Node {
                        at: at.clone(),
                        ..n
                    })
                })
                .collect(),
        ),
        Value::Table(entries) => Value::Table(
            entries
                .into_iter()
                .map(|e| Entry {
                    key: e.key,
                    key_at: at.clone(),
                    node: relocate(Node {
                        at: at.clone(),
                        ..e.node
                    }),
                })
                .collect(),
        ),
        other => other,
    };
    Node { value, at }
}

/// The key a string stands for when a path goes through it: `material = "red.toml"` overridden
/// at `material.r` becomes `{ file = "red.toml", r = … }`, `material = "smooth-red"` (a preset's
/// name, which `parse::material` reads as the preset) `{ preset = "smooth-red", r = … }`;
/// likewise `environment = "none"`.
fn string_as_table_key(parent_key: &str, text: &str) -> Option<&'static str> {
    match parent_key {
        "material" if crate::model::LacquerMaterial::preset(text.trim()).is_ok() => Some("preset"),
        "material" => Some("file"),
        "environment" => Some("source"),
        _ => None,
    }
}

/// Replaces (or adds) the value at the dotted `path` of `root` by `value`. Numeric segments index
/// arrays (`object.0`); missing tables on the way are created. The error names the path and what
/// was found where it stopped.
pub fn set_path(root: &mut Node, path: &str, value: Node) -> Result<()> {
    let segments: Vec<&str> = path.split('.').map(str::trim).collect();
    if segments.iter().any(|s| s.is_empty()) {
        return Err(value.at.error(format!(
            "`{path}` is not a field path; write segments separated by dots, e.g. \
             object.0.material.r or camera.fov_deg"
        )));
    }
    let mut current = root;
    let mut parent_key = "";
    for (i, segment) in segments.iter().enumerate() {
        let last = i + 1 == segments.len();
        let as_key = match &current.value {
            Value::Str(s) => string_as_table_key(parent_key, s),
            _ => None,
        };
        if let (Value::Str(s), Some(key)) = (&current.value, as_key) {
            let inner = Node {
                value: Value::Str(s.clone()),
                at: current.at.clone(),
            };
            current.value = Value::Table(vec![Entry {
                key: key.to_string(),
                key_at: current.at.clone(),
                node: inner,
            }]);
        }
        let at = current.at.clone();
        current = match &mut current.value {
            Value::Table(_) if segment.parse::<usize>().is_ok() => {
                return Err(value.at.error(format!(
                    "`{path}`: `{parent_key}` is not an array (write [[{parent_key}]] in the \
                     scene file to have element {segment})"
                )))
            }
            Value::Table(entries) => {
                let index = match entries.iter().position(|e| e.key == *segment) {
                    Some(index) => index,
                    None => {
                        entries.push(Entry {
                            key: segment.to_string(),
                            key_at: value.at.clone(),
                            node: Node {
                                value: Value::Table(Vec::new()),
                                at: value.at.clone(),
                            },
                        });
                        entries.len() - 1
                    }
                };
                &mut entries[index].node
            }
            Value::Array(items) => {
                let len = items.len();
                let index = segment.parse::<usize>().ok().filter(|&k| k < len);
                match index {
                    Some(k) => &mut items[k],
                    None => {
                        return Err(value.at.error(format!(
                            "`{path}`: `{segment}` must index the array defined at {} \
                             (0..{len})",
                            at.describe(),
                            len = len
                        )))
                    }
                }
            }
            other => {
                return Err(value.at.error(format!(
                    "`{path}`: cannot go into `{parent_key}`, which is {} (at {})",
                    other.type_name(),
                    at.describe()
                )))
            }
        };
        if last {
            *current = value;
            return Ok(());
        }
        parent_key = segment;
    }
    Ok(())
}

/// "unknown key `x` in [camera]; valid keys are …; did you mean `y`?"
pub fn unknown_key(entry: &Entry, section: &str, valid: &[&str]) -> Error {
    let mut message = format!(
        "unknown key `{}` in {section}; valid keys are {}",
        entry.key,
        valid.join(", ")
    );
    if let Some(near) = crate::text::nearest(valid, &entry.key) {
        message.push_str(&format!("; did you mean `{near}`?"));
    }
    entry.key_at.error(message)
}

/// A path relative to where it was written.
pub fn resolve_path(at: &Origin, path: &str) -> PathBuf {
    at.base_dir().join(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn doc(text: &str) -> Node {
        parse_document(text, "s.toml", Path::new("/base")).unwrap()
    }

    fn entry<'a>(node: &'a Node, key: &str) -> &'a Node {
        match &node.value {
            Value::Table(entries) => &entries.iter().find(|e| e.key == key).unwrap().node,
            other => panic!("not a table: {other:?}"),
        }
    }

    #[test]
    fn origins_count_lines_and_columns_from_one() {
        // `fov_deg = 30` on line 3, its value starts at character 11 (hand-counted).
        let d = doc("# c\n[camera]\nfov_deg = 30\n");
        let fov = entry(entry(&d, "camera"), "fov_deg");
        assert_eq!(fov.value, Value::Integer(30));
        assert_eq!(fov.at.describe(), "s.toml:3:11");
    }

    #[test]
    fn syntax_error_names_line_and_column() {
        let err = parse_document("a = 1\nb = = 2\n", "s.toml", Path::new(".")).unwrap_err();
        match err {
            Error::Parse { file, line, .. } => assert_eq!((file.as_str(), line), ("s.toml", 2)),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn set_path_indexes_arrays_and_creates_tables() {
        let mut d = doc("[[object]]\nmesh = \"builtin:bowl\"\n[[object]]\nmesh = \"x\"\n");
        let two = parse_override_value("2", "--set object.1.material.r", Path::new("."));
        set_path(&mut d, "object.1.material.r", two).unwrap();
        let objects = match &entry(&d, "object").value {
            Value::Array(items) => items.clone(),
            other => panic!("{other:?}"),
        };
        assert_eq!(
            entry(entry(&objects[1], "material"), "r").value,
            Value::Integer(2)
        );
        let bad = parse_override_value("1", "--set object.2.mesh", Path::new("."));
        assert!(set_path(&mut d, "object.2.mesh", bad).is_err());
    }

    #[test]
    fn material_string_becomes_a_file_table_when_overridden() {
        let mut d = doc("[[object]]\nmaterial = \"red.toml\"\n");
        let v = parse_override_value("3", "sweep", Path::new("."));
        set_path(&mut d, "object.0.material.r", v).unwrap();
        let Value::Array(objects) = &entry(&d, "object").value else {
            panic!()
        };
        let material = entry(&objects[0], "material");
        assert_eq!(entry(material, "file").value, Value::Str("red.toml".into()));
        assert_eq!(entry(material, "r").value, Value::Integer(3));
    }

    /// The line and column of every character boundary, asked in order and out of order, are
    /// those of counting from the start of the text (the rule the lines' starts and the last
    /// column replace for speed).
    #[test]
    fn spans_are_located_as_by_counting_from_the_start() {
        let text = "a = 1\nb = [\"東京\", 2, 3]\n\n  c = \"é\" # x\nd=4";
        let locator = Locator::new(text, "t", Path::new("."));
        let counted = |offset: usize| {
            let before = &text[..offset];
            let line_start = before.rfind('\n').map_or(0, |i| i + 1);
            (
                before.matches('\n').count() + 1,
                before[line_start..].chars().count() + 1,
            )
        };
        let boundaries: Vec<usize> = (0..=text.len())
            .filter(|&i| text.is_char_boundary(i))
            .collect();
        let shuffled = boundaries
            .iter()
            .rev()
            .step_by(3)
            .chain(boundaries.iter().step_by(2));
        for &offset in boundaries.iter().chain(shuffled) {
            match locator.origin(offset..offset) {
                Origin::File { line, column, .. } => {
                    assert_eq!((line, column), counted(offset), "offset {offset}")
                }
                other => panic!("{other:?}"),
            }
        }
    }

    #[test]
    fn override_values_parse_as_toml_or_fall_back_to_strings() {
        let p = |t: &str| parse_override_value(t, "x", Path::new(".")).value;
        assert_eq!(p("2.5"), Value::Float(2.5));
        assert_eq!(p("builtin:plate"), Value::Str("builtin:plate".into()));
        assert_eq!(p("smooth-red"), Value::Str("smooth-red".into()));
        assert!(matches!(p("[0, 1, 4]"), Value::Array(v) if v.len() == 3));
        // A size typed on the command line, not TOML's hexadecimal 100.
        assert_eq!(p("0x64"), Value::Str("0x64".into()));
        assert_eq!(p("0b1"), Value::Str("0b1".into()));
        assert_eq!(p("-0o7"), Value::Str("-0o7".into()));
        assert_eq!(p("0"), Value::Integer(0));
    }
}
