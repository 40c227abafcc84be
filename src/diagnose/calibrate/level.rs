//! The friction level and the noise levels where the data have no friction
//! channels: `a` solved so that the simulated mean peaks (or mean phases)
//! match the measured ones, and σ_μ and σ_N scaled so that the simulated
//! spread (peak or phase variance) matches the measured one, on small
//! ensembles of the fitting units.

use crate::diagnose::data::Data;
use crate::diagnose::observable::Observable;
use crate::diagnose::simulate::{PathStats, ensemble_path_stats};
use crate::diagnose::{DiagnoseSettings, mean};
use crate::engine::reduce::{circular_mean_var, wrap_angle};
use crate::engine::{Condition, Engine, Model};
use crate::error::Result;

/// What pins the baseline where the data have no friction channels: the
/// response statistic the friction level is solved on (the mean peak where
/// any fitting unit has one, else the mean phase: phase-only tables) and the
/// spread statistic the noise levels are scaled on (the peak variance, else
/// the phase variance), if the data have one.
#[derive(Clone, Copy, Debug)]
pub(super) struct ResponseTargets {
    pub(super) level: Observable,
    pub(super) spread: Option<Observable>,
}

impl ResponseTargets {
    pub(super) fn of(data: &Data<'_>) -> Option<Self> {
        let has = |o: Observable| {
            data.units.iter().zip(&data.measured).any(|(u, m)| !u.heldout && m.get(&o).is_some_and(|v| v.is_finite()))
        };
        let level = [Observable::PeakMeanM, Observable::PhaseMeanDeg].into_iter().find(|&o| has(o))?;
        let spread = match level {
            Observable::PeakMeanM => Some(Observable::PeakVarM2),
            _ => Some(Observable::PhaseVarDeg2),
        }
        .filter(|&o| has(o));
        Some(Self { level, spread })
    }

    /// The model's level error at one condition: relative for mean peaks,
    /// in radians for mean phases.
    fn level_error(&self, paths: &[PathStats], measured: f64) -> Option<f64> {
        match self.level {
            Observable::PeakMeanM => (measured > 0.0)
                .then(|| mean(&paths.iter().map(|p| p.peak_mean_m).collect::<Vec<_>>()) / measured - 1.0),
            _ => {
                let phases: Vec<f64> = paths.iter().map(|p| p.phase_mean_deg.to_radians()).collect();
                Some(wrap_angle(circular_mean_var(&phases).0 - measured.to_radians()))
            }
        }
    }

    /// The slope a failed search falls back on, per unit of `a`: more
    /// friction lowers the mean peaks (below the no-stop threshold, where
    /// the data's loads lie) and delays the response.
    fn fallback_slope(&self) -> f64 {
        if self.level == Observable::PeakMeanM { -1.0 } else { 1.0 }
    }
}

/// The fitting units as simulated conditions, the measured values of one
/// observable there (NaN where absent) and the record length in periods:
/// what the baseline's level and noise are solved against without
/// friction channels.
struct FittingTargets {
    conditions: Vec<Condition>,
    measured: Vec<f64>,
    cycles: u32,
}

impl FittingTargets {
    fn of(model: &Model, data: &Data<'_>, observable: Observable) -> FittingTargets {
        let fit: Vec<usize> = (0..data.units.len()).filter(|&i| !data.units[i].heldout).collect();
        let conditions = fit.iter().map(|&i| data.simulated_condition(&data.units[i], model)).collect();
        let measured = fit.iter().map(|&i| data.measured[i].get(&observable).copied().unwrap_or(f64::NAN)).collect();
        // The same window as the data: the records' (or summaries') length.
        let cycles = fit
            .iter()
            .map(|&i| (data.record_s[i] * data.units[i].condition.excitation_frequency_hz).round() as u32)
            .max()
            .unwrap_or(100);
        FittingTargets { conditions, measured, cycles }
    }

