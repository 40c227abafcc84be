//! The measured data as the diagnosis sees it: grouped into units (one
//! condition's runs, or one run, or one summary row), split into fitting and
//! held-out units, with each unit's measured observables.

use std::collections::BTreeMap;
use std::sync::Arc;

use serde::Serialize;

use crate::diagnose::cache::Caches;
use crate::diagnose::derived::DerivedChannels;
use crate::diagnose::features::{RunFeatures, run_features_read, white_noise_sd};
use crate::diagnose::law::{self, FrictionLaw, LawMoments, Spread};
use crate::diagnose::observable::Observable;
use crate::diagnose::{Model, mean};
use crate::engine::Condition;
use crate::engine::effects::HarmonicForm;
use crate::engine::reduce::circular_mean_var;
use crate::error::{Error, Result};
use crate::measure::{MeasurementSet, Run, SAMPLING_TOLERANCE, fmt_rate_hz, sample_rate_hz};
use crate::text::shown;

/// One group of measured data at one condition.
#[derive(Clone, Debug)]
pub(crate) struct Unit {
    pub(crate) condition: Condition,
    /// Indices into `set.runs` (time series) ...
    pub(crate) runs: Vec<usize>,
    /// ... or into `set.summary`.
    pub(crate) summary: Option<usize>,
    pub(crate) heldout: bool,
}

/// The measured data as one view of its folds sees it: every unit, with
/// the ones this view holds out marked, and the friction law fitted to the
/// force channels of the units it fits. [`Data::new`] makes the view that
/// holds nothing out (every model's full-data fit); [`Data::view`] the view
/// of one fold. Views share the simulation caches.
#[derive(Clone)]
pub(crate) struct Data<'a> {
    pub(crate) set: &'a MeasurementSet,
    pub(crate) units: Vec<Unit>,
    /// Measured observables per unit (mean over its runs).
    pub(crate) measured: Vec<BTreeMap<Observable, f64>>,
    /// The features of each unit's measured runs (empty for summary rows).
    pub(crate) features: Vec<Vec<RunFeatures>>,
    /// Record length per unit, s (for simulated records).
    pub(crate) record_s: Vec<f64>,
    pub(crate) sample_interval_s: f64,
    /// The measured normal force per condition key (where recorded).
    pub(crate) measured_load: BTreeMap<(i64, i64), MeasuredLoad>,
    /// Longest record, s.
    pub(crate) longest_record_s: f64,
    /// The friction law fitted to the fitting units' force channels, at the
    /// Stribeck rate `c` of the law fitted to every unit's (one rate for
    /// every view, so the simulated records' law moments serve them all).
    pub(crate) measured_law: Option<FrictionLaw>,
    /// The Stribeck rate of the law fitted to every unit's force channels,
    /// s/m: the rate at which every view's measured law, and the law
    /// moments of every simulated record, are taken.
    pub(crate) law_c: Option<f64>,
    /// Per unit, its records' law moments at `law_c` (empty without a law
    /// or for summary rows): what each condition's spread about a view's
    /// law is read from ([`Data::measured_spreads`]).
    pub(crate) unit_moments: Arc<Vec<Vec<LawMoments>>>,
    /// The measurement noise on the records' channels.
    pub(crate) sensor: SensorNoise,
    /// The channels derived from the displacement (none of the runs
    /// records them): the replicate records' are derived alike.
    pub(crate) derived: DerivedChannels,
    /// The folds of the set.
    pub(crate) folds: Folds,
    /// The fold this view holds out (`None`: every unit is fitted).
    pub(crate) fold: Option<usize>,
    /// What every view shares: the simulation caches.
    pub(crate) caches: Arc<Caches>,
}

/// A condition's measured normal force, and the moments of its records'
/// displacement that a load following the position needs.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct MeasuredLoad {
    /// Mean normal force, N.
    pub(crate) mean_n: f64,
    /// Mean of r = x/U0 and of r² (–; U0 the run's base amplitude, 0
    /// where it is 0).
    pub(crate) mean_r: f64,
    pub(crate) mean_r2: f64,
}

impl MeasuredLoad {
    fn of(n: &[f64], x_m: &[f64], u0_m: f64) -> MeasuredLoad {
        let r: Vec<f64> = if u0_m > 0.0 { x_m.iter().map(|x| x / u0_m).collect() } else { Vec::new() };
        let r2: Vec<f64> = r.iter().map(|r| r * r).collect();
        let or_zero = |v: &[f64]| if v.is_empty() { 0.0 } else { mean(v) };
        MeasuredLoad { mean_n: mean(n), mean_r: or_zero(&r), mean_r2: or_zero(&r2) }
    }

