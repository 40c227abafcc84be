//! The effect tables of a model file: one struct per effect, with its
//! `form` enum (the first form is the candidate's) and its strength.

use serde::{Deserialize, Serialize};

use super::{DRIFT_SATURATION_S, DRIFT_WANDER_S, Form};

/// Periodic parts of N(t) at 1×..4× the excitation frequency, or (form
/// `position`) a normal force that follows the block's position.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NormalForceHarmonics {
    /// `fourier`: Σ A_k cos(kΩt + φ_k); `bumps`: Σ A_k (max(0, cos(kΩt + φ_k))^shape − its mean);
    /// `square`: Σ A_k tanh(shape·cos(kΩt + φ_k)) / tanh(shape).
    ///
    /// `position`: the normal force follows the block's displacement x
    /// instead of the base's phase, N0 (α x/U0 + β (x/U0)²) added to the
    /// mean, so N = N0 (1 + α x/U0 + β (x/U0)²) + σ_N ξ_N (clipped at 0 as
    /// always): a leaf-spring or linkage geometry that tilts and shortens as
    /// the block moves (the normal load of a parallel-spring flexure stage
    /// changes with its deflection through the springs' tilt and arc
    /// shortening, to first order in the deflection and to second: S. T.
    /// Smith, *Flexures: Elements of Elastic Mechanisms*, 2000). α =
    /// `amplitudes_per_n0[0]` (–, share of N0 per U0 of displacement) and
    /// β = `amplitudes_per_n0[1]` (–, share of N0 per U0²), U0 =
    /// `excitation.amplitude_m` (m; the form needs it > 0 where α or β is
    /// not 0). x is the displacement at the start of each noise interval,
    /// held over the interval like every time-varying part, so breakaway
    /// stays closed-form. N0 is the point's nominal normal force, as in
    /// the other forms' `amplitudes_per_n0` (a `normal_force_drift` moves
    /// the mean, not this term). `amplitudes_n`, `amplitudes_per_n0[2..]`,
    /// `phases_rad` and `shape` are unused by this form. At α = β = 0 it is
    /// the baseline.
    #[serde(default)]
    pub form: HarmonicForm,
    /// Amplitudes A_1..A_4, N (unused by `position`).
    #[serde(default)]
    pub amplitudes_n: [f64; 4],
    /// Amplitudes that scale with the load, as shares of N0 (each harmonic's
    /// amplitude is `amplitudes_n[k] + amplitudes_per_n0[k]·N0`), –; for
    /// `position`, α (per U0) and β (per U0²) of the first two (the other
    /// two unused).
    #[serde(default)]
    pub amplitudes_per_n0: [f64; 4],
    /// Phases φ_1..φ_4, rad (unused by `position`).
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
    Fourier = 0,
    Bumps = 1,
    Square = 2,
    Position = 3,
}

impl Form for HarmonicForm {
    const ALL: &'static [Self] =
        &[HarmonicForm::Fourier, HarmonicForm::Bumps, HarmonicForm::Square, HarmonicForm::Position];

    fn code(self) -> u32 {
        self as u32
    }
}

/// A skewed or heavy-tailed random part of the friction coefficient.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NonGaussianFriction {
    /// `skew`: (z + s (z'² − 1)/√2)/√(1+s²); `lognormal`: standardised exp(s z);
    /// `tukey_h`: standardised z·exp(h z²/2) (heavy tails); `mixture`: with
    /// probability 0.1 (z' below its 10% quantile) an outlier component
    /// N(3s, (1 + s)²), else N(0, 1), standardised (skewed and heavy-tailed);
    /// `polynomial`: Fleishman's power polynomial −c + b z + c z² + d z³
    /// (Fleishman 1978, Psychometrika 43), c = `strength`, d = `cubic`, b
    /// the positive root that makes the variance 1: c sets the skew and d
    /// the tails apart (d > 0 heavier, d < 0 lighter than a Gaussian's), so
    /// one form reaches skew with light tails as well as heavy symmetric
    /// tails. All have mean 0, variance 1.
    #[serde(default)]
    pub form: NonGaussianForm,
    /// s (skew, lognormal, mixture), h (tukey_h, < 0.25) or c (polynomial;
    /// 2c² + 15d² < 1), –.
    pub strength: f64,
    /// d, the `polynomial` form's cubic coefficient (0 for the other forms), –.
    #[serde(default)]
    pub cubic: f64,
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
    Skew = 0,
    Lognormal = 1,
    TukeyH = 2,
    Mixture = 3,
    Polynomial = 4,
}

