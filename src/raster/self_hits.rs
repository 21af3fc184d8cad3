//! Which meshes rays leaving them never meet again, for the ray-traced shading pass
//! (visibility.glsl's `trace_mask`) and its CPU twin (`oracle::shadows`).
//!
//! A mesh that is convex on the side a surface point is shaded from stands for a smooth convex
//! surface, and a ray leaving such a surface never meets it again: rays leaving it leave its
//! instance out. That is SPEC §6 for the surface the normals describe. Traced against the flat
//! triangles instead, a ray just above the shading normal's horizon but below its face's plane
//! entered the mesh and met its far side: a lone sphere's silhouette pixels differed from the
//! image without ray tracing by up to 0.4 % of the pixel (46 % in a dark channel; found by a probe,
//! 2026-12-06), where SPEC §6 says they are equal. It also saves lavapipe the walk of the mesh's
//! bottom-level structure that most such rays needed (the origin lies inside the mesh's box): most
//! of a lone sphere's render time (BENCHMARKS.md, "Rays that cannot meet their own mesh").
//!
//! What is classified, per mesh, is whether every vertex lies on or behind the plane of every
//! face, as seen from the face's winding normal n = (p1 − p0) × (p2 − p0) / |…| ("front": a ray
//! leaving a face along +n never meets the mesh), or on or in front of it ("back": along −n),
//! within a slack of 2^-20 of the mesh's largest coordinate. A convex closed mesh wound outwards
//! is front-clear, one wound inwards back-clear, a flat one both; a bowl neither.
//!
//! The check visits, per face, the nodes of a tree over the vertices whose bounds reach above the
//! plane: near the face itself for a convex mesh, and it stops at the first vertex above a face
//! for one that is not. It runs at upload, while the render's pipelines build on another core.

use super::mesh::Mesh;
use crate::gpu::shaders::interface::TRACE_MASK_SHARED;
use glam::DVec3;

/// Whether rays leaving a mesh's faces can meet it again (see the module comment).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SelfHits {
    /// Every vertex lies on or behind every face's plane (as seen from its winding normal): a
    /// ray leaving a face along its winding normal's side never meets the mesh again.
    pub front_clear: bool,
    /// Every vertex lies on or in front of every face's plane: the same for rays leaving along
    /// −n.
    pub back_clear: bool,
    /// How far a vertex may lie on the wrong side of a face's plane and still count as on it:
    /// 2^-20 of the mesh's largest coordinate (f32 meshes are rarely exactly convex: a sphere's
    /// quads split in two have their fourth vertex a few ulps off the plane).
    pub slack: f32,
}

impl SelfHits {
    /// Rays leaving any face may meet the mesh again (a mesh that is not convex).
    pub const ANY: SelfHits = SelfHits {
        front_clear: false,
        back_clear: false,
        slack: 0.0,
    };

    /// The mesh's classification (see the module comment).
    pub fn of(mesh: &Mesh) -> SelfHits {
        let points: Vec<DVec3> = mesh
            .positions
            .iter()
            .map(|p| DVec3::from_array(p.map(f64::from)))
            .collect();
        let largest = points
            .iter()
            .map(|p| p.abs().max_element())
            .fold(0.0, f64::max);
        let slack = largest * 2f64.powi(-20);
        let normals: Vec<DVec3> = mesh
            .normals
            .iter()
            .map(|n| DVec3::from_array(n.map(f64::from)))
            .collect();
        let tree = BoxTree::new(&points, &normals);
        let mut stack = Vec::new();
        let (mut front, mut back) = (true, true);
        for face in mesh.indices.chunks_exact(3) {
            let corner = |k: usize| points.get(face[k] as usize).copied();
            let (Some(p0), Some(p1), Some(p2)) = (corner(0), corner(1), corner(2)) else {
                return SelfHits::ANY;
            };
            // A face without area has no plane; the shader never skips on one either.
            let Some(n) = (p1 - p0).cross(p2 - p0).try_normalize() else {
                continue;
            };
            let offset = n.dot(p0);
            front = front && tree.nothing_above(n, offset + slack, &mut stack);
            back = back && tree.nothing_above(-n, -offset + slack, &mut stack);
            if !front && !back {
                return SelfHits::ANY;
            }
        }
        SelfHits {
            front_clear: front,
            back_clear: back,
            slack: slack as f32,
        }
    }
}

/// Vertices in leaves of at most this many. The leaves by a face straddle its plane whatever
/// their size, and a scan of 32 contiguous points costs less than the nodes above 8 would
/// (BENCHMARKS.md).
const LEAF_SIZE: usize = 32;

/// A binary tree of axis-aligned boxes over a point set, split at the median of the widest axis.
struct BoxTree<'a> {
    points: &'a [DVec3],
    /// The points' normals (the mesh's), which only orient the nodes' cylinders.
    normals: &'a [DVec3],
    /// Point indices, reordered so that each node's points are contiguous.
    order: Vec<u32>,
    /// The points in that order.
    sorted: Vec<DVec3>,
    nodes: Vec<Node>,
}

