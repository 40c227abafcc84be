//! The unmodelled effects of `docs/model.md`, as optional extensions
//! of the baseline. Each has its own table in the model file, a `form` (how
//! it is shaped) and a strength; at zero strength the arithmetic reduces
//! exactly to the baseline's, so paths are bit-identical (a test checks it).
//!
//! The first form of each effect is the one `diagnose` fits (the candidate);
//! the others exist so synthetic data can carry an effect whose shape no
//! candidate matches exactly. Grounding in the literature:
//! - harmonics of the normal force: the paper's Figure 4 (misalignment 1×,
//!   uneven wear 2×, bumps higher); and a normal force that follows the
//!   block's position, N0 (1 + α x/U0 + β (x/U0)²) (`position`: the load of
//!   a leaf-spring or flexure stage changes with its deflection through the
//!   springs' tilt and arc shortening, S. T. Smith, *Flexures*, 2000), held
//!   over each noise interval at the interval's start like the rest;
//! - non-Gaussian friction noise: the paper's Figure 6 (skew growing with load);
//! - hysteresis: frictional memory (Hess & Soom 1990), Dahl's pre-sliding
//!   build-up of friction over a characteristic displacement after reversal,
//!   and the two rate-and-state evolution laws: the slip law (Ruina 1983:
//!   friction relaxes to the steady law over a slip distance L, `slip`) and
//!   the ageing law (Dieterich 1979, Ruina 1983: a contact age θ that grows
//!   while stuck and raises the static and early sliding friction by
//!   B ln θ, `ageing`);
//! - coloured friction noise: correlated asperity contact (Ornstein–Uhlenbeck);
//! - stiction: static friction above kinetic at breakaway (Rabinowicz; LuGre);
//! - load-dependent friction: μ changing with contact pressure, either by an
//!   offset of `a` (several shapes), by a factor (N0/Nref)^k on the whole
//!   law (`scaled`), or as the two-term law F = μN + A with an adhesion
//!   force A (Derjaguin 1934; Bowden & Tabor, `adhesion`);
//! - normal-force drift: wear and heating during a run (paper §2.2.1).
//!
//! Everything time-varying is evaluated once per noise interval (at the
//! interval's start) and held, like the noise itself: results do not depend
//! on the step size, and breakaway from stick stays a closed-form event.
//! The friction memory of hysteresis `lag`, `slip` and `ageing` is one more
//! state of the slip ODE (μ_f, –, for `lag` and `slip`; the contact age θ,
//! s, for `ageing`), integrated by the same RK4 step as x and v; while stuck
//! θ ages with time and is read at each interval's start.
//!
//! Units: lengths in m, times in s, forces in N, coefficients and exponents
//! dimensionless (–), as each table's field names say.

mod params;
mod tables;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
pub use params::EffectParams;
pub(crate) use params::Memory;
pub use tables::*;

/// The unmodelled effects of `model.md`, by their fixed names. Every match
/// on an effect is exhaustive, so adding one is a change the compiler walks
/// through (model tables, both integrators, the candidates, the synthetic
/// generator, the report).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Effect {
    NormalForceHarmonics,
    NonGaussianFriction,
    FrictionHysteresis,
    ColouredFrictionNoise,
    Stiction,
    LoadDependentFriction,
    NormalForceDrift,
}

