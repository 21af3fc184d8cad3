//! Material files: a [`LacquerMaterial`] as TOML, read and written.
//!
//! ```toml
//! preset = "smooth-red"     # optional starting point (default smooth-black)
//! m = 0.05                  # any key of MATERIAL_KEYS, with the meaning of SPEC §2–4
//! kd = [0.5, 0.06, 0.03]
//! fresnel = "lacquer.fresnel.csv"   # relative paths resolve against the TOML file's directory
//! ```
//!
//! Owns the file format and its error messages (file:line, the column in the message, nearest
//! valid key, expected type). The rules for each field stay in [`LacquerMaterial::set`] and
//! [`LacquerMaterial::validate`]: values are handed to them as text, never checked twice here.
//! A scene file embeds the same table: [`material_from_de_table`] keeps its line numbers,
//! [`material_from_toml_table`] takes a plain `toml::Table` (no spans, so errors name the key).

use std::ops::Range;
use std::path::{Path, PathBuf};

use toml::de::{DeTable, DeValue};

use super::fresnel::FresnelTable;
use super::material::{LacquerMaterial, MATERIAL_KEYS};
use crate::{Error, Result};

/// The key that names the preset a file starts from.
pub const PRESET_KEY: &str = "preset";

/// Reads and parses a material TOML file; relative `fresnel` paths resolve against its directory.
pub fn load_material_file(path: &Path) -> Result<LacquerMaterial> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let base_dir = path.parent().unwrap_or(Path::new(""));
    material_from_toml_str(&text, base_dir, &path.display().to_string())
}

/// Parses a material from TOML text; `source` names it in errors, `base_dir` anchors `fresnel`.
pub fn material_from_toml_str(
    text: &str,
    base_dir: &Path,
    source: &str,
) -> Result<LacquerMaterial> {
    let table = DeTable::parse(text).map_err(|e| {
        let at = Located::new(text, e.span());
        at.error(source, e.message().trim_end())
    })?;
    material_from_de_table(table.get_ref(), text, base_dir, source)
}

/// A material from a parsed (spanned) table: `text` is the whole document the spans point into,
/// so a scene file can hand over its `[material]` table and keep line numbers in errors.
pub fn material_from_de_table(
    table: &DeTable,
    text: &str,
    base_dir: &Path,
    source: &str,
) -> Result<LacquerMaterial> {
    let entries = table
        .iter()
        .map(|(key, value)| Entry {
            key: key.get_ref().to_string(),
            key_span: Some(key.span()),
            value: Value::from_de(value.get_ref()),
            value_span: Some(value.span()),
        })
        .collect();
    build(entries, &Spans { text, source }, base_dir)
}

/// A material from a plain `toml::Table` (no spans: errors name `source` and the key).
pub fn material_from_toml_table(
    table: &toml::Table,
    base_dir: &Path,
    source: &str,
) -> Result<LacquerMaterial> {
    let entries = table
        .iter()
        .map(|(key, value)| Entry {
            key: key.clone(),
            key_span: None,
            value: Value::from_toml(value),
            value_span: None,
        })
        .collect();
    build(entries, &Spans { text: "", source }, base_dir)
}

/// Every field written out explicitly (no preset), so the file does not depend on preset values
/// that might change. `fresnel_file_name` (a path relative to the TOML file, or absolute) is
/// written as `fresnel`; without it, the material's own `fresnel_file` if it has one.
pub fn material_to_toml(material: &LacquerMaterial, fresnel_file_name: Option<&str>) -> String {
    let number = |v: f64| format!("{v:?}");
    let [c0, c1, c2] = material.lacquer_law;
    let [kr, kg, kb] = material.albedo;
    let mut out = String::from(
        "# A shikki lacquer material (SPEC §2–4). Keys left out keep the values of `preset`.\n",
    );
    let mut line = |key: &str, value: String| out.push_str(&format!("{key} = {value}\n"));
    line("m", number(material.beckmann_m));
    line("a", number(material.diffuse_a));
    line("b", number(material.diffuse_b));
    line("c0", number(c0));
    line("c1", number(c1));
    line("c2", number(c2));
    line("r", number(material.lacquer_ratio));
    line(
        "kd",
        format!("[{}, {}, {}]", number(kr), number(kg), number(kb)),
    );
    line("extrapolate_g", material.extrapolate_g.to_string());
    line("ior_a", number(material.ior_a));
    line("ior_b", number(material.ior_b));
    let fresnel = fresnel_file_name.map(str::to_owned).or_else(|| {
        material
            .fresnel_file
            .as_ref()
            .map(|p| p.display().to_string())
    });
    if let Some(name) = fresnel {
        line("fresnel", toml::Value::String(name).to_string());
    }
    line("beta_normal", number(material.beta_normal));
    line("beta_grazing", number(material.beta_grazing));
    line("beta_power", number(material.beta_power));
    out
}

