// The friction oscillator, one realisation per invocation, in f32.
// This is src/cpu.rs's algorithm (same function names, same order): fixed
// steps per excitation period, steps split at noise-interval boundaries,
// RK4 in slip with the slip direction frozen, velocity zeros located by root
// finding on the RK4 map, breakaway from stick in closed form.
// Time inside a period comes from the integer step counter, never from
// accumulating dt; noise boundaries are 32.32 fixed-point positions in periods.
// Requires philox.wgsl.

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
    steps_per_period: u32,
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
    histogram_bins: u32,
}

// The effects (src/effects.rs); forms are 0 = the candidate form. All
// strengths zero reduces every formula to the baseline's arithmetic.
struct Effects {
    harmonic_form: u32,
    harmonic_shape: f32,
    harmonic_shape_mean: f32,
    non_gaussian_form: u32,
    harmonic_amplitude_1_n: f32,
    harmonic_amplitude_2_n: f32,
    harmonic_amplitude_3_n: f32,
    harmonic_amplitude_4_n: f32,
    harmonic_phase_1_rad: f32,
    harmonic_phase_2_rad: f32,
    harmonic_phase_3_rad: f32,
    harmonic_phase_4_rad: f32,
    hysteresis_form: u32,
    hysteresis_length_m: f32,
    colour_form: u32,
    colour_rho: f32,
    colour_hold_intervals: u32,
    stiction_form: u32,
    stiction_excess: f32,
    drift_form: u32,
    drift_rate_per_s: f32,
    noise_interval_s: f32,
    stiction_release_m: f32,
    _pad1: u32,
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
    // and binned from histogram_lo_m at histogram_bins_per_m (src/reduce.rs).
    peak_centre_m: f32,
    inv_quantum_per_m: f32,
    histogram_lo_m: f32,
    histogram_bins_per_m: f32,
    // Load-dependent friction offset Δa at this point's N0, –.
    friction_offset: f32,
    // Non-Gaussian strength at this point's N0, –.
    non_gaussian_strength: f32,
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
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> points: array<GridPoint>;
@group(0) @binding(2) var<storage, read_write> states: array<PathState>;
@group(0) @binding(3) var<storage, read_write> peaks: array<f32>;
// Per grid point: ACCUMULATOR_WORDS words of exact integer sums.
@group(0) @binding(4) var<storage, read_write> accumulators: array<atomic<u32>>;
// Per grid point: histogram_bins counts (first: below range, last: above).
@group(0) @binding(5) var<storage, read_write> histograms: array<atomic<u32>>;
@group(0) @binding(6) var<uniform> effects: Effects;

// Accumulator words: 0-1 peaks (u64), 2-3 Σ(q + 2^31) (u64), 4-6 Σq² (u96),
// 7-8 stuck time in T/2^20 (u64), 9 clamped peaks, 10-11 unused.
const ACCUMULATOR_WORDS: u32 = 12u;

const MODE_STICK: i32 = 0;
const MAX_EVENTS_PER_SEGMENT: u32 = 16u;
const TAU: f32 = 6.283185307179586;
const FIXED_ONE_INV: f32 = 2.3283064365386963e-10; // 2^-32

// The realisation being integrated (module-private, like `self` on the CPU).
struct Path {
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
    period_max_x_m: f32,
    period_stick_s: f32,
}

var<private> path: Path;
var<private> point: GridPoint;
var<private> realisation: u32;
var<private> key: vec2<u32>;

fn harmonic_wave(c: f32) -> f32 {
    if (effects.harmonic_form == 1u) {
        return pow(max(c, 0.0), effects.harmonic_shape) - effects.harmonic_shape_mean;
    }
    if (effects.harmonic_form == 2u) {
        return tanh(effects.harmonic_shape * c) / tanh(effects.harmonic_shape);
    }
    return c;
}

fn harmonic_term(amplitude_n: f32, phase_rad: f32, multiple: f32, theta: f32) -> f32 {
    if (amplitude_n == 0.0) {
        return 0.0;
    }
    return amplitude_n * harmonic_wave(cos(multiple * theta + phase_rad));
}

fn non_gaussian(s: f32, g: f32, g2: f32) -> f32 {
    if (effects.non_gaussian_form == 1u) {
        if (s == 0.0) {
            return g;
        }
        let v = s * s;
        return (exp(s * g) - exp(0.5 * v)) / sqrt((exp(v) - 1.0) * exp(v));
    }
    if (effects.non_gaussian_form == 2u) {
        return g * exp(0.5 * s * g * g) * pow(1.0 - 2.0 * s, 0.75);
    }
    return (g + s * (g2 * g2 - 1.0) * 0.7071067811865476) / sqrt(1.0 + s * s);
}

fn hysteresis_factor(slipped_m: f32) -> f32 {
    let length = effects.hysteresis_length_m;
    if (length == 0.0) {
        return 1.0;
    }
    let r = slipped_m / length;
    if (effects.hysteresis_form == 1u) {
        return tanh(r);
    }
    if (effects.hysteresis_form == 2u) {
        return r / (r + 1.0);
    }
    return 1.0 - exp(-r);
}

fn drift_factor(t_s: f32) -> f32 {
    let rate = effects.drift_rate_per_s;
    if (effects.drift_form == 1u) {
        return 1.0 + rate * 20.0 * (1.0 - exp(-t_s / 20.0));
    }
    if (effects.drift_form == 2u) {
        return 1.0 + rate * 15.0 * sin(t_s / 15.0);
    }
    return 1.0 + rate * t_s;
}

fn draw_noise() {
    var friction_interval = path.interval;
    if (effects.colour_form == 1u) {
        friction_interval = path.interval / effects.colour_hold_intervals;
    }
    let z = gaussian_pair(key, realisation, STREAM_FRICTION, friction_interval);
    let innovation = sqrt(1.0 - effects.colour_rho * effects.colour_rho);
    var g = z.x;
    if (effects.colour_form == 2u && effects.colour_rho > 0.0) {
        let slow = gaussian_pair(key, realisation, STREAM_COLOUR, path.interval).x;
        path.colour_state = select(effects.colour_rho * path.colour_state + innovation * slow, slow, path.interval == 0u);
        g = 0.7071067811865476 * (z.x + path.colour_state);
    } else if (effects.colour_form == 0u) {
        path.colour_state = select(effects.colour_rho * path.colour_state + innovation * z.x, z.x, path.interval == 0u);
        g = path.colour_state;
    }
    let xi_mu = non_gaussian(point.non_gaussian_strength, g, z.y);
    path.friction_noise = params.friction_sigma * xi_mu;
    let xi_n = gaussian_pair(key, realisation, STREAM_NORMAL_FORCE, path.interval).x;
    let t_s = f32(path.interval) * effects.noise_interval_s;
    let mean_n = point.normal_force_mean_n * drift_factor(t_s);
    let theta = TAU * path.interval_phase;
    let harmonics_n = harmonic_term(effects.harmonic_amplitude_1_n, effects.harmonic_phase_1_rad, 1.0, theta)
        + harmonic_term(effects.harmonic_amplitude_2_n, effects.harmonic_phase_2_rad, 2.0, theta)
        + harmonic_term(effects.harmonic_amplitude_3_n, effects.harmonic_phase_3_rad, 3.0, theta)
        + harmonic_term(effects.harmonic_amplitude_4_n, effects.harmonic_phase_4_rad, 4.0, theta);
    path.normal_force_n = max(mean_n + params.normal_force_sigma_n * xi_n + harmonics_n, 0.0);
    path.stiction_excess = effects.stiction_excess;
    if (effects.stiction_form == 1u) {
        let zs = gaussian_pair(key, realisation, STREAM_STICTION, path.interval).x;
        path.stiction_excess = effects.stiction_excess * max(1.0 + 0.5 * zs, 0.0);
    }
}

fn spring_force(t_local_s: f32, x_m: f32) -> f32 {
    return params.stiffness_n_per_m * (params.base_amplitude_m * cos(point.omega_rad_per_s * t_local_s) - x_m);
}

fn friction_coefficient(speed_m_per_s: f32, v_m_per_s: f32, x_m: f32) -> f32 {
    let slipped_m = abs(x_m - path.slip_start_x_m);
    let law = params.friction_a + point.friction_offset
        + params.friction_b / (1.0 + params.friction_c_s_per_m * speed_m_per_s)
        + params.friction_d_s2_per_m2 * v_m_per_s * v_m_per_s
        + path.friction_noise;
    var mu = law * hysteresis_factor(slipped_m);
    if (effects.stiction_form == 2u) {
        mu += path.stiction_excess * exp(-slipped_m / 1e-4);
    } else if (effects.stiction_form == 0u && effects.stiction_release_m > 0.0) {
        mu += path.stiction_excess * max(1.0 - slipped_m / effects.stiction_release_m, 0.0);
    }
    return max(mu, 0.0);
}

fn breakaway_force() -> f32 {
    let mu_static = params.friction_a + point.friction_offset + params.friction_b + path.friction_noise + path.stiction_excess;
    return max(mu_static, 0.0) * path.normal_force_n;
}

fn slip_acceleration(t_local_s: f32, x_m: f32, v_m_per_s: f32, sign: f32) -> f32 {
    let friction = sign * friction_coefficient(sign * v_m_per_s, v_m_per_s, x_m) * path.normal_force_n;
    return (spring_force(t_local_s, x_m) - params.damping_n_s_per_m * v_m_per_s - friction) / params.mass_kg;
}

fn rk4_slip(t_local_s: f32, x_m: f32, v_m_per_s: f32, h_s: f32, sign: f32) -> vec2<f32> {
    let half = 0.5 * h_s;
    let k1x = v_m_per_s;
    let k1v = slip_acceleration(t_local_s, x_m, v_m_per_s, sign);
    let k2x = v_m_per_s + half * k1v;
    let k2v = slip_acceleration(t_local_s + half, x_m + half * k1x, k2x, sign);
    let k3x = v_m_per_s + half * k2v;
    let k3v = slip_acceleration(t_local_s + half, x_m + half * k2x, k3x, sign);
    let k4x = v_m_per_s + h_s * k3v;
    let k4v = slip_acceleration(t_local_s + h_s, x_m + h_s * k3x, k4x, sign);
    return vec2<f32>(
        x_m + h_s / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
        v_m_per_s + h_s / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v));
}

