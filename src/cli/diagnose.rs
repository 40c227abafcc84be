//! `stickslip diagnose` and `stickslip benchmark-diagnosis`.

use std::path::PathBuf;
use std::time::Instant;

use super::{BackendArg, Progress, emit, emit_bytes, open_engine};
use crate::budget::Cost;
use crate::diagnose::benchmark::{BenchmarkSettings, Generator, Origins, run_benchmark as run_benchmark_sets};
use crate::diagnose::report::{RunInfo, write_diagnosis_with};
use crate::diagnose::synthetic::SetShape;
use crate::diagnose::{DiagnoseSettings, MAX_REPLICATES, MIN_REPLICATES, diagnose_set};
use crate::engine::{Effect, GpuOptions};
use crate::io::{OutputSet, owned};
use crate::measure::read_measurement_set;
use anyhow::Result;
use clap::Args;

#[derive(Args, Debug)]
pub(crate) struct DiagnoseArgs {
    /// The measurement set (a directory with manifest.json).
    pub(crate) dir: PathBuf,
    /// Output directory (report.json, report.html, baseline-model.toml, fitted-model.toml).
    #[arg(long)]
    pub(crate) out: PathBuf,
    /// Where to simulate: a hardware GPU if there is one (else the CPU reference), a GPU, or the CPU reference.
    #[arg(long, value_enum, default_value = "auto")]
    pub(crate) backend: BackendArg,
    /// Random seed of the simulated replicates and ensembles (the report is reproducible from it).
    #[arg(long, default_value_t = 20_251_122)]
    pub(crate) seed: u64,
    /// Simulated replicate records per condition.
    #[arg(long, default_value_t = 8)]
    pub(crate) replicates: u32,
    /// Realisations per condition in the ensembles that score summary data.
    #[arg(long, default_value_t = 64)]
    pub(crate) realisations: u32,
    /// Thin each run to this sample rate, Hz, by keeping every k-th sample (its rate divided by a whole
    /// number): records sampled far faster than the response needs are diagnosed in minutes, not hours.
    /// The baseline's noise is then held over 1/HZ.
    #[arg(long, value_name = "HZ", allow_hyphen_values = true)]
    pub(crate) sample_rate: Option<f64>,
}

#[derive(Args, Debug)]
pub(crate) struct BenchmarkArgs {
    /// Where the synthetic sets and their diagnoses go (a directory per set, and its diagnosis).
    #[arg(long, default_value = "out/benchmark-diagnosis")]
    pub(crate) out: PathBuf,
    /// Number of null sets (no withheld effect; the friction law drawn from the whole eq. 7 family).
    #[arg(long, default_value_t = 20)]
    pub(crate) nulls: u32,
    /// Number of sets with two withheld effects at once.
    #[arg(long, default_value_t = 6)]
    pub(crate) pairs: u32,
    /// Number of summary-only sets that carry the response phase (null and load-dependent friction
    /// alternately) [default: 2; 0 with --generator independent, which writes records only].
    #[arg(long)]
    pub(crate) phase_only: Option<u32>,
    /// Which functional forms of each withheld effect generate sets (comma list of 1 and 2; neither is a
    /// form the diagnosis fits).
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    pub(crate) forms: Vec<u32>,
    /// Which strength levels of each withheld effect generate sets (comma list: 0 moderate, 1 strong).
    #[arg(long, value_delimiter = ',', default_value = "0,1")]
    pub(crate) levels: Vec<u32>,
    /// Withhold only these effects (comma list of effect names); all seven by default.
    #[arg(long, value_delimiter = ',')]
    pub(crate) effects: Vec<String>,
    /// Time-series records (run files) per condition in each synthetic set.
    #[arg(long, default_value_t = 1)]
    pub(crate) runs_per_condition: u32,
    /// Length of each synthetic record, s (5 to 600).
    #[arg(long, default_value_t = 20.0)]
    pub(crate) duration: f64,
    /// Normal-force levels of stickslip's own generator, as shares of Den
    /// Hartog's no-stop threshold (comma list; below 1 the noiseless block
    /// never stops) [default: 0.4,0.65,0.9].
    #[arg(long, value_delimiter = ',')]
    pub(crate) load_shares: Option<Vec<f64>>,
    /// Excitation frequencies as ratios of each set's natural frequency
    /// (comma list, 0.2 to 3, at most 8; e.g. 0.6,0.7,0.8,0.9,1.1,1.2 with
    /// three load shares and --duration 50 makes the 18-run sets of 3 loads ×
    /// 6 frequencies).
    #[arg(long, value_delimiter = ',', default_values_t = crate::diagnose::synthetic::FREQUENCY_RATIOS)]
    pub(crate) frequency_ratios: Vec<f64>,
    /// Random seed of the synthetic sets (each diagnosis derives its own from it).
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// Where to simulate: a hardware GPU if there is one (else the CPU reference), a GPU, or the CPU reference.
    #[arg(long, value_enum, default_value = "auto")]
    pub(crate) backend: BackendArg,
    /// Simulated replicate records per condition in each diagnosis.
    #[arg(long, default_value_t = 8)]
    pub(crate) replicates: u32,
    /// Run only these sets of the plan (comma list of the indices the full run prints, e.g. 4,8);
    /// each keeps the data and seed it has in the full run, so one verdict can be re-checked alone.
    #[arg(long, value_delimiter = ',')]
    pub(crate) sets: Vec<usize>,
    /// Which generator makes the sets: stickslip's own engine with its withheld effect forms, or the
    /// independent one (its own integrator at 200 kHz with explicit stick/slip switching, and effect forms
    /// from the literature that no candidate has; loads from --loads).
    #[arg(long, value_enum, default_value = "engine")]
    pub(crate) generator: GeneratorArg,
    /// Normal forces of the independent generator's sets, N (comma list) [default: 4,8,16].
    #[arg(long, value_delimiter = ',')]
    pub(crate) loads: Option<Vec<f64>>,
    /// The time frame of the independent generator's records: `t` in the model's frame, a free time origin
    /// (declared in the manifest), a free one with a base_x column, or the three in turn.
    #[arg(long, value_enum, default_value = "mixed")]
    pub(crate) time_origin: OriginArg,
    /// The independent generator's records carry `t` and `x` (and `base_x` where the time origin gives one)
    /// alone, as a rig without velocity or force sensors: the diagnosis derives the rest from `x`.
    #[arg(long)]
    pub(crate) displacement_only: bool,
}

