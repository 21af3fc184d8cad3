//! Direction bins of the rough split's lights (bright.rs `split_bright_rough`), so that a narrow
//! lobe visits only the lights near its mirror direction instead of all of them (on lavapipe a
//! loop's every lap costs a whole light: both sides of each `if` run under a lane mask, quirk
//! `loop_body_runs_when_no_lane_enters`).
//!
//! The cells are the cube's faces cut into `ENV_LIGHT_BIN_CELLS`² squares of face coordinates
//! (cube.rs's face table). A cell lists every light within `cull + radius + BIN_MARGIN` of its
//! centre, where `cull` is the light's cull angle (`brdf_quadrature::light_cull_cos`) at the
//! largest m the bins serve and `radius` the angle from the centre to the cell's farthest
//! corner: a mirror direction R inside the cell then finds in its list every light that
//! `bright_light` (brdf_environment.glsl) does not cull for any m up to that one. The bins change which lights a pixel visits, never the sum: a light left out
//! would have added an exact 0. Read by brdf_environment.glsl `binned_rough_bright_specular`.
//!
//! The texels (RGBA32F, appended to the draw's knot buffer at `Frame::env_rough.z`): one header
//! per cell, face after face, row after row, (first, count, 0, 0) with `first` the cell's first
//! entry in the list; then the list, two texels per entry, the light's (direction, 0) and
//! (irradiance, 0) as the frame packs them, each cell's lights in the frame's order (that of the
//! full loop, so the sum is the same number). The lights themselves, not their indices: lavapipe
//! loads a uniform array at an index that differs between lanes lane by lane, and gathers a
//! texel per lane in one go (quirk `ssbo_gather_is_per_lane`).

use super::brdf_quadrature::light_cull_cos;
use super::cube::{direction_to_face, face_direction};
use crate::gpu::shaders::interface::ENV_LIGHT_BIN_CELLS;
use glam::DVec3;

/// Slack (radians) on each cell's reach: the shader places R in a cell and tests the angle to a
/// light in f32 (~1e-7 rad each); a thousand times that keeps every light it would not cull.
pub const BIN_MARGIN: f64 = 1e-4;

/// The cell holding direction `d` (not zero): face·C² + row·C + column, C = `ENV_LIGHT_BIN_CELLS`
/// (the shader's `light_bin`).
pub fn light_bin(d: DVec3) -> usize {
    let (face, sc, tc) = direction_to_face(d);
    let cell = |x: f64| {
        (((x + 1.0) * 0.5 * ENV_LIGHT_BIN_CELLS as f64).floor() as usize)
            .min(ENV_LIGHT_BIN_CELLS - 1)
    };
    (face * ENV_LIGHT_BIN_CELLS + cell(tc)) * ENV_LIGHT_BIN_CELLS + cell(sc)
}

