//! The independent generator's effect forms, from the literature (none a candidate form of the diagnosis), and how each acts on the plant.

use super::*;

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

    pub(super) fn visit_strength(&mut self, f: impl FnOnce(&mut f64)) {
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
