//! The engine: the model and its effects, the noise, the two integrators
//! (the f64 CPU reference and the f32 WGSL kernel) and the exact reductions.
//!
//! It exposes one way to run an ensemble, whatever the backend: describe the
//! work as a [`Job`] (model, points, realisations, seed, run plan and what to
//! [`Record`]) and hand it to [`Engine::run`]. Only this module knows that
//! there are two backends ([`Backend`]); [`Engine::open`] is the one place
//! that chooses between them, under one policy for every front end
//! (the command line and the Python package pass their options, such as
//! [`GpuOptions::allow_software_gpu`], and decide nothing themselves).

pub mod analytic;
pub mod cpu;
pub mod effects;
pub mod gpu;
pub mod model;
pub mod oscillator;
pub mod reduce;
pub mod rng;
pub mod schedule;
pub mod steps;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
pub use effects::{Effect, Effects};
pub use model::{Condition, Model};
pub use oscillator::{InitialState, Oscillator, PathResult, PeakRange, Point, RunPlan, Sample};
pub use reduce::{PointAccumulator, PointStats};

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
        /// Sample at the noise-interval boundaries when `interval_s` is the
        /// model's noise interval (to 1e-9): samples then split no steps, and
        /// the interval is the noise's 32.32 fixed-point one (within 1e-8 of
        /// `interval_s`). Otherwise, and when false, samples fall exactly
        /// every `interval_s`.
        at_noise_boundaries: bool,
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
    /// Index of each point's first realisation, before the point's own
    /// [`Point::realisation_offset`] (realisation `r` has the same noise at
    /// every point of equal offset: common random numbers).
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

    /// The number of point `point`'s realisation `r` (the noise path it
    /// keys): [`Job::first_realisation`] + the point's
    /// [`Point::realisation_offset`] + `r`, below 2^32 ([`Job::validate`]).
    pub fn realisation(&self, point: usize, r: u32) -> u32 {
        self.first_realisation + self.points[point].realisation_offset + r
    }

    /// The derived constants of every point, a drift's clock started at the
    /// end of the warm-up ([`Oscillator::drift_start_s`]).
    pub fn oscillators(&self) -> Result<Vec<Oscillator>> {
        self.points
            .iter()
            .map(|p| {
                let mut o = Oscillator::new(self.model, p.condition)?;
                o.drift_start_s = f64::from(self.plan.warmup_cycles) * o.period_s;
                Ok(o)
            })
            .collect()
    }

    /// Most grid points in one job: the host keeps each point's sums and
    /// 2048-bin histogram (16 KiB), so 2^16 points take 1 GiB.
    pub const MAX_POINTS: usize = 1 << 16;
    /// Most realisations per grid point (one GPU dispatch's invocations,
    /// 2^20; the CPU runs them in chunks of [`cpu::PATHS_PER_CHUNK`]).
    pub const MAX_REALISATIONS: u32 = 1 << 20;
    /// Most excitation periods one realisation integrates: warm-up plus
    /// measured periods, or warm-up plus a record's periods (2^24).
    pub const MAX_CYCLES: u64 = 1 << 24;
    /// Most peaks per grid point, realisations × measured periods: the exact
    /// sums and histogram bins count them in 32 bits on the GPU.
    pub const MAX_PEAKS_PER_POINT: u64 = (1 << 32) - 1;
    /// Most noise intervals one realisation spans (counted in 32 bits on the GPU).
    pub const MAX_NOISE_INTERVALS: u128 = 1 << 32;
    /// Most bytes of per-realisation output a job keeps in memory: 16 B per
    /// measured period for [`Record::Peaks`], 40 B per sample for
    /// [`Record::Samples`] (2 GiB).
    pub const MAX_KEPT_BYTES: u64 = 2 << 30;

    /// Checks what every backend needs, against the same limits for both
    /// (so both refuse a request with the same message), before anything is
    /// allocated: the grid, the realisations, the periods each realisation
    /// runs, the output it keeps, and that every point's model and starting
    /// state are finite.
    pub fn validate(&self) -> Result<()> {
        if self.points.is_empty() {
            return Err(Error::setting("grid", "no grid points"));
        }
        if self.points.len() > Self::MAX_POINTS {
            return Err(Error::setting(
                "grid",
                format!(
                    "{} grid points exceed the limit of {} per run (each keeps a 16 KiB histogram); split the grid",
                    self.points.len(),
                    Self::MAX_POINTS
                ),
            ));
        }
        if self.realisations == 0 {
            return Err(Error::setting("realisations", "must be at least 1"));
        }
        if self.realisations > Self::MAX_REALISATIONS {
            return Err(Error::setting(
                "realisations",
                format!(
                    "{} per grid point exceed the limit of {} (2^20) on either backend",
                    self.realisations,
                    Self::MAX_REALISATIONS
                ),
            ));
        }
        let highest_offset = self.points.iter().map(|p| p.realisation_offset).max().unwrap_or(0);
        if self.first_realisation.checked_add(highest_offset).and_then(|f| f.checked_add(self.realisations)).is_none() {
            return Err(Error::setting("realisations", "the realisation indices must stay below 2^32"));
        }
        let paths = self.points.len() as u64 * u64::from(self.realisations);
        let highest_hz = self.points.iter().map(|p| p.condition.excitation_frequency_hz).fold(0.0, f64::max);
        let (cycles, kept_bytes) = match self.record {
            Record::Samples { interval_s, duration_s, .. } => {
                if !(interval_s.is_finite() && interval_s > 0.0) {
                    return Err(Error::setting("sample interval", format!("{interval_s} s must be > 0")));
                }
                if !(duration_s.is_finite() && duration_s >= interval_s) {
                    return Err(Error::setting(
                        "record length",
                        format!("{duration_s} s must be at least one sample interval"),
                    ));
                }
                let periods = (duration_s * highest_hz).ceil() + 1.0 + f64::from(self.plan.warmup_cycles);
                let samples = (duration_s / interval_s).round();
                (periods.min(1e30) as u64, (samples * paths as f64 * 40.0).min(1e30) as u64)
            }
            Record::Peaks => {
                (self.plan.total_cycles(), paths.saturating_mul(u64::from(self.plan.measured_cycles)) * 16)
            }
            Record::Sums => (self.plan.total_cycles(), 0),
        };
        if cycles > Self::MAX_CYCLES {
            return Err(Error::setting(
                "cycles",
                format!(
                    "{cycles} excitation periods per realisation (warm-up included) exceed the limit of {} (2^24) \
                     on either backend",
                    Self::MAX_CYCLES
                ),
            ));
        }
        let peaks = u64::from(self.realisations) * u64::from(self.plan.measured_cycles);
        if !matches!(self.record, Record::Samples { .. }) && peaks > Self::MAX_PEAKS_PER_POINT {
            return Err(Error::setting(
                "run size",
                format!(
                    "realisations × measured cycles = {peaks} peaks per grid point exceed the limit of 2^32 − 1 on \
                     either backend"
                ),
            ));
        }
        if kept_bytes > Self::MAX_KEPT_BYTES {
            return Err(Error::setting(
                "run size",
                format!(
                    "the per-realisation output kept in memory would take {} MiB, over the limit of {} MiB",
                    kept_bytes >> 20,
                    Self::MAX_KEPT_BYTES >> 20
                ),
            ));
        }
        self.model.validate()?;
        for p in self.points {
            let o = Oscillator::new(self.model, p.condition)?;
            let at = p.condition.describe();
            if !(p.initial.x_m.is_finite() && p.initial.v_m_per_s.is_finite()) {
                return Err(Error::Diverged {
                    point: at,
                    message: "the starting state is not finite (an undamped model driven exactly at resonance has \
                              no steady state); move the frequency or add damping"
                        .into(),
                });
            }
            let r = &p.range;
            if !(r.lo_m.is_finite() && r.hi_m.is_finite() && r.lo_m < r.hi_m && r.phase_ref_rad.is_finite()) {
                return Err(Error::setting("peak range", format!("the range at {at} must be finite and non-empty")));
            }
            let point_cycles = match self.record {
                Record::Samples { duration_s, .. } => {
                    ((duration_s * p.condition.excitation_frequency_hz).ceil() + 1.0) as u64
                        + u64::from(self.plan.warmup_cycles)
                }
                _ => cycles,
            };
            if o.noise_intervals_in(point_cycles) >= Self::MAX_NOISE_INTERVALS {
                return Err(Error::setting(
                    "run length",
                    format!(
                        "{point_cycles} cycles at {at} span {} noise intervals of {} s, which must stay below 2^32 on \
                         either backend",
                        o.noise_intervals_in(point_cycles),
                        self.model.noise.interval_s
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// The largest displacement a simulated path may reach at `point`, m: 100
/// times the sum of the frictionless steady amplitude there, the base
/// amplitude and the starting displacement, and at least
/// [`model::limits::DISPLACEMENT_MAX_M`]. Friction only takes energy out,
/// and a stuck block sits within its breakaway force of the base, so a path
/// beyond this is an integration that went unstable, not physics.
pub fn plausible_displacement_m(model: &Model, point: &Point) -> f64 {
    let scale = model.linear_amplitude_m(point.condition.excitation_frequency_hz).abs()
        + model.excitation.amplitude_m.abs()
        + point.initial.x_m.abs();
    (100.0 * scale).max(model::limits::DISPLACEMENT_MAX_M)
}

/// Refuses `output` when a displacement in it (a point's extreme peak, a
/// path's peak or a record's sample) lies beyond
/// [`plausible_displacement_m`], naming the point.
fn refuse_diverged(job: &Job<'_>, output: &Output) -> Result<()> {
    let per_point = job.realisations as usize;
    for (i, point) in job.points.iter().enumerate() {
        let paths = output.paths.get(i * per_point..(i + 1) * per_point).unwrap_or_default();
        let records = output.records.get(i * per_point..(i + 1) * per_point).unwrap_or_default();
        let farthest = [
            output
                .sums
                .get(i)
                .and_then(|a| a.peak_extremes_m)
                .map_or(0.0, |(lo, hi)| f64::from(lo.abs().max(hi.abs()))),
            paths.iter().flat_map(|p| &p.peaks_m).fold(0.0, |m: f64, x| m.max(x.abs())),
            records.iter().flatten().fold(0.0, |m: f64, s| m.max(s.x_m.abs())),
        ]
        .into_iter()
        .fold(0.0, f64::max);
        let bound = plausible_displacement_m(job.model, point);
        if farthest > bound {
            return Err(Error::Diverged {
                point: point.condition.describe(),
                message: format!(
                    "the block reaches {} m, beyond the {} m no physical path of this model \
                     reaches (100 times its frictionless and base amplitudes, and at least {} m): the \
                     integration is unstable here (a friction law this steep or strong needs more steps, \
                     solver.steps_per_period), and nothing of it is reported",
                    model::fmt_value(farthest),
                    model::fmt_value(bound),
                    model::limits::DISPLACEMENT_MAX_M
                ),
            });
        }
    }
    Ok(())
}

/// The refusal of a point whose peaks lie outside every range it can be
/// reduced in.
fn peaks_outside(point: &Point, a: &PointAccumulator) -> Error {
    let extremes = a.peak_extremes_m.map_or(String::new(), |(lo, hi)| format!(" (they span {lo:e} to {hi:e} m)"));
    Error::Diverged {
        point: point.condition.describe(),
        message: format!(
            "{} of {} peaks lie outside the range they can be binned and summed in{extremes}; no statistic of \
             this point would be what it claims to be",
            a.outside_range(),
            a.peaks
        ),
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

    /// Whether this backend runs `job` itself; [`Engine::run`] gives the
    /// jobs it does not run to the CPU reference.
    fn runs(&self, _job: &Job<'_>) -> Result<bool> {
        Ok(true)
    }
}

/// The `--backend` choice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BackendChoice {
    /// A hardware GPU, else the CPU reference. A software Vulkan adapter
    /// (lavapipe) is not taken: it runs the WGSL kernel on the same CPU cores
    /// no faster than the f64 reference does (the main job on the 2-core
    /// machine: 9.6 s on lavapipe against 9.1 s, with the kernel specialised
    /// for no effects; any effect takes the general kernel, about half as
    /// fast; `benches/RESULTS.md`), so it is only used when asked for with
    /// `--backend gpu`. On a hardware GPU, jobs that sample time-series
    /// records (a diagnosis's replicates, `simulate`) still run on the
    /// reference, which is the faster path for them.
    Auto,
    /// A GPU adapter (hardware or software); an error when there is none.
    Gpu,
    /// The f64 CPU reference integrator.
    Cpu,
}

/// Settings of the GPU backend, and which adapters [`Engine::open`] may take.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GpuOptions {
    /// Integration steps (invocations × steps) per dispatch: bounds each
    /// submission's run time.
    pub steps_per_dispatch: u64,
    /// Whether [`BackendChoice::Gpu`] may take a software adapter (Mesa's
    /// lavapipe), which runs the kernel on the CPU cores; without it such an
    /// adapter is refused. [`BackendChoice::Auto`] never takes one.
    pub allow_software_gpu: bool,
}

impl Default for GpuOptions {
    fn default() -> Self {
        GpuOptions { steps_per_dispatch: gpu::DEFAULT_STEPS_PER_DISPATCH, allow_software_gpu: false }
    }
}

/// Runs ensembles on one backend and says which.
pub struct Engine {
    backend: Box<dyn Backend>,
    description: String,
    /// The GPU adapter's class and description; none on the CPU.
    adapter: Option<(gpu::AdapterClass, String)>,
    /// Whether jobs that sample time-series records run on the CPU
    /// reference although a GPU is open (`Auto` on a hardware GPU): a
    /// diagnosis's trial is every unit's replicates, a hundred-odd records
    /// of 50 s, far too few to fill a GPU, and each record is one long
    /// chain of steps on one GPU thread; on an NVIDIA H200 with 16 CPU
    /// threads beside it, an 18-run diagnosis took 51 s with its records
    /// from the kernel (a job per trial) and 11 s from the reference, with
    /// the same verdict (`benches/RESULTS.md`). `--backend gpu` keeps
    /// every job on the GPU.
    records_on_cpu: bool,
}

impl Engine {
    /// Opens the chosen backend under the one backend policy every front end
    /// shares: `Cpu` is the f64 reference; `Gpu` a GPU adapter or an error,
    /// a software one only with [`GpuOptions::allow_software_gpu`]; `Auto` a
    /// hardware GPU, else the reference. [`Engine::description`] says which
    /// was taken and why.
    pub fn open(choice: BackendChoice, options: GpuOptions) -> Result<Engine> {
        match choice {
            BackendChoice::Cpu => Ok(Engine::cpu("chosen as the backend")),
            BackendChoice::Gpu => {
                let ctx = gpu::GpuContext::new(true)?;
                if ctx.adapter_class() == gpu::AdapterClass::Software && !options.allow_software_gpu {
                    return Err(Error::NoGpu(format!(
                        "the only GPU adapter is the software {}, which runs the kernel on the CPU cores; pass \
                         --allow-software-gpu (allow_software_gpu=True in Python) to use it anyway, or --backend cpu \
                         for the f64 reference (faster on the same cores){}",
                        ctx.describe(),
                        gpu::context::driver_hint()
                            .unwrap_or_else(|| "; on a GPU node, the GPU's Vulkan driver (ICD) is missing".into())
                    )));
                }
                Ok(Engine::gpu(ctx, options))
            }
            BackendChoice::Auto => match gpu::GpuContext::new(true) {
                Ok(ctx) => match ctx.adapter_class() {
                    gpu::AdapterClass::Hardware => {
                        let mut engine = Engine::gpu(ctx, options);
                        engine.records_on_cpu = true;
                        engine.description.push_str("; time-series records on the f64 CPU reference");
                        Ok(engine)
                    }
                    gpu::AdapterClass::Software => Ok(Engine::cpu(&format!(
                        "no hardware GPU; the only adapter is the software {}, which is slower than this \
                         integrator on the same cores (--backend gpu --allow-software-gpu runs on it anyway){}",
                        ctx.describe(),
                        gpu::context::driver_hint().unwrap_or_default()
                    ))),
                },
                Err(e) => Ok(Engine::cpu(&format!("no GPU adapter ({e})"))),
            },
        }
    }

    /// The f64 CPU reference on all of rayon's threads; `reason` says why.
    pub fn cpu(reason: &str) -> Engine {
        let description =
            format!("CPU: f64 reference integrator on {} threads ({reason})", rayon::current_num_threads());
        Engine { backend: Box::new(cpu::CpuBackend), description, adapter: None, records_on_cpu: false }
    }

    /// The WGSL kernel on an opened GPU context, whatever its adapter.
    pub fn gpu(ctx: gpu::GpuContext, options: GpuOptions) -> Engine {
        let description = format!("GPU: {}", ctx.describe());
        let adapter = Some((ctx.adapter_class(), ctx.describe()));
        Engine { backend: Box::new(gpu::GpuBackend::new(ctx, options)), description, adapter, records_on_cpu: false }
    }

    /// The GPU adapter the jobs run on, its class and description; `None`
    /// on the CPU reference.
    pub fn adapter(&self) -> Option<(gpu::AdapterClass, &str)> {
        self.adapter.as_ref().map(|(class, name)| (*class, name.as_str()))
    }

    /// Which integrator runs the jobs.
    pub fn kind(&self) -> BackendKind {
        self.backend.kind()
    }

    /// Whether jobs of time-series records run side by side on rayon's
    /// threads, each on the CPU reference (true there, and where a GPU
    /// leaves records to the CPU), rather than one at a time on a GPU
    /// that samples them itself.
    pub fn records_side_by_side(&self) -> bool {
        self.backend.kind() == BackendKind::Cpu || self.records_on_cpu
    }

    /// The points of a set of time-series records (a diagnosis's measured
    /// units, at `frequencies_hz`) cut into jobs, as indices. Where records
    /// run side by side ([`Engine::records_side_by_side`]), a job holds the
    /// points of one frequency: their realisations step together in lane
    /// groups whatever their loads, and the job runs on the thread that
    /// asked, its records read there while only they are in memory (one job
    /// of every unit holds all of a trial's records at once, hundreds of
    /// megabytes, and pays for them in page faults). On a GPU that samples
    /// the records itself, up to [`Job::MAX_POINTS`] a job: its dispatch
    /// integrates all of a job's realisations at once, where jobs of one
    /// unit each would take turns on it, all but idle (`benches/RESULTS.md`).
    pub fn record_jobs(&self, frequencies_hz: &[f64]) -> Vec<Vec<usize>> {
        let points: Vec<usize> = (0..frequencies_hz.len()).collect();
        if !self.records_side_by_side() {
            return points.chunks(Job::MAX_POINTS).map(<[usize]>::to_vec).collect();
        }
        let mut jobs: Vec<(u64, Vec<usize>)> = Vec::new();
        for (p, f) in frequencies_hz.iter().enumerate() {
            match jobs.iter_mut().find(|(bits, _)| *bits == f.to_bits()) {
                Some((_, job)) => job.push(p),
                None => jobs.push((f.to_bits(), vec![p])),
            }
        }
        jobs.into_iter().map(|(_, job)| job).collect()
    }

    /// One line: the backend, its adapter or threads, and why it was chosen.
    pub fn description(&self) -> &str {
        &self.description
    }

    /// Runs `job` on this engine's backend. A job the backend does not run
    /// itself (on a GPU: records sampled off the noise boundaries, which
    /// would split the kernel's steps) runs on the CPU reference, on the
    /// same noise keys. A result with a displacement beyond
    /// [`plausible_displacement_m`] is refused, naming the point.
    pub fn run(&self, job: &Job<'_>, progress: &mut dyn FnMut(u64, u64)) -> Result<Output> {
        job.validate()?;
        let records = matches!(job.record, Record::Samples { .. });
        let output = if (records && self.records_on_cpu) || !self.backend.runs(job)? {
            cpu::CpuBackend.run(job, progress)?
        } else {
            self.backend.run(job, progress)?
        };
        refuse_diverged(job, &output)?;
        Ok(output)
    }

    /// Runs `job` and returns its per-point sums, every point's peaks inside
    /// its range: a point with peaks outside it is run again (the same
    /// realisations, so the same peaks) over the range that holds them
    /// ([`PointAccumulator::range_holding_peaks`]); its sums then carry that
    /// range. A point whose peaks still leave it is an error.
    pub fn sums(&self, job: &Job<'_>, progress: &mut dyn FnMut(u64, u64)) -> Result<Vec<PointAccumulator>> {
        let job = Job { record: Record::Sums, ..*job };
        let mut sums = self.run(&job, progress)?.sums;
        let outside: Vec<usize> = (0..sums.len()).filter(|&i| sums[i].outside_range() > 0).collect();
        if outside.is_empty() {
            return Ok(sums);
        }
        let mut points = Vec::with_capacity(outside.len());
        for &i in &outside {
            let range = sums[i].range_holding_peaks().ok_or_else(|| peaks_outside(&job.points[i], &sums[i]))?;
            points.push(Point { range, ..job.points[i] });
        }
        let again = Job { points: &points, ..job };
        let (first, total) = (job.work(), job.work() + again.work());
        let wider = self.run(&again, &mut |done, _| progress(first + done, total))?.sums;
        for (&i, a) in outside.iter().zip(wider) {
            if a.outside_range() > 0 {
                return Err(peaks_outside(&job.points[i], &a));
            }
            sums[i] = a;
        }
        Ok(sums)
    }

    /// Runs `job` and returns every realisation's peaks, point-major.
    pub fn paths(&self, job: &Job<'_>) -> Result<Vec<PathResult>> {
        Ok(self.run(&Job { record: Record::Peaks, ..*job }, &mut |_, _| {})?.paths)
    }

    /// Records of `duration_s` s sampled every `interval_s` s after the
    /// plan's warm-up, point-major.
    pub fn records(&self, job: &Job<'_>, interval_s: f64, duration_s: f64) -> Result<Vec<Vec<Sample>>> {
        let record = Record::Samples { interval_s, duration_s, at_noise_boundaries: false };
        Ok(self.run(&Job { record, ..*job }, &mut |_, _| {})?.records)
    }
}
