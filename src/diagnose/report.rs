//! The diagnosis's outputs: `report.json` (the contract of `interfaces.md`,
//! written from the serde structs below, plus extra keys), the two model
//! files, and an HTML report with its chart. Every file is written
//! atomically; nothing is written when the diagnosis fails.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::diagnose::candidates::parameter_meaning;
use crate::diagnose::observable::Observable;
use crate::diagnose::score::Score;
use crate::diagnose::search::power::Power;
use crate::diagnose::{Diagnosis, FoldGap, RefusalReason, Unexplained, chart, sd};
use crate::engine::effects::HysteresisForm;
use crate::error::{Error, Result};
use crate::io::{OutputSet, owned, write_atomically};

/// The format tag of `report.json`.
pub const REPORT_FORMAT: &str = "stickslip-diagnosis/1";

/// What the gap metric measures, as `report.json` states it.
pub const GAP_METRIC: &str = "mean over (condition, observable) of ln(1 + z²), z = (measured − simulated)/(the spread of their difference under the simulator; after: under the fitted model, the baseline measured in the same spread); about 0.6 for a model that is right; baseline/after over every unit with models fitted to every unit; heldout_* over every unit with each fold predicted by models fitted without it";

/// `report.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// Always [`REPORT_FORMAT`].
    pub format: String,
    pub verdict: VerdictReport,
    pub gap: GapReport,
    /// Where the calibrated baseline departs from the data (|z| > 3), largest first.
    pub locations: Vec<Location>,
    /// Every effect tried in the first round, most wins first.
    pub candidates: Vec<CandidateReport>,
    pub models: ModelFiles,
    /// The measurement set diagnosed.
    pub source: String,
    /// Run time of the diagnosis, s.
    pub elapsed_s: f64,
    /// How the data were read (time frames, observables set aside).
    #[serde(default)]
    pub notes: Vec<String>,
    /// The channels derived from the displacement because no run records
    /// them (all false for a set that records them, or for summary rows).
    #[serde(default)]
    pub derived_channels: crate::diagnose::derived::DerivedChannels,
}

/// How the confidence is defined, as `report.json` states it.
pub const CONFIDENCE_MEANING: &str = "the share of 2000 bootstrap resamples of the conditions (drawn with replacement) that give this verdict, times the share of the baseline's explainable out-of-sample gap the named effects close, or each named effect's margin over the best rival family of its round where that is smaller, over one half (at most 1): an effect is named in a resample when its family closes the largest share of the current model's explainable out-of-sample gap beyond the noise and the model with it and the effects named before it predicts every withheld fold no worse than the baseline (up to the noise, and to what its form leaves of that fold when fitted to it too), over every observable and over the response's (peaks and phase) alone, and the response over every withheld fold together no worse than the baseline (the last named effect also no worse than the model before it); `none` where no effect is named, and a `none` beside a gap far above its noise is divided by the square root of how many noise thresholds it stands above; where nothing can be held out (one run of one condition), `none` is judged so on the baseline's gap in sample; and a `none` is at most the least of `verdict.power`, each effect family's chance, at the smallest size of interest, of raising the baseline's gap above that noise in these records";

/// `verdict`: the effect named (`none` when the baseline explains the data).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VerdictReport {
    /// The leading effect (the contract's key).
    pub effect: String,
    /// –, in [0, 1] (see `confidence_meaning`).
    pub confidence: f64,
    /// What the confidence is.
    #[serde(default)]
    pub confidence_meaning: String,
    /// Every effect named, in the order they were added (empty for `none`).
    #[serde(default)]
    pub effects: Vec<VerdictEffect>,
    /// The share of the baseline's explainable out-of-sample gap (its gap
    /// less the noise floor of about 1.3) that the named effects leave, –.
    #[serde(default)]
    pub unexplained_share: f64,
    /// Where the fitted model still misfits beyond noise: which
    /// observables, what that points at, and every effect family whose
    /// signature still stands out. Absent when it fits.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub misfit: Option<MisfitReport>,
    /// The first family that led a round of the selection and is not
    /// named, and why; absent where every leader is named.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refused: Option<RefusedReport>,
    /// Where nothing is named: how surely these records would have shown
    /// each effect family at its smallest size of interest; absent where
    /// an effect is named.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub power: Vec<Power>,
}

/// A family that led a round and is not named ([`crate::diagnose::Refusal`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RefusedReport {
    pub effect: String,
    /// The form of its best full-data fit, as in the model file.
    pub form: String,
    /// The share of what the effects named before it left of the
    /// explainable out-of-sample gap that its family closed, –.
    pub share_of_gap: f64,
    /// How many effects are named before it.
    pub after_named: usize,
    pub reason: RefusalReason,
}

