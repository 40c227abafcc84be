//! The physical model (`docs/model.md`): its parameters, the TOML model
//! files that hold them, and their validation. The constants the integrators
//! derive from it are in [`crate::engine::oscillator`].
//!
//! Units are SI throughout; every field name carries its unit.

use serde::{Deserialize, Serialize};

use crate::engine::effects::{Effect, Effects, HarmonicForm, LoadForm};
use crate::error::{Error, Result};

/// The physically sensible ranges that every parameter and grid coordinate
/// must lie in, wherever it comes from (model file, `--set`, grid flags,
/// manifests). They are wide enough for any friction rig and keep every
/// derived quantity (stiffness, damping coefficient, forces) finite in f64
/// and in the GPU's f32.
pub mod limits {
    /// Block mass, kg.
    pub const MASS_KG: (f64, f64) = (1e-9, 1e6);
    /// Natural and excitation frequencies, Hz.
    pub const FREQUENCY_HZ: (f64, f64) = (1e-3, 1e6);
    /// Damping ratio, – (below, not up to).
    pub const DAMPING_RATIO_BELOW: f64 = 10.0;
    /// Base excitation amplitude, m.
    pub const AMPLITUDE_MAX_M: f64 = 1.0;
    /// Normal force, its standard deviation and its harmonics, N.
    pub const FORCE_MAX_N: f64 = 1e6;
    /// |a|, |b|, σ_μ and the stiction excess, –.
    pub const FRICTION_COEFFICIENT_MAX: f64 = 100.0;
    /// Stribeck rate c, s/m.
    pub const STRIBECK_RATE_MAX_S_PER_M: f64 = 1e6;
    /// |d|, s²/m².
    pub const QUADRATIC_MAX_S2_PER_M2: f64 = 1e6;
    /// Noise hold interval, s.
    pub const NOISE_INTERVAL_S: (f64, f64) = (1e-9, 1e6);
    /// Effect lengths (hysteresis, stiction release), m.
    pub const LENGTH_MAX_M: f64 = 1.0;
    /// Effect times (noise correlation), s.
    pub const TIME_MAX_S: f64 = 1e6;
    /// Effect rates (normal-force drift), 1/s; effect strengths and exponents, –.
    pub const RATE_MAX: f64 = 100.0;
    /// Largest displacement of the block a measurement may hold (`x`,
    /// `base_x`, a summary's peak mean; a peak variance up to its square),
    /// and the least bound on a simulated one
    /// ([`crate::engine::plausible_displacement_m`]), m.
    pub const DISPLACEMENT_MAX_M: f64 = 10.0;
    /// Largest phase a measurement or a score may hold, in either sense
    /// (a summary's phase mean; its variance up to the square), degrees.
    pub const PHASE_MAX_DEG: f64 = 360.0;
    /// Largest speed of the block a measurement may hold (`v`), m/s.
    pub const SPEED_MAX_M_PER_S: f64 = 1e4;
    /// Stiffness `k = m (2π f0)²` the ranges above allow, N/m.
    pub const STIFFNESS_N_PER_M: (f64, f64) = (1e-15, 1e20);
}

/// A number for a message: plain when of ordinary size, else in exponent
/// form (never 309 digits).
pub fn fmt_value(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e9).contains(&v.abs()) { v.to_string() } else { format!("{v:e}") }
}

/// What is wrong with `value` for the range `[lo, hi]` (`lo` excluded when
/// `lo_open`), in words with `unit`; `None` when it is fine.
pub fn range_problem(value: f64, lo: f64, hi: f64, lo_open: bool, unit: &str) -> Option<String> {
    let unit = if unit.is_empty() { String::new() } else { format!(" {unit}") };
    let (lo_s, hi_s) = (fmt_bound(lo), fmt_bound(hi));
    let lower = if lo_open { format!("> {lo_s}{unit}") } else { format!(">= {lo_s}{unit}") };
    if !value.is_finite() {
        Some(format!("must be a finite number ({lower} and <= {hi_s}{unit})"))
    } else if value < lo || (lo_open && value == lo) {
        Some(format!("must be {lower} (and <= {hi_s}{unit})"))
    } else if value > hi {
        Some(format!("must be <= {hi_s}{unit} (a physically sensible range)"))
    } else {
        None
    }
}

