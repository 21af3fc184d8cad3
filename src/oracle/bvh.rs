//! A CPU bounding-volume hierarchy over triangle meshes: the oracle's twin of the GPU ray query.
//!
//! Tests trace the same rays here and through `rayQueryEXT` and compare the first hits. To keep
//! the two comparable it works in f32 like the GPU, and it favours being obviously right over
//! being fast:
//!
//! - The build is a binned surface-area-heuristic split on the longest axis of the centroid
//!   bounds, with leaves of at most `MAX_LEAF_TRIANGLES` triangles, done with an explicit work
//!   list so that no input can exhaust the call stack.
//! - Traversal walks a flattened node array with a fixed stack, nearer child first.
//! - The triangle test is the watertight one of Woop, Benthin & Wald, "Watertight Ray/Triangle
//!   Intersection" (JCGT 2013), so a ray through an edge or vertex shared by two triangles hits
//!   at least one of them: a leak there would show up as a spurious GPU/oracle difference.
//! - Box tests are widened a little (see `BOX_SLACK`) so that rounding does not prune a box
//!   whose triangle the triangle test would accept: the answer is meant to be exactly that of
//!   testing every triangle, and the tests check it against such a loop.
//!
//! Ties in t (a ray through a shared edge hits both triangles at the same t) go to the lowest
//! `(object, triangle)`, so the answer does not depend on the tree's shape or traversal order.

use glam::Vec3;

/// Leaves hold at most this many triangles; small leaves keep the test of a leaf cheap.
const MAX_LEAF_TRIANGLES: usize = 4;

/// How many bins the SAH split evaluates along its axis; 16 is the usual quality/speed balance.
const SAH_BINS: usize = 16;

/// Below this depth nodes are split by the SAH; deeper ones are split at the median triangle,
/// which halves the count each level. An adversarial input (say, centroids spaced
/// exponentially) can make every SAH split peel off a single leaf, and this cap is what bounds
/// the tree's depth, and so the traversal stack, for any input.
const MAX_SAH_DEPTH: usize = 48;

/// Entries in the traversal stack. Each level of the descent pushes at most one node, and the
/// depth is at most `MAX_SAH_DEPTH` + log2(2³² / `MAX_LEAF_TRIANGLES`) + 1 = 79 for any triangle
/// count that fits the u32 indices, so this can never overflow.
const TRAVERSAL_STACK_SIZE: usize = 96;

/// Relative widening of each box's [entry, exit] interval. The computed slab distances and the
/// computed triangle t each carry a few ulps of relative error; without the margin a ray could
/// graze a box face that a triangle's vertex lies on and skip a hit the triangle test accepts.
/// 1e-5 is far more than the error and costs only the odd extra box.
const BOX_SLACK: f32 = 1e-5;

/// The first hit of a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BvhHit {
    /// Ray parameter of the hit: the point is `origin + t·dir`.
    pub t: f32,
    /// Index of the object in the slice given to [`SceneBvh::new`].
    pub object: u32,
    /// Index of the triangle within its object's index list (its first index is `3·triangle`).
    pub triangle: u32,
    /// barycentrics (u, v) of vertices 1 and 2; vertex 0 has 1-u-v
    pub barycentrics: [f32; 2],
}

/// A bounding-volume hierarchy over the triangles of several objects, in world space.
pub struct SceneBvh {
    /// Flattened tree; node 0 is the root. Empty when the scene has no usable triangle.
    nodes: Vec<Node>,
    /// The non-degenerate triangles, in leaf order: each leaf owns a contiguous run.
    triangles: Vec<Triangle>,
    /// Every triangle given, degenerate ones included.
    triangle_count: usize,
}

/// An axis-aligned box. The empty box has min = +inf and max = -inf, so growing it by any point
/// gives that point.
#[derive(Clone, Copy, Debug)]
struct Aabb {
    min: Vec3,
    max: Vec3,
}

/// One node of the flattened tree. A leaf (`count > 0`) owns `triangles[first..first + count]`;
/// an interior node (`count == 0`) has its two children at `nodes[first]` and `nodes[first + 1]`.
#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    first: u32,
    count: u32,
}

/// A triangle with its vertices copied out, so a leaf test touches one contiguous array.
#[derive(Clone, Copy, Debug)]
struct Triangle {
    vertices: [Vec3; 3],
    object: u32,
    index: u32,
}

/// What the build needs of a triangle: its bounds, their centre, and where it came from.
#[derive(Clone, Copy, Debug)]
struct BuildItem {
    bounds: Aabb,
    centroid: Vec3,
    triangle: u32,
}

/// A ray with what both the slab and the watertight triangle test precompute from it.
struct Ray {
    origin: Vec3,
    /// Componentwise 1/dir; a zero component gives ±inf, which the slab test relies on.
    inv_dir: Vec3,
    /// The axis along which |dir| is largest, and the other two, ordered so that the winding of
    /// a triangle seen along the ray is kept (the paper's swap when dir[kz] < 0).
    kx: usize,
    ky: usize,
    kz: usize,
    /// The shear that maps dir to (0, 0, 1) in (kx, ky, kz) coordinates.
    shear_x: f32,
    shear_y: f32,
    shear_z: f32,
}

