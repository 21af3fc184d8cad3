//! The ranges the renderer's f32 arithmetic carries. Every input is held to these beside its own
//! rule (SPEC §2's m in (0, 1], a light's E ≥ 0, …): a value past one is refused with an error
//! that names it, where it used to be accepted and drawn black (an f32 overflow or underflow on
//! the device; found by a probe of the C API, 2026-12-06).

use crate::error::show_number;

/// The smallest Beckmann m. SPEC §2 allows any m > 0; the device computes D in f32, where m²
/// underflows below ~1e-19 and the draw went black (m = 1e-20). At m = 1e-3 the GLSL BRDF is
/// within 1e-5 of the CPU model around the highlight, at 3e-4 1.1e-4 (`shikki brdf --backend
/// gpu`, 30° from the normal): 1e-3 keeps the 1e-4 the tests hold every m to, and is 50× smoother
/// than the smooth preset.
pub const MIN_BECKMANN_M: f64 = 1e-3;

/// The largest light level: an environment's radiance (a pixel times `intensity`), a directional
/// light's irradiance E, a point light's intensity I. A highlight multiplies it by D (up to
/// 1/(π·m²) = 3.2e5 at [`MIN_BECKMANN_M`]) and G/(4·nv·nl), sixteen lights add, and the prefilter
/// sums a map's pixels: 1e20 keeps all of it inside f32 (3.4e38). 1e39 was accepted and drawn
/// black. The sun is ~1e5 W/m²; a real HDRI's brightest pixels 1e4–1e9.
pub const MAX_LIGHT_LEVEL: f64 = 1e20;

/// The largest |a|, |b|, |c0|, |c1|, |c2| of the diffuse law f(nv)·g(r). With r up to r* ≈ 5.6
/// g grows ~37× its largest coefficient; 1e6 keeps f·g·k_d·E inside f32 at [`MAX_LIGHT_LEVEL`].
/// The paper's fits are within ±1.3.
pub const MAX_DIFFUSE_COEFFICIENT: f64 = 1e6;

/// The largest coordinate of a camera's eye or target, an object's translation or a light's
/// position or direction component. Positions are f32 on the device, whose spacing at 1e15 is
/// 6.7e7: nothing there keeps its shape. 1e39 overflowed to infinity.
pub const MAX_COORDINATE: f64 = 1e15;

/// The least distance between the camera's eye and target, relative to the larger of their
/// distances from the origin (and 1): closer, and the f32 view direction is rounding noise
/// (eye (0, 0, 1 + 1e-9), target (0, 0, 1) drew black).
pub const MIN_VIEW_DISTANCE: f64 = 1e-6;

/// The least vertical field of view in degrees: at 1e-300° the projection's 1/tan(fov/2)
/// overflowed f32 and the image was black. 0.001° is a 60-million-pixel-wide telephoto.
pub const MIN_FOV_DEG: f64 = 1e-3;

/// An object's placement: the shortest of its transform's three axes (the columns of the 3 × 3
/// part) at least this share of the longest, and the axes' volume |det| at least this share of
/// the product of their lengths (not flattened into a plane by a shear). A mesh flattened 1e30
/// to 1 (scale [1, 1, 1e-30]) put both its sides on one f32 plane, and each shadowed the other:
/// the object drew black.
pub const MIN_AXIS_RATIO: f64 = 1e-4;

/// The shortest axis of a placement: a scale of 1e-300 collapsed every normal to zero in f32.
pub const MIN_AXIS_LENGTH: f64 = 1e-12;

/// The largest axis of a placement: at 1e300 every position overflowed f32.
pub const MAX_AXIS_LENGTH: f64 = 1e12;

/// Why `value` (a light level: radiance, irradiance or intensity) is out of range, if it is.
pub fn light_level_problem(value: f64) -> Option<String> {
    (!(value.is_finite() && (0.0..=MAX_LIGHT_LEVEL).contains(&value))).then(|| {
        format!("every channel must be a finite number in [0, {MAX_LIGHT_LEVEL:e}] (linear RGB)")
    })
}

