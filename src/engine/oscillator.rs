//! What the integrators work on: the constants of one grid point derived
//! from a model ([`Oscillator`]), the initial state, how long a realisation
//! runs ([`RunPlan`]), where its peaks are binned ([`PeakRange`]), and what
//! one realisation produces ([`PathResult`], [`Sample`]). Both backends
//! share these types.

use serde::{Deserialize, Serialize};

use crate::engine::effects::{EffectParams, HysteresisForm};
use crate::engine::model::{Condition, Model, Solver};
use crate::error::{Error, Result};

/// How long a realisation runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RunPlan {
    /// Excitation periods discarded before measuring.
    pub warmup_cycles: u32,
    /// Excitation periods whose peaks are measured.
    pub measured_cycles: u32,
}

impl RunPlan {
    /// All periods integrated: warm-up plus measured.
    pub fn total_cycles(&self) -> u64 {
        u64::from(self.warmup_cycles) + u64::from(self.measured_cycles)
    }
}

/// State at t = 0: displacement (m) and velocity (m/s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InitialState {
    /// Displacement x, m.
    pub x_m: f64,
    /// Velocity v, m/s.
    pub v_m_per_s: f64,
}

impl InitialState {
    /// The default initial state at a grid point: the frictionless steady
    /// state of `model` at t = 0.
    pub fn steady(model: &Model, condition: Condition) -> InitialState {
        let (x_m, v_m_per_s) = model.linear_steady_state_at_zero(condition.excitation_frequency_hz);
        InitialState { x_m, v_m_per_s }
    }
}

/// One grid point of an ensemble: where it is, where its realisations
/// start, and the range its peaks are binned and quantised in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// Excitation frequency and mean normal force.
    pub condition: Condition,
    /// State of every realisation at t = 0.
    pub initial: InitialState,
    /// Where the point's peaks are binned and quantised.
    pub range: PeakRange,
    /// Where this point's realisation numbers start, past the job's
    /// [`Job::first_realisation`](crate::engine::Job::first_realisation):
    /// realisation `r` of the point is number `first_realisation +
    /// realisation_offset + r`, the noise path that number keys. 0 (the
    /// default) gives every point of a job the same paths (common random
    /// numbers across a sweep's grid); points that stand for separate
    /// experiments (a diagnosis's measured units, simulated in one job)
    /// are kept apart by it.
    pub realisation_offset: u32,
}

impl Point {
    /// A point started from the frictionless steady state, with the default
    /// peak range (`PeakRange::for_point`).
    pub fn steady(model: &Model, condition: Condition) -> Point {
        Point {
            condition,
            initial: InitialState::steady(model, condition),
            range: PeakRange::for_point(model, condition),
            realisation_offset: 0,
        }
    }
}

/// Where a point's peaks are binned and how they are quantised, and the
/// reference its phases are measured from (the reduction's arithmetic on it
/// is in [`crate::engine::reduce`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PeakRange {
    /// Lower edge of the first inner bin, m.
    pub lo_m: f64,
    /// Upper edge of the last inner bin, m.
    pub hi_m: f64,
    /// Phases are reduced as their deviation from this angle, rad (the
    /// frictionless phase at the point; any reference gives the same
    /// statistics, a near one keeps tiny spreads precise).
    pub phase_ref_rad: f64,
}

impl PeakRange {
    /// The range for a grid point: `[−0.5 A, 1.5 A]` around zero, with `A`
    /// the frictionless steady amplitude there (friction only lowers peaks;
    /// sticking blocks can sit on the negative side).
    pub fn for_point(model: &Model, condition: Condition) -> PeakRange {
        let a = model.linear_amplitude_m(condition.excitation_frequency_hz);
        let a = if a.is_finite() && a > 0.0 { a } else { model.excitation.amplitude_m.max(1e-6) };
        PeakRange {
            lo_m: -0.5 * a,
            hi_m: 1.5 * a,
            phase_ref_rad: model.linear_phase_rad(condition.excitation_frequency_hz),
        }
    }
}

/// What one realisation produced.
#[derive(Clone, Debug, PartialEq)]
pub struct PathResult {
    /// Peak displacement of each measured period, m.
    pub peaks_m: Vec<f64>,
    /// Phase lag of each measured period's fundamental behind the base, rad
    /// in (−π, π] (`interfaces.md`).
    pub phases_rad: Vec<f64>,
    /// Time spent stuck during the measured periods, s.
    pub stick_time_s: f64,
}

