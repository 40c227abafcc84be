// The friction oscillator, one realisation per invocation, in f32.
// This is src/engine/cpu/oscillator/'s algorithm (same function names, same
// order): fixed steps per excitation period, steps split at noise-interval
// boundaries, RK4 in slip with the slip direction frozen, velocity zeros
// located by root finding on the RK4 map, breakaway from stick in closed form.
// The base's cos and sin are exact at each step start and carried through the
// step by rotation. Time inside a period comes from the integer step counter,
// never from accumulating dt; noise boundaries are 32.32 fixed-point positions
// in periods. The deliberate f32/f64 differences are tabled in that file's docs.

const MODE_STICK: i32 = 0;
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
    colour_state_1: f32,
    colour_state_2: f32,
    // μ_f of hysteresis `lag` and `slip` (–), the contact age θ of `ageing`
    // (s; while stuck, θ when the stick began), the factor φ₀ the slip's
    // friction turned from under `dahl` (–).
    memory: f32,
    stick_since_s: f32,
    // The static coefficient's contact-age term of `ageing`, –.
    ageing_excess: f32,
    // The `random_walk` drift's walk W (N0 is times 1 + W), –.
    drift_walk: f32,
    period_max_x_m: f32,
    period_stick_s: f32,
    // ∫ x cos(Ωt) dt and ∫ x sin(Ωt) dt over the period so far (phase_of).
    period_cos_integral: f32,
    period_sin_integral: f32,
}

// One RK4 step of the slip ODE with what the phase quadrature needs: the
// stage displacements and the base's (cos, sin) at the step's start, middle
// and end.
struct SlipStep {
    x_m: f32,
    v_m_per_s: f32,
    memory: f32,
    x2_m: f32,
    x3_m: f32,
    x4_m: f32,
    trig0: vec2<f32>,
    trig1: vec2<f32>,
    trig2: vec2<f32>,
}

var<private> path: Path;
var<private> point: GridPoint;
var<private> realisation: u32;
var<private> key: vec2<u32>;
// The law's a, b, d at this point's load (load dependence `scaled`), set
// with the point.
var<private> law_a: f32;
var<private> law_b: f32;
var<private> law_d: f32;
// κ of hysteresis `bristle` (0: a rigid stick), set with the point, and the
// anchored slider's position w while stuck (m; the CPU's Path fields).
var<private> stick_compliance: f32;
var<private> stick_anchor_m: f32;

// (cos, sin) of a phase, and a rotation of one by another.
fn trig_at(theta: f32) -> vec2<f32> {
    return vec2<f32>(cos(theta), sin(theta));
}

fn rotated(a: vec2<f32>, by: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(a.x * by.x - a.y * by.y, a.y * by.x + a.x * by.y);
}

// The normal force's harmonics (N) at the interval's start: Σ A_k w(cos(kθ + φ_k))
// at θ = 2π interval_phase, or the `position` form's αN0 r + βN0 r² with
// r = x_per_u0, the displacement over the base amplitude.
fn harmonics_n(interval_phase: f32, x_per_u0: f32) -> f32 {
    if (point.harmonic_amplitude_1_n == 0.0 && point.harmonic_amplitude_2_n == 0.0
        && point.harmonic_amplitude_3_n == 0.0 && point.harmonic_amplitude_4_n == 0.0) {
        return 0.0;
    }
    if (effects.harmonic_form == HARMONIC_FORM_POSITION) {
        return position_load(point.harmonic_amplitude_1_n, point.harmonic_amplitude_2_n, x_per_u0);
    }
    let theta = TAU * interval_phase;
    return harmonic_term(point.harmonic_amplitude_1_n, effects.harmonic_phase_1_rad, 1.0, theta)
        + harmonic_term(point.harmonic_amplitude_2_n, effects.harmonic_phase_2_rad, 2.0, theta)
        + harmonic_term(point.harmonic_amplitude_3_n, effects.harmonic_phase_3_rad, 3.0, theta)
        + harmonic_term(point.harmonic_amplitude_4_n, effects.harmonic_phase_4_rad, 4.0, theta);
}

fn ar1(state: f32, rho: f32, innovation: f32) -> f32 {
    if (path.interval == 0u) {
        return innovation;
    }
    return rho * state + sqrt(1.0 - rho * rho) * innovation;
}

