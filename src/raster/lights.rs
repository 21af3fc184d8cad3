//! Punctual lights of SPEC §4 (directional and point), their CLI syntax and the default rig.
//!
//! Owns what a light is and the irradiance it delivers at a point; the GPU draw packs the same
//! values into its uniform buffer and the oracle calls [`Light::incident_at`]. Environment
//! lighting lives in `environment/`, not here.

use std::fmt;

use glam::DVec3;

use crate::model::limits;
use crate::{Error, Result};

/// One punctual light. Colours are linear Rec.709 RGB.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// `to_light` is the unit vector towards the light; `irradiance` is E at normal incidence.
    Directional { to_light: DVec3, irradiance: DVec3 },
    /// `intensity` is I per steradian; the irradiance at distance d is E = I / d².
    Point { position: DVec3, intensity: DVec3 },
}

/// The most lights one draw takes (the size of the shader's light array).
pub use crate::gpu::shaders::interface::MAX_LIGHTS;

const SYNTAX: &str = "expected `dir:x,y,z:r,g,b` (direction towards the light, irradiance) or \
                      `point:x,y,z:r,g,b` (position, intensity per steradian), e.g. dir:0,1,1:3,3,3";

impl Light {
    /// Parses the CLI syntax `dir:x,y,z:r,g,b` (direction towards the light, normalised here;
    /// irradiance E) or `point:x,y,z:r,g,b` (position; intensity I), then validates it.
    pub fn parse(spec: &str) -> Result<Self> {
        let parts: Vec<&str> = spec.trim().split(':').collect();
        let [kind, vector, colour] = parts[..] else {
            return Err(Error::invalid(
                "light",
                spec,
                format!(
                    "needs three `:`-separated parts, found {}; {SYNTAX}",
                    parts.len()
                ),
            ));
        };
        let kind = kind.trim();
        let (vector_name, colour_name) = match kind {
            "dir" => ("direction", "irradiance"),
            "point" => ("position", "intensity"),
            _ => {
                return Err(Error::invalid(
                    "light",
                    spec,
                    format!("unknown light kind `{kind}` (valid: dir, point); {SYNTAX}"),
                ))
            }
        };
        let vector = parse_triple(spec, vector_name, vector)?;
        let colour = parse_triple(spec, colour_name, colour)?;
        let light = if kind == "dir" {
            // Scaling by the largest component first keeps huge inputs from overflowing the
            // length; a zero or non-finite vector is kept as given for validate() to report.
            let to_light = (vector / vector.abs().max_element())
                .try_normalize()
                .unwrap_or(vector);
            Light::Directional {
                to_light,
                irradiance: colour,
            }
        } else {
            Light::Point {
                position: vector,
                intensity: colour,
            }
        };
        light.validate().map_err(|e| match e {
            Error::InvalidParameter { field, reason, .. } => Error::InvalidParameter {
                field,
                value: spec.to_string(),
                reason: format!("{reason}; {SYNTAX}"),
            },
            other => other,
        })?;
        Ok(light)
    }

    /// Finite values, colours >= 0 in every channel, a non-zero direction.
    pub fn validate(&self) -> Result<()> {
        let (vector_field, vector, colour_field, colour) = match *self {
            Light::Directional {
                to_light,
                irradiance,
            } => ("light.direction", to_light, "light.irradiance", irradiance),
            Light::Point {
                position,
                intensity,
            } => ("light.position", position, "light.intensity", intensity),
        };
        if let Some(reason) = limits::coordinate_problem(vector) {
            return Err(Error::invalid(vector_field, format_triple(vector), reason));
        }
        if matches!(self, Light::Directional { .. }) && vector.length() == 0.0 {
            return Err(Error::invalid(
                vector_field,
                format_triple(vector),
                "the direction towards the light must be non-zero",
            ));
        }
        if let Some(reason) = colour
            .to_array()
            .into_iter()
            .find_map(limits::light_level_problem)
        {
            return Err(Error::invalid(colour_field, format_triple(colour), reason));
        }
        Ok(())
    }

