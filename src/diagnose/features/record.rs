//! Features of the whole record: per-period peaks, the normal force, and
//! the share of time at rest.

use super::stats::{Design, moments, shape, slope};
use super::{
    HARMONIC_RATE_LIMIT, HARMONICS, NormalForceFeatures, PeakFeatures, SLOW_DEGREE, STICK_SPEED_FRACTION,
    WANDER_WINDOW_S,
};
use crate::engine::reduce::circular_mean_var;
use crate::measure::{self, Run};

/// Per-period peaks (see [`PeakFeatures`]).
pub(super) fn peak_features(run: &Run, base: &[(f64, f64)]) -> Option<PeakFeatures> {
    let periods = Periods::of(run, base)?;
    let period_s = periods.period_s;
    let mut peak = vec![f64::NEG_INFINITY; periods.count];
    let mut fundamental = vec![FundamentalSums::default(); periods.count];
    for ((&t, &x), &b) in run.t_s.iter().zip(&run.x_m).zip(base).take(periods.samples) {
        if let (Some(k), true) = (periods.of_time(t), x.is_finite()) {
            peak[k] = peak[k].max(x);
            fundamental[k].add(b, x);
        }
    }
    let phases: Vec<f64> = fundamental.iter().filter_map(FundamentalSums::phase_rad).collect();
    let (phase_mean, phase_var) = circular_mean_var(&phases);
    let (times, peaks): (Vec<f64>, Vec<f64>) =
        peak.iter().enumerate().filter(|(_, p)| p.is_finite()).map(|(k, &p)| ((k as f64 + 0.5) * period_s, p)).unzip();
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
        phase_mean_deg: if phases.is_empty() { 0.0 } else { phase_mean.to_degrees() },
        phase_var_deg2: if phases.len() < 2 { 0.0 } else { phase_var.to_degrees().to_degrees() },
    })
}

/// The largest `x` in each period of `run` ([`PeakFeatures`] reads its
/// statistics on the same windows), in time order, m; empty where the
/// record is too short or does not move. For a plot of the record's peaks
/// beside the features the diagnosis reads.
pub fn period_peaks(run: &Run) -> Vec<f64> {
    let base = super::base_of(&run.t_s, run.excitation_frequency_hz);
    let Some(periods) = Periods::of(run, &base) else { return Vec::new() };
    let mut peak = vec![f64::NEG_INFINITY; periods.count];
    for (&t, &x) in run.t_s.iter().zip(&run.x_m).take(periods.samples) {
        if let (Some(k), true) = (periods.of_time(t), x.is_finite()) {
            peak[k] = peak[k].max(x);
        }
    }
    peak.retain(|p| p.is_finite());
    peak
}

/// A record's periods: windows one excitation period long that start where
/// its fundamental (fitted over the whole record against the base's
/// `(cos Ωt, sin Ωt)`) first crosses its mean rising, at or after the first
/// sample ([`PeakFeatures`]), and end within the record.
struct Periods {
    /// Where the first window starts, s.
    start_s: f64,
    /// The excitation period, s.
    period_s: f64,
    /// Complete windows (at least 2).
    count: usize,
    /// Samples of the record read (those with both `t` and `x`).
    samples: usize,
}

impl Periods {
    /// `run`'s periods, `base` the base's `(cos Ωt, sin Ωt)` at its samples;
    /// `None` without a positive frequency and sample interval or with
    /// fewer than two complete windows. Where the fundamental cannot be
    /// fitted (a record that does not move) the windows start at the first
    /// sample.
    fn of(run: &Run, base: &[(f64, f64)]) -> Option<Periods> {
        let f = run.excitation_frequency_hz;
        let samples = run.t_s.len().min(run.x_m.len());
        let dt = run.sample_interval_s();
        if !(f.is_finite() && f > 0.0) || samples < 2 || dt <= 0.0 {
            return None;
        }
        let period_s = 1.0 / f;
        let t0 = run.t_s[0];
        let mut whole = FundamentalSums::default();
        for (&x, &b) in run.x_m.iter().zip(base).take(samples).filter(|(x, _)| x.is_finite()) {
            whole.add(b, x);
        }
        // x ≈ c + A cos(Ωt − φ) crosses its mean rising at Ωt = φ − π/2;
        // Ωt0 and that phase in turns of the excitation.
        let start_s = whole.phase_rad().map_or(t0, |phase| {
            let (now, crossing) = (t0 / period_s, (phase - std::f64::consts::FRAC_PI_2) / std::f64::consts::TAU);
            t0 + (crossing - now).rem_euclid(1.0) * period_s
        });
        let count = ((t0 + samples as f64 * dt - start_s) / period_s + 1e-9).floor();
        (count >= 2.0).then_some(Periods { start_s, period_s, count: count as usize, samples })
    }

    /// The window that time `t` (s) falls in, if any.
    fn of_time(&self, t: f64) -> Option<usize> {
        let k = ((t - self.start_s) / self.period_s).floor();
        (k >= 0.0 && k < self.count as f64).then_some(k as usize)
    }
}

