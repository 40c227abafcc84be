//! Features of one time-series record, computed by the same code from
//! measured runs (`measure::read_measurement_set`) and from simulated runs
//! (`cpu::simulate_path` samples → [`Run::from_samples`]).
//!
//! Each feature targets one of the effects named in `shared/spec/model.md`:
//!
//! | group | features | effect it looks at |
//! | --- | --- | --- |
//! | peaks | mean, variance, skewness, count, trend | the paper's Figures 8 and 9 |
//! | normal force | mean, variance, harmonics 1×–4×, residual variance, drift | `normal_force_harmonics`, `normal_force_drift` |
//! | friction | mean μ, residual std / skewness / excess kurtosis | `non_gaussian_friction`, `load_dependent_friction` |
//! | friction | residual autocorrelation at lags 1 and 10 | `coloured_friction_noise` |
//! | friction | accelerating − decelerating μ | `friction_hysteresis` |
//! | friction | breakaway ratio − low-speed μ | `stiction` |
//! | stick fraction | share of samples at rest | all of them, indirectly |
//!
//! Every feature is finite or absent (`None`); degenerate inputs (no slip,
//! zero variance, too few samples) give `None` or a documented neutral value,
//! never NaN.

use crate::measure::{self, Run};

/// Slipping samples have `|v|` above this fraction of the record's largest `|v|`.
pub const SLIP_SPEED_FRACTION: f64 = 0.05;
/// Stuck samples have `|v|` at most this fraction of the record's largest `|v|`.
pub const STICK_SPEED_FRACTION: f64 = 0.01;
/// "Low-speed" slip, for the stiction feature: `|v|` below this fraction of the largest `|v|`.
pub const LOW_SPEED_FRACTION: f64 = 0.2;
/// Number of `|v|` bins in which accelerating and decelerating friction are compared.
pub const HYSTERESIS_BINS: usize = 8;
/// Fewest accelerating and fewest decelerating samples a bin needs to count.
pub const HYSTERESIS_MIN_PER_SIDE: usize = 3;
/// Stick samples before a breakaway whose largest `|F|/N` is the breakaway ratio.
pub const BREAKAWAY_SAMPLES: usize = 3;
/// Shortest run of stuck samples that counts as a stick phase.
pub const MIN_STICK_SAMPLES: usize = 2;
/// Normal-force harmonics fitted: 1× … `HARMONICS`× the excitation frequency.
pub const HARMONICS: usize = 4;
/// A harmonic is fitted only below this fraction of the sample rate (Nyquist is 0.5).
pub const HARMONIC_RATE_LIMIT: f64 = 0.45;
/// Fewest sample pairs behind an autocorrelation.
pub const MIN_PAIRS: usize = 10;
/// Fewest slipping samples behind the friction features.
pub const MIN_SLIP_SAMPLES: usize = 20;

/// All features of one record.
#[derive(Clone, Debug, PartialEq)]
pub struct RunFeatures {
    /// Per-period peak statistics; `None` with fewer than two complete periods.
    pub peaks: Option<PeakFeatures>,
    /// Normal-force features; `None` without a `normal_force` channel.
    pub normal_force: Option<NormalForceFeatures>,
    /// Friction-coefficient features; `None` without `v`, `friction_force`
    /// and `normal_force`, or with too few slipping samples.
    pub friction: Option<FrictionFeatures>,
    /// Share of samples at rest, dimensionless in [0, 1]: `|v|` at most
    /// [`STICK_SPEED_FRACTION`] of the largest `|v|`; without `v`, the share
    /// of successive `x` differences at most that fraction of the largest
    /// difference. `None` with fewer than two samples.
    pub stick_fraction: Option<f64>,
}

