//! `stickslip sweep` and `stickslip merge`.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use clap::Args;

use super::{BackendArg, ModelArgs, progress_bar};
use crate::engine::{Engine, GpuOptions, Model, Oscillator, RunPlan};
use crate::sweep::{self, Grid, RunIdentity, Shard, SweepSettings, write_output_set};

#[derive(Args, Debug)]
pub(crate) struct SweepArgs {
    #[command(flatten)]
    pub(crate) model: ModelArgs,
    /// Excitation frequencies, Hz: a comma list or START:STOP:COUNT.
    #[arg(long, default_value = "5:15:41")]
    pub(crate) frequencies: String,
    /// Nominal normal forces, N: a comma list or START:STOP:COUNT.
    #[arg(long, default_value = "4,8,12,16.39")]
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
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// Output directory.
    #[arg(long, default_value = "out/sweep")]
    pub(crate) out: PathBuf,
    /// Where to run: a GPU if there is one (else lavapipe, else the CPU), a GPU, or the CPU reference.
    #[arg(long, value_enum, default_value = "auto")]
    pub(crate) backend: BackendArg,
    /// Integration steps per GPU dispatch (bounds each submission's run time).
    #[arg(long, default_value_t = crate::engine::gpu::DEFAULT_STEPS_PER_DISPATCH)]
    pub(crate) steps_per_dispatch: u64,
    /// Run only part K/N of the grid (zero-based); combine parts with `stickslip merge`.
    #[arg(long, value_name = "K/N")]
    pub(crate) shard: Option<String>,
    /// Frequency (Hz) whose points Figure 8 shows (the nearest grid frequency).
    #[arg(long, default_value_t = 7.0)]
    pub(crate) fig8_frequency: f64,
    /// Skip the PNG/SVG plots.
    #[arg(long)]
    pub(crate) no_plots: bool,
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
    #[arg(long, default_value_t = 7.0)]
    pub(crate) fig8_frequency: f64,
}

pub(crate) fn run_sweep(args: SweepArgs) -> Result<()> {
    let model = args.model.load()?;
    let grid = Grid {
        frequencies_hz: sweep::parse_list("--frequencies", &args.frequencies)?,
        normal_forces_n: sweep::parse_list("--normal-forces", &args.normal_forces)?,
    };
    let shard = match &args.shard {
        Some(text) => Shard::parse(text)?,
        None => Shard::WHOLE,
    };
    let all_conditions = grid.conditions();
    for c in &all_conditions {
        Oscillator::new(&model, *c)?;
    }
    let conditions = &all_conditions[shard.points(all_conditions.len())];
    let settings = SweepSettings {
        realisations: args.realisations,
        plan: RunPlan { warmup_cycles: args.warmup_cycles, measured_cycles: args.cycles },
        seed: args.seed,
    };
    settings.validate()?;
    if args.steps_per_dispatch == 0 {
        anyhow::bail!("invalid --steps-per-dispatch: must be at least 1");
    }
    let engine = Engine::open(args.backend.into(), GpuOptions { steps_per_dispatch: args.steps_per_dispatch })?;
    let description = engine.description().to_string();
    eprintln!("backend: {description}");
    if shard != Shard::WHOLE {
        eprintln!(
            "shard {}/{}: {} of {} grid points",
            shard.index,
            shard.count,
            conditions.len(),
            all_conditions.len()
        );
    }
    let started = Instant::now();
    let bar = progress_bar(1, "sweep");
    let result = sweep::run_sweep(&model, conditions, &settings, &engine, &mut |done, total| {
        bar.set_length(total);
        bar.set_position(done);
    })?;
    bar.finish_and_clear();
    let run_s = started.elapsed().as_secs_f64();
    let identity = RunIdentity {
        model_toml: model.to_toml_string(),
        frequencies_hz: grid.frequencies_hz.clone(),
        normal_forces_n: grid.normal_forces_n.clone(),
        realisations: settings.realisations,
        warmup_cycles: settings.plan.warmup_cycles,
        measured_cycles: settings.plan.measured_cycles,
        seed: settings.seed,
        backend: engine.kind(),
    };
    let timings = serde_json::json!({ "run_s": run_s });
    let plots = (!args.no_plots).then_some(args.fig8_frequency);
    write_output_set(&args.out, &model, &identity, shard, &result, &description, timings, plots)?;
    eprintln!(
        "{} grid points × {} realisations × {} cycles in {run_s:.1} s; wrote {}",
        conditions.len(),
        settings.realisations,
        settings.plan.measured_cycles,
        args.out.join("sweep.csv").display()
    );
    Ok(())
}

pub(crate) fn merge(args: MergeArgs) -> Result<()> {
    let (identity, result) = sweep::merge_shards(&args.shards)?;
    let model = Model::from_toml_str(&identity.model_toml, "merged shards", &[])?;
    let description = format!("merged from {} shards", args.shards.len());
    let timings = serde_json::json!({ "merged_shards": args.shards.len() });
    let plots = Some(args.fig8_frequency);
    write_output_set(&args.out, &model, &identity, Shard::WHOLE, &result, &description, timings, plots)?;
    eprintln!(
        "merged {} shards ({} grid points) into {}",
        args.shards.len(),
        result.conditions.len(),
        args.out.display()
    );
    Ok(())
}
