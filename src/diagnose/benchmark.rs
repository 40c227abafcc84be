//! The blind benchmark of the diagnosis (`stickslip benchmark-diagnosis`):
//! synthetic sets ([`crate::diagnose::synthetic`]) with withheld effects in
//! forms no candidate has, two-effect sets, phase-only summary sets and null
//! sets from the whole eq. 7 family, each diagnosed without being told what
//! it hides. The summary reports top-1 accuracy, both-named rates, the
//! false-positive rate, a reliability table of the confidence, and the shrink
//! of the fitted model's error at the withheld load level against the
//! generator's truth there.
pub mod independent;

use std::path::PathBuf;
use std::time::Instant;

use crate::diagnose::candidates::NULL_HUBER;
use crate::diagnose::data::condition_key;
use crate::diagnose::report::write_diagnosis;
use crate::diagnose::simulate::{path_stats_per_condition, record_path_stats};
use crate::diagnose::synthetic::{PlannedSet, SetShape, benchmark_plan, random_truth, write_set};
use crate::diagnose::{DiagnoseSettings, diagnose_set, mean, sd};
use crate::engine::reduce::circular_mean_var;
use crate::engine::{Condition, Effect, Engine, Model};
use crate::error::Result;
use crate::io::{create_dir, write_atomically};
use crate::measure::{MeasurementSet, RigInfo, SummaryRow, read_measurement_set};

/// What the benchmark runs.
#[derive(Clone, Debug)]
pub struct BenchmarkSettings {
    /// Where the synthetic sets and their diagnoses go.
    pub out: PathBuf,
    /// Null sets (no effect).
    pub nulls: u32,
    /// Withheld effect forms used (1, 2).
    pub forms: Vec<u32>,
    /// Strength levels (0 moderate, 1 strong).
    pub levels: Vec<u32>,
    /// Two-effect sets.
    pub pairs: u32,
    /// Phase-only summary sets.
    pub phase_only: u32,
    /// Only sets hiding these effects (and nulls); all when empty.
    pub effects: Vec<Effect>,
    pub shape: SetShape,
    /// Normal-force levels as shares of Den Hartog's no-stop threshold.
    pub load_shares: Vec<f64>,
    /// Excitation frequencies as ratios of the rig's natural frequency, –.
    pub frequency_ratios: Vec<f64>,
    /// Seed of the sets (and, mixed, of the diagnoses).
    pub seed: u64,
    /// Simulated replicate records per condition in each diagnosis.
    pub replicates: u32,
    /// Only these sets of the plan, by index (all when empty).
    pub sets: Vec<usize>,
    /// Which generator makes the sets.
    pub generator: Generator,
}

/// Which generator makes a benchmark's sets.
#[derive(Clone, Debug, PartialEq)]
pub enum Generator {
    /// stickslip's own engine with its effect library's withheld forms
    /// ([`crate::diagnose::synthetic`]), loads as shares of the no-stop
    /// threshold.
    Engine,
    /// The independent generator ([`independent`]): its own integrator and
    /// effect forms from the literature, at fixed loads in newtons, with the
    /// records' time frames as `origins` says, and their channels `t` and
    /// `x` (and `base_x`) alone where `displacement_only`.
    Independent { loads_n: Vec<f64>, origins: Origins, displacement_only: bool },
}

/// The time frames of an independent benchmark's records.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Origins {
    /// `t` in the model's frame.
    Model,
    /// A free time origin, declared in the manifest.
    Free,
    /// A free time origin with a `base_x` column.
    BaseX,
    /// The three in turn, set by set.
    Mixed,
}

impl Origins {
    /// The record shape of set `index` (its channels `t` and `x`, and
    /// `base_x` where it has one, alone where `displacement_only`).
    fn shape(
        self,
        index: usize,
        runs_per_condition: u32,
        duration_s: f64,
        displacement_only: bool,
    ) -> independent::RecordShape {
        let pick = match self {
            Origins::Mixed => [Origins::Model, Origins::Free, Origins::BaseX][index % 3],
            other => other,
        };
        let shape = match pick {
            Origins::Free => independent::RecordShape::free_origin(),
            Origins::BaseX => independent::RecordShape::free_origin_with_base(),
            _ => independent::RecordShape::default(),
        };
        independent::RecordShape { runs_per_condition, duration_s, displacement_only, ..shape }
    }
}

impl BenchmarkSettings {
    /// The sets this benchmark runs, each with its index in the plan (which
    /// names its directory and seeds its data): `sets` picks some without
    /// changing what each one is.
    pub fn plan(&self) -> Vec<(usize, PlannedSet)> {
        benchmark_plan(self.nulls, &self.forms, &self.levels, self.pairs, self.phase_only)
            .into_iter()
            .filter(|p| self.effects.is_empty() || p.hidden.iter().all(|h| self.effects.contains(&h.effect)))
            .enumerate()
            .filter(|(i, _)| self.sets.is_empty() || self.sets.contains(i))
            .collect()
    }

