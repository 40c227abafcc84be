//! The GPU ensemble: one context owning device, queue and pipelines, the
//! host structs shared with `shaders/*.wgsl`, and the dispatch loop.
//!
//! Functions take `&Device, &Queue` (and the pipelines in [`Kernels`]) so
//! tests can pass their own device.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::cpu::{InitialState, PathResult, RunPlan};
use crate::error::{Error, Result};
use crate::model::Oscillator;
use crate::reduce::{PeakRange, PointAccumulator, HISTOGRAM_BINS};

/// The ensemble kernel: Philox plus the oscillator.
pub const ENSEMBLE_WGSL: &str = concat!(include_str!("../shaders/philox.wgsl"), include_str!("../shaders/ensemble.wgsl"));
/// The generator check kernel: Philox plus a kernel writing raw words.
pub const PHILOX_CHECK_WGSL: &str =
    concat!(include_str!("../shaders/philox.wgsl"), include_str!("../shaders/philox_check.wgsl"));

/// Invocations per workgroup in every kernel (`@workgroup_size(64)`).
pub const WORKGROUP_SIZE: u32 = 64;
/// Most workgroups per dispatch dimension (WebGPU's guaranteed limit).
const MAX_WORKGROUPS_PER_DIMENSION: u32 = 65_535;
/// Estimated loop iterations one invocation may run per dispatch.
///
/// llvmpipe (lavapipe) bounds loops with a counter of 65535 iterations and
/// then silently leaves every loop. The counter is not simply per
/// invocation: divergent SIMD lanes and the invocations of a workgroup share
/// it, so a dispatch of ~28 cycles at 7 Hz (≈ 9·10^3 estimated iterations per
/// invocation) was cut short while ~25 cycles passed. Dispatches stay below
/// 8192 estimated iterations, and every result is checked: each path counts
/// only the periods whose step loop really finished, and the host refuses a
/// dispatch with a short count.
pub const LOOP_ITERATIONS_PER_DISPATCH: u64 = 8_192;

/// Upper estimate of one invocation's loop iterations per excitation period:
/// the step loop and the segment loop run once per step and per noise
/// boundary, plus root finding at a few stick/slip events.
pub fn loop_iterations_per_cycle(osc: &Oscillator) -> u64 {
    let boundaries = (1u64 << 32).div_ceil(osc.noise_interval_fixed) + 1;
    2 * (u64::from(osc.steps_per_period) + boundaries) + 400
}

/// Integration steps (invocations × steps) per dispatch. Keeps each
/// submission near 0.1 s on lavapipe and far below desktop drivers' watchdogs.
pub const DEFAULT_STEPS_PER_DISPATCH: u64 = 1 << 22;

/// Uniform parameters of `ensemble.wgsl` (struct `Params`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Params {
    /// kg
    pub mass_kg: f32,
    /// N/m
    pub stiffness_n_per_m: f32,
    /// N·s/m
    pub damping_n_s_per_m: f32,
    /// m
    pub base_amplitude_m: f32,
    /// –
    pub friction_a: f32,
    /// –
    pub friction_b: f32,
    /// s/m
    pub friction_c_s_per_m: f32,
    /// s²/m²
    pub friction_d_s2_per_m2: f32,
    /// –
    pub friction_sigma: f32,
    /// N
    pub normal_force_sigma_n: f32,
    pub steps_per_period: u32,
    pub warmup_cycles: u32,
    pub seed_lo: u32,
    pub seed_hi: u32,
    /// Invocations in this dispatch.
    pub invocations: u32,
    pub realisations_per_point: u32,
    /// Realisation index of the dispatch's first realisation of each point.
    pub realisation_offset: u32,
    /// Index (from the start of the run) of the first cycle of this dispatch.
    pub first_cycle: u32,
    /// Cycles integrated by this dispatch.
    pub cycles: u32,
    /// Index into the grid-point buffer of this dispatch's first point.
    pub point_offset: u32,
    /// 1: also write every measured peak to the peaks buffer.
    pub record_peaks: u32,
    /// Histogram bins per point ([`crate::reduce::HISTOGRAM_BINS`]).
    pub histogram_bins: u32,
}

