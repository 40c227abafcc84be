//! Small numerics behind the features: moments, a slope, and linear least
//! squares by Cholesky on the normal equations.

/// Mean and central moments `(mean, m2, m3, m4)` (population, divided by n).
pub(super) fn moments(values: &[f64]) -> (f64, f64, f64, f64) {
    let n = values.len() as f64;
    if values.is_empty() {
        return (0.0, 0.0, 0.0, 0.0);
    }
    // Shifted by the first value: exact for constant data, and no
    // cancellation for data with a large offset.
    let shift = values[0];
    let offset = values.iter().map(|x| x - shift).sum::<f64>() / n;
    let mean = shift + offset;
    let (mut m2, mut m3, mut m4) = (0.0, 0.0, 0.0);
    for &x in values {
        let d = (x - shift) - offset;
        let d2 = d * d;
        m2 += d2;
        m3 += d2 * d;
        m4 += d2 * d2;
    }
    (mean, m2 / n, m3 / n, m4 / n)
}

/// Whether a second moment is too small, relative to the values' scale, to
/// divide by (zero variance up to rounding).
pub(super) fn negligible(m2: f64, mean: f64) -> bool {
    m2.is_nan() || m2 <= (1e-24 * mean * mean).max(f64::MIN_POSITIVE)
}

/// Skewness and excess kurtosis from central moments (0, 0 when `m2` is negligible).
pub(super) fn shape(mean: f64, m2: f64, m3: f64, m4: f64) -> (f64, f64) {
    if negligible(m2, mean) { (0.0, 0.0) } else { (m3 / m2.powf(1.5), m4 / (m2 * m2) - 3.0) }
}

/// Least-squares slope of `y` against `x`; `None` when `x` does not vary.
pub(super) fn slope(x: &[f64], y: &[f64]) -> Option<f64> {
    let (mx, sxx, _, _) = moments(x);
    if x.len() < 2 || negligible(sxx, mx) {
        return None;
    }
    let my = y.iter().sum::<f64>() / y.len() as f64;
    let sxy = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum::<f64>() / x.len() as f64;
    Some(sxy / sxx)
}

/// Linear least squares: accumulates the normal equations of `rows`
/// (`fill(i, row)` writes row `i` of the design matrix) against `y` in one
/// pass, and solves them by Cholesky. Returns the coefficients and the
/// residual sum of squares (from the normal equations), or `None` when the
/// design is (numerically) singular. Up to [`MAX_COLUMNS`] columns.
pub(crate) fn least_squares(
    n: usize,
    p: usize,
    fill: impl Fn(usize, &mut [f64]),
    y: impl Fn(usize) -> f64,
) -> Option<(Vec<f64>, f64)> {
    // One monomorphised accumulator per width keeps the hot loop in registers.
    match p {
        1 => fixed::<1>(n, fill, y),
        2 => fixed::<2>(n, fill, y),
        3 => fixed::<3>(n, fill, y),
        4 => fixed::<4>(n, fill, y),
        5 => fixed::<5>(n, fill, y),
        6 => fixed::<6>(n, fill, y),
        7 => fixed::<7>(n, fill, y),
        8 => fixed::<8>(n, fill, y),
        9 => fixed::<9>(n, fill, y),
        10 => fixed::<10>(n, fill, y),
        11 => fixed::<11>(n, fill, y),
        12 => fixed::<12>(n, fill, y),
        13 => fixed::<13>(n, fill, y),
        14 => fixed::<14>(n, fill, y),
        _ => None,
    }
}

fn fixed<const P: usize>(
    n: usize,
    fill: impl Fn(usize, &mut [f64]),
    y: impl Fn(usize) -> f64,
) -> Option<(Vec<f64>, f64)> {
    if n < P {
        return None;
    }
    let mut ata = [[0.0f64; P]; P];
    let mut aty = [0.0f64; P];
    let mut yty = 0.0;
    let mut row = [0.0f64; P];
    for i in 0..n {
        fill(i, &mut row);
        let yi = y(i);
        yty += yi * yi;
        for a in 0..P {
            aty[a] += row[a] * yi;
            for b in 0..=a {
                ata[a][b] += row[a] * row[b];
            }
        }
    }
    solve_normal(&ata, &aty, yty)
}