/// One effect of the verdict.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VerdictEffect {
    pub effect: String,
    /// The form that fitted best, as in the model file.
    pub form: String,
    /// –, in [0, 1].
    pub confidence: f64,
    /// The share of what the model before it left of the out-of-sample
    /// gap (above the noise floor) that this effect closed, each fold
    /// predicted by models refitted without it, –.
    pub share_of_gap: f64,
    /// What the effect's best form leaves of that gap (1 − share), –: the
    /// data's effect has a shape no candidate form has exactly.
    #[serde(default)]
    pub form_misfit: f64,
    /// Per fold: the gap at its units without and with the effect.
    #[serde(default)]
    pub folds: Vec<FoldReport>,
    /// The fitted parameters by name (names carry units).
    pub parameters: BTreeMap<String, f64>,
    /// A load dependence in physical terms: the friction coefficient at
    /// rest at each measured load, baseline and fitted (empty for other
    /// effects).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub friction_at_loads: Vec<FrictionAtLoad>,
}

/// The friction coefficient at rest, μ(0) = a + b with the load dependence
/// applied (an adhesion force A counted as A/N0), at one measured load.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrictionAtLoad {
    /// The nominal normal force, N.
    pub normal_force_n: f64,
    /// The calibrated baseline's μ(0) there, –.
    pub baseline_mu: f64,
    /// The fitted model's μ(0) there, –.
    pub fitted_mu: f64,
    /// The standard deviation of μ(0) over the models refitted without each
    /// fold, –: how much the fitted value depends on which loads it saw;
    /// absent with fewer than two folds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fitted_mu_sd: Option<f64>,
}

/// μ(0) of `model` at nominal load `n0_n` (N): see [`FrictionAtLoad`].
fn mu_at_rest(model: &crate::engine::Model, n0_n: f64) -> f64 {
    let law = model.friction.a + model.friction.b;
    let e = crate::engine::effects::EffectParams::new(&model.effects, n0_n, law, model.noise.interval_s);
    law * e.friction_scale + e.friction_offset + e.adhesion_force_n / n0_n.max(1e-9)
}

/// The friction at each measured load, for a named load dependence.
fn friction_at_loads(d: &Diagnosis) -> Vec<FrictionAtLoad> {
    let mut loads: Vec<f64> = d.conditions.iter().map(|c| c.normal_force_n).collect();
    loads.sort_by(f64::total_cmp);
    loads.dedup();
    loads
        .into_iter()
        .map(|n| {
            let folds: Vec<f64> = d.fold_models.iter().map(|(_, after)| mu_at_rest(after, n)).collect();
            FrictionAtLoad {
                normal_force_n: n,
                baseline_mu: mu_at_rest(&d.baseline, n),
                fitted_mu: mu_at_rest(&d.fitted, n),
                fitted_mu_sd: (folds.len() >= 2).then(|| sd(&folds)),
            }
        })
        .collect()
}

/// One fold's gap before and after.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FoldReport {
    /// What the fold holds out.
    pub heldout: String,
    pub before: f64,
    pub after: f64,
    /// `(before − after) / before`, –.
    pub shrink: f64,
}

/// `verdict.misfit`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MisfitReport {
    pub observables: Vec<MisfitObservableReport>,
    pub hints: Vec<String>,
}

/// One observable the model misfits: its mean z and mean Huber loss over
/// every unit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MisfitObservableReport {
    pub observable: Observable,
    pub mean_z: f64,
    pub mean_loss: f64,
}

/// `gap`: the gap metric before and after the verdict's effects.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GapReport {
    pub metric: String,
    /// The calibrated baseline's gap over every unit (fitted to them all).
    pub baseline: f64,
    /// The fitted model's gap over every unit.
    pub after: f64,
    /// `(baseline − after) / baseline`, –.
    pub shrink: f64,
    /// The same out of sample (each fold predicted by the models refitted
    /// without it), and the out-of-sample gaps before and after; absent
    /// where nothing could be held out (`heldout_units` says so), so that
    /// no number is `null`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heldout_shrink: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heldout_baseline: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heldout_after: Option<f64>,
    /// `heldout_shrink` fold by fold.
    #[serde(default)]
    pub heldout_folds: Vec<FoldReport>,
    /// The standard deviation of the folds' shrinks, –; absent with fewer
    /// than two folds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heldout_shrink_sd: Option<f64>,
    /// The out-of-sample gap's noise threshold: a gap within it of the
    /// floor (about 1.3) has nothing to explain.
    pub noise_threshold: f64,
    /// How the units were cut into folds.
    #[serde(default)]
    pub heldout_units: String,
    /// The folds each family's out-of-sample share (`candidates[].cv_share`)
    /// was measured on: the same as `heldout_units`, or, where no family
    /// predicts a withheld level beyond the noise and the units are load
    /// levels at several frequencies, conditions crossed over loads and
    /// frequencies (so that an effect seen at one load can be learned).
    #[serde(default)]
    pub attribution_units: String,
}

