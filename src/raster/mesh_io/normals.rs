//! Angle-weighted smooth vertex normals (Thürmer & Wüthrich 1998), for meshes that arrive
//! without normals.
//!
//! Owns only the normal computation. It smooths across exactly the vertices the index list
//! shares: a mesh that splits a vertex (a crease, a glTF non-indexed primitive) keeps that split
//! as a hard edge. Does not drop degenerate triangles from the mesh (the loaders do); it only
//! ignores them here.

use glam::DVec3;

/// A vertex whose summed normal is shorter than this fraction of its summed weight has
/// incident faces that cancel (a two-sided sheet sharing vertices); its direction would be
/// rounding noise, so the first incident face's normal is used instead.
const CANCELLATION_FRACTION: f64 = 1e-6;

/// One unit normal per position: Σ θ_i·n̂_i over the incident triangles, normalised, where θ_i is
/// the triangle's interior angle at the vertex and n̂_i its unit face normal (CCW = front).
///
/// Weighting by the angle makes the result independent of how a flat region is triangulated: a
/// cube corner gets normalize(1, 1, 1) whichever diagonal splits each face. Triangles with an
/// index out of range or zero area are ignored; a vertex no valid triangle touches gets
/// `[0, 0, 0]` (callers drop such vertices).
pub fn angle_weighted_normals(positions: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
    let mut sums = vec![DVec3::ZERO; positions.len()];
    let mut weights = vec![0.0f64; positions.len()];
    for_each_face(positions, indices, |corners, face_normal| {
        let points = corners.map(|(_, p)| p);
        for k in 0..3 {
            let (vertex, p) = corners[k];
            let angle = interior_angle(p, points[(k + 1) % 3], points[(k + 2) % 3]);
            sums[vertex] += face_normal * angle;
            weights[vertex] += angle;
        }
    });

    let mut normals = vec![[0.0f32; 3]; positions.len()];
    let mut cancelled = Vec::new();
    for (vertex, (sum, weight)) in sums.iter().zip(&weights).enumerate() {
        if *weight == 0.0 {
            continue;
        }
        if sum.length() > CANCELLATION_FRACTION * weight {
            normals[vertex] = to_f32(sum.normalize());
        } else {
            cancelled.push(vertex);
        }
    }
    if !cancelled.is_empty() {
        // Rare, so a second pass over the faces rather than a per-vertex fallback array.
        let mut pending = vec![false; positions.len()];
        for &vertex in &cancelled {
            pending[vertex] = true;
        }
        for_each_face(positions, indices, |corners, face_normal| {
            for (vertex, _) in corners {
                if pending[vertex] {
                    normals[vertex] = to_f32(face_normal);
                    pending[vertex] = false;
                }
            }
        });
    }
    normals
}

/// The unit face normal (b−a)×(c−a)/|…| in f64, or `None` for a zero-area or non-finite
/// triangle (whose normal is undefined).
pub fn face_normal(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Option<DVec3> {
    let (a, b, c) = (to_f64(a), to_f64(b), to_f64(c));
    (b - a).cross(c - a).try_normalize()
}

/// Calls `visit` with each valid triangle's (vertex index, position) corners and unit normal.
fn for_each_face(
    positions: &[[f32; 3]],
    indices: &[u32],
    mut visit: impl FnMut([(usize, DVec3); 3], DVec3),
) {
    for triangle in indices.chunks_exact(3) {
        let corner = |k: usize| {
            let vertex = triangle[k] as usize;
            positions.get(vertex).map(|&p| (vertex, p))
        };
        let (Some(a), Some(b), Some(c)) = (corner(0), corner(1), corner(2)) else {
            continue;
        };
        if let Some(normal) = face_normal(a.1, b.1, c.1) {
            visit([a, b, c].map(|(v, p)| (v, to_f64(p))), normal);
        }
    }
}

/// The angle at `p` between the edges to `q` and `r`; atan2 of |u×v| and u·v stays accurate for
/// angles near 0 and π, where acos of a normalised dot product loses half its digits.
fn interior_angle(p: DVec3, q: DVec3, r: DVec3) -> f64 {
    let (u, v) = (q - p, r - p);
    u.cross(v).length().atan2(u.dot(v))
}

fn to_f64(p: [f32; 3]) -> DVec3 {
    DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]))
}

