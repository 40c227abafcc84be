//! Diagnosis of the sim-to-real gap (`stickslip diagnose`): where the
//! simulation departs from a measurement set, which unmodelled effect
//! explains it, and how far the gap shrinks once it is added.
//!
//! 1. **Calibrate** the baseline to the data ([`calibrate`]).
//! 2. **Locate**: every observable ([`observable`], [`features`]) is computed
//!    by the same code from the measured records and from simulated
//!    replicate records of the same length and sampling; each (condition,
//!    observable) gets a z-score against the simulator's own replicate
//!    spread ([`score`]). `locations` are those with |z| > 3.
//! 3. **Attribute**: for each effect ([`candidates`]), the strength is
//!    searched with the baseline recalibrated at every trial, so an effect
//!    cannot win by shifting the baseline and is not judged against a law
//!    its own signature distorted ([`search`]).
//! 4. **Quantify**: the gap metric is the mean Huber loss of z over
//!    (condition, observable) — z² up to |z| = 3, linear beyond; `shrink` is
//!    measured on the fitting units and `heldout_shrink` on units left out
//!    of every fit (alternate runs of a condition, or alternate conditions,
//!    [`data`]). The verdict is `none` unless the best candidate lowers both
//!    the held-out and the fitting gaps by more than their noise.
//!
//! [`measure`] reads (and writes) measurement sets, [`report`] writes the
//! outputs, and [`synthetic`] and [`benchmark`] check the whole blind.

pub mod benchmark;
pub mod calibrate;
pub mod candidates;
mod chart;
pub mod data;
pub mod features;
pub mod measure;
pub mod observable;
pub mod report;
pub mod score;
pub mod search;
pub mod simulate;
pub mod synthetic;

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use crate::engine::{Condition, Effect, Engine, Model};
use crate::error::Result;
use data::{Data, condition_key};
use measure::{MeasurementSet, read_measurement_set};
use observable::Observable;
use score::{Score, gap_of};

/// Settings of a diagnosis.
#[derive(Clone, Copy, Debug)]
pub struct DiagnoseSettings {
    /// The noise seed of every simulation.
    pub seed: u64,
    /// Simulated replicate records per condition.
    pub replicates: u32,
    /// Realisations per condition in the ensembles that score summary data
    /// and solve for `a`.
    pub ensemble_realisations: u32,
    /// Warm-up periods before a simulated record starts.
    pub warmup_cycles: u32,
}

impl Default for DiagnoseSettings {
    fn default() -> Self {
        DiagnoseSettings { seed: 20_251_122, replicates: 8, ensemble_realisations: 64, warmup_cycles: 60 }
    }
}

/// One (condition, observable) a candidate leaves unexplained.
#[derive(Clone, Debug, Serialize)]
pub struct Unexplained {
    pub observable: Observable,
    /// Hz
    pub excitation_frequency_hz: f64,
    /// N
    pub normal_force_n: f64,
    /// –
    pub z: f64,
}

/// A candidate's result.
#[derive(Clone, Debug)]
pub struct Candidate {
    pub effect: Effect,
    /// Gap on the fitting units after fitting this effect.
    pub gap_fit: f64,
    /// Gap on the held-out units.
    pub gap_heldout: f64,
    /// Relative fall of the fitting gap, –.
    pub shrink: f64,
    /// Relative fall of the held-out gap, –; `None` without held-out units.
    pub heldout_shrink: Option<f64>,
    /// The fitted parameters by name (names carry units).
    pub parameters: BTreeMap<String, f64>,
    /// What the candidate still leaves: its five largest |z|.
    pub unexplained: Vec<Unexplained>,
    /// The calibrated model with this effect.
    pub model: Model,
}

/// Everything a diagnosis found.
#[derive(Clone, Debug)]
pub struct Diagnosis {
    pub baseline: Model,
    pub fitted: Model,
    /// The effect named; `None` when the baseline explains the data.
    pub verdict: Option<Effect>,
    /// –, in [0, 1].
    pub confidence: f64,
    pub baseline_scores: Vec<Score>,
    pub fitted_scores: Vec<Score>,
    /// The baseline's gap on the fitting units.
    pub gap_fit: f64,
    /// The baseline's gap on the held-out units.
    pub gap_heldout: f64,
    /// Every candidate tried, best first.
    pub candidates: Vec<Candidate>,
    /// Threshold the held-out improvement had to beat.
    pub noise_threshold: f64,
    pub has_heldout: bool,
    pub conditions: Vec<Condition>,
}

impl Diagnosis {
    /// The verdict's name: an effect's, or `none`.
    pub fn verdict_name(&self) -> &'static str {
        self.verdict.map_or("none", Effect::name)
    }

    /// The candidate the verdict chose, if any.
    pub fn chosen(&self) -> Option<&Candidate> {
        self.candidates.iter().find(|c| Some(c.effect) == self.verdict)
    }
}

/// Arithmetic mean; 0 for no values.
pub(crate) fn mean(values: &[f64]) -> f64 {
    values.iter().sum::<f64>() / values.len().max(1) as f64
}

/// Sample standard deviation; 0 for fewer than two values.
pub(crate) fn sd(values: &[f64]) -> f64 {
    if values.len() < 2 {
        return 0.0;
    }
    let m = mean(values);
    (values.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (values.len() - 1) as f64).sqrt()
}

/// Runs the whole diagnosis on a measurement set directory.
pub fn diagnose(
    dir: &Path,
    settings: &DiagnoseSettings,
    engine: &Engine,
    progress: &mut dyn FnMut(&str),
) -> Result<Diagnosis> {
    let set = read_measurement_set(dir)?;
    diagnose_set(&set, settings, engine, progress)
}

/// Runs the whole diagnosis on a measurement set already read.
pub fn diagnose_set(
    set: &MeasurementSet,
    settings: &DiagnoseSettings,
    engine: &Engine,
    progress: &mut dyn FnMut(&str),
) -> Result<Diagnosis> {
    let data = Data::new(set)?;
    progress("calibrating the baseline");
    let (baseline, baseline_scores, slope) =
        calibrate::calibrate_and_score(&calibrate::initial_baseline(&data)?, &data, settings, engine, None)?;
    let gaps = (gap_of(&baseline_scores, false), gap_of(&baseline_scores, true));
    let specs = candidates::candidate_specs(&data, &baseline, &baseline_scores);
    let mut candidates = Vec::new();
    for spec in &specs {
        progress(&format!("trying {}", spec.effect));
        if let Some(c) = search::fit_candidate(spec, &baseline, gaps, slope, &data, settings, engine)? {
            candidates.push(c);
        }
    }
    let verdict = search::decide(&mut candidates, &baseline_scores, data.has_heldout());
    let (fitted, fitted_scores) = match verdict.effect.and_then(|e| candidates.iter().find(|c| c.effect == e)) {
        Some(best) => (best.model.clone(), score::score(engine, &best.model, &data, settings)?),
        None => (baseline.clone(), baseline_scores.clone()),
    };
    let mut conditions: Vec<Condition> = data.units.iter().map(|u| u.condition).collect();
    conditions.dedup_by_key(|c| condition_key(*c));
    Ok(Diagnosis {
        baseline,
        fitted,
        verdict: verdict.effect,
        confidence: verdict.confidence,
        gap_fit: gaps.0,
        gap_heldout: gaps.1,
        baseline_scores,
        fitted_scores,
        candidates,
        noise_threshold: verdict.noise_threshold,
        has_heldout: data.has_heldout(),
        conditions,
    })
}
