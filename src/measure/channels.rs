//! Conventions of a run's channels that no single value can break, checked
//! over the whole record: `v` is the rate of change of `x` (the same sign,
//! in m/s as `x` is in m), and the friction force is the force on the
//! block, which opposes the block's motion while it slips and is, in
//! newtons, what the equation of motion says it is.
//!
//! A record that breaks one of them (a velocity in mm/s, a channel wired
//! the other way round, the force on the friction element instead of the
//! one on the block, a dead channel that reads 0 throughout) reads without
//! a single bad value. Read as it is, none of its samples counts as
//! slipping, every friction feature vanishes without a word, and a
//! diagnosis is sure of `none` on data it never looked at. So such a record is refused, by file and column, with what
//! the check saw.

use std::path::Path;

use super::json::bad;
use super::{RigInfo, Run};
use crate::diagnose::features::least_squares;
use crate::engine::analytic::linear_amplitude_ratio;
use crate::engine::model::fmt_value;
use crate::error::{Error, Result};

/// Fewest samples either check reads before it judges: fewer say nothing
/// either way (a block that barely moves).
const MIN_SAMPLES: usize = 20;

/// The correlation of `v` with the rate of change of `x` beyond which the
/// two are the same signal, up to its sign and scale: a velocity channel
/// that tracks `x` this closely (or its mirror image) is not noise.
const SAME_SIGNAL: f64 = 0.5;

/// The factor by which `v` may differ in scale from the rate of change of
/// `x` before its unit is called wrong: sensor noise, filtering and
/// differencing move the ratio by percent, a unit of mm/s by a thousand.
const SCALE_FACTOR: f64 = 10.0;

/// The share of the fastest samples at which a friction force that pushes
/// the block along its motion is called reversed: a friction force
/// opposes the motion at every sample where the block slips, so only
/// sensor noise and offsets push a few the other way, and a block at rest
/// (whose velocity is noise) gives about half.
const REVERSED_SHARE: f64 = 0.8;

/// The rate of change of `x` (m/s) at each interior sample with finite
/// neighbours, by central differences over the times `t_s` (s), with the
/// sample's index.
fn displacement_rate(t_s: &[f64], x_m: &[f64]) -> Vec<(usize, f64)> {
    let n = t_s.len().min(x_m.len());
    (1..n.saturating_sub(1))
        .filter_map(|i| {
            let rate = (x_m[i + 1] - x_m[i - 1]) / (t_s[i + 1] - t_s[i - 1]);
            rate.is_finite().then_some((i, rate))
        })
        .collect()
}

/// The samples where the block moves at more than half its peak speed (so
/// slips, where it moves at all), with the rate of change of `x_m` (m/s)
/// there ([`displacement_rate`] at times `t_s`, s); none where it does not
/// move.
pub(crate) fn fast_motion(t_s: &[f64], x_m: &[f64]) -> Vec<(usize, f64)> {
    let rate = displacement_rate(t_s, x_m);
    let peak = rate.iter().fold(0.0f64, |m, &(_, r)| m.max(r.abs()));
    if peak <= 0.0 {
        return Vec::new();
    }
    rate.into_iter().filter(|&(_, r)| r.abs() >= 0.5 * peak).collect()
}

