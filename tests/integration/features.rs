//! Run features on synthetic records with known answers, on degenerate
//! records, and on a record simulated from the default model.

use std::f64::consts::TAU;

use stickslip::diagnose::features::{
    MotionReading, RunFeatures, SampleGrid, period_peaks, run_features, run_features_on,
};
use stickslip::engine::{Condition, Model};
use stickslip::measure::Run;

use crate::common;

const RATE_HZ: f64 = 600.0;
const F_HZ: f64 = 7.0;

/// A small deterministic generator (SplitMix64) with uniform, Gaussian and
/// exponential draws, so the tests do not depend on any RNG crate.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1).
    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    fn gaussian(&mut self) -> f64 {
        (-2.0 * self.uniform().ln()).sqrt() * (TAU * self.uniform()).cos()
    }

    /// Exponential with mean 1.
    fn exponential(&mut self) -> f64 {
        -self.uniform().ln()
    }
}

/// Sample times of a `duration_s` record at 600 Hz starting at `t0_s`.
fn times(t0_s: f64, duration_s: f64) -> Vec<f64> {
    (0..(duration_s * RATE_HZ).round() as usize).map(|i| t0_s + i as f64 / RATE_HZ).collect()
}

/// A record with only `t` and `x`.
fn run_tx(t: Vec<f64>, x: Vec<f64>) -> Run {
    Run {
        file: Default::default(),
        excitation_frequency_hz: F_HZ,
        excitation_amplitude_m: 0.0025,
        normal_force_n: 16.0,
        t_s: t,
        x_m: x,
        v_m_per_s: None,
        normal_force: None,
        friction_force: None,
        time_origin: Default::default(),
    }
}

/// A record with `x` and `v` of a sinusoid (amplitude 4 mm) and a normal force `n`.
fn run_with_force(t: Vec<f64>, n: Vec<f64>) -> Run {
    let x = t.iter().map(|t| 0.004 * (TAU * F_HZ * t).cos()).collect();
    let mut run = run_tx(t, x);
    run.normal_force = Some(n);
    run
}

/// A slipping record: `v = V sin(Ωt)`, `N = 16 N`, `F = −μ N sgn(v)` with
/// `μ = 0.4 + noise[i]`.
fn friction_run(noise: &[f64]) -> Run {
    let t = times(0.0, noise.len() as f64 / RATE_HZ);
    let v: Vec<f64> = t.iter().map(|t| 0.15 * (TAU * F_HZ * t).sin()).collect();
    let n = vec![16.0; t.len()];
    let f: Vec<f64> = v.iter().zip(noise).map(|(v, e)| -(0.4 + e) * 16.0 * v.signum()).collect();
    let x = t.iter().map(|t| -0.15 / (TAU * F_HZ) * (TAU * F_HZ * t).cos()).collect();
    let mut run = run_tx(t, x);
    run.v_m_per_s = Some(v);
    run.normal_force = Some(n);
    run.friction_force = Some(f);
    run
}

fn value(features: &RunFeatures, name: &str) -> Option<f64> {
    features.named_values().into_iter().find(|(o, _)| o.name() == name).map(|(_, v)| v)
}

#[test]
fn sinusoid_peaks_equal_the_amplitude() {
    let amplitude = 3.85e-3;
    for (t0, phase) in [(0.0, 0.0), (12.345, 1.1), (-3.0, 2.9)] {
        let t = times(t0, 50.0);
        let x = t.iter().map(|t| amplitude * (TAU * F_HZ * t + phase).cos()).collect();
        let features = run_features(&run_tx(t, x));
        let peaks = features.peaks.as_ref().expect("peaks");
        // 350 periods, less the part before the first trough.
        assert!((349..=350).contains(&peaks.count), "{peaks:?}");
        assert!((peaks.mean_m / amplitude - 1.0).abs() < 1e-3, "{peaks:?}");
        assert!(peaks.var_m2 < (1e-3 * amplitude).powi(2), "{peaks:?}");
        assert!(peaks.trend_per_s.unwrap().abs() < 1e-5, "{peaks:?}");
        // No velocity: the stick fraction comes from x differences; a sinusoid never rests long.
        assert!(features.stick_fraction.unwrap() < 0.02, "{features:?}");
    }
    // A growing amplitude shows as a positive trend: 1 %/s.
    let t = times(0.0, 20.0);
    let x = t.iter().map(|t| amplitude * (1.0 + 0.01 * t) * (TAU * F_HZ * t).cos()).collect();
    let peaks = run_features(&run_tx(t, x)).peaks.unwrap();
    let expected = 0.01 / (1.0 + 0.01 * 10.0);
    assert!((peaks.trend_per_s.unwrap() / expected - 1.0).abs() < 0.02, "{peaks:?}");
}

