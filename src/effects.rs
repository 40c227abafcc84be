//! The unmodelled effects of `shared/spec/model.md`, as optional extensions
//! of the baseline. Each has its own table in the model file, a `form` (how
//! it is shaped) and a strength; at zero strength the arithmetic reduces
//! exactly to the baseline's, so paths are bit-identical (a test checks it).
//!
//! The first form of each effect is the one `diagnose` fits (the candidate);
//! the others exist so synthetic data can carry an effect whose shape no
//! candidate matches exactly. Grounding in the literature:
//! - harmonics of the normal force: the paper's Figure 4 (misalignment 1×,
//!   uneven wear 2×, bumps higher);
//! - non-Gaussian friction noise: the paper's Figure 6 (skew growing with load);
//! - hysteresis: frictional memory (Hess & Soom 1990), Dahl's pre-sliding
//!   build-up of friction over a characteristic displacement after reversal;
//! - coloured friction noise: correlated asperity contact (Ornstein–Uhlenbeck);
//! - stiction: static friction above kinetic at breakaway (Rabinowicz; LuGre);
//! - load-dependent friction: μ changing with contact pressure;
//! - normal-force drift: wear and heating during a run (paper §2.2.1).
//!
//! Everything time-varying is evaluated once per noise interval (at the
//! interval's start) and held, like the noise itself: results do not depend
//! on the step size, and breakaway from stick stays a closed-form event.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Periodic parts of N(t) at 1×..4× the excitation frequency.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NormalForceHarmonics {
    /// `fourier`: Σ A_k cos(kΩt + φ_k); `bumps`: Σ A_k (max(0, cos(kΩt + φ_k))^shape − its mean);
    /// `square`: Σ A_k tanh(shape·cos(kΩt + φ_k)) / tanh(shape).
    #[serde(default)]
    pub form: HarmonicForm,
    /// Amplitudes A_1..A_4, N.
    pub amplitudes_n: [f64; 4],
    /// Phases φ_1..φ_4, rad.
    #[serde(default)]
    pub phases_rad: [f64; 4],
    /// Shape of `bumps` (power) and `square` (sharpness), –.
    #[serde(default = "two")]
    pub shape: f64,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HarmonicForm {
    #[default]
    Fourier,
    Bumps,
    Square,
}

/// A skewed or heavy-tailed random part of the friction coefficient.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NonGaussianFriction {
    /// `skew`: (z + s (z'² − 1)/√2)/√(1+s²); `lognormal`: standardised exp(s z);
    /// `tukey_h`: standardised z·exp(h z²/2) (heavy tails). All have mean 0, variance 1.
    #[serde(default)]
    pub form: NonGaussianForm,
    /// s (skew, lognormal) or h (tukey_h, < 0.5), –.
    pub strength: f64,
    /// Strength scales as (N0 / reference)^load_exponent, –.
    #[serde(default)]
    pub load_exponent: f64,
    /// Reference normal force of the load scaling, N.
    #[serde(default = "ten")]
    pub reference_force_n: f64,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NonGaussianForm {
    #[default]
    Skew,
    Lognormal,
    TukeyH,
}

/// Friction that depends on the motion's history: after each slip start the
/// sliding friction builds up over a displacement (Dahl-like pre-sliding), so
/// accelerating and decelerating branches differ.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrictionHysteresis {
    /// Build-up φ(d) of the sliding friction with displacement d since slip
    /// start: `exponential` 1 − e^(−d/δ); `tanh` tanh(d/δ); `rational` d/(d+δ).
    #[serde(default)]
    pub form: HysteresisForm,
    /// Characteristic displacement δ, m.
    pub length_m: f64,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HysteresisForm {
    #[default]
    Exponential,
    Tanh,
    Rational,
}

/// A friction noise correlated for longer than one hold interval.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColouredFrictionNoise {
    /// `ar1`: Ornstein–Uhlenbeck sampled per interval, ρ = e^(−τ/τc);
    /// `hold`: each value held for round(τc/τ) intervals;
    /// `two_scale`: half white, half AR(1) with τc (variance split equally;
    /// white only when τc = 0).
    #[serde(default)]
    pub form: ColourForm,
    /// Correlation time τc, s.
    pub correlation_time_s: f64,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ColourForm {
    #[default]
    Ar1,
    Hold,
    TwoScale,
}

