//! Surfaces of revolution ("lathe" meshes) and the built-in `bowl` and `plate` of SPEC §5.
//!
//! Owns the 2D profiles and their revolution about +Y. A profile is a closed cross-section of a
//! solid in the (r, y) half-plane, from the axis back to the axis, made of runs of smooth pieces
//! (lines, circular arcs, cubic Béziers). Pieces inside a run meet with a common tangent; between
//! runs the profile has a deliberate crease (the foot ring's edges), where the mesh duplicates
//! the ring of vertices so each side keeps its own normal. Normals come from the pieces'
//! analytic tangents, not from averaging faces. Does not touch the GPU or mesh files.
//!
//! Conventions (both built-ins): axis +Y, standing on y = 0 (the foot ring's base), 1 unit =
//! 10 cm, so they fit inside the unit sphere and share one scale with each other.
//! The profile is walked with the solid on the right of the direction of travel; the outward
//! normal is then the tangent turned 90° anticlockwise, (−t_y, t_r). Revolving by φ (from +X
//! towards −Z, counter-clockwise seen from +Y, as `mesh::sphere`) maps (r, y) to
//! (r·cos φ, y, −r·sin φ).

use std::f64::consts::PI;

use glam::{DVec2, DVec3};

use super::mesh::Mesh;

/// Default segments around the axis for both built-ins.
pub const LATHE_SEGMENTS_AROUND: u32 = 256;
/// Default profile segments for both: 256·(2·196 − 2) = 99 840 triangles (SPEC §5: ~100k).
pub const LATHE_PROFILE_SEGMENTS: u32 = 196;

/// Profile units per centimetre: 1 unit = 10 cm.
const UNITS_PER_CM: f64 = 0.1;

/// One smooth piece of a profile, in centimetres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Piece {
    Line(DVec2, DVec2),
    /// Centre, radius, start and end angle (radians, measured from +r towards +y).
    Arc(DVec2, f64, f64, f64),
    /// A cubic Bézier by its four control points.
    Bezier([DVec2; 4]),
}

impl Piece {
    pub fn point(&self, u: f64) -> DVec2 {
        match *self {
            Piece::Line(a, b) => a.lerp(b, u),
            Piece::Arc(centre, radius, from, to) => {
                let angle = from + (to - from) * u;
                centre + radius * DVec2::new(angle.cos(), angle.sin())
            }
            Piece::Bezier([p0, p1, p2, p3]) => {
                let v = 1.0 - u;
                p0 * (v * v * v)
                    + p1 * (3.0 * v * v * u)
                    + p2 * (3.0 * v * u * u)
                    + p3 * (u * u * u)
            }
        }
    }

    /// d(point)/du, not normalised.
    pub fn derivative(&self, u: f64) -> DVec2 {
        match *self {
            Piece::Line(a, b) => b - a,
            Piece::Arc(_, radius, from, to) => {
                let angle = from + (to - from) * u;
                radius * (to - from) * DVec2::new(-angle.sin(), angle.cos())
            }
            Piece::Bezier([p0, p1, p2, p3]) => {
                let v = 1.0 - u;
                3.0 * ((p1 - p0) * (v * v) + (p2 - p1) * (2.0 * v * u) + (p3 - p2) * (u * u))
            }
        }
    }

    /// The unit tangent; where the derivative vanishes (a Bézier with coincident control points)
    /// the chord towards the inside of the piece gives the direction.
    pub fn tangent(&self, u: f64) -> DVec2 {
        self.derivative(u).try_normalize().unwrap_or_else(|| {
            let step = if u < 0.5 { 1e-4 } else { -1e-4 };
            ((self.point(u + step) - self.point(u)) * step.signum()).normalize_or_zero()
        })
    }

