//! A second, independent generator of synthetic measurement sets for the
//! blind benchmark of the diagnosis.
//!
//! [`crate::diagnose::synthetic`] makes its sets with stickslip's own engine
//! and effect code, so its data share the diagnosis' assumptions (the same
//! integrator, the same event handling, the same noise and effect forms).
//! This module is written apart from all of that: it has its own integrator,
//! its own noise, its own effect forms (taken from the literature, none of
//! them a candidate form of the diagnosis) and its own writer. It uses from
//! the crate only the family *names* ([`Effect`]), [`Condition`], the error
//! type and two plain IO helpers.
//!
//! **The integrator.** Semi-implicit (symplectic) Euler at a fixed step
//! (default 200 kHz, never below 100 kHz; the step divides the noise
//! interval exactly) for `m x'' + c x' + k x = k u(t) + F`,
//! `u = U0 cos(Ω t)`, `k = m (2π f0)²`, `c = 2 ζ sqrt(k m)`, with explicit
//! Karnopp-style stick/slip switching: whenever the block's speed would cross
//! zero within a step, or falls (decelerating) below a small `v_eps`, it is at
//! rest for that instant; it then sticks while the spring force `k (u − x)`
//! stays within the breakaway force `μ_s N`, and otherwise slips in the
//! direction of that force with the kinetic friction just above zero speed.
//! While slipping, `F = −sgn(v) μ(|v|) N` (it opposes the sliding velocity,
//! `model.md`). The LuGre form of `friction_hysteresis` replaces the switch
//! by its own bristle state (it has its own stick: pre-sliding).
//!
//! **The noise.** `ξ_μ`, `ξ_N` are standard Gaussian values (Box–Muller on
//! [`StdRng`]) held over intervals `τ` (default 1/600 s). Every random
//! quantity has its own stream, seeded from (seed, path, stream), so an
//! effect at zero strength leaves the baseline's noise — and so its path —
//! bit for bit as it was.
//!
//! **The truth.** A rig and friction law drawn from the whole of the paper's
//! eq. 7, `μ(v) = a + b/(1 + c|v|) + d v² + σ_μ ξ_μ`, at a grid of normal
//! forces × frequency ratios, with up to one effect per family, each in one
//! of the forms of [`FORMS`] at a moderate or a strong preset.
//!
//! **Presets** (moderate / strong strength; [`IndependentEffect::preset`]),
//! and how far the strong one moves its family's signature on 50 s records,
//! in units of the baseline's record-to-record spread (5 records each, the
//! ignored test `presets_move_their_signatures_beyond_the_record_spread`;
//! rig m = 1 kg, f0 = 10 Hz, U0 = 2 mm, at 6 Hz/20 N (stops), 7 Hz/4 N,
//! 9 Hz/8 N):
//!
//! | family | form | moderate | strong | strong moves (σ of the baseline) |
//! | --- | --- | --- | --- | --- |
//! | load_dependent_friction | hertzian (κ) | 0.8 | 3.0 | sliding \|F\|/N −430, mean peak +32 |
//! | | logistic (s, ± random) | 0.15 | 0.35 | sliding \|F\|/N −311, mean peak −39 |
//! | | jkr_adhesion (N_a / N_ref) | 0.3 | 1.0 | sliding \|F\|/N +465, mean peak −36 |
//! | friction_hysteresis | lugre (L, m) | 1e-4 | 4e-4 | branch gap −52, mean peak −245 |
//! | | rate_state (b) | 0.015 | 0.035 | branch gap +54, mean peak +45 |
//! | normal_force_harmonics | position_following (α) | 0.015 | 0.04 | N at 1× +2517, at 2× +1529 |
//! | | wandering_harmonic (h) | 0.03 | 0.08 | N at its order +1500 |
//! | coloured_friction_noise | pink (s) | 0.5 | 0.9 | residual lag-10 autocorrelation +130, peak variance +182 |
//! | | telegraph (s) | 0.35 | 0.7 | lag-10 autocorrelation +126, peak variance +349 |
//! | non_gaussian_friction | student_t (s) | 0.6 | 1.0 | residual kurtosis +337 |
//! | | bimodal (s) | 0.5 | 0.85 | residual skewness +57 |
//! | stiction | karnopp (s) | 0.2 | 0.4 | breakaway \|F\|/N +28, peak variance +20 |
//! | | dwell_ageing (B) | 0.03 | 0.08 | breakaway \|F\|/N +95, peak variance +148 |
//! | normal_force_drift | thermal_relaxation (Δ, ± random) | 0.06 | 0.15 | N's last-fifth − first-fifth mean +327 |
//! | | brownian_wear (σ_w, 1/√s) | 0.008 | 0.02 | N's last-fifth − first-fifth mean −221 |
//!
//! Every moderate preset moves its signature by ≥ 18σ there except the
//! stiction forms (2.8σ and 1.0σ in breakaway friction; 6.6σ and 4.0σ in
//! the mean peak), which act only where the block stops and grow with the
//! time it stays stuck.
//!
//! **Records** are written in `shared/spec/measurement-format.md`'s format,
//! with sensor noise on every channel, optionally a `base_x` column and
//! optionally a free time origin; the truth goes to `truth.json` next to
//! the data directory ([`truth_path`]).

use std::f64::consts::{PI, TAU};
use std::path::{Path, PathBuf};

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rayon::prelude::*;
use serde::Serialize;

use crate::engine::{Condition, Effect};
use crate::error::{Error, Result};
use crate::io::{create_dir, write_atomically};

/// The generator's name and version, written into every truth.
pub const GENERATOR: &str = "stickslip-independent-generator/1";

/// Default normal-force levels of a set, N.
pub const DEFAULT_LOADS_N: [f64; 3] = [4.0, 8.0, 16.0];

/// Default excitation frequencies of a set, as ratios of the rig's natural
/// frequency.
pub const DEFAULT_FREQUENCY_RATIOS: [f64; 6] = [0.6, 0.7, 0.8, 0.9, 1.1, 1.2];

/// The lowest step rate the integrator accepts, Hz.
pub const MIN_STEP_RATE_HZ: f64 = 100e3;

/// One hidden effect for [`random_truth`]: its family, the index of its form
/// in that family's list in [`FORMS`] (0-based), and whether it takes the
/// strong preset (else the moderate one).
pub type HiddenForm = (Effect, u32, bool);

/// Every effect family's forms (index = form index of [`HiddenForm`]), each
/// with its formula and source. None is a candidate form of the diagnosis.
pub const FORMS: [(Effect, &[&str]); 7] = [
    (
        Effect::LoadDependentFriction,
        &[
            "hertzian: whole law scaled by ((1 + κ)/(1 + κ N/N_ref))^(1/3), i.e. μ ∝ (1 + N/N_c)^(-1/3), \
             κ = N_ref/N_c (elastic Hertzian contact area ∝ N^(2/3): Bowden & Tabor 1950; Archard 1957)",
            "logistic: whole law scaled by 1 + s (ℓ(N) − ℓ(N_ref)), ℓ(N) = 1/(1 + exp(−(N − N_t)/w)), a transition \
             of the friction level between two loads (elastic–plastic contact transition, Chang, Etsion & Bogy \
             1988; run-in, Blau 2005)",
            "jkr_adhesion: whole law scaled by ((1 + N_a/N)/(1 + N_a/N_ref))^p, p = 2/3 (adhesive contact area, \
             Johnson, Kendall & Roberts 1971)",
        ],
    ),
    (
        Effect::FrictionHysteresis,
        &[
            "lugre: bristle state z, dz/dt = v − |v| z/(g(v) L), μ = z/L + σ1 exp(−(v/v_d)²) dz/dt, g = eq. 7 law \
             (Canudas de Wit, Olsson, Åström & Lischinsky 1995; velocity-dependent σ1: Olsson et al. 1998)",
            "rate_state: Δμ = a asinh(|v|/(2v_r) exp(ψ/a)) − (same at steady state), ψ = b ln(v_r θ/D_c), \
             aging law dθ/dt = 1 − |v|θ/D_c, a = 2b (Dieterich 1979; Ruina 1983; regularised at v = 0: Rice & \
             Ben-Zion 1996, Lapusta et al. 2000)",
        ],
    ),
    (
        Effect::NormalForceHarmonics,
        &[
            "position_following: N = N0 (1 + α x/U0 + β (x/U0)²) (normal load that follows the block's position \
             through the leaf-spring geometry: tilt α, arc shortening β; flexure kinematics, Smith 2000)",
            "wandering_harmonic: N = N0 (1 + h cos(m Ω t + φ(t))), φ a slow random walk (phase diffusion of an \
             imperfect periodic source, Demir, Mehrotra & Roychowdhury 2000)",
        ],
    ),
    (
        Effect::ColouredFrictionNoise,
        &[
            "pink: a share s of ξ_μ's variance from a 1/f process, the sum of AR(1)s with log-spaced time \
             constants over decades (superposed relaxation processes, van der Ziel 1950; Kasdin 1995)",
            "telegraph: a share s of ξ_μ's variance from a random telegraph signal, a two-state Markov process \
             (Machlup 1954)",
        ],
    ),
    (
        Effect::NonGaussianFriction,
        &[
            "student_t: a share s of ξ_μ's variance from a unit-variance Student-t variate, ν = 3–5 (Student \
             1908; heavy-tailed force fluctuations)",
            "bimodal: a share s of ξ_μ's variance from a two-level (Bernoulli, p = 0.15–0.3) variate: two contact \
             states (bistable asperity contact, cf. Persson 2000)",
        ],
    ),
    (
        Effect::Stiction,
        &[
            "karnopp: breakaway μ_s = μ_k(0) (1 + s (1 + r ε)), ε a new standard Gaussian at every stop (static \
             coefficient with scatter from stick to stick; Karnopp 1985; Rabinowicz 1965)",
            "dwell_ageing: μ_s = μ_k(0) + B ln(1 + t_stick/t0) (logarithmic ageing of the static coefficient \
             with dwell time: Rabinowicz 1951; Dieterich 1972)",
        ],
    ),
    (
        Effect::NormalForceDrift,
        &[
            "thermal_relaxation: N0(t) = N0 (1 + Δ (1 − exp(−t/τ_th))) (first-order thermal relaxation of the \
             preload, Newton's law of cooling)",
            "brownian_wear: N0(t) = N0 (1 + W(t)), W a Brownian motion of rate σ_w (random-walk wear, stochastic \
             Archard wear increments; Archard 1953)",
        ],
    ),
];

/// The forms of one family, as listed in [`FORMS`].
pub fn forms_of(family: Effect) -> &'static [&'static str] {
    FORMS.iter().find(|(f, _)| *f == family).map(|(_, forms)| *forms).unwrap_or(&[])
}

// ---------------------------------------------------------------------------
// The truth
// ---------------------------------------------------------------------------

/// The rig without friction contact, and the base motion's amplitude.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TruthRig {
    pub mass_kg: f64,
    pub natural_frequency_hz: f64,
    pub damping_ratio: f64,
    /// Base displacement amplitude `U0`, m.
    pub excitation_amplitude_m: f64,
}

impl TruthRig {
    /// `k = m (2π f0)²`, N/m.
    pub fn stiffness_n_per_m(&self) -> f64 {
        self.mass_kg * (TAU * self.natural_frequency_hz).powi(2)
    }

    /// `c = 2 ζ sqrt(k m)`, N s/m.
    pub fn damping_n_s_per_m(&self) -> f64 {
        2.0 * self.damping_ratio * (self.stiffness_n_per_m() * self.mass_kg).sqrt()
    }
}

/// The eq. 7 friction law and the baseline's noise.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TruthFriction {
    pub a: f64,
    pub b: f64,
    /// `c` of eq. 7, s/m.
    pub c_s_per_m: f64,
    /// `d` of eq. 7, s²/m².
    pub d_s2_per_m2: f64,
    /// Standard deviation of the friction coefficient's random part, –.
    pub sigma_mu: f64,
    /// Standard deviation of the normal force's random part, N.
    pub sigma_n_n: f64,
    /// How long each random value is held, s.
    pub noise_interval_s: f64,
}

/// How the truth is integrated.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Integration {
    /// Requested step rate, Hz (≥ [`MIN_STEP_RATE_HZ`]); the step used is
    /// the largest that divides the noise interval and is no longer than
    /// `1/step_rate_hz`.
    pub step_rate_hz: f64,
    /// Warm-up before each record or statistic, s (rounded up to whole
    /// excitation periods).
    pub warmup_s: f64,
    /// Speed below which a decelerating block counts as at rest, m/s.
    pub rest_speed_m_per_s: f64,
}

impl Default for Integration {
    fn default() -> Self {
        Integration { step_rate_hz: 200e3, warmup_s: 5.0, rest_speed_m_per_s: 1e-5 }
    }
}

/// One condition of the truth's grid.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TruthCondition {
    pub excitation_frequency_hz: f64,
    /// `Ω / ω0`, –.
    pub frequency_ratio: f64,
    /// Nominal normal force `N0`, N.
    pub normal_force_n: f64,
    /// `μ(0) N0 ≥ k U0`: the baseline's block can hold against the whole
    /// base stroke, so it is expected to stay stuck through the record
    /// (noise may break it loose now and then).
    pub expected_to_stick_throughout: bool,
}

