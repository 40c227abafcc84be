// The ensemble kernel's interface: the structs shared with the host
// (src/engine/gpu/shared.rs, checked by tests/integration/layout.rs), the
// bindings, and the two entry points that src/engine/gpu/ensemble.rs
// dispatches. Assembled after the generated constants, rng.wgsl,
// effects.wgsl, oscillator.wgsl and reduce.wgsl (src/engine/gpu/source.rs).

struct Params {
    mass_kg: f32,
    stiffness_n_per_m: f32,
    damping_n_s_per_m: f32,
    base_amplitude_m: f32,
    friction_a: f32,
    friction_b: f32,
    friction_c_s_per_m: f32,
    friction_d_s2_per_m2: f32,
    friction_sigma: f32,
    normal_force_sigma_n: f32,
    warmup_cycles: u32,
    seed_lo: u32,
    seed_hi: u32,
    invocations: u32,
    realisations_per_point: u32,
    realisation_offset: u32,
    first_cycle: u32,
    cycles: u32,
    point_offset: u32,
    // 1: also write every measured peak to `peaks` (for path-by-path checks).
    record_peaks: u32,
    // 1: write a sample to `samples` at every noise boundary of the measured
    // cycles (records aligned with the noise).
    record_samples: u32,
    // Samples per path in `samples`: the most noise boundaries one dispatch crosses.
    sample_slots: u32,
}

// The effects (src/engine/effects.rs EffectParams); forms are the codes of
// the generated FORM constants. All strengths zero is the baseline.
struct EffectParams {
    harmonic_form: u32,
    harmonic_shape: f32,
    harmonic_shape_mean: f32,
    non_gaussian_form: u32,
    harmonic_phase_1_rad: f32,
    harmonic_phase_2_rad: f32,
    harmonic_phase_3_rad: f32,
    harmonic_phase_4_rad: f32,
    hysteresis_form: u32,
    hysteresis_length_m: f32,
    hysteresis_lag_s: f32,
    colour_form: u32,
    colour_rho: f32,
    colour_share: f32,
    colour_rho_1: f32,
    colour_rho_2: f32,
    colour_rho_3: f32,
    colour_hold_intervals: u32,
    stiction_form: u32,
    stiction_excess: f32,
    stiction_release_m: f32,
    stiction_dwell_s: f32,
    drift_form: u32,
    drift_rate_per_s: f32,
    noise_interval_s: f32,
    drift_curvature_per_s2: f32,
    // B of hysteresis `ageing`, –.
    hysteresis_strength: f32,
    // Adhesion force A of load dependence `adhesion`, N.
    adhesion_force_n: f32,
}

struct GridPoint {
    omega_rad_per_s: f32,
    period_s: f32,
    normal_force_mean_n: f32,
    noise_interval_whole: u32,
    noise_interval_frac: u32,
    initial_x_m: f32,
    initial_v_m_per_s: f32,
    // Reduction: peaks are quantised as round((x − centre) · inv_quantum)
    // and binned from histogram_lo_m at histogram_bins_per_m (src/engine/reduce.rs).
    peak_centre_m: f32,
    inv_quantum_per_m: f32,
    histogram_lo_m: f32,
    histogram_bins_per_m: f32,
    // Load-dependent friction offset Δa at this point's N0, –.
    friction_offset: f32,
    // Non-Gaussian strength at this point's N0, –.
    non_gaussian_strength: f32,
    // The polynomial non-Gaussian form's cubic coefficient at this point's N0, –.
    non_gaussian_cubic: f32,
    // Phases are reduced as their deviation from this angle, rad.
    phase_ref_rad: f32,
    // Normal-force harmonic amplitudes at this point's N0, N.
    harmonic_amplitude_1_n: f32,
    harmonic_amplitude_2_n: f32,
    harmonic_amplitude_3_n: f32,
    harmonic_amplitude_4_n: f32,
    // Factor (N0/Nref)^k of the law's a, b, d (load dependence `scaled`; else 1), –.
    friction_scale: f32,
    // Steps per period at this point (raised by a friction memory, by frequency).
    steps_per_period: u32,
    // Added to params.realisation_offset for this point's realisation numbers.
    realisation_offset: u32,
    // Where a normal-force drift's clock starts, s from the run's start (the end of the warm-up).
    drift_start_s: f32,
}

