//! Triangle meshes for the GPU draw and the built-in shapes of SPEC §5 (sphere, board, and the
//! lathed bowl and plate of `lathe.rs`).
//!
//! Owns the vertex/index layout the draw uploads (f32 positions and normals, u32 indices,
//! counter-clockwise front faces seen from outside) and its validation. Does not touch the GPU
//! or mesh files (`mesh_io/`); the oracle ray-casts exact analytic shapes instead of these
//! tessellations.

use std::f64::consts::PI;

use super::lathe::{self, LATHE_PROFILE_SEGMENTS, LATHE_SEGMENTS_AROUND};
use crate::{Error, Result};

/// An indexed triangle list; `normals[i]` belongs to `positions[i]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub indices: Vec<u32>,
}

impl Mesh {
    /// Checks the mesh can be drawn without reading out of bounds or producing NaN shading.
    pub fn validate(&self) -> Result<()> {
        if self.normals.len() != self.positions.len() {
            return Err(Error::invalid(
                "mesh.normals",
                format!("{} normals", self.normals.len()),
                format!(
                    "there must be one normal per position ({} positions)",
                    self.positions.len()
                ),
            ));
        }
        if self.indices.is_empty() || self.indices.len() % 3 != 0 {
            return Err(Error::invalid(
                "mesh.indices",
                format!("{} indices", self.indices.len()),
                "a triangle list needs a non-zero multiple of 3 indices",
            ));
        }
        if let Some(&index) = self
            .indices
            .iter()
            .find(|&&i| i as usize >= self.positions.len())
        {
            return Err(Error::invalid(
                "mesh.indices",
                index,
                format!(
                    "every index must be below the vertex count {}",
                    self.positions.len()
                ),
            ));
        }
        if let Some(i) = self
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(Error::invalid(
                "mesh.positions",
                format!("vertex {i} = {:?}", self.positions[i]),
                "every coordinate must be a finite number",
            ));
        }
        if let Some(i) = self
            .normals
            .iter()
            .position(|n| !n.iter().all(|c| c.is_finite()) || n.iter().all(|&c| c == 0.0))
        {
            return Err(Error::invalid(
                "mesh.normals",
                format!("vertex {i} = {:?}", self.normals[i]),
                "every normal must be finite and non-zero",
            ));
        }
        Ok(())
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// The largest distance of a vertex from the origin (0 for an empty mesh).
    /// The axis-aligned bounding box (min, max) of the positions; None for a mesh without any.
    pub fn bounding_box(&self) -> Option<(glam::DVec3, glam::DVec3)> {
        let first = self.positions.first()?;
        let first = glam::Vec3::from_array(*first);
        let (min, max) = self.positions.iter().fold((first, first), |(lo, hi), p| {
            let p = glam::Vec3::from_array(*p);
            (lo.min(p), hi.max(p))
        });
        Some((min.as_dvec3(), max.as_dvec3()))
    }

    pub fn bounding_radius(&self) -> f64 {
        self.positions
            .iter()
            .map(|p| {
                let [x, y, z] = p.map(f64::from);
                (x * x + y * y + z * z).sqrt()
            })
            .fold(0.0, f64::max)
    }
}

/// The sphere's default tessellation, SPEC §5.
pub const SPHERE_SEGMENTS_AROUND: u32 = 256;
pub const SPHERE_SEGMENTS_DOWN: u32 = 128;