    fn mean(loads: &[MeasuredLoad]) -> MeasuredLoad {
        let of = |f: fn(&MeasuredLoad) -> f64| mean(&loads.iter().map(f).collect::<Vec<_>>());
        MeasuredLoad { mean_n: of(|l| l.mean_n), mean_r: of(|l| l.mean_r), mean_r2: of(|l| l.mean_r2) }
    }
}

/// Averages the scored features of several records.
fn average_features(features: &[RunFeatures]) -> BTreeMap<Observable, f64> {
    let mut sums: BTreeMap<Observable, Vec<f64>> = BTreeMap::new();
    for f in features {
        for (observable, value) in f.named_values() {
            if observable.scored() {
                sums.entry(observable).or_default().push(value);
            }
        }
    }
    sums.into_iter()
        .filter(|(_, v)| v.len() == features.len())
        .map(|(k, v)| {
            let average = if k.is_angle_deg() {
                let radians: Vec<f64> = v.iter().map(|d| d.to_radians()).collect();
                circular_mean_var(&radians).0.to_degrees()
            } else {
                mean(&v)
            };
            (k, average)
        })
        .collect()
}

pub(crate) fn condition_key(c: Condition) -> (i64, i64) {
    ((c.excitation_frequency_hz * 1e6).round() as i64, (c.normal_force_n * 1e6).round() as i64)
}

/// How a set is cut into folds for cross-validation: each fold is a group
/// of units that a model is fitted without and then asked to predict.
/// Whole normal-force levels where there are three or more loads at some
/// frequency (every level in turn, the lightest and the heaviest included:
/// a fitted model is used beyond the loads it saw); else whole frequency
/// groups; else alternate runs of every condition; else alternate
/// conditions; else nothing (one unit: no cross-validation).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FoldKind {
    /// The k-th lightest load at each frequency (with a load grid shared by
    /// every frequency, one load level).
    LoadLevels,
    /// Groups of neighbouring excitation frequencies.
    Frequencies,
    /// Alternate runs of every condition.
    AlternateRuns,
    /// Alternate conditions.
    AlternateConditions,
    /// Nothing is held out (too little data).
    Nothing,
    /// Conditions crossed over load levels and frequencies: the k-th fold
    /// holds out, at the j-th frequency, the load level group (k + j) mod
    /// K, so every fold holds out some conditions at every load and every
    /// frequency (see [`Folds::crossed`]).
    Crossed,
}

/// One fold: the units it holds out, and what they are in words.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Fold {
    /// What is held out, e.g. "normal force 8 N" or "7.0–7.5 Hz".
    pub label: String,
    /// Indices of the held-out units.
    #[serde(skip)]
    pub units: Vec<usize>,
    /// Their conditions (nominal), each once.
    #[serde(skip)]
    pub conditions: Vec<Condition>,
}

/// The folds of a set.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Folds {
    pub kind: FoldKind,
    pub folds: Vec<Fold>,
}

impl Folds {
    /// In words, for the report.
    pub fn describe(&self) -> String {
        let labels = self.folds.iter().map(|f| f.label.as_str()).collect::<Vec<_>>().join("; ");
        match self.kind {
            FoldKind::LoadLevels => format!("each normal-force level in turn ({labels})"),
            FoldKind::Frequencies => format!("each frequency group in turn ({labels})"),
            FoldKind::AlternateRuns => "alternate runs of every condition, each half in turn".into(),
            FoldKind::AlternateConditions => format!("alternate conditions, each half in turn ({labels})"),
            FoldKind::Nothing => "nothing (too little data to hold any out)".into(),
            FoldKind::Crossed => format!("conditions crossed over loads and frequencies ({labels})"),
        }
    }

