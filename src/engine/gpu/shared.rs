//! The host structs shared with the WGSL, field for field. Each is
//! `#[repr(C)]` and `Pod` with 4-byte fields only, so Rust and WGSL lay them
//! out alike without implicit padding; `tests/integration/layout.rs` parses
//! the assembled shader with naga and checks every size and offset.

use bytemuck::{Pod, Zeroable};

use crate::engine::RunPlan;
use crate::engine::effects::{self, Effects, Form, HysteresisForm, Memory};
use crate::engine::oscillator::{Oscillator, Point};
use crate::engine::rng;

/// Uniform parameters of `ensemble.wgsl` (struct `Params`): the rig, the
/// baseline friction law and noise, and this dispatch's slice of the run.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Params {
    /// kg
    pub mass_kg: f32,
    /// N/m
    pub stiffness_n_per_m: f32,
    /// N·s/m
    pub damping_n_s_per_m: f32,
    /// m
    pub base_amplitude_m: f32,
    /// –
    pub friction_a: f32,
    /// –
    pub friction_b: f32,
    /// s/m
    pub friction_c_s_per_m: f32,
    /// s²/m²
    pub friction_d_s2_per_m2: f32,
    /// –
    pub friction_sigma: f32,
    /// N
    pub normal_force_sigma_n: f32,
    pub warmup_cycles: u32,
    pub seed_lo: u32,
    pub seed_hi: u32,
    /// Invocations in this dispatch.
    pub invocations: u32,
    pub realisations_per_point: u32,
    /// Realisation index of the dispatch's first realisation of each point.
    pub realisation_offset: u32,
    /// Index (from the start of the run) of the first cycle of this dispatch.
    pub first_cycle: u32,
    /// Cycles integrated by this dispatch.
    pub cycles: u32,
    /// Index into the grid-point buffer of this dispatch's first point.
    pub point_offset: u32,
    /// 1: also write every measured peak to the peaks buffer.
    pub record_peaks: u32,
    /// 1: write a sample at every noise boundary of the measured cycles to
    /// the samples buffer (records aligned with the noise).
    pub record_samples: u32,
    /// Samples per path in the samples buffer: the most noise boundaries
    /// one dispatch crosses.
    pub sample_slots: u32,
}

/// The effects as the kernel sees them (struct `EffectParams`, uniform):
/// [`effects::EffectParams`] in f32, forms as their `u32` codes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct EffectParams {
    pub harmonic_form: u32,
    pub harmonic_shape: f32,
    pub harmonic_shape_mean: f32,
    pub non_gaussian_form: u32,
    /// rad
    pub harmonic_phase_1_rad: f32,
    pub harmonic_phase_2_rad: f32,
    pub harmonic_phase_3_rad: f32,
    pub harmonic_phase_4_rad: f32,
    pub hysteresis_form: u32,
    /// Build-up length, or the slip distance of `slip` and `ageing`, m.
    pub hysteresis_length_m: f32,
    /// s
    pub hysteresis_lag_s: f32,
    pub colour_form: u32,
    pub colour_rho: f32,
    pub colour_share: f32,
    pub colour_rho_1: f32,
    pub colour_rho_2: f32,
    pub colour_rho_3: f32,
    pub colour_hold_intervals: u32,
    pub stiction_form: u32,
    pub stiction_excess: f32,
    /// m
    pub stiction_release_m: f32,
    /// s
    pub stiction_dwell_s: f32,
    pub drift_form: u32,
    /// 1/s
    pub drift_rate_per_s: f32,
    /// s
    pub noise_interval_s: f32,
    /// 1/s²
    pub drift_curvature_per_s2: f32,
    /// B of hysteresis `ageing`, –.
    pub hysteresis_strength: f32,
    /// Adhesion force A of load dependence `adhesion`, N.
    pub adhesion_force_n: f32,
}

impl EffectParams {
    /// The uniform for an oscillator's effects (the per-point ones are in
    /// [`GridPoint`]).
    pub fn from_oscillator(o: &Oscillator) -> EffectParams {
        Self::from_effects(&o.effects, o.noise_interval_s)
    }

