//! What the diagnosis simulates, always through the engine: replicate
//! records of a measured unit (sampled like the data, on noise paths that
//! are the same for every model, so differences between models are not
//! noise), and per-path peak statistics of small ensembles.

use std::collections::BTreeMap;
use std::sync::Arc;

use rayon::prelude::*;

use crate::diagnose::cache::RecordReading;
use crate::diagnose::data::Data;
use crate::diagnose::derived;
use crate::diagnose::features::{RunFeatures, SampleGrid, run_features_on};
use crate::diagnose::law::{FrictionLaw, LawMoments, MIN_SLIP_SAMPLES, Spread, variance_gap};
use crate::diagnose::observable::Observable;
use crate::diagnose::{DiagnoseSettings, mean, sd};
use crate::engine::reduce::circular_mean_var;
use crate::engine::{Condition, Engine, Job, Model, PathResult, Point, Record, RunPlan, Sample, rng};
use crate::error::Result;
use crate::measure::Run;

/// Realisation numbers of unit `u`'s replicates start at `u × REPLICATE_STRIDE`.
const REPLICATE_STRIDE: u32 = 1000;

/// Steps per period of the replicate records. The records are sampled at the
/// noise boundaries, which split every period into spans of one noise
/// interval (1/600 s: 1/86 of a 7 Hz period), so the steps are set by the
/// noise, not by this: 32 or 256 give features within 0.05 of a replicate's
/// standard deviation of each other on the same noise (measured at 5.5 and
/// 7 Hz on the paper's rig).
const REPLICATE_STEPS_PER_PERIOD: u32 = 32;

/// Replicates `numbers` (of `0..settings.replicates`, say) of each unit of
/// `units` under `model`, in one engine job (a point per unit; which
/// units a job should hold is the engine's [`Engine::record_jobs`]):
/// records as long as the unit's, sampled like the data (at the noise
/// boundaries, the noise interval being the data's sample interval), with
/// the measurement noise estimated on the data added. Every unit of `units`
/// must have the same record length; per unit, in the order of `units`.
pub(crate) fn replicates(
    engine: &Engine,
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    units: &[usize],
    numbers: std::ops::Range<u32>,
) -> Result<Vec<Vec<Run>>> {
    let Some(&first_unit) = units.first() else { return Ok(Vec::new()) };
    if numbers.is_empty() {
        return Ok(vec![Vec::new(); units.len()]);
    }
    let duration_s = data.record_s[first_unit];
    debug_assert!(units.iter().all(|&u| data.record_s[u].to_bits() == duration_s.to_bits()));
    let mut model = model.clone();
    model.solver.steps_per_period = model.solver.steps_per_period.min(REPLICATE_STEPS_PER_PERIOD);
    let conditions: Vec<Condition> = units.iter().map(|&u| data.simulated_condition(&data.units[u], &model)).collect();
    // Each replicate's noise is keyed by its realisation number alone, so a
    // replicate is the same record whichever others are simulated with it;
    // unit `u`'s numbers start at `u × REPLICATE_STRIDE`.
    let points: Vec<Point> = units
        .iter()
        .zip(&conditions)
        .map(|(&u, &c)| Point { realisation_offset: REPLICATE_STRIDE * u as u32, ..Point::steady(&model, c) })
        .collect();
    let job = Job {
        model: &model,
        points: &points,
        realisations: numbers.len() as u32,
        first_realisation: numbers.start,
        seed: settings.seed,
        plan: RunPlan { warmup_cycles: settings.warmup_cycles, measured_cycles: 0 },
        record: Record::Samples { interval_s: data.sample_interval_s, duration_s, at_noise_boundaries: true },
    };
    let records = engine.run(&job, &mut |_, _| {})?.records;
    let per_unit = numbers.len();
    let runs: Vec<Run> = records
        .into_par_iter()
        .enumerate()
        .map(|(i, mut samples)| {
            let (p, r) = (i / per_unit, (i % per_unit) as u32);
            add_sensor_noise(&mut samples, data, settings.seed, job.realisation(p, r));
            let mut run = Run::from_samples(
                &samples,
                conditions[p].excitation_frequency_hz,
                model.excitation.amplitude_m,
                conditions[p].normal_force_n,
            );
            // The unit's grid, which its records are read on too, serves the
            // base's trigonometry the friction force needs.
            let grid = data.derived.friction.then(|| data.caches.grids.of(units[p], &run));
            derived::derive_on(&mut run, data.derived, &data.set.rig, grid.as_deref().map(SampleGrid::base));
            run
        })
        .collect();
    let mut runs = runs.into_iter();
    Ok(units.iter().map(|_| runs.by_ref().take(per_unit).collect()).collect())
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
    let draws = data.caches.sensor_draws.get(seed, realisation, samples.len(), |i| {
        rng::pair_a(rng::noise_block(key, realisation, rng::STREAM_SENSOR, i as u64))
    });
    for (s, &(gx, gv)) in samples.iter_mut().zip(draws.iter()) {
        s.x_m += noise.x_m * gx;
        s.v_m_per_s += noise.v_m_per_s * gv;
    }
}

