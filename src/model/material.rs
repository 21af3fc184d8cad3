//! A lacquer material: the parameters of SPEC §2 (BRDF), §3 (Fresnel source, lacquer IOR) and
//! §4 (view-dependent environment blur), the paper's presets, text setters for the CLI and
//! config files, and validation with messages that state the valid range.
//!
//! Owns the parameter rules; it does not evaluate the BRDF ([`super::brdf`]) or build tables
//! itself ([`super::fresnel`]).

use std::path::PathBuf;

use super::brdf::BrdfParams;
use super::fresnel::{check_ior, FresnelTable, DEFAULT_IOR_A, DEFAULT_IOR_B};
use super::limits;
use crate::text::nearest;
// Only for the scene loader's imports until they name `crate::text`.
use crate::{Error, Result};

/// One lacquer material. Field names follow the paper; the text keys of [`LacquerMaterial::set`]
/// are noted on each field.
#[derive(Clone, Debug, PartialEq)]
pub struct LacquerMaterial {
    /// Beckmann RMS slope m, in (0, 1]. Key `m`.
    pub beckmann_m: f64,
    /// a of f(N·V) = a + b·N·V. Key `a`.
    pub diffuse_a: f64,
    /// b of f(N·V) = a + b·N·V. Key `b`.
    pub diffuse_b: f64,
    /// (c0, c1, c2) of g(r) = c0 + c1·r + c2·r². Keys `c0`, `c1`, `c2`.
    pub lacquer_law: [f64; 3],
    /// r, lacquer : colorant ratio relative to the least-lacquer sample. Key `r`.
    pub lacquer_ratio: f64,
    /// k_d, colorant albedo, linear RGB in [0, 1]. Key `kd` (value "r,g,b").
    pub albedo: [f64; 3],
    /// Allow r outside the fitted domain [1, r*]. Key `extrapolate_g`.
    pub extrapolate_g: bool,
    /// A of n(λ) = A + B/λ². Key `ior_a`.
    pub ior_a: f64,
    /// B of n(λ) = A + B/λ² [µm²]. Key `ior_b`.
    pub ior_b: f64,
    /// A Fresnel CSV (RGB or spectral); None → the dielectric table. Key `fresnel` ("" → None).
    pub fresnel_file: Option<PathBuf>,
    /// β at normal view (SPEC §4). Key `beta_normal`.
    pub beta_normal: f64,
    /// β at grazing view (SPEC §4). Key `beta_grazing`.
    pub beta_grazing: f64,
    /// p of β(nv) = β_grazing + (β_normal - β_grazing)·nv^p. Key `beta_power`.
    pub beta_power: f64,
}

/// Every preset name; `smooth` and `rough` alone mean the black colorant (SPEC §2).
#[rustfmt::skip]
pub const PRESET_NAMES: &[&str] = &[
    "smooth", "rough", "smooth-black", "smooth-red", "rough-black", "rough-red",
];

/// Every key [`LacquerMaterial::set`] accepts, in field order.
#[rustfmt::skip]
pub const MATERIAL_KEYS: &[&str] = &[
    "m", "a", "b", "c0", "c1", "c2", "r", "kd", "extrapolate_g", "ior_a", "ior_b", "fresnel",
    "beta_normal", "beta_grazing", "beta_power",
];

/// A field's value as typed data, for [`LacquerMaterial::set_value`]; [`LacquerMaterial::set`]
/// parses the CLI's `KEY=VALUE` text into one.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialValue {
    /// m, a, b, c0, c1, c2, r, ior_a, ior_b, beta_normal, beta_grazing, beta_power.
    Number(f64),
    /// kd.
    Rgb([f64; 3]),
    /// extrapolate_g.
    Bool(bool),
    /// fresnel: a CSV path, or `None` for the dielectric table.
    Path(Option<PathBuf>),
}

/// g(r) coefficients fitted by the paper, shared by both finishes (SPEC §2).
const PAPER_LACQUER_LAW: [f64; 3] = [1.22, -0.224, 0.0199];
/// Colorant albedos (SPEC §2): kuro-urushi and shu-urushi.
const BLACK_ALBEDO: [f64; 3] = [0.02, 0.02, 0.02];
const RED_ALBEDO: [f64; 3] = [0.50, 0.06, 0.03];

