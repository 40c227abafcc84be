//! Diagnosis of the sim-to-real gap (`stickslip diagnose`).
//!
//! 1. **Calibrate** the baseline: the friction law and its noise from the
//!    force channels where they exist (a least-squares Stribeck fit of
//!    μ = |F|/N against speed while slipping, matched between measured and
//!    simulated records by indirect inference), σ_N and each condition's N0
//!    from the measured normal force. Without force channels the friction
//!    level `a` is solved so the simulated mean peaks (GPU ensembles) match
//!    the measured ones.
//! 2. **Locate**: every observable of `features.rs` is computed by the same
//!    code from the measured records and from simulated replicate records of
//!    the same length and sampling; each (condition, observable) gets a
//!    z-score against the simulator's own replicate spread. `locations` are
//!    those with |z| > 3.
//! 3. **Attribute**: for each effect (its candidate form), the strength is
//!    searched with the baseline recalibrated at every trial (the friction
//!    law and σ_μ, or `a`), so an effect cannot win by shifting the baseline
//!    and is not judged against a law its own signature distorted; the gap
//!    left is measured.
//! 4. **Quantify**: the gap metric is the mean z² over (condition,
//!    observable); `shrink` is measured on the fitting units and
//!    `heldout_shrink` on units left out of every fit (alternate runs of a
//!    condition, or alternate conditions). The verdict is `none` unless the
//!    best candidate lowers the held-out gap by more than its noise.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use crate::cpu::{self, RunPlan};
use crate::effects;
use crate::error::{Error, Result};
use crate::features::{run_features, RunFeatures};
use crate::gpu;
use crate::measure::{read_measurement_set, MeasurementSet, Run};
use crate::model::{Condition, Model, Oscillator};
use crate::reduce::PeakRange;
use crate::sweep::{initial_state, Backend};

/// Settings of a diagnosis.
#[derive(Clone, Copy, Debug)]
pub struct DiagnoseSettings {
    pub seed: u64,
    /// Simulated replicate records per condition.
    pub replicates: u32,
    /// Realisations per condition in the GPU ensembles that solve for `a`.
    pub ensemble_realisations: u32,
    /// Warm-up periods before a simulated record starts.
    pub warmup_cycles: u32,
}

impl Default for DiagnoseSettings {
    fn default() -> Self {
        DiagnoseSettings { seed: 20_251_122, replicates: 8, ensemble_realisations: 64, warmup_cycles: 60 }
    }
}

/// Observables not scored: counts, and what calibration sets by construction.
const UNSCORED: [&str; 5] = ["peak_count", "friction_slip_samples", "normal_force_mean_n", "normal_force_var_n2", "normal_force_drift_n_per_s"];

/// Huber threshold of the gap metric: z² up to |z| = 3, then 6|z| − 9, so a
/// wild observable counts linearly (it cannot swamp the rest) yet every
/// improvement still counts. Under pure noise the mean is about 0.98.
const HUBER_K: f64 = 3.0;

fn huber(z: f64) -> f64 {
    let a = z.abs();
    if a <= HUBER_K { a * a } else { 2.0 * HUBER_K * a - HUBER_K * HUBER_K }
}

/// Which motion phase an observable describes (for `locations`).
fn phase_of(observable: &str) -> &'static str {
    match observable {
        o if o.starts_with("peak_") => "whole cycle: per-period peak amplitude",
        o if o.starts_with("normal_force") => "whole cycle: normal force",
        "friction_hysteresis" => "slip: accelerating against decelerating branch",
        "friction_breakaway_mean" | "friction_stiction_excess" => "stick to slip: breakaway",
        "friction_low_speed_mu_mean" => "slip: just above zero velocity",
        "stick_fraction" => "stick",
        _ => "slip: random part of the friction coefficient",
    }
}

/// One group of measured data at one condition.
#[derive(Clone, Debug)]
struct Unit {
    condition: Condition,
    /// Indices into `set.runs` (time series) ...
    runs: Vec<usize>,
    /// ... or into `set.summary`.
    summary: Option<usize>,
    heldout: bool,
}

/// Per (condition, observable): measured value and simulated replicates.
#[derive(Clone, Debug, Serialize)]
pub struct Score {
    pub excitation_frequency_hz: f64,
    pub normal_force_n: f64,
    pub observable: String,
    pub measured: f64,
    pub simulated: f64,
    pub z: f64,
    pub heldout: bool,
}

/// Mean Huber loss of z over scores; 0 for none.
fn gap_of(scores: &[Score], heldout: bool) -> f64 {
    let picked: Vec<f64> = scores.iter().filter(|s| s.heldout == heldout).map(|s| huber(s.z)).collect();
    if picked.is_empty() { 0.0 } else { picked.iter().sum::<f64>() / picked.len() as f64 }
}

fn count_of(scores: &[Score], heldout: bool) -> usize {
    scores.iter().filter(|s| s.heldout == heldout).count()
}

/// A candidate's result.
#[derive(Clone, Debug, Serialize)]
pub struct Candidate {
    pub effect: String,
    /// Gap on the fitting units after fitting this effect.
    pub gap_fit: f64,
    /// Gap on the held-out units.
    pub gap_heldout: f64,
    pub shrink: f64,
    pub heldout_shrink: Option<f64>,
    pub parameters: BTreeMap<String, f64>,
    /// What the candidate still leaves: its five largest |z|.
    pub unexplained: Vec<(String, f64, f64, f64)>,
    #[serde(skip)]
    pub model: Model,
}

/// Everything a diagnosis found.
#[derive(Clone, Debug)]
pub struct Diagnosis {
    pub baseline: Model,
    pub fitted: Model,
    pub verdict: String,
    pub confidence: f64,
    pub baseline_scores: Vec<Score>,
    pub fitted_scores: Vec<Score>,
    pub gap_fit: f64,
    pub gap_heldout: f64,
    pub candidates: Vec<Candidate>,
    /// Threshold the held-out improvement had to beat.
    pub noise_threshold: f64,
    pub has_heldout: bool,
    pub conditions: Vec<Condition>,
}

