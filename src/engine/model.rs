//! The physical model (`shared/spec/model.md`): its parameters, the TOML model
//! files that hold them, and their validation. The constants the integrators
//! derive from it are in [`crate::engine::oscillator`].
//!
//! Units are SI throughout; every field name carries its unit.

use serde::{Deserialize, Serialize};

use crate::engine::effects::{Effect, Effects};
use crate::error::{Error, Result};

/// The embedded default: the seed paper's rig (see the README for how the
/// friction law was chosen).
pub const PAPER_RIG_TOML: &str = include_str!("../../models/paper-rig.toml");

/// A complete model: rig, excitation, friction law, noise, solver, and the
/// optional effects (each its own table; see [`crate::effects`]).
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

    fn default_steps_per_period() -> u32 {
        256
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
    /// Checks that the condition is physical.
    pub fn validate(&self) -> Result<()> {
        if !(self.excitation_frequency_hz.is_finite() && self.excitation_frequency_hz > 0.0) {
            return Err(Error::InvalidParameter {
                key: "excitation_frequency_hz".into(),
                value: self.excitation_frequency_hz.to_string(),
                message: "the excitation frequency must be a finite number > 0 Hz".into(),
            });
        }
        if !(self.normal_force_n.is_finite() && self.normal_force_n >= 0.0) {
            return Err(Error::InvalidParameter {
                key: "normal_force_n".into(),
                value: self.normal_force_n.to_string(),
                message: "the normal force must be a finite number >= 0 N".into(),
            });
        }
        Ok(())
    }
}

impl Default for Model {
    /// The embedded paper rig.
    fn default() -> Self {
        Model::from_toml_str(PAPER_RIG_TOML, "embedded paper rig", &[]).expect("the embedded default model is valid")
    }
}

impl Model {
    /// Reads a model file, applies `--set KEY=VALUE` overrides, and validates.
    pub fn from_file(path: &std::path::Path, overrides: &[String]) -> Result<Model> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Model::from_toml_str(&text, &path.display().to_string(), overrides)
    }

    /// The embedded default with overrides applied.
    pub fn paper_rig(overrides: &[String]) -> Result<Model> {
        Model::from_toml_str(PAPER_RIG_TOML, "embedded paper rig", overrides)
    }

    /// Parses TOML text, applies overrides, and validates.
    pub fn from_toml_str(text: &str, source_name: &str, overrides: &[String]) -> Result<Model> {
        let syntax = |message: String| Error::ModelSyntax { source_name: source_name.to_string(), message };
        let mut table: toml::Table = text.parse().map_err(|e: toml::de::Error| syntax(e.to_string()))?;
        for assignment in overrides {
            apply_override(&mut table, assignment)?;
        }
        // `flatten` cannot deny unknown keys, so the top level is checked here.
        let is_effect = |k: &str| Effect::ALL.iter().any(|e| e.name() == k);
        if let Some(unknown) = table.keys().find(|k| !MODEL_TABLES.contains(&k.as_str()) && !is_effect(k)) {
            let effects: Vec<&str> = Effect::ALL.iter().map(|e| e.name()).collect();
            return Err(syntax(format!(
                "unknown table `{unknown}`; expected one of {} or an effect ({})",
                MODEL_TABLES.join(", "),
                effects.join(", ")
            )));
        }
        let model: Model =
            Model::deserialize(toml::Value::Table(table)).map_err(|e: toml::de::Error| syntax(e.to_string()))?;
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
                Err(Error::InvalidParameter { key: key.into(), value: value.to_string(), message: message.into() })
            }
        };
        let r = &self.rig;
        check("rig.mass_kg", r.mass_kg, r.mass_kg > 0.0, "the mass must be > 0 kg")?;
        check(
            "rig.natural_frequency_hz",
            r.natural_frequency_hz,
            r.natural_frequency_hz > 0.0,
            "the natural frequency must be > 0 Hz",
        )?;
        check(
            "rig.damping_ratio",
            r.damping_ratio,
            (0.0..10.0).contains(&r.damping_ratio),
            "the damping ratio must be >= 0 (and < 10)",
        )?;
        let e = &self.excitation;
        check("excitation.amplitude_m", e.amplitude_m, e.amplitude_m >= 0.0, "the base amplitude must be >= 0 m")?;
        let f = &self.friction;
        check("friction.a", f.a, true, "must be a finite number")?;
        check("friction.b", f.b, f.a + f.b >= 0.0, "the friction coefficient at rest, a + b, must be >= 0")?;
        check("friction.c", f.c, f.c >= 0.0, "the Stribeck rate must be >= 0 s/m")?;
        check("friction.d", f.d, true, "must be a finite number")?;
        check("friction.sigma", f.sigma, f.sigma >= 0.0, "a standard deviation must be >= 0")?;
        let n = &self.normal_force;
        check("normal_force.sigma", n.sigma, n.sigma >= 0.0, "a standard deviation must be >= 0 N")?;
        check(
            "noise.interval_s",
            self.noise.interval_s,
            self.noise.interval_s > 0.0,
            "the noise hold interval must be > 0 s",
        )?;
        self.effects.validate()?;
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