/// Breakaway friction above the friction just above zero velocity.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stiction {
    /// `constant`: μ_s = μ(0) + Δ, and after breakaway an extra
    /// Δ·max(0, 1 − d/L) that fades linearly over the first `release_length_m`
    /// L of slip (L = 0: friction drops to the kinetic law at once);
    /// `noisy`: Δ·max(0, 1 + z/2) per interval, dropping at once;
    /// `decaying`: Δ at breakaway, and an extra Δ·e^(−d/0.1 mm) while the
    /// slip begins (a smooth static-to-kinetic transition).
    #[serde(default)]
    pub form: StictionForm,
    /// Excess Δ of the static coefficient, –.
    pub excess: f64,
    /// Slip L over which the `constant` form's excess fades, m (0: at once).
    #[serde(default)]
    pub release_length_m: f64,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StictionForm {
    #[default]
    Constant,
    Noisy,
    Decaying,
}

/// The mean friction coefficient changes with the normal-force level N0.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadDependentFriction {
    /// Offset Δa added to `a`: `linear` k (N0 − Nref) with k in 1/N;
    /// `power` a ((N0/Nref)^k − 1); `saturating` k Nref (1 − e^(−(N0 − Nref)/Nref)).
    #[serde(default)]
    pub form: LoadForm,
    /// k (see `form`).
    pub strength: f64,
    /// Reference normal force Nref, N.
    #[serde(default = "ten")]
    pub reference_force_n: f64,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LoadForm {
    #[default]
    Linear,
    Power,
    Saturating,
}

/// The mean normal force drifts during a run (time t from the run's start).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NormalForceDrift {
    /// N0 × `linear` (1 + r t); `saturating` (1 + r·20 s·(1 − e^(−t/20 s)));
    /// `wander` (1 + r·15 s·sin(t/15 s)).
    #[serde(default)]
    pub form: DriftForm,
    /// Initial relative rate r, 1/s.
    pub rate_per_s: f64,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DriftForm {
    #[default]
    Linear,
    Saturating,
    Wander,
}

fn two() -> f64 {
    2.0
}

fn ten() -> f64 {
    10.0
}

/// Time scale of the `saturating` drift, s.
pub const DRIFT_SATURATION_S: f64 = 20.0;
/// Time scale of the `wander` drift, s.
pub const DRIFT_WANDER_S: f64 = 15.0;
/// Displacement over which `decaying` stiction fades, m.
pub const STICTION_DECAY_M: f64 = 1e-4;

/// All effects of a model; `None` is off.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Effects {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal_force_harmonics: Option<NormalForceHarmonics>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub non_gaussian_friction: Option<NonGaussianFriction>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction_hysteresis: Option<FrictionHysteresis>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coloured_friction_noise: Option<ColouredFrictionNoise>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiction: Option<Stiction>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load_dependent_friction: Option<LoadDependentFriction>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal_force_drift: Option<NormalForceDrift>,
}

/// The effect names of `model.md`, in a fixed order.
pub const EFFECT_NAMES: [&str; 7] = [
    "normal_force_harmonics",
    "non_gaussian_friction",
    "friction_hysteresis",
    "coloured_friction_noise",
    "stiction",
    "load_dependent_friction",
    "normal_force_drift",
];

fn check(key: &str, value: f64, ok: bool, message: &str) -> Result<()> {
    if value.is_finite() && ok {
        Ok(())
    } else {
        Err(Error::InvalidParameter { key: key.into(), value: value.to_string(), message: message.into() })
    }
}

impl Effects {
    /// Whether any effect table is present (then noise intervals matter even
    /// without noise).
    pub fn any(&self) -> bool {
        self.normal_force_harmonics.is_some()
            || self.non_gaussian_friction.is_some()
            || self.friction_hysteresis.is_some()
            || self.coloured_friction_noise.is_some()
            || self.stiction.is_some()
            || self.load_dependent_friction.is_some()
            || self.normal_force_drift.is_some()
    }

