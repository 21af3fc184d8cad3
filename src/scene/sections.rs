//! The scene sections that hold no meshes or materials: `[[light]]`, `[environment]`, `[render]` and
//! `[output]` (docs/scene.md). Split from [`super::parse`], whose helpers and rules they share.

use glam::DVec3;

use super::doc::{self, Node, Value};
use super::parse::{
    boolean, format_of, located, located_at_field, number, show, string, table, vec3, whole,
    ENVIRONMENT_KEYS, LIGHT_KEYS, OUTPUT_KEYS, RENDER_KEYS,
};
use super::{EnvironmentLight, EnvironmentSource, EnvironmentSpec, OutputSpec, RenderSpec};
use crate::environment::load::BUILTIN_STUDIO;
use crate::environment::EnvironmentModel;
use crate::output::ToneCurve;
use crate::raster::draw::{Background, SUPPORTED_SAMPLES};
use crate::raster::draw::{MAX_BOUNCES, MAX_RAYS};
use crate::raster::lights::Light;
use crate::text::builtin_name;
use crate::Result;

/// The keys of a directional light besides `kind`.
const DIR_KEYS: &[&str] = &["to_light", "irradiance"];
/// The keys of a point light besides `kind`.
const POINT_KEYS: &[&str] = &["position", "intensity"];

/// `[[light]]`: `kind = "dir"` (to_light, irradiance) or `"point"` (position, intensity).
pub(super) fn light(node: &Node) -> Result<Light> {
    let entries = table(node, "[[light]]", LIGHT_KEYS)?;
    let get = |key: &str| entries.iter().find(|e| e.key == key).map(|e| &e.node);
    let missing = |key: &str, kind: &str| node.at.error(format!("a {kind} light needs `{key}`"));
    let colour = |n: &Node, key: &str| match n.value {
        Value::Array(_) => vec3(n, key),
        _ => number(n, key).map(DVec3::splat),
    };
    let kind = get("kind").map(|n| string(n, "kind")).transpose()?;
    let kind = kind.unwrap_or("dir").to_ascii_lowercase();
    let kind = kind.as_str();
    // A key of the other kind was ignored, so a light written as one kind with the other's keys
    // drew with values the author never wrote (or failed on a missing key without saying why).
    let (takes, other_kind, other_keys) = match kind {
        "dir" | "directional" => ("`to_light` and `irradiance`", "point", POINT_KEYS),
        "point" => ("`position` and `intensity`", "dir", DIR_KEYS),
        _ => ("", "", &[][..]),
    };
    if let Some(e) = entries
        .iter()
        .find(|e| other_keys.contains(&e.key.as_str()))
    {
        return Err(e.key_at.error(format!(
            "`{}` is a key of a {other_kind:?} light, and this light's kind is {kind:?}, which \
             takes {takes}; remove `{}`, or write kind = {other_kind:?}",
            e.key, e.key
        )));
    }
    let light = match kind {
        "dir" | "directional" => {
            let to = get("to_light").ok_or_else(|| missing("to_light", "dir"))?;
            let e = get("irradiance").ok_or_else(|| missing("irradiance", "dir"))?;
            let to_light = vec3(to, "to_light")?;
            if to_light.length() == 0.0 {
                return Err(to.at.error("`to_light` must not be the zero vector"));
            }
            Light::Directional {
                to_light: to_light.normalize(),
                irradiance: colour(e, "irradiance")?,
            }
        }
        "point" => {
            let p = get("position").ok_or_else(|| missing("position", "point"))?;
            let i = get("intensity").ok_or_else(|| missing("intensity", "point"))?;
            Light::Point {
                position: vec3(p, "position")?,
                intensity: colour(i, "intensity")?,
            }
        }
        other => {
            let at = get("kind").map_or(&node.at, |n| &n.at);
            return Err(at.error(format!(
                "unknown light kind {other:?}; valid: \"dir\" (to_light, irradiance) or \"point\" \
                 (position, intensity)"
            )));
        }
    };
    let written = [("direction", "to_light")];
    located_at_field(&node.at, entries, &written, light.validate())?;
    Ok(light)
}