/// The measured data and how it is split.
struct Data<'a> {
    set: &'a MeasurementSet,
    units: Vec<Unit>,
    /// Measured observables per unit (mean over its runs).
    measured: Vec<BTreeMap<String, f64>>,
    /// Record length per unit in excitation periods (for simulated records).
    record_s: Vec<f64>,
    sample_interval_s: f64,
    /// Mean measured normal force per condition key (where recorded), N.
    measured_normal_force_n: BTreeMap<(i64, i64), f64>,
    /// Longest record, s.
    longest_record_s: f64,
    /// The friction law fitted to the fitting units' force channels.
    measured_law: Option<FrictionLaw>,
}

fn mean(values: &[f64]) -> f64 {
    values.iter().sum::<f64>() / values.len().max(1) as f64
}

fn sd(values: &[f64]) -> f64 {
    if values.len() < 2 {
        return 0.0;
    }
    let m = mean(values);
    (values.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (values.len() - 1) as f64).sqrt()
}

/// Averages the named features of several records.
fn average_features(features: &[RunFeatures]) -> BTreeMap<String, f64> {
    let mut sums: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for f in features {
        for (name, value) in f.named_values() {
            if !UNSCORED.contains(&name) {
                sums.entry(name.to_string()).or_default().push(value);
            }
        }
    }
    sums.into_iter().filter(|(_, v)| v.len() == features.len()).map(|(k, v)| (k, mean(&v))).collect()
}

fn condition_key(c: Condition) -> (i64, i64) {
    ((c.excitation_frequency_hz * 1e6).round() as i64, (c.normal_force_n * 1e6).round() as i64)
}