impl Form for NonGaussianForm {
    const ALL: &'static [Self] = &[
        NonGaussianForm::Skew,
        NonGaussianForm::Lognormal,
        NonGaussianForm::TukeyH,
        NonGaussianForm::Mixture,
        NonGaussianForm::Polynomial,
    ];

    fn code(self) -> u32 {
        self as u32
    }
}

/// Friction that depends on the motion's history, so accelerating and
/// decelerating branches differ: after each slip start the sliding friction
/// builds up over a displacement, or turns over one through a reversal
/// (Dahl's pre-sliding friction), lags behind the
/// steady law in time (Hess & Soom's frictional memory), relaxes to it over a
/// slip distance (rate-and-state slip law), or carries a contact age that
/// heals while stuck (rate-and-state ageing law).
///
/// In every form μ_ss(v) is the steady law the baseline uses, with its
/// noise and any load offset: `a + Δa + b S(c, |v|) + d v² + σ_μ ξ_μ`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrictionHysteresis {
    /// Build-up φ(d) of the sliding friction with displacement d since slip
    /// start: `exponential` 1 − e^(−d/δ); `tanh` tanh(d/δ); `rational`
    /// d/(d+δ) (δ = `length_m`).
    ///
    /// `dahl`: Dahl's pre-sliding law (Dahl 1968; the bristle state of
    /// LuGre, Canudas de Wit et al. 1995, without its damping), whose
    /// friction is continuous through a reversal: after the block reverses
    /// without sticking, the friction it slid against, now pointing along
    /// the new motion, turns over the displacement δ (`length_m`),
    /// φ(d) = 1 − (1 − φ₀) e^(−d/δ) with φ₀ = −φ at the reversal (−1 after
    /// steady sliding: the friction passes from −μ to +μ over a few δ, and
    /// for a while helps the block along). After a breakaway from a stick
    /// the static friction that held the block already acts, φ₀ = 1, and
    /// there is no build-up. Off (the baseline) when δ = 0.
    ///
    /// `bristle`: `dahl`'s friction, and a stick held by the contact's
    /// elasticity instead of a rigid one (the bristle picture of LuGre,
    /// Canudas de Wit et al. 1995, and the elasto-plastic model, Dupont et
    /// al. 2002, taken quasi-statically: the bristles are stiff and damped
    /// beside the rig). While stuck the contact is a tangential spring of
    /// stiffness k_t = μ₀ N0 / δ (μ₀ = a + Δa + b, the law at rest without
    /// its noise; N0 the nominal normal force), in series with the anchored
    /// slider, so the block creeps with the base, x = κ u + (1 − κ) w with
    /// κ = k / (k + k_t) and w fixed at the stick's start, and breaks away
    /// when the contact force k (1 − κ)(u − w) reaches μ_s N. The friction
    /// that turns over a δ in a slip is the bristles' deflection, so one
    /// length sets both. Off (the baseline) when δ = 0 (κ = 0: a rigid stick).
    ///
    /// `lag`: the friction coefficient μ_f follows the steady law μ_ss(v)
    /// with a first-order lag in time, dμ_f/dt = (μ_ss(v) − μ_f)/τ_m
    /// (τ_m = `time_constant_s`), starting at the static coefficient at each
    /// breakaway (Hess & Soom 1990). Off (the baseline) when τ_m = 0.
    ///
    /// `slip`: the rate-and-state *slip law* in friction form (Ruina 1983,
    /// linearised about steady sliding): μ_f relaxes to μ_ss(v) over a slip
    /// distance L = `length_m`, dμ_f/dt = (|v|/L)(μ_ss(v) − μ_f), starting at
    /// the static coefficient at each breakaway: `lag` with the memory time
    /// L/|v|, so the relaxation is the same per metre slid at every speed.
    /// Off (the baseline) when L = 0.
    ///
    /// `ageing`: the Dieterich–Ruina *ageing law* (Dieterich 1979, Ruina
    /// 1983) with a contact age θ (s): dθ/dt = 1 − |v| θ / L, so θ grows at
    /// rate 1 while stuck (contact healing) and tends to L/|v| in steady
    /// sliding (L = `length_m`). Sliding friction is
    /// μ = μ_ss(v) + B ln((θ + θ_0)/(θ_ss(v) + θ_0)) with θ_ss(v) = L/(|v| + v_c),
    /// v_c = [`AGEING_CUTOFF_SPEED_M_PER_S`] (1 mm/s: the steady age stays
    /// finite at rest, θ_c = L/v_c), θ_0 = L/v_0, v_0 =
    /// [`AGEING_FLOOR_SPEED_M_PER_S`] (1 m/s: the floor keeps the logarithm
    /// finite at θ = 0 and is below every steady age of a slip the rig
    /// makes, so the term follows ln θ through a slip's transient) and
    /// B = `strength`. The static coefficient adds the same term at v = 0:
    /// μ_s = μ(0) + B ln((θ + θ_0)/(θ_c + θ_0)), with θ evaluated at the start of
    /// each noise interval while stuck (held over the interval, so breakaway
    /// stays closed-form) and at the start of each stick. θ is not reset at a
    /// breakaway: the slip starts from the θ the static coefficient was judged
    /// by (so friction starts from that static coefficient; the healing of
    /// under one noise interval before the breakaway is not counted) and
    /// evolves continuously after. θ starts at 0 at the run's start. Off (the
    /// baseline) when B = 0 or L = 0.
    ///
    /// [`AGEING_CUTOFF_SPEED_M_PER_S`]: super::AGEING_CUTOFF_SPEED_M_PER_S
    /// [`AGEING_FLOOR_SPEED_M_PER_S`]: super::AGEING_FLOOR_SPEED_M_PER_S
    #[serde(default)]
    pub form: HysteresisForm,
    /// Characteristic displacement δ of the build-up forms, or the slip
    /// distance L of `slip` and `ageing`, m (≥ 0).
    #[serde(default)]
    pub length_m: f64,
    /// Memory time τ_m of the `lag` form, s (≥ 0).
    #[serde(default)]
    pub time_constant_s: f64,
    /// B of the `ageing` form, – (finite; the rise of the static coefficient
    /// per e-fold of contact age beside θ_c; 0: the baseline). Unused by the
    /// other forms.
    #[serde(default)]
    pub strength: f64,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HysteresisForm {
    #[default]
    Exponential = 0,
    Tanh = 1,
    Rational = 2,
    Lag = 3,
    Slip = 4,
    Ageing = 5,
    Dahl = 6,
    Bristle = 7,
}

