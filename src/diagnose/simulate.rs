//! What the diagnosis simulates, always through the engine: replicate
//! records of a measured unit (sampled like the data, on noise paths that
//! are the same for every model, so differences between models are not
//! noise), and per-path peak statistics of small ensembles.

use rayon::prelude::*;

use crate::diagnose::data::Data;
use crate::diagnose::measure::Run;
use crate::diagnose::observable::Observable;
use crate::diagnose::{DiagnoseSettings, mean, sd};
use crate::engine::reduce::circular_mean_var;
use crate::engine::{Condition, Engine, Job, Model, PathResult, Point, Record, RunPlan, Sample, rng};
use crate::error::Result;

/// Realisation numbers of unit `u`'s replicates start at `u × REPLICATE_STRIDE`.
const REPLICATE_STRIDE: u32 = 1000;

/// Steps per period of the replicate records. The records are sampled at the
/// noise boundaries, which split every period into spans of one noise
/// interval (1/600 s: 1/86 of a 7 Hz period), so the steps are set by the
/// noise, not by this: 32 or 256 give features within 0.05 of a replicate's
/// standard deviation of each other on the same noise (measured at 5.5 and
/// 7 Hz on the paper's rig).
const REPLICATE_STEPS_PER_PERIOD: u32 = 32;

/// Replicates `0..settings.replicates` of unit `unit` under `model`: records
/// as long as the unit's, sampled like the data (at the noise boundaries,
/// the noise interval being the data's sample interval), with the
/// measurement noise estimated on the data added.
pub(crate) fn replicates(
    engine: &Engine,
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    unit: usize,
) -> Result<Vec<Run>> {
    let mut model = model.clone();
    model.solver.steps_per_period = model.solver.steps_per_period.min(REPLICATE_STEPS_PER_PERIOD);
    let condition = data.simulated_condition(&data.units[unit], &model, settings.warmup_cycles);
    let points = [Point::steady(&model, condition)];
    let first_realisation = REPLICATE_STRIDE * unit as u32;
    let job = Job {
        model: &model,
        points: &points,
        realisations: settings.replicates,
        first_realisation,
        seed: settings.seed,
        plan: RunPlan { warmup_cycles: settings.warmup_cycles, measured_cycles: 0 },
        record: Record::Samples {
            interval_s: data.sample_interval_s,
            duration_s: data.record_s[unit],
            at_noise_boundaries: true,
        },
    };
    let records = engine.run(&job, &mut |_, _| {})?.records;
    Ok(records
        .into_iter()
        .enumerate()
        .map(|(r, mut samples)| {
            add_sensor_noise(&mut samples, data, settings.seed, first_realisation + r as u32);
            Run::from_samples(
                &samples,
                condition.excitation_frequency_hz,
                model.excitation.amplitude_m,
                condition.normal_force_n,
            )
        })
        .collect())
}

/// Adds white Gaussian measurement noise to a simulated record's `x` and `v`
/// (the same draws for every model, keyed by seed and realisation, and
/// drawn once per diagnosis).
fn add_sensor_noise(samples: &mut [Sample], data: &Data<'_>, seed: u64, realisation: u32) {
    let noise = data.sensor;
    if noise.x_m == 0.0 && noise.v_m_per_s == 0.0 {
        return;
    }
    let key = rng::seed_key(seed ^ 0x5E45_0E5E_0000_0000);
    let draws = data.sensor_draws.get(seed, realisation, samples.len(), |i| {
        rng::pair_a(rng::block(key, realisation, rng::STREAM_SENSOR, i as u64))
    });
    for (s, &(gx, gv)) in samples.iter_mut().zip(draws.iter()) {
        s.x_m += noise.x_m * gx;
        s.v_m_per_s += noise.v_m_per_s * gv;
    }
}

/// The replicates of several units, unit by unit (in `units`' order), with
/// the units simulated in parallel.
pub(crate) fn replicates_of(
    engine: &Engine,
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    units: &[usize],
) -> Result<Vec<Vec<Run>>> {
    units.par_iter().map(|&u| replicates(engine, model, data, settings, u)).collect()
}

/// One realisation's statistics over its measured periods.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PathStats {
    /// Mean peak, m.
    pub(crate) peak_mean_m: f64,
    /// Variance of the peaks, m².
    pub(crate) peak_var_m2: f64,
    /// Circular mean of the phases, degrees.
    pub(crate) phase_mean_deg: f64,
    /// Circular variance of the phases, degrees².
    pub(crate) phase_var_deg2: f64,
}