    /// The seed of set `index`'s truth and data.
    fn set_seed(&self, index: usize) -> u64 {
        self.seed.wrapping_mul(1_000_003).wrapping_add(index as u64)
    }

    /// The settings each set is diagnosed with.
    pub fn diagnose_settings(&self) -> DiagnoseSettings {
        DiagnoseSettings { seed: self.seed ^ 0xD1A6, replicates: self.replicates.max(2), ..DiagnoseSettings::default() }
    }

    /// What each planned set will hold, without simulating anything (its
    /// truth is drawn, not run): for the cost budget.
    pub fn outlines(&self) -> Result<Vec<SetOutline>> {
        let shape = self.shape;
        self.plan()
            .into_iter()
            .map(|(i, planned)| {
                let seed = self.set_seed(i);
                Ok(match &self.generator {
                    Generator::Engine => SetOutline {
                        conditions: random_truth(seed, &planned.hidden, &self.frequency_ratios, &self.load_shares)?.1,
                        runs_per_condition: shape.runs_per_condition,
                        duration_s: shape.duration_s,
                        sample_rate_hz: shape.sample_rate_hz,
                        summary_only: planned.phase_only,
                    },
                    Generator::Independent { loads_n, origins, displacement_only } => {
                        let hidden: Vec<independent::HiddenForm> =
                            planned.hidden.iter().map(|h| (h.effect, h.form.saturating_sub(1), h.level == 1)).collect();
                        let record = origins.shape(i, shape.runs_per_condition, shape.duration_s, *displacement_only);
                        SetOutline {
                            conditions: independent::random_truth(seed, &hidden, loads_n, &self.frequency_ratios)?.1,
                            runs_per_condition: record.runs_per_condition,
                            duration_s: record.duration_s,
                            sample_rate_hz: record.sample_rate_hz,
                            summary_only: false,
                        }
                    }
                })
            })
            .collect()
    }
}

/// What one planned set of a benchmark holds ([`BenchmarkSettings::outlines`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SetOutline {
    pub conditions: Vec<Condition>,
    /// Records per condition (none when `summary_only`).
    pub runs_per_condition: u32,
    /// Length of each record, s; a summary-only set's rows cover as many
    /// periods as such a record would.
    pub duration_s: f64,
    /// Sampling rate of the records, Hz.
    pub sample_rate_hz: f64,
    /// A summary-only (phase) set: one row per condition, no records.
    pub summary_only: bool,
}

/// One diagnosed set.
#[derive(Clone, Debug)]
pub struct BenchmarkRow {
    /// What the set hides, leading first (empty: a null set).
    pub truth: Vec<Effect>,
    pub phase_only: bool,
    /// What the diagnosis named, best first.
    pub verdict: Vec<Effect>,
    /// The verdict's confidence.
    pub confidence: f64,
    /// The report's held-out shrink.
    pub heldout_shrink: Option<f64>,
    /// The shrink of the fitted models' error against the truth at the
    /// conditions each fold withholds (each model fitted without its fold),
    /// relative to the baselines fitted the same way, pooled over the
    /// folds (`None` without folds or for a null set).
    pub truth_shrink: Option<f64>,
    /// The smallest of those shrinks fold by fold.
    pub worst_fold: Option<f64>,
    /// Whether the hidden effects move the response statistics (peak
    /// mean, variance and phase) beyond their noise: the mean squared z,
    /// over every condition, of the truth without its effects against the
    /// truth exceeds [`RESPONSE_NOISE_WEIGHT`] (see `Truth::effect_weight`).
    pub moves_statistics: bool,
    /// Whether the calibrated baseline's gap was within its noise threshold
    /// of the noise floor.
    pub baseline_within_noise: bool,
    /// For a two-effect set, how much the data weigh each hidden effect
    /// (in `truth`'s order): the error of the truth without that effect
    /// against the truth, over every condition ([`error_against_truth`]
    /// for stickslip's own generator; for the independent one, its own twin
    /// without the effect on the same noise paths). Empty otherwise.
    pub data_weights: Vec<f64>,
    /// Where the verdict is `none`: the families the diagnosis said these
    /// records could not show ([`crate::diagnose::search::power`]).
    pub could_not_show: Vec<Effect>,
    /// Time of the diagnosis, s.
    pub seconds: f64,
}

/// The mean squared z of the response statistics (peak mean, variance
/// and phase, over every condition) beyond which an effect moves the
/// response beyond its noise, –: the split of the single-effect and the
/// two-effect scores by what the response can show.
pub const RESPONSE_NOISE_WEIGHT: f64 = 4.0;

