//! Material handles: a preset, a TOML text or file, and a setter for every SPEC field. Setters
//! go through `LacquerMaterial::set` (text) or `set_value` (typed: a double stays a double), so
//! the C API checks each field exactly as the CLI and scene files do; rules that tie fields
//! together (r within [1, r*]) are checked by `shikki_material_validate` and when a scene is
//! rendered.

use std::ffi::c_char;
use std::path::Path;

use shikki::model::material::MaterialValue;
use shikki::model::material_file::{load_material_file, material_from_toml_str};
use shikki::model::LacquerMaterial;

use crate::boundary::{c_str, check_out, ffi_boundary, opt_c_str, write_out, FfiResult};
use crate::handles::{self, ShikkiMaterial};
use crate::status::ShikkiStatus;

fn make(material: LacquerMaterial, out: *mut ShikkiMaterial) -> FfiResult {
    let handle = handles::insert::<ShikkiMaterial, _>(material);
    // SAFETY: every caller checked `out` with check_out and the C contract makes it writable.
    unsafe { write_out(out, "out", handle) }
}

/// A preset: "smooth", "rough", "smooth-black", "smooth-red", "rough-black", "rough-red".
///
/// # Safety
/// `name` is a NUL-terminated UTF-8 string; `out` is valid for one write.
#[no_mangle]
pub unsafe extern "C" fn shikki_material_create_preset(
    name: *const c_char,
    out: *mut ShikkiMaterial,
) -> ShikkiStatus {
    ffi_boundary!({
        check_out(out, "out")?;
        // SAFETY: the caller's contract above.
        let name = unsafe { c_str(name, "name") }?;
        make(LacquerMaterial::preset(name)?, out)
    })
}

/// A material from TOML text (the material-file format: `preset = "…"` plus field keys).
/// `base_dir` (may be NULL: the current directory) resolves a relative `fresnel` path.
///
/// # Safety
/// `toml` and `base_dir` (unless NULL) are NUL-terminated UTF-8 strings; `out` is valid for one
/// write.
#[no_mangle]
pub unsafe extern "C" fn shikki_material_create_toml(
    toml: *const c_char,
    base_dir: *const c_char,
    out: *mut ShikkiMaterial,
) -> ShikkiStatus {
    ffi_boundary!({
        check_out(out, "out")?;
        // SAFETY: the caller's contract above.
        let text = unsafe { c_str(toml, "toml") }?;
        // SAFETY: the caller's contract above.
        let base = unsafe { opt_c_str(base_dir, "base_dir") }?.unwrap_or(".");
        let material = material_from_toml_str(text, Path::new(base), "<toml string>")?;
        make(material, out)
    })
}

/// A material from a TOML file.
///
/// # Safety
/// `path` is a NUL-terminated UTF-8 string; `out` is valid for one write.
#[no_mangle]
pub unsafe extern "C" fn shikki_material_load(
    path: *const c_char,
    out: *mut ShikkiMaterial,
) -> ShikkiStatus {
    ffi_boundary!({
        check_out(out, "out")?;
        // SAFETY: the caller's contract above.
        let path = unsafe { c_str(path, "path") }?;
        make(load_material_file(Path::new(path))?, out)
    })
}

/// Destroys a material. Scenes keep the copy they took when the object was added. 0 is a no-op.
#[no_mangle]
pub extern "C" fn shikki_material_destroy(material: ShikkiMaterial) -> ShikkiStatus {
    ffi_boundary!({ handles::remove(material) })
}

fn set(material: ShikkiMaterial, key: &str, value: &str) -> FfiResult {
    let object = handles::get::<_, LacquerMaterial>(material)?;
    let mut material = handles::lock(&object)?;
    material.set(key, value)?;
    Ok(())
}

fn set_value(material: ShikkiMaterial, key: &str, value: MaterialValue) -> FfiResult {
    let object = handles::get::<_, LacquerMaterial>(material)?;
    let mut material = handles::lock(&object)?;
    material.set_value(key, value)?;
    Ok(())
}

