//! Conventions of a run's channels that no single value can break, checked
//! over the whole record: `v` is the rate of change of `x` (the same sign,
//! in m/s as `x` is in m), and the friction force is the force on the
//! block, which opposes the block's motion while it slips and is, in
//! newtons, what the equation of motion says it is.
//!
//! A record that breaks one of them (a velocity in mm/s, a channel wired
//! the other way round, the force on the friction element instead of the
//! one on the block) reads without a single bad value. Read as it is, none
//! of its samples counts as slipping, every friction feature vanishes
//! without a word, and a diagnosis is sure of `none` on data it never
//! looked at. So such a record is refused, by file and column, with what
//! the check saw.

use std::path::Path;

use super::json::bad;
use super::{RigInfo, Run};
use crate::diagnose::features::least_squares;
use crate::engine::model::fmt_value;
use crate::error::Result;

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
    let (vv, rr, vr) = pairs.iter().fold((0.0, 0.0, 0.0), |(vv, rr, vr), &(v, r)| (vv + v * v, rr + r * r, vr + v * r));
    if pairs.len() < MIN_SAMPLES || !(vv > 0.0 && rr > 0.0) {
        return Ok(());
    }
    let correlation = vr / (vv * rr).sqrt();
    let scale = (vv / rr).sqrt();
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

/// Refuses a friction-force column (N) that pushes the block along its
/// motion, the motion read from `x_m` (m) at times `t_s` (s): at
/// [`REVERSED_SHARE`] or more of the samples where the block moves at more
/// than half its peak speed, where it slips.
pub(super) fn check_friction(path: &Path, t_s: &[f64], x_m: &[f64], friction_n: &[f64]) -> Result<()> {
    let signs: Vec<f64> = fast_motion(t_s, x_m)
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
/// equation of motion puts on the block before its unit is called wrong:
/// on the 250 benchmark records (seeds 7 and 36, sensor noise included)
/// where the two are the same signal ([`BALANCE_CORRELATION`]) they agree
/// within 3–48%; a friction force in kN is a thousand times too small.
const BALANCE_FACTOR: f64 = 5.0;

/// The correlation of the two sides of the equation of motion (each less
/// its part at the excitation frequency) below which their ratio is not
/// judged: a block stuck throughout leaves the friction force's residual
/// below the noise that differencing puts into x'' (correlations of 0.02–0.1
/// on such records), and noise in the friction force alone inflates the
/// ratio by about the inverse square of the correlation (at most 2 here).
const BALANCE_CORRELATION: f64 = 0.7;

/// Refuses a run whose friction force is not, within [`BALANCE_FACTOR`],
/// the force the rest of the equation of motion puts on the block:
/// `m x'' + c x' + k x = k u(t) + F` with the rig's m, c and k and `x''`,
/// `x'` by central differences, both sides stripped of their parts at the
/// excitation frequency and a constant (the base's k u(t), whose phase a
/// record with a free time origin does not fix, and any offset). The
/// factor is the regression of the rig's side on the friction force
/// (noise in `x''`, amplified by the differencing, does not bias it that
/// way round), inverted, judged where the two are the same signal.
pub(super) fn check_force_balance(run: &Run, rig: &RigInfo) -> Result<()> {
    let Some(friction_n) = &run.friction_force else { return Ok(()) };
    let (t, x) = (&run.t_s, &run.x_m);
    let n = t.len().min(x.len()).min(friction_n.len());
    let k = rig.mass_kg * (std::f64::consts::TAU * rig.natural_frequency_hz).powi(2);
    let c = 2.0 * rig.damping_ratio * (k * rig.mass_kg).sqrt();
    let w = std::f64::consts::TAU * run.excitation_frequency_hz;
    // Rows (rig's force, friction force, cos Ωt, sin Ωt, 1).
    let rows: Vec<[f64; 5]> = (1..n.saturating_sub(1))
        .filter_map(|i| {
            let (h0, h1) = (t[i] - t[i - 1], t[i + 1] - t[i]);
            let rate = (x[i + 1] - x[i - 1]) / (h0 + h1);
            let accel = 2.0 * ((x[i + 1] - x[i]) / h1 - (x[i] - x[i - 1]) / h0) / (h0 + h1);
            let rig_n = rig.mass_kg * accel + c * rate + k * x[i];
            let row = [rig_n, friction_n[i], (w * t[i]).cos(), (w * t[i]).sin(), 1.0];
            row.iter().all(|v| v.is_finite()).then_some(row)
        })
        .collect();
    if rows.len() < MIN_SAMPLES {
        return Ok(());
    }
    let (rig_side, friction) = (residual(&rows, 0), residual(&rows, 1));
    let ff: f64 = friction.iter().map(|f| f * f).sum();
    let rr: f64 = rig_side.iter().map(|r| r * r).sum();
    let rf: f64 = rig_side.iter().zip(&friction).map(|(r, f)| r * f).sum();
    if !(ff > 0.0 && rr > 0.0 && rf / (rr * ff).sqrt() >= BALANCE_CORRELATION) {
        return Ok(());
    }
    let factor = ff / rf;
    if !(1.0 / BALANCE_FACTOR..=BALANCE_FACTOR).contains(&factor) {
        return Err(bad(
            &run.file,
            None,
            format!(
                "column `friction_force`: it is {} times the force the rest of the equation of motion puts on the \
                 block (m x'' + c x' + k x from `x` and the rig, less its part at the excitation frequency): the \
                 friction force must be in newtons, and the rig's mass and natural frequency those of this block",
                fmt_value(float_3(factor))
            ),
        ));
    }
    Ok(())
}

/// Column `j` of `rows` less its least-squares fit on the last three
/// columns (cos Ωt, sin Ωt, 1); all zeros where that fit is singular.
fn residual(rows: &[[f64; 5]], j: usize) -> Vec<f64> {
    let fill = |i: usize, basis: &mut [f64]| basis.copy_from_slice(&rows[i][2..]);
    match least_squares(rows.len(), 3, fill, |i| rows[i][j]) {
        Some((coef, _)) => {
            rows.iter().map(|row| row[j] - coef[0] * row[2] - coef[1] * row[3] - coef[2] * row[4]).collect()
        }
        None => vec![0.0; rows.len()],
    }
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
        // A block at rest, whose velocity and friction force are noise, and
        // a zero friction column say nothing either way.
        let still = vec![0.0; t.len()];
        let noise: Vec<f64> = (0..t.len()).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
        assert!(check_friction(path, &t, &still, &noise).is_ok());
        assert!(check_velocity(path, &t, &still, &noise).is_ok());
        assert!(check_friction(path, &t, &x, &still).is_ok());
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
        let err = check_friction(path, &t, &x, &negated(&f)).unwrap_err().to_string();
        assert!(err.contains("column `friction_force`") && err.contains("sign reversed"), "{err}");
        // An offset or a few samples pushed the wrong way by noise are not a
        // reversed sign.
        let offset: Vec<f64> = f.iter().map(|f| f + 1.0).collect();
        assert!(check_friction(path, &t, &x, &offset).is_ok());
    }
}
