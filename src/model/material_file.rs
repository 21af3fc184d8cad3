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
use super::material::{LacquerMaterial, MaterialValue, MATERIAL_KEYS};
use crate::text::nearest;
// Public only for the scene loader's imports, until they name `crate::text`.
use crate::text::read_text_file;
use crate::{Error, Result};

/// The key that names the preset a file starts from.
pub const PRESET_KEY: &str = "preset";

/// The largest material file read (1 MiB): a material is a dozen lines.
pub const MAX_MATERIAL_FILE_BYTES: u64 = 1 << 20;

/// Reads and parses a material TOML file; relative `fresnel` paths resolve against its directory.
pub fn load_material_file(path: &Path) -> Result<LacquerMaterial> {
    let text = read_text_file(path, MAX_MATERIAL_FILE_BYTES, "material")?;
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
        "# A shikki lacquer material (SPEC §2–4). Every key is written; in a hand-written file, keys\n\
         # left out keep the values of `preset` (default smooth-black).\n",
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

    /// The type with its article, for "found …".
    fn type_name(&self) -> String {
        let name = match self {
            Value::Number(_) => "number",
            Value::Bool(_) => "boolean",
            Value::Str(_) => "string",
            Value::Array(_) => "array",
            Value::Other(name) => name,
        };
        let article = if name.starts_with(['a', 'e', 'i', 'o', 'u']) {
            "an"
        } else {
            "a"
        };
        format!("{article} {name}")
    }
}

/// Where errors point: the document text (empty when spans are unknown) and its name.
struct Spans<'a> {
    text: &'a str,
    source: &'a str,
}