impl Form for HysteresisForm {
    const ALL: &'static [Self] = &[
        HysteresisForm::Exponential,
        HysteresisForm::Tanh,
        HysteresisForm::Rational,
        HysteresisForm::Lag,
        HysteresisForm::Slip,
        HysteresisForm::Ageing,
        HysteresisForm::Dahl,
        HysteresisForm::Bristle,
    ];

    fn code(self) -> u32 {
        self as u32
    }
}

/// A friction noise correlated for longer than one hold interval.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColouredFrictionNoise {
    /// `ar1`: Ornstein–Uhlenbeck sampled per interval, ρ = e^(−τ/τc), of
    /// which `coloured_share` of the variance (the rest stays white);
    /// `hold`: each value held for round(τc/τ) intervals;
    /// `two_scale`: half white, half AR(1) with τc (variance split equally;
    /// white only when τc = 0); `multi_scale`: the mean of three AR(1) parts
    /// with τc/4, τc and 4τc, equal in variance (a spectrum close to 1/f);
    /// `fast_slow`: two AR(1) parts with τc and 10 τc, no white part, of which
    /// the slow one carries `coloured_share` of the variance (a spectrum
    /// with two corners; white only when τc = 0).
    #[serde(default)]
    pub form: ColourForm,
    /// Correlation time τc, s.
    pub correlation_time_s: f64,
    /// Share of the variance that is coloured (`ar1`), or in the slow part
    /// (`fast_slow`), –, in [0, 1].
    #[serde(default = "one")]
    pub coloured_share: f64,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ColourForm {
    #[default]
    Ar1 = 0,
    Hold = 1,
    TwoScale = 2,
    MultiScale = 3,
    FastSlow = 4,
}