/// One place the baseline departs from the data.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Location {
    /// Hz
    pub excitation_frequency_hz: f64,
    /// N
    pub normal_force_n: f64,
    pub observable: Observable,
    pub detail: String,
    /// |z|, –.
    pub score: f64,
}

/// One candidate effect family of the first round.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CandidateReport {
    pub effect: String,
    /// The form that fitted best.
    #[serde(default)]
    pub form: String,
    /// The relative fall of the gap over every unit with its best fit, –.
    pub shrink: f64,
    /// The relative fall of the out-of-sample gap, –; absent where nothing
    /// could be held out.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heldout_shrink: Option<f64>,
    /// The share of the explainable gap closed in sample and out of sample, –.
    #[serde(default)]
    pub share_in_sample: f64,
    #[serde(default)]
    pub share_out_of_sample: f64,
    /// The share of bootstrap resamples it won, –.
    #[serde(default)]
    pub wins: f64,
    /// Whether it was searched in full (else coarsely).
    #[serde(default)]
    pub searched_in_full: bool,
    pub gap_fit: f64,
    /// The fitted parameters by name (names carry units).
    pub parameters: BTreeMap<String, f64>,
    /// The five largest |z| the candidate leaves.
    pub unexplained: Vec<UnexplainedReport>,
}

/// One (condition, observable) a candidate leaves unexplained.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct UnexplainedReport {
    pub observable: Observable,
    pub excitation_frequency_hz: f64,
    pub normal_force_n: f64,
    pub z: f64,
}

/// `models`: the two model files beside the report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelFiles {
    pub baseline: String,
    pub fitted: String,
}

impl Report {
    /// Refuses a report that would hold a number that is not finite: JSON
    /// has none (it would be written as `null`, where a number is promised).
    /// Written and read back, the report must be itself.
    pub fn check_numbers(&self) -> Result<()> {
        let text = serde_json::to_string(self).map_err(|e| Error::Mismatch(format!("report.json: {e}")))?;
        match serde_json::from_str::<Report>(&text) {
            Ok(back) if back == *self => Ok(()),
            _ => Err(Error::Mismatch(format!(
                "the diagnosis of {} gave a number that is not finite (gap {} -> {}): the data lie where the \
                 scores overflow; nothing was written",
                self.source, self.gap.baseline, self.gap.after
            ))),
        }
    }
}

impl From<&Unexplained> for UnexplainedReport {
    fn from(u: &Unexplained) -> Self {
        UnexplainedReport {
            observable: u.observable,
            excitation_frequency_hz: u.excitation_frequency_hz,
            normal_force_n: u.normal_force_n,
            z: u.z,
        }
    }
}

impl From<&FoldGap> for FoldReport {
    fn from(f: &FoldGap) -> Self {
        FoldReport { heldout: f.label.clone(), before: f.before, after: f.after, shrink: f.shrink() }
    }
}

