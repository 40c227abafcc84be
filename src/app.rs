//! What a front end does with a request, from its checked settings to the
//! files it writes. The command line (`cli`) and the Python package both
//! call these functions, so a sweep written from Python is the one the
//! command line writes: the same checks in the same order, the same
//! refinement, run and output set. The front ends only parse their
//! arguments (blaming their own flag names), open the [`Engine`] and report.

use std::path::Path;
use std::time::Instant;

use crate::budget::{Cost, Force};
use crate::engine::{BackendKind, Condition, Engine, Job, Model, Oscillator, Record, RunPlan};
use crate::error::{Error, Result};
use crate::io::{OutputSet, owned};
use crate::sweep::{self, Grid, RefineSettings, Refinement, RunIdentity, Shard, SweepResult, SweepSettings};

/// A sweep to run: the model, the grid as given, the run settings, whether
/// to refine the frequencies first, and which shard of the grid.
#[derive(Clone, Debug)]
pub struct SweepRequest {
    pub model: Model,
    pub grid: Grid,
    pub settings: SweepSettings,
    /// Frequencies added where the response changes fast before the run
    /// (`None`: the grid as given).
    pub refine: Option<RefineSettings>,
    pub shard: Shard,
    /// Whether a run beyond the cost budget ([`crate::budget`]) goes ahead.
    pub force: Force,
}

/// A sweep checked, refined and ready to run ([`SweepRequest::prepare`]).
pub struct PreparedSweep {
    pub model: Model,
    /// The grid after refinement: the same in every shard (it depends on
    /// neither the seed nor the backend).
    pub grid: Grid,
    pub refinement: Option<Refinement>,
    /// Seconds the refinement took.
    pub refine_s: f64,
    pub settings: SweepSettings,
    pub shard: Shard,
    /// The grid points this shard runs.
    pub conditions: Vec<Condition>,
    pub force: Force,
    /// Where the output set is written, prepared before anything ran.
    out: Option<OutputSet>,
}

/// What a sweep produced, and how long its run took (s).
pub struct Swept {
    pub result: SweepResult,
    pub run_s: f64,
    /// Grid points whose peaks left their histogram's range and were run
    /// again over a range that holds them (`sweep.json`'s `widened_ranges`).
    pub widened_points: usize,
}

impl SweepRequest {
    /// Checks everything before any computation and before anything is
    /// written: the run settings, every grid point's model, and the output
    /// directory `out` (`(directory, the flag or argument naming it)`; `None`
    /// writes nothing). Then refines the grid, takes this shard's points and
    /// checks the job they make. The refinement's pilot is checked against
    /// the cost budget before it runs (the run itself in
    /// [`PreparedSweep::run`], once the backend is known).
    pub fn prepare(self, out: Option<(&Path, &str)>) -> Result<PreparedSweep> {
        let SweepRequest { model, grid, settings, refine, shard, force } = self;
        settings.validate()?;
        for c in &grid.conditions() {
            Oscillator::new(&model, *c)?;
        }
        let out = match out {
            Some((dir, flag)) => Some(OutputSet::prepare(dir, flag, owned::SWEEP, &[])?),
            None => None,
        };
        if refine.is_some() && sweep::not_refinable(&grid.frequencies_hz).is_none() {
            pilot_cost(&model, &grid, settings.plan.warmup_cycles)?.check(
                BackendKind::Cpu,
                crate::budget::cpu_threads(),
                force,
                "sweep's refinement",
                &format!(
                    "ask for fewer warm-up cycles or grid points, or {} to keep the grid as given",
                    force.spelled("--no-refine", "refine=False")
                ),
            )?;
        }
        let started = Instant::now();
        let (grid, refinement) = sweep::refined_grid(&model, grid, settings.plan.warmup_cycles, refine)?;
        let refine_s = started.elapsed().as_secs_f64();
        let all = grid.conditions();
        if shard.count as usize > all.len() {
            // Every shard must hold a point, or `merge` could never be given
            // all N of them.
            return Err(Error::setting(
                "--shard",
                format!(
                    "{}/{}: the grid has {} point(s), so it splits into at most {} shards",
                    shard.index,
                    shard.count,
                    all.len(),
                    all.len()
                ),
            ));
        }
        let conditions = all[shard.points(all.len())].to_vec();
        if !conditions.is_empty() {
            let points = sweep::steady_points(&model, &conditions);
            sweep::sweep_job(&model, &points, &settings).validate()?;
        }
        Ok(PreparedSweep { model, grid, refinement, refine_s, settings, shard, conditions, force, out })
    }
}

/// An upper estimate of the refinement's pilot: it runs on the CPU, noise
/// free, one path per point with `warmup_cycles` and
/// [`sweep::refine::PILOT_CYCLES`] periods, at up to twice the grid's
/// frequencies (counted here as two realisations per point).
fn pilot_cost(model: &Model, grid: &Grid, warmup_cycles: u32) -> Result<Cost> {
    let mut pilot = model.clone();
    pilot.friction.sigma = 0.0;
    pilot.normal_force.sigma = 0.0;
    let points = sweep::steady_points(&pilot, &grid.conditions());
    let plan = RunPlan { warmup_cycles, measured_cycles: sweep::refine::PILOT_CYCLES };
    Cost::of_job(&Job {
        model: &pilot,
        points: &points,
        realisations: 2,
        first_realisation: 0,
        seed: 1,
        plan,
        record: Record::Sums,
    })
}

impl PreparedSweep {
    /// Runs this shard's points on `engine` and, where an output directory
    /// was prepared, writes the output set there (the figures with Figure 8
    /// at `plots_at_hz`; none without) and swaps it into place. A run whose
    /// estimated work is beyond the budget of `engine`'s backend is refused
    /// first, unless forced.
    pub fn run(self, engine: &Engine, plots_at_hz: Option<f64>, progress: &mut dyn FnMut(u64, u64)) -> Result<Swept> {
        if !self.conditions.is_empty() {
            let points = sweep::steady_points(&self.model, &self.conditions);
            let cost = Cost::of_job(&sweep::sweep_job(&self.model, &points, &self.settings))?;
            cost.check(
                engine.kind(),
                crate::budget::cpu_threads(),
                self.force,
                "sweep",
                &format!(
                    "lower {}, {} or the grid, or raise noise.interval_s",
                    self.force.spelled("--realisations", "realisations"),
                    self.force.spelled("--cycles", "cycles")
                ),
            )?;
        }
        let started = Instant::now();
        let result = sweep::run_sweep(&self.model, &self.conditions, &self.settings, engine, progress)?;
        let run_s = started.elapsed().as_secs_f64();
        let widened_points = sweep::output::widened_ranges(&self.model, &result).len();
        if let Some(out) = self.out {
            let identity = RunIdentity {
                model_toml: self.model.to_toml_string(),
                frequencies_hz: self.grid.frequencies_hz.clone(),
                normal_forces_n: self.grid.normal_forces_n.clone(),
                realisations: self.settings.realisations,
                warmup_cycles: self.settings.plan.warmup_cycles,
                measured_cycles: self.settings.plan.measured_cycles,
                seed: self.settings.seed,
                backend: engine.kind(),
            };
            let timings = serde_json::json!({ "run_s": run_s, "refine_s": self.refine_s });
            sweep::write_output_set(
                out.dir(),
                &self.model,
                &identity,
                self.shard,
                &result,
                engine.description(),
                timings,
                self.refinement.as_ref(),
                plots_at_hz,
            )?;
            out.commit()?;
        }
        Ok(Swept { result, run_s, widened_points })
    }
}