impl Form for ColourForm {
    const ALL: &'static [Self] =
        &[ColourForm::Ar1, ColourForm::Hold, ColourForm::TwoScale, ColourForm::MultiScale, ColourForm::FastSlow];

    fn code(self) -> u32 {
        self as u32
    }
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
    /// slip begins (a smooth static-to-kinetic transition);
    /// `dwell`: the excess grows with the time stuck, Δ·(1 − e^(−t_d/τ_d))
    /// (Rabinowicz; rate-and-state ageing), dropping at once at breakaway.
    #[serde(default)]
    pub form: StictionForm,
    /// Excess Δ of the static coefficient, –.
    pub excess: f64,
    /// Slip L over which the `constant` form's excess fades, m (0: at once).
    #[serde(default)]
    pub release_length_m: f64,
    /// Ageing time τ_d of the `dwell` form, s (0: the full excess at once).
    #[serde(default)]
    pub dwell_time_s: f64,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StictionForm {
    #[default]
    Constant = 0,
    Noisy = 1,
    Decaying = 2,
    Dwell = 3,
}

impl Form for StictionForm {
    const ALL: &'static [Self] =
        &[StictionForm::Constant, StictionForm::Noisy, StictionForm::Decaying, StictionForm::Dwell];

    fn code(self) -> u32 {
        self as u32
    }
}

/// The friction changes with the normal-force level N0.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadDependentFriction {
    /// Offset Δa added to `a`: `linear` k (N0 − Nref) with k in 1/N;
    /// `quadratic` k (N0 − Nref) + q (N0 − Nref)² (a friction whose change
    /// with load steepens or flattens); `power` μ₀ ((N0/Nref)^k − 1) with
    /// μ₀ = a + b the law's level at rest (so it scales with the friction
    /// however a and b share it); `saturating` k Nref (1 − e^(−(N0 − Nref)/Nref));
    /// `exponential` k Nref (e^((N0 − Nref)/Nref) − 1).
    ///
    /// `adhesion`: the two-term law F = μN + A (Derjaguin 1934; Bowden &
    /// Tabor): an adhesion force A = k in newtons (any finite value) adds to
    /// the friction force's magnitude while slipping,
    /// F = −sgn(v) max(0, μ(v, t) N(t) + A), and to the breakaway force,
    /// max(0, μ_s N + A). No offset of μ; Nref unused.
    ///
    /// `scaled`: the whole law scales with the load,
    /// μ(v, N0) = (N0/Nref)^k (a + b S(c, |v|) + d v²) + σ_μ ξ_μ, and the
    /// static coefficient's a + b likewise (the noise and any other offset,
    /// such as a stiction excess, are not scaled); k is an exponent, –.
    ///
    /// Every form is the baseline at k = 0.
    #[serde(default)]
    pub form: LoadForm,
    /// k (see `form`): 1/N (`linear`, `quadratic`, `saturating`,
    /// `exponential`), an exponent, – (`power`, `scaled`), or the adhesion
    /// force A, N (`adhesion`).
    pub strength: f64,
    /// q of the `quadratic` form, 1/N² (0 where the table does not say;
    /// only the quadratic form reads it).
    #[serde(default)]
    pub curvature_per_n2: f64,
    /// Reference normal force Nref, N.
    #[serde(default = "ten")]
    pub reference_force_n: f64,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LoadForm {
    #[default]
    Linear = 0,
    Power = 1,
    Saturating = 2,
    Exponential = 3,
    Quadratic = 4,
    Adhesion = 5,
    Scaled = 6,
}

impl Form for LoadForm {
    const ALL: &'static [Self] = &[
        LoadForm::Linear,
        LoadForm::Power,
        LoadForm::Saturating,
        LoadForm::Exponential,
        LoadForm::Quadratic,
        LoadForm::Adhesion,
        LoadForm::Scaled,
    ];

    fn code(self) -> u32 {
        self as u32
    }
}