/// A range's bound for a message: `0`, `0.001`, `100`, `1e6`, `1e-9`.
pub fn fmt_bound(v: f64) -> String {
    if v == 0.0 || (1e-3..1e4).contains(&v.abs()) { v.to_string() } else { format!("{v:e}") }
}

/// What is wrong with an excitation frequency (Hz), if anything.
pub fn excitation_frequency_problem(hz: f64) -> Option<String> {
    let (lo, hi) = limits::FREQUENCY_HZ;
    if hz.is_finite() && hz <= 0.0 {
        return Some(format!(
            "the excitation frequency must be > 0 Hz (between {} and {} Hz)",
            fmt_bound(lo),
            fmt_bound(hi)
        ));
    }
    range_problem(hz, lo, hi, false, "Hz").map(|p| format!("the excitation frequency {p}"))
}

/// What is wrong with a nominal normal force (N), if anything.
pub fn normal_force_problem(n: f64) -> Option<String> {
    range_problem(n, 0.0, limits::FORCE_MAX_N, false, "N").map(|p| format!("the normal force {p}"))
}

/// The embedded default: the seed paper's rig (see the README for how the
/// friction law was chosen).
pub const PAPER_RIG_TOML: &str = include_str!("../../models/paper-rig.toml");

/// A complete model: rig, excitation, friction law, noise, solver, and the
/// optional effects (each its own table; see [`crate::engine::effects`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Model {
    pub rig: Rig,
    pub excitation: Excitation,
    pub friction: Friction,
    pub normal_force: NormalForce,
    pub noise: Noise,
    #[serde(default)]
    pub solver: Solver,
    #[serde(flatten)]
    pub effects: Effects,
}

/// The top-level tables a model file may have.
const MODEL_TABLES: [&str; 6] = ["rig", "excitation", "friction", "normal_force", "noise", "solver"];

/// The block on its leaf springs, without friction contact.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rig {
    /// Block mass `m`, kg.
    pub mass_kg: f64,
    /// Natural frequency without friction contact `f0`, Hz.
    pub natural_frequency_hz: f64,
    /// Viscous damping ratio `ζ`, dimensionless.
    pub damping_ratio: f64,
}

/// Base excitation `u(t) = U0 cos(Ω t)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Excitation {
    /// Base displacement amplitude `U0`, m.
    pub amplitude_m: f64,
}

/// The friction law `μ(v) = a + b / (1 + c|v|) + d v² + σ ξ_μ` (paper eq. 7).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Friction {
    /// Kinetic level `a`, dimensionless.
    pub a: f64,
    /// Stribeck drop `b`, dimensionless (`μ(0) = a + b`).
    pub b: f64,
    /// Stribeck rate `c`, s/m.
    pub c: f64,
    /// Quadratic viscous term `d`, s²/m².
    pub d: f64,
    /// Standard deviation of the random part `σ_μ`, dimensionless.
    pub sigma: f64,
}

/// The normal force's random part; its mean is a grid coordinate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NormalForce {
    /// Standard deviation `σ_N` of the random part, N.
    pub sigma: f64,
}

/// How the random values are held.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Noise {
    /// Hold interval `τ` of each random value, s.
    pub interval_s: f64,
}

/// Integrator settings (optional table).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Solver {
    /// Fixed integration steps per excitation period (noise-interval
    /// boundaries and stick/slip events split steps further).
    #[serde(default = "Solver::default_steps_per_period")]
    pub steps_per_period: u32,
}

impl Solver {
    /// Smallest accepted `steps_per_period`.
    pub const MIN_STEPS_PER_PERIOD: u32 = 16;
    /// Largest accepted `steps_per_period`.
    pub const MAX_STEPS_PER_PERIOD: u32 = 1 << 20;

    /// 64: chosen by measurement. Noise boundaries (every 1/600 s) already
    /// split a period into 40–120 spans at the main job's 5–15 Hz, and
    /// stick/slip events are located exactly, so against 256 steps on the
    /// same noise the main job's mean peaks move by at most 0.18 of their
    /// standard error (next to resonance; median 0.002, 4e-5 relative at
    /// most), in half the time. `default_step_is_converged_next_to_resonance`
    /// checks it.
    fn default_steps_per_period() -> u32 {
        64
    }
}