impl<'a> Data<'a> {
    fn new(set: &'a MeasurementSet) -> Result<Data<'a>> {
        let mut by_condition: BTreeMap<(i64, i64), (Condition, Vec<usize>)> = BTreeMap::new();
        for (i, run) in set.runs.iter().enumerate() {
            let c = Condition { excitation_frequency_hz: run.excitation_frequency_hz, normal_force_n: run.normal_force_n };
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
                units.push(Unit { condition: *c, runs: runs.clone(), summary: None, heldout: by_condition.len() > 1 && ci % 2 == 1 });
            }
        }
        let n_summary = set.summary.len();
        for (i, row) in set.summary.iter().enumerate() {
            let c = Condition { excitation_frequency_hz: row.excitation_frequency_hz, normal_force_n: row.normal_force_mean_n };
            units.push(Unit { condition: c, runs: Vec::new(), summary: Some(i), heldout: n_summary > 2 && i % 2 == 1 && set.runs.is_empty() });
        }
        if units.is_empty() {
            return Err(Error::Measurement { file: set.dir.join("manifest.json"), line: None, message: "no runs and no summary rows".into() });
        }
        let mut measured = Vec::new();
        let mut record_s = Vec::new();
        for u in &units {
            if let Some(i) = u.summary {
                let row = &set.summary[i];
                let mut m = BTreeMap::new();
                m.insert("peak_mean_m".to_string(), row.peak_mean_m);
                if let Some(v) = row.peak_var_m2 {
                    m.insert("peak_var_m2".to_string(), v);
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
                let c = Condition { excitation_frequency_hz: r.excitation_frequency_hz, normal_force_n: r.normal_force_n };
                forces.entry(condition_key(c)).or_default().push(mean(n));
            }
        }
        let measured_normal_force_n = forces.into_iter().map(|(k, v)| (k, mean(&v))).collect();
        let longest_record_s = set.runs.iter().map(|r| r.duration_s()).fold(0.0, f64::max);
        let fit_runs: Vec<&Run> = units.iter().filter(|u| !u.heldout).flat_map(|u| u.runs.iter().map(|&r| &set.runs[r])).collect();
        let measured_law = fit_friction_law(&fit_runs);
        Ok(Data { set, units, measured, record_s, sample_interval_s, measured_normal_force_n, longest_record_s, measured_law })
    }

    fn has_heldout(&self) -> bool {
        self.units.iter().any(|u| u.heldout)
    }

    /// The condition a unit is simulated at under `model`: N0 such that the
    /// simulated record's mean normal force equals the measured mean (where
    /// recorded), allowing for the model's drift over warm-up and record.
    fn simulated_condition(&self, u: &Unit, model: &Model, warmup_cycles: u32) -> Condition {
        let Some(&measured) = self.measured_normal_force_n.get(&condition_key(u.condition)) else { return u.condition };
        let start = f64::from(warmup_cycles) / u.condition.excitation_frequency_hz;
        let length = self.longest_record_s;
        let factor = match &model.effects.normal_force_drift {
            Some(d) => {
                let form = d.form as u32;
                (0..64).map(|i| effects::drift_factor(form, d.rate_per_s, start + length * (f64::from(i) + 0.5) / 64.0)).sum::<f64>() / 64.0
            }
            None => 1.0,
        };
        Condition { normal_force_n: measured / factor, ..u.condition }
    }
}

/// Simulates one record of `seconds` at `condition`, sampled like the data.
fn simulate_record(model: &Model, condition: Condition, seconds: f64, sample_interval_s: f64, seed: u64, realisation: u32, warmup: u32) -> Result<Run> {
    let osc = Oscillator::new(model, condition)?;
    let samples = cpu::sample_record(&osc, seed, realisation, warmup, seconds, sample_interval_s, initial_state(model, condition));
    Ok(Run::from_samples(&samples, condition.excitation_frequency_hz, model.excitation.amplitude_m, condition.normal_force_n))
}

/// Per-path peak statistics of a GPU (or CPU) ensemble: for each condition,
/// the per-realisation mean and variance of `cycles` peaks.
fn ensemble_path_stats(model: &Model, conditions: &[Condition], cycles: u32, realisations: u32, seed: u64, warmup: u32, backend: &Backend) -> Result<Vec<Vec<(f64, f64)>>> {
    let plan = RunPlan { warmup_cycles: warmup, measured_cycles: cycles.max(2) };
    let stats = |peaks: &[f64]| (mean(peaks), sd(peaks).powi(2));
    match backend {
        Backend::Gpu(ctx) => {
            let specs = conditions
                .iter()
                .map(|&c| Ok(gpu::PointSpec { oscillator: Oscillator::new(model, c)?, initial: initial_state(model, c), range: PeakRange::for_point(model, c) }))
                .collect::<Result<Vec<_>>>()?;
            let request = gpu::EnsembleRequest {
                points: &specs,
                realisations_per_point: realisations,
                realisation_offset: 0,
                seed,
                plan,
                steps_per_dispatch: gpu::DEFAULT_STEPS_PER_DISPATCH,
                record_peaks: true,
            };
            let out = gpu::run_ensemble(&ctx.device, &ctx.queue, &ctx.kernels, &request, &mut |_, _| {})?;
            let paths = out.paths.expect("recorded");
            Ok(paths.chunks(realisations as usize).map(|chunk| chunk.iter().map(|p| stats(&p.peaks_m)).collect()).collect())
        }
        Backend::Cpu => conditions
            .iter()
            .map(|&c| {
                let osc = Oscillator::new(model, c)?;
                Ok(cpu::simulate_ensemble(&osc, seed, 0..realisations, plan, initial_state(model, c)).iter().map(|p| stats(&p.peaks_m)).collect())
            })
            .collect(),
    }
}

/// Solves for the friction level `a` (with everything else fixed) so the
/// simulated mean peaks match the measured ones on the fitting units, on
/// average (relative), with small GPU ensembles. With `slope` (d residual /
/// d a, from the baseline's solve) one Newton step is taken; without it a
/// secant search runs and returns the slope it found.
fn solve_friction_level(model: &Model, data: &Data<'_>, settings: &DiagnoseSettings, backend: &Backend, slope: Option<f64>) -> Result<(Model, f64)> {
    let fit: Vec<&Unit> = data.units.iter().filter(|u| !u.heldout).collect();
    let conditions: Vec<Condition> = fit.iter().map(|u| data.simulated_condition(u, model, settings.warmup_cycles)).collect();
    let targets: Vec<f64> = data.units.iter().zip(&data.measured).filter(|(u, _)| !u.heldout).map(|(_, m)| m.get("peak_mean_m").copied().unwrap_or(f64::NAN)).collect();
    // The same window as the data: the records' (or summaries') length.
    let cycles = data
        .units
        .iter()
        .zip(&data.record_s)
        .filter(|(u, _)| !u.heldout)
        .map(|(u, s)| (s * u.condition.excitation_frequency_hz).round() as u32)
        .max()
        .unwrap_or(100);
    let residual = |a: f64| -> Result<f64> {
        let mut m = model.clone();
        m.friction.a = a;
        m.validate()?;
        let stats = ensemble_path_stats(&m, &conditions, cycles, settings.ensemble_realisations.min(24), settings.seed ^ 0xA5A5, settings.warmup_cycles, backend)?;
        let errs: Vec<f64> = stats.iter().zip(&targets).filter(|(_, t)| t.is_finite() && **t > 0.0).map(|(s, t)| mean(&s.iter().map(|p| p.0).collect::<Vec<_>>()) / t - 1.0).collect();
        Ok(mean(&errs))
    };
    let lowest = (-model.friction.b).max(0.0);
    let with_a = |a: f64| {
        let mut out = model.clone();
        out.friction.a = a.clamp(lowest, 5.0);
        out
    };
    let mut a0 = model.friction.a.max(lowest);
    let mut r0 = residual(a0)?;
    if let Some(slope) = slope {
        return Ok((with_a(a0 - r0 / slope), slope));
    }
    let mut a1 = (a0 + 0.05).max(lowest + 0.01);
    let mut r1 = residual(a1)?;
    let mut slope = (r1 - r0) / (a1 - a0);
    for _ in 0..5 {
        if r1.abs() < 5e-4 || (r1 - r0).abs() < 1e-12 {
            break;
        }
        let a2 = (a1 - r1 * (a1 - a0) / (r1 - r0)).clamp(lowest, a1 + 0.5).min(5.0);
        (a0, r0) = (a1, r1);
        a1 = a2;
        r1 = residual(a1)?;
        if (a1 - a0).abs() > 1e-9 {
            slope = (r1 - r0) / (a1 - a0);
        }
    }
    let best = if r1.abs() <= r0.abs() { a1 } else { a0 };
    Ok((with_a(best), if slope.is_finite() && slope < 0.0 { slope } else { -1.0 }))
}

/// Calibrates the friction law of `model` to the data and scores it.
///
/// With friction channels this is indirect inference: the same
/// least-squares Stribeck fit (`fit_friction_law_at`, at the measured data's
/// best `c`) is run on the measured records and on the model's simulated
/// replicate records, and `a`, `b` and σ_μ are moved by the difference
/// (σ_μ² by the difference of the residual variances). The fit's numbers are
/// then those of the data whatever else the model carries (two steps, each
/// from the fitting units' replicates alone), so an effect that
/// changes friction (hysteresis lowering it early in a slip, stiction raising
/// it, a noise that is coloured or skewed) is judged with the law and noise
/// level that the data imply *given that effect*, not the ones it distorted.
/// Without friction channels `a` is solved from the response (mean peaks,
/// GPU ensembles).
fn calibrate_and_score(model: &Model, data: &Data<'_>, settings: &DiagnoseSettings, backend: &Backend, slope: Option<f64>) -> Result<(Model, Vec<Score>, f64)> {
    if let Some(measured) = data.measured_law {
        let mut m = model.clone();
        m.friction.c = measured.c;
        for _ in 0..LAW_STEPS {
            let Some(simulated) = simulated_law(&m, data, settings, measured.c)? else { break };
            m.friction.b += measured.b - simulated.b;
            m.friction.a = (m.friction.a + measured.a - simulated.a).max((-m.friction.b).max(0.0));
            let variance = m.friction.sigma.powi(2) + measured.sigma.powi(2) - simulated.sigma.powi(2);
            m.friction.sigma = variance.max((0.1 * measured.sigma).powi(2)).sqrt();
        }
        let scores = score(&m, data, settings, backend)?;
        return Ok((m, scores, slope.unwrap_or(-1.0)));
    }
    let (m, slope) = solve_friction_level(model, data, settings, backend, slope)?;
    let scores = score(&m, data, settings, backend)?;
    Ok((m, scores, slope))
}

/// Scores a model against the data: z per (unit, observable).
fn score(model: &Model, data: &Data<'_>, settings: &DiagnoseSettings, backend: &Backend) -> Result<Vec<Score>> {
    let mut scores = Vec::new();
    let summary_units: Vec<usize> = (0..data.units.len()).filter(|&i| data.units[i].summary.is_some()).collect();
    if !summary_units.is_empty() {
        let conditions: Vec<Condition> = summary_units.iter().map(|&i| data.units[i].condition).collect();
        let cycles = summary_units.iter().map(|&i| data.set.summary[data.units[i].summary.unwrap()].n_peaks.unwrap_or(350) as u32).max().unwrap_or(350);
        let stats = ensemble_path_stats(model, &conditions, cycles, settings.ensemble_realisations, settings.seed, settings.warmup_cycles, backend)?;
        for (&i, per_path) in summary_units.iter().zip(&stats) {
            let u = &data.units[i];
            let means: Vec<f64> = per_path.iter().map(|p| p.0).collect();
            let vars: Vec<f64> = per_path.iter().map(|p| p.1).collect();
            for (name, sim) in [("peak_mean_m", &means), ("peak_var_m2", &vars)] {
                if let Some(&m) = data.measured[i].get(name) {
                    let spread = sd(sim).max(1e-9 * mean(sim).abs() + 1e-300);
                    scores.push(Score {
                        excitation_frequency_hz: u.condition.excitation_frequency_hz,
                        normal_force_n: u.condition.normal_force_n,
                        observable: name.to_string(),
                        measured: m,
                        simulated: mean(sim),
                        z: (m - mean(sim)) / (spread * (1.0 + 1.0 / sim.len() as f64).sqrt()),
                        heldout: u.heldout,
                    });
                }
            }
        }
    }
    // Time series: simulated replicate records through the same feature code.
    let run_units: Vec<usize> = (0..data.units.len()).filter(|&i| data.units[i].summary.is_none()).collect();
    use rayon::prelude::*;
    let simulated: Vec<Result<Vec<RunFeatures>>> = run_units
        .par_iter()
        .map(|&i| (0..settings.replicates).map(|r| Ok(run_features(&simulate_replicate(model, data, settings, i, r)?))).collect())
        .collect();
    for (&i, sims) in run_units.iter().zip(simulated) {
        let sims = sims?;
        let u = &data.units[i];
        let n_meas = u.runs.len() as f64;
        for (name, &m) in &data.measured[i] {
            let values: Vec<f64> = sims.iter().filter_map(|f| f.named_values().into_iter().find(|(n, _)| n == name).map(|(_, v)| v)).collect();
            if values.len() < 2 {
                continue;
            }
            let spread = sd(&values).max(1e-6 * mean(&values).abs()).max(1e-12);
            scores.push(Score {
                excitation_frequency_hz: u.condition.excitation_frequency_hz,
                normal_force_n: u.condition.normal_force_n,
                observable: name.clone(),
                measured: m,
                simulated: mean(&values),
                z: (m - mean(&values)) / (spread * (1.0 / n_meas + 1.0 / values.len() as f64).sqrt()),
                heldout: u.heldout,
            });
        }
    }
    Ok(scores)
}

/// Replicate `replicate` of unit `unit` under `model`: a record as long as
/// the unit's, sampled like the data, on its own noise path (the same path
/// for every model, so differences between models are not noise).
fn simulate_replicate(model: &Model, data: &Data<'_>, settings: &DiagnoseSettings, unit: usize, replicate: u32) -> Result<Run> {
    let c = data.simulated_condition(&data.units[unit], model, settings.warmup_cycles);
    simulate_record(model, c, data.record_s[unit], data.sample_interval_s, settings.seed, replicate + 1000 * unit as u32, settings.warmup_cycles)
}

/// The friction law fitted at `c` to the model's simulated replicates of the
/// fitting units, pooled like the measured fitting runs are.
fn simulated_law(model: &Model, data: &Data<'_>, settings: &DiagnoseSettings, c: f64) -> Result<Option<FrictionLaw>> {
    use rayon::prelude::*;
    let jobs: Vec<(usize, u32)> = (0..data.units.len())
        .filter(|&i| !data.units[i].heldout && data.units[i].summary.is_none())
        .flat_map(|i| (0..settings.replicates).map(move |r| (i, r)))
        .collect();
    let runs = jobs.par_iter().map(|&(i, r)| simulate_replicate(model, data, settings, i, r)).collect::<Result<Vec<Run>>>()?;
    Ok(fit_friction_law_at(&runs.iter().collect::<Vec<_>>(), c))
}

/// The baseline from the data, before solving for `a`.
fn initial_baseline(data: &Data<'_>) -> Result<Model> {
    let set = data.set;
    let mut m = Model::default();
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
    let fit_runs: Vec<&Run> = data.units.iter().filter(|u| !u.heldout).flat_map(|u| u.runs.iter().map(|&r| &data.set.runs[r])).collect();
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
    // The friction law from the force channels, where recorded.
    if let Some(law) = data.measured_law {
        m.friction.a = law.a;
        m.friction.b = law.b;
        m.friction.c = law.c;
        m.friction.d = 0.0;
        m.friction.sigma = law.sigma;
    }
    m.validate()?;
    Ok(m)
}

/// A Stribeck law `μ(v) = a + b / (1 + c |v|)` fitted to slipping samples,
/// with the residual standard deviation around it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct FrictionLaw {
    /// –
    a: f64,
    /// –
    b: f64,
    /// s/m
    c: f64,
    /// Residual standard deviation of μ, –.
    sigma: f64,
}