impl Diagnosis {
    /// `report.json` as `interfaces.md` describes it (plus extra keys).
    pub fn report(&self, source: &Path, elapsed_s: f64) -> Report {
        let shrink = if self.gap_fit > 0.0 { (self.gap_fit - self.gap_after) / self.gap_fit } else { 0.0 };
        let heldout_shrink = self.cv_gaps.map(|(b, a)| if b > 0.0 { (b - a) / b } else { 0.0 });
        let fold_shrinks: Vec<f64> = self.fold_gaps.iter().map(FoldGap::shrink).collect();
        let mut locations: Vec<&Score> = self.baseline_scores.iter().filter(|s| s.z.abs() > 3.0).collect();
        locations.sort_by(|a, b| b.z.abs().total_cmp(&a.z.abs()));
        Report {
            format: REPORT_FORMAT.to_string(),
            verdict: VerdictReport {
                effect: self.verdict_name().to_string(),
                confidence: self.confidence,
                confidence_meaning: CONFIDENCE_MEANING.to_string(),
                effects: self
                    .effects
                    .iter()
                    .map(|e| VerdictEffect {
                        effect: e.effect.name().to_string(),
                        form: e.form.to_string(),
                        confidence: e.confidence,
                        share_of_gap: e.share,
                        form_misfit: e.form_misfit,
                        folds: e.folds.iter().map(FoldReport::from).collect(),
                        parameters: e.parameters.clone(),
                        friction_at_loads: if e.effect == crate::engine::Effect::LoadDependentFriction {
                            friction_at_loads(self)
                        } else {
                            Vec::new()
                        },
                    })
                    .collect(),
                unexplained_share: self.unexplained_share,
                misfit: self.misfit.as_ref().map(|m| MisfitReport {
                    observables: m
                        .observables
                        .iter()
                        .map(|o| MisfitObservableReport {
                            observable: o.observable,
                            mean_z: o.mean_z,
                            mean_loss: o.mean_loss,
                        })
                        .collect(),
                    hints: m.hints.clone(),
                }),
                refused: self.refused.as_ref().map(|r| RefusedReport {
                    effect: r.effect.name().to_string(),
                    form: r.form.to_string(),
                    share_of_gap: r.share_of_gap,
                    after_named: r.after_named,
                    reason: r.reason.clone(),
                }),
                power: self.powers.clone(),
            },
            gap: GapReport {
                metric: GAP_METRIC.to_string(),
                baseline: self.gap_fit,
                after: self.gap_after,
                shrink,
                heldout_shrink,
                heldout_baseline: self.cv_gaps.map(|g| g.0),
                heldout_after: self.cv_gaps.map(|g| g.1),
                heldout_folds: self.fold_gaps.iter().map(FoldReport::from).collect(),
                heldout_shrink_sd: (fold_shrinks.len() >= 2).then(|| sd(&fold_shrinks)),
                noise_threshold: self.noise_threshold,
                heldout_units: self.folds.describe(),
                attribution_units: self.attribution_folds.describe(),
            },
            locations: locations
                .iter()
                .map(|s| Location {
                    excitation_frequency_hz: s.excitation_frequency_hz,
                    normal_force_n: s.normal_force_n,
                    observable: s.observable,
                    detail: format!(
                        "{}: measured {:.6e}, baseline simulates {:.6e}",
                        s.observable.phase().describe(),
                        s.measured,
                        s.simulated,
                    ),
                    score: s.z.abs(),
                })
                .collect(),
            candidates: self
                .candidates
                .iter()
                .map(|c| CandidateReport {
                    effect: c.effect.name().to_string(),
                    form: c.form.to_string(),
                    shrink: c.shrink,
                    heldout_shrink: self.cv_gaps.map(|_| c.heldout_shrink),
                    share_in_sample: c.in_sample_share,
                    share_out_of_sample: c.cv_share,
                    wins: c.wins,
                    searched_in_full: c.refined,
                    gap_fit: c.gap_fit,
                    parameters: c.parameters.clone(),
                    unexplained: c.unexplained.iter().map(UnexplainedReport::from).collect(),
                })
                .collect(),
            models: ModelFiles { baseline: "baseline-model.toml".into(), fitted: "fitted-model.toml".into() },
            source: source.display().to_string(),
            elapsed_s,
            notes: self.notes.clone(),
            derived_channels: self.derived_channels,
        }
    }
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

pub use crate::diagnose::chart::{ChartData, ScoreRow, write_charts};

/// How a diagnosis was run, for the HTML report's header (report.json keeps
/// its keys; these are the command line's facts).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunInfo {
    /// The seed of the simulated replicates.
    pub seed: Option<u64>,
    /// The backend line (`engine.description()`).
    pub backend: Option<String>,
}

/// Writes `report.json`, `baseline-model.toml`, `fitted-model.toml`,
/// `report.html`, `scores.csv` and the charts into `out`; returns the report.
pub fn write_diagnosis(out: &Path, diagnosis: &Diagnosis, source: &Path, elapsed_s: f64) -> Result<Report> {
    write_diagnosis_with(out, diagnosis, source, elapsed_s, &RunInfo::default())
}

