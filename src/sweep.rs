//! Frequency × normal-force sweeps: grids, backends, per-point statistics
//! and `sweep.csv`.

use std::path::Path;

use crate::cpu::{self, InitialState, RunPlan};
use crate::reduce::{PeakRange, PointAccumulator};
use crate::error::{Error, Result};
use crate::gpu::{self, GpuContext};
use crate::io::write_atomically;
use crate::model::{Condition, Model, Oscillator};

/// Parses a grid flag: a comma list (`6,7,8`) or `START:STOP:COUNT`.
pub fn parse_list(flag: &str, text: &str) -> Result<Vec<f64>> {
    let bad = |message: String| Error::setting(flag, format!("`{text}`: {message}"));
    let number = |s: &str| -> Result<f64> {
        let v: f64 = s.trim().parse().map_err(|_| bad(format!("`{}` is not a number", s.trim())))?;
        if v.is_finite() { Ok(v) } else { Err(bad(format!("`{}` is not finite", s.trim()))) }
    };
    let values = if text.contains(':') {
        let parts: Vec<&str> = text.split(':').collect();
        if parts.len() != 3 {
            return Err(bad("expected START:STOP:COUNT".into()));
        }
        let (start, stop) = (number(parts[0])?, number(parts[1])?);
        let count: usize = parts[2].trim().parse().map_err(|_| bad(format!("COUNT `{}` is not a whole number", parts[2])))?;
        match count {
            0 => return Err(bad("COUNT must be at least 1".into())),
            1 if start != stop => return Err(bad("COUNT 1 needs START = STOP".into())),
            1 => vec![start],
            _ => (0..count).map(|i| start + (stop - start) * i as f64 / (count - 1) as f64).collect(),
        }
    } else {
        text.split(',').map(number).collect::<Result<Vec<f64>>>()?
    };
    if values.is_empty() {
        return Err(bad("no values".into()));
    }
    Ok(values)
}

/// A frequency × normal-force grid; points run frequency-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Excitation frequencies, Hz.
    pub frequencies_hz: Vec<f64>,
    /// Nominal normal forces, N.
    pub normal_forces_n: Vec<f64>,
}

impl Grid {
    /// All grid points, frequency-major.
    pub fn conditions(&self) -> Vec<Condition> {
        self.frequencies_hz
            .iter()
            .flat_map(|&f| self.normal_forces_n.iter().map(move |&n| Condition { excitation_frequency_hz: f, normal_force_n: n }))
            .collect()
    }
}

/// How a sweep runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SweepSettings {
    pub realisations: u32,
    pub plan: RunPlan,
    pub seed: u64,
    /// Integration steps per GPU dispatch.
    pub steps_per_dispatch: u64,
}

impl SweepSettings {
    /// Checks the settings that do not depend on the grid.
    pub fn validate(&self) -> Result<()> {
        if self.realisations == 0 {
            return Err(Error::setting("--realisations", "must be at least 1"));
        }
        if self.plan.measured_cycles == 0 {
            return Err(Error::setting("--cycles", "must be at least 1 measured cycle"));
        }
        if self.steps_per_dispatch == 0 {
            return Err(Error::setting("--steps-per-dispatch", "must be at least 1"));
        }
        Ok(())
    }
}

/// Where a sweep runs.
pub enum Backend {
    Gpu(Box<GpuContext>),
    Cpu,
}

/// The `--backend` choice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BackendChoice {
    /// A hardware GPU, else a software Vulkan adapter (lavapipe), else the CPU.
    Auto,
    /// A GPU adapter (hardware or software); an error when there is none.
    Gpu,
    /// The f64 CPU reference integrator.
    Cpu,
}