    fn reversed(&self) -> Piece {
        match *self {
            Piece::Line(a, b) => Piece::Line(b, a),
            Piece::Arc(c, radius, from, to) => Piece::Arc(c, radius, to, from),
            Piece::Bezier([p0, p1, p2, p3]) => Piece::Bezier([p3, p2, p1, p0]),
        }
    }
}

/// A closed cross-section: runs of G1-continuous pieces; consecutive runs meet at a crease.
#[derive(Clone, Debug, PartialEq)]
pub struct Profile {
    pub runs: Vec<Vec<Piece>>,
}

/// A sampled profile vertex: position (r, y) in units and the outward unit normal (n_r, n_y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProfileVertex {
    pub position: DVec2,
    pub normal: DVec2,
}

/// Below this radius (in units) a profile vertex is on the axis and becomes a single pole.
const AXIS_EPSILON: f64 = 1e-9;

/// Dense samples per piece for measuring length and turning.
const COST_SAMPLES: usize = 512;
/// Sampling cost: 1 mm of length weighs as much as 4° of turning, and the segment budget is spread
/// evenly over the cost, so flat walls get evenly spaced rings and the tight rim enough of them
/// for a round silhouette.
const COST_LENGTH_CM: f64 = 0.1;
const COST_TURN_RAD: f64 = 4.0 * PI / 180.0;

impl Profile {
    /// The sampled runs, `segments` edges in total (at least one per piece), spaced by length and
    /// turning. Positions are scaled to units.
    pub fn sample(&self, segments: u32) -> Vec<Vec<ProfileVertex>> {
        let pieces: Vec<&Piece> = self.runs.iter().flatten().collect();
        let tables: Vec<Vec<f64>> = pieces.iter().map(|p| cumulative_cost(p)).collect();
        let costs: Vec<f64> = tables.iter().map(|t| t[COST_SAMPLES]).collect();
        let counts = allocate(&costs, segments as usize);

        let mut counts = counts.into_iter();
        let mut tables = tables.iter();
        let mut runs = Vec::new();
        for run in &self.runs {
            let mut vertices = Vec::new();
            for piece in run {
                let (Some(count), Some(table)) = (counts.next(), tables.next()) else {
                    break;
                };
                // Piece k's first vertex is piece k−1's last: skip it after the first piece.
                let first = if vertices.is_empty() { 0 } else { 1 };
                for j in first..=count {
                    let u = parameter_at(table, table[COST_SAMPLES] * j as f64 / count as f64);
                    let t = piece.tangent(u);
                    vertices.push(ProfileVertex {
                        position: piece.point(u) * UNITS_PER_CM,
                        normal: DVec2::new(-t.y, t.x),
                    });
                }
            }
            runs.push(vertices);
        }
        runs
    }
}

/// Cost (length/COST_LENGTH_CM + turning/COST_TURN_RAD) from u = 0 to u = k/COST_SAMPLES.
fn cumulative_cost(piece: &Piece) -> Vec<f64> {
    let mut table = Vec::with_capacity(COST_SAMPLES + 1);
    table.push(0.0);
    let mut previous = piece.point(0.0);
    let mut previous_tangent = piece.tangent(0.0);
    for k in 1..=COST_SAMPLES {
        let u = k as f64 / COST_SAMPLES as f64;
        let (point, tangent) = (piece.point(u), piece.tangent(u));
        let turn = previous_tangent.angle_to(tangent).abs();
        let cost = (point - previous).length() / COST_LENGTH_CM + turn / COST_TURN_RAD;
        table.push(table[k - 1] + cost);
        (previous, previous_tangent) = (point, tangent);
    }
    table
}