/// A response nearly in phase with the base (3°, as well below resonance)
/// whose amplitude varies from period to period by 1 %: the peaks' mean and
/// variance are the amplitudes' wherever the record starts (its time
/// origin), since each window holds one peak. Windows that started at the
/// base's phase would end just short of the next peak and take the larger
/// of two amplitudes about half the time.
#[test]
fn peak_statistics_do_not_depend_on_where_the_record_starts() {
    let mut rng = Rng(11);
    let amplitudes: Vec<f64> = (0..400).map(|_| 3.85e-3 * (1.0 + 0.01 * rng.gaussian())).collect();
    let lag = 3f64.to_radians();
    for start_turns in [0.0, 0.25, 0.5, 0.75, 0.99] {
        let t = times(start_turns / F_HZ, 50.0);
        // The amplitude of period k holds from one trough (Ωt − lag = π) to the next.
        let period = |t: f64| ((TAU * F_HZ * t - lag) / TAU + 0.5).floor() as usize;
        let x: Vec<f64> = t.iter().map(|&t| amplitudes[period(t)] * (TAU * F_HZ * t - lag).cos()).collect();
        let (first, last) = (period(t[0]), period(*t.last().unwrap()));
        let run = run_tx(t, x);
        let peaks = run_features(&run).peaks.unwrap();
        // A plot of the record's peaks reads the same periods.
        let each = period_peaks(&run);
        assert_eq!(each.len(), peaks.count);
        assert!((each.iter().sum::<f64>() / each.len() as f64 - peaks.mean_m).abs() < 1e-15);
        // The complete periods between the first sample and the last.
        let seen = &amplitudes[first + 1..last];
        let mean = seen.iter().sum::<f64>() / seen.len() as f64;
        let var = seen.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / (seen.len() - 1) as f64;
        assert!((peaks.mean_m - mean).abs() < 0.1 * var.sqrt(), "from {start_turns} turns: {peaks:?} against {mean}");
        assert!((peaks.var_m2 / var - 1.0).abs() < 0.1, "from {start_turns} turns: {peaks:?} against {var}");
        assert_eq!(peaks.count, seen.len(), "from {start_turns} turns");
    }
}

#[test]
fn peak_skewness_has_the_sign_of_the_outliers() {
    let mut rng = Rng(3);
    let t = times(0.0, 50.0);
    // A different random amplitude each period (changing at the troughs),
    // exponentially distributed: skewness 2.
    let bumps: Vec<f64> = (0..400).map(|_| 1e-4 * rng.exponential()).collect();
    let x: Vec<f64> =
        t.iter().map(|t| (3e-3 + bumps[(t * F_HZ + 0.5).floor() as usize]) * (TAU * F_HZ * t).cos()).collect();
    let peaks = run_features(&run_tx(t, x)).peaks.unwrap();
    assert!(peaks.skewness > 1.2 && peaks.skewness < 3.0, "{peaks:?}");
}