/// Refuses a velocity column `v` (m/s) that is not the rate of change of
/// `x_m` (m) at times `t_s` (s): one that falls where `x` rises (its sign
/// reversed), or one that tracks it at more than [`SCALE_FACTOR`] times its
/// size or less than its inverse (another unit).
pub(super) fn check_velocity(path: &Path, t_s: &[f64], x_m: &[f64], v: &[f64]) -> Result<()> {
    let pairs: Vec<(f64, f64)> = displacement_rate(t_s, x_m)
        .into_iter()
        .filter_map(|(i, rate)| v.get(i).filter(|v| v.is_finite()).map(|&v| (v, rate)))
        .collect();
    // Sums of the channels divided by their largest magnitudes, so that
    // no square underflows (a displacement in units of 1e-200 m is still
    // one the scale check must see) or overflows.
    let peak = |f: fn(&(f64, f64)) -> f64| pairs.iter().fold(0.0f64, |m, p| m.max(f(p).abs()));
    let (v_peak, r_peak) = (peak(|p| p.0), peak(|p| p.1));
    if pairs.len() < MIN_SAMPLES || r_peak <= 0.0 {
        return Ok(());
    }
    let v_unit = if v_peak > 0.0 { v_peak } else { 1.0 };
    let (vv, rr, vr) = pairs.iter().fold((0.0, 0.0, 0.0), |(vv, rr, vr), &(v, r)| {
        let (v, r) = (v / v_unit, r / r_peak);
        (vv + v * v, rr + r * r, vr + v * r)
    });
    // A channel that never changes while `x` moves is dead (or a constant
    // written in its place): read as a velocity, it would make a sliding
    // block look stuck throughout.
    if let Some(&(first, _)) = pairs.first()
        && pairs.iter().all(|&(v, _)| v == first)
    {
        return Err(dead_channel(path, "v", first, "m/s", "the block's velocity dx/dt"));
    }
    let correlation = vr / (vv * rr).sqrt();
    let scale = (v_unit / r_peak) * (vv / rr).sqrt();
    if correlation < -SAME_SIGNAL {
        return Err(bad(
            path,
            None,
            format!(
                "column `v`: it falls where `x` rises (its correlation with the rate of change of `x` is {}): \
                 `v` is the block's velocity, dx/dt, so one of the two channels has its sign reversed",
                fmt_value((correlation * 1e3).round() / 1e3)
            ),
        ));
    }
    if correlation > SAME_SIGNAL && !(1.0 / SCALE_FACTOR..=SCALE_FACTOR).contains(&scale) {
        return Err(bad(
            path,
            None,
            format!(
                "column `v`: it follows the rate of change of `x` but is {} times its size: `v` must be in m/s as \
                 `x` is in m (a velocity in mm/s is 1000 times too large)",
                fmt_value(float_3(scale))
            ),
        ));
    }
    Ok(())
}

/// The refusal of a `column` of run file `path` that reads `value` (in
/// `unit`) at every sample while the block moves: a dead channel (or a
/// constant written in its place), not `what` it claims to be.
fn dead_channel(path: &Path, column: &str, value: f64, unit: &str, what: &str) -> Error {
    bad(
        path,
        None,
        format!(
            "column `{column}`: it is {} {unit} at every sample while the block moves: a dead channel, not {what} \
             (leave the column out if the rig did not record it)",
            fmt_value(value + 0.0)
        ),
    )
}

/// Refuses a friction-force column (N) that pushes the block along its
/// motion, the motion read from `x_m` (m) at times `t_s` (s): at
/// [`REVERSED_SHARE`] or more of the samples where the block moves at more
/// than half its peak speed, where it slips.
pub(super) fn check_friction(path: &Path, t_s: &[f64], x_m: &[f64], friction_n: &[f64]) -> Result<()> {
    let moving = fast_motion(t_s, x_m);
    // The friction force on this rig never holds still while the block
    // moves: it turns with the motion where the block slips, and balances
    // the springs' pull, which follows the base, where it sticks.
    let finite = || friction_n.iter().filter(|f| f.is_finite());
    if let Some(&first) = finite().next()
        && moving.len() >= MIN_SAMPLES
        && finite().all(|&f| f == first)
    {
        return Err(dead_channel(path, "friction_force", first, "N", "the force on the block"));
    }
    let signs: Vec<f64> = moving
        .into_iter()
        .filter_map(|(i, r)| friction_n.get(i).map(|&f| f * r))
        .filter(|p| p.is_finite() && *p != 0.0)
        .collect();
    let along = signs.iter().filter(|&&p| p > 0.0).count();
    if signs.len() >= MIN_SAMPLES && along as f64 >= REVERSED_SHARE * signs.len() as f64 {
        return Err(bad(
            path,
            None,
            format!(
                "column `friction_force`: it pushes the block along its motion at {along} of the {} samples where \
                 the block moves at more than half its peak speed: the friction force is the force on the block, \
                 which opposes its velocity while it slips, so this one has its sign reversed (the force on the \
                 friction element, or the other sign convention)",
                signs.len()
            ),
        ));
    }
    Ok(())
}