fn to_f32(v: DVec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_close(actual: [f32; 3], expected: [f64; 3], tolerance: f64) {
        for k in 0..3 {
            assert!(
                (f64::from(actual[k]) - expected[k]).abs() < tolerance,
                "{actual:?} vs {expected:?}"
            );
        }
    }

    /// The unit cube [0,1]³ as 12 CCW-from-outside triangles on 8 shared corners; corner index
    /// bits are (x, y, z) = (i & 1, i >> 1 & 1, i >> 2 & 1).
    fn cube() -> (Vec<[f32; 3]>, Vec<u32>) {
        let positions = (0..8)
            .map(|i| [(i & 1) as f32, (i >> 1 & 1) as f32, (i >> 2 & 1) as f32])
            .collect();
        #[rustfmt::skip]
        let indices = vec![
            0, 2, 3, 0, 3, 1, // z = 0, normal -z
            4, 5, 7, 4, 7, 6, // z = 1, +z
            0, 1, 5, 0, 5, 4, // y = 0, -y
            2, 6, 7, 2, 7, 3, // y = 1, +y
            0, 4, 6, 0, 6, 2, // x = 0, -x
            1, 3, 7, 1, 7, 5, // x = 1, +x
        ];
        (positions, indices)
    }

    #[test]
    fn cube_corners_get_the_diagonal_whatever_the_face_split() {
        // At each corner three faces meet at 90° each; their split diagonals give one corner 1
        // triangle (90°) or 2 (45° + 45°) per face, the same total angle. So the normal is
        // (±1, ±1, ±1)/√3 pointing away from the centre. 1e-6: f32 output rounding.
        let (positions, indices) = cube();
        let normals = angle_weighted_normals(&positions, &indices);
        let s = 1.0 / 3f64.sqrt();
        for (p, n) in positions.iter().zip(&normals) {
            let expected = p.map(|c| if c > 0.5 { s } else { -s });
            assert_close(*n, expected, 1e-6);
        }
    }

    #[test]
    fn area_weighting_would_differ_but_angle_weighting_does_not() {
        // A vertex at the origin with two faces: the XY-plane quarter (a 90° corner split into a
        // large 10×10 triangle) and one small YZ triangle of angle 90°. Equal angles → equal
        // weights → normal = normalize((0,0,1) + (1,0,0)) although the areas are 50 : 0.5.
        let positions = vec![
            [0.0, 0.0, 0.0],
            [10.0, 0.0, 0.0],
            [0.0, 10.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 1.0, 0.0],
        ];
        // (0,1,2): CCW seen from +z; (0,4,3): (4−0)×(3−0) = (0,1,0)×(0,0,1) = (1,0,0).
        let normals = angle_weighted_normals(&positions, &[0, 1, 2, 0, 4, 3]);
        let s = 0.5f64.sqrt();
        assert_close(normals[0], [s, 0.0, s], 1e-6);
    }

    #[test]
    fn degenerate_and_out_of_range_triangles_are_ignored_and_lonely_vertices_get_zero() {
        let positions = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [2.0, 0.0, 0.0], // collinear with 0 and 1: the second triangle has zero area
            [5.0, 5.0, 5.0], // referenced by nothing valid
        ];
        let normals = angle_weighted_normals(&positions, &[0, 1, 2, 0, 1, 3, 4, 9, 2]);
        // Only the first triangle counts, CCW from +z.
        for vertex in [0, 1, 2] {
            assert_eq!(normals[vertex], [0.0, 0.0, 1.0]);
        }
        assert_eq!(normals[3], [0.0; 3]);
        assert_eq!(normals[4], [0.0; 3]);
    }

    #[test]
    fn opposite_faces_sharing_vertices_fall_back_to_a_face_normal() {
        // The same triangle listed both ways round: the sums cancel exactly, so each vertex takes
        // the first face's normal, +z, rather than noise or zero.
        let positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let normals = angle_weighted_normals(&positions, &[0, 1, 2, 0, 2, 1]);
        assert!(normals.iter().all(|n| *n == [0.0, 0.0, 1.0]), "{normals:?}");
    }
}