fn draw_noise() {
    let main = noise_block(key, realisation, STREAM_MAIN, path.interval);
    let a = pair_a(main);
    let white = a.x;
    let xi_n = a.y;
    var friction_block = main;
    var z = white;
    if (effects.colour_form == COLOUR_FORM_HOLD && effects.colour_hold_intervals > 1u) {
        friction_block = noise_block(key, realisation, STREAM_MAIN, path.interval / effects.colour_hold_intervals);
        z = pair_a(friction_block).x;
    }
    var g = z;
    if (effects.colour_rho != 0.0) {
        if (effects.colour_form == COLOUR_FORM_AR1) {
            if (effects.colour_share >= 1.0) {
                path.colour_state = ar1(path.colour_state, effects.colour_rho, z);
                g = path.colour_state;
            } else {
                let c = pair_a(noise_block(key, realisation, STREAM_COLOUR, path.interval)).x;
                path.colour_state = ar1(path.colour_state, effects.colour_rho, c);
                g = sqrt(1.0 - effects.colour_share) * z + sqrt(effects.colour_share) * path.colour_state;
            }
        } else if (effects.colour_form == COLOUR_FORM_TWO_SCALE) {
            let slow = pair_a(noise_block(key, realisation, STREAM_COLOUR, path.interval)).x;
            path.colour_state = ar1(path.colour_state, effects.colour_rho, slow);
            g = 0.7071067811865476 * (z + path.colour_state);
        } else if (effects.colour_form == COLOUR_FORM_MULTI_SCALE) {
            let words = noise_block(key, realisation, STREAM_COLOUR, path.interval);
            let c01 = pair_a(words);
            let c2 = pair_b(words).x;
            path.colour_state = ar1(path.colour_state, effects.colour_rho_1, c01.x);
            path.colour_state_1 = ar1(path.colour_state_1, effects.colour_rho_2, c01.y);
            path.colour_state_2 = ar1(path.colour_state_2, effects.colour_rho_3, c2);
            g = (path.colour_state + path.colour_state_1 + path.colour_state_2) * 0.5773502691896258;
        } else if (effects.colour_form == COLOUR_FORM_FAST_SLOW) {
            let c01 = pair_a(noise_block(key, realisation, STREAM_COLOUR, path.interval));
            path.colour_state = ar1(path.colour_state, effects.colour_rho_1, c01.x);
            path.colour_state_1 = ar1(path.colour_state_1, effects.colour_rho_2, c01.y);
            g = sqrt(1.0 - effects.colour_share) * path.colour_state + sqrt(effects.colour_share) * path.colour_state_1;
        }
    }
    var xi_mu = g;
    if (point.non_gaussian_strength != 0.0 || point.non_gaussian_cubic != 0.0) {
        xi_mu = non_gaussian(point.non_gaussian_strength, point.non_gaussian_cubic, g, pair_b(friction_block).x);
    }
    path.friction_noise = params.friction_sigma * xi_mu;
    let t_s = f32(path.interval) * effects.noise_interval_s;
    // The drift's time, s from the end of the warm-up (where its clock starts).
    let drift_t_s = max(t_s - point.drift_start_s, 0.0);
    if (effects.drift_form == DRIFT_FORM_RANDOM_WALK && path.interval != 0u && t_s > point.drift_start_s) {
        let step = pair_a(noise_block(key, realisation, STREAM_DRIFT, path.interval)).x;
        path.drift_walk += sqrt(effects.drift_rate_per_s * effects.noise_interval_s) * step;
    }
    let mean_n = point.normal_force_mean_n * (drift_factor(drift_t_s) + path.drift_walk);
    let harmonic_part_n = harmonics_n(path.interval_phase, path.x_m / params.base_amplitude_m);
    path.normal_force_n = max(mean_n + params.normal_force_sigma_n * xi_n + harmonic_part_n, 0.0);
    path.stiction_excess = effects.stiction_excess;
    if (effects.stiction_form == STICTION_FORM_NOISY && effects.stiction_excess != 0.0) {
        path.stiction_excess = effects.stiction_excess * max(1.0 + 0.5 * pair_b(main).y, 0.0);
    } else if (effects.stiction_form == STICTION_FORM_DWELL) {
        path.stiction_excess = 0.0;
        if (path.mode == MODE_STICK) {
            path.stiction_excess = dwell_excess(effects.stiction_excess, t_s - path.stick_since_s, effects.stiction_dwell_s);
        }
    }
    if (memory_form() == MEMORY_AGEING && path.mode == MODE_STICK) {
        path.ageing_excess = contact_age_excess(contact_age_at(t_s));
    }
}

