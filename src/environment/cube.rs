//! Cube-map and equirectangular geometry (SPEC §4), shared by the CPU oracle and mirrored in
//! `shaders/common/cubemap.glsl`: change both together.
//!
//! Faces are in Vulkan's order (+X, −X, +Y, −Y, +Z, −Z). Texel (i, j) of a face of size M has its
//! centre at s = (i + ½)/M, t = (j + ½)/M, and (sc, tc) = (2s − 1, 2t − 1) are the face
//! coordinates of the Vulkan specification's cube-map face-selection table:
//!
//! | face | major axis | sc  | tc  |
//! |------|------------|-----|-----|
//! | +X   | +x         | −z  | −y  |
//! | −X   | −x         | +z  | −y  |
//! | +Y   | +y         | +x  | +z  |
//! | −Y   | −y         | +x  | −z  |
//! | +Z   | +z         | +x  | −y  |
//! | −Z   | −z         | −x  | −y  |
//!
//! A cube is stored face after face, row after row: texel (f, i, j) at index (f·M + j)·M + i.

use glam::DVec3;

/// Unnormalised direction of face coordinates (sc, tc) ∈ [−1, 1]² on `face` (0..6): the inverse
/// of the table above with |major axis| = 1.
pub fn face_direction(face: usize, sc: f64, tc: f64) -> DVec3 {
    match face {
        0 => DVec3::new(1.0, -tc, -sc),
        1 => DVec3::new(-1.0, -tc, sc),
        2 => DVec3::new(sc, 1.0, tc),
        3 => DVec3::new(sc, -1.0, -tc),
        4 => DVec3::new(sc, -tc, 1.0),
        _ => DVec3::new(-sc, -tc, -1.0),
    }
}

/// Face coordinates of texel centre i of a face of size M.
pub fn texel_coord(i: u32, face_size: u32) -> f64 {
    2.0 * (f64::from(i) + 0.5) / f64::from(face_size) - 1.0
}

/// Unit direction through the centre of texel (i, j) of `face`.
pub fn texel_direction(face: usize, i: u32, j: u32, face_size: u32) -> DVec3 {
    face_direction(face, texel_coord(i, face_size), texel_coord(j, face_size)).normalize()
}

/// Solid angle of texel (i, j), to second order: dω = (2/M)² / (1 + sc² + tc²)^{3/2}, the
/// area of the texel on the face plane at unit distance, projected onto the sphere. Exact to
/// O(1/M²) relative, and unlike the exact atan form it does not cancel catastrophically in fp32.
/// The prefilter normalises every sum by Σ w·dω, so a common scale error cancels.
pub fn texel_solid_angle(i: u32, j: u32, face_size: u32) -> f64 {
    let sc = texel_coord(i, face_size);
    let tc = texel_coord(j, face_size);
    let h = 2.0 / f64::from(face_size);
    h * h / (1.0 + sc * sc + tc * tc).powf(1.5)
}

/// (face, sc, tc) of a direction, by the face-selection table (ties go to X, then Y, then Z, as
/// in Vulkan's "largest magnitude, first in order").
pub fn direction_to_face(d: DVec3) -> (usize, f64, f64) {
    let (ax, ay, az) = (d.x.abs(), d.y.abs(), d.z.abs());
    if ax >= ay && ax >= az {
        if d.x >= 0.0 {
            (0, -d.z / ax, -d.y / ax)
        } else {
            (1, d.z / ax, -d.y / ax)
        }
    } else if ay >= az {
        if d.y >= 0.0 {
            (2, d.x / ay, d.z / ay)
        } else {
            (3, d.x / ay, -d.z / ay)
        }
    } else if d.z >= 0.0 {
        (4, d.x / az, -d.y / az)
    } else {
        (5, -d.x / az, -d.y / az)
    }
}

/// Rotates a world direction into the environment's frame: the environment is turned by
/// `rotation_deg` about +Y (right-handed), so a world direction sees R_y(−ρ)·d.
pub fn world_to_environment(d: DVec3, rotation_deg: f64) -> DVec3 {
    let (s, c) = rotation_deg.to_radians().sin_cos();
    DVec3::new(d.x * c - d.z * s, d.y, d.x * s + d.z * c)
}

