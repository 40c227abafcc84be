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

mod forms;
mod integrator;
mod records;
#[cfg(test)]
mod tests;

pub use forms::*;
use integrator::*;
pub use records::*;

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