impl Default for Solver {
    fn default() -> Self {
        Solver { steps_per_period: Self::default_steps_per_period() }
    }
}

/// One point of the frequency × normal-force grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Condition {
    /// Excitation frequency `Ω / 2π`, Hz.
    pub excitation_frequency_hz: f64,
    /// Nominal (mean) normal force `N0`, N.
    pub normal_force_n: f64,
}

impl Condition {
    /// Checks that the condition is physical ([`limits`]).
    pub fn validate(&self) -> Result<()> {
        if let Some(message) = excitation_frequency_problem(self.excitation_frequency_hz) {
            return Err(Error::InvalidParameter {
                key: "excitation_frequency_hz".into(),
                value: fmt_value(self.excitation_frequency_hz),
                message,
            });
        }
        if let Some(message) = normal_force_problem(self.normal_force_n) {
            return Err(Error::InvalidParameter {
                key: "normal_force_n".into(),
                value: fmt_value(self.normal_force_n),
                message,
            });
        }
        Ok(())
    }

    /// The same checks, blaming the flags the values came from.
    pub fn validate_flags(&self, frequency_flag: &str, force_flag: &str) -> Result<()> {
        if let Some(message) = excitation_frequency_problem(self.excitation_frequency_hz) {
            return Err(Error::setting(
                frequency_flag,
                format!("`{}`: {message}", fmt_value(self.excitation_frequency_hz)),
            ));
        }
        if let Some(message) = normal_force_problem(self.normal_force_n) {
            return Err(Error::setting(force_flag, format!("`{}`: {message}", fmt_value(self.normal_force_n))));
        }
        Ok(())
    }

    /// Short description for messages, e.g. `7 Hz, 16.39 N`.
    pub fn describe(&self) -> String {
        format!("{} Hz, {} N", self.excitation_frequency_hz, self.normal_force_n)
    }
}

impl Default for Model {
    /// The embedded paper rig.
    fn default() -> Self {
        Model::from_toml_str(PAPER_RIG_TOML, "embedded paper rig", &[]).expect("the embedded default model is valid")
    }
}

impl Model {
    /// Reads a model file (a regular file of at most
    /// [`MAX_MODEL_FILE_BYTES`](crate::io::MAX_MODEL_FILE_BYTES), UTF-8, an
    /// optional byte-order mark), applies `--set KEY=VALUE` overrides, and
    /// validates.
    pub fn from_file(path: &std::path::Path, overrides: &[String]) -> Result<Model> {
        let source_name = crate::text::shown(path);
        let refuse = |message: String| Error::ModelSyntax { source_name: source_name.clone(), message };
        let bytes = crate::io::read_bounded(path, crate::io::MAX_MODEL_FILE_BYTES)
            .map_err(|e| refuse(format!("cannot read it: {e}")))?;
        let text = std::str::from_utf8(crate::io::strip_bom(&bytes))
            .map_err(|e| refuse(format!("not UTF-8 text (at byte {})", e.valid_up_to())))?;
        Model::from_toml_str(text, &source_name, overrides)
    }

    /// The embedded default with overrides applied.
    pub fn paper_rig(overrides: &[String]) -> Result<Model> {
        Model::from_toml_str(PAPER_RIG_TOML, "embedded paper rig", overrides)
    }

