// The friction oscillator, one realisation per invocation, in f32.
// This is src/engine/cpu/oscillator.rs's algorithm (same function names, same
// order): fixed steps per excitation period, steps split at noise-interval
// boundaries, RK4 in slip with the slip direction frozen, velocity zeros
// located by root finding on the RK4 map, breakaway from stick in closed form.
// Time inside a period comes from the integer step counter, never from
// accumulating dt; noise boundaries are 32.32 fixed-point positions in periods.
// The deliberate f32/f64 differences are tabled in that file's docs.

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
    period_max_x_m: f32,
    period_stick_s: f32,
    // ∫ x cos(Ωt) dt and ∫ x sin(Ωt) dt over the period so far (phase_of).
    period_cos_integral: f32,
    period_sin_integral: f32,
}

// One RK4 step of the slip ODE with what the phase quadrature needs: the
// stage displacements and cos(Ωt) at the step's start, middle and end.
struct SlipStep {
    x_m: f32,
    v_m_per_s: f32,
    x2_m: f32,
    x3_m: f32,
    x4_m: f32,
    cos0: f32,
    cos1: f32,
    cos2: f32,
}

var<private> path: Path;
var<private> point: GridPoint;
var<private> realisation: u32;
var<private> key: vec2<u32>;

fn draw_noise() {
    var friction_interval = path.interval;
    if (effects.colour_form == COLOUR_FORM_HOLD) {
        friction_interval = path.interval / effects.colour_hold_intervals;
    }
    let z = gaussian_pair(key, realisation, STREAM_FRICTION, friction_interval);
    let innovation = sqrt(1.0 - effects.colour_rho * effects.colour_rho);
    var g = z.x;
    if (effects.colour_form == COLOUR_FORM_TWO_SCALE && effects.colour_rho > 0.0) {
        let slow = gaussian_pair(key, realisation, STREAM_COLOUR, path.interval).x;
        path.colour_state = select(effects.colour_rho * path.colour_state + innovation * slow, slow, path.interval == 0u);
        g = 0.7071067811865476 * (z.x + path.colour_state);
    } else if (effects.colour_form == COLOUR_FORM_AR1) {
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
    if (effects.stiction_form == STICTION_FORM_NOISY) {
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
    if (effects.stiction_form == STICTION_FORM_DECAYING) {
        mu += path.stiction_excess * exp(-slipped_m / STICTION_DECAY_M);
    } else if (effects.stiction_form == STICTION_FORM_CONSTANT && effects.stiction_release_m > 0.0) {
        mu += path.stiction_excess * max(1.0 - slipped_m / effects.stiction_release_m, 0.0);
    }
    return max(mu, 0.0);
}

fn breakaway_force() -> f32 {
    let mu_static = params.friction_a + point.friction_offset + params.friction_b + path.friction_noise + path.stiction_excess;
    return max(mu_static, 0.0) * path.normal_force_n;
}

fn slip_acceleration(cos_omega_t: f32, x_m: f32, v_m_per_s: f32, sign: f32) -> f32 {
    let friction = sign * friction_coefficient(sign * v_m_per_s, v_m_per_s, x_m) * path.normal_force_n;
    let spring = params.stiffness_n_per_m * (params.base_amplitude_m * cos_omega_t - x_m);
    return (spring - params.damping_n_s_per_m * v_m_per_s - friction) / params.mass_kg;
}

// Stages 2 and 3 share the excitation's cos at the midpoint.
fn rk4_slip(t_local_s: f32, x_m: f32, v_m_per_s: f32, h_s: f32, sign: f32) -> SlipStep {
    let w = point.omega_rad_per_s;
    let half = 0.5 * h_s;
    let cos0 = cos(w * t_local_s);
    let cos1 = cos(w * (t_local_s + half));
    let cos2 = cos(w * (t_local_s + h_s));
    let k1x = v_m_per_s;
    let k1v = slip_acceleration(cos0, x_m, v_m_per_s, sign);
    let k2x = v_m_per_s + half * k1v;
    let x2 = x_m + half * k1x;
    let k2v = slip_acceleration(cos1, x2, k2x, sign);
    let k3x = v_m_per_s + half * k2v;
    let x3 = x_m + half * k2x;
    let k3v = slip_acceleration(cos1, x3, k3x, sign);
    let k4x = v_m_per_s + h_s * k3v;
    let x4 = x_m + h_s * k3x;
    let k4v = slip_acceleration(cos2, x4, k4x, sign);
    return SlipStep(
        x_m + h_s / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
        v_m_per_s + h_s / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
        x2, x3, x4, cos0, cos1, cos2);
}

// The RK4 quadrature of x cos(Ωt) and x sin(Ωt) over an accepted slip step.
fn add_slip_phase(t_local_s: f32, h_s: f32, step: SlipStep) {
    let w = point.omega_rad_per_s;
    let sin0 = sin(w * t_local_s);
    let sin1 = sin(w * (t_local_s + 0.5 * h_s));
    let sin2 = sin(w * (t_local_s + h_s));
    let x1 = path.x_m;
    path.period_cos_integral += h_s / 6.0 * (x1 * step.cos0 + 2.0 * (step.x2_m + step.x3_m) * step.cos1 + step.x4_m * step.cos2);
    path.period_sin_integral += h_s / 6.0 * (x1 * sin0 + 2.0 * (step.x2_m + step.x3_m) * sin1 + step.x4_m * sin2);
}

// A stuck interval [t_a, t_b] added exactly: x is constant.
fn add_stick_phase(t_a: f32, t_b: f32) {
    let w = point.omega_rad_per_s;
    path.period_cos_integral += path.x_m * (sin(w * t_b) - sin(w * t_a)) / w;
    path.period_sin_integral += path.x_m * (cos(w * t_a) - cos(w * t_b)) / w;
}

fn locate_velocity_zero(t_local_s: f32, h_s: f32, sign: f32) -> f32 {
    var lo = 0.0;
    var g_lo = sign * path.v_m_per_s;
    var hi = h_s;
    var g_hi = sign * rk4_slip(t_local_s, path.x_m, path.v_m_per_s, h_s, sign).v_m_per_s;
    if (g_lo <= 0.0) {
        var probe = 0.5 * h_s;
        var found = false;
        for (var i = 0u; i < PROBE_HALVINGS; i++) {
            let g_probe = sign * rk4_slip(t_local_s, path.x_m, path.v_m_per_s, probe, sign).v_m_per_s;
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
        let g_mid = sign * rk4_slip(t_local_s, path.x_m, path.v_m_per_s, mid, sign).v_m_per_s;
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

// The phase lag of a period's fundamental behind the base (see phase_of in
// the CPU reference).
fn phase_of(cos_integral: f32, sin_integral: f32) -> f32 {
    return atan2(sin_integral, cos_integral);
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
                add_stick_phase(t_a, t_end);
            }
            path.mode = i32(until.y);
            path.slip_start_x_m = path.x_m;
            t_a = t_end;
            events += 1u;
        } else {
            let sign = f32(path.mode);
            let h = t_b - t_a;
            let step = rk4_slip(t_a, path.x_m, path.v_m_per_s, h, sign);
            if (sign * step.v_m_per_s > 0.0) {
                if (measuring) {
                    add_slip_phase(t_a, h, step);
                }
                path.x_m = step.x_m;
                path.v_m_per_s = step.v_m_per_s;
                path.period_max_x_m = max(path.period_max_x_m, step.x_m);
                t_a = t_b;
            } else {
                let h_zero = locate_velocity_zero(t_a, h, sign);
                let to_zero = rk4_slip(t_a, path.x_m, path.v_m_per_s, h_zero, sign);
                if (measuring) {
                    add_slip_phase(t_a, h_zero, to_zero);
                }
                let x_zero = to_zero.x_m;
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
    path.period_cos_integral = 0.0;
    path.period_sin_integral = 0.0;
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
