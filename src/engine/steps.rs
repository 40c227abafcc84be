//! How many integration steps per excitation period a grid point takes: the
//! model's own (`[solver] steps_per_period`), raised where the rig's natural
//! period, a friction memory or a law that rises with speed from rest needs
//! more for classical RK4 to stay stable. Both backends take the result,
//! the oscillator's `steps_per_period`.

use crate::engine::effects::{EffectParams, HysteresisForm};
use crate::engine::model::{Condition, Model, Solver};
use crate::error::{Error, Result};

/// Fewest integration steps per period of the rig's natural frequency, –.
pub const NATURAL_PERIOD_STEPS: f64 = 16.0;

/// The steps per period of a grid point at `condition` under `model`, whose
/// effects there are `effects` and mean normal force `normal_force_mean_n`
/// (N): the most any of the rules below asks for, and at least the
/// model's own. A model no allowed step count resolves is refused by name.
pub(crate) fn steps_per_period(
    model: &Model,
    condition: Condition,
    effects: &EffectParams,
    normal_force_mean_n: f64,
) -> Result<u32> {
    Ok(model
        .solver
        .steps_per_period
        .max(steps_resolving_the_rig(model, condition)?)
        .max(steps_resolving_the_memory(model, condition)?)
        .max(steps_resolving_the_law(model, condition, effects, normal_force_mean_n)?))
}

/// Steps per excitation period where a friction memory is on, so that no
/// step is longer than its memory time (1 without one): classical RK4 on
/// `dμ_f/dt = (μ − μ_f)/τ_m` is unstable for steps beyond 2.8 τ_m (the
/// lagged coefficient then grew without bound, 15 and more, instead of
/// following the law) and inaccurate well before; at one step per τ_m it
/// follows the exact decay within 2% per step.
///
/// - hysteresis `lag`: τ_m is its memory time.
/// - hysteresis `slip` and `ageing`: their states relax over the slip
///   distance L, with rate |v|/L (`dμ_f/dt = (|v|/L)(μ_ss − μ_f)`,
///   `dθ/dt = 1 − |v| θ/L`), so the memory time L/|v| shortens with
///   speed. It is taken at the speed scale max(Ω, ω0) X, X the
///   frictionless steady amplitude at this frequency
///   ([`Model::linear_amplitude_m`]): friction only takes energy out, so
///   the motion stays within about X, and a slip from a stick, driven by
///   the springs, is at most as fast as a swing at the natural frequency
///   ω0 (on the paper rig at 5–15 Hz and 4–16 N: slips up to 1.7 Ω X =
///   0.83 ω0 X at 5 Hz, where they start from sticks, and within 1.06 Ω X
///   elsewhere; RK4 stays stable up to 2.8 times the scale). That is
///   2π X max(f, f0) / (f L) steps per period: about 440 at 7 Hz with
///   L = 0.1 mm, 14 500 next to resonance (10 Hz, X = 0.23 m), ten times
///   more for each tenfold shorter L.
///
/// A memory that would need more than
/// [`Solver::MAX_STEPS_PER_PERIOD`] steps is refused, by name.
fn steps_resolving_the_memory(model: &Model, condition: Condition) -> Result<u32> {
    let Some(h) = model.effects.friction_hysteresis.as_ref() else {
        return Ok(1);
    };
    let period_s = 1.0 / condition.excitation_frequency_hz;
    let fastest_hz = condition.excitation_frequency_hz.max(model.rig.natural_frequency_hz);
    let speed_scale = std::f64::consts::TAU * fastest_hz * model.linear_amplitude_m(condition.excitation_frequency_hz);
    let (memory_s, key, value, what) = match h.form {
        HysteresisForm::Lag if h.time_constant_s > 0.0 => (
            h.time_constant_s,
            "friction_hysteresis.time_constant_s",
            h.time_constant_s,
            format!("a memory time of {:e} s", h.time_constant_s),
        ),
        HysteresisForm::Slip | HysteresisForm::Ageing
            if h.length_m > 0.0 && (h.form == HysteresisForm::Slip || h.strength != 0.0) =>
        {
            let memory_s = h.length_m / speed_scale;
            (
                memory_s,
                "friction_hysteresis.length_m",
                h.length_m,
                format!(
                    "a slip distance of {:e} m at the speed scale {speed_scale:e} m/s (the faster of the \
                     excitation's and the natural angular frequency times the frictionless steady amplitude) \
                     is a memory time of {memory_s:e} s, which",
                    h.length_m
                ),
            )
        }
        _ => return Ok(1),
    };
    // NaN too (no finite speed scale): refused.
    allowed((period_s / memory_s).ceil(), key, value, |needed| {
        format!(
            "{what} needs {needed:e} steps per period at {} Hz to be integrated stably; at most {} are allowed",
            condition.excitation_frequency_hz,
            Solver::MAX_STEPS_PER_PERIOD
        )
    })
}

