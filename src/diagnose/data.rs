//! The measured data as the diagnosis sees it: grouped into units (one
//! condition's runs, or one run, or one summary row), split into fitting and
//! held-out units, with each unit's measured observables.

use std::collections::{BTreeMap, HashMap};
use std::sync::{Arc, Mutex};

use serde::Serialize;

use crate::diagnose::calibrate::{self, FrictionLaw};
use crate::diagnose::features::{RunFeatures, run_features};
use crate::diagnose::measure::{MeasurementSet, Run};
use crate::diagnose::observable::Observable;
use crate::diagnose::simulate::{RecordCache, UnitGrids};
use crate::diagnose::{Model, mean};
use crate::engine::Condition;
use crate::engine::cpu::effects::drift_factor;
use crate::engine::reduce::circular_mean_var;
use crate::error::{Error, Result};

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

/// The measured data and how it is split.
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
    /// Mean measured normal force per condition key (where recorded), N.
    pub(crate) measured_normal_force_n: BTreeMap<(i64, i64), f64>,
    /// Longest record, s.
    pub(crate) longest_record_s: f64,
    /// The friction law fitted to the fitting units' force channels.
    pub(crate) measured_law: Option<FrictionLaw>,
    /// The measurement noise on the records' channels.
    pub(crate) sensor: SensorNoise,
    /// Which units are held out.
    pub(crate) hold_out: HoldOut,
    /// The sensor-noise draws of simulated replicate records, by (seed,
    /// realisation): the same for every model, so drawn once per diagnosis
    /// (they were a tenth of its time).
    pub(crate) sensor_draws: SensorDraws,
    /// What the last models' replicate records of the fitting units gave
    /// (features, the law's moments): each record simulated once.
    pub(crate) fitting_records: RecordCache,
    /// Each unit's simulated records' sample grid, made once.
    pub(crate) grids: UnitGrids,
}

/// Standard Gaussian pairs (for `x`, `v`) per sample of a simulated record,
/// by (seed, realisation), computed once and shared.
#[derive(Debug, Default)]
pub(crate) struct SensorDraws(Mutex<HashMap<(u64, u32), Draws>>);

/// One record's sensor-noise draws: a standard Gaussian pair per sample.
type Draws = Arc<Vec<(f64, f64)>>;