/// The factor by which the friction force may differ from the force the
/// equation of motion puts on the block before its unit is called wrong: at
/// the excitation's harmonics the two agree within 5% (0.984–1.042) on the
/// 965 judged runs of three benchmark collections of either generator
/// (sensor noise included); a friction force in kN is a thousand times too
/// small, a dead channel zero times.
const BALANCE_FACTOR: f64 = 5.0;

/// How many times its own noise the rig's side must stand out at the
/// harmonics before the balance is judged: a block stuck throughout, or one
/// sliding in a near-sinusoid, leaves its harmonics at the noise of `x`, and
/// there the ratio says nothing.
const BALANCE_SIGNAL_TO_NOISE: f64 = 10.0;

/// The highest harmonic of the excitation the balance reads (from the 2nd):
/// the odd ones up to the 5th carry most of a stick-slip force's shape, and
/// the least-squares fit of [`least_squares`] holds the constant, the
/// fundamental and these five.
const BALANCE_HARMONICS: usize = 6;

/// The share of the sample rate every harmonic the balance reads stays
/// below, clear of Nyquist's half.
const BALANCE_NYQUIST_SHARE: f64 = 0.4;

/// The stretches of a record the balance reads apart, to see how far its
/// harmonics move from one to the next (their noise): a record covers at
/// least ten excitation periods, so each covers at least two.
const BALANCE_STRETCHES: usize = 5;

/// The harmonics' coefficients (cos, sin of each of `harmonics` of the
/// angular frequency `w`, rad/s) of `y` over samples `range` at times `t`
/// (s), fitted beside a constant and the fundamental.
fn harmonic_parts(
    t: &[f64],
    y: &[f64],
    range: std::ops::Range<usize>,
    w: f64,
    harmonics: &[usize],
) -> Option<Vec<f64>> {
    let offset = range.start;
    let fill = |i: usize, row: &mut [f64]| {
        row[0] = 1.0;
        for (slot, j) in std::iter::once(1).chain(harmonics.iter().copied()).enumerate() {
            let (s, c) = (j as f64 * w * t[offset + i]).sin_cos();
            row[1 + 2 * slot] = c;
            row[2 + 2 * slot] = s;
        }
    };
    let (coefficients, _) = least_squares(range.len(), 3 + 2 * harmonics.len(), fill, |i| y[offset + i])?;
    Some(coefficients[3..].to_vec())
}