/// A node bounds its points twice: by their box, and by a cylinder about an axis m through their
/// centroid c (m the mean of their normals, any unit vector would do): each point is
/// c + h·m + q with q ⊥ m, h in [h_min, h_max], |q| ≤ q_max. The box is tight for a node far
/// from a face; the cylinder for a patch of a curved surface seen from a face on it (n ≈ m), whose
/// box's corners stand far above the face's plane.
struct Node {
    min: DVec3,
    max: DVec3,
    centroid: DVec3,
    axis: DVec3,
    h_min: f64,
    h_max: f64,
    q_max: f64,
    /// The node's points: `order[first..first + count]`.
    first: usize,
    count: usize,
    /// Its children's indices in `nodes` (none for a leaf).
    children: Option<(usize, usize)>,
}

impl<'a> BoxTree<'a> {
    fn new(points: &'a [DVec3], normals: &'a [DVec3]) -> Self {
        let mut tree = BoxTree {
            points,
            normals,
            order: (0..points.len() as u32).collect(),
            sorted: Vec::new(),
            nodes: Vec::new(),
        };
        if !points.is_empty() {
            tree.build(0, points.len());
        }
        tree.sorted = tree.order.iter().map(|&i| points[i as usize]).collect();
        tree
    }

    /// Adds the node over `order[first..first + count]` (and its subtree); returns its index.
    fn build(&mut self, first: usize, count: usize) -> usize {
        let slice = &mut self.order[first..first + count];
        let (mut min, mut max) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for &i in slice.iter() {
            min = min.min(self.points[i as usize]);
            max = max.max(self.points[i as usize]);
        }
        let centroid = slice
            .iter()
            .map(|&i| self.points[i as usize])
            .sum::<DVec3>()
            / count as f64;
        let axis = slice
            .iter()
            .filter_map(|&i| self.normals.get(i as usize))
            .sum::<DVec3>()
            .try_normalize()
            .unwrap_or(DVec3::Z);
        let (mut h_min, mut h_max, mut q_max) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
        for &i in slice.iter() {
            let r = self.points[i as usize] - centroid;
            let h = r.dot(axis);
            h_min = h_min.min(h);
            h_max = h_max.max(h);
            q_max = q_max.max((r - h * axis).length());
        }
        let index = self.nodes.len();
        self.nodes.push(Node {
            min,
            max,
            centroid,
            axis,
            h_min,
            h_max,
            // Rounding of the subtraction above: a relative 2^-40 of the point's size.
            q_max: q_max * (1.0 + 2f64.powi(-40))
                + 2f64.powi(-40) * max.abs().max(min.abs()).max_element(),
            first,
            count,
            children: None,
        });
        if count > LEAF_SIZE {
            let extent = max - min;
            let axis = if extent.x >= extent.y && extent.x >= extent.z {
                0
            } else if extent.y >= extent.z {
                1
            } else {
                2
            };
            let half = count / 2;
            let points = self.points;
            slice.select_nth_unstable_by(half, |&a, &b| {
                points[a as usize][axis].total_cmp(&points[b as usize][axis])
            });
            let left = self.build(first, half);
            let right = self.build(first + half, count - half);
            self.nodes[index].children = Some((left, right));
        }
        index
    }

    /// Whether n·p ≤ limit for every point p (`stack`: scratch, reused across calls).
    fn nothing_above(&self, n: DVec3, limit: f64, stack: &mut Vec<usize>) -> bool {
        stack.clear();
        if !self.nodes.is_empty() {
            stack.push(0);
        }
        while let Some(index) = stack.pop() {
            let node = &self.nodes[index];
            // The box's highest corner along n, and the cylinder's highest point.
            let box_top = n.x * if n.x > 0.0 { node.max.x } else { node.min.x }
                + n.y * if n.y > 0.0 { node.max.y } else { node.min.y }
                + n.z * if n.z > 0.0 { node.max.z } else { node.min.z };
            let along = n.dot(node.axis);
            let across = (n - along * node.axis).length();
            let cylinder_top = n.dot(node.centroid)
                + (along * node.h_min).max(along * node.h_max)
                + across * node.q_max;
            if box_top.min(cylinder_top) <= limit {
                continue;
            }
            match node.children {
                Some((left, right)) => {
                    stack.push(left);
                    stack.push(right);
                }
                None => {
                    let points = &self.sorted[node.first..node.first + node.count];
                    let top = points
                        .iter()
                        .map(|p| n.x * p.x + n.y * p.y + n.z * p.z)
                        .fold(f64::MIN, f64::max);
                    if top > limit {
                        return false;
                    }
                }
            }
        }
        true
    }
}