/// The effects as the kernel sees them (struct `Effects`, uniform).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Effects {
    pub harmonic_form: u32,
    pub harmonic_shape: f32,
    pub harmonic_shape_mean: f32,
    pub non_gaussian_form: u32,
    /// N
    pub harmonic_amplitude_1_n: f32,
    pub harmonic_amplitude_2_n: f32,
    pub harmonic_amplitude_3_n: f32,
    pub harmonic_amplitude_4_n: f32,
    /// rad
    pub harmonic_phase_1_rad: f32,
    pub harmonic_phase_2_rad: f32,
    pub harmonic_phase_3_rad: f32,
    pub harmonic_phase_4_rad: f32,
    pub hysteresis_form: u32,
    /// m
    pub hysteresis_length_m: f32,
    pub colour_form: u32,
    pub colour_rho: f32,
    pub colour_hold_intervals: u32,
    pub stiction_form: u32,
    pub stiction_excess: f32,
    pub drift_form: u32,
    /// 1/s
    pub drift_rate_per_s: f32,
    /// s
    pub noise_interval_s: f32,
    /// m
    pub stiction_release_m: f32,
    pub _pad1: u32,
}

impl Effects {
    fn from_oscillator(o: &Oscillator) -> Effects {
        let e = &o.effects;
        Effects {
            harmonic_form: e.harmonic_form,
            harmonic_shape: e.harmonic_shape as f32,
            harmonic_shape_mean: e.harmonic_shape_mean as f32,
            non_gaussian_form: e.non_gaussian_form,
            harmonic_amplitude_1_n: e.harmonic_amplitudes_n[0] as f32,
            harmonic_amplitude_2_n: e.harmonic_amplitudes_n[1] as f32,
            harmonic_amplitude_3_n: e.harmonic_amplitudes_n[2] as f32,
            harmonic_amplitude_4_n: e.harmonic_amplitudes_n[3] as f32,
            harmonic_phase_1_rad: e.harmonic_phases_rad[0] as f32,
            harmonic_phase_2_rad: e.harmonic_phases_rad[1] as f32,
            harmonic_phase_3_rad: e.harmonic_phases_rad[2] as f32,
            harmonic_phase_4_rad: e.harmonic_phases_rad[3] as f32,
            hysteresis_form: e.hysteresis_form,
            hysteresis_length_m: e.hysteresis_length_m as f32,
            colour_form: e.colour_form,
            colour_rho: e.colour_rho as f32,
            colour_hold_intervals: e.colour_hold_intervals,
            stiction_form: e.stiction_form,
            stiction_excess: e.stiction_excess as f32,
            drift_form: e.drift_form,
            drift_rate_per_s: e.drift_rate_per_s as f32,
            noise_interval_s: o.noise_interval_s as f32,
            stiction_release_m: e.stiction_release_m as f32,
            _pad1: 0,
        }
    }
}

/// One grid point as the kernel sees it (struct `GridPoint`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GridPoint {
    /// rad/s
    pub omega_rad_per_s: f32,
    /// s
    pub period_s: f32,
    /// N
    pub normal_force_mean_n: f32,
    /// Noise hold interval in periods, 32.32 fixed point: whole part.
    pub noise_interval_whole: u32,
    /// Fractional part (units of 2^-32 periods).
    pub noise_interval_frac: u32,
    /// m
    pub initial_x_m: f32,
    /// m/s
    pub initial_v_m_per_s: f32,
    /// Centre of the peak range, m.
    pub peak_centre_m: f32,
    /// 1 / quantisation step, 1/m.
    pub inv_quantum_per_m: f32,
    /// Lower edge of the first inner histogram bin, m.
    pub histogram_lo_m: f32,
    /// Inner histogram bins per metre, 1/m.
    pub histogram_bins_per_m: f32,
    /// Load-dependent friction offset Δa at this point, –.
    pub friction_offset: f32,
    /// Non-Gaussian strength at this point's N0, –.
    pub non_gaussian_strength: f32,
}

/// Per-invocation state kept between dispatches (struct `PathState`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PathState {
    pub x_m: f32,
    pub v_m_per_s: f32,
    pub mode: i32,
    pub period: u32,
    pub interval: u32,
    pub next_boundary_whole: u32,
    pub next_boundary_frac: u32,
    pub friction_noise: f32,
    pub normal_force_n: f32,
    /// Time stuck during measured cycles, s.
    pub stick_time_s: f32,
    pub slip_start_x_m: f32,
    pub colour_state: f32,
    pub interval_phase: f32,
    pub stiction_excess: f32,
}