/// The bins of `lights`, packed as the shader reads them ((direction, spread), (irradiance, 0);
/// the direction unit), for every m up to `max_m`, as texels (module doc).
pub fn light_bin_texels(lights: &[([f32; 4], [f32; 4])], max_m: f64) -> Vec<[f32; 4]> {
    let cells = ENV_LIGHT_BIN_CELLS;
    // Each light's cull angle at max_m with the margin, as (angle, cos, sin).
    let culls: Vec<(f64, f64, f64)> = lights
        .iter()
        .map(|(d, _)| {
            let angle = light_cull_cos(max_m, f64::from(d[3]))
                .clamp(-1.0, 1.0)
                .acos()
                + BIN_MARGIN;
            (angle, angle.cos(), angle.sin())
        })
        .collect();
    let directions: Vec<DVec3> = lights
        .iter()
        .map(|(d, _)| DVec3::new(f64::from(d[0]), f64::from(d[1]), f64::from(d[2])))
        .collect();
    let mut headers = Vec::with_capacity(6 * cells * cells);
    let mut list: Vec<[f32; 4]> = Vec::new();
    let edge = |i: usize| -1.0 + 2.0 * i as f64 / cells as f64;
    for face in 0..6 {
        for row in 0..cells {
            for column in 0..cells {
                let centre_sc = 0.5 * (edge(column) + edge(column + 1));
                let centre_tc = 0.5 * (edge(row) + edge(row + 1));
                let centre = face_direction(face, centre_sc, centre_tc).normalize();
                // A cell is a convex spherical quadrilateral: its farthest point from the centre
                // is a corner.
                let radius = [(0, 0), (1, 0), (0, 1), (1, 1)]
                    .into_iter()
                    .map(|(i, j)| {
                        let corner = face_direction(face, edge(column + i), edge(row + j));
                        centre.angle_between(corner)
                    })
                    .fold(0.0, f64::max);
                let (cos_r, sin_r) = (radius.cos(), radius.sin());
                let first = list.len() / 2;
                for ((light, direction), &(cull, cos_c, sin_c)) in
                    lights.iter().zip(&directions).zip(&culls)
                {
                    // Within cull + radius of the centre: cos of the sum by its formula.
                    let keep = cull + radius >= std::f64::consts::PI
                        || centre.dot(*direction) >= cos_c * cos_r - sin_c * sin_r;
                    if keep {
                        list.extend([light.0, light.1]);
                    }
                }
                headers.push([first as f32, (list.len() / 2 - first) as f32, 0.0, 0.0]);
            }
        }
    }
    headers.extend(list);
    headers
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Directions spread over the sphere (a Fibonacci lattice), plus the cube's edges and
    /// corners and cell boundaries, where the cell a direction lands in is decided by rounding.
    fn directions(count: usize) -> Vec<DVec3> {
        let golden = std::f64::consts::PI * (3.0 - 5.0_f64.sqrt());
        let mut dirs: Vec<DVec3> = (0..count)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / count as f64;
                let r = (1.0 - z * z).sqrt();
                DVec3::new(
                    r * (golden * i as f64).cos(),
                    z,
                    r * (golden * i as f64).sin(),
                )
            })
            .collect();
        for face in 0..6 {
            for k in 0..=ENV_LIGHT_BIN_CELLS {
                let x = -1.0 + 2.0 * k as f64 / ENV_LIGHT_BIN_CELLS as f64;
                for y in [-1.0, -0.37, 0.0, 0.61, 1.0] {
                    dirs.push(face_direction(face, x, y).normalize());
                    dirs.push(face_direction(face, y, x).normalize());
                }
            }
        }
        dirs
    }

    /// Every light a mirror direction keeps (within the cull angle at the bins' m, or any
    /// smaller m) is in the list of the cell that direction lands in, including at cell edges;
    /// and a list holds far fewer than all lights where the cull is narrow.
    #[test]
    fn a_cell_lists_every_light_its_directions_keep() {
        let lights = directions(300);
        // The light's index as its irradiance, to read the lists back by; every third light has
        // the spread of a 3° block.
        let spread = |i: usize| match i % 3 {
            0 => 3f64.to_radians().powi(2) / 12.0,
            _ => 0.0,
        };
        let packed: Vec<([f32; 4], [f32; 4])> = lights
            .iter()
            .enumerate()
            .map(|(i, d)| {
                let direction = [d.x as f32, d.y as f32, d.z as f32, spread(i) as f32];
                (direction, [i as f32, 0.0, 0.0, 0.0])
            })
            .collect();
        let max_m = 0.06;
        let texels = light_bin_texels(&packed, max_m);
        let cells = 6 * ENV_LIGHT_BIN_CELLS * ENV_LIGHT_BIN_CELLS;
        let list = |bin: usize| -> Vec<usize> {
            let [first, count, ..] = texels[bin];
            (first as usize..(first + count) as usize)
                .map(|k| {
                    assert_eq!(
                        texels[cells + 2 * k],
                        packed[texels[cells + 2 * k + 1][0] as usize].0
                    );
                    texels[cells + 2 * k + 1][0] as usize
                })
                .collect()
        };
        let mut longest = 0;
        for r in directions(5000) {
            let listed = list(light_bin(r));
            longest = longest.max(listed.len());
            assert!(listed.windows(2).all(|w| w[0] < w[1]), "{listed:?}");
            for m in [0.01, 0.03, max_m] {
                for (i, l) in lights.iter().enumerate() {
                    if r.dot(*l) >= light_cull_cos(m, f64::from(packed[i].0[3])) {
                        assert!(listed.contains(&i), "R {r}, m {m}: light {i} not listed");
                    }
                }
            }
        }
        // At m = 0.06 the cull is 20° (2·atan(3·0.06)); a cell reaches ~2° further: under a
        // tenth of the sphere.
        assert!(longest < lights.len() / 4, "{longest} of {}", lights.len());
    }
}