fn locate_velocity_zero(t_local_s: f32, h_s: f32, sign: f32) -> f32 {
    var lo = 0.0;
    var g_lo = sign * path.v_m_per_s;
    var hi = h_s;
    var g_hi = sign * rk4_slip(t_local_s, path.x_m, path.v_m_per_s, h_s, sign).y;
    if (g_lo <= 0.0) {
        var probe = 0.5 * h_s;
        var found = false;
        for (var i = 0u; i < 30u; i++) {
            let g_probe = sign * rk4_slip(t_local_s, path.x_m, path.v_m_per_s, probe, sign).y;
            if (g_probe > 0.0) {
                lo = probe;
                g_lo = g_probe;
                found = true;
                break;
            }
            hi = probe;
            g_hi = g_probe;
            probe = probe * 0.5;
        }
        if (!found) {
            return hi;
        }
    }
    var side = 0;
    for (var i = 0u; i < 40u; i++) {
        if (hi - lo <= 2e-7 * h_s) {
            break;
        }
        var mid = (lo * g_hi - hi * g_lo) / (g_hi - g_lo);
        if (!(mid > lo && mid < hi)) {
            mid = 0.5 * (lo + hi);
        }
        let g_mid = sign * rk4_slip(t_local_s, path.x_m, path.v_m_per_s, mid, sign).y;
        if (g_mid > 0.0) {
            lo = mid;
            g_lo = g_mid;
            if (side == 1) {
                g_hi = g_hi * 0.5;
            }
            side = 1;
        } else {
            hi = mid;
            g_hi = g_mid;
            if (side == -1) {
                g_lo = g_lo * 0.5;
            }
            side = -1;
        }
    }
    return hi;
}