impl Effect {
    /// What the effect is, in words a report's reader understands.
    pub fn meaning(self) -> &'static str {
        match self {
            Effect::NormalForceHarmonics => {
                "The normal force is not steady: it swings at multiples of the excitation frequency \
             (misalignment at 1×, uneven wear at 2×, bumps higher), as in the paper's Figure 4."
            }
            Effect::NonGaussianFriction => {
                "The random part of the friction coefficient is not Gaussian: it is skewed or has heavy tails, \
             as the paper's Figure 6 shows at high load."
            }
            Effect::FrictionHysteresis => {
                "Friction has memory: after the block starts to slide it builds up over a short distance (or \
             time) instead of following the steady friction law at once."
            }
            Effect::ColouredFrictionNoise => {
                "The friction noise is correlated in time (coloured): a high coefficient tends to stay high for \
             a while, as with asperities in contact for longer than one sample."
            }
            Effect::Stiction => {
                "Static friction exceeds sliding friction: the block needs an extra push to break away, and the \
             excess fades as it starts to slide."
            }
            Effect::LoadDependentFriction => {
                "The friction coefficient itself changes with the normal force (contact pressure), instead of \
             being the same law at every load."
            }
            Effect::NormalForceDrift => {
                "The normal force drifts during a run (wear, heating), instead of holding its setting."
            }
        }
    }

    /// Every effect, in the order of `model.md`'s table.
    pub const ALL: [Effect; 7] = [
        Effect::NormalForceHarmonics,
        Effect::NonGaussianFriction,
        Effect::FrictionHysteresis,
        Effect::ColouredFrictionNoise,
        Effect::Stiction,
        Effect::LoadDependentFriction,
        Effect::NormalForceDrift,
    ];

    /// The name used in model files and reports.
    pub fn name(self) -> &'static str {
        match self {
            Effect::NormalForceHarmonics => "normal_force_harmonics",
            Effect::NonGaussianFriction => "non_gaussian_friction",
            Effect::FrictionHysteresis => "friction_hysteresis",
            Effect::ColouredFrictionNoise => "coloured_friction_noise",
            Effect::Stiction => "stiction",
            Effect::LoadDependentFriction => "load_dependent_friction",
            Effect::NormalForceDrift => "normal_force_drift",
        }
    }
}

impl std::fmt::Display for Effect {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Effect {
    type Err = String;

    fn from_str(name: &str) -> std::result::Result<Effect, String> {
        Effect::ALL.into_iter().find(|e| e.name() == name).ok_or_else(|| {
            let names: Vec<&str> = Effect::ALL.iter().map(|e| e.name()).collect();
            format!("`{name}` is not an effect; expected one of {}", names.join(", "))
        })
    }
}

/// The shape of an effect (its `form` key). Forms are enums everywhere on
/// the host; they become `u32` codes only at the GPU boundary, where the
/// kernel sees one generated constant per variant.
pub trait Form: Copy + Serialize + 'static {
    /// Every form, in code order (the first is the candidate form).
    const ALL: &'static [Self];
    /// The code the kernel sees.
    fn code(self) -> u32;
}

/// Time scale of the `saturating` drift, s.
pub const DRIFT_SATURATION_S: f64 = 20.0;
/// Time scale of the `wander` drift, s.
pub const DRIFT_WANDER_S: f64 = 15.0;
/// Displacement over which `decaying` stiction fades, m.
pub const STICTION_DECAY_M: f64 = 1e-4;
/// Cut-off speed v_c of hysteresis `ageing`, m/s: the steady contact age is
/// L/(|v| + v_c), finite at rest, where it is θ_c = L/v_c (the age whose
/// static coefficient is the law's μ(0)). 1 mm/s: well below the paper
/// rig's sliding speeds (cm/s to m/s), so in steady sliding (θ = L/|v|)
/// the state term is under 1% of B at 10 cm/s.
pub const AGEING_CUTOFF_SPEED_M_PER_S: f64 = 1e-3;
/// Floor speed v_0 of hysteresis `ageing`, m/s: θ_0 = L/v_0 is added to
/// every contact age in the logarithm, so that it stays finite for a
/// fresh contact (θ = 0). 1 m/s: above the paper rig's sliding speeds, so
/// θ_0 is below the steady age of any slip the rig makes and the state
/// term follows ln θ through a slip's transient (a floor as large as θ_c
/// would flatten that transient to a few per cent of B).
pub const AGEING_FLOOR_SPEED_M_PER_S: f64 = 1.0;

/// Whether the `polynomial` non-Gaussian form with quadratic coefficient
/// `c` and cubic coefficient `d` (both –) has a positive linear coefficient
/// that gives unit variance: 2c² + 15d² < 1.
pub fn polynomial_feasible(c: f64, d: f64) -> bool {
    2.0 * c * c + 15.0 * d * d < 1.0
}