/// The finish-dependent parameters of a preset (SPEC §2 and §4 tables).
struct Finish {
    beckmann_m: f64,
    diffuse_a: f64,
    diffuse_b: f64,
    beta_normal: f64,
    beta_grazing: f64,
    beta_power: f64,
}

const SMOOTH: Finish = Finish {
    beckmann_m: 0.05,
    diffuse_a: -0.03,
    diffuse_b: 1.05,
    beta_normal: 0.10,
    beta_grazing: 0.10,
    beta_power: 1.0,
};

const ROUGH: Finish = Finish {
    beckmann_m: 0.20,
    diffuse_a: 0.01,
    diffuse_b: 0.96,
    beta_normal: 0.60,
    beta_grazing: 0.05,
    beta_power: 1.0,
};

impl LacquerMaterial {
    /// The preset `name` (one of [`PRESET_NAMES`]).
    pub fn preset(name: &str) -> Result<Self> {
        let lower = name.to_ascii_lowercase();
        let (finish, colorant) = lower.split_once('-').unwrap_or((&lower, "black"));
        let finish = match finish {
            "smooth" => Some(&SMOOTH),
            "rough" => Some(&ROUGH),
            _ => None,
        };
        let albedo = match colorant {
            "black" => Some(BLACK_ALBEDO),
            "red" => Some(RED_ALBEDO),
            _ => None,
        };
        match (finish, albedo) {
            (Some(finish), Some(albedo)) => Ok(Self::with_finish(finish, albedo)),
            _ => Err(Error::invalid(
                "preset",
                name,
                one_of("preset", PRESET_NAMES, name),
            )),
        }
    }

    /// A preset finish with a colorant; everything else at the paper's values.
    fn with_finish(finish: &Finish, albedo: [f64; 3]) -> Self {
        LacquerMaterial {
            beckmann_m: finish.beckmann_m,
            diffuse_a: finish.diffuse_a,
            diffuse_b: finish.diffuse_b,
            lacquer_law: PAPER_LACQUER_LAW,
            lacquer_ratio: 1.0,
            albedo,
            extrapolate_g: false,
            ior_a: DEFAULT_IOR_A,
            ior_b: DEFAULT_IOR_B,
            fresnel_file: None,
            beta_normal: finish.beta_normal,
            beta_grazing: finish.beta_grazing,
            beta_power: finish.beta_power,
        }
    }

    /// Parses `value` into the field named by `key` (one of [`MATERIAL_KEYS`]) and checks that
    /// field's own range. On error the material is unchanged. Rules that tie fields together
    /// (r within [1, r*] of the current c, g(r) ≥ 0) are left to [`LacquerMaterial::validate`],
    /// so that keys may be set in any order.
    pub fn set(&mut self, key: &str, value: &str) -> Result<()> {
        let typed = match key {
            "kd" => MaterialValue::Rgb(parse_albedo(value)?),
            "extrapolate_g" => MaterialValue::Bool(match value.trim() {
                "true" | "1" => true,
                "false" | "0" => false,
                _ => return Err(Error::invalid(key, value, "must be `true` or `false`")),
            }),
            "fresnel" => {
                let path = value.trim();
                MaterialValue::Path((!path.is_empty()).then(|| PathBuf::from(path)))
            }
            _ if MATERIAL_KEYS.contains(&key) => MaterialValue::Number(parse_number(key, value)?),
            _ => return Err(unknown_key(key)),
        };
        self.set_value(key, typed)
    }