fn stick_or_slip(t_local_s: f32) -> i32 {
    let force = spring_force(t_local_s, path.x_m);
    if (abs(force) <= breakaway_force()) {
        return MODE_STICK;
    }
    return select(-1, 1, force > 0.0);
}

// Entering cos(θ) >= C+ happens at θ = 2πn − acos(C+); entering
// cos(θ) <= C− at θ = 2πn + acos(C−). Keeps `best` unless this entry is earlier.
fn earliest_entry(best: vec2<f32>, sign: f32, phase_a: f32, reach: f32, t_a: f32, t_b: f32) -> vec2<f32> {
    let level = (path.x_m + sign * reach) / params.base_amplitude_m;
    if (level < -1.0 || level > 1.0) {
        return best;
    }
    let w = point.omega_rad_per_s;
    let base = -sign * acos(level);
    let n = ceil((phase_a - base) / TAU);
    let t = (base + n * TAU) / w;
    if (t <= t_b && (best.y == 0.0 || t < best.x)) {
        return vec2<f32>(max(t, t_a), sign);
    }
    return best;
}

// Earliest (time, direction) of breakaway in [t_a, t_b]; direction 0 = none.
fn breakaway_time(t_a: f32, t_b: f32) -> vec2<f32> {
    let force = spring_force(t_a, path.x_m);
    let threshold = breakaway_force();
    if (force > threshold) {
        return vec2<f32>(t_a, 1.0);
    }
    if (force < -threshold) {
        return vec2<f32>(t_a, -1.0);
    }
    if (params.base_amplitude_m == 0.0) {
        return vec2<f32>(t_b, 0.0);
    }
    let phase_a = point.omega_rad_per_s * t_a;
    let reach = threshold / params.stiffness_n_per_m;
    var best = vec2<f32>(t_b, 0.0);
    best = earliest_entry(best, 1.0, phase_a, reach, t_a, t_b);
    best = earliest_entry(best, -1.0, phase_a, reach, t_a, t_b);
    return best;
}