/// `load_dependent_friction` forms. Each scales the whole friction law
/// (noise included) by a factor of the instantaneous normal force `N`,
/// normalised to 1 at the reference load `N_ref` (the geometric mean of the
/// set's loads). Strength 0 gives the factor 1.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "form", rename_all = "snake_case")]
pub enum LoadForm {
    /// Elastic (Hertzian) contact: the real contact area grows as `N^(2/3)`,
    /// so the friction coefficient falls as `(1 + N/N_c)^(−1/3)` (Bowden &
    /// Tabor 1950, *The Friction and Lubrication of Solids*; Archard 1957,
    /// Proc. R. Soc. A 243). Factor `((1 + κ)/(1 + κ N/N_ref))^(1/3)`;
    /// strength `κ = N_ref/N_c`.
    Hertzian { strength: f64, reference_load_n: f64 },
    /// A logistic transition of the friction level between two loads
    /// (elastic–plastic contact transition, Chang, Etsion & Bogy 1988,
    /// J. Tribol. 110; run-in, Blau 2005, Tribol. Int. 38). Factor
    /// `1 + s (ℓ(N) − ℓ(N_ref))`, `ℓ(N) = 1/(1 + exp(−(N − N_t)/w))`;
    /// strength `s` (either sign).
    Logistic { strength: f64, transition_load_n: f64, width_n: f64, reference_load_n: f64 },
    /// Adhesive (JKR) contact: the area carries an adhesive load `N_a`, so
    /// `μ_eff = μ(v) (1 + N_a/N)^p` (Johnson, Kendall & Roberts 1971, Proc.
    /// R. Soc. A 324). Factor `((1 + N_a/N)/(1 + N_a/N_ref))^p`; strength
    /// `N_a`, N.
    JkrAdhesion { strength: f64, exponent: f64, reference_load_n: f64 },
}

/// `friction_hysteresis` (frictional memory) forms.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "form", rename_all = "snake_case")]
pub enum MemoryForm {
    /// The LuGre bristle model (Canudas de Wit, Olsson, Åström & Lischinsky
    /// 1995, IEEE TAC 40(3)): `dz/dt = v − |v| z / (g(v) L)`,
    /// `μ = z/L + σ1(v) dz/dt`, `F = −N μ`, `g(v)` the eq. 7 law (noise,
    /// load factor and any stiction included), `σ0 = 1/L`, `σ2 = 0` (eq. 7
    /// already holds the velocity dependence), `σ1(v) = σ1 exp(−(v/v_d)²)`
    /// (Olsson et al. 1998, Eur. J. Control 4) with `σ1 = 2 ζ_b sqrt(m /
    /// (N_ref L))`. Strength: the bristle length `L`, m (steady deflection
    /// `g L`); 0 is the Karnopp baseline. LuGre has its own stick
    /// (pre-sliding), so the Karnopp switch is off.
    Lugre { strength: f64, bristle_damping_ratio: f64, damping_decay_speed_m_per_s: f64, reference_load_n: f64 },
    /// Rate-and-state friction with the aging law (Dieterich 1979, JGR 84;
    /// Ruina 1983, JGR 88) in the form regularised at `v = 0` (Rice &
    /// Ben-Zion 1996, PNAS 93; Lapusta et al. 2000, JGR 105):
    /// `f(v, θ) = a asinh(|v|/(2 v_r) exp(b ln(v_r θ/D_c)/a))`, `a = 2b`,
    /// `dθ/dt = 1 − |v| θ / D_c`. Its steady state is taken out, so eq. 7
    /// stays the steady law: `Δμ = f(v, θ) − f(v, D_c/|v|)` (0 at steady
    /// sliding and at `v = 0`; `+b ln(v θ/D_c)` away from both: friction
    /// above the steady law while accelerating, below it while slowing).
    /// Strength `b`.
    RateState { strength: f64, slip_distance_m: f64, reference_speed_m_per_s: f64 },
}

/// `normal_force_harmonics` forms.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "form", rename_all = "snake_case")]
pub enum HarmonicForm {
    /// A normal load that follows the block's position through the
    /// leaf-spring geometry: `N = N0 (1 + α x/U0 + β (x/U0)²)` (tilt `α`,
    /// arc shortening `β`; parallel-flexure kinematics, Smith 2000,
    /// *Flexures*), so `N` has harmonics at 1× and 2× of the response.
    /// Strength `α`; `β = α · quadratic_per_linear`.
    PositionFollowing { strength: f64, quadratic_per_linear: f64 },
    /// A harmonic of the base whose phase wanders slowly:
    /// `N = N0 (1 + h cos(m Ω t + φ(t)))`, `φ` a random walk with diffusion
    /// `D_φ` (rad²/s), as an imperfect periodic source's phase diffuses
    /// (Demir, Mehrotra & Roychowdhury 2000, IEEE TCAS-I 47). Strength `h`.
    WanderingHarmonic { strength: f64, order: u32, phase_diffusion_rad2_per_s: f64, initial_phase_rad: f64 },
}

/// `coloured_friction_noise` forms. A share `s` (the strength) of `ξ_μ`'s
/// unit variance is coloured: `ξ_μ = sqrt(1 − s) w + sqrt(s) c`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "form", rename_all = "snake_case")]
pub enum ColourForm {
    /// `c`: 1/f (pink) noise, the normalised sum of `components` AR(1)
    /// processes of equal variance with time constants spaced evenly in log
    /// between `shortest_s` and `longest_s` (superposed relaxations give
    /// 1/f: van der Ziel 1950, Physica 16; Kasdin 1995, Proc. IEEE 83).
    Pink { strength: f64, shortest_s: f64, longest_s: f64, components: u32 },
    /// `c`: a random telegraph signal ±1, a two-state Markov process with
    /// mean dwell `mean_dwell_s` in each state (Machlup 1954, J. Appl.
    /// Phys. 25).
    Telegraph { strength: f64, mean_dwell_s: f64 },
}

/// `non_gaussian_friction` forms. A share `s` (the strength) of `ξ_μ`'s unit
/// variance is non-Gaussian and white: `ξ_μ = sqrt(1 − s) w + sqrt(s) q`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "form", rename_all = "snake_case")]
pub enum ShapeForm {
    /// `q`: a Student-t variate with `ν` degrees of freedom scaled to unit
    /// variance (Student 1908, Biometrika 6): heavy tails.
    StudentT { strength: f64, degrees_of_freedom: u32 },
    /// `q`: a two-level variate, `(B − p)/sqrt(p (1 − p))` with `B` Bernoulli
    /// (`p` the high level's probability): two contact states, skewed
    /// and bimodal (bistable asperity contact, Persson 2000, *Sliding
    /// Friction*).
    Bimodal { strength: f64, high_probability: f64 },
}

/// `stiction` forms: the breakaway coefficient `μ_s` above the kinetic one
/// just above zero speed, `μ_k(0)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "form", rename_all = "snake_case")]
pub enum StaticForm {
    /// Karnopp static friction (Karnopp 1985, ASME J. Dyn. Syst. Meas.
    /// Control 107) with a static/kinetic ratio `1 + s` that scatters from
    /// stop to stop (Rabinowicz 1965, *Friction and Wear of Materials*):
    /// `μ_s = μ_k(0) (1 + s (1 + r ε))`, `ε` standard Gaussian, new at every
    /// stop, the factor never below 1. Strength `s`.
    Karnopp { strength: f64, scatter: f64 },
    /// Logarithmic ageing of the static coefficient with the time stuck
    /// (Rabinowicz 1951, J. Appl. Phys. 22; Dieterich 1972, JGR 77):
    /// `μ_s = μ_k(0) + B ln(1 + t_stick/t0)`. Strength `B`.
    DwellAgeing { strength: f64, time_constant_s: f64 },
}

/// `normal_force_drift` forms: the mean normal force `N0` changes during a
/// record (from its first sample; the warm-up sees `N0`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "form", rename_all = "snake_case")]
pub enum DriftForm {
    /// First-order thermal relaxation of the preload toward a new level
    /// (Newton's law of cooling): `N0(t) = N0 (1 + Δ (1 − exp(−t/τ_th)))`.
    /// Strength `Δ` (either sign).
    ThermalRelaxation { strength: f64, time_constant_s: f64 },
    /// Random-walk wear (stochastic increments of Archard's 1953 wear law,
    /// J. Appl. Phys. 24): `N0(t) = N0 (1 + W(t))`, `W` a Brownian motion
    /// with `Var W(t) = σ_w² t`. Strength `σ_w`, 1/sqrt(s).
    BrownianWear { strength: f64 },
}

/// One effect of the truth: its family and form with parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "effect", content = "parameters", rename_all = "snake_case")]
pub enum IndependentEffect {
    LoadDependentFriction(LoadForm),
    FrictionHysteresis(MemoryForm),
    NormalForceHarmonics(HarmonicForm),
    ColouredFrictionNoise(ColourForm),
    NonGaussianFriction(ShapeForm),
    Stiction(StaticForm),
    NormalForceDrift(DriftForm),
}

impl IndependentEffect {
    /// The family (the fixed effect name of `model.md`).
    pub fn family(&self) -> Effect {
        match self {
            IndependentEffect::LoadDependentFriction(_) => Effect::LoadDependentFriction,
            IndependentEffect::FrictionHysteresis(_) => Effect::FrictionHysteresis,
            IndependentEffect::NormalForceHarmonics(_) => Effect::NormalForceHarmonics,
            IndependentEffect::ColouredFrictionNoise(_) => Effect::ColouredFrictionNoise,
            IndependentEffect::NonGaussianFriction(_) => Effect::NonGaussianFriction,
            IndependentEffect::Stiction(_) => Effect::Stiction,
            IndependentEffect::NormalForceDrift(_) => Effect::NormalForceDrift,
        }
    }

    /// The form's index in its family's list of [`FORMS`].
    pub fn form_index(&self) -> u32 {
        match self {
            IndependentEffect::LoadDependentFriction(f) => match f {
                LoadForm::Hertzian { .. } => 0,
                LoadForm::Logistic { .. } => 1,
                LoadForm::JkrAdhesion { .. } => 2,
            },
            IndependentEffect::FrictionHysteresis(f) => match f {
                MemoryForm::Lugre { .. } => 0,
                MemoryForm::RateState { .. } => 1,
            },
            IndependentEffect::NormalForceHarmonics(f) => match f {
                HarmonicForm::PositionFollowing { .. } => 0,
                HarmonicForm::WanderingHarmonic { .. } => 1,
            },
            IndependentEffect::ColouredFrictionNoise(f) => match f {
                ColourForm::Pink { .. } => 0,
                ColourForm::Telegraph { .. } => 1,
            },
            IndependentEffect::NonGaussianFriction(f) => match f {
                ShapeForm::StudentT { .. } => 0,
                ShapeForm::Bimodal { .. } => 1,
            },
            IndependentEffect::Stiction(f) => match f {
                StaticForm::Karnopp { .. } => 0,
                StaticForm::DwellAgeing { .. } => 1,
            },
            IndependentEffect::NormalForceDrift(f) => match f {
                DriftForm::ThermalRelaxation { .. } => 0,
                DriftForm::BrownianWear { .. } => 1,
            },
        }
    }