/// One `key = value` of the table, with where it came from when known.
struct Entry {
    key: String,
    key_span: Option<Range<usize>>,
    value: Value,
    value_span: Option<Range<usize>>,
}

/// The value kinds a material file uses; anything else keeps only its type name for errors.
enum Value {
    Number(f64),
    Bool(bool),
    Str(String),
    Array(Vec<Value>),
    Other(&'static str),
}

impl Value {
    fn from_de(value: &DeValue) -> Self {
        match value {
            DeValue::Integer(i) => i64::from_str_radix(i.as_str(), i.radix())
                .map(|v| Value::Number(v as f64))
                .unwrap_or(Value::Other("integer out of range")),
            // TOML's inf/nan parse too; `set` rejects them with its own message.
            DeValue::Float(f) => f
                .as_str()
                .parse::<f64>()
                .map(Value::Number)
                .unwrap_or(Value::Other("float")),
            DeValue::Boolean(b) => Value::Bool(*b),
            DeValue::String(s) => Value::Str(s.to_string()),
            DeValue::Array(items) => {
                Value::Array(items.iter().map(|v| Value::from_de(v.get_ref())).collect())
            }
            DeValue::Table(_) => Value::Other("table"),
            DeValue::Datetime(_) => Value::Other("datetime"),
        }
    }

    fn from_toml(value: &toml::Value) -> Self {
        match value {
            toml::Value::Integer(i) => Value::Number(*i as f64),
            toml::Value::Float(f) => Value::Number(*f),
            toml::Value::Boolean(b) => Value::Bool(*b),
            toml::Value::String(s) => Value::Str(s.clone()),
            toml::Value::Array(items) => Value::Array(items.iter().map(Value::from_toml).collect()),
            toml::Value::Table(_) => Value::Other("table"),
            toml::Value::Datetime(_) => Value::Other("datetime"),
        }
    }

    fn type_name(&self) -> &'static str {
        match self {
            Value::Number(_) => "number",
            Value::Bool(_) => "boolean",
            Value::Str(_) => "string",
            Value::Array(_) => "array",
            Value::Other(name) => name,
        }
    }
}

/// Where errors point: the document text (empty when spans are unknown) and its name.
struct Spans<'a> {
    text: &'a str,
    source: &'a str,
}

impl Spans<'_> {
    /// An error at `span` if known, else naming `key`.
    fn error(&self, span: Option<&Range<usize>>, key: &str, message: &str) -> Error {
        match span {
            Some(span) => Located::new(self.text, Some(span.clone())).error(self.source, message),
            None => Error::invalid(format!("{}: key `{key}`", self.source), key, message),
        }
    }
}

/// A 1-based line and column (in characters) of a byte offset.
struct Located {
    line: usize,
    column: usize,
}

impl Located {
    fn new(text: &str, span: Option<Range<usize>>) -> Self {
        let offset = span.map_or(0, |s| s.start).min(text.len());
        let before = text.get(..offset).unwrap_or("");
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let column = before[line_start..].chars().count() + 1;
        Located { line, column }
    }

    fn error(&self, source: &str, message: &str) -> Error {
        Error::parse(
            source,
            self.line,
            format!("column {}: {message}", self.column),
        )
    }
}