/// Sums of one window for the least-squares fit `x ≈ c0 + a cos θ + b sin θ`
/// (θ = Ωt): the response's fundamental in that window.
#[derive(Clone, Copy, Debug, Default)]
struct FundamentalSums {
    n: f64,
    c: f64,
    s: f64,
    x: f64,
    cc: f64,
    ss: f64,
    cs: f64,
    xc: f64,
    xs: f64,
}

impl FundamentalSums {
    /// Adds a sample `x` where the base's (cos Ωt, sin Ωt) is `(c, s)`.
    fn add(&mut self, (c, s): (f64, f64), x: f64) {
        self.n += 1.0;
        self.c += c;
        self.s += s;
        self.x += x;
        self.cc += c * c;
        self.ss += s * s;
        self.cs += c * s;
        self.xc += x * c;
        self.xs += x * s;
    }

    /// `atan2(b, a)`, rad; `None` with too few samples or a singular fit.
    fn phase_rad(&self) -> Option<f64> {
        if self.n < 4.0 {
            return None;
        }
        let n = self.n;
        // Centred cross-products (the constant c0 eliminated).
        let cc = self.cc - self.c * self.c / n;
        let ss = self.ss - self.s * self.s / n;
        let cs = self.cs - self.c * self.s / n;
        let xc = self.xc - self.x * self.c / n;
        let xs = self.xs - self.x * self.s / n;
        let det = cc * ss - cs * cs;
        let singular = det.is_nan() || det <= 1e-12 * n * n;
        if singular {
            return None;
        }
        let a = (xc * ss - xs * cs) / det;
        let b = (xs * cc - xc * cs) / det;
        (a != 0.0 || b != 0.0).then(|| b.atan2(a))
    }
}

/// The normal-force fit's design for `n` samples of a record: Legendre
/// polynomials of its time and the harmonics of the excitation below
/// [`HARMONIC_RATE_LIMIT`] × the sample rate. It depends on the sample times
/// and the frequency only, so records sampled alike share one.
#[derive(Clone, Debug)]
pub(super) struct ForceDesign {
    /// The harmonics fitted (1-based multiples of the excitation frequency).
    fitted: Vec<usize>,
    /// Time from the first sample to the last, s.
    span_s: f64,
    design: Design,
}

impl ForceDesign {
    /// For the first `n` samples of `run`, whose base trig is `base`; `None`
    /// when the samples span no time or are fewer than the columns.
    pub(super) fn of(run: &Run, base: &[(f64, f64)], n: usize) -> Option<ForceDesign> {
        let n = n.min(run.t_s.len()).min(base.len());
        if n < 2 {
            return None;
        }
        let t = &run.t_s[..n];
        let f = run.excitation_frequency_hz;
        let rate = measure::sample_rate_hz(run);
        let fitted: Vec<usize> = (1..=HARMONICS)
            .filter(|&k| f.is_finite() && f > 0.0 && k as f64 * f < HARMONIC_RATE_LIMIT * rate)
            .collect();
        let t0 = t[0];
        let span_s = t[n - 1] - t0;
        if span_s.is_nan() || span_s <= 0.0 {
            return None;
        }
        let centre = 0.5 * (t[n - 1] + t0);
        // The slow part: Legendre polynomials P0 … P_SLOW_DEGREE of the record's
        // time scaled to [−1, 1], so that a drift that is not a straight line
        // (wear that saturates, heating that comes and goes) is not read as
        // noise; P1's coefficient is the straight-line drift.
        let slow = 1 + SLOW_DEGREE;
        let p = slow + 2 * fitted.len();
        // cos kΩt and sin kΩt from the fundamental's by the multiple-angle
        // recurrence (the base's one sin/cos per sample, made once per grid).
        let fill_row = |i: usize, row: &mut [f64]| {
            let s = 2.0 * (t[i] - centre) / span_s;
            legendre(s, &mut row[..slow]);
            let (c1, s1) = base[i];
            let (mut ck, mut sk) = (1.0, 0.0);
            let mut k_done = 0;
            for (j, &k) in fitted.iter().enumerate() {
                while k_done < k {
                    (ck, sk) = (ck * c1 - sk * s1, sk * c1 + ck * s1);
                    k_done += 1;
                }
                row[slow + 2 * j] = ck;
                row[slow + 1 + 2 * j] = sk;
            }
        };
        let design = Design::new(n, p, fill_row)?;
        Some(ForceDesign { fitted, span_s, design })
    }
}

