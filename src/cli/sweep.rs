//! `stickslip sweep` and `stickslip merge`.

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args;

use super::{BackendArg, ModelArgs, Progress, emit, info, open_engine};
use crate::app::SweepRequest;
use crate::engine::model::{excitation_frequency_problem, fmt_value, normal_force_problem};
use crate::engine::{GpuOptions, Job, Model, RunPlan};
use crate::io::{OutputSet, owned};
use crate::sweep::{self, Grid, RefineSettings, Shard, SweepSettings, write_output_set};

#[derive(Args, Debug)]
pub(crate) struct SweepArgs {
    #[command(flatten)]
    pub(crate) model: ModelArgs,
    /// Excitation frequencies, Hz: a comma list or START:STOP:COUNT.
    #[arg(long, default_value = "5:15:41", allow_hyphen_values = true)]
    pub(crate) frequencies: String,
    /// Nominal normal forces, N: a comma list or START:STOP:COUNT.
    #[arg(long, default_value = "4,8,12,16.39", allow_hyphen_values = true)]
    pub(crate) normal_forces: String,
    /// Realisations per grid point.
    #[arg(long, default_value_t = 64)]
    pub(crate) realisations: u32,
    /// Excitation periods discarded before measuring.
    #[arg(long, default_value_t = 100)]
    pub(crate) warmup_cycles: u32,
    /// Measured excitation periods per realisation (one peak each).
    #[arg(long, default_value_t = 100)]
    pub(crate) cycles: u32,
    /// Random seed of the noise (Philox key); the same seed gives the same paths on either backend.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// Output directory.
    #[arg(long, default_value = "out/sweep")]
    pub(crate) out: PathBuf,
    /// Where to run: a hardware GPU if there is one (else the CPU reference), a GPU, or the CPU reference.
    #[arg(long, value_enum, default_value = "auto")]
    pub(crate) backend: BackendArg,
    /// Integration steps per GPU dispatch (bounds each submission's run time).
    #[arg(long, default_value_t = crate::engine::gpu::DEFAULT_STEPS_PER_DISPATCH)]
    pub(crate) steps_per_dispatch: u64,
    /// Run only part K/N of the grid (zero-based); combine parts with `stickslip merge`.
    #[arg(long, value_name = "K/N")]
    pub(crate) shard: Option<String>,
    /// Frequency (Hz) whose points Figure 8 shows (the nearest grid frequency).
    #[arg(long, default_value_t = 7.0, allow_negative_numbers = true)]
    pub(crate) fig8_frequency: f64,
    /// Skip the PNG/SVG plots.
    #[arg(long)]
    pub(crate) no_plots: bool,
    /// Keep the frequencies as given: add none where the response changes fast (resonance, stick onset).
    #[arg(long)]
    pub(crate) no_refine: bool,
    /// Frequencies the refinement may add at most (never more than --frequencies has).
    #[arg(long, default_value_t = RefineSettings::default().max_added, value_name = "N")]
    pub(crate) refine_max: usize,
}

#[derive(Args, Debug)]
pub(crate) struct MergeArgs {
    /// Output directory for the merged result.
    #[arg(long)]
    pub(crate) out: PathBuf,
    /// The shard output directories (any order).
    #[arg(required = true)]
    pub(crate) shards: Vec<PathBuf>,
    /// Frequency (Hz) whose points Figure 8 shows (the nearest grid frequency).
    #[arg(long, default_value_t = 7.0, allow_negative_numbers = true)]
    pub(crate) fig8_frequency: f64,
}

/// Parses a grid flag ([`sweep::parse_list`], which refuses more than
/// [`Job::MAX_POINTS`] values before making them); every value must be a
/// physical frequency or force (`check`), and the error names the flag.
fn grid_values(flag: &str, text: &str, check: fn(f64) -> Option<String>) -> Result<Vec<f64>> {
    let values = sweep::parse_list(flag, text)?;
    for &v in &values {
        if let Some(problem) = check(v) {
            anyhow::bail!("invalid {flag}: `{}`: {problem}", fmt_value(v));
        }
    }
    // A value given twice is one grid point: it runs once, and that is said.
    let mut unique: Vec<f64> = Vec::with_capacity(values.len());
    let mut repeated: Vec<String> = Vec::new();
    for v in values {
        if unique.contains(&v) {
            if !repeated.contains(&fmt_value(v)) {
                repeated.push(fmt_value(v));
            }
        } else {
            unique.push(v);
        }
    }
    if !repeated.is_empty() {
        info(&format!(
            "note: {flag} gives {} more than once; each value runs once ({} distinct)",
            repeated.join(", "),
            unique.len()
        ));
    }
    Ok(unique)
}

/// The run settings' limits, blamed on their flags (the engine checks the
/// same limits again, for every caller).
fn check_run_flags(realisations: u32, warmup_cycles: u32, cycles: u32) -> Result<()> {
    if realisations > Job::MAX_REALISATIONS {
        anyhow::bail!(
            "invalid --realisations: {realisations} per grid point exceed the limit of {} (2^20) on either backend",
            Job::MAX_REALISATIONS
        );
    }
    let total = u64::from(warmup_cycles) + u64::from(cycles);
    if total > Job::MAX_CYCLES {
        anyhow::bail!(
            "invalid --cycles/--warmup-cycles: {warmup_cycles} + {cycles} = {total} excitation periods per \
             realisation exceed the limit of {} (2^24) on either backend",
            Job::MAX_CYCLES
        );
    }
    let peaks = u64::from(realisations) * u64::from(cycles);
    if peaks > Job::MAX_PEAKS_PER_POINT {
        anyhow::bail!(
            "invalid --realisations × --cycles: {peaks} peaks per grid point exceed the limit of 2^32 − 1 on either \
             backend"
        );
    }
    Ok(())
}