impl Backend {
    /// Opens the chosen backend. The string says which was taken and why.
    pub fn open(choice: BackendChoice) -> Result<(Backend, String)> {
        match choice {
            BackendChoice::Cpu => Ok((Backend::Cpu, cpu_description("chosen with --backend cpu"))),
            BackendChoice::Gpu => {
                let ctx = GpuContext::new(true)?;
                let text = format!("GPU: {}", ctx.describe());
                Ok((Backend::Gpu(Box::new(ctx)), text))
            }
            BackendChoice::Auto => match GpuContext::new(true) {
                Ok(ctx) => {
                    let text = match ctx.adapter_class() {
                        gpu::AdapterClass::Hardware => format!("GPU: {}", ctx.describe()),
                        gpu::AdapterClass::Software => {
                            format!("GPU: no hardware GPU found; using the software Vulkan adapter {}", ctx.describe())
                        }
                    };
                    Ok((Backend::Gpu(Box::new(ctx)), text))
                }
                Err(e) => Ok((Backend::Cpu, cpu_description(&format!("no GPU adapter ({e})")))),
            },
        }
    }

    /// Short name for files: `gpu` or `cpu`.
    pub fn name(&self) -> &'static str {
        match self {
            Backend::Gpu(_) => "gpu",
            Backend::Cpu => "cpu",
        }
    }
}

fn cpu_description(reason: &str) -> String {
    format!("CPU: f64 reference integrator on {} threads ({reason})", rayon::current_num_threads())
}

/// Statistics of the peak amplitudes at one grid point (one `sweep.csv` row).
#[derive(Clone, Debug, PartialEq)]
pub struct PointStats {
    pub excitation_frequency_hz: f64,
    pub normal_force_n: f64,
    pub realisations: u32,
    /// Number of peaks behind the statistics.
    pub peaks: u64,
    /// m
    pub peak_mean_m: f64,
    /// m², unbiased
    pub peak_var_m2: f64,
    /// m
    pub peak_p05_m: f64,
    pub peak_p50_m: f64,
    pub peak_p95_m: f64,
    /// Share of measured time spent stuck.
    pub stick_fraction: f64,
}

/// The default initial state at a grid point: the frictionless steady state.
pub fn initial_state(model: &Model, condition: Condition) -> InitialState {
    let (x_m, v_m_per_s) = model.linear_steady_state_at_zero(condition.excitation_frequency_hz);
    InitialState { x_m, v_m_per_s }
}

/// Runs every grid point and reduces it. `progress(done, total)` reports work.
pub fn run_sweep(
    model: &Model,
    conditions: &[Condition],
    settings: &SweepSettings,
    backend: &Backend,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<SweepResult> {
    settings.validate()?;
    let oscillators = conditions.iter().map(|&c| Oscillator::new(model, c)).collect::<Result<Vec<_>>>()?;
    let accumulators: Vec<PointAccumulator> = match backend {
        Backend::Gpu(ctx) => {
            let specs: Vec<gpu::PointSpec> = oscillators
                .iter()
                .zip(conditions)
                .map(|(o, &c)| gpu::PointSpec {
                    oscillator: o.clone(),
                    initial: initial_state(model, c),
                    range: PeakRange::for_point(model, c),
                })
                .collect();
            let request = gpu::EnsembleRequest {
                points: &specs,
                realisations_per_point: settings.realisations,
                realisation_offset: 0,
                seed: settings.seed,
                plan: settings.plan,
                steps_per_dispatch: settings.steps_per_dispatch,
                record_peaks: false,
            };
            gpu::run_ensemble(&ctx.device, &ctx.queue, &ctx.kernels, &request, progress)?.points
        }
        Backend::Cpu => {
            let total = conditions.len() as u64
                * u64::from(settings.realisations)
                * u64::from(settings.plan.warmup_cycles + settings.plan.measured_cycles);
            let mut out = Vec::with_capacity(conditions.len());
            for (i, (o, &c)) in oscillators.iter().zip(conditions).enumerate() {
                let paths = cpu::simulate_ensemble(o, settings.seed, 0..settings.realisations, settings.plan, initial_state(model, c));
                let mut acc = PointAccumulator::new(PeakRange::for_point(model, c));
                for p in &paths {
                    acc.add_path(&p.peaks_m, p.stick_time_s, o.period_s);
                }
                out.push(acc);
                progress(total * (i as u64 + 1) / conditions.len() as u64, total);
            }
            out
        }
    };
    Ok(SweepResult { conditions: conditions.to_vec(), accumulators })
}

/// A finished sweep: per point, its condition and exact sums.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepResult {
    pub conditions: Vec<Condition>,
    pub accumulators: Vec<PointAccumulator>,
}

