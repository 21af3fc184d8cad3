//! Diffuse/specular separation and the Beckmann m (paper §3, §3.1), by variable projection.
//!
//! For a fixed m the model of SPEC §2 is *linear* in everything else. Per channel c and row i
//! (reflectance factor y = π·f_r):
//!
//! ```text
//! y_ic ≈ P_sc + Q_sc·nv_i  +  Σ_k λ_k(θ_i) · F_kc · S_i(m),     S_i(m) = π·D(nh; m)·G / (4·nv·nl)
//! ```
//!
//! where s is the row's board, P + Q·nv its diffuse part (k_d·g(r)·(a + b·nv), unconstrained
//! here), F_k the Fresnel table at whole degrees k = 0..90 and λ_k the linear-interpolation
//! weights of θ = acos(V·H) — the same table and interpolation the renderer uses. So for each m
//! the best diffuse and Fresnel values are one weighted linear least-squares solve, and m is found
//! by minimising that solve's residual J(m) over a log-spaced grid, then a golden section.
//!
//! The curvature of the table is penalised very lightly (10⁻⁸ of the data's mean weight per
//! knot, so measured knots do not move) so that knots no row reaches (between measured angles,
//! beyond the last) are filled smoothly; where the data reach no knot near 90°, F(90°) = 1 is
//! added as a constraint (every Fresnel curve reaches 1 at grazing incidence). Owns the linear model and the m search; the per-board laws f and g are in
//! [`super::diffuse`].

use glam::DVec3;

use super::data::Measurement;
use super::linalg::{minimise_1d, SymmetricMatrix};
use crate::model::brdf::{beckmann_d_sin2, cook_torrance_g};

/// Fresnel knots at whole degrees 0..=90.
pub const FRESNEL_KNOTS: usize = 91;
/// The m search range, log-spaced: (0, 1] is SPEC's domain; below 0.005 a lobe is narrower than
/// any goniometer's angular resolution.
pub const BECKMANN_M_RANGE: (f64, f64) = (0.005, 1.0);
/// Curvature penalty relative to the mean data weight of the measured knots.
const CURVATURE_PENALTY: f64 = 1e-8;

/// What one row contributes, independent of the parameters.
#[derive(Clone, Copy, Debug)]
pub struct RowGeometry {
    pub nv: f64,
    pub nl: f64,
    pub nh: f64,
    /// |N×H|² = sin²α, the accurate form the model uses.
    pub sin2_alpha: f64,
    /// α, the half-vector's angle from the normal [degrees].
    pub tilt_deg: f64,
    /// θ = acos(V·H) [degrees], where the Fresnel table is read.
    pub fresnel_deg: f64,
    /// The lower knot of θ and the interpolation weight of the upper one.
    pub knot: usize,
    pub knot_t: f64,
    /// π·G/(4·nv·nl): S_i(m) = this × D(nh; m).
    pub spec_geometry: f64,
}

impl RowGeometry {
    pub fn new(light: DVec3, view: DVec3) -> Self {
        let n = DVec3::Z;
        let (nv, nl) = (n.dot(view), n.dot(light));
        let h = (view + light).normalize_or_zero();
        let nh = n.dot(h);
        let vh = view.dot(h);
        let sin2_alpha = n.cross(h).length_squared();
        let fresnel_deg = vh.clamp(0.0, 1.0).acos().to_degrees();
        let knot = (fresnel_deg.floor() as usize).min(FRESNEL_KNOTS - 2);
        let g = cook_torrance_g(nh, nv, nl, vh);
        RowGeometry {
            nv,
            nl,
            nh,
            sin2_alpha,
            tilt_deg: nh.clamp(-1.0, 1.0).acos().to_degrees(),
            fresnel_deg,
            knot,
            knot_t: fresnel_deg - knot as f64,
            spec_geometry: std::f64::consts::PI * g / (4.0 * nv * nl),
        }
    }

    /// S_i(m) = π·D·G/(4·nv·nl): the specular reflectance factor per unit F.
    pub fn specular_per_fresnel(&self, beckmann_m: f64) -> f64 {
        self.spec_geometry * beckmann_d_sin2(self.nh, self.sin2_alpha, beckmann_m)
    }
}

/// The weighted linear problem of the module doc.
pub struct Separation<'a> {
    pub rows: &'a [Measurement],
    pub geometry: &'a [RowGeometry],
    /// Per row and channel: 1/σ², σ the row's expected error (relative noise × value).
    pub weights: &'a [[f64; 3]],
    pub sample_count: usize,
}