    /// Parses TOML text, applies overrides, and validates.
    pub fn from_toml_str(text: &str, source_name: &str, overrides: &[String]) -> Result<Model> {
        let syntax = |message: String| Error::ModelSyntax { source_name: source_name.to_string(), message };
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut table: toml::Table = text.parse().map_err(|e: toml::de::Error| syntax(toml_problem(text, &e)))?;
        // The tables the text itself has; one a `--set` creates is that flag's.
        let own_tables: Vec<String> = table.keys().cloned().collect();
        for assignment in overrides {
            apply_override(&mut table, assignment)?;
        }
        // `flatten` cannot deny unknown keys, so the top level is checked here.
        let is_effect = |k: &str| Effect::ALL.iter().any(|e| e.name() == k);
        if let Some(unknown) = table.keys().find(|k| !MODEL_TABLES.contains(&k.as_str()) && !is_effect(k)) {
            let effects: Vec<&str> = Effect::ALL.iter().map(|e| e.name()).collect();
            let message = format!(
                "unknown table `{unknown}`; expected one of {} or an effect ({})",
                MODEL_TABLES.join(", "),
                effects.join(", ")
            );
            // A table the text does not have is the `--set` that made it.
            let made_by = (!own_tables.contains(unknown)).then(|| {
                overrides.iter().find(|a| {
                    a.split_once('=').is_some_and(|(key, _)| key.trim().split('.').next() == Some(unknown.as_str()))
                })
            });
            return Err(match made_by.flatten() {
                Some(assignment) => Error::ModelSyntax { source_name: format!("--set {assignment}"), message },
                None => syntax(message),
            });
        }
        let model: Model = match Model::deserialize(toml::Value::Table(table.clone())) {
            Ok(model) => model,
            Err(e) => {
                // A value a `--set` put there is that flag's fault, not the file's.
                let problem = schema_problem(&table, &e);
                let set_here = overrides.iter().find(|a| {
                    a.split_once('=').is_some_and(|(key, _)| {
                        let (key, table) = (key.trim(), key.trim().split('.').next().unwrap_or_default());
                        problem.starts_with(&format!("`{key}`"))
                            || (problem.starts_with(&format!("in table `{table}`"))
                                && !own_tables.iter().any(|t| t == table))
                    })
                });
                return Err(match set_here {
                    Some(assignment) => {
                        Error::ModelSyntax { source_name: format!("--set {assignment}"), message: problem }
                    }
                    None => syntax(problem),
                });
            }
        };
        model.validate()?;
        Ok(model)
    }

    /// The model as TOML, in the same form as a model file.
    pub fn to_toml_string(&self) -> String {
        toml::to_string(self).expect("a model always serialises")
    }