    /// Unit vector towards the light and the irradiance at normal incidence at `p`;
    /// `None` when `p` is at the point light (no direction) or the direction is zero.
    pub fn incident_at(&self, p: DVec3) -> Option<(DVec3, DVec3)> {
        match *self {
            Light::Directional {
                to_light,
                irradiance,
            } => Some((to_light.try_normalize()?, irradiance)),
            Light::Point {
                position,
                intensity,
            } => {
                let offset = position - p;
                let distance_squared = offset.length_squared();
                if distance_squared == 0.0 {
                    return None;
                }
                // Inverse-square law of SPEC §4: E = I / d².
                Some((offset.try_normalize()?, intensity / distance_squared))
            }
        }
    }
}

impl fmt::Display for Light {
    /// The CLI syntax [`Light::parse`] reads; f64 `Display` is the shortest exact form, so the
    /// text parses back to the same numbers.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Light::Directional {
                to_light,
                irradiance,
            } => write!(
                f,
                "dir:{}:{}",
                format_triple(to_light),
                format_triple(irradiance)
            ),
            Light::Point {
                position,
                intensity,
            } => write!(
                f,
                "point:{}:{}",
                format_triple(position),
                format_triple(intensity)
            ),
        }
    }
}

/// The default scene's rig, for the unit sphere seen from (0, 0, 4): a warm key from the upper
/// left front, a dim cool fill from the right, and a point rim light behind and above that
/// draws the silhouette where lacquer's Fresnel reflectance rises.
pub fn default_lights() -> Vec<Light> {
    vec![
        Light::Directional {
            to_light: DVec3::new(-0.5, 0.7, 0.5).normalize(),
            irradiance: DVec3::new(3.0, 2.85, 2.6),
        },
        Light::Directional {
            to_light: DVec3::new(0.8, 0.1, 0.6).normalize(),
            irradiance: DVec3::new(0.35, 0.4, 0.5),
        },
        // About 4.3 units from the sphere's far side: E ≈ 32 / 18 ≈ 1.7 there.
        Light::Point {
            position: DVec3::new(1.5, 2.5, -3.0),
            intensity: DVec3::new(30.0, 31.0, 34.0),
        },
    ]
}

fn parse_triple(spec: &str, part: &str, text: &str) -> Result<DVec3> {
    let values: Vec<&str> = text.split(',').map(str::trim).collect();
    let numbers: Option<Vec<f64>> = values.iter().map(|v| v.parse::<f64>().ok()).collect();
    match numbers.as_deref() {
        Some(&[x, y, z]) => Ok(DVec3::new(x, y, z)),
        _ => Err(Error::invalid(
            "light",
            spec,
            format!("the {part} part `{text}` must be three comma-separated numbers; {SYNTAX}"),
        )),
    }
}