// The contact age θ (s) while stuck, held over the interval starting at
// interval_start_s: θ at the stick's start plus the time stuck up to then.
fn contact_age_at(interval_start_s: f32) -> f32 {
    return path.memory + max(interval_start_s - path.stick_since_s, 0.0);
}

// B ln((θ + θ_0)/(θ_c + θ_0)): the static coefficient's contact-age term.
fn contact_age_excess(age_s: f32) -> f32 {
    let cutoff_age_s = effects.hysteresis_length_m / AGEING_CUTOFF_SPEED_M_PER_S;
    let floor_age_s = effects.hysteresis_length_m / AGEING_FLOOR_SPEED_M_PER_S;
    return contact_age_term(age_s, cutoff_age_s, floor_age_s);
}

// A stick starts at t_s (from the run's start, the base at `trig`): dwell
// stiction ages anew, and the slider is anchored where the block rests on it.
fn start_stick(t_s: f32, trig: vec2<f32>) {
    path.stick_since_s = t_s;
    stick_anchor_m = anchor_of(trig);
    if (effects.stiction_form == STICTION_FORM_DWELL) {
        path.stiction_excess = dwell_excess(effects.stiction_excess, 0.0, effects.stiction_dwell_s);
    }
}

// w = (x − κ u) / (1 − κ): where the slider is anchored for the block at x (m).
fn anchor_of(trig: vec2<f32>) -> f32 {
    if (stick_compliance == 0.0) {
        return path.x_m;
    }
    return (path.x_m - stick_compliance * params.base_amplitude_m * trig.x) / (1.0 - stick_compliance);
}

// A stuck block's (x, v): κ u + (1 − κ) w and κ du/dt (m, m/s).
fn stuck_state(trig: vec2<f32>) -> vec2<f32> {
    let moving = stick_compliance * params.base_amplitude_m;
    return vec2<f32>(moving * trig.x + (1.0 - stick_compliance) * stick_anchor_m,
        -moving * point.omega_rad_per_s * trig.y);
}

fn spring_force(cos_omega_t: f32, x_m: f32) -> f32 {
    return params.stiffness_n_per_m * (params.base_amplitude_m * cos_omega_t - x_m);
}

// The law's Stribeck factor 1/(1 + c s), and for s < 0 (an RK4 stage past
// a velocity zero) its first-order continuation 1 − c s: the law's pole at
// s = −1/c is never reached (the CPU reference's `stribeck_factor`).
fn stribeck_factor(c_s_per_m: f32, speed_m_per_s: f32) -> f32 {
    if (speed_m_per_s >= 0.0) {
        return 1.0 / (1.0 + c_s_per_m * speed_m_per_s);
    }
    return 1.0 - c_s_per_m * speed_m_per_s;
}

fn steady_law(speed_m_per_s: f32, v_m_per_s: f32) -> f32 {
    return mean_law(speed_m_per_s, v_m_per_s) + path.friction_noise;
}

// The steady law without its random part: what a friction memory follows.
fn mean_law(speed_m_per_s: f32, v_m_per_s: f32) -> f32 {
    return law_a + point.friction_offset
        + law_b * stribeck_factor(params.friction_c_s_per_m, speed_m_per_s)
        + law_d * v_m_per_s * v_m_per_s;
}