/// Statistics of the largest `x` in each excitation period.
///
/// Periods are the windows `[t0 + kT, t0 + (k+1)T)`, `T = 1/f`, from the
/// record's first sample `t0`; only complete windows count. The peak is the
/// largest sample, not interpolated (for a sinusoid sampled `r` times per
/// period this is low by at most `1 − cos(π/r)`, relative: 6.7e-4 at 7 Hz
/// and 600 Hz).
#[derive(Clone, Debug, PartialEq)]
pub struct PeakFeatures {
    /// Number of peaks (complete periods).
    pub count: usize,
    /// Mean peak, m.
    pub mean_m: f64,
    /// Unbiased variance of the peaks, m² (0 with one peak).
    pub var_m2: f64,
    /// Skewness `m3 / m2^1.5` of the peaks, dimensionless (0 when they do not vary).
    pub skewness: f64,
    /// Least-squares slope of the peaks against time divided by their mean,
    /// 1/s; `None` when the mean peak is 0.
    pub trend_per_s: Option<f64>,
}

/// Features of the measured normal force `N(t)`.
///
/// `N` is fitted by least squares with a constant, a straight line in time
/// and `cos`/`sin` at `k·f`, `k = 1…4`, jointly over the whole record.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalForceFeatures {
    /// Mean, N.
    pub mean_n: f64,
    /// Unbiased variance, N².
    pub var_n2: f64,
    /// Amplitude `sqrt(a² + b²)` of the fitted harmonic at `(k+1)·f`, N;
    /// `None` for harmonics at or above [`HARMONIC_RATE_LIMIT`] × the sample
    /// rate, or when the fit is singular.
    pub harmonic_amplitude_n: [Option<f64>; HARMONICS],
    /// Variance of what the fit leaves (mean, drift and harmonics removed),
    /// N², with the fitted parameters' degrees of freedom taken off.
    pub residual_var_n2: Option<f64>,
    /// Slope of the fitted line, N/s.
    pub drift_n_per_s: Option<f64>,
    /// Slope of the fitted line divided by the mean, 1/s (`None` for a zero mean).
    pub drift_per_s: Option<f64>,
}

/// Features of the friction coefficient `μ = |F| / N` while slipping.
///
/// Slipping samples: `|v|` above [`SLIP_SPEED_FRACTION`] of the largest
/// `|v|`, friction opposing the motion (`F·v < 0`) and `N > 0`. A baseline
/// law `μ(s) = p0 + p1 s + p2 s² + p3 / (1 + c s)`, `s = |v| / max|v|`, is
/// fitted by least squares (`c` from a fixed grid, or without the last term,
/// whichever fits best); its residuals `r` are the "random part".
#[derive(Clone, Debug, PartialEq)]
pub struct FrictionFeatures {
    /// Number of slipping samples.
    pub slip_samples: usize,
    /// Mean μ over slipping samples, dimensionless.
    pub mu_mean: f64,
    /// Standard deviation of the residuals, dimensionless.
    pub residual_std: f64,
    /// Skewness `m3 / m2^1.5` of the residuals (0 when they do not vary).
    pub residual_skewness: f64,
    /// Excess kurtosis `m4 / m2² − 3` of the residuals (0 when they do not vary).
    pub residual_excess_kurtosis: f64,
    /// Autocorrelation of the residuals between successive samples of the
    /// same slip phase; `None` with fewer than [`MIN_PAIRS`] pairs.
    pub residual_autocorr_lag1: Option<f64>,
    /// The same at a lag of 10 samples (both within one slip phase).
    pub residual_autocorr_lag10: Option<f64>,
    /// Mean residual on accelerating samples (`v · dv/dt > 0`, central
    /// differences) minus that on decelerating samples, compared within
    /// [`HYSTERESIS_BINS`] equal `|v|` bins and averaged with weights
    /// `n_acc·n_dec / (n_acc + n_dec)`, dimensionless. Positive: more
    /// friction while speeding up. `None` when no bin has both kinds.
    pub hysteresis: Option<f64>,
    /// Mean breakaway ratio: over each stick phase (at least
    /// [`MIN_STICK_SAMPLES`] samples with `|v|` at most
    /// [`STICK_SPEED_FRACTION`] of the largest `|v|`) followed by motion, the
    /// largest `|F|/N` in its last [`BREAKAWAY_SAMPLES`] samples;
    /// dimensionless, `None` without such phases.
    pub breakaway_mean: Option<f64>,
    /// Mean μ over slipping samples with `|v|` below [`LOW_SPEED_FRACTION`]
    /// of the largest `|v|`; `None` without such samples.
    pub low_speed_mu_mean: Option<f64>,
    /// Excess static friction: `breakaway_mean − low_speed_mu_mean`.
    pub stiction_excess: Option<f64>,
}

