//! Features of one time-series record, computed by the same code from
//! measured runs ([`read_measurement_set`](crate::measure::read_measurement_set))
//! and from simulated records (the engine's samples → [`Run::from_samples`]).
//!
//! Each feature targets one of the effects named in `docs/model.md`:
//!
//! | group | features | effect it looks at |
//! | --- | --- | --- |
//! | peaks | mean, variance, skewness, count, trend | the paper's Figures 8 and 9 |
//! | phase | circular mean and variance of each period's fundamental | the response phase (`interfaces.md`) |
//! | normal force | mean, variance, harmonics 1×–4×, residual variance, drift | `normal_force_harmonics`, `normal_force_drift` |
//! | friction | mean μ, residual std / quantile skewness / tail weight | `non_gaussian_friction`, `load_dependent_friction` |
//! | friction | residual autocorrelation at lags 1 and 10 | `coloured_friction_noise` |
//! | friction | accelerating − decelerating μ | `friction_hysteresis` |
//! | friction | breakaway ratio − low-speed μ | `stiction` |
//! | stick fraction | share of samples at rest | all of them, indirectly |
//!
//! Every feature is finite or absent (`None`); degenerate inputs (no slip,
//! zero variance, too few samples) give `None` or a documented neutral value,
//! never NaN.

mod friction;
mod record;
pub use record::period_peaks;
mod stats;

pub(crate) use friction::GAUSSIAN_TAIL_RATIO;
pub(crate) use stats::{least_squares, solve_normal, white_noise_sd};

use std::borrow::Cow;

use crate::diagnose::observable::Observable;
use crate::measure::Run;

/// Slipping samples have `|v|` above this fraction of the record's largest `|v|`.
pub const SLIP_SPEED_FRACTION: f64 = 0.05;
/// A sample counts as slipping only beyond this many standard deviations of
/// the velocity channel's white noise (and beyond [`SLIP_SPEED_FRACTION`]
/// of its record's largest speed): a stuck block's measured speed is that
/// noise alone, and its |F|/N (the spring's force, anywhere below the
/// static friction) is not friction while slipping. At 3 sd a stuck sample
/// passes with probability 0.0013 (half of that with the sign friction has
/// while slipping).
pub const SLIP_SPEED_NOISE_SDS: f64 = 3.0;
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
/// Degree of the polynomial in time that a record's slow normal force
/// (its mean and drift) is fitted with, beside the harmonics.
pub const SLOW_DEGREE: usize = 4;
/// Normal-force harmonics fitted: 1× … `HARMONICS`× the excitation frequency.
pub const HARMONICS: usize = 4;
/// A harmonic is fitted only below this fraction of the sample rate (Nyquist is 0.5).
pub const HARMONIC_RATE_LIMIT: f64 = 0.45;
/// Fewest sample pairs behind an autocorrelation.
pub const MIN_PAIRS: usize = 10;
/// Fewest slipping samples behind the friction features.
pub const MIN_SLIP_SAMPLES: usize = 20;
/// A sample's friction coefficient |F|/N is read only where the normal
/// force is at least this share of the record's median: where N nears zero
/// (a load that follows a large motion, a contact that lifts), the force
/// sensors' noise divided by it is not friction, and a few such samples
/// would make the friction noise look hundreds of times larger than it is.
pub const MIN_NORMAL_FORCE_SHARE: f64 = 0.1;

/// The smallest normal force at which a record's |F|/N is read:
/// [`MIN_NORMAL_FORCE_SHARE`] of its median (positive), N.
pub fn normal_force_floor(normal_n: &[f64]) -> f64 {
    let mut finite: Vec<f64> = normal_n.iter().copied().filter(|x| x.is_finite()).collect();
    if finite.is_empty() {
        return f64::INFINITY;
    }
    let mid = finite.len() / 2;
    let median = *finite.select_nth_unstable_by(mid, f64::total_cmp).1;
    (MIN_NORMAL_FORCE_SHARE * median).max(f64::MIN_POSITIVE)
}