// Which friction memory the slip ODE carries (the CPU's Memory::of; the
// MEMORY_* codes are generated). The host runs a copy of this kernel in
// which this function returns its memory as a constant
// (source::ensemble_wgsl_with_memory), so the others' branches fold away.
fn memory_form() -> i32 {
    if (effects.hysteresis_form == HYSTERESIS_FORM_LAG && effects.hysteresis_lag_s > 0.0) {
        return MEMORY_LAG;
    }
    if (effects.hysteresis_form == HYSTERESIS_FORM_SLIP && effects.hysteresis_length_m > 0.0) {
        return MEMORY_SLIP;
    }
    if (effects.hysteresis_form == HYSTERESIS_FORM_AGEING && effects.hysteresis_length_m > 0.0
        && effects.hysteresis_strength != 0.0) {
        return MEMORY_AGEING;
    }
    return MEMORY_NONE;
}

fn friction_coefficient(speed_m_per_s: f32, v_m_per_s: f32, x_m: f32, memory: f32) -> f32 {
    let slipped_m = abs(x_m - path.slip_start_x_m);
    let form = memory_form();
    var mu = memory + path.friction_noise;
    if (form == MEMORY_AGEING) {
        mu = ageing_coefficient(speed_m_per_s, v_m_per_s, memory);
    } else if (dahl()) {
        mu = max(steady_law(speed_m_per_s, v_m_per_s), 0.0) * hysteresis_factor(slipped_m, memory);
    } else if (form == MEMORY_NONE) {
        mu = steady_law(speed_m_per_s, v_m_per_s) * hysteresis_factor(slipped_m, memory);
    }
    if (effects.stiction_form == STICTION_FORM_DECAYING) {
        mu += path.stiction_excess * exp(-slipped_m / STICTION_DECAY_M);
    } else if (effects.stiction_form == STICTION_FORM_CONSTANT && effects.stiction_release_m > 0.0) {
        mu += path.stiction_excess * max(1.0 - slipped_m / effects.stiction_release_m, 0.0);
    }
    // Dahl's friction may point along the motion just after a reversal.
    return select(max(mu, 0.0), mu, dahl());
}

// μN plus the adhesion force (the sum clipped at 0), N: the CPU's
// Path::friction_force_n. slip_rates forms the same force inline, as
// −sign·μ·N − sign·(adhesion), so that the baseline's expression keeps its
// shape where a driver fuses multiplies into adds.
fn friction_force_n(speed_m_per_s: f32, v_m_per_s: f32, x_m: f32, memory: f32) -> f32 {
    let friction_n = friction_coefficient(speed_m_per_s, v_m_per_s, x_m, memory) * path.normal_force_n;
    if (effects.adhesion_force_n != 0.0) {
        return friction_n + adhesion(friction_n);
    }
    return friction_n;
}

// μ_ss(v) + B ln((θ + θ_0)/(θ_ss(v) + θ_0)), θ_ss(v) = L/(|v| + v_c),
// θ_0 = L/v_0: the sliding coefficient of hysteresis `ageing` before stiction.
fn ageing_coefficient(speed_m_per_s: f32, v_m_per_s: f32, age_s: f32) -> f32 {
    let length_m = effects.hysteresis_length_m;
    let steady_age_s = length_m / (abs(v_m_per_s) + AGEING_CUTOFF_SPEED_M_PER_S);
    let floor_age_s = length_m / AGEING_FLOOR_SPEED_M_PER_S;
    return steady_law(speed_m_per_s, v_m_per_s) + contact_age_term(age_s, steady_age_s, floor_age_s);
}

fn static_coefficient() -> f32 {
    return max(law_a + point.friction_offset + law_b + path.friction_noise + path.stiction_excess
        + path.ageing_excess, 0.0);
}

// Whether hysteresis `dahl` or `bristle` is on (δ > 0; the CPU's Path::dahl).
fn dahl() -> bool {
    return (effects.hysteresis_form == HYSTERESIS_FORM_DAHL || effects.hysteresis_form == HYSTERESIS_FORM_BRISTLE)
        && effects.hysteresis_length_m != 0.0;
}

// The friction memory a slip starts with at a breakaway: lag_start_coefficient, or φ₀ = 1
// under `dahl` (the CPU's Path::breakaway_memory).
fn breakaway_memory() -> f32 {
    if (dahl()) {
        return 1.0;
    }
    return lag_start_coefficient();
}