/// The solution for one m.
#[derive(Clone, Debug)]
pub struct LinearSolution {
    pub beckmann_m: f64,
    /// Per board and channel: (P, Q) of the diffuse part P + Q·nv.
    pub diffuse: Vec<[[f64; 2]; 3]>,
    /// F at 0..=90 degrees, per channel, not clamped.
    pub fresnel: Vec<[f64; 3]>,
    /// Per knot and channel: the data's weight on the knot (the normal matrix's diagonal); 0 for
    /// a knot no row reaches.
    pub fresnel_information: Vec<[f64; 3]>,
    /// Per knot and channel: √(A⁻¹)_kk, F's standard error per unit relative noise (the weights
    /// are 1/value², so σ_F = σ_relative × this). Large where only the curvature penalty fixes
    /// the knot (between measured angles, or two knots only one θ reaches). Empty unless asked.
    pub fresnel_unit_error: Vec<[f64; 3]>,
    /// J(m): the weighted sum of squared residuals over all channels.
    pub objective: f64,
}

/// The m search's result: the best solution and J on the coarse grid (for the report's plot).
pub struct BeckmannSearch {
    pub solution: LinearSolution,
    pub grid: Vec<(f64, f64)>,
}

impl Separation<'_> {
    /// The linear solve for one m; None when the normal equations are singular (the data do not
    /// fix some diffuse or Fresnel unknown).
    pub fn solve(&self, beckmann_m: f64) -> Option<LinearSolution> {
        self.solve_inner(beckmann_m, false)
    }

    /// [`Separation::solve`] with [`LinearSolution::fresnel_unit_error`] (91 more solves per
    /// channel: for the final m only).
    pub fn solve_with_errors(&self, beckmann_m: f64) -> Option<LinearSolution> {
        self.solve_inner(beckmann_m, true)
    }

    fn solve_inner(&self, beckmann_m: f64, with_errors: bool) -> Option<LinearSolution> {
        let s2 = 2 * self.sample_count;
        let n = s2 + FRESNEL_KNOTS;
        let mut normal = [(); 3].map(|_| SymmetricMatrix::zeros(n));
        let mut rhs = [(); 3].map(|_| vec![0.0; n]);
        for ((row, geo), w) in self.rows.iter().zip(self.geometry).zip(self.weights) {
            let s = geo.specular_per_fresnel(beckmann_m);
            let cols = [
                2 * row.sample,
                2 * row.sample + 1,
                s2 + geo.knot,
                s2 + geo.knot + 1,
            ];
            let values = [1.0, geo.nv, (1.0 - geo.knot_t) * s, geo.knot_t * s];
            for c in 0..3 {
                for a in 0..4 {
                    let wa = w[c] * values[a];
                    rhs[c][cols[a]] += wa * row.reflectance[c];
                    for b in a..4 {
                        normal[c].add(cols[a], cols[b], wa * values[b]);
                    }
                }
            }
        }
        let mut solved = Vec::with_capacity(3);
        let mut information = vec![[0.0; 3]; FRESNEL_KNOTS];
        let mut unit_error = if with_errors {
            vec![[0.0; 3]; FRESNEL_KNOTS]
        } else {
            Vec::new()
        };
        for c in 0..3 {
            for (k, info) in information.iter_mut().enumerate() {
                info[c] = normal[c].get(s2 + k, s2 + k);
            }
            regularise(&mut normal[c], &mut rhs[c], s2);
            let factor = normal[c].cholesky()?;
            solved.push(factor.solve(&rhs[c]));
            if with_errors {
                let variances = factor.inverse_diagonal(s2..s2 + FRESNEL_KNOTS);
                for (e, v) in unit_error.iter_mut().zip(variances) {
                    e[c] = v.max(0.0).sqrt();
                }
            }
        }
        let diffuse = (0..self.sample_count)
            .map(|s| std::array::from_fn(|c| [solved[c][2 * s], solved[c][2 * s + 1]]))
            .collect();
        let fresnel = (0..FRESNEL_KNOTS)
            .map(|k| std::array::from_fn(|c| solved[c][s2 + k]))
            .collect();
        let mut solution = LinearSolution {
            beckmann_m,
            diffuse,
            fresnel,
            fresnel_information: information,
            fresnel_unit_error: unit_error,
            objective: 0.0,
        };
        solution.objective = self.objective(&solution);
        Some(solution)
    }

    /// Σ w·(y − model)² of a solution.
    pub fn objective(&self, solution: &LinearSolution) -> f64 {
        let mut sum = 0.0;
        for ((row, geo), w) in self.rows.iter().zip(self.geometry).zip(self.weights) {
            let (diffuse, specular) = solution.parts(row.sample, geo);
            for c in 0..3 {
                let residual = row.reflectance[c] - diffuse[c] - specular[c];
                sum += w[c] * residual * residual;
            }
        }
        sum
    }

    /// m by a `grid`-point grid over log m in `range`, then golden section in log m to 1e-8
    /// (below that, comparisons of J cannot resolve m: see [`minimise_1d`]). None when no m
    /// gives a solvable system.
    pub fn search_beckmann_m(&self, range: (f64, f64), grid: usize) -> Option<BeckmannSearch> {
        let objective = |log_m: f64| {
            self.solve(log_m.exp())
                .map_or(f64::INFINITY, |s| s.objective)
        };
        let (log_m, best, grid) = minimise_1d(objective, range.0.ln(), range.1.ln(), grid, 1e-8);
        if !best.is_finite() {
            return None;
        }
        let solution = self.solve_with_errors(log_m.exp())?;
        let grid = grid.into_iter().map(|(x, j)| (x.exp(), j)).collect();
        Some(BeckmannSearch { solution, grid })
    }
}

