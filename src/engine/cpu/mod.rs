//! The CPU backend: the f64 reference integrator ([`oscillator`]) run over
//! an ensemble with rayon, reduced with the same exact integer sums as the
//! GPU ([`crate::engine::reduce`]).
//!
//! Work is done in chunks of at most [`PATHS_PER_CHUNK`] realisations, so
//! memory stays bounded (for [`Record::Sums`]) whatever the ensemble size;
//! within a chunk, groups of realisations run in parallel, each group
//! stepped together (`oscillator::LANES` of them, of one point or of
//! several loads at one frequency, `oscillator::steps_beside`). The sums are
//! integers, so the result does not depend on the chunking or the number
//! of threads.

pub mod effects;
mod noise;
pub mod oscillator;

use rayon::prelude::*;

use crate::engine::oscillator::{InitialState, Oscillator, PathResult, RunPlan, Sample};
use crate::engine::reduce::PointAccumulator;
use crate::engine::schedule::{first_sampled_interval, record_cycles, samples_at_noise_boundaries};
use crate::engine::{Backend, BackendKind, Job, Output, Record, rng};
use crate::error::{Error, Result};
use oscillator::{LANE_WIDTHS, LANES, Path, Sampler, phase_of, run_period};

/// Most realisations integrated between two progress reports (and held in
/// memory at once when only sums are kept).
pub const PATHS_PER_CHUNK: usize = 1 << 14;

/// Progress reports a run aims for: a run smaller than this many full
/// chunks is cut into smaller ones (never below [`MIN_PATHS_PER_CHUNK`]), so
/// that a log shows it move. The reduction runs in task order, so the chunk
/// size does not change a bit of the result.
const PROGRESS_REPORTS: usize = 32;

/// Fewest realisations per chunk: each chunk ends at a barrier, where a
/// core that has finished its groups waits for the other's last (about
/// half a group's time), so a chunk holds some 32 groups of [`LANES`] for
/// each of two cores: the noisy workload's 256-realisation chunks kept its
/// cores 97% busy.
const MIN_PATHS_PER_CHUNK: usize = 1024;

/// Realisations per chunk for a run of `total_paths`.
fn paths_per_chunk(total_paths: usize) -> usize {
    (total_paths / PROGRESS_REPORTS).clamp(MIN_PATHS_PER_CHUNK, PATHS_PER_CHUNK)
}

/// The f64 reference integrator on all of rayon's threads.
pub struct CpuBackend;

impl Backend for CpuBackend {
    fn kind(&self) -> BackendKind {
        BackendKind::Cpu
    }

    fn run(&self, job: &Job<'_>, progress: &mut dyn FnMut(u64, u64)) -> Result<Output> {
        let oscillators = job.oscillators()?;
        let n = job.realisations as usize;
        // Tasks (point, realisation) are numbered point-major and made one
        // chunk at a time, so nothing grows with the ensemble but the output.
        let total_paths = job.points.len() * n;
        let task = |i: usize| (i / n, job.realisation(i / n, (i % n) as u32));
        let total = job.work();
        let per_path = job.plan.total_cycles();
        let chunk = paths_per_chunk(total_paths);
        let shared = shares_draws(job, &oscillators);
        let runs = point_runs(&oscillators);
        let mut output = Output::default();
        if let Record::Samples { interval_s, duration_s, at_noise_boundaries } = job.record {
            for start in (0..total_paths).step_by(chunk) {
                let end = (start + chunk).min(total_paths);
                let records: Vec<Vec<Sample>> = lane_groups(job, &runs, start, end, lane_width(end - start))
                    .into_par_iter()
                    .flat_map_iter(|group| {
                        sample_records(
                            job.seed,
                            &lanes_of(job, &oscillators, &group),
                            job.plan.warmup_cycles,
                            duration_s,
                            interval_s,
                            at_noise_boundaries,
                            shared,
                        )
                    })
                    .collect();
                for (i, record) in (start..end).zip(&records) {
                    if let Some(s) = record.iter().find(|s| !sample_is_finite(s)) {
                        let (p, r) = task(i);
                        return Err(diverged(job, p, r, &format!("a non-finite sample at t = {} s", s.t_s)));
                    }
                }
                output.records.extend(records);
                progress((end as u64 * per_path).min(total), total);
            }
            return Ok(output);
        }
        output.sums = job.points.iter().map(|p| PointAccumulator::new(p.range)).collect();
        let mut done = 0u64;
        for start in (0..total_paths).step_by(chunk) {
            let end = (start + chunk).min(total_paths);
            let paths: Vec<PathResult> = lane_groups(job, &runs, start, end, lane_width(end - start))
                .into_par_iter()
                .flat_map_iter(|group| {
                    simulate_paths(job.seed, &lanes_of(job, &oscillators, &group), job.plan, shared, None)
                })
                .collect();
            for (i, path) in (start..end).zip(&paths) {
                let (p, r) = task(i);
                if let Some(what) = non_finite_part(path) {
                    return Err(diverged(job, p, r, what));
                }
                output.sums[p].add_path(path, oscillators[p].period_s);
                if output.sums[p].non_finite > 0 {
                    return Err(diverged(job, p, r, "a peak beyond the range of f32"));
                }
            }
            if job.record == Record::Peaks {
                output.paths.extend(paths);
            }
            done += (end - start) as u64 * per_path;
            progress(done, total);
        }
        debug_assert!(job.record != Record::Peaks || output.paths.len() == n * job.points.len());
        Ok(output)
    }
}

