//! The blind benchmark of the diagnosis (`stickslip benchmark-diagnosis`):
//! synthetic sets ([`crate::diagnose::synthetic`]) with a withheld effect,
//! each diagnosed without being told what it hides, scored as a confusion
//! matrix, top-1 accuracy, false-positive rate and median held-out shrink.

use std::path::PathBuf;
use std::time::Instant;

use crate::diagnose::measure::read_measurement_set;
use crate::diagnose::report::write_diagnosis;
use crate::diagnose::simulate::ensemble_path_stats;
use crate::diagnose::synthetic::{SetShape, benchmark_plan, random_truth, write_set};
use crate::diagnose::{DiagnoseSettings, diagnose_set, mean, sd};
use crate::engine::{Condition, Effect, Engine, Model};
use crate::error::Result;
use crate::io::{create_dir, write_atomically};

/// What the benchmark runs.
#[derive(Clone, Debug)]
pub struct BenchmarkSettings {
    /// Where the synthetic sets and their diagnoses go.
    pub out: PathBuf,
    /// Null sets (no effect).
    pub nulls: u32,
    /// Effect forms used (1 and 2 are the non-candidate forms).
    pub forms: Vec<u32>,
    /// Strength levels (0 moderate, 1 strong).
    pub levels: Vec<u32>,
    /// Only these effects; all of them when empty.
    pub effects: Vec<Effect>,
    pub shape: SetShape,
    /// Normal-force levels as shares of Den Hartog's no-stop threshold.
    pub load_shares: Vec<f64>,
    /// Seed of the sets (and, mixed, of the diagnoses).
    pub seed: u64,
    /// Simulated replicate records per condition in each diagnosis.
    pub replicates: u32,
}

/// One diagnosed set.
#[derive(Clone, Debug)]
pub struct BenchmarkRow {
    /// What the set hides (`None`: a null set).
    pub truth: Option<Effect>,
    pub form: u32,
    pub level: u32,
    /// What the diagnosis named.
    pub verdict: Option<Effect>,
    pub heldout_shrink: Option<f64>,
    /// Whether the effect moves the peak statistics beyond their noise.
    pub moves_peaks: bool,
    /// Time of the diagnosis, s.
    pub seconds: f64,
}

/// How far an effect moves the peak statistics, in units of their noise in
/// one measured record: the largest over conditions of |Δ mean peak| / (sd of
/// a record's mean peak) and |Δ peak variance| / (sd of a record's variance),
/// from ensembles of the truth with and without the effect on the same noise.
pub fn peak_shift_in_noise_units(
    with: &Model,
    without: &Model,
    conditions: &[Condition],
    shape: SetShape,
    engine: &Engine,
) -> Result<f64> {
    let cycles = conditions.iter().map(|c| (shape.duration_s * c.excitation_frequency_hz) as u32).max().unwrap_or(100);
    let a = ensemble_path_stats(engine, with, conditions, cycles, 32, 99, 60)?;
    let b = ensemble_path_stats(engine, without, conditions, cycles, 32, 99, 60)?;
    let mut worst: f64 = 0.0;
    for (pa, pb) in a.iter().zip(&b) {
        let (ma, mb): (Vec<f64>, Vec<f64>) =
            (pa.iter().map(|p| p.peak_mean_m).collect(), pb.iter().map(|p| p.peak_mean_m).collect());
        let (va, vb): (Vec<f64>, Vec<f64>) =
            (pa.iter().map(|p| p.peak_var_m2).collect(), pb.iter().map(|p| p.peak_var_m2).collect());
        let runs = f64::from(shape.runs_per_condition.max(1)).sqrt();
        worst = worst.max((mean(&ma) - mean(&mb)).abs() / (sd(&mb).max(1e-15) / runs));
        worst = worst.max((mean(&va) - mean(&vb)).abs() / (sd(&vb).max(1e-30) / runs));
    }
    Ok(worst)
}