    /// These load-level folds crossed with the frequencies (`conditions[i]`
    /// of unit i): with K level groups, the j-th lowest frequency's units of
    /// level group g go to fold (g + j) mod K. Each fold then holds out
    /// conditions at every load and at every frequency, and a unit is
    /// predicted from the other frequencies at its own load. An effect seen
    /// at one load alone (stiction where the block sticks only under the
    /// heaviest load) can be learned out of sample in these folds, and in
    /// no level fold, where a model fitted to the loads that never stick is
    /// asked about the one that does. `None` for folds of another kind or
    /// at one frequency.
    pub(crate) fn crossed(&self, conditions: &[Condition]) -> Option<Folds> {
        let k = self.folds.len();
        let units = || self.folds.iter().flat_map(|f| f.units.iter().copied());
        let frequencies = levels(units().map(|i| conditions[i].excitation_frequency_hz));
        if self.kind != FoldKind::LoadLevels || k < 2 || frequencies.len() < 2 {
            return None;
        }
        let mut held = vec![Vec::new(); k];
        for (g, fold) in self.folds.iter().enumerate() {
            for &i in &fold.units {
                let f = conditions[i].excitation_frequency_hz;
                let j = frequencies.iter().position(|&x| same_level(x, f)).unwrap_or(0);
                held[(g + j) % k].push(i);
            }
        }
        let folds = held
            .into_iter()
            .enumerate()
            .filter(|(_, u)| !u.is_empty())
            .map(|(n, mut units)| {
                units.sort_unstable();
                let mut at: Vec<Condition> = units.iter().map(|&i| conditions[i]).collect();
                at.dedup_by_key(|c| condition_key(*c));
                Fold { label: format!("crossed set {} of {k}", n + 1), units, conditions: at }
            })
            .collect();
        Some(Folds { kind: FoldKind::Crossed, folds })
    }

    /// Whether there is anything to cross-validate.
    pub fn any(&self) -> bool {
        !self.folds.is_empty()
    }
}

/// At most this many folds: levels or frequencies beyond it are grouped
/// (every fold costs a refit of each model it judges).
pub const MAX_FOLDS: usize = 5;

/// Whether two nominal levels (N or Hz) are the same one: equal to 1e-6.
pub(crate) fn same_level(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * b.abs().max(1.0)
}

/// Distinct values, sorted, compared by [`same_level`].
pub(crate) fn levels(values: impl Iterator<Item = f64>) -> Vec<f64> {
    let mut v: Vec<f64> = values.collect();
    v.sort_by(f64::total_cmp);
    v.dedup_by(|a, b| same_level(*a, *b));
    v
}

/// `n` items cut into at most [`MAX_FOLDS`] contiguous groups of nearly
/// equal size: the group of each item.
fn groups(n: usize) -> Vec<usize> {
    let k = n.clamp(1, MAX_FOLDS);
    (0..n).map(|i| i * k / n.max(1)).collect()
}

/// A list of values with a unit, for fold labels: "8 N", "7–7.5 Hz".
fn span_label(values: &[f64], unit: &str) -> String {
    let show = |x: f64| crate::engine::model::fmt_value(x);
    match values {
        [] => String::new(),
        [one] => format!("{} {unit}", show(*one)),
        [first, .., last] => format!("{}–{} {unit}", show(*first), show(*last)),
    }
}