impl SceneBvh {
    /// One entry per object: its world-space vertex positions and triangle index list (3 per
    /// triangle). Objects with no triangles are allowed.
    ///
    /// Degenerate triangles (zero area, or a non-finite vertex) are counted by
    /// [`Self::triangle_count`] but left out of the tree, so they are never hit.
    ///
    /// # Panics
    ///
    /// If an index list's length is not a multiple of 3 or an index is out of range for its
    /// object's positions: such a mesh is a bug in the caller, and skipping the bad triangles
    /// would make the oracle quietly disagree with the GPU instead.
    pub fn new(objects: &[(&[[f32; 3]], &[u32])]) -> Self {
        assert!(
            u32::try_from(objects.len()).is_ok(),
            "too many objects for u32 ids"
        );
        let mut triangles = Vec::new();
        let mut triangle_count = 0;
        for (object, &(positions, indices)) in objects.iter().enumerate() {
            assert!(
                indices.len() % 3 == 0,
                "object {object}: {} indices is not a whole number of triangles",
                indices.len()
            );
            assert!(
                u32::try_from(indices.len() / 3).is_ok(),
                "object {object}: too many triangles for u32 ids"
            );
            let vertex = |index: u32| match positions.get(index as usize) {
                Some(&position) => Vec3::from_array(position),
                None => panic!(
                    "object {object}: index {index} is out of range for {} positions",
                    positions.len()
                ),
            };
            for (index, corners) in indices.chunks_exact(3).enumerate() {
                let vertices = [vertex(corners[0]), vertex(corners[1]), vertex(corners[2])];
                triangle_count += 1;
                if !is_degenerate(&vertices) {
                    triangles.push(Triangle {
                        vertices,
                        object: object as u32,
                        index: index as u32,
                    });
                }
            }
        }

        let (nodes, order) = build(&triangles);
        let triangles = order.iter().map(|&i| triangles[i as usize]).collect();
        Self {
            nodes,
            triangles,
            triangle_count,
        }
    }