    /// Range checks; errors name the dotted key.
    pub fn validate(&self) -> Result<()> {
        if let Some(h) = &self.normal_force_harmonics {
            for (k, (a, p)) in h.amplitudes_n.iter().zip(&h.phases_rad).enumerate() {
                check(&format!("normal_force_harmonics.amplitudes_n[{k}]"), *a, true, "must be a finite number of N")?;
                check(&format!("normal_force_harmonics.phases_rad[{k}]"), *p, true, "must be a finite angle")?;
            }
            check("normal_force_harmonics.shape", h.shape, h.shape > 0.0, "must be > 0")?;
        }
        if let Some(g) = &self.non_gaussian_friction {
            let ok = match g.form {
                NonGaussianForm::Skew => true,
                NonGaussianForm::Lognormal => g.strength >= 0.0 && g.strength <= 3.0,
                NonGaussianForm::TukeyH => (0.0..0.25).contains(&g.strength),
            };
            check("non_gaussian_friction.strength", g.strength, ok, "lognormal needs 0..=3, tukey_h needs 0 <= h < 0.25")?;
            check("non_gaussian_friction.load_exponent", g.load_exponent, true, "must be finite")?;
            check("non_gaussian_friction.reference_force_n", g.reference_force_n, g.reference_force_n > 0.0, "must be > 0 N")?;
        }
        if let Some(h) = &self.friction_hysteresis {
            check("friction_hysteresis.length_m", h.length_m, h.length_m >= 0.0, "must be >= 0 m")?;
        }
        if let Some(c) = &self.coloured_friction_noise {
            check("coloured_friction_noise.correlation_time_s", c.correlation_time_s, c.correlation_time_s >= 0.0, "must be >= 0 s")?;
        }
        if let Some(s) = &self.stiction {
            check("stiction.excess", s.excess, s.excess >= 0.0, "must be >= 0")?;
            check("stiction.release_length_m", s.release_length_m, s.release_length_m >= 0.0, "must be >= 0 m")?;
        }
        if let Some(l) = &self.load_dependent_friction {
            check("load_dependent_friction.strength", l.strength, true, "must be finite")?;
            check("load_dependent_friction.reference_force_n", l.reference_force_n, l.reference_force_n > 0.0, "must be > 0 N")?;
        }
        if let Some(d) = &self.normal_force_drift {
            check("normal_force_drift.rate_per_s", d.rate_per_s, true, "must be finite")?;
        }
        Ok(())
    }
}

/// Effect parameters for one grid point, flattened for the integrators.
/// Forms are small integers (0 = the candidate form); all strengths zero
/// means the baseline.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EffectParams {
    pub harmonic_form: u32,
    /// N
    pub harmonic_amplitudes_n: [f64; 4],
    /// rad
    pub harmonic_phases_rad: [f64; 4],
    pub harmonic_shape: f64,
    /// Mean of max(0, cos)^shape over a period (bumps form).
    pub harmonic_shape_mean: f64,
    pub non_gaussian_form: u32,
    /// Strength at this point's N0 (load scaling applied), –.
    pub non_gaussian_strength: f64,
    pub hysteresis_form: u32,
    /// m
    pub hysteresis_length_m: f64,
    pub colour_form: u32,
    /// AR(1) coefficient per interval, –.
    pub colour_rho: f64,
    /// Intervals a value is held (hold form).
    pub colour_hold_intervals: u32,
    pub stiction_form: u32,
    pub stiction_excess: f64,
    /// Slip over which the constant form's excess fades, m.
    pub stiction_release_m: f64,
    /// Δa at this point's N0, –.
    pub friction_offset: f64,
    pub drift_form: u32,
    /// 1/s
    pub drift_rate_per_s: f64,
}

/// E[max(0, cos θ)^p] over θ uniform: Γ((p+1)/2) / (2 √π Γ(p/2 + 1)).
fn bump_mean(p: f64) -> f64 {
    use statrs::function::gamma::gamma;
    gamma((p + 1.0) / 2.0) / (2.0 * std::f64::consts::PI.sqrt() * gamma(p / 2.0 + 1.0))
}

