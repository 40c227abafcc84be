//! `stickslip simulate`: time-series records of one condition, written as a
//! measurement set.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use super::ModelArgs;
use crate::diagnose::measure::{RunEntry, write_manifest, write_run_file};
use crate::engine::{Condition, Engine, Job, Oscillator, Point, Record, RunPlan};
use crate::io;

#[derive(Args, Debug)]
pub(crate) struct SimulateArgs {
    #[command(flatten)]
    pub(crate) model: ModelArgs,
    /// Excitation frequency, Hz.
    #[arg(long, default_value_t = 7.0)]
    pub(crate) frequency: f64,
    /// Nominal normal force, N.
    #[arg(long, default_value_t = 16.39)]
    pub(crate) normal_force: f64,
    /// Number of realisations (one run file each).
    #[arg(long, default_value_t = 3)]
    pub(crate) realisations: u32,
    /// Record length after warm-up, s.
    #[arg(long, default_value_t = 50.0)]
    pub(crate) duration: f64,
    /// Sampling rate of the records, Hz.
    #[arg(long, default_value_t = 600.0)]
    pub(crate) sample_rate: f64,
    /// Excitation periods discarded before recording.
    #[arg(long, default_value_t = 100)]
    pub(crate) warmup_cycles: u32,
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// Output directory (created; run files and manifest.json go here).
    #[arg(long, default_value = "out/simulate")]
    pub(crate) out: PathBuf,
}

pub(crate) fn simulate(args: SimulateArgs) -> Result<()> {
    let model = args.model.load()?;
    let condition = Condition { excitation_frequency_hz: args.frequency, normal_force_n: args.normal_force };
    Oscillator::new(&model, condition)?;
    if args.realisations == 0 {
        anyhow::bail!("invalid --realisations: must be at least 1");
    }
    if !(args.duration.is_finite() && args.duration > 0.0) {
        anyhow::bail!("invalid --duration {}: must be > 0 s", args.duration);
    }
    if !(args.sample_rate.is_finite() && args.sample_rate > 0.0) {
        anyhow::bail!("invalid --sample-rate {}: must be > 0 Hz", args.sample_rate);
    }
    let engine = Engine::cpu("simulate runs on the reference");
    let points = [Point::steady(&model, condition)];
    let job = Job {
        model: &model,
        points: &points,
        realisations: args.realisations,
        first_realisation: 0,
        seed: args.seed,
        plan: RunPlan { warmup_cycles: args.warmup_cycles, measured_cycles: 0 },
        record: Record::Sums,
    };
    let records = engine.records(&job, 1.0 / args.sample_rate, args.duration)?;
    io::create_dir(&args.out)?;
    let mut runs = Vec::new();
    for (r, samples) in records.iter().enumerate() {
        let file = format!("run-{:.3}hz-{:.3}n-r{r:03}.csv", args.frequency, args.normal_force);
        write_run_file(&args.out.join(&file), samples)?;
        runs.push(RunEntry {
            file,
            excitation_frequency_hz: args.frequency,
            excitation_amplitude_m: model.excitation.amplitude_m,
            normal_force_n: args.normal_force,
        });
    }
    let description =
        format!("simulated by stickslip {} (CPU f64 reference), seed {}", env!("CARGO_PKG_VERSION"), args.seed);
    write_manifest(&args.out, &description, &model, &runs)?;
    io::write_atomically(&args.out.join("model.toml"), |w| w.write_all(model.to_toml_string().as_bytes()))?;
    let samples_per_run = records.first().map_or(0, Vec::len);
    println!("wrote {} run files of {samples_per_run} samples to {}", runs.len(), args.out.display());
    Ok(())
}