    /// Small ensembles (at most 24 realisations) of `model` at every
    /// condition, on the noise paths of the diagnosis's seed with `salt`
    /// (one salt per search, so its trials share their paths).
    fn simulate(
        &self,
        engine: &Engine,
        model: &Model,
        settings: &DiagnoseSettings,
        salt: u64,
    ) -> Result<Vec<Vec<PathStats>>> {
        ensemble_path_stats(
            engine,
            model,
            &self.conditions,
            self.cycles,
            settings.ensemble_realisations.min(24),
            settings.seed ^ salt,
            settings.warmup_cycles,
        )
    }
}

/// Solves for the friction level `a` (with everything else fixed) so the
/// simulated mean peaks (or, in phase-only data, mean phases) match the
/// measured ones on the fitting units, with small ensembles. The loss that
/// decides is the mean square of the units' level errors. Mean peaks are
/// continuous in `a`, so it is minimised by Gauss-Newton steps whose units'
/// slopes (d error / d a) are read from the last two levels tried: an
/// effect that moves the loads apart (a load dependence) has its least
/// loss away from where the mean error is zero, and these steps go
/// straight there. Phases wrap where a load's passes a branch, so their
/// loss jumps and no straight line tells where its least lies: the mean
/// error is zeroed by a secant instead, and a trial then scans the window
/// about the best level. Either's first step is a Newton step on `slope`
/// (the mean error's, from the baseline's solve) where given (an effect's
/// trial moves the level a long way where the response is steep in it, as
/// phases are near the no-stop threshold); for Gauss-Newton it is at least
/// a scan step long, so each unit's slope is read over a span its noise
/// does not swamp. Returns the mean error's slope found.
pub(super) fn solve_friction_level(
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
    targets: ResponseTargets,
    slope: Option<f64>,
) -> Result<(Model, f64)> {
    let slope_given = slope.is_some();
    let fitting = FittingTargets::of(model, data, targets.level);
    let level_at = |a: f64| -> Result<Level> {
        let mut m = model.clone();
        m.friction.a = a;
        m.validate()?;
        let stats = fitting.simulate(engine, &m, settings, 0xA5A5)?;
        let errors: Vec<f64> = stats
            .iter()
            .zip(&fitting.measured)
            .filter(|(_, t)| t.is_finite())
            .filter_map(|(s, &t)| targets.level_error(s, t))
            .collect();
        Ok(Level::new(a, errors))
    };
    // The mean error and the loss at level `a`, for the scans.
    let residual = |a: f64| level_at(a).map(|l| (l.mean, l.loss));
    let lowest = (-model.friction.b).max(0.0);
    let with_a = |a: f64| {
        let mut out = model.clone();
        out.friction.a = a.clamp(lowest, 5.0);
        out
    };
    let mut tried: Vec<(f64, f64)> = Vec::new();
    let mut a0 = model.friction.a.max(lowest);
    if slope.is_none() {
        // The baseline starts from the best of a scan of levels, so that a
        // prior far from the data (its loads past the no-stop threshold,
        // where the block sticks, phases mean nothing and the residual is
        // flat) does not hold the search.
        for i in 0..LEVEL_SCAN {
            let a = lowest + 0.02 + 0.05 * f64::from(i);
            tried.push((a, residual(a)?.1));
        }
        a0 = scan_best(&mut tried, &residual)?;
    }
    // Where the loss can jump (a level read from phases, whose errors wrap
    // where a load's phase passes a branch), no straight line through two
    // levels' errors tells where its least lies: there the mean error is
    // zeroed by a secant and the window about the best level scanned.
    let jumps = targets.level != Observable::PeakMeanM;
    let mut previous = level_at(a0)?;
    tried.push((previous.a, previous.loss));
    // The second level: a Newton step on the known slope (for Gauss-Newton
    // at least a scan step long), or a scan step up.
    let step = match slope {
        Some(s) if jumps && previous.mean.abs() < MEAN_TOLERANCE => {
            return Ok((with_a(a0), s));
        }
        Some(s) if jumps => -previous.mean / s,
        Some(s) if s != 0.0 && previous.mean != 0.0 => {
            let newton = -previous.mean / s;
            newton.signum() * newton.abs().max(TRIAL_SCAN_STEP)
        }
        _ => TRIAL_SCAN_STEP,
    };
    let mut a1 = (a0 + step).clamp(lowest, a0 + 0.5).min(5.0);
    if a1 == a0 && !jumps {
        a1 = (a0 + TRIAL_SCAN_STEP).min(5.0);
    }
    let mut current = level_at(a1)?;
    tried.push((current.a, current.loss));
    let mut slope = previous.mean_slope(&current);
    for _ in 0..5 {
        let next = if jumps {
            if current.mean.abs() < MEAN_TOLERANCE || (current.mean - previous.mean).abs() < 1e-12 {
                break;
            }
            current.a - current.mean * (current.a - previous.a) / (current.mean - previous.mean)
        } else {
            match previous.gauss_newton(&current) {
                Some(next) => next,
                None => break,
            }
        };
        let next = next.clamp(lowest, current.a + 0.5).min(5.0);
        if !jumps && ((next - current.a).abs() < LEVEL_TOLERANCE || tried.iter().any(|t| t.0 == next)) {
            break;
        }
        previous = std::mem::replace(&mut current, level_at(next)?);
        tried.push((current.a, current.loss));
        slope = previous.mean_slope(&current).or(slope);
    }
    let mut best = tried.iter().min_by(|x, y| x.1.total_cmp(&y.1)).map_or(current.a, |t| t.0);
    if slope_given && jumps {
        // A trial's loss is also scanned about the best point (the
        // baseline's whole scan, narrower): without it, trials that differ
        // in their last bits can end on different branches of the loss.
        let centre = tried.iter().copied().find(|t| t.0 == best).unwrap_or((best, f64::INFINITY));
        let mut around = scan_about(centre, lowest, &residual)?;
        // The parabola's vertex is tried and kept in `around`; the best
        // of everything tried is taken below.
        scan_best(&mut around, &residual)?;
        tried.extend(around);
        best = tried.iter().min_by(|x, y| x.1.total_cmp(&y.1)).map_or(best, |t| t.0);
    }
    let fallback = targets.fallback_slope();
    let slope = slope.filter(|s| s.is_finite() && s * fallback > 0.0).unwrap_or(fallback);
    Ok((with_a(best), slope))
}

