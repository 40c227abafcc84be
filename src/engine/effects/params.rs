//! The effects flattened for one grid point, as both integrators read them.

use super::{ColourForm, DriftForm, Effects, HarmonicForm, HysteresisForm, LoadForm, NonGaussianForm, StictionForm};

/// Effect parameters for one grid point, flattened for the integrators.
/// An absent effect has its first (candidate) form at zero strength: the
/// baseline. That is [`EffectParams::new`] of no effects, not `default()`
/// (whose shares, hold interval and law factor are 0).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EffectParams {
    pub harmonic_form: HarmonicForm,
    /// Amplitudes at this point's N0 (load scaling applied), N; for the
    /// `position` form α N0 and β N0 (N per U0 and per U0² of
    /// displacement), the other two 0.
    pub harmonic_amplitudes_n: [f64; 4],
    /// rad
    pub harmonic_phases_rad: [f64; 4],
    /// (cos, sin) of each phase, so the CPU reference turns the phase by
    /// angle addition instead of a `cos` per harmonic per noise interval.
    pub harmonic_phase_cos_sin: [(f64, f64); 4],
    pub harmonic_shape: f64,
    /// Mean of max(0, cos)^shape over a period (bumps form).
    pub harmonic_shape_mean: f64,
    pub non_gaussian_form: NonGaussianForm,
    /// Strength at this point's N0 (load scaling applied), –.
    pub non_gaussian_strength: f64,
    /// The `polynomial` form's cubic coefficient at this point's N0 (load
    /// scaling applied), –.
    pub non_gaussian_cubic: f64,
    pub hysteresis_form: HysteresisForm,
    /// Build-up length δ, or the slip distance L of `slip` and `ageing`, m.
    pub hysteresis_length_m: f64,
    /// Memory time of the `lag` form, s.
    pub hysteresis_lag_s: f64,
    /// B of the `ageing` form, –.
    pub hysteresis_strength: f64,
    pub colour_form: ColourForm,
    /// AR(1) coefficient per interval, –.
    pub colour_rho: f64,
    /// Coloured share of the variance (`ar1`), –.
    pub colour_share: f64,
    /// AR(1) coefficients per interval of `multi_scale`'s parts (τc/4, τc,
    /// 4τc), or of `fast_slow`'s (τc, 10 τc, unused), –.
    pub colour_rhos: [f64; 3],
    /// Intervals a value is held (hold form).
    pub colour_hold_intervals: u32,
    pub stiction_form: StictionForm,
    pub stiction_excess: f64,
    /// Slip over which the constant form's excess fades, m.
    pub stiction_release_m: f64,
    /// Ageing time of the `dwell` form, s.
    pub stiction_dwell_s: f64,
    /// Δa at this point's N0, –.
    pub friction_offset: f64,
    /// Factor (N0/Nref)^k of the law's a, b and d at this point's N0
    /// (load dependence `scaled`; exactly 1 otherwise), –.
    pub friction_scale: f64,
    /// Adhesion force A added to the friction force's magnitude (load
    /// dependence `adhesion`; 0 otherwise), N.
    pub adhesion_force_n: f64,
    pub drift_form: DriftForm,
    /// 1/s
    pub drift_rate_per_s: f64,
    /// 1/s²
    pub drift_curvature_per_s2: f64,
}

/// E[max(0, cos θ)^p] over θ uniform: Γ((p+1)/2) / (2 √π Γ(p/2 + 1)).
fn bump_mean(p: f64) -> f64 {
    use statrs::function::gamma::gamma;
    gamma((p + 1.0) / 2.0) / (2.0 * std::f64::consts::PI.sqrt() * gamma(p / 2.0 + 1.0))
}

