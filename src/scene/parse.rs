//! The scene schema (docs/scene.md): from a located TOML tree ([`super::doc`]) to a [`Scene`].
//!
//! Owns the key names, their defaults and types, and the rule that every error names where the
//! value was written. The ranges of each quantity stay with their owners (`Camera::validate`,
//! `Light::validate`, `LacquerMaterial::set_value/validate`, `Mesh::validate`); their messages
//! are wrapped with the location here, never re-checked. Values reach them typed: a TOML number
//! is never turned back into text.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

use glam::{DMat4, DQuat, DVec3, EulerRot};

use super::doc::{self, Entry, Node, Origin, Value};
use super::sections::{environment, light, output, render};
use super::{EnvironmentSpec, MeshSource, OutputSpec, RenderSpec, Scene, SceneObject};
use crate::environment::load::{environment_file, BUILTIN_STUDIO};
use crate::model::fresnel::FresnelTable;
use crate::model::limits;
use crate::model::material::{MaterialValue, MATERIAL_KEYS};
use crate::model::material_file::load_material_file;
use crate::model::LacquerMaterial;
use crate::output::OutputFormat;
use crate::raster::lights::{default_lights, MAX_LIGHTS};
use crate::raster::mesh::{BuiltinMesh, Mesh};
use crate::raster::mesh_io::load_mesh_with_report;
use crate::raster::Camera;
use crate::text::read_text_file;
use crate::{Error, Result};

/// The largest scene file read (16 MiB): hand-written scenes are a few KiB.
pub const MAX_SCENE_FILE_BYTES: u64 = 16 << 20;

const TOP_KEYS: &[&str] = &[
    "camera",
    "object",
    "light",
    "environment",
    "render",
    "output",
];
const CAMERA_KEYS: &[&str] = &["eye", "target", "up", "fov_deg", "orbit_deg"];
const OBJECT_KEYS: &[&str] = &[
    "mesh",
    "translate",
    "rotate_deg",
    "scale",
    "transform",
    "material",
];
pub(super) const LIGHT_KEYS: &[&str] = &["kind", "to_light", "irradiance", "position", "intensity"];
pub(super) const ENVIRONMENT_KEYS: &[&str] = &["source", "intensity", "rotation_deg"];
pub(super) const RENDER_KEYS: &[&str] = &[
    "environment_model",
    "shadows",
    "ray_tracing",
    "bounces",
    "rays",
    "seed",
    "denoise",
];
pub(super) const OUTPUT_KEYS: &[&str] = &[
    "size",
    "width",
    "height",
    "samples",
    "exposure",
    "tonemap",
    "format",
    "background",
];

/// A scene as written plus overrides: what `--set` and batch sweeps edit before [`Self::build`].
#[derive(Clone, Debug)]
pub struct SceneDocument {
    pub root: Node,
}

impl SceneDocument {
    /// Parses TOML text (syntax errors name `source_name:line` and the column).
    pub fn parse(text: &str, source_name: &str, base_dir: &Path) -> Result<Self> {
        Ok(SceneDocument {
            root: doc::parse_document(text, source_name, base_dir)?,
        })
    }

    /// Reads a scene file (at most [`MAX_SCENE_FILE_BYTES`]); relative paths in it resolve against
    /// its directory.
    pub fn load(path: &Path) -> Result<Self> {
        let text = read_text_file(path, MAX_SCENE_FILE_BYTES, "scene")?;
        let base_dir = path.parent().unwrap_or(Path::new(""));
        Self::parse(&text, &path.display().to_string(), base_dir)
    }

    /// `--set path=value`: the value is TOML (`2`, `[0, 1, 4]`) or else a plain string. A path
    /// starting with `material.` sets that field of every object's material.
    pub fn set(&mut self, assignment: &str, base_dir: &Path) -> Result<()> {
        let (path, text) = assignment.split_once('=').ok_or_else(|| {
            Error::invalid(
                "--set",
                assignment,
                "expected PATH=VALUE, e.g. --set camera.fov_deg=30 or --set object.0.material.r=2",
            )
        })?;
        let path = path.trim();
        let value = doc::parse_override_value(text, &format!("--set {path}"), base_dir);
        self.set_node(path, value)
    }