/// A friction level tried and the fitting units' level errors there.
struct Level {
    /// The level, –.
    a: f64,
    /// Each unit's level error (relative for mean peaks, rad for phases).
    errors: Vec<f64>,
    /// Their mean.
    mean: f64,
    /// Their mean square: the loss that decides between levels.
    loss: f64,
}

impl Level {
    fn new(a: f64, errors: Vec<f64>) -> Level {
        let (m, loss) = (mean(&errors), mean(&errors.iter().map(|e| e * e).collect::<Vec<_>>()));
        Level { a, errors, mean: m, loss }
    }

    /// The mean error's slope from this level to `other`, per unit of `a`.
    fn mean_slope(&self, other: &Level) -> Option<f64> {
        let da = other.a - self.a;
        (da.abs() > 1e-9).then(|| (other.mean - self.mean) / da)
    }

    /// The level of least loss where each unit's error is the straight
    /// line through its errors at this level and at `other`: a Gauss-Newton
    /// step from `other`. `None` where the two levels cannot tell the
    /// slopes.
    fn gauss_newton(&self, other: &Level) -> Option<f64> {
        let da = other.a - self.a;
        if da.abs() <= 1e-9 || self.errors.len() != other.errors.len() {
            return None;
        }
        let slopes: Vec<f64> = self.errors.iter().zip(&other.errors).map(|(e0, e1)| (e1 - e0) / da).collect();
        let curvature: f64 = slopes.iter().map(|s| s * s).sum();
        let gradient: f64 = slopes.iter().zip(&other.errors).map(|(s, e)| s * e).sum();
        (curvature > 1e-18).then(|| other.a - gradient / curvature)
    }
}

/// A Gauss-Newton step shorter than this (of `a`) ends the solve: a scan
/// step's fortieth, below what the small ensembles' noise tells apart.
const LEVEL_TOLERANCE: f64 = 5e-4;

/// A mean level error smaller than this ends the secant (relative, or rad).
const MEAN_TOLERANCE: f64 = 5e-4;