/// Uniform of `philox_check.wgsl` (struct `CheckParams`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CheckParams {
    pub seed_lo: u32,
    pub seed_hi: u32,
    pub first: u32,
    pub count: u32,
}

/// Compiled pipelines and their bind-group layouts.
pub struct Kernels {
    ensemble_layout: wgpu::BindGroupLayout,
    init_paths: wgpu::ComputePipeline,
    run_cycles: wgpu::ComputePipeline,
    check_layout: wgpu::BindGroupLayout,
    philox_check: wgpu::ComputePipeline,
}

fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn compute_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    module: &wgpu::ShaderModule,
    entry_point: &str,
) -> wgpu::ComputePipeline {
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(entry_point),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry_point),
        layout: Some(&pipeline_layout),
        module,
        entry_point: Some(entry_point),
        compilation_options: Default::default(),
        cache: None,
    })
}

impl Kernels {
    /// Compiles the WGSL and builds the pipelines.
    pub fn new(device: &wgpu::Device) -> Kernels {
        let ensemble = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("ensemble.wgsl"),
            source: wgpu::ShaderSource::Wgsl(ENSEMBLE_WGSL.into()),
        });
        let ensemble_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("ensemble"),
            entries: &[
                uniform_entry(0),
                storage_entry(1, true),
                storage_entry(2, false),
                storage_entry(3, false),
                storage_entry(4, false),
                storage_entry(5, false),
                uniform_entry(6),
            ],
        });
        let check = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("philox_check.wgsl"),
            source: wgpu::ShaderSource::Wgsl(PHILOX_CHECK_WGSL.into()),
        });
        let check_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("philox_check"),
            entries: &[uniform_entry(0), storage_entry(1, false), storage_entry(2, false)],
        });
        Kernels {
            init_paths: compute_pipeline(device, &ensemble_layout, &ensemble, "init_paths"),
            run_cycles: compute_pipeline(device, &ensemble_layout, &ensemble, "run_cycles"),
            philox_check: compute_pipeline(device, &check_layout, &check, "philox_check"),
            ensemble_layout,
            check_layout,
        }
    }
}

/// What kind of adapter a context runs on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AdapterClass {
    /// A hardware GPU (discrete, integrated or virtual).
    Hardware,
    /// A software rasteriser such as Mesa's lavapipe.
    Software,
}

/// One GPU: device, queue, adapter description and compiled pipelines.
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter_info: wgpu::AdapterInfo,
    pub kernels: Kernels,
}

impl GpuContext {
    /// Opens the best adapter: a hardware GPU if there is one, otherwise a
    /// software one (lavapipe) when `allow_software` is set.
    pub fn new(allow_software: bool) -> Result<GpuContext> {
        pollster::block_on(Self::new_async(allow_software, None))
    }

    /// Like [`GpuContext::new`], but the device gets `limits` instead of
    /// everything the adapter offers (tests use this to force chunking).
    pub fn with_limits(allow_software: bool, limits: wgpu::Limits) -> Result<GpuContext> {
        pollster::block_on(Self::new_async(allow_software, Some(limits)))
    }

    async fn new_async(allow_software: bool, limits: Option<wgpu::Limits>) -> Result<GpuContext> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle());
        let mut adapters = instance.enumerate_adapters(wgpu::Backends::all()).await;
        let rank = |a: &wgpu::Adapter| match a.get_info().device_type {
            wgpu::DeviceType::DiscreteGpu => 0,
            wgpu::DeviceType::IntegratedGpu => 1,
            wgpu::DeviceType::VirtualGpu => 2,
            wgpu::DeviceType::Cpu => 3,
            wgpu::DeviceType::Other => 4,
        };
        adapters.retain(|a| a.get_info().backend != wgpu::Backend::Noop && (allow_software || rank(a) < 3));
        adapters.sort_by_key(|a| rank(a));
        let adapter = adapters.into_iter().next().ok_or_else(|| {
            Error::NoGpu(if allow_software {
                "no Vulkan, Metal or DX12 adapter found (install Mesa's lavapipe, package mesa-vulkan-drivers, for a software one)".into()
            } else {
                "no hardware GPU adapter found".into()
            })
        })?;
        let adapter_info = adapter.get_info();
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("stickslip"),
                required_limits: limits.unwrap_or_else(|| adapter.limits()),
                ..Default::default()
            })
            .await
            .map_err(|e| Error::NoGpu(format!("{}: {e}", adapter_info.name)))?;
        let kernels = Kernels::new(&device);
        Ok(GpuContext { device, queue, adapter_info, kernels })
    }

    /// Hardware or software adapter.
    pub fn adapter_class(&self) -> AdapterClass {
        match self.adapter_info.device_type {
            wgpu::DeviceType::Cpu | wgpu::DeviceType::Other => AdapterClass::Software,
            _ => AdapterClass::Hardware,
        }
    }

    /// A one-line description: name, type, backend, driver.
    pub fn describe(&self) -> String {
        let i = &self.adapter_info;
        format!("{} ({:?}, {:?}, {} {})", i.name, i.device_type, i.backend, i.driver, i.driver_info)
    }
}