fn advance_segment(t_start: f32, t_b: f32, measuring: bool) {
    var t_a = t_start;
    var events = 0u;
    loop {
        if (!(t_a < t_b)) {
            break;
        }
        if (path.mode == MODE_STICK) {
            var until = vec2<f32>(t_b, 0.0);
            if (events < MAX_EVENTS_PER_SEGMENT) {
                until = breakaway_time(t_a, t_b);
            }
            let t_end = select(until.x, t_b, until.y == 0.0);
            if (measuring) {
                path.period_stick_s += t_end - t_a;
            }
            path.mode = i32(until.y);
            path.slip_start_x_m = path.x_m;
            t_a = t_end;
            events += 1u;
        } else {
            let sign = f32(path.mode);
            let h = t_b - t_a;
            let y1 = rk4_slip(t_a, path.x_m, path.v_m_per_s, h, sign);
            if (sign * y1.y > 0.0) {
                path.x_m = y1.x;
                path.v_m_per_s = y1.y;
                path.period_max_x_m = max(path.period_max_x_m, y1.x);
                t_a = t_b;
            } else {
                let h_zero = locate_velocity_zero(t_a, h, sign);
                let x_zero = rk4_slip(t_a, path.x_m, path.v_m_per_s, h_zero, sign).x;
                path.x_m = x_zero;
                path.v_m_per_s = 0.0;
                path.period_max_x_m = max(path.period_max_x_m, x_zero);
                t_a = t_a + h_zero;
                if (events < MAX_EVENTS_PER_SEGMENT) {
                    path.mode = stick_or_slip(t_a);
                } else {
                    path.mode = MODE_STICK;
                }
                path.slip_start_x_m = path.x_m;
                events += 1u;
            }
        }
    }
}