/// The folds of units at these conditions (`conditions[i]` of unit i). With
/// `run_index` (units of one run each, `run_index[i]` the unit's index among
/// its condition's runs) and neither loads nor frequencies to hold out,
/// alternate runs.
fn choose_folds(conditions: &[Condition], run_index: Option<&[usize]>) -> Folds {
    let frequencies = levels(conditions.iter().map(|c| c.excitation_frequency_hz));
    let loads_at = |f: f64| {
        levels(conditions.iter().filter(|c| same_level(c.excitation_frequency_hz, f)).map(|c| c.normal_force_n))
    };
    let ranks = frequencies.iter().map(|&f| loads_at(f).len()).max().unwrap_or(0);
    let make = |kind: FoldKind, group_of: &dyn Fn(usize) -> usize, label_of: &dyn Fn(&[usize]) -> String| {
        let count = (0..conditions.len()).map(group_of).max().map_or(0, |m| m + 1);
        let folds = (0..count)
            .map(|g| {
                let units: Vec<usize> = (0..conditions.len()).filter(|&i| group_of(i) == g).collect();
                let mut held: Vec<Condition> = units.iter().map(|&i| conditions[i]).collect();
                held.dedup_by_key(|c| condition_key(*c));
                Fold { label: label_of(&units), units, conditions: held }
            })
            .filter(|f| !f.units.is_empty())
            .collect();
        Folds { kind, folds }
    };
    if ranks >= 3 {
        // The k-th lightest load at each frequency (grouped beyond MAX_FOLDS).
        let rank_group = groups(ranks);
        let rank_of = |i: usize| {
            let c = conditions[i];
            let at_f = loads_at(c.excitation_frequency_hz);
            at_f.iter().position(|&n| same_level(n, c.normal_force_n)).unwrap_or(0)
        };
        let group_of = |i: usize| rank_group[rank_of(i)];
        let label_of = |units: &[usize]| {
            let loads = levels(units.iter().map(|&i| conditions[i].normal_force_n));
            if loads.len() <= 2 {
                format!("normal force {}", loads.iter().map(|&n| span_label(&[n], "N")).collect::<Vec<_>>().join(", "))
            } else {
                format!("normal forces {}", span_label(&loads, "N"))
            }
        };
        return make(FoldKind::LoadLevels, &group_of, &label_of);
    }
    if frequencies.len() >= 2 {
        let frequency_group = groups(frequencies.len());
        let group_of = |i: usize| {
            let f = conditions[i].excitation_frequency_hz;
            frequency_group[frequencies.iter().position(|&x| same_level(x, f)).unwrap_or(0)]
        };
        let label_of =
            |units: &[usize]| span_label(&levels(units.iter().map(|&i| conditions[i].excitation_frequency_hz)), "Hz");
        return make(FoldKind::Frequencies, &group_of, &label_of);
    }
    if let Some(run_index) = run_index {
        let group_of = |i: usize| run_index[i] % 2;
        let label_of =
            |units: &[usize]| if run_index[units[0]] % 2 == 0 { "even runs".into() } else { "odd runs".into() };
        return make(FoldKind::AlternateRuns, &group_of, &label_of);
    }
    if conditions.len() >= 3 {
        let group_of = |i: usize| i % 2;
        let label_of = |units: &[usize]| {
            if units[0].is_multiple_of(2) { "even conditions".into() } else { "odd conditions".into() }
        };
        return make(FoldKind::AlternateConditions, &group_of, &label_of);
    }
    Folds { kind: FoldKind::Nothing, folds: Vec::new() }
}

/// The measurement noise estimated on the records' channels, added to every
/// simulated replicate record so that features see the same noise on both
/// sides (a stick test at 1% of the largest speed, say, is decided by it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct SensorNoise {
    /// Displacement noise, m.
    pub x_m: f64,
    /// Velocity noise, m/s.
    pub v_m_per_s: f64,
}