/// Steps of the friction law's indirect inference (each simulates the
/// fitting units' replicates once).
const LAW_STEPS: usize = 2;

/// Stribeck decay rates `c` (s/m) the law is fitted over.
const LAW_C_GRID: [f64; 7] = [0.0, 2.0, 5.0, 10.0, 20.0, 40.0, 80.0];

/// The law with the smallest residual over [`LAW_C_GRID`]; `None` without
/// force channels or with fewer than 50 slipping samples.
fn fit_friction_law(runs: &[&Run]) -> Option<FrictionLaw> {
    LAW_C_GRID
        .iter()
        .filter_map(|&c| fit_friction_law_at(runs, c))
        .filter(|law| law.a >= 0.0 && law.a + law.b >= 0.0)
        .min_by(|x, y| x.sigma.total_cmp(&y.sigma))
}

/// Least squares of μ = |F|/N against speed on slipping samples (|v| above
/// 5% of the record's largest, friction opposing motion) at a given `c`:
/// linear in (a, b) with basis (1, 1/(1 + c|v|)). `None` with too few
/// samples. The fit is not constrained (as a statistic of simulated records
/// it must be the same function as on the measured ones).
fn fit_friction_law_at(runs: &[&Run], c: f64) -> Option<FrictionLaw> {
    let mut speeds = Vec::new();
    let mut mus = Vec::new();
    for r in runs {
        let (Some(v), Some(f), Some(n)) = (&r.v_m_per_s, &r.friction_force, &r.normal_force) else { continue };
        let vmax = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for i in 0..v.len() {
            if v[i].abs() > 0.05 * vmax && f[i] * v[i] < 0.0 && n[i] > 0.0 {
                speeds.push(v[i].abs());
                mus.push(f[i].abs() / n[i]);
            }
        }
    }
    if mus.len() < 50 {
        return None;
    }
    let basis: Vec<f64> = speeds.iter().map(|s| 1.0 / (1.0 + c * s)).collect();
    let (n, sx, sy) = (mus.len() as f64, basis.iter().sum::<f64>(), mus.iter().sum::<f64>());
    let sxx: f64 = basis.iter().map(|x| x * x).sum();
    let sxy: f64 = basis.iter().zip(&mus).map(|(x, y)| x * y).sum();
    let det = n * sxx - sx * sx;
    let (a, b) = if c == 0.0 || det.abs() < 1e-12 { (sy / n, 0.0) } else { ((sxx * sy - sx * sxy) / det, (n * sxy - sx * sy) / det) };
    let rss: f64 = basis.iter().zip(&mus).map(|(x, y)| (y - a - b * x).powi(2)).sum();
    Some(FrictionLaw { a, b, c, sigma: (rss / (n - 2.0)).sqrt() })
}