/// What the diagnosis reads from a model's replicate records of the data's
/// fitting units (time-series units that are not held out): each record's
/// features, and the friction law fitted to their slipping samples.
pub(crate) struct FittingRecords {
    /// The fitting units, in unit order.
    pub(crate) units: Vec<usize>,
    /// Per unit of `units`, its replicates' features.
    pub(crate) features: Vec<Vec<RunFeatures>>,
    /// The law of eq. 7 fitted within records to all of their slipping
    /// samples at the measured law's Stribeck rate `c` (`None` without a
    /// measured law or with fewer than 50 slipping samples). It carries no
    /// anchors: a simulated law is read through `mu` and `sigma` alone.
    pub(crate) law: Option<FrictionLaw>,
    /// Per unit of `units`, its replicates' spread about `law`
    /// ([`Spread::about`]; `None` without a law or with too few samples).
    pub(crate) spreads: Vec<Option<Spread>>,
}

impl FittingRecords {
    /// How much more the friction's residual variance is in the data than
    /// in these records, –²: condition by condition ([`variance_gap`]), the
    /// data's spreads `measured` given per unit of [`FittingRecords::units`],
    /// where any condition has a spread on both sides; else the data's
    /// pooled σ_μ², `pooled_variance`, less the records' law's (0 where the
    /// caller reads only a difference of two gaps, in which it cancels).
    /// `None` without a simulated law.
    pub(crate) fn variance_gap(&self, measured: &[Option<Spread>], pooled_variance: f64) -> Option<f64> {
        let law = self.law?;
        Some(variance_gap(measured, &self.spreads).unwrap_or(pooled_variance - law.sigma.powi(2)))
    }
}

/// The readings of `model`'s replicates `0..settings.replicates` of the
/// record units `units` (simulated in parallel where not kept), in the
/// order of `units`.
fn readings_of(
    engine: &Engine,
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    units: &[usize],
) -> Result<Vec<Vec<RecordReading>>> {
    let wanted = settings.replicates as usize;
    let mut kept = data.caches.records.get(model, settings);
    // The units short of replicates, one job per number of replicates kept
    // and record length (every unit of a job runs the same replicates).
    let mut short: BTreeMap<(usize, u64), Vec<usize>> = BTreeMap::new();
    for &u in units {
        let have = kept.get(&u).map_or(0, Vec::len);
        if have < wanted {
            short.entry((have, data.record_s[u].to_bits())).or_default().push(u);
        }
    }
    if !short.is_empty() {
        let c = data.law_c;
        let reading = data.reading();
        let mut added = BTreeMap::new();
        for ((have, _), group) in short {
            let numbers = have as u32..settings.replicates;
            let frequencies: Vec<f64> =
                group.iter().map(|&u| data.units[u].condition.excitation_frequency_hz).collect();
            let jobs: Vec<Vec<usize>> = engine
                .record_jobs(&frequencies)
                .into_iter()
                .map(|job| job.iter().map(|&i| group[i]).collect())
                .collect();
            let read: Vec<Vec<Vec<RecordReading>>> = jobs
                .par_iter()
                .map(|units| {
                    let runs = replicates(engine, model, data, settings, units, numbers.clone())?;
                    // Read record by record, in parallel, each on its unit's
                    // grid (made once per diagnosis: every model's records of
                    // a unit are sampled at the same times, and the grid's
                    // base trigonometry and normal-force design cost several
                    // percent of a diagnosis when made for every model).
                    let records: Vec<(Arc<SampleGrid>, &Run)> = units
                        .iter()
                        .zip(&runs)
                        .filter_map(|(&u, runs)| Some((data.caches.grids.of(u, runs.first()?), runs)))
                        .flat_map(|(grid, runs)| runs.iter().map(move |run| (Arc::clone(&grid), run)))
                        .collect();
                    let mut readings = records
                        .into_par_iter()
                        .map(|(grid, run)| RecordReading {
                            features: run_features_on(run, &grid, reading.motion(run)),
                            moments: c.map(|c| LawMoments::of_run(run, &reading, c)),
                        })
                        .collect::<Vec<_>>()
                        .into_iter();
                    Ok(runs.iter().map(|r| readings.by_ref().take(r.len()).collect()).collect())
                })
                .collect::<Result<_>>()?;
            for (&u, readings) in jobs.iter().flatten().zip(read.into_iter().flatten()) {
                let all = kept.entry(u).or_default();
                all.extend(readings);
                added.insert(u, all.clone());
            }
        }
        data.caches.records.insert(model, settings, added);
    }
    Ok(units.iter().map(|u| kept.get(u).map(|r| r[..wanted.min(r.len())].to_vec()).unwrap_or_default()).collect())
}

