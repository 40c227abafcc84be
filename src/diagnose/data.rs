//! The measured data as the diagnosis sees it: grouped into units (one
//! condition's runs, or one run, or one summary row), split into fitting and
//! held-out units, with each unit's measured observables.

use std::collections::BTreeMap;

use crate::diagnose::calibrate::{self, FrictionLaw};
use crate::diagnose::features::{RunFeatures, run_features};
use crate::diagnose::measure::{MeasurementSet, Run};
use crate::diagnose::observable::Observable;
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
    /// Record length per unit, s (for simulated records).
    pub(crate) record_s: Vec<f64>,
    pub(crate) sample_interval_s: f64,
    /// Mean measured normal force per condition key (where recorded), N.
    pub(crate) measured_normal_force_n: BTreeMap<(i64, i64), f64>,
    /// Longest record, s.
    pub(crate) longest_record_s: f64,
    /// The friction law fitted to the fitting units' force channels.
    pub(crate) measured_law: Option<FrictionLaw>,
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

impl<'a> Data<'a> {
    pub(crate) fn new(set: &'a MeasurementSet) -> Result<Data<'a>> {
        let mut by_condition: BTreeMap<(i64, i64), (Condition, Vec<usize>)> = BTreeMap::new();
        for (i, run) in set.runs.iter().enumerate() {
            let c =
                Condition { excitation_frequency_hz: run.excitation_frequency_hz, normal_force_n: run.normal_force_n };
            by_condition.entry(condition_key(c)).or_insert((c, Vec::new())).1.push(i);
        }
        let mut units = Vec::new();
        let multi = by_condition.values().all(|(_, runs)| runs.len() >= 2);
        for (ci, (c, runs)) in by_condition.values().enumerate() {
            if multi {
                for (k, r) in runs.iter().enumerate() {
                    units.push(Unit { condition: *c, runs: vec![*r], summary: None, heldout: k % 2 == 1 });
                }
            } else {
                units.push(Unit {
                    condition: *c,
                    runs: runs.clone(),
                    summary: None,
                    heldout: by_condition.len() > 1 && ci % 2 == 1,
                });
            }
        }
        let n_summary = set.summary.len();
        for (i, row) in set.summary.iter().enumerate() {
            let c = Condition {
                excitation_frequency_hz: row.excitation_frequency_hz,
                normal_force_n: row.normal_force_mean_n,
            };
            units.push(Unit {
                condition: c,
                runs: Vec::new(),
                summary: Some(i),
                heldout: n_summary > 2 && i % 2 == 1 && set.runs.is_empty(),
            });
        }
        if units.is_empty() {
            return Err(Error::Measurement {
                file: set.dir.join("manifest.json"),
                line: None,
                message: "no runs and no summary rows".into(),
            });
        }
        let mut measured = Vec::new();
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
                record_s.push(row.n_peaks.unwrap_or(350) as f64 / row.excitation_frequency_hz);
            } else {
                let feats: Vec<RunFeatures> = u.runs.iter().map(|&r| run_features(&set.runs[r])).collect();
                measured.push(average_features(&feats));
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
        let measured_law = calibrate::fit_friction_law(&fit_runs);
        Ok(Data {
            set,
            units,
            measured,
            record_s,
            sample_interval_s,
            measured_normal_force_n,
            longest_record_s,
            measured_law,
        })
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
                    .map(|i| drift_factor(d.form, d.rate_per_s, start + length * (f64::from(i) + 0.5) / 64.0))
                    .sum::<f64>()
                    / 64.0
            }
            None => 1.0,
        };
        Condition { normal_force_n: measured / factor, ..u.condition }
    }
}
