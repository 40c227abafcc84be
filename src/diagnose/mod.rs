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
pub mod features;
mod frame;
pub mod law;
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
use crate::measure::{MeasurementSet, read_measurement_set};
use data::{Data, Folds, condition_key};
use observable::Observable;
use score::{Scope, Score};

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

/// Where the calibrated baseline misfits in a way no effect explains.
#[derive(Clone, Debug, Serialize)]
pub struct Misfit {
    /// The observables whose mean Huber loss over the fitting units is
    /// furthest above noise, worst first.
    pub observables: Vec<MisfitObservable>,
    /// What that pattern points at, in words.
    pub hints: Vec<String>,
}

/// One observable the baseline misfits.
#[derive(Clone, Debug, Serialize)]
pub struct MisfitObservable {
    pub observable: Observable,
    /// Mean z over the fitting units (sign: measured above simulated), –.
    pub mean_z: f64,
    /// Mean loss ln(1 + z²) over the units, –.
    pub mean_loss: f64,
    /// How many units it is scored at.
    #[serde(skip)]
    pub count: usize,
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
    /// fold's noise; `response_over_every_fold`: the response over every
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
    pub conditions: Vec<Condition>,
    /// The baseline and the fitted model refitted without each fold (for
    /// checks against a known truth at a withheld level).
    pub fold_models: Vec<(Model, Model)>,
    /// What the reader of the report should know about how the data were
    /// read (time frames, observables set aside).
    pub notes: Vec<String>,
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

/// What a misfit of an observable points at: the parameters of the
/// baseline it moves with, or the effect whose form-agnostic signature it
/// is (so a misfit that no candidate's form closed still names where to
/// look). Every observable has one.
fn misfit_hint(o: Observable) -> &'static str {
    use Observable as O;
    match o {
        O::FrictionMuMean | O::FrictionLowSpeedMuMean => "the friction law's level (a, b, c, d) or its load dependence",
        O::FrictionResidualStd => "the friction noise level sigma_mu",
        O::PeakMeanM | O::PhaseMeanDeg => "the friction level a or the rig (mass, stiffness, damping, base amplitude)",
        O::PeakVarM2 | O::PhaseVarDeg2 | O::PeakSkewness => "the friction noise (its level or its spectrum)",
        O::NormalForceMeanN | O::NormalForceVarN2 | O::NormalForceResidualVarN2 => {
            "the normal-force noise sigma_N or N0"
        }
        O::StickFraction | O::FrictionBreakawayMean | O::FrictionStictionExcess | O::FrictionSlipSamples => {
            "the friction near zero speed (the Stribeck drop b, c, or stiction)"
        }
        O::FrictionHysteresis => {
            "a friction memory: the accelerating and decelerating branches of mu(v) differ (friction_hysteresis, perhaps in a form no candidate has)"
        }
        O::FrictionResidualAutocorrLag1 | O::FrictionResidualAutocorrLag10 => {
            "friction that remembers beyond one noise interval: coloured friction noise or a friction memory"
        }
        O::FrictionResidualSkewness | O::FrictionResidualTailWeight => {
            "the friction noise's distribution (skew or heavy tails: non_gaussian_friction)"
        }
        O::NormalForceHarmonic1N | O::NormalForceHarmonic2N | O::NormalForceHarmonic3N | O::NormalForceHarmonic4N => {
            "a normal force that varies with the excitation (normal_force_harmonics)"
        }
        O::NormalForceDriftNPerS | O::NormalForceDriftPerS | O::NormalForceCurvaturePerS2 | O::PeakTrendPerS => {
            "a slow change over the record (normal_force_drift, or wear)"
        }
        O::NormalForceWander => {
            "a normal force that wanders slowly over the record (normal_force_drift random_walk, or wear)"
        }
        O::PeakCount => "the record's length or the excitation frequency (a peak per period)",
    }
}