#[test]
fn normal_force_harmonic_is_recovered() {
    let mut rng = Rng(7);
    let t = times(0.0, 50.0);
    let n: Vec<f64> =
        t.iter().map(|t| 16.0 + 0.3 * (2.0 * TAU * F_HZ * t + 0.7).cos() + 0.33 * rng.gaussian()).collect();
    let features = run_features(&run_with_force(t, n));
    let nf = features.normal_force.as_ref().expect("normal-force features");
    let h = nf.harmonic_amplitude_n.map(|a| a.expect("all four harmonics are below Nyquist"));
    assert!((h[1] / 0.3 - 1.0).abs() < 0.05, "{nf:?}");
    for k in [0, 2, 3] {
        assert!(h[k] < 0.02, "harmonic {}: {nf:?}", k + 1);
    }
    assert!((nf.mean_n - 16.0).abs() < 0.01, "{nf:?}");
    // Total variance includes the harmonic (0.3²/2); the residual does not.
    assert!((nf.var_n2 / (0.33f64.powi(2) + 0.045) - 1.0).abs() < 0.05, "{nf:?}");
    assert!((nf.residual_var_n2.unwrap() / 0.33f64.powi(2) - 1.0).abs() < 0.05, "{nf:?}");
    assert!(nf.drift_n_per_s.unwrap().abs() < 1e-3, "{nf:?}");
    assert_eq!(value(&features, "normal_force_harmonic2_n"), Some(h[1]));
}

#[test]
fn records_sampled_alike_share_a_grid_and_get_the_same_features() {
    // Replicates of one condition: the same times, other forces and motions.
    let mut rng = Rng(23);
    let t = times(3.0, 20.0);
    let replicate = |rng: &mut Rng| {
        let n = t.iter().map(|t| 16.0 + 0.2 * (TAU * F_HZ * t).sin() + 0.3 * rng.gaussian()).collect();
        let mut run = run_with_force(t.clone(), n);
        run.x_m.iter_mut().for_each(|x| *x += 1e-4 * rng.gaussian());
        run
    };
    let runs: Vec<Run> = (0..3).map(|_| replicate(&mut rng)).collect();
    let grid = SampleGrid::of(&runs[0]);
    for run in &runs {
        assert_eq!(run_features_on(run, &grid, MotionReading::default()), run_features(run));
    }
    // A record the grid was not made for (other times, another frequency)
    // gets its own features, not the grid's.
    let mut shifted = replicate(&mut rng);
    shifted.t_s.iter_mut().for_each(|t| *t += 0.5 / RATE_HZ);
    let mut other_frequency = replicate(&mut rng);
    other_frequency.excitation_frequency_hz = 1.5 * F_HZ;
    for run in [&shifted, &other_frequency] {
        assert_eq!(run_features_on(run, &grid, MotionReading::default()), run_features(run));
    }
}

#[test]
fn normal_force_drift_is_recovered() {
    let mut rng = Rng(11);
    let t = times(5.0, 50.0);
    let n: Vec<f64> = t.iter().map(|t| 16.0 + 0.02 * t + 0.33 * rng.gaussian()).collect();
    let nf = run_features(&run_with_force(t, n)).normal_force.unwrap();
    assert!((nf.drift_n_per_s.unwrap() / 0.02 - 1.0).abs() < 0.05, "{nf:?}");
    let mean = 16.0 + 0.02 * 30.0;
    assert!((nf.mean_n - mean).abs() < 0.01, "{nf:?}");
    assert!((nf.drift_per_s.unwrap() / (0.02 / mean) - 1.0).abs() < 0.05, "{nf:?}");
    // The drift is fitted jointly, so it does not leak into the harmonics.
    assert!(nf.harmonic_amplitude_n.iter().all(|a| a.unwrap() < 0.02), "{nf:?}");
    assert!((nf.residual_var_n2.unwrap() / 0.33f64.powi(2) - 1.0).abs() < 0.05, "{nf:?}");
}