impl SensorDraws {
    /// The first `n` pairs of (seed, realisation), made by `draw` (given
    /// the sample index) the first time they are asked for.
    pub(crate) fn get(&self, seed: u64, realisation: u32, n: usize, draw: impl Fn(usize) -> (f64, f64)) -> Draws {
        let cached = self.0.lock().expect("sensor draws lock").get(&(seed, realisation)).cloned();
        if let Some(d) = cached.filter(|d| d.len() >= n) {
            return d;
        }
        let drawn = Arc::new((0..n).map(draw).collect::<Vec<_>>());
        self.0.lock().expect("sensor draws lock").insert((seed, realisation), Arc::clone(&drawn));
        drawn
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

/// How a set is split into fitting and held-out units: whole normal-force
/// levels where there are three or more (so the held-out gap measures the
/// fitted model at a load no fit saw), else whole frequencies, else
/// alternate runs or conditions.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HoldOut {
    /// These nominal normal forces are held out, N.
    LoadLevels(Vec<f64>),
    /// These excitation frequencies are held out, Hz.
    Frequencies(Vec<f64>),
    /// Alternate runs of every condition.
    AlternateRuns,
    /// Alternate conditions.
    AlternateConditions,
    /// Nothing is held out (too little data).
    Nothing,
}

impl HoldOut {
    /// In words, for the report.
    pub fn describe(&self) -> String {
        let list = |v: &[f64], unit: &str| v.iter().map(|x| format!("{x} {unit}")).collect::<Vec<_>>().join(", ");
        match self {
            HoldOut::LoadLevels(v) => format!("the normal-force level(s) {} (every condition there)", list(v, "N")),
            HoldOut::Frequencies(v) => format!("the frequency(ies) {} (every condition there)", list(v, "Hz")),
            HoldOut::AlternateRuns => "alternate runs of every condition".into(),
            HoldOut::AlternateConditions => "alternate conditions".into(),
            HoldOut::Nothing => "nothing (too little data)".into(),
        }
    }
}

/// The interior levels of a sorted list taken alternately (index 1, 3, …,
/// never the extremes), from three levels up.
fn interior_alternates(levels: &[f64]) -> Vec<f64> {
    if levels.len() < 3 {
        return Vec::new();
    }
    levels.iter().enumerate().filter(|(i, _)| i % 2 == 1 && *i + 1 < levels.len()).map(|(_, v)| *v).collect()
}

/// Whether two nominal levels (N or Hz) are the same one: equal to 1e-6.
fn same_level(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6 * b.abs().max(1.0)
}

/// Distinct values, sorted, compared by [`same_level`].
pub(crate) fn levels(values: impl Iterator<Item = f64>) -> Vec<f64> {
    let mut v: Vec<f64> = values.collect();
    v.sort_by(f64::total_cmp);
    v.dedup_by(|a, b| same_level(*a, *b));
    v
}

/// The load levels to hold out: at each frequency, the interior levels of
/// that frequency's own loads taken alternately, so that every held-out
/// condition lies between two fitted loads at its frequency (the fit is
/// asked to interpolate in load, and in the sliding speeds that load sets,
/// not to extrapolate past the fastest or slowest motion it saw). Where the
/// loads form a grid shared by every frequency this is the grid's interior
/// alternates; where no frequency has three loads of its own, the interior
/// alternates of all loads.
fn held_out_loads(conditions: &[Condition], loads: &[f64], frequencies: &[f64]) -> Vec<f64> {
    let mut held: Vec<f64> = frequencies
        .iter()
        .flat_map(|&f| {
            let at_f = levels(
                conditions.iter().filter(|c| same_level(c.excitation_frequency_hz, f)).map(|c| c.normal_force_n),
            );
            interior_alternates(&at_f)
        })
        .collect();
    held = levels(held.into_iter());
    if held.is_empty() { interior_alternates(loads) } else { held }
}

/// Chooses the split for conditions with these (frequency, load) pairs.
fn choose_hold_out(conditions: &[Condition], runs_per_condition: &[usize]) -> HoldOut {
    let loads = levels(conditions.iter().map(|c| c.normal_force_n));
    let frequencies = levels(conditions.iter().map(|c| c.excitation_frequency_hz));
    if loads.len() >= 3 {
        HoldOut::LoadLevels(held_out_loads(conditions, &loads, &frequencies))
    } else if frequencies.len() >= 3 {
        HoldOut::Frequencies(interior_alternates(&frequencies))
    } else if !runs_per_condition.is_empty() && runs_per_condition.iter().all(|&r| r >= 2) {
        HoldOut::AlternateRuns
    } else if conditions.len() > 1 {
        HoldOut::AlternateConditions
    } else {
        HoldOut::Nothing
    }
}

impl HoldOut {
    /// Whether a condition (the `index`-th of its kind) is held out.
    fn holds(&self, c: Condition, index: usize) -> bool {
        let near = |list: &[f64], x: f64| list.iter().any(|&v| same_level(v, x));
        match self {
            HoldOut::LoadLevels(v) => near(v, c.normal_force_n),
            HoldOut::Frequencies(v) => near(v, c.excitation_frequency_hz),
            HoldOut::AlternateRuns | HoldOut::AlternateConditions => index % 2 == 1,
            HoldOut::Nothing => false,
        }
    }
}

/// Standard deviation of the white measurement noise on a uniformly sampled
/// channel: from the median absolute fourth difference, which a smooth signal
/// barely moves at the sample rate while white noise of sd σ gives sd √70 σ
/// (the median makes the occasional kink of a stick/slip event harmless).
pub(crate) fn white_noise_sd(values: &[f64]) -> f64 {
    if values.len() < 64 {
        return 0.0;
    }
    let mut d4: Vec<f64> =
        values.windows(5).map(|w| (w[0] - 4.0 * w[1] + 6.0 * w[2] - 4.0 * w[3] + w[4]).abs()).collect();
    let mid = d4.len() / 2;
    let (_, median, _) = d4.select_nth_unstable_by(mid, f64::total_cmp);
    (*median / 0.674_489_750_196_081_7 / 70f64.sqrt()).max(0.0)
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

impl<'a> Data<'a> {
    pub(crate) fn new(set: &'a MeasurementSet) -> Result<Data<'a>> {
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
        // Time series decide the split when there are any; a summary-only
        // set is split by its rows.
        let hold_out = if set.runs.is_empty() {
            let h = choose_hold_out(&summary_conditions, &[]);
            // Two summary rows leave nothing worth holding out.
            if h == HoldOut::AlternateConditions && summary_conditions.len() <= 2 { HoldOut::Nothing } else { h }
        } else {
            choose_hold_out(&conditions, &runs_per_condition)
        };
        let mut units = Vec::new();
        for (ci, (c, runs)) in by_condition.values().enumerate() {
            if hold_out == HoldOut::AlternateRuns {
                for (k, r) in runs.iter().enumerate() {
                    units.push(Unit { condition: *c, runs: vec![*r], summary: None, heldout: k % 2 == 1 });
                }
            } else {
                units.push(Unit { condition: *c, runs: runs.clone(), summary: None, heldout: hold_out.holds(*c, ci) });
            }
        }
        for (i, c) in summary_conditions.iter().enumerate() {
            let heldout = set.runs.is_empty() && hold_out.holds(*c, i);
            units.push(Unit { condition: *c, runs: Vec::new(), summary: Some(i), heldout });
        }
        if units.is_empty() {
            return Err(Error::Measurement {
                file: set.dir.join("manifest.json"),
                line: None,
                message: "no runs and no summary rows".into(),
            });
        }
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
                let feats: Vec<RunFeatures> = u.runs.iter().map(|&r| run_features(&set.runs[r])).collect();
                measured.push(average_features(&feats));
                features.push(feats);
                record_s.push(mean(&u.runs.iter().map(|&r| set.runs[r].duration_s()).collect::<Vec<_>>()));
            }
        }
        let sample_interval_s = set.runs.first().map(|r| r.sample_interval_s()).unwrap_or(1.0 / 600.0);
        // Mean measured normal force per condition, over the runs that record it.
        let mut forces: BTreeMap<(i64, i64), Vec<f64>> = BTreeMap::new();
        for r in &set.runs {
            if let Some(n) = &r.normal_force {
                let c =
                    Condition { excitation_frequency_hz: r.excitation_frequency_hz, normal_force_n: r.normal_force_n };
                forces.entry(condition_key(c)).or_default().push(mean(n));
            }
        }
        let measured_normal_force_n = forces.into_iter().map(|(k, v)| (k, mean(&v))).collect();
        let longest_record_s = set.runs.iter().map(|r| r.duration_s()).fold(0.0, f64::max);
        let fit_runs: Vec<&Run> =
            units.iter().filter(|u| !u.heldout).flat_map(|u| u.runs.iter().map(|&r| &set.runs[r])).collect();
        let sensor = SensorNoise::estimate(&set.runs);
        let measured_law = calibrate::fit_friction_law(&fit_runs, sensor.v_m_per_s);
        Ok(Data {
            set,
            units,
            measured,
            features,
            record_s,
            sample_interval_s,
            measured_normal_force_n,
            longest_record_s,
            measured_law,
            sensor,
            hold_out,
            sensor_draws: SensorDraws::default(),
            fitting_records: RecordCache::default(),
            grids: UnitGrids::default(),
        })
    }

    /// Whether the data state the normal force's noise: a recorded N
    /// channel or a stated N variance. The baseline's σ_N then comes from
    /// them ([`crate::diagnose::calibrate`]) and is not scaled on the
    /// response's spread.
    pub(crate) fn states_normal_force_noise(&self) -> bool {
        self.set.summary.iter().any(|s| s.normal_force_var_n2.is_some())
            || self.set.runs.iter().any(|r| r.normal_force.is_some())
    }

    pub(crate) fn has_heldout(&self) -> bool {
        self.units.iter().any(|u| u.heldout)
    }

    /// The condition a unit is simulated at under `model`: N0 such that the
    /// simulated record's mean normal force equals the measured mean (where
    /// recorded), allowing for the model's drift over warm-up and record.
    pub(crate) fn simulated_condition(&self, u: &Unit, model: &Model, warmup_cycles: u32) -> Condition {
        let Some(&measured) = self.measured_normal_force_n.get(&condition_key(u.condition)) else { return u.condition };
        let start = f64::from(warmup_cycles) / u.condition.excitation_frequency_hz;
        let length = self.longest_record_s;
        let factor = match &model.effects.normal_force_drift {
            Some(d) => {
                (0..64)
                    .map(|i| {
                        drift_factor(
                            d.form,
                            d.rate_per_s,
                            d.curvature_per_s2,
                            start + length * (f64::from(i) + 0.5) / 64.0,
                        )
                    })
                    .sum::<f64>()
                    / 64.0
            }
            None => 1.0,
        };
        Condition { normal_force_n: measured / factor, ..u.condition }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(pairs: &[(f64, f64)]) -> Vec<Condition> {
        pairs.iter().map(|&(f, n)| Condition { excitation_frequency_hz: f, normal_force_n: n }).collect()
    }

    /// A load grid shared by every frequency: its interior levels, taken
    /// alternately, are held out at every frequency.
    #[test]
    fn a_shared_load_grid_holds_out_its_interior_levels() {
        let c: Vec<(f64, f64)> =
            [5.0, 6.0, 7.0].iter().flat_map(|&f| [10.0, 20.0, 30.0, 40.0, 50.0].map(|n| (f, n))).collect();
        assert_eq!(choose_hold_out(&grid(&c), &[1; 15]), HoldOut::LoadLevels(vec![20.0, 40.0]));
    }

    /// Loads that differ by frequency (each a share of that frequency's own
    /// threshold): the middle load at each frequency is held out, never two
    /// loads of one frequency that leave its fastest motion unfitted.
    #[test]
    fn loads_that_differ_by_frequency_are_held_out_within_each_frequency() {
        let c = grid(&[(8.0, 20.4), (8.0, 33.2), (8.0, 45.9), (10.0, 26.3), (10.0, 42.8), (10.0, 59.2)]);
        assert_eq!(choose_hold_out(&c, &[1; 6]), HoldOut::LoadLevels(vec![33.2, 42.8]));
        // No frequency with three loads of its own: the interior alternates
        // of all the loads.
        let c = grid(&[(8.0, 10.0), (9.0, 20.0), (10.0, 30.0), (11.0, 40.0)]);
        assert_eq!(choose_hold_out(&c, &[1; 4]), HoldOut::LoadLevels(vec![20.0]));
    }
}