/// The fitted model's misfit by observable, when it is beyond `noise`,
/// with a hint for each of the worst observables and one for every effect
/// family whose form-agnostic signature still stands out of the noise
/// ([`candidates::signature_excess`]): where to look when no candidate's
/// form explained the gap.
fn misfit_of(scores: &[Score], null: search::cv::NullLoss, named: &[Effect]) -> Option<Misfit> {
    let mut by: BTreeMap<Observable, Vec<f64>> = BTreeMap::new();
    for s in scores.iter().filter(|s| !s.heldout) {
        by.entry(s.observable).or_default().push(s.z);
    }
    let mut worst: Vec<MisfitObservable> = by
        .into_iter()
        .map(|(observable, z)| MisfitObservable {
            observable,
            mean_z: mean(&z),
            mean_loss: mean(&z.iter().map(|&z| search::cv::loss(z)).collect::<Vec<_>>()),
            count: z.len(),
        })
        .filter(|m| m.mean_loss - null.mean > null.noise(m.count))
        .collect();
    let mut families: Vec<(Effect, f64)> = Effect::ALL
        .into_iter()
        .filter(|e| !named.contains(e))
        .map(|e| (e, candidates::signature_excess(e, scores)))
        .filter(|(_, x)| *x > candidates::SIGNATURE_STANDS_OUT)
        .collect();
    families.sort_by(|a, b| b.1.total_cmp(&a.1));
    if worst.is_empty() && families.is_empty() {
        return None;
    }
    worst.sort_by(|a, b| b.mean_loss.total_cmp(&a.mean_loss));
    worst.truncate(6);
    let mut hints: Vec<String> = worst
        .iter()
        .map(|m| {
            format!(
                "{} ({} {})",
                misfit_hint(m.observable),
                m.observable.name(),
                if m.mean_z > 0.0 { "measured above simulated" } else { "measured below simulated" }
            )
        })
        .collect();
    hints.extend(
        families
            .iter()
            .map(|(e, x)| format!("the signature of {e} stands {x:.0} noise units out of the noise: {}", e.meaning())),
    );
    Some(Misfit { observables: worst, hints })
}