impl EffectParams {
    /// Flattens `effects` for a point with mean normal force `n0` (N), the
    /// friction law's level at rest `mu_at_rest` (a + b, –) and noise hold
    /// interval `interval_s` (s).
    pub fn new(effects: &Effects, n0: f64, mu_at_rest: f64, interval_s: f64) -> EffectParams {
        let mut p = EffectParams {
            harmonic_shape: 2.0,
            colour_hold_intervals: 1,
            colour_share: 1.0,
            friction_scale: 1.0,
            ..Default::default()
        };
        if let Some(h) = &effects.normal_force_harmonics {
            p.harmonic_form = h.form;
            p.harmonic_amplitudes_n = match h.form {
                HarmonicForm::Position => [h.amplitudes_per_n0[0] * n0, h.amplitudes_per_n0[1] * n0, 0.0, 0.0],
                _ => std::array::from_fn(|k| h.amplitudes_n[k] + h.amplitudes_per_n0[k] * n0),
            };
            p.harmonic_phases_rad = h.phases_rad;
            p.harmonic_phase_cos_sin = h.phases_rad.map(|phase| {
                let (sin, cos) = phase.sin_cos();
                (cos, sin)
            });
            p.harmonic_shape = h.shape;
            p.harmonic_shape_mean = bump_mean(h.shape);
        }
        if let Some(g) = &effects.non_gaussian_friction {
            p.non_gaussian_form = g.form;
            let scale =
                if g.load_exponent == 0.0 { 1.0 } else { (n0.max(1e-9) / g.reference_force_n).powf(g.load_exponent) };
            p.non_gaussian_strength = g.strength * scale;
            p.non_gaussian_cubic = g.cubic * scale;
            match g.form {
                NonGaussianForm::TukeyH => p.non_gaussian_strength = p.non_gaussian_strength.min(0.24),
                NonGaussianForm::Polynomial => {
                    // A load scaling may carry the coefficients out of the
                    // form's range at another load.
                    (p.non_gaussian_strength, p.non_gaussian_cubic) =
                        super::polynomial_within_reach(p.non_gaussian_strength, p.non_gaussian_cubic);
                }
                _ => {}
            }
        }
        if let Some(h) = &effects.friction_hysteresis {
            p.hysteresis_form = h.form;
            p.hysteresis_length_m = h.length_m;
            p.hysteresis_lag_s = h.time_constant_s;
            p.hysteresis_strength = h.strength;
        }
        if let Some(c) = &effects.coloured_friction_noise {
            p.colour_form = c.form;
            let rho = |tau_s: f64| if tau_s > 0.0 { (-interval_s / tau_s).exp() } else { 0.0 };
            p.colour_rho = rho(c.correlation_time_s);
            p.colour_share = c.coloured_share;
            p.colour_rhos = match c.form {
                ColourForm::FastSlow => [rho(c.correlation_time_s), rho(10.0 * c.correlation_time_s), 0.0],
                _ => [0.25, 1.0, 4.0].map(|f| rho(f * c.correlation_time_s)),
            };
            p.colour_hold_intervals = ((c.correlation_time_s / interval_s).round() as u32).max(1);
        }
        if let Some(s) = &effects.stiction {
            p.stiction_form = s.form;
            p.stiction_excess = s.excess;
            p.stiction_release_m = s.release_length_m;
            p.stiction_dwell_s = s.dwell_time_s;
        }
        if let Some(l) = &effects.load_dependent_friction {
            let r = l.reference_force_n;
            p.friction_offset = match l.form {
                LoadForm::Linear => l.strength * (n0 - r),
                LoadForm::Quadratic => (l.strength + l.curvature_per_n2 * (n0 - r)) * (n0 - r),
                LoadForm::Power => mu_at_rest.max(0.0) * ((n0.max(1e-9) / r).powf(l.strength) - 1.0),
                LoadForm::Saturating => l.strength * r * (1.0 - (-(n0 - r) / r).exp()),
                LoadForm::Exponential => l.strength * r * (((n0 - r) / r).exp() - 1.0),
                LoadForm::Adhesion | LoadForm::Scaled => 0.0,
            };
            if l.form == LoadForm::Adhesion {
                p.adhesion_force_n = l.strength;
            }
            // Only where k is not 0, so that k = 0 multiplies by exactly 1.
            if l.form == LoadForm::Scaled && l.strength != 0.0 {
                p.friction_scale = (n0.max(1e-9) / r).powf(l.strength);
            }
        }
        if let Some(d) = &effects.normal_force_drift {
            p.drift_form = d.form;
            p.drift_rate_per_s = d.rate_per_s;
            p.drift_curvature_per_s2 = d.curvature_per_s2;
        }
        p
    }
}

/// The friction memory the slip ODE carries as its third state (hysteresis
/// `lag`, `slip` or `ageing` switched on), or none. The kernel sees the
/// codes as the generated `MEMORY_*` constants.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Memory {
    None = 0,
    /// μ_f lags the steady law in time (memory time τ_m).
    Lag = 1,
    /// μ_f relaxes to the steady law over a slip distance L (the slip law).
    Slip = 2,
    /// The contact age θ of the ageing law.
    Ageing = 3,
}

impl Memory {
    /// Every memory, in code order, with its name in the kernel's constants.
    pub(crate) const ALL: [(Memory, &'static str); 4] =
        [(Memory::None, "NONE"), (Memory::Lag, "LAG"), (Memory::Slip, "SLIP"), (Memory::Ageing, "AGEING")];

    /// The memory of flattened effects: on where its form's strength is not
    /// zero (`lag`: τ_m > 0; `slip`: L > 0; `ageing`: L > 0 and B ≠ 0). The
    /// kernel's `memory_form` is the same.
    pub(crate) fn form(e: &EffectParams) -> Memory {
        match e.hysteresis_form {
            HysteresisForm::Lag if e.hysteresis_lag_s > 0.0 => Memory::Lag,
            HysteresisForm::Slip if e.hysteresis_length_m > 0.0 => Memory::Slip,
            HysteresisForm::Ageing if e.hysteresis_length_m > 0.0 && e.hysteresis_strength != 0.0 => Memory::Ageing,
            _ => Memory::None,
        }
    }
}
