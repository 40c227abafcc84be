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
//! [`crate::measure`] reads (and writes) measurement sets, [`report`] writes the
//! outputs, and [`synthetic`] and [`benchmark`] check the whole blind.

pub mod benchmark;
pub(crate) mod cache;
pub mod calibrate;
pub mod candidates;
mod chart;
pub mod data;
pub mod derived;
pub mod features;
mod frame;
pub mod law;
mod misfit;
pub mod observable;
pub mod report;
pub mod score;
pub mod search;
pub mod simulate;
pub mod synthetic;

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use crate::engine::{Condition, Effect, Engine, Job, Model};
use crate::error::{Error, Result};
use crate::measure::{MeasurementSet, read_measurement_set};
use data::{Data, Folds, condition_key};
use observable::Observable;
use score::Score;

pub use misfit::{Misfit, MisfitObservable};

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
    /// The sample rate (Hz) the runs are thinned to before the diagnosis
    /// (every k-th sample kept, [`crate::measure::thinned`]); `None` keeps
    /// them as recorded.
    pub sample_rate_hz: Option<f64>,
}

/// Fewest simulated replicates per condition: a spread needs two.
pub const MIN_REPLICATES: u32 = 2;
/// Most simulated replicates per condition (each is a whole record in memory).
pub const MAX_REPLICATES: u32 = 1000;
/// Fewest realisations in the ensembles that score summary data.
pub const MIN_ENSEMBLE_REALISATIONS: u32 = 4;

impl DiagnoseSettings {
    /// Refuses settings a diagnosis cannot run with, each named as the
    /// front end spells it (`command_line`: `--replicates`, else the Python
    /// keyword `replicates`), before any data is read.
    pub fn check(&self, command_line: bool) -> Result<()> {
        let name = |flag: &str, keyword: &str| if command_line { flag.to_string() } else { keyword.to_string() };
        if !(MIN_REPLICATES..=MAX_REPLICATES).contains(&self.replicates) {
            return Err(Error::setting(
                name("--replicates", "replicates"),
                format!(
                    "{} simulated replicates per condition; a z-score needs a spread, so at least {MIN_REPLICATES} \
                     (and at most {MAX_REPLICATES})",
                    self.replicates
                ),
            ));
        }
        if !(MIN_ENSEMBLE_REALISATIONS..=Job::MAX_REALISATIONS).contains(&self.ensemble_realisations) {
            return Err(Error::setting(
                name("--realisations", "realisations"),
                format!(
                    "{} realisations per condition; the ensembles that score summary data need at least \
                     {MIN_ENSEMBLE_REALISATIONS} (and at most {})",
                    self.ensemble_realisations,
                    Job::MAX_REALISATIONS
                ),
            ));
        }
        match self.sample_rate_hz {
            Some(rate_hz) => crate::measure::check_sample_rate(rate_hz, &name("--sample-rate", "sample_rate_hz")),
            None => Ok(()),
        }
    }

    /// These settings as a search uses them: half the replicates per
    /// condition (at least 4, at most all), and half the realisations of
    /// the ensembles that score summary rows (at least 16). Trials are
    /// compared with each other on the same noise paths, so halving the
    /// replicates moves a search's choices little while halving its cost,
    /// the bulk of a diagnosis. Every model the cross-validation compares is
    /// scored on these replicates too, so no model's z-scores are measured
    /// with a different yardstick; a named effect's model, and the
    /// baseline at the Stribeck rate its search keeps, are then calibrated
    /// on all of them.
    pub(crate) fn for_search(&self) -> DiagnoseSettings {
        DiagnoseSettings {
            replicates: (self.replicates / 2).max(4).min(self.replicates),
            ensemble_realisations: (self.ensemble_realisations / 2).max(16).min(self.ensemble_realisations),
            ..*self
        }
    }
}