/// The most columns a [`Design`] (and [`least_squares`]) takes.
const MAX_COLUMNS: usize = 14;

/// A least-squares design kept for many right-hand sides: its rows and the
/// lower triangle of its normal matrix `AᵀA`, accumulated in the order
/// [`least_squares`] accumulates them, so that [`Design::solve`] returns
/// exactly what `least_squares` would for the same rows.
#[derive(Clone, Debug)]
pub(super) struct Design {
    n: usize,
    p: usize,
    /// Row `i` at `rows[i * p .. (i + 1) * p]`.
    rows: Vec<f64>,
    ata: [[f64; MAX_COLUMNS]; MAX_COLUMNS],
}

impl Design {
    /// The `n` rows of `p` columns that `fill(i, row)` writes; `None` with
    /// more than [`MAX_COLUMNS`] columns or fewer rows than columns.
    pub(super) fn new(n: usize, p: usize, fill: impl Fn(usize, &mut [f64])) -> Option<Design> {
        if p == 0 || p > MAX_COLUMNS || n < p {
            return None;
        }
        let mut rows = vec![0.0; n * p];
        let mut ata = [[0.0f64; MAX_COLUMNS]; MAX_COLUMNS];
        for (i, row) in rows.chunks_exact_mut(p).enumerate() {
            fill(i, row);
            for a in 0..p {
                for b in 0..=a {
                    ata[a][b] += row[a] * row[b];
                }
            }
        }
        Some(Design { n, p, rows, ata })
    }

    /// Number of rows.
    pub(super) fn rows(&self) -> usize {
        self.n
    }

    /// Row `i` times `coef`: the fitted value at row `i`.
    pub(super) fn fitted(&self, i: usize, coef: &[f64]) -> f64 {
        self.rows[i * self.p..(i + 1) * self.p].iter().zip(coef).map(|(a, c)| a * c).sum()
    }

    /// The coefficients against `y` and the residual sum of squares, as
    /// [`least_squares`] returns them.
    pub(super) fn solve(&self, y: impl Fn(usize) -> f64) -> Option<(Vec<f64>, f64)> {
        match self.p {
            1 => self.solve_fixed::<1>(y),
            2 => self.solve_fixed::<2>(y),
            3 => self.solve_fixed::<3>(y),
            4 => self.solve_fixed::<4>(y),
            5 => self.solve_fixed::<5>(y),
            6 => self.solve_fixed::<6>(y),
            7 => self.solve_fixed::<7>(y),
            8 => self.solve_fixed::<8>(y),
            9 => self.solve_fixed::<9>(y),
            10 => self.solve_fixed::<10>(y),
            11 => self.solve_fixed::<11>(y),
            12 => self.solve_fixed::<12>(y),
            13 => self.solve_fixed::<13>(y),
            14 => self.solve_fixed::<14>(y),
            _ => None,
        }
    }

    fn solve_fixed<const P: usize>(&self, y: impl Fn(usize) -> f64) -> Option<(Vec<f64>, f64)> {
        let mut aty = [0.0f64; P];
        let mut yty = 0.0;
        for (i, row) in self.rows.chunks_exact(P).enumerate() {
            let yi = y(i);
            yty += yi * yi;
            for a in 0..P {
                aty[a] += row[a] * yi;
            }
        }
        let ata: [[f64; P]; P] = std::array::from_fn(|a| std::array::from_fn(|b| self.ata[a][b]));
        solve_normal(&ata, &aty, yty)
    }
}