/// Sets one field by its text key (the keys of material files: m, a, b, c0, c1, c2, r, kd,
/// extrapolate_g, ior_a, ior_b, fresnel, beta_normal, beta_grazing, beta_power). On error the
/// material is unchanged.
///
/// # Safety
/// `key` and `value` are NUL-terminated UTF-8 strings.
#[no_mangle]
pub unsafe extern "C" fn shikki_material_set(
    material: ShikkiMaterial,
    key: *const c_char,
    value: *const c_char,
) -> ShikkiStatus {
    ffi_boundary!({
        // SAFETY: the caller's contract above.
        let key = unsafe { c_str(key, "key") }?;
        // SAFETY: the caller's contract above.
        let value = unsafe { c_str(value, "value") }?;
        set(material, key, value)
    })
}

/// Beckmann RMS slope m, in (0, 1].
#[no_mangle]
pub extern "C" fn shikki_material_set_beckmann_m(
    material: ShikkiMaterial,
    value: f64,
) -> ShikkiStatus {
    ffi_boundary!({ set_value(material, "m", MaterialValue::Number(value)) })
}

/// a of f(N·V) = a + b·N·V.
#[no_mangle]
pub extern "C" fn shikki_material_set_diffuse_a(
    material: ShikkiMaterial,
    value: f64,
) -> ShikkiStatus {
    ffi_boundary!({ set_value(material, "a", MaterialValue::Number(value)) })
}

/// b of f(N·V) = a + b·N·V.
#[no_mangle]
pub extern "C" fn shikki_material_set_diffuse_b(
    material: ShikkiMaterial,
    value: f64,
) -> ShikkiStatus {
    ffi_boundary!({ set_value(material, "b", MaterialValue::Number(value)) })
}

/// r, the lacquer : colorant ratio, in [1, r*] unless extrapolate_g.
#[no_mangle]
pub extern "C" fn shikki_material_set_lacquer_ratio(
    material: ShikkiMaterial,
    value: f64,
) -> ShikkiStatus {
    ffi_boundary!({ set_value(material, "r", MaterialValue::Number(value)) })
}

/// A of the lacquer's n(λ) = A + B/λ², in [1, 10] (real lacquers 1.4–1.9).
#[no_mangle]
pub extern "C" fn shikki_material_set_ior_a(material: ShikkiMaterial, value: f64) -> ShikkiStatus {
    ffi_boundary!({ set_value(material, "ior_a", MaterialValue::Number(value)) })
}

/// B of n(λ) = A + B/λ², in µm², in [0, 1] (real lacquers ≤ 0.02).
#[no_mangle]
pub extern "C" fn shikki_material_set_ior_b(material: ShikkiMaterial, value: f64) -> ShikkiStatus {
    ffi_boundary!({ set_value(material, "ior_b", MaterialValue::Number(value)) })
}

/// β of the environment blur at normal view (≥ 0; 0 is the sharp map).
#[no_mangle]
pub extern "C" fn shikki_material_set_beta_normal(
    material: ShikkiMaterial,
    value: f64,
) -> ShikkiStatus {
    ffi_boundary!({ set_value(material, "beta_normal", MaterialValue::Number(value)) })
}

/// β of the environment blur at grazing view (≥ 0; 0 is the sharp map).
#[no_mangle]
pub extern "C" fn shikki_material_set_beta_grazing(
    material: ShikkiMaterial,
    value: f64,
) -> ShikkiStatus {
    ffi_boundary!({ set_value(material, "beta_grazing", MaterialValue::Number(value)) })
}

/// p of β(nv) = β_grazing + (β_normal − β_grazing)·nv^p (> 0).
#[no_mangle]
pub extern "C" fn shikki_material_set_beta_power(
    material: ShikkiMaterial,
    value: f64,
) -> ShikkiStatus {
    ffi_boundary!({ set_value(material, "beta_power", MaterialValue::Number(value)) })
}