/// Refuses a run whose friction force is not, within [`BALANCE_FACTOR`],
/// the force the rest of the equation of motion puts on the block:
/// `m x'' + c x' + k x = k u(t) + F`, with the rig's m, c and k. Both are
/// read at the excitation's harmonics from the 2nd to the
/// [`BALANCE_HARMONICS`]th, where the base's `k u(t)` (at the fundamental
/// only, whatever the time origin) does not enter: `x` and the friction
/// force are fitted by least squares on a constant, the fundamental and
/// those harmonics, and the rig's side at harmonic `j` follows from `x`'s
/// there exactly, `(k − m (jΩ)² + i c jΩ) X_j`, with no differencing. So
/// sensor noise averages out over the record, and the factor (the friction
/// force's regression on the rig's side) is sharp wherever the motion has
/// harmonics that stand out of their noise ([`BALANCE_SIGNAL_TO_NOISE`],
/// the noise read from how the harmonics move between
/// [`BALANCE_STRETCHES`] stretches of the record): a channel in another
/// unit, another signal, or a dead one reads far from 1.
pub(super) fn check_force_balance(run: &Run, rig: &RigInfo) -> Result<()> {
    let Some(friction_n) = &run.friction_force else { return Ok(()) };
    let (t, x) = (&run.t_s, &run.x_m);
    let n = t.len().min(x.len()).min(friction_n.len());
    if n < MIN_SAMPLES * BALANCE_STRETCHES {
        return Ok(());
    }
    let (k, c) = (rig.stiffness_n_per_m(), rig.damping_n_s_per_m());
    let w = std::f64::consts::TAU * run.excitation_frequency_hz;
    let sample_rate_hz = super::sample_rate_hz(run);
    let harmonics: Vec<usize> = (2..=BALANCE_HARMONICS)
        .filter(|&j| j as f64 * run.excitation_frequency_hz < BALANCE_NYQUIST_SHARE * sample_rate_hz)
        .collect();
    if harmonics.is_empty() {
        return Ok(());
    }
    // Per stretch, the rig's side and the friction force at the harmonics.
    let mut rig_parts = Vec::with_capacity(BALANCE_STRETCHES);
    let mut friction_parts = Vec::with_capacity(BALANCE_STRETCHES);
    for stretch in 0..BALANCE_STRETCHES {
        let range = stretch * n / BALANCE_STRETCHES..(stretch + 1) * n / BALANCE_STRETCHES;
        let (Some(xc), Some(fc)) =
            (harmonic_parts(t, x, range.clone(), w, &harmonics), harmonic_parts(t, friction_n, range, w, &harmonics))
        else {
            return Ok(());
        };
        let mut rig_side = Vec::with_capacity(xc.len());
        for (slot, &j) in harmonics.iter().enumerate() {
            let (a, b) = (xc[2 * slot], xc[2 * slot + 1]);
            let jw = j as f64 * w;
            let (spring, damper) = (k - rig.mass_kg * jw * jw, c * jw);
            // x = a cos + b sin: m x'' + c x' + k x has cos part
            // (k − m (jω)²) a + c jω b and sin part (k − m (jω)²) b − c jω a.
            rig_side.extend([spring * a + damper * b, spring * b - damper * a]);
        }
        rig_parts.push(rig_side);
        friction_parts.push(fc);
    }
    let mean = |parts: &[Vec<f64>]| -> Vec<f64> {
        (0..parts[0].len()).map(|i| parts.iter().map(|p| p[i]).sum::<f64>() / parts.len() as f64).collect()
    };
    let (rig_side, friction) = (mean(&rig_parts), mean(&friction_parts));
    // The noise of the mean rig side: its stretches' scatter over B(B − 1).
    let stretches = BALANCE_STRETCHES as f64;
    let noise: f64 =
        rig_parts.iter().flat_map(|p| p.iter().zip(&rig_side).map(|(v, m)| (v - m) * (v - m))).sum::<f64>()
            / (stretches * (stretches - 1.0));
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| a * b).sum::<f64>();
    let (rr, rf, ff) = (dot(&rig_side, &rig_side), dot(&rig_side, &friction), dot(&friction, &friction));
    if !(rr > 0.0 && rr >= BALANCE_SIGNAL_TO_NOISE * BALANCE_SIGNAL_TO_NOISE * noise) {
        return Ok(());
    }
    let factor = rf / rr;
    let correlation = if ff > 0.0 { rf / (rr * ff).sqrt() } else { 0.0 };
    if !(1.0 / BALANCE_FACTOR..=BALANCE_FACTOR).contains(&factor) {
        let last = harmonics.last().copied().unwrap_or(2);
        return Err(bad(
            &run.file,
            None,
            format!(
                "column `friction_force`: at the excitation's harmonics 2 to {last} it is {} times the force the rest \
                 of the equation of motion puts on the block there (m x'' + c x' + k x from `x` and the rig; the two \
                 correlate at {}): the friction force must be the force on this block, in newtons, and the rig's \
                 mass and natural frequency those of this block (a factor near 0 is a dead or unrelated channel)",
                fmt_value(float_3(factor)),
                fmt_value(float_3(correlation))
            ),
        ));
    }
    Ok(())
}

/// How many times the rig's frictionless steady amplitude a record's `x`
/// may swing before its unit is called wrong: friction only takes energy
/// out of the block (it opposes the motion at every instant), so a block
/// swings at most about as far as it would without it; the margin covers a
/// natural frequency or damping stated loosely near resonance, and a
/// column in millimetres is a thousand times too large.
const SWING_FACTOR: f64 = 100.0;