/// A candidate: how to set its effect from one strength value.
struct CandidateSpec {
    effect: &'static str,
    /// Strength values to try.
    grid: Vec<f64>,
    /// Values of a second parameter, each tried with every strength
    /// (`[0.0]` where the candidate has one parameter).
    second: Vec<f64>,
    apply: Box<dyn Fn(&Model, f64, f64) -> Model + Sync>,
    /// Parameter names for the report.
    describe: Box<dyn Fn(&Model) -> BTreeMap<String, f64> + Sync>,
}

fn measured_mean(data: &Data<'_>, name: &str) -> Option<f64> {
    let v: Vec<f64> = data.units.iter().zip(&data.measured).filter(|(u, _)| !u.heldout).filter_map(|(_, m)| m.get(name).copied()).collect();
    (!v.is_empty()).then(|| mean(&v))
}

fn log_grid(centre: f64, factors: &[f64]) -> Vec<f64> {
    factors.iter().map(|f| centre * f).collect()
}

fn candidate_specs(data: &Data<'_>, baseline: &Model, baseline_scores: &[Score]) -> Vec<CandidateSpec> {
    let dt = data.sample_interval_s;
    let mean_n0 = mean(&data.units.iter().map(|u| data.simulated_condition(u, baseline, 0).normal_force_n).collect::<Vec<_>>());
    let sim_of = |name: &str| {
        let v: Vec<f64> = baseline_scores.iter().filter(|s| !s.heldout && s.observable == name).map(|s| s.simulated).collect();
        (!v.is_empty()).then(|| mean(&v))
    };
    // Harmonic amplitudes in excess of the baseline's noise floor.
    let harmonic_excess: Vec<f64> = (1..=4)
        .map(|k| {
            let name = format!("normal_force_harmonic{k}_n");
            match (measured_mean(data, &name), sim_of(&name)) {
                (Some(m), Some(s)) => (m * m - s * s).max(0.0).sqrt(),
                _ => 0.0,
            }
        })
        .collect();
    let has_n = harmonic_excess.iter().any(|a| *a > 0.0);
    let skew = measured_mean(data, "friction_residual_skewness").unwrap_or(0.5);
    let drift = measured_mean(data, "normal_force_drift_per_s").or_else(|| measured_mean(data, "peak_trend_per_s").map(|t| -t)).unwrap_or(0.002);
    let mut specs: Vec<CandidateSpec> = Vec::new();
    let excess = harmonic_excess.clone();
    specs.push(CandidateSpec {
        effect: "normal_force_harmonics",
        grid: if has_n { vec![0.5, 0.75, 1.0, 1.25] } else { vec![0.1, 0.3, 1.0, 2.0] },
        second: vec![0.0],
        apply: Box::new(move |m, s, _| {
            let mut m = m.clone();
            let amps = if has_n { [excess[0] * s, excess[1] * s, excess[2] * s, excess[3] * s] } else { [s, 0.0, 0.0, 0.0] };
            m.effects.normal_force_harmonics = Some(effects::NormalForceHarmonics { form: effects::HarmonicForm::Fourier, amplitudes_n: amps, phases_rad: [0.0; 4], shape: 2.0 });
            m
        }),
        describe: Box::new(|m| {
            let h = m.effects.normal_force_harmonics.as_ref().unwrap();
            (0..4).map(|k| (format!("amplitude_{}x_n", k + 1), h.amplitudes_n[k])).collect()
        }),
    });
    let sign = if skew < 0.0 { -1.0 } else { 1.0 };
    specs.push(CandidateSpec {
        effect: "non_gaussian_friction",
        grid: [0.15, 0.3, 0.5, 0.8, 1.2].iter().map(|s| s * sign).collect(),
        second: vec![0.0],
        apply: Box::new(|m, s, _| {
            let mut m = m.clone();
            m.effects.non_gaussian_friction = Some(effects::NonGaussianFriction { form: effects::NonGaussianForm::Skew, strength: s, load_exponent: 0.0, reference_force_n: 10.0 });
            m
        }),
        describe: Box::new(|m| BTreeMap::from([("skew_strength".to_string(), m.effects.non_gaussian_friction.as_ref().unwrap().strength)])),
    });
    specs.push(CandidateSpec {
        effect: "friction_hysteresis",
        grid: vec![2e-5, 5e-5, 1e-4, 2e-4, 4e-4, 8e-4],
        second: vec![0.0],
        apply: Box::new(|m, s, _| {
            let mut m = m.clone();
            m.effects.friction_hysteresis = Some(effects::FrictionHysteresis { form: effects::HysteresisForm::Exponential, length_m: s });
            m
        }),
        describe: Box::new(|m| BTreeMap::from([("length_m".to_string(), m.effects.friction_hysteresis.as_ref().unwrap().length_m)])),
    });
    specs.push(CandidateSpec {
        effect: "coloured_friction_noise",
        grid: log_grid(dt, &[2.0, 4.0, 8.0, 16.0, 32.0]),
        second: vec![0.0],
        apply: Box::new(|m, s, _| {
            let mut m = m.clone();
            m.effects.coloured_friction_noise = Some(effects::ColouredFrictionNoise { form: effects::ColourForm::Ar1, correlation_time_s: s });
            m
        }),
        describe: Box::new(|m| BTreeMap::from([("correlation_time_s".to_string(), m.effects.coloured_friction_noise.as_ref().unwrap().correlation_time_s)])),
    });
    specs.push(CandidateSpec {
        effect: "stiction",
        grid: vec![0.02, 0.05, 0.1, 0.2, 0.35],
        // Static friction that is released at once, or over the first
        // 0.1 or 0.3 mm of slip.
        second: vec![0.0, 1e-4, 3e-4],
        apply: Box::new(|m, s, release| {
            let mut m = m.clone();
            m.effects.stiction = Some(effects::Stiction { form: effects::StictionForm::Constant, excess: s, release_length_m: release });
            m
        }),
        describe: Box::new(|m| {
            let s = m.effects.stiction.as_ref().unwrap();
            BTreeMap::from([("excess".to_string(), s.excess), ("release_length_m".to_string(), s.release_length_m)])
        }),
    });
    // Where friction is measured, the slope of mean μ against N0 across the
    // fitting conditions centres the search.
    let points: Vec<(f64, f64)> = data
        .units
        .iter()
        .zip(&data.measured)
        .filter(|(u, _)| !u.heldout)
        .filter_map(|(u, m)| m.get("friction_mu_mean").map(|mu| (data.simulated_condition(u, baseline, 0).normal_force_n, *mu)))
        .collect();
    let slope_estimate = if points.len() >= 2 {
        let (mx, my) = (mean(&points.iter().map(|p| p.0).collect::<Vec<_>>()), mean(&points.iter().map(|p| p.1).collect::<Vec<_>>()));
        let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
        let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
        (sxx > 0.0).then(|| sxy / sxx).filter(|s| s.abs() > 1e-5)
    } else {
        None
    };
    specs.push(CandidateSpec {
        effect: "load_dependent_friction",
        grid: match slope_estimate {
            Some(s) => log_grid(s, &[0.5, 0.75, 1.0, 1.25, 1.5]),
            None => vec![-0.04, -0.02, -0.01, -0.004, 0.004, 0.01, 0.02, 0.04],
        },
        second: vec![0.0],
        apply: Box::new(move |m, s, _| {
            let mut m = m.clone();
            m.effects.load_dependent_friction = Some(effects::LoadDependentFriction { form: effects::LoadForm::Linear, strength: s, reference_force_n: mean_n0.max(1e-3) });
            m
        }),
        describe: Box::new(|m| {
            let l = m.effects.load_dependent_friction.as_ref().unwrap();
            BTreeMap::from([("slope_per_n".to_string(), l.strength), ("reference_force_n".to_string(), l.reference_force_n)])
        }),
    });
    specs.push(CandidateSpec {
        effect: "normal_force_drift",
        grid: log_grid(if drift == 0.0 { 0.002 } else { drift }, &[0.5, 0.75, 1.0, 1.5]),
        second: vec![0.0],
        apply: Box::new(|m, s, _| {
            let mut m = m.clone();
            m.effects.normal_force_drift = Some(effects::NormalForceDrift { form: effects::DriftForm::Linear, rate_per_s: s });
            m
        }),
        describe: Box::new(|m| BTreeMap::from([("rate_per_s".to_string(), m.effects.normal_force_drift.as_ref().unwrap().rate_per_s)])),
    });
    specs
}