    /// Checks every parameter's physical range; errors name the dotted key.
    pub fn validate(&self) -> Result<()> {
        let check = |key: &str, value: f64, ok: bool, message: &str| -> Result<()> {
            if value.is_finite() && ok {
                Ok(())
            } else {
                Err(Error::InvalidParameter { key: key.into(), value: fmt_value(value), message: message.into() })
            }
        };
        // A value within [lo, hi] (lo excluded when `open`); the message names the rule.
        let within = |key: &str, value: f64, lo: f64, hi: f64, open: bool, unit: &str, what: &str| -> Result<()> {
            match range_problem(value, lo, hi, open, unit) {
                None => Ok(()),
                Some(problem) => Err(Error::InvalidParameter {
                    key: key.into(),
                    value: fmt_value(value),
                    message: format!("{what} {problem}"),
                }),
            }
        };
        use limits::*;
        let r = &self.rig;
        if r.mass_kg <= 0.0 {
            check("rig.mass_kg", r.mass_kg, false, "the mass must be > 0 kg")?;
        }
        within("rig.mass_kg", r.mass_kg, MASS_KG.0, MASS_KG.1, false, "kg", "the mass")?;
        if r.natural_frequency_hz <= 0.0 {
            check("rig.natural_frequency_hz", r.natural_frequency_hz, false, "the natural frequency must be > 0 Hz")?;
        }
        let (f_lo, f_hi) = FREQUENCY_HZ;
        within("rig.natural_frequency_hz", r.natural_frequency_hz, f_lo, f_hi, false, "Hz", "the natural frequency")?;
        check(
            "rig.damping_ratio",
            r.damping_ratio,
            (0.0..DAMPING_RATIO_BELOW).contains(&r.damping_ratio),
            "the damping ratio must be >= 0 (and < 10)",
        )?;
        let e = &self.excitation;
        within("excitation.amplitude_m", e.amplitude_m, 0.0, AMPLITUDE_MAX_M, false, "m", "the base amplitude")?;
        let f = &self.friction;
        let mu = FRICTION_COEFFICIENT_MAX;
        within("friction.a", f.a, -mu, mu, false, "", "the friction level a")?;
        within("friction.b", f.b, -mu, mu, false, "", "the Stribeck drop b")?;
        if f.a + f.b < 0.0 {
            return Err(Error::InvalidParameter {
                key: "friction.a + friction.b".into(),
                value: format!("{} + {} = {}", fmt_value(f.a), fmt_value(f.b), fmt_value(f.a + f.b)),
                message: "the friction coefficient at rest, a + b, must be >= 0".into(),
            });
        }
        within("friction.c", f.c, 0.0, STRIBECK_RATE_MAX_S_PER_M, false, "s/m", "the Stribeck rate")?;
        let d_max = QUADRATIC_MAX_S2_PER_M2;
        within("friction.d", f.d, -d_max, d_max, false, "s²/m²", "the quadratic term")?;
        within("friction.sigma", f.sigma, 0.0, mu, false, "", "a standard deviation")?;
        let n = &self.normal_force;
        within("normal_force.sigma", n.sigma, 0.0, FORCE_MAX_N, false, "N", "a standard deviation")?;
        if self.noise.interval_s <= 0.0 {
            check("noise.interval_s", self.noise.interval_s, false, "the noise hold interval must be > 0 s")?;
        }
        let (t_lo, t_hi) = NOISE_INTERVAL_S;
        within("noise.interval_s", self.noise.interval_s, t_lo, t_hi, false, "s", "the noise hold interval")?;
        // The effects' own checks; their values are shown compactly (no 309-digit numbers).
        self.effects.validate().map_err(|e| match e {
            Error::InvalidParameter { key, value, message } => {
                let value = value.parse::<f64>().map(fmt_value).unwrap_or(value);
                Error::InvalidParameter { key, value, message }
            }
            e => e,
        })?;
        self.validate_effect_ranges()?;
        // Derived quantities: within the ranges above they are finite; checked all the same.
        let k = self.stiffness_n_per_m();
        let (k_lo, k_hi) = STIFFNESS_N_PER_M;
        if !(k.is_finite() && (k_lo..=k_hi).contains(&k)) {
            return Err(Error::InvalidParameter {
                key: "rig".into(),
                value: format!("k = {k:e} N/m"),
                message: format!(
                    "the stiffness m (2π f0)² must lie between {} and {} N/m; change rig.mass_kg or \
                     rig.natural_frequency_hz",
                    fmt_bound(k_lo),
                    fmt_bound(k_hi)
                ),
            });
        }
        let c = self.damping_n_s_per_m();
        let base_force = k * self.excitation.amplitude_m;
        if !(c.is_finite() && base_force.is_finite()) {
            return Err(Error::InvalidParameter {
                key: "rig".into(),
                value: format!("c = {c:e} N·s/m, k U0 = {base_force:e} N"),
                message: "the damping coefficient and the base force must be finite".into(),
            });
        }
        let s = self.solver.steps_per_period;
        if !(Solver::MIN_STEPS_PER_PERIOD..=Solver::MAX_STEPS_PER_PERIOD).contains(&s) {
            return Err(Error::InvalidParameter {
                key: "solver.steps_per_period".into(),
                value: s.to_string(),
                message: format!(
                    "the step must be between 1/{} and 1/{} of an excitation period",
                    Solver::MAX_STEPS_PER_PERIOD,
                    Solver::MIN_STEPS_PER_PERIOD
                ),
            });
        }
        Ok(())
    }

