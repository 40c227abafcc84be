//! Scoring a model against the data: a z-score per (unit, observable)
//! against the simulator's own replicate spread, and the gap metric over
//! them.

use serde::Serialize;

use crate::diagnose::data::Data;
use crate::diagnose::features::RunFeatures;
use crate::diagnose::observable::Observable;
use crate::diagnose::simulate::{fitting_records, path_stats_per_condition, record_features};
use crate::diagnose::{DiagnoseSettings, mean, sd};
use crate::engine::reduce::{circular_mean_var, wrap_angle};
use crate::engine::{Condition, Engine, Model};
use crate::error::Result;

/// Huber threshold of the gap metric: z² up to |z| = 3, then 6|z| − 9, so a
/// wild observable counts linearly (it cannot swamp the rest) yet every
/// improvement still counts. Under pure noise the mean is about 0.98.
pub const HUBER_K: f64 = 3.0;

/// The Huber loss of one z-score.
pub fn huber(z: f64) -> f64 {
    let a = z.abs();
    if a <= HUBER_K { a * a } else { 2.0 * HUBER_K * a - HUBER_K * HUBER_K }
}

/// The noise a fall of the mean Huber loss over `k` scores must beat:
/// 3·sqrt(2/k) (three standard deviations of a mean of k values of about
/// z², each of variance about 2) plus 0.5 for the replicate estimate of each
/// z's spread.
pub fn gap_noise(k: usize) -> f64 {
    3.0 * (2.0 / k.max(1) as f64).sqrt() + 0.5
}

/// Per (condition, observable): measured value and simulated replicates.
#[derive(Clone, Debug, Serialize)]
pub struct Score {
    /// Hz
    pub excitation_frequency_hz: f64,
    /// Nominal normal force, N.
    pub normal_force_n: f64,
    pub observable: Observable,
    /// The measured value, in the observable's unit.
    pub measured: f64,
    /// Mean of the simulated replicates, in the observable's unit.
    pub simulated: f64,
    /// (measured − simulated) / the spread of their difference, –.
    pub z: f64,
    /// Whether the unit was left out of every fit.
    pub heldout: bool,
    /// The unit (index into the diagnosis's units) it scores.
    #[serde(skip)]
    pub unit: usize,
    /// What z divides measured − simulated by, in the observable's unit: the
    /// spread of their difference under the model scored.
    #[serde(skip)]
    pub scale: f64,
    /// The share of `scale²` that is the variance of the simulated mean
    /// (the rest is the measured value's): `(1/R) / (1/n + 1/R)` for R
    /// simulated and n measured values, –. What the simulated side adds to
    /// the noise of a comparison between two models on the same data.
    #[serde(skip)]
    pub simulated_share: f64,
}

/// Mean Huber loss of z over the fitting (or held-out) scores; 0 for none.
pub fn gap_of(scores: &[Score], heldout: bool) -> f64 {
    let picked: Vec<f64> = scores.iter().filter(|s| s.heldout == heldout).map(|s| huber(s.z)).collect();
    if picked.is_empty() { 0.0 } else { picked.iter().sum::<f64>() / picked.len() as f64 }
}

/// A score of `observable` at `unit` with z = `z` and scale 1 at 7 Hz and
/// 10 N, held out or fitting (for unit tests).
#[cfg(test)]
pub(crate) fn test_score(unit: usize, observable: Observable, z: f64, heldout: bool) -> Score {
    Score {
        excitation_frequency_hz: 7.0,
        normal_force_n: 10.0,
        observable,
        measured: z,
        simulated: 0.0,
        z,
        heldout,
        unit,
        scale: 1.0,
        simulated_share: 0.5,
    }
}

/// How many fitting (or held-out) scores there are.
pub fn count_of(scores: &[Score], heldout: bool) -> usize {
    scores.iter().filter(|s| s.heldout == heldout).count()
}

/// A measured value against simulated replicate values: (the replicates'
/// centre, measured − centre, the replicates' spread). Angles (degrees) are
/// compared on the circle: the centre is their circular mean and every
/// difference is wrapped into (−180°, 180°].
pub(crate) fn compare(observable: Observable, measured: f64, values: &[f64]) -> (f64, f64, f64) {
    if observable.is_angle_deg() {
        let radians: Vec<f64> = values.iter().map(|v| v.to_radians()).collect();
        let (centre, _) = circular_mean_var(&radians);
        let deviations: Vec<f64> = radians.iter().map(|r| wrap_angle(r - centre).to_degrees()).collect();
        (centre.to_degrees(), wrap_angle(measured.to_radians() - centre).to_degrees(), sd(&deviations))
    } else {
        let centre = mean(values);
        (centre, measured - centre, sd(values))
    }
}

/// Which measured units a score covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Scope {
    /// Every unit.
    All,
    /// The fitting units' records, and every summary unit (a summary's
    /// ensembles are one job, cheap beside the records): what a search's
    /// trials are compared on ([`gap_of`] of the fitting scores). The
    /// held-out records are added for the trial a search keeps
    /// ([`add_heldout`]), with the same numbers as a score over all units.
    Fitting,
}