    /// [`set`](Self::set) for a value that is already typed (a scene file's TOML number, array
    /// or boolean; a C caller's double), so that a number is never printed and parsed again.
    /// The same checks, the same messages.
    pub fn set_value(&mut self, key: &str, value: MaterialValue) -> Result<()> {
        use MaterialValue::{Bool, Number, Path, Rgb};
        if !MATERIAL_KEYS.contains(&key) {
            return Err(unknown_key(key));
        }
        let value = match value {
            Number(x) => Number(finite_number(key, x)?),
            Rgb(kd) => Rgb([
                finite_number("kd", kd[0])?,
                finite_number("kd", kd[1])?,
                finite_number("kd", kd[2])?,
            ]),
            other => other,
        };
        match (key, value) {
            ("m", Number(x)) => self.beckmann_m = checked_beckmann_m(x)?,
            ("a", Number(x)) => self.diffuse_a = checked_coefficient(key, x)?,
            ("b", Number(x)) => self.diffuse_b = checked_coefficient(key, x)?,
            ("c0", Number(x)) => self.lacquer_law[0] = checked_coefficient(key, x)?,
            ("c1", Number(x)) => self.lacquer_law[1] = checked_coefficient(key, x)?,
            ("c2", Number(x)) => self.lacquer_law[2] = checked_coefficient(key, x)?,
            ("r", Number(x)) => self.lacquer_ratio = x,
            ("kd", Rgb(kd)) => self.albedo = checked_albedo(kd)?,
            ("extrapolate_g", Bool(b)) => self.extrapolate_g = b,
            ("ior_a", Number(ior_a)) => {
                check_ior(ior_a, self.ior_b.max(0.0))?;
                self.ior_a = ior_a;
            }
            ("ior_b", Number(ior_b)) => {
                check_ior(self.ior_a.max(1.0), ior_b)?;
                self.ior_b = ior_b;
            }
            ("fresnel", Path(path)) => self.fresnel_file = path,
            ("beta_normal", Number(x)) => self.beta_normal = checked_blur(key, x)?,
            ("beta_grazing", Number(x)) => self.beta_grazing = checked_blur(key, x)?,
            ("beta_power", Number(x)) => self.beta_power = checked_positive(key, x)?,
            (_, value) => {
                let wanted = match key {
                    "kd" => "three numbers [r, g, b]",
                    "extrapolate_g" => "true or false",
                    "fresnel" => "a path",
                    _ => "a number",
                };
                return Err(Error::invalid(
                    key,
                    format!("{value:?}"),
                    format!("must be {wanted}"),
                ));
            }
        }
        Ok(())
    }

    /// Every rule of SPEC §2 (and the ranges of §3–4 fields); the first broken one is the error.
    pub fn validate(&self) -> Result<()> {
        checked_beckmann_m(self.beckmann_m)?;
        checked_coefficient("a", self.diffuse_a)?;
        checked_coefficient("b", self.diffuse_b)?;
        for (key, c) in ["c0", "c1", "c2"].iter().zip(self.lacquer_law) {
            checked_coefficient(key, c)?;
        }
        checked_albedo(self.albedo)?;
        self.check_lacquer_ratio()?;
        check_ior(self.ior_a, self.ior_b)?;
        checked_blur("beta_normal", self.beta_normal)?;
        checked_blur("beta_grazing", self.beta_grazing)?;
        checked_positive("beta_power", self.beta_power)?;
        Ok(())
    }

    /// g(r) = c0 + c1·r + c2·r² (Horner form).
    pub fn lacquer_g(&self) -> f64 {
        let [c0, c1, c2] = self.lacquer_law;
        let r = self.lacquer_ratio;
        c0 + r * (c1 + c2 * r)
    }

    /// r* = -c1/(2·c2), where g turns upward (≈ 5.63 for the paper's fit). When c2 <= 0, g has no
    /// minimum (it is linear or concave), nothing turns upward, and the only upper limit is g ≥ 0,
    /// which [`LacquerMaterial::validate`] checks separately: f64::INFINITY.
    pub fn lacquer_ratio_max(&self) -> f64 {
        let [_, c1, c2] = self.lacquer_law;
        if c2 > 0.0 {
            -c1 / (2.0 * c2)
        } else {
            f64::INFINITY
        }
    }

    /// Validates, then the BRDF's parameters with g(r) evaluated.
    pub fn brdf_params(&self) -> Result<BrdfParams> {
        self.validate()?;
        Ok(BrdfParams {
            beckmann_m: self.beckmann_m,
            diffuse_a: self.diffuse_a,
            diffuse_b: self.diffuse_b,
            lacquer_g: self.lacquer_g(),
            albedo: self.albedo,
        })
    }

