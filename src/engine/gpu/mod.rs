//! The GPU backend: the WGSL kernel (`shaders/`) on a wgpu adapter, in f32,
//! reducing peaks exactly on the GPU.
//!
//! - [`context`]: adapter, device, queue and pipelines;
//! - [`shared`]: the host structs the kernel reads and writes;
//! - [`source`]: the WGSL, assembled after constants generated from Rust;
//! - [`ensemble`]: the dispatch loop; [`check`]: the generator check kernel.

pub mod check;
pub mod context;
pub mod ensemble;
pub mod shared;
pub mod source;

pub use context::{AdapterClass, GpuContext, Kernels};

use crate::engine::oscillator::Oscillator;
use crate::engine::{Backend, BackendKind, GpuOptions, Job, Output, Record};
use crate::error::{Error, Result};

/// Invocations per workgroup in every kernel (`@workgroup_size(WORKGROUP_SIZE)`).
pub const WORKGROUP_SIZE: u32 = 64;
/// Most workgroups per dispatch dimension (WebGPU's guaranteed limit).
pub const MAX_WORKGROUPS_PER_DIMENSION: u32 = 65_535;
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

/// The same bound on a hardware adapter, which runs loops to their end:
/// it only keeps one invocation's chain of steps short of desktop drivers'
/// watchdogs (about 2 s). 65 536 estimated iterations (an upper estimate,
/// [`loop_iterations_per_cycle`]) are about 90 periods at 6 Hz, so a
/// diagnosis's trial (every unit's replicates, 360 periods each) takes a
/// few dispatches where the software bound cut it into some thirty, each
/// waited for and read back. Larger jobs are bounded by
/// [`DEFAULT_STEPS_PER_DISPATCH`] first.
pub const HARDWARE_LOOP_ITERATIONS_PER_DISPATCH: u64 = 65_536;

/// The loop iterations one invocation may run per dispatch on an adapter
/// of class `class`.
pub fn loop_iterations_per_dispatch(class: AdapterClass) -> u64 {
    match class {
        AdapterClass::Software => LOOP_ITERATIONS_PER_DISPATCH,
        AdapterClass::Hardware => HARDWARE_LOOP_ITERATIONS_PER_DISPATCH,
    }
}

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

/// The GPU backend: a context and its dispatch settings.
pub struct GpuBackend {
    ctx: GpuContext,
    options: GpuOptions,
}

impl GpuBackend {
    /// A backend on an opened context.
    pub fn new(ctx: GpuContext, options: GpuOptions) -> GpuBackend {
        GpuBackend { ctx, options }
    }
}

impl Backend for GpuBackend {
    fn kind(&self) -> BackendKind {
        BackendKind::Gpu
    }

    /// Sums and peaks come from the kernel. So do records sampled at the
    /// noise boundaries (`at_noise_boundaries` with the noise on and the
    /// sampling interval equal to the noise interval, as a diagnosis's
    /// replicates are): the kernel writes a sample at each boundary, in f32.
    fn run(&self, job: &Job<'_>, progress: &mut dyn FnMut(u64, u64)) -> Result<Output> {
        ensemble::run(&self.ctx, self.options, job, progress)
    }

    /// Records sampled otherwise (between boundaries, or without noise)
    /// would split the kernel's steps: [`Engine::run`](crate::engine::Engine::run)
    /// runs them on the CPU reference, on the same noise keys.
    fn runs(&self, job: &Job<'_>) -> Result<bool> {
        Ok(match job.record {
            Record::Samples { interval_s, at_noise_boundaries, .. } => {
                ensemble::records_on_gpu(&job.oscillators()?, interval_s, at_noise_boundaries)
            }
            Record::Sums | Record::Peaks => true,
        })
    }
}

/// Waits for the queue and reads a buffer back.
pub(crate) fn read_back(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
    size: u64,
) -> Result<Vec<u8>> {
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

pub(crate) fn storage_buffer(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

pub(crate) fn workgroups(invocations: u32) -> u32 {
    invocations.div_ceil(WORKGROUP_SIZE)
}