/// Inverts the cumulative table by linear interpolation.
fn parameter_at(table: &[f64], cost: f64) -> f64 {
    let k = table.partition_point(|&c| c < cost).clamp(1, COST_SAMPLES);
    let (c0, c1) = (table[k - 1], table[k]);
    let fraction = if c1 > c0 {
        ((cost - c0) / (c1 - c0)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (k as f64 - 1.0 + fraction) / COST_SAMPLES as f64
}

/// Splits `total` segments in proportion to `costs` (largest remainder), at least one each.
fn allocate(costs: &[f64], total: usize) -> Vec<usize> {
    let sum: f64 = costs.iter().sum();
    let ideal: Vec<f64> = costs
        .iter()
        .map(|c| {
            if sum > 0.0 {
                c / sum * total as f64
            } else {
                1.0
            }
        })
        .collect();
    let mut counts: Vec<usize> = ideal.iter().map(|x| (x.floor() as usize).max(1)).collect();
    let mut order: Vec<usize> = (0..costs.len()).collect();
    order.sort_by(|&a, &b| (ideal[b] - ideal[b].floor()).total_cmp(&(ideal[a] - ideal[a].floor())));
    let assigned: usize = counts.iter().sum();
    for &i in order.iter().take(total.saturating_sub(assigned)) {
        counts[i] += 1;
    }
    counts
}

/// Revolves sampled runs about +Y with `around` segments (at least 3). A run's end on the axis
/// becomes one pole vertex; a crease (run boundary) duplicates the ring. Triangles are CCW seen
/// from the side the profile normal points to.
pub fn revolve(runs: &[Vec<ProfileVertex>], around: u32) -> Mesh {
    let around = around.max(3);
    let mut mesh = Mesh {
        positions: Vec::new(),
        normals: Vec::new(),
        indices: Vec::new(),
    };
    for run in runs {
        // Each ring: Some(first vertex index) for a full ring, None + pole index for the axis.
        let rings: Vec<Ring> = run.iter().map(|v| add_ring(&mut mesh, v, around)).collect();
        for pair in rings.windows(2) {
            add_band(&mut mesh, pair[0], pair[1], around);
        }
    }
    mesh
}

#[derive(Clone, Copy)]
enum Ring {
    Pole(u32),
    Full(u32),
}

fn add_ring(mesh: &mut Mesh, vertex: &ProfileVertex, around: u32) -> Ring {
    let first = mesh.positions.len() as u32;
    let (p, n) = (vertex.position, vertex.normal);
    if p.x.abs() < AXIS_EPSILON {
        mesh.positions.push([0.0, p.y as f32, 0.0]);
        mesh.normals.push([0.0, n.y.signum() as f32, 0.0]);
        return Ring::Pole(first);
    }
    for k in 0..around {
        let phi = 2.0 * PI * f64::from(k) / f64::from(around);
        let (sin, cos) = phi.sin_cos();
        let position = DVec3::new(p.x * cos, p.y, -p.x * sin);
        let normal = DVec3::new(n.x * cos, n.y, -n.x * sin);
        mesh.positions.push(position.as_vec3().to_array());
        mesh.normals.push(normal.as_vec3().to_array());
    }
    Ring::Full(first)
}

/// With ∂P/∂s along the profile and ∂P/∂φ around, ∂P/∂s × ∂P/∂φ = r·(n_r cos φ, n_y, −n_r sin φ)
/// (at φ = 0: (r′, y′, 0) × (0, 0, −r) = r·(−y′, r′, 0)), so (s,φ) → (s+1,φ) → (s,φ+1) is CCW
/// seen from the normal's side.
fn add_band(mesh: &mut Mesh, upper: Ring, lower: Ring, around: u32) {
    for k in 0..around {
        let next = (k + 1) % around;
        match (upper, lower) {
            (Ring::Pole(pole), Ring::Full(b)) => mesh.indices.extend([pole, b + k, b + next]),
            (Ring::Full(a), Ring::Pole(pole)) => mesh.indices.extend([a + k, pole, a + next]),
            (Ring::Full(a), Ring::Full(b)) => {
                mesh.indices.extend([a + k, b + k, a + next]);
                mesh.indices.extend([a + next, b + k, b + next]);
            }
            (Ring::Pole(_), Ring::Pole(_)) => {}
        }
    }
}

/// A rounded rim: the arc of radius `lip` reaching out to r = `outer_radius` and up to
/// y = `height`, tangent at both ends to walls running along ±(sin flare, cos flare).
/// Returns (arc from the inner wall over the top to the outer wall, inner end, outer end).
fn rim(outer_radius: f64, height: f64, lip: f64, flare: f64) -> (Piece, DVec2, DVec2) {
    let centre = DVec2::new(outer_radius - lip, height - lip);
    let inner_angle = PI - flare;
    let outer_angle = -flare;
    let at = |angle: f64| centre + lip * DVec2::new(angle.cos(), angle.sin());
    (
        Piece::Arc(centre, lip, inner_angle, outer_angle),
        at(inner_angle),
        at(outer_angle),
    )
}

fn direction(angle_from_horizontal_deg: f64) -> DVec2 {
    let a = angle_from_horizontal_deg.to_radians();
    DVec2::new(a.cos(), a.sin())
}

/// The wan (soup bowl) cross-section, in cm: rim Ø 12.0, height 7.2, foot ring Ø 6.2 × 1.0
/// high, walls 0.3 cm at the rim thickening towards the bottom (real lacquer wan: rim
/// 11.5–12.5 cm, height 7–8 cm, kōdai ~6 cm and ~1 cm tall).
pub fn bowl_profile() -> Profile {
    let flare = 6f64.to_radians();
    let wall_up = DVec2::new(flare.sin(), flare.cos());
    let (lip, lip_inner, lip_outer) = rim(6.0, 7.2, 0.16, flare);
    let inner_bottom = DVec2::new(0.0, 1.3);
    let foot_top = DVec2::new(3.0, 1.0);
    let foot_outer = DVec2::new(3.1, 0.0);
    let foot_inner = DVec2::new(2.62, 0.0);
    let underside_edge = DVec2::new(2.56, 0.55);
    let underside_centre = DVec2::new(0.0, 0.62);

    let inner_wall = Piece::Bezier([
        inner_bottom,
        inner_bottom + DVec2::new(3.6, 0.0),
        lip_inner - wall_up * 3.9,
        lip_inner,
    ]);
    let outer_wall = Piece::Bezier([
        foot_top,
        foot_top + direction(22.0) * 2.3,
        lip_outer - wall_up * 3.4,
        lip_outer,
    ]);
    let underside = Piece::Bezier([
        underside_edge,
        underside_edge + DVec2::new(-0.9, 0.05),
        underside_centre + DVec2::new(1.0, 0.0),
        underside_centre,
    ]);
    Profile {
        runs: vec![
            vec![inner_wall, lip, outer_wall.reversed()],
            vec![Piece::Line(foot_top, foot_outer)],
            vec![Piece::Line(foot_outer, foot_inner)],
            vec![Piece::Line(foot_inner, underside_edge)],
            vec![underside],
        ],
    }
}

/// A shallow round lacquer plate, in cm: Ø 18.0, 2.4 high, flat floor, low flared rim, foot
/// ring Ø 11.0 × 0.55 high.
pub fn plate_profile() -> Profile {
    let flare = 16f64.to_radians();
    let wall_up = DVec2::new(flare.sin(), flare.cos());
    let (lip, lip_inner, lip_outer) = rim(9.0, 2.4, 0.17, flare);
    let floor_centre = DVec2::new(0.0, 1.05);
    let floor_edge = DVec2::new(6.0, 1.05);
    let foot_top = DVec2::new(5.5, 0.55);
    let foot_outer = DVec2::new(5.55, 0.0);
    let foot_inner = DVec2::new(5.05, 0.0);
    let underside_edge = DVec2::new(5.0, 0.35);
    let underside_centre = DVec2::new(0.0, 0.42);

    let inner_rim = Piece::Bezier([
        floor_edge,
        floor_edge + DVec2::new(1.4, 0.0),
        lip_inner - wall_up * 0.7,
        lip_inner,
    ]);
    let outer_wall = Piece::Bezier([
        foot_top,
        foot_top + direction(6.0) * 1.6,
        lip_outer - wall_up * 1.1,
        lip_outer,
    ]);
    let underside = Piece::Bezier([
        underside_edge,
        underside_edge + DVec2::new(-1.6, 0.03),
        underside_centre + DVec2::new(1.8, 0.0),
        underside_centre,
    ]);
    Profile {
        runs: vec![
            vec![
                Piece::Line(floor_centre, floor_edge),
                inner_rim,
                lip,
                outer_wall.reversed(),
            ],
            vec![Piece::Line(foot_top, foot_outer)],
            vec![Piece::Line(foot_outer, foot_inner)],
            vec![Piece::Line(foot_inner, underside_edge)],
            vec![underside],
        ],
    }
}

/// The built-in bowl at a chosen tessellation.
pub fn bowl(around: u32, profile_segments: u32) -> Mesh {
    revolve(&bowl_profile().sample(profile_segments), around)
}

/// The built-in plate at a chosen tessellation.
pub fn plate(around: u32, profile_segments: u32) -> Mesh {
    revolve(&plate_profile().sample(profile_segments), around)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cylinder of radius 1 cm, height 1 cm, as three runs (top, side, bottom) with creases at
    /// both rims, walked with the solid on the right.
    fn cylinder() -> Profile {
        let (top_centre, top_rim) = (DVec2::new(0.0, 1.0), DVec2::new(1.0, 1.0));
        let (bottom_rim, bottom_centre) = (DVec2::new(1.0, 0.0), DVec2::new(0.0, 0.0));
        Profile {
            runs: vec![
                vec![Piece::Line(top_centre, top_rim)],
                vec![Piece::Line(top_rim, bottom_rim)],
                vec![Piece::Line(bottom_rim, bottom_centre)],
            ],
        }
    }

    #[test]
    fn cylinder_counts_normals_and_winding_match_the_hand_layout() {
        // One segment per piece, 4 around: top = pole + ring (5 vertices, 4 triangles), side =
        // 2 rings (8, 8), bottom = ring + pole (5, 4): 18 vertices, 16 triangles.
        let mesh = revolve(&cylinder().sample(3), 4);
        assert_eq!(mesh.positions.len(), 18);
        assert_eq!(mesh.triangle_count(), 16);
        mesh.validate().unwrap();
        // Normals: top +Y, bottom −Y, side radial (y = 0, along the position's xz). Exact: the
        // profile's lines are axis-aligned, and cos/sin of multiples of 90° round to 0 or ±1
        // within 1e-7 in f32.
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            let p = DVec3::from_array(p.map(f64::from));
            let n = DVec3::from_array(n.map(f64::from));
            let radial = DVec3::new(p.x, 0.0, p.z) / 0.1;
            let ok = (n - DVec3::Y).length() < 1e-7
                || (n + DVec3::Y).length() < 1e-7
                || (n - radial).length() < 1e-7;
            assert!(ok, "normal {n} at {p}");
        }
        // Winding: every triangle's (b−a)×(c−a) agrees with its vertices' normals.
        for t in mesh.indices.chunks_exact(3) {
            let [a, b, c] =
                [0, 1, 2].map(|k| DVec3::from_array(mesh.positions[t[k] as usize].map(f64::from)));
            let face = (b - a).cross(c - a);
            for &i in t {
                let n = DVec3::from_array(mesh.normals[i as usize].map(f64::from));
                assert!(
                    face.dot(n) > 0.0,
                    "triangle {t:?} faces away from its normals"
                );
            }
        }
        // Units: 1 cm = 0.1; the top is at y = 0.1 and the widest ring has radius 0.1.
        assert!((mesh.bounding_radius() - 0.1 * 2f64.sqrt()).abs() < 1e-7);
    }

    #[test]
    fn allocation_is_proportional_with_at_least_one_each() {
        assert_eq!(allocate(&[1.0, 1.0, 2.0], 8), vec![2, 2, 4]);
        // 10 × 0.2/10.2 ≈ 0.196 → raised to 1; 9.80 floors to 9, and the total 10 is reached.
        assert_eq!(allocate(&[0.2, 10.0], 10), vec![1, 9]);
        assert_eq!(allocate(&[1.0, 1.0, 1.0], 3), vec![1, 1, 1]);
    }

    #[test]
    fn arc_and_bezier_tangents_match_their_closed_forms() {
        // Quarter arc from (1,0) to (0,1) about the origin: tangent at angle a is (−sin a, cos a).
        let arc = Piece::Arc(DVec2::ZERO, 1.0, 0.0, PI / 2.0);
        let a = PI / 6.0;
        assert!((arc.tangent(1.0 / 3.0) - DVec2::new(-a.sin(), a.cos())).length() < 1e-12);
        assert!((arc.point(1.0) - DVec2::new(0.0, 1.0)).length() < 1e-12);
        // A Bézier's end tangents point along its first and last control legs.
        let bezier = Piece::Bezier([
            DVec2::ZERO,
            DVec2::new(2.0, 0.0),
            DVec2::new(3.0, 1.0),
            DVec2::new(3.0, 3.0),
        ]);
        assert_eq!(bezier.tangent(0.0), DVec2::X);
        assert_eq!(bezier.tangent(1.0), DVec2::Y);
        // (P0 + 3·P1 + 3·P2 + P3)/8 = ((0 + 6 + 9 + 3)/8, (0 + 0 + 3 + 3)/8).
        assert_eq!(bezier.point(0.5), DVec2::new(2.25, 0.75));
        // Coincident control points: the chord gives the direction.
        let pinched = Piece::Bezier([DVec2::ZERO, DVec2::ZERO, DVec2::new(1.0, 0.0), DVec2::X]);
        assert!((pinched.tangent(0.0) - DVec2::X).length() < 1e-6);
        // Reversal swaps the ends and the direction.
        assert_eq!(bezier.reversed().tangent(0.0), -DVec2::Y);
    }

    #[test]
    fn built_in_profiles_are_closed_and_g1_inside_runs() {
        for profile in [bowl_profile(), plate_profile()] {
            let pieces: Vec<&Piece> = profile.runs.iter().flatten().collect();
            // Starts and ends on the axis, horizontal there (so the poles are smooth).
            assert_eq!(pieces[0].point(0.0).x, 0.0);
            assert_eq!(pieces[pieces.len() - 1].point(1.0).x, 0.0);
            assert!(pieces[0].tangent(0.0).y.abs() < 1e-12);
            assert!(pieces[pieces.len() - 1].tangent(1.0).y.abs() < 1e-12);
            // Consecutive pieces share their end points (1e-12 cm: the same arithmetic).
            for pair in pieces.windows(2) {
                assert!((pair[0].point(1.0) - pair[1].point(0.0)).length() < 1e-12);
            }
            // Inside a run the tangent is continuous (1e-9 rad); across runs it is not (a crease
            // of more than 30°: the foot ring's corners are deliberate).
            for run in &profile.runs {
                for pair in run.windows(2) {
                    let turn = pair[0].tangent(1.0).angle_to(pair[1].tangent(0.0)).abs();
                    assert!(turn < 1e-9, "run not smooth: {turn} rad");
                }
            }
            for pair in profile.runs.windows(2) {
                let (Some(end), Some(start)) = (pair[0].last(), pair[1].first()) else {
                    panic!("empty run");
                };
                let turn = end.tangent(1.0).angle_to(start.tangent(0.0)).abs();
                assert!(turn > 30f64.to_radians(), "crease of only {turn} rad");
            }
        }
    }
}