    /// The form's entry in [`FORMS`] (name, formula and source).
    pub fn form_description(&self) -> &'static str {
        forms_of(self.family())[self.form_index() as usize]
    }

    /// The strength parameter (0: the baseline).
    pub fn strength(&self) -> f64 {
        let mut s = 0.0;
        let mut copy = *self;
        copy.visit_strength(|v| s = *v);
        s
    }

    /// The same effect with strength `s` (0: the baseline).
    pub fn with_strength(mut self, s: f64) -> Self {
        self.visit_strength(|v| *v = s);
        self
    }

    fn visit_strength(&mut self, f: impl FnOnce(&mut f64)) {
        let s = match self {
            IndependentEffect::LoadDependentFriction(
                LoadForm::Hertzian { strength, .. }
                | LoadForm::Logistic { strength, .. }
                | LoadForm::JkrAdhesion { strength, .. },
            ) => strength,
            IndependentEffect::FrictionHysteresis(
                MemoryForm::Lugre { strength, .. } | MemoryForm::RateState { strength, .. },
            ) => strength,
            IndependentEffect::NormalForceHarmonics(
                HarmonicForm::PositionFollowing { strength, .. } | HarmonicForm::WanderingHarmonic { strength, .. },
            ) => strength,
            IndependentEffect::ColouredFrictionNoise(
                ColourForm::Pink { strength, .. } | ColourForm::Telegraph { strength, .. },
            ) => strength,
            IndependentEffect::NonGaussianFriction(
                ShapeForm::StudentT { strength, .. } | ShapeForm::Bimodal { strength, .. },
            ) => strength,
            IndependentEffect::Stiction(
                StaticForm::Karnopp { strength, .. } | StaticForm::DwellAgeing { strength, .. },
            ) => strength,
            IndependentEffect::NormalForceDrift(
                DriftForm::ThermalRelaxation { strength, .. } | DriftForm::BrownianWear { strength },
            ) => strength,
        };
        f(s);
    }

    /// The effect in `family`'s form `form` at its moderate or strong
    /// preset, with the form's other parameters drawn from `rng`;
    /// `reference_load_n` is the set's reference load.
    pub fn preset(
        family: Effect,
        form: u32,
        strong: bool,
        reference_load_n: f64,
        rng: &mut StdRng,
    ) -> Result<IndependentEffect> {
        let count = forms_of(family).len() as u32;
        if form >= count {
            return Err(Error::setting(
                "hidden effect",
                format!("{family} has {count} independent forms (0..{}), not form {form}", count - 1),
            ));
        }
        let pick = |moderate: f64, strong_value: f64| if strong { strong_value } else { moderate };
        let sign = |rng: &mut StdRng| if rng.random::<f64>() < 0.5 { -1.0 } else { 1.0 };
        let n_ref = reference_load_n;
        Ok(match (family, form) {
            (Effect::LoadDependentFriction, 0) => IndependentEffect::LoadDependentFriction(LoadForm::Hertzian {
                strength: pick(0.8, 3.0),
                reference_load_n: n_ref,
            }),
            (Effect::LoadDependentFriction, 1) => {
                let n_t = n_ref * uniform(rng, 0.8, 1.25);
                IndependentEffect::LoadDependentFriction(LoadForm::Logistic {
                    strength: sign(rng) * pick(0.15, 0.35),
                    transition_load_n: n_t,
                    width_n: n_t / 6.0,
                    reference_load_n: n_ref,
                })
            }
            (Effect::LoadDependentFriction, _) => IndependentEffect::LoadDependentFriction(LoadForm::JkrAdhesion {
                strength: pick(0.3, 1.0) * n_ref,
                exponent: 2.0 / 3.0,
                reference_load_n: n_ref,
            }),
            (Effect::FrictionHysteresis, 0) => IndependentEffect::FrictionHysteresis(MemoryForm::Lugre {
                strength: pick(1e-4, 4e-4),
                bristle_damping_ratio: uniform(rng, 0.5, 1.0),
                damping_decay_speed_m_per_s: 1e-3,
                reference_load_n: n_ref,
            }),
            (Effect::FrictionHysteresis, _) => IndependentEffect::FrictionHysteresis(MemoryForm::RateState {
                strength: pick(0.015, 0.035),
                slip_distance_m: 10f64.powf(uniform(rng, -3.7, -2.7)),
                reference_speed_m_per_s: 1e-6,
            }),
            (Effect::NormalForceHarmonics, 0) => {
                IndependentEffect::NormalForceHarmonics(HarmonicForm::PositionFollowing {
                    strength: pick(0.015, 0.04),
                    quadratic_per_linear: sign(rng) * uniform(rng, 0.5, 1.0),
                })
            }
            (Effect::NormalForceHarmonics, _) => {
                IndependentEffect::NormalForceHarmonics(HarmonicForm::WanderingHarmonic {
                    strength: pick(0.03, 0.08),
                    order: if rng.random::<f64>() < 0.5 { 1 } else { 2 },
                    phase_diffusion_rad2_per_s: 10f64.powf(uniform(rng, -2.0, -0.7)),
                    initial_phase_rad: uniform(rng, 0.0, TAU),
                })
            }
            (Effect::ColouredFrictionNoise, 0) => IndependentEffect::ColouredFrictionNoise(ColourForm::Pink {
                strength: pick(0.5, 0.9),
                shortest_s: 0.005,
                longest_s: 20.0,
                components: 12,
            }),
            (Effect::ColouredFrictionNoise, _) => IndependentEffect::ColouredFrictionNoise(ColourForm::Telegraph {
                strength: pick(0.35, 0.7),
                mean_dwell_s: uniform(rng, 0.05, 0.3),
            }),
            (Effect::NonGaussianFriction, 0) => IndependentEffect::NonGaussianFriction(ShapeForm::StudentT {
                strength: pick(0.6, 1.0),
                degrees_of_freedom: 3 + (rng.random::<f64>() * 3.0) as u32,
            }),
            (Effect::NonGaussianFriction, _) => IndependentEffect::NonGaussianFriction(ShapeForm::Bimodal {
                strength: pick(0.5, 0.85),
                high_probability: uniform(rng, 0.15, 0.3),
            }),
            (Effect::Stiction, 0) => {
                IndependentEffect::Stiction(StaticForm::Karnopp { strength: pick(0.2, 0.4), scatter: 0.3 })
            }
            (Effect::Stiction, _) => IndependentEffect::Stiction(StaticForm::DwellAgeing {
                strength: pick(0.03, 0.08),
                time_constant_s: uniform(rng, 0.0005, 0.003),
            }),
            (Effect::NormalForceDrift, 0) => IndependentEffect::NormalForceDrift(DriftForm::ThermalRelaxation {
                strength: sign(rng) * pick(0.06, 0.15),
                time_constant_s: uniform(rng, 8.0, 25.0),
            }),
            (Effect::NormalForceDrift, _) => {
                IndependentEffect::NormalForceDrift(DriftForm::BrownianWear { strength: pick(0.008, 0.02) })
            }
        })
    }
}

/// A synthetic truth: rig, friction law, noise, effects and the integration
/// it is simulated with. Serialised as `truth.json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct IndependentTruth {
    /// [`GENERATOR`].
    pub generator: String,
    /// The seed it was drawn from.
    pub seed: u64,
    /// What it is, in words: the law, the effects with their sources, and
    /// the conditions where the block is expected to stay stuck.
    pub description: String,
    pub rig: TruthRig,
    pub friction: TruthFriction,
    /// At most one per family.
    pub effects: Vec<IndependentEffect>,
    pub integration: Integration,
    /// The grid it was drawn for.
    pub conditions: Vec<TruthCondition>,
}

impl IndependentTruth {
    /// The families hidden in it.
    pub fn families(&self) -> Vec<Effect> {
        self.effects.iter().map(IndependentEffect::family).collect()
    }

    /// The same truth with every effect at strength 0 (the baseline).
    pub fn baseline(&self) -> IndependentTruth {
        let mut t = self.clone();
        t.effects = t.effects.iter().map(|e| e.with_strength(0.0)).collect();
        t
    }

    /// Checks that the truth can be simulated.
    pub fn validate(&self) -> Result<()> {
        let r = &self.rig;
        let f = &self.friction;
        let positive = [
            ("rig.mass_kg", r.mass_kg),
            ("rig.natural_frequency_hz", r.natural_frequency_hz),
            ("friction.noise_interval_s", f.noise_interval_s),
            ("integration.step_rate_hz", self.integration.step_rate_hz),
        ];
        for (key, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(Error::setting(key, format!("{value} must be a positive finite number")));
            }
        }
        let non_negative = [
            ("rig.damping_ratio", r.damping_ratio),
            ("rig.excitation_amplitude_m", r.excitation_amplitude_m),
            ("friction.c_s_per_m", f.c_s_per_m),
            ("friction.sigma_mu", f.sigma_mu),
            ("friction.sigma_n_n", f.sigma_n_n),
            ("integration.warmup_s", self.integration.warmup_s),
            ("integration.rest_speed_m_per_s", self.integration.rest_speed_m_per_s),
        ];
        for (key, value) in non_negative {
            if !(value.is_finite() && value >= 0.0) {
                return Err(Error::setting(key, format!("{value} must be a finite number ≥ 0")));
            }
        }
        for (key, value) in [("friction.a", f.a), ("friction.b", f.b), ("friction.d_s2_per_m2", f.d_s2_per_m2)] {
            if !value.is_finite() {
                return Err(Error::setting(key, format!("{value} is not finite")));
            }
        }
        if self.integration.step_rate_hz < MIN_STEP_RATE_HZ {
            return Err(Error::setting(
                "integration.step_rate_hz",
                format!(
                    "{} Hz is below the integrator's minimum of {MIN_STEP_RATE_HZ} Hz",
                    self.integration.step_rate_hz
                ),
            ));
        }
        let mut seen = Vec::new();
        for e in &self.effects {
            if seen.contains(&e.family()) {
                return Err(Error::setting("effects", format!("{} appears twice; one form per family", e.family())));
            }
            seen.push(e.family());
            if !e.strength().is_finite() {
                return Err(Error::setting("effects", format!("{}: strength is not finite", e.family())));
            }
        }
        Ok(())
    }
}