/// Unit sphere at the origin with vertex normal = position; CCW seen from outside.
///
/// One vertex at each pole and `segments_down - 1` rings of `segments_around` vertices, so there
/// are no degenerate pole triangles: 2 + (down-1)·around vertices, 2·around·(down-1) triangles.
/// Counts below 3 around or 2 down are raised to those minima (the smallest closed solid).
pub fn sphere(segments_around: u32, segments_down: u32) -> Mesh {
    let around = segments_around.max(3);
    let down = segments_down.max(2);
    let mut positions = Vec::with_capacity((2 + (down - 1) * around) as usize);
    positions.push([0.0, 1.0, 0.0]);
    for ring in 1..down {
        let theta = PI * f64::from(ring) / f64::from(down);
        for k in 0..around {
            // φ runs from +X towards -Z, i.e. counter-clockwise seen from +Y.
            let phi = 2.0 * PI * f64::from(k) / f64::from(around);
            positions.push([
                (theta.sin() * phi.cos()) as f32,
                theta.cos() as f32,
                (-theta.sin() * phi.sin()) as f32,
            ]);
        }
    }
    positions.push([0.0, -1.0, 0.0]);

    let north = 0;
    let south = 1 + (down - 1) * around;
    let ring_vertex = |ring: u32, k: u32| 1 + (ring - 1) * around + k % around;
    let mut indices = Vec::with_capacity((6 * around * (down - 1)) as usize);
    // Seen from outside, φ increases to the right and the north pole is up; each triangle
    // below is listed counter-clockwise in that view.
    for k in 0..around {
        indices.extend([north, ring_vertex(1, k), ring_vertex(1, k + 1)]);
    }
    for ring in 1..down - 1 {
        for k in 0..around {
            let (upper_left, upper_right) = (ring_vertex(ring, k), ring_vertex(ring, k + 1));
            let (lower_left, lower_right) =
                (ring_vertex(ring + 1, k), ring_vertex(ring + 1, k + 1));
            indices.extend([upper_left, lower_left, lower_right]);
            indices.extend([upper_left, lower_right, upper_right]);
        }
    }
    for k in 0..around {
        indices.extend([
            ring_vertex(down - 1, k),
            south,
            ring_vertex(down - 1, k + 1),
        ]);
    }

    Mesh {
        normals: positions.clone(),
        positions,
        indices,
    }
}

/// The measured sample board: a 2 × 2 square in the XZ plane at y = 0, normal +Y, CCW from +Y.
pub fn board() -> Mesh {
    Mesh {
        positions: vec![
            [-1.0, 0.0, -1.0],
            [-1.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 0.0, -1.0],
        ],
        normals: vec![[0.0, 1.0, 0.0]; 4],
        indices: vec![0, 1, 2, 0, 2, 3],
    }
}

/// The meshes shikki builds itself, named `builtin:<name>` on the command line.
///
/// [`BuiltinMesh::ALL`] and [`BuiltinMesh::name`] are the one list of them: parsing, error
/// messages, `--help` and `shikki mesh` all read it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BuiltinMesh {
    Sphere,
    Board,
    /// A lacquer soup bowl (wan) standing on y = 0: `lathe::bowl_profile`.
    Bowl,
    /// A shallow round lacquer plate standing on y = 0: `lathe::plate_profile`.
    Plate,
}

/// What a built-in's name follows: `builtin:bowl`.
pub const BUILTIN_PREFIX: &str = "builtin:";

/// The segment counts a tessellated built-in takes (segments around its +Y axis). 4 is the
/// coarsest closed solid (a sphere of 4 × 2); 2048 keeps the finest, the bowl's
/// 2048·(2·1568 − 2) ≈ 6.4 M triangles, far below the mesh loader's limit, so an exported file
/// always loads back.
pub const BUILTIN_SEGMENTS: std::ops::RangeInclusive<u32> = 4..=2048;

impl BuiltinMesh {
    /// Every built-in, in the order help and error messages list them.
    pub const ALL: [BuiltinMesh; 4] = [
        BuiltinMesh::Sphere,
        BuiltinMesh::Board,
        BuiltinMesh::Bowl,
        BuiltinMesh::Plate,
    ];