impl SensorNoise {
    /// The median over the runs of each channel's estimate.
    fn estimate(runs: &[Run]) -> SensorNoise {
        let median = |mut v: Vec<f64>| {
            if v.is_empty() {
                return 0.0;
            }
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        SensorNoise {
            x_m: median(runs.iter().map(|r| white_noise_sd(&r.x_m)).collect()),
            v_m_per_s: median(runs.iter().filter_map(|r| r.v_m_per_s.as_deref().map(white_noise_sd)).collect()),
        }
    }
}

/// The sample interval (s) every run of a set shares (within
/// [`SAMPLING_TOLERANCE`]; 1/600 s, the paper's, for a set of summary rows
/// alone). A diagnosis simulates every record at one sample interval, which
/// is also the baseline's noise interval (the friction and normal-force
/// noise held over one sample), so a set whose runs are sampled at
/// different rates is refused, naming a run of each rate: scored against
/// replicates sampled at another rate, a record's noise features (the
/// friction's lag-1 autocorrelation, say) are tens of standard errors off
/// for that reason alone.
fn one_sample_interval(runs: &[Run]) -> Result<f64> {
    let Some(first) = runs.first() else { return Ok(1.0 / 600.0) };
    let dt = first.sample_interval_s();
    match runs.iter().find(|r| (r.sample_interval_s() / dt - 1.0).abs() > SAMPLING_TOLERANCE) {
        None => Ok(dt),
        Some(other) => Err(Error::Measurement {
            file: other.file.clone(),
            line: None,
            message: format!(
                "sampled at {} Hz, while {} is sampled at {} Hz: a diagnosis simulates every record at one rate \
                 (the baseline's noise is held over one sample interval), so the runs of a set must share one; {}",
                fmt_rate_hz(sample_rate_hz(other)),
                shown(&first.file),
                fmt_rate_hz(sample_rate_hz(first)),
                common_rate_hint(runs)
            ),
        }),
    }
}

/// How runs sampled at different rates can be brought to one: where the
/// slowest rate divides every other (each an integer multiple of it),
/// thinning the faster runs to it (`--sample-rate`) does it in place;
/// otherwise they must be resampled.
fn common_rate_hint(runs: &[Run]) -> String {
    let slowest = runs.iter().map(sample_rate_hz).fold(f64::INFINITY, f64::min);
    let divides = runs.iter().all(|r| {
        let ratio = sample_rate_hz(r) / slowest;
        (ratio - ratio.round()).abs() <= SAMPLING_TOLERANCE * ratio
    });
    if divides {
        let rate = fmt_rate_hz(slowest);
        format!("{rate} Hz divides every run's rate, so `--sample-rate {rate}` thins the faster runs to it")
    } else {
        "no run's rate divides all the others, so resample them to a common rate".to_string()
    }
}

impl<'a> Data<'a> {
    /// The data of `set`, whose channels `derived` names were derived from
    /// the displacement ([`crate::diagnose::derived`]): the model's
    /// replicate records are then derived the same way, and a derived
    /// velocity's noise is the displacement's through the filter.
    pub(crate) fn new(set: &'a MeasurementSet, derived: DerivedChannels) -> Result<Data<'a>> {
        let mut by_condition: BTreeMap<(i64, i64), (Condition, Vec<usize>)> = BTreeMap::new();
        for (i, run) in set.runs.iter().enumerate() {
            let c =
                Condition { excitation_frequency_hz: run.excitation_frequency_hz, normal_force_n: run.normal_force_n };
            by_condition.entry(condition_key(c)).or_insert((c, Vec::new())).1.push(i);
        }
        let conditions: Vec<Condition> = by_condition.values().map(|(c, _)| *c).collect();
        let runs_per_condition: Vec<usize> = by_condition.values().map(|(_, r)| r.len()).collect();
        let summary_conditions: Vec<Condition> = set
            .summary
            .iter()
            .map(|row| Condition {
                excitation_frequency_hz: row.excitation_frequency_hz,
                normal_force_n: row.normal_force_mean_n,
            })
            .collect();
        // Time series decide the folds when there are any; a summary-only
        // set is cut by its rows. Units hold every run of a condition,
        // unless nothing but alternate runs can be held out.
        let mut units: Vec<Unit> = by_condition
            .values()
            .map(|(c, runs)| Unit { condition: *c, runs: runs.clone(), summary: None, heldout: false })
            .collect();
        let mut folds =
            if set.runs.is_empty() { choose_folds(&summary_conditions, None) } else { choose_folds(&conditions, None) };
        let only_alternates = matches!(folds.kind, FoldKind::Nothing | FoldKind::AlternateConditions);
        if !set.runs.is_empty() && only_alternates && runs_per_condition.iter().all(|&r| r >= 2) {
            units = by_condition
                .values()
                .flat_map(|(c, runs)| {
                    runs.iter().map(|&r| Unit { condition: *c, runs: vec![r], summary: None, heldout: false })
                })
                .collect();
            let run_index: Vec<usize> = by_condition.values().flat_map(|(_, runs)| 0..runs.len()).collect();
            let per_run: Vec<Condition> = units.iter().map(|u| u.condition).collect();
            folds = choose_folds(&per_run, Some(&run_index));
        }
        let record_units = units.len();
        for c in &summary_conditions {
            units.push(Unit { condition: *c, runs: Vec::new(), summary: None, heldout: false });
        }
        for (i, u) in units[record_units..].iter_mut().enumerate() {
            u.summary = Some(i);
        }
        // Record folds hold out the record units; a summary table beside
        // records is fitted in every fold.
        if !set.runs.is_empty() {
            for f in &mut folds.folds {
                f.units.retain(|&i| i < record_units);
            }
        }
        if units.is_empty() {
            return Err(Error::Measurement {
                file: set.dir.join("manifest.json"),
                line: None,
                message: "no runs and no summary rows".into(),
            });
        }
        let mut sensor = SensorNoise::estimate(&set.runs);
        if derived.v {
            let mut noise: Vec<f64> =
                set.runs.iter().map(|r| crate::diagnose::derived::velocity_noise(r, sensor.x_m)).collect();
            noise.sort_by(f64::total_cmp);
            sensor.v_m_per_s = noise.get(noise.len() / 2).copied().unwrap_or(0.0);
        }
        // The measured records read as the model's replicates are.
        let reading = reading_of(set, &sensor, derived);
        let mut measured = Vec::new();
        let mut features = Vec::new();
        let mut record_s = Vec::new();
        for u in &units {
            if let Some(i) = u.summary {
                let row = &set.summary[i];
                let mut m = BTreeMap::new();
                for (observable, value) in [
                    (Observable::PeakMeanM, row.peak_mean_m),
                    (Observable::PeakVarM2, row.peak_var_m2),
                    (Observable::PhaseMeanDeg, row.phase_mean_deg),
                    (Observable::PhaseVarDeg2, row.phase_var_deg2),
                ] {
                    if let Some(v) = value {
                        m.insert(observable, v);
                    }
                }
                measured.push(m);
                features.push(Vec::new());
                record_s.push(row.n_peaks.unwrap_or(350) as f64 / row.excitation_frequency_hz);
            } else {
                let feats: Vec<RunFeatures> =
                    u.runs.iter().map(|&r| run_features_read(&set.runs[r], reading.motion(&set.runs[r]))).collect();
                measured.push(average_features(&feats));
                features.push(feats);
                record_s.push(mean(&u.runs.iter().map(|&r| set.runs[r].duration_s()).collect::<Vec<_>>()));
            }
        }
        let sample_interval_s = one_sample_interval(&set.runs)?;
        // The measured normal force per condition, over the runs that record it.
        let mut forces: BTreeMap<(i64, i64), Vec<MeasuredLoad>> = BTreeMap::new();
        for r in &set.runs {
            if let Some(n) = &r.normal_force {
                let c =
                    Condition { excitation_frequency_hz: r.excitation_frequency_hz, normal_force_n: r.normal_force_n };
                forces.entry(condition_key(c)).or_default().push(MeasuredLoad::of(n, &r.x_m, r.excitation_amplitude_m));
            }
        }
        let measured_load = forces.into_iter().map(|(k, v)| (k, MeasuredLoad::mean(&v))).collect();
        let longest_record_s = set.runs.iter().map(|r| r.duration_s()).fold(0.0, f64::max);
        let all_runs: Vec<&Run> = set.runs.iter().collect();
        let measured_law = law::fit_friction_law(&all_runs, &reading);
        let unit_moments = units
            .iter()
            .map(|u| match measured_law {
                Some(l) => u.runs.iter().map(|&r| LawMoments::of_run(&set.runs[r], &reading, l.c)).collect(),
                None => Vec::new(),
            })
            .collect();
        Ok(Data {
            set,
            units,
            measured,
            features,
            record_s,
            sample_interval_s,
            measured_load,
            longest_record_s,
            measured_law,
            law_c: measured_law.map(|l| l.c),
            unit_moments: Arc::new(unit_moments),
            sensor,
            derived,
            folds,
            fold: None,
            caches: Arc::new(Caches::default()),
        })
    }

    /// The view of fold `fold` (`None`: nothing held out): its units marked,
    /// and the friction law fitted to the force channels of the units it
    /// fits, at the full data's Stribeck rate (`None` where those runs give
    /// no law).
    pub(crate) fn view(&self, fold: Option<usize>) -> Data<'a> {
        let mut view = self.clone();
        let held: &[usize] = fold.and_then(|k| self.folds.folds.get(k)).map_or(&[], |f| &f.units[..]);
        for (i, u) in view.units.iter_mut().enumerate() {
            u.heldout = held.contains(&i);
        }
        view.fold = fold;
        if let Some(all) = self.measured_law.filter(|_| fold.is_some()) {
            let runs: Vec<&Run> = view
                .units
                .iter()
                .filter(|u| !u.heldout)
                .flat_map(|u| u.runs.iter().map(|&r| &self.set.runs[r]))
                .collect();
            view.measured_law = law::fit_friction_law_at(&runs, &self.reading(), all.c);
        }
        view
    }