    /// Puts `value` at `path` (see [`Self::set`]).
    pub fn set_node(&mut self, path: &str, value: Node) -> Result<()> {
        if let Some(rest) = path.strip_prefix("material.") {
            let count = match table_get(&self.root, "object").map(|n| &n.value) {
                Some(Value::Array(items)) => items.len(),
                _ => 0,
            };
            for k in 0..count {
                doc::set_path(
                    &mut self.root,
                    &format!("object.{k}.material.{rest}"),
                    value.clone(),
                )?;
            }
            return Ok(());
        }
        doc::set_path(&mut self.root, path, value)
    }

    /// The scene, every value checked.
    pub fn build(&self) -> Result<Scene> {
        scene_from_document(&self.root)
    }

    /// The file `[environment] source` names, if it names one (not a built-in), resolved as the
    /// scene resolves it; read from the document, so it is known even when the scene does not
    /// build. A render must not write its image over it, nor remove it as a failed run's output.
    pub fn environment_file(&self) -> Option<PathBuf> {
        let source = table_get(&self.root, "environment").and_then(|e| table_get(e, "source"))?;
        match &source.value {
            Value::Str(s) => environment_file(s).map(|_| doc::resolve_path(&source.at, s)),
            _ => None,
        }
    }

    /// `[output] format` (default png).
    pub fn output_format(&self) -> Result<OutputFormat> {
        let output = table_get(&self.root, "output");
        match output.and_then(|o| table_get(o, "format")) {
            None => Ok(OutputFormat::Png),
            Some(node) => format_of(node),
        }
    }
}

pub(super) fn format_of(node: &Node) -> Result<OutputFormat> {
    match &node.value {
        Value::Str(s) if s.eq_ignore_ascii_case("png") => Ok(OutputFormat::Png),
        Value::Str(s) if s.eq_ignore_ascii_case("exr") => Ok(OutputFormat::Exr),
        _ => Err(node.at.error(format!(
            "`format` must be \"png\" (8-bit sRGB after exposure and tone curve) or \
             \"exr\" (linear float32 radiance), found {}",
            show(node)
        ))),
    }
}

/// The entry `key` of a table node, if the node is a table and has it.
pub fn table_get<'a>(node: &'a Node, key: &str) -> Option<&'a Node> {
    match &node.value {
        Value::Table(entries) => entries.iter().find(|e| e.key == key).map(|e| &e.node),
        _ => None,
    }
}

/// Checks `node` is a table with only `valid` keys and returns its entries.
pub(super) fn table<'a>(node: &'a Node, section: &str, valid: &[&str]) -> Result<&'a [Entry]> {
    match &node.value {
        Value::Table(entries) => {
            if let Some(bad) = entries.iter().find(|e| !valid.contains(&e.key.as_str())) {
                return Err(doc::unknown_key(bad, section, valid));
            }
            Ok(entries)
        }
        other => Err(node.at.error(format!(
            "{section} must be a table, found {}",
            other.type_name()
        ))),
    }
}

pub(super) fn show(node: &Node) -> String {
    format!("{} `{}`", node.value.type_name(), node.value.to_text())
}

pub(super) fn number(node: &Node, key: &str) -> Result<f64> {
    let x = match node.value {
        Value::Integer(i) => i as f64,
        Value::Float(f) => f,
        _ => {
            return Err(node
                .at
                .error(format!("`{key}` must be a number, found {}", show(node))))
        }
    };
    if !x.is_finite() {
        return Err(node.at.error(format!("`{key}` must be finite, found {x}")));
    }
    Ok(x)
}