/// Levels the baseline's level search scans first: `a` from 0.02 above
/// its lowest in steps of 0.05 (to about 1).
const LEVEL_SCAN: u32 = 20;

/// A trial's level search also scans this many steps of
/// [`TRIAL_SCAN_STEP`] on each side of its best point.
const TRIAL_SCAN: i32 = 3;

/// The step of a trial's scan about its best level (of `a`).
const TRIAL_SCAN_STEP: f64 = 0.02;

/// The loss at the levels `TRIAL_SCAN_STEP` apart about `centre` (a level
/// and its loss), [`TRIAL_SCAN`] steps either way and none below `lowest`
/// or above 5, in increasing order, `centre` among them: every level of the
/// window, since a lower well can lie behind a jump of the loss.
fn scan_about(
    centre: (f64, f64),
    lowest: f64,
    loss_at: &impl Fn(f64) -> Result<(f64, f64)>,
) -> Result<Vec<(f64, f64)>> {
    let mut around = vec![centre];
    for side in [-1.0, 1.0] {
        for k in 1..=TRIAL_SCAN {
            let a = centre.0 + side * TRIAL_SCAN_STEP * f64::from(k);
            if a < lowest || a > 5.0 {
                break;
            }
            around.push((a, loss_at(a)?.1));
        }
    }
    around.sort_by(|x, y| x.0.total_cmp(&y.0));
    Ok(around)
}

/// The best of `scan` (levels `a` in increasing order, equally spaced, each
/// with its loss), refined to the vertex of the parabola through it and its
/// neighbours where that lies between them and is lower (the vertex is
/// appended to `scan`).
fn scan_best(scan: &mut Vec<(f64, f64)>, loss_at: &impl Fn(f64) -> Result<(f64, f64)>) -> Result<f64> {
    let i = (0..scan.len()).min_by(|&x, &y| scan[x].1.total_cmp(&scan[y].1)).unwrap_or(0);
    let mut best = scan[i].0;
    if i > 0 && i + 1 < scan.len() {
        let ((xa, ya), (xb, yb), (xc, yc)) = (scan[i - 1], scan[i], scan[i + 1]);
        // Equally spaced: the vertex is xb + h (ya − yc) / (2 (ya − 2 yb + yc)).
        let curvature = ya - 2.0 * yb + yc;
        if curvature > 0.0 && (xc - xb - (xb - xa)).abs() <= 1e-9 {
            let vertex = xb + 0.5 * (xc - xb) * (ya - yc) / curvature;
            if vertex > xa && vertex < xc {
                let l = loss_at(vertex)?.1;
                scan.push((vertex, l));
                if l < yb {
                    best = vertex;
                }
            }
        }
    }
    Ok(best)
}

/// One step that scales the noise levels so that the simulated spread
/// statistic (peak or phase variance) matches the measured one on the
/// fitting units. The spread is split by simulation into the part the
/// friction noise makes and the part the normal-force noise makes (the
/// model with σ_μ = 0 on the same noise paths), and the two parts' scale
/// factors (σ_μ² and σ_N² multipliers) are fitted to the measured spreads
/// in log terms with a robust loss ([`noise_scales`]). σ_N stays where the
/// data's normal-force channel (or stated variance) put it.
pub(super) fn scale_noise(
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
    spread: Observable,
) -> Result<Model> {
    let fitting = FittingTargets::of(model, data, spread);
    let simulate = |m: &Model| -> Result<Vec<f64>> {
        let stats = fitting.simulate(engine, m, settings, 0x5CA1)?;
        Ok(stats.iter().map(|s| mean(&s.iter().filter_map(|p| p.get(spread)).collect::<Vec<_>>())).collect())
    };
    let whole = simulate(model)?;
    let mut quiet = model.clone();
    quiet.friction.sigma = 0.0;
    let from_normal = simulate(&quiet)?;
    let parts: Vec<(f64, f64, f64)> = whole
        .iter()
        .zip(&from_normal)
        .zip(&fitting.measured)
        .filter(|(_, t)| t.is_finite() && **t > 0.0)
        .map(|((&w, &n), &t)| (t, (w - n).max(0.0), n.max(0.0)))
        .collect();
    let Some((k_mu, k_n)) = noise_scales(&parts, !data.states_normal_force_noise()) else { return Ok(model.clone()) };
    let mut out = model.clone();
    out.friction.sigma = (out.friction.sigma * k_mu.sqrt()).min(1.0);
    out.normal_force.sigma *= k_n.sqrt();
    Ok(out)
}