fn uniform(rng: &mut StdRng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

/// splitmix64: decorrelates seeds built from small integers.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The RNG of one stream of one path.
fn stream_rng(seed: u64, path: u64, stream: u64) -> StdRng {
    StdRng::seed_from_u64(mix(mix(mix(seed) ^ path) ^ stream.wrapping_mul(0xD6E8_FEB8_6659_FD93)))
}

/// Which stream each random quantity draws from.
mod streams {
    pub const FRICTION: u64 = 1;
    pub const NORMAL: u64 = 2;
    pub const SHAPE: u64 = 3;
    pub const COLOUR: u64 = 4;
    pub const HARMONIC: u64 = 5;
    pub const DRIFT: u64 = 6;
    pub const STICTION: u64 = 7;
    pub const SENSOR: u64 = 8;
    pub const ORIGIN: u64 = 9;
    pub const TRUTH: u64 = 10;
}

/// Path identifiers: records and statistics never share noise.
fn record_path(condition: usize, run: u32) -> u64 {
    (1 << 62) | ((condition as u64) << 24) | u64::from(run)
}

fn stats_path(condition: usize, path: u32) -> u64 {
    (2 << 61) | ((condition as u64) << 24) | u64::from(path)
}

/// Draws a truth: a random rig and eq. 7 law (the same for a given `seed`
/// whatever is hidden), each `hidden` effect at its preset (its other
/// parameters from a stream of its own), at every frequency ratio × load
/// (frequency-major). The reference load of the load forms is the geometric
/// mean of `loads_n`.
pub fn random_truth(
    seed: u64,
    hidden: &[HiddenForm],
    loads_n: &[f64],
    frequency_ratios: &[f64],
) -> Result<(IndependentTruth, Vec<Condition>)> {
    if loads_n.is_empty() || loads_n.iter().any(|n| !(n.is_finite() && *n > 0.0)) {
        return Err(Error::setting("loads", format!("{loads_n:?}: need at least one positive normal force")));
    }
    if frequency_ratios.is_empty() || frequency_ratios.iter().any(|r| !(r.is_finite() && *r > 0.0)) {
        return Err(Error::setting(
            "frequency ratios",
            format!("{frequency_ratios:?}: need at least one positive frequency ratio"),
        ));
    }
    let mut rng = stream_rng(seed, 0, streams::TRUTH);
    let rig = TruthRig {
        mass_kg: uniform(&mut rng, 0.6, 1.6),
        natural_frequency_hz: uniform(&mut rng, 8.0, 13.0),
        damping_ratio: uniform(&mut rng, 0.002, 0.01),
        excitation_amplitude_m: uniform(&mut rng, 1.5e-3, 3e-3),
    };
    let friction = TruthFriction {
        a: uniform(&mut rng, 0.15, 0.35),
        b: uniform(&mut rng, -0.04, 0.12),
        c_s_per_m: 10f64.powf(uniform(&mut rng, 0.3, 1.6)),
        d_s2_per_m2: uniform(&mut rng, 0.0, 0.3),
        sigma_mu: uniform(&mut rng, 0.015, 0.07),
        sigma_n_n: uniform(&mut rng, 0.1, 0.4),
        noise_interval_s: 1.0 / 600.0,
    };
    let reference_load_n = (loads_n.iter().map(|n| n.ln()).sum::<f64>() / loads_n.len() as f64).exp();
    let mut effects = Vec::new();
    for &(family, form, strong) in hidden {
        if effects.iter().any(|e: &IndependentEffect| e.family() == family) {
            return Err(Error::setting("hidden effect", format!("{family} is hidden twice; one form per family")));
        }
        let mut effect_rng = stream_rng(seed, Effect::ALL.iter().position(|e| *e == family).unwrap_or(0) as u64, 11);
        effects.push(IndependentEffect::preset(family, form, strong, reference_load_n, &mut effect_rng)?);
    }
    let k = rig.stiffness_n_per_m();
    let mut conditions = Vec::new();
    let mut truth_conditions = Vec::new();
    for &eta in frequency_ratios {
        for &n0 in loads_n {
            let c = Condition { excitation_frequency_hz: eta * rig.natural_frequency_hz, normal_force_n: n0 };
            c.validate()?;
            conditions.push(c);
            truth_conditions.push(TruthCondition {
                excitation_frequency_hz: c.excitation_frequency_hz,
                frequency_ratio: eta,
                normal_force_n: n0,
                expected_to_stick_throughout: (friction.a + friction.b) * n0 >= k * rig.excitation_amplitude_m,
            });
        }
    }
    let mut truth = IndependentTruth {
        generator: GENERATOR.to_string(),
        seed,
        description: String::new(),
        rig,
        friction,
        effects,
        integration: Integration::default(),
        conditions: truth_conditions,
    };
    truth.description = describe(&truth, hidden);
    truth.validate()?;
    Ok((truth, conditions))
}

fn describe(truth: &IndependentTruth, hidden: &[HiddenForm]) -> String {
    let f = &truth.friction;
    let r = &truth.rig;
    let mut text = format!(
        "Independent synthetic truth ({GENERATOR}, seed {}): rig m = {:.4} kg, f0 = {:.4} Hz, ζ = {:.5}, U0 = {:.3} mm \
         (k U0 = {:.3} N); friction μ(v) = {:.4} + {:.4}/(1 + {:.3}|v|) + {:.4} v² + {:.4} ξ_μ, σ_N = {:.3} N, noise held \
         {:.6} s. ",
        truth.seed,
        r.mass_kg,
        r.natural_frequency_hz,
        r.damping_ratio,
        r.excitation_amplitude_m * 1e3,
        r.stiffness_n_per_m() * r.excitation_amplitude_m,
        f.a,
        f.b,
        f.c_s_per_m,
        f.d_s2_per_m2,
        f.sigma_mu,
        f.sigma_n_n,
        f.noise_interval_s
    );
    if truth.effects.is_empty() {
        text.push_str("No effect: the baseline (eq. 7 with Gaussian short-interval noise). ");
    }
    for (e, h) in truth.effects.iter().zip(hidden) {
        text.push_str(&format!(
            "Hidden: {} at the {} preset (strength {}), form {} — {}. ",
            e.family(),
            if h.2 { "strong" } else { "moderate" },
            e.strength(),
            e.form_index(),
            e.form_description()
        ));
    }
    let stuck: Vec<String> = truth
        .conditions
        .iter()
        .filter(|c| c.expected_to_stick_throughout)
        .map(|c| format!("{:.3} Hz/{} N", c.excitation_frequency_hz, c.normal_force_n))
        .collect();
    if !stuck.is_empty() {
        text.push_str(&format!(
            "At {} the breakaway force μ(0) N0 is at least k U0: the block is expected to stay stuck for the whole \
             record there (noise may free it now and then).",
            stuck.join(", ")
        ));
    }
    text.trim_end().to_string()
}

// ---------------------------------------------------------------------------
// Noise
// ---------------------------------------------------------------------------

/// A stream of standard Gaussian (Box–Muller) and uniform values.
struct Gauss {
    rng: StdRng,
    spare: Option<f64>,
}

impl Gauss {
    fn new(seed: u64, path: u64, stream: u64) -> Gauss {
        Gauss { rng: stream_rng(seed, path, stream), spare: None }
    }

    fn uniform(&mut self) -> f64 {
        self.rng.random::<f64>()
    }

    fn normal(&mut self) -> f64 {
        if let Some(s) = self.spare.take() {
            return s;
        }
        let u1 = 1.0 - self.rng.random::<f64>(); // (0, 1]
        let u2 = self.rng.random::<f64>();
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (TAU * u2).sin_cos();
        self.spare = Some(r * s);
        r * c
    }
}

/// The per-path state of the random parts that change once per noise
/// interval.
struct Noise {
    friction: Gauss,
    normal: Gauss,
    shape: Gauss,
    colour: Gauss,
    harmonic: Gauss,
    drift: Gauss,
    /// Pink: (ρ, innovation scale, value) per AR(1).
    pink: Vec<(f64, f64, f64)>,
    telegraph: f64,
    telegraph_switch: f64,
    phase: f64,
    wear: f64,
}

/// What is held over one noise interval.
#[derive(Clone, Copy, Debug, Default)]
struct Held {
    /// `σ_μ ξ_μ`.
    mu_noise: f64,
    /// The mean normal force with its drift, N.
    n_mean: f64,
    /// `σ_N ξ_N`, N.
    n_noise: f64,
    /// cos and sin of the wandering harmonic's phase.
    phase_cos: f64,
    phase_sin: f64,
}

impl Noise {
    fn new(plant: &Plant, seed: u64, path: u64) -> Noise {
        let mut colour = Gauss::new(seed, path, streams::COLOUR);
        let tau = plant.noise_interval_s;
        let mut pink = Vec::new();
        let mut telegraph = 1.0;
        let mut telegraph_switch = 0.0;
        match plant.colour {
            Some(ColourForm::Pink { shortest_s, longest_s, components, .. }) => {
                let count = components.max(1);
                for i in 0..count {
                    let frac = if count > 1 { f64::from(i) / f64::from(count - 1) } else { 0.0 };
                    let time = shortest_s * (longest_s / shortest_s).powf(frac);
                    let rho = (-tau / time.max(1e-12)).exp();
                    // Each component starts in its stationary law: no warm-up of the noise.
                    pink.push((rho, (1.0 - rho * rho).sqrt(), colour.normal()));
                }
            }
            Some(ColourForm::Telegraph { mean_dwell_s, .. }) => {
                telegraph = if colour.uniform() < 0.5 { -1.0 } else { 1.0 };
                telegraph_switch = 1.0 - (-tau / mean_dwell_s.max(1e-12)).exp();
            }
            None => {}
        }
        let phase = match plant.harmonic {
            Some(HarmonicForm::WanderingHarmonic { initial_phase_rad, .. }) => initial_phase_rad,
            _ => 0.0,
        };
        Noise {
            friction: Gauss::new(seed, path, streams::FRICTION),
            normal: Gauss::new(seed, path, streams::NORMAL),
            shape: Gauss::new(seed, path, streams::SHAPE),
            colour,
            harmonic: Gauss::new(seed, path, streams::HARMONIC),
            drift: Gauss::new(seed, path, streams::DRIFT),
            pink,
            telegraph,
            telegraph_switch,
            phase,
            wear: 0.0,
        }
    }

    /// The values of the interval that starts at record time `t` (negative
    /// during the warm-up).
    fn interval(&mut self, plant: &Plant, t: f64) -> Held {
        let tau = plant.noise_interval_s;
        let mut xi = self.friction.normal();
        if let Some(shape) = plant.shape {
            let (s, q) = match shape {
                ShapeForm::StudentT { strength, degrees_of_freedom } => {
                    let nu = degrees_of_freedom.max(3);
                    let z = self.shape.normal();
                    let chi2: f64 = (0..nu).map(|_| self.shape.normal().powi(2)).sum::<f64>().max(1e-300);
                    let nu = f64::from(nu);
                    (strength, z / (chi2 / nu).sqrt() / (nu / (nu - 2.0)).sqrt())
                }
                ShapeForm::Bimodal { strength, high_probability } => {
                    let p = high_probability.clamp(1e-6, 1.0 - 1e-6);
                    let bit = if self.shape.uniform() < p { 1.0 } else { 0.0 };
                    (strength, (bit - p) / (p * (1.0 - p)).sqrt())
                }
            };
            let s = s.clamp(0.0, 1.0);
            xi = (1.0 - s).sqrt() * xi + s.sqrt() * q;
        }
        if let Some(colour) = plant.colour {
            let (s, c) = match colour {
                ColourForm::Pink { strength, .. } => {
                    let mut sum = 0.0;
                    for (rho, scale, value) in &mut self.pink {
                        *value = *rho * *value + *scale * self.colour.normal();
                        sum += *value;
                    }
                    (strength, sum / (self.pink.len().max(1) as f64).sqrt())
                }
                ColourForm::Telegraph { strength, .. } => {
                    if self.colour.uniform() < self.telegraph_switch {
                        self.telegraph = -self.telegraph;
                    }
                    (strength, self.telegraph)
                }
            };
            let s = s.clamp(0.0, 1.0);
            xi = (1.0 - s).sqrt() * xi + s.sqrt() * c;
        }
        let n_noise = plant.sigma_n * self.normal.normal();
        let since_start = t.max(0.0);
        let drift = match plant.drift {
            None => 1.0,
            Some(DriftForm::ThermalRelaxation { strength, time_constant_s }) => {
                1.0 + strength * (1.0 - (-since_start / time_constant_s.max(1e-12)).exp())
            }
            Some(DriftForm::BrownianWear { strength }) => {
                let z = self.drift.normal();
                if t > 0.0 {
                    self.wear += strength * tau.sqrt() * z;
                }
                1.0 + self.wear
            }
        };
        let (mut phase_cos, mut phase_sin) = (1.0, 0.0);
        if let Some(HarmonicForm::WanderingHarmonic { phase_diffusion_rad2_per_s, .. }) = plant.harmonic {
            self.phase += (phase_diffusion_rad2_per_s * tau).sqrt() * self.harmonic.normal();
            (phase_sin, phase_cos) = self.phase.sin_cos();
        }
        Held { mu_noise: plant.sigma_mu * xi, n_mean: plant.n0 * drift, n_noise, phase_cos, phase_sin }
    }
}

// ---------------------------------------------------------------------------
// The integrator
// ---------------------------------------------------------------------------

/// The constants of one condition.
#[derive(Clone, Debug)]
struct Plant {
    m: f64,
    k: f64,
    c: f64,
    u0: f64,
    omega: f64,
    n0: f64,
    a: f64,
    b: f64,
    cs: f64,
    d: f64,
    sigma_mu: f64,
    sigma_n: f64,
    noise_interval_s: f64,
    rest_speed: f64,
    load: Option<LoadForm>,
    memory: Option<MemoryForm>,
    harmonic: Option<HarmonicForm>,
    colour: Option<ColourForm>,
    shape: Option<ShapeForm>,
    stiction: Option<StaticForm>,
    drift: Option<DriftForm>,
    /// LuGre: (L, σ1, v_d), when LuGre is on with a positive strength.
    lugre: Option<(f64, f64, f64)>,
}

impl Plant {
    fn new(truth: &IndependentTruth, condition: Condition) -> Plant {
        let r = &truth.rig;
        let f = &truth.friction;
        let mut p = Plant {
            m: r.mass_kg,
            k: r.stiffness_n_per_m(),
            c: r.damping_n_s_per_m(),
            u0: r.excitation_amplitude_m,
            omega: TAU * condition.excitation_frequency_hz,
            n0: condition.normal_force_n,
            a: f.a,
            b: f.b,
            cs: f.c_s_per_m,
            d: f.d_s2_per_m2,
            sigma_mu: f.sigma_mu,
            sigma_n: f.sigma_n_n,
            noise_interval_s: f.noise_interval_s,
            rest_speed: truth.integration.rest_speed_m_per_s,
            load: None,
            memory: None,
            harmonic: None,
            colour: None,
            shape: None,
            stiction: None,
            drift: None,
            lugre: None,
        };
        for e in &truth.effects {
            match *e {
                IndependentEffect::LoadDependentFriction(form) => p.load = Some(form),
                IndependentEffect::FrictionHysteresis(form) => {
                    p.memory = Some(form);
                    if let MemoryForm::Lugre {
                        strength,
                        bristle_damping_ratio,
                        damping_decay_speed_m_per_s,
                        reference_load_n,
                    } = form
                        && strength > 0.0
                    {
                        let sigma1 =
                            2.0 * bristle_damping_ratio * (p.m / (reference_load_n.max(1e-9) * strength)).sqrt();
                        p.lugre = Some((strength, sigma1, damping_decay_speed_m_per_s.max(1e-12)));
                    }
                }
                IndependentEffect::NormalForceHarmonics(form) => p.harmonic = Some(form),
                IndependentEffect::ColouredFrictionNoise(form) => p.colour = Some(form),
                IndependentEffect::NonGaussianFriction(form) => p.shape = Some(form),
                IndependentEffect::Stiction(form) => p.stiction = Some(form),
                IndependentEffect::NormalForceDrift(form) => p.drift = Some(form),
            }
        }
        p
    }

    /// The load factor of the friction law at normal force `n`.
    fn load_factor(&self, n: f64) -> f64 {
        match self.load {
            None => 1.0,
            Some(LoadForm::Hertzian { strength, reference_load_n }) => {
                ((1.0 + strength) / (1.0 + strength * n / reference_load_n)).cbrt()
            }
            Some(LoadForm::Logistic { strength, transition_load_n, width_n, reference_load_n }) => {
                let l = |n: f64| 1.0 / (1.0 + (-(n - transition_load_n) / width_n).exp());
                (1.0 + strength * (l(n) - l(reference_load_n))).max(0.0)
            }
            Some(LoadForm::JkrAdhesion { strength, exponent, reference_load_n }) => {
                ((1.0 + strength / n.max(1e-9)) / (1.0 + strength / reference_load_n)).powf(exponent)
            }
        }
    }

    /// The starting state: the harmonic-balance (equivalent viscous
    /// damping) steady state of the baseline at base phase `theta`, or rest
    /// where friction holds the block.
    fn initial_state(&self, theta: f64) -> (f64, f64) {
        let eta = self.omega / (self.k / self.m).sqrt();
        let zeta = self.c / (2.0 * (self.k * self.m).sqrt());
        let f0 = (self.a + 0.5 * self.b).max(0.0) * self.n0;
        let r = if self.u0 > 0.0 { 4.0 * f0 / (PI * self.k * self.u0) } else { 1.0 };
        if r >= 1.0 {
            return (0.0, 0.0);
        }
        let big_a = (1.0 - eta * eta).powi(2) + (2.0 * zeta * eta).powi(2);
        let disc = (2.0 * zeta * eta * r).powi(2) - big_a * (r * r - 1.0);
        let y = (-2.0 * zeta * eta * r + disc.max(0.0).sqrt()) / big_a;
        if !(y.is_finite() && y > 0.0) {
            return (0.0, 0.0);
        }
        let lag = (2.0 * zeta * eta + r / y).atan2(1.0 - eta * eta);
        let amplitude = y * self.u0;
        (amplitude * (theta - lag).cos(), -amplitude * self.omega * (theta - lag).sin())
    }
}

/// Where a path starts and how it is stepped.
#[derive(Clone, Copy, Debug)]
struct Grid {
    /// Step, s.
    dt: f64,
    /// Steps per noise interval.
    hold: u64,
    /// Warm-up steps (a whole number of noise intervals, at least whole
    /// excitation periods).
    warmup_steps: u64,
    /// Steps from the record's start to its end.
    record_steps: u64,
}

impl Grid {
    fn new(truth: &IndependentTruth, frequency_hz: f64, duration_s: f64) -> Grid {
        let tau = truth.friction.noise_interval_s;
        let hold = (tau * truth.integration.step_rate_hz.max(MIN_STEP_RATE_HZ)).ceil().max(1.0) as u64;
        let dt = tau / hold as f64;
        let periods = (truth.integration.warmup_s * frequency_hz).ceil();
        let intervals = (periods / frequency_hz / tau).ceil() as u64;
        Grid { dt, hold, warmup_steps: intervals * hold, record_steps: (duration_s / dt).ceil() as u64 }
    }
}

/// What a path reports at each step of its record, before the step: its
/// step index from the record's start, its time, the base phase's cos and
/// sin, the state `x`, `v`, the normal force and the friction force.
trait Sink {
    #[allow(clippy::too_many_arguments)]
    fn step(&mut self, n: u64, t: f64, cos: f64, sin: f64, x: f64, v: f64, normal: f64, friction: f64);
}

/// `exp(−x)` for `x ≥ 0`: a 4th-order series below 0.02 (relative error
/// under 3e-11), 0 above 40, the library's `exp` between.
fn exp_neg(x: f64) -> f64 {
    if x < 0.02 {
        1.0 - x * (1.0 - 0.5 * x * (1.0 - x / 3.0 * (1.0 - 0.25 * x)))
    } else if x > 40.0 {
        0.0
    } else {
        (-x).exp()
    }
}

fn sign(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Integrates one path of `truth` at `condition`: the warm-up, then the
/// record's `grid.record_steps` steps, each reported to `sink`. The base is
/// `u = U0 cos(Ω t + phase0)`, `t` from the record's start.
fn simulate<S: Sink>(plant: &Plant, grid: Grid, seed: u64, path: u64, phase0: f64, sink: &mut S) {
    let dt = grid.dt;
    let mut noise = Noise::new(plant, seed, path);
    let mut stiction_rng = Gauss::new(seed, path, streams::STICTION);
    let total = grid.warmup_steps + grid.record_steps;
    let t_of = |n: u64| (n as f64 - grid.warmup_steps as f64) * dt;
    let (rot_sin, rot_cos) = (plant.omega * dt).sin_cos();
    let (mut x, mut v) = plant.initial_state(plant.omega * t_of(0) + phase0);
    let mut stuck = v == 0.0;
    let mut held = Held::default();
    let (mut cb, mut sb) = (1.0, 0.0);
    let mut cached_n = f64::NAN;
    let mut cached_factor = 1.0;
    // Stiction: time stuck, and the scatter draw of the current stop.
    let mut t_stick = 0.0;
    let mut scatter = 0.0;
    // Rate-and-state: the state θ.
    let mut theta = match plant.memory {
        Some(MemoryForm::RateState { slip_distance_m, .. }) => slip_distance_m / v.abs().max(1e-3),
        _ => 0.0,
    };
    // LuGre: the bristle deflection z (steady at the start).
    let mut z = 0.0;
    let (k, c, u0) = (plant.k, plant.c, plant.u0);
    let dt_over_m = dt / plant.m;
    let (a, b, cs, d) = (plant.a, plant.b, plant.cs, plant.d);
    let draw_scatter = |rng: &mut Gauss| match plant.stiction {
        Some(StaticForm::Karnopp { .. }) => rng.normal(),
        _ => 0.0,
    };
    let mut countdown = 0;
    for n in 0..total {
        let t = t_of(n);
        if countdown == 0 {
            countdown = grid.hold;
            held = noise.interval(plant, t);
            // Re-anchor the base's rotation on the exact phase.
            (sb, cb) = (plant.omega * t + phase0).sin_cos();
        }
        let u = u0 * cb;
        // The normal force.
        let mut nf = held.n_mean;
        match plant.harmonic {
            None => {}
            Some(HarmonicForm::PositionFollowing { strength, quadratic_per_linear }) => {
                let r = if u0 > 0.0 { x / u0 } else { 0.0 };
                nf *= (1.0 + strength * r + strength * quadratic_per_linear * r * r).max(0.0);
            }
            Some(HarmonicForm::WanderingHarmonic { strength, order, .. }) => {
                let (mut hc, mut hs) = (cb, sb);
                for _ in 1..order.max(1) {
                    (hc, hs) = (hc * cb - hs * sb, hs * cb + hc * sb);
                }
                nf *= 1.0 + strength * (hc * held.phase_cos - hs * held.phase_sin);
            }
        }
        nf = (nf + held.n_noise).max(0.0);
        let lf = if plant.load.is_some() {
            if nf != cached_n {
                cached_n = nf;
                cached_factor = plant.load_factor(nf);
            }
            cached_factor
        } else {
            1.0
        };
        // The eq. 7 law at speed s (noise and load factor included), ≥ 0.
        let law = |s: f64| ((a + b / (1.0 + cs * s) + d * s * s + held.mu_noise) * lf).max(0.0);
        let mu_k0 = ((a + b + held.mu_noise) * lf).max(0.0);
        let breakaway = |t_stick: f64, scatter: f64| match plant.stiction {
            None => mu_k0,
            Some(StaticForm::Karnopp { strength, scatter: r }) => {
                mu_k0 * (1.0 + strength * (1.0 + r * scatter)).max(1.0)
            }
            Some(StaticForm::DwellAgeing { strength, time_constant_s }) => {
                mu_k0 + strength * (t_stick / time_constant_s.max(1e-12)).ln_1p()
            }
        };

        let friction;
        if let Some((length, sigma1, v_d)) = plant.lugre {
            // LuGre: the bristle state carries stick (pre-sliding).
            let s = v.abs();
            let resting = s < 1e-3;
            if resting {
                if t_stick == 0.0 {
                    scatter = draw_scatter(&mut stiction_rng);
                }
                t_stick += dt;
            } else {
                t_stick = 0.0;
            }
            let excess = breakaway(t_stick, scatter) - mu_k0;
            let g = (law(s) + if excess > 0.0 { excess * exp_neg((s / 1e-3).powi(2)) } else { 0.0 }).max(1e-9);
            let zn = if s > 0.0 {
                let z_ss = sign(v) * g * length;
                z_ss + (z - z_ss) * exp_neg(s * dt / (g * length))
            } else {
                z
            };
            let zdot = (zn - z) / dt;
            let mu = zn / length + sigma1 * exp_neg((v / v_d).powi(2)) * zdot;
            friction = -nf * mu;
            let p = k * (u - x) - c * v;
            if n >= grid.warmup_steps {
                sink.step(n - grid.warmup_steps, t, cb, sb, x, v, nf, friction);
            }
            z = zn;
            v += dt_over_m * (p + friction);
            x += dt * v;
        } else if stuck {
            let p = k * (u - x);
            if p.abs() <= breakaway(t_stick, scatter) * nf {
                friction = -p;
                if n >= grid.warmup_steps {
                    sink.step(n - grid.warmup_steps, t, cb, sb, x, 0.0, nf, friction);
                }
                t_stick += dt;
                if let Some(MemoryForm::RateState { .. }) = plant.memory {
                    theta += dt;
                }
            } else {
                // Breakaway in the direction of the spring force, with the
                // kinetic friction just above zero speed.
                let dir = sign(p);
                friction = -dir * mu_k0 * nf;
                if n >= grid.warmup_steps {
                    sink.step(n - grid.warmup_steps, t, cb, sb, x, 0.0, nf, friction);
                }
                let vn = dt_over_m * (p + friction);
                if vn * dir > 0.0 {
                    stuck = false;
                    t_stick = 0.0;
                    v = vn;
                    x += dt * v;
                } else {
                    t_stick += dt;
                }
                if let Some(MemoryForm::RateState { .. }) = plant.memory {
                    theta += dt;
                }
            }
        } else {
            let s = v.abs();
            let mut mu = law(s);
            if let Some(MemoryForm::RateState { strength, slip_distance_m, reference_speed_m_per_s }) = plant.memory {
                // Δμ = 2b [asinh(y) − asinh(z)], y² = v² θ/(4 v_r D_c), z² = |v|/(4 v_r).
                let vr = reference_speed_m_per_s;
                let y2 = s * s * theta / (4.0 * vr * slip_distance_m);
                let z2 = s / (4.0 * vr);
                let delta = if y2.min(z2) > 1e3 {
                    // asinh(w) = ln(2w) + 1/(4w²) − O(1/w⁴): to 1e-7 b.
                    strength * ((y2 / z2).ln() + 0.5 * (1.0 / y2 - 1.0 / z2))
                } else {
                    let (y, zz) = (y2.sqrt(), z2.sqrt());
                    2.0 * strength * ((y + (y2 + 1.0).sqrt()) / (zz + (z2 + 1.0).sqrt())).ln()
                };
                mu = (mu + delta).max(0.0);
                // Aging law, exact for a step at constant speed.
                let theta_ss = slip_distance_m / s.max(1e-300);
                theta = theta_ss + (theta - theta_ss) * exp_neg(s * dt / slip_distance_m);
            }
            friction = -sign(v) * mu * nf;
            if n >= grid.warmup_steps {
                sink.step(n - grid.warmup_steps, t, cb, sb, x, v, nf, friction);
            }
            let p = k * (u - x) - c * v;
            let mut vn = v + dt_over_m * (p + friction);
            let crossing = vn * v <= 0.0;
            if crossing || (vn.abs() < plant.rest_speed && vn.abs() < s) {
                // At rest for an instant: stick, or go on in the direction
                // of the spring force.
                let p0 = k * (u - x);
                t_stick = 0.0;
                scatter = draw_scatter(&mut stiction_rng);
                if p0.abs() <= breakaway(0.0, scatter) * nf {
                    stuck = true;
                    vn = 0.0;
                } else if crossing || p0 * v < 0.0 {
                    let dir = sign(p0);
                    vn = dt_over_m * (p0 - dir * mu_k0 * nf);
                }
            }
            v = vn;
            x += dt * v;
        }
        countdown -= 1;
        // Advance the base's rotation by one step.
        (cb, sb) = (cb * rot_cos - sb * rot_sin, sb * rot_cos + cb * rot_sin);
    }
}

// ---------------------------------------------------------------------------
// Records
// ---------------------------------------------------------------------------

/// Where a record's time origin lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TimeOrigin {
    /// `t` in the frame of `u = U0 cos(2π f t)` (the format's default).
    Model,
    /// Each record starts at a random base phase, `t` from 0; the manifest
    /// says `"time_origin": "free"`.
    Free,
}

/// Standard deviations of the Gaussian sensor noise on each channel.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SensorNoise {
    pub x_m: f64,
    pub v_m_per_s: f64,
    pub normal_force_n: f64,
    pub friction_force_n: f64,
    pub base_x_m: f64,
}