impl BenchmarkRow {
    /// Whether each of a two-effect set's hidden effects moves the response
    /// beyond its noise on its own ([`BenchmarkRow::data_weights`] above
    /// [`RESPONSE_NOISE_WEIGHT`]); false for other sets.
    pub fn every_effect_moves_response(&self) -> bool {
        self.data_weights.len() >= 2 && self.data_weights.iter().all(|&w| w > RESPONSE_NOISE_WEIGHT)
    }

    /// Whether the leading verdict is right (`none` for a null set; for a
    /// two-effect set, the leading hidden effect).
    pub fn leading_right(&self) -> bool {
        self.verdict.first() == self.truth.first()
    }

    /// The hidden effect the data weigh more (see
    /// [`BenchmarkRow::data_weights`]; the labelled leader where they weigh
    /// both alike); `None` for a set with fewer than two effects.
    pub fn heavier_effect(&self) -> Option<Effect> {
        match self.data_weights[..] {
            [lead, other] => self.truth.get(usize::from(other > lead)).copied(),
            _ => None,
        }
    }

    /// Whether exactly the hidden effects were named.
    pub fn all_right(&self) -> bool {
        self.verdict.len() == self.truth.len() && self.truth.iter().all(|e| self.verdict.contains(e))
    }
}

/// One path's statistics over a record: mean peak (m), peak variance (m²)
/// and circular mean phase (degrees).
pub type TruthStat = (f64, f64, f64);

/// The error of `model`'s statistics against the truth's (`truth[i]`: its
/// paths' statistics at `conditions[i]`): `stats_error` of the model's
/// paths (simulated by the engine) against the truth's.
pub fn error_against_stats(
    model: &Model,
    truth: &[Vec<TruthStat>],
    conditions: &[Condition],
    shape: SetShape,
    engine: &Engine,
) -> Result<f64> {
    let m = record_path_stats(engine, model, conditions, shape.duration_s, 32, 77, 60)?;
    let m: Vec<Vec<TruthStat>> =
        m.iter().map(|pm| pm.iter().map(|p| (p.peak_mean_m, p.peak_var_m2, p.phase_mean_deg)).collect()).collect();
    Ok(stats_error(truth, &m, shape.runs_per_condition))
}

/// The error of one set of paths' statistics (`other[i]`) against the
/// truth's (`truth[i]`), condition by condition: the mean over conditions
/// of the squared differences of the ensemble mean peak, peak variance and
/// phase, each in units of the truth's per-record noise (the spread over
/// paths of one record's statistic over `runs` records), –.
fn stats_error(truth: &[Vec<TruthStat>], other: &[Vec<TruthStat>], runs: u32) -> f64 {
    let runs = f64::from(runs.max(1)).sqrt();
    let mut terms = Vec::new();
    for (pt, pm) in truth.iter().zip(other) {
        let stat = |p: &[TruthStat], f: fn(&TruthStat) -> f64| p.iter().map(f).collect::<Vec<f64>>();
        for f in [|p: &TruthStat| p.0, |p: &TruthStat| p.1] {
            let (a, b) = (stat(pt, f), stat(pm, f));
            terms.push(((mean(&b) - mean(&a)) / (sd(&a).max(1e-30) / runs)).powi(2));
        }
        let phases = |p: &[TruthStat]| p.iter().map(|s| s.2.to_radians()).collect::<Vec<f64>>();
        let (a, b) = (phases(pt), phases(pm));
        let (ca, va) = circular_mean_var(&a);
        let (cb, _) = circular_mean_var(&b);
        let d = crate::engine::reduce::wrap_angle(cb - ca);
        terms.push((d / (va.sqrt().max(1e-9) / runs)).powi(2));
    }
    mean(&terms)
}

/// The paths' statistics of an engine model at `conditions` over records of
/// the benchmark's length.
fn engine_stats(
    model: &Model,
    conditions: &[Condition],
    shape: SetShape,
    engine: &Engine,
) -> Result<Vec<Vec<TruthStat>>> {
    Ok(record_path_stats(engine, model, conditions, shape.duration_s, 32, 77, 60)?
        .into_iter()
        .map(|paths| paths.iter().map(|p| (p.peak_mean_m, p.peak_var_m2, p.phase_mean_deg)).collect())
        .collect())
}

/// The error of `model` against `truth` at `conditions` (both simulated by
/// the engine; see [`error_against_stats`]).
pub fn error_against_truth(
    model: &Model,
    truth: &Model,
    conditions: &[Condition],
    shape: SetShape,
    engine: &Engine,
) -> Result<f64> {
    error_against_stats(model, &engine_stats(truth, conditions, shape, engine)?, conditions, shape, engine)
}