pub(crate) fn run_sweep(args: SweepArgs) -> Result<()> {
    // Everything is checked before any computation and before anything is written.
    let model = args.model.load()?;
    let grid = Grid {
        frequencies_hz: grid_values("--frequencies", &args.frequencies, excitation_frequency_problem)?,
        normal_forces_n: grid_values("--normal-forces", &args.normal_forces, normal_force_problem)?,
    };
    let total_points = grid.frequencies_hz.len() * grid.normal_forces_n.len();
    if total_points > Job::MAX_POINTS {
        anyhow::bail!(
            "invalid grid: --frequencies × --normal-forces = {total_points} points, over the limit of {} per run; \
             split it into several runs",
            Job::MAX_POINTS
        );
    }
    let shard = match &args.shard {
        Some(text) => Shard::parse(text)?,
        None => Shard::WHOLE,
    };
    let settings = SweepSettings {
        realisations: args.realisations,
        plan: RunPlan { warmup_cycles: args.warmup_cycles, measured_cycles: args.cycles },
        seed: args.seed,
    };
    settings.validate()?;
    check_run_flags(args.realisations, args.warmup_cycles, args.cycles)?;
    if args.steps_per_dispatch == 0 {
        anyhow::bail!("invalid --steps-per-dispatch: must be at least 1");
    }
    super::check_fig8_frequency(args.fig8_frequency)?;
    // The grid is refined the same in every shard, before the shard takes its part.
    let refine = (!args.no_refine).then_some(RefineSettings { max_added: args.refine_max, ..Default::default() });
    if refine.is_some()
        && args.refine_max > 0
        && let Some(why) = sweep::not_refinable(&grid.frequencies_hz)
        && grid.frequencies_hz.len() > 1
    {
        info(&format!("refine: the grid is kept as given ({why})"));
    }
    let request = SweepRequest { model, grid, settings, refine, shard, force: super::force() };
    let prepared = request.prepare(Some((&args.out, "--out")))?;
    if let Some(r) = &prepared.refinement {
        let added: Vec<String> = r.added_hz.iter().map(|f| fmt_value(*f)).collect();
        info(&format!(
            "refine: added {} frequencies where the response changes fast{}{} ({:.1} s; --no-refine keeps the grid as given)",
            added.len(),
            if added.is_empty() { "" } else { ": " },
            added.join(", "),
            prepared.refine_s
        ));
    }
    let engine =
        open_engine(args.backend, GpuOptions { steps_per_dispatch: args.steps_per_dispatch, ..GpuOptions::default() })?;
    let points = prepared.conditions.len();
    if shard != Shard::WHOLE {
        info(&format!(
            "shard {}/{}: {points} of {} grid points",
            shard.index,
            shard.count,
            prepared.grid.frequencies_hz.len() * prepared.grid.normal_forces_n.len()
        ));
    }
    let added = prepared.refinement.as_ref().map_or(0, |r| r.added_hz.len());
    let (frequencies, forces) = (prepared.grid.frequencies_hz.len(), prepared.grid.normal_forces_n.len());
    let progress = Progress::bar("sweep");
    let plots = (!args.no_plots).then_some(args.fig8_frequency);
    if plots.is_some() {
        super::note_fig8_frequency(args.fig8_frequency, prepared.conditions.iter().map(|c| c.excitation_frequency_hz));
    }
    let swept = prepared.run(&engine, plots, &mut |done, total| progress.position(done, total))?;
    progress.finish();
    if swept.widened_points > 0 {
        info(&format!(
            "note: the peaks of {} grid point(s) left the range their histogram covers (−0.5 to 1.5 times the \
             frictionless amplitude); each was run again over a range that holds them, so its statistics are exact \
             (sweep.json lists them under widened_ranges)",
            swept.widened_points
        ));
    }
    emit(&format!(
        "{points} grid points ({frequencies} frequencies{}; {forces} normal forces{}) × {} realisations × {} cycles in \
         {:.1} s; wrote {}",
        if added > 0 { format!(", {added} added by refinement") } else { String::new() },
        if shard == Shard::WHOLE { String::new() } else { format!("; shard {}/{}", shard.index, shard.count) },
        settings.realisations,
        settings.plan.measured_cycles,
        swept.run_s,
        args.out.join("sweep.csv").display()
    ))?;
    Ok(())
}

pub(crate) fn merge(args: MergeArgs) -> Result<()> {
    super::check_fig8_frequency(args.fig8_frequency)?;
    let inputs: Vec<&Path> = args.shards.iter().map(PathBuf::as_path).collect();
    // --out may be neither a shard nor contain one: checked before reading them.
    let out = OutputSet::prepare(&args.out, "--out", owned::SWEEP, &inputs)?;
    let (identity, result) = sweep::merge_shards(&args.shards)?;
    let model = Model::from_toml_str(&identity.model_toml, "merged shards", &[])?;
    let description = format!("merged from {} shards", args.shards.len());
    let timings = serde_json::json!({ "merged_shards": args.shards.len() });
    let plots = Some(args.fig8_frequency);
    super::note_fig8_frequency(args.fig8_frequency, result.conditions.iter().map(|c| c.excitation_frequency_hz));
    write_output_set(out.dir(), &model, &identity, Shard::WHOLE, &result, &description, timings, None, plots)?;
    out.commit()?;
    emit(&format!(
        "merged {} shards ({} grid points) into {}",
        args.shards.len(),
        result.conditions.len(),
        args.out.display()
    ))?;
    Ok(())
}
