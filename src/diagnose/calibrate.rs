//! Calibrating the baseline to the data.
//!
//! With force channels, the friction law `μ(v) = a + b/(1 + c|v|) + d v²`
//! and its noise σ_μ come from a least-squares fit of μ = |F|/N against
//! speed while slipping, within records (a level per record, so friction
//! that differs between loads is left to the effect that makes it instead
//! of bending the curve), matched between measured and simulated records by
//! indirect inference; σ_N and each condition's N0 come from the measured
//! normal force. Without force channels, the friction level `a` is solved so
//! that the simulated mean peaks match the measured ones.

use crate::diagnose::data::Data;
use crate::diagnose::features::run_features;
use crate::diagnose::law::{self, FrictionLaw, Spread, variance_gap};
use crate::diagnose::observable::Observable;
use crate::diagnose::score::{Scope, Score, add_heldout, gap_of, score};
use crate::diagnose::simulate::{PathStats, ensemble_path_stats, fits_per_task, fitting_records};
use crate::diagnose::{DiagnoseSettings, mean};
use crate::engine::effects::{ColourForm, ColouredFrictionNoise};
use crate::engine::oscillator::Oscillator;
use crate::engine::reduce::{circular_mean_var, wrap_angle};
use crate::engine::{Condition, Engine, Model};
use crate::error::{Error, Result};
use crate::measure::Run;
use rayon::prelude::*;

/// What pins the baseline where the data have no friction channels: the
/// response statistic the friction level is solved on (the mean peak where
/// any fitting unit has one, else the mean phase: phase-only tables) and the
/// spread statistic the noise levels are scaled on (the peak variance, else
/// the phase variance), if the data have one.
#[derive(Clone, Copy, Debug)]
struct ResponseTargets {
    level: Observable,
    spread: Option<Observable>,
}