/// Waits for the queue and reads a buffer back.
fn read_back(device: &wgpu::Device, queue: &wgpu::Queue, buffer: &wgpu::Buffer, size: u64) -> Result<Vec<u8>> {
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read back"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("read back") });
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
    queue.submit([encoder.finish()]);
    let slice = staging.slice(..);
    let (sender, receiver) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |result| {
        let _ = sender.send(result);
    });
    device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| Error::Gpu(e.to_string()))?;
    receiver
        .recv()
        .map_err(|e| Error::Gpu(e.to_string()))?
        .map_err(|e| Error::Gpu(format!("mapping a result buffer: {e}")))?;
    let bytes = slice.get_mapped_range().map_err(|e| Error::Gpu(e.to_string()))?.to_vec();
    staging.unmap();
    Ok(bytes)
}

fn storage_buffer(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

fn workgroups(invocations: u32) -> u32 {
    invocations.div_ceil(WORKGROUP_SIZE)
}

/// The Philox key and counter that check index `i` uses in `philox_check.wgsl`.
pub fn philox_check_input(seed: u64, i: u32) -> ([u32; 4], [u32; 2]) {
    let [lo, hi] = crate::rng::seed_key(seed);
    (
        [i, i.wrapping_mul(0x9E37_79B9), !i, i ^ 0x85EB_CA6B],
        [lo ^ i, hi.wrapping_add(i >> 3)],
    )
}

/// Raw Philox words and Gaussians for check indices `first..first+count`,
/// computed by the WGSL generator.
pub fn philox_check(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    kernels: &Kernels,
    seed: u64,
    first: u32,
    count: u32,
) -> Result<(Vec<[u32; 4]>, Vec<f32>)> {
    if count == 0 || workgroups(count) > MAX_WORKGROUPS_PER_DIMENSION {
        return Err(Error::setting("philox check", format!("count {count} must be in 1..={}", MAX_WORKGROUPS_PER_DIMENSION * WORKGROUP_SIZE)));
    }
    let [seed_lo, seed_hi] = crate::rng::seed_key(seed);
    let params = CheckParams { seed_lo, seed_hi, first, count };
    let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("check params"),
        contents: bytemuck::bytes_of(&params),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let words = storage_buffer(device, "words", u64::from(count) * 16);
    let normals = storage_buffer(device, "normals", u64::from(count) * 4);
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("philox check"),
        layout: &kernels.check_layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: words.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 2, resource: normals.as_entire_binding() },
        ],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&kernels.philox_check);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(workgroups(count), 1, 1);
    }
    queue.submit([encoder.finish()]);
    let w = read_back(device, queue, &words, u64::from(count) * 16)?;
    let n = read_back(device, queue, &normals, u64::from(count) * 4)?;
    Ok((bytemuck::cast_slice(&w).to_vec(), bytemuck::cast_slice(&n).to_vec()))
}

/// One grid point of a GPU ensemble.
#[derive(Clone, Debug)]
pub struct PointSpec {
    pub oscillator: Oscillator,
    pub initial: InitialState,
    /// Where the point's peaks are binned and quantised.
    pub range: PeakRange,
}

/// What an ensemble produced.
#[derive(Clone, Debug)]
pub struct EnsembleOutput {
    /// Every path's peaks, in invocation order, when the request asked for them.
    pub paths: Option<Vec<PathResult>>,
    /// Exact per-point sums, in point order.
    pub points: Vec<PointAccumulator>,
}