/// The factors `(k_μ, k_N)`, each in [0.01, 100], by which the friction
/// noise's and the normal-force noise's parts of the spread (`(measured,
/// friction part, normal-force part)` per unit) are best scaled so that
/// their sum matches the measured spread: the least Cauchy loss ln(1 + e²)
/// of the log ratios e (quadratic near a fit, growing only as the log of
/// the misfit beyond a factor e, so a unit near the no-stop threshold whose
/// model spreads a hundred times more than the data while its level is
/// still off does not steer the rest), plus a
/// small pull of each log factor towards 0 (no change), which decides a
/// factor the spreads cannot tell (on the benchmark's phase tables σ_N's
/// part is below 1% at heavy loads). `k_N` stays 1 unless `free_normal`.
/// `None` without a unit whose model spreads at all.
fn noise_scales(parts: &[(f64, f64, f64)], free_normal: bool) -> Option<(f64, f64)> {
    if !parts.iter().any(|&(_, p, q)| p + q > 0.0) {
        return None;
    }
    let loss = |k_mu: f64, k_n: f64| -> f64 {
        let fit: f64 = parts
            .iter()
            .filter(|&&(_, p, q)| p + q > 0.0)
            .map(|&(t, p, q)| {
                let e = (t / (k_mu * p + k_n * q)).ln();
                e.mul_add(e, 1.0).ln()
            })
            .sum();
        fit + 0.01 * (k_mu.ln().powi(2) + k_n.ln().powi(2))
    };
    // Log grid, 0.05 apart over a factor 100 each way.
    let grid = || (-92..=92).map(|i| (f64::from(i) * 0.05).exp());
    let normal_factors: Vec<f64> = if free_normal { grid().collect() } else { vec![1.0] };
    let mut best = (f64::INFINITY, 1.0, 1.0);
    for k_mu in grid() {
        for &k_n in &normal_factors {
            let l = loss(k_mu, k_n);
            if l < best.0 {
                best = (l, k_mu, k_n);
            }
        }
    }
    Some((best.1, best.2))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_level_scan_takes_its_lowest_point_and_the_parabola_through_it() {
        // A loss with a jump (a load's phase past a branch) beside a smooth
        // well whose bottom lies between the scan's points: the scan finds
        // the well, not the point the search started from, and the vertex
        // of the parabola through the well's three points is its bottom.
        let loss = |a: f64| -> Result<(f64, f64)> {
            Ok((0.0, if a > 0.35 { 2.0 } else { 0.03 + 4.0 * (a - 0.3127) * (a - 0.3127) }))
        };
        let mut scan: Vec<(f64, f64)> =
            (-3..=3).map(|k| 0.3353 + 0.02 * f64::from(k)).map(|a| (a, loss(a).unwrap().1)).collect();
        let best = scan_best(&mut scan, &loss).unwrap();
        assert!((best - 0.3127).abs() < 1e-9, "the well's bottom, not {best}");
        assert_eq!(scan.len(), 8, "the vertex is tried and kept");
        // A lowest point at the scan's end has no parabola: it is taken as is.
        let mut edge: Vec<(f64, f64)> = [0.30, 0.32, 0.34].iter().map(|&a| (a, 1.0 - a)).collect();
        assert_eq!(scan_best(&mut edge, &loss).unwrap(), 0.34);
        assert_eq!(edge.len(), 3);
    }

    /// A phase level's scan tries the whole window about its centre, and so
    /// finds the lower well behind a jump of the loss beside the centre;
    /// the window's lower edge is `lowest`.
    #[test]
    fn a_trial_scan_spans_a_jumping_loss() {
        let calls = std::cell::Cell::new(0);
        let jumping = |a: f64| -> Result<(f64, f64)> {
            calls.set(calls.get() + 1);
            Ok((0.0, if (0.41..0.43).contains(&a) { 2.0 } else { (a - 0.44).abs() }))
        };
        let spanned = scan_about((0.40, 0.04), 0.0, &jumping).unwrap();
        assert_eq!(calls.get(), 6);
        assert!(spanned.windows(2).all(|w| w[0].0 < w[1].0), "in increasing order");
        let lowest = spanned.iter().copied().min_by(|x, y| x.1.total_cmp(&y.1)).unwrap().0;
        assert!((lowest - 0.44).abs() < 1e-12, "{spanned:?}");
        let edge = scan_about((0.03, 0.0), 0.005, &|a: f64| Ok((0.0, a))).unwrap();
        assert!(edge.iter().all(|p| p.0 >= 0.005) && edge.len() == 5, "{edge:?}");
    }

    /// Where the units' level errors are straight lines in `a` of different
    /// slopes (an effect that moves the loads apart), one Gauss-Newton step
    /// from any two levels lands on the least mean square, which is not
    /// where the mean error is zero (where a secant on the mean stopped),
    /// and has the lower loss; two levels at one `a` tell no slopes.
    #[test]
    fn a_gauss_newton_step_lands_on_the_least_square_not_the_zero_mean() {
        let errors = |a: f64| vec![0.5 * (a - 0.40) - 0.01, 2.0 * (a - 0.40) + 0.01, a - 0.40];
        let least = 0.40 - (0.5 * -0.01 + 2.0 * 0.01) / (0.25 + 4.0 + 1.0);
        for (a0, a1) in [(0.30, 0.45), (0.50, 0.41), (0.395, 0.40)] {
            let next = Level::new(a0, errors(a0)).gauss_newton(&Level::new(a1, errors(a1))).unwrap();
            assert!((next - least).abs() < 1e-12, "from {a0}, {a1}: {next} against {least}");
        }
        let zero_mean = Level::new(0.40, errors(0.40));
        assert!(zero_mean.mean.abs() < 1e-15 && (least - 0.40).abs() > 2e-3);
        assert!(Level::new(least, errors(least)).loss < zero_mean.loss);
        assert_eq!(zero_mean.gauss_newton(&Level::new(0.40, errors(0.40))), None);
    }

    #[test]
    fn noise_scales_recover_both_sources_and_shrug_off_one_unit_off_its_branch() {
        // Friction noise's part grows with the load, the normal force's
        // stays: four units whose measured spread is 2.0 × the one and
        // 0.5 × the other, and a fifth where the model spreads 100 times
        // more than the data (a load near the no-stop threshold).
        let (k_mu, k_n) = (2.0, 0.5);
        let mut parts: Vec<(f64, f64, f64)> = [1.0, 2.0, 4.0, 8.0]
            .iter()
            .map(|&load: &f64| {
                let (p, q) = (0.1 * load * load, 0.4);
                (k_mu * p + k_n * q, p, q)
            })
            .collect();
        // Alone, the four are fitted to the grid's resolution (a factor
        // e^0.05 on the variance), less the small pull towards no change.
        let (a, b) = noise_scales(&parts, true).expect("the model spreads");
        assert!((a / k_mu).ln().abs() < 0.06 && (b / k_n).ln().abs() < 0.06, "k {a} {b}");
        // With the fifth, the standard deviations are still within 10%.
        parts.push((0.01, 1.0, 0.0));
        let (a, b) = noise_scales(&parts, true).expect("the model spreads");
        assert!(((a / k_mu).sqrt() - 1.0).abs() < 0.1, "k_mu {a}");
        assert!(((b / k_n).sqrt() - 1.0).abs() < 0.1, "k_N {b}");
        // With σ_N given by the data, its factor stays 1.
        let (_, b) = noise_scales(&parts, false).expect("the model spreads");
        assert_eq!(b, 1.0);
        // A model that does not spread at all cannot be scaled.
        assert!(noise_scales(&[(1.0, 0.0, 0.0)], true).is_none());
    }
}