    /// The data cut into [`Folds::crossed`], where the set's folds are load
    /// levels at several frequencies (`None` otherwise): the weaker test a
    /// family is judged on where none predicts a withheld level beyond the
    /// noise, whether it predicts conditions it was not fitted to within
    /// the loads it was. A model named on it must still predict every
    /// withheld level no worse than the baseline.
    pub(crate) fn crossed(&self) -> Option<Data<'a>> {
        let conditions: Vec<Condition> = self.units.iter().map(|u| u.condition).collect();
        let folds = self.folds.crossed(&conditions)?;
        Some(Data { folds, ..self.clone() })
    }

    /// Every fold's view, in fold order.
    pub(crate) fn fold_views(&self) -> Vec<Data<'a>> {
        (0..self.folds.folds.len()).map(|k| self.view(Some(k))).collect()
    }

    /// Whether the data state the normal force's noise: a recorded N
    /// channel or a stated N variance. The baseline's σ_N then comes from
    /// them ([`crate::diagnose::calibrate`]) and is not scaled on the
    /// response's spread.
    pub(crate) fn states_normal_force_noise(&self) -> bool {
        self.set.summary.iter().any(|s| s.normal_force_var_n2.is_some())
            || self.set.runs.iter().any(|r| r.normal_force.is_some())
    }

    /// How the friction law reads this data's records, and the model's
    /// replicates of them ([`law::Reading`]).
    pub(crate) fn reading(&self) -> law::Reading<'a> {
        reading_of(self.set, &self.sensor, self.derived)
    }

    /// Per unit of `units`, its records' spread about this view's measured
    /// law ([`Spread::about`]; `None` without a law).
    pub(crate) fn measured_spreads(&self, units: &[usize]) -> Vec<Option<Spread>> {
        units.iter().map(|&u| self.measured_law.and_then(|l| Spread::about(&self.unit_moments[u], &l))).collect()
    }

    pub(crate) fn has_heldout(&self) -> bool {
        self.units.iter().any(|u| u.heldout)
    }

    /// The set's normal-force levels (nominal, N), fitting and held-out
    /// units alike, ascending. A load dependence is what differs between
    /// them: on a set of one load it is the baseline's law, and it is
    /// neither searched nor tested for power there.
    pub(crate) fn loads(&self) -> Vec<f64> {
        levels(self.units.iter().map(|u| u.condition.normal_force_n))
    }

    /// The condition a unit is simulated at under `model`: N0 such that the
    /// simulated record's mean normal force equals the measured mean (where
    /// recorded), allowing for the model's drift over the record (its clock
    /// starts where the record does) and for a load that follows the
    /// position (its N0 is the load at x = 0, read from the measured mean
    /// with the measured displacement's moments).
    pub(crate) fn simulated_condition(&self, u: &Unit, model: &Model) -> Condition {
        let Some(&load) = self.measured_load.get(&condition_key(u.condition)) else { return u.condition };
        // The engine scales N0 by the drift's nominal scale (where the model
        // says over which window N0 is the mean force), then by the drift.
        let factor = model
            .effects
            .normal_force_drift
            .as_ref()
            .map_or(1.0, |d| d.mean_factor(0.0, self.longest_record_s) * d.nominal_scale());
        // A load that follows the position adds N0 (α r + β r²) to N, whose
        // mean over the measured record is N0 (α r̄ + β r²̄).
        let position = match &model.effects.normal_force_harmonics {
            Some(h) if h.form == HarmonicForm::Position => {
                (1.0 + h.amplitudes_per_n0[0] * load.mean_r + h.amplitudes_per_n0[1] * load.mean_r2).max(0.1)
            }
            _ => 1.0,
        };
        Condition { normal_force_n: load.mean_n / (factor * position), ..u.condition }
    }
}

