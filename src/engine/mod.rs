//! The engine: the model and its effects, the noise, the two integrators
//! (the f64 CPU reference and the f32 WGSL kernel) and the exact reductions.
//!
//! It exposes one way to run an ensemble, whatever the backend: describe the
//! work as a [`Job`] (model, points, realisations, seed, run plan and what to
//! [`Record`]) and hand it to [`Engine::run`]. Only this module knows that
//! there are two backends ([`Backend`]); [`Engine::open`] is the one place
//! that chooses between them.

pub mod analytic;
pub mod cpu;
pub mod effects;
pub mod gpu;
pub mod model;
pub mod oscillator;
pub mod reduce;
pub mod rng;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
pub use effects::{Effect, Effects};
pub use model::{Condition, Model};
pub use oscillator::{InitialState, Oscillator, PathResult, Point, RunPlan, Sample};
pub use reduce::{PeakRange, PointAccumulator, PointStats};

/// What a job keeps of each realisation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Record {
    /// Only the exact per-point sums and histograms ([`Output::sums`]).
    Sums,
    /// Also every realisation's per-period peaks and stuck time
    /// ([`Output::paths`]); memory grows with the run.
    Peaks,
    /// Time-series records ([`Output::records`]) sampled like measured ones:
    /// `duration_s` seconds of samples every `interval_s` seconds, from the
    /// end of the plan's warm-up, with times measured from the record's
    /// start. The plan's measured cycles are not used: each record runs the
    /// periods its duration needs. No sums are kept.
    Samples {
        /// Sampling interval, s.
        interval_s: f64,
        /// Record length, s.
        duration_s: f64,
    },
}

/// One ensemble to run: every point of `points` × realisations
/// `first_realisation .. first_realisation + realisations`, all of `model`.
#[derive(Clone, Copy, Debug)]
pub struct Job<'a> {
    pub model: &'a Model,
    pub points: &'a [Point],
    /// Realisations per point.
    pub realisations: u32,
    /// Index of each point's first realisation (realisation `r` has the
    /// same noise at every point: common random numbers).
    pub first_realisation: u32,
    /// The noise seed (Philox key).
    pub seed: u64,
    pub plan: RunPlan,
    pub record: Record,
}

impl Job<'_> {
    /// Integrated periods × paths, the unit of progress.
    pub fn work(&self) -> u64 {
        self.points.len() as u64 * u64::from(self.realisations) * self.plan.total_cycles()
    }

    /// The derived constants of every point.
    pub fn oscillators(&self) -> Result<Vec<Oscillator>> {
        self.points.iter().map(|p| Oscillator::new(self.model, p.condition)).collect()
    }

    /// Checks what every backend needs.
    pub fn validate(&self) -> Result<()> {
        if self.points.is_empty() {
            return Err(Error::setting("grid", "no grid points"));
        }
        if self.realisations == 0 {
            return Err(Error::setting("realisations", "must be at least 1"));
        }
        if let Record::Samples { interval_s, duration_s } = self.record {
            if !(interval_s.is_finite() && interval_s > 0.0) {
                return Err(Error::setting("sample interval", format!("{interval_s} s must be > 0")));
            }
            if !(duration_s.is_finite() && duration_s >= interval_s) {
                return Err(Error::setting(
                    "record length",
                    format!("{duration_s} s must be at least one sample interval"),
                ));
            }
        }
        Ok(())
    }
}

/// What a job produced. Paths and records are point-major: realisation `r`
/// of point `i` is at `i × realisations + r`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Output {
    /// Exact per-point sums, in point order (empty for [`Record::Samples`]).
    pub sums: Vec<PointAccumulator>,
    /// Per-realisation peaks, for [`Record::Peaks`].
    pub paths: Vec<PathResult>,
    /// Per-realisation records, for [`Record::Samples`].
    pub records: Vec<Vec<Sample>>,
}

/// Which integrator a backend runs: it identifies a run's numbers (f32 and
/// f64 paths differ in the last digits), so shards of different kinds never
/// merge.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BackendKind {
    /// The WGSL kernel on a wgpu adapter (f32).
    Gpu,
    /// The f64 reference integrator.
    Cpu,
}

impl BackendKind {
    /// `gpu` or `cpu`.
    pub fn name(self) -> &'static str {
        match self {
            BackendKind::Gpu => "gpu",
            BackendKind::Cpu => "cpu",
        }
    }
}