/// Runs the whole diagnosis on a measurement set directory.
pub fn diagnose(dir: &Path, settings: &DiagnoseSettings, backend: &Backend, progress: &mut dyn FnMut(&str)) -> Result<Diagnosis> {
    let set = read_measurement_set(dir)?;
    diagnose_set(&set, settings, backend, progress)
}

/// Runs the whole diagnosis on a measurement set already read.
pub fn diagnose_set(set: &MeasurementSet, settings: &DiagnoseSettings, backend: &Backend, progress: &mut dyn FnMut(&str)) -> Result<Diagnosis> {
    let data = Data::new(set)?;
    progress("calibrating the baseline");
    let (baseline, baseline_scores, slope) = calibrate_and_score(&initial_baseline(&data)?, &data, settings, backend, None)?;
    let (g0_fit, g0_ho) = (gap_of(&baseline_scores, false), gap_of(&baseline_scores, true));
    let specs = candidate_specs(&data, &baseline, &baseline_scores);
    let mut candidates = Vec::new();
    for spec in &specs {
        progress(&format!("trying {}", spec.effect));
        // (gap on the fitting units, calibrated model, scores, strength, second parameter)
        let mut best: Option<(f64, Model, Vec<Score>, f64, f64)> = None;
        let trial_at = |s: f64, t: f64, best: &mut Option<(f64, Model, Vec<Score>, f64, f64)>| -> Result<()> {
            let trial = (spec.apply)(&baseline, s, t);
            if trial.validate().is_err() {
                return Ok(());
            }
            let (trial, scores, _) = calibrate_and_score(&trial, &data, settings, backend, Some(slope))?;
            let g = gap_of(&scores, false);
            if std::env::var_os("STICKSLIP_DEBUG").is_some() {
                let mut w: Vec<&Score> = scores.iter().filter(|s| !s.heldout).collect();
                w.sort_by(|a, b| b.z.abs().total_cmp(&a.z.abs()));
                let top: Vec<String> = w.iter().take(6).map(|s| format!("{}@{:.1}N {:+.1} (m {:.3e} s {:.3e})", s.observable, s.normal_force_n, s.z, s.measured, s.simulated)).collect();
                eprintln!("{} {s:e} {t:e}: a {:.4} b {:.4} sigma {:.4} gap {g:.2} | {}", spec.effect, trial.friction.a, trial.friction.b, trial.friction.sigma, top.join("; "));
            }
            if best.as_ref().is_none_or(|b| g < b.0) {
                *best = Some((g, trial, scores, s, t));
            }
            Ok(())
        };
        for &t in &spec.second {
            for &s in &spec.grid {
                trial_at(s, t, &mut best)?;
            }
        }
        // Refine: halfway to each neighbour of the best strength.
        if let Some((at, t)) = best.as_ref().map(|b| (b.3, b.4)) {
            if let Some(i) = spec.grid.iter().position(|&g| g == at) {
                let neighbours = [i.checked_sub(1).map(|j| spec.grid[j]), spec.grid.get(i + 1).copied()];
                for n in neighbours.into_iter().flatten() {
                    trial_at(0.5 * (at + n), t, &mut best)?;
                }
            }
        }
        let best = best.map(|(g, m, sc, _, _)| (g, m, sc));
        let Some((g1_fit, model, scores)) = best else { continue };
        let g1_ho = gap_of(&scores, true);
        let mut worst: Vec<&Score> = scores.iter().collect();
        worst.sort_by(|a, b| b.z.abs().total_cmp(&a.z.abs()));
        let unexplained = worst.iter().take(5).map(|s| (s.observable.clone(), s.excitation_frequency_hz, s.normal_force_n, s.z)).collect();
        candidates.push(Candidate {
            unexplained,
            effect: spec.effect.to_string(),
            gap_fit: g1_fit,
            gap_heldout: g1_ho,
            shrink: if g0_fit > 0.0 { (g0_fit - g1_fit) / g0_fit } else { 0.0 },
            heldout_shrink: (data.has_heldout() && g0_ho > 0.0).then(|| (g0_ho - g1_ho) / g0_ho),
            parameters: (spec.describe)(&model),
            model,
        });
    }
    // Rank by held-out gap where there is one, else by the fitting gap.
    let key = |c: &Candidate| if data.has_heldout() { c.gap_heldout } else { c.gap_fit };
    candidates.sort_by(|a, b| key(a).total_cmp(&key(b)));
    let k_ho = count_of(&baseline_scores, data.has_heldout()).max(1) as f64;
    // The noise of a mean of k values of z² is about sqrt(2/k): the held-out
    // improvement must beat three of those plus a margin of 0.5 for the
    // replicate estimate of each z's spread.
    let noise_threshold = 3.0 * (2.0 / k_ho).sqrt() + 0.5;
    let g0_key = if data.has_heldout() { g0_ho } else { g0_fit };
    // A real effect must help where it was fitted as well as where it was
    // not: the fitting gap must also fall by more than its own noise.
    let k_fit = count_of(&baseline_scores, false).max(1) as f64;
    let fit_threshold = 3.0 * (2.0 / k_fit).sqrt() + 0.5;
    let (verdict, confidence, fitted, fitted_scores) = match candidates.first() {
        Some(best) if g0_key - key(best) > noise_threshold && g0_fit - best.gap_fit > fit_threshold => {
            let margin = (g0_key - key(best)) / noise_threshold;
            let runner_up = candidates.get(1).map(key).unwrap_or(g0_key);
            let separation = ((runner_up - key(best)) / (g0_key - key(best)).max(1e-9)).clamp(0.0, 1.0);
            let confidence = ((1.0 - (-margin).exp()) * (0.5 + 0.5 * separation)).clamp(0.0, 1.0);
            let scores = score(&best.model, &data, settings, backend)?;
            (best.effect.clone(), confidence, best.model.clone(), scores)
        }
        _ => {
            let best_gain = candidates.first().map(|b| (g0_key - key(b)) / noise_threshold).unwrap_or(0.0);
            ("none".to_string(), (1.0 - best_gain.max(0.0)).clamp(0.05, 0.95), baseline.clone(), baseline_scores.clone())
        }
    };
    let mut conditions: Vec<Condition> = data.units.iter().map(|u| u.condition).collect();
    conditions.dedup_by_key(|c| condition_key(*c));
    Ok(Diagnosis {
        baseline,
        fitted,
        verdict,
        confidence,
        gap_fit: g0_fit,
        gap_heldout: g0_ho,
        baseline_scores,
        fitted_scores,
        candidates,
        noise_threshold,
        has_heldout: data.has_heldout(),
        conditions,
    })
}