impl Default for SensorNoise {
    fn default() -> Self {
        SensorNoise { x_m: 2e-6, v_m_per_s: 2e-3, normal_force_n: 0.02, friction_force_n: 0.02, base_x_m: 2e-6 }
    }
}

/// How the records of a set are taken.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RecordShape {
    pub runs_per_condition: u32,
    /// Record length after the warm-up, s.
    pub duration_s: f64,
    /// Sampling rate, Hz.
    pub sample_rate_hz: f64,
    pub time_origin: TimeOrigin,
    /// Write the base displacement `u(t)` as a `base_x` column.
    pub base_x: bool,
    pub sensor: SensorNoise,
}

impl Default for RecordShape {
    /// Option A: one 50 s run per condition at 600 Hz, model time origin,
    /// no `base_x`.
    fn default() -> Self {
        RecordShape {
            runs_per_condition: 1,
            duration_s: 50.0,
            sample_rate_hz: 600.0,
            time_origin: TimeOrigin::Model,
            base_x: false,
            sensor: SensorNoise::default(),
        }
    }
}

impl RecordShape {
    /// Option B: a free time origin without `base_x`.
    pub fn free_origin() -> RecordShape {
        RecordShape { time_origin: TimeOrigin::Free, ..RecordShape::default() }
    }

    /// Option C: a free time origin with a `base_x` column.
    pub fn free_origin_with_base() -> RecordShape {
        RecordShape { time_origin: TimeOrigin::Free, base_x: true, ..RecordShape::default() }
    }

    fn validate(&self, conditions: &[Condition]) -> Result<()> {
        if self.runs_per_condition == 0 {
            return Err(Error::setting("runs per condition", "must be at least 1"));
        }
        if !(self.duration_s.is_finite() && self.duration_s > 0.0) {
            return Err(Error::setting("record duration", format!("{} s must be positive", self.duration_s)));
        }
        if !(self.sample_rate_hz.is_finite() && self.sample_rate_hz > 0.0) {
            return Err(Error::setting("sample rate", format!("{} Hz must be positive", self.sample_rate_hz)));
        }
        let s = self.sensor;
        for value in [s.x_m, s.v_m_per_s, s.normal_force_n, s.friction_force_n, s.base_x_m] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(Error::setting("sensor noise", format!("{value} must be finite and ≥ 0")));
            }
        }
        for c in conditions {
            c.validate()?;
            if self.sample_rate_hz <= 2.0 * c.excitation_frequency_hz {
                return Err(Error::setting(
                    "sample rate",
                    format!("{} Hz does not resolve {} Hz", self.sample_rate_hz, c.excitation_frequency_hz),
                ));
            }
            if self.duration_s * c.excitation_frequency_hz < 10.0 {
                return Err(Error::setting(
                    "record duration",
                    format!("{} s holds fewer than ten periods at {} Hz", self.duration_s, c.excitation_frequency_hz),
                ));
            }
        }
        Ok(())
    }
}

/// One record's channels, SI units, sensor noise included.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct RecordColumns {
    pub t: Vec<f64>,
    pub x: Vec<f64>,
    pub v: Vec<f64>,
    pub normal_force: Vec<f64>,
    pub friction_force: Vec<f64>,
    /// The base displacement `u(t)`.
    pub base_x: Vec<f64>,
}

struct Sampler {
    next: u64,
    index: u64,
    sample_interval_s: f64,
    dt: f64,
    u0: f64,
    out: RecordColumns,
}

impl Sampler {
    /// The step nearest to sample `i`'s time.
    fn step_of(&self, i: u64) -> u64 {
        (i as f64 * self.sample_interval_s / self.dt).round() as u64
    }
}

impl Sink for Sampler {
    fn step(&mut self, n: u64, _t: f64, cos: f64, _sin: f64, x: f64, v: f64, normal: f64, friction: f64) {
        if n != self.next {
            return;
        }
        self.out.t.push(self.index as f64 * self.sample_interval_s);
        self.out.x.push(x);
        self.out.v.push(v);
        self.out.normal_force.push(normal);
        self.out.friction_force.push(friction);
        self.out.base_x.push(self.u0 * cos);
        self.index += 1;
        self.next = self.step_of(self.index);
    }
}