fn run_period(measuring: bool) {
    let steps = params.steps_per_period;
    let dt = point.period_s / f32(steps);
    path.period_max_x_m = path.x_m;
    path.period_stick_s = 0.0;
    var t = 0.0;
    var step = 0u;
    loop {
        let step_end = select(f32(step + 1u) * dt, point.period_s, step + 1u == steps);
        var noise_t = 3.0e38;
        if (path.next_boundary_whole == path.period) {
            // Position of the boundary in steps: frac * steps / 2^32, exactly.
            let position = mulhilo(path.next_boundary_frac, steps);
            noise_t = (f32(position.x) + f32(position.y) * FIXED_ONE_INV) * dt;
        }
        let target_t = max(min(step_end, noise_t), t);
        advance_segment(t, target_t, measuring);
        t = target_t;
        if (noise_t <= target_t) {
            path.interval_phase = f32(path.next_boundary_frac) * FIXED_ONE_INV;
            path.interval += 1u;
            let frac = path.next_boundary_frac + point.noise_interval_frac;
            let carry = select(0u, 1u, frac < path.next_boundary_frac);
            path.next_boundary_frac = frac;
            path.next_boundary_whole += point.noise_interval_whole + carry;
            draw_noise();
        }
        if (step_end <= target_t) {
            step += 1u;
            if (step == steps) {
                break;
            }
        }
    }
    // Counted only when the step loop really finished: a loop ended early by
    // the driver leaves the count short, and the host refuses the result.
    if (step == steps) {
        path.period += 1u;
    }
}

// This invocation's sums over the dispatch, flushed once at its end.
struct Tally {
    peaks: u32,
    sum_biased: vec2<u32>,
    sum_squares: vec3<u32>,
    stick_units: vec2<u32>,
    clamped: u32,
}

var<private> tally: Tally;
var<private> point_index: u32;

fn add_u64(a: vec2<u32>, b: u32) -> vec2<u32> {
    let lo = a.x + b;
    return vec2<u32>(lo, a.y + select(0u, 1u, lo < b));
}

// a (96 bits) + b (64 bits: lo, hi)
fn add_u96(a: vec3<u32>, b: vec2<u32>) -> vec3<u32> {
    let lo = a.x + b.x;
    let carry0 = select(0u, 1u, lo < b.x);
    let mid0 = a.y + b.y;
    let carry1 = select(0u, 1u, mid0 < b.y);
    let mid = mid0 + carry0;
    let carry2 = select(0u, 1u, mid < carry0);
    return vec3<u32>(lo, mid, a.z + carry1 + carry2);
}

// The histogram bin of a peak; mirrors PeakRange::bin.
fn histogram_bin(peak_m: f32) -> u32 {
    let inner = params.histogram_bins - 2u;
    let position = (peak_m - point.histogram_lo_m) * point.histogram_bins_per_m;
    if (position < 0.0) {
        return 0u;
    }
    if (position >= f32(inner)) {
        return inner + 1u;
    }
    return u32(position) + 1u;
}

// Quantises and tallies one measured period; mirrors PointAccumulator::add_period.
fn tally_period(peak_m: f32, stuck_share: f32) {
    let limit = 2147483520.0;
    let q_real = round((peak_m - point.peak_centre_m) * point.inv_quantum_per_m);
    let q = i32(clamp(q_real, -limit, limit));
    tally.peaks += 1u;
    tally.sum_biased = add_u64(tally.sum_biased, bitcast<u32>(q) ^ 0x80000000u);
    let magnitude = u32(abs(q));
    let square = mulhilo(magnitude, magnitude);
    tally.sum_squares = add_u96(tally.sum_squares, vec2<u32>(square.y, square.x));
    tally.stick_units = add_u64(tally.stick_units, u32(round(stuck_share * 1048576.0)));
    tally.clamped += select(0u, 1u, abs(q_real) > limit);
    atomicAdd(&histograms[point_index * params.histogram_bins + histogram_bin(peak_m)], 1u);
}