/// The preset, then every other key through `set`, then `validate` — the same order of rules as
/// `--preset` and `--set` on the command line.
fn build(entries: Vec<Entry>, spans: &Spans, base_dir: &Path) -> Result<LacquerMaterial> {
    let preset = entries.iter().find(|e| e.key == PRESET_KEY);
    let mut material = match preset {
        None => LacquerMaterial::default(),
        Some(entry) => match &entry.value {
            Value::Str(name) => LacquerMaterial::preset(name)
                .map_err(|e| spans.error(entry.value_span.as_ref(), &entry.key, &e.to_string()))?,
            other => {
                let message = format!(
                    "`preset` must be a string such as \"smooth-red\", found a {}",
                    other.type_name()
                );
                return Err(spans.error(entry.value_span.as_ref(), &entry.key, &message));
            }
        },
    };
    for entry in entries.iter().filter(|e| e.key != PRESET_KEY) {
        apply(&mut material, entry, spans, base_dir)?;
    }
    material.validate().map_err(|e| {
        // A rule that ties fields together points at the failing field's line if the file set it,
        // else at the preset it came from.
        let field = match &e {
            Error::InvalidParameter { field, .. } => field.as_str(),
            _ => "",
        };
        let entry = entries
            .iter()
            .find(|en| en.key == field)
            .or(preset)
            .or(entries.first());
        let (span, key) = entry.map_or((None, field), |en| (en.key_span.as_ref(), &en.key));
        spans.error(span, key, &e.to_string())
    })?;
    Ok(material)
}

/// One non-preset key: type check, then `set` (or the path resolution for `fresnel`).
fn apply(
    material: &mut LacquerMaterial,
    entry: &Entry,
    spans: &Spans,
    base_dir: &Path,
) -> Result<()> {
    let key = entry.key.as_str();
    let at_value = |message: &str| spans.error(entry.value_span.as_ref(), key, message);
    let wrong_type = |expected: &str| {
        at_value(&format!(
            "`{key}` must be {expected}, found a {}",
            entry.value.type_name()
        ))
    };
    if !MATERIAL_KEYS.contains(&key) {
        let message = unknown_key_message(key);
        return Err(spans.error(entry.key_span.as_ref(), key, &message));
    }
    let text = match (key, &entry.value) {
        ("kd", Value::Array(items)) => {
            let numbers: Vec<f64> = items
                .iter()
                .filter_map(|v| match v {
                    Value::Number(x) => Some(*x),
                    _ => None,
                })
                .collect();
            if numbers.len() != 3 || items.len() != 3 {
                return Err(wrong_type("an array of three numbers [r, g, b]"));
            }
            format!("{},{},{}", numbers[0], numbers[1], numbers[2])
        }
        ("kd", _) => return Err(wrong_type("an array of three numbers [r, g, b]")),
        ("extrapolate_g", Value::Bool(b)) => b.to_string(),
        ("extrapolate_g", _) => return Err(wrong_type("a boolean (true or false)")),
        ("fresnel", Value::Str(path)) => {
            return set_fresnel(material, path, base_dir).map_err(|e| at_value(&e.to_string()));
        }
        ("fresnel", _) => return Err(wrong_type("a string (the path of a Fresnel CSV)")),
        (_, Value::Number(x)) => format!("{x}"),
        (_, _) => return Err(wrong_type("a number")),
    };
    material
        .set(key, &text)
        .map_err(|e| at_value(&e.to_string()))
}

/// `fresnel = "…"`: "" means the dielectric table; otherwise the path, relative to `base_dir`,
/// must load as a Fresnel table now, so that the error points at this line.
fn set_fresnel(material: &mut LacquerMaterial, path: &str, base_dir: &Path) -> Result<()> {
    let path = path.trim();
    if path.is_empty() {
        material.fresnel_file = None;
        return Ok(());
    }
    let resolved: PathBuf = base_dir.join(path);
    FresnelTable::from_csv_file(&resolved)?;
    material.fresnel_file = Some(resolved);
    Ok(())
}

/// "unknown key `x`; valid keys are …; did you mean `y`?"
fn unknown_key_message(key: &str) -> String {
    let valid: Vec<&str> = std::iter::once(PRESET_KEY)
        .chain(MATERIAL_KEYS.iter().copied())
        .collect();
    let mut message = format!("unknown key `{key}`; valid keys are {}", valid.join(", "));
    if let Some(near) = valid.iter().min_by_key(|v| edit_distance(v, key)) {
        message.push_str(&format!("; did you mean `{near}`?"));
    }
    message
}

/// Levenshtein distance, for "did you mean".
fn edit_distance(a: &str, b: &str) -> usize {
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