/// A phase-only summary set: one record's phase mean and variance per
/// condition (no amplitudes, no records), as some rigs publish.
fn phase_only_set(
    truth: &Model,
    conditions: &[Condition],
    shape: SetShape,
    seed: u64,
    engine: &Engine,
) -> Result<MeasurementSet> {
    let reference = Engine::cpu("the synthetic truth");
    let _ = engine;
    // Each row over its own record's periods, as a rig measuring for the
    // same time at each frequency would publish.
    let cycles: Vec<u32> = conditions.iter().map(|c| (shape.duration_s * c.excitation_frequency_hz) as u32).collect();
    let stats = path_stats_per_condition(&reference, truth, conditions, &cycles, 1, seed, 60)?;
    let summary = conditions
        .iter()
        .zip(&stats)
        .zip(&cycles)
        .enumerate()
        .map(|(i, ((c, s), &cycles))| SummaryRow {
            excitation_frequency_hz: c.excitation_frequency_hz,
            excitation_amplitude_m: truth.excitation.amplitude_m,
            normal_force_mean_n: c.normal_force_n,
            normal_force_var_n2: None,
            peak_mean_m: None,
            peak_var_m2: None,
            n_peaks: Some(u64::from(cycles.max(2))),
            phase_mean_deg: Some(s[0].phase_mean_deg),
            phase_var_deg2: Some(s[0].phase_var_deg2),
            line: i as u64 + 2,
        })
        .collect();
    Ok(MeasurementSet {
        dir: PathBuf::from("(in memory)"),
        description: "phase-only summary set (stickslip benchmark-diagnosis)".into(),
        rig: RigInfo {
            mass_kg: truth.rig.mass_kg,
            natural_frequency_hz: truth.rig.natural_frequency_hz,
            damping_ratio: truth.rig.damping_ratio,
        },
        runs: Vec::new(),
        summary,
        summary_file: None,
    })
}

/// A benchmark set's truth: an engine model, or an independent one (with
/// the set's seed).
enum Truth {
    Engine(Box<Model>),
    Independent(Box<independent::IndependentTruth>, u64),
}

impl Truth {
    /// Its paths' statistics at `conditions` over records of the set's
    /// length (the independent truth simulated by its own generator).
    fn stats(&self, conditions: &[Condition], shape: SetShape, engine: &Engine) -> Result<Vec<Vec<TruthStat>>> {
        match self {
            Truth::Engine(m) => engine_stats(m, conditions, shape, engine),
            Truth::Independent(t, seed) => {
                Ok(independent::truth_path_stats(t, conditions, shape.duration_s, 16, *seed)
                    .into_iter()
                    .map(|paths| paths.iter().map(|p| (p.peak_mean_m, p.peak_var_m2, p.phase_mean_deg)).collect())
                    .collect())
            }
        }
    }

    /// How far the hidden effects move the response statistics (peak
    /// mean, variance and phase) at `conditions`
    /// ([`stats_error`] of the truth without its effects against `stats`,
    /// the truth's own paths there), –: an engine truth's baseline simulated
    /// by the engine; an independent truth's twin without effects by its
    /// own generator, on the same noise paths.
    fn effect_weight(
        &self,
        stats: &[Vec<TruthStat>],
        conditions: &[Condition],
        shape: SetShape,
        engine: &Engine,
    ) -> Result<f64> {
        match self {
            Truth::Engine(_) => error_against_stats(&self.engine_baseline(), stats, conditions, shape, engine),
            Truth::Independent(t, seed) => {
                let twin = Truth::Independent(
                    Box::new(independent::IndependentTruth { effects: Vec::new(), ..(**t).clone() }),
                    *seed,
                );
                Ok(stats_error(stats, &twin.stats(conditions, shape, engine)?, shape.runs_per_condition))
            }
        }
    }

    /// The engine model without effects nearest the truth (an independent
    /// truth's rig and eq. 7 law).
    fn engine_baseline(&self) -> Model {
        match self {
            Truth::Engine(m) => Model { effects: Default::default(), ..(**m).clone() },
            Truth::Independent(t, _) => {
                let mut m = Model::default();
                m.rig.mass_kg = t.rig.mass_kg;
                m.rig.natural_frequency_hz = t.rig.natural_frequency_hz;
                m.rig.damping_ratio = t.rig.damping_ratio;
                m.excitation.amplitude_m = t.rig.excitation_amplitude_m;
                m.friction.a = t.friction.a;
                m.friction.b = t.friction.b;
                m.friction.c = t.friction.c_s_per_m;
                m.friction.d = t.friction.d_s2_per_m2;
                m.friction.sigma = t.friction.sigma_mu;
                m.normal_force.sigma = t.friction.sigma_n_n;
                m
            }
        }
    }
}