/// What to run: points × realisations, all with the same rig and friction law.
#[derive(Clone, Debug)]
pub struct EnsembleRequest<'a> {
    pub points: &'a [PointSpec],
    pub realisations_per_point: u32,
    /// Realisation index of the first realisation of each point.
    pub realisation_offset: u32,
    pub seed: u64,
    pub plan: RunPlan,
    /// Budget of integration steps per dispatch.
    pub steps_per_dispatch: u64,
    /// Also return every path's per-cycle peaks (memory grows with the run).
    pub record_peaks: bool,
}

fn params_for(osc: &Oscillator, request: &EnsembleRequest<'_>) -> Params {
    let [seed_lo, seed_hi] = crate::rng::seed_key(request.seed);
    Params {
        mass_kg: osc.mass_kg as f32,
        stiffness_n_per_m: osc.stiffness_n_per_m as f32,
        damping_n_s_per_m: osc.damping_n_s_per_m as f32,
        base_amplitude_m: osc.base_amplitude_m as f32,
        friction_a: osc.friction_a as f32,
        friction_b: osc.friction_b as f32,
        friction_c_s_per_m: osc.friction_c_s_per_m as f32,
        friction_d_s2_per_m2: osc.friction_d_s2_per_m2 as f32,
        friction_sigma: osc.friction_sigma as f32,
        normal_force_sigma_n: osc.normal_force_sigma_n as f32,
        steps_per_period: osc.steps_per_period,
        warmup_cycles: request.plan.warmup_cycles,
        seed_lo,
        seed_hi,
        invocations: 0,
        realisations_per_point: request.realisations_per_point,
        realisation_offset: request.realisation_offset,
        first_cycle: 0,
        cycles: 0,
        point_offset: 0,
        record_peaks: u32::from(request.record_peaks),
        histogram_bins: HISTOGRAM_BINS,
    }
}

impl GridPoint {
    fn from_spec(spec: &PointSpec) -> GridPoint {
        let o = &spec.oscillator;
        GridPoint {
            omega_rad_per_s: o.omega_rad_per_s as f32,
            period_s: o.period_s as f32,
            normal_force_mean_n: o.normal_force_mean_n as f32,
            noise_interval_whole: (o.noise_interval_fixed >> 32) as u32,
            noise_interval_frac: o.noise_interval_fixed as u32,
            initial_x_m: spec.initial.x_m as f32,
            initial_v_m_per_s: spec.initial.v_m_per_s as f32,
            peak_centre_m: spec.range.centre_f32(),
            inv_quantum_per_m: spec.range.inv_quantum_f32(),
            histogram_lo_m: spec.range.lo_m as f32,
            histogram_bins_per_m: spec.range.bins_per_m_f32(),
            friction_offset: o.effects.friction_offset as f32,
            non_gaussian_strength: o.effects.non_gaussian_strength as f32,
        }
    }
}

/// Checks that a request can run on the GPU: one rig and friction law for
/// all points, noise intervals and periods that fit the kernel's counters.
fn validate_request(request: &EnsembleRequest<'_>) -> Result<()> {
    let first = request.points.first().ok_or_else(|| Error::setting("grid", "no grid points"))?;
    if request.realisations_per_point == 0 {
        return Err(Error::setting("realisations", "must be at least 1"));
    }
    let cycles = u64::from(request.plan.warmup_cycles) + u64::from(request.plan.measured_cycles);
    if u64::from(request.realisations_per_point) * u64::from(request.plan.measured_cycles) >= 1 << 32 {
        return Err(Error::setting("run size", "realisations × measured cycles per point must stay below 2^32"));
    }
    for spec in request.points {
        let o = &spec.oscillator;
        let shared = |o: &Oscillator| {
            let mut effects = o.effects.clone();
            effects.friction_offset = 0.0;
            effects.non_gaussian_strength = 0.0;
            Oscillator { omega_rad_per_s: 0.0, period_s: 0.0, normal_force_mean_n: 0.0, noise_interval_fixed: 0, effects, ..o.clone() }
        };
        let same_model = shared(o) == shared(&first.oscillator);
        if !same_model {
            return Err(Error::Mismatch("all grid points of one GPU ensemble must share the model".into()));
        }
        if o.noise_intervals_in(cycles) >= 1 << 32 || o.noise_interval_fixed >> 32 >= 1 << 31 {
            return Err(Error::setting(
                "run length",
                format!(
                    "{cycles} cycles at {:.4} Hz span {} noise intervals; the GPU kernel counts them in 32 bits",
                    1.0 / o.period_s,
                    o.noise_intervals_in(cycles)
                ),
            ));
        }
    }
    Ok(())
}