    /// Magnitude limits of the effect tables (their forms and signs are
    /// checked by [`Effects::validate`]).
    fn validate_effect_ranges(&self) -> Result<()> {
        use limits::*;
        let bound = |key: &str, value: f64, max: f64, unit: &str| -> Result<()> {
            if value.abs() <= max {
                Ok(())
            } else {
                let unit = if unit.is_empty() { String::new() } else { format!(" {unit}") };
                Err(Error::InvalidParameter {
                    key: key.into(),
                    value: fmt_value(value),
                    message: format!("its magnitude must be <= {}{unit} (a physically sensible range)", fmt_bound(max)),
                })
            }
        };
        let e = &self.effects;
        if let Some(h) = &e.normal_force_harmonics {
            for (k, a) in h.amplitudes_n.iter().enumerate() {
                bound(&format!("normal_force_harmonics.amplitudes_n[{k}]"), *a, FORCE_MAX_N, "N")?;
            }
            for (k, p) in h.phases_rad.iter().enumerate() {
                bound(&format!("normal_force_harmonics.phases_rad[{k}]"), *p, 1e3, "rad")?;
            }
            bound("normal_force_harmonics.shape", h.shape, RATE_MAX, "")?;
            let on = h.amplitudes_per_n0[0] != 0.0 || h.amplitudes_per_n0[1] != 0.0;
            if h.form == HarmonicForm::Position && on && self.excitation.amplitude_m == 0.0 {
                return Err(Error::InvalidParameter {
                    key: "normal_force_harmonics.form".into(),
                    value: "\"position\"".into(),
                    message: "measures the displacement in units of excitation.amplitude_m, which must then be > 0 m"
                        .into(),
                });
            }
        }
        if let Some(g) = &e.non_gaussian_friction {
            bound("non_gaussian_friction.strength", g.strength, RATE_MAX, "")?;
            bound("non_gaussian_friction.load_exponent", g.load_exponent, RATE_MAX, "")?;
            bound("non_gaussian_friction.reference_force_n", g.reference_force_n, FORCE_MAX_N, "N")?;
        }
        if let Some(h) = &e.friction_hysteresis {
            bound("friction_hysteresis.length_m", h.length_m, LENGTH_MAX_M, "m")?;
            bound("friction_hysteresis.strength", h.strength, FRICTION_COEFFICIENT_MAX, "")?;
        }
        if let Some(c) = &e.coloured_friction_noise {
            bound("coloured_friction_noise.correlation_time_s", c.correlation_time_s, TIME_MAX_S, "s")?;
        }
        if let Some(s) = &e.stiction {
            bound("stiction.excess", s.excess, FRICTION_COEFFICIENT_MAX, "")?;
            bound("stiction.release_length_m", s.release_length_m, LENGTH_MAX_M, "m")?;
        }
        if let Some(l) = &e.load_dependent_friction {
            match l.form {
                // The adhesion force A, N.
                LoadForm::Adhesion => bound("load_dependent_friction.strength", l.strength, FORCE_MAX_N, "N")?,
                _ => bound("load_dependent_friction.strength", l.strength, RATE_MAX, "")?,
            }
            bound("load_dependent_friction.curvature_per_n2", l.curvature_per_n2, RATE_MAX, "1/N²")?;
            bound("load_dependent_friction.reference_force_n", l.reference_force_n, FORCE_MAX_N, "N")?;
        }
        if let Some(d) = &e.normal_force_drift {
            bound("normal_force_drift.rate_per_s", d.rate_per_s, RATE_MAX, "1/s")?;
            bound("normal_force_drift.curvature_per_s2", d.curvature_per_s2, RATE_MAX, "1/s²")?;
        }
        Ok(())
    }

    /// Spring stiffness `k = m (2π f0)²`, N/m.
    pub fn stiffness_n_per_m(&self) -> f64 {
        let w0 = std::f64::consts::TAU * self.rig.natural_frequency_hz;
        self.rig.mass_kg * w0 * w0
    }

    /// Viscous damping coefficient `c = 2 ζ sqrt(k m)`, N·s/m.
    pub fn damping_n_s_per_m(&self) -> f64 {
        2.0 * self.rig.damping_ratio * (self.stiffness_n_per_m() * self.rig.mass_kg).sqrt()
    }

    /// Frictionless steady-state amplitude `U0 / sqrt((1−η²)² + (2ζη)²)`, m.
    pub fn linear_amplitude_m(&self, excitation_frequency_hz: f64) -> f64 {
        let eta = excitation_frequency_hz / self.rig.natural_frequency_hz;
        let zeta = self.rig.damping_ratio;
        self.excitation.amplitude_m / ((1.0 - eta * eta).powi(2) + (2.0 * zeta * eta).powi(2)).sqrt()
    }

    /// Frictionless steady-state phase lag of the response behind the base,
    /// `atan2(2ζη, 1 − η²)`, rad.
    pub fn linear_phase_rad(&self, excitation_frequency_hz: f64) -> f64 {
        let eta = excitation_frequency_hz / self.rig.natural_frequency_hz;
        (2.0 * self.rig.damping_ratio * eta).atan2(1.0 - eta * eta)
    }