/// How a record's slipping samples are told from its sensors' noise and
/// from a derived force's blur. The measured records and the model's
/// replicates are read with the same one.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MotionReading {
    /// The velocity channel's white noise, m/s (0 where none is known).
    pub v_noise_m_per_s: f64,
    /// How many samples either side of one a friction force derived from
    /// the displacement reads (its filter's half-width and one more, 0 for
    /// a recorded force): a sample's derived force is the friction of a
    /// slip only where all of them slip, and the same way. Within a slip
    /// shorter than the window, or near a stop or a reversal, it blends
    /// the spring's force at rest into the friction.
    pub blur_samples: usize,
}

impl MotionReading {
    /// The speed a slipping sample of a record whose largest `|v|` is
    /// `v_max_m_per_s` stands above, m/s: [`SLIP_SPEED_FRACTION`] of it,
    /// and [`SLIP_SPEED_NOISE_SDS`] sd of the velocity's noise.
    pub fn slip_threshold(&self, v_max_m_per_s: f64) -> f64 {
        (SLIP_SPEED_FRACTION * v_max_m_per_s).max(SLIP_SPEED_NOISE_SDS * self.v_noise_m_per_s)
    }

    /// Which samples of `v` (m/s) slip: `|v|` above
    /// [`MotionReading::slip_threshold`], and so at every sample within
    /// [`MotionReading::blur_samples`] either side, all moving the same way.
    pub fn slipping(&self, v: &[f64]) -> Vec<bool> {
        let v_max = v.iter().filter(|x| x.is_finite()).fold(0.0f64, |m, x| m.max(x.abs()));
        let threshold = self.slip_threshold(v_max);
        let direction = |x: f64| {
            if x > threshold {
                1i8
            } else if x < -threshold {
                -1
            } else {
                0
            }
        };
        let reach = self.blur_samples;
        if reach == 0 {
            return v.iter().map(|&x| direction(x) != 0).collect();
        }
        // How many samples up to and including each move the same way
        // without a break: sample i's neighbourhood does throughout when
        // the run ending at i + reach is longer than 2 reach.
        let mut run = vec![0usize; v.len()];
        for i in 0..v.len() {
            let d = direction(v[i]);
            run[i] = match d {
                0 => 0,
                _ if i > 0 && direction(v[i - 1]) == d => run[i - 1] + 1,
                _ => 1,
            };
        }
        (0..v.len()).map(|i| i >= reach && i + reach < v.len() && run[i + reach] > 2 * reach).collect()
    }
}

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
    /// Whether the record's time is in the frame of the base motion, so
    /// that its absolute phases (the response's lag behind the base, the
    /// normal force's harmonics) mean something: false for a record with a
    /// free time origin, whose phases are then those of its own clock (only
    /// their spread and their differences are read).
    pub absolute_phase: bool,
}

/// Statistics of the largest `x` in each excitation period.
///
/// Periods are windows one excitation period `T = 1/f` long that start
/// where the record's own fundamental (fitted over the whole record)
/// crosses its mean rising: each holds one peak a quarter period from its
/// start and one trough three quarters in, and its edges fall mid-slip,
/// away from the stops at either turning point. Only complete windows
/// count. Where a window starts is a property of the response, not of the
/// record's time origin: a record that starts at another phase of the base
/// (a free time origin, or one framed by a `base_x` column) gives the same
/// statistics as one in the model's frame, and the replicates it is
/// compared with window alike. (Windows that start at a fixed phase of the
/// base cut through the peaks wherever the response is nearly in phase
/// with the base, well below resonance: a window then holds the end of one
/// peak and the start of the next, and its largest sample is sometimes
/// neither.) The per-period phases below are read on the same windows. The
/// peak is the largest sample, not interpolated (for a sinusoid sampled `r`
/// times per period this is low by at most `1 − cos(π/r)`, relative: 6.7e-4
/// at 7 Hz and 600 Hz).
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
    /// Circular mean of the per-period phase lag of the response's
    /// fundamental behind the base `U0 cos(Ωt)` (with the record's own `t`),
    /// degrees in (−180, 180]: per window, `x ≈ c + a cos Ωt + b sin Ωt` by
    /// least squares and `φ = atan2(b, a)`.
    pub phase_mean_deg: f64,
    /// Circular variance of those phases, degrees²
    /// ([`circular_mean_var`](crate::engine::reduce::circular_mean_var)).
    pub phase_var_deg2: f64,
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
    /// Its phase φ in `A cos(kΩt + φ)`, rad, with the record's own `t` (the
    /// base at `U0 cos Ωt`).
    pub harmonic_phase_rad: [Option<f64>; HARMONICS],
    /// Variance of what the fit leaves (the slow part — a polynomial of
    /// degree [`SLOW_DEGREE`] in time — and the harmonics removed),
    /// N², with the fitted parameters' degrees of freedom taken off.
    pub residual_var_n2: Option<f64>,
    /// Slope of the fitted line, N/s.
    pub drift_n_per_s: Option<f64>,
    /// Slope of the fitted line divided by the mean, 1/s (`None` for a zero mean).
    pub drift_per_s: Option<f64>,
    /// The slow part's curvature: the coefficient of t² of its quadratic
    /// (Legendre P2) term, divided by the mean, 1/s² (`None` for a zero
    /// mean).
    pub curvature_per_s2: Option<f64>,
    /// How far the residual wanders slowly: the natural log of the variance
    /// of its means over [`WANDER_WINDOW_S`] windows, times the samples in
    /// a window, over its variance, –. About 0 (ln of the samples a noise
    /// value is held for) where what the fit leaves is white; above it
    /// where the normal force wanders beyond the slow polynomial (a
    /// random-walk drift). A ratio of variances, compared in logs: a
    /// wander's ratio scatters in proportion to its size. `None` for fewer
    /// than four windows.
    pub wander: Option<f64>,
}

