//! The command line (the only place that uses `anyhow`).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use crate::cpu::{self, RunPlan, Sampler};
use crate::io;
use crate::model::{Condition, Model, Oscillator};
use crate::diagnose::{self, DiagnoseSettings};
use crate::plot;
use crate::sweep::{self, Backend, BackendChoice, Grid, RunIdentity, Shard, SweepResult, SweepSettings};

#[derive(Parser, Debug)]
#[command(name = "stickslip", version, about = "Ensembles of a stochastic stick-slip friction oscillator on the GPU, checked against an exact CPU reference")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Simulate one condition and write time-series records (run files + manifest.json).
    Simulate(SimulateArgs),
    /// Run a frequency × normal-force grid and write per-point peak statistics (sweep.csv) and plots.
    Sweep(SweepArgs),
    /// Combine the outputs of `sweep --shard K/N` runs into what the unsharded run writes.
    Merge(MergeArgs),
    /// Diagnose the gap between a measurement set and the model: where, which effect, how far it shrinks.
    Diagnose(DiagnoseArgs),
    /// Benchmark the diagnosis blind on synthetic sets with a withheld effect.
    BenchmarkDiagnosis(BenchmarkArgs),
}

#[derive(Args, Debug)]
struct DiagnoseArgs {
    /// The measurement set (a directory with manifest.json).
    dir: PathBuf,
    /// Output directory (report.json, report.html, baseline-model.toml, fitted-model.toml).
    #[arg(long)]
    out: PathBuf,
    #[arg(long, value_enum, default_value = "auto")]
    backend: BackendArg,
    #[arg(long, default_value_t = 20_251_122)]
    seed: u64,
    /// Simulated replicate records per condition.
    #[arg(long, default_value_t = 8)]
    replicates: u32,
    /// Realisations per condition in the ensembles that score summary data.
    #[arg(long, default_value_t = 64)]
    realisations: u32,
}

#[derive(Args, Debug)]
struct BenchmarkArgs {
    /// Where the synthetic sets and their diagnoses go.
    #[arg(long, default_value = "out/benchmark-diagnosis")]
    out: PathBuf,
    /// Null sets (no effect).
    #[arg(long, default_value_t = 8)]
    nulls: u32,
    /// Effect forms used (1 and 2 are the non-candidate forms).
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    forms: Vec<u32>,
    /// Strength levels (0 moderate, 1 strong).
    #[arg(long, value_delimiter = ',', default_value = "0,1")]
    levels: Vec<u32>,
    /// Only these effects (comma list of names); all seven by default.
    #[arg(long, value_delimiter = ',')]
    effects: Vec<String>,
    /// Runs per condition and record length (s).
    #[arg(long, default_value_t = 2)]
    runs_per_condition: u32,
    #[arg(long, default_value_t = 20.0)]
    duration: f64,
    /// Normal-force levels as shares of Den Hartog's no-stop threshold
    /// (comma list; below 1 the noiseless block never stops).
    #[arg(long, value_delimiter = ',', default_values_t = crate::synthetic::LOAD_SHARES)]
    load_shares: Vec<f64>,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[arg(long, value_enum, default_value = "auto")]
    backend: BackendArg,
    /// Simulated replicate records per condition in each diagnosis.
    #[arg(long, default_value_t = 8)]
    replicates: u32,
}

#[derive(Args, Debug)]
struct MergeArgs {
    /// Output directory for the merged result.
    #[arg(long)]
    out: PathBuf,
    /// The shard output directories (any order).
    #[arg(required = true)]
    shards: Vec<PathBuf>,
    /// Frequency (Hz) whose points Figure 8 shows (the nearest grid frequency).
    #[arg(long, default_value_t = 7.0)]
    fig8_frequency: f64,
}