    /// The frictionless steady-state solution's displacement (m) and velocity
    /// (m/s) at t = 0: the default initial state of every realisation.
    pub fn linear_steady_state_at_zero(&self, excitation_frequency_hz: f64) -> (f64, f64) {
        let omega = std::f64::consts::TAU * excitation_frequency_hz;
        let k = self.stiffness_n_per_m();
        // x = Re{X e^{iΩt}}, X = k U0 / (k − mΩ² + i c Ω)
        let re = k - self.rig.mass_kg * omega * omega;
        let im = self.damping_n_s_per_m() * omega;
        let scale = k * self.excitation.amplitude_m / (re * re + im * im);
        let (x_re, x_im) = (scale * re, -scale * im);
        (x_re, -omega * x_im)
    }
}

/// A TOML syntax error as `line L, column C: message`, without quoting the
/// file (it may not be a model file at all).
fn toml_problem(text: &str, e: &toml::de::Error) -> String {
    let message = crate::text::excerpt(e.message().trim(), 200);
    match e.span() {
        Some(span) => {
            let before = &text.as_bytes()[..span.start.min(text.len())];
            let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
            let column = before.iter().rev().take_while(|&&b| b != b'\n').count() + 1;
            format!("line {line}, column {column}: {message}")
        }
        None => message,
    }
}

/// A schema error (wrong type, length, unknown or missing key) with the
/// dotted key it concerns: each table is deserialised alone, from TOML text
/// written for it, so that the error's span points at the key.
fn schema_problem(table: &toml::Table, whole: &toml::de::Error) -> String {
    fn first_error<T: serde::de::DeserializeOwned>(text: &str) -> Option<toml::de::Error> {
        toml::from_str::<T>(text).err()
    }
    for (name, value) in table {
        let shown_name = crate::text::excerpt(name, 60);
        let Some(inner) = value.as_table() else {
            return format!("`{shown_name}` must be a table");
        };
        let core = MODEL_TABLES.contains(&name.as_str());
        let text = if core {
            toml::to_string(inner).unwrap_or_default()
        } else {
            let mut single = toml::Table::new();
            single.insert(name.clone(), value.clone());
            toml::to_string(&single).unwrap_or_default()
        };
        let error = match name.as_str() {
            "rig" => first_error::<Rig>(&text),
            "excitation" => first_error::<Excitation>(&text),
            "friction" => first_error::<Friction>(&text),
            "normal_force" => first_error::<NormalForce>(&text),
            "noise" => first_error::<Noise>(&text),
            "solver" => first_error::<Solver>(&text),
            _ => first_error::<Effects>(&text),
        };
        if let Some(e) = error {
            let message = crate::text::excerpt(e.message().trim(), 200);
            // A missing key has no line of its own: the error's span is
            // the table's, whose first line names another key.
            let missing = message.strip_prefix("missing field `").and_then(|m| m.split('`').next());
            if let Some(field) = missing {
                let field = crate::text::excerpt(field, 60);
                return if core {
                    format!("`{shown_name}.{field}`: {message}")
                } else {
                    format!("in table `{shown_name}`: {message}")
                };
            }
            return match key_at(&text, e.span()) {
                Some(key) if core => format!("`{shown_name}.{key}`: {message}"),
                Some(key) => format!("`{key}`: {message}"),
                None => format!("in table `{shown_name}`: {message}"),
            };
        }
    }
    crate::text::excerpt(whole.message().trim(), 200)
}

/// The dotted key of the `key = value` line that `span` starts on in TOML
/// text written by `toml::to_string` (with its table header, if any).
fn key_at(text: &str, span: Option<std::ops::Range<usize>>) -> Option<String> {
    let start = span?.start.min(text.len());
    let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
    let line = text[line_start..].lines().next()?;
    let (key, _) = line.split_once('=')?;
    let key = crate::text::excerpt(key.trim().trim_matches('"'), 60);
    let header = text[..line_start]
        .lines()
        .rev()
        .find_map(|l| l.trim().strip_prefix('[').and_then(|h| h.strip_suffix(']')).map(|h| h.trim().to_string()));
    Some(match header {
        Some(h) => format!("{}.{key}", crate::text::excerpt(&h, 60)),
        None => key,
    })
}