/// `--generator`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum GeneratorArg {
    Engine,
    Independent,
}

/// `--time-origin`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum OriginArg {
    Model,
    Free,
    BaseX,
    Mixed,
}

/// Characters of each report note shown on the terminal.
const NOTE_CHARS: usize = 160;

pub(crate) fn run_diagnose(args: DiagnoseArgs) -> Result<()> {
    // The flags, the set and --out are checked before any computation; bad
    // input writes nothing.
    let settings = DiagnoseSettings {
        seed: args.seed,
        replicates: args.replicates,
        ensemble_realisations: args.realisations,
        sample_rate_hz: args.sample_rate,
        ..DiagnoseSettings::default()
    };
    settings.check(true)?;
    let set = read_measurement_set(&args.dir)?;
    let out = OutputSet::prepare(&args.out, "--out", owned::DIAGNOSIS, &[args.dir.as_path()])?;
    let engine = open_engine(args.backend, GpuOptions::default())?;
    super::check_budget(
        Cost::of_diagnosis(&set, &settings),
        engine.kind(),
        "diagnose",
        "lower --replicates or --realisations, thin the records with --sample-rate, or give fewer or shorter \
         records",
    )?;
    let started = Instant::now();
    let progress = Progress::steps("diagnose");
    let diagnosis = diagnose_set(&set, &settings, &engine, &mut |step| progress.step(step))?;
    // What the report says about the records and how they were read (an
    // offset, a dead channel, phases set aside), so that a user who reads
    // only the terminal sees it is there: the start of each, in full in
    // the report.
    for note in &diagnosis.notes {
        progress.println(&format!("note: {}", crate::text::excerpt(note, NOTE_CHARS)));
    }
    progress.finish();
    let elapsed = started.elapsed().as_secs_f64();
    let run = RunInfo { seed: Some(args.seed), backend: Some(engine.description().to_string()) };
    let report = write_diagnosis_with(out.dir(), &diagnosis, &args.dir, elapsed, &run)?;
    out.commit()?;
    emit(&format!(
        "verdict: {} (confidence {:.2}){}; gap {:.3} -> {:.3} (shrink {:.2}, held-out shrink {}) in {elapsed:.0} s; wrote {}",
        report.verdict.effect,
        report.verdict.confidence,
        if report.verdict.effects.len() > 1 {
            format!(
                ", with {}",
                report.verdict.effects[1..]
                    .iter()
                    .map(|e| format!("{} ({:.2})", e.effect, e.confidence))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        } else {
            let blind: Vec<String> = report
                .verdict
                .power
                .iter()
                .filter(|p| !p.could_show())
                .map(|p| format!("{} ({:.2})", p.effect, p.power))
                .collect();
            if blind.is_empty() {
                String::new()
            } else {
                format!(", but these records could not show {}", blind.join(", "))
            }
        },
        report.gap.baseline,
        report.gap.after,
        report.gap.shrink,
        report.gap.heldout_shrink.map_or("n/a".to_string(), |h| format!("{h:.2}")),
        args.out.display()
    ))?;
    Ok(())
}

pub(crate) fn run_benchmark(args: BenchmarkArgs) -> Result<()> {
    let backend = args.backend;
    let settings = benchmark_settings(args)?;
    let planned: Vec<usize> = settings.plan().into_iter().map(|(i, _)| i).collect();
    if let Some(i) = settings.sets.iter().find(|i| !planned.contains(i)) {
        let all = BenchmarkSettings { sets: Vec::new(), ..settings.clone() }.plan().len();
        anyhow::bail!("invalid --sets: {i}; this plan has sets 0 to {}", all.saturating_sub(1));
    }
    let out = OutputSet::prepare(&settings.out, "--out", owned::BENCHMARK, &[])?;
    let settings = BenchmarkSettings { out: out.dir().to_path_buf(), ..settings };
    let engine = open_engine(backend, GpuOptions::default())?;
    super::check_budget(
        Cost::of_benchmark(&settings)?,
        engine.kind(),
        "benchmark-diagnosis (its largest set's diagnosis)",
        "ask for fewer sets (--nulls, --pairs, --phase-only, --effects, --forms, --levels or --sets), fewer \
         --replicates, or fewer or shorter records (--runs-per-condition, --duration, --frequency-ratios, \
         --load-shares)",
    )?;
    let sets = planned.len();
    let progress = Progress::bar("benchmark-diagnosis");
    let mut done = 0;
    progress.position(0, sets as u64);
    let (_, text) = run_benchmark_sets(&settings, &engine, &mut |line| {
        progress.println(line);
        done += 1;
        progress.position(done, sets as u64);
    })?;
    progress.finish();
    out.commit()?;
    emit_bytes(text.as_bytes())
}

/// The benchmark `args` ask for, every flag checked.
fn benchmark_settings(args: BenchmarkArgs) -> Result<BenchmarkSettings> {
    let effects = args
        .effects
        .iter()
        .map(|e| e.parse::<Effect>())
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| anyhow::anyhow!("invalid --effects: {e}"))?;
    // Each generator reads its own flag for the loads; the other's is refused, not ignored.
    let independent = args.generator == GeneratorArg::Independent;
    if independent && args.load_shares.is_some() {
        anyhow::bail!("invalid --load-shares with --generator independent: its loads are set by --loads (in N)");
    }
    if !independent && args.loads.is_some() {
        anyhow::bail!(
            "invalid --loads with --generator engine: its loads are set by --load-shares (shares of the no-stop \
             threshold)"
        );
    }
    if !independent && args.displacement_only {
        anyhow::bail!(
            "invalid --displacement-only with --generator engine: only the independent generator writes records \
             of x alone"
        );
    }
    let load_shares = args.load_shares.unwrap_or_else(|| crate::diagnose::synthetic::LOAD_SHARES.to_vec());
    let loads = args.loads.unwrap_or_else(|| crate::diagnose::benchmark::independent::DEFAULT_LOADS_N.to_vec());
    if load_shares.is_empty() || load_shares.iter().any(|s| !(s.is_finite() && *s > 0.0 && *s <= 10.0)) {
        anyhow::bail!(
            "invalid --load-shares {load_shares:?}: each must be a number > 0 and at most 10 (a share of the no-stop threshold)"
        );
    }
    for (flag, values) in
        [("--load-shares", &load_shares), ("--loads", &loads), ("--frequency-ratios", &args.frequency_ratios)]
    {
        if let Some(v) = values.iter().enumerate().find_map(|(i, v)| values[..i].contains(v).then_some(v)) {
            anyhow::bail!("invalid {flag}: {v} is given twice; each level once");
        }
    }
    if let Some(f) = args.forms.iter().find(|f| !(1..=2).contains(*f)) {
        anyhow::bail!("invalid --forms: {f}; the withheld forms are 1 and 2");
    }
    if let Some(l) = args.levels.iter().find(|l| **l > 1) {
        anyhow::bail!("invalid --levels: {l}; the strength levels are 0 (moderate) and 1 (strong)");
    }
    if args.runs_per_condition == 0 || args.runs_per_condition > 100 {
        anyhow::bail!("invalid --runs-per-condition: {}; it must be 1 to 100", args.runs_per_condition);
    }
    if !(args.duration.is_finite() && (5.0..=600.0).contains(&args.duration)) {
        anyhow::bail!(
            "invalid --duration: {} s; a record must be 5 s to 600 s (at least tens of periods at the sets' 5-10 Hz)",
            args.duration
        );
    }
    if !(MIN_REPLICATES..=MAX_REPLICATES).contains(&args.replicates) {
        anyhow::bail!("invalid --replicates: {}; it must be {MIN_REPLICATES} to {MAX_REPLICATES}", args.replicates);
    }
    if args.frequency_ratios.is_empty()
        || args.frequency_ratios.len() > 8
        || args.frequency_ratios.iter().any(|r| !(r.is_finite() && (0.2..=3.0).contains(r)))
    {
        anyhow::bail!(
            "invalid --frequency-ratios {:?}: 1 to 8 ratios of the natural frequency, each 0.2 to 3",
            args.frequency_ratios
        );
    }
    if loads.is_empty() || loads.len() > 8 || loads.iter().any(|n| !(n.is_finite() && *n > 0.0)) {
        anyhow::bail!("invalid --loads {loads:?}: 1 to 8 normal forces, each > 0 N");
    }
    let phase_only = match (args.generator, args.phase_only) {
        (GeneratorArg::Independent, Some(n)) if n > 0 => {
            anyhow::bail!("invalid --phase-only {n}: the independent generator writes records only (use 0)")
        }
        (GeneratorArg::Independent, _) => 0,
        (_, n) => n.unwrap_or(2),
    };
    if load_shares.len() > 8 {
        anyhow::bail!("invalid --load-shares: {} levels; at most 8", load_shares.len());
    }
    Ok(BenchmarkSettings {
        out: args.out,
        nulls: args.nulls,
        pairs: args.pairs,
        phase_only,
        forms: args.forms,
        levels: args.levels,
        effects,
        shape: SetShape {
            runs_per_condition: args.runs_per_condition,
            duration_s: args.duration,
            ..SetShape::default()
        },
        load_shares,
        frequency_ratios: args.frequency_ratios,
        seed: args.seed,
        replicates: args.replicates,
        sets: args.sets,
        generator: match args.generator {
            GeneratorArg::Engine => Generator::Engine,
            GeneratorArg::Independent => Generator::Independent {
                loads_n: loads,
                origins: match args.time_origin {
                    OriginArg::Model => Origins::Model,
                    OriginArg::Free => Origins::Free,
                    OriginArg::BaseX => Origins::BaseX,
                    OriginArg::Mixed => Origins::Mixed,
                },
                displacement_only: args.displacement_only,
            },
        },
    })
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::super::{Cli, Command};
    use super::*;
    use crate::budget::Force;
    use crate::engine::BackendKind;

    fn settings(args: &[&str]) -> BenchmarkSettings {
        let cli = Cli::try_parse_from([&["stickslip", "benchmark-diagnosis"], args].concat()).unwrap();
        let Command::BenchmarkDiagnosis(args) = cli.command else { unreachable!() };
        benchmark_settings(args).unwrap()
    }

    /// The independent generator runs on its defaults (it writes no
    /// phase-only sets unless asked, and refuses them by the flag's name),
    /// and a load share out of range is refused by its flag.
    #[test]
    fn the_independent_generator_runs_on_its_defaults() {
        assert_eq!(settings(&["--generator", "independent"]).phase_only, 0);
        assert_eq!(settings(&[]).phase_only, 2);
        let refused = |args: &[&str]| {
            let cli = Cli::try_parse_from([&["stickslip", "benchmark-diagnosis"], args].concat()).unwrap();
            let Command::BenchmarkDiagnosis(args) = cli.command else { unreachable!() };
            benchmark_settings(args).unwrap_err().to_string()
        };
        let phase = refused(&["--generator", "independent", "--phase-only", "1"]);
        assert!(phase.contains("--phase-only 1"), "{phase}");
        let shares = refused(&["--load-shares", "0.5,1e6"]);
        assert!(shares.contains("--load-shares") && shares.contains("at most 10"), "{shares}");
    }

    /// The benchmark as the command line runs it by default passes the
    /// budget on a two-core machine's CPU reference, and so does one in the
    /// independent checks' shape (18 records of 50 s per set); records
    /// thirty times as long and four times as many do not. Each set is budgeted, not their
    /// sum: twice the null sets cost no more per set.
    #[test]
    fn the_default_benchmark_is_within_the_budget() {
        let check = |cost: Cost| cost.check(BackendKind::Cpu, 2, Force::flag(false), "benchmark-diagnosis", "");
        let default = Cost::of_benchmark(&settings(&[])).unwrap();
        check(default).unwrap();
        let independent = settings(&[
            "--generator",
            "independent",
            "--phase-only",
            "0",
            "--frequency-ratios",
            "0.6,0.7,0.8,0.9,1.1,1.2",
            "--duration",
            "50",
        ]);
        check(Cost::of_benchmark(&independent).unwrap()).unwrap();
        assert_eq!(Cost::of_benchmark(&settings(&["--nulls", "40"])).unwrap(), default);
        let long = Cost::of_benchmark(&settings(&["--duration", "600", "--runs-per-condition", "4"])).unwrap();
        // The default's largest set is a phase-only one (its ensembles);
        // records 30 times as long and 4 times as many cost some 20 times it.
        assert!(long.steps > 15.0 * default.steps, "{long:?} vs {default:?}");
        assert!(check(long).unwrap_err().to_string().contains("--force"));
    }
}