    /// The table from `fresnel_file` if set, else the dielectric table for (ior_a, ior_b).
    pub fn fresnel_table(&self) -> Result<FresnelTable> {
        match &self.fresnel_file {
            Some(path) => FresnelTable::from_csv_file(path),
            None => FresnelTable::dielectric(self.ior_a, self.ior_b),
        }
    }

    /// r must be finite; in [1, r*] unless extrapolate_g; and g(r) must be ≥ 0 either way
    /// (a negative g would make the diffuse radiance negative).
    fn check_lacquer_ratio(&self) -> Result<()> {
        let r = self.lacquer_ratio;
        checked_finite("r", r)?;
        let r_max = self.lacquer_ratio_max();
        if !self.extrapolate_g && !(1.0..=r_max).contains(&r) {
            let reason = if r_max < 1.0 {
                format!(
                    "g(r) = c0 + c1·r + c2·r² has its minimum at r* = {r_max} < 1, so no r is in \
                     the fitted domain [1, r*]; fix c0, c1, c2 or set extrapolate_g = true"
                )
            } else if r_max.is_finite() {
                format!(
                    "must be in [1, {}] (the paper fitted g(r) from r = 1 up to its minimum \
                     r* = -c1/(2·c2)); use a value in that range or set extrapolate_g = true",
                    crate::error::show_number(r_max)
                )
            } else {
                // c2 <= 0: g has no minimum, so the fitted domain has no upper end.
                "must be at least 1 (the paper fitted g(r) from r = 1 upward); use r >= 1 or set \
                 extrapolate_g = true"
                    .to_string()
            };
            return Err(Error::invalid("r", r, reason));
        }
        let g = self.lacquer_g();
        if g.is_nan() || g < 0.0 {
            let reason = format!(
                "gives g(r) = {g} < 0, which would make the diffuse radiance negative; choose r \
                 (or c0, c1, c2) so that c0 + c1·r + c2·r² >= 0"
            );
            return Err(Error::invalid("r", r, reason));
        }
        Ok(())
    }
}

impl Default for LacquerMaterial {
    /// The preset `smooth-black`.
    fn default() -> Self {
        Self::with_finish(&SMOOTH, BLACK_ALBEDO)
    }
}

/// A finite number from text, or an error naming the key.
fn parse_number(key: &str, value: &str) -> Result<f64> {
    match value.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(Error::invalid(
            key,
            value,
            "must be a finite number (NaN and infinity are not allowed)",
        )),
        Err(_) => Err(Error::invalid(
            key,
            value,
            "is not a number; write a decimal number such as 0.5",
        )),
    }
}

/// "r,g,b" → three finite numbers.
fn parse_albedo(value: &str) -> Result<[f64; 3]> {
    let parts: Vec<&str> = value.split(',').collect();
    let [r, g, b] = parts.as_slice() else {
        return Err(Error::invalid(
            "kd",
            value,
            "must be three comma-separated numbers `r,g,b`, each in [0, 1]",
        ));
    };
    Ok([
        parse_number("kd", r)?,
        parse_number("kd", g)?,
        parse_number("kd", b)?,
    ])
}

/// The message [`parse_number`] gives a non-finite number, for numbers that arrive typed.
fn finite_number(key: &str, v: f64) -> Result<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::invalid(
            key,
            v,
            "must be a finite number (NaN and infinity are not allowed)",
        ))
    }
}

fn unknown_key(key: &str) -> Error {
    Error::invalid("material key", key, one_of("key", MATERIAL_KEYS, key))
}

fn checked_finite(key: &str, v: f64) -> Result<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::invalid(key, v, "must be a finite number"))
    }
}

/// A coefficient of the diffuse law: finite, and within what f32 carries
/// ([`limits::MAX_DIFFUSE_COEFFICIENT`]).
fn checked_coefficient(key: &str, v: f64) -> Result<f64> {
    checked_finite(key, v)?;
    if v.abs() <= limits::MAX_DIFFUSE_COEFFICIENT {
        Ok(v)
    } else {
        Err(Error::invalid(
            key,
            v,
            format!(
                "must be within ±{:e} (the paper's fits are within ±1.3)",
                limits::MAX_DIFFUSE_COEFFICIENT
            ),
        ))
    }
}