    /// The uniform for flattened effects and a noise hold interval, s.
    fn from_effects(e: &effects::EffectParams, noise_interval_s: f64) -> EffectParams {
        EffectParams {
            harmonic_form: e.harmonic_form.code(),
            harmonic_shape: e.harmonic_shape as f32,
            harmonic_shape_mean: e.harmonic_shape_mean as f32,
            non_gaussian_form: e.non_gaussian_form.code(),
            harmonic_phase_1_rad: e.harmonic_phases_rad[0] as f32,
            harmonic_phase_2_rad: e.harmonic_phases_rad[1] as f32,
            harmonic_phase_3_rad: e.harmonic_phases_rad[2] as f32,
            harmonic_phase_4_rad: e.harmonic_phases_rad[3] as f32,
            hysteresis_form: e.hysteresis_form.code(),
            hysteresis_length_m: e.hysteresis_length_m as f32,
            hysteresis_lag_s: e.hysteresis_lag_s as f32,
            colour_form: e.colour_form.code(),
            colour_rho: e.colour_rho as f32,
            colour_share: e.colour_share as f32,
            colour_rho_1: e.colour_rhos[0] as f32,
            colour_rho_2: e.colour_rhos[1] as f32,
            colour_rho_3: e.colour_rhos[2] as f32,
            colour_hold_intervals: e.colour_hold_intervals,
            stiction_form: e.stiction_form.code(),
            stiction_excess: e.stiction_excess as f32,
            stiction_release_m: e.stiction_release_m as f32,
            stiction_dwell_s: e.stiction_dwell_s as f32,
            drift_form: e.drift_form.code(),
            drift_rate_per_s: e.drift_rate_per_s as f32,
            noise_interval_s: noise_interval_s as f32,
            drift_curvature_per_s2: e.drift_curvature_per_s2 as f32,
            hysteresis_strength: e.hysteresis_strength as f32,
            adhesion_force_n: e.adhesion_force_n as f32,
        }
    }

    /// The uniform of a model without effects, its noise interval 0: what
    /// the kernel specialised for that case has compiled in
    /// (`source::ensemble_wgsl_without_effects`).
    pub fn without_effects() -> EffectParams {
        Self::from_effects(&effects::EffectParams::new(&Effects::default(), 0.0, 0.0, 0.0), 0.0)
    }

    /// The friction memory the kernel's `memory_form()` decides from this
    /// uniform (its f32 values, so that the two agree): the one
    /// `source::ensemble_wgsl_with_memory` fixes.
    pub(crate) fn memory(&self) -> Memory {
        let form = |f: HysteresisForm| self.hysteresis_form == f.code();
        if form(HysteresisForm::Lag) && self.hysteresis_lag_s > 0.0 {
            Memory::Lag
        } else if form(HysteresisForm::Slip) && self.hysteresis_length_m > 0.0 {
            Memory::Slip
        } else if form(HysteresisForm::Ageing) && self.hysteresis_length_m > 0.0 && self.hysteresis_strength != 0.0 {
            Memory::Ageing
        } else {
            Memory::None
        }
    }

    /// Whether this uniform is [`EffectParams::without_effects`] but for
    /// the noise interval (which that kernel still reads).
    pub fn is_without_effects(&self) -> bool {
        EffectParams { noise_interval_s: 0.0, ..*self } == Self::without_effects()
    }
}

/// One grid point as the kernel sees it (struct `GridPoint`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GridPoint {
    /// rad/s
    pub omega_rad_per_s: f32,
    /// s
    pub period_s: f32,
    /// N
    pub normal_force_mean_n: f32,
    /// Noise hold interval in periods, 32.32 fixed point: whole part.
    pub noise_interval_whole: u32,
    /// Fractional part (units of 2^-32 periods).
    pub noise_interval_frac: u32,
    /// m
    pub initial_x_m: f32,
    /// m/s
    pub initial_v_m_per_s: f32,
    /// Centre of the peak range, m.
    pub peak_centre_m: f32,
    /// 1 / quantisation step, 1/m.
    pub inv_quantum_per_m: f32,
    /// Lower edge of the first inner histogram bin, m.
    pub histogram_lo_m: f32,
    /// Inner histogram bins per metre, 1/m.
    pub histogram_bins_per_m: f32,
    /// Load-dependent friction offset Δa at this point, –.
    pub friction_offset: f32,
    /// Non-Gaussian strength at this point's N0, –.
    pub non_gaussian_strength: f32,
    /// The `polynomial` non-Gaussian form's cubic coefficient at this point's N0, –.
    pub non_gaussian_cubic: f32,
    /// Phases are reduced as their deviation from this angle, rad.
    pub phase_ref_rad: f32,
    /// Normal-force harmonic amplitudes at this point's N0, N.
    pub harmonic_amplitude_1_n: f32,
    pub harmonic_amplitude_2_n: f32,
    pub harmonic_amplitude_3_n: f32,
    pub harmonic_amplitude_4_n: f32,
    /// Factor (N0/Nref)^k of the law's a, b and d at this point (load
    /// dependence `scaled`; exactly 1 otherwise), –.
    pub friction_scale: f32,
    /// Integration steps per period at this point (the model's, raised by
    /// frequency where a friction memory needs it: `Oscillator`).
    pub steps_per_period: u32,
    /// Added to `Params::realisation_offset` for this point's realisation
    /// numbers (`Point::realisation_offset`).
    pub realisation_offset: u32,
    /// Where a normal-force drift's clock starts, s from the run's start
    /// (`Oscillator::drift_start_s`).
    pub drift_start_s: f32,
}

