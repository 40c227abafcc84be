//! The cost budget: `sweep`, `simulate`, `diagnose` and
//! `benchmark-diagnosis` estimate their work before they start and refuse beyond a documented limit unless forced
//! (`--force` on the command line, `force=True` in Python; `docs/formats.md`,
//! "The cost budget").
//!
//! Work is counted in *realisation-steps*: per realisation and excitation
//! period, the integrator's steps plus one per noise interval (each noise
//! boundary splits a step) plus one per output sample; summed over periods,
//! realisations and grid points. Two limits apply:
//!
//! - **per period**, [`MAX_STEPS_PER_PERIOD`]: a noise interval or sample
//!   interval far below the period (`noise.interval_s = 1e-9` is 1.4e8
//!   intervals per period at 7 Hz) makes even one period of one realisation
//!   cost seconds;
//! - **in all**, [`CPU_LIMIT`] on the CPU reference and [`GPU_LIMIT`] on a
//!   GPU.
//!
//! A sweep point whose peaks leave its range runs twice (`docs/formats.md`);
//! the estimate counts each point once. A diagnosis is estimated as
//! [`DIAGNOSIS_PASSES`] times the simulation that scores one model, and a
//! benchmark as the diagnosis of each of its sets.

use crate::diagnose::DiagnoseSettings;
use crate::diagnose::benchmark::BenchmarkSettings;
use crate::engine::model::fmt_value;
use crate::engine::{BackendKind, Job, Model, Oscillator, Record};
use crate::error::{Error, Result};
use crate::measure::MeasurementSet;

/// Whether a run beyond the budget goes ahead, and which front end asked:
/// a refusal names that front end's arguments (`--force` or `force=True`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Force {
    /// Run whatever the estimate.
    pub given: bool,
    /// Whether the request came from the command line (else from Python).
    pub command_line: bool,
}

impl Force {
    /// The command line's `--force`.
    pub fn flag(given: bool) -> Force {
        Force { given, command_line: true }
    }

    /// The Python package's `force=True`.
    pub fn keyword(given: bool) -> Force {
        Force { given, command_line: false }
    }

    /// An argument as the asking front end spells it: `flag` on the
    /// command line, `keyword` in Python.
    pub fn spelled<'a>(&self, flag: &'a str, keyword: &'a str) -> &'a str {
        if self.command_line { flag } else { keyword }
    }
}

/// The threads the CPU reference runs on here (rayon's pool), for
/// [`Cost::check`]'s time estimate.
pub fn cpu_threads() -> usize {
    rayon::current_num_threads()
}

/// Most realisation-steps per excitation period without `--force` (2^21:
/// the solver's largest step count, 2^20, plus as many noise intervals).
pub const MAX_STEPS_PER_PERIOD: f64 = (1u64 << 21) as f64;
/// Most realisation-steps of a run on the CPU reference without `--force`:
/// 1e11, about an hour and a half on two cores (the reference takes about
/// 1.2e7 realisation-steps per second per thread).
pub const CPU_LIMIT: f64 = 1e11;
/// Most realisation-steps of a run on a GPU without `--force`: 1e13, about
/// ten minutes on an H100 (2e10 realisation-steps per second).
pub const GPU_LIMIT: f64 = 1e13;
/// The CPU reference's rate, realisation-steps per second per thread, for
/// the time a message estimates.
pub const CPU_STEPS_PER_THREAD_S: f64 = 1.2e7;
/// How many times a diagnosis simulates the scoring of one model, for its
/// estimate (calibration, every candidate's search and the folds' refits:
/// about 750 on the paper's Figure 8 table).
pub const DIAGNOSIS_PASSES: f64 = 1000.0;
/// Steps per period of a diagnosis's replicate records (its simulate module
/// uses this many, or the model's if fewer).
const REPLICATE_STEPS_PER_PERIOD: f64 = 32.0;

/// A run's estimated work.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cost {
    /// Realisation-steps in all.
    pub steps: f64,
    /// The most realisation-steps one period of one realisation takes.
    pub steps_per_period: f64,
}

impl Cost {
    const NONE: Cost = Cost { steps: 0.0, steps_per_period: 0.0 };

    /// `periods` periods of `realisations` realisations at `per_period`
    /// realisation-steps each.
    fn of(realisations: f64, periods: f64, per_period: f64) -> Cost {
        Cost { steps: realisations * periods * per_period, steps_per_period: per_period }
    }

    fn plus(self, other: Cost) -> Cost {
        Cost { steps: self.steps + other.steps, steps_per_period: self.steps_per_period.max(other.steps_per_period) }
    }