/// [`write_diagnosis`], with the run's seed and backend in the HTML report.
pub fn write_diagnosis_with(
    out: &Path,
    diagnosis: &Diagnosis,
    source: &Path,
    elapsed_s: f64,
    run: &RunInfo,
) -> Result<Report> {
    // The set is built beside `out` and swapped in whole; a set the caller
    // prepared (the command line, before computing) is written straight into.
    let set = OutputSet::prepare(out, "output directory", owned::DIAGNOSIS, &[source])?;
    let out = set.dir();
    let report = diagnosis.report(source, elapsed_s);
    report.check_numbers()?;
    write_atomically(&out.join("report.json"), |w| {
        serde_json::to_writer_pretty(&mut *w, &report)?;
        writeln!(w)
    })?;
    let header = |what: &str| {
        format!(
            "# {what} written by stickslip diagnose from {}\n# Run it with: stickslip sweep --config THIS_FILE\n\n",
            source.display()
        )
    };
    write_atomically(&out.join("baseline-model.toml"), |w| {
        w.write_all(header("The calibrated baseline").as_bytes())?;
        w.write_all(diagnosis.baseline.to_toml_string().as_bytes())
    })?;
    write_atomically(&out.join("fitted-model.toml"), |w| {
        w.write_all(
            header(&format!("The baseline plus the verdict's effects ({})", diagnosis.verdict_names())).as_bytes(),
        )?;
        if let Some([start, end]) = diagnosis.fitted.effects.normal_force_drift.as_ref().and_then(|d| d.mean_over_s) {
            writeln!(
                w,
                "# normal_force_drift: a sweep's normal force is the drifting force's mean over {start:.3} s to {end:.3} s after each\n# run's warm-up (normal_force_drift.mean_over_s), as the measured records' nominal force was their mean.\n"
            )?;
        }
        if diagnosis
            .fitted
            .effects
            .normal_force_harmonics
            .as_ref()
            .is_some_and(|h| h.form == crate::engine::effects::HarmonicForm::Position)
        {
            writeln!(
                w,
                "# normal_force_harmonics (position): a sweep's normal force N0 is the load with the block at x = 0; the mean\n# force over a record is N0 (1 + a mean(x/U0) + b mean((x/U0)^2)), as the measured records' mean was.\n"
            )?;
        }
        if let Some(h) =
            diagnosis.fitted.effects.friction_hysteresis.as_ref().filter(|h| h.form == HysteresisForm::Bristle)
        {
            writeln!(
                w,
                "# friction_hysteresis (bristle): a stuck block rests on a contact of stiffness mu0 N0 / {:.3e} m at each\n# sweep point's nominal normal force N0 (mu0 = a + b), so it follows the base by k delta / (k delta + mu0 N0)\n# of its motion; the records' normal_force_n was taken as the load their contact carried.\n",
                h.length_m
            )?;
        }
        w.write_all(diagnosis.fitted.to_toml_string().as_bytes())
    })?;
    let files = chart::write_gap_chart(out, diagnosis)?;
    let has_comparison = files.iter().any(|f| f.file_name().is_some_and(|n| n == "comparison.png"));
    let html = html(diagnosis, &report, run, has_comparison);
    write_atomically(&out.join("report.html"), |w| w.write_all(html.as_bytes()))?;
    set.commit()?;
    Ok(report)
}

/// A number with about four significant digits and no e-notation for
/// ordinary magnitudes.
fn sig(v: f64) -> String {
    if !v.is_finite() {
        return "–".into();
    }
    let a = v.abs();
    if a == 0.0 {
        return "0".into();
    }
    if !(1e-4..1e6).contains(&a) {
        return format!("{v:.3e}");
    }
    let decimals = (3 - a.log10().floor() as i32).clamp(0, 8) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s }
}

/// A value of the observable named `observable` in a readable unit
/// ([`crate::diagnose::observable::Unit::show`]); the bare number for a
/// name that is no observable.
pub fn readable(observable: &str, v: f64) -> String {
    match Observable::named(observable) {
        Some(o) => o.unit().show(v, sig),
        None => sig(v),
    }
}
/// The report's sentence on a family that led a round and is not named.
fn refusal_sentence(r: &crate::diagnose::Refusal) -> String {
    let lead = format!(
        "{} ({}) led {}, closing {:.0}% of {} out of sample, and is not named: ",
        r.effect.name(),
        r.form.name(),
        if r.after_named == 0 { "the first round".to_string() } else { format!("round {}", r.after_named + 1) },
        100.0 * r.share_of_gap,
        if r.after_named == 0 { "the baseline's gap" } else { "what the effects before it left" }
    );
    let why = match &r.reason {
        RefusalReason::NotBeyondNoise { refitted_share } => format!(
            "refitted from scratch without each fold it closed {:.0}%, which is within the noise of the replicate records",
            100.0 * refitted_share
        ),
        RefusalReason::WorseFolds {
            than_baseline,
            than_model_before,
            response_than_baseline,
            response_over_every_fold,
        } => {
            let mut parts = Vec::new();
            if !than_baseline.is_empty() {
                parts.push(format!("predicts {} worse than the baseline", than_baseline.join(", ")));
            }
            if !than_model_before.is_empty() && than_model_before != than_baseline {
                parts.push(format!("predicts {} worse than the model before it", than_model_before.join(", ")));
            }
            let response: Vec<&str> =
                response_than_baseline.iter().filter(|f| !than_baseline.contains(f)).map(String::as_str).collect();
            if !response.is_empty() {
                parts.push(format!(
                    "predicts the response (the peaks' and the phase's mean and variance) at {} worse than the \
                     baseline",
                    response.join(", ")
                ));
            } else if *response_over_every_fold && than_baseline.is_empty() {
                parts.push(
                    "predicts the response (the peaks' and the phase's mean and variance) over the withheld folds \
                     together worse than the baseline"
                        .to_string(),
                );
            }
            if parts.is_empty() {
                "the verdict's checks at the withheld folds leave it out".to_string()
            } else {
                format!(
                    "refitted without each fold, the model with it {}, beyond the noise and beyond what its form \
                     leaves of those folds when fitted to them too. Its form does not carry over to conditions it \
                     was not fitted on: the effect may be there in a shape no candidate has, which more conditions \
                     around those folds would tell",
                    parts.join(", and ")
                )
            }
        }
    };
    format!("{lead}{why}.")
}