// The friction memory a slip starts with where the block slips on at a velocity zero
// (`reversed`: the other way): as at a breakaway, but ±φ of the ended slip under `dahl`,
// − where it reversed (the CPU's Path::reversal_memory). Read before slip_start_x_m moves.
fn reversal_memory(reversed: bool) -> f32 {
    if (!dahl()) {
        return lag_start_coefficient();
    }
    let end = hysteresis_factor(abs(path.x_m - path.slip_start_x_m), path.memory);
    return select(end, -end, reversed);
}

// Where the friction memory of `lag` and `slip` starts at a breakaway: the static one less
// the stiction excess friction_coefficient adds while it is released
// (src/engine/cpu/oscillator/mod.rs: Path::lag_start_coefficient).
fn lag_start_coefficient() -> f32 {
    let released = effects.stiction_form == STICTION_FORM_DECAYING
        || (effects.stiction_form == STICTION_FORM_CONSTANT && effects.stiction_release_m > 0.0);
    var excess = 0.0;
    if (released) {
        excess = path.stiction_excess;
    }
    return static_coefficient() - excess - path.friction_noise;
}

// μ_s N, plus the adhesion force (the sum clipped at 0).
fn breakaway_force() -> f32 {
    let friction_n = static_coefficient() * path.normal_force_n;
    if (effects.adhesion_force_n != 0.0) {
        return friction_n + adhesion(friction_n);
    }
    return friction_n;
}

// Rate of the friction memory: lag (μ_ss − μ_f)/τ_m, slip (|v|/L)(μ_ss − μ_f),
// ageing 1 − |v| θ/L.
fn memory_rate(speed_m_per_s: f32, v_m_per_s: f32, memory: f32) -> f32 {
    let form = memory_form();
    if (form == MEMORY_LAG) {
        return (mean_law(speed_m_per_s, v_m_per_s) - memory) / effects.hysteresis_lag_s;
    }
    if (form == MEMORY_SLIP) {
        return slip_law_rate(mean_law(speed_m_per_s, v_m_per_s), memory, abs(v_m_per_s));
    }
    if (form == MEMORY_AGEING) {
        return ageing_rate(memory, abs(v_m_per_s));
    }
    return 0.0;
}

// (acceleration, rate of the friction memory).
fn slip_rates(cos_omega_t: f32, x_m: f32, v_m_per_s: f32, memory: f32, sign: f32) -> vec2<f32> {
    let mu = friction_coefficient(sign * v_m_per_s, v_m_per_s, x_m, memory);
    var force = spring_force(cos_omega_t, x_m) - params.damping_n_s_per_m * v_m_per_s
        - sign * mu * path.normal_force_n;
    if (effects.adhesion_force_n != 0.0) {
        force -= sign * adhesion(mu * path.normal_force_n);
    }
    // Times 1/m like the CPU reference: the reciprocal depends on the
    // uniform only, so no stage waits on a division by the mass.
    let acceleration = force * (1.0 / params.mass_kg);
    return vec2<f32>(acceleration, memory_rate(sign * v_m_per_s, v_m_per_s, memory));
}

fn rk4_slip(start: vec2<f32>, x_m: f32, v_m_per_s: f32, h_s: f32, half_turn: vec2<f32>, sign: f32) -> SlipStep {
    let mid = rotated(start, half_turn);
    let end = rotated(mid, half_turn);
    let m0 = path.memory;
    let hh = 0.5 * h_s;
    let k1x = v_m_per_s;
    let k1 = slip_rates(start.x, x_m, v_m_per_s, m0, sign);
    let k2x = v_m_per_s + hh * k1.x;
    let x2 = x_m + hh * k1x;
    let k2 = slip_rates(mid.x, x2, k2x, m0 + hh * k1.y, sign);
    let k3x = v_m_per_s + hh * k2.x;
    let x3 = x_m + hh * k2x;
    let k3 = slip_rates(mid.x, x3, k3x, m0 + hh * k2.y, sign);
    let k4x = v_m_per_s + h_s * k3.x;
    let x4 = x_m + h_s * k3x;
    let k4 = slip_rates(end.x, x4, k4x, m0 + h_s * k3.y, sign);
    return SlipStep(
        x_m + h_s / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
        v_m_per_s + h_s / 6.0 * (k1.x + 2.0 * k2.x + 2.0 * k3.x + k4.x),
        m0 + h_s / 6.0 * (k1.y + 2.0 * k2.y + 2.0 * k3.y + k4.y),
        x2, x3, x4, start, mid, end);
}