/// A hint for each family of the first round, not named, that closes
/// more of the baseline's gap in sample than `noise` (the out-of-sample
/// noise threshold of the gap) but none of it at the withheld folds: what
/// it fits at some folds does not carry over to the others, which the
/// user should hear about rather than see only `none`.
fn fitting_only_hints(first_round: &[Candidate], named: &[Effect], noise: f64) -> Vec<String> {
    first_round
        .iter()
        .filter(|c| !named.contains(&c.effect) && c.cv_share <= 0.0 && c.shrink < 1.0)
        .filter(|c| c.gap_fit / (1.0 - c.shrink) - c.gap_fit > noise)
        .map(|c| {
            let example = match c.effect {
                Effect::LoadDependentFriction => {
                    " (as when the friction changes between two of the loads measured and holds beyond them: \
                     more load levels between those two would tell)"
                }
                _ => "",
            };
            format!(
                "{} ({}) closes {:.0}% of the baseline's gap in sample but none of it at the withheld folds \
                 ({:+.0}%): what it fits at some folds does not carry over to the others{example}",
                c.effect,
                c.form,
                100.0 * c.in_sample_share,
                100.0 * c.cv_share
            )
        })
        .collect()
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
    let mut data = Data::new(set)?;
    let mut notes = frame::frame_notes(&data);
    progress(&format!("calibrating the baseline (folds: {})", data.folds.describe()));
    let (baseline, baseline_scores, slope) = calibrate::calibrate_and_score(
        &calibrate::initial_baseline(&data)?,
        &data,
        settings,
        engine,
        None,
        0,
        Scope::All,
    )?;
    let (baseline, mut baseline_scores) = calibrate::converge_law(baseline, baseline_scores, &data, settings, engine)?;
    if let Some(note) = frame::check_phases(&mut data, &baseline_scores) {
        progress("the records' phases look as if their time origin were free; their phase means are set aside");
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
    let (mut fitted, fitted_scores) = match selection.steps.last() {
        Some(last) => (last.candidate.model.clone(), last.candidate.scores.clone()),
        None => (baseline.clone(), baseline_scores.clone()),
    };
    // A drift fitted to records whose nominal force is their measured mean
    // means the same in the model file: the nominal force is the mean over
    // the records' window (the replicates' warm-up at the data's mean
    // frequency, then the records' length), and a sweep at it gives it.
    if let Some(d) = fitted.effects.normal_force_drift.as_mut() {
        let frequency = mean(&data.units.iter().map(|u| u.condition.excitation_frequency_hz).collect::<Vec<_>>());
        let start = f64::from(settings.warmup_cycles) / frequency.max(1e-9);
        d.mean_over_s = Some([start, start + data.longest_record_s.max(1e-3)]);
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
    let mut misfit = misfit_of(&fitted_scores, search::cv::NullLoss::for_replicates(settings.replicates), &named);
    if let Some(m) = misfit.as_mut() {
        m.hints.extend(fitting_only_hints(&selection.first_round, &named, selection.noise));
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
        conditions,
        fold_models,
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::{Candidate, Effect, Observable, Score, fitting_only_hints, misfit_of};

    /// A fitting score of `observable` at unit `unit` with z = `z`.
    fn fitting_score(unit: usize, observable: Observable, z: f64) -> Score {
        crate::diagnose::score::test_score(unit, observable, z, false)
    }

    /// A friction memory in a form no candidate has leaves the branch
    /// asymmetry and the residual's autocorrelation far off: each misfit
    /// observable says where to look, worst first, and so does the family
    /// whose signature stands out.
    #[test]
    fn every_misfit_observable_and_family_says_where_to_look() {
        let scores = [
            fitting_score(0, Observable::FrictionHysteresis, -135.0),
            fitting_score(0, Observable::FrictionResidualAutocorrLag1, 113.0),
            fitting_score(0, Observable::PeakMeanM, 0.5),
        ];
        let null = crate::diagnose::search::cv::NullLoss { mean: 0.6, sd: 0.6 };
        let misfit = misfit_of(&scores, null, &[]).expect("a misfit beyond the noise");
        assert_eq!(misfit.observables.len(), 2, "the peak mean is within the noise");
        assert!(misfit.hints[0].contains("friction memory") && misfit.hints[0].contains("measured below simulated"));
        assert!(misfit.hints[1].contains("coloured friction noise"));
        assert!(misfit.hints.iter().any(|h| h.contains("signature of friction_hysteresis")), "{:?}", misfit.hints);
        // A named family is not pointed at again.
        let misfit = misfit_of(&scores, null, &[Effect::FrictionHysteresis]).expect("a misfit");
        assert!(!misfit.hints.iter().any(|h| h.contains("signature of friction_hysteresis")));
    }

    /// A first-round family with `shrink` of the gap `gap_before` in sample
    /// and `cv_share` out of sample.
    fn candidate(effect: Effect, gap_before: f64, shrink: f64, cv_share: f64) -> Candidate {
        Candidate {
            effect,
            form: crate::diagnose::candidates::SearchedForm::Linear,
            gap_fit: gap_before * (1.0 - shrink),
            shrink,
            in_sample_share: shrink,
            cv_share,
            heldout_shrink: cv_share,
            wins: 0.0,
            refined: true,
            parameters: Default::default(),
            unexplained: Vec::new(),
            model: Default::default(),
            scores: Vec::new(),
        }
    }

    /// A family that fits the data in sample but predicts no withheld fold
    /// is pointed at, unless it is named, its fall is within the noise, or
    /// it predicts the withheld folds too.
    #[test]
    fn a_family_that_fits_only_in_sample_is_pointed_at() {
        let noise = 0.06;
        let round = [
            candidate(Effect::LoadDependentFriction, 1.4, 0.3, -0.05),
            candidate(Effect::Stiction, 1.4, 0.02, -0.01),
            candidate(Effect::NormalForceDrift, 1.4, 0.3, 0.2),
        ];
        let hints = fitting_only_hints(&round, &[], noise);
        assert_eq!(hints.len(), 1, "{hints:?}");
        assert!(hints[0].starts_with("load_dependent_friction (linear) closes 30%") && hints[0].contains("(-5%)"));
        assert!(fitting_only_hints(&round, &[Effect::LoadDependentFriction], noise).is_empty());
    }
}