/// Writes, diagnoses and scores every set of the plan; `line` receives one
/// line per set as it finishes. Returns the rows and the summary text
/// (also written to `OUT/summary.txt`).
pub fn run_benchmark(
    settings: &BenchmarkSettings,
    engine: &Engine,
    line: &mut dyn FnMut(&str),
) -> Result<(Vec<BenchmarkRow>, String)> {
    let plan: Vec<_> = benchmark_plan(settings.nulls, &settings.forms, &settings.levels)
        .into_iter()
        .filter(|(e, _, _)| settings.effects.is_empty() || e.is_none_or(|e| settings.effects.contains(&e)))
        .collect();
    let diagnose_settings = DiagnoseSettings {
        seed: settings.seed ^ 0xD1A6,
        replicates: settings.replicates.max(2),
        ..DiagnoseSettings::default()
    };
    let shape = settings.shape;
    let mut rows = Vec::new();
    let started = Instant::now();
    for (i, &(effect, form, level)) in plan.iter().enumerate() {
        let seed = settings.seed.wrapping_mul(1_000_003).wrapping_add(i as u64);
        let (truth, conditions) = random_truth(seed, effect, form, level, &settings.load_shares)?;
        let dir = settings.out.join(format!("set-{i:03}"));
        write_set(&dir.join("data"), &truth, &conditions, shape, seed)?;
        let set = read_measurement_set(&dir.join("data"))?;
        let t0 = Instant::now();
        let d = diagnose_set(&set, &diagnose_settings, engine, &mut |_| {})?;
        let seconds = t0.elapsed().as_secs_f64();
        let report = write_diagnosis(&dir.join("diagnosis"), &d, &dir.join("data"), seconds)?;
        // Does the effect move the peak statistics beyond their noise? Compare
        // the truth with and without it on the same noise.
        let moves_peaks = match effect {
            None => false,
            Some(_) => {
                let mut without = truth.clone();
                without.effects = Default::default();
                peak_shift_in_noise_units(&truth, &without, &conditions, shape, engine)? > 2.0
            }
        };
        let heldout = report.gap.heldout_shrink;
        let truth_name = effect.map_or("none", Effect::name);
        line(&format!(
            "set {i:3}: truth {truth_name:<24} form {form} level {level} -> {:<24} held-out shrink {} {}({seconds:.0} s)",
            d.verdict_name(),
            heldout.map_or("n/a".into(), |h| format!("{h:+.2}")),
            if moves_peaks || effect.is_none() { "" } else { "[effect within peak noise] " }
        ));
        rows.push(BenchmarkRow {
            truth: effect,
            form,
            level,
            verdict: d.verdict,
            heldout_shrink: heldout,
            moves_peaks,
            seconds,
        });
    }
    let text = summary(settings, engine, &rows, started.elapsed().as_secs_f64());
    create_dir(&settings.out)?;
    write_atomically(&settings.out.join("summary.txt"), |w| w.write_all(text.as_bytes()))?;
    Ok((rows, text))
}

/// The confusion matrix and the three headline numbers.
fn summary(settings: &BenchmarkSettings, engine: &Engine, rows: &[BenchmarkRow], total_s: f64) -> String {
    let labels: Vec<Option<Effect>> = Effect::ALL.iter().copied().map(Some).chain([None]).collect();
    let index = |e: Option<Effect>| labels.iter().position(|l| *l == e).expect("every effect and none is a label");
    let mut confusion = vec![vec![0u32; labels.len()]; labels.len()];
    for r in rows {
        confusion[index(r.truth)][index(r.verdict)] += 1;
    }
    let effect_rows: Vec<&BenchmarkRow> = rows.iter().filter(|r| r.truth.is_some()).collect();
    let null_rows: Vec<&BenchmarkRow> = rows.iter().filter(|r| r.truth.is_none()).collect();
    let correct = effect_rows.iter().filter(|r| r.truth == r.verdict).count();
    let false_positives = null_rows.iter().filter(|r| r.verdict.is_some()).count();
    let mut shrinks: Vec<f64> = effect_rows.iter().filter(|r| r.moves_peaks).filter_map(|r| r.heldout_shrink).collect();
    shrinks.sort_by(f64::total_cmp);
    let median = if shrinks.is_empty() {
        f64::NAN
    } else if shrinks.len() % 2 == 1 {
        shrinks[shrinks.len() / 2]
    } else {
        0.5 * (shrinks[shrinks.len() / 2 - 1] + shrinks[shrinks.len() / 2])
    };
    let name = |e: Option<Effect>| e.map_or("none", Effect::name);
    let shape = settings.shape;
    let mut text = String::new();
    text.push_str(&format!(
        "blind benchmark of the diagnosis: {} sets ({} with an effect, {} null), {} runs x {} s per condition, 2 frequencies x loads at {:?} of the no-stop threshold; {}\n",
        rows.len(),
        effect_rows.len(),
        null_rows.len(),
        shape.runs_per_condition,
        shape.duration_s,
        settings.load_shares,
        engine.description()
    ));
    text.push_str("confusion matrix (rows: withheld effect, columns: verdict)\n");
    let short = |l: &str| l.split('_').map(|w| &w[..w.len().min(4)]).collect::<Vec<_>>().join("_");
    text.push_str(&format!("{:<26}", ""));
    for &l in &labels {
        text.push_str(&format!("{:>11}", short(name(l))));
    }
    text.push('\n');
    for (r, &l) in labels.iter().enumerate() {
        text.push_str(&format!("{:<26}", name(l)));
        for count in &confusion[r] {
            text.push_str(&format!("{count:>11}"));
        }
        text.push('\n');
    }
    let pct = |a: usize, b: usize| if b == 0 { f64::NAN } else { 100.0 * a as f64 / b as f64 };
    text.push_str(&format!(
        "top-1 accuracy: {correct}/{} = {:.1}% (target >= 90%)\n",
        effect_rows.len(),
        pct(correct, effect_rows.len())
    ));
    text.push_str(&format!(
        "false-positive rate on null sets: {false_positives}/{} = {:.1}% (target <= 10%)\n",
        null_rows.len(),
        pct(false_positives, null_rows.len())
    ));
    text.push_str(&format!(
        "median held-out shrink where the effect moves the peak statistics beyond their noise ({} sets): {:.2} (target >= 0.60)\n",
        shrinks.len(),
        median
    ));
    text.push_str(&format!("total time {total_s:.0} s\n"));
    text
}