/// g(r) = c0 + c1·r + c2·r². All three are set, or none (on error).
#[no_mangle]
pub extern "C" fn shikki_material_set_lacquer_law(
    material: ShikkiMaterial,
    c0: f64,
    c1: f64,
    c2: f64,
) -> ShikkiStatus {
    ffi_boundary!({
        let object = handles::get::<_, LacquerMaterial>(material)?;
        let mut material = handles::lock(&object)?;
        let mut updated = material.clone();
        updated.set_value("c0", MaterialValue::Number(c0))?;
        updated.set_value("c1", MaterialValue::Number(c1))?;
        updated.set_value("c2", MaterialValue::Number(c2))?;
        *material = updated;
        Ok(())
    })
}

/// k_d, the colorant albedo, linear RGB in [0, 1].
#[no_mangle]
pub extern "C" fn shikki_material_set_albedo(
    material: ShikkiMaterial,
    r: f64,
    g: f64,
    b: f64,
) -> ShikkiStatus {
    ffi_boundary!({ set_value(material, "kd", MaterialValue::Rgb([r, g, b])) })
}

/// Allow r outside the fitted domain [1, r*] of g.
#[no_mangle]
pub extern "C" fn shikki_material_set_extrapolate_g(
    material: ShikkiMaterial,
    extrapolate: bool,
) -> ShikkiStatus {
    ffi_boundary!({ set_value(material, "extrapolate_g", MaterialValue::Bool(extrapolate)) })
}

/// A Fresnel CSV (RGB or spectral, SPEC §3); NULL or "" returns to the dielectric table.
///
/// # Safety
/// `path` is NULL or a NUL-terminated UTF-8 string.
#[no_mangle]
pub unsafe extern "C" fn shikki_material_set_fresnel_file(
    material: ShikkiMaterial,
    path: *const c_char,
) -> ShikkiStatus {
    ffi_boundary!({
        // SAFETY: the caller's contract above.
        let path = unsafe { opt_c_str(path, "path") }?.unwrap_or("");
        set(material, "fresnel", path)
    })
}

/// Checks every rule of SPEC §2–4, including those between fields, and that the Fresnel table
/// can be built.
#[no_mangle]
pub extern "C" fn shikki_material_validate(material: ShikkiMaterial) -> ShikkiStatus {
    ffi_boundary!({
        let object = handles::get::<_, LacquerMaterial>(material)?;
        let material = handles::lock(&object)?;
        material.brdf_params()?;
        material.fresnel_table()?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boundary::last_error;

    #[test]
    fn ior_setters_refuse_values_outside_their_range_and_keep_the_material() {
        let _turn = handles::test_table_turn();
        let handle = handles::insert::<ShikkiMaterial, _>(LacquerMaterial::default());
        type Setter = extern "C" fn(ShikkiMaterial, f64) -> ShikkiStatus;
        const B_RANGE: &str = "must be a finite number in [0, 1] µm²";
        const A_RANGE: &str = "must be a finite number in [1, 10]";
        let cases: [(Setter, f64, &str, &str); 4] = [
            (shikki_material_set_ior_b, 1e308, "ior_b", B_RANGE),
            (shikki_material_set_ior_b, -0.1, "ior_b", B_RANGE),
            (shikki_material_set_ior_a, 11.0, "ior_a", A_RANGE),
            (shikki_material_set_ior_a, 0.5, "ior_a", A_RANGE),
        ];
        for (setter, value, field, range) in cases {
            assert_eq!(
                setter(handle, value),
                ShikkiStatus::InvalidArgument,
                "{field} = {value}"
            );
            // The setter refuses the value itself, naming the field and its range (1e308 used to
            // pass here and fail at render as a NaN Fresnel table that named neither).
            let message = last_error();
            assert!(
                message.contains(&format!("invalid {field} = ")) && message.contains(range),
                "{field} = {value}: `{message}`"
            );
        }
        let material = handles::read::<_, LacquerMaterial>(handle).expect("the handle is live");
        assert_eq!(
            material,
            LacquerMaterial::default(),
            "a refused value changes nothing"
        );
        assert_eq!(shikki_material_set_ior_b(handle, 0.02), ShikkiStatus::Ok);
        assert_eq!(shikki_material_destroy(handle), ShikkiStatus::Ok);
    }
}