/// Steps per excitation period that keep every slip step within the
/// time a slip's velocity takes to settle where the friction law
/// strengthens with speed: there the friction's slope `N ∂μ/∂|v|`
/// acts as a damping, and a slip relaxes towards the speed at which
/// friction balances the springs at the rate `λ = (c_r + N ∂μ/∂|v|)/m`
/// (1/s; `c_r` the rig's damping, N/(m/s)). Classical RK4 overshoots a
/// relaxation past its end once a step exceeds 2.8/λ: from rest, the
/// step's velocity comes out negative, which the integrator reads as a
/// stop, and the slip turns into a chatter of stops and starts, each
/// located exactly, up to the event limit of every step (a fitted law
/// rising from 0.06 at rest to 0.33 within a few mm/s, b = −0.27 and
/// c = 950 s/m, settles in 0.24 ms at 16 N on the paper's rig, a
/// seventh of a 600 Hz noise interval). As for a friction memory, no
/// step is longer than 1/λ.
///
/// The slope is eq. 7's Stribeck term at rest, `−b c` where `b < 0`
/// (the term rising with speed, steepest at rest), scaled as this
/// point's law is ([`EffectParams::friction_scale`]); the load is
/// bounded by its mean, three standard deviations of its noise and its
/// harmonics' amplitudes. The quadratic term's slope `2 d v` is not
/// counted: it grows with a speed that the term itself holds down, so
/// no speed scale bounds it usefully, and a `d` steep enough to matter
/// at the model's steps is caught as a divergence. Unchanged for a law
/// that weakens with speed (the paper's), where `λ` is the rig's
/// damping alone. A law that would need more than
/// [`Solver::MAX_STEPS_PER_PERIOD`] is refused, by name.
fn steps_resolving_the_law(
    model: &Model,
    condition: Condition,
    effects: &EffectParams,
    normal_force_mean_n: f64,
) -> Result<u32> {
    let f = &model.friction;
    let slope_s_per_m = effects.friction_scale * (-f.b * f.c).max(0.0);
    let harmonics_n: f64 = effects.harmonic_amplitudes_n.iter().map(|a| a.abs()).sum();
    let load_n = normal_force_mean_n.abs() + 3.0 * model.normal_force.sigma + harmonics_n;
    let rate_per_s = (model.damping_n_s_per_m() + load_n * slope_s_per_m) / model.rig.mass_kg;
    allowed((rate_per_s / condition.excitation_frequency_hz).ceil(), "friction.b", f.b, |needed| {
        format!(
            "a friction law rising from rest by {slope_s_per_m:e} per m/s (b = {}, c = {} s/m) settles a slip at \
             {load_n:.3} N within {:.2e} s, which needs {needed:.3e} steps per period at {} Hz to be integrated \
             stably; at most {} are allowed",
            f.b,
            f.c,
            1.0 / rate_per_s,
            condition.excitation_frequency_hz,
            Solver::MAX_STEPS_PER_PERIOD
        )
    })
}

/// Steps per excitation period that give a swing at the rig's natural
/// frequency f0 at least [`NATURAL_PERIOD_STEPS`] steps: RK4 is stable
/// only below ω0·dt ≈ 2.8, and a stiff rig driven far below resonance
/// (f0 = 1 kHz at 8 Hz) would otherwise diverge at the default steps.
/// On the paper rig (f0 near 10 Hz, 5–15 Hz) it asks for at most 32,
/// below the default. A rig that would need more than
/// [`Solver::MAX_STEPS_PER_PERIOD`] is refused, by name.
fn steps_resolving_the_rig(model: &Model, condition: Condition) -> Result<u32> {
    let f0 = model.rig.natural_frequency_hz;
    allowed(
        (NATURAL_PERIOD_STEPS * f0 / condition.excitation_frequency_hz).ceil(),
        "rig.natural_frequency_hz",
        f0,
        |needed| {
            format!(
                "a natural frequency {:e} times the excitation's ({} Hz) needs {needed:e} steps per period to be \
             integrated stably ({NATURAL_PERIOD_STEPS} per natural period); at most {} are allowed",
                f0 / condition.excitation_frequency_hz,
                condition.excitation_frequency_hz,
                Solver::MAX_STEPS_PER_PERIOD
            )
        },
    )
}

/// `needed` steps per period (–), or the refusal of the model parameter
/// `key` at `value` that asks for them, with `message(needed)`, where they
/// are more than [`Solver::MAX_STEPS_PER_PERIOD`] or not a number.
fn allowed(needed: f64, key: &str, value: f64, message: impl FnOnce(f64) -> String) -> Result<u32> {
    if needed.is_nan() || needed > f64::from(Solver::MAX_STEPS_PER_PERIOD) {
        return Err(Error::InvalidParameter { key: key.into(), value: value.to_string(), message: message(needed) });
    }
    Ok(needed as u32)
}