/// SPEC §2's (0, 1], from [`limits::MIN_BECKMANN_M`]: below it the device's f32 loses the lobe.
fn checked_beckmann_m(m: f64) -> Result<f64> {
    if (limits::MIN_BECKMANN_M..=1.0).contains(&m) {
        Ok(m)
    } else {
        Err(Error::invalid(
            "m",
            m,
            format!(
                "the Beckmann RMS slope must be in [{}, 1] (smooth lacquer 0.05, rough 0.20; \
                 SPEC §2's (0, 1], from the least m the renderer's f32 arithmetic resolves)",
                limits::MIN_BECKMANN_M
            ),
        ))
    }
}

fn checked_albedo(kd: [f64; 3]) -> Result<[f64; 3]> {
    if kd.iter().all(|c| (0.0..=1.0).contains(c)) {
        Ok(kd)
    } else {
        Err(Error::invalid(
            "kd",
            format!("{},{},{}", kd[0], kd[1], kd[2]),
            "each channel of the colorant albedo must be in [0, 1] \
             (black 0.02,0.02,0.02; red 0.5,0.06,0.03)",
        ))
    }
}

/// A blur width β of SPEC §4: finite and ≥ 0. β = 0 is the sharp layer 0 (SPEC's β_0), which
/// both the shader and the CPU twin read as layer 0 alone; an audit found 0 refused, 2026-12-06.
fn checked_blur(key: &str, v: f64) -> Result<f64> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(Error::invalid(
            key,
            v,
            "must be a finite blur width ≥ 0 (0: the sharp environment, SPEC §4's β_0; the \
             presets use 0.05 to 0.6)",
        ))
    }
}

fn checked_positive(key: &str, v: f64) -> Result<f64> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(Error::invalid(key, v, "must be a finite number > 0"))
    }
}

/// "valid <what>s: …; did you mean `x`?" for an unknown name.
fn one_of(what: &str, valid: &[&str], got: &str) -> String {
    let mut message = format!("valid {what}s are {}", valid.join(", "));
    if let Some(near) = nearest(valid, got) {
        message.push_str(&format!("; did you mean `{near}`?"));
    }
    message
}

#[cfg(test)]
mod tests {
    use super::*;

    fn invalid_field(result: Result<impl std::fmt::Debug>) -> (String, String) {
        match result {
            Err(Error::InvalidParameter { field, reason, .. }) => (field, reason),
            other => panic!("expected InvalidParameter, got {other:?}"),
        }
    }

    #[test]
    fn presets_hold_the_paper_values() {
        // SPEC §2 and §4 tables, typed from the spec.
        let s = LacquerMaterial::preset("smooth-red").unwrap();
        assert_eq!(
            (s.beckmann_m, s.diffuse_a, s.diffuse_b),
            (0.05, -0.03, 1.05)
        );
        assert_eq!(s.albedo, [0.50, 0.06, 0.03]);
        assert_eq!(
            (s.beta_normal, s.beta_grazing, s.beta_power),
            (0.10, 0.10, 1.0)
        );
        let r = LacquerMaterial::preset("rough-black").unwrap();
        assert_eq!((r.beckmann_m, r.diffuse_a, r.diffuse_b), (0.20, 0.01, 0.96));
        assert_eq!(r.albedo, [0.02, 0.02, 0.02]);
        assert_eq!(
            (r.beta_normal, r.beta_grazing, r.beta_power),
            (0.60, 0.05, 1.0)
        );
        for m in [&s, &r] {
            assert_eq!(m.lacquer_law, [1.22, -0.224, 0.0199]);
            assert_eq!((m.lacquer_ratio, m.ior_a, m.ior_b), (1.0, 1.5, 0.0045));
            assert!(!m.extrapolate_g && m.fresnel_file.is_none());
        }
        assert_eq!(
            LacquerMaterial::preset("smooth").unwrap(),
            LacquerMaterial::preset("smooth-black").unwrap()
        );
        assert_eq!(LacquerMaterial::preset("rough").unwrap(), r);
        assert_eq!(
            LacquerMaterial::default(),
            LacquerMaterial::preset("smooth-black").unwrap()
        );
        assert_eq!(
            LacquerMaterial::preset("rough-red").unwrap().albedo,
            [0.50, 0.06, 0.03]
        );
        for name in PRESET_NAMES {
            LacquerMaterial::preset(name).unwrap().validate().unwrap();
        }
    }

