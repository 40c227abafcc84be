//! The dispatch loop of the ensemble kernel (`shaders/ensemble.wgsl`): path
//! state lives in a storage buffer between dispatches, each invocation
//! integrates one realisation for a few cycles per dispatch, and peaks are
//! reduced exactly on the GPU into per-point sums and histograms. Records
//! sampled at the noise boundaries are written by the kernel (16 B per path
//! and boundary of a dispatch) and read back after each measured dispatch.
//!
//! Memory: points are processed in chunks of at most 2^20 invocations, so
//! the GPU holds at most 48 MiB of path state plus 8 KiB of histogram and
//! 48 B of sums per point of the chunk, whatever the grid size.

use wgpu::util::DeviceExt;

use crate::engine::gpu::shared::{EffectParams, GridPoint, Params, PathState};
use crate::engine::gpu::source::ACCUMULATOR_WORDS;
use crate::engine::gpu::{
    GpuContext, loop_iterations_per_cycle, loop_iterations_per_dispatch, read_back, storage_buffer, workgroups,
};
use crate::engine::oscillator::{Oscillator, PathResult, PeakRange, RunPlan, Sample};
use crate::engine::reduce::{HISTOGRAM_BINS, PointAccumulator};
use crate::engine::schedule::{
    first_boundary_from, first_sampled_interval, noise_boundary_time_s, record_cycles, samples_at_noise_boundaries,
};
use crate::engine::{GpuOptions, Job, Output, Record};
use crate::error::{Error, Result};