/// The features of `model`'s replicates `0..settings.replicates` of the
/// record units `units`, in their order ([`RecordCache`]).
pub(crate) fn record_features(
    engine: &Engine,
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    units: &[usize],
) -> Result<Vec<Vec<RunFeatures>>> {
    Ok(readings_of(engine, model, data, settings, units)?
        .into_iter()
        .map(|r| r.into_iter().map(|x| x.features).collect())
        .collect())
}

/// The [`FittingRecords`] of `model`'s replicates `0..settings.replicates`
/// of every fitting record unit of the view `data` (the units simulated in
/// parallel), each record simulated once per diagnosis ([`RecordCache`]).
pub(crate) fn fitting_records(
    engine: &Engine,
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
) -> Result<FittingRecords> {
    let units: Vec<usize> =
        (0..data.units.len()).filter(|&i| data.units[i].summary.is_none() && !data.units[i].heldout).collect();
    let readings = readings_of(engine, model, data, settings, &units)?;
    let features = readings.iter().map(|r| r.iter().map(|x| x.features.clone()).collect()).collect();
    let by_unit: Vec<Vec<LawMoments>> = readings.iter().map(|r| r.iter().filter_map(|x| x.moments).collect()).collect();
    let law = data.measured_law.and_then(|measured| {
        let records: Vec<LawMoments> = by_unit.iter().flatten().copied().collect();
        // As few slipping samples as the measured law is refused for.
        let count: usize = records.iter().map(LawMoments::count).sum();
        (count >= MIN_SLIP_SAMPLES).then(|| LawMoments::law_of_records(&records, measured.c, [0.0; 10])).flatten()
    });
    let spreads = by_unit.iter().map(|records| law.and_then(|l| Spread::about(records, &l))).collect();
    Ok(FittingRecords { units, features, law, spreads })
}