#[test]
fn a_bent_drift_is_not_read_as_noise() {
    // A quadratic drift: its t² term comes back as the curvature (relative
    // to the record's mean), and what is left is the noise put in.
    let mut rng = Rng(19);
    let t = times(5.0, 50.0);
    let n: Vec<f64> = t.iter().map(|t| 16.0 * (1.0 + 0.01 * t - 2e-4 * t * t) + 0.33 * rng.gaussian()).collect();
    let nf = run_features(&run_with_force(t.clone(), n)).normal_force.unwrap();
    let curvature = -2e-4 * 16.0 / nf.mean_n;
    assert!((nf.curvature_per_s2.unwrap() / curvature - 1.0).abs() < 0.05, "{nf:?}");
    assert!((nf.residual_var_n2.unwrap() / 0.33f64.powi(2) - 1.0).abs() < 0.05, "{nf:?}");
    // A wandering one (a sine of period 94 s, 18 % of N0): a straight line
    // would leave a variance of about (16 · 0.18)² / 8 ≈ 1 N² as noise.
    let n: Vec<f64> = t.iter().map(|t| 16.0 * (1.0 + 0.18 * (t / 15.0).sin()) + 0.33 * rng.gaussian()).collect();
    let nf = run_features(&run_with_force(t, n)).normal_force.unwrap();
    assert!((nf.residual_var_n2.unwrap() / 0.33f64.powi(2) - 1.0).abs() < 0.05, "{nf:?}");
    assert!(nf.curvature_per_s2.unwrap() < 0.0, "{nf:?}");
}

#[test]
fn friction_residual_shape() {
    let n = 30_000;
    // Gaussian noise: no skew, no excess kurtosis, no correlation, no hysteresis.
    let mut rng = Rng(13);
    let gauss: Vec<f64> = (0..n).map(|_| 0.03 * rng.gaussian()).collect();
    let fr = run_features(&friction_run(&gauss)).friction.expect("friction features");
    assert!((fr.mu_mean - 0.4).abs() < 1e-3, "{fr:?}");
    assert!((fr.residual_std / 0.03 - 1.0).abs() < 0.03, "{fr:?}");
    assert!(fr.residual_skewness.abs() < 0.03, "{fr:?}");
    assert!(fr.residual_tail_weight.abs() < 0.05, "{fr:?}");
    assert!(fr.residual_autocorr_lag1.unwrap().abs() < 0.05, "{fr:?}");
    assert!(fr.residual_autocorr_lag10.unwrap().abs() < 0.05, "{fr:?}");
    assert!(fr.hysteresis.unwrap().abs() < 0.003, "{fr:?}");
    assert!(fr.breakaway_mean.is_none() && fr.stiction_excess.is_none(), "no stick phases: {fr:?}");
    // Most samples slip (|v| > 5 % of max): all but 2·asin(0.05)/π ≈ 3 %.
    assert!(fr.slip_samples > 29_000 && fr.slip_samples < 29_300, "{fr:?}");

    // Exponential noise: Kelly skewness (ln 10 + ln(10/9) − 2 ln 2) /
    // (ln 10 − ln(10/9)) = 0.465, tail weight (ln 40 − ln(40/39)) / ln 3 /
    // 2.906 − 1 = 0.148.
    let mut rng = Rng(17);
    let skewed: Vec<f64> = (0..n).map(|_| 0.03 * (rng.exponential() - 1.0)).collect();
    let fr = run_features(&friction_run(&skewed)).friction.unwrap();
    assert!((fr.residual_skewness - 0.465).abs() < 0.03, "{fr:?}");
    assert!((fr.residual_tail_weight - 0.148).abs() < 0.04, "{fr:?}");
}

#[test]
fn friction_trend_is_the_relative_change_per_second() {
    // μ = 0.4 (1 + r t) over a 50 s record (a load drifting by r per
    // second, read against its nominal value), with white noise of 0.03:
    // the trend comes back as r within about four of its standard errors
    // (0.03 / 0.4 / √(30 000 · 50² / 12) ≈ 3e-5 /s); without the drift it
    // is zero within them.
    let t = times(0.0, 50.0);
    for r in [0.002, 0.0] {
        let mut rng = Rng(29);
        let noise: Vec<f64> = t.iter().map(|t| 0.4 * r * t + 0.03 * rng.gaussian()).collect();
        let fr = run_features(&friction_run(&noise)).friction.unwrap();
        let trend = fr.trend_per_s.expect("a trend");
        let relative = r / (1.0 + r * 25.0);
        assert!((trend - relative).abs() < 1.2e-4, "r {r}: {fr:?}");
        assert_eq!(value(&run_features(&friction_run(&noise)), "friction_trend_per_s"), Some(trend));
    }
}