    /// The name after `builtin:`.
    pub fn name(self) -> &'static str {
        match self {
            BuiltinMesh::Sphere => "sphere",
            BuiltinMesh::Board => "board",
            BuiltinMesh::Bowl => "bowl",
            BuiltinMesh::Plate => "plate",
        }
    }

    /// `builtin:<name>`, as the command line and scene files spell it.
    pub fn spec(self) -> String {
        format!("{BUILTIN_PREFIX}{}", self.name())
    }

    /// "builtin:sphere, builtin:board, …": every built-in, for help and error messages.
    pub fn list() -> String {
        Self::ALL.map(Self::spec).join(", ")
    }

    /// `builtin:<name>`, or `<name>` alone, for one of [`BuiltinMesh::ALL`] (any case).
    pub fn parse(spec: &str) -> Result<Self> {
        let trimmed = spec.trim();
        // `sphere` alone names the built-in too (a mesh file needs an extension), in any case.
        let name = crate::text::builtin_name(trimmed).unwrap_or(trimmed);
        Self::ALL
            .into_iter()
            .find(|b| b.name().eq_ignore_ascii_case(name))
            .ok_or_else(|| {
                Error::invalid(
                    "mesh",
                    spec,
                    format!("unknown built-in mesh; valid: {}", Self::list()),
                )
            })
    }

    /// The segments around the axis of the default tessellation; `None` for the board, whose
    /// two triangles are exact.
    pub fn default_segments(self) -> Option<u32> {
        match self {
            BuiltinMesh::Sphere => Some(SPHERE_SEGMENTS_AROUND),
            BuiltinMesh::Board => None,
            BuiltinMesh::Bowl | BuiltinMesh::Plate => Some(LATHE_SEGMENTS_AROUND),
        }
    }

    /// The mesh at its default tessellation.
    pub fn mesh(self) -> Mesh {
        match self.default_segments() {
            Some(segments) => self.tessellate(segments),
            None => board(),
        }
    }

    /// The mesh with `segments` around its +Y axis (in [`BUILTIN_SEGMENTS`]); the other
    /// direction keeps the default's proportion (sphere: segments/2 down; bowl and plate:
    /// segments·196/256 along the profile), so `segments` = the default gives [`Self::mesh`].
    /// An error for the board, which has no segments, and for a count out of range.
    pub fn mesh_with_segments(self, segments: u32) -> Result<Mesh> {
        if self.default_segments().is_none() {
            return Err(Error::invalid(
                "segments",
                segments,
                format!(
                    "{} is exact and has no segments; only the tessellated built-ins take them ({})",
                    self.spec(),
                    Self::ALL
                        .into_iter()
                        .filter(|b| b.default_segments().is_some())
                        .map(Self::spec)
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
        if !BUILTIN_SEGMENTS.contains(&segments) {
            return Err(Error::invalid(
                "segments",
                segments,
                format!(
                    "{} takes {}..={} segments around its axis",
                    self.spec(),
                    BUILTIN_SEGMENTS.start(),
                    BUILTIN_SEGMENTS.end()
                ),
            ));
        }
        Ok(self.tessellate(segments))
    }

    /// `segments` around; the second count is the default ratio, rounded to nearest.
    fn tessellate(self, around: u32) -> Mesh {
        let scaled = |default_other: u32, default_around: u32| {
            ((around * default_other + default_around / 2) / default_around).max(1)
        };
        match self {
            BuiltinMesh::Sphere => {
                sphere(around, scaled(SPHERE_SEGMENTS_DOWN, SPHERE_SEGMENTS_AROUND))
            }
            BuiltinMesh::Board => board(),
            BuiltinMesh::Bowl => lathe::bowl(
                around,
                scaled(LATHE_PROFILE_SEGMENTS, LATHE_SEGMENTS_AROUND),
            ),
            BuiltinMesh::Plate => lathe::plate(
                around,
                scaled(LATHE_PROFILE_SEGMENTS, LATHE_SEGMENTS_AROUND),
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn vertex(mesh: &Mesh, i: u32) -> DVec3 {
        let [x, y, z] = mesh.positions[i as usize].map(f64::from);
        DVec3::new(x, y, z)
    }

    /// Unnormalised face normal (b-a)×(c-a): points to the side from which a, b, c run CCW.
    fn face_normals(mesh: &Mesh) -> impl Iterator<Item = (DVec3, DVec3)> + '_ {
        mesh.indices.chunks_exact(3).map(|t| {
            let (a, b, c) = (vertex(mesh, t[0]), vertex(mesh, t[1]), vertex(mesh, t[2]));
            ((b - a).cross(c - a), (a + b + c) / 3.0)
        })
    }

    #[test]
    fn sphere_counts_match_the_pole_and_ring_layout() {
        // 4 around × 3 down: poles + 2 rings of 4 = 10 vertices; 4 + 4·2 (one band) + 4 = 16
        // triangles, by counting the octahedron-like solid by hand.
        let small = sphere(4, 3);
        assert_eq!(small.positions.len(), 10);
        assert_eq!(small.triangle_count(), 16);
        // Default: 2 + 127·256 = 32514 vertices, 2·256·127 = 65024 triangles.
        let default = BuiltinMesh::Sphere.mesh();
        assert_eq!(default.positions.len(), 32_514);
        assert_eq!(default.triangle_count(), 65_024);
        default.validate().unwrap();
    }

    #[test]
    fn sphere_vertices_are_on_the_unit_sphere_with_normal_equal_to_position() {
        let mesh = sphere(64, 32);
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            let length = p.map(f64::from).iter().map(|c| c * c).sum::<f64>().sqrt();
            // 3e-7: each f32 coordinate is rounded once (half an ulp ≈ 6e-8 relative).
            assert!((length - 1.0).abs() < 3e-7, "{p:?} has length {length}");
            assert_eq!(p, n);
        }
        // Bounding radius 1 within the same f32 rounding.
        assert!((mesh.bounding_radius() - 1.0).abs() < 3e-7);
    }

    #[test]
    fn sphere_triangles_are_ccw_from_outside() {
        for mesh in [sphere(3, 2), sphere(4, 3), sphere(64, 32)] {
            for (normal, centroid) in face_normals(&mesh) {
                assert!(normal.dot(centroid) > 0.0, "inward face at {centroid}");
            }
        }
    }

    #[test]
    fn sphere_is_closed() {
        // Every undirected edge is shared by exactly two triangles, in opposite directions.
        let mesh = sphere(8, 5);
        let mut edges = std::collections::HashMap::new();
        for t in mesh.indices.chunks_exact(3) {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *edges.entry((a, b)).or_insert(0) += 1;
            }
        }
        for (&(a, b), &count) in &edges {
            assert_eq!(count, 1, "edge {a}->{b} used {count} times");
            assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}->{b} has no twin");
        }
    }

    #[test]
    fn board_faces_up_and_spans_two_by_two() {
        let mesh = board();
        mesh.validate().unwrap();
        assert_eq!(mesh.triangle_count(), 2);
        assert!(mesh.normals.iter().all(|n| *n == [0.0, 1.0, 0.0]));
        let mut area = 0.0;
        for (normal, _) in face_normals(&mesh) {
            // CCW from +Y: the face normal is along +Y with no other component.
            assert!(normal.y > 0.0 && normal.x == 0.0 && normal.z == 0.0);
            area += 0.5 * normal.length();
        }
        assert_eq!(area, 4.0);
        assert_eq!(mesh.bounding_radius(), 2f64.sqrt());
    }

    #[test]
    fn validate_rejects_broken_meshes() {
        let good = board();
        let mut cases: Vec<(Mesh, &str)> = Vec::new();
        let mut m = good.clone();
        m.normals.pop();
        cases.push((m, "mesh.normals"));
        let mut m = good.clone();
        m.indices.pop();
        cases.push((m, "mesh.indices"));
        let mut m = good.clone();
        m.indices.clear();
        cases.push((m, "mesh.indices"));
        let mut m = good.clone();
        m.indices[4] = 4;
        cases.push((m, "mesh.indices"));
        let mut m = good.clone();
        m.positions[2][1] = f32::NAN;
        cases.push((m, "mesh.positions"));
        let mut m = good.clone();
        m.normals[3] = [0.0; 3];
        cases.push((m, "mesh.normals"));
        let mut m = good;
        m.normals[0][0] = f32::INFINITY;
        cases.push((m, "mesh.normals"));
        for (mesh, field) in cases {
            match mesh.validate() {
                Err(Error::InvalidParameter { field: f, .. }) => assert_eq!(f, field),
                other => panic!("expected invalid {field}, got {other:?}"),
            }
        }
    }

    #[test]
    fn every_builtin_round_trips_through_its_spec_and_the_list_names_each() {
        let list = BuiltinMesh::list();
        for builtin in BuiltinMesh::ALL {
            assert_eq!(BuiltinMesh::parse(&builtin.spec()).unwrap(), builtin);
            assert!(list.contains(&builtin.spec()), "{list}");
        }
        // The names are distinct, so parse finds exactly one.
        let mut names = BuiltinMesh::ALL.map(BuiltinMesh::name).to_vec();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), BuiltinMesh::ALL.len());
    }

    #[test]
    fn segments_at_the_default_give_the_default_mesh_and_errors_name_the_range() {
        for builtin in BuiltinMesh::ALL {
            match builtin.default_segments() {
                Some(default) => {
                    assert_eq!(builtin.mesh_with_segments(default).unwrap(), builtin.mesh());
                    let coarse = builtin
                        .mesh_with_segments(*BUILTIN_SEGMENTS.start())
                        .unwrap();
                    coarse.validate().unwrap();
                    for bad in [BUILTIN_SEGMENTS.start() - 1, BUILTIN_SEGMENTS.end() + 1, 0] {
                        match builtin.mesh_with_segments(bad) {
                            Err(Error::InvalidParameter { reason, .. }) => {
                                assert!(reason.contains("4..=2048"), "{reason}")
                            }
                            other => panic!("{bad}: {other:?}"),
                        }
                    }
                }
                None => match builtin.mesh_with_segments(64) {
                    Err(Error::InvalidParameter { reason, .. }) => {
                        assert!(reason.contains("no segments"), "{reason}")
                    }
                    other => panic!("{other:?}"),
                },
            }
        }
        // Sphere: N around, N/2 down (8 × 4: 2 + 3·8 vertices, 2·8·3 triangles).
        let sphere = BuiltinMesh::Sphere.mesh_with_segments(8).unwrap();
        assert_eq!(sphere.positions.len(), 26);
        assert_eq!(sphere.triangle_count(), 48);
    }

    #[test]
    fn builtin_names_parse_and_errors_list_the_valid_ones() {
        assert_eq!(
            BuiltinMesh::parse("builtin:sphere").unwrap(),
            BuiltinMesh::Sphere
        );
        assert_eq!(
            BuiltinMesh::parse("builtin:board").unwrap(),
            BuiltinMesh::Board
        );
        assert_eq!(
            BuiltinMesh::parse("builtin:bowl").unwrap(),
            BuiltinMesh::Bowl
        );
        assert_eq!(
            BuiltinMesh::parse(" builtin:plate ").unwrap(),
            BuiltinMesh::Plate
        );
        // A name alone and any case, as scene files, the CLI and the C API write them.
        assert_eq!(BuiltinMesh::parse("sphere").unwrap(), BuiltinMesh::Sphere);
        assert_eq!(BuiltinMesh::parse("Bowl").unwrap(), BuiltinMesh::Bowl);
        assert_eq!(
            BuiltinMesh::parse("BUILTIN:Plate").unwrap(),
            BuiltinMesh::Plate
        );
        for bad in ["builtin:cube", "cube", "bowl.obj", "builtin:", ""] {
            match BuiltinMesh::parse(bad) {
                Err(Error::InvalidParameter { reason, .. }) => {
                    for name in ["sphere", "board", "bowl", "plate"] {
                        assert!(reason.contains(&format!("builtin:{name}")), "{reason}");
                    }
                }
                other => panic!("{bad}: {other:?}"),
            }
        }
    }
}