    /// The cost of `job`: every point's periods (warm-up included; a
    /// record's own) × realisations × its steps, noise intervals and samples
    /// per period.
    pub fn of_job(job: &Job<'_>) -> Result<Cost> {
        let mut cost = Cost::NONE;
        for point in job.points {
            let o = Oscillator::new(job.model, point.condition)?;
            let f = point.condition.excitation_frequency_hz;
            let (periods, samples_per_period) = match job.record {
                Record::Samples { interval_s, duration_s, .. } => {
                    ((duration_s * f).ceil() + 1.0 + f64::from(job.plan.warmup_cycles), 1.0 / (interval_s * f))
                }
                _ => (job.plan.total_cycles() as f64, 0.0),
            };
            let intervals_per_period = (1u64 << 32) as f64 / o.noise_interval_fixed as f64;
            let per_period = f64::from(o.steps_per_period) + intervals_per_period + samples_per_period;
            cost = cost.plus(Cost::of(f64::from(job.realisations), periods, per_period));
        }
        Ok(cost)
    }

    /// The estimated cost of diagnosing `set`: [`DIAGNOSIS_PASSES`] times
    /// one scoring pass, which simulates `settings.replicates` records as
    /// long as each run, and an ensemble of `settings.ensemble_realisations`
    /// realisations over each summary row's `n_peaks` periods (350 when not
    /// given), with the noise held over the first run's sample interval
    /// (1/600 s without runs), or over that of the rate the runs are
    /// thinned to.
    pub fn of_diagnosis(set: &MeasurementSet, settings: &DiagnoseSettings) -> Cost {
        let recorded_s = set.runs.first().map_or(1.0 / 600.0, |r| r.sample_interval_s());
        let interval_s = settings.sample_rate_hz.map_or(recorded_s, |r| recorded_s.max(1.0 / r));
        let records = set.runs.iter().map(|r| (r.excitation_frequency_hz, r.duration_s()));
        let rows = set.summary.iter().map(|row| (row.excitation_frequency_hz, row.n_peaks));
        Cost::of_diagnosed(records, rows, interval_s, settings)
    }

    /// The estimated cost of a benchmark's largest set: each planned set's
    /// diagnosis ([`Cost::of_diagnosis`] of the set it will hold: its
    /// conditions' records, or for a summary-only set one row per condition
    /// over a record's periods), the largest of them. A benchmark is a batch
    /// of diagnoses, each its own run with its own line of progress: the
    /// budget bounds each one, as it bounds a `diagnose`, and the number of
    /// sets is what the user asked for. Generating a set and scoring its
    /// truth take a few passes more, against the thousand of its diagnosis.
    pub fn of_benchmark(settings: &BenchmarkSettings) -> Result<Cost> {
        let diagnose = settings.diagnose_settings();
        let mut largest = Cost::NONE;
        for set in settings.outlines()? {
            let interval_s = 1.0 / set.sample_rate_hz;
            let frequencies = set.conditions.iter().map(|c| c.excitation_frequency_hz);
            let set_cost = if set.summary_only {
                let rows = frequencies.map(|f| (f, Some(((set.duration_s * f) as u64).max(2))));
                Cost::of_diagnosed(std::iter::empty(), rows, interval_s, &diagnose)
            } else {
                let runs = set.runs_per_condition as usize;
                let records = frequencies.flat_map(|f| std::iter::repeat_n((f, set.duration_s), runs));
                Cost::of_diagnosed(records, std::iter::empty(), interval_s, &diagnose)
            };
            // NaN is the largest: it is over every limit.
            let steps = if set_cost.steps.is_nan() || largest.steps.is_nan() {
                f64::NAN
            } else {
                largest.steps.max(set_cost.steps)
            };
            largest = Cost { steps, steps_per_period: largest.steps_per_period.max(set_cost.steps_per_period) };
        }
        Ok(largest)
    }

    /// [`DIAGNOSIS_PASSES`] scoring passes over `records` (frequency, Hz, and
    /// length, s) and summary `rows` (frequency, Hz, and `n_peaks`), with
    /// the noise held over `interval_s` (s).
    fn of_diagnosed(
        records: impl Iterator<Item = (f64, f64)>,
        rows: impl Iterator<Item = (f64, Option<u64>)>,
        interval_s: f64,
        settings: &DiagnoseSettings,
    ) -> Cost {
        let warmup = f64::from(settings.warmup_cycles);
        let steps = f64::from(Model::default().solver.steps_per_period);
        let records = records.map(|(f, duration_s)| {
            let per_period = REPLICATE_STEPS_PER_PERIOD.min(steps) + 1.0 / (interval_s * f);
            Cost::of(f64::from(settings.replicates), warmup + (duration_s * f).ceil() + 1.0, per_period)
        });
        let rows = rows.map(|(f, n_peaks)| {
            let per_period = steps + 1.0 / (interval_s * f);
            let periods = warmup + n_peaks.unwrap_or(350) as f64;
            Cost::of(f64::from(settings.ensemble_realisations), periods, per_period)
        });
        let pass = records.chain(rows).fold(Cost::NONE, Cost::plus);
        Cost { steps: DIAGNOSIS_PASSES * pass.steps, ..pass }
    }