/// Refuses a run whose `x` swings (half its range) more than
/// [`SWING_FACTOR`] times the frictionless steady amplitude of the rig at
/// the run's excitation: a displacement in another unit, or another rig.
pub(super) fn check_displacement_scale(run: &Run, rig: &RigInfo) -> Result<()> {
    let (lo, hi) = run
        .x_m
        .iter()
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| (lo.min(x), hi.max(x)));
    let swing_m = 0.5 * (hi - lo);
    let eta = run.excitation_frequency_hz / rig.natural_frequency_hz;
    let frictionless_m = linear_amplitude_ratio(eta, rig.damping_ratio) * run.excitation_amplitude_m;
    if swing_m > SWING_FACTOR * frictionless_m {
        return Err(bad(
            &run.file,
            None,
            format!(
                "column `x`: it swings {} m, {} times as far as this rig would without friction at {} Hz ({} m \
                 for excitation_amplitude_m = {} m): friction only takes energy out, so `x` must be in metres (a \
                 column in millimetres is 1000 times too large) and the rig's natural frequency and damping ratio \
                 those of this block",
                fmt_value(float_3(swing_m)),
                fmt_value(float_3(swing_m / frictionless_m)),
                fmt_value(run.excitation_frequency_hz),
                fmt_value(float_3(frictionless_m)),
                fmt_value(run.excitation_amplitude_m)
            ),
        ));
    }
    Ok(())
}