impl Default for DiagnoseSettings {
    fn default() -> Self {
        DiagnoseSettings {
            seed: 20_251_122,
            replicates: 8,
            ensemble_realisations: 64,
            warmup_cycles: 60,
            sample_rate_hz: None,
        }
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

/// One effect family as a round of the selection tried it: its best form
/// fitted to every unit, what that closes of the gap in sample, what the
/// family closes out of sample, and how often it won the contest.
#[derive(Clone, Debug)]
pub struct Candidate {
    pub effect: Effect,
    /// The form that fitted best, in the model file's words.
    pub form: candidates::SearchedForm,
    /// Gap over every unit after fitting this effect (in sample), –.
    pub gap_fit: f64,
    /// Relative fall of that gap from the model it was added to, –.
    pub shrink: f64,
    /// The share of that model's explainable gap (its gap less the noise
    /// floor) the best fit closes in sample, –.
    pub in_sample_share: f64,
    /// The share of that model's explainable out-of-sample gap the family
    /// closes, each fold predicted by the family member that fits the
    /// other folds best, –.
    pub cv_share: f64,
    /// The relative fall of that model's out-of-sample gap the family
    /// gives: `(before − after) / before`, –.
    pub heldout_shrink: f64,
    /// The share of bootstrap resamples of the conditions the family won
    /// (see [`search::cv::contest`]), –.
    pub wins: f64,
    /// Whether the family was searched in full (else only its coarse fit).
    pub refined: bool,
    /// The fitted parameters by name (names carry units).
    pub parameters: BTreeMap<String, f64>,
    /// What the candidate still leaves: its five largest |z|.
    pub unexplained: Vec<Unexplained>,
    /// The calibrated model with this effect.
    pub model: Model,
    /// Its scores.
    pub scores: Vec<Score>,
}

/// One effect of the verdict.
#[derive(Clone, Debug)]
pub struct NamedEffect {
    pub effect: Effect,
    /// The form that fitted best.
    pub form: candidates::SearchedForm,
    /// Its fitted parameters by name (names carry units).
    pub parameters: BTreeMap<String, f64>,
    /// The share of what the model before it left of the out-of-sample gap
    /// (above the noise floor) that adding it closed, from the refits
    /// without each fold, –.
    pub share: f64,
    /// What its form leaves of that gap: 1 − `share` (an effect is named
    /// for its family; no rig matches a candidate's shape exactly), –.
    pub form_misfit: f64,
    /// The share of bootstrap resamples of the conditions it won, –, in
    /// [0, 1].
    pub confidence: f64,
    /// Per fold: the gap at the fold's units of the model before it and
    /// with it, both fitted without the fold.
    pub folds: Vec<FoldGap>,
}

/// The gap at one fold's units of two models fitted without it.
#[derive(Clone, Debug, Serialize)]
pub struct FoldGap {
    /// What the fold holds out.
    pub label: String,
    /// –
    pub before: f64,
    /// –
    pub after: f64,
}

impl FoldGap {
    /// (before − after) / before, –; 0 for a zero gap.
    pub fn shrink(&self) -> f64 {
        if self.before > 0.0 { (self.before - self.after) / self.before } else { 0.0 }
    }
}

/// A family that led a round of the selection and is not named, and why:
/// where the verdict is `none` (or stops short) although a family explains
/// part of the gap, the researcher reads what held it back.
#[derive(Clone, Debug)]
pub struct Refusal {
    pub effect: Effect,
    /// The form of its best full-data fit.
    pub form: candidates::SearchedForm,
    /// The share of what the effects named before it left of the
    /// explainable out-of-sample gap that its family closed, –.
    pub share_of_gap: f64,
    /// How many effects are named before it.
    pub after_named: usize,
    pub reason: RefusalReason,
}

/// Why a leading family is not named.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum RefusalReason {
    /// Refitted from scratch without each fold, it closed `refitted_share`
    /// of that gap (–), not beyond the noise.
    NotBeyondNoise { refitted_share: f64 },
    /// Refitted without each fold, the model with it predicts these folds
    /// (their labels) worse than the baseline does, these worse than the
    /// model before it, and the response (the peaks' and the phase's mean
    /// and variance) at these worse than the baseline does, beyond each
    /// fold's noise and beyond what its form leaves of that fold fitted to
    /// every unit; `response_over_every_fold`: the response over every
    /// withheld fold together worse than the baseline, beyond the noise of
    /// that pooled mean. Its form does not carry over to the conditions it
    /// was not fitted on.
    WorseFolds {
        than_baseline: Vec<String>,
        than_model_before: Vec<String>,
        #[serde(default)]
        response_than_baseline: Vec<String>,
        #[serde(default)]
        response_over_every_fold: bool,
    },
}

/// Everything a diagnosis found.
#[derive(Clone, Debug)]
pub struct Diagnosis {
    pub baseline: Model,
    pub fitted: Model,
    /// The leading effect named; `None` when the baseline explains the data.
    pub verdict: Option<Effect>,
    /// Every effect named, in the order they were added.
    pub effects: Vec<NamedEffect>,
    /// –, in [0, 1].
    pub confidence: f64,
    /// The baseline's and the fitted model's scores on every unit.
    pub baseline_scores: Vec<Score>,
    pub fitted_scores: Vec<Score>,
    /// The baseline's gap over every unit (in sample), –.
    pub gap_fit: f64,
    /// The fitted model's gap over every unit (in sample), –.
    pub gap_after: f64,
    /// Out of sample: the gaps of the baseline and of the fitted model, each
    /// fold predicted by the model refitted without it, –; `None` without
    /// folds.
    pub cv_gaps: Option<(f64, f64)>,
    /// Per fold: those two gaps at the fold's units.
    pub fold_gaps: Vec<FoldGap>,
    /// The share of the baseline's explainable out-of-sample gap left after
    /// the named effects, –.
    pub unexplained_share: f64,
    /// Every family of the first round, most wins first.
    pub candidates: Vec<Candidate>,
    /// The out-of-sample gap's noise threshold, –.
    pub noise_threshold: f64,
    /// How the set was cut into folds.
    pub folds: Folds,
    /// The folds the first round's families were judged on: `folds`, or
    /// folds crossed over loads and frequencies where no family predicts a
    /// withheld level beyond the noise and the set holds out load levels
    /// at several frequencies.
    pub attribution_folds: Folds,
    /// Where the baseline misfits beyond what the named effects explain.
    pub misfit: Option<Misfit>,
    /// The first family that led a round and is not named, where one did.
    pub refused: Option<Refusal>,
    /// Where nothing is named: each family's power to show itself in these
    /// records at its smallest size of interest (empty otherwise).
    pub powers: Vec<search::power::Power>,
    pub conditions: Vec<Condition>,
    /// The baseline and the fitted model refitted without each fold (for
    /// checks against a known truth at a withheld level).
    pub fold_models: Vec<(Model, Model)>,
    /// What the reader of the report should know about how the data were
    /// read (time frames, observables set aside).
    pub notes: Vec<String>,
    /// The channels derived from the displacement ([`derived`]).
    pub derived_channels: derived::DerivedChannels,
}

impl Diagnosis {
    /// The verdict's name: the leading effect's, or `none`.
    pub fn verdict_name(&self) -> &'static str {
        self.verdict.map_or("none", Effect::name)
    }