impl SweepResult {
    /// The `sweep.csv` rows.
    pub fn rows(&self) -> Vec<PointStats> {
        self.conditions.iter().zip(&self.accumulators).map(|(&c, a)| a.stats(c)).collect()
    }
}

/// The columns of `sweep.csv` (`interfaces.md`).
pub const SWEEP_COLUMNS: [&str; 10] = [
    "excitation_frequency_hz",
    "normal_force_n",
    "realisations",
    "peaks",
    "peak_mean_m",
    "peak_var_m2",
    "peak_p05_m",
    "peak_p50_m",
    "peak_p95_m",
    "stick_fraction",
];

/// Writes `sweep.csv` atomically.
pub fn write_sweep_csv(path: &Path, rows: &[PointStats]) -> Result<()> {
    write_atomically(path, |w| {
        writeln!(w, "{}", SWEEP_COLUMNS.join(","))?;
        for r in rows {
            writeln!(
                w,
                "{},{},{},{},{:e},{:e},{:e},{:e},{:e},{}",
                r.excitation_frequency_hz,
                r.normal_force_n,
                r.realisations,
                r.peaks,
                r.peak_mean_m,
                r.peak_var_m2,
                r.peak_p05_m,
                r.peak_p50_m,
                r.peak_p95_m,
                r.stick_fraction
            )?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_and_ranges_parse() {
        assert_eq!(parse_list("--frequencies", "6,7,8").unwrap(), vec![6.0, 7.0, 8.0]);
        assert_eq!(parse_list("--frequencies", "5:15:3").unwrap(), vec![5.0, 10.0, 15.0]);
        assert!(parse_list("--frequencies", "5:15").unwrap_err().to_string().contains("--frequencies"));
        assert!(parse_list("--normal-forces", "4,x").unwrap_err().to_string().contains("`x`"));
    }

}

/// One part of a grid split across machines: shard `index` of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Shard {
    /// The whole grid.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// Parses `K/N` (zero-based `K < N`).
    pub fn parse(text: &str) -> Result<Shard> {
        let bad = |m: &str| Error::setting("--shard", format!("`{text}`: {m}"));
        let (k, n) = text.split_once('/').ok_or_else(|| bad("expected K/N, e.g. 0/4"))?;
        let index: u32 = k.trim().parse().map_err(|_| bad("K is not a whole number"))?;
        let count: u32 = n.trim().parse().map_err(|_| bad("N is not a whole number"))?;
        if count == 0 || index >= count {
            return Err(bad("need 0 <= K < N"));
        }
        Ok(Shard { index, count })
    }

    /// The contiguous range of grid-point indices this shard runs.
    pub fn points(&self, total: usize) -> std::ops::Range<usize> {
        let part = |k: u32| (total as u64 * u64::from(k) / u64::from(self.count)) as usize;
        part(self.index)..part(self.index + 1)
    }
}

/// What identifies a run: everything that determines its numbers. Shards
/// merge only when these are equal.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunIdentity {
    pub model_toml: String,
    pub frequencies_hz: Vec<f64>,
    pub normal_forces_n: Vec<f64>,
    pub realisations: u32,
    pub warmup_cycles: u32,
    pub measured_cycles: u32,
    pub seed: u64,
    /// `gpu` or `cpu`: f32 and f64 paths differ in the last digits.
    pub backend: String,
}

/// The file `accumulators.json`: a run's (or shard's) exact per-point sums.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AccumulatorFile {
    pub format: String,
    pub identity: RunIdentity,
    pub shard: Shard,
    pub points: Vec<StoredPoint>,
}