pub(super) fn vec3(node: &Node, key: &str) -> Result<DVec3> {
    let wrong = || {
        node.at.error(format!(
            "`{key}` must be an array of three numbers [x, y, z], found {}",
            show(node)
        ))
    };
    match &node.value {
        Value::Array(items) if items.len() == 3 => {
            let mut v = [0.0; 3];
            for (slot, item) in v.iter_mut().zip(items) {
                *slot = match item.value {
                    // A number that is not finite says so (it read as "not three numbers").
                    Value::Float(f) if !f.is_finite() => {
                        return Err(item.at.error(format!(
                            "`{key}` must be three finite numbers, found {} in {}",
                            f,
                            show(node)
                        )))
                    }
                    _ => number(item, key).map_err(|_| wrong())?,
                };
            }
            Ok(DVec3::from_array(v))
        }
        _ => Err(wrong()),
    }
}

pub(super) fn string<'a>(node: &'a Node, key: &str) -> Result<&'a str> {
    match &node.value {
        Value::Str(s) => Ok(s),
        _ => Err(node
            .at
            .error(format!("`{key}` must be a string, found {}", show(node)))),
    }
}

pub(super) fn boolean(node: &Node, key: &str) -> Result<bool> {
    match node.value {
        Value::Bool(b) => Ok(b),
        _ => Err(node.at.error(format!(
            "`{key}` must be true or false, found {}",
            show(node)
        ))),
    }
}

pub(super) fn whole(node: &Node, key: &str, range: std::ops::RangeInclusive<u32>) -> Result<u32> {
    match node.value {
        Value::Integer(i) if i >= i64::from(*range.start()) && i <= i64::from(*range.end()) => {
            Ok(i as u32)
        }
        _ => Err(node.at.error(format!(
            "`{key}` must be a whole number in {}..={}, found {}",
            range.start(),
            range.end(),
            show(node)
        ))),
    }
}

/// Wraps an owner's validation error with where the value was written.
pub(super) fn located<T>(at: &Origin, result: Result<T>) -> Result<T> {
    result.map_err(|e| at.locate(e))
}

/// `result`'s error located at the entry its field names (`camera.fov_deg` → the `fov_deg`
/// value, which for a `--set` override is the override), `aliases` mapping a field's last part to
/// the key written (`direction` → `to_light`); at the table `at` when no entry names it.
pub(super) fn located_at_field<T>(
    at: &Origin,
    entries: &[Entry],
    aliases: &[(&str, &str)],
    result: Result<T>,
) -> Result<T> {
    result.map_err(|e| {
        let key = match &e {
            Error::InvalidParameter { field, .. } => {
                let last = field.rsplit('.').next().unwrap_or(field);
                aliases
                    .iter()
                    .find(|(from, _)| *from == last)
                    .map_or(last, |(_, to)| *to)
                    .to_string()
            }
            _ => String::new(),
        };
        entries
            .iter()
            .find(|entry| entry.key == key)
            .map_or(at, |entry| &entry.node.at)
            .locate(e)
    })
}

/// The whole scene from its document root.
pub fn scene_from_document(root: &Node) -> Result<Scene> {
    let entries = table(root, "the scene file", TOP_KEYS)?;
    let get = |key: &str| entries.iter().find(|e| e.key == key).map(|e| &e.node);
    let camera = match get("camera") {
        Some(node) => camera(node)?,
        None => Camera::default(),
    };
    let objects = match get("object") {
        None => Vec::new(),
        Some(node) => array_of_tables(node, "object")?
            .iter()
            .map(object)
            .collect::<Result<_>>()?,
    };
    let lights = match get("light") {
        None => default_lights(),
        Some(node) => {
            let items = array_of_tables(node, "light")?;
            if items.len() > MAX_LIGHTS {
                return Err(node.at.error(format!(
                    "{} lights; a scene takes at most {MAX_LIGHTS}",
                    items.len()
                )));
            }
            items.iter().map(light).collect::<Result<_>>()?
        }
    };
    let environment = match get("environment") {
        None => EnvironmentSpec::named(BUILTIN_STUDIO),
        Some(node) => environment(node)?,
    };
    let render = match get("render") {
        None => RenderSpec::default(),
        Some(node) => render(node)?,
    };
    let output = match get("output") {
        None => OutputSpec::default(),
        Some(node) => output(node)?,
    };
    Ok(Scene {
        camera,
        objects,
        lights,
        environment,
        render,
        output,
    })
}