/// `[environment]` or `environment = "none" | "builtin:studio" | "path.hdr"`.
pub(super) fn environment(node: &Node) -> Result<EnvironmentSpec> {
    let (mut source, mut intensity, mut rotation_deg) = (None, 1.0, 0.0);
    let mut intensity_at = &node.at;
    if let Value::Str(_) = node.value {
        source = Some(node);
    } else {
        for e in table(node, "[environment]", ENVIRONMENT_KEYS)? {
            match e.key.as_str() {
                "source" => source = Some(&e.node),
                "intensity" => {
                    intensity = number(&e.node, "intensity")?;
                    intensity_at = &e.node.at;
                }
                _ => rotation_deg = number(&e.node, "rotation_deg")?,
            }
        }
    }
    if intensity < 0.0 {
        return Err(intensity_at.error(format!("`intensity` must be ≥ 0, found {intensity}")));
    }
    let light = EnvironmentLight {
        intensity,
        rotation_deg,
    };
    // docs/scene.md: `source` defaults to builtin:studio, as a scene without the section does;
    // so `[environment]` with only `intensity` (or `--set environment.intensity=…` on a scene
    // without the section, which creates that table) dims the studio.
    let Some(source) = source else {
        return Ok(EnvironmentSpec::Map {
            source: EnvironmentSource::Named(BUILTIN_STUDIO.to_string()),
            light,
        });
    };
    let spec = string(source, "source")?;
    if spec.eq_ignore_ascii_case("none") {
        return Ok(EnvironmentSpec::None);
    }
    let resolved = if builtin_name(spec).is_some() {
        if !spec.eq_ignore_ascii_case(BUILTIN_STUDIO) {
            return Err(source.at.error(format!(
                "unknown built-in environment {spec:?}; valid: {}",
                BUILTIN_STUDIO
            )));
        }
        BUILTIN_STUDIO.to_string()
    } else {
        let path = doc::resolve_path(&source.at, spec);
        if !path.is_file() {
            // An I/O failure at this line (the C API's IO_ERROR), as a missing mesh is.
            let missing = std::io::Error::new(
                std::io::ErrorKind::NotFound,
                "it does not exist (relative paths resolve against the file that names them)",
            );
            return Err(source.at.locate(crate::Error::Read {
                path: path.clone(),
                source: missing,
            }));
        }
        path.display().to_string()
    };
    Ok(EnvironmentSpec::Map {
        source: EnvironmentSource::Named(resolved),
        light,
    })
}

/// `"WxH"`, both whole numbers in 1..=16384.
fn size_text(node: &Node, s: &str) -> Result<(u32, u32)> {
    let parsed = s.split_once(['x', 'X']).and_then(|(w, h)| {
        let w: u32 = w.trim().parse().ok()?;
        let h: u32 = h.trim().parse().ok()?;
        ((1..=16384).contains(&w) && (1..=16384).contains(&h)).then_some((w, h))
    });
    parsed.ok_or_else(|| {
        node.at.error(format!(
            "`size` must be \"WxH\" with whole numbers in 1..=16384, e.g. \"1024x768\"; found {s:?}"
        ))
    })
}

/// `[render]`: how light is computed.
pub(super) fn render(node: &Node) -> Result<RenderSpec> {
    let mut spec = RenderSpec::default();
    for e in table(node, "[render]", RENDER_KEYS)? {
        match e.key.as_str() {
            "shadows" => spec.shadows = boolean(&e.node, "shadows")?,
            "ray_tracing" => spec.ray_tracing = boolean(&e.node, "ray_tracing")?,
            "bounces" => spec.bounces = whole(&e.node, "bounces", 0..=MAX_BOUNCES)?,
            "rays" => spec.rays = whole(&e.node, "rays", 1..=MAX_RAYS)?,
            "seed" => spec.seed = whole(&e.node, "seed", 0..=u32::MAX)?,
            "denoise" => spec.denoise = boolean(&e.node, "denoise")?,
            _ => {
                let text = string(&e.node, "environment_model")?;
                spec.environment_model = EnvironmentModel::from_name(text).ok_or_else(|| {
                    e.node.at.error(format!(
                        "`environment_model` must be {}, found {text:?}",
                        EnvironmentModel::choices()
                    ))
                })?;
            }
        }
    }
    Ok(spec)
}