/// One point in `accumulators.json`; wide integers are decimal strings and
/// the histogram is sparse (`[bin, count]` pairs).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StoredPoint {
    pub excitation_frequency_hz: f64,
    pub normal_force_n: f64,
    pub range: PeakRange,
    pub realisations: u64,
    pub peaks: u64,
    pub sum_q: String,
    pub sum_q2: String,
    pub stick_units: u64,
    pub clamped: u64,
    pub histogram: Vec<(u32, u64)>,
}

/// Format tag of `accumulators.json`.
pub const ACCUMULATOR_FORMAT: &str = "stickslip-accumulators/1";

impl StoredPoint {
    fn from_accumulator(c: Condition, a: &PointAccumulator) -> Self {
        StoredPoint {
            excitation_frequency_hz: c.excitation_frequency_hz,
            normal_force_n: c.normal_force_n,
            range: a.range,
            realisations: a.realisations,
            peaks: a.peaks,
            sum_q: a.sum_q.to_string(),
            sum_q2: a.sum_q2.to_string(),
            stick_units: a.stick_units,
            clamped: a.clamped,
            histogram: a.histogram.iter().enumerate().filter(|(_, c)| **c > 0).map(|(b, c)| (b as u32, *c)).collect(),
        }
    }

    fn to_accumulator(&self, file: &Path) -> Result<(Condition, PointAccumulator)> {
        let bad = |m: String| Error::Measurement { file: file.to_path_buf(), line: None, message: m };
        let mut a = PointAccumulator::new(self.range);
        a.realisations = self.realisations;
        a.peaks = self.peaks;
        a.sum_q = self.sum_q.parse().map_err(|_| bad(format!("sum_q `{}` is not an integer", self.sum_q)))?;
        a.sum_q2 = self.sum_q2.parse().map_err(|_| bad(format!("sum_q2 `{}` is not an integer", self.sum_q2)))?;
        a.stick_units = self.stick_units;
        a.clamped = self.clamped;
        for &(b, c) in &self.histogram {
            *a.histogram.get_mut(b as usize).ok_or_else(|| bad(format!("histogram bin {b} out of range")))? = c;
        }
        let c = Condition { excitation_frequency_hz: self.excitation_frequency_hz, normal_force_n: self.normal_force_n };
        Ok((c, a))
    }
}

impl SweepResult {
    /// The `accumulators.json` content for this result.
    pub fn to_file(&self, identity: &RunIdentity, shard: Shard) -> AccumulatorFile {
        AccumulatorFile {
            format: ACCUMULATOR_FORMAT.to_string(),
            identity: identity.clone(),
            shard,
            points: self.conditions.iter().zip(&self.accumulators).map(|(&c, a)| StoredPoint::from_accumulator(c, a)).collect(),
        }
    }
}

/// Reads `DIR/accumulators.json`.
pub fn read_accumulators(dir: &Path) -> Result<(AccumulatorFile, SweepResult)> {
    let path = dir.join("accumulators.json");
    let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
    let file: AccumulatorFile = serde_json::from_str(&text)
        .map_err(|e| Error::Measurement { file: path.clone(), line: Some(e.line() as u64), message: e.to_string() })?;
    if file.format != ACCUMULATOR_FORMAT {
        return Err(Error::Measurement { file: path, line: None, message: format!("format `{}` is not {ACCUMULATOR_FORMAT}", file.format) });
    }
    let mut result = SweepResult { conditions: Vec::new(), accumulators: Vec::new() };
    for p in &file.points {
        let (c, a) = p.to_accumulator(&path)?;
        result.conditions.push(c);
        result.accumulators.push(a);
    }
    Ok((file, result))
}