/// Window of [`NormalForceFeatures::wander`]'s means, s.
pub const WANDER_WINDOW_S: f64 = 1.0;

/// Features of the friction coefficient `μ = |F| / N` while slipping.
///
/// Slipping samples: those [`MotionReading::slipping`] keeps (`|v|` above
/// [`SLIP_SPEED_FRACTION`] of the largest `|v|` and above the velocity's
/// noise, clear of a derived force's blur), with friction opposing the
/// motion (`F·v < 0`) and `N` above [`normal_force_floor`]. A baseline
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
    /// Kelly's quantile skewness of the residuals, (q90 + q10 − 2 q50) /
    /// (q90 − q10), in [−1, 1] (0 when they do not vary).
    pub residual_skewness: f64,
    /// The residuals' excess tail weight: (q97.5 − q2.5) / (q75 − q25)
    /// divided by a Gaussian's 2.906, less 1 (0 for Gaussian residuals, 0
    /// when they do not vary).
    pub residual_tail_weight: f64,
    /// Autocorrelation of the residuals between successive samples of the
    /// same slip phase; `None` with fewer than [`MIN_PAIRS`] pairs.
    pub residual_autocorr_lag1: Option<f64>,
    /// The same at a lag of 10 samples (both within one slip phase).
    pub residual_autocorr_lag10: Option<f64>,
    /// The residuals' least-squares slope against time over the record,
    /// over the mean μ, 1/s: a friction (or, read against the nominal
    /// load, a normal force) that changes over the record changes μ by
    /// this share per second. `None` when the residuals do not vary or the
    /// slipping samples span no time.
    pub trend_per_s: Option<f64>,
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

/// What the features of records sampled at the same times under the same
/// excitation frequency share: the base's `(cos Ωt, sin Ωt)` at every sample
/// and the normal-force fit's design. A diagnosis simulates several replicate
/// records per condition on one grid; made once, it serves them all, and
/// their features are exactly those [`run_features`] computes alone.
#[derive(Clone, Debug)]
pub struct SampleGrid {
    t_s: Vec<f64>,
    excitation_frequency_hz: f64,
    base: Vec<(f64, f64)>,
    normal_force: Option<record::ForceDesign>,
}

impl SampleGrid {
    /// The grid of `run`'s sample times and excitation frequency.
    pub fn of(run: &Run) -> SampleGrid {
        let base = base_of(&run.t_s, run.excitation_frequency_hz);
        let normal_force = run.normal_force.as_ref().and_then(|_| record::ForceDesign::of(run, &base, run.t_s.len()));
        SampleGrid { t_s: run.t_s.clone(), excitation_frequency_hz: run.excitation_frequency_hz, base, normal_force }
    }

    /// The base's `(cos Ωt, sin Ωt)` at every sample, Ω the excitation's
    /// angular frequency (rad/s) and t the grid's times (s).
    pub(crate) fn base(&self) -> &[(f64, f64)] {
        &self.base
    }