fn format_triple(v: DVec3) -> String {
    format!("{},{},{}", v.x, v.y, v.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reason_of(result: Result<Light>) -> (String, String) {
        match result {
            Err(Error::InvalidParameter { field, reason, .. }) => (field, reason),
            other => panic!("expected InvalidParameter, got {other:?}"),
        }
    }

    #[test]
    fn parse_directional_normalises_direction() {
        // (0, 3, 4) has length 5: exactly (0, 0.6, 0.8) up to one rounding each (1e-15).
        let light = Light::parse("dir:0,3,4:1,2,3").unwrap();
        let Light::Directional {
            to_light,
            irradiance,
        } = light
        else {
            panic!("{light:?}");
        };
        assert!((to_light - DVec3::new(0.0, 0.6, 0.8)).abs().max_element() < 1e-15);
        assert_eq!(irradiance, DVec3::new(1.0, 2.0, 3.0));
    }

    #[test]
    fn parse_point_keeps_position() {
        let light = Light::parse(" point: 1.5,-2,0.25 : 10,0,1e2 ").unwrap();
        assert_eq!(
            light,
            Light::Point {
                position: DVec3::new(1.5, -2.0, 0.25),
                intensity: DVec3::new(10.0, 0.0, 100.0),
            }
        );
    }

    #[test]
    fn display_parse_round_trips() {
        // Exact equality: Display prints the shortest representation that parses back
        // bit-exactly, and (0, 1, 0) normalises to itself exactly.
        let lights = [
            Light::Directional {
                to_light: DVec3::Y,
                irradiance: DVec3::new(0.1, 2.5, 1e-3),
            },
            Light::Point {
                position: DVec3::new(-1.25, 3.0e5, 0.1),
                intensity: DVec3::new(0.3, 0.0, 7.0),
            },
        ];
        for light in lights {
            assert_eq!(Light::parse(&light.to_string()).unwrap(), light);
        }
        // The default rig's directions are unit but not exactly: allow 2 ulp-scale drift.
        for light in default_lights() {
            let back = Light::parse(&light.to_string()).unwrap();
            match (light, back) {
                (
                    Light::Directional {
                        to_light: a,
                        irradiance: ea,
                    },
                    Light::Directional {
                        to_light: b,
                        irradiance: eb,
                    },
                ) => {
                    assert!((a - b).abs().max_element() < 1e-15);
                    assert_eq!(ea, eb);
                }
                (a, b) => assert_eq!(a, b),
            }
        }
    }

    #[test]
    fn parse_errors_name_the_wrong_part() {
        let cases = [
            ("dir:0,1,0", "three `:`-separated parts"),
            ("dir:0,1,0:1,1,1:extra", "three `:`-separated parts"),
            ("spot:0,1,0:1,1,1", "unknown light kind `spot`"),
            ("dir:0,1:1,1,1", "direction part `0,1`"),
            ("dir:0,1,x:1,1,1", "direction part `0,1,x`"),
            ("point:0,1,0,2:1,1,1", "position part"),
            ("dir:0,1,0:1,1", "irradiance part `1,1`"),
            ("point:0,1,0:a,1,1", "intensity part"),
            ("dir:0,0,0:1,1,1", "non-zero"),
            ("dir:0,nan,1:1,1,1", "finite"),
            ("point:inf,0,0:1,1,1", "finite"),
            ("dir:0,1,0:1,-1,1", "in [0, 1e20]"),
            ("point:0,1,0:1,1,nan", "in [0, 1e20]"),
            ("dir:0,1,0:1,1e21,1", "in [0, 1e20]"),
            ("point:0,1e16,0:1,1,1", "within ±1e15"),
        ];
        for (spec, expected) in cases {
            let (field, reason) = reason_of(Light::parse(spec));
            assert!(field.starts_with("light"), "{spec}: field {field}");
            assert!(
                reason.contains(expected),
                "{spec}: reason `{reason}` lacks `{expected}`"
            );
            assert!(
                reason.contains("dir:x,y,z:r,g,b"),
                "{spec}: no syntax shown"
            );
        }
    }

    #[test]
    fn point_light_follows_inverse_square() {
        // I = (8, 4, 2) at (0, 2, 0) seen from the origin: d = 2, E = I/4, L = +Y exactly.
        let light = Light::Point {
            position: DVec3::new(0.0, 2.0, 0.0),
            intensity: DVec3::new(8.0, 4.0, 2.0),
        };
        let (l, e) = light.incident_at(DVec3::ZERO).unwrap();
        assert_eq!(l, DVec3::Y);
        assert_eq!(e, DVec3::new(2.0, 1.0, 0.5));
        assert!(light.incident_at(DVec3::new(0.0, 2.0, 0.0)).is_none());
    }

    #[test]
    fn directional_light_is_the_same_everywhere() {
        let light = Light::Directional {
            to_light: DVec3::X,
            irradiance: DVec3::ONE,
        };
        for p in [DVec3::ZERO, DVec3::new(5.0, -3.0, 100.0)] {
            assert_eq!(light.incident_at(p), Some((DVec3::X, DVec3::ONE)));
        }
    }

    #[test]
    fn default_lights_are_valid_and_fit() {
        let lights = default_lights();
        assert!(!lights.is_empty() && lights.len() <= MAX_LIGHTS);
        for light in &lights {
            light.validate().unwrap();
            if let Light::Directional { to_light, .. } = light {
                // Unit to 1e-15: normalised once in f64.
                assert!((to_light.length() - 1.0).abs() < 1e-15);
            }
        }
    }
}
