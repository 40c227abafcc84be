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