fn array_of_tables<'a>(node: &'a Node, key: &str) -> Result<&'a [Node]> {
    match &node.value {
        Value::Array(items) => Ok(items),
        _ => Err(node.at.error(format!(
            "`{key}` must be an array of tables, written [[{key}]], found {}",
            show(node)
        ))),
    }
}

/// `[camera]`: look-at camera; `orbit_deg` turns the eye about +Y around the target.
fn camera(node: &Node) -> Result<Camera> {
    let mut camera = Camera::default();
    let mut orbit = 0.0;
    let entries = table(node, "[camera]", CAMERA_KEYS)?;
    for e in entries {
        let n = &e.node;
        match e.key.as_str() {
            "eye" => camera.eye = vec3(n, "eye")?,
            "target" => camera.target = vec3(n, "target")?,
            "up" => camera.up = vec3(n, "up")?,
            "fov_deg" => camera.fov_deg = number(n, "fov_deg")?,
            _ => orbit = number(n, "orbit_deg")?,
        }
    }
    let offset = camera.eye - camera.target;
    camera.eye = camera.target + DQuat::from_rotation_y(orbit.to_radians()) * offset;
    located_at_field(&node.at, entries, &[], camera.validate())?;
    Ok(camera)
}

/// `[[object]]`: mesh, placement (translate/rotate_deg/scale or a 4×4 `transform`), material.
fn object(node: &Node) -> Result<SceneObject> {
    let entries = table(node, "[[object]]", OBJECT_KEYS)?;
    let get = |key: &str| entries.iter().find(|e| e.key == key);
    let mesh_node = get("mesh").map(|e| &e.node).ok_or_else(|| {
        node.at.error(
            "[[object]] needs `mesh`: \"builtin:bowl\" (or sphere, board, plate) or the path of \
             an .obj, .gltf or .glb file",
        )
    })?;
    let mesh = mesh_source(mesh_node)?;
    let trs: Vec<&Entry> = ["translate", "rotate_deg", "scale"]
        .iter()
        .filter_map(|k| get(k))
        .collect();
    let transform = match (get("transform"), trs.first()) {
        (Some(t), Some(other)) => {
            return Err(other.key_at.error(format!(
                "`{}` and `transform` (at {}) both place the object; use one or the other",
                other.key,
                t.key_at.describe()
            )))
        }
        (Some(t), None) => matrix(&t.node)?,
        (None, _) => {
            let translate = get("translate").map(|e| vec3(&e.node, "translate"));
            let rotate = get("rotate_deg").map(|e| vec3(&e.node, "rotate_deg"));
            let scale = get("scale").map(|e| scale(&e.node));
            let r = rotate.transpose()?.unwrap_or(DVec3::ZERO);
            let rotation = DQuat::from_euler(
                EulerRot::ZYX,
                r.z.to_radians(),
                r.y.to_radians(),
                r.x.to_radians(),
            );
            DMat4::from_scale_rotation_translation(
                scale.transpose()?.unwrap_or(DVec3::ONE),
                rotation,
                translate.transpose()?.unwrap_or(DVec3::ZERO),
            )
        }
    };
    if let Some(reason) = limits::placement_problem(&transform) {
        let at = get("transform")
            .or(trs.first().copied())
            .map_or(&node.at, |e| &e.key_at);
        return Err(at.error(format!("the object's placement cannot be drawn: {reason}")));
    }
    let material = match get("material") {
        None => LacquerMaterial::default(),
        Some(e) => material(&e.node)?,
    };
    Ok(SceneObject {
        mesh,
        transform,
        material,
    })
}