/// Words of one point's accumulator in `ensemble.wgsl`.
const ACCUMULATOR_WORDS: usize = 12;

/// Decodes one point's accumulator words and histogram.
fn decode_accumulator(range: PeakRange, realisations: u32, words: &[u32], histogram: &[u32]) -> PointAccumulator {
    let wide = |w: &[u32]| w.iter().rev().fold(0u128, |acc, &x| (acc << 32) | u128::from(x));
    let peaks = wide(&words[0..2]) as u64;
    let mut acc = PointAccumulator::new(range);
    acc.realisations = u64::from(realisations);
    acc.peaks = peaks;
    acc.sum_q = wide(&words[2..4]) as i128 - (i128::from(peaks) << 31);
    acc.sum_q2 = wide(&words[4..7]);
    acc.stick_units = wide(&words[7..9]) as u64;
    acc.clamped = u64::from(words[9]);
    acc.histogram = histogram.iter().map(|&c| u64::from(c)).collect();
    acc
}

/// Runs an ensemble on the GPU and reduces it per point, exactly, on the
/// GPU. Paths (when recorded) are in invocation order: point-major, then
/// realisation. `progress(done, total)` counts integrated cycles × paths.
///
/// Memory: points are processed in chunks of at most 2^20 invocations, so
/// the GPU holds at most 48 MiB of path state plus 8 KiB of histogram and
/// 48 B of sums per point of the chunk, whatever the grid size.
pub fn run_ensemble(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    kernels: &Kernels,
    request: &EnsembleRequest<'_>,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<EnsembleOutput> {
    validate_request(request)?;
    let limits = device.limits();
    let rpp = u64::from(request.realisations_per_point);
    let total_invocations = request.points.len() as u64 * rpp;
    let plan = request.plan;
    let total_cycles = plan.warmup_cycles + plan.measured_cycles;
    let steps = u64::from(request.points[0].oscillator.steps_per_period);
    let binding_limit = u64::from(limits.max_storage_buffer_binding_size).min(limits.max_buffer_size);
    // Invocations per chunk: whole points, within the dispatch and binding limits.
    let max_invocations = (1u64 << 20)
        .min(binding_limit / std::mem::size_of::<PathState>() as u64)
        .min(binding_limit / 4);
    let bytes_per_point = u64::from(HISTOGRAM_BINS) * 4;
    let points_per_chunk = (max_invocations / rpp).max(1).min(binding_limit / bytes_per_point);
    if rpp > max_invocations {
        return Err(Error::setting(
            "realisations",
            format!("{rpp} realisations per point exceed one dispatch ({max_invocations}); split them with --shard"),
        ));
    }
    let mut results = Vec::with_capacity(if request.record_peaks { total_invocations as usize } else { 0 });
    let mut accumulators = Vec::with_capacity(request.points.len());
    let work_total = total_invocations * u64::from(total_cycles);
    let mut work_done = 0u64;
    for chunk in request.points.chunks(points_per_chunk as usize){
        let invocations = (chunk.len() as u64 * rpp) as u32;
        let loop_bound = chunk.iter().map(|p| loop_iterations_per_cycle(&p.oscillator)).max().unwrap_or(1);
        let cycles_per_dispatch = (request.steps_per_dispatch / (u64::from(invocations) * steps))
            .min(LOOP_ITERATIONS_PER_DISPATCH / loop_bound)
            .clamp(1, u64::from(total_cycles.max(1)))
            .min(binding_limit / (4 * u64::from(invocations))) as u32;
        let mut params = params_for(&chunk[0].oscillator, request);
        params.invocations = invocations;
        let grid: Vec<GridPoint> = chunk.iter().map(GridPoint::from_spec).collect();
        let effects_uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("effects"),
            contents: bytemuck::bytes_of(&Effects::from_oscillator(&chunk[0].oscillator)),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let points_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("grid points"),
            contents: bytemuck::cast_slice(&grid),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("params"),
            size: std::mem::size_of::<Params>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let states = storage_buffer(device, "path states", u64::from(invocations) * std::mem::size_of::<PathState>() as u64);
        let peaks_len = if request.record_peaks { u64::from(invocations) * u64::from(cycles_per_dispatch) } else { 1 };
        let peaks = storage_buffer(device, "peaks", peaks_len * 4);
        let sums_bytes = (chunk.len() * ACCUMULATOR_WORDS * 4) as u64;
        let sums = storage_buffer(device, "point sums", sums_bytes);
        let histogram_bytes = chunk.len() as u64 * bytes_per_point;
        let histograms = storage_buffer(device, "histograms", histogram_bytes);
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("ensemble"),
            layout: &kernels.ensemble_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: points_buffer.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: states.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: peaks.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: sums.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 5, resource: histograms.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 6, resource: effects_uniform.as_entire_binding() },
            ],
        });
        let dispatch = |pipeline: &wgpu::ComputePipeline, params: &Params| {
            queue.write_buffer(&uniform, 0, bytemuck::bytes_of(params));
            let mut encoder = device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &bind, &[]);
                pass.dispatch_workgroups(workgroups(invocations), 1, 1);
            }
            queue.submit([encoder.finish()]);
        };
        dispatch(&kernels.init_paths, &params);
        let mut chunk_peaks: Vec<Vec<f64>> = if request.record_peaks {
            vec![Vec::with_capacity(plan.measured_cycles as usize); invocations as usize]
        } else {
            Vec::new()
        };
        let mut first_cycle = 0;
        while first_cycle < total_cycles {
            let cycles = cycles_per_dispatch.min(total_cycles - first_cycle);
            params.first_cycle = first_cycle;
            params.cycles = cycles;
            dispatch(&kernels.run_cycles, &params);
            let measured_from = plan.warmup_cycles.saturating_sub(first_cycle).min(cycles);
            if request.record_peaks && measured_from < cycles {
                let bytes = read_back(device, queue, &peaks, u64::from(invocations) * u64::from(cycles) * 4)?;
                let values: &[f32] = bytemuck::cast_slice(&bytes);
                for (n, path_peaks) in chunk_peaks.iter_mut().enumerate() {
                    let row = &values[n * cycles as usize..(n + 1) * cycles as usize];
                    path_peaks.extend(row[measured_from as usize..].iter().map(|&p| f64::from(p)));
                }
            } else {
                device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| Error::Gpu(e.to_string()))?;
            }
            first_cycle += cycles;
            work_done += u64::from(invocations) * u64::from(cycles);
            progress(work_done, work_total);
        }
        let state_bytes = read_back(device, queue, &states, u64::from(invocations) * std::mem::size_of::<PathState>() as u64)?;
        let final_states: &[PathState] = bytemuck::cast_slice(&state_bytes);
        if let Some(short) = final_states.iter().position(|s| s.period != total_cycles) {
            return Err(Error::Gpu(format!(
                "the driver ended a dispatch early: path {short} completed {} of {total_cycles} cycles; \
                 lower the steps per dispatch",
                final_states[short].period
            )));
        }
        if request.record_peaks {
            for (peaks_m, state) in chunk_peaks.into_iter().zip(final_states) {
                results.push(PathResult { peaks_m, stick_time_s: f64::from(state.stick_time_s) });
            }
        }
        let sum_words = read_back(device, queue, &sums, sums_bytes)?;
        let sum_words: &[u32] = bytemuck::cast_slice(&sum_words);
        let histogram_words = read_back(device, queue, &histograms, histogram_bytes)?;
        let histogram_words: &[u32] = bytemuck::cast_slice(&histogram_words);
        for (i, spec) in chunk.iter().enumerate() {
            accumulators.push(decode_accumulator(
                spec.range,
                request.realisations_per_point,
                &sum_words[i * ACCUMULATOR_WORDS..(i + 1) * ACCUMULATOR_WORDS],
                &histogram_words[i * HISTOGRAM_BINS as usize..(i + 1) * HISTOGRAM_BINS as usize],
            ));
        }
    }
    Ok(EnsembleOutput { paths: request.record_peaks.then_some(results), points: accumulators })
}