/// Simulates run `run` of condition `index` of a set (as [`write_set`]
/// writes it): noise-free channels first, then the sensor noise of `shape`.
pub fn simulate_run(
    truth: &IndependentTruth,
    condition: Condition,
    index: usize,
    run: u32,
    shape: &RecordShape,
    seed: u64,
) -> Result<RecordColumns> {
    truth.validate()?;
    shape.validate(&[condition])?;
    let plant = Plant::new(truth, condition);
    let path = record_path(index, run);
    let phase0 = match shape.time_origin {
        TimeOrigin::Model => 0.0,
        TimeOrigin::Free => TAU * Gauss::new(seed, path, streams::ORIGIN).uniform(),
    };
    let samples = (shape.duration_s * shape.sample_rate_hz).round() as u64;
    let sample_interval_s = 1.0 / shape.sample_rate_hz;
    let mut grid = Grid::new(truth, condition.excitation_frequency_hz, shape.duration_s);
    let mut sampler =
        Sampler { next: 0, index: 0, sample_interval_s, dt: grid.dt, u0: plant.u0, out: RecordColumns::default() };
    grid.record_steps = sampler.step_of(samples - 1) + 1;
    simulate(&plant, grid, seed, path, phase0, &mut sampler);
    let mut out = sampler.out;
    let mut sensor = Gauss::new(seed, path, streams::SENSOR);
    let s = shape.sensor;
    for i in 0..out.t.len() {
        out.x[i] += s.x_m * sensor.normal();
        out.v[i] += s.v_m_per_s * sensor.normal();
        out.normal_force[i] += s.normal_force_n * sensor.normal();
        out.friction_force[i] += s.friction_force_n * sensor.normal();
        out.base_x[i] += s.base_x_m * sensor.normal();
    }
    Ok(out)
}

/// Where [`write_set`] puts the truth of the set in `dir`: `truth.json` in
/// `dir`'s parent (next to the data directory, never inside it — so give
/// each set's data directory a parent of its own, e.g. `set-07/data`).
pub fn truth_path(dir: &Path) -> PathBuf {
    dir.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new(".")).join("truth.json")
}

/// The data file of run `run` of condition `index`.
fn run_file(index: usize, run: u32) -> String {
    format!("run-{index:02}-{run}.csv")
}

/// Writes a measurement set simulated from `truth` at `conditions` into
/// `dir` (`manifest.json` and one CSV per run), and the truth with the
/// set's shape and seed into [`truth_path`]`(dir)`. The manifest says
/// nothing of the truth. Same inputs, same bytes.
pub fn write_set(
    dir: &Path,
    truth: &IndependentTruth,
    conditions: &[Condition],
    shape: &RecordShape,
    seed: u64,
) -> Result<()> {
    truth.validate()?;
    if conditions.is_empty() {
        return Err(Error::setting("conditions", "a set needs at least one condition"));
    }
    shape.validate(conditions)?;
    let jobs: Vec<(usize, u32)> =
        (0..conditions.len()).flat_map(|i| (0..shape.runs_per_condition).map(move |r| (i, r))).collect();
    let records: Vec<RecordColumns> = jobs
        .par_iter()
        .map(|&(i, r)| simulate_run(truth, conditions[i], i, r, shape, seed))
        .collect::<Result<Vec<_>>>()?;
    create_dir(dir)?;
    let mut runs = Vec::new();
    for (&(i, r), record) in jobs.iter().zip(&records) {
        let file = run_file(i, r);
        write_run(&dir.join(&file), record, shape.base_x)?;
        runs.push(serde_json::json!({
            "file": file,
            "excitation_frequency_hz": conditions[i].excitation_frequency_hz,
            "excitation_amplitude_m": truth.rig.excitation_amplitude_m,
            "normal_force_n": conditions[i].normal_force_n,
        }));
    }
    let mut manifest = serde_json::json!({
        "format": "stickslip-measurements/1",
        "description": "synthetic measurement set from stickslip's independent generator (benchmark-diagnosis)",
        "rig": {
            "mass_kg": truth.rig.mass_kg,
            "natural_frequency_hz": truth.rig.natural_frequency_hz,
            "damping_ratio": truth.rig.damping_ratio,
        },
        "runs": runs,
    });
    if shape.time_origin == TimeOrigin::Free {
        manifest["time_origin"] = serde_json::json!("free");
    }
    write_json(&dir.join("manifest.json"), &manifest)?;
    let truth_file = serde_json::json!({
        "truth": truth,
        "data_directory": dir.file_name().map(|n| n.to_string_lossy().into_owned()),
        "set_seed": seed,
        "record_shape": shape,
        "conditions": conditions
            .iter()
            .map(|c| serde_json::json!({
                "excitation_frequency_hz": c.excitation_frequency_hz,
                "normal_force_n": c.normal_force_n,
            }))
            .collect::<Vec<_>>(),
    });
    write_json(&truth_path(dir), &truth_file)
}

fn write_json(path: &Path, value: &serde_json::Value) -> Result<()> {
    write_atomically(path, |w| {
        serde_json::to_writer_pretty(&mut *w, value)?;
        writeln!(w)
    })
}

fn write_run(path: &Path, r: &RecordColumns, base_x: bool) -> Result<()> {
    write_atomically(path, |w| {
        write!(w, "t,x,v,normal_force,friction_force")?;
        writeln!(w, "{}", if base_x { ",base_x" } else { "" })?;
        for i in 0..r.t.len() {
            write!(w, "{},{},{},{},{}", r.t[i], r.x[i], r.v[i], r.normal_force[i], r.friction_force[i])?;
            if base_x {
                write!(w, ",{}", r.base_x[i])?;
            }
            writeln!(w)?;
        }
        Ok(())
    })
}

// ---------------------------------------------------------------------------
// Truth statistics
// ---------------------------------------------------------------------------

/// One realisation's statistics over the whole periods of its record.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PathStat {
    /// Mean of the per-period peaks (largest `x` in each period), m.
    pub peak_mean_m: f64,
    /// Sample variance of the per-period peaks, m².
    pub peak_var_m2: f64,
    /// Circular mean of the per-period phase lag of the response's
    /// fundamental behind the base (`interfaces.md`), degrees in (−180, 180].
    pub phase_mean_deg: f64,
    /// Circular variance of that lag, `n/(n−1) · (−2 ln R̄)`, degrees².
    pub phase_var_deg2: f64,
    /// Share of the record's time spent stuck (Karnopp rest), –.
    pub stick_fraction: f64,
    /// Periods behind the statistics.
    pub periods: u32,
}

struct PeriodStats {
    dt: f64,
    /// The time (less half a step) at which the current period ends.
    boundary: f64,
    period_s: f64,
    periods: u32,
    current: u32,
    peak: f64,
    a: f64,
    b: f64,
    peaks: Vec<f64>,
    phases: Vec<f64>,
    stuck_steps: u64,
    steps: u64,
}

impl PeriodStats {
    fn close(&mut self) {
        if self.peak.is_finite() {
            self.peaks.push(self.peak);
            self.phases.push(self.b.atan2(self.a));
        }
        self.peak = f64::NEG_INFINITY;
        self.a = 0.0;
        self.b = 0.0;
        self.current += 1;
    }
}

impl Sink for PeriodStats {
    fn step(&mut self, n: u64, t: f64, cos: f64, sin: f64, x: f64, v: f64, _normal: f64, _friction: f64) {
        let _ = n;
        while t >= self.boundary {
            self.close();
            self.boundary = if self.current < self.periods {
                f64::from(self.current + 1) * self.period_s - 0.5 * self.dt
            } else {
                f64::INFINITY
            };
        }
        if self.current >= self.periods {
            return;
        }
        self.peak = self.peak.max(x);
        self.a += x * cos;
        self.b += x * sin;
        self.steps += 1;
        if v == 0.0 {
            self.stuck_steps += 1;
        }
    }
}

fn path_stat(p: &PeriodStats) -> PathStat {
    let n = p.peaks.len() as f64;
    let mean = p.peaks.iter().sum::<f64>() / n.max(1.0);
    let var = if n > 1.0 { p.peaks.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0) } else { 0.0 };
    let (s, c) = p.phases.iter().fold((0.0, 0.0), |(s, c), ph| (s + ph.sin(), c + ph.cos()));
    let r = ((s * s + c * c).sqrt() / n.max(1.0)).clamp(1e-300, 1.0);
    let phase_var = if n > 1.0 { n / (n - 1.0) * (-2.0 * r.ln()) } else { 0.0 };
    let mut mean_phase = s.atan2(c).to_degrees();
    if mean_phase <= -180.0 {
        mean_phase += 360.0;
    }
    PathStat {
        peak_mean_m: mean,
        peak_var_m2: var,
        phase_mean_deg: mean_phase,
        phase_var_deg2: phase_var.to_degrees().to_degrees(),
        stick_fraction: p.stuck_steps as f64 / (p.steps.max(1)) as f64,
        periods: p.peaks.len() as u32,
    }
}