#[test]
fn friction_residual_correlation() {
    let rho: f64 = 0.9;
    let mut rng = Rng(19);
    let mut e = 0.0;
    let ar1: Vec<f64> = (0..30_000)
        .map(|_| {
            e = rho * e + (1.0 - rho * rho).sqrt() * 0.03 * rng.gaussian();
            e
        })
        .collect();
    let fr = run_features(&friction_run(&ar1)).friction.unwrap();
    assert!((fr.residual_autocorr_lag1.unwrap() - rho).abs() < 0.05, "{fr:?}");
    assert!((fr.residual_autocorr_lag10.unwrap() - rho.powi(10)).abs() < 0.1, "{fr:?}");
}

#[test]
fn friction_hysteresis_and_stiction() {
    // Friction 0.05 higher while |v| grows.
    let t = times(0.0, 50.0);
    let mut rng = Rng(23);
    let noise: Vec<f64> = t
        .iter()
        .map(|t| {
            let phase = (TAU * F_HZ * t).rem_euclid(TAU);
            // |sin| grows in the first and third quarters of the cycle.
            let accelerating = (phase % std::f64::consts::PI) < std::f64::consts::FRAC_PI_2;
            0.05 * f64::from(u8::from(accelerating)) + 0.01 * rng.gaussian()
        })
        .collect();
    let fr = run_features(&friction_run(&noise)).friction.unwrap();
    assert!((fr.hysteresis.unwrap() - 0.05).abs() < 0.005, "{fr:?}");

    // Stick phases where |sin| ≤ 0.1 (v = 0), with |F|/N 0.3 and 0.6 at the
    // last stuck sample; μ = 0.4 while slipping.
    let mut run = friction_run(&vec![0.0; t.len()]);
    let v = run.v_m_per_s.as_mut().unwrap();
    let f = run.friction_force.as_mut().unwrap();
    let mut stuck = 0usize;
    for i in 0..v.len() {
        let s = (TAU * F_HZ * t[i]).sin();
        if s.abs() <= 0.1 {
            v[i] = 0.0;
            stuck += 1;
            let next_moves = i + 1 < t.len() && (TAU * F_HZ * t[i + 1]).sin().abs() > 0.1;
            f[i] = if next_moves { 0.6 * 16.0 } else { 0.3 * 16.0 };
        }
    }
    let features = run_features(&run);
    let fr = features.friction.as_ref().unwrap();
    assert!((fr.breakaway_mean.unwrap() - 0.6).abs() < 1e-9, "{fr:?}");
    assert!((fr.low_speed_mu_mean.unwrap() - 0.4).abs() < 1e-9, "{fr:?}");
    assert!((fr.stiction_excess.unwrap() - 0.2).abs() < 1e-9, "{fr:?}");
    let expected_stick = stuck as f64 / t.len() as f64;
    assert!((features.stick_fraction.unwrap() - expected_stick).abs() < 1e-12, "{features:?}");
    assert!((expected_stick - 4.0 * 0.1f64.asin() / TAU).abs() < 0.005);
}