/// Computes every feature of `run`.
pub fn run_features(run: &Run) -> RunFeatures {
    RunFeatures {
        peaks: peak_features(run),
        normal_force: run
            .normal_force
            .as_deref()
            .and_then(|n| normal_force_features(run, n)),
        friction: match (&run.v_m_per_s, &run.friction_force, &run.normal_force) {
            (Some(v), Some(f), Some(n)) => friction_features(v, f, n),
            _ => None,
        },
        stick_fraction: stick_fraction(run),
    }
}

impl RunFeatures {
    /// Every feature by name, in a fixed order, `None` where it is missing.
    /// Names carry units (`_m`, `_n`, `_per_s`, …); dimensionless ones none.
    pub fn all(&self) -> Vec<(&'static str, Option<f64>)> {
        let p = self.peaks.as_ref();
        let n = self.normal_force.as_ref();
        let f = self.friction.as_ref();
        let harmonic = |k: usize| n.and_then(|n| n.harmonic_amplitude_n[k]);
        vec![
            ("peak_count", p.map(|p| p.count as f64)),
            ("peak_mean_m", p.map(|p| p.mean_m)),
            ("peak_var_m2", p.map(|p| p.var_m2)),
            ("peak_skewness", p.map(|p| p.skewness)),
            ("peak_trend_per_s", p.and_then(|p| p.trend_per_s)),
            ("normal_force_mean_n", n.map(|n| n.mean_n)),
            ("normal_force_var_n2", n.map(|n| n.var_n2)),
            ("normal_force_harmonic1_n", harmonic(0)),
            ("normal_force_harmonic2_n", harmonic(1)),
            ("normal_force_harmonic3_n", harmonic(2)),
            ("normal_force_harmonic4_n", harmonic(3)),
            (
                "normal_force_residual_var_n2",
                n.and_then(|n| n.residual_var_n2),
            ),
            (
                "normal_force_drift_n_per_s",
                n.and_then(|n| n.drift_n_per_s),
            ),
            ("normal_force_drift_per_s", n.and_then(|n| n.drift_per_s)),
            ("friction_slip_samples", f.map(|f| f.slip_samples as f64)),
            ("friction_mu_mean", f.map(|f| f.mu_mean)),
            ("friction_residual_std", f.map(|f| f.residual_std)),
            ("friction_residual_skewness", f.map(|f| f.residual_skewness)),
            (
                "friction_residual_excess_kurtosis",
                f.map(|f| f.residual_excess_kurtosis),
            ),
            (
                "friction_residual_autocorr_lag1",
                f.and_then(|f| f.residual_autocorr_lag1),
            ),
            (
                "friction_residual_autocorr_lag10",
                f.and_then(|f| f.residual_autocorr_lag10),
            ),
            ("friction_hysteresis", f.and_then(|f| f.hysteresis)),
            ("friction_breakaway_mean", f.and_then(|f| f.breakaway_mean)),
            (
                "friction_low_speed_mu_mean",
                f.and_then(|f| f.low_speed_mu_mean),
            ),
            (
                "friction_stiction_excess",
                f.and_then(|f| f.stiction_excess),
            ),
            ("stick_fraction", self.stick_fraction),
        ]
    }

    /// The features that are present (and finite), by name, for scoring.
    pub fn named_values(&self) -> Vec<(&'static str, f64)> {
        self.all()
            .into_iter()
            .filter_map(|(name, value)| value.filter(|v| v.is_finite()).map(|v| (name, v)))
            .collect()
    }
}