/// Writes, diagnoses and scores every set of the plan; `line` receives one
/// line per set as it finishes. Returns the rows and the summary text
/// (also written to `OUT/summary.txt`).
pub fn run_benchmark(
    settings: &BenchmarkSettings,
    engine: &Engine,
    line: &mut dyn FnMut(&str),
) -> Result<(Vec<BenchmarkRow>, String)> {
    let plan = settings.plan();
    let diagnose_settings = settings.diagnose_settings();
    let shape = settings.shape;
    let mut rows = Vec::new();
    let started = Instant::now();
    for &(i, ref planned) in &plan {
        let seed = settings.set_seed(i);
        let dir = settings.out.join(format!("set-{i:03}"));
        // The truth beside (not inside) the data, for whoever checks a verdict.
        create_dir(&dir)?;
        let (truth, conditions, set) = match &settings.generator {
            Generator::Engine => {
                let (truth, conditions) =
                    random_truth(seed, &planned.hidden, &settings.frequency_ratios, &settings.load_shares)?;
                write_atomically(&dir.join("truth-model.toml"), |w| w.write_all(truth.to_toml_string().as_bytes()))?;
                let set = if planned.phase_only {
                    phase_only_set(&truth, &conditions, shape, seed, engine)?
                } else {
                    write_set(&dir.join("data"), &truth, &conditions, shape, seed)?;
                    read_measurement_set(&dir.join("data"))?
                };
                (Truth::Engine(Box::new(truth)), conditions, set)
            }
            Generator::Independent { loads_n, origins, displacement_only } => {
                let hidden: Vec<independent::HiddenForm> =
                    planned.hidden.iter().map(|h| (h.effect, h.form.saturating_sub(1), h.level == 1)).collect();
                let (truth, conditions) =
                    independent::random_truth(seed, &hidden, loads_n, &settings.frequency_ratios)?;
                let record = origins.shape(i, shape.runs_per_condition, shape.duration_s, *displacement_only);
                independent::write_set(&dir.join("data"), &truth, &conditions, &record, seed)?;
                (Truth::Independent(Box::new(truth), seed), conditions, read_measurement_set(&dir.join("data"))?)
            }
        };
        let t0 = Instant::now();
        let d = diagnose_set(&set, &diagnose_settings, engine, &mut |_| {})?;
        let seconds = t0.elapsed().as_secs_f64();
        let report = write_diagnosis(&dir.join("diagnosis"), &d, &dir.join("data"), seconds)?;
        // Each fold's fitted model (fitted without it) against the truth at
        // the fold's conditions, relative to that fold's baseline: pooled
        // over the folds, and the worst fold.
        // The truth's own paths' statistics at every condition, where it
        // hides an effect.
        let all = if planned.hidden.is_empty() { Vec::new() } else { truth.stats(&conditions, shape, engine)? };
        let (truth_shrink, worst_fold, moves_statistics) = if d.folds.folds.is_empty() || planned.hidden.is_empty() {
            (None, None, false)
        } else {
            let moved = truth.effect_weight(&all, &conditions, shape, engine)?;
            let at = |fold: &crate::diagnose::data::Fold| -> Vec<Vec<TruthStat>> {
                fold.conditions
                    .iter()
                    .map(|c| {
                        let k = conditions.iter().position(|x| condition_key(*x) == condition_key(*c)).unwrap_or(0);
                        all[k].clone()
                    })
                    .collect()
            };
            let (mut base, mut fitted, mut worst) = (0.0, 0.0, f64::INFINITY);
            for (fold, (b, f)) in d.folds.folds.iter().zip(&d.fold_models) {
                let stats = at(fold);
                let eb = error_against_stats(b, &stats, &fold.conditions, shape, engine)?;
                let ef = error_against_stats(f, &stats, &fold.conditions, shape, engine)?;
                base += eb;
                fitted += ef;
                if eb > 0.0 {
                    worst = worst.min(1.0 - ef / eb);
                }
            }
            // Whether the effects move the response beyond its noise.
            let moves = moved > RESPONSE_NOISE_WEIGHT;
            ((base > 0.0).then(|| 1.0 - fitted / base), worst.is_finite().then_some(worst), moves)
        };
        // How far the data move without each of two hidden effects: the
        // generator's "strong" and "moderate" are levels of different
        // effects, and the data may weigh the moderate one more.
        let data_weights = match &truth {
            Truth::Engine(truth) if planned.hidden.len() >= 2 => planned
                .hidden
                .iter()
                .map(|h| {
                    let mut without = truth.clone();
                    without.effects.remove(h.effect);
                    error_against_truth(&without, truth, &conditions, shape, engine)
                })
                .collect::<Result<Vec<f64>>>()?,
            // An independent truth's twin without each effect, by its own
            // generator on the same noise paths, against the truth's paths.
            Truth::Independent(t, seed) if planned.hidden.len() >= 2 => planned
                .hidden
                .iter()
                .map(|h| {
                    let mut without = (**t).clone();
                    without.effects.retain(|e| e.family() != h.effect);
                    let twin = Truth::Independent(Box::new(without), *seed).stats(&conditions, shape, engine)?;
                    Ok(stats_error(&all, &twin, shape.runs_per_condition))
                })
                .collect::<Result<Vec<f64>>>()?,
            _ => Vec::new(),
        };
        let key0 = report.gap.heldout_baseline.unwrap_or(report.gap.baseline);
        let baseline_within_noise = key0 - NULL_HUBER <= report.gap.noise_threshold;
        let name = |v: &[Effect]| {
            if v.is_empty() { "none".to_string() } else { v.iter().map(|e| e.name()).collect::<Vec<_>>().join("+") }
        };
        let truth_effects: Vec<Effect> = planned.hidden.iter().map(|h| h.effect).collect();
        let verdict: Vec<Effect> = d.effects.iter().map(|e| e.effect).collect();
        let could_not_show: Vec<Effect> = d.powers.iter().filter(|p| !p.could_show()).map(|p| p.effect).collect();
        let forms: Vec<String> =
            planned.hidden.iter().map(|h| format!("{}{}", h.form, if h.level == 1 { "s" } else { "m" })).collect();
        line(&format!(
            "set {i:3}: truth {:<40} [{}{}] -> {:<40} conf {:.2} held-out shrink {} truth shrink {}{}{}{} ({seconds:.0} s)",
            name(&truth_effects),
            forms.join(","),
            if planned.phase_only { " phase-only" } else { "" },
            name(&verdict),
            d.confidence,
            report.gap.heldout_shrink.map_or("n/a".into(), |h| format!("{h:+.2}")),
            truth_shrink
                .map_or("n/a".into(), |h| format!("{h:+.2}{}", if moves_statistics { "" } else { " (within noise)" })),
            worst_fold.map_or(String::new(), |w| format!(" (worst fold {w:+.2})")),
            if data_weights.is_empty() {
                String::new()
            } else {
                format!(
                    " data weights {}",
                    data_weights.iter().map(|w| format!("{w:.1}")).collect::<Vec<_>>().join("/")
                )
            },
            if could_not_show.is_empty() {
                String::new()
            } else {
                format!(" could not show {}", name(&could_not_show))
            },
        ));
        rows.push(BenchmarkRow {
            truth: truth_effects,
            phase_only: planned.phase_only,
            verdict,
            confidence: d.confidence,
            heldout_shrink: report.gap.heldout_shrink,
            truth_shrink,
            worst_fold,
            moves_statistics,
            baseline_within_noise,
            data_weights,
            could_not_show,
            seconds,
        });
    }
    let text = summary(settings, engine, &rows, started.elapsed().as_secs_f64());
    create_dir(&settings.out)?;
    write_atomically(&settings.out.join("summary.txt"), |w| w.write_all(text.as_bytes()))?;
    Ok((rows, text))
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
}