/// Normal-force features (see [`NormalForceFeatures`]), with the fit's
/// design `prepared` where it was made for this many samples (else made here).
pub(super) fn normal_force_features(
    run: &Run,
    force: &[f64],
    base: &[(f64, f64)],
    prepared: Option<&ForceDesign>,
) -> Option<NormalForceFeatures> {
    let n = force.len().min(run.t_s.len()).min(base.len());
    if n < 2 || force[..n].iter().any(|v| !v.is_finite()) {
        return None;
    }
    let force = &force[..n];
    let (mean, m2, _, _) = moments(force);
    let var_n2 = m2 * n as f64 / (n - 1) as f64;

    let made_here;
    let design = match prepared {
        Some(d) if d.design.rows() == n => Some(d),
        _ => {
            made_here = ForceDesign::of(run, base, n);
            made_here.as_ref()
        }
    };
    let slow = 1 + SLOW_DEGREE;
    let fit = design.and_then(|d| Some((d, d.design.solve(|i| force[i] - mean)?)));
    let mut harmonic_amplitude_n = [None; HARMONICS];
    let mut harmonic_phase_rad = [None; HARMONICS];
    let (mut residual_var_n2, mut drift_n_per_s, mut curvature_n_per_s2, mut wander) = (None, None, None, None);
    if let Some((d, (coef, ssr))) = fit {
        let (p, span) = (coef.len(), d.span_s);
        for (j, &k) in d.fitted.iter().enumerate() {
            let (a, b) = (coef[slow + 2 * j], coef[slow + 1 + 2 * j]);
            harmonic_amplitude_n[k - 1] = Some(a.hypot(b));
            // a cos kΩt + b sin kΩt = A cos(kΩt + φ) with φ = atan2(−b, a).
            harmonic_phase_rad[k - 1] = Some((-b).atan2(a));
        }
        residual_var_n2 = (n > p).then(|| ssr / (n - p) as f64);
        // P1 = s = 2 (t − centre) / span; P2 = (3 s² − 1) / 2, whose t² term
        // is 6 / span² per unit of its coefficient.
        drift_n_per_s = Some(2.0 * coef[1] / span);
        curvature_n_per_s2 = Some(6.0 * coef[2] / (span * span));
        wander =
            residual_var_n2.and_then(|v| wander_of(&run.t_s[..n], |i| force[i] - mean - d.design.fitted(i, &coef), v));
    }
    let relative = |v: Option<f64>| v.filter(|_| mean != 0.0).map(|d| d / mean);
    let drift_per_s = relative(drift_n_per_s);
    let curvature_per_s2 = relative(curvature_n_per_s2);
    Some(NormalForceFeatures {
        mean_n: mean,
        var_n2,
        harmonic_amplitude_n,
        harmonic_phase_rad,
        residual_var_n2,
        drift_n_per_s,
        drift_per_s,
        curvature_per_s2,
        wander,
    })
}

/// [`NormalForceFeatures::wander`] of the residual `residual(i)` at times
/// `t` (s), whose variance is `var` (N²): the log of the variance of its
/// means over consecutive [`WANDER_WINDOW_S`] windows times the mean
/// samples per window, over `var`.
fn wander_of(t: &[f64], residual: impl Fn(usize) -> f64, var: f64) -> Option<f64> {
    let (t0, n) = (*t.first()?, t.len());
    let mut means = Vec::new();
    let (mut sum, mut count, mut window) = (0.0, 0usize, 0u64);
    for (i, &ti) in t.iter().enumerate() {
        let w = ((ti - t0) / WANDER_WINDOW_S).max(0.0) as u64;
        if w != window && count > 0 {
            means.push(sum / count as f64);
            (sum, count) = (0.0, 0);
        }
        window = w;
        sum += residual(i);
        count += 1;
    }
    // The last window counts only when it is whole (about).
    let per_window = n as f64 / ((t[n - 1] - t0) / WANDER_WINDOW_S).max(1e-12);
    if count as f64 >= 0.9 * per_window {
        means.push(sum / count as f64);
    }
    if means.len() < 4 || var.is_nan() || var <= 0.0 {
        return None;
    }
    let m = means.iter().sum::<f64>() / means.len() as f64;
    let spread = means.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (means.len() - 1) as f64;
    let ratio = spread * per_window.min(n as f64) / var;
    (ratio > 0.0).then(|| ratio.ln())
}

/// `P0(s) … P_{k−1}(s)` into `out` (k = `out.len()`), by Bonnet's recursion.
fn legendre(s: f64, out: &mut [f64]) {
    for k in 0..out.len() {
        out[k] = match k {
            0 => 1.0,
            1 => s,
            _ => ((2 * k - 1) as f64 * s * out[k - 1] - (k - 1) as f64 * out[k - 2]) / k as f64,
        };
    }
}

/// Share of samples at rest (see [`RunFeatures::stick_fraction`]).
pub(super) fn stick_fraction(run: &Run) -> Option<f64> {
    let share = |values: &[f64]| -> Option<f64> {
        let finite: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).map(f64::abs).collect();
        if finite.is_empty() {
            return None;
        }
        let max = finite.iter().copied().fold(0.0, f64::max);
        let at_rest = finite.iter().filter(|&&x| x <= STICK_SPEED_FRACTION * max).count();
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