/// Mean and central moments `(mean, m2, m3, m4)` (population, divided by n).
fn moments(values: &[f64]) -> (f64, f64, f64, f64) {
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
fn negligible(m2: f64, mean: f64) -> bool {
    m2.is_nan() || m2 <= (1e-24 * mean * mean).max(f64::MIN_POSITIVE)
}

/// Skewness and excess kurtosis from central moments (0, 0 when `m2` is negligible).
fn shape(mean: f64, m2: f64, m3: f64, m4: f64) -> (f64, f64) {
    if negligible(m2, mean) {
        (0.0, 0.0)
    } else {
        (m3 / m2.powf(1.5), m4 / (m2 * m2) - 3.0)
    }
}

/// Least-squares slope of `y` against `x`; `None` when `x` does not vary.
fn slope(x: &[f64], y: &[f64]) -> Option<f64> {
    let (mx, sxx, _, _) = moments(x);
    if x.len() < 2 || negligible(sxx, mx) {
        return None;
    }
    let my = y.iter().sum::<f64>() / y.len() as f64;
    let sxy = x
        .iter()
        .zip(y)
        .map(|(a, b)| (a - mx) * (b - my))
        .sum::<f64>()
        / x.len() as f64;
    Some(sxy / sxx)
}

/// Linear least squares: accumulates the normal equations of `rows`
/// (`fill(i, row)` writes row `i` of the design matrix) against `y`, and
/// solves them by Cholesky. Returns the coefficients and the residual sum of
/// squares, or `None` when the design is (numerically) singular.
fn least_squares(
    n: usize,
    p: usize,
    mut fill: impl FnMut(usize, &mut [f64]),
    y: impl Fn(usize) -> f64,
) -> Option<(Vec<f64>, f64)> {
    if n < p || p == 0 {
        return None;
    }
    let mut ata = vec![0.0; p * p];
    let mut aty = vec![0.0; p];
    let mut row = vec![0.0; p];
    for i in 0..n {
        fill(i, &mut row);
        let yi = y(i);
        for a in 0..p {
            aty[a] += row[a] * yi;
            for b in 0..=a {
                ata[a * p + b] += row[a] * row[b];
            }
        }
    }
    // Cholesky: ata = L Lᵀ, L stored in the lower triangle.
    let mut l = vec![0.0; p * p];
    for a in 0..p {
        for b in 0..=a {
            let mut sum = ata[a * p + b];
            for k in 0..b {
                sum -= l[a * p + k] * l[b * p + k];
            }
            if a == b {
                if sum.is_nan() || sum <= (1e-10 * ata[a * p + a]).max(0.0) {
                    return None;
                }
                l[a * p + a] = sum.sqrt();
            } else {
                l[a * p + b] = sum / l[b * p + b];
            }
        }
    }
    let mut z = vec![0.0; p];
    for a in 0..p {
        let mut sum = aty[a];
        for k in 0..a {
            sum -= l[a * p + k] * z[k];
        }
        z[a] = sum / l[a * p + a];
    }
    let mut coef = vec![0.0; p];
    for a in (0..p).rev() {
        let mut sum = z[a];
        for k in a + 1..p {
            sum -= l[k * p + a] * coef[k];
        }
        coef[a] = sum / l[a * p + a];
    }
    let mut ssr = 0.0;
    for i in 0..n {
        fill(i, &mut row);
        let fit: f64 = row.iter().zip(&coef).map(|(r, c)| r * c).sum();
        ssr += (y(i) - fit).powi(2);
    }
    coef.iter().all(|c| c.is_finite()).then_some((coef, ssr))
}

/// Per-period peaks (see [`PeakFeatures`]).
fn peak_features(run: &Run) -> Option<PeakFeatures> {
    let f = run.excitation_frequency_hz;
    let n = run.t_s.len().min(run.x_m.len());
    let dt = run.sample_interval_s();
    if !(f.is_finite() && f > 0.0) || n < 2 || dt <= 0.0 {
        return None;
    }
    let period_s = 1.0 / f;
    let t0 = run.t_s[0];
    let windows = (n as f64 * dt / period_s + 1e-9).floor();
    if windows.is_nan() || windows < 2.0 {
        return None;
    }
    let windows = windows as usize;
    let mut peak = vec![f64::NEG_INFINITY; windows];
    for i in 0..n {
        let k = ((run.t_s[i] - t0) / period_s).floor();
        if k >= 0.0 && (k as usize) < windows && run.x_m[i].is_finite() {
            let k = k as usize;
            peak[k] = peak[k].max(run.x_m[i]);
        }
    }
    let (times, peaks): (Vec<f64>, Vec<f64>) = peak
        .iter()
        .enumerate()
        .filter(|(_, p)| p.is_finite())
        .map(|(k, &p)| ((k as f64 + 0.5) * period_s, p))
        .unzip();
    let count = peaks.len();
    if count < 2 {
        return None;
    }
    let (mean, m2, m3, m4) = moments(&peaks);
    let (skewness, _) = shape(mean, m2, m3, m4);
    let trend_per_s = match slope(&times, &peaks) {
        Some(s) if mean != 0.0 => Some(s / mean),
        _ => None,
    };
    Some(PeakFeatures {
        count,
        mean_m: mean,
        var_m2: m2 * count as f64 / (count - 1) as f64,
        skewness,
        trend_per_s,
    })
}

/// Normal-force features (see [`NormalForceFeatures`]).
fn normal_force_features(run: &Run, force: &[f64]) -> Option<NormalForceFeatures> {
    let n = force.len().min(run.t_s.len());
    if n < 2 || force[..n].iter().any(|v| !v.is_finite()) {
        return None;
    }
    let force = &force[..n];
    let t = &run.t_s[..n];
    let (mean, m2, _, _) = moments(force);
    let var_n2 = m2 * n as f64 / (n - 1) as f64;

    let f = run.excitation_frequency_hz;
    let rate = measure::sample_rate_hz(run);
    let fitted: Vec<usize> = (1..=HARMONICS)
        .filter(|&k| f.is_finite() && f > 0.0 && k as f64 * f < HARMONIC_RATE_LIMIT * rate)
        .collect();
    let t0 = t[0];
    let span = t[n - 1] - t0;
    let centre = 0.5 * (t[n - 1] + t0);
    let p = 2 + 2 * fitted.len();
    let fit = (span > 0.0)
        .then(|| {
            least_squares(
                n,
                p,
                |i, row| {
                    row[0] = 1.0;
                    row[1] = (t[i] - centre) / span;
                    for (j, &k) in fitted.iter().enumerate() {
                        let phase = std::f64::consts::TAU * k as f64 * f * (t[i] - t0);
                        row[2 + 2 * j] = phase.cos();
                        row[3 + 2 * j] = phase.sin();
                    }
                },
                |i| force[i] - mean,
            )
        })
        .flatten();
    let mut harmonic_amplitude_n = [None; HARMONICS];
    let (mut residual_var_n2, mut drift_n_per_s) = (None, None);
    if let Some((coef, ssr)) = fit {
        for (j, &k) in fitted.iter().enumerate() {
            harmonic_amplitude_n[k - 1] = Some(coef[2 + 2 * j].hypot(coef[3 + 2 * j]));
        }
        residual_var_n2 = (n > p).then(|| ssr / (n - p) as f64);
        drift_n_per_s = Some(coef[1] / span);
    }
    let drift_per_s = drift_n_per_s.filter(|_| mean != 0.0).map(|d| d / mean);
    Some(NormalForceFeatures {
        mean_n: mean,
        var_n2,
        harmonic_amplitude_n,
        residual_var_n2,
        drift_n_per_s,
        drift_per_s,
    })
}

/// Grid of Stribeck rates `c` (in units of 1 / max|v|) tried by the friction baseline.
fn stribeck_grid() -> impl Iterator<Item = f64> {
    (0..21).map(|i| 0.3 * 10f64.powf(i as f64 * 0.2))
}

/// Friction-coefficient features (see [`FrictionFeatures`]).
fn friction_features(v: &[f64], force: &[f64], normal: &[f64]) -> Option<FrictionFeatures> {
    let n = v.len().min(force.len()).min(normal.len());
    let (v, force, normal) = (&v[..n], &force[..n], &normal[..n]);
    let v_max = v
        .iter()
        .filter(|x| x.is_finite())
        .fold(0.0f64, |m, x| m.max(x.abs()));
    if v_max <= 0.0 {
        return None;
    }
    let usable = |i: usize| {
        v[i].is_finite() && force[i].is_finite() && normal[i].is_finite() && normal[i] > 0.0
    };
    let slipping: Vec<bool> = (0..n)
        .map(|i| usable(i) && v[i].abs() > SLIP_SPEED_FRACTION * v_max && force[i] * v[i] < 0.0)
        .collect();
    let idx: Vec<usize> = (0..n).filter(|&i| slipping[i]).collect();
    if idx.len() < MIN_SLIP_SAMPLES {
        return None;
    }
    let mu: Vec<f64> = idx.iter().map(|&i| force[i].abs() / normal[i]).collect();
    let speed: Vec<f64> = idx.iter().map(|&i| v[i].abs() / v_max).collect();
    let (mu_mean, _, _, _) = moments(&mu);

    // Baseline law μ(s): quadratic, plus a Stribeck term when it fits better.
    let m = mu.len();
    let y = |i: usize| mu[i] - mu_mean;
    let quadratic = |i: usize, row: &mut [f64]| {
        row[0] = 1.0;
        row[1] = speed[i];
        row[2] = speed[i] * speed[i];
    };
    let mut best: Option<(Vec<f64>, f64, Option<f64>)> =
        least_squares(m, 3, quadratic, y).map(|(coef, ssr)| (coef, ssr, None));
    for c in stribeck_grid() {
        let design = |i: usize, row: &mut [f64]| {
            quadratic(i, row);
            row[3] = 1.0 / (1.0 + c * speed[i]);
        };
        if let Some((coef, ssr)) = least_squares(m, 4, design, y) {
            if best.as_ref().is_none_or(|b| ssr < b.1) {
                best = Some((coef, ssr, Some(c)));
            }
        }
    }
    let residual: Vec<f64> = match &best {
        Some((coef, _, c)) => (0..m)
            .map(|i| {
                let s = speed[i];
                let mut fit = coef[0] + coef[1] * s + coef[2] * s * s;
                if let Some(c) = c {
                    fit += coef[3] / (1.0 + c * s);
                }
                y(i) - fit
            })
            .collect(),
        None => (0..m).map(y).collect(),
    };
    let (r_mean, r2, r3, r4) = moments(&residual);
    let (residual_skewness, residual_excess_kurtosis) = shape(mu_mean, r2, r3, r4);
    let residual_std = (r2 * m as f64 / (m - 1) as f64).sqrt();

    // Slip phases: runs of consecutive slipping samples moving the same way.
    let mut phase = vec![0usize; m];
    for j in 1..m {
        let same = idx[j] == idx[j - 1] + 1 && v[idx[j]].signum() == v[idx[j - 1]].signum();
        phase[j] = if same { phase[j - 1] } else { phase[j - 1] + 1 };
    }
    let autocorr = |lag: usize| -> Option<f64> {
        if negligible(r2, mu_mean) {
            return None;
        }
        let (mut sum, mut pairs) = (0.0, 0usize);
        for j in 0..m.saturating_sub(lag) {
            if phase[j + lag] == phase[j] {
                sum += (residual[j] - r_mean) * (residual[j + lag] - r_mean);
                pairs += 1;
            }
        }
        (pairs >= MIN_PAIRS).then(|| sum / pairs as f64 / r2)
    };

    // Hysteresis: accelerating minus decelerating residual within |v| bins.
    let mut bins = [(0.0, 0usize, 0.0, 0usize); HYSTERESIS_BINS];
    for (j, &i) in idx.iter().enumerate() {
        if i == 0 || i + 1 >= n || !v[i - 1].is_finite() || !v[i + 1].is_finite() {
            continue;
        }
        let dv = v[i + 1] - v[i - 1];
        let b = ((speed[j] - SLIP_SPEED_FRACTION) / (1.0 - SLIP_SPEED_FRACTION)
            * HYSTERESIS_BINS as f64) as usize;
        let bin = &mut bins[b.min(HYSTERESIS_BINS - 1)];
        if v[i] * dv > 0.0 {
            bin.0 += residual[j];
            bin.1 += 1;
        } else if v[i] * dv < 0.0 {
            bin.2 += residual[j];
            bin.3 += 1;
        }
    }
    let (mut weighted, mut weights) = (0.0, 0.0);
    for &(acc_sum, n_acc, dec_sum, n_dec) in &bins {
        if n_acc >= HYSTERESIS_MIN_PER_SIDE && n_dec >= HYSTERESIS_MIN_PER_SIDE {
            let (a, d) = (n_acc as f64, n_dec as f64);
            let w = a * d / (a + d);
            weighted += w * (acc_sum / a - dec_sum / d);
            weights += w;
        }
    }
    let hysteresis = (weights > 0.0).then(|| weighted / weights);

    // Breakaway: the largest |F|/N over the end of each stick phase followed by motion.
    let stuck = |i: usize| v[i].is_finite() && v[i].abs() <= STICK_SPEED_FRACTION * v_max;
    let mut ratios = Vec::new();
    let mut start = 0;
    while start < n {
        if !stuck(start) {
            start += 1;
            continue;
        }
        let mut end = start;
        while end < n && stuck(end) {
            end += 1;
        }
        if end - start >= MIN_STICK_SAMPLES && end < n {
            let ratio = (end.saturating_sub(BREAKAWAY_SAMPLES).max(start)..end)
                .filter(|&i| usable(i))
                .map(|i| force[i].abs() / normal[i])
                .fold(f64::NEG_INFINITY, f64::max);
            if ratio.is_finite() {
                ratios.push(ratio);
            }
        }
        start = end;
    }
    let breakaway_mean =
        (!ratios.is_empty()).then(|| ratios.iter().sum::<f64>() / ratios.len() as f64);
    let low: Vec<f64> = speed
        .iter()
        .zip(&mu)
        .filter(|(s, _)| **s < LOW_SPEED_FRACTION)
        .map(|(_, m)| *m)
        .collect();
    let low_speed_mu_mean = (!low.is_empty()).then(|| low.iter().sum::<f64>() / low.len() as f64);
    let stiction_excess = breakaway_mean.zip(low_speed_mu_mean).map(|(b, l)| b - l);

    Some(FrictionFeatures {
        slip_samples: m,
        mu_mean,
        residual_std,
        residual_skewness,
        residual_excess_kurtosis,
        residual_autocorr_lag1: autocorr(1),
        residual_autocorr_lag10: autocorr(10),
        hysteresis,
        breakaway_mean,
        low_speed_mu_mean,
        stiction_excess,
    })
}

/// Share of samples at rest (see [`RunFeatures::stick_fraction`]).
fn stick_fraction(run: &Run) -> Option<f64> {
    let share = |values: &[f64]| -> Option<f64> {
        let finite: Vec<f64> = values
            .iter()
            .copied()
            .filter(|x| x.is_finite())
            .map(f64::abs)
            .collect();
        if finite.is_empty() {
            return None;
        }
        let max = finite.iter().copied().fold(0.0, f64::max);
        let at_rest = finite
            .iter()
            .filter(|&&x| x <= STICK_SPEED_FRACTION * max)
            .count();
        Some(at_rest as f64 / finite.len() as f64)
    };
    match &run.v_m_per_s {
        Some(v) if v.len() >= 2 => share(v),
        Some(_) => None,
        None => {
            let dx: Vec<f64> = run.x_m.windows(2).map(|w| w[1] - w[0]).collect();
            share(&dx)
        }
    }
}