impl Diagnosis {
    /// `report.json` as `interfaces.md` describes it (plus extra keys).
    pub fn report_json(&self) -> serde_json::Value {
        let chosen = self.candidates.iter().find(|c| c.effect == self.verdict);
        let after_fit = chosen.map_or(self.gap_fit, |c| c.gap_fit);
        let after_ho = chosen.map_or(self.gap_heldout, |c| c.gap_heldout);
        let shrink = if self.gap_fit > 0.0 { (self.gap_fit - after_fit) / self.gap_fit } else { 0.0 };
        let heldout_shrink = (self.has_heldout && self.gap_heldout > 0.0).then(|| (self.gap_heldout - after_ho) / self.gap_heldout);
        let mut locations: Vec<&Score> = self.baseline_scores.iter().filter(|s| s.z.abs() > 3.0).collect();
        locations.sort_by(|a, b| b.z.abs().total_cmp(&a.z.abs()));
        serde_json::json!({
            "format": "stickslip-diagnosis/1",
            "verdict": { "effect": self.verdict, "confidence": self.confidence },
            "gap": {
                "metric": "mean over (condition, observable) of the Huber loss of z (z² for |z| <= 3, 6|z| − 9 beyond), z = (measured − simulated)/(simulator's replicate spread); fitting units (held-out units for heldout_*)",
                "baseline": self.gap_fit,
                "after": after_fit,
                "shrink": shrink,
                "heldout_shrink": heldout_shrink,
                "heldout_baseline": self.has_heldout.then_some(self.gap_heldout),
                "heldout_after": self.has_heldout.then_some(after_ho),
                "noise_threshold": self.noise_threshold,
            },
            "locations": locations.iter().map(|s| serde_json::json!({
                "excitation_frequency_hz": s.excitation_frequency_hz,
                "normal_force_n": s.normal_force_n,
                "observable": s.observable,
                "detail": format!("{}: measured {:.6e}, baseline simulates {:.6e}{}", phase_of(&s.observable), s.measured, s.simulated, if s.heldout { " (held-out unit)" } else { "" }),
                "score": s.z.abs(),
            })).collect::<Vec<_>>(),
            "candidates": self.candidates.iter().map(|c| serde_json::json!({
                "effect": c.effect,
                "shrink": c.shrink,
                "heldout_shrink": c.heldout_shrink,
                "gap_fit": c.gap_fit,
                "gap_heldout": c.gap_heldout,
                "parameters": c.parameters,
                "unexplained": c.unexplained.iter().map(|(o, f, n, z)| serde_json::json!({"observable": o, "excitation_frequency_hz": f, "normal_force_n": n, "z": z})).collect::<Vec<_>>(),
            })).collect::<Vec<_>>(),
            "models": { "baseline": "baseline-model.toml", "fitted": "fitted-model.toml" },
        })
    }
}

