//! `stickslip simulate`: time-series records of one condition, written as a
//! measurement set.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use super::{ModelArgs, Progress, emit};
use crate::budget::Cost;
use crate::engine::model::{fmt_bound, fmt_value, limits};
use crate::engine::{Condition, Engine, Job, Oscillator, Point, Record, RunPlan, Sample};
use crate::io::{self, OutputSet, owned};
use crate::measure::{MIN_PERIODS, RunEntry, write_manifest, write_run_file};

#[derive(Args, Debug)]
pub(crate) struct SimulateArgs {
    #[command(flatten)]
    pub(crate) model: ModelArgs,
    /// Excitation frequency, Hz.
    #[arg(long, default_value_t = 7.0, allow_negative_numbers = true)]
    pub(crate) frequency: f64,
    /// Nominal normal force, N.
    #[arg(long, default_value_t = 16.39, allow_negative_numbers = true)]
    pub(crate) normal_force: f64,
    /// Number of realisations (one run file each).
    #[arg(long, default_value_t = 3)]
    pub(crate) realisations: u32,
    /// Record length after warm-up, s.
    #[arg(long, default_value_t = 50.0, allow_negative_numbers = true)]
    pub(crate) duration: f64,
    /// Sampling rate of the records, Hz.
    #[arg(long, default_value_t = 600.0, allow_negative_numbers = true)]
    pub(crate) sample_rate: f64,
    /// Excitation periods discarded before recording.
    #[arg(long, default_value_t = 100)]
    pub(crate) warmup_cycles: u32,
    /// Random seed of the noise (Philox key); realisation r of a seed is the same path as in `sweep`.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// Output directory (created; run files and manifest.json go here).
    #[arg(long, default_value = "out/simulate")]
    pub(crate) out: PathBuf,
}

/// Most samples one simulated record may hold (the run-file limit allows
/// about this many rows of five channels).
const MAX_SAMPLES_PER_RECORD: f64 = 2_500_000.0;