#[test]
fn degenerate_records_give_no_nan() {
    // Empty.
    let empty = run_features(&run_tx(vec![], vec![]));
    assert!(empty.peaks.is_none() && empty.stick_fraction.is_none() && empty.named_values().is_empty());

    // At rest: constant x, v = 0, F = 0, N = 0.
    let t = times(0.0, 5.0);
    let len = t.len();
    let mut run = run_tx(t, vec![1e-3; len]);
    run.v_m_per_s = Some(vec![0.0; len]);
    run.normal_force = Some(vec![0.0; len]);
    run.friction_force = Some(vec![0.0; len]);
    let features = run_features(&run);
    let peaks = features.peaks.as_ref().unwrap();
    assert_eq!((peaks.mean_m, peaks.var_m2, peaks.skewness), (1e-3, 0.0, 0.0));
    assert!(features.friction.is_none(), "nothing slips");
    assert_eq!(features.stick_fraction, Some(1.0));
    let nf = features.normal_force.as_ref().unwrap();
    assert_eq!(nf.var_n2, 0.0);
    assert_eq!(nf.drift_per_s, None, "relative drift of a zero mean");
    for (name, v) in features.all() {
        assert!(v.is_none_or(f64::is_finite), "{name} = {v:?}");
    }

    // Shorter than two periods; a frequency of zero.
    let short = run_tx(times(0.0, 0.2), vec![0.0; 120]);
    assert!(run_features(&short).peaks.is_none());
    let mut zero_f = run_tx(times(0.0, 2.0), vec![0.0; 1200]);
    zero_f.excitation_frequency_hz = 0.0;
    assert!(run_features(&zero_f).peaks.is_none());

    // Names are unique.
    let names: Vec<&str> = features.all().iter().map(|(o, _)| o.name()).collect();
    let mut sorted = names.clone();
    sorted.sort();
    sorted.dedup();
    assert_eq!(sorted.len(), names.len());
}

#[test]
fn simulated_default_model_run() {
    let model = Model::default();
    let condition = Condition { excitation_frequency_hz: F_HZ, normal_force_n: 16.39 };
    let samples = common::record(&model, condition, 1, 100, 20.0, RATE_HZ);
    let run = Run::from_samples(&samples, F_HZ, model.excitation.amplitude_m, 16.39);
    let features = run_features(&run);
    let all = features.all();
    for (name, v) in &all {
        assert!(v.is_some(), "{name} missing: {features:#?}");
        assert!(v.unwrap().is_finite(), "{name} = {v:?}");
    }
    assert_eq!(features.named_values().len(), all.len());
    let peaks = features.peaks.as_ref().unwrap();
    // 140 periods, less the part before the response's first trough.
    assert_eq!(peaks.count, 139);
    assert!((peaks.mean_m / 3.85e-3 - 1.0).abs() < 0.1, "{peaks:?}");
    let nf = features.normal_force.as_ref().unwrap();
    assert!((nf.mean_n - 16.39).abs() < 0.02, "{nf:?}");
    assert!((nf.var_n2 / model.normal_force.sigma.powi(2) - 1.0).abs() < 0.1, "{nf:?}");
    let fr = features.friction.as_ref().unwrap();
    assert!(fr.mu_mean > 0.3 && fr.mu_mean < 0.6, "{fr:?}");
    let stick = features.stick_fraction.unwrap();
    assert!(stick > 0.0 && stick < 1.0, "{stick}");
    eprintln!("{features:#?}");
}

/// The slow wander (a log): about 0 for white noise around harmonics and a
/// bent drift (the fit takes both out), far above it for a random walk of
/// the same white noise's size over the record (a 1 s mean of 45 s of walk
/// wanders about 0.1 N, against 0.33/sqrt(RATE_HZ) N of white noise).
#[test]
fn a_wandering_normal_force_stands_out_of_white_noise() {
    let mut rng = Rng(29);
    let t = times(5.0, 50.0);
    let white: Vec<f64> = t
        .iter()
        .map(|t| 16.0 * (1.0 + 0.01 * t - 2e-4 * t * t) + 0.3 * (TAU * F_HZ * t).cos() + 0.33 * rng.gaussian())
        .collect();
    let wander = |n: Vec<f64>| run_features(&run_with_force(t.clone(), n)).normal_force.unwrap().wander.unwrap();
    let w = wander(white);
    // Under white noise the estimate is the log of a variance of 45 window
    // means: sd about sqrt(2/44) ≈ 0.21.
    assert!((-0.9..0.6).contains(&w), "white: {w}");
    let mut walk = 0.0;
    let step = (2e-4 / RATE_HZ).sqrt();
    let walked: Vec<f64> = t
        .iter()
        .map(|_| {
            walk += step * rng.gaussian();
            16.0 * (1.0 + walk) + 0.33 * rng.gaussian()
        })
        .collect();
    let w = wander(walked);
    assert!(w > 20f64.ln(), "random walk: {w}");
}