impl ResponseTargets {
    fn of(data: &Data<'_>) -> Option<Self> {
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
    fn of(model: &Model, data: &Data<'_>, settings: &DiagnoseSettings, observable: Observable) -> FittingTargets {
        let fit: Vec<usize> = (0..data.units.len()).filter(|&i| !data.units[i].heldout).collect();
        let conditions =
            fit.iter().map(|&i| data.simulated_condition(&data.units[i], model, settings.warmup_cycles)).collect();
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
fn solve_friction_level(
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
    targets: ResponseTargets,
    slope: Option<f64>,
) -> Result<(Model, f64)> {
    let slope_given = slope.is_some();
    let fitting = FittingTargets::of(model, data, settings, targets.level);
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
fn scale_noise(
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
    spread: Observable,
) -> Result<Model> {
    let fitting = FittingTargets::of(model, data, settings, spread);
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

/// Calibrates the friction law of `model` to the data and scores it.
///
/// With friction channels this is indirect inference over the whole of
/// eq. 7: the same least-squares fit of `a + b/(1 + c|v|) + d v²`
/// ([`crate::diagnose::law::fit_friction_law`]) is run on the measured records and on the model's
/// simulated replicate records (which carry the data's measurement noise),
/// and `a`, `b`, `d` are moved by the difference (`c` stays the measured
/// law's) and σ_μ² by the difference of the residual variances within
/// records (each record's mean residual removed, so a friction level that changes with
/// the load or over time is left to the effect that makes it), condition by
/// condition ([`crate::diagnose::law::variance_gap`]). The fit's numbers are then
/// those of the data whatever else the model carries (`law_steps` steps, 0
/// for the baseline's [`LAW_STEPS`], each from the fitting units'
/// replicates alone), so an effect that
/// changes friction (hysteresis lowering it early in a slip, stiction raising
/// it, a noise that is coloured or skewed) is judged with the law and noise
/// level that the data imply *given that effect*, not the ones it distorted.
/// Without friction channels `a` is solved from the response (mean peaks,
/// GPU ensembles). The scores cover the units in `scope`.
pub(crate) fn calibrate_and_score(
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
    slope: Option<f64>,
    law_steps: usize,
    scope: Scope,
) -> Result<(Model, Vec<Score>, f64)> {
    if let Some(measured) = data.measured_law {
        let mut m = model.clone();
        let response = sigma_response(engine, &m, data, settings)?;
        for _ in 0..if law_steps == 0 { LAW_STEPS } else { law_steps } {
            let Some((simulated, gap)) = simulated_law(engine, &m, data, settings)? else { break };
            if crate::diagnose::tracing() {
                let law = |l: &FrictionLaw| format!("a {:.4} b {:.4} d {:.4} sigma {:.4}", l.a, l.b, l.d, l.sigma);
                eprintln!(
                    "law step: model sigma {:.4}; measured {}; simulated {}; variance gap {gap:.3e}; response {response:.3}",
                    m.friction.sigma,
                    law(&measured),
                    law(&simulated)
                );
            }
            step_law(&mut m, &measured, &simulated, gap, response);
        }
        let scores = score(engine, &m, data, settings, scope)?;
        return Ok((m, scores, slope.unwrap_or(-1.0)));
    }
    let Some(targets) = ResponseTargets::of(data) else {
        let scores = score(engine, model, data, settings, scope)?;
        return Ok((model.clone(), scores, slope.unwrap_or(-1.0)));
    };
    let baseline = slope.is_none();
    let (mut m, slope) = solve_friction_level(model, data, settings, engine, targets, slope)?;
    if let Some(spread) = targets.spread {
        // The baseline settles level and noise together; a trial takes one
        // step of each from where its model stands.
        for _ in 0..if baseline { NOISE_ROUNDS } else { 1 } {
            m = scale_noise(&m, data, settings, engine, spread)?;
            if baseline {
                m = solve_friction_level(&m, data, settings, engine, targets, Some(slope))?.0;
            }
        }
    }
    let scores = score(engine, &m, data, settings, scope)?;
    Ok((m, scores, slope))
}

/// Rounds of noise scaling and level solving that calibrate a baseline
/// without friction channels.
const NOISE_ROUNDS: usize = 3;

/// Steps of the friction law's indirect inference for the baseline (each
/// simulates the fitting units' replicates once); a candidate's trial takes
/// one, from the calibrated baseline's law.
const LAW_STEPS: usize = 3;

/// Law-only recalibration steps after a model was calibrated, at most
/// this many: each moves the friction law one more step of the indirect
/// inference with nothing else changed.
pub(crate) const POLISH_STEPS: usize = 3;

/// Further law-only steps from a calibrated model and its scores, kept while
/// they lower the fitting gap, at most [`POLISH_STEPS`]. A search carries the
/// law one step per trial, so when an effect's strength moved a lot the law
/// is still on its way to the one the data imply with that effect; scoring
/// the next round against it would credit any further effect with the
/// remaining steps of the law (a second effect "explaining" what one more
/// law step explains). A no-op without friction channels (no law to step).
/// `scores` may cover the fitting units only ([`Scope::Fitting`]): the steps
/// are judged by the fitting gap, and the held-out units are scored once,
/// for the model kept; the result covers every unit.
pub(crate) fn converge_law(
    model: Model,
    scores: Vec<Score>,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
) -> Result<(Model, Vec<Score>)> {
    let (mut model, mut scores) = (model, scores);
    let mut complete = scores.iter().any(|s| s.heldout) || !data.has_heldout();
    if data.measured_law.is_some() {
        for _ in 0..POLISH_STEPS {
            let (m, s, _) = calibrate_and_score(&model, data, settings, engine, None, 1, Scope::Fitting)?;
            if gap_of(&s, false) >= gap_of(&scores, false) {
                break;
            }
            (model, scores, complete) = (m, s, false);
        }
    }
    if !complete {
        scores = add_heldout(engine, &model, data, settings, scores)?;
    }
    Ok((model, scores))
}

/// The friction law fitted to the model's simulated replicates of the
/// fitting units, pooled like the measured fitting runs are, at the
/// measured law's Stribeck rate `c` (s/m). The measured law is the fit at
/// that `c` too (it is where its residual is smallest), so both sides of
/// the indirect inference are the same statistic, the linear fit at a
/// fixed `c`, one fit instead of the ~27 of a search over `c`. Its cost:
/// where the model misfits the data's speed distribution (a drift of the
/// normal force it lacks, in the benchmark), the simulated residual at that
/// `c` stays above the measured one whatever σ_μ is, and the step drives
/// σ_μ to its floor; searching `c` on both sides avoided that and did no
/// better over the benchmark (`benches/RESULTS.md`). The records are the
/// ones the model's score on the fitting units reads ([`fitting_records`]):
/// simulated once for both.
///
/// With it, how much more the friction's residual variance is in the data
/// than in the replicates, –²: condition by condition where any condition
/// has slipping samples on both sides ([`crate::diagnose::law::variance_gap`]),
/// else the pooled laws' σ² apart.
fn simulated_law(
    engine: &Engine,
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
) -> Result<Option<(FrictionLaw, f64)>> {
    let records = fitting_records(engine, model, data, settings)?;
    let (Some(simulated), Some(measured)) = (records.law, data.measured_law) else { return Ok(None) };
    let gap = variance_gap(&data.measured_spreads(&records.units), &records.spreads)
        .unwrap_or(measured.sigma.powi(2) - simulated.sigma.powi(2));
    Ok(Some((simulated, gap)))
}

/// How far the replicates' friction residual variance moves per unit of
/// σ_μ² (–), which a σ step divides the variance gap by: one for one with
/// a recorded friction force; through a derived one's filter
/// ([`crate::diagnose::derived`]) a fraction, which depends on the noise's
/// spectrum: a white noise held for one interval is mostly smoothed away,
/// a noise correlated over many intervals mostly passes. The noise is a
/// sum of independent parts ([`noise_parts`]), whose variances add through
/// the filter, so the response is their responses weighted by their shares
/// of σ_μ². Each part's is measured once ([`part_response`]). One white
/// response for every model stepped a half-coloured noise's σ_μ about
/// twice too far, and its law steps swung about the σ_μ the data imply
/// instead of reaching it.
fn sigma_response(engine: &Engine, model: &Model, data: &Data<'_>, settings: &DiagnoseSettings) -> Result<f64> {
    if !data.derived.friction {
        return Ok(1.0);
    }
    let mut response = 0.0;
    for (share, part) in noise_parts(&model.effects.coloured_friction_noise).into_iter().filter(|p| p.0 > 0.0) {
        response += share * part_response(engine, model, &part, data, settings)?;
    }
    Ok(response)
}

/// The independent parts of a friction noise of colour `colour` (`None`:
/// white), each with its share of the noise's variance (–): `None` for a
/// white part, else a whole-variance `ar1` at its correlation time, or a
/// `hold`. The parts of every form are those of its simulation
/// ([`crate::engine::effects::ColouredFrictionNoise`]).
fn noise_parts(colour: &Option<ColouredFrictionNoise>) -> Vec<(f64, Option<ColouredFrictionNoise>)> {
    let Some(c) = colour.as_ref().filter(|c| c.correlation_time_s > 0.0) else { return vec![(1.0, None)] };
    let ar1 = |tau_s: f64| {
        Some(ColouredFrictionNoise { form: ColourForm::Ar1, correlation_time_s: tau_s, coloured_share: 1.0 })
    };
    let tau = c.correlation_time_s;
    let share = c.coloured_share.clamp(0.0, 1.0);
    match c.form {
        ColourForm::Ar1 => vec![(1.0 - share, None), (share, ar1(tau))],
        ColourForm::Hold => vec![(1.0, colour.clone())],
        ColourForm::TwoScale => vec![(0.5, None), (0.5, ar1(tau))],
        ColourForm::MultiScale => [0.25, 1.0, 4.0].iter().map(|f| (1.0 / 3.0, ar1(f * tau))).collect(),
        ColourForm::FastSlow => vec![(1.0 - share, ar1(tau)), (share, ar1(10.0 * tau))],
    }
}

/// The response to σ_μ² (–) of a noise that is wholly `part` (`None`:
/// white; see [`noise_parts`]), measured once per diagnosis on one model:
/// the first asked for a response (the initial baseline), with `part` put
/// on it and every unit fitted, as the gap's fall when σ_μ alone is raised
/// by a quarter, the replicates' noise the same. Read between successive
/// steps instead, it also carried what the law's move between them did to
/// the residual, and came out at either bound of its clamp: a step ten
/// times too long, or σ left short.
fn part_response(
    engine: &Engine,
    model: &Model,
    part: &Option<ColouredFrictionNoise>,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
) -> Result<f64> {
    let responses = &data.caches.sigma_response;
    if let Some(r) = responses.get(part) {
        return Ok(r);
    }
    let every_unit = data.view(None);
    let (on, on_settings, measured) = responses.measured_on(|| {
        let units: Vec<usize> = (0..every_unit.units.len()).collect();
        (model.clone(), *settings, every_unit.measured_spreads(&units))
    });
    let mut base = on;
    base.effects.coloured_friction_noise = part.clone();
    let mut raised = base.clone();
    raised.friction.sigma = 1.25 * base.friction.sigma.max(1e-3);
    // The gap to the spreads kept with that model: its data's, whichever
    // view asks. Where no condition has a spread on both sides, the pooled
    // laws' σ² apart (the data's own σ² cancels in the fall).
    let gap = |m: &Model| -> Result<Option<f64>> {
        let records = fitting_records(engine, m, &every_unit, &on_settings)?;
        let at: Vec<Option<Spread>> = records.units.iter().map(|&u| measured[u]).collect();
        Ok(records.law.map(|law| variance_gap(&at, &records.spreads).unwrap_or(-law.sigma.powi(2))))
    };
    let (Some(before), Some(after)) = (gap(&base)?, gap(&raised)?) else {
        return Ok(1.0);
    };
    let base_variance = base.friction.sigma.powi(2);
    let response = ((before - after) / (raised.friction.sigma.powi(2) - base_variance)).clamp(MIN_SIGMA_RESPONSE, 1.5);
    if crate::diagnose::tracing() {
        eprintln!(
            "sigma response {response:.3} for {} (gap {before:.3e} at sigma {:.4}, {after:.3e} at {:.4})",
            part.as_ref().map_or("a white noise".to_string(), |c| format!("{:?} {} s", c.form, c.correlation_time_s)),
            base.friction.sigma,
            raised.friction.sigma
        );
    }
    Ok(responses.insert(part, response))
}

/// `model` with its friction law moved one step towards the data from what
/// scoring it gave (`scores`, on the view's fitting units), without a
/// simulation of its own: with force channels one step of the indirect
/// inference from its replicate records (those that scored it); without
/// them, a Newton step of the friction level `a` on `slope` (d level error /
/// d a) from the mean level error of its scores; unchanged where neither
/// applies.
pub(crate) fn law_step(
    model: &Model,
    scores: &[Score],
    slope: f64,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
) -> Result<Model> {
    let mut m = model.clone();
    if let Some(measured) = data.measured_law {
        if let Some((simulated, gap)) = simulated_law(engine, model, data, settings)? {
            let response = sigma_response(engine, model, data, settings)?;
            step_law(&mut m, &measured, &simulated, gap, response);
        }
        return Ok(m);
    }
    let Some(targets) = ResponseTargets::of(data) else { return Ok(m) };
    let errors: Vec<f64> = scores
        .iter()
        .filter(|s| !s.heldout && s.observable == targets.level && s.measured.is_finite())
        .filter_map(|s| match targets.level {
            Observable::PeakMeanM => (s.measured > 0.0).then(|| s.simulated / s.measured - 1.0),
            _ => Some(wrap_angle((s.simulated - s.measured).to_radians())),
        })
        .collect();
    if !errors.is_empty() && slope.is_finite() && slope != 0.0 {
        let lowest = (-m.friction.b).max(0.0);
        m.friction.a = (m.friction.a - mean(&errors) / slope).clamp(lowest, (m.friction.a + 0.5).min(5.0));
    }
    Ok(m)
}

/// One step of the indirect inference, in curve space: the model's law
/// μ(v) is moved at the measured slipping speeds' deciles by what the
/// measured fit and the fit on its own simulated records differ by there,
/// and a, b, d are refitted to the moved curve at the model's own Stribeck
/// rate c (linear least squares, so the step is continuous and cannot
/// wander off along the directions in which a, b, c and d trade off; c
/// itself is the model's: the measured records' fit, or for a force
/// derived from `x` the one [`calibrate_baseline`] chose).
/// `response`: how far the simulated residual variance moves per unit of
/// σ_μ² (1 with recorded channels; a derived friction force, read through
/// a smoothing filter, passes a fraction of the noise, [`crate::diagnose::derived`]).
/// `variance_gap`: how much more the friction's residual variance is in
/// the data than in the replicates, –² ([`simulated_law`]).
fn step_law(model: &mut Model, measured: &FrictionLaw, simulated: &FrictionLaw, variance_gap: f64, response: f64) {
    if let Some(law) = FrictionLaw::of(model).moved(measured, simulated) {
        let f = &mut model.friction;
        f.a = law.a.max(0.0);
        f.b = law.b.max(-f.a);
        f.d = law.d;
    }
    let f = &mut model.friction;
    let variance = f.sigma.powi(2) + variance_gap / response;
    f.sigma = variance.max((0.1 * measured.sigma).powi(2)).sqrt().max(SIGMA_STEP_MIN_SHARE * f.sigma);
}

/// A law step lowers σ_μ to no less than this share of what it was. The
/// σ step is a Newton step that takes the simulated residual variance to
/// move one for one with σ_μ²; an effect whose form differs from the
/// data's (a friction memory of another shape, in a trial of the search)
/// adds a structured residual of its own, and one full step can then take
/// σ_μ straight to its floor, hiding the effect behind a noise level no
/// trial had tried. Repeated steps still reach a σ_μ the data imply; a
/// single step cannot collapse it.
const SIGMA_STEP_MIN_SHARE: f64 = 0.5;

/// The least response of the simulated residual variance to σ_μ² a σ step
/// assumes: a step is then at most ten times the variance gap.
const MIN_SIGMA_RESPONSE: f64 = 0.1;

/// A calibrated model, its scores and the friction level's slope (see
/// [`calibrate_and_score`]).
type Calibrated = (Model, Vec<Score>, f64);

/// The baseline calibrated to the data, its scores at every unit and the
/// friction level's slope ([`calibrate_and_score`], then [`converge_law`]).
///
/// A friction force derived from `x` does not pin the Stribeck rate `c`
/// (see [`initial_baseline`]), yet the rate sets the law's friction at
/// rest, `a + b`, which the law's fit only extrapolates to: the slowest
/// slips it reads are blurred, and a block held throughout reads none.
/// Held at a rate far from the rig's, a law that matches the sliding
/// friction can break away at a tenth less than the rig does, and its
/// replicates then slide at a load where the data's block never moves
/// (peak means hundreds of noise units apart). The data as a whole do pin
/// it: the baseline is calibrated at each rate of
/// [`DERIVED_RATE_GRID_S_PER_M`], then a quarter-decade either side of the
/// best, and the rate whose calibrated baseline fits the fitting units best
/// is kept. The rates are compared as a search compares its trials, on
/// half the replicates ([`DiagnoseSettings::for_search`]); the kept one is
/// then stepped on all of them. With a recorded force the rate is the
/// data's, and one calibration is made.
pub(crate) fn calibrate_baseline(data: &Data<'_>, settings: &DiagnoseSettings, engine: &Engine) -> Result<Calibrated> {
    let converged = |(baseline, scores, slope): Calibrated| -> Result<Calibrated> {
        let (baseline, scores) = converge_law(baseline, scores, data, settings, engine)?;
        Ok((baseline, scores, slope))
    };
    if !searches_rate(data) {
        let start = initial_baseline(data, None)?;
        return converged(calibrate_and_score(&start, data, settings, engine, None, 0, Scope::All)?);
    }
    let search = settings.for_search();
    // The filter's response to σ_μ is measured on this model, on every
    // replicate (each colour of the noise a model later carries too).
    sigma_response(engine, &initial_baseline(data, Some(DERIVED_RATE_GRID_S_PER_M[0]))?, data, settings)?;
    // (fitting gap, rate in s/m, the baseline calibrated at it on the
    // search's replicates)
    let at = |rate: f64| -> Result<(f64, f64, Calibrated)> {
        let start = initial_baseline(data, Some(rate))?;
        let calibrated = calibrate_and_score(&start, data, &search, engine, None, 0, Scope::Fitting)?;
        let gap = gap_of(&calibrated.1, false);
        if crate::diagnose::tracing() {
            eprintln!("baseline at Stribeck rate {rate:.3} s/m: fitting gap {gap:.4}");
        }
        Ok((gap, rate, calibrated))
    };
    // The index of the best fit so far (a gap that is NaN sorts last).
    let best = |tried: &[(f64, f64, Calibrated)]| {
        (0..tried.len()).min_by(|&i, &j| tried[i].0.total_cmp(&tried[j].0)).expect("the rate grid is not empty")
    };
    // Each rate's calibration is independent of the others': side by side
    // ([`fits_per_task`]). (Trace lines interleave.)
    let at_each = |rates: &[f64]| -> Result<Vec<(f64, f64, Calibrated)>> {
        rates.par_iter().with_min_len(fits_per_task(engine)).map(|&rate| at(rate)).collect()
    };
    let mut tried = at_each(&DERIVED_RATE_GRID_S_PER_M)?;
    let around = tried[best(&tried)].1;
    let half_step = (DERIVED_RATE_GRID_S_PER_M[1] / DERIVED_RATE_GRID_S_PER_M[0]).sqrt();
    tried.extend(at_each(&[around / half_step, around * half_step])?);
    let kept = tried.swap_remove(best(&tried)).2.0;
    // On every replicate: one more step of its law, then on while the steps
    // lower the fitting gap.
    converged(calibrate_and_score(&kept, data, settings, engine, None, 1, Scope::Fitting)?)
}

/// Whether [`calibrate_baseline`] searches the Stribeck rate: where the
/// friction force is derived from `x` and gives a law.
pub(crate) fn searches_rate(data: &Data<'_>) -> bool {
    data.derived.friction && data.measured_law.is_some()
}

/// The Stribeck rates (s/m) a baseline with a friction force derived from
/// `x` is calibrated at first ([`calibrate_baseline`]): half-decade steps
/// through the paper's 20 s/m. With the refinement about the best, the
/// rates reach from 1.1 to 112 s/m.
pub(crate) const DERIVED_RATE_GRID_S_PER_M: [f64; 4] = [2.0, 6.32, 20.0, 63.2];

/// How many rates [`calibrate_baseline`] calibrates a baseline at: the
/// grid's and the two about its best.
pub(crate) const DERIVED_RATES_TRIED: usize = DERIVED_RATE_GRID_S_PER_M.len() + 2;

/// The baseline before calibration: the rig and excitation from the
/// manifest, σ_N from the data, and the friction law read from the force
/// channels; where the force is derived from `x`, at the Stribeck rate
/// `rate` (s/m; `None`: the paper's).
fn initial_baseline(data: &Data<'_>, rate: Option<f64>) -> Result<Model> {
    let set = data.set;
    let mut m = Model::default();
    if let Some(c) = rate {
        m.friction.c = c;
    }
    m.rig.mass_kg = set.rig.mass_kg;
    m.rig.natural_frequency_hz = set.rig.natural_frequency_hz;
    m.rig.damping_ratio = set.rig.damping_ratio;
    m.excitation.amplitude_m = set
        .runs
        .first()
        .map(|r| r.excitation_amplitude_m)
        .or_else(|| set.summary.first().map(|s| s.excitation_amplitude_m))
        .unwrap_or(m.excitation.amplitude_m);
    m.noise.interval_s = data.sample_interval_s;
    let fit_runs: Vec<&Run> =
        data.units.iter().filter(|u| !u.heldout).flat_map(|u| u.runs.iter().map(|&r| &data.set.runs[r])).collect();
    // σ_N: what the measured N varies by once its mean, straight-line drift
    // and first four harmonics are removed (summary: its stated variance).
    let n_vars: Vec<f64> = fit_runs
        .iter()
        .filter_map(|r| run_features(r).normal_force.and_then(|n| n.residual_var_n2.or(Some(n.var_n2))))
        .collect();
    let summary_vars: Vec<f64> = set.summary.iter().filter_map(|s| s.normal_force_var_n2).collect();
    if !n_vars.is_empty() {
        m.normal_force.sigma = mean(&n_vars).sqrt();
    } else if !summary_vars.is_empty() {
        m.normal_force.sigma = mean(&summary_vars).sqrt();
    }
    // The friction law from the force channels, recorded or derived. The
    // rate that fits a recorded force best is the rig's. Through a derived
    // force's filter it is not (a stick's onset blurred over the window
    // reads as a drop tens of times faster), and the rate the data's and
    // the replicates' fits read does not follow the model's closely enough
    // to be inferred from: the model takes a given rate (the paper's, or
    // one of [`calibrate_baseline`]'s grid), and `a`, `b` and `d` are
    // inferred at it, starting from the data's curve read at that rate. Not
    // from the terms read at the data's own rate: where that rate is slow,
    // a and b trade off along the near-constant 1/(1 + c |v|) (a 1.40,
    // b −1.00 at c = 1 s/m for a curve near 0.45), a law far from the
    // data's at the model's rate.
    if let Some(measured) = data.measured_law {
        let law = if data.derived.friction {
            law::fit_friction_law_at(&fit_runs, &data.reading(), m.friction.c).unwrap_or(measured)
        } else {
            m.friction.c = measured.c;
            measured
        };
        m.friction.a = law.a.max(0.0);
        m.friction.b = law.b.max(-m.friction.a);
        m.friction.d = law.d;
        m.friction.sigma = law.sigma;
    }
    m.validate().map_err(|e| named_by_manifest(data, e))?;
    // A rig the oscillator cannot integrate at some condition (one far
    // stiffer than the excitation is slow) is the manifest's.
    for unit in &data.units {
        Oscillator::new(&m, unit.condition).map_err(|e| named_by_manifest(data, e))?;
    }
    Ok(m)
}

/// What the report says where the baseline's σ_N (N) is not read from the
/// data: with friction channels (recorded or derived) the law and σ_μ come
/// from them, and σ_N from a normal-force channel or a stated variance;
/// with neither, `baseline`'s σ_N is the paper's. `None` where the data
/// give σ_N, or where the response sets it (no friction channels).
pub(crate) fn assumed_normal_force_noise_note(data: &Data<'_>, baseline: &Model) -> Option<String> {
    (data.measured_law.is_some() && !data.states_normal_force_noise()).then(|| {
        format!(
            "no run records the normal force and no summary states its variance, so the normal force's noise is \
             not read from the data: the baseline keeps σ_N = {:.3} N (the paper's). μ is read as the friction \
             force over the nominal load, so a σ_N unlike the rig's moves into σ_μ, most at the lightest loads; a \
             normal-force channel settles it",
            baseline.normal_force.sigma
        )
    })
}

/// An error in a parameter of the model that the manifest's `rig` gave,
/// or in the friction law the baseline was calibrated to from the records,
/// named by the measurement set instead of as a model parameter the user
/// never wrote. Other errors pass through.
pub(crate) fn named_by_manifest(data: &Data<'_>, e: Error) -> Error {
    let manifest = data.set.dir.join("manifest.json");
    match e {
        Error::InvalidParameter { key, value, message } if key.starts_with("rig.") => {
            Error::Measurement { file: manifest, line: None, message: format!("`{key}` = {value}: {message}") }
        }
        Error::InvalidParameter { key, value, message } if key.starts_with("friction.") => {
            let read = match (data.measured_law.is_some(), data.derived.friction) {
                (true, true) => {
                    "the friction derived from the displacement through the equation of motion with the rig's \
                     mass, natural frequency and damping ratio"
                }
                (true, false) => "the recorded friction and normal forces",
                (false, _) => "the response at the rig's mass, natural frequency and damping ratio",
            };
            Error::Measurement {
                file: manifest,
                line: None,
                message: format!(
                    "calibrating the baseline to these records took `{key}` to {value}, and {message}. It was \
                     read from {read}, so the records and the manifest disagree: check `rig` (mass_kg, \
                     natural_frequency_hz, damping_ratio) and each run's normal_force_n and excitation against \
                     the rig that made the records"
                ),
            }
        }
        other => other,
    }
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

    #[test]
    fn a_law_step_at_most_halves_sigma_and_otherwise_takes_the_newton_step() {
        let mut model = Model::default();
        model.friction.sigma = 0.03;
        let law = |sigma: f64| FrictionLaw {
            sigma,
            anchors_m_per_s: std::array::from_fn(|k| 0.01 * (k + 1) as f64),
            ..FrictionLaw::of(&model)
        };
        let gap = |simulated: f64| 0.02f64.powi(2) - simulated * simulated;
        // The simulated residual far above the measured one (a trial's
        // effect adds a residual of its own): the full step would end at
        // the floor, 0.1 × 0.02; it ends at half of 0.03.
        let mut m = model.clone();
        step_law(&mut m, &law(0.02), &law(0.1), gap(0.1), 1.0);
        assert!((m.friction.sigma - 0.015).abs() < 1e-12, "sigma {}", m.friction.sigma);
        // A moderate step down and a step up are the Newton step itself:
        // σ² + measured² − simulated².
        for simulated in [0.025, 0.01] {
            let mut m = model.clone();
            step_law(&mut m, &law(0.02), &law(simulated), gap(simulated), 1.0);
            let expected = (0.03f64.powi(2) + 0.02f64.powi(2) - simulated * simulated).sqrt();
            assert!((m.friction.sigma - expected).abs() < 1e-12, "simulated {simulated}: sigma {}", m.friction.sigma);
        }
    }
}

#[cfg(test)]
mod derived_tests {
    use super::*;
    use crate::diagnose::derived::with_derived_channels;
    use crate::diagnose::score::Scope;

    /// Through a derived friction force's filter the replicates' residual
    /// variance moves by a fraction of σ_μ² (measured once, with the law
    /// held), and σ_μ calibrated with that fraction comes back from half
    /// as much again as the truth's in the baseline's three steps.
    #[test]
    fn sigma_through_a_derived_force_is_stepped_by_the_filters_measured_response() {
        let truth = Model::paper_rig(&[]).expect("the paper rig");
        let set = crate::diagnose::synthetic::displacement_only_set(&truth, 5);
        let (derived_set, derived) = with_derived_channels(&set);
        let set = derived_set.expect("derived");
        let data = Data::new(&set, derived).expect("data");
        let engine = Engine::cpu("test");
        let settings = DiagnoseSettings { replicates: 8, warmup_cycles: 5, ..DiagnoseSettings::default() };
        let mut start = truth.clone();
        start.friction.sigma *= 1.5;
        let response = sigma_response(&engine, &start, &data, &settings).expect("response");
        assert!(response > MIN_SIGMA_RESPONSE && response < 0.8, "a fraction, not a bound: {response}");
        let (m, _, _) =
            calibrate_and_score(&start, &data, &settings, &engine, None, 0, Scope::Fitting).expect("calibrated");
        let off = m.friction.sigma / truth.friction.sigma - 1.0;
        assert!(off.abs() < 0.15, "sigma {} against the truth's {}", m.friction.sigma, truth.friction.sigma);
    }

    /// A noise correlated over many hold intervals passes the filter more
    /// than a white one of the same variance: its response is measured on
    /// its own (on the model the white one was measured on), and σ_μ of a
    /// truth whose noise is mostly coloured comes back from half as much
    /// again in the baseline's three steps, as a white one's does.
    #[test]
    fn a_coloured_noise_has_its_own_response_through_a_derived_force() {
        let mut truth = Model::paper_rig(&[]).expect("the paper rig");
        let white = truth.clone();
        truth.effects.coloured_friction_noise =
            Some(ColouredFrictionNoise { form: ColourForm::Ar1, correlation_time_s: 0.05, coloured_share: 0.8 });
        let set = crate::diagnose::synthetic::displacement_only_set(&truth, 6);
        let (derived_set, derived) = with_derived_channels(&set);
        let set = derived_set.expect("derived");
        let data = Data::new(&set, derived).expect("data");
        let engine = Engine::cpu("test");
        let settings = DiagnoseSettings { replicates: 8, warmup_cycles: 5, ..DiagnoseSettings::default() };
        let white_response = sigma_response(&engine, &white, &data, &settings).expect("white response");
        let coloured_response = sigma_response(&engine, &truth, &data, &settings).expect("coloured response");
        assert!(
            coloured_response > 1.5 * white_response,
            "coloured {coloured_response} against white {white_response}"
        );
        let mut start = truth.clone();
        start.friction.sigma *= 1.5;
        let (m, _, _) =
            calibrate_and_score(&start, &data, &settings, &engine, None, 0, Scope::Fitting).expect("calibrated");
        let off = m.friction.sigma / truth.friction.sigma - 1.0;
        assert!(off.abs() < 0.15, "sigma {} against the truth's {}", m.friction.sigma, truth.friction.sigma);
    }
}