#[derive(Args, Debug)]
struct ModelArgs {
    /// Model file (TOML); without it, the embedded paper rig.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Override one model parameter by its dotted key, e.g. friction.a=0.3 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

impl ModelArgs {
    fn load(&self) -> Result<Model> {
        Ok(match &self.config {
            Some(path) => Model::from_file(path, &self.set)?,
            None => Model::paper_rig(&self.set)?,
        })
    }
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum BackendArg {
    Auto,
    Gpu,
    Cpu,
}

impl From<BackendArg> for BackendChoice {
    fn from(b: BackendArg) -> Self {
        match b {
            BackendArg::Auto => BackendChoice::Auto,
            BackendArg::Gpu => BackendChoice::Gpu,
            BackendArg::Cpu => BackendChoice::Cpu,
        }
    }
}

#[derive(Args, Debug)]
struct SimulateArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Excitation frequency, Hz.
    #[arg(long, default_value_t = 7.0)]
    frequency: f64,
    /// Nominal normal force, N.
    #[arg(long, default_value_t = 16.39)]
    normal_force: f64,
    /// Number of realisations (one run file each).
    #[arg(long, default_value_t = 3)]
    realisations: u32,
    /// Record length after warm-up, s.
    #[arg(long, default_value_t = 50.0)]
    duration: f64,
    /// Sampling rate of the records, Hz.
    #[arg(long, default_value_t = 600.0)]
    sample_rate: f64,
    /// Excitation periods discarded before recording.
    #[arg(long, default_value_t = 100)]
    warmup_cycles: u32,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output directory (created; run files and manifest.json go here).
    #[arg(long, default_value = "out/simulate")]
    out: PathBuf,
}

#[derive(Args, Debug)]
struct SweepArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Excitation frequencies, Hz: a comma list or START:STOP:COUNT.
    #[arg(long, default_value = "5:15:41")]
    frequencies: String,
    /// Nominal normal forces, N: a comma list or START:STOP:COUNT.
    #[arg(long, default_value = "4,8,12,16.39")]
    normal_forces: String,
    /// Realisations per grid point.
    #[arg(long, default_value_t = 64)]
    realisations: u32,
    /// Excitation periods discarded before measuring.
    #[arg(long, default_value_t = 100)]
    warmup_cycles: u32,
    /// Measured excitation periods per realisation (one peak each).
    #[arg(long, default_value_t = 100)]
    cycles: u32,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output directory.
    #[arg(long, default_value = "out/sweep")]
    out: PathBuf,
    /// Where to run: a GPU if there is one (else lavapipe, else the CPU), a GPU, or the CPU reference.
    #[arg(long, value_enum, default_value = "auto")]
    backend: BackendArg,
    /// Integration steps per GPU dispatch (bounds each submission's run time).
    #[arg(long, default_value_t = crate::gpu::DEFAULT_STEPS_PER_DISPATCH)]
    steps_per_dispatch: u64,
    /// Run only part K/N of the grid (zero-based); combine parts with `stickslip merge`.
    #[arg(long, value_name = "K/N")]
    shard: Option<String>,
    /// Frequency (Hz) whose points Figure 8 shows (the nearest grid frequency).
    #[arg(long, default_value_t = 7.0)]
    fig8_frequency: f64,
    /// Skip the PNG/SVG plots.
    #[arg(long)]
    no_plots: bool,
}