/// How many independent fits (a search round's coarse fits, full searches
/// and refits without each fold; the baseline's Stribeck rates) one rayon
/// task takes, for `with_min_len`: one, so all run side by side, where a trial's records
/// are a job per frequency read where it ran (a few MB each, on the CPU
/// reference); all of them, one after another, where a trial's records
/// are one job (a GPU that samples them), which holds every record of the
/// trial in host memory at once (some 90 MB for 18 runs on search
/// replicates, nine times that for 162): side by side on every thread,
/// that would multiply by the threads.
pub(crate) fn fits_per_task(engine: &Engine) -> usize {
    if engine.records_side_by_side() { 1 } else { usize::MAX }
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

    /// A model's fitting records read with replicates 0..2 kept and 2..4
    /// simulated on top are those of all four simulated at once (in a
    /// fresh diagnosis): features record by record and the friction law.
    #[test]
    fn records_kept_and_added_are_those_simulated_at_once() {
        let dir = std::env::temp_dir().join(format!("stickslip-records-kept-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let truth = Model::paper_rig(&[]).expect("the paper rig");
        let at = |f: f64, n: f64| Condition { excitation_frequency_hz: f, normal_force_n: n };
        let shape =
            crate::diagnose::synthetic::SetShape { runs_per_condition: 2, duration_s: 3.0, sample_rate_hz: 600.0 };
        crate::diagnose::synthetic::write_set(&dir, &truth, &[at(6.0, 10.0), at(7.0, 14.0)], shape, 3).expect("set");
        let set = crate::measure::read_measurement_set(&dir).expect("read");
        let _ = std::fs::remove_dir_all(&dir);
        let engine = Engine::cpu("test");
        let settings = |replicates| DiagnoseSettings { replicates, warmup_cycles: 5, ..DiagnoseSettings::default() };
        let stepwise = Data::new(&set, Default::default()).expect("data");
        fitting_records(&engine, &truth, &stepwise, &settings(2)).expect("two");
        let added = fitting_records(&engine, &truth, &stepwise, &settings(4)).expect("four");
        let at_once =
            fitting_records(&engine, &truth, &Data::new(&set, Default::default()).expect("data"), &settings(4))
                .expect("four");
        assert!(!added.units.is_empty() && added.features.iter().all(|f| f.len() == 4));
        assert_eq!(added.features, at_once.features);
        let (law, law_at_once) = (added.law.expect("a law"), at_once.law.expect("a law"));
        assert_eq!((law.a, law.b, law.d, law.sigma), (law_at_once.a, law_at_once.b, law_at_once.d, law_at_once.sigma));
        // Fewer replicates read the first ones' records.
        let two = fitting_records(&engine, &truth, &stepwise, &settings(2)).expect("two");
        assert!(two.features.iter().zip(&at_once.features).all(|(a, b)| a[..] == b[..2]));
    }
}

#[cfg(test)]
mod derived_tests {
    use super::*;
    use crate::diagnose::derived::{DerivedChannels, with_derived_channels};

    /// Records of the displacement alone (and the base's frame): the law
    /// read from their derived friction force is the law the model's
    /// replicates, derived alike, give (the indirect inference's premise),
    /// and it tells a friction level 0.03 away apart; with a free time
    /// origin too (the base's phase read from each record).
    #[test]
    fn a_law_read_from_derived_channels_is_the_replicates_law() {
        let truth = Model::paper_rig(&[]).expect("the paper rig");
        let set = crate::diagnose::synthetic::displacement_only_set(&truth, 3);
        for run in &set.runs {
            // The base's phase read from a record in the model's frame is
            // about 0.
            let phase = crate::diagnose::derived::base_phase_of(run, &set.rig);
            assert!(phase.abs() < 0.1, "{phase}");
        }
        let mut free = set.clone();
        for run in &mut free.runs {
            run.time_origin = crate::measure::TimeOrigin::Free;
        }
        for (set, base_from_record) in [(set, false), (free, true)] {
            same_law_as_the_replicates(&set, base_from_record, &truth);
        }
    }

    fn same_law_as_the_replicates(set: &crate::measure::MeasurementSet, base_from_record: bool, truth: &Model) {
        let (derived_set, derived) = with_derived_channels(set);
        assert_eq!(derived, DerivedChannels { v: true, friction: true, nominal_load: true, base_from_record });
        let set = derived_set.expect("derived");
        let data = Data::new(&set, derived).expect("data");
        let measured = data.measured_law.expect("a law from the derived channels");
        let engine = Engine::cpu("test");
        let settings = DiagnoseSettings { replicates: 8, warmup_cycles: 5, ..DiagnoseSettings::default() };
        let law_of = |m: &Model| fitting_records(&engine, m, &data, &settings).expect("records").law.expect("a law");
        let same = law_of(truth);
        let mut shifted = truth.clone();
        shifted.friction.a += 0.03;
        let other = law_of(&shifted);
        let (near, far) = ((measured.mu(0.1) - same.mu(0.1)).abs(), (measured.mu(0.1) - other.mu(0.1)).abs());
        assert!(near < 0.25 * far, "measured {measured:?}, same model {same:?}, shifted {other:?}");
        // The residual's spread, which the filter shapes, alike too.
        assert!((measured.sigma - same.sigma).abs() < 0.1 * same.sigma, "measured {measured:?}, same model {same:?}");
    }
}