/// Per-invocation state kept between dispatches (struct `PathState`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PathState {
    pub x_m: f32,
    pub v_m_per_s: f32,
    pub mode: i32,
    pub period: u32,
    pub interval: u32,
    pub next_boundary_whole: u32,
    pub next_boundary_frac: u32,
    pub friction_noise: f32,
    pub normal_force_n: f32,
    /// Time stuck during measured cycles, s.
    pub stick_time_s: f32,
    pub slip_start_x_m: f32,
    pub colour_state: f32,
    pub interval_phase: f32,
    pub stiction_excess: f32,
    pub colour_state_1: f32,
    pub colour_state_2: f32,
    /// The friction memory: μ_f of hysteresis `lag` and `slip` (–), the
    /// contact age θ of `ageing` (s).
    pub memory: f32,
    /// When the current stick began, s from the run's start.
    pub stick_since_s: f32,
    /// The static coefficient's contact-age term of hysteresis `ageing`, –.
    pub ageing_excess: f32,
    /// The `random_walk` drift's walk W (N0 is times 1 + W), –.
    pub drift_walk: f32,
}

/// Uniform of `check.wgsl` (struct `CheckParams`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CheckParams {
    pub seed_lo: u32,
    pub seed_hi: u32,
    pub first: u32,
    pub count: u32,
}

impl Params {
    /// The uniform for a chunk of points sharing `osc`'s model, before the
    /// dispatch fields (`invocations`, `first_cycle`, `cycles`) are set.
    pub fn new(
        osc: &Oscillator,
        seed: u64,
        plan: RunPlan,
        realisations_per_point: u32,
        realisation_offset: u32,
        record_peaks: bool,
    ) -> Params {
        let [seed_lo, seed_hi] = rng::seed_key(seed);
        Params {
            mass_kg: osc.mass_kg as f32,
            stiffness_n_per_m: osc.stiffness_n_per_m as f32,
            damping_n_s_per_m: osc.damping_n_s_per_m as f32,
            base_amplitude_m: osc.base_amplitude_m as f32,
            friction_a: osc.friction_a as f32,
            friction_b: osc.friction_b as f32,
            friction_c_s_per_m: osc.friction_c_s_per_m as f32,
            friction_d_s2_per_m2: osc.friction_d_s2_per_m2 as f32,
            friction_sigma: osc.friction_sigma as f32,
            normal_force_sigma_n: osc.normal_force_sigma_n as f32,
            warmup_cycles: plan.warmup_cycles,
            seed_lo,
            seed_hi,
            invocations: 0,
            realisations_per_point,
            realisation_offset,
            first_cycle: 0,
            cycles: 0,
            point_offset: 0,
            record_peaks: u32::from(record_peaks),
            record_samples: 0,
            sample_slots: 0,
        }
    }
}

impl GridPoint {
    /// One point as the kernel sees it.
    pub fn new(point: &Point, o: &Oscillator) -> GridPoint {
        GridPoint {
            omega_rad_per_s: o.omega_rad_per_s as f32,
            period_s: o.period_s as f32,
            normal_force_mean_n: o.normal_force_mean_n as f32,
            noise_interval_whole: (o.noise_interval_fixed >> 32) as u32,
            noise_interval_frac: o.noise_interval_fixed as u32,
            initial_x_m: point.initial.x_m as f32,
            initial_v_m_per_s: point.initial.v_m_per_s as f32,
            peak_centre_m: point.range.centre_f32(),
            inv_quantum_per_m: point.range.inv_quantum_f32(),
            histogram_lo_m: point.range.lo_m as f32,
            histogram_bins_per_m: point.range.bins_per_m_f32(),
            friction_offset: o.effects.friction_offset as f32,
            non_gaussian_strength: o.effects.non_gaussian_strength as f32,
            non_gaussian_cubic: o.effects.non_gaussian_cubic as f32,
            phase_ref_rad: point.range.phase_ref_f32(),
            harmonic_amplitude_1_n: o.effects.harmonic_amplitudes_n[0] as f32,
            harmonic_amplitude_2_n: o.effects.harmonic_amplitudes_n[1] as f32,
            harmonic_amplitude_3_n: o.effects.harmonic_amplitudes_n[2] as f32,
            harmonic_amplitude_4_n: o.effects.harmonic_amplitudes_n[3] as f32,
            friction_scale: o.effects.friction_scale as f32,
            steps_per_period: o.steps_per_period,
            realisation_offset: point.realisation_offset,
            drift_start_s: o.drift_start_s as f32,
        }
    }
}