impl EffectParams {
    /// Flattens `effects` for a point with mean normal force `n0` (N), base
    /// friction level `a` and noise hold interval `interval_s` (s).
    pub fn new(effects: &Effects, n0: f64, a: f64, interval_s: f64) -> EffectParams {
        let mut p = EffectParams { harmonic_shape: 2.0, colour_hold_intervals: 1, ..Default::default() };
        if let Some(h) = &effects.normal_force_harmonics {
            p.harmonic_form = h.form as u32;
            p.harmonic_amplitudes_n = h.amplitudes_n;
            p.harmonic_phases_rad = h.phases_rad;
            p.harmonic_shape = h.shape;
            p.harmonic_shape_mean = bump_mean(h.shape);
        }
        if let Some(g) = &effects.non_gaussian_friction {
            p.non_gaussian_form = g.form as u32;
            let scale = if g.load_exponent == 0.0 { 1.0 } else { (n0.max(1e-9) / g.reference_force_n).powf(g.load_exponent) };
            p.non_gaussian_strength = g.strength * scale;
            if g.form == NonGaussianForm::TukeyH {
                p.non_gaussian_strength = p.non_gaussian_strength.min(0.24);
            }
        }
        if let Some(h) = &effects.friction_hysteresis {
            p.hysteresis_form = h.form as u32;
            p.hysteresis_length_m = h.length_m;
        }
        if let Some(c) = &effects.coloured_friction_noise {
            p.colour_form = c.form as u32;
            p.colour_rho = if c.correlation_time_s > 0.0 { (-interval_s / c.correlation_time_s).exp() } else { 0.0 };
            p.colour_hold_intervals = ((c.correlation_time_s / interval_s).round() as u32).max(1);
        }
        if let Some(s) = &effects.stiction {
            p.stiction_form = s.form as u32;
            p.stiction_excess = s.excess;
            p.stiction_release_m = s.release_length_m;
        }
        if let Some(l) = &effects.load_dependent_friction {
            let r = l.reference_force_n;
            p.friction_offset = match l.form {
                LoadForm::Linear => l.strength * (n0 - r),
                LoadForm::Power => a * ((n0.max(1e-9) / r).powf(l.strength) - 1.0),
                LoadForm::Saturating => l.strength * r * (1.0 - (-(n0 - r) / r).exp()),
            };
        }
        if let Some(d) = &effects.normal_force_drift {
            p.drift_form = d.form as u32;
            p.drift_rate_per_s = d.rate_per_s;
        }
        p
    }
}

/// Harmonic waveform g(c) of a form, c = cos(kθ + φ). Mirrors the kernel.
pub fn harmonic_wave(form: u32, c: f64, shape: f64, shape_mean: f64) -> f64 {
    match form {
        1 => c.max(0.0).powf(shape) - shape_mean,
        2 => (shape * c).tanh() / shape.tanh(),
        _ => c,
    }
}

/// Standardised non-Gaussian transform of a standard normal `g`, with an
/// independent standard normal `g2`. Mirrors the kernel.
pub fn non_gaussian(form: u32, s: f64, g: f64, g2: f64) -> f64 {
    match form {
        1 => {
            if s == 0.0 {
                g
            } else {
                let v = s * s;
                ((s * g).exp() - (0.5 * v).exp()) / ((v.exp() - 1.0) * v.exp()).sqrt()
            }
        }
        2 => g * (0.5 * s * g * g).exp() * (1.0 - 2.0 * s).powf(0.75),
        _ => (g + s * (g2 * g2 - 1.0) * std::f64::consts::FRAC_1_SQRT_2) / (1.0 + s * s).sqrt(),
    }
}

/// Build-up of sliding friction with displacement `d` (m) since slip start.
pub fn hysteresis_factor(form: u32, d: f64, length: f64) -> f64 {
    if length == 0.0 {
        return 1.0;
    }
    let r = d / length;
    match form {
        1 => r.tanh(),
        2 => r / (r + 1.0),
        _ => 1.0 - (-r).exp(),
    }
}

/// Drift factor of N0 at time `t` (s) from the run's start.
pub fn drift_factor(form: u32, rate: f64, t: f64) -> f64 {
    match form {
        1 => 1.0 + rate * DRIFT_SATURATION_S * (1.0 - (-t / DRIFT_SATURATION_S).exp()),
        2 => 1.0 + rate * DRIFT_WANDER_S * (t / DRIFT_WANDER_S).sin(),
        _ => 1.0 + rate * t,
    }
}
