//! Measurements as the fit sees them: boards (samples) with their lacquer ratio, and rows of
//! (light, view, RGB reflectance factor) in the board's frame, N = +Z.
//!
//! Owns the goniometer angle convention (docs/measurements.md): θ_i is the light's angle from the normal,
//! θ_o the viewer's, φ the viewer's azimuth from the plane of incidence, and φ = 0 with θ_o = θ_i
//! is the mirror direction. So the light lies at azimuth 180°: L = (−sin θ_i, 0, cos θ_i) and
//! V = (sin θ_o cos φ, sin θ_o sin φ, cos θ_o); a negative θ_o at φ = 0 is on the light's side.
//! It does not read files ([`super::csv`], [`super::merl`]) or fit anything.

use glam::DVec3;

/// One board: a name and its lacquer ratio r (relative to the least-lacquer board, so ≥ 1).
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    pub name: String,
    pub lacquer_ratio: f64,
}

/// One measured value.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// Index into [`Measurements::samples`].
    pub sample: usize,
    /// Unit vector towards the light, N = +Z.
    pub light: DVec3,
    /// Unit vector towards the viewer, N = +Z.
    pub view: DVec3,
    /// Reflectance factor π·f_r, linear RGB (spectral rows are converted by SPEC §3's path).
    pub reflectance: [f64; 3],
    /// The 1-based line of a CSV row; 0 for binary formats.
    pub line: usize,
}

/// A data set: where it came from, its boards and its rows.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurements {
    /// The file name, for messages.
    pub source: String,
    pub samples: Vec<Sample>,
    pub rows: Vec<Measurement>,
    /// What reading did that a user should know (columns it did not read); the fit passes them
    /// on as notes.
    pub notes: Vec<String>,
}

/// The light direction of a goniometer row (see the module doc).
pub fn light_direction(theta_i_deg: f64) -> DVec3 {
    let t = theta_i_deg.to_radians();
    DVec3::new(-t.sin(), 0.0, t.cos())
}

/// The view direction of a goniometer row (see the module doc).
pub fn view_direction(theta_o_deg: f64, phi_deg: f64) -> DVec3 {
    let (t, p) = (theta_o_deg.to_radians(), phi_deg.to_radians());
    DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// The goniometer angles (θ_i, θ_o, φ) in degrees of a (light, view) pair: the inverse of
/// [`light_direction`] and [`view_direction`], with θ_o ≥ 0 and φ in (−180, 180] measured from
/// the mirror side of the plane of incidence. In-plane rows have φ = 0 (mirror side) or 180.
pub fn goniometer_angles(light: DVec3, view: DVec3) -> (f64, f64, f64) {
    let theta_i = light.z.clamp(-1.0, 1.0).acos().to_degrees();
    let theta_o = view.z.clamp(-1.0, 1.0).acos().to_degrees();
    // The light's azimuth + 180° is the mirror azimuth; at normal incidence any plane will do.
    let mirror_azimuth = if light.x == 0.0 && light.y == 0.0 {
        0.0
    } else {
        light.y.atan2(light.x) + std::f64::consts::PI
    };
    let mut phi = (view.y.atan2(view.x) - mirror_azimuth).to_degrees();
    while phi > 180.0 {
        phi -= 360.0;
    }
    while phi <= -180.0 {
        phi += 360.0;
    }
    if view.x == 0.0 && view.y == 0.0 {
        phi = 0.0;
    }
    (theta_i, theta_o, phi)
}

/// The signed in-plane viewing angle of a row, if it lies in the plane of incidence (within
/// `tolerance_deg` of φ = 0 or 180): positive on the mirror side, negative on the light's side.
pub fn in_plane_theta_o(light: DVec3, view: DVec3, tolerance_deg: f64) -> Option<f64> {
    let (_, theta_o, phi) = goniometer_angles(light, view);
    if phi.abs() <= tolerance_deg {
        Some(theta_o)
    } else if phi.abs() >= 180.0 - tolerance_deg {
        Some(-theta_o)
    } else {
        None
    }
}

pub use crate::model::spectral::luminance;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirror_direction_is_theta_o_equal_theta_i_at_phi_zero() {
        // The convention of docs/measurements.md: L and V = reflect(L) about N are at θ_o = θ_i, φ = 0.
        for theta in [0.0, 10.0, 45.0, 80.0] {
            let l = light_direction(theta);
            let v = view_direction(theta, 0.0);
            let mirror = 2.0 * l.z * DVec3::Z - l;
            assert!((v - mirror).length() < 1e-15, "θ = {theta}");
        }
    }

    #[test]
    fn negative_theta_o_is_on_the_light_side() {
        // θ_o = −θ_i at φ = 0 is the retro-reflection direction V = L.
        let (l, v) = (light_direction(30.0), view_direction(-30.0, 0.0));
        assert!((l - v).length() < 1e-15);
    }

    #[test]
    fn goniometer_angles_invert_the_directions() {
        // Round trip (1e-12 degrees: acos/atan2 rounding near 1 ulp of the radians).
        for (ti, to, phi) in [(30.0, 40.0, 0.0), (10.0, 70.0, 90.0), (60.0, 20.0, -135.0)] {
            let (a, b, c) = goniometer_angles(light_direction(ti), view_direction(to, phi));
            assert!((a - ti).abs() < 1e-12 && (b - to).abs() < 1e-12 && (c - phi).abs() < 1e-12);
        }
        let (l, v) = (light_direction(30.0), view_direction(-50.0, 0.0));
        assert!((in_plane_theta_o(l, v, 0.5).unwrap() + 50.0).abs() < 1e-12);
        assert_eq!(in_plane_theta_o(l, view_direction(50.0, 45.0), 0.5), None);
    }

    #[test]
    fn luminance_of_white_is_one() {
        // The Rec. 709 weights sum to 1.
        assert!((luminance([1.0; 3]) - 1.0).abs() < 1e-15);
    }
}
