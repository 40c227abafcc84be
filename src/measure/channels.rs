//! Conventions of a run's channels that no single value can break, checked
//! over the whole record: `v` is the rate of change of `x` (the same sign,
//! in m/s as `x` is in m), and the friction force is the force on the
//! block, which opposes the block's motion while it slips.
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
    let rate = displacement_rate(t_s, x_m);
    let peak = rate.iter().fold(0.0f64, |m, &(_, r)| m.max(r.abs()));
    let signs: Vec<f64> = rate
        .iter()
        .filter(|&&(_, r)| r.abs() >= 0.5 * peak)
        .filter_map(|&(i, r)| friction_n.get(i).map(|&f| f * r))
        .filter(|p| p.is_finite() && *p != 0.0)
        .collect();
    let along = signs.iter().filter(|&&p| p > 0.0).count();
    if peak > 0.0 && signs.len() >= MIN_SAMPLES && along as f64 >= REVERSED_SHARE * signs.len() as f64 {
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