/// SPEC §4: u = ½ + atan2(x, −z)/2π, v = acos(y)/π (d unit; v via atan2 for accuracy at the poles).
pub fn direction_to_equirect(d: DVec3) -> (f64, f64) {
    let u = 0.5 + d.x.atan2(-d.z) / std::f64::consts::TAU;
    let v = (d.x.hypot(d.z)).atan2(d.y) / std::f64::consts::PI;
    (u, v)
}

/// The solid angle of a pixel in row `y` of a `width` × `height` equirect map (SPEC §1):
/// 2π/width · (cos θ_top − cos θ_bottom).
pub fn equirect_row_solid_angle(y: u32, width: u32, height: u32) -> f64 {
    let top = std::f64::consts::PI * f64::from(y) / f64::from(height);
    let bottom = std::f64::consts::PI * f64::from(y + 1) / f64::from(height);
    std::f64::consts::TAU / f64::from(width) * (top.cos() - bottom.cos())
}

/// SPEC §4 inverse: φ = 2π(u − ½), θ = πv, d = (sin θ sin φ, cos θ, −sin θ cos φ).
pub fn equirect_to_direction(u: f64, v: f64) -> DVec3 {
    let phi = std::f64::consts::TAU * (u - 0.5);
    let theta = std::f64::consts::PI * v;
    DVec3::new(
        theta.sin() * phi.sin(),
        theta.cos(),
        -theta.sin() * phi.cos(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn face_direction_inverts_face_selection() {
        for face in 0..6 {
            for (sc, tc) in [(0.0, 0.0), (0.5, -0.25), (-0.9, 0.8)] {
                let d = face_direction(face, sc, tc).normalize();
                let (f, s, t) = direction_to_face(d);
                assert_eq!(f, face);
                assert!((s - sc).abs() < 1e-12 && (t - tc).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn face_centres_are_the_axes_in_vulkan_order() {
        let axes = [
            DVec3::X,
            -DVec3::X,
            DVec3::Y,
            -DVec3::Y,
            DVec3::Z,
            -DVec3::Z,
        ];
        for (face, axis) in axes.iter().enumerate() {
            assert_eq!(face_direction(face, 0.0, 0.0), *axis);
        }
        // +X face: s grows towards −z, t grows towards −y (row 0 is the top, +y).
        assert_eq!(face_direction(0, 1.0, 0.0), DVec3::new(1.0, 0.0, -1.0));
        assert_eq!(face_direction(0, 0.0, 1.0), DVec3::new(1.0, -1.0, 0.0));
    }

    #[test]
    fn texel_solid_angles_sum_to_four_pi() {
        for m in [8u32, 32, 128] {
            let mut sum = 0.0;
            for j in 0..m {
                for i in 0..m {
                    sum += texel_solid_angle(i, j, m);
                }
            }
            let rel = (6.0 * sum - 4.0 * std::f64::consts::PI).abs() / (4.0 * std::f64::consts::PI);
            // Second-order midpoint rule: error ∝ 1/M².
            assert!(rel < 0.5 / f64::from(m * m), "M = {m}: {rel}");
        }
    }

    #[test]
    fn equirect_mapping_matches_spec_landmarks() {
        // Image centre is −Z; u = 0.75 is +X; v = 0 is +Y.
        let (u, v) = direction_to_equirect(-DVec3::Z);
        assert!((u - 0.5).abs() < 1e-15 && (v - 0.5).abs() < 1e-15);
        let (u, _) = direction_to_equirect(DVec3::X);
        assert!((u - 0.75).abs() < 1e-15);
        assert!(direction_to_equirect(DVec3::Y).1.abs() < 1e-15);
        let d = equirect_to_direction(0.3, 0.7);
        let (u, v) = direction_to_equirect(d);
        assert!((u - 0.3).abs() < 1e-12 && (v - 0.7).abs() < 1e-12);
    }

    #[test]
    fn rotation_turns_the_environment_about_y() {
        // Turning the environment by +90° brings what was at −Z to... world +X? R_y(90°) maps
        // −Z to −X (right-handed), so the world direction −X now sees the environment's −Z.
        let seen = world_to_environment(-DVec3::X, 90.0);
        assert!((seen - (-DVec3::Z)).length() < 1e-12, "{seen}");
    }
}
