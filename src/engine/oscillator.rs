//! What the integrators work on: the constants of one grid point derived
//! from a model ([`Oscillator`]), the initial state, how long a realisation
//! runs ([`RunPlan`]), where its peaks are binned ([`PeakRange`]), and what
//! one realisation produces ([`PathResult`], [`Sample`]). Both backends
//! share these types.

use serde::{Deserialize, Serialize};

use crate::engine::effects::EffectParams;
use crate::engine::model::{Condition, Model};
use crate::engine::steps;
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
    /// Where a normal-force drift's clock starts, s from the run's start:
    /// the end of the job's warm-up ([`crate::engine::Job::oscillators`];
    /// 0 for an oscillator made alone). The force holds its starting value
    /// until then, so what is measured sees the same drift whatever the
    /// warm-up (a number of periods: seconds that differ with the
    /// frequency).
    pub drift_start_s: f64,
}

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
        let steps_per_period = steps::steps_per_period(model, condition, &effects, normal_force_mean_n)?;
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
            drift_start_s: 0.0,
        })
    }

    /// A drift's time at `t_s` (s from the run's start), s: from
    /// [`Oscillator::drift_start_s`], 0 before it.
    pub fn drift_time_s(&self, t_s: f64) -> f64 {
        (t_s - self.drift_start_s).max(0.0)
    }

    /// The noise interval of a noiseless model: 2^31 − 1 periods, longer
    /// than any run, so no boundary ever splits a step.
    pub const NOISELESS_INTERVAL: u64 = ((1 << 31) - 1) << 32;

    /// How many noise intervals a run of `periods` excitation periods spans.
    pub fn noise_intervals_in(&self, periods: u64) -> u128 {
        ((periods as u128) << 32) / self.noise_interval_fixed as u128 + 1
    }
}