/// Combines shard outputs into the unsharded result. Refuses shards of
/// different runs (model, grid, settings, seed, backend), a shard given
/// twice, a missing shard, and shards whose point counts do not fit.
pub fn merge_shards(dirs: &[std::path::PathBuf]) -> Result<(RunIdentity, SweepResult)> {
    let first = dirs.first().ok_or_else(|| Error::setting("merge", "no shard directories given"))?;
    let mut parts = Vec::new();
    for dir in dirs {
        parts.push((dir, read_accumulators(dir)?));
    }
    let (_, (reference, _)) = &parts[0];
    let identity = reference.identity.clone();
    let count = reference.shard.count;
    for (dir, (file, _)) in &parts {
        let differs = |what: &str| {
            Error::Mismatch(format!(
                "cannot merge {} with {}: the shards differ in {what}",
                dir.display(),
                first.display()
            ))
        };
        let other = &file.identity;
        if other.model_toml != identity.model_toml {
            return Err(differs("their model"));
        }
        if other.seed != identity.seed {
            return Err(differs(&format!("their seed ({} vs {})", other.seed, identity.seed)));
        }
        if other.frequencies_hz != identity.frequencies_hz || other.normal_forces_n != identity.normal_forces_n {
            return Err(differs("their grid"));
        }
        if (other.realisations, other.warmup_cycles, other.measured_cycles) != (identity.realisations, identity.warmup_cycles, identity.measured_cycles) {
            return Err(differs("realisations or cycle counts"));
        }
        if other.backend != identity.backend {
            return Err(differs(&format!("backend ({} vs {})", other.backend, identity.backend)));
        }
        if file.shard.count != count {
            return Err(differs(&format!("shard count ({} vs {count})", file.shard.count)));
        }
    }
    parts.sort_by_key(|(_, (f, _))| f.shard.index);
    for (expected, (dir, (file, _))) in parts.iter().enumerate() {
        if file.shard.index as usize != expected {
            let problem = if (file.shard.index as usize) < expected { "given twice" } else { "missing" };
            return Err(Error::Mismatch(format!(
                "shard {expected}/{count} is {problem} (at {})",
                dir.display()
            )));
        }
    }
    if parts.len() != count as usize {
        return Err(Error::Mismatch(format!("{} shards given, the run was split into {count}", parts.len())));
    }
    let total = identity.frequencies_hz.len() * identity.normal_forces_n.len();
    let mut merged = SweepResult { conditions: Vec::new(), accumulators: Vec::new() };
    for (dir, (file, result)) in parts {
        if result.conditions.len() != file.shard.points(total).len() {
            return Err(Error::Mismatch(format!("{} holds {} points, its shard should hold {}", dir.display(), result.conditions.len(), file.shard.points(total).len())));
        }
        merged.conditions.extend(result.conditions);
        merged.accumulators.extend(result.accumulators);
    }
    Ok((identity, merged))
}

/// Writes `histograms.csv`: every non-empty bin of every point, in metres,
/// with its probability density (1/m). The first and last bins of a point
/// (below and above its range) have infinite outer edges.
pub fn write_histograms_csv(path: &Path, result: &SweepResult) -> Result<()> {
    write_atomically(path, |w| {
        writeln!(w, "excitation_frequency_hz,normal_force_n,bin_lo_m,bin_hi_m,count,density_per_m")?;
        for (c, a) in result.conditions.iter().zip(&result.accumulators) {
            let last = a.histogram.len() as u32 - 1;
            for (b, &count) in a.histogram.iter().enumerate() {
                if count == 0 {
                    continue;
                }
                let b = b as u32;
                let (lo, hi) = if b == 0 {
                    (f64::NEG_INFINITY, a.range.lo_m)
                } else if b == last {
                    (a.range.hi_m, f64::INFINITY)
                } else {
                    a.range.bin_edges(b)
                };
                let density = if lo.is_finite() && hi.is_finite() { count as f64 / (a.peaks as f64 * (hi - lo)) } else { 0.0 };
                writeln!(w, "{},{},{:e},{:e},{count},{density:e}", c.excitation_frequency_hz, c.normal_force_n, lo, hi)?;
            }
        }
        Ok(())
    })
}

/// Writes `accumulators.json`.
pub fn write_accumulators(path: &Path, file: &AccumulatorFile) -> Result<()> {
    write_atomically(path, |w| {
        serde_json::to_writer(&mut *w, file)?;
        writeln!(w)
    })
}