    #[test]
    fn unknown_preset_lists_the_names_and_the_nearest() {
        let (field, reason) = invalid_field(LacquerMaterial::preset("smoth-red"));
        assert_eq!(field, "preset");
        assert!(
            reason.contains("rough-black") && reason.contains("did you mean `smooth-red`"),
            "{reason}"
        );
        for bad in ["", "red", "smooth-blue", "smooth-red-x"] {
            assert!(LacquerMaterial::preset(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn lacquer_law_of_the_paper() {
        // g(1) = 1.22 - 0.224 + 0.0199 = 1.0159; r* = 0.224 / 0.0398 = 5.6281407…
        let mut m = LacquerMaterial::default();
        assert!((m.lacquer_g() - 1.0159).abs() < 1e-15);
        assert!((m.lacquer_ratio_max() - 0.224 / 0.0398).abs() < 1e-12);
        m.lacquer_ratio = 3.0; // 1.22 - 0.672 + 0.1791 = 0.7271
        assert!((m.lacquer_g() - 0.7271).abs() < 1e-15);
        m.lacquer_law[2] = 0.0;
        assert_eq!(m.lacquer_ratio_max(), f64::INFINITY);
        m.lacquer_law[2] = -0.01;
        assert_eq!(m.lacquer_ratio_max(), f64::INFINITY);
    }

    #[test]
    fn brdf_params_carry_the_evaluated_g() {
        let p = LacquerMaterial::preset("rough-red")
            .unwrap()
            .brdf_params()
            .unwrap();
        assert_eq!(p.beckmann_m, 0.20);
        assert_eq!((p.diffuse_a, p.diffuse_b), (0.01, 0.96));
        assert_eq!(p.albedo, [0.50, 0.06, 0.03]);
        assert!((p.lacquer_g - 1.0159).abs() < 1e-15);
    }

    #[test]
    fn every_validation_rule_rejects_with_its_range() {
        type Edit = fn(&mut LacquerMaterial);
        #[rustfmt::skip]
        let cases: [(Edit, &str, &str); 18] = [
            (|m| m.beckmann_m = 0.0, "m", "(0, 1]"),
            (|m| m.beckmann_m = 1.5, "m", "(0, 1]"),
            (|m| m.beckmann_m = f64::NAN, "m", "(0, 1]"),
            (|m| m.diffuse_a = f64::INFINITY, "a", "finite"),
            (|m| m.diffuse_b = f64::NAN, "b", "finite"),
            (|m| m.lacquer_law[1] = f64::NEG_INFINITY, "c1", "finite"),
            (|m| m.albedo = [0.5, 1.2, 0.0], "kd", "[0, 1]"),
            (|m| m.albedo = [-0.1, 0.5, 0.5], "kd", "[0, 1]"),
            (|m| m.lacquer_ratio = 0.5, "r", "[1, 5.62"),
            (|m| m.lacquer_ratio = 6.0, "r", "extrapolate_g"),
            (|m| m.lacquer_ratio = f64::NAN, "r", "finite"),
            (|m| m.lacquer_law = [1.0, 0.1, 0.1], "r", "no r is in the fitted domain"),
            (|m| (m.extrapolate_g, m.lacquer_ratio, m.lacquer_law[2]) = (true, 10.0, -0.1),
                "r", "g(r) ="),
            (|m| m.ior_a = 0.99, "ior_a", ">= 1"),
            (|m| m.ior_b = -0.001, "ior_b", ">= 0"),
            (|m| m.beta_normal = -0.01, "beta_normal", "≥ 0"),
            (|m| m.beta_grazing = f64::INFINITY, "beta_grazing", "≥ 0"),
            (|m| m.beta_power = -1.0, "beta_power", "> 0"),
        ];
        for (edit, field, needle) in cases {
            let mut m = LacquerMaterial::default();
            edit(&mut m);
            let (got_field, reason) = invalid_field(m.validate());
            assert_eq!(got_field, field, "{m:?}");
            assert!(
                reason.contains(needle),
                "{field}: `{reason}` lacks `{needle}`"
            );
            assert!(m.brdf_params().is_err());
        }
    }

    #[test]
    fn extrapolate_g_admits_r_beyond_the_fitted_domain() {
        // g(8) = 1.22 - 1.792 + 1.2736 = 0.7016 ≥ 0, but 8 > r*.
        let mut m = LacquerMaterial {
            lacquer_ratio: 8.0,
            ..LacquerMaterial::default()
        };
        assert!(m.validate().is_err());
        m.extrapolate_g = true;
        m.validate().unwrap();
        // The upper end r* itself is inside the domain.
        let mut m = LacquerMaterial::default();
        m.lacquer_ratio = m.lacquer_ratio_max();
        m.validate().unwrap();
    }

    #[test]
    fn set_round_trips_every_key() {
        let mut m = LacquerMaterial::default();
        #[rustfmt::skip]
        let edits = [
            ("m", "0.3"), ("a", "-0.5"), ("b", " 2 "), ("c0", "1.1"), ("c1", "-0.2"),
            ("c2", "0.01"), ("r", "2.5"), ("kd", "0.1, 0.2,0.3"), ("extrapolate_g", "true"),
            ("ior_a", "1.6"), ("ior_b", "0.01"), ("fresnel", "tables/blue.csv"),
            ("beta_normal", "0.4"), ("beta_grazing", "0.02"), ("beta_power", "2"),
        ];
        assert_eq!(edits.len(), MATERIAL_KEYS.len());
        for (key, value) in edits {
            m.set(key, value).unwrap();
        }
        let expected = LacquerMaterial {
            beckmann_m: 0.3,
            diffuse_a: -0.5,
            diffuse_b: 2.0,
            lacquer_law: [1.1, -0.2, 0.01],
            lacquer_ratio: 2.5,
            albedo: [0.1, 0.2, 0.3],
            extrapolate_g: true,
            ior_a: 1.6,
            ior_b: 0.01,
            fresnel_file: Some(PathBuf::from("tables/blue.csv")),
            beta_normal: 0.4,
            beta_grazing: 0.02,
            beta_power: 2.0,
        };
        assert_eq!(m, expected);
        m.set("fresnel", "").unwrap();
        m.set("extrapolate_g", "false").unwrap();
        assert!(m.fresnel_file.is_none() && !m.extrapolate_g);
    }

    #[test]
    fn set_rejects_bad_values_and_leaves_the_material_unchanged() {
        let cases = [
            ("m", "abc", "not a number"),
            ("m", "NaN", "finite"),
            ("a", "inf", "finite"),
            ("m", "0", "(0, 1]"),
            ("kd", "0.5,0.5", "three"),
            ("kd", "0.5,x,0.5", "not a number"),
            ("kd", "0.5,2,0.5", "[0, 1]"),
            ("extrapolate_g", "yes", "`true` or `false`"),
            ("ior_a", "0.5", ">= 1"),
            ("ior_b", "-1", ">= 0"),
            ("beta_power", "0", "> 0"),
        ];
        for (key, value, needle) in cases {
            let mut m = LacquerMaterial::default();
            let (field, reason) = invalid_field(m.set(key, value));
            assert_eq!(field, key);
            assert!(
                reason.contains(needle),
                "{key}={value}: `{reason}` lacks `{needle}`"
            );
            assert_eq!(m, LacquerMaterial::default());
        }
    }

    #[test]
    fn unknown_key_suggests_the_nearest() {
        let (field, reason) = invalid_field(LacquerMaterial::default().set("beta_normall", "0.1"));
        assert_eq!(field, "material key");
        assert!(
            reason.contains("ior_a") && reason.contains("did you mean `beta_normal`"),
            "{reason}"
        );
    }

    #[test]
    fn fresnel_table_defaults_to_the_dielectric_and_reads_files() {
        let mut m = LacquerMaterial::default();
        assert_eq!(
            m.fresnel_table().unwrap(),
            FresnelTable::dielectric(1.5, 0.0045).unwrap()
        );
        m.set("fresnel", "/nonexistent/shikki.csv").unwrap();
        assert!(matches!(m.fresnel_table(), Err(Error::Read { .. })));
    }
}