impl Spans<'_> {
    /// An error at `span` if known, else naming `key`.
    /// [`error`](Self::error) for an error of the value at `span`: a file that could not be read
    /// stays a read failure ([`Error::located_at`]).
    fn locate(&self, span: Option<&Range<usize>>, key: &str, error: Error) -> Error {
        match span {
            Some(span) => {
                let at = Located::new(self.text, Some(span.clone()));
                error.located_at(self.source, at.line, &format!("column {}: ", at.column))
            }
            None => self.error(span, key, &error.to_string()),
        }
    }

    fn error(&self, span: Option<&Range<usize>>, key: &str, message: &str) -> Error {
        match span {
            Some(span) => Located::new(self.text, Some(span.clone())).error(self.source, message),
            None => Error::invalid(
                format!("material in {}", self.source),
                format!("`{key}`"),
                message,
            ),
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
                    "`preset` must be a string such as \"smooth-red\", found {}",
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
            Error::InvalidParameter { field, .. } => field.clone(),
            _ => String::new(),
        };
        let entry = entries
            .iter()
            .find(|en| en.key == field)
            .or(preset)
            .or(entries.first());
        let (span, key) = entry.map_or((None, field.as_str()), |en| {
            (en.key_span.as_ref(), en.key.as_str())
        });
        spans.locate(span, key, e)
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
            "`{key}` must be {expected}, found {}",
            entry.value.type_name()
        ))
    };
    if !MATERIAL_KEYS.contains(&key) {
        let message = unknown_key_message(key);
        return Err(spans.error(entry.key_span.as_ref(), key, &message));
    }
    let value = match (key, &entry.value) {
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
            MaterialValue::Rgb([numbers[0], numbers[1], numbers[2]])
        }
        ("kd", _) => return Err(wrong_type("an array of three numbers [r, g, b]")),
        ("extrapolate_g", Value::Bool(b)) => MaterialValue::Bool(*b),
        ("extrapolate_g", _) => return Err(wrong_type("a boolean (true or false)")),
        ("fresnel", Value::Str(path)) => {
            return set_fresnel(material, path, base_dir)
                .map_err(|e| spans.locate(entry.value_span.as_ref(), key, e));
        }
        ("fresnel", _) => return Err(wrong_type("a string (the path of a Fresnel CSV)")),
        (_, Value::Number(x)) => MaterialValue::Number(*x),
        (_, _) => return Err(wrong_type("a number")),
    };
    material
        .set_value(key, value)
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
    if let Some(near) = nearest(&valid, key) {
        message.push_str(&format!("; did you mean `{near}`?"));
    }
    message
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<LacquerMaterial> {
        material_from_toml_str(text, Path::new("/base"), "m.toml")
    }

    fn parse_error(text: &str) -> (usize, String) {
        match parse(text) {
            Err(Error::Parse {
                file,
                line,
                message,
            }) => {
                assert_eq!(file, "m.toml");
                (line, message)
            }
            other => panic!("expected a parse error for {text:?}, got {other:?}"),
        }
    }

    #[test]
    fn preset_then_keys_then_validate() {
        let m = parse(
            "preset = \"rough-red\"\nm = 0.3\nkd = [0.1, 0.2, 0.3]\nextrapolate_g = true\nr = 7\n",
        )
        .unwrap();
        let expected = LacquerMaterial {
            beckmann_m: 0.3,
            albedo: [0.1, 0.2, 0.3],
            extrapolate_g: true,
            lacquer_ratio: 7.0,
            ..LacquerMaterial::preset("rough-red").unwrap()
        };
        assert_eq!(m, expected);
        // No preset: smooth-black; integers are numbers.
        let m = parse("b = 1\n").unwrap();
        assert_eq!(m.diffuse_b, 1.0);
        assert_eq!(m.beckmann_m, LacquerMaterial::default().beckmann_m);
    }

    #[test]
    fn written_file_reads_back_identically() {
        // Every field off its preset value, written and read: exactly equal (Debug formatting of
        // f64 is the shortest text that parses to the same bits).
        let m = LacquerMaterial {
            beckmann_m: 0.123_456_789_012_345_67,
            diffuse_a: -0.031,
            diffuse_b: 1.0000000000000002,
            lacquer_law: [1.2, -0.2, 0.01],
            lacquer_ratio: 2.5,
            albedo: [0.5, 0.06, 1e-7],
            extrapolate_g: true,
            ior_a: 1.6,
            ior_b: 0.01,
            fresnel_file: None,
            beta_normal: 0.4,
            beta_grazing: 0.02,
            beta_power: 2.0,
        };
        let text = material_to_toml(&m, None);
        assert_eq!(parse(&text).unwrap(), m);
        assert!(!text.contains("fresnel"));
    }

    #[test]
    fn fresnel_paths_resolve_against_the_file_directory() {
        let dir = std::env::temp_dir().join(format!("shikki-material-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let table = FresnelTable::new(vec![0.0, 90.0], vec![[0.04; 3], [1.0; 3]]).unwrap();
        std::fs::write(dir.join("t.csv"), table.to_csv()).unwrap();
        let toml_path = dir.join("lacquer.toml");
        std::fs::write(&toml_path, "fresnel = \"t.csv\"\n").unwrap();
        let m = load_material_file(&toml_path).unwrap();
        assert_eq!(m.fresnel_file, Some(dir.join("t.csv")));
        assert_eq!(m.fresnel_table().unwrap(), table);
        // The writer names the file it is given.
        let text = material_to_toml(&m, Some("t.csv"));
        assert!(text.contains("fresnel = \"t.csv\"\n"), "{text}");
        // A missing table is an error at the `fresnel` line.
        std::fs::write(&toml_path, "m = 0.1\nfresnel = \"missing.csv\"\n").unwrap();
        let err = load_material_file(&toml_path).unwrap_err().to_string();
        assert!(
            err.starts_with(&format!(
                "{}:2: column 11: cannot read",
                toml_path.display()
            )),
            "{err}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn unknown_key_names_line_column_and_nearest() {
        let (line, message) = parse_error("m = 0.1\n  bta_normal = 0.2\n");
        assert_eq!(line, 2);
        assert!(
            message.starts_with("column 3: unknown key `bta_normal`; valid keys are preset, m, a,"),
            "{message}"
        );
        assert!(
            message.ends_with("did you mean `beta_normal`?"),
            "{message}"
        );
    }

    #[test]
    fn wrong_types_say_what_is_expected() {
        let cases = [
            (
                "m = \"0.1\"",
                "column 5: `m` must be a number, found a string",
            ),
            (
                "kd = [0.1, 0.2]",
                "column 6: `kd` must be an array of three numbers [r, g, b], found an array",
            ),
            (
                "kd = 0.5",
                "column 6: `kd` must be an array of three numbers [r, g, b], found a number",
            ),
            (
                "extrapolate_g = 1",
                "column 17: `extrapolate_g` must be a boolean (true or false), found a number",
            ),
            (
                "fresnel = 3",
                "column 11: `fresnel` must be a string (the path of a Fresnel CSV), found a number",
            ),
            (
                "preset = 1",
                "column 10: `preset` must be a string such as \"smooth-red\", found a number",
            ),
            (
                "m = { x = 1 }",
                "column 5: `m` must be a number, found a table",
            ),
        ];
        for (text, expected) in cases {
            assert_eq!(parse_error(text), (1, expected.to_string()), "{text}");
        }
    }

    #[test]
    fn field_rules_come_from_the_material() {
        // `set`'s own message, at the value's position.
        let (line, message) = parse_error("a = 1\nm = 1.5\n");
        assert_eq!(line, 2);
        assert!(
            message.starts_with(
                "column 5: invalid m = 1.5: the Beckmann RMS slope must be in [0.001, 1]"
            ),
            "{message}"
        );
        // A cross-field rule (validate) points at the key that broke it.
        let (line, message) = parse_error("preset = \"smooth\"\n\nr = 6.5\n");
        assert_eq!(line, 3);
        assert!(
            message.starts_with("column 1: invalid r = 6.5: must be in [1, "),
            "{message}"
        );
        let (_, message) = parse_error("preset = \"smoth\"");
        assert!(message.contains("did you mean `smooth`"), "{message}");
    }

    #[test]
    fn toml_syntax_errors_have_a_position() {
        let (line, message) = parse_error("m = 0.1\nb = = 2\n");
        assert_eq!(line, 2);
        assert!(message.starts_with("column "), "{message}");
    }

    #[test]
    fn embedded_table_keeps_the_documents_line_numbers() {
        // A scene file's [material] table: spans point into the whole document.
        let text = "[camera]\nfov_deg = 40\n\n[material]\npreset = \"rough\"\nm = 2\n";
        let document = DeTable::parse(text).unwrap();
        let material = document.get_ref().get("material").unwrap();
        let table = material.get_ref().as_table().unwrap();
        let err = material_from_de_table(table, text, Path::new("."), "scene.toml").unwrap_err();
        match err {
            Error::Parse { line, message, .. } => {
                assert_eq!(line, 6);
                assert!(message.starts_with("column 5: invalid m = 2"), "{message}");
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn plain_tables_work_without_spans() {
        let table: toml::Table = toml::from_str("preset = \"rough\"\nc0 = 1.1\n").unwrap();
        let m = material_from_toml_table(&table, Path::new("."), "scene.toml").unwrap();
        assert_eq!(m.lacquer_law[0], 1.1);
        let table: toml::Table = toml::from_str("mm = 0.1\n").unwrap();
        let err = material_from_toml_table(&table, Path::new("."), "scene.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("scene.toml") && err.contains("did you mean `m`?"),
            "{err}"
        );
    }
}