    /// The names of every effect of the verdict, joined by " + ", or `none`.
    pub fn verdict_names(&self) -> String {
        if self.effects.is_empty() {
            return "none".into();
        }
        self.effects.iter().map(|e| e.effect.name()).collect::<Vec<_>>().join(" + ")
    }
}

/// Where the simulated replicates' records lie on a drift's clock, s: from
/// the end of the warm-up, where the clock starts, for the longest record's
/// length. What a drift's nominal force is the mean over, in a fitted
/// model and in the power's reference.
pub(crate) fn records_window_s(data: &Data<'_>) -> [f64; 2] {
    [0.0, data.longest_record_s.max(1e-3)]
}

/// Whether tracing is on (`STICKSLIP_DEBUG` set): every trial, decision
/// and calibration step is printed to stderr.
pub(crate) fn tracing() -> bool {
    std::env::var_os("STICKSLIP_DEBUG").is_some()
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
    let thinned = settings.sample_rate_hz.map(|rate_hz| crate::measure::thinned(set, rate_hz)).transpose()?;
    let set = thinned.as_ref().map_or(set, |(set, _)| set);
    let (with_derived, derived) = derived::with_derived_channels(set);
    let set = with_derived.as_ref().unwrap_or(set);
    let mut data = Data::new(set, derived)?;
    let mut notes = frame::frame_notes(&data);
    notes.extend(derived.note());
    if let (Some((_, n @ 1..)), Some(rate_hz)) = (&thinned, settings.sample_rate_hz) {
        notes.push(format!(
            "{n} of {} runs were thinned to {rate_hz} Hz (every k-th sample kept) before the diagnosis: the \
             baseline's noise is held over 1/{rate_hz} s",
            set.runs.len()
        ));
    }
    notes.extend(frame::still_channel_notes(&data));
    notes.extend(frame::displacement_offset_note(&data));
    notes.extend(frame::friction_offset_note(&data));
    notes.extend(law::implausible_law_note(data.measured_law.as_ref()));
    let rates = if calibrate::searches_rate(&data) {
        format!(" at {} Stribeck rates (a force derived from x does not give it)", calibrate::DERIVED_RATES_TRIED)
    } else {
        String::new()
    };
    progress(&format!("calibrating the baseline{rates} (folds: {})", data.folds.describe()));
    let (baseline, mut baseline_scores, slope) =
        calibrate::calibrate_baseline(&data, settings, engine).map_err(|e| calibrate::named_by_manifest(&data, e))?;
    notes.extend(calibrate::assumed_normal_force_noise_note(&data, &baseline));
    for (note, line) in frame::check_phases(&mut data, &baseline_scores) {
        progress(line);
        notes.push(note);
        baseline_scores.retain(|s| data.measured[s.unit].contains_key(&s.observable));
    }
    if !data.folds.any() {
        notes.push(
            "nothing could be held out (one run of one condition), so no effect can be tested out of sample \
             and none is named: the confidence of `none` says only how well the baseline fits the data in \
             sample; more runs, frequencies or loads let effects be tested"
                .into(),
        );
    }
    let selection = search::select(&baseline, slope, &data, settings, engine, progress)?;
    let effects: Vec<NamedEffect> = selection
        .steps
        .iter()
        .map(|s| NamedEffect {
            effect: s.candidate.effect,
            form: s.candidate.form,
            parameters: s.candidate.parameters.clone(),
            share: s.share,
            form_misfit: (1.0 - s.share).clamp(0.0, 1.0),
            confidence: s.confidence,
            folds: data
                .folds
                .folds
                .iter()
                .zip(&s.folds)
                .map(|(f, r)| FoldGap { label: f.label.clone(), before: r.gap_before, after: r.gap_after })
                .collect(),
        })
        .collect();
    for c in &selection.misfit_folds {
        let label = &data.folds.folds[c.fold].label;
        notes.push(format!(
            "refitted without {label}, the fitted model predicts {} there worse than the baseline does (mean loss \
             {:.2} against {:.2}), and about as closely as its form fits {label} when fitted to it too ({:.2}): \
             that is the form's misfit there, not a failed prediction, and predictions at {label} from the fitted \
             model carry it",
            if c.response { "the response (the peaks' and the phase's mean and variance)" } else { "the data" },
            c.rise.model,
            c.rise.other,
            c.rise.own_fit.unwrap_or(f64::NAN)
        ));
    }
    let (mut fitted, fitted_scores) = match &selection.named_model {
        Some(named) => (named.full.model.clone(), named.full.scores.clone()),
        None => (baseline.clone(), baseline_scores.clone()),
    };
    // A drift fitted to records whose nominal force is their measured mean
    // means the same in the model file: the nominal force is the mean over
    // the records' window (from the end of the warm-up, where the drift's
    // clock starts, for the records' length), and a sweep at it gives it.
    if let Some(d) = fitted.effects.normal_force_drift.as_mut() {
        d.mean_over_s = Some(records_window_s(&data));
    }
    let fitted_folds = selection.fitted_folds();
    let fold_gaps: Vec<FoldGap> = (0..data.folds.folds.len())
        .map(|k| {
            let units = data.folds.folds[k].units.iter().copied();
            let (before, after) =
                search::pair_gaps(&selection.baseline_folds[k].scores, &fitted_folds[k].scores, &data, units);
            FoldGap { label: data.folds.folds[k].label.clone(), before, after }
        })
        .collect();
    let cv_gaps = data.folds.any().then(|| {
        // Every unit is held out once: weighted by each fold's scores.
        let counts: Vec<f64> = data
            .folds
            .folds
            .iter()
            .map(|f| f.units.iter().map(|&u| data.measured[u].len() as f64).sum::<f64>())
            .collect();
        let total: f64 = counts.iter().sum::<f64>().max(1.0);
        let weighted =
            |g: fn(&FoldGap) -> f64| fold_gaps.iter().zip(&counts).map(|(f, n)| g(f) * n).sum::<f64>() / total;
        (weighted(|f| f.before), weighted(|f| f.after))
    });
    let floor = selection.null.mean;
    let in_sample = search::pair_gaps(&baseline_scores, &fitted_scores, &data, 0..data.units.len());
    let gaps = [in_sample.0, in_sample.1].into_iter().chain(cv_gaps.into_iter().flat_map(|(b, a)| [b, a]));
    if gaps.chain(fold_gaps.iter().flat_map(|f| [f.before, f.after])).any(|g| !g.is_finite()) {
        // Name the first score that overflows: which observable, where, and
        // what the model made of it (a spread of 0 where the data move, say).
        let culprit = baseline_scores.iter().chain(&fitted_scores).find(|s| !(s.z * s.z).is_finite()).map_or_else(
            String::new,
            |s| {
                format!(
                    "; first at {} Hz, {} N: {} measured {:.4e} against {:.4e} simulated with a spread of {:.4e}",
                    s.excitation_frequency_hz, s.normal_force_n, s.observable, s.measured, s.simulated, s.scale
                )
            },
        );
        return Err(crate::Error::Measurement {
            file: set.dir.clone(),
            line: None,
            message: format!(
                "the gap between the set and the model is not a finite number (baseline {} -> after {}): a \
                 measured value lies where the scores overflow, so there is no result to report{culprit}",
                in_sample.0, in_sample.1
            ),
        });
    }
    let unexplained_share = match cv_gaps {
        Some((before, after)) => ((after - floor).max(0.0) / (before - floor).max(1e-9)).clamp(0.0, 1.0),
        None => 1.0,
    };
    let named: Vec<Effect> = effects.iter().map(|e| e.effect).collect();
    let mut misfit =
        misfit::misfit_of(&fitted_scores, search::cv::NullLoss::for_replicates(settings.replicates), &named);
    if let Some(m) = misfit.as_mut() {
        m.hints.extend(misfit::fitting_only_hints(&selection.first_round, &named, selection.noise));
    }
    if let Some((above, noise)) = selection.left_after_most {
        notes.push(format!(
            "{} effects were named, the most a verdict names; the model with them still leaves an out-of-sample \
             gap {above:.2} above the floor of a right model (beyond its noise threshold, {noise:.2}), and that \
             is not pinned on a further family: `verdict.misfit` lists what it misses and the families whose \
             signatures stand out there",
            named.len()
        ));
    }
    let blind: Vec<String> = selection
        .powers
        .iter()
        .filter(|p| !p.could_show())
        .map(|p| format!("{} ({}: power {:.2})", p.effect, p.reference, p.power))
        .collect();
    if !blind.is_empty() {
        notes.push(format!(
            "nothing is named, but these records could not have shown {}: the `none` does not rule {} out, and \
             its confidence is at most the least of these powers; records where such an effect would move what \
             is measured (for a stiction, conditions where the block sticks) can test it",
            blind.join("; "),
            if blind.len() == 1 { "it" } else { "them" }
        ));
    }
    let (verdict, confidence) = match effects.first() {
        Some(e) => (Some(e.effect), e.confidence),
        None => (None, selection.none_confidence),
    };
    let mut conditions: Vec<Condition> = data.units.iter().map(|u| u.condition).collect();
    conditions.dedup_by_key(|c| condition_key(*c));
    let fold_models =
        selection.baseline_folds.iter().zip(&fitted_folds).map(|(b, f)| (b.model.clone(), f.model.clone())).collect();
    Ok(Diagnosis {
        baseline,
        fitted,
        verdict,
        effects,
        confidence,
        gap_fit: in_sample.0,
        gap_after: in_sample.1,
        cv_gaps,
        fold_gaps,
        unexplained_share,
        baseline_scores,
        fitted_scores,
        candidates: selection.first_round,
        noise_threshold: selection.noise,
        folds: data.folds.clone(),
        attribution_folds: selection.attribution_folds.clone(),
        misfit,
        refused: selection.refused,
        powers: selection.powers,
        conditions,
        fold_models,
        notes,
        derived_channels: data.derived,
    })
}