/// Per object, given its mesh's triangle count and classification, the instance mask bit that
/// rays leaving it leave out where its mesh is convex on their side (visibility.glsl's
/// `trace_mask`): a bit of its own below `TRACE_MASK_SHARED` for each of the first seven objects
/// with a clear side, 0 for every other object (its rays are traced against its triangles). The
/// GPU's instances and the CPU twin (`oracle::shadows::TracedScene`) both take these.
pub fn own_mask_bits(meshes: impl Iterator<Item = (u32, SelfHits)>) -> Vec<u32> {
    let mut next = 1;
    meshes
        .map(|(triangles, hits)| {
            let clear = triangles > 0 && (hits.front_clear || hits.back_clear);
            match clear && next < TRACE_MASK_SHARED {
                true => {
                    next <<= 1;
                    next >> 1
                }
                false => 0,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::BuiltinMesh;

    fn flipped(mut mesh: Mesh) -> Mesh {
        for face in mesh.indices.chunks_exact_mut(3) {
            face.swap(1, 2);
        }
        mesh
    }

    fn classes(mesh: &Mesh) -> (bool, bool) {
        let c = SelfHits::of(mesh);
        (c.front_clear, c.back_clear)
    }

    #[test]
    fn the_builtins_are_classified_by_their_shape() {
        // The sphere is convex and wound outwards, the board flat; the bowl and the tray hold
        // their own inside.
        assert_eq!(classes(&BuiltinMesh::Sphere.mesh()), (true, false));
        assert_eq!(classes(&BuiltinMesh::Board.mesh()), (true, true));
        assert_eq!(classes(&BuiltinMesh::Bowl.mesh()), (false, false));
        assert_eq!(classes(&BuiltinMesh::Plate.mesh()), (false, false));
    }

    #[test]
    fn winding_inwards_clears_the_other_side() {
        assert_eq!(classes(&flipped(BuiltinMesh::Sphere.mesh())), (false, true));
    }

    #[test]
    fn one_vertex_pushed_in_makes_the_sphere_concave() {
        // A dent of 1 % of the radius at one vertex of the coarse sphere: its neighbours' faces
        // now see the far side of the dent above their planes.
        let mut sphere = crate::raster::mesh::sphere(16, 8);
        let k = sphere.positions.len() / 2;
        sphere.positions[k] = sphere.positions[k].map(|c| c * 0.99);
        assert_eq!(classes(&sphere), (false, false));
    }

    #[test]
    fn a_vertex_above_a_face_by_less_than_the_slack_still_counts_as_on_it() {
        // A flat square of two triangles with one corner lifted: by a quarter of the slack it is
        // still flat; by four times the slack the two triangles fold (each sees the other's
        // corner on one side: one side stays clear, the other not).
        let square = |lift: f32| Mesh {
            positions: vec![
                [-1.0, 0.0, -1.0],
                [1.0, 0.0, -1.0],
                [1.0, lift, 1.0],
                [-1.0, 0.0, 1.0],
            ],
            normals: vec![[0.0, 1.0, 0.0]; 4],
            indices: vec![0, 2, 1, 0, 3, 2],
        };
        let slack = SelfHits::of(&square(0.0)).slack;
        assert_eq!(slack, 2f32.powi(-20));
        assert_eq!(classes(&square(slack / 4.0)), (true, true));
        let folded = classes(&square(4.0 * slack));
        assert!(folded.0 != folded.1, "{folded:?}");
    }

    #[test]
    fn an_index_out_of_range_or_no_faces_is_handled() {
        let mut board = BuiltinMesh::Board.mesh();
        board.indices[0] = 99;
        assert_eq!(SelfHits::of(&board), SelfHits::ANY);
        let empty = Mesh {
            positions: Vec::new(),
            normals: Vec::new(),
            indices: Vec::new(),
        };
        assert_eq!(classes(&empty), (true, true));
    }

    #[test]
    fn the_tree_agrees_with_a_scan_of_every_vertex() {
        let sphere = crate::raster::mesh::sphere(24, 12);
        let points: Vec<DVec3> = sphere
            .positions
            .iter()
            .map(|p| DVec3::from_array(p.map(f64::from)))
            .collect();
        let tree = BoxTree::new(&points, &[]);
        let mut stack = Vec::new();
        for (i, n) in [DVec3::X, DVec3::new(0.3, -0.5, 0.8).normalize(), -DVec3::Y]
            .into_iter()
            .enumerate()
        {
            let highest = points.iter().map(|p| n.dot(*p)).fold(f64::MIN, f64::max);
            let margin = 1e-9 * (i + 1) as f64;
            assert!(tree.nothing_above(n, highest + margin, &mut stack));
            assert!(!tree.nothing_above(n, highest - margin, &mut stack));
        }
    }

    #[test]
    fn the_first_seven_clear_objects_get_a_mask_bit_of_their_own() {
        let convex = SelfHits {
            front_clear: true,
            back_clear: false,
            slack: 0.0,
        };
        let flat = SelfHits {
            back_clear: true,
            ..convex
        };
        // A bowl, an empty mesh, then nine convex or flat ones.
        let mut meshes = vec![(100, SelfHits::ANY), (0, convex)];
        meshes.extend((0..9).map(|i| (12, if i % 2 == 0 { convex } else { flat })));
        let bits = own_mask_bits(meshes.into_iter());
        assert_eq!(bits, [0, 0, 1, 2, 4, 8, 16, 32, 64, 0, 0]);
        // No bit is the shared one, so a ray that leaves its own out still meets the others.
        assert!(bits.iter().all(|&b| b & TRACE_MASK_SHARED == 0));
    }
}