/// What a `none`'s records could have shown: each family's power at its
/// smallest size of interest, least first.
fn power_table(powers: &[Power]) -> String {
    if powers.is_empty() {
        return String::new();
    }
    let mut sorted: Vec<&Power> = powers.iter().collect();
    sorted.sort_by(|a, b| a.power.total_cmp(&b.power));
    let mut s = String::from(
        "<p>What these records could have shown: for each effect family, the chance that an effect of the smallest size of interest would have lifted the baseline's out-of-sample gap above its noise (an upper bound). The verdict's confidence is at most the least of them; a family the records cannot show is not ruled out by this <code>none</code>.</p><table><tr><th>effect</th><th>smallest size of interest</th><th>rise of the gap</th><th>noise threshold</th><th>power</th></tr>",
    );
    for p in sorted {
        s.push_str(&format!(
            "<tr><td>{}</td><td style=\"text-align:left\">{}</td><td>{:.3}</td><td>{:.3}</td><td>{:.2}</td></tr>",
            escape(p.effect.name()),
            escape(&p.reference),
            p.rise,
            p.threshold,
            p.power
        ));
    }
    s.push_str("</table>");
    s
}

fn html(d: &Diagnosis, report: &Report, run: &RunInfo, has_comparison: bool) -> String {
    let gap = &report.gap;
    let num = |v: Option<f64>| v.map_or("–".to_string(), |x| format!("{x:.3}"));
    let params = |p: &BTreeMap<String, f64>| {
        p.iter()
            .map(|(k, v)| {
                let unit = parameter_meaning(k);
                if unit.is_empty() {
                    format!("{} = {}", escape(k), sig(*v))
                } else {
                    format!("{} = {} <span class=\"note\">({})</span>", escape(k), sig(*v), escape(unit))
                }
            })
            .collect::<Vec<_>>()
            .join("<br>")
    };
    let mut s = String::new();
    s.push_str("<!doctype html><html><head><meta charset=\"utf-8\"><title>stickslip diagnosis</title><style>");
    s.push_str("body{font-family:'DejaVu Sans',sans-serif;max-width:1000px;margin:2em auto;padding:0 1em;color:#222;line-height:1.45}table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:4px 8px;text-align:right;vertical-align:top}th{background:#f3f3f3}td:first-child,th:first-child{text-align:left}.verdict{font-size:1.4em}.note{color:#555;font-size:0.9em}.meta{color:#555;font-size:0.9em;border-bottom:1px solid #ddd;padding-bottom:0.6em}img{max-width:100%;height:auto}");
    s.push_str("</style></head><body><h1>Diagnosis of the sim-to-real gap</h1>");
    let elapsed = if report.elapsed_s >= 120.0 {
        format!("{:.1} min", report.elapsed_s / 60.0)
    } else {
        format!("{:.1} s", report.elapsed_s)
    };
    s.push_str(&format!(
        "<p class=\"meta\">stickslip {} · measurement set <code>{}</code> · seed {} · backend {} · run time {}</p>",
        env!("CARGO_PKG_VERSION"),
        escape(&report.source),
        run.seed.map_or("(not recorded)".to_string(), |x| x.to_string()),
        escape(run.backend.as_deref().unwrap_or("(not recorded)")),
        elapsed
    ));
    s.push_str(&format!(
        "<p class=\"verdict\">Verdict: <b>{}</b> (confidence {:.2})</p>",
        escape(&d.verdict_names()),
        d.confidence
    ));
    if d.effects.is_empty() {
        s.push_str("<p>No unmodelled effect is named: no effect family closed a share of the calibrated baseline's out-of-sample gap beyond the noise while predicting every withheld fold no worse than the baseline, or than its form fits that fold (see <i>Candidates</i> below for what each family closed).</p>");
        s.push_str(&power_table(&d.powers));
    } else {
        s.push_str("<table><tr><th>effect</th><th>what it means</th><th>form</th><th>confidence</th><th>share of the gap closed (out of sample)</th><th>form misfit</th><th>fitted parameters (unit, meaning)</th></tr>");
        for e in &d.effects {
            s.push_str(&format!(
                "<tr><td><b>{}</b></td><td style=\"text-align:left\">{}</td><td>{}</td><td>{:.2}</td><td>{:.0}%</td><td>{:.0}%</td><td style=\"text-align:left\">{}</td></tr>",
                escape(e.effect.name()),
                escape(e.effect.meaning()),
                escape(e.form.name()),
                e.confidence,
                100.0 * e.share,
                100.0 * e.form_misfit,
                params(&e.parameters)
            ));
        }
        s.push_str("</table><p class=\"note\"><b>Confidence</b> is the share of 2000 bootstrap resamples of the conditions that give this verdict (its family closes the largest share of what the model before it left of the out-of-sample gap, beyond the noise, and predicts every withheld fold no worse than the baseline, or than its form fits that fold, and the response over every fold together no worse than the baseline), times the share of the gap the named effects close (or each one's margin over the best rival family, where smaller) over one half, at most 1: a form that leaves much of the gap unexplained, or a rival that explains nearly as much, makes the verdict less sure. <b>Share of the gap closed</b> is measured on conditions the models were not fitted to (each fold predicted by models refitted without it). <b>Form misfit</b> is what the best candidate form leaves of that gap: real rigs never match a candidate's shape exactly, so an effect is named for its family. <code>fitted-model.toml</code> holds the effects with these values.</p>");
        for e in report.verdict.effects.iter().filter(|e| !e.friction_at_loads.is_empty()) {
            s.push_str(&format!("<p>{} in physical terms: the friction coefficient at rest, μ(0), at each measured load.</p><table><tr><th>normal force (N)</th><th>baseline μ(0)</th><th>fitted μ(0)</th><th>± over the folds' refits</th></tr>", escape(&e.effect)));
            for f in &e.friction_at_loads {
                s.push_str(&format!(
                    "<tr><td>{}</td><td>{:.4}</td><td>{:.4}</td><td>{}</td></tr>",
                    sig(f.normal_force_n),
                    f.baseline_mu,
                    f.fitted_mu,
                    f.fitted_mu_sd.map_or("–".to_string(), |x| format!("{x:.4}"))
                ));
            }
            s.push_str("</table>");
        }
    }
    if let Some(r) = &d.refused {
        s.push_str(&format!("<p>{}</p>", escape(&refusal_sentence(r))));
    }
    let judged = if d.attribution_folds == d.folds {
        String::new()
    } else {
        // An effect seen at one load alone: named on the weaker test.
        format!(
            " No family predicted a withheld level beyond the noise, so the families were compared on {}, \
             each fall judged against the noise of the scores the family moved.",
            d.attribution_folds.describe()
        )
    };
    s.push_str(&format!(
        "<p>Left unexplained: {:.0}% of the baseline's out-of-sample gap above the noise floor. Folds: {}.{}</p>",
        100.0 * d.unexplained_share,
        escape(&d.folds.describe()),
        escape(&judged)
    ));
    if !d.notes.is_empty() {
        s.push_str("<h2>How the data were read</h2><ul>");
        for n in &d.notes {
            s.push_str(&format!("<li>{}</li>", escape(n)));
        }
        s.push_str("</ul>");
    }
    if let Some(m) = &d.misfit {
        s.push_str("<h2>Where the fitted model still misfits</h2><ul>");
        for h in &m.hints {
            s.push_str(&format!("<li>{}</li>", escape(h)));
        }
        s.push_str("</ul>");
    }
    if has_comparison {
        s.push_str("<h2>Measured against simulated, per condition</h2><img src=\"comparison.png\" alt=\"mean peak amplitude per condition: measured, calibrated baseline and fitted model, mm\">");
        s.push_str("<p class=\"note\">Black: the measured mean peak amplitude. Red: what the calibrated baseline simulates; blue: the fitted model. The bars are ± one spread of the simulator (the standard deviation of measured − simulated that the z-scores divide by), so a measured point outside a bar is more than 1 spread away.</p>");
    }
    s.push_str("<h2>How large the gap is</h2>");
    s.push_str(&format!(
        "<table><tr><th></th><th>baseline</th><th>after the verdict</th><th>shrink</th></tr><tr><td>every condition, models fitted to them all</td><td>{}</td><td>{}</td><td>{}</td></tr><tr><td>out of sample (each fold predicted by models fitted without it)</td><td>{}</td><td>{}</td><td>{}</td></tr>",
        num(Some(gap.baseline)),
        num(Some(gap.after)),
        num(Some(gap.shrink)),
        num(gap.heldout_baseline),
        num(gap.heldout_after),
        num(gap.heldout_shrink),
    ));
    for f in &gap.heldout_folds {
        s.push_str(&format!(
            "<tr><td>&nbsp;&nbsp;held out: {}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(&f.heldout),
            num(Some(f.before)),
            num(Some(f.after)),
            num(Some(f.shrink))
        ));
    }
    s.push_str("</table>");
    s.push_str("<p class=\"note\">The gap is the mean over every scored (condition, observable) of ln(1 + z²), where z is measured − simulated in units of the simulator's own spread: about z² for small misses and growing only with the logarithm of large ones, so a model that matches the data to within noise scores about 0.6. <b>Shrink</b> = (baseline − after) / baseline: 0.4 means the gap fell by 40%. <b>A negative shrink</b> means the fitted model predicts that fold worse than the baseline does.</p>");
    let worse: Vec<&FoldReport> = gap.heldout_folds.iter().filter(|f| f.shrink < 0.0).collect();
    if !d.effects.is_empty() && !worse.is_empty() {
        s.push_str(&format!(
            "<p><b>Predicted worse than by the baseline:</b> {}. Read the fitted model there with care.</p>",
            escape(&worse.iter().map(|f| f.heldout.as_str()).collect::<Vec<_>>().join("; "))
        ));
    }
    s.push_str("<h2>Where the baseline departs from the data</h2><img src=\"gap.png\" alt=\"|z| of the worst observables, calibrated baseline and fitted\">");
    s.push_str("<p class=\"note\">Each row is one observable at one condition, its |z| on a log scale under the calibrated baseline (red) and the fitted model (blue). The dashed line is |z| = 3: three spreads, past which a difference is unlikely to be noise; the table lists every such departure. All scores are in <a href=\"scores.csv\">scores.csv</a>.</p>");
    s.push_str("<table><tr><th>condition</th><th>observable</th><th>|z|</th><th>part of the motion</th><th>measured</th><th>baseline simulates</th></tr>");
    let mut departures: Vec<&Score> = d.baseline_scores.iter().filter(|s| s.z.abs() > 3.0).collect();
    departures.sort_by(|a, b| b.z.abs().total_cmp(&a.z.abs()));
    for sc in departures.iter().take(30) {
        let name = sc.observable.name();
        s.push_str(&format!(
            "<tr><td>{} Hz, {} N{}</td><td title=\"{}\">{}</td><td>{:.1}</td><td style=\"text-align:left\">{}</td><td>{}</td><td>{}</td></tr>",
            sig(sc.excitation_frequency_hz),
            sig(sc.normal_force_n),
            if sc.heldout { " (held out)" } else { "" },
            escape(name),
            escape(sc.observable.label()),
            sc.z.abs(),
            escape(sc.observable.phase().describe()),
            escape(&readable(name, sc.measured)),
            escape(&readable(name, sc.simulated)),
        ));
    }
    if departures.len() > 30 {
        s.push_str(&format!(
            "<tr><td colspan=\"6\">… and {} more (report.json lists them all)</td></tr>",
            departures.len() - 30
        ));
    }
    s.push_str("</table><h2>Candidates of the first round</h2><table><tr><th>effect</th><th>form</th><th>share closed in sample</th><th>share closed out of sample</th><th>wins</th><th>searched</th><th>parameters</th></tr>");
    for c in &d.candidates {
        s.push_str(&format!(
            "<tr><td title=\"{}\">{}</td><td>{}</td><td>{:.0}%</td><td>{:.0}%</td><td>{:.2}</td><td>{}</td><td style=\"text-align:left\">{}</td></tr>",
            escape(c.effect.meaning()),
            escape(c.effect.name()),
            escape(c.form.name()),
            100.0 * c.in_sample_share,
            100.0 * c.cv_share,
            c.wins,
            if c.refined { "in full" } else { "coarsely" },
            params(&c.parameters)
        ));
    }
    s.push_str(&format!(
        "</table><p class=\"note\">Every family the data have a channel for is fitted at least coarsely (each form at the parameters the data point to); the closest are searched in full. The out-of-sample gap's noise threshold is {:.3}. Models: <a href=\"baseline-model.toml\">baseline-model.toml</a>, <a href=\"fitted-model.toml\">fitted-model.toml</a>; both run with <code>stickslip sweep --config</code>.</p></body></html>\n",
        d.noise_threshold
    ));
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::{Refusal, candidates::SearchedForm};
    use crate::engine::Effect;

    /// The sentence of a stiction refused for its response alone: worse at
    /// the folds `at` and, with `pooled`, over every fold together.
    fn refused(at: &[&str], pooled: bool) -> String {
        refusal_sentence(&Refusal {
            effect: Effect::Stiction,
            form: SearchedForm::Position,
            share_of_gap: 0.4,
            after_named: 0,
            reason: RefusalReason::WorseFolds {
                than_baseline: vec![],
                than_model_before: vec![],
                response_than_baseline: at.iter().map(|f| f.to_string()).collect(),
                response_over_every_fold: pooled,
            },
        })
    }

    /// A leader refused only because its model predicts the response over
    /// the withheld folds together worse says so; one refused at a fold
    /// names the fold, and the pooled reason is not repeated beside it.
    #[test]
    fn a_refusal_says_when_the_response_over_every_fold_together_is_worse() {
        let pooled = refused(&[], true);
        assert!(pooled.contains("over the withheld folds together worse than the baseline"), "{pooled}");
        let at_fold = refused(&["normal force 16 N"], true);
        assert!(at_fold.contains("at normal force 16 N worse") && !at_fold.contains("together"), "{at_fold}");
        let none = refused(&[], false);
        assert!(none.contains("leave it out"), "{none}");
    }
}