/// Solves normal equations accumulated like [`least_squares`] does (`ata`'s
/// lower triangle, `aty`, `yty`) by Cholesky: the coefficients and the
/// residual sum of squares, or `None` when they are (numerically) singular.
pub(crate) fn solve_normal<const P: usize>(ata: &[[f64; P]; P], aty: &[f64; P], yty: f64) -> Option<(Vec<f64>, f64)> {
    // Cholesky: ata = L Lᵀ.
    let mut l = [[0.0f64; P]; P];
    for a in 0..P {
        for b in 0..=a {
            let mut sum = ata[a][b];
            sum -= (0..b).map(|k| l[a][k] * l[b][k]).sum::<f64>();
            if a == b {
                if sum.is_nan() || sum <= (1e-10 * ata[a][a]).max(0.0) {
                    return None;
                }
                l[a][a] = sum.sqrt();
            } else {
                l[a][b] = sum / l[b][b];
            }
        }
    }
    let mut z = [0.0f64; P];
    for a in 0..P {
        let mut sum = aty[a];
        for k in 0..a {
            sum -= l[a][k] * z[k];
        }
        z[a] = sum / l[a][a];
    }
    let mut coef = vec![0.0; P];
    for a in (0..P).rev() {
        let mut sum = z[a];
        for k in a + 1..P {
            sum -= l[k][a] * coef[k];
        }
        coef[a] = sum / l[a][a];
    }
    // The residual sum of squares without a second pass: yᵀy − ‖L⁻¹Aᵀy‖².
    let ssr = (yty - z.iter().map(|v| v * v).sum::<f64>()).max(0.0);
    coef.iter().all(|c| c.is_finite()).then_some((coef, ssr))
}

/// Standard deviation of the white measurement noise on a uniformly sampled
/// channel: from the median absolute fourth difference, which a smooth signal
/// barely moves at the sample rate while white noise of sd σ gives sd √70 σ
/// (the median makes the occasional kink of a stick/slip event harmless).
pub(crate) fn white_noise_sd(values: &[f64]) -> f64 {
    if values.len() < 64 {
        return 0.0;
    }
    let mut d4: Vec<f64> =
        values.windows(5).map(|w| (w[0] - 4.0 * w[1] + 6.0 * w[2] - 4.0 * w[3] + w[4]).abs()).collect();
    let mid = d4.len() / 2;
    let (_, median, _) = d4.select_nth_unstable_by(mid, f64::total_cmp);
    (*median / 0.674_489_750_196_081_7 / 70f64.sqrt()).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A kept design answers every right-hand side exactly (bit for bit) as a
    /// one-pass [`least_squares`] over the same rows does, at every width.
    #[test]
    fn a_kept_design_solves_exactly_as_least_squares() {
        let n = 500;
        let fill = |p: usize| {
            move |i: usize, row: &mut [f64]| {
                let s = i as f64 / n as f64;
                for (j, r) in row.iter_mut().enumerate().take(p) {
                    *r = (s * (j + 1) as f64 * 2.3).sin() + if j == 0 { 1.0 } else { 0.0 };
                }
            }
        };
        for p in 1..=MAX_COLUMNS {
            let design = Design::new(n, p, fill(p)).expect("a full-rank design");
            assert_eq!(design.rows(), n);
            for k in 0..3 {
                let y = |i: usize| ((i * 7919 + k * 104_729) % 1013) as f64 / 1013.0 - 0.3 * k as f64;
                let (coef, ssr) = least_squares(n, p, fill(p), y).expect("solvable");
                let (kept, kept_ssr) = design.solve(y).expect("solvable");
                assert_eq!(
                    coef.iter().map(|c| c.to_bits()).collect::<Vec<_>>(),
                    kept.iter().map(|c| c.to_bits()).collect::<Vec<_>>(),
                    "p = {p}"
                );
                assert_eq!(ssr.to_bits(), kept_ssr.to_bits(), "p = {p}");
            }
        }
        assert!(Design::new(n, MAX_COLUMNS + 1, fill(MAX_COLUMNS + 1)).is_none());
        assert!(Design::new(3, 4, fill(4)).is_none(), "fewer rows than columns");
    }
}