fn scale(node: &Node) -> Result<DVec3> {
    let s = match node.value {
        Value::Array(_) => vec3(node, "scale")?,
        _ => DVec3::splat(number(node, "scale")?),
    };
    if s.min_element() <= 0.0 {
        return Err(node.at.error(
            "`scale` must be positive (a number or [x, y, z]); mirror with `transform` instead",
        ));
    }
    Ok(s)
}

/// `transform = [[row 0], [row 1], [row 2], [row 3]]`, rows as a matrix is written on paper
/// (translation in the last column), affine (last row 0, 0, 0, 1).
fn matrix(node: &Node) -> Result<DMat4> {
    let wrong = || {
        node.at.error(format!(
            "`transform` must be 4 rows of 4 numbers, the last row [0, 0, 0, 1], found {}",
            show(node)
        ))
    };
    let Value::Array(rows) = &node.value else {
        return Err(wrong());
    };
    if rows.len() != 4 {
        return Err(wrong());
    }
    let mut m = [[0.0; 4]; 4];
    for (i, row) in rows.iter().enumerate() {
        let Value::Array(cells) = &row.value else {
            return Err(wrong());
        };
        if cells.len() != 4 {
            return Err(wrong());
        }
        for (j, cell) in cells.iter().enumerate() {
            m[i][j] = number(cell, "transform")?;
        }
    }
    if m[3] != [0.0, 0.0, 0.0, 1.0] {
        return Err(wrong());
    }
    // A singular or degenerate matrix is refused with every other placement, in `object`
    // (`limits::placement_problem`).
    Ok(DMat4::from_cols_array_2d(&m).transpose())
}

/// Meshes read from files, kept for the life of the process keyed by path, size and modification
/// time: a batch names the same file in every job, and the scene must load it at parse time so a
/// bad mesh is reported at the line that names it.
type MeshCache = Mutex<Vec<(PathBuf, u64, Option<std::time::SystemTime>, FileMesh)>>;

/// A mesh file as loaded, with what the loader changed (`LoadReport::notes`; empty when it loaded
/// as written).
#[derive(Clone, Debug)]
pub struct FileMesh {
    pub mesh: Arc<Mesh>,
    pub notes: Arc<[String]>,
}

impl FileMesh {
    /// Loads the mesh file at `path` (not from the process cache).
    pub fn load(path: &Path) -> Result<Self> {
        let (mesh, report) = load_mesh_with_report(path)?;
        Ok(Self {
            mesh: Arc::new(mesh),
            notes: report.notes().into(),
        })
    }
}

/// Loads (or finds in the process cache) the mesh file at `path`.
pub fn cached_file_mesh(path: &Path) -> Result<Arc<Mesh>> {
    cached_file_mesh_noted(path).map(|file| file.mesh)
}