/// One output sample of a time-series record.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Time since the start of the record, s.
    pub t_s: f64,
    /// Displacement, m.
    pub x_m: f64,
    /// Velocity, m/s.
    pub v_m_per_s: f64,
    /// Normal force, N.
    pub normal_force_n: f64,
    /// Friction force on the block, N.
    pub friction_force_n: f64,
}

/// Everything the integrators need for one grid point, derived once from a
/// [`Model`] and a [`Condition`]. The GPU's `Params` is built from this too.
#[derive(Clone, Debug, PartialEq)]
pub struct Oscillator {
    /// Block mass `m`, kg.
    pub mass_kg: f64,
    /// Spring stiffness `k`, N/m.
    pub stiffness_n_per_m: f64,
    /// Viscous damping coefficient `c`, N·s/m.
    pub damping_n_s_per_m: f64,
    /// Base displacement amplitude `U0`, m.
    pub base_amplitude_m: f64,
    /// Excitation angular frequency `Ω`, rad/s.
    pub omega_rad_per_s: f64,
    /// Excitation period `T = 2π/Ω`, s.
    pub period_s: f64,
    /// Friction law parameters `a` (–), `b` (–), `c` (s/m), `d` (s²/m²).
    pub friction_a: f64,
    pub friction_b: f64,
    pub friction_c_s_per_m: f64,
    pub friction_d_s2_per_m2: f64,
    /// Standard deviation of the friction coefficient's random part, –.
    pub friction_sigma: f64,
    /// Mean normal force `N0`, N.
    pub normal_force_mean_n: f64,
    /// Standard deviation of the normal force's random part, N.
    pub normal_force_sigma_n: f64,
    /// Integration steps per excitation period.
    pub steps_per_period: u32,
    /// Noise hold interval τ, s.
    pub noise_interval_s: f64,
    /// The effects at this grid point (all zero: the baseline).
    pub effects: EffectParams,
    /// Noise hold interval in excitation periods, as 32.32 fixed point:
    /// boundary `j` lies at `j * noise_interval_fixed / 2^32` periods.
    pub noise_interval_fixed: u64,
}

/// Fewest integration steps per period of the rig's natural frequency, –.
pub const NATURAL_PERIOD_STEPS: f64 = 16.0;

impl Oscillator {
    /// Derives the constants for one grid point.
    pub fn new(model: &Model, condition: Condition) -> Result<Oscillator> {
        condition.validate()?;
        let omega = std::f64::consts::TAU * condition.excitation_frequency_hz;
        let period_s = 1.0 / condition.excitation_frequency_hz;
        let periods_per_interval = model.noise.interval_s / period_s;
        let noise_interval_fixed = (periods_per_interval * 4_294_967_296.0).round();
        let noiseless = model.friction.sigma == 0.0 && model.normal_force.sigma == 0.0 && !model.effects.any();
        let representable = noise_interval_fixed >= 1.0 && noise_interval_fixed < 2f64.powi(63);
        if !noiseless && !representable {
            return Err(Error::InvalidParameter {
                key: "noise.interval_s".into(),
                value: model.noise.interval_s.to_string(),
                message: format!(
                    "the hold interval is {periods_per_interval:e} excitation periods at {} Hz; \
                     it must lie between 2^-32 and 2^31 periods",
                    condition.excitation_frequency_hz
                ),
            });
        }
        let normal_force_mean_n =
            condition.normal_force_n * model.effects.normal_force_drift.as_ref().map_or(1.0, |d| d.nominal_scale());
        let effects = EffectParams::new(
            &model.effects,
            condition.normal_force_n,
            model.friction.a + model.friction.b,
            model.noise.interval_s,
        );
        let steps_per_period = Self::steps_resolving(model, condition)?.max(Self::steps_resolving_the_law(
            model,
            condition,
            &effects,
            normal_force_mean_n,
        )?);
        Ok(Oscillator {
            mass_kg: model.rig.mass_kg,
            stiffness_n_per_m: model.stiffness_n_per_m(),
            damping_n_s_per_m: model.damping_n_s_per_m(),
            base_amplitude_m: model.excitation.amplitude_m,
            omega_rad_per_s: omega,
            period_s,
            friction_a: model.friction.a,
            friction_b: model.friction.b,
            friction_c_s_per_m: model.friction.c,
            friction_d_s2_per_m2: model.friction.d,
            friction_sigma: model.friction.sigma,
            normal_force_mean_n,
            normal_force_sigma_n: model.normal_force.sigma,
            steps_per_period,
            noise_interval_s: model.noise.interval_s,
            effects,
            // Without noise there is nothing to hold: no boundaries split the steps.
            noise_interval_fixed: if noiseless { Self::NOISELESS_INTERVAL } else { noise_interval_fixed as u64 },
        })
    }