/// The `polynomial` form's linear coefficient b (–) for quadratic and cubic
/// coefficients `c` and `d` (–): the positive root of b² + 6bd + 2c² + 15d² =
/// 1, which gives the noise unit variance.
pub fn polynomial_linear(c: f64, d: f64) -> f64 {
    (1.0 - 2.0 * c * c - 6.0 * d * d).max(0.0).sqrt() - 3.0 * d
}

/// The largest 2c² + 15d² a `polynomial` noise is given where the
/// coefficients are not a user's own (scaled to another load, or stepped by
/// the diagnosis's search).
pub const POLYNOMIAL_REACH: f64 = 0.95;

/// The `polynomial` form's (c, d), shrunk along their ray to 2c² + 15d² ≤
/// [`POLYNOMIAL_REACH`] where they reach beyond it (unchanged otherwise).
pub fn polynomial_within_reach(c: f64, d: f64) -> (f64, f64) {
    let reach = 2.0 * c * c + 15.0 * d * d;
    if reach <= POLYNOMIAL_REACH {
        (c, d)
    } else {
        let shrink = (POLYNOMIAL_REACH / reach).sqrt();
        (c * shrink, d * shrink)
    }
}

/// Share of `mixture` non-Gaussian noise drawn from its outlier component.
pub const MIXTURE_OUTLIER_SHARE: f64 = 0.1;
/// The standard normal's quantile at [`MIXTURE_OUTLIER_SHARE`].
pub const MIXTURE_OUTLIER_QUANTILE: f64 = -1.281_551_565_544_600_4;

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
        Effect::ALL.into_iter().any(|e| self.has(e))
    }

    /// Whether `effect`'s table is present.
    pub fn has(&self, effect: Effect) -> bool {
        match effect {
            Effect::NormalForceHarmonics => self.normal_force_harmonics.is_some(),
            Effect::NonGaussianFriction => self.non_gaussian_friction.is_some(),
            Effect::FrictionHysteresis => self.friction_hysteresis.is_some(),
            Effect::ColouredFrictionNoise => self.coloured_friction_noise.is_some(),
            Effect::Stiction => self.stiction.is_some(),
            Effect::LoadDependentFriction => self.load_dependent_friction.is_some(),
            Effect::NormalForceDrift => self.normal_force_drift.is_some(),
        }
    }

    /// Takes `effect`'s table out (the baseline's behaviour for it).
    pub fn remove(&mut self, effect: Effect) {
        match effect {
            Effect::NormalForceHarmonics => self.normal_force_harmonics = None,
            Effect::NonGaussianFriction => self.non_gaussian_friction = None,
            Effect::FrictionHysteresis => self.friction_hysteresis = None,
            Effect::ColouredFrictionNoise => self.coloured_friction_noise = None,
            Effect::Stiction => self.stiction = None,
            Effect::LoadDependentFriction => self.load_dependent_friction = None,
            Effect::NormalForceDrift => self.normal_force_drift = None,
        }
    }

    /// Range checks; errors name the dotted key.
    pub fn validate(&self) -> Result<()> {
        if let Some(h) = &self.normal_force_harmonics {
            for k in 0..4 {
                let (a, r, p) = (h.amplitudes_n[k], h.amplitudes_per_n0[k], h.phases_rad[k]);
                check(&format!("normal_force_harmonics.amplitudes_n[{k}]"), a, true, "must be a finite number of N")?;
                check(
                    &format!("normal_force_harmonics.amplitudes_per_n0[{k}]"),
                    r,
                    r.abs() <= 10.0,
                    "must be a share of N0 within ±10",
                )?;
                check(&format!("normal_force_harmonics.phases_rad[{k}]"), p, true, "must be a finite angle")?;
            }
            check("normal_force_harmonics.shape", h.shape, h.shape > 0.0, "must be > 0")?;
        }
        if let Some(g) = &self.non_gaussian_friction {
            let ok = match g.form {
                NonGaussianForm::Skew => true,
                NonGaussianForm::Lognormal => g.strength >= 0.0 && g.strength <= 3.0,
                NonGaussianForm::TukeyH => (0.0..0.25).contains(&g.strength),
                NonGaussianForm::Mixture => (0.0..=3.0).contains(&g.strength),
                NonGaussianForm::Polynomial => polynomial_feasible(g.strength, g.cubic),
            };
            check(
                "non_gaussian_friction.strength",
                g.strength,
                ok,
                "lognormal and mixture need 0..=3, tukey_h needs 0 <= h < 0.25, polynomial needs \
                 2·strength² + 15·cubic² < 1",
            )?;
            let polynomial = g.form == NonGaussianForm::Polynomial;
            check(
                "non_gaussian_friction.cubic",
                g.cubic,
                polynomial || g.cubic == 0.0,
                "is read by the polynomial form only (0 for the others)",
            )?;
            check("non_gaussian_friction.load_exponent", g.load_exponent, true, "must be finite")?;
            check(
                "non_gaussian_friction.reference_force_n",
                g.reference_force_n,
                g.reference_force_n > 0.0,
                "must be > 0 N",
            )?;
        }
        if let Some(h) = &self.friction_hysteresis {
            check("friction_hysteresis.length_m", h.length_m, h.length_m >= 0.0, "must be >= 0 m")?;
            check(
                "friction_hysteresis.time_constant_s",
                h.time_constant_s,
                h.time_constant_s >= 0.0,
                "must be >= 0 s",
            )?;
            check(
                "friction_hysteresis.strength",
                h.strength,
                true,
                "must be a finite number (B of the ageing form, –)",
            )?;
        }
        if let Some(c) = &self.coloured_friction_noise {
            check(
                "coloured_friction_noise.correlation_time_s",
                c.correlation_time_s,
                c.correlation_time_s >= 0.0,
                "must be >= 0 s",
            )?;
            check(
                "coloured_friction_noise.coloured_share",
                c.coloured_share,
                (0.0..=1.0).contains(&c.coloured_share),
                "must be a share in [0, 1]",
            )?;
        }
        if let Some(s) = &self.stiction {
            check("stiction.excess", s.excess, s.excess >= 0.0, "must be >= 0")?;
            check("stiction.release_length_m", s.release_length_m, s.release_length_m >= 0.0, "must be >= 0 m")?;
            check("stiction.dwell_time_s", s.dwell_time_s, s.dwell_time_s >= 0.0, "must be >= 0 s")?;
        }
        if let Some(l) = &self.load_dependent_friction {
            let what = match l.form {
                LoadForm::Adhesion => "must be a finite force (the adhesion force A of the adhesion form, N)",
                LoadForm::Scaled | LoadForm::Power => "must be a finite exponent",
                _ => "must be finite",
            };
            check("load_dependent_friction.strength", l.strength, true, what)?;
            check("load_dependent_friction.curvature_per_n2", l.curvature_per_n2, true, "must be finite")?;
            check(
                "load_dependent_friction.reference_force_n",
                l.reference_force_n,
                l.reference_force_n > 0.0,
                "must be > 0 N",
            )?;
        }
        if let Some(d) = &self.normal_force_drift {
            check("normal_force_drift.rate_per_s", d.rate_per_s, true, "must be finite")?;
            if d.form == DriftForm::RandomWalk {
                check(
                    "normal_force_drift.rate_per_s",
                    d.rate_per_s,
                    d.rate_per_s >= 0.0,
                    "a random walk's variance per second must be >= 0 (1/s)",
                )?;
            }
            check("normal_force_drift.curvature_per_s2", d.curvature_per_s2, true, "must be finite")?;
            if let Some([start, end]) = d.mean_over_s {
                check("normal_force_drift.mean_over_s[0]", start, start >= 0.0, "must be >= 0 s")?;
                check("normal_force_drift.mean_over_s[1]", end, end > start, "must be after the window's start, s")?;
                let m = d.mean_factor(start, end);
                check(
                    "normal_force_drift.mean_over_s",
                    m,
                    m > 0.0,
                    "the drift's mean over the window must be a positive share of N0",
                )?;
            }
        }
        Ok(())
    }
}