pub(crate) fn simulate(args: SimulateArgs) -> Result<()> {
    // Everything is checked before any computation and before anything is
    // written: what `simulate` writes, `diagnose` must be able to read.
    let model = args.model.load()?;
    let condition = Condition { excitation_frequency_hz: args.frequency, normal_force_n: args.normal_force };
    condition.validate_flags("--frequency", "--normal-force")?;
    if args.normal_force <= 0.0 {
        anyhow::bail!(
            "invalid --normal-force {}: a measurement set's runs are pressed together (normal_force_n > 0 N); \
             `sweep` runs an unloaded rig",
            args.normal_force
        );
    }
    Oscillator::new(&model, condition)?;
    if args.realisations == 0 || args.realisations > Job::MAX_REALISATIONS {
        anyhow::bail!(
            "invalid --realisations: {} (one run file each) must be between 1 and {}",
            args.realisations,
            Job::MAX_REALISATIONS
        );
    }
    if !(args.sample_rate.is_finite() && args.sample_rate > 0.0) {
        anyhow::bail!("invalid --sample-rate {}: must be a finite number > 0 Hz", fmt_value(args.sample_rate));
    }
    if args.sample_rate <= 2.0 * args.frequency {
        anyhow::bail!(
            "invalid --sample-rate {}: a record must be sampled above twice its excitation frequency ({} Hz, the \
             Nyquist rate)",
            fmt_value(args.sample_rate),
            fmt_value(2.0 * args.frequency)
        );
    }
    let (dt_lo, dt_hi) = limits::NOISE_INTERVAL_S;
    if !(dt_lo..=dt_hi).contains(&(1.0 / args.sample_rate)) {
        anyhow::bail!(
            "invalid --sample-rate {}: the sample interval must lie between {} and {} s",
            fmt_value(args.sample_rate),
            fmt_bound(dt_lo),
            fmt_bound(dt_hi)
        );
    }
    if !(args.duration.is_finite() && args.duration > 0.0) {
        anyhow::bail!("invalid --duration {}: must be a finite number > 0 s", fmt_value(args.duration));
    }
    let periods = args.duration * args.frequency;
    if periods < MIN_PERIODS {
        anyhow::bail!(
            "invalid --duration {}: a record must cover at least {MIN_PERIODS} excitation periods ({} s at {} Hz)",
            fmt_value(args.duration),
            fmt_value(MIN_PERIODS / args.frequency),
            fmt_value(args.frequency)
        );
    }
    let samples = args.duration * args.sample_rate;
    if samples > MAX_SAMPLES_PER_RECORD {
        anyhow::bail!(
            "invalid --duration × --sample-rate: {} samples per record, over the limit of {MAX_SAMPLES_PER_RECORD}",
            fmt_value(samples.round())
        );
    }
    if periods.ceil() + 1.0 + f64::from(args.warmup_cycles) > Job::MAX_CYCLES as f64 {
        anyhow::bail!(
            "invalid --duration/--warmup-cycles: {} excitation periods per record, over the limit of {}",
            fmt_value(periods.ceil() + 1.0 + f64::from(args.warmup_cycles)),
            Job::MAX_CYCLES
        );
    }
    let points = [Point::steady(&model, condition)];
    let job = Job {
        model: &model,
        points: &points,
        realisations: args.realisations,
        first_realisation: 0,
        seed: args.seed,
        plan: RunPlan { warmup_cycles: args.warmup_cycles, measured_cycles: 0 },
        record: Record::Samples {
            interval_s: 1.0 / args.sample_rate,
            duration_s: args.duration,
            at_noise_boundaries: false,
        },
    };
    job.validate()?;
    let engine = Engine::cpu("simulate runs on the reference");
    super::check_budget(
        Cost::of_job(&job)?,
        engine.kind(),
        "simulate",
        "lower --realisations, --duration or --sample-rate, or raise noise.interval_s",
    )?;
    let out = OutputSet::prepare(&args.out, "--out", owned::SIMULATION, &[])?;
    super::info(&format!("backend: {}", engine.description()));
    super::info("adapter: none (CPU reference)");
    let progress = Progress::bar("simulate");
    let mut records = engine.run(&job, &mut |done, total| progress.position(done, total))?.records;
    progress.finish();
    exact_sample_times(&mut records, args.sample_rate);
    let mut runs = Vec::new();
    for (r, samples) in records.iter().enumerate() {
        let file = format!("run-{:.3}hz-{:.3}n-r{r:03}.csv", args.frequency, args.normal_force);
        write_run_file(&out.dir().join(&file), samples)?;
        runs.push(RunEntry {
            file,
            excitation_frequency_hz: args.frequency,
            excitation_amplitude_m: model.excitation.amplitude_m,
            normal_force_n: args.normal_force,
        });
    }
    let description =
        format!("simulated by stickslip {} (CPU f64 reference), seed {}", env!("CARGO_PKG_VERSION"), args.seed);
    write_manifest(out.dir(), &description, &model, &runs)?;
    io::write_atomically(&out.dir().join("model.toml"), |w| w.write_all(model.to_toml_string().as_bytes()))?;
    out.commit()?;
    let samples_per_run = records.first().map_or(0, Vec::len);
    emit(&format!("wrote {} run files of {samples_per_run} samples to {}", runs.len(), args.out.display()))?;
    Ok(())
}

/// Sets each record's sample times to `i / rate_hz`, the sampling grid the
/// engine steps to, computed from the sample's index: the engine's times are
/// differences of absolute times, which leave float noise in the last bits
/// (`0.0016666666666669272` for the second sample at 600 Hz), and a run file
/// writes the shortest decimal that reads back as the same `f64`
/// (`0.0016666666666666668`). The first sample is at `t = 0`, a whole number of
/// periods after the start, so `t` stays in the frame of the base motion
/// `u = U0 cos(2π f t)`.
pub fn exact_sample_times(records: &mut [Vec<Sample>], rate_hz: f64) {
    for record in records {
        for (i, s) in record.iter_mut().enumerate() {
            let t = i as f64 / rate_hz;
            debug_assert!((s.t_s - t).abs() <= 1e-9 * t.max(1.0), "sample {i} at {} s, not {t} s", s.t_s);
            s.t_s = t;
        }
    }
}