/// Runs the command line; returns the process exit code.
pub fn main() -> ExitCode {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // Mesa's Vulkan loader probes Wayland and prints a misleading
        // "error: XDG_RUNTIME_DIR is invalid" on headless machines.
        // SAFETY: no other thread exists yet.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Simulate(args) => simulate(args),
        Command::Sweep(args) => run_sweep(args),
        Command::Merge(args) => merge(args),
        Command::Diagnose(args) => run_diagnose(args),
        Command::BenchmarkDiagnosis(args) => run_benchmark(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn progress_bar(total: u64, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {percent:>3}% {elapsed_precise} (eta {eta})")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(what.to_string());
    bar
}

fn simulate(args: SimulateArgs) -> Result<()> {
    let model = args.model.load()?;
    let condition = Condition { excitation_frequency_hz: args.frequency, normal_force_n: args.normal_force };
    let osc = Oscillator::new(&model, condition)?;
    if args.realisations == 0 {
        anyhow::bail!("invalid --realisations: must be at least 1");
    }
    if !(args.duration.is_finite() && args.duration > 0.0) {
        anyhow::bail!("invalid --duration {}: must be > 0 s", args.duration);
    }
    if !(args.sample_rate.is_finite() && args.sample_rate > 0.0) {
        anyhow::bail!("invalid --sample-rate {}: must be > 0 Hz", args.sample_rate);
    }
    let samples_per_run = (args.duration * args.sample_rate).floor() as usize;
    let measured_cycles = (args.duration * args.frequency).ceil() as u32 + 1;
    let plan = RunPlan { warmup_cycles: args.warmup_cycles, measured_cycles };
    let record_start_s = f64::from(args.warmup_cycles) * osc.period_s;
    io::create_dir(&args.out)?;
    let initial = sweep::initial_state(&model, condition);
    let mut runs = Vec::new();
    for r in 0..args.realisations {
        let mut sampler = Sampler::new(1.0 / args.sample_rate, record_start_s);
        cpu::simulate_path(&osc, args.seed, r, plan, initial, Some(&mut sampler));
        let mut samples = sampler.samples;
        samples.truncate(samples_per_run);
        for s in &mut samples {
            s.t_s -= record_start_s;
        }
        let file = format!("run-{:.3}hz-{:.3}n-r{r:03}.csv", args.frequency, args.normal_force);
        io::write_run_file(&args.out.join(&file), &samples)?;
        runs.push(io::RunEntry {
            file,
            excitation_frequency_hz: args.frequency,
            excitation_amplitude_m: model.excitation.amplitude_m,
            normal_force_n: args.normal_force,
        });
    }
    let description = format!("simulated by stickslip {} (CPU f64 reference), seed {}", env!("CARGO_PKG_VERSION"), args.seed);
    io::write_manifest(&args.out, &description, &model, &runs)?;
    io::write_atomically(&args.out.join("model.toml"), |w| w.write_all(model.to_toml_string().as_bytes()))?;
    println!("wrote {} run files of {samples_per_run} samples to {}", runs.len(), args.out.display());
    Ok(())
}

fn run_sweep(args: SweepArgs) -> Result<()> {
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
        steps_per_dispatch: args.steps_per_dispatch,
    };
    settings.validate()?;
    let (backend, description) = Backend::open(args.backend.into())?;
    eprintln!("backend: {description}");
    if shard != Shard::WHOLE {
        eprintln!("shard {}/{}: {} of {} grid points", shard.index, shard.count, conditions.len(), all_conditions.len());
    }
    let started = Instant::now();
    let bar = progress_bar(1, "sweep");
    let result = sweep::run_sweep(&model, conditions, &settings, &backend, &mut |done, total| {
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
        backend: backend.name().to_string(),
    };
    let timings = serde_json::json!({ "run_s": run_s });
    write_outputs(&args.out, &model, &identity, shard, &result, &description, timings, (!args.no_plots).then_some(args.fig8_frequency))?;
    eprintln!(
        "{} grid points × {} realisations × {} cycles in {run_s:.1} s; wrote {}",
        conditions.len(),
        settings.realisations,
        settings.plan.measured_cycles,
        args.out.join("sweep.csv").display()
    );
    Ok(())
}

fn merge(args: MergeArgs) -> Result<()> {
    let (identity, result) = sweep::merge_shards(&args.shards)?;
    let model = Model::from_toml_str(&identity.model_toml, "merged shards", &[])?;
    let description = format!("merged from {} shards", args.shards.len());
    let timings = serde_json::json!({ "merged_shards": args.shards.len() });
    write_outputs(&args.out, &model, &identity, Shard::WHOLE, &result, &description, timings, Some(args.fig8_frequency))?;
    eprintln!("merged {} shards ({} grid points) into {}", args.shards.len(), result.conditions.len(), args.out.display());
    Ok(())
}

/// Writes everything a sweep (or a merge) produces into `out`: sweep.csv,
/// histograms.csv, accumulators.json, sweep.json and (optionally) the plots.
#[allow(clippy::too_many_arguments)]
fn write_outputs(
    out: &Path,
    model: &Model,
    identity: &RunIdentity,
    shard: Shard,
    result: &SweepResult,
    description: &str,
    timings: serde_json::Value,
    plots_at_hz: Option<f64>,
) -> Result<()> {
    io::create_dir(out)?;
    sweep::write_sweep_csv(&out.join("sweep.csv"), &result.rows())?;
    sweep::write_histograms_csv(&out.join("histograms.csv"), result)?;
    sweep::write_accumulators(&out.join("accumulators.json"), &result.to_file(identity, shard))?;
    let mut files = vec!["sweep.csv".to_string(), "histograms.csv".into(), "accumulators.json".into()];
    if let Some(f) = plots_at_hz {
        for path in plot::write_sweep_plots(out, result, f)? {
            files.push(path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default());
        }
    }
    let sidecar = serde_json::json!({
        "format": "stickslip-sweep/1",
        "stickslip_version": env!("CARGO_PKG_VERSION"),
        "model": model,
        "model_toml": identity.model_toml,
        "frequencies_hz": identity.frequencies_hz,
        "normal_forces_n": identity.normal_forces_n,
        "realisations": identity.realisations,
        "warmup_cycles": identity.warmup_cycles,
        "measured_cycles": identity.measured_cycles,
        "seed": identity.seed,
        "backend": identity.backend,
        "adapter": description,
        "shard": shard,
        "files": files,
        "timings": timings,
    });
    let path = out.join("sweep.json");
    io::write_atomically(&path, |w| {
        serde_json::to_writer_pretty(&mut *w, &sidecar)?;
        writeln!(w)
    })
    .with_context(|| format!("writing {}", path.display()))
}

fn run_diagnose(args: DiagnoseArgs) -> Result<()> {
    // Read (and so validate) the set before anything else: bad input writes nothing.
    let set = crate::measure::read_measurement_set(&args.dir)?;
    let (backend, description) = Backend::open(args.backend.into())?;
    eprintln!("backend: {description}");
    let settings = DiagnoseSettings {
        seed: args.seed,
        replicates: args.replicates.max(2),
        ensemble_realisations: args.realisations.max(4),
        ..DiagnoseSettings::default()
    };
    let started = Instant::now();
    let spinner = ProgressBar::new_spinner();
    spinner.enable_steady_tick(std::time::Duration::from_millis(200));
    let diagnosis = diagnose::diagnose_set(&set, &settings, &backend, &mut |step| spinner.set_message(step.to_string()))?;
    spinner.finish_and_clear();
    let elapsed = started.elapsed().as_secs_f64();
    crate::report::write_diagnosis(&args.out, &diagnosis, &args.dir, elapsed)?;
    let report = diagnosis.report_json();
    println!(
        "verdict: {} (confidence {:.2}); gap {:.3} -> {:.3} (shrink {:.2}, held-out shrink {}) in {elapsed:.0} s; wrote {}",
        diagnosis.verdict,
        diagnosis.confidence,
        report["gap"]["baseline"].as_f64().unwrap_or(f64::NAN),
        report["gap"]["after"].as_f64().unwrap_or(f64::NAN),
        report["gap"]["shrink"].as_f64().unwrap_or(f64::NAN),
        report["gap"]["heldout_shrink"].as_f64().map_or("n/a".to_string(), |h| format!("{h:.2}")),
        args.out.display()
    );
    Ok(())
}

fn run_benchmark(args: BenchmarkArgs) -> Result<()> {
    use crate::effects::EFFECT_NAMES;
    use crate::synthetic::{benchmark_plan, random_truth, write_set, SetShape};
    for e in &args.effects {
        if !EFFECT_NAMES.contains(&e.as_str()) {
            anyhow::bail!("invalid --effects: `{e}` is not one of {}", EFFECT_NAMES.join(", "));
        }
    }
    if args.load_shares.is_empty() || args.load_shares.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
        anyhow::bail!("invalid --load-shares {:?}: each must be a number > 0 (a share of the no-stop threshold)", args.load_shares);
    }
    let (backend, description) = Backend::open(args.backend.into())?;
    eprintln!("backend: {description}");
    let shape = SetShape { runs_per_condition: args.runs_per_condition.max(1), duration_s: args.duration, ..SetShape::default() };
    let plan: Vec<_> = benchmark_plan(args.nulls, &args.forms, &args.levels)
        .into_iter()
        .filter(|(e, _, _)| args.effects.is_empty() || e.is_none_or(|e| args.effects.iter().any(|n| n == EFFECT_NAMES[e])))
        .collect();
    let settings = DiagnoseSettings { seed: args.seed ^ 0xD1A6, replicates: args.replicates.max(2), ..DiagnoseSettings::default() };
    let labels: Vec<&str> = EFFECT_NAMES.iter().copied().chain(["none"]).collect();
    let mut confusion = vec![vec![0u32; labels.len()]; labels.len()];
    let mut rows = Vec::new();
    let bar = progress_bar(plan.len() as u64, "diagnosing");
    let started = Instant::now();
    for (i, &(effect, form, level)) in plan.iter().enumerate() {
        let seed = args.seed.wrapping_mul(1_000_003).wrapping_add(i as u64);
        let (truth, conditions) = random_truth(seed, effect, form, level, &args.load_shares)?;
        let dir = args.out.join(format!("set-{i:03}"));
        write_set(&dir.join("data"), &truth, &conditions, shape, seed)?;
        let set = crate::measure::read_measurement_set(&dir.join("data"))?;
        let t0 = Instant::now();
        let d = diagnose::diagnose_set(&set, &settings, &backend, &mut |_| {})?;
        let seconds = t0.elapsed().as_secs_f64();
        crate::report::write_diagnosis(&dir.join("diagnosis"), &d, &dir.join("data"), seconds)?;
        let truth_name = effect.map_or("none", |e| EFFECT_NAMES[e]);
        // Does the effect move the peak statistics beyond their noise? Compare
        // the truth with and without it on the same noise.
        let moves = match effect {
            None => false,
            Some(_) => {
                let mut without = truth.clone();
                without.effects = Default::default();
                diagnose::peak_shift_in_noise_units(&truth, &without, &conditions, shape, &backend)? > 2.0
            }
        };
        let report = d.report_json();
        let heldout = report["gap"]["heldout_shrink"].as_f64();
        let row = labels.iter().position(|l| *l == truth_name).unwrap();
        let col = labels.iter().position(|l| *l == d.verdict).unwrap_or(labels.len() - 1);
        confusion[row][col] += 1;
        rows.push((truth_name.to_string(), form, level, d.verdict.clone(), heldout, moves, seconds));
        bar.inc(1);
        let line = format!(
            "set {i:3}: truth {truth_name:<24} form {form} level {level} -> {:<24} held-out shrink {} {}({seconds:.0} s)",
            d.verdict,
            heldout.map_or("n/a".into(), |h| format!("{h:+.2}")),
            if moves { "" } else { "[effect within peak noise] " }
        );
        // A hidden bar (output not a terminal) drops println: print directly.
        if bar.is_hidden() {
            eprintln!("{line}");
        } else {
            bar.println(line);
        }
    }
    bar.finish_and_clear();
    let effect_rows: Vec<_> = rows.iter().filter(|r| r.0 != "none").collect();
    let null_rows: Vec<_> = rows.iter().filter(|r| r.0 == "none").collect();
    let correct = effect_rows.iter().filter(|r| r.0 == r.3).count();
    let false_positives = null_rows.iter().filter(|r| r.3 != "none").count();
    let mut shrinks: Vec<f64> = effect_rows.iter().filter(|r| r.5).filter_map(|r| r.4).collect();
    shrinks.sort_by(f64::total_cmp);
    let median = if shrinks.is_empty() { f64::NAN } else if shrinks.len() % 2 == 1 { shrinks[shrinks.len() / 2] } else { 0.5 * (shrinks[shrinks.len() / 2 - 1] + shrinks[shrinks.len() / 2]) };
    let mut text = String::new();
    text.push_str(&format!("blind benchmark of the diagnosis: {} sets ({} with an effect, {} null), {} runs x {} s per condition, 2 frequencies x loads at {:?} of the no-stop threshold; {description}\n", rows.len(), effect_rows.len(), null_rows.len(), shape.runs_per_condition, shape.duration_s, args.load_shares));
    text.push_str("confusion matrix (rows: withheld effect, columns: verdict)\n");
    let short = |l: &str| l.split('_').map(|w| &w[..w.len().min(4)]).collect::<Vec<_>>().join("_");
    text.push_str(&format!("{:<26}", ""));
    for l in &labels {
        text.push_str(&format!("{:>11}", short(l)));
    }
    text.push('\n');
    for (r, l) in labels.iter().enumerate() {
        text.push_str(&format!("{l:<26}"));
        for c in 0..labels.len() {
            text.push_str(&format!("{:>11}", confusion[r][c]));
        }
        text.push('\n');
    }
    let pct = |a: usize, b: usize| if b == 0 { f64::NAN } else { 100.0 * a as f64 / b as f64 };
    text.push_str(&format!("top-1 accuracy: {correct}/{} = {:.1}% (target >= 90%)\n", effect_rows.len(), pct(correct, effect_rows.len())));
    text.push_str(&format!("false-positive rate on null sets: {false_positives}/{} = {:.1}% (target <= 10%)\n", null_rows.len(), pct(false_positives, null_rows.len())));
    text.push_str(&format!("median held-out shrink where the effect moves the peak statistics beyond their noise ({} sets): {:.2} (target >= 0.60)\n", shrinks.len(), median));
    text.push_str(&format!("total time {:.0} s\n", started.elapsed().as_secs_f64()));
    print!("{text}");
    crate::io::create_dir(&args.out)?;
    crate::io::write_atomically(&args.out.join("summary.txt"), |w| w.write_all(text.as_bytes()))?;
    Ok(())
}