    /// Refuses a cost beyond the budget of `backend` (on `threads` threads
    /// for the CPU reference) unless `force` is given; `what` names the run
    /// and `lower` says what makes it smaller.
    pub fn check(&self, backend: BackendKind, threads: usize, force: Force, what: &str, lower: &str) -> Result<()> {
        if force.given {
            return Ok(());
        }
        let (limit, on) = match backend {
            BackendKind::Cpu => (CPU_LIMIT, "the CPU reference"),
            BackendKind::Gpu => (GPU_LIMIT, "a GPU"),
        };
        let time = match backend {
            BackendKind::Cpu => format!(
                ", about {} on {threads} threads",
                duration(self.steps / (CPU_STEPS_PER_THREAD_S * threads.max(1) as f64))
            ),
            BackendKind::Gpu => String::new(),
        };
        let problem = if self.steps_per_period.is_nan() || self.steps_per_period > MAX_STEPS_PER_PERIOD {
            format!(
                "one excitation period of one realisation takes {} integration steps (noise intervals and samples \
                 each split a step), over the limit of {} per period; {:.2e} realisation-steps in all{time}",
                fmt_value(self.steps_per_period.round()),
                fmt_value(MAX_STEPS_PER_PERIOD),
                self.steps
            )
        } else if self.steps.is_nan() || self.steps > limit {
            format!(
                "it would take an estimated {:.2e} realisation-steps{time}, over the limit of {limit:e} on {on}",
                self.steps
            )
        } else {
            return Ok(());
        };
        Err(Error::setting(
            "run size",
            format!(
                "{what}: {problem}; {lower}, or pass {} to run it anyway (docs/formats.md, the cost budget)",
                force.spelled("--force", "force=True")
            ),
        ))
    }
}

/// A duration in words: seconds, minutes, hours or days.
fn duration(seconds: f64) -> String {
    match seconds {
        s if s < 120.0 => format!("{s:.0} s"),
        s if s < 7200.0 => format!("{:.0} minutes", s / 60.0),
        s if s < 172_800.0 => format!("{:.0} hours", s / 3600.0),
        s => format!("{} days", fmt_value((s / 86_400.0).round())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::{Condition, Point, RunPlan};

    #[test]
    fn a_job_costs_its_steps_and_noise_intervals() {
        let model = Model::default();
        let c = Condition { excitation_frequency_hz: 6.0, normal_force_n: 10.0 };
        let points = [Point::steady(&model, c)];
        let plan = RunPlan { warmup_cycles: 10, measured_cycles: 90 };
        let job = Job {
            model: &model,
            points: &points,
            realisations: 4,
            first_realisation: 0,
            seed: 1,
            plan,
            record: Record::Sums,
        };
        let cost = Cost::of_job(&job).unwrap();
        // 64 steps and 100 noise intervals (1/600 s at 6 Hz) per period.
        assert!((cost.steps_per_period - 164.0).abs() < 1e-3, "{cost:?}");
        assert!((cost.steps - 4.0 * 100.0 * 164.0).abs() < 1.0, "{cost:?}");
        cost.check(BackendKind::Cpu, 2, Force::flag(false), "sweep", "").unwrap();
        let big = Cost { steps: 2.0 * CPU_LIMIT, ..cost };
        let err = big.check(BackendKind::Cpu, 2, Force::flag(false), "sweep", "lower it").unwrap_err().to_string();
        assert!(err.contains("2.00e11") && err.contains("1e11") && err.contains("--force"), "{err}");
        let err = big.check(BackendKind::Cpu, 2, Force::keyword(false), "sweep", "lower it").unwrap_err().to_string();
        assert!(err.contains("force=True") && !err.contains("--force"), "{err}");
        big.check(BackendKind::Gpu, 2, Force::flag(false), "sweep", "").unwrap();
        big.check(BackendKind::Cpu, 2, Force::flag(true), "sweep", "").unwrap();
    }
}