/// Adds the held-out records' scores to scores of `model` made with
/// [`Scope::Fitting`], in the order a score over all units has them, so the
/// result is the same as that score's.
pub(crate) fn add_heldout(
    engine: &Engine,
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    mut scores: Vec<Score>,
) -> Result<Vec<Score>> {
    let heldout: Vec<usize> =
        (0..data.units.len()).filter(|&i| data.units[i].summary.is_none() && data.units[i].heldout).collect();
    if heldout.is_empty() {
        return Ok(scores);
    }
    scores.extend(record_scores(engine, model, data, settings, &heldout)?);
    // Summary units first, then records, each in unit order (a stable sort
    // keeps each unit's observables in their order).
    scores.sort_by_key(|s| (data.units[s.unit].summary.is_none(), s.unit));
    Ok(scores)
}

/// Scores a model against the data's units in `scope`: z per (unit, observable).
pub(crate) fn score(
    engine: &Engine,
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    scope: Scope,
) -> Result<Vec<Score>> {
    let mut scores = Vec::new();
    let summary_units: Vec<usize> = (0..data.units.len()).filter(|&i| data.units[i].summary.is_some()).collect();
    if !summary_units.is_empty() {
        let conditions: Vec<Condition> = summary_units.iter().map(|&i| data.units[i].condition).collect();
        // Each row over as many periods as it averaged (350 where it does
        // not say), so its simulated spread is that of its own statistic.
        let cycles: Vec<u32> = summary_units
            .iter()
            .map(|&i| data.units[i].summary.map_or(350, |row| data.set.summary[row].n_peaks.unwrap_or(350) as u32))
            .collect();
        let stats = path_stats_per_condition(
            engine,
            model,
            &conditions,
            &cycles,
            settings.ensemble_realisations,
            settings.seed,
            settings.warmup_cycles,
        )?;
        for (&i, per_path) in summary_units.iter().zip(&stats) {
            let u = &data.units[i];
            for (&observable, &m) in &data.measured[i] {
                let sim: Vec<f64> = per_path.iter().filter_map(|p| p.get(observable)).collect();
                if sim.len() < 2 {
                    continue;
                }
                let (simulated, deviation, spread) = compare(observable, m, &sim);
                let spread = spread.max(1e-9 * simulated.abs() + 1e-300);
                let scale = spread * (1.0 + 1.0 / sim.len() as f64).sqrt();
                scores.push(Score {
                    excitation_frequency_hz: u.condition.excitation_frequency_hz,
                    normal_force_n: u.condition.normal_force_n,
                    observable,
                    measured: m,
                    simulated,
                    z: deviation / scale,
                    heldout: u.heldout,
                    unit: i,
                    scale,
                    simulated_share: 1.0 / (sim.len() as f64 + 1.0),
                });
            }
        }
    }
    // Time series: simulated replicate records through the same feature
    // code, the fitting units' as the law's calibration reads them too.
    let fitting = fitting_records(engine, model, data, settings)?;
    scores.extend(scores_of_records(data, &fitting.units, &fitting.features));
    if scope == Scope::All {
        scores = add_heldout(engine, model, data, settings, scores)?;
    }
    Ok(scores)
}

/// The scores of record units `run_units` (in that order).
fn record_scores(
    engine: &Engine,
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    run_units: &[usize],
) -> Result<Vec<Score>> {
    let simulated = record_features(engine, model, data, settings, run_units)?;
    Ok(scores_of_records(data, run_units, &simulated))
}

/// The scores of record units `run_units` given their simulated replicates'
/// features (`simulated[k]` for unit `run_units[k]`).
fn scores_of_records(data: &Data<'_>, run_units: &[usize], simulated: &[Vec<RunFeatures>]) -> Vec<Score> {
    let mut scores = Vec::new();
    for (&i, sims) in run_units.iter().zip(simulated) {
        let u = &data.units[i];
        let n_meas = u.runs.len() as f64;
        for (&observable, &m) in &data.measured[i] {
            let values: Vec<f64> = sims
                .iter()
                .filter_map(|f| f.named_values().into_iter().find(|(o, _)| *o == observable).map(|(_, v)| v))
                .collect();
            if values.len() < 2 {
                continue;
            }
            let (simulated, deviation, spread) = compare(observable, m, &values);
            let spread = spread.max(1e-6 * simulated.abs()).max(1e-12);
            let scale = spread * (1.0 / n_meas + 1.0 / values.len() as f64).sqrt();
            scores.push(Score {
                excitation_frequency_hz: u.condition.excitation_frequency_hz,
                normal_force_n: u.condition.normal_force_n,
                observable,
                measured: m,
                simulated,
                z: deviation / scale,
                heldout: u.heldout,
                unit: i,
                scale,
                simulated_share: n_meas / (n_meas + values.len() as f64),
            });
        }
    }
    scores
}
