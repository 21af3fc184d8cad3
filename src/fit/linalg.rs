//! The small numerical tools of the fit: a symmetric positive-definite solve for the normal
//! equations and a one-dimensional minimiser (coarse grid, then golden section).
//!
//! Owns no model knowledge; sizes are tens to a hundred unknowns, so dense O(n³) is fine.

/// A dense symmetric matrix, row-major, n × n.
#[derive(Clone, Debug)]
pub struct SymmetricMatrix {
    pub n: usize,
    pub values: Vec<f64>,
}

impl SymmetricMatrix {
    pub fn zeros(n: usize) -> Self {
        SymmetricMatrix {
            n,
            values: vec![0.0; n * n],
        }
    }

    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.values[i * self.n + j]
    }

    /// Adds `v` at (i, j) and, off the diagonal, at (j, i).
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        self.values[i * self.n + j] += v;
        if i != j {
            self.values[j * self.n + i] += v;
        }
    }

    /// Solves A·x = b; see [`SymmetricMatrix::cholesky`].
    pub fn solve(&self, b: &[f64]) -> Option<Vec<f64>> {
        Some(self.cholesky()?.solve(b))
    }

    /// The Cholesky factor after symmetric Jacobi scaling (D^-1/2 A D^-1/2), which makes unknowns
    /// of very different size (a diffuse offset and a Fresnel knot) equally accurate. None if A
    /// is not positive definite to working precision (a term the data do not fix).
    pub fn cholesky(&self) -> Option<Cholesky> {
        let n = self.n;
        let scale: Vec<f64> = (0..n)
            .map(|i| {
                let d = self.get(i, i);
                (d > 0.0 && d.is_finite()).then(|| 1.0 / d.sqrt())
            })
            .collect::<Option<_>>()?;
        let mut l = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..=i {
                let mut sum = self.get(i, j) * scale[i] * scale[j];
                for k in 0..j {
                    sum -= l[i * n + k] * l[j * n + k];
                }
                if i == j {
                    // Relative pivot test: 1e-13 of the (unit) scaled diagonal is where f64 stops
                    // telling a pivot from rounding noise.
                    if sum <= 1e-13 {
                        return None;
                    }
                    l[i * n + i] = sum.sqrt();
                } else {
                    l[i * n + j] = sum / l[j * n + j];
                }
            }
        }
        Some(Cholesky { n, l, scale })
    }
}

/// A = D^1/2 · L·Lᵀ · D^1/2, from [`SymmetricMatrix::cholesky`].
pub struct Cholesky {
    n: usize,
    l: Vec<f64>,
    scale: Vec<f64>,
}

impl Cholesky {
    /// x with A·x = b.
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let (n, l) = (self.n, &self.l);
        let mut y: Vec<f64> = (0..n).map(|i| b[i] * self.scale[i]).collect();
        for i in 0..n {
            for k in 0..i {
                y[i] -= l[i * n + k] * y[k];
            }
            y[i] /= l[i * n + i];
        }
        for i in (0..n).rev() {
            for k in i + 1..n {
                y[i] -= l[k * n + i] * y[k];
            }
            y[i] /= l[i * n + i];
        }
        y.iter().zip(&self.scale).map(|(v, s)| v * s).collect()
    }

    /// (A⁻¹)_ii for each i in `indices`: the variances of those unknowns in a least-squares fit
    /// whose normal matrix is A (unit noise).
    pub fn inverse_diagonal(&self, indices: impl Iterator<Item = usize>) -> Vec<f64> {
        indices
            .map(|i| {
                let mut unit = vec![0.0; self.n];
                unit[i] = 1.0;
                self.solve(&unit)[i]
            })
            .collect()
    }
}