// The RK4 quadrature of x cos(Ωt) and x sin(Ωt) over an accepted slip step.
fn add_slip_phase(h_s: f32, step: SlipStep) {
    let x1 = path.x_m;
    let x23 = 2.0 * (step.x2_m + step.x3_m);
    path.period_cos_integral += h_s / 6.0 * (x1 * step.trig0.x + x23 * step.trig1.x + step.x4_m * step.trig2.x);
    path.period_sin_integral += h_s / 6.0 * (x1 * step.trig0.y + x23 * step.trig1.y + step.x4_m * step.trig2.y);
}

// A stuck interval of duration_s between base trigs a and b, added exactly: x
// is constant on a rigid stick, κ u + (1 − κ) w on an elastic one.
fn add_stick_phase(a: vec2<f32>, b: vec2<f32>, duration_s: f32) {
    let w = point.omega_rad_per_s;
    if (stick_compliance == 0.0) {
        path.period_cos_integral += path.x_m * (b.y - a.y) / w;
        path.period_sin_integral += path.x_m * (a.x - b.x) / w;
        return;
    }
    let held = (1.0 - stick_compliance) * stick_anchor_m;
    let moving = stick_compliance * params.base_amplitude_m;
    let cos2 = 0.5 * duration_s + (b.y * b.x - a.y * a.x) / (2.0 * w);
    let cos_sin = (b.y * b.y - a.y * a.y) / (2.0 * w);
    path.period_cos_integral += held * (b.y - a.y) / w + moving * cos2;
    path.period_sin_integral += held * (a.x - b.x) / w + moving * cos_sin;
}

// A block stuck on an elastic contact moves to where the base at `end` puts it;
// its period's largest x counts the base's top inside the interval (the CPU's
// Path::creep).
fn creep(start: vec2<f32>, end: vec2<f32>) {
    if (stick_compliance == 0.0) {
        return;
    }
    let state = stuck_state(end);
    path.x_m = state.x;
    path.v_m_per_s = state.y;
    var top = path.x_m;
    if (start.y < 0.0 && end.y >= 0.0) {
        top = stuck_state(vec2<f32>(1.0, 0.0)).x;
    }
    path.period_max_x_m = max(path.period_max_x_m, top);
}