    /// Whether `run` was sampled on this grid (bit for bit the same times and frequency).
    pub(crate) fn serves(&self, run: &Run) -> bool {
        let same = |a: f64, b: f64| a.to_bits() == b.to_bits();
        same(run.excitation_frequency_hz, self.excitation_frequency_hz)
            && run.t_s.len() == self.t_s.len()
            && run.t_s.iter().zip(&self.t_s).all(|(&a, &b)| same(a, b))
    }
}

/// The normal force μ is read against in `run`, N: its `normal_force`
/// channel, else its nominal load at every sample (a set that records no
/// normal force is read so on both sides: the model's replicate records
/// then drop theirs, [`crate::diagnose::derived`]).
pub fn load_of(run: &Run) -> Cow<'_, [f64]> {
    match &run.normal_force {
        Some(n) => Cow::Borrowed(n),
        None => Cow::Owned(vec![run.normal_force_n; run.len()]),
    }
}

/// The base's `(cos Ωt, sin Ωt)` at each of the times `t_s` (s), Ω = 2π ×
/// `frequency_hz`: the record's own clock.
fn base_of(t_s: &[f64], frequency_hz: f64) -> Vec<(f64, f64)> {
    let omega = std::f64::consts::TAU * frequency_hz;
    t_s.iter()
        .map(|&t| {
            let (s, c) = (omega * t).sin_cos();
            (c, s)
        })
        .collect()
}

/// Computes every feature of `run`, its channels read as they are (no
/// velocity noise known, a recorded force).
pub fn run_features(run: &Run) -> RunFeatures {
    run_features_read(run, MotionReading::default())
}

/// Computes every feature of `run`, its slipping samples told apart as
/// `motion` says.
pub fn run_features_read(run: &Run, motion: MotionReading) -> RunFeatures {
    features_on_grid(run, &SampleGrid::of(run), motion)
}

/// Computes every feature of `run` with what `grid` holds where `run` was
/// sampled on it (else as [`run_features_read`] does).
pub fn run_features_on(run: &Run, grid: &SampleGrid, motion: MotionReading) -> RunFeatures {
    if grid.serves(run) { features_on_grid(run, grid, motion) } else { run_features_read(run, motion) }
}

fn features_on_grid(run: &Run, grid: &SampleGrid, motion: MotionReading) -> RunFeatures {
    let base = &grid.base;
    RunFeatures {
        peaks: record::peak_features(run, base),
        normal_force: run
            .normal_force
            .as_deref()
            .and_then(|n| record::normal_force_features(run, n, base, grid.normal_force.as_ref())),
        friction: match (&run.v_m_per_s, &run.friction_force) {
            (Some(v), Some(f)) => friction::friction_features(&run.t_s, v, f, &load_of(run), motion),
            _ => None,
        },
        stick_fraction: record::stick_fraction(run),
        absolute_phase: run.time_origin.phase_known(),
    }
}