/// The minimum of `f` over [lo, hi]: `grid` evenly spaced points, then golden-section search
/// between the best point's neighbours until the bracket is `tolerance` wide (comparisons of f
/// resolve x only to about √ε relative near a minimum, whatever the tolerance). Returns (x, f(x))
/// and the grid it evaluated, for plots. A coarse grid first makes the search robust against a
/// second, shallower minimum (the golden section alone would find whichever it brackets).
pub fn minimise_1d(
    mut f: impl FnMut(f64) -> f64,
    lo: f64,
    hi: f64,
    grid: usize,
    tolerance: f64,
) -> (f64, f64, Vec<(f64, f64)>) {
    let grid = grid.max(3);
    let step = (hi - lo) / (grid - 1) as f64;
    let samples: Vec<(f64, f64)> = (0..grid)
        .map(|i| {
            let x = lo + step * i as f64;
            (x, f(x))
        })
        .collect();
    let best = (0..grid)
        .min_by(|&a, &b| samples[a].1.total_cmp(&samples[b].1))
        .unwrap_or(0);
    let (mut a, mut b) = (
        samples[best.saturating_sub(1)].0,
        samples[(best + 1).min(grid - 1)].0,
    );
    let ratio = (5f64.sqrt() - 1.0) / 2.0;
    let mut c = b - ratio * (b - a);
    let mut d = a + ratio * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    while (b - a).abs() > tolerance {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - ratio * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + ratio * (b - a);
            fd = f(d);
        }
    }
    let (x, fx) = if fc < fd { (c, fc) } else { (d, fd) };
    // The grid's best point may still beat the bracket's interior (a minimum at an end).
    if samples[best].1 < fx {
        (samples[best].0, samples[best].1, samples)
    } else {
        (x, fx, samples)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solve_recovers_a_known_solution() {
        // A = [[4, 2, 0], [2, 5, 1], [0, 1, 3]] is SPD (diagonally dominant); x = (1, -2, 0.5)
        // gives b = A·x = (0, -7.5, -0.5) by hand. Rounding only: 1e-14.
        let mut a = SymmetricMatrix::zeros(3);
        for (i, j, v) in [
            (0, 0, 4.0),
            (0, 1, 2.0),
            (1, 1, 5.0),
            (1, 2, 1.0),
            (2, 2, 3.0),
        ] {
            a.add(i, j, v);
        }
        let x = a.solve(&[0.0, -7.5, -0.5]).unwrap();
        for (got, want) in x.iter().zip([1.0, -2.0, 0.5]) {
            assert!((got - want).abs() < 1e-14, "{x:?}");
        }
    }

    #[test]
    fn inverse_diagonal_of_a_known_inverse() {
        // [[2, 1], [1, 2]]⁻¹ = [[2, −1], [−1, 2]]/3: diagonal 2/3 (hand value; rounding 1e-15).
        let mut a = SymmetricMatrix::zeros(2);
        a.add(0, 0, 2.0);
        a.add(0, 1, 1.0);
        a.add(1, 1, 2.0);
        let d = a.cholesky().unwrap().inverse_diagonal(0..2);
        assert!(d.iter().all(|v| (v - 2.0 / 3.0).abs() < 1e-15), "{d:?}");
    }

    #[test]
    fn solve_refuses_a_singular_matrix() {
        // Rank 1: [[1, 1], [1, 1]].
        let mut a = SymmetricMatrix::zeros(2);
        a.add(0, 0, 1.0);
        a.add(0, 1, 1.0);
        a.add(1, 1, 1.0);
        assert!(a.solve(&[1.0, 1.0]).is_none());
        assert!(SymmetricMatrix::zeros(2).solve(&[0.0, 0.0]).is_none());
    }

    #[test]
    fn minimise_finds_the_global_minimum_of_a_double_well() {
        // f = (x² − 1)² + 0.3x has its global minimum at the root of f' = 4x³ − 4x + 0.3 near −1
        // (Newton in Python: −1.0355787140888537) and a shallower one near 0.96.
        let f = |x: f64| (x * x - 1.0).powi(2) + 0.3 * x;
        let (x, _, grid) = minimise_1d(f, -2.0, 2.0, 21, 1e-10);
        assert_eq!(grid.len(), 21);
        // Comparing f values resolves x only to √(ε·|f|/f'') ≈ 3e-9 near a minimum; 1e-8.
        assert!((x + 1.035_578_714_088_853_7).abs() < 1e-8, "x = {x}");
    }

    #[test]
    fn minimise_handles_a_minimum_at_the_end() {
        let (x, fx, _) = minimise_1d(|x| x, 0.0, 1.0, 5, 1e-9);
        assert!(x < 1e-8 && fx < 1e-8);
    }
}