// Exact multi-word atomic addition: each word's carry is added to the next.
fn atomic_add_u64(word: u32, value: vec2<u32>) {
    let old = atomicAdd(&accumulators[word], value.x);
    let carry = select(0u, 1u, old + value.x < old);
    atomicAdd(&accumulators[word + 1u], value.y + carry);
}

fn atomic_add_u96(word: u32, value: vec3<u32>) {
    let old0 = atomicAdd(&accumulators[word], value.x);
    let carry0 = select(0u, 1u, old0 + value.x < old0);
    let mid = value.y + carry0;
    let carry_mid = select(0u, 1u, mid < carry0);
    let old1 = atomicAdd(&accumulators[word + 1u], mid);
    let carry1 = select(0u, 1u, old1 + mid < old1) + carry_mid;
    atomicAdd(&accumulators[word + 2u], value.z + carry1);
}

fn flush_tally() {
    if (tally.peaks == 0u) {
        return;
    }
    let base = point_index * ACCUMULATOR_WORDS;
    atomic_add_u64(base, vec2<u32>(tally.peaks, 0u));
    atomic_add_u64(base + 2u, tally.sum_biased);
    atomic_add_u96(base + 4u, tally.sum_squares);
    atomic_add_u64(base + 7u, tally.stick_units);
    atomicAdd(&accumulators[base + 9u], tally.clamped);
}

fn load_invocation(n: u32) {
    point_index = n / params.realisations_per_point;
    point = points[params.point_offset + point_index];
    realisation = params.realisation_offset + n % params.realisations_per_point;
    key = vec2<u32>(params.seed_lo, params.seed_hi);
}

fn store_path(n: u32) {
    states[n] = PathState(path.x_m, path.v_m_per_s, path.mode, path.period, path.interval,
        path.next_boundary_whole, path.next_boundary_frac, path.friction_noise,
        path.normal_force_n, path.stick_time_s, path.slip_start_x_m, path.colour_state,
        path.interval_phase, path.stiction_excess);
}

@compute @workgroup_size(64)
fn init_paths(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = gid.x + gid.y * 65535u * 64u;
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
    path.interval_phase = 0.0;
    draw_noise();
    if (path.v_m_per_s > 0.0) {
        path.mode = 1;
    } else if (path.v_m_per_s < 0.0) {
        path.mode = -1;
    } else {
        path.mode = stick_or_slip(0.0);
    }
    store_path(n);
}

@compute @workgroup_size(64)
fn run_cycles(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = gid.x + gid.y * 65535u * 64u;
    if (n >= params.invocations) {
        return;
    }
    load_invocation(n);
    let s = states[n];
    path = Path(s.x_m, s.v_m_per_s, s.mode, s.period, s.interval, s.next_boundary_whole,
        s.next_boundary_frac, s.friction_noise, s.normal_force_n, s.stick_time_s,
        s.slip_start_x_m, s.colour_state, s.interval_phase, s.stiction_excess, 0.0, 0.0);
    tally = Tally(0u, vec2<u32>(0u), vec3<u32>(0u), vec2<u32>(0u), 0u);
    for (var c = 0u; c < params.cycles; c++) {
        let measuring = params.first_cycle + c >= params.warmup_cycles;
        run_period(measuring);
        if (measuring) {
            if (params.record_peaks != 0u) {
                peaks[n * params.cycles + c] = path.period_max_x_m;
            }
            tally_period(path.period_max_x_m, path.period_stick_s / point.period_s);
            path.stick_time_s += path.period_stick_s;
        }
    }
    flush_tally();
    store_path(n);
}
