//! The dispatch loop of the ensemble kernel (`shaders/ensemble.wgsl`): path
//! state lives in a storage buffer between dispatches, each invocation
//! integrates one realisation for a few cycles per dispatch, and peaks are
//! reduced exactly on the GPU into per-point sums and histograms.
//!
//! Memory: points are processed in chunks of at most 2^20 invocations, so
//! the GPU holds at most 48 MiB of path state plus 8 KiB of histogram and
//! 48 B of sums per point of the chunk, whatever the grid size.

use wgpu::util::DeviceExt;

use crate::engine::gpu::shared::{EffectParams, GridPoint, Params, PathState};
use crate::engine::gpu::{
    GpuContext, LOOP_ITERATIONS_PER_DISPATCH, loop_iterations_per_cycle, read_back, storage_buffer, workgroups,
};
use crate::engine::oscillator::{Oscillator, PathResult};
use crate::engine::reduce::{HISTOGRAM_BINS, PeakRange, PointAccumulator};
use crate::engine::{GpuOptions, Job, Output, Record};
use crate::error::{Error, Result};

/// Events one invocation handles within a segment before it forces progress
/// (the CPU allows 64; see the table in `engine/cpu/oscillator.rs`).
pub const MAX_EVENTS_PER_SEGMENT: u32 = 16;
/// Halvings of the step that probe for motion after a start from rest (CPU: 60).
pub const PROBE_HALVINGS: u32 = 30;
/// Illinois iterations locating a velocity zero (CPU: 100).
pub const ILLINOIS_ITERATIONS: u32 = 40;
/// Illinois stops when the bracket is below this fraction of the step (CPU: 1e-15).
pub const ILLINOIS_TOLERANCE: f64 = 2e-7;
/// Within a span, the base's trig is recomputed exactly every this many
/// steps (the CPU carries it through the whole span: f32 rotations drift).
pub const TRIG_REFRESH_STEPS: u32 = 16;
/// Words of one point's accumulator in `reduce.wgsl`.
pub const ACCUMULATOR_WORDS: usize = 16;