/// `[output]`.
pub(super) fn output(node: &Node) -> Result<OutputSpec> {
    let mut out = OutputSpec::default();
    for e in table(node, "[output]", OUTPUT_KEYS)? {
        let n = &e.node;
        match e.key.as_str() {
            "size" => {
                (out.width, out.height) = match &n.value {
                    Value::Str(s) => size_text(n, s)?,
                    Value::Array(items) if items.len() == 2 => (
                        whole(&items[0], "size", 1..=16384)?,
                        whole(&items[1], "size", 1..=16384)?,
                    ),
                    _ => {
                        return Err(n.at.error(format!(
                            "`size` must be \"WxH\" or [W, H], found {}",
                            show(n)
                        )))
                    }
                }
            }
            "width" => out.width = whole(n, "width", 1..=16384)?,
            "height" => out.height = whole(n, "height", 1..=16384)?,
            "samples" => {
                out.samples = whole(n, "samples", 1..=4)?;
                if !SUPPORTED_SAMPLES.contains(&out.samples) {
                    return Err(n.at.error(format!(
                        "`samples` must be one of {SUPPORTED_SAMPLES:?}, found {}",
                        out.samples
                    )));
                }
            }
            "exposure" => out.exposure_ev = number(n, "exposure")? as f32,
            "tonemap" => {
                out.tone_curve = located(&n.at, string(n, "tonemap")?.parse::<ToneCurve>())?
            }
            "format" => {
                format_of(n)?;
            }
            _ => {
                out.background = match &n.value {
                    Value::Str(s) if s.eq_ignore_ascii_case("env") => Background::Environment,
                    Value::Str(s) if s.eq_ignore_ascii_case("transparent") => {
                        Background::Transparent
                    }
                    Value::Array(_) => {
                        let c = vec3(n, "background")?;
                        if c.min_element() < 0.0 {
                            return Err(n.at.error("`background` colour components must be ≥ 0"));
                        }
                        Background::Color([c.x as f32, c.y as f32, c.z as f32])
                    }
                    _ => {
                        return Err(n.at.error(format!(
                            "`background` must be \"env\", \"transparent\" or a linear colour \
                             [r, g, b], found {}",
                            show(n)
                        )))
                    }
                }
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::scene::{Scene, SceneDocument};
    use crate::Error;

    fn build(text: &str) -> Result<Scene> {
        SceneDocument::parse(text, "test.toml", Path::new(""))?.build()
    }

    /// The line and message of a scene that must fail to build.
    fn parse_error(text: &str) -> (usize, String) {
        match build(text) {
            Err(Error::Parse { line, message, .. }) => (line, message),
            Err(other) => panic!("expected a parse error for {text:?}, got {other}"),
            Ok(_) => panic!("expected a parse error for {text:?}, got a scene"),
        }
    }

    fn studio(intensity: f64, rotation_deg: f64) -> EnvironmentSpec {
        EnvironmentSpec::Map {
            source: EnvironmentSource::Named(BUILTIN_STUDIO.to_string()),
            light: EnvironmentLight {
                intensity,
                rotation_deg,
            },
        }
    }

    #[test]
    fn environment_table_without_source_is_the_studio() {
        // docs/scene.md: `source` defaults to builtin:studio, like a scene without the section.
        let scene = build("[environment]\nintensity = 0.5\nrotation_deg = 30\n")
            .expect("[environment] without source builds");
        assert_eq!(scene.environment, studio(0.5, 30.0));
        let scene = build("[environment]\n").expect("an empty [environment] builds");
        assert_eq!(scene.environment, studio(1.0, 0.0));
    }

    #[test]
    fn set_environment_intensity_without_the_section_dims_the_studio() {
        let mut document = SceneDocument::parse("", "test.toml", Path::new("")).expect("parses");
        assert_eq!(
            document.build().expect("builds").environment,
            studio(1.0, 0.0)
        );
        document
            .set("environment.intensity=0.5", Path::new(""))
            .expect("--set applies");
        assert_eq!(
            document.build().expect("builds").environment,
            studio(0.5, 0.0)
        );
    }

    #[test]
    fn keys_of_the_other_light_kind_are_refused_at_their_line() {
        let cases = [
            (
                "[[light]]\nkind = \"dir\"\nto_light = [0, 1, 0]\nirradiance = 1\nintensity = 2\n",
                5,
                "`intensity` is a key of a \"point\" light, and this light's kind is \"dir\", \
                 which takes `to_light` and `irradiance`",
            ),
            (
                // No kind is "dir" (docs/scene.md).
                "[[light]]\nposition = [0, 1, 0]\nto_light = [0, 1, 0]\nirradiance = 1\n",
                2,
                "`position` is a key of a \"point\" light",
            ),
            (
                "[[light]]\nkind = \"point\"\nposition = [0, 2, 0]\nintensity = 1\n\
                 to_light = [0, 1, 0]\n",
                5,
                "`to_light` is a key of a \"dir\" light, and this light's kind is \"point\", \
                 which takes `position` and `intensity`; remove `to_light`, or write kind = \"dir\"",
            ),
            (
                "[[light]]\nkind = \"point\"\nirradiance = [1, 1, 1]\nposition = [0, 2, 0]\n",
                3,
                "`irradiance` is a key of a \"dir\" light",
            ),
        ];
        for (text, line, needle) in cases {
            let (got_line, message) = parse_error(text);
            assert_eq!(got_line, line, "{text:?}: {message}");
            assert!(
                message.contains(needle),
                "{text:?}: `{message}` lacks `{needle}`"
            );
        }
    }

    #[test]
    fn lights_with_their_own_keys_still_build() {
        let scene = build(
            "[[light]]\nkind = \"dir\"\nto_light = [0, 2, 0]\nirradiance = 1\n\n\
             [[light]]\nkind = \"point\"\nposition = [0, 2, 0]\nintensity = [1, 2, 3]\n",
        )
        .expect("both lights build");
        assert_eq!(
            scene.lights,
            vec![
                Light::Directional {
                    to_light: DVec3::Y,
                    irradiance: DVec3::ONE,
                },
                Light::Point {
                    position: DVec3::new(0.0, 2.0, 0.0),
                    intensity: DVec3::new(1.0, 2.0, 3.0),
                },
            ]
        );
    }
}