/// Why an object's 4 × 4 placement (column-major, affine) cannot be drawn, if it cannot: a
/// sentence that names the rule and the fix.
pub fn placement_problem(m: &glam::DMat4) -> Option<String> {
    if !m.is_finite() {
        return Some("every element must be a finite number".into());
    }
    if m.row(3) != glam::DVec4::W {
        return Some("the last row must be (0, 0, 0, 1): a placement is affine".into());
    }
    let axes = [m.x_axis, m.y_axis, m.z_axis].map(|c| c.truncate());
    let lengths = axes.map(|a| a.length());
    let longest = lengths.iter().copied().fold(0.0, f64::max);
    let shortest = lengths.iter().copied().fold(f64::INFINITY, f64::min);
    if !(MIN_AXIS_LENGTH..=MAX_AXIS_LENGTH).contains(&shortest)
        || !(MIN_AXIS_LENGTH..=MAX_AXIS_LENGTH).contains(&longest)
    {
        return Some(format!(
            "its axes (the scale) are {} long: each must be in [{MIN_AXIS_LENGTH:e}, \
             {MAX_AXIS_LENGTH:e}]; scale the mesh's units instead",
            show_lengths(lengths)
        ));
    }
    if shortest < MIN_AXIS_RATIO * longest {
        return Some(format!(
            "its axes (the scale) are {} long: the shortest must be at least {MIN_AXIS_RATIO:e} \
             of the longest, or the flattened mesh's two sides meet in f32; use a thin mesh \
             such as builtin:board instead",
            show_lengths(lengths)
        ));
    }
    let volume = axes[0].dot(axes[1].cross(axes[2])).abs();
    if volume < MIN_AXIS_RATIO * lengths.iter().product::<f64>() {
        return Some(format!(
            "its axes are (nearly) in one plane (|det| {volume:e} of the axes' product {:e}): \
             the shear or projection flattens the mesh",
            lengths.iter().product::<f64>()
        ));
    }
    let translation = m.w_axis.truncate();
    if translation.abs().max_element() > MAX_COORDINATE {
        return Some(format!(
            "its translation {} has a coordinate beyond ±{MAX_COORDINATE:e}, where f32 positions \
             keep no shape",
            show_vec(translation)
        ));
    }
    None
}

/// Why a position or direction coordinate is out of range, if one is.
pub fn coordinate_problem(v: glam::DVec3) -> Option<String> {
    (!(v.is_finite() && v.abs().max_element() <= MAX_COORDINATE))
        .then(|| format!("every component must be a finite number within ±{MAX_COORDINATE:e}"))
}

fn show_vec(v: glam::DVec3) -> String {
    crate::error::show_numbers(&v.to_array())
}

fn show_lengths(l: [f64; 3]) -> String {
    format!(
        "{}, {}, {}",
        show_number(l[0]),
        show_number(l[1]),
        show_number(l[2])
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DMat4, DQuat, DVec3};

    fn scaled(s: DVec3) -> DMat4 {
        DMat4::from_scale_rotation_translation(s, DQuat::from_rotation_y(0.3), DVec3::ONE)
    }

    #[test]
    fn placements_within_the_ranges_pass() {
        for s in [DVec3::ONE, DVec3::new(1.0, 1e-4, 1.0), DVec3::splat(1e-12)] {
            assert_eq!(placement_problem(&scaled(s)), None, "{s}");
        }
        assert_eq!(
            placement_problem(&DMat4::from_scale(DVec3::splat(1e12))),
            None
        );
        // A mirror is a placement like any other.
        assert_eq!(
            placement_problem(&DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0))),
            None
        );
    }

    #[test]
    fn each_broken_placement_is_named() {
        let cases = [
            (scaled(DVec3::new(1.0, 1.0, 1e-6)), "shortest must be"),
            (scaled(DVec3::new(1.0, 1.0, 1e-30)), "each must be in"),
            (scaled(DVec3::new(1.0, 1.0, 0.0)), "each must be in"),
            (scaled(DVec3::splat(1e300)), "each must be in"),
            (scaled(DVec3::splat(1e-300)), "each must be in"),
            (
                DMat4::from_translation(DVec3::new(0.0, 1e39, 0.0)),
                "beyond ±1e15",
            ),
            (
                DMat4::from_cols_array(&[
                    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 1e-9, 0.0, 0.0, 0.0, 0.0, 1.0,
                ]),
                "in one plane",
            ),
            (DMat4::from_scale(DVec3::splat(f64::NAN)), "finite"),
        ];
        for (m, expected) in cases {
            let problem = placement_problem(&m).expect("refused");
            assert!(problem.contains(expected), "{problem}");
            assert!(problem.len() < 300, "{problem}");
        }
    }

    #[test]
    fn light_levels_and_coordinates_have_bounds() {
        assert_eq!(light_level_problem(0.0), None);
        assert_eq!(light_level_problem(MAX_LIGHT_LEVEL), None);
        for bad in [-1e-9, 1e21, f64::INFINITY, f64::NAN] {
            assert!(light_level_problem(bad).is_some(), "{bad}");
        }
        assert_eq!(coordinate_problem(DVec3::splat(1e15)), None);
        assert!(coordinate_problem(DVec3::new(0.0, 0.0, 1e39)).is_some());
    }
}