/// Checks that a job can run on the GPU with `plan`: one rig and friction
/// law for all points, noise intervals and periods that fit the kernel's
/// counters.
fn validate(job: &Job<'_>, plan: RunPlan, oscillators: &[Oscillator]) -> Result<()> {
    let cycles = plan.total_cycles();
    if u64::from(job.realisations) * u64::from(plan.measured_cycles) >= 1 << 32 {
        return Err(Error::setting("run size", "realisations × measured cycles per point must stay below 2^32"));
    }
    let shared = |o: &Oscillator| {
        let mut effects = o.effects.clone();
        effects.friction_offset = 0.0;
        effects.non_gaussian_strength = 0.0;
        effects.non_gaussian_cubic = 0.0;
        // Per point on the GPU too (`GridPoint`): they scale with N0.
        effects.harmonic_amplitudes_n = [0.0; 4];
        effects.friction_scale = 1.0;
        Oscillator {
            omega_rad_per_s: 0.0,
            period_s: 0.0,
            normal_force_mean_n: 0.0,
            // Per point too: a friction memory raises them by frequency.
            steps_per_period: 0,
            noise_interval_fixed: 0,
            // Per point too: the warm-up's periods last longer at lower frequencies.
            drift_start_s: 0.0,
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

/// A [`Record::Samples`] job the kernel samples itself: its sampler is
/// aligned with the noise ([`samples_at_noise_boundaries`]) at every point,
/// so each record holds one sample per noise boundary from the first at or
/// after the warm-up's end, `samples_per_record` of them at most, exactly
/// like the CPU reference's.
#[derive(Clone, Copy, Debug)]
struct AlignedRecord {
    /// Record length, s.
    duration_s: f64,
    /// Samples each record keeps: `round(duration / interval)`.
    samples_per_record: u64,
}

impl AlignedRecord {
    /// The aligned record a job asks for, or `None` when it asks for none
    /// (the kernel cannot sample a record whose sampler is not aligned).
    fn of(job: &Job<'_>, oscillators: &[Oscillator]) -> Result<Option<AlignedRecord>> {
        let Record::Samples { interval_s, duration_s, at_noise_boundaries } = job.record else {
            return Ok(None);
        };
        if !records_on_gpu(oscillators, interval_s, at_noise_boundaries) {
            return Err(Error::Mismatch(
                "the GPU kernel samples records only at the noise boundaries (interval = the noise interval)".into(),
            ));
        }
        Ok(Some(AlignedRecord { duration_s, samples_per_record: (duration_s / interval_s).round() as u64 }))
    }
}

/// Whether the kernel samples records taken every `interval_s` (s) at these
/// points: when they fall on the noise boundaries at every one of them.
pub(crate) fn records_on_gpu(oscillators: &[Oscillator], interval_s: f64, at_noise_boundaries: bool) -> bool {
    oscillators.iter().all(|o| samples_at_noise_boundaries(o, interval_s, at_noise_boundaries))
}

/// Index of the noise interval in force when period `period` begins (the
/// count of boundaries `j ≥ 1` before it: `j · noise_interval_fixed <
/// period · 2^32`), as the kernel counts them.
fn interval_at_period_start(o: &Oscillator, period: u64) -> u64 {
    first_boundary_from(o, period).saturating_sub(1)
}

/// The most noise boundaries any `cycles` consecutive periods hold.
fn boundaries_within(o: &Oscillator, cycles: u64) -> u64 {
    first_boundary_from(o, cycles)
}

/// Floats per sample in the samples buffer: x, v, N, friction force.
const SAMPLE_FLOATS: u64 = 4;

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
    acc.peak_extremes_m = (peaks > 0).then(|| (-from_order_key(words[16]), from_order_key(words[15])));
    acc.histogram = histogram.iter().map(|&c| u64::from(c)).collect();
    acc
}

/// The f32 whose `order_key` (in `reduce.wgsl`) is `key`.
fn from_order_key(key: u32) -> f32 {
    f32::from_bits(if key & 0x8000_0000 != 0 { key & 0x7fff_ffff } else { !key })
}

/// Runs a job's sums (and peaks, for [`Record::Peaks`]) on the GPU, or its
/// records for a [`Record::Samples`] job whose sampler is aligned with the
/// noise (`records_on_gpu`; no sums then, like the CPU reference). Paths
/// and records are in invocation order: point-major, then realisation.
pub fn run(ctx: &GpuContext, options: GpuOptions, job: &Job<'_>, progress: &mut dyn FnMut(u64, u64)) -> Result<Output> {
    let (device, queue, kernels) = (&ctx.device, &ctx.queue, &ctx.kernels);
    let oscillators = job.oscillators()?;
    let record = AlignedRecord::of(job, &oscillators)?;
    // A record runs the periods the longest point's record needs (each
    // point keeps the samples its own record's periods hold, as on the CPU).
    let plan = match record {
        Some(r) => RunPlan {
            warmup_cycles: job.plan.warmup_cycles,
            measured_cycles: oscillators.iter().map(|o| record_cycles(o, r.duration_s)).max().unwrap_or(1),
        },
        None => job.plan,
    };
    validate(job, plan, &oscillators)?;
    let record_peaks = job.record == Record::Peaks;
    let limits = device.limits();
    let rpp = u64::from(job.realisations);
    let total_invocations = job.points.len() as u64 * rpp;
    let total_cycles = plan.warmup_cycles + plan.measured_cycles;
    // The most steps of any point (a friction memory raises them where its
    // memory time is shorter than a step, by frequency; each point takes
    // its own, `GridPoint::steps_per_period`).
    let steps = oscillators.iter().map(|o| u64::from(o.steps_per_period)).max().unwrap_or(1);
    let binding_limit = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
    // Invocations per chunk: whole points, within the dispatch and binding limits.
    let mut max_invocations =
        (1u64 << 20).min(binding_limit / std::mem::size_of::<PathState>() as u64).min(binding_limit / 4);
    // The most samples one period writes per path (the kernel samples every
    // noise boundary of the measured periods).
    let most_boundaries = |cycles: u64| oscillators.iter().map(|o| boundaries_within(o, cycles)).max().unwrap_or(1);
    let sample_bytes = SAMPLE_FLOATS * 4;
    if record.is_some() {
        max_invocations = max_invocations.min(binding_limit / (sample_bytes * most_boundaries(1)));
    }
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
        records: Vec::with_capacity(if record.is_some() { total_invocations as usize } else { 0 }),
    };
    let work_total = total_invocations * u64::from(total_cycles);
    let mut work_done = 0u64;
    let chunk_len = points_per_chunk as usize;
    for (chunk_index, (chunk, chunk_oscillators)) in
        job.points.chunks(chunk_len).zip(oscillators.chunks(chunk_len)).enumerate()
    {
        let invocations = (chunk.len() as u64 * rpp) as u32;
        let loop_bound = chunk_oscillators.iter().map(loop_iterations_per_cycle).max().unwrap_or(1);
        let mut cycles_per_dispatch = (options.steps_per_dispatch / (u64::from(invocations) * steps))
            .min(loop_iterations_per_dispatch(ctx.adapter_class()) / loop_bound)
            .clamp(1, u64::from(total_cycles.max(1)))
            .min(binding_limit / (8 * u64::from(invocations)));
        if record.is_some() {
            // Every path's samples of one dispatch within the binding limit:
            // `c` periods hold at most ceil(c · 2^32 / interval) boundaries.
            let slots_per_path = binding_limit / (sample_bytes * u64::from(invocations));
            let narrowest = chunk_oscillators.iter().map(|o| o.noise_interval_fixed).min().unwrap_or(1);
            let fitting = ((u128::from(slots_per_path) * u128::from(narrowest)) >> 32) as u64;
            cycles_per_dispatch = cycles_per_dispatch.min(fitting).max(1);
        }
        let cycles_per_dispatch = cycles_per_dispatch as u32;
        let sample_slots = match record {
            Some(_) => chunk_oscillators.iter().map(|o| boundaries_within(o, u64::from(cycles_per_dispatch))).max(),
            None => None,
        }
        .unwrap_or(0);
        let mut params =
            Params::new(&chunk_oscillators[0], job.seed, plan, job.realisations, job.first_realisation, record_peaks);
        params.invocations = invocations;
        params.record_samples = u32::from(record.is_some());
        params.sample_slots = u32::try_from(sample_slots)
            .map_err(|_| Error::setting("sample interval", "too many noise boundaries per period for the GPU"))?;
        let grid: Vec<GridPoint> = chunk.iter().zip(chunk_oscillators).map(|(p, o)| GridPoint::new(p, o)).collect();
        let effects = EffectParams::from_oscillator(&chunk_oscillators[0]);
        let run_cycles = kernels.run_cycles_for(device, &effects);
        let effects_uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("effects"),
            contents: bytemuck::bytes_of(&effects),
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
        let samples_bytes = u64::from(invocations) * sample_slots * sample_bytes;
        let samples = storage_buffer(device, "samples", samples_bytes);
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
                wgpu::BindGroupEntry { binding: 7, resource: samples.as_entire_binding() },
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
        // Per point of the chunk, a record's sampled intervals: from the
        // first at or after the warm-up's end, while the record and its own
        // periods last (`first .. end`).
        let sampled_intervals: Vec<(u64, u64)> = match record {
            Some(r) => chunk_oscillators
                .iter()
                .map(|o| {
                    let first = first_sampled_interval(o, plan.warmup_cycles);
                    let own_periods = u64::from(plan.warmup_cycles) + u64::from(record_cycles(o, r.duration_s));
                    (first, (first + r.samples_per_record).min(interval_at_period_start(o, own_periods) + 1))
                })
                .collect(),
            None => Vec::new(),
        };
        let mut chunk_records: Vec<Vec<Sample>> = sampled_intervals
            .iter()
            .flat_map(|&(first, end)| (0..rpp).map(move |_| Vec::with_capacity(end.saturating_sub(first) as usize)))
            .collect();
        let mut first_cycle = 0;
        while first_cycle < total_cycles {
            let cycles = cycles_per_dispatch.min(total_cycles - first_cycle);
            params.first_cycle = first_cycle;
            params.cycles = cycles;
            dispatch(run_cycles, &params);
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
            } else if record.is_some() && measured_from < cycles {
                let bytes = read_back(device, queue, &samples, samples_bytes)?;
                let values: &[f32] = bytemuck::cast_slice(&bytes);
                let row_len = (sample_slots * SAMPLE_FLOATS) as usize;
                for (n, samples_of_path) in chunk_records.iter_mut().enumerate() {
                    let p = n / rpp as usize;
                    let o = &chunk_oscillators[p];
                    let (first, end) = sampled_intervals[p];
                    let base = interval_at_period_start(o, u64::from(first_cycle));
                    let last = interval_at_period_start(o, u64::from(first_cycle + cycles));
                    let start_s = f64::from(plan.warmup_cycles) * o.period_s;
                    let row = &values[n * row_len..(n + 1) * row_len];
                    for j in first.max(base + 1)..end.min(last + 1) {
                        let at = ((j - base - 1) * SAMPLE_FLOATS) as usize;
                        let Some(&[x, v, normal, friction]) = row.get(at..at + 4) else {
                            return Err(Error::Gpu(format!(
                                "noise interval {j} falls outside the {sample_slots} sample slots of a dispatch"
                            )));
                        };
                        let sample = Sample {
                            t_s: noise_boundary_time_s(o, j) - start_s,
                            x_m: f64::from(x),
                            v_m_per_s: f64::from(v),
                            normal_force_n: f64::from(normal),
                            friction_force_n: f64::from(friction),
                        };
                        if ![x, v, normal, friction].iter().all(|value| value.is_finite()) {
                            let realisation = job.realisation(chunk_index * chunk_len + p, (n as u64 % rpp) as u32);
                            return Err(Error::Diverged {
                                point: chunk[p].condition.describe(),
                                message: format!(
                                    "realisation {realisation} produced a non-finite sample at t = {} s (the f32 GPU \
                                     kernel); the model drives the oscillator out of range there, so check its \
                                     parameters",
                                    sample.t_s
                                ),
                            });
                        }
                        samples_of_path.push(sample);
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
        if record.is_some() {
            // The host's count of noise boundaries (which placed every
            // sample) must be the kernel's.
            for (n, state) in final_states.iter().enumerate() {
                let expected = interval_at_period_start(&chunk_oscillators[n / rpp as usize], u64::from(total_cycles));
                if u64::from(state.interval) != expected {
                    return Err(Error::Gpu(format!(
                        "path {n} crossed {} noise boundaries where the host counts {expected}",
                        state.interval
                    )));
                }
            }
            output.records.extend(chunk_records);
            continue;
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