/// Applies one `KEY=VALUE` override to a TOML table, creating tables on the
/// way. The value is read as a TOML value (number, boolean, string); a bare
/// word is taken as a string.
fn apply_override(table: &mut toml::Table, assignment: &str) -> Result<()> {
    let bad =
        |message: &str| Error::ModelSyntax { source_name: format!("--set {assignment}"), message: message.into() };
    let (key, raw) = assignment.split_once('=').ok_or_else(|| bad("expected KEY=VALUE"))?;
    let key = key.trim();
    let parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err(bad("the key must be dotted names such as friction.a"));
    }
    let value: toml::Value = match format!("v = {}", raw.trim()).parse::<toml::Table>() {
        Ok(mut t) => t.remove("v").expect("parsed key"),
        Err(_) => toml::Value::String(raw.trim().to_string()),
    };
    let mut node = table;
    for part in &parts[..parts.len() - 1] {
        let entry = node.entry(part.to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new()));
        node = entry.as_table_mut().ok_or_else(|| bad(&format!("`{part}` is not a table")))?;
    }
    let leaf = parts[parts.len() - 1];
    if leaf.contains('[') {
        return Err(bad("a list is set whole, as KEY=[v1, v2, ...]; one element cannot be set by its index"));
    }
    // An integer given where the schema has a float is fine: serde converts.
    node.insert(leaf.to_string(), value);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_model_is_the_paper_rig() {
        let m = Model::default();
        assert_eq!(m.rig.mass_kg, 1.028);
        assert_eq!(m.rig.natural_frequency_hz, 10.05);
        assert_eq!(m.rig.damping_ratio, 0.00225);
        assert_eq!(m.excitation.amplitude_m, 0.0025);
        assert!((m.normal_force.sigma.powi(2) - 0.1102).abs() < 1e-4);
    }

    #[test]
    fn a_bad_set_is_named_as_the_flag_not_the_file() {
        for (assignment, needle) in [
            ("friction.a=abc", "expected f64"),
            ("friction.zzz=1", "unknown field"),
            ("normal_force_harmonics.amplitudes_n[0]=1", "set whole"),
            ("stiction.release_length_m=1", "missing field `excess`"),
        ] {
            let err = Model::paper_rig(&[assignment.into()]).unwrap_err().to_string();
            assert!(err.contains(&format!("--set {assignment}")) && err.contains(needle), "{err}");
            assert!(!err.contains("embedded"), "{err}");
        }
    }

    /// A required key left out of a model file is named by its own dotted
    /// key, not by the first key of its table.
    #[test]
    fn a_missing_key_is_named_by_itself() {
        let text = Model::default().to_toml_string();
        let without: String =
            text.lines().filter(|l| !l.trim_start().starts_with("mass_kg")).map(|l| format!("{l}\n")).collect();
        let err = Model::from_toml_str(&without, "model.toml", &[]).unwrap_err().to_string();
        assert!(err.contains("`rig.mass_kg`") && err.contains("missing field"), "{err}");
        assert!(!err.contains("damping_ratio"), "{err}");
    }

    #[test]
    fn set_overrides_a_dotted_key() {
        let m = Model::paper_rig(&["friction.a=0.3".into(), "solver.steps_per_period=512".into()]).unwrap();
        assert_eq!(m.friction.a, 0.3);
        assert_eq!(m.solver.steps_per_period, 512);
    }

    #[test]
    fn unknown_key_is_named() {
        let err = Model::paper_rig(&["friction.mu=0.3".into()]).unwrap_err().to_string();
        assert!(err.contains("mu"), "{err}");
    }

    #[test]
    fn round_trips_through_toml() {
        let m = Model::default();
        let back = Model::from_toml_str(&m.to_toml_string(), "round trip", &[]).unwrap();
        assert_eq!(m, back);
    }

    #[test]
    fn linear_steady_state_matches_amplitude() {
        let m = Model::default();
        let f = 7.0;
        let (x, v) = m.linear_steady_state_at_zero(f);
        let w = std::f64::consts::TAU * f;
        let amp = (x * x + (v / w).powi(2)).sqrt();
        assert!((amp / m.linear_amplitude_m(f) - 1.0).abs() < 1e-12);
    }
}