/// The mean normal force drifts during a run (time t from the run's start).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NormalForceDrift {
    /// N0 × `linear` (1 + r t); `quadratic` (max(0, 1 + r t + q t²): wear
    /// that slows, heating that comes and goes; never below zero);
    /// `saturating` (1 + r·20 s·(1 − e^(−t/20 s))); `wander`
    /// (1 + r·15 s·sin(t/15 s)); `random_walk` (1 + W(t), W a random walk
    /// of its own in each realisation, from 0 at the run's start, with
    /// variance r t: preload that wanders with wear and temperature, its
    /// course different in every run).
    #[serde(default)]
    pub form: DriftForm,
    /// Initial relative rate r, 1/s; of `random_walk`, the walk's variance
    /// per second (its diffusion, ≥ 0), 1/s.
    pub rate_per_s: f64,
    /// Relative curvature q of the `quadratic` form, 1/s² (unused by the
    /// others).
    #[serde(default)]
    pub curvature_per_s2: f64,
    /// Where the nominal normal force is the drifting force's mean: a window
    /// `[start, end]` of each run, s from the end of its warm-up (where a
    /// record starts, and the drift's clock: [`drift_factor`]). With
    /// it, N0 is divided by the drift factor's mean over the window, so a
    /// sweep at a nominal force gives that mean force there (a model fitted
    /// to records whose nominal force is their measured mean means what the
    /// records meant); without it, N0 is the force at the warm-up's end.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean_over_s: Option<[f64; 2]>,
}

impl NormalForceDrift {
    /// The drift factor's mean over `[start, end]` (s of the drift's clock),
    /// by the midpoint rule on 64 intervals.
    pub fn mean_factor(&self, start_s: f64, end_s: f64) -> f64 {
        let n = 64;
        (0..n)
            .map(|i| {
                let t = start_s + (end_s - start_s) * (f64::from(i) + 0.5) / f64::from(n);
                drift_factor(self.form, self.rate_per_s, self.curvature_per_s2, t)
            })
            .sum::<f64>()
            / f64::from(n)
    }

    /// What N0 is multiplied by so that the nominal force is the mean over
    /// [`NormalForceDrift::mean_over_s`] (1 without it).
    pub fn nominal_scale(&self) -> f64 {
        match self.mean_over_s {
            Some([start, end]) => {
                let m = self.mean_factor(start, end);
                if m > 0.0 { 1.0 / m } else { 1.0 }
            }
            None => 1.0,
        }
    }
}

/// Drift factor of N0 at time `t` (s) of the drift's clock, which starts
/// at the end of a run's warm-up (the force holds its starting value
/// through the warm-up: what is measured sees the same drift whatever the
/// warm-up's length, a number of periods), initial
/// relative rate `rate` (1/s), relative curvature `curvature` (1/s², the
/// quadratic form's). The kernel's `drift_factor` (`effects.wgsl`) is the
/// same in f32; it is here, not with the other effects' arithmetic in
/// `engine/cpu/effects.rs`, because the model scales N0 by its mean
/// ([`NormalForceDrift::nominal_scale`]). A `random_walk`'s factor is its
/// expectation, 1: each realisation adds its own walk.
pub fn drift_factor(form: DriftForm, rate: f64, curvature: f64, t: f64) -> f64 {
    match form {
        DriftForm::RandomWalk => 1.0,
        DriftForm::Quadratic => (1.0 + (rate + curvature * t) * t).max(0.0),
        DriftForm::Saturating => 1.0 + rate * DRIFT_SATURATION_S * (1.0 - (-t / DRIFT_SATURATION_S).exp()),
        DriftForm::Wander => 1.0 + rate * DRIFT_WANDER_S * (t / DRIFT_WANDER_S).sin(),
        DriftForm::Linear => 1.0 + rate * t,
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DriftForm {
    #[default]
    Linear = 0,
    Saturating = 1,
    Wander = 2,
    Quadratic = 3,
    RandomWalk = 4,
}

impl Form for DriftForm {
    const ALL: &'static [Self] =
        &[DriftForm::Linear, DriftForm::Saturating, DriftForm::Wander, DriftForm::Quadratic, DriftForm::RandomWalk];

    fn code(self) -> u32 {
        self as u32
    }
}

fn two() -> f64 {
    2.0
}

fn ten() -> f64 {
    10.0
}

fn one() -> f64 {
    1.0
}