/// Whether the job's paths share their main-stream draws through
/// [`noise`]'s tables: where its points integrate the same realisations
/// (a sweep: each table is read once per point), or where its tables are
/// small (at most [`SHARED_JOB_BYTES`]: a diagnosis's replicates, which
/// its next trial integrates again). A single point's large ensemble, read
/// once, draws as it goes: tables would only add their memory traffic.
fn shares_draws(job: &Job<'_>, oscillators: &[Oscillator]) -> bool {
    let intervals = oscillators
        .iter()
        .map(|o| {
            let cycles = match job.record {
                Record::Samples { duration_s, .. } => {
                    u64::from(job.plan.warmup_cycles) + u64::from(record_cycles(o, duration_s))
                }
                _ => job.plan.total_cycles(),
            };
            o.noise_intervals_in(cycles) + 1
        })
        .max()
        .unwrap_or(0);
    let bytes = intervals.saturating_mul(u128::from(job.realisations)) * 16;
    job.points.len() > 1 || bytes <= SHARED_JOB_BYTES as u128
}

/// Largest tables in all a job of one point shares, bytes (a diagnosis's
/// eight replicates of 50 s records take 4 MB).
const SHARED_JOB_BYTES: usize = noise::BUDGET_BYTES / 16;

fn sample_is_finite(s: &Sample) -> bool {
    [s.t_s, s.x_m, s.v_m_per_s, s.normal_force_n, s.friction_force_n].iter().all(|v| v.is_finite())
}

/// What of a finished path is not finite, if anything.
fn non_finite_part(path: &PathResult) -> Option<&'static str> {
    if path.peaks_m.iter().any(|v| !v.is_finite()) {
        Some("a non-finite peak")
    } else if path.phases_rad.iter().any(|v| !v.is_finite()) {
        Some("a non-finite phase")
    } else if !path.stick_time_s.is_finite() {
        Some("a non-finite stuck time")
    } else {
        None
    }
}

/// The error for a path that left the finite numbers: nothing of it is reduced.
fn diverged(job: &Job<'_>, point: usize, realisation: u32, what: &str) -> Error {
    Error::Diverged {
        point: job.points[point].condition.describe(),
        message: format!(
            "realisation {realisation} produced {what} (the f64 reference integrator); the model drives the \
             oscillator out of range there, so check its parameters"
        ),
    }
}

/// Most samples a record reserves room for before it is taken.
const MAX_RESERVED_SAMPLES: f64 = 1e7;

/// One realisation of a lane group: its point's oscillator and initial
/// state, and its realisation number.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lane<'a> {
    pub(crate) osc: &'a Oscillator,
    pub(crate) realisation: u32,
    pub(crate) initial: InitialState,
}

/// The lanes of a group of the job's tasks (point, realisation).
fn lanes_of<'a>(job: &Job<'_>, oscillators: &'a [Oscillator], group: &[(usize, u32)]) -> Vec<Lane<'a>> {
    group
        .iter()
        .map(|&(p, realisation)| Lane { osc: &oscillators[p], realisation, initial: job.points[p].initial })
        .collect()
}