    /// Nearest hit with t in [t_min, t_max] of origin + t·dir (dir need not be unit; both faces
    /// count). A non-finite or zero ray, or a NaN bound, hits nothing.
    pub fn intersect(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Option<BvhHit> {
        self.traverse(origin, dir, (t_min, t_max), None, false)
    }

    /// Whether any triangle is hit with t in [t_min, t_max] (may stop at the first found).
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> bool {
        self.traverse(origin, dir, (t_min, t_max), None, true)
            .is_some()
    }

    /// [`Self::intersect`] for t ≥ 0 with object `skip`'s triangles left out (an instance mask).
    pub fn intersect_skipping(&self, origin: Vec3, dir: Vec3, skip: Option<u32>) -> Option<BvhHit> {
        self.traverse(origin, dir, (0.0, f32::INFINITY), skip, false)
    }

    /// [`Self::occluded`] with object `skip`'s triangles left out (an instance mask).
    pub fn occluded_skipping(
        &self,
        origin: Vec3,
        dir: Vec3,
        (t_min, t_max): (f32, f32),
        skip: Option<u32>,
    ) -> bool {
        self.traverse(origin, dir, (t_min, t_max), skip, true)
            .is_some()
    }

    /// The number of triangles given to [`Self::new`], degenerate ones included.
    pub fn triangle_count(&self) -> usize {
        self.triangle_count
    }

    /// The shared walk of `intersect` and `occluded`; `any_hit` returns the first hit found.
    fn traverse(
        &self,
        origin: Vec3,
        dir: Vec3,
        (t_min, mut t_max): (f32, f32),
        skip: Option<u32>,
        any_hit: bool,
    ) -> Option<BvhHit> {
        if t_min.is_nan() || t_max.is_nan() || t_min > t_max {
            return None;
        }
        let ray = Ray::new(origin, dir)?;
        let root = self.nodes.first()?;
        ray.enter(&root.bounds, t_min, t_max)?;

        // Pending far children with the t at which the ray enters them, so that a child behind
        // a hit found meanwhile is dropped without a box test.
        let mut stack = [(0u32, 0.0f32); TRAVERSAL_STACK_SIZE];
        let mut pending = 0;
        let mut node = 0usize;
        let mut best: Option<BvhHit> = None;
        loop {
            let Node { first, count, .. } = self.nodes[node];
            if count > 0 {
                let leaf = &self.triangles[first as usize..(first + count) as usize];
                for triangle in leaf.iter().filter(|t| Some(t.object) != skip) {
                    let Some((t, u, v)) = ray.hit_triangle(&triangle.vertices, t_min, t_max) else {
                        continue;
                    };
                    // t <= t_max here, so only a tie needs the id comparison.
                    let better = match best {
                        None => true,
                        Some(b) => {
                            t < b.t || (triangle.object, triangle.index) < (b.object, b.triangle)
                        }
                    };
                    if better {
                        best = Some(BvhHit {
                            t,
                            object: triangle.object,
                            triangle: triangle.index,
                            barycentrics: [u, v],
                        });
                        t_max = t;
                        if any_hit {
                            return best;
                        }
                    }
                }
            } else {
                let (a, b) = (first as usize, first as usize + 1);
                let entry_a = ray.enter(&self.nodes[a].bounds, t_min, t_max);
                let entry_b = ray.enter(&self.nodes[b].bounds, t_min, t_max);
                match (entry_a, entry_b) {
                    (Some(ta), Some(tb)) => {
                        let (near, far, t_far) = if ta <= tb { (a, b, tb) } else { (b, a, ta) };
                        stack[pending] = (far as u32, t_far);
                        pending += 1;
                        node = near;
                        continue;
                    }
                    (Some(_), None) => {
                        node = a;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = b;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Next pending node that is not wholly behind the nearest hit so far. Ties in t are
            // kept (<=) so that the lowest-id rule sees every triangle at the nearest t.
            loop {
                if pending == 0 {
                    return best;
                }
                pending -= 1;
                let (next, entry) = stack[pending];
                if entry <= t_max {
                    node = next as usize;
                    break;
                }
            }
        }
    }
}

/// A triangle is degenerate when its area is zero, which the exact-ish f64 cross product of two
/// edges detects for repeated and collinear vertices, or when a vertex is not finite (its box
/// would be infinite and its hits meaningless). Such triangles have no interior to hit, and the
/// projected test would otherwise divide by a determinant that is zero only up to rounding.
fn is_degenerate(vertices: &[Vec3; 3]) -> bool {
    if !vertices.iter().all(|v| v.is_finite()) {
        return true;
    }
    let [a, b, c] = vertices.map(|v| v.as_dvec3());
    (b - a).cross(c - a) == glam::DVec3::ZERO
}

impl Aabb {
    const EMPTY: Self = Self {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    fn of_triangle(vertices: &[Vec3; 3]) -> Self {
        let [a, b, c] = *vertices;
        Self {
            min: a.min(b).min(c),
            max: a.max(b).max(c),
        }
    }

    fn union(self, other: Self) -> Self {
        Self {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    fn grow(self, point: Vec3) -> Self {
        Self {
            min: self.min.min(point),
            max: self.max.max(point),
        }
    }

    /// The centre, halved before adding so that coordinates near f32::MAX cannot overflow.
    fn centre(self) -> Vec3 {
        self.min * 0.5 + self.max * 0.5
    }

    /// Half the surface area, the SAH's measure of how likely a ray is to enter the box
    /// (the factor 2 cancels in comparisons). The empty box has none.
    fn half_area(self) -> f32 {
        if self.min.cmpgt(self.max).any() {
            return 0.0;
        }
        let e = self.max - self.min;
        e.x * e.y + e.y * e.z + e.z * e.x
    }
}

/// Builds the flattened tree over `triangles` and returns it with the leaf order: `order[i]` is
/// the index in `triangles` of the i-th triangle the leaves refer to.
fn build(triangles: &[Triangle]) -> (Vec<Node>, Vec<u32>) {
    let mut items: Vec<BuildItem> = triangles
        .iter()
        .enumerate()
        .map(|(i, triangle)| {
            let bounds = Aabb::of_triangle(&triangle.vertices);
            BuildItem {
                bounds,
                centroid: bounds.centre(),
                triangle: i as u32,
            }
        })
        .collect();
    let mut nodes = Vec::new();
    if items.is_empty() {
        return (nodes, Vec::new());
    }

    let placeholder = Node {
        bounds: Aabb::EMPTY,
        first: 0,
        count: 0,
    };
    nodes.reserve(2 * items.len() / MAX_LEAF_TRIANGLES + 1);
    nodes.push(placeholder);
    // (node, first item, end item, depth). An explicit list rather than recursion: the depth is
    // bounded (see MAX_SAH_DEPTH) but need not be small.
    let mut work = vec![(0usize, 0usize, items.len(), 0usize)];
    while let Some((node, start, end, depth)) = work.pop() {
        let range = &mut items[start..end];
        let (bounds, centroids) = range
            .iter()
            .fold((Aabb::EMPTY, Aabb::EMPTY), |(b, c), item| {
                (b.union(item.bounds), c.grow(item.centroid))
            });
        nodes[node].bounds = bounds;
        if range.len() <= MAX_LEAF_TRIANGLES {
            nodes[node].first = start as u32;
            nodes[node].count = range.len() as u32;
            continue;
        }
        let mid = start + split(range, centroids, depth);
        let left = nodes.len();
        nodes.push(placeholder);
        nodes.push(placeholder);
        nodes[node].first = left as u32;
        work.push((left, start, mid, depth + 1));
        work.push((left + 1, mid, end, depth + 1));
    }
    let order = items.iter().map(|item| item.triangle).collect();
    (nodes, order)
}

/// Reorders `items` into two non-empty halves and returns the length of the first. The SAH is
/// tried while the depth allows and the centroids are spread out; when all centroids coincide
/// no plane separates them, so (like past the depth cap) the items are split at the median
/// along the axis, which still halves the count and keeps leaves small.
fn split(items: &mut [BuildItem], centroids: Aabb, depth: usize) -> usize {
    let extent = centroids.max - centroids.min;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    if depth < MAX_SAH_DEPTH && extent[axis] > 0.0 {
        if let Some(mid) = sah_split(items, centroids, axis) {
            return mid;
        }
    }
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
    mid
}

/// Binned SAH: drop the centroids into equal bins along `axis`, pick the bin boundary that
/// minimises area × count summed over both sides, and partition at it. `None` when rounding
/// leaves one side empty (only possible for a vanishingly small centroid extent).
fn sah_split(items: &mut [BuildItem], centroids: Aabb, axis: usize) -> Option<usize> {
    let origin = centroids.min[axis];
    let scale = SAH_BINS as f32 / (centroids.max[axis] - origin);
    // `as usize` saturates (and maps NaN to 0), so the clamp is all the guarding this needs.
    let bin_of =
        |item: &BuildItem| (((item.centroid[axis] - origin) * scale) as usize).min(SAH_BINS - 1);

    let mut bin_bounds = [Aabb::EMPTY; SAH_BINS];
    let mut bin_counts = [0usize; SAH_BINS];
    for item in items.iter() {
        let bin = bin_of(item);
        bin_bounds[bin] = bin_bounds[bin].union(item.bounds);
        bin_counts[bin] += 1;
    }

    // right_cost[i]: area × count of bins i.. (the right side of the plane before bin i).
    let mut right_cost = [0.0f32; SAH_BINS];
    let (mut bounds, mut count) = (Aabb::EMPTY, 0usize);
    for bin in (1..SAH_BINS).rev() {
        bounds = bounds.union(bin_bounds[bin]);
        count += bin_counts[bin];
        right_cost[bin] = bounds.half_area() * count as f32;
    }
    let (mut bounds, mut count) = (Aabb::EMPTY, 0usize);
    let (mut best_plane, mut best_cost) = (None, f32::INFINITY);
    for plane in 1..SAH_BINS {
        bounds = bounds.union(bin_bounds[plane - 1]);
        count += bin_counts[plane - 1];
        if count == 0 || count == items.len() {
            continue;
        }
        let cost = bounds.half_area() * count as f32 + right_cost[plane];
        if cost < best_cost {
            (best_plane, best_cost) = (Some(plane), cost);
        }
    }
    let plane = best_plane?;

    // In-place partition: items in bins below `plane` to the front.
    let mut mid = 0;
    for i in 0..items.len() {
        if bin_of(&items[i]) < plane {
            items.swap(i, mid);
            mid += 1;
        }
    }
    (mid > 0 && mid < items.len()).then_some(mid)
}

impl Ray {
    /// `None` for a ray that cannot hit anything: a non-finite origin or direction, or dir = 0.
    fn new(origin: Vec3, dir: Vec3) -> Option<Self> {
        if !origin.is_finite() || !dir.is_finite() {
            return None;
        }
        let abs = dir.abs();
        let kz = if abs.x >= abs.y && abs.x >= abs.z {
            0
        } else if abs.y >= abs.z {
            1
        } else {
            2
        };
        if dir[kz] == 0.0 {
            return None;
        }
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        Some(Self {
            origin,
            inv_dir: dir.recip(),
            kx,
            ky,
            kz,
            shear_x: dir[kx] / dir[kz],
            shear_y: dir[ky] / dir[kz],
            shear_z: 1.0 / dir[kz],
        })
    }

    /// The slab test: the t at which the ray enters `bounds` within [t_min, t_max], or `None`.
    ///
    /// With a zero dir component 1/dir is ±inf and each slab distance is ±inf, except for an
    /// origin exactly on that slab's plane, where 0·inf is NaN. The ray then runs inside the
    /// plane, i.e. within the closed slab, so a NaN means "this axis does not limit t".
    fn enter(&self, bounds: &Aabb, t_min: f32, t_max: f32) -> Option<f32> {
        let t0 = (bounds.min - self.origin) * self.inv_dir;
        let t1 = (bounds.max - self.origin) * self.inv_dir;
        let mut near = f32::NEG_INFINITY;
        let mut far = f32::INFINITY;
        for axis in 0..3 {
            let (a, b) = (t0[axis], t1[axis]);
            if a.is_nan() || b.is_nan() {
                continue;
            }
            near = near.max(a.min(b));
            far = far.min(a.max(b));
        }
        // Widen by BOX_SLACK of the larger finite end; an infinite end needs no widening.
        let finite_abs = |x: f32| if x.is_finite() { x.abs() } else { 0.0 };
        let slack = BOX_SLACK * finite_abs(near).max(finite_abs(far));
        let entry = (near - slack).max(t_min);
        let exit = (far + slack).min(t_max);
        (entry <= exit).then_some(entry)
    }

    /// The watertight ray/triangle test (Woop, Benthin & Wald 2013). Returns (t, u, v) with u
    /// and v the barycentrics of vertices 1 and 2, for a hit with t in [t_min, t_max].
    ///
    /// The vertices are moved to the ray origin and sheared so that the ray becomes the +z axis
    /// of the (kx, ky, kz) frame; the hit test is then 2D: is (0, 0) inside the projected
    /// triangle? Each projected vertex depends only on that vertex and the ray, so a vertex
    /// shared by two triangles lands on exactly the same point for both, and the edge
    /// function of a shared edge is computed from the same two points (with its sign flipped)
    /// for both triangles. No gap between them can open, whatever the rounding.
    fn hit_triangle(
        &self,
        vertices: &[Vec3; 3],
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, f32, f32)> {
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let [a, b, c] = vertices.map(|v| v - self.origin);
        let ax = a[kx] - self.shear_x * a[kz];
        let ay = a[ky] - self.shear_y * a[kz];
        let bx = b[kx] - self.shear_x * b[kz];
        let by = b[ky] - self.shear_y * b[kz];
        let cx = c[kx] - self.shear_x * c[kz];
        let cy = c[ky] - self.shear_y * c[kz];

        // Edge functions: twice the signed areas of the sub-triangles that (0, 0) forms with
        // each edge, i.e. the unnormalised barycentric weights of vertices 0, 1 and 2.
        let mut e0 = cx * by - cy * bx;
        let mut e1 = ax * cy - ay * cx;
        let mut e2 = bx * ay - by * ax;
        // A product rounds monotonically, so a nonzero f32 difference of two products has the
        // exact sign; only a 0 can be wrong. Then redo it in f64, where the products of f32
        // values are exact and the sign of the difference is right.
        if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
            let d = f64::from;
            e0 = (d(cx) * d(by) - d(cy) * d(bx)) as f32;
            e1 = (d(ax) * d(cy) - d(ay) * d(cx)) as f32;
            e2 = (d(bx) * d(ay) - d(by) * d(ax)) as f32;
        }
        // Inside (or on an edge) when no two weights have opposite signs: both windings count.
        let any_negative = e0 < 0.0 || e1 < 0.0 || e2 < 0.0;
        let any_positive = e0 > 0.0 || e1 > 0.0 || e2 > 0.0;
        if any_negative && any_positive {
            return None;
        }
        let det = e0 + e1 + e2;
        if det == 0.0 {
            // The ray lies in the triangle's plane: no single hit point.
            return None;
        }

        // The sheared z of each vertex is its distance along the ray in units of |dir|, so the
        // weighted sum over det is the hit's t.
        let az = self.shear_z * a[kz];
        let bz = self.shear_z * b[kz];
        let cz = self.shear_z * c[kz];
        let inv_det = 1.0 / det;
        let t = (e0 * az + e1 * bz + e2 * cz) * inv_det;
        // Written so that a NaN t (from an overflowing shear) fails.
        if !(t >= t_min && t <= t_max) {
            return None;
        }
        Some((t, e1 * inv_det, e2 * inv_det))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// xorshift64*: enough randomness for test geometry, with no extra crate.
    struct Rng(u64);

    impl Rng {
        fn next_u64(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
        }

        /// Uniform in [0, 1).
        fn unit(&mut self) -> f32 {
            (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
        }

        fn range(&mut self, low: f32, high: f32) -> f32 {
            low + (high - low) * self.unit()
        }

        fn point(&mut self, low: f32, high: f32) -> Vec3 {
            Vec3::new(
                self.range(low, high),
                self.range(low, high),
                self.range(low, high),
            )
        }

        /// A multiple of 1/8 in [low, high]: lands vertices and ray origins on shared planes.
        fn grid(&mut self, low: f32, high: f32) -> f32 {
            (self.range(low, high) * 8.0).round() / 8.0
        }
    }

    /// An owned object, since `SceneBvh::new` takes borrowed slices.
    struct Mesh {
        positions: Vec<[f32; 3]>,
        indices: Vec<u32>,
    }

    fn scene(meshes: &[Mesh]) -> SceneBvh {
        let objects: Vec<(&[[f32; 3]], &[u32])> = meshes
            .iter()
            .map(|m| (m.positions.as_slice(), m.indices.as_slice()))
            .collect();
        SceneBvh::new(&objects)
    }

    /// A soup of `count` random triangles of size ~`size` in [-1, 1]³. Every other triangle has
    /// its vertices on the 1/8 grid, so axis-aligned rays from grid origins run exactly in the
    /// planes of box faces and exercise the slab test's 0·inf case.
    fn random_soup(rng: &mut Rng, count: usize, size: f32) -> Mesh {
        let mut positions = Vec::new();
        for i in 0..count {
            let centre = rng.point(-1.0, 1.0);
            for _ in 0..3 {
                let p = if i % 2 == 0 {
                    centre + rng.point(-size, size)
                } else {
                    Vec3::new(
                        rng.grid(-1.0, 1.0),
                        rng.grid(-1.0, 1.0),
                        rng.grid(-1.0, 1.0),
                    ) * 0.25
                        + centre.map(|x| (x * 8.0).round() / 8.0)
                };
                positions.push(p.to_array());
            }
        }
        let indices = (0..3 * count as u32).collect();
        Mesh { positions, indices }
    }

    /// The nearest hit by testing every triangle in input order; a later triangle wins only
    /// with a strictly smaller t, which is the BVH's lowest-id tie rule.
    fn brute_force(
        meshes: &[Mesh],
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<BvhHit> {
        if t_min.is_nan() || t_max.is_nan() {
            return None;
        }
        let ray = Ray::new(origin, dir)?;
        let mut best: Option<BvhHit> = None;
        for (object, mesh) in meshes.iter().enumerate() {
            for (triangle, corners) in mesh.indices.chunks_exact(3).enumerate() {
                let vertices =
                    [0, 1, 2].map(|k| Vec3::from_array(mesh.positions[corners[k] as usize]));
                if is_degenerate(&vertices) {
                    continue;
                }
                if let Some((t, u, v)) = ray.hit_triangle(&vertices, t_min, t_max) {
                    let better = match best {
                        None => true,
                        Some(b) => t < b.t,
                    };
                    if better {
                        best = Some(BvhHit {
                            t,
                            object: object as u32,
                            triangle: triangle as u32,
                            barycentrics: [u, v],
                        });
                    }
                }
            }
        }
        best
    }

    /// A random ray: from outside or inside the soup, towards a random point, or along an axis
    /// from a grid point (so zero dir components and origins on box planes both occur).
    fn random_ray(rng: &mut Rng) -> (Vec3, Vec3) {
        match rng.next_u64() % 3 {
            0 => {
                let origin = rng.point(-3.0, 3.0);
                (origin, rng.point(-1.0, 1.0) - origin)
            }
            1 => (rng.point(-1.0, 1.0), rng.point(-1.0, 1.0)),
            _ => {
                let origin = Vec3::new(
                    rng.grid(-1.5, 1.5),
                    rng.grid(-1.5, 1.5),
                    rng.grid(-1.5, 1.5),
                );
                let mut dir = Vec3::ZERO;
                let axis = (rng.next_u64() % 3) as usize;
                dir[axis] = if rng.unit() < 0.5 { -1.0 } else { 1.0 };
                (origin, dir)
            }
        }
    }

    fn relative_eq(a: f32, b: f32, tolerance: f32) -> bool {
        (a - b).abs() <= tolerance * a.abs().max(b.abs()).max(f32::MIN_POSITIVE)
    }

    /// Two objects of random triangles (plus an empty one in between) against thousands of
    /// random rays: the BVH's nearest hit is the brute-force one.
    #[test]
    fn nearest_hit_matches_brute_force_on_random_soup() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let meshes = [
            random_soup(&mut rng, 250, 0.3),
            Mesh {
                positions: Vec::new(),
                indices: Vec::new(),
            },
            random_soup(&mut rng, 150, 0.05),
        ];
        let bvh = scene(&meshes);
        assert_eq!(bvh.triangle_count(), 400);

        let mut hits = 0;
        for _ in 0..5000 {
            let (origin, dir) = random_ray(&mut rng);
            let expected = brute_force(&meshes, origin, dir, 0.0, f32::INFINITY);
            let actual = bvh.intersect(origin, dir, 0.0, f32::INFINITY);
            match (actual, expected) {
                (Some(a), Some(e)) => {
                    hits += 1;
                    // Same t; a different triangle only at a tie (it is the same by the tie rule).
                    assert!(
                        relative_eq(a.t, e.t, 1e-5),
                        "{origin} {dir}: t {} vs {}",
                        a.t,
                        e.t
                    );
                    if (a.object, a.triangle) != (e.object, e.triangle) {
                        assert_eq!(a.t, e.t, "{origin} {dir}: {a:?} vs {e:?}");
                    }
                    // The barycentrics give back the hit point.
                    let mesh = &meshes[a.object as usize];
                    let corner = |k: usize| {
                        let index = mesh.indices[3 * a.triangle as usize + k];
                        Vec3::from_array(mesh.positions[index as usize])
                    };
                    let [u, v] = a.barycentrics;
                    let point = corner(0) * (1.0 - u - v) + corner(1) * u + corner(2) * v;
                    let error = (point - (origin + a.t * dir)).length();
                    assert!(error < 1e-4, "{origin} {dir}: {a:?} off by {error}");
                }
                (None, None) => {}
                _ => panic!("{origin} {dir}: bvh {actual:?} vs brute force {expected:?}"),
            }
        }
        // The rays are aimed at the soup, so a good share hit: the test is not vacuous.
        assert!(hits > 1500, "only {hits} hits");
    }

    /// The quad (0,0,0) (1,0,0) (1,1,0) (0,1,0) as triangles 0-1-2 and 0-2-3, which share the
    /// diagonal 0-2 and the vertices 0 and 2.
    fn quad() -> Mesh {
        Mesh {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            indices: vec![0, 1, 2, 0, 2, 3],
        }
    }

    #[test]
    fn ray_through_shared_edge_and_shared_vertex_hits() {
        let bvh = scene(&[quad()]);
        let down = Vec3::new(0.0, 0.0, -1.0);
        for target in [
            Vec3::new(0.5, 0.5, 0.0),   // the middle of the shared diagonal
            Vec3::new(0.25, 0.25, 0.0), // elsewhere on it
            Vec3::new(0.0, 0.0, 0.0),   // shared vertex 0
            Vec3::new(1.0, 1.0, 0.0),   // shared vertex 2
        ] {
            for dir in [down, Vec3::new(0.3, -0.2, -1.0), Vec3::new(-1.0, 2.0, -0.5)] {
                let origin = target - 2.0 * dir;
                let hit = bvh.intersect(origin, dir, 0.0, f32::INFINITY);
                let hit = hit.unwrap_or_else(|| panic!("{origin} {dir} leaks through {target}"));
                assert!(relative_eq(hit.t, 2.0, 1e-5), "{hit:?}");
                // Both triangles are at the same t; the tie goes to triangle 0.
                assert_eq!(hit.triangle, 0, "{hit:?}");
                assert!(bvh.occluded(origin, dir, 0.0, f32::INFINITY));
            }
        }
    }

    /// A jittered 16×16 grid of quads with the diagonals in both directions: rays from random
    /// origins through random points of interior edges and at interior vertices (where up to
    /// eight triangles meet) must all hit, since the grid has no holes inside.
    #[test]
    fn no_leaks_through_interior_edges_and_vertices_of_a_grid() {
        let mut rng = Rng(0x1234_5678_9abc_def1);
        const N: usize = 16;
        let mut positions = Vec::new();
        for j in 0..=N {
            for i in 0..=N {
                let jitter = if i == 0 || j == 0 || i == N || j == N {
                    0.0
                } else {
                    0.3
                };
                positions.push([
                    i as f32 + rng.range(-jitter, jitter),
                    j as f32 + rng.range(-jitter, jitter),
                    rng.range(-0.2, 0.2),
                ]);
            }
        }
        let id = |i: usize, j: usize| (j * (N + 1) + i) as u32;
        let mut indices = Vec::new();
        for j in 0..N {
            for i in 0..N {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                if (i + j) % 2 == 0 {
                    indices.extend([a, b, c, a, c, d]);
                } else {
                    indices.extend([a, b, d, b, c, d]);
                }
            }
        }
        let mesh = Mesh { positions, indices };
        let vertex = |index: u32| Vec3::from_array(mesh.positions[index as usize]);
        let bvh = scene(std::slice::from_ref(&mesh));

        let mut tested = 0;
        for triangle in mesh.indices.chunks_exact(3) {
            for k in 0..3 {
                let (p, q) = (vertex(triangle[k]), vertex(triangle[(k + 1) % 3]));
                let interior = |v: Vec3| v.x > 0.0 && v.y > 0.0 && v.x < N as f32 && v.y < N as f32;
                if !(interior(p) || interior(q)) || !interior((p + q) * 0.5) {
                    continue;
                }
                for target in [p, q, p.lerp(q, rng.unit()), p.lerp(q, 0.5)] {
                    if !interior(target) {
                        continue;
                    }
                    let dir = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), -1.0);
                    let origin = target - rng.range(0.5, 20.0) * dir;
                    assert!(
                        bvh.intersect(origin, dir, 0.0, f32::INFINITY).is_some(),
                        "{origin} {dir} leaks through {target}"
                    );
                    // Straight down, too: the case with two zero dir components.
                    let down = Vec3::new(0.0, 0.0, -1.0);
                    assert!(
                        bvh.intersect(target + Vec3::Z, down, 0.0, 10.0).is_some(),
                        "straight down leaks through {target}"
                    );
                    tested += 1;
                }
            }
        }
        assert!(tested > 1000, "only {tested} rays");
    }

    #[test]
    fn occluded_agrees_with_intersect() {
        let mut rng = Rng(0xdead_beef_cafe_f00d);
        let meshes = [random_soup(&mut rng, 300, 0.2)];
        let bvh = scene(&meshes);
        for _ in 0..5000 {
            let (origin, dir) = random_ray(&mut rng);
            let t_max = rng.range(0.0, 3.0);
            assert_eq!(
                bvh.occluded(origin, dir, 0.0, t_max),
                bvh.intersect(origin, dir, 0.0, t_max).is_some(),
                "{origin} {dir} up to {t_max}"
            );
        }
    }

    #[test]
    fn t_range_is_respected() {
        // Three parallel quads at z = 0, -1, -2, seen from z = 1 looking down with |dir| = 2,
        // so they are at t = 0.5, 1 and 1.5.
        let layers: Vec<Mesh> = (0..3)
            .map(|k| {
                let mut mesh = quad();
                for p in &mut mesh.positions {
                    p[2] = -(k as f32);
                }
                mesh
            })
            .collect();
        let bvh = scene(&layers);
        let (origin, dir) = (Vec3::new(0.3, 0.6, 1.0), Vec3::new(0.0, 0.0, -2.0));
        let first = |t_min: f32, t_max: f32| {
            bvh.intersect(origin, dir, t_min, t_max)
                .map(|hit| (hit.object, hit.t))
        };

        assert_eq!(first(0.0, f32::INFINITY), Some((0, 0.5)));
        assert_eq!(first(0.6, f32::INFINITY), Some((1, 1.0)));
        assert_eq!(first(1.2, 1.4), None);
        assert_eq!(first(0.0, 0.4), None);
        assert_eq!(first(1.6, f32::INFINITY), None);
        // The bounds are inclusive.
        assert_eq!(first(1.0, 1.0), Some((1, 1.0)));
        assert_eq!(first(0.0, 0.5), Some((0, 0.5)));
        assert_eq!(first(1.5, 7.0), Some((2, 1.5)));
        // Behind the origin only with a negative range, where the nearest is the smallest t
        // (the farthest layer back). An empty range hits nothing.
        assert_eq!(first(f32::NEG_INFINITY, 0.0), None);
        assert_eq!(
            bvh.intersect(origin, -dir, f32::NEG_INFINITY, 0.0)
                .map(|hit| (hit.object, hit.t)),
            Some((2, -1.5))
        );
        assert_eq!(first(1.0, 0.9), None);
        assert!(!bvh.occluded(origin, dir, 1.2, 1.4));
        assert!(bvh.occluded(origin, dir, 1.2, 1.5));
    }

    #[test]
    fn degenerate_triangles_are_never_hit() {
        let mesh = Mesh {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [2.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [f32::NAN, 0.0, 0.0],
                [f32::INFINITY, 1.0, 0.0],
            ],
            // A repeated vertex, three collinear ones, all one point, and non-finite vertices.
            indices: vec![0, 1, 1, 0, 1, 2, 3, 3, 3, 0, 4, 3, 0, 5, 3],
        };
        let bvh = scene(&[mesh]);
        assert_eq!(bvh.triangle_count(), 5);
        let down = Vec3::new(0.0, 0.0, -1.0);
        for target in [
            Vec3::new(0.5, 0.0, 0.0),
            Vec3::new(1.5, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.2, 0.2, 0.0),
        ] {
            for dir in [down, Vec3::new(0.0, 1.0, -1.0), Vec3::new(0.0, -1.0, 0.0)] {
                let origin = target - dir;
                assert_eq!(bvh.intersect(origin, dir, 0.0, f32::INFINITY), None);
                assert!(!bvh.occluded(origin, dir, 0.0, f32::INFINITY));
            }
        }
    }

    #[test]
    fn non_finite_and_zero_rays_miss_without_panicking() {
        let bvh = scene(&[quad()]);
        let (origin, dir) = (Vec3::new(0.3, 0.6, 1.0), Vec3::new(0.0, 0.0, -1.0));
        assert!(bvh.intersect(origin, dir, 0.0, f32::INFINITY).is_some());
        let bad_vectors = [
            Vec3::new(f32::NAN, 0.0, 0.0),
            Vec3::new(0.0, f32::INFINITY, 0.0),
            Vec3::new(0.0, 0.0, f32::NEG_INFINITY),
        ];
        for bad in bad_vectors {
            assert_eq!(bvh.intersect(bad, dir, 0.0, f32::INFINITY), None);
            assert_eq!(bvh.intersect(origin, bad, 0.0, f32::INFINITY), None);
            assert!(!bvh.occluded(bad, dir, 0.0, f32::INFINITY));
            assert!(!bvh.occluded(origin, bad, 0.0, f32::INFINITY));
        }
        assert_eq!(bvh.intersect(origin, Vec3::ZERO, 0.0, f32::INFINITY), None);
        assert_eq!(bvh.intersect(origin, dir, f32::NAN, 1.0), None);
        assert_eq!(bvh.intersect(origin, dir, 0.0, f32::NAN), None);
        assert!(!bvh.occluded(origin, dir, f32::NAN, f32::NAN));
        // Subnormal directions and huge coordinates may miss but must not panic.
        let tiny = Vec3::new(1e-45, 0.0, -1e-45);
        let _ = bvh.intersect(origin, tiny, 0.0, f32::INFINITY);
        let _ = bvh.intersect(Vec3::splat(f32::MAX), -dir, 0.0, f32::INFINITY);
    }

    #[test]
    fn empty_scenes_hit_nothing() {
        let empty = Mesh {
            positions: vec![[0.0; 3]],
            indices: Vec::new(),
        };
        for bvh in [SceneBvh::new(&[]), scene(&[empty])] {
            assert_eq!(bvh.triangle_count(), 0);
            assert_eq!(bvh.intersect(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY), None);
            assert!(!bvh.occluded(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY));
        }
    }

    /// 10 000 copies of one triangle: every centroid coincides, so no plane separates them. The
    /// build must still finish with small leaves, and the tie goes to the lowest id.
    #[test]
    fn coincident_centroids_build_and_break_ties_by_id() {
        let positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let indices = [0, 1, 2].repeat(10_000);
        let bvh = scene(&[Mesh { positions, indices }]);
        assert!(bvh
            .nodes
            .iter()
            .all(|n| n.count as usize <= MAX_LEAF_TRIANGLES));
        let hit = bvh.intersect(
            Vec3::new(0.25, 0.25, 1.0),
            Vec3::new(0.0, 0.0, -1.0),
            0.0,
            f32::INFINITY,
        );
        assert_eq!(
            hit,
            Some(BvhHit {
                t: 1.0,
                object: 0,
                triangle: 0,
                barycentrics: [0.25, 0.25]
            })
        );
    }

    /// Exponentially spaced triangles, the input that makes SAH splits peel off one leaf at a
    /// time: the depth cap must keep the tree within the traversal stack.
    #[test]
    fn depth_stays_within_the_traversal_stack() {
        let mut positions = Vec::new();
        for k in 0..2000 {
            let x = 1.01f32.powi(k);
            positions.extend([[x, 0.0, 0.0], [x, 1.0, 0.0], [x, 0.0, 1.0]]);
        }
        let indices = (0..positions.len() as u32).collect();
        let bvh = scene(&[Mesh { positions, indices }]);
        let mut depth = vec![0usize; bvh.nodes.len()];
        for (i, node) in bvh.nodes.iter().enumerate() {
            if node.count == 0 {
                depth[node.first as usize] = depth[i] + 1;
                depth[node.first as usize + 1] = depth[i] + 1;
            }
        }
        let max_depth = depth.iter().copied().max().unwrap_or(0);
        assert!(max_depth < TRAVERSAL_STACK_SIZE, "depth {max_depth}");
        let hit = bvh.intersect(Vec3::new(-1.0, 0.25, 0.25), Vec3::X, 0.0, f32::INFINITY);
        assert_eq!(hit.map(|h| (h.triangle, h.t)), Some((0, 2.0)));
    }
}