impl PathStats {
    /// The statistic a summary observable compares, if it is one.
    pub(crate) fn get(&self, observable: Observable) -> Option<f64> {
        match observable {
            Observable::PeakMeanM => Some(self.peak_mean_m),
            Observable::PeakVarM2 => Some(self.peak_var_m2),
            Observable::PhaseMeanDeg => Some(self.phase_mean_deg),
            Observable::PhaseVarDeg2 => Some(self.phase_var_deg2),
            _ => None,
        }
    }
}

/// Per-path statistics over records of `duration_s` seconds: like
/// [`ensemble_path_stats`], but each condition runs the periods its own
/// record holds (`duration_s` × its frequency), as a measured record there
/// would.
pub(crate) fn record_path_stats(
    engine: &Engine,
    model: &Model,
    conditions: &[Condition],
    duration_s: f64,
    realisations: u32,
    seed: u64,
    warmup: u32,
) -> Result<Vec<Vec<PathStats>>> {
    let cycles: Vec<u32> = conditions.iter().map(|c| (duration_s * c.excitation_frequency_hz) as u32).collect();
    path_stats_per_condition(engine, model, conditions, &cycles, realisations, seed, warmup)
}

/// Per-path statistics with each condition's own number of measured
/// periods (`cycles[i]` for `conditions[i]`, at least 2): one ensemble per
/// distinct length. One length for all would measure the short records'
/// conditions over a longer window than their data: their simulated spread
/// would be too small, and time-dependent effects (a drift) would reach
/// values the records never saw.
pub(crate) fn path_stats_per_condition(
    engine: &Engine,
    model: &Model,
    conditions: &[Condition],
    cycles: &[u32],
    realisations: u32,
    seed: u64,
    warmup: u32,
) -> Result<Vec<Vec<PathStats>>> {
    debug_assert_eq!(conditions.len(), cycles.len());
    let mut lengths: Vec<u32> = cycles.iter().map(|&c| c.max(2)).collect();
    lengths.sort_unstable();
    lengths.dedup();
    let mut out = vec![Vec::new(); conditions.len()];
    for length in lengths {
        let members: Vec<usize> = (0..conditions.len()).filter(|&i| cycles[i].max(2) == length).collect();
        let group: Vec<Condition> = members.iter().map(|&i| conditions[i]).collect();
        let stats = ensemble_path_stats(engine, model, &group, length, realisations, seed, warmup)?;
        for (i, per_path) in members.into_iter().zip(stats) {
            out[i] = per_path;
        }
    }
    Ok(out)
}

/// Per-path statistics of an ensemble: for each condition, every
/// realisation's statistics over `cycles` measured periods.
pub(crate) fn ensemble_path_stats(
    engine: &Engine,
    model: &Model,
    conditions: &[Condition],
    cycles: u32,
    realisations: u32,
    seed: u64,
    warmup: u32,
) -> Result<Vec<Vec<PathStats>>> {
    let points: Vec<Point> = conditions.iter().map(|&c| Point::steady(model, c)).collect();
    let job = Job {
        model,
        points: &points,
        realisations,
        first_realisation: 0,
        seed,
        plan: RunPlan { warmup_cycles: warmup, measured_cycles: cycles.max(2) },
        record: Record::Peaks,
    };
    let paths = engine.paths(&job)?;
    let stats = |p: &PathResult| {
        let (phase_mean, phase_var) = circular_mean_var(&p.phases_rad);
        PathStats {
            peak_mean_m: mean(&p.peaks_m),
            peak_var_m2: sd(&p.peaks_m).powi(2),
            phase_mean_deg: phase_mean.to_degrees(),
            phase_var_deg2: phase_var.to_degrees().to_degrees(),
        }
    };
    Ok(paths.chunks(realisations as usize).map(|chunk| chunk.iter().map(stats).collect()).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each condition gets its own number of periods, and the results come
    /// back in the conditions' order, as if each ran alone.
    #[test]
    fn each_condition_runs_its_own_record_length() {
        let model = Model::paper_rig(&[]).expect("the paper rig");
        let engine = Engine::cpu("test");
        let at = |f: f64, n: f64| Condition { excitation_frequency_hz: f, normal_force_n: n };
        let conditions = [at(9.0, 12.0), at(6.0, 10.0), at(9.0, 16.0)];
        let cycles = [30, 12, 30];
        let together = path_stats_per_condition(&engine, &model, &conditions, &cycles, 3, 5, 4).expect("runs");
        for (i, c) in conditions.iter().enumerate() {
            let alone = ensemble_path_stats(&engine, &model, &[*c], cycles[i], 3, 5, 4).expect("runs");
            assert_eq!(together[i], alone[0], "condition {i}");
        }
        // Not what one length for all would give.
        let one_length = ensemble_path_stats(&engine, &model, &conditions[1..2], 30, 3, 5, 4).expect("runs");
        assert_ne!(together[1], one_length[0]);
    }
}