/// The confusion matrix (leading verdict), the headline numbers against
/// their targets and the reliability table.
fn summary(settings: &BenchmarkSettings, engine: &Engine, rows: &[BenchmarkRow], total_s: f64) -> String {
    let labels: Vec<Option<Effect>> = Effect::ALL.iter().copied().map(Some).chain([None]).collect();
    let index = |e: Option<Effect>| labels.iter().position(|l| *l == e).expect("every effect and none is a label");
    let mut confusion = vec![vec![0u32; labels.len()]; labels.len()];
    for r in rows {
        confusion[index(r.truth.first().copied())][index(r.verdict.first().copied())] += 1;
    }
    let singles: Vec<&BenchmarkRow> = rows.iter().filter(|r| r.truth.len() == 1 && !r.phase_only).collect();
    let pairs: Vec<&BenchmarkRow> = rows.iter().filter(|r| r.truth.len() == 2).collect();
    let nulls: Vec<&BenchmarkRow> = rows.iter().filter(|r| r.truth.is_empty() && !r.phase_only).collect();
    let phase: Vec<&BenchmarkRow> = rows.iter().filter(|r| r.phase_only).collect();
    let count = |v: &[&BenchmarkRow], f: &dyn Fn(&BenchmarkRow) -> bool| v.iter().filter(|r| f(r)).count();
    let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
    // A share of no sets is not a number: it reads "n/a".
    let percent = |a: usize, b: usize| if b == 0 { "n/a".to_string() } else { format!("{:.1}%", pct(a, b)) };
    let name = |e: Option<Effect>| e.map_or("none", Effect::name);
    let shape = settings.shape;
    let mut text = String::new();
    text.push_str(&format!(
        "blind benchmark of the diagnosis: {} sets ({} single-effect, {} two-effect, {} phase-only, {} null), {} run(s) x {} s per condition, {} frequencies x {}, baselines from the whole eq. 7 family, effects in forms no candidate has; {}\n",
        rows.len(),
        singles.len(),
        pairs.len(),
        phase.len(),
        nulls.len(),
        shape.runs_per_condition,
        shape.duration_s,
        settings.frequency_ratios.len(),
        match &settings.generator {
            Generator::Engine => format!("loads at {:?} of the no-stop threshold, stickslip's own generator", settings.load_shares),
            Generator::Independent { loads_n, origins, displacement_only } => format!(
                "loads {loads_n:?} N, the independent generator (its own integrator and literature forms), time origins {origins:?}{}",
                if *displacement_only { ", records of t and x (and base_x) alone" } else { "" }
            ),
        },
        engine.description()
    ));
    text.push_str("confusion matrix of the leading verdict (rows: leading hidden effect, columns: verdict)\n");
    // Column heads: each word of the name cut to three letters (at most 11
    // characters), a space between columns.
    let short = |l: &str| l.split('_').map(|w| &w[..w.len().min(3)]).collect::<Vec<_>>().join("_");
    text.push_str(&format!("{:<26}", ""));
    for &l in &labels {
        text.push_str(&format!(" {:>11}", short(name(l))));
    }
    text.push('\n');
    for (r, &l) in labels.iter().enumerate() {
        text.push_str(&format!("{:<26}", name(l)));
        for c in &confusion[r] {
            text.push_str(&format!(" {c:>11}"));
        }
        text.push('\n');
    }
    let single_right = count(&singles, &|r| r.leading_right());
    text.push_str(&format!(
        "single-effect sets, top-1: {single_right}/{} = {} (target >= 90%)\n",
        singles.len(),
        percent(single_right, singles.len())
    ));
    // Split by the response statistics alone: an effect seen in another
    // channel (the normal force, the friction) may leave them within their
    // noise and still be named; one that moves no channel cannot be.
    let (moved, still): (Vec<&BenchmarkRow>, Vec<&BenchmarkRow>) = singles.iter().partition(|r| r.moves_statistics);
    let (moved_right, still_right) = (count(&moved, &|r| r.leading_right()), count(&still, &|r| r.leading_right()));
    text.push_str(&format!(
        "  those whose hidden effect moves the response (peak mean, variance, phase) beyond its noise: top-1 {moved_right}/{} = {}; those whose effect leaves it within its noise: top-1 {still_right}/{}\n",
        moved.len(),
        percent(moved_right, moved.len()),
        still.len(),
    ));
    // Whether a `none` on a single effect came with the warning that the
    // records could not show that family: what keeps it from being sure.
    let missed: Vec<&BenchmarkRow> = singles.iter().copied().filter(|r| r.verdict.is_empty()).collect();
    let warned = count(&missed, &|r| r.truth.iter().any(|e| r.could_not_show.contains(e)));
    text.push_str(&format!(
        "  single-effect sets called none: {}; the diagnosis said the records could not show the hidden family on {warned} of them\n",
        missed.len()
    ));
    let (both, lead) = (count(&pairs, &|r| r.all_right()), count(&pairs, &|r| r.leading_right()));
    text.push_str(&format!(
        "two-effect sets: both named and no third {both}/{} = {} (target >= 80%); leading right {lead}/{} = {} (target >= 90%)\n",
        pairs.len(),
        percent(both, pairs.len()),
        pairs.len(),
        percent(lead, pairs.len())
    ));
    // Split as the single-effect sets are: a second effect that leaves the
    // response within its noise can be named only from another channel.
    let (seen, unseen): (Vec<&BenchmarkRow>, Vec<&BenchmarkRow>) =
        pairs.iter().partition(|r| r.every_effect_moves_response());
    text.push_str(&format!(
        "  those whose every hidden effect moves the response beyond its noise on its own (data weight above {RESPONSE_NOISE_WEIGHT}): both named {}/{}; the others: both named {}/{}\n",
        count(&seen, &|r| r.all_right()),
        seen.len(),
        count(&unseen, &|r| r.all_right()),
        unseen.len(),
    ));
    // The label says which effect the generator made strong; the data may
    // weigh the other more. Both readings, so that neither hides the other.
    let agreeing: Vec<&BenchmarkRow> =
        pairs.iter().copied().filter(|r| r.heavier_effect().as_ref() == r.truth.first()).collect();
    let heavier_right = count(&pairs, &|r| r.heavier_effect().is_some_and(|e| r.verdict.first() == Some(&e)));
    text.push_str(&format!(
        "two-effect sets whose data weigh the labelled leader more ({}): leading right {}/{}; every two-effect set, leading the effect the data weigh more: {heavier_right}/{} (data weight: the truth's error without the effect, mean squared z of peak mean, variance and phase over every condition)\n",
        agreeing.len(),
        count(&agreeing, &|r| r.leading_right()),
        agreeing.len(),
        pairs.len(),
    ));
    let (fp, within) = (count(&nulls, &|r| !r.verdict.is_empty()), count(&nulls, &|r| r.baseline_within_noise));
    text.push_str(&format!(
        "null sets: false positives {fp}/{} = {} (target <= 5%); calibrated baseline's gap within its noise threshold on {within}/{}\n",
        nulls.len(),
        percent(fp, nulls.len()),
        nulls.len()
    ));
    let phase_right = count(&phase, &|r| r.all_right());
    text.push_str(&format!("phase-only summary sets: right {phase_right}/{}\n", phase.len()));
    text.push_str("reliability of the confidence (every verdict, `none` included; right = the leading verdict is the leading hidden effect, or none for a null)\n");
    text.push_str("  confidence    verdicts   right   share right\n");
    for (lo, hi) in [(0.0, 0.5), (0.5, 0.7), (0.7, 0.9), (0.9, 1.01)] {
        let bin: Vec<&BenchmarkRow> = rows.iter().filter(|r| r.confidence >= lo && r.confidence < hi).collect();
        let right = count(&bin, &|r| r.leading_right());
        text.push_str(&format!(
            "  [{lo:.1}, {:.1})  {:>8} {:>7}   {}\n",
            hi.min(1.0),
            bin.len(),
            right,
            if bin.is_empty() { "–".into() } else { format!("{:.0}%", pct(right, bin.len())) }
        ));
    }
    let named: Vec<&BenchmarkRow> = rows.iter().filter(|r| !r.verdict.is_empty() && r.confidence >= 0.9).collect();
    let named_right = count(&named, &|r| r.truth.contains(&r.verdict[0]));
    text.push_str(&format!(
        "effects named at confidence >= 0.9: {named_right}/{} right = {} (target >= 90%)\n",
        named.len(),
        percent(named_right, named.len())
    ));
    let moving: Vec<&BenchmarkRow> =
        rows.iter().filter(|r| r.moves_statistics && r.truth_shrink.is_some() && !r.verdict.is_empty()).collect();
    let truth_shrinks: Vec<f64> = moving.iter().filter_map(|r| r.truth_shrink).collect();
    let no_worse = count(&moving, &|r| r.truth_shrink.is_some_and(|s| s >= 0.0));
    let every_fold = count(&moving, &|r| r.worst_fold.is_some_and(|s| s >= 0.0));
    text.push_str(&format!(
        "withheld levels (every fold in turn, the outer ones included), sets with an effect named that moves the statistics beyond their noise ({}): the fitted models' error against the truth no worse than the baseline's on {no_worse}/{} = {} pooled over the folds (target >= 90%), in every fold on {every_fold}/{}; median shrink {:.2} (target >= 0.5)\n",
        moving.len(),
        moving.len(),
        percent(no_worse, moving.len()),
        moving.len(),
        median(truth_shrinks),
    ));
    text.push_str(&format!(
        "time: {total_s:.0} s in all, median {:.0} s per diagnosis\n",
        median(rows.iter().map(|r| r.seconds).collect())
    ));
    text
}

