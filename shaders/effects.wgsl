// The effects' arithmetic in f32: src/engine/cpu/effects.rs, function for
// function (the forms are the generated constants of src/engine/gpu/source.rs).
// Every function reduces to the baseline's arithmetic at zero strength.

fn harmonic_wave(c: f32) -> f32 {
    if (effects.harmonic_form == HARMONIC_FORM_BUMPS) {
        return pow(max(c, 0.0), effects.harmonic_shape) - effects.harmonic_shape_mean;
    }
    if (effects.harmonic_form == HARMONIC_FORM_SQUARE) {
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

// The `position` form's part of the normal force, (αN0 + βN0 r) r, N, with
// r = x/U0 at the interval's start.
fn position_load(linear_n: f32, quadratic_n: f32, r: f32) -> f32 {
    return (linear_n + quadratic_n * r) * r;
}

fn non_gaussian(s: f32, d: f32, g: f32, g2: f32) -> f32 {
    if (effects.non_gaussian_form == NON_GAUSSIAN_FORM_POLYNOMIAL) {
        // b solves b² + 6bd + 2c² + 15d² = 1 (unit variance), c = s.
        let b = sqrt(max(1.0 - 2.0 * s * s - 6.0 * d * d, 0.0)) - 3.0 * d;
        return g * (b + g * (s + d * g)) - s;
    }
    if (effects.non_gaussian_form == NON_GAUSSIAN_FORM_LOGNORMAL) {
        if (s == 0.0) {
            return g;
        }
        let v = s * s;
        return (exp(s * g) - exp(0.5 * v)) / sqrt((exp(v) - 1.0) * exp(v));
    }
    if (effects.non_gaussian_form == NON_GAUSSIAN_FORM_TUKEY_H) {
        return g * exp(0.5 * s * g * g) * pow(1.0 - 2.0 * s, 0.75);
    }
    if (effects.non_gaussian_form == NON_GAUSSIAN_FORM_MIXTURE) {
        if (s == 0.0) {
            return g;
        }
        let p = MIXTURE_OUTLIER_SHARE;
        let shift = 3.0 * s;
        let width = 1.0 + s;
        let x = select(g, shift + width * g, g2 < MIXTURE_OUTLIER_QUANTILE);
        let mean = p * shift;
        let variance = p * (width * width + shift * shift) + (1.0 - p) - mean * mean;
        return (x - mean) / sqrt(variance);
    }
    return (g + s * (g2 * g2 - 1.0) * 0.7071067811865476) / sqrt(1.0 + s * s);
}

fn dwell_excess(excess: f32, dwell_s: f32, ageing_s: f32) -> f32 {
    if (ageing_s == 0.0) {
        return excess;
    }
    return excess * (1.0 - exp(-max(dwell_s, 0.0) / ageing_s));
}

// `start`: φ₀ of `dahl` and `bristle` (–), unused by the other forms.
fn hysteresis_factor(slipped_m: f32, start: f32) -> f32 {
    let length = effects.hysteresis_length_m;
    if (length == 0.0) {
        return 1.0;
    }
    let r = slipped_m / length;
    if (effects.hysteresis_form == HYSTERESIS_FORM_TANH) {
        return tanh(r);
    }
    if (effects.hysteresis_form == HYSTERESIS_FORM_RATIONAL) {
        return r / (r + 1.0);
    }
    if (effects.hysteresis_form == HYSTERESIS_FORM_DAHL || effects.hysteresis_form == HYSTERESIS_FORM_BRISTLE) {
        return 1.0 - (1.0 - start) * exp(-r);
    }
    if (effects.hysteresis_form == HYSTERESIS_FORM_LAG || effects.hysteresis_form == HYSTERESIS_FORM_SLIP
        || effects.hysteresis_form == HYSTERESIS_FORM_AGEING) {
        return 1.0;
    }
    return 1.0 - exp(-r);
}

// κ = k δ / (k δ + μ₀ N0) of `bristle` (the CPU's effects::bristle_compliance), –.
fn bristle_compliance(stiffness_n_per_m: f32, held_n: f32, length_m: f32) -> f32 {
    let elastic = stiffness_n_per_m * length_m;
    if (elastic > 0.0 && held_n > 0.0) {
        return elastic / (elastic + held_n);
    }
    return 0.0;
}

// (|v|/L)(μ_ss − μ_f): the slip law's rate of the friction memory, 1/s.
fn slip_law_rate(steady_mu: f32, memory_mu: f32, speed: f32) -> f32 {
    return speed / effects.hysteresis_length_m * (steady_mu - memory_mu);
}

// 1 − |v| θ / L: the ageing law's rate of the contact age θ (s), –.
fn ageing_rate(age_s: f32, speed: f32) -> f32 {
    return 1.0 - speed * age_s / effects.hysteresis_length_m;
}

// B ln((θ + θ_0)/(θ_ref + θ_0)), θ read as 0 below 0, θ_0 the floor age, –.
fn contact_age_term(age_s: f32, reference_age_s: f32, floor_age_s: f32) -> f32 {
    return effects.hysteresis_strength * log((max(age_s, 0.0) + floor_age_s) / (reference_age_s + floor_age_s));
}

// A `random_walk`'s factor is its expectation, 1: each path adds its walk.
fn drift_factor(t_s: f32) -> f32 {
    let rate = effects.drift_rate_per_s;
    if (effects.drift_form == DRIFT_FORM_RANDOM_WALK) {
        return 1.0;
    }
    if (effects.drift_form == DRIFT_FORM_SATURATING) {
        return 1.0 + rate * DRIFT_SATURATION_S * (1.0 - exp(-t_s / DRIFT_SATURATION_S));
    }
    if (effects.drift_form == DRIFT_FORM_WANDER) {
        return 1.0 + rate * DRIFT_WANDER_S * sin(t_s / DRIFT_WANDER_S);
    }
    if (effects.drift_form == DRIFT_FORM_QUADRATIC) {
        return max(0.0, 1.0 + (rate + effects.drift_curvature_per_s2 * t_s) * t_s);
    }
    return 1.0 + rate * t_s;
}

// The adhesion force A, no less than −μN (the friction force's magnitude
// μN + A is clipped at 0), N.
fn adhesion(friction_n: f32) -> f32 {
    return max(effects.adhesion_force_n, -friction_n);
}