struct PathState {
    x_m: f32,
    v_m_per_s: f32,
    mode: i32,
    period: u32,
    interval: u32,
    next_boundary_whole: u32,
    next_boundary_frac: u32,
    friction_noise: f32,
    normal_force_n: f32,
    stick_time_s: f32,
    slip_start_x_m: f32,
    colour_state: f32,
    interval_phase: f32,
    stiction_excess: f32,
    colour_state_1: f32,
    colour_state_2: f32,
    // μ_f of hysteresis `lag` and `slip` (–), θ of `ageing` (s).
    memory: f32,
    stick_since_s: f32,
    ageing_excess: f32,
    // The `random_walk` drift's walk W (N0 is times 1 + W), –.
    drift_walk: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> points: array<GridPoint>;
@group(0) @binding(2) var<storage, read_write> states: array<PathState>;
// Per path and recorded cycle: (peak, phase) when params.record_peaks is 1.
@group(0) @binding(3) var<storage, read_write> peaks: array<f32>;
// Per grid point: ACCUMULATOR_WORDS words of exact integer sums.
@group(0) @binding(4) var<storage, read_write> accumulators: array<atomic<u32>>;
// Per grid point: HISTOGRAM_BINS counts (first: below range, last: above).
@group(0) @binding(5) var<storage, read_write> histograms: array<atomic<u32>>;
@group(0) @binding(6) var<uniform> effects: EffectParams;
// Per path and noise boundary crossed in this dispatch (slot k: the k-th
// boundary): (x m, v m/s, N N, friction force N) when params.record_samples
// is 1; the host picks the slots of the measured boundaries.
@group(0) @binding(7) var<storage, read_write> samples: array<f32>;

// This invocation's first slot in `samples`, and its noise interval index
// when the dispatch began.
var<private> sample_row: u32;
var<private> interval_at_dispatch: u32;

// Writes the sample of the noise boundary just crossed, at local time t_s in
// the period (s), after the new interval's noise was drawn (the CPU's
// aligned Sampler).
fn record_sample(t_s: f32) {
    let slot = path.interval - interval_at_dispatch - 1u;
    if (slot >= params.sample_slots) {
        return;
    }
    let at = 4u * (sample_row + slot);
    samples[at] = path.x_m;
    samples[at + 1u] = path.v_m_per_s;
    samples[at + 2u] = path.normal_force_n;
    samples[at + 3u] = friction_force(trig_at(point.omega_rad_per_s * t_s));
}

fn load_invocation(n: u32) {
    point_index = n / params.realisations_per_point;
    point = points[params.point_offset + point_index];
    realisation = params.realisation_offset + point.realisation_offset + n % params.realisations_per_point;
    key = vec2<u32>(params.seed_lo, params.seed_hi);
    law_a = params.friction_a * point.friction_scale;
    law_b = params.friction_b * point.friction_scale;
    law_d = params.friction_d_s2_per_m2 * point.friction_scale;
    stick_compliance = 0.0;
    if (effects.hysteresis_form == HYSTERESIS_FORM_BRISTLE) {
        stick_compliance = bristle_compliance(params.stiffness_n_per_m,
            (law_a + point.friction_offset + law_b) * point.normal_force_mean_n, effects.hysteresis_length_m);
    }
}

fn store_path(n: u32) {
    states[n] = PathState(path.x_m, path.v_m_per_s, path.mode, path.period, path.interval,
        path.next_boundary_whole, path.next_boundary_frac, path.friction_noise,
        path.normal_force_n, path.stick_time_s, path.slip_start_x_m, path.colour_state,
        path.interval_phase, path.stiction_excess, path.colour_state_1, path.colour_state_2,
        path.memory, path.stick_since_s, path.ageing_excess, path.drift_walk);
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn init_paths(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = gid.x + gid.y * MAX_WORKGROUPS_PER_DIMENSION * WORKGROUP_SIZE;
    if (n >= params.invocations) {
        return;
    }
    load_invocation(n);
    path.x_m = point.initial_x_m;
    path.v_m_per_s = point.initial_v_m_per_s;
    path.period = 0u;
    path.interval = 0u;
    path.next_boundary_whole = point.noise_interval_whole;
    path.next_boundary_frac = point.noise_interval_frac;
    path.stick_time_s = 0.0;
    path.slip_start_x_m = path.x_m;
    path.colour_state = 0.0;
    path.colour_state_1 = 0.0;
    path.colour_state_2 = 0.0;
    path.interval_phase = 0.0;
    path.mode = MODE_STICK;
    path.stick_since_s = 0.0;
    path.memory = 0.0;
    path.ageing_excess = 0.0;
    path.drift_walk = 0.0;
    draw_noise();
    if (path.v_m_per_s > 0.0) {
        path.mode = 1;
    } else if (path.v_m_per_s < 0.0) {
        path.mode = -1;
    } else {
        path.mode = stick_or_slip(vec2<f32>(1.0, 0.0));
    }
    if (path.mode == MODE_STICK) {
        start_stick(0.0, vec2<f32>(1.0, 0.0));
    } else if (memory_form() != MEMORY_AGEING) {
        // The contact age starts at 0 whether the block sticks or slips.
        path.memory = breakaway_memory();
    }
    store_path(n);
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn run_cycles(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = gid.x + gid.y * MAX_WORKGROUPS_PER_DIMENSION * WORKGROUP_SIZE;
    if (n >= params.invocations) {
        return;
    }
    load_invocation(n);
    let s = states[n];
    path = Path(s.x_m, s.v_m_per_s, s.mode, s.period, s.interval, s.next_boundary_whole,
        s.next_boundary_frac, s.friction_noise, s.normal_force_n, s.stick_time_s,
        s.slip_start_x_m, s.colour_state, s.interval_phase, s.stiction_excess, s.colour_state_1,
        s.colour_state_2, s.memory, s.stick_since_s, s.ageing_excess, s.drift_walk, 0.0, 0.0, 0.0, 0.0);
    // A stuck block's anchor from where it rests, the base at the period's
    // start (the states keep no anchor).
    stick_anchor_m = anchor_of(vec2<f32>(1.0, 0.0));
    sample_row = n * params.sample_slots;
    interval_at_dispatch = s.interval;
    tally = Tally(0u, vec2<u32>(0u), vec3<u32>(0u), vec2<u32>(0u), 0u, vec2<u32>(0u), vec2<u32>(0u), 0u, 0u);
    for (var c = 0u; c < params.cycles; c++) {
        let measuring = params.first_cycle + c >= params.warmup_cycles;
        run_period(measuring);
        if (measuring) {
            let phase = phase_of(path.period_cos_integral, path.period_sin_integral);
            if (params.record_peaks != 0u) {
                peaks[2u * (n * params.cycles + c)] = path.period_max_x_m;
                peaks[2u * (n * params.cycles + c) + 1u] = phase;
            }
            tally_period(path.period_max_x_m, phase, path.period_stick_s / point.period_s);
            path.stick_time_s += path.period_stick_s;
        }
    }
    flush_tally();
    store_path(n);
}