impl RunFeatures {
    /// Every feature by observable, in a fixed order, `None` where it is missing.
    pub fn all(&self) -> Vec<(Observable, Option<f64>)> {
        let p = self.peaks.as_ref();
        let n = self.normal_force.as_ref();
        let f = self.friction.as_ref();
        let harmonic = |k: usize| n.and_then(|n| n.harmonic_amplitude_n[k]);
        vec![
            (Observable::PeakCount, p.map(|p| p.count as f64)),
            (Observable::PeakMeanM, p.map(|p| p.mean_m)),
            (Observable::PeakVarM2, p.map(|p| p.var_m2)),
            (Observable::PeakSkewness, p.map(|p| p.skewness)),
            (Observable::PeakTrendPerS, p.and_then(|p| p.trend_per_s)),
            (Observable::PhaseMeanDeg, p.filter(|_| self.absolute_phase).map(|p| p.phase_mean_deg)),
            (Observable::PhaseVarDeg2, p.map(|p| p.phase_var_deg2)),
            (Observable::NormalForceMeanN, n.map(|n| n.mean_n)),
            (Observable::NormalForceVarN2, n.map(|n| n.var_n2)),
            (Observable::NormalForceHarmonic1N, harmonic(0)),
            (Observable::NormalForceHarmonic2N, harmonic(1)),
            (Observable::NormalForceHarmonic3N, harmonic(2)),
            (Observable::NormalForceHarmonic4N, harmonic(3)),
            (Observable::NormalForceResidualVarN2, n.and_then(|n| n.residual_var_n2)),
            (Observable::NormalForceDriftNPerS, n.and_then(|n| n.drift_n_per_s)),
            (Observable::NormalForceDriftPerS, n.and_then(|n| n.drift_per_s)),
            (Observable::NormalForceCurvaturePerS2, n.and_then(|n| n.curvature_per_s2)),
            (Observable::NormalForceWander, n.and_then(|n| n.wander)),
            (Observable::FrictionSlipSamples, f.map(|f| f.slip_samples as f64)),
            (Observable::FrictionMuMean, f.map(|f| f.mu_mean)),
            (Observable::FrictionResidualStd, f.map(|f| f.residual_std)),
            (Observable::FrictionResidualSkewness, f.map(|f| f.residual_skewness)),
            (Observable::FrictionResidualTailWeight, f.map(|f| f.residual_tail_weight)),
            (Observable::FrictionResidualAutocorrLag1, f.and_then(|f| f.residual_autocorr_lag1)),
            (Observable::FrictionResidualAutocorrLag10, f.and_then(|f| f.residual_autocorr_lag10)),
            (Observable::FrictionTrendPerS, f.and_then(|f| f.trend_per_s)),
            (Observable::FrictionHysteresis, f.and_then(|f| f.hysteresis)),
            (Observable::FrictionBreakawayMean, f.and_then(|f| f.breakaway_mean)),
            (Observable::FrictionLowSpeedMuMean, f.and_then(|f| f.low_speed_mu_mean)),
            (Observable::FrictionStictionExcess, f.and_then(|f| f.stiction_excess)),
            (Observable::StickFraction, self.stick_fraction),
        ]
    }

    /// The features that are present (and finite), for scoring.
    pub fn named_values(&self) -> Vec<(Observable, f64)> {
        self.all().into_iter().filter_map(|(name, value)| value.filter(|v| v.is_finite()).map(|v| (name, v))).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// A stuck block's measured speed is its sensor's noise: read against
    /// its own largest value alone, a third of its samples "slip"; above
    /// three of the noise's standard deviations, almost none do.
    #[test]
    fn a_stuck_record_does_not_slip_on_its_noise() {
        let sd = 4e-4;
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        // Box–Muller: a Gaussian of sd `sd` from two uniforms.
        let v: Vec<f64> = (0..30_000)
            .map(|_| {
                let (u1, u2) = (1.0 - rng.random::<f64>(), rng.random::<f64>());
                sd * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
            })
            .collect();
        let share = |motion: MotionReading| motion.slipping(&v).iter().filter(|&&s| s).count() as f64 / v.len() as f64;
        assert!(share(MotionReading::default()) > 0.5, "{}", share(MotionReading::default()));
        let read = share(MotionReading { v_noise_m_per_s: sd, blur_samples: 0 });
        assert!(read < 0.005, "{read}");
    }

    /// A derived force is read only where the filter's reach lies within
    /// one slip: a slip no longer than twice the reach gives no sample, a
    /// longer one its interior, and a reversal between two slips none
    /// within the reach of it.
    #[test]
    fn a_derived_force_is_read_clear_of_its_blur() {
        let reach = 3;
        let motion = MotionReading { v_noise_m_per_s: 0.0, blur_samples: reach };
        // At rest, a slip of 6 samples, rest, a slip of 20, then 20 back.
        let mut v = vec![0.0; 10];
        v.extend([1.0; 6]);
        v.extend([0.0; 10]);
        v.extend([1.0; 20]);
        v.extend([-1.0; 20]);
        v.extend([0.0; 10]);
        let kept: Vec<usize> = motion.slipping(&v).iter().enumerate().filter(|(_, s)| **s).map(|(i, _)| i).collect();
        let forward = 26..46;
        let back = 46..66;
        let expected: Vec<usize> =
            (forward.start + reach..forward.end - reach).chain(back.start + reach..back.end - reach).collect();
        assert_eq!(kept, expected);
        // Without a reach, every moving sample.
        let all = MotionReading::default().slipping(&v).iter().filter(|&&s| s).count();
        assert_eq!(all, 46);
    }
}