/// How far an effect moves the peak statistics, in units of their noise in
/// one measured record: the largest over conditions of |Δ mean peak| / (sd of
/// a record's mean peak) and |Δ peak variance| / (sd of a record's variance),
/// from ensembles of the truth with and without the effect on the same noise.
pub fn peak_shift_in_noise_units(with: &Model, without: &Model, conditions: &[Condition], shape: crate::synthetic::SetShape, backend: &Backend) -> Result<f64> {
    let cycles = conditions.iter().map(|c| (shape.duration_s * c.excitation_frequency_hz) as u32).max().unwrap_or(100);
    let a = ensemble_path_stats(with, conditions, cycles, 32, 99, 60, backend)?;
    let b = ensemble_path_stats(without, conditions, cycles, 32, 99, 60, backend)?;
    let mut worst: f64 = 0.0;
    for (pa, pb) in a.iter().zip(&b) {
        let (ma, mb): (Vec<f64>, Vec<f64>) = (pa.iter().map(|p| p.0).collect(), pb.iter().map(|p| p.0).collect());
        let (va, vb): (Vec<f64>, Vec<f64>) = (pa.iter().map(|p| p.1).collect(), pb.iter().map(|p| p.1).collect());
        let runs = f64::from(shape.runs_per_condition.max(1)).sqrt();
        worst = worst.max((mean(&ma) - mean(&mb)).abs() / (sd(&mb).max(1e-15) / runs));
        worst = worst.max((mean(&va) - mean(&vb)).abs() / (sd(&vb).max(1e-30) / runs));
    }
    Ok(worst)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cpu::Sample;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    /// A record sliding back and forth at 1 Hz with friction from a known
    /// Stribeck law plus Gaussian noise of sd `sigma`.
    fn record(a: f64, b: f64, c: f64, sigma: f64, seed: u64) -> Run {
        let mut rng = StdRng::seed_from_u64(seed);
        let samples: Vec<Sample> = (0..12_000)
            .map(|i| {
                let t_s = f64::from(i) / 600.0;
                let v = 0.2 * (std::f64::consts::TAU * t_s).sin();
                let (u1, u2): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
                let noise = sigma * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
                let mu = a + b / (1.0 + c * v.abs()) + noise;
                Sample { t_s, x_m: 0.0, v_m_per_s: v, normal_force_n: 10.0, friction_force_n: -v.signum() * mu * 10.0 }
            })
            .collect();
        Run::from_samples(&samples, 1.0, 1e-3, 10.0)
    }

    #[test]
    fn friction_law_fit_recovers_a_known_law() {
        let run = record(0.25, 0.1, 20.0, 0.04, 1);
        let law = fit_friction_law(&[&run]).unwrap();
        assert_eq!(law.c, 20.0, "{law:?}");
        assert!((law.a - 0.25).abs() < 0.005 && (law.b - 0.1).abs() < 0.01, "{law:?}");
        assert!((law.sigma / 0.04 - 1.0).abs() < 0.03, "{law:?}");
        // At a fixed c the fit is the unconstrained least squares, so a law
        // with friction falling below zero at rest is still reported.
        let rising = fit_friction_law_at(&[&record(0.4, -0.3, 80.0, 0.0, 2)], 80.0).unwrap();
        assert!((rising.b + 0.3).abs() < 1e-6 && (rising.a - 0.4).abs() < 1e-6, "{rising:?}");
        assert!(fit_friction_law(&[&record(0.4, -0.5, 80.0, 0.0, 2)]).is_none_or(|l| l.a + l.b >= 0.0));
    }
}