#[cfg(test)]
mod tests {
    use super::{RESPONSE_NOISE_WEIGHT, SetShape, Truth, independent};
    use crate::engine::{Effect, Engine};

    /// How far a truth's one hidden effect moves the response at `ratios`
    /// of its natural frequency and `loads_n`, over 5 s records.
    fn weight(effect: Effect, form: u32, loads_n: &[f64], ratios: &[f64]) -> f64 {
        let (mut truth, conditions) =
            independent::random_truth(3, &[(effect, form, true)], loads_n, ratios).expect("a truth");
        truth.integration.warmup_s = 1.0;
        truth.integration.step_rate_hz = 100e3;
        let shape = SetShape { runs_per_condition: 1, duration_s: 5.0, sample_rate_hz: 600.0 };
        let engine = Engine::cpu("a test");
        let truth = Truth::Independent(Box::new(truth), 3);
        let stats = truth.stats(&conditions, shape, &engine).expect("its statistics");
        truth.effect_weight(&stats, &conditions, shape, &engine).expect("its weight")
    }

    /// An independent truth's effect is weighed against its twin without
    /// it on the same noise paths: a load dependence of the whole law moves
    /// the response far beyond its noise, and stiction where the block
    /// never stops (near resonance, at a light load) not at all.
    #[test]
    fn an_effect_is_weighed_against_its_twin_without_it() {
        let load = weight(Effect::LoadDependentFriction, 0, &[4.0, 16.0], &[0.8]);
        assert!(load > RESPONSE_NOISE_WEIGHT, "a strong Hertzian load dependence moves the response by {load}");
        let stiction = weight(Effect::Stiction, 0, &[1.0], &[1.1, 1.2]);
        assert!(stiction < RESPONSE_NOISE_WEIGHT, "stiction where the block never stops moves it by {stiction}");
    }
}