/// Simulates `paths` independent realisations of `truth` at each of
/// `conditions` (model time origin, the truth's warm-up) over the whole
/// excitation periods of a record of `duration_s`, and returns per
/// condition, per path: the mean and variance of the per-period peaks and
/// the circular mean (and variance) of the per-period phase lag. Paths are
/// independent of any written set's runs; parallel over conditions × paths
/// and deterministic (same seed, same numbers, whatever the threads).
pub fn truth_path_stats(
    truth: &IndependentTruth,
    conditions: &[Condition],
    duration_s: f64,
    paths: u32,
    seed: u64,
) -> Vec<Vec<PathStat>> {
    if paths == 0 {
        return vec![Vec::new(); conditions.len()];
    }
    let jobs: Vec<(usize, u32)> = (0..conditions.len()).flat_map(|i| (0..paths).map(move |p| (i, p))).collect();
    let stats: Vec<PathStat> = jobs
        .par_iter()
        .map(|&(i, p)| {
            let c = conditions[i];
            let plant = Plant::new(truth, c);
            let periods = (duration_s * c.excitation_frequency_hz).floor().max(1.0) as u32;
            let period_s = 1.0 / c.excitation_frequency_hz;
            let mut grid = Grid::new(truth, c.excitation_frequency_hz, duration_s);
            grid.record_steps = (f64::from(periods) * period_s / grid.dt).ceil() as u64 + 1;
            let mut sink = PeriodStats {
                dt: grid.dt,
                boundary: period_s - 0.5 * grid.dt,
                period_s,
                periods,
                current: 0,
                peak: f64::NEG_INFINITY,
                a: 0.0,
                b: 0.0,
                peaks: Vec::with_capacity(periods as usize),
                phases: Vec::with_capacity(periods as usize),
                stuck_steps: 0,
                steps: 0,
            };
            simulate(&plant, grid, seed, stats_path(i, p), 0.0, &mut sink);
            while sink.current < sink.periods {
                sink.close();
            }
            path_stat(&sink)
        })
        .collect();
    stats.chunks(paths as usize).map(<[PathStat]>::to_vec).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A truth with the given rig and law, no effects.
    fn plain(rig: TruthRig, friction: TruthFriction) -> IndependentTruth {
        IndependentTruth {
            generator: GENERATOR.into(),
            seed: 0,
            description: String::new(),
            rig,
            friction,
            effects: Vec::new(),
            integration: Integration::default(),
            conditions: Vec::new(),
        }
    }

    fn rig(zeta: f64) -> TruthRig {
        TruthRig { mass_kg: 1.0, natural_frequency_hz: 10.0, damping_ratio: zeta, excitation_amplitude_m: 2.5e-3 }
    }

    fn coulomb(mu: f64) -> TruthFriction {
        TruthFriction {
            a: mu,
            b: 0.0,
            c_s_per_m: 0.0,
            d_s2_per_m2: 0.0,
            sigma_mu: 0.0,
            sigma_n_n: 0.0,
            noise_interval_s: 1.0 / 600.0,
        }
    }

    /// Without friction and noise the steady amplitude is the linear one.
    #[test]
    fn linear_amplitude_matches_the_closed_form() {
        for (zeta, eta) in [(0.005, 0.7), (0.01, 0.9), (0.003, 1.2), (0.008, 0.6)] {
            let truth = plain(rig(zeta), coulomb(0.0));
            let c = Condition { excitation_frequency_hz: 10.0 * eta, normal_force_n: 4.0 };
            let stats = truth_path_stats(&truth, &[c], 5.0, 1, 1);
            let want = 2.5e-3 / ((1.0 - eta * eta).powi(2) + (2.0 * zeta * eta).powi(2)).sqrt();
            let got = stats[0][0].peak_mean_m;
            eprintln!("linear ζ={zeta} η={eta}: {got} vs {want} ({:+.4}%)", 100.0 * (got / want - 1.0));
            assert!((got / want - 1.0).abs() < 0.005, "ζ={zeta} η={eta}: {got} vs {want}");
            let phase = (2.0 * zeta * eta).atan2(1.0 - eta * eta).to_degrees();
            assert!((stats[0][0].phase_mean_deg - phase).abs() < 0.5, "{} vs {phase}", stats[0][0].phase_mean_deg);
        }
    }

    /// Den Hartog's Coulomb solution without stops (ζ = 0).
    #[test]
    fn coulomb_amplitude_matches_den_hartog() {
        use crate::engine::analytic::DenHartog;
        let r = rig(0.0);
        let k_u0 = r.stiffness_n_per_m() * r.excitation_amplitude_m;
        for (eta, share) in [(0.6, 0.5), (0.8, 0.7), (1.2, 0.5), (0.7, 0.3)] {
            let beta = share * DenHartog::stop_threshold(eta);
            let n0 = 10.0;
            let truth = plain(r, coulomb(beta * k_u0 / n0));
            let c = Condition { excitation_frequency_hz: 10.0 * eta, normal_force_n: n0 };
            let stats = truth_path_stats(&truth, &[c], 5.0, 1, 1);
            let want = DenHartog { eta, beta }.amplitude_ratio().expect("no stops") * r.excitation_amplitude_m;
            let got = stats[0][0].peak_mean_m;
            eprintln!("den hartog η={eta} share={share}: {got} vs {want} ({:+.4}%)", 100.0 * (got / want - 1.0));
            assert!((got / want - 1.0).abs() < 0.01, "η={eta}: {got} vs {want}");
            assert_eq!(stats[0][0].stick_fraction, 0.0);
        }
    }

    /// Statistics of one record that the effects' signatures move.
    #[derive(Clone, Copy, Debug, Default)]
    struct Signature {
        /// Mean and variance of the per-period peaks, m, m².
        peak_mean: f64,
        peak_var: f64,
        /// Mean friction coefficient `|F|/N` while sliding (|v| > 2 cm/s).
        mu_mean: f64,
        /// Lag-10 autocorrelation of the friction residual `|F|/N − μ(|v|)`.
        lag10: f64,
        /// Kurtosis and skewness of that residual.
        kurtosis: f64,
        skewness: f64,
        /// Mean residual on the accelerating branch minus the decelerating one.
        branch_gap: f64,
        /// Amplitude of N at 1× and 2× the excitation, per mean N.
        n_h1: f64,
        n_h2: f64,
        /// Mean N of the last fifth minus the first, per mean N.
        n_drift: f64,
        /// Mean over stick episodes of the largest `|F|/N` (0 without stops).
        stick_mu: f64,
    }

    fn moments(values: &[f64]) -> (f64, f64, f64, f64) {
        let n = values.len().max(1) as f64;
        let mean = values.iter().sum::<f64>() / n;
        let m2 = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
        let m3 = values.iter().map(|v| (v - mean).powi(3)).sum::<f64>() / n;
        let m4 = values.iter().map(|v| (v - mean).powi(4)).sum::<f64>() / n;
        (mean, m2, m3 / m2.powf(1.5), m4 / (m2 * m2))
    }

    fn signature(truth: &IndependentTruth, c: Condition, r: &RecordColumns) -> Signature {
        let f = &truth.friction;
        let law = |s: f64| f.a + f.b / (1.0 + f.c_s_per_m * s) + f.d_s2_per_m2 * s * s;
        let len = r.t.len();
        let dt = r.t[1] - r.t[0];
        let period = 1.0 / c.excitation_frequency_hz;
        // Peaks per period (model origin).
        let mut peaks = Vec::new();
        let mut current = f64::NEG_INFINITY;
        let mut k = 0;
        for i in 0..len {
            if r.t[i] >= f64::from(k + 1) * period - 0.5 * dt {
                peaks.push(current);
                current = f64::NEG_INFINITY;
                k += 1;
            }
            current = current.max(r.x[i]);
        }
        let (peak_mean, peak_var, _, _) = moments(&peaks);
        // Friction while sliding.
        let sliding: Vec<bool> = r.v.iter().map(|v| v.abs() > 0.02).collect();
        let mu_hat: Vec<f64> = (0..len).map(|i| (r.friction_force[i] / r.normal_force[i].max(1e-9)).abs()).collect();
        let resid: Vec<f64> = (0..len).map(|i| mu_hat[i] - law(r.v[i].abs())).collect();
        let slid: Vec<f64> = (0..len).filter(|&i| sliding[i]).map(|i| resid[i]).collect();
        let mu_slid: Vec<f64> = (0..len).filter(|&i| sliding[i]).map(|i| mu_hat[i]).collect();
        let (mu_mean, _, _, _) = moments(&mu_slid);
        let (r_mean, r_var, skewness, kurtosis) = moments(&slid);
        let pairs: Vec<(f64, f64)> =
            (0..len - 10).filter(|&i| sliding[i] && sliding[i + 10]).map(|i| (resid[i], resid[i + 10])).collect();
        let lag10 =
            pairs.iter().map(|(a, b)| (a - r_mean) * (b - r_mean)).sum::<f64>() / pairs.len().max(1) as f64 / r_var;
        let (mut up, mut down) = (Vec::new(), Vec::new());
        for i in 1..len - 1 {
            if sliding[i] && sliding[i - 1] && sliding[i + 1] {
                let accel = r.v[i].signum() * (r.v[i + 1] - r.v[i - 1]);
                if accel > 0.0 { up.push(resid[i]) } else { down.push(resid[i]) }
            }
        }
        let branch_gap = moments(&up).0 - moments(&down).0;
        let n_mean = r.normal_force.iter().sum::<f64>() / len as f64;
        let harmonic = |h: f64| {
            let w = TAU * h * c.excitation_frequency_hz;
            let (mut a, mut b) = (0.0, 0.0);
            for i in 0..len {
                a += (r.normal_force[i] - n_mean) * (w * r.t[i]).cos();
                b += (r.normal_force[i] - n_mean) * (w * r.t[i]).sin();
            }
            2.0 * (a * a + b * b).sqrt() / len as f64 / n_mean
        };
        let fifth = len / 5;
        let first = r.normal_force[..fifth].iter().sum::<f64>() / fifth as f64;
        let last = r.normal_force[len - fifth..].iter().sum::<f64>() / fifth as f64;
        // Stick episodes: at least 3 samples in a row below 6 mm/s.
        let mut episodes = Vec::new();
        let mut i = 0;
        while i < len {
            if r.v[i].abs() < 6e-3 {
                let start = i;
                while i < len && r.v[i].abs() < 6e-3 {
                    i += 1;
                }
                if i - start >= 3 {
                    episodes.push(mu_hat[start..i].iter().cloned().fold(0.0, f64::max));
                }
            }
            i += 1;
        }
        Signature {
            peak_mean,
            peak_var,
            mu_mean,
            lag10,
            kurtosis,
            skewness,
            branch_gap,
            n_h1: harmonic(1.0),
            n_h2: harmonic(2.0),
            n_drift: (last - first) / n_mean,
            stick_mu: if episodes.is_empty() { 0.0 } else { moments(&episodes).0 },
        }
    }

    /// The characterisation rig: stops at η = 0.6 and 20 N, none at 4 N.
    fn test_truth(effects: Vec<IndependentEffect>) -> IndependentTruth {
        let mut t = plain(
            TruthRig { mass_kg: 1.0, natural_frequency_hz: 10.0, damping_ratio: 0.004, excitation_amplitude_m: 2e-3 },
            TruthFriction {
                a: 0.22,
                b: 0.05,
                c_s_per_m: 10.0,
                d_s2_per_m2: 0.1,
                sigma_mu: 0.03,
                sigma_n_n: 0.2,
                noise_interval_s: 1.0 / 600.0,
            },
        );
        t.effects = effects;
        t
    }

    fn at(eta: f64, n: f64) -> Condition {
        Condition { excitation_frequency_hz: 10.0 * eta, normal_force_n: n }
    }

    /// Prints, for every form at both presets, how far its records'
    /// signatures lie from the baseline's, in units of the baseline's
    /// record-to-record spread (50 s records). Run with
    /// `cargo test --release --lib independent::tests::presets -- --ignored --nocapture`.
    #[test]
    #[ignore = "minutes on 2 cores: the check that the presets are above a 50 s record's noise"]
    fn presets_move_their_signatures_beyond_the_record_spread() {
        let records = 5u32;
        let conditions = [at(0.6, 20.0), at(0.7, 4.0), at(0.9, 8.0)];
        let shape = RecordShape { duration_s: 50.0, ..RecordShape::default() };
        let run = |truth: &IndependentTruth| -> Vec<Vec<Signature>> {
            conditions
                .iter()
                .enumerate()
                .map(|(ci, &c)| {
                    (0..records)
                        .into_par_iter()
                        .map(|r| signature(truth, c, &simulate_run(truth, c, ci, r, &shape, 11).expect("a run")))
                        .collect()
                })
                .collect()
        };
        let names = [
            "peak_mean",
            "peak_var",
            "mu_mean",
            "lag10",
            "kurtosis",
            "skewness",
            "branch_gap",
            "n_h1",
            "n_h2",
            "n_drift",
            "stick_mu",
        ];
        let get = |s: &Signature| {
            [
                s.peak_mean,
                s.peak_var,
                s.mu_mean,
                s.lag10,
                s.kurtosis,
                s.skewness,
                s.branch_gap,
                s.n_h1,
                s.n_h2,
                s.n_drift,
                s.stick_mu,
            ]
        };
        let base = run(&test_truth(Vec::new()));
        let spread = |sigs: &[Signature], j: usize| {
            let v: Vec<f64> = sigs.iter().map(|s| get(s)[j]).collect();
            let (m, var, _, _) = moments(&v);
            (m, (var * v.len() as f64 / (v.len() as f64 - 1.0)).sqrt())
        };
        for (ci, c) in conditions.iter().enumerate() {
            let row: Vec<String> = (0..names.len())
                .map(|j| {
                    let (m, sd) = spread(&base[ci], j);
                    format!("{}={m:.4e}±{sd:.1e}", names[j])
                })
                .collect();
            eprintln!("baseline {:.1} Hz {} N: {}", c.excitation_frequency_hz, c.normal_force_n, row.join(" "));
        }
        let mut rng = stream_rng(1, 2, 3);
        for (family, forms) in FORMS {
            for form in 0..forms.len() as u32 {
                for strong in [false, true] {
                    let e = IndependentEffect::preset(family, form, strong, 8.0, &mut rng).expect("a preset");
                    let sigs = run(&test_truth(vec![e]));
                    let mut best = Vec::new();
                    for (j, name) in names.iter().enumerate() {
                        let (zmax, at) = (0..conditions.len())
                            .map(|ci| {
                                let (m0, sd0) = spread(&base[ci], j);
                                let (m1, _) = spread(&sigs[ci], j);
                                ((m1 - m0) / sd0.max(1e-300), ci)
                            })
                            .fold((0.0, 0), |acc, x| if x.0.abs() > f64::abs(acc.0) { x } else { acc });
                        best.push(format!("{name}:{zmax:+.1}@{at}"));
                    }
                    eprintln!(
                        "{family} form {form} {}: {}",
                        if strong { "strong" } else { "moderate" },
                        best.join(" ")
                    );
                }
            }
        }
    }

    /// A quick version of the characterisation truth: 1 s warm-up, 100 kHz.
    fn quick(effects: Vec<IndependentEffect>) -> IndependentTruth {
        let mut t = test_truth(effects);
        t.integration.warmup_s = 1.0;
        t.integration.step_rate_hz = MIN_STEP_RATE_HZ;
        t
    }

    fn short(duration_s: f64) -> RecordShape {
        RecordShape { duration_s, ..RecordShape::default() }
    }

    /// Signatures of `records` runs of `truth` at `c`.
    fn signatures(truth: &IndependentTruth, c: Condition, records: u32, duration_s: f64) -> Vec<Signature> {
        (0..records)
            .into_par_iter()
            .map(|r| signature(truth, c, &simulate_run(truth, c, 0, r, &short(duration_s), 5).expect("a run")))
            .collect()
    }

    fn mean_of(sigs: &[Signature], f: impl Fn(&Signature) -> f64) -> f64 {
        sigs.iter().map(f).sum::<f64>() / sigs.len() as f64
    }

    fn strong(family: Effect, form: u32) -> IndependentEffect {
        IndependentEffect::preset(family, form, true, 8.0, &mut stream_rng(4, 5, 6)).expect("a preset")
    }

    /// Every form at strength 0 gives the baseline's record bit for bit.
    #[test]
    fn zero_strength_effects_equal_the_baseline_path() {
        let c = at(0.6, 20.0);
        let shape = short(3.0);
        let base = simulate_run(&quick(Vec::new()), c, 0, 0, &shape, 9).expect("a run");
        for (family, forms) in FORMS {
            for form in 0..forms.len() as u32 {
                let e = strong(family, form);
                let zero = simulate_run(&quick(vec![e.with_strength(0.0)]), c, 0, 0, &shape, 9).expect("a run");
                assert!(zero == base, "{family} form {form} at strength 0 differs from the baseline");
                let on = simulate_run(&quick(vec![e]), c, 0, 0, &shape, 9).expect("a run");
                assert!(on != base, "{family} form {form} at its strong preset changes nothing");
            }
        }
        // Two at once, both at zero.
        let pair = vec![
            strong(Effect::Stiction, 1).with_strength(0.0),
            strong(Effect::ColouredFrictionNoise, 0).with_strength(0.0),
        ];
        assert!(simulate_run(&quick(pair), c, 0, 0, &shape, 9).expect("a run") == base);
    }

    #[test]
    fn load_forms_change_the_friction_level_with_load() {
        for form in 0..3 {
            let e = strong(Effect::LoadDependentFriction, form);
            let mut moved = 0.0f64;
            for n in [4.0, 16.0] {
                let c = at(0.7, n);
                let base = mean_of(&signatures(&quick(Vec::new()), c, 1, 10.0), |s| s.mu_mean);
                let on = mean_of(&signatures(&quick(vec![e]), c, 1, 10.0), |s| s.mu_mean);
                moved = moved.max((on - base).abs());
            }
            eprintln!("load form {form}: sliding μ moves by {moved}");
            assert!(moved > 0.01, "load form {form}: sliding μ moves by {moved} only");
        }
    }

    #[test]
    fn memory_forms_separate_the_accelerating_and_decelerating_branches() {
        let c = at(0.9, 8.0);
        let base = mean_of(&signatures(&quick(Vec::new()), c, 2, 10.0), |s| s.branch_gap);
        let lugre =
            mean_of(&signatures(&quick(vec![strong(Effect::FrictionHysteresis, 0)]), c, 2, 10.0), |s| s.branch_gap);
        let rate_state =
            mean_of(&signatures(&quick(vec![strong(Effect::FrictionHysteresis, 1)]), c, 2, 10.0), |s| s.branch_gap);
        eprintln!("branch gap: baseline {base}, LuGre {lugre}, rate-and-state {rate_state}");
        assert!(base.abs() < 0.002, "baseline gap {base}");
        // LuGre: friction builds up over the bristle length after each reversal,
        // so it is lower while accelerating.
        assert!(lugre - base < -0.005, "LuGre gap {lugre}");
        // Rate-and-state: the state lags, so friction is higher while accelerating.
        assert!(rate_state - base > 0.004, "rate-and-state gap {rate_state}");
    }

    #[test]
    fn harmonic_forms_put_harmonics_into_the_normal_force() {
        let c = at(0.7, 8.0);
        let base = signatures(&quick(Vec::new()), c, 1, 10.0)[0];
        assert!(base.n_h1 < 0.003 && base.n_h2 < 0.003, "baseline harmonics {} {}", base.n_h1, base.n_h2);
        let pos = signatures(&quick(vec![strong(Effect::NormalForceHarmonics, 0)]), c, 1, 10.0)[0];
        eprintln!("harmonics: baseline {} {}, position-following {} {}", base.n_h1, base.n_h2, pos.n_h1, pos.n_h2);
        assert!(pos.n_h1 > 0.03 && pos.n_h2 > 0.005, "position-following: 1× {} 2× {}", pos.n_h1, pos.n_h2);
        let wander = IndependentEffect::NormalForceHarmonics(HarmonicForm::WanderingHarmonic {
            strength: 0.08,
            order: 2,
            phase_diffusion_rad2_per_s: 0.05,
            initial_phase_rad: 1.0,
        });
        let w = signatures(&quick(vec![wander]), c, 1, 10.0)[0];
        eprintln!("wandering 2×: {} {}", w.n_h1, w.n_h2);
        assert!(w.n_h2 > 0.04 && w.n_h1 < 0.01, "wandering 2×: 1× {} 2× {}", w.n_h1, w.n_h2);
    }

    #[test]
    fn colour_forms_raise_the_residuals_lag_10_autocorrelation() {
        let c = at(0.7, 8.0);
        let base = mean_of(&signatures(&quick(Vec::new()), c, 2, 10.0), |s| s.lag10);
        assert!(base.abs() < 0.05, "baseline lag-10 autocorrelation {base}");
        for form in 0..2 {
            let on = mean_of(&signatures(&quick(vec![strong(Effect::ColouredFrictionNoise, form)]), c, 2, 10.0), |s| {
                s.lag10
            });
            eprintln!("colour form {form}: lag-10 {on} (baseline {base})");
            assert!(on > 0.25, "colour form {form}: lag-10 autocorrelation {on}");
        }
    }

    #[test]
    fn non_gaussian_forms_change_the_residuals_shape() {
        let c = at(0.7, 8.0);
        let base = signatures(&quick(Vec::new()), c, 2, 10.0);
        let (k0, s0) = (mean_of(&base, |s| s.kurtosis), mean_of(&base, |s| s.skewness));
        assert!((k0 - 3.0).abs() < 0.3 && s0.abs() < 0.1, "baseline kurtosis {k0}, skewness {s0}");
        let t = IndependentEffect::NonGaussianFriction(ShapeForm::StudentT { strength: 1.0, degrees_of_freedom: 4 });
        let k = mean_of(&signatures(&quick(vec![t]), c, 2, 10.0), |s| s.kurtosis);
        eprintln!("shape: baseline kurtosis {k0} skewness {s0}; Student-t kurtosis {k}");
        assert!(k > 4.5, "Student-t kurtosis {k}");
        let skew =
            mean_of(&signatures(&quick(vec![strong(Effect::NonGaussianFriction, 1)]), c, 2, 10.0), |s| s.skewness);
        eprintln!("bimodal skewness {skew}");
        assert!(skew > 0.4, "bimodal skewness {skew}");
    }

    #[test]
    fn stiction_forms_raise_the_breakaway_friction() {
        let c = at(0.6, 20.0);
        let base = mean_of(&signatures(&quick(Vec::new()), c, 2, 10.0), |s| s.stick_mu);
        assert!(base > 0.25, "the baseline sticks here ({base})");
        for form in 0..2 {
            let on = mean_of(&signatures(&quick(vec![strong(Effect::Stiction, form)]), c, 2, 10.0), |s| s.stick_mu);
            eprintln!("stiction form {form}: breakaway |F|/N {on} against {base}");
            assert!(on - base > 0.02, "stiction form {form}: breakaway |F|/N {on} against {base}");
        }
    }

    #[test]
    fn drift_forms_move_the_mean_normal_force() {
        let c = at(0.7, 8.0);
        let base = mean_of(&signatures(&quick(Vec::new()), c, 4, 10.0), |s| s.n_drift.abs());
        assert!(base < 0.005, "baseline drift {base}");
        let thermal =
            IndependentEffect::NormalForceDrift(DriftForm::ThermalRelaxation { strength: -0.15, time_constant_s: 5.0 });
        let d = mean_of(&signatures(&quick(vec![thermal]), c, 1, 10.0), |s| s.n_drift);
        eprintln!("drift: baseline {base}, thermal {d}");
        assert!(d < -0.06, "thermal relaxation drift {d}");
        let wear =
            mean_of(&signatures(&quick(vec![strong(Effect::NormalForceDrift, 1)]), c, 4, 10.0), |s| s.n_drift.abs());
        eprintln!("Brownian wear |drift| {wear}");
        assert!(wear > 0.015, "Brownian wear drift {wear}");
    }

    /// The truth statistics and the records see the same dynamics.
    #[test]
    fn truth_statistics_agree_with_the_records() {
        let truth = quick(Vec::new());
        for c in [at(0.7, 4.0), at(0.6, 20.0)] {
            let records = signatures(&truth, c, 2, 10.0);
            let stats = truth_path_stats(&truth, &[c], 10.0, 4, 3);
            assert_eq!(stats.len(), 1);
            assert_eq!(stats[0].len(), 4);
            let from_stats = stats[0].iter().map(|s| s.peak_mean_m).sum::<f64>() / 4.0;
            let from_records = mean_of(&records, |s| s.peak_mean);
            assert!((from_stats / from_records - 1.0).abs() < 0.005, "{from_stats} vs {from_records}");
            assert!(stats[0].iter().all(|s| s.periods == (10.0 * c.excitation_frequency_hz) as u32));
        }
        let stats = truth_path_stats(&truth, &[at(0.6, 20.0)], 10.0, 2, 3);
        assert!(stats[0][0].stick_fraction > 0.0, "stops at η = 0.6, 20 N");
        // Same seed, same numbers; another seed, other numbers.
        assert_eq!(stats, truth_path_stats(&truth, &[at(0.6, 20.0)], 10.0, 2, 3));
        assert_ne!(stats, truth_path_stats(&truth, &[at(0.6, 20.0)], 10.0, 2, 4));
        assert!(truth_path_stats(&truth, &[at(0.6, 20.0)], 10.0, 0, 3)[0].is_empty());
    }

    #[test]
    fn random_truths_are_deterministic_and_refuse_bad_requests() {
        let hidden = [(Effect::Stiction, 1, true), (Effect::NormalForceDrift, 0, false)];
        let (a, ca) = random_truth(5, &hidden, &DEFAULT_LOADS_N, &DEFAULT_FREQUENCY_RATIOS).expect("a truth");
        let (b, cb) = random_truth(5, &hidden, &DEFAULT_LOADS_N, &DEFAULT_FREQUENCY_RATIOS).expect("a truth");
        assert_eq!(a, b);
        assert_eq!(ca, cb);
        assert_eq!(ca.len(), 18);
        assert_eq!(a.families(), vec![Effect::Stiction, Effect::NormalForceDrift]);
        // The rig and law do not depend on what is hidden.
        let (plain, _) = random_truth(5, &[], &DEFAULT_LOADS_N, &DEFAULT_FREQUENCY_RATIOS).expect("a truth");
        assert_eq!((plain.rig, plain.friction), (a.rig, a.friction));
        assert!(random_truth(6, &hidden, &DEFAULT_LOADS_N, &DEFAULT_FREQUENCY_RATIOS).expect("a truth").0 != a);
        assert!(a.description.contains("stiction") && a.description.contains("Dieterich"));
        // Frequency-major grid.
        assert_eq!(ca[1].normal_force_n, 8.0);
        assert_eq!(ca[3].excitation_frequency_hz, 0.7 * a.rig.natural_frequency_hz);
        let dup = [(Effect::Stiction, 0, true), (Effect::Stiction, 1, true)];
        assert!(random_truth(5, &dup, &DEFAULT_LOADS_N, &DEFAULT_FREQUENCY_RATIOS).is_err());
        assert!(random_truth(5, &[(Effect::Stiction, 2, true)], &DEFAULT_LOADS_N, &DEFAULT_FREQUENCY_RATIOS).is_err());
        assert!(random_truth(5, &[], &[], &DEFAULT_FREQUENCY_RATIOS).is_err());
        assert!(random_truth(5, &[], &DEFAULT_LOADS_N, &[0.0]).is_err());
        // Every family and form has a preset and serialises.
        for (family, forms) in FORMS {
            for form in 0..forms.len() as u32 {
                let (t, _) = random_truth(1, &[(family, form, false)], &[4.0], &[0.8]).expect("a truth");
                assert_eq!(t.effects[0].family(), family);
                assert_eq!(t.effects[0].form_index(), form);
                let json = serde_json::to_value(&t).expect("serialises");
                assert_eq!(json["effects"][0]["effect"], family.name());
            }
        }
    }

    /// Some drawn truths hold the block at the heaviest load; the
    /// description says so.
    #[test]
    fn a_truth_that_sticks_throughout_says_so() {
        let stuck = (0..200)
            .map(|seed| random_truth(seed, &[], &DEFAULT_LOADS_N, &DEFAULT_FREQUENCY_RATIOS).expect("a truth").0)
            .find(|t| t.conditions.iter().any(|c| c.expected_to_stick_throughout))
            .expect("some seed draws a heavy friction level");
        assert!(stuck.description.contains("stay stuck"), "{}", stuck.description);
        let (n, _) = random_truth(0, &[], &[0.5], &[0.8]).expect("a truth");
        assert!(!n.description.contains("stay stuck"));
    }

    /// One path's statistics on one thread, and the thread's CPU time, s.
    fn truth_path_stats_on_one_thread(truth: &IndependentTruth, c: Condition, duration_s: f64) -> (PathStat, f64) {
        let thread_cpu_s = || {
            let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
            // SAFETY: clock_gettime writes one timespec into `ts`.
            unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
            ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
        };
        rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("a pool").install(|| {
            let start = thread_cpu_s();
            let stat = truth_path_stats(truth, &[c], duration_s, 1, 1)[0][0];
            (stat, thread_cpu_s() - start)
        })
    }

    /// Times one 18-run set (3 loads × 6 frequencies × 50 s) and one truth-
    /// statistics call (32 paths × 18 conditions × 50 s). Run with
    /// `cargo test --release --lib independent::tests::timing -- --ignored --nocapture`.
    #[test]
    #[ignore = "minutes: the runtime of a full set and of the truth statistics (12.7e9 steps)"]
    fn timing_of_a_full_set_and_the_truth_statistics() {
        let (truth, conditions) =
            random_truth(7, &[(Effect::FrictionHysteresis, 1, true)], &DEFAULT_LOADS_N, &DEFAULT_FREQUENCY_RATIOS)
                .expect("a truth");
        // CPU time per step of one path on one thread (the machine may be shared).
        for (name, t) in [("baseline", truth.baseline()), ("rate-and-state", truth.clone())] {
            let (stat, cpu_s) = truth_path_stats_on_one_thread(&t, conditions[4], 50.0);
            let grid = Grid::new(&t, conditions[4].excitation_frequency_hz, 50.0);
            let steps = (grid.warmup_steps + grid.record_steps) as f64;
            eprintln!("{name}: {:.1} ns CPU per step ({} periods, {cpu_s:.2} s)", cpu_s / steps * 1e9, stat.periods);
        }
        let dir = std::env::temp_dir().join(format!("stickslip-independent-timing-{}", std::process::id()));
        let data = dir.join("data");
        let start = std::time::Instant::now();
        write_set(&data, &truth, &conditions, &RecordShape::default(), 3).expect("the set is written");
        eprintln!("18-run set (rate-and-state hidden): {:.2} s", start.elapsed().as_secs_f64());
        let (plain, _) = random_truth(7, &[], &DEFAULT_LOADS_N, &DEFAULT_FREQUENCY_RATIOS).expect("a truth");
        let start = std::time::Instant::now();
        write_set(&data, &plain, &conditions, &RecordShape::default(), 3).expect("the set is written");
        eprintln!("18-run set (baseline): {:.2} s", start.elapsed().as_secs_f64());
        let start = std::time::Instant::now();
        let stats = truth_path_stats(&plain, &conditions, 50.0, 32, 5);
        eprintln!("truth stats 32 × 18 × 50 s (baseline): {:.2} s", start.elapsed().as_secs_f64());
        assert_eq!(stats.len(), 18);
        let start = std::time::Instant::now();
        let stats = truth_path_stats(&truth, &conditions, 50.0, 32, 5);
        eprintln!("truth stats 32 × 18 × 50 s (rate-and-state): {:.2} s", start.elapsed().as_secs_f64());
        assert!(stats.iter().all(|s| s.len() == 32));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