impl LinearSolution {
    /// (diffuse, specular) reflectance factors this solution predicts for a row of board `sample`.
    pub fn parts(&self, sample: usize, geo: &RowGeometry) -> ([f64; 3], [f64; 3]) {
        let s = geo.specular_per_fresnel(self.beckmann_m);
        let (lo, hi) = (self.fresnel[geo.knot], self.fresnel[geo.knot + 1]);
        let [p, q] = [0, 1].map(|i| self.diffuse[sample].map(|pq| pq[i]));
        (
            std::array::from_fn(|c| p[c] + q[c] * geo.nv),
            std::array::from_fn(|c| (lo[c] + geo.knot_t * (hi[c] - lo[c])) * s),
        )
    }
}

/// Adds the curvature penalty over the Fresnel block (starting at `offset`) and, when no row
/// reaches the grazing knot, F(90°) = 1.
fn regularise(normal: &mut SymmetricMatrix, rhs: &mut [f64], offset: usize) {
    let diagonal: Vec<f64> = (0..FRESNEL_KNOTS)
        .map(|k| normal.get(offset + k, offset + k))
        .collect();
    let measured: Vec<f64> = diagonal.iter().copied().filter(|&d| d > 0.0).collect();
    let mean = measured.iter().sum::<f64>() / measured.len().max(1) as f64;
    let lambda = CURVATURE_PENALTY * mean.max(f64::MIN_POSITIVE);
    for k in 1..FRESNEL_KNOTS - 1 {
        let stencil = [(k - 1, 1.0), (k, -2.0), (k + 1, 1.0)];
        for (i, (a, va)) in stencil.iter().enumerate() {
            for (b, vb) in &stencil[i..] {
                normal.add(offset + a, offset + b, lambda * va * vb);
            }
        }
    }
    let grazing = FRESNEL_KNOTS - 1;
    if diagonal[grazing] <= 1e-9 * mean {
        normal.add(offset + grazing, offset + grazing, mean);
        rhs[offset + grazing] += mean;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::data::{light_direction, view_direction};

    #[test]
    fn geometry_of_the_mirror_direction() {
        // θ_i = θ_o = 30°, φ = 0: H = N, α = 0, θ = 30°, G = 1, S = π·D/(4 cos²30°).
        let g = RowGeometry::new(light_direction(30.0), view_direction(30.0, 0.0));
        // acos near 1 loses half the digits: α is exact to ~1e-6 degrees.
        assert!(g.tilt_deg.abs() < 1e-6 && (g.fresnel_deg - 30.0).abs() < 1e-9);
        assert!((g.knot as f64 + g.knot_t - 30.0).abs() < 1e-9);
        let m = 0.1;
        let d = 1.0 / (std::f64::consts::PI * m * m);
        let expected = std::f64::consts::PI * d / (4.0 * 0.75);
        assert!((g.specular_per_fresnel(m) / expected - 1.0).abs() < 1e-12);
    }

    #[test]
    fn in_plane_half_angle_is_the_mean_of_the_two_angles() {
        // In-plane, L at θ_i and V at θ_o on the other side: θ = (θ_i + θ_o)/2 and α = |θ_o − θ_i|/2
        // (half the angle between them, and H's tilt); 1e-9 degrees of rounding.
        let g = RowGeometry::new(light_direction(20.0), view_direction(50.0, 0.0));
        assert!((g.fresnel_deg - 35.0).abs() < 1e-9 && (g.tilt_deg - 15.0).abs() < 1e-9);
        assert!((g.knot as f64 + g.knot_t - 35.0).abs() < 1e-9);
    }
}