/// [`cached_file_mesh`] with the loader's notes.
pub fn cached_file_mesh_noted(path: &Path) -> Result<FileMesh> {
    static CACHE: OnceLock<MeshCache> = OnceLock::new();
    let metadata = std::fs::metadata(path).map_err(|source| Error::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let stamp = (metadata.len(), metadata.modified().ok());
    let cache = CACHE.get_or_init(|| Mutex::new(Vec::new()));
    if let Ok(entries) = cache.lock() {
        if let Some(hit) = entries
            .iter()
            .find(|(p, len, time, _)| p == path && (*len, *time) == stamp)
        {
            return Ok(hit.3.clone());
        }
    }
    let file = FileMesh::load(path)?;
    if let Ok(mut entries) = cache.lock() {
        entries.retain(|(p, ..)| p != path);
        entries.push((path.to_path_buf(), stamp.0, stamp.1, file.clone()));
    }
    Ok(file)
}

fn mesh_source(node: &Node) -> Result<MeshSource> {
    let spec = string(node, "mesh")?;
    if crate::text::builtin_name(spec).is_some() {
        return located(&node.at, BuiltinMesh::parse(spec).map(MeshSource::Builtin));
    }
    // `sphere` alone is the built-in (a mesh file needs an extension, so it cannot mean one).
    if let Ok(builtin) = BuiltinMesh::parse(spec) {
        return Ok(MeshSource::Builtin(builtin));
    }
    let path = doc::resolve_path(&node.at, spec);
    located(&node.at, cached_file_mesh(&path))?;
    Ok(MeshSource::File(path))
}

/// `material = "file.toml"`, or a preset's name: `material = "smooth-red"` is the preset (a
/// preset's name has no extension, so it cannot mean a material file; it was read as a missing
/// one). The same for `file` in a table, which is what `--set object.0.material.r=2` makes of
/// the string.
fn material_named(node: &Node, text: &str) -> Result<LacquerMaterial> {
    if Path::new(text).extension().is_none() {
        if let Ok(preset) = LacquerMaterial::preset(text.trim()) {
            return Ok(preset);
        }
    }
    let path = doc::resolve_path(&node.at, text);
    located(&node.at, load_material_file(&path))
}

/// `material = "file.toml"` or a table: `file` or `preset` to start from, then SPEC keys.
fn material(node: &Node) -> Result<LacquerMaterial> {
    if let Value::Str(text) = &node.value {
        return material_named(node, text);
    }
    let mut valid = vec!["file", "preset"];
    valid.extend_from_slice(MATERIAL_KEYS);
    let entries = table(node, "the material", &valid)?;
    let get = |key: &str| entries.iter().find(|e| e.key == key).map(|e| &e.node);
    let mut material = match (get("file"), get("preset")) {
        (Some(file), Some(preset)) => {
            // At the override that added the second start (a sweep of `preset` over a scene's
            // `material = "red.toml"`), else at the file.
            let at = match (&preset.at, &file.at) {
                (at @ Origin::Override { .. }, _) | (_, at) => at,
            };
            return Err(at.error(format!(
                "a material starts from `file` or from `preset`, not both (file {}, preset {})",
                show(file),
                show(preset)
            )));
        }
        (Some(file), None) => material_named(file, string(file, "file")?)?,
        (None, Some(preset)) => located(
            &preset.at,
            LacquerMaterial::preset(string(preset, "preset")?),
        )?,
        (None, None) => LacquerMaterial::default(),
    };
    for e in entries
        .iter()
        .filter(|e| e.key != "file" && e.key != "preset")
    {
        let n = &e.node;
        let value = match (e.key.as_str(), &n.value) {
            ("kd", Value::Array(_)) => MaterialValue::Rgb(vec3(n, "kd")?.to_array()),
            ("extrapolate_g", Value::Bool(b)) => MaterialValue::Bool(*b),
            ("fresnel", Value::Str(path)) => {
                let resolved = doc::resolve_path(&n.at, path);
                located(&n.at, FresnelTable::from_csv_file(&resolved))?;
                MaterialValue::Path(Some(resolved))
            }
            ("kd", _) => {
                return Err(n
                    .at
                    .error(format!("`kd` must be [r, g, b], found {}", show(n))))
            }
            ("extrapolate_g", _) | ("fresnel", _) => {
                return Err(n.at.error(format!(
                    "`{}` must be {}, found {}",
                    e.key,
                    if e.key == "fresnel" {
                        "a string (a CSV path)"
                    } else {
                        "true or false"
                    },
                    show(n)
                )))
            }
            (key, _) => MaterialValue::Number(number(n, key)?),
        };
        located(&n.at, material.set_value(&e.key, value))?;
    }
    // A rule tying fields together points at the failing field if this table set it.
    material.validate().map_err(|e| {
        let field = match &e {
            Error::InvalidParameter { field, .. } => field.as_str(),
            _ => "",
        };
        get(field).map_or(&node.at, |n| &n.at).error(e)
    })?;
    Ok(material)
}