/// `x` rounded to three significant figures, for messages.
fn float_3(x: f64) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let scale = 10f64.powi(2 - x.abs().log10().floor() as i32);
    (x * scale).round() / scale
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A slipping block's record at 600 Hz for 2 s: x = 4 mm cos(Ωt) at
    /// 7 Hz, its velocity, and a friction force of 2 N opposing it.
    fn record() -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
        let w = std::f64::consts::TAU * 7.0;
        let t: Vec<f64> = (0..1200).map(|i| i as f64 / 600.0).collect();
        let x = t.iter().map(|t| 0.004 * (w * t).cos()).collect();
        let v: Vec<f64> = t.iter().map(|t| -0.004 * w * (w * t).sin()).collect();
        let f = v.iter().map(|v: &f64| -2.0 * v.signum()).collect();
        (t, x, v, f)
    }

    #[test]
    fn a_record_that_keeps_the_conventions_reads() {
        let (t, x, v, f) = record();
        let path = Path::new("run.csv");
        assert!(check_velocity(path, &t, &x, &v).is_ok());
        assert!(check_friction(path, &t, &x, &f).is_ok());
        // A block at rest, whose velocity and friction force are noise, says
        // nothing either way.
        let still = vec![0.0; t.len()];
        let noise: Vec<f64> = (0..t.len()).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
        assert!(check_friction(path, &t, &still, &noise).is_ok());
        assert!(check_velocity(path, &t, &still, &noise).is_ok());
        // A dead channel beside a moving block is refused, by column.
        let err = check_friction(path, &t, &x, &still).unwrap_err().to_string();
        assert!(err.contains("column `friction_force`") && err.contains("dead channel"), "{err}");
        let err = check_velocity(path, &t, &x, &still).unwrap_err().to_string();
        assert!(err.contains("column `v`") && err.contains("dead channel"), "{err}");
    }

    /// A record that keeps the equation of motion exactly: `x` with a 3rd
    /// and 5th harmonic beside the fundamental (`shaped`; a pure sinusoid
    /// otherwise), 7 Hz on the paper's rig for 4 s at 600 Hz, and the
    /// friction force the equation puts on the block, times `gain`; `x` is
    /// read with a sensor's noise.
    fn balanced_run(shaped: bool, gain: f64) -> (Run, RigInfo) {
        let rig = RigInfo { mass_kg: 1.028, natural_frequency_hz: 10.05, damping_ratio: 0.00225 };
        let (k, c) = (rig.stiffness_n_per_m(), rig.damping_n_s_per_m());
        let w = std::f64::consts::TAU * 7.0;
        let parts: &[(f64, f64, f64)] =
            if shaped { &[(1.0, 4e-3, 0.0), (3.0, 2e-4, 1.0), (5.0, 5e-5, 2.0)] } else { &[(1.0, 4e-3, 0.0)] };
        let t: Vec<f64> = (0..2400).map(|i| i as f64 / 600.0).collect();
        let mut x = Vec::new();
        let mut friction = Vec::new();
        for &t in &t {
            let (mut xi, mut rig_side) = (0.0, 0.0);
            for &(j, a, phase) in parts {
                let (jw, angle) = (j * w, j * w * t + phase);
                xi += a * angle.cos();
                rig_side += a * ((k - rig.mass_kg * jw * jw) * angle.cos() - c * jw * angle.sin());
            }
            // A sensor's noise of about 2 µm.
            let noise = ((x.len() * 7919) % 13) as f64 / 6.0 - 1.0;
            x.push(xi + 2e-6 * noise);
            friction.push(gain * (rig_side - k * 2.5e-3 * (w * t).cos()));
        }
        let run = Run {
            file: "run.csv".into(),
            excitation_frequency_hz: 7.0,
            excitation_amplitude_m: 2.5e-3,
            normal_force_n: 16.0,
            t_s: t,
            x_m: x,
            v_m_per_s: None,
            normal_force: None,
            friction_force: Some(friction),
            time_origin: Default::default(),
        };
        (run, rig)
    }

    #[test]
    fn the_friction_force_is_weighed_against_the_equation_of_motion_at_the_harmonics() {
        let balanced = |shaped, gain| {
            let (run, rig) = balanced_run(shaped, gain);
            check_force_balance(&run, &rig)
        };
        assert!(balanced(true, 1.0).is_ok());
        // Within the factor a sensor's calibration may miss by, it reads.
        assert!(balanced(true, 3.0).is_ok() && balanced(true, 0.3).is_ok());
        for gain in [10.0, 1e-3, -1.0] {
            let err = balanced(true, gain).unwrap_err().to_string();
            assert!(err.contains("column `friction_force`") && err.contains("harmonics 2 to 6"), "{err}");
        }
        let err = balanced(true, 10.0).unwrap_err().to_string();
        assert!(err.contains("it is 10 times"), "{err}");
        // A motion without harmonics says nothing of the force's scale.
        assert!(balanced(false, 10.0).is_ok());
    }

    #[test]
    fn a_reversed_or_rescaled_channel_is_refused_by_column() {
        let (t, x, v, f) = record();
        let path = Path::new("run.csv");
        let negated = |c: &[f64]| c.iter().map(|v| -v).collect::<Vec<f64>>();
        let err = check_velocity(path, &t, &x, &negated(&v)).unwrap_err().to_string();
        assert!(err.contains("run.csv") && err.contains("column `v`") && err.contains("falls where"), "{err}");
        let in_mm: Vec<f64> = v.iter().map(|v| v * 1000.0).collect();
        let err = check_velocity(path, &t, &x, &in_mm).unwrap_err().to_string();
        assert!(err.contains("column `v`") && err.contains("1000 times its size"), "{err}");
        // However small `x` is written, a `v` in m/s is still seen to be
        // out of scale with it (the sums do not underflow).
        for tiny in [1e-100, 1e-200, 1e-300] {
            let x_tiny: Vec<f64> = x.iter().map(|x| x * tiny).collect();
            let err = check_velocity(path, &t, &x_tiny, &v).unwrap_err().to_string();
            assert!(err.contains("column `v`") && err.contains("times its size"), "{tiny}: {err}");
        }
        let err = check_friction(path, &t, &x, &negated(&f)).unwrap_err().to_string();
        assert!(err.contains("column `friction_force`") && err.contains("sign reversed"), "{err}");
        // An offset or a few samples pushed the wrong way by noise are not a
        // reversed sign.
        let offset: Vec<f64> = f.iter().map(|f| f + 1.0).collect();
        assert!(check_friction(path, &t, &x, &offset).is_ok());
    }
}