/// A place ensembles run. [`cpu::CpuBackend`] and [`gpu::GpuBackend`] are
/// the two; everything outside the engine sees only an [`Engine`].
pub trait Backend: Send + Sync {
    /// Which integrator this is.
    fn kind(&self) -> BackendKind;
    /// Runs `job`; `progress(done, total)` counts integrated periods × paths.
    fn run(&self, job: &Job<'_>, progress: &mut dyn FnMut(u64, u64)) -> Result<Output>;
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

/// Settings of the GPU backend.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GpuOptions {
    /// Integration steps (invocations × steps) per dispatch: bounds each
    /// submission's run time.
    pub steps_per_dispatch: u64,
}

impl Default for GpuOptions {
    fn default() -> Self {
        GpuOptions { steps_per_dispatch: gpu::DEFAULT_STEPS_PER_DISPATCH }
    }
}

/// Runs ensembles on one backend and says which.
pub struct Engine {
    backend: Box<dyn Backend>,
    description: String,
}

impl Engine {
    /// Opens the chosen backend; [`Engine::description`] says which was
    /// taken and why.
    pub fn open(choice: BackendChoice, options: GpuOptions) -> Result<Engine> {
        match choice {
            BackendChoice::Cpu => Ok(Engine::cpu("chosen with --backend cpu")),
            BackendChoice::Gpu => {
                let ctx = gpu::GpuContext::new(true)?;
                let description = format!("GPU: {}", ctx.describe());
                Ok(Engine::gpu_described(ctx, options, description))
            }
            BackendChoice::Auto => match gpu::GpuContext::new(true) {
                Ok(ctx) => {
                    let description = match ctx.adapter_class() {
                        gpu::AdapterClass::Hardware => format!("GPU: {}", ctx.describe()),
                        gpu::AdapterClass::Software => {
                            format!("GPU: no hardware GPU found; using the software Vulkan adapter {}", ctx.describe())
                        }
                    };
                    Ok(Engine::gpu_described(ctx, options, description))
                }
                Err(e) => Ok(Engine::cpu(&format!("no GPU adapter ({e})"))),
            },
        }
    }

    /// The f64 CPU reference on all of rayon's threads; `reason` says why.
    pub fn cpu(reason: &str) -> Engine {
        let description =
            format!("CPU: f64 reference integrator on {} threads ({reason})", rayon::current_num_threads());
        Engine { backend: Box::new(cpu::CpuBackend), description }
    }

    /// The WGSL kernel on an opened GPU context.
    pub fn gpu(ctx: gpu::GpuContext, options: GpuOptions) -> Engine {
        let description = format!("GPU: {}", ctx.describe());
        Engine::gpu_described(ctx, options, description)
    }

    fn gpu_described(ctx: gpu::GpuContext, options: GpuOptions, description: String) -> Engine {
        Engine { backend: Box::new(gpu::GpuBackend::new(ctx, options)), description }
    }

    /// Which integrator runs the jobs.
    pub fn kind(&self) -> BackendKind {
        self.backend.kind()
    }

    /// One line: the backend, its adapter or threads, and why it was chosen.
    pub fn description(&self) -> &str {
        &self.description
    }

    /// Runs `job` on this engine's backend.
    pub fn run(&self, job: &Job<'_>, progress: &mut dyn FnMut(u64, u64)) -> Result<Output> {
        job.validate()?;
        self.backend.run(job, progress)
    }

    /// Runs `job` and returns its per-point sums.
    pub fn sums(&self, job: &Job<'_>, progress: &mut dyn FnMut(u64, u64)) -> Result<Vec<PointAccumulator>> {
        Ok(self.run(&Job { record: Record::Sums, ..*job }, progress)?.sums)
    }

    /// Runs `job` and returns every realisation's peaks, point-major.
    pub fn paths(&self, job: &Job<'_>) -> Result<Vec<PathResult>> {
        Ok(self.run(&Job { record: Record::Peaks, ..*job }, &mut |_, _| {})?.paths)
    }

    /// Records of `duration_s` s sampled every `interval_s` s after the
    /// plan's warm-up, point-major.
    pub fn records(&self, job: &Job<'_>, interval_s: f64, duration_s: f64) -> Result<Vec<Vec<Sample>>> {
        Ok(self.run(&Job { record: Record::Samples { interval_s, duration_s }, ..*job }, &mut |_, _| {})?.records)
    }
}
