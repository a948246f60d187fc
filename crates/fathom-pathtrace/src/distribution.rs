//! Piecewise-constant 1D and 2D distributions for importance sampling tabulated functions
//! (an environment map's luminance), after pbrt-v4's `PiecewiseConstant1D/2D`: sample the
//! marginal over rows, then the row's conditional, by inverting their cumulative sums.

/// A piecewise-constant density on [0, 1) with `n` equal cells.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    func: Vec<f64>,
    cdf: Vec<f64>,
    integral: f64,
}

impl Distribution1D {
    /// From non-negative cell values (negative or non-finite ones count as 0). An all-zero
    /// function samples uniformly.
    pub fn new(f: &[f64]) -> Self {
        let n = f.len().max(1);
        let func: Vec<f64> = (0..n)
            .map(|i| {
                f.get(i)
                    .copied()
                    .filter(|v| v.is_finite() && *v > 0.0)
                    .unwrap_or(0.0)
            })
            .collect();
        let mut cdf = vec![0.0; n + 1];
        for i in 0..n {
            cdf[i + 1] = cdf[i] + func[i] / n as f64;
        }
        let integral = cdf[n];
        if integral > 0.0 {
            for c in &mut cdf {
                *c /= integral;
            }
        } else {
            for (i, c) in cdf.iter_mut().enumerate() {
                *c = i as f64 / n as f64;
            }
        }
        cdf[n] = 1.0;
        Distribution1D {
            func,
            cdf,
            integral,
        }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.func.len()
    }

    /// Whether there are no cells (never: at least one is kept).
    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// The integral of the function over [0, 1).
    pub fn integral(&self) -> f64 {
        self.integral
    }

    /// A sample in [0, 1) for uniform `u`: (x, density at x, cell index).
    pub fn sample(&self, u: f64) -> (f64, f64, usize) {
        let n = self.len();
        // The last cell whose cdf start is <= u.
        let i = self
            .cdf
            .partition_point(|&c| c <= u)
            .saturating_sub(1)
            .min(n - 1);
        let width = self.cdf[i + 1] - self.cdf[i];
        let du = if width > 0.0 {
            (u - self.cdf[i]) / width
        } else {
            0.0
        };
        let x = ((i as f64 + du.clamp(0.0, 1.0)) / n as f64).min(1.0 - f64::EPSILON);
        (x, self.pdf_cell(i), i)
    }

    /// Density of cell `i`.
    pub fn pdf_cell(&self, i: usize) -> f64 {
        if self.integral > 0.0 {
            self.func[i] / self.integral
        } else {
            1.0
        }
    }
}

/// A piecewise-constant density on [0, 1)^2 over a `w` x `h` grid (row-major).
#[derive(Clone, Debug)]
pub struct Distribution2D {
    rows: Vec<Distribution1D>,
    marginal: Distribution1D,
}

impl Distribution2D {
    /// From `w` x `h` non-negative values, row-major.
    pub fn new(f: &[f64], w: usize, h: usize) -> Self {
        let rows: Vec<Distribution1D> = (0..h)
            .map(|y| Distribution1D::new(&f[y * w..(y + 1) * w]))
            .collect();
        let marg: Vec<f64> = rows.iter().map(|r| r.integral()).collect();
        Distribution2D {
            marginal: Distribution1D::new(&marg),
            rows,
        }
    }

    /// A sample (u, v) in [0, 1)^2 and its density.
    pub fn sample(&self, u: [f64; 2]) -> ([f64; 2], f64) {
        let (v, pv, row) = self.marginal.sample(u[1]);
        let (x, pu, _) = self.rows[row].sample(u[0]);
        ([x, v], pv * pu)
    }

    /// Density at (u, v).
    pub fn pdf(&self, uv: [f64; 2]) -> f64 {
        let h = self.rows.len();
        let w = self.rows[0].len();
        let y = ((uv[1] * h as f64) as usize).min(h - 1);
        let x = ((uv[0] * w as f64) as usize).min(w - 1);
        self.marginal.pdf_cell(y) * self.rows[y].pdf_cell(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_follow_the_function() {
        let f = [1.0, 0.0, 3.0, 4.0];
        let d = Distribution1D::new(&f);
        let mut hist = [0usize; 4];
        let n = 8000;
        for k in 0..n {
            let (x, p, i) = d.sample((k as f64 + 0.5) / n as f64);
            assert_eq!((x * 4.0) as usize, i);
            assert!((p - f[i] / 2.0).abs() < 1e-12);
            hist[i] += 1;
        }
        for i in 0..4 {
            let want = f[i] / 8.0 * n as f64;
            assert!((hist[i] as f64 - want).abs() <= 1.0, "{hist:?}");
        }
    }

    #[test]
    fn two_d_density_integrates_to_one() {
        let (w, h) = (8, 4);
        let f: Vec<f64> = (0..w * h).map(|i| ((i * 7) % 5) as f64).collect();
        let d = Distribution2D::new(&f, w, h);
        let mut s = 0.0;
        for y in 0..h {
            for x in 0..w {
                s += d.pdf([(x as f64 + 0.5) / w as f64, (y as f64 + 0.5) / h as f64]);
            }
        }
        assert!((s / (w * h) as f64 - 1.0).abs() < 1e-12);
        let (uv, p) = d.sample([0.3, 0.7]);
        assert!((p - d.pdf(uv)).abs() < 1e-12);
    }
}