/// Realisations (at most [`LANES`], of oscillators that step together,
/// [`oscillator::steps_beside`]) stepped together and sampled like a
/// measured record: `seconds` of samples every `sample_interval_s`, starting
/// after `warmup_cycles` periods, with times measured from the end of the
/// warm-up. With `at_noise_boundaries` and samples as far apart as the noise
/// intervals (as a diagnosis's replicates are), they are taken at the noise
/// boundaries themselves, from the first one at or after the warm-up's end
/// (so the first sample's time is within one interval of 0): samples then
/// split no steps.
pub(crate) fn sample_records(
    seed: u64,
    lanes: &[Lane<'_>],
    warmup_cycles: u32,
    seconds: f64,
    sample_interval_s: f64,
    at_noise_boundaries: bool,
    shared: bool,
) -> Vec<Vec<Sample>> {
    // The step grid is every lane's.
    let osc = lanes[0].osc;
    let start_s = f64::from(warmup_cycles) * osc.period_s;
    let cycles = record_cycles(osc, seconds);
    let aligned = samples_at_noise_boundaries(osc, sample_interval_s, at_noise_boundaries);
    // Room for every sample the cycles take (a few more than are kept), so
    // the records are not copied as they grow (up to a bound: a larger
    // record grows as before).
    let expected = (f64::from(cycles) * osc.period_s / sample_interval_s).ceil();
    let room = if (0.0..=MAX_RESERVED_SAMPLES).contains(&expected) { expected as usize + 2 } else { 0 };
    let mut samplers: Vec<Sampler> = lanes
        .iter()
        .map(|_| {
            let mut sampler = if aligned {
                Sampler::at_noise_boundaries(first_sampled_interval(osc, warmup_cycles))
            } else {
                Sampler::new(sample_interval_s, start_s)
            };
            sampler.samples.reserve(room);
            sampler
        })
        .collect();
    let plan = RunPlan { warmup_cycles, measured_cycles: cycles };
    simulate_paths(seed, lanes, plan, shared, Some(&mut samplers));
    samplers
        .into_iter()
        .map(|sampler| {
            let mut samples = sampler.samples;
            samples.truncate((seconds / sample_interval_s).round() as usize);
            for s in &mut samples {
                s.t_s -= start_s;
            }
            samples
        })
        .collect()
}

/// Runs `lanes` (at most [`LANES`], of oscillators that step together,
/// [`oscillator::steps_beside`]) stepped together, and returns each one's
/// per-period peaks and phases; with `samplers` (one per lane), samples
/// each. With `shared`, each realisation's main-stream draws come from a
/// shared table ([`noise`]), made now unless held; without, from one if it
/// is held. The answers are the same either way, and each lane's are those
/// it has stepped alone.
pub(crate) fn simulate_paths(
    seed: u64,
    lanes: &[Lane<'_>],
    plan: RunPlan,
    shared: bool,
    mut samplers: Option<&mut [Sampler]>,
) -> Vec<PathResult> {
    // The intervals the run draws (the last boundary's included; the step
    // grid is every lane's).
    let intervals = lanes[0].osc.noise_intervals_in(u64::from(plan.warmup_cycles + plan.measured_cycles)) + 1;
    let mut paths: Vec<Path<'_>> = lanes
        .iter()
        .map(|lane| {
            debug_assert!(oscillator::steps_beside(lanes[0].osc, lane.osc));
            let r = lane.realisation;
            let mut path = Path::new(lane.osc, seed, r, lane.initial);
            let table =
                u64::try_from(intervals).ok().and_then(|n| noise::pair_a_table(rng::seed_key(seed), r, n, shared));
            path.pair_a_table = noise::PathPairs(table);
            path
        })
        .collect();
    let mut results: Vec<PathResult> = lanes
        .iter()
        .map(|_| PathResult {
            peaks_m: Vec::with_capacity(plan.measured_cycles as usize),
            phases_rad: Vec::with_capacity(plan.measured_cycles as usize),
            stick_time_s: 0.0,
        })
        .collect();
    for cycle in 0..plan.warmup_cycles + plan.measured_cycles {
        let measuring = cycle >= plan.warmup_cycles;
        run_period(&mut paths, measuring, samplers.as_deref_mut());
        if measuring {
            for (path, result) in paths.iter().zip(&mut results) {
                result.peaks_m.push(path.period_max_x_m);
                result.phases_rad.push(phase_of(path.period_cos_integral, path.period_sin_integral));
                result.stick_time_s += path.period_stick_s;
            }
        }
    }
    results
}

/// Most realisations a group of a chunk of `tasks` steps together: the
/// widest of [`LANE_WIDTHS`] (else 1) that still leaves a group for
/// every thread, so a small run (`simulate`'s three records, one point of
/// eight) keeps both cores busy; [`LANES`] when the run is itself one of
/// several in parallel (a diagnosis simulates each frequency's units side by side), whose
/// caller fills the cores.
fn lane_width(tasks: usize) -> usize {
    if rayon::current_thread_index().is_some() {
        return LANES;
    }
    let threads = rayon::current_num_threads();
    LANE_WIDTHS.into_iter().find(|&w| tasks.div_ceil(w) >= threads).unwrap_or(1)
}

/// Where the run of points that step together from each point on ends
/// ([`oscillator::steps_beside`]: the loads of one frequency, in a row):
/// one past its last point. Stepping beside is sameness but for the
/// load, so a chain of neighbours is a run.
fn point_runs(oscillators: &[Oscillator]) -> Vec<usize> {
    let mut run_end = vec![oscillators.len(); oscillators.len()];
    for p in (0..oscillators.len().saturating_sub(1)).rev() {
        run_end[p] =
            if oscillator::steps_beside(&oscillators[p], &oscillators[p + 1]) { run_end[p + 1] } else { p + 1 };
    }
    run_end
}

/// The job's tasks from `start` to `end` (numbered point-major,
/// `job.realisations` each) cut into groups that step together, in order,
/// at most `width` ([`lane_width`]) each: the widest of [`LANE_WIDTHS`]
/// there are as many left for, then one by one (fewer step one by one
/// anyway, and alone they run in parallel). A group may run on from one
/// point into the next within a run of points that step together
/// (`run_end`, [`point_runs`]), so a diagnosis's few realisations per load
/// fill wide groups. Each task is (point, realisation).
fn lane_groups(job: &Job<'_>, run_end: &[usize], start: usize, end: usize, width: usize) -> Vec<Vec<(usize, u32)>> {
    let n = job.realisations as usize;
    let mut groups = Vec::new();
    let mut i = start;
    while i < end {
        let left = end.min(run_end[i / n] * n) - i;
        let group_end = i + LANE_WIDTHS.into_iter().find(|&w| w <= width && left >= w).unwrap_or(1);
        groups.push((i..group_end).map(|k| (k / n, job.realisation(k / n, (k % n) as u32))).collect());
        i = group_end;
    }
    groups
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::{Condition, Model, Point};
    use oscillator::QUARTER_LANES;

    /// Lane groups cover the chunk's tasks once, in order, and take sixteen
    /// while sixteen are left, then eight, then four, then one by one
    /// (29 realisations per point: 16, 8, 4, 1), none wider than asked;
    /// they run on from one point into the next at the same frequency
    /// (the loads of one model step together) and never into another
    /// frequency's.
    #[test]
    fn lane_groups_cover_the_tasks_in_order_within_a_frequency() {
        let model = Model::paper_rig(&[]).expect("the paper rig");
        let at = |f: f64, n: f64| Point::steady(&model, Condition { excitation_frequency_hz: f, normal_force_n: n });
        let points = [at(7.0, 4.0), at(8.0, 8.0), at(8.0, 12.0)];
        let oscillators: Vec<Oscillator> =
            points.iter().map(|p| Oscillator::new(&model, p.condition).expect("an oscillator")).collect();
        let job = Job {
            model: &model,
            points: &points,
            realisations: 29,
            first_realisation: 100,
            seed: 1,
            plan: RunPlan { warmup_cycles: 0, measured_cycles: 1 },
            record: Record::Sums,
        };
        let groups = |start, end, width| lane_groups(&job, &point_runs(&oscillators), start, end, width);
        let sizes = |start, end| groups(start, end, LANES).iter().map(Vec::len).collect::<Vec<_>>();
        let (half, quarter) = (LANES / 2, QUARTER_LANES);
        // 7 Hz alone; then 8 Hz's two loads, 58 tasks: 16, 16, 16, 8, 1, 1.
        assert_eq!(sizes(0, 87), [LANES, half, quarter, 1, LANES, LANES, LANES, half, 1, 1]);
        let straddling = &groups(0, 87, LANES)[5];
        assert_eq!(straddling.first().map(|t| t.0), Some(1));
        assert_eq!(straddling.last().map(|t| t.0), Some(2));
        let narrow = groups(0, 29, quarter).iter().map(Vec::len).collect::<Vec<_>>();
        assert_eq!(narrow, [quarter, quarter, quarter, quarter, quarter, quarter, quarter, 1]);
        assert_eq!(groups(0, 3, 1).len(), 3);
        // A chunk that starts and ends inside points.
        let tasks: Vec<(usize, u32)> = groups(5, 43, LANES).into_iter().flatten().collect();
        let expected: Vec<(usize, u32)> = (5..43).map(|i| (i / 29, 100 + (i % 29) as u32)).collect();
        assert_eq!(tasks, expected);
        assert_eq!(sizes(5, 43), [LANES, half, half, quarter, 1, 1]);
        // Another model's oscillator at the same frequency and load does
        // not step beside this one's.
        let rough = Model::paper_rig(&["friction.a=0.3".to_string()]).expect("a rougher rig");
        let other = Oscillator::new(&rough, points[1].condition).expect("an oscillator");
        assert!(!oscillator::steps_beside(&oscillators[1], &other));
        assert!(oscillator::steps_beside(&oscillators[1], &oscillators[2]));
        assert!(!oscillator::steps_beside(&oscillators[0], &oscillators[1]));
    }

    fn bits(values: &[f64]) -> Vec<u64> {
        values.iter().map(|v| v.to_bits()).collect()
    }

    /// Realisations stepped together are those stepped one at a time, bit
    /// for bit: peaks, phases, stuck time and sampled records, at a
    /// condition that slips throughout and one that sticks much of each
    /// period (so lanes part at events), without effects, with effects held
    /// per interval (harmonics, coloured noise), with an adhesion force (on
    /// the baseline's vector step) and with a friction history (hysteresis
    /// by slip length, Dahl's with a decaying stiction, a stiction released
    /// over a slip length, and a friction memory, one more state of the
    /// step: a time lag, the slip law, the ageing law with adhesion),
    /// with the main stream's draws read from shared tables and drawn side
    /// by side; and with every other lane at a second load, under effects
    /// whose terms differ between loads (a friction offset, the law scaled
    /// by the load, harmonics in proportion to it, a non-Gaussian noise
    /// that grows with it).
    #[test]
    fn realisations_stepped_together_are_those_stepped_alone() {
        let cases: [&[&str]; 14] = [
            &[],
            &[
                "normal_force_harmonics.amplitudes_n=[0.4, 0.3, 0.0, 0.1]",
                "coloured_friction_noise.correlation_time_s=0.01",
            ],
            &["load_dependent_friction.form=\"adhesion\"", "load_dependent_friction.strength=-6.0"],
            &["friction_hysteresis.length_m=2e-4"],
            &[
                "friction_hysteresis.form=\"dahl\"",
                "friction_hysteresis.length_m=2e-4",
                "stiction.excess=0.15",
                "stiction.form=\"decaying\"",
            ],
            &["stiction.excess=0.15", "stiction.release_length_m=3e-4"],
            &["friction_hysteresis.form=\"lag\"", "friction_hysteresis.time_constant_s=0.01"],
            &["friction_hysteresis.form=\"slip\"", "friction_hysteresis.length_m=2e-4"],
            &[
                "friction_hysteresis.form=\"ageing\"",
                "friction_hysteresis.length_m=2e-4",
                "friction_hysteresis.strength=0.05",
                "load_dependent_friction.form=\"adhesion\"",
                "load_dependent_friction.strength=0.5",
            ],
            &["load_dependent_friction.form=\"power\"", "load_dependent_friction.strength=-0.3"],
            // No offset at the heavier load, one at the lighter.
            &[
                "load_dependent_friction.form=\"linear\"",
                "load_dependent_friction.strength=0.004",
                "load_dependent_friction.reference_force_n=16.39",
            ],
            &[
                "load_dependent_friction.form=\"scaled\"",
                "load_dependent_friction.strength=-0.4",
                "normal_force_harmonics.amplitudes_per_n0=[0.03, 0.0, 0.01, 0.0]",
            ],
            &["non_gaussian_friction.strength=0.3", "non_gaussian_friction.load_exponent=1.0"],
            // A law that rises with speed from rest: more steps per
            // period at the heavier load, all longer than the noise's.
            &["friction.b=-0.1", "friction.c=300.0", "friction.a=0.35"],
        ];
        for (case, overrides, lanes) in cases.into_iter().enumerate().flat_map(|(i, c)| LANE_WIDTHS.map(|w| (i, c, w)))
        {
            let realisations: Vec<u32> = (3..3 + lanes as u32).collect();
            let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
            let model = Model::paper_rig(&overrides).expect("the paper rig");
            for hz in [7.0, 12.0] {
                let initial = InitialState { x_m: 0.0, v_m_per_s: 0.0 };
                let at = |n: f64| {
                    Oscillator::new(&model, Condition { excitation_frequency_hz: hz, normal_force_n: n })
                        .expect("an oscillator")
                };
                let (heavy, light) = (at(16.39), at(9.0));
                assert!(oscillator::steps_beside(&heavy, &light), "{overrides:?} at {hz} Hz");
                if case == 13 && hz == 7.0 {
                    assert!(heavy.steps_per_period > light.steps_per_period, "{overrides:?} at {hz} Hz");
                }
                let one_load: Vec<Lane<'_>> =
                    realisations.iter().map(|&realisation| Lane { osc: &heavy, realisation, initial }).collect();
                let mut two_loads = one_load.clone();
                two_loads.iter_mut().skip(1).step_by(2).for_each(|lane| lane.osc = &light);
                let plan = RunPlan { warmup_cycles: 3, measured_cycles: 12 };
                for (loads, group) in [(1, &one_load), (2, &two_loads)] {
                    // With the draws from shared tables, and drawn side by
                    // side (under a seed of its own, which no table holds: a
                    // held table serves a path that would not make one).
                    for shared in [true, false] {
                        let seed = if shared { 9 } else { 0x5EED_0000 + 100 * case as u64 + hz as u64 + lanes as u64 };
                        let alone: Vec<PathResult> = group
                            .iter()
                            .map(|lane| simulate_paths(seed, &[*lane], plan, false, None).remove(0))
                            .collect();
                        let together = simulate_paths(seed, group, plan, shared, None);
                        let mut stuck = 0;
                        for ((lane, path), alone) in group.iter().zip(&together).zip(&alone) {
                            let (r, n) = (lane.realisation, lane.osc.normal_force_mean_n);
                            let what = format!("{overrides:?} at {hz} Hz and {n} N, realisation {r}, shared {shared}");
                            assert_eq!(bits(&path.peaks_m), bits(&alone.peaks_m), "peaks, {what}");
                            assert_eq!(bits(&path.phases_rad), bits(&alone.phases_rad), "phases, {what}");
                            assert_eq!(path.stick_time_s.to_bits(), alone.stick_time_s.to_bits(), "stuck, {what}");
                            stuck += usize::from(path.stick_time_s > 0.0);
                        }
                        if hz == 12.0 && overrides.is_empty() && loads == 1 {
                            assert_eq!(stuck, lanes, "every realisation sticks at 12 Hz");
                        }
                    }
                    let records = sample_records(9, group, 3, 1.0, 1.0 / 600.0, true, true);
                    for (lane, record) in group.iter().zip(&records) {
                        let alone = sample_records(9, &[*lane], 3, 1.0, 1.0 / 600.0, true, false).remove(0);
                        assert_eq!(record.len(), 600);
                        let flat = |s: &[Sample]| -> Vec<u64> {
                            s.iter()
                                .flat_map(|s| [s.t_s, s.x_m, s.v_m_per_s, s.normal_force_n, s.friction_force_n])
                                .map(f64::to_bits)
                                .collect()
                        };
                        let (r, n) = (lane.realisation, lane.osc.normal_force_mean_n);
                        assert_eq!(
                            flat(record),
                            flat(&alone),
                            "record, {overrides:?} at {hz} Hz and {n} N, realisation {r}"
                        );
                    }
                }
            }
        }
    }
}