fn locate_velocity_zero(start: vec2<f32>, h_s: f32, sign: f32) -> f32 {
    let w = point.omega_rad_per_s;
    var lo = 0.0;
    var g_lo = sign * path.v_m_per_s;
    var hi = h_s;
    var g_hi = sign * rk4_slip(start, path.x_m, path.v_m_per_s, h_s, trig_at(0.5 * w * h_s), sign).v_m_per_s;
    if (g_lo <= 0.0) {
        var probe = 0.5 * h_s;
        var found = false;
        for (var i = 0u; i < PROBE_HALVINGS; i++) {
            let g_probe = sign * rk4_slip(start, path.x_m, path.v_m_per_s, probe, trig_at(0.5 * w * probe), sign).v_m_per_s;
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
    for (var i = 0u; i < ILLINOIS_ITERATIONS; i++) {
        if (hi - lo <= ILLINOIS_TOLERANCE * h_s) {
            break;
        }
        var mid = (lo * g_hi - hi * g_lo) / (g_hi - g_lo);
        if (!(mid > lo && mid < hi)) {
            mid = 0.5 * (lo + hi);
        }
        let g_mid = sign * rk4_slip(start, path.x_m, path.v_m_per_s, mid, trig_at(0.5 * w * mid), sign).v_m_per_s;
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

fn stick_or_slip(trig: vec2<f32>) -> i32 {
    let force = spring_force(trig.x, path.x_m);
    if (abs(force) <= breakaway_force()) {
        return MODE_STICK;
    }
    return select(-1, 1, force > 0.0);
}

// Entering cos(θ) >= C+ happens at θ = 2πn − acos(C+); entering
// cos(θ) <= C− at θ = 2πn + acos(C−). Keeps `best` unless this entry is earlier.
fn earliest_entry(best: vec2<f32>, sign: f32, phase_a: f32, reach: f32, t_a: f32, t_b: f32) -> vec2<f32> {
    var anchor = stick_anchor_m;
    if (stick_compliance == 0.0) {
        anchor = path.x_m;
    }
    let level = (anchor + sign * reach) / params.base_amplitude_m;
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

// The phase lag of a period's fundamental behind the base (see phase_of in
// the CPU reference).
fn phase_of(cos_integral: f32, sin_integral: f32) -> f32 {
    return atan2(sin_integral, cos_integral);
}

// Earliest (time, direction) of breakaway in [t_a, t_b]; direction 0 = none.
fn breakaway_time(t_a: f32, start: vec2<f32>, t_b: f32) -> vec2<f32> {
    let force = spring_force(start.x, path.x_m);
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
    let reach = threshold / (params.stiffness_n_per_m * (1.0 - stick_compliance));
    var best = vec2<f32>(t_b, 0.0);
    best = earliest_entry(best, 1.0, phase_a, reach, t_a, t_b);
    best = earliest_entry(best, -1.0, phase_a, reach, t_a, t_b);
    return best;
}

// Advances from t_start to t_b (the base's trig at t_start is `start_trig`);
// `regular` says the segment is a whole grid step, whose half turn is
// `half_step`. Returns the base's trig at t_b.
fn advance_segment(t_start: f32, t_b: f32, start_trig: vec2<f32>, regular: bool, half_step: vec2<f32>, measuring: bool) -> vec2<f32> {
    let w = point.omega_rad_per_s;
    let period_start_s = f32(path.period) * point.period_s;
    var t_a = t_start;
    var start = start_trig;
    var whole = regular;
    var events = 0u;
    loop {
        if (!(t_a < t_b)) {
            break;
        }
        if (path.mode == MODE_STICK) {
            var until = vec2<f32>(t_b, 0.0);
            if (events < MAX_EVENTS_PER_SEGMENT) {
                until = breakaway_time(t_a, start, t_b);
            }
            let t_end = select(until.x, t_b, until.y == 0.0);
            // A whole grid step held to its end is carried by rotation like
            // a slip step; an event's time exactly.
            var end: vec2<f32>;
            if (whole && until.y == 0.0) {
                end = rotated(rotated(start, half_step), half_step);
            } else {
                end = trig_at(w * t_end);
            }
            if (measuring) {
                path.period_stick_s += t_end - t_a;
                add_stick_phase(start, end, t_end - t_a);
            }
            creep(start, end);
            if (until.y != 0.0 && stick_compliance != 0.0) {
                // Off an elastic stick the block slips on from the speed it
                // crept at, where that is the slip's way.
                path.v_m_per_s = until.y * max(until.y * path.v_m_per_s, 0.0);
            }
            path.mode = i32(until.y);
            path.slip_start_x_m = path.x_m;
            if (path.mode != MODE_STICK) {
                if (memory_form() == MEMORY_AGEING) {
                    // The slip starts from the contact age the breakaway was judged by.
                    path.memory = contact_age_at(f32(path.interval) * effects.noise_interval_s);
                } else {
                    path.memory = breakaway_memory();
                }
            }
            t_a = t_end;
            start = end;
            whole = false;
            events += 1u;
        } else {
            let sign = f32(path.mode);
            let h = t_b - t_a;
            var half_turn = half_step;
            if (!whole) {
                half_turn = trig_at(0.5 * w * h);
            }
            let step = rk4_slip(start, path.x_m, path.v_m_per_s, h, half_turn, sign);
            if (sign * step.v_m_per_s > 0.0) {
                if (measuring) {
                    add_slip_phase(h, step);
                }
                path.x_m = step.x_m;
                path.v_m_per_s = step.v_m_per_s;
                path.memory = step.memory;
                path.period_max_x_m = max(path.period_max_x_m, step.x_m);
                return step.trig2;
            }
            let h_zero = locate_velocity_zero(start, h, sign);
            let to_zero = rk4_slip(start, path.x_m, path.v_m_per_s, h_zero, trig_at(0.5 * w * h_zero), sign);
            if (measuring) {
                add_slip_phase(h_zero, to_zero);
            }
            path.x_m = to_zero.x_m;
            path.v_m_per_s = 0.0;
            path.memory = to_zero.memory;
            path.period_max_x_m = max(path.period_max_x_m, to_zero.x_m);
            t_a = t_a + h_zero;
            start = trig_at(w * t_a);
            whole = false;
            if (memory_form() == MEMORY_AGEING) {
                // At rest the static coefficient reads the contact age the slip reached.
                path.ageing_excess = contact_age_excess(path.memory);
            }
            let slid = path.mode;
            if (events < MAX_EVENTS_PER_SEGMENT) {
                path.mode = stick_or_slip(start);
            } else {
                path.mode = MODE_STICK;
            }
            if (path.mode == MODE_STICK) {
                start_stick(period_start_s + t_a, start);
            } else if (memory_form() != MEMORY_AGEING) {
                // A slip from rest is a breakaway: μ_f starts at the static
                // coefficient; the contact age goes on from where the slip left it;
                // Dahl's friction turns over from where it was.
                path.memory = reversal_memory(path.mode != slid);
            }
            path.slip_start_x_m = path.x_m;
            events += 1u;
        }
    }
    return start;
}

// Friction force on the block with the base at `trig` (for output samples), N.
fn friction_force(trig: vec2<f32>) -> f32 {
    if (path.mode == MODE_STICK) {
        return -spring_force(trig.x, path.x_m);
    }
    let sign = f32(path.mode);
    return -sign * friction_force_n(sign * path.v_m_per_s, path.v_m_per_s, path.x_m, path.memory);
}

// The fewest equal steps no longer than max_step that cover span (the CPU's
// span_steps).
fn span_steps(span: f32, max_step: f32) -> u32 {
    return u32(max(ceil((span / max_step) * (1.0 - 1e-6)), 1.0));
}

// Noise boundaries and the period's end are step boundaries: each span
// between them is divided into equal steps no longer than T / S.
fn run_period(measuring: bool) {
    let steps_per_period = point.steps_per_period;
    let max_step = point.period_s / f32(steps_per_period);
    let w = point.omega_rad_per_s;
    path.period_max_x_m = path.x_m;
    path.period_stick_s = 0.0;
    path.period_cos_integral = 0.0;
    path.period_sin_integral = 0.0;
    var t = 0.0;
    var trig = vec2<f32>(1.0, 0.0);
    var finished = false;
    loop {
        var noise_t = point.period_s;
        var at_noise = false;
        if (path.next_boundary_whole == path.period) {
            // Position of the boundary in steps: frac * S / 2^32, exactly.
            let position = mulhilo(path.next_boundary_frac, steps_per_period);
            noise_t = min((f32(position.x) + f32(position.y) * FIXED_ONE_INV) * max_step, point.period_s);
            at_noise = true;
        }
        let target_t = max(noise_t, t);
        let span = target_t - t;
        if (span > 0.0) {
            let steps = span_steps(span, max_step);
            let h = span / f32(steps);
            let turn = trig_at(0.5 * w * h);
            var step_start = t;
            for (var k = 1u; k <= steps; k++) {
                var step_end = t + f32(k) * h;
                if (k == steps) {
                    step_end = target_t;
                }
                if (k % TRIG_REFRESH_STEPS == 0u) {
                    trig = trig_at(w * step_start);
                }
                trig = advance_segment(step_start, step_end, trig, true, turn, measuring);
                step_start = step_end;
            }
        }
        t = target_t;
        if (at_noise) {
            path.interval_phase = f32(path.next_boundary_frac) * FIXED_ONE_INV;
            path.interval += 1u;
            let frac = path.next_boundary_frac + point.noise_interval_frac;
            let carry = select(0u, 1u, frac < path.next_boundary_frac);
            path.next_boundary_frac = frac;
            path.next_boundary_whole += point.noise_interval_whole + carry;
            draw_noise();
            // Records aligned with the noise sample each boundary of the
            // measured cycles, with the new interval's noise.
            if (measuring && params.record_samples != 0u) {
                record_sample(t);
            }
        }
        if (!(t < point.period_s)) {
            finished = true;
            break;
        }
        trig = trig_at(w * t);
    }
    // Counted only when the loop really finished: a loop ended early by the
    // driver leaves the count short, and the host refuses the result.
    if (finished) {
        path.period += 1u;
    }
}