/// Checks that a job can run on the GPU: one rig and friction law for all
/// points, noise intervals and periods that fit the kernel's counters.
fn validate(job: &Job<'_>, oscillators: &[Oscillator]) -> Result<()> {
    let cycles = job.plan.total_cycles();
    if u64::from(job.realisations) * u64::from(job.plan.measured_cycles) >= 1 << 32 {
        return Err(Error::setting("run size", "realisations × measured cycles per point must stay below 2^32"));
    }
    let shared = |o: &Oscillator| {
        let mut effects = o.effects.clone();
        effects.friction_offset = 0.0;
        effects.non_gaussian_strength = 0.0;
        // Per point on the GPU too (`GridPoint`): they scale with N0.
        effects.harmonic_amplitudes_n = [0.0; 4];
        Oscillator {
            omega_rad_per_s: 0.0,
            period_s: 0.0,
            normal_force_mean_n: 0.0,
            noise_interval_fixed: 0,
            effects,
            ..o.clone()
        }
    };
    let first = shared(&oscillators[0]);
    for o in oscillators {
        if shared(o) != first {
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
    acc.sum_phase_sin = wide(&words[10..12]) as i128 - (i128::from(peaks) << 31);
    acc.sum_phase_versine = wide(&words[12..14]);
    acc.non_finite = u64::from(words[14]);
    acc.histogram = histogram.iter().map(|&c| u64::from(c)).collect();
    acc
}

/// Runs a job's sums (and peaks, for [`Record::Peaks`]) on the GPU. Paths
/// are in invocation order: point-major, then realisation.
pub fn run(ctx: &GpuContext, options: GpuOptions, job: &Job<'_>, progress: &mut dyn FnMut(u64, u64)) -> Result<Output> {
    let (device, queue, kernels) = (&ctx.device, &ctx.queue, &ctx.kernels);
    let oscillators = job.oscillators()?;
    validate(job, &oscillators)?;
    let record_peaks = job.record == Record::Peaks;
    let limits = device.limits();
    let rpp = u64::from(job.realisations);
    let total_invocations = job.points.len() as u64 * rpp;
    let plan = job.plan;
    let total_cycles = plan.warmup_cycles + plan.measured_cycles;
    // The most steps of any point (hysteresis `lag` raises them where its
    // memory time is shorter than a step, by frequency).
    let steps = oscillators.iter().map(|o| u64::from(o.steps_per_period)).max().unwrap_or(1);
    let binding_limit = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
    // Invocations per chunk: whole points, within the dispatch and binding limits.
    let max_invocations =
        (1u64 << 20).min(binding_limit / std::mem::size_of::<PathState>() as u64).min(binding_limit / 4);
    let bytes_per_point = u64::from(HISTOGRAM_BINS) * 4;
    let points_per_chunk = (max_invocations / rpp).max(1).min(binding_limit / bytes_per_point);
    if rpp > max_invocations {
        return Err(Error::setting(
            "realisations",
            format!("{rpp} realisations per point exceed one dispatch ({max_invocations}); split them with --shard"),
        ));
    }
    let mut output = Output {
        sums: Vec::with_capacity(job.points.len()),
        paths: Vec::with_capacity(if record_peaks { total_invocations as usize } else { 0 }),
        records: Vec::new(),
    };
    let work_total = job.work();
    let mut work_done = 0u64;
    let chunk_len = points_per_chunk as usize;
    for (chunk, chunk_oscillators) in job.points.chunks(chunk_len).zip(oscillators.chunks(chunk_len)) {
        let invocations = (chunk.len() as u64 * rpp) as u32;
        let loop_bound = chunk_oscillators.iter().map(loop_iterations_per_cycle).max().unwrap_or(1);
        let cycles_per_dispatch = (options.steps_per_dispatch / (u64::from(invocations) * steps))
            .min(LOOP_ITERATIONS_PER_DISPATCH / loop_bound)
            .clamp(1, u64::from(total_cycles.max(1)))
            .min(binding_limit / (8 * u64::from(invocations))) as u32;
        let mut params =
            Params::new(&chunk_oscillators[0], job.seed, plan, job.realisations, job.first_realisation, record_peaks);
        params.invocations = invocations;
        let grid: Vec<GridPoint> = chunk.iter().zip(chunk_oscillators).map(|(p, o)| GridPoint::new(p, o)).collect();
        let effects_uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("effects"),
            contents: bytemuck::bytes_of(&EffectParams::from_oscillator(&chunk_oscillators[0])),
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
        let states =
            storage_buffer(device, "path states", u64::from(invocations) * std::mem::size_of::<PathState>() as u64);
        // Two floats, the peak and the phase, per path and cycle.
        let peaks_len = if record_peaks { 2 * u64::from(invocations) * u64::from(cycles_per_dispatch) } else { 1 };
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
        let mut chunk_paths: Vec<PathResult> = if record_peaks {
            let capacity = plan.measured_cycles as usize;
            let empty = PathResult {
                peaks_m: Vec::with_capacity(capacity),
                phases_rad: Vec::with_capacity(capacity),
                stick_time_s: 0.0,
            };
            vec![empty; invocations as usize]
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
            if record_peaks && measured_from < cycles {
                let bytes = read_back(device, queue, &peaks, 2 * u64::from(invocations) * u64::from(cycles) * 4)?;
                let values: &[f32] = bytemuck::cast_slice(&bytes);
                let row_len = 2 * cycles as usize;
                for (n, path) in chunk_paths.iter_mut().enumerate() {
                    let row = &values[n * row_len..(n + 1) * row_len];
                    for pair in row[2 * measured_from as usize..].chunks_exact(2) {
                        path.peaks_m.push(f64::from(pair[0]));
                        path.phases_rad.push(f64::from(pair[1]));
                    }
                }
            } else {
                device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| Error::Gpu(e.to_string()))?;
            }
            first_cycle += cycles;
            work_done += u64::from(invocations) * u64::from(cycles);
            progress(work_done, work_total);
        }
        let state_bytes =
            read_back(device, queue, &states, u64::from(invocations) * std::mem::size_of::<PathState>() as u64)?;
        let final_states: &[PathState] = bytemuck::cast_slice(&state_bytes);
        if let Some(short) = final_states.iter().position(|s| s.period != total_cycles) {
            return Err(Error::Gpu(format!(
                "the driver ended a dispatch early: path {short} completed {} of {total_cycles} cycles; \
                 lower the steps per dispatch",
                final_states[short].period
            )));
        }
        if record_peaks {
            for (mut path, state) in chunk_paths.into_iter().zip(final_states) {
                path.stick_time_s = f64::from(state.stick_time_s);
                output.paths.push(path);
            }
        }
        let sum_words = read_back(device, queue, &sums, sums_bytes)?;
        let sum_words: &[u32] = bytemuck::cast_slice(&sum_words);
        let histogram_words = read_back(device, queue, &histograms, histogram_bytes)?;
        let histogram_words: &[u32] = bytemuck::cast_slice(&histogram_words);
        for (i, point) in chunk.iter().enumerate() {
            let acc = decode_accumulator(
                point.range,
                job.realisations,
                &sum_words[i * ACCUMULATOR_WORDS..(i + 1) * ACCUMULATOR_WORDS],
                &histogram_words[i * HISTOGRAM_BINS as usize..(i + 1) * HISTOGRAM_BINS as usize],
            );
            if acc.non_finite > 0 {
                return Err(Error::Diverged {
                    point: point.condition.describe(),
                    message: format!(
                        "{} measured periods produced a non-finite peak or phase (the f32 GPU kernel); the model \
                         drives the oscillator out of range there, so check its parameters",
                        acc.non_finite
                    ),
                });
            }
            output.sums.push(acc);
        }
    }
    Ok(output)
}