/// How the friction law reads `set`'s records: with the sensors' velocity
/// noise, and through the rig's equation of motion where the friction is
/// derived from the displacement ([`law::Reading`]).
fn reading_of<'a>(set: &'a MeasurementSet, sensor: &SensorNoise, derived: DerivedChannels) -> law::Reading<'a> {
    law::Reading { v_noise_m_per_s: sensor.v_m_per_s, derived_with: derived.friction.then_some(&set.rig) }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(pairs: &[(f64, f64)]) -> Vec<Condition> {
        pairs.iter().map(|&(f, n)| Condition { excitation_frequency_hz: f, normal_force_n: n }).collect()
    }

    /// The loads held out by each fold, by unit.
    fn fold_loads(folds: &Folds, c: &[Condition]) -> Vec<Vec<f64>> {
        folds.folds.iter().map(|f| levels(f.units.iter().map(|&i| c[i].normal_force_n))).collect()
    }

    /// A load grid shared by every frequency: every level is a fold, the
    /// lightest and the heaviest included.
    #[test]
    fn a_shared_load_grid_holds_out_each_level_in_turn() {
        let c: Vec<(f64, f64)> = [5.0, 6.0, 7.0].iter().flat_map(|&f| [4.0, 8.0, 16.0].map(|n| (f, n))).collect();
        let folds = choose_folds(&grid(&c), None);
        assert_eq!(folds.kind, FoldKind::LoadLevels);
        assert_eq!(fold_loads(&folds, &grid(&c)), vec![vec![4.0], vec![8.0], vec![16.0]]);
        assert!(folds.folds.iter().all(|f| f.units.len() == 3));
        assert_eq!(folds.folds[0].label, "normal force 4 N");
    }

    /// Loads that differ by frequency (each a share of that frequency's own
    /// threshold): fold k holds the k-th lightest load of every frequency.
    #[test]
    fn loads_that_differ_by_frequency_are_held_out_by_rank() {
        let c = grid(&[(8.0, 20.4), (8.0, 33.2), (8.0, 45.9), (10.0, 26.3), (10.0, 42.8), (10.0, 59.2)]);
        let folds = choose_folds(&c, None);
        assert_eq!(fold_loads(&folds, &c), vec![vec![20.4, 26.3], vec![33.2, 42.8], vec![45.9, 59.2]]);
        // Many levels are grouped into at most MAX_FOLDS folds.
        let many: Vec<(f64, f64)> = (0..9).map(|i| (7.0, 2.0 + f64::from(i))).collect();
        assert_eq!(choose_folds(&grid(&many), None).folds.len(), MAX_FOLDS);
    }

    /// Two loads: whole frequencies are held out instead (a load dependence
    /// needs both loads in every fit); one condition, alternate runs.
    #[test]
    fn few_loads_hold_out_frequencies_and_one_condition_alternate_runs() {
        let c = grid(&[(6.0, 4.0), (6.0, 8.0), (7.0, 4.0), (7.0, 8.0), (8.0, 4.0), (8.0, 8.0)]);
        let folds = choose_folds(&c, None);
        assert_eq!(folds.kind, FoldKind::Frequencies);
        assert_eq!(folds.folds.len(), 3);
        assert!(folds.folds.iter().all(|f| f.units.len() == 2));
        let one = grid(&[(7.0, 8.0); 4]);
        let folds = choose_folds(&one, Some(&[0, 1, 2, 3]));
        assert_eq!(folds.kind, FoldKind::AlternateRuns);
        assert_eq!(folds.folds.iter().map(|f| f.units.clone()).collect::<Vec<_>>(), vec![vec![0, 2], vec![1, 3]]);
        assert_eq!(choose_folds(&grid(&[(7.0, 8.0)]), None).kind, FoldKind::Nothing);
    }

    /// Crossed folds hold out every unit once; each holds out every
    /// frequency once and every load twice (three loads, six
    /// frequencies), and a held-out unit's load is fitted at the other
    /// frequencies. Folds of other kinds are not crossed.
    #[test]
    fn crossed_folds_hold_out_every_load_and_frequency() {
        let freqs = [5.0, 6.0, 7.0, 8.0, 9.0, 10.0];
        let c = grid(&freqs.iter().flat_map(|&f| [4.0, 8.0, 16.0].map(|n| (f, n))).collect::<Vec<_>>());
        let crossed = choose_folds(&c, None).crossed(&c).expect("crossed");
        assert_eq!(crossed.kind, FoldKind::Crossed);
        assert_eq!(crossed.folds.len(), 3);
        let mut all: Vec<usize> = crossed.folds.iter().flat_map(|f| f.units.clone()).collect();
        all.sort_unstable();
        assert_eq!(all, (0..c.len()).collect::<Vec<_>>());
        for fold in &crossed.folds {
            let at = |f: f64| fold.units.iter().filter(|&&i| c[i].excitation_frequency_hz == f).count();
            assert!(freqs.iter().all(|&f| at(f) == 1), "{fold:?}");
            for n in [4.0, 8.0, 16.0] {
                assert_eq!(fold.units.iter().filter(|&&i| c[i].normal_force_n == n).count(), 2, "{fold:?}");
                let fitted = (0..c.len()).filter(|i| !fold.units.contains(i) && c[*i].normal_force_n == n).count();
                assert_eq!(fitted, 4);
            }
        }
        // One frequency, or folds of frequencies: nothing to cross.
        let one = grid(&[(7.0, 4.0), (7.0, 8.0), (7.0, 16.0)]);
        assert_eq!(choose_folds(&one, None).crossed(&one), None);
        let two_loads = grid(&[(6.0, 4.0), (6.0, 8.0), (7.0, 4.0), (7.0, 8.0)]);
        assert_eq!(choose_folds(&two_loads, None).crossed(&two_loads), None);
    }
}