    /// The model's steps per period, raised where a friction memory is on
    /// so that no step is longer than its memory time: classical RK4 on
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
    /// Unchanged for every other model and where the memory time is longer
    /// than a step. A memory that would need more than
    /// [`Solver::MAX_STEPS_PER_PERIOD`] steps is refused, by name.
    fn steps_resolving(model: &Model, condition: Condition) -> Result<u32> {
        let steps = model.solver.steps_per_period.max(Self::steps_resolving_the_rig(model, condition)?);
        let Some(h) = model.effects.friction_hysteresis.as_ref() else {
            return Ok(steps);
        };
        let period_s = 1.0 / condition.excitation_frequency_hz;
        let fastest_hz = condition.excitation_frequency_hz.max(model.rig.natural_frequency_hz);
        let speed_scale =
            std::f64::consts::TAU * fastest_hz * model.linear_amplitude_m(condition.excitation_frequency_hz);
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
            _ => return Ok(steps),
        };
        let needed = (period_s / memory_s).ceil();
        // NaN too (no finite speed scale): refused.
        if needed.is_nan() || needed > f64::from(Solver::MAX_STEPS_PER_PERIOD) {
            return Err(Error::InvalidParameter {
                key: key.into(),
                value: value.to_string(),
                message: format!(
                    "{what} needs {needed:e} steps per period at {} Hz to be integrated stably; at most {} are \
                     allowed",
                    condition.excitation_frequency_hz,
                    Solver::MAX_STEPS_PER_PERIOD
                ),
            });
        }
        Ok(steps.max(needed as u32))
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
        let needed = (rate_per_s / condition.excitation_frequency_hz).ceil();
        if needed.is_nan() || needed > f64::from(Solver::MAX_STEPS_PER_PERIOD) {
            return Err(Error::InvalidParameter {
                key: "friction.b".into(),
                value: f.b.to_string(),
                message: format!(
                    "a friction law rising from rest by {slope_s_per_m:e} per m/s (b = {}, c = {} s/m) settles a \
                     slip at {load_n:.3} N within {:.2e} s, which needs {needed:.3e} steps per period at {} Hz to be \
                     integrated stably; at most {} are allowed",
                    f.b,
                    f.c,
                    1.0 / rate_per_s,
                    condition.excitation_frequency_hz,
                    Solver::MAX_STEPS_PER_PERIOD
                ),
            });
        }
        Ok(needed as u32)
    }

    /// Steps per excitation period that give a swing at the rig's natural
    /// frequency f0 at least [`NATURAL_PERIOD_STEPS`] steps: RK4 is stable
    /// only below ω0·dt ≈ 2.8, and a stiff rig driven far below resonance
    /// (f0 = 1 kHz at 8 Hz) would otherwise diverge at the default steps.
    /// On the paper rig (f0 near 10 Hz, 5–15 Hz) it asks for at most 32,
    /// below the default. A rig that would need more than
    /// [`Solver::MAX_STEPS_PER_PERIOD`] is refused, by name.
    fn steps_resolving_the_rig(model: &Model, condition: Condition) -> Result<u32> {
        let needed = (NATURAL_PERIOD_STEPS * model.rig.natural_frequency_hz / condition.excitation_frequency_hz).ceil();
        if needed.is_nan() || needed > f64::from(Solver::MAX_STEPS_PER_PERIOD) {
            return Err(Error::InvalidParameter {
                key: "rig.natural_frequency_hz".into(),
                value: model.rig.natural_frequency_hz.to_string(),
                message: format!(
                    "a natural frequency {:e} times the excitation's ({} Hz) needs {needed:e} steps per period to be \
                     integrated stably ({NATURAL_PERIOD_STEPS} per natural period); at most {} are allowed",
                    model.rig.natural_frequency_hz / condition.excitation_frequency_hz,
                    condition.excitation_frequency_hz,
                    Solver::MAX_STEPS_PER_PERIOD
                ),
            });
        }
        Ok(needed as u32)
    }

    /// The noise interval of a noiseless model: 2^31 − 1 periods, longer
    /// than any run, so no boundary ever splits a step.
    pub const NOISELESS_INTERVAL: u64 = ((1 << 31) - 1) << 32;

    /// How many noise intervals a run of `periods` excitation periods spans.
    pub fn noise_intervals_in(&self, periods: u64) -> u128 {
        ((periods as u128) << 32) / self.noise_interval_fixed as u128 + 1
    }
}
