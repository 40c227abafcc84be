//! Closed-form results the integrators are checked against.
//!
//! **Den Hartog (1931), Coulomb friction `F0`, ζ = 0, no stops.** With the
//! time origin at a turning point `x = x0, v = 0` and the base at
//! `u = U0 cos(Ω t' + θ)`, the half period with `v < 0` is
//! `x = C1 cos ω0 t' + C2 sin ω0 t' + V U0 cos(Ω t' + θ) + β U0` with
//! `V = 1/(1−η²)`, `β = F0/(k U0)`. Half-period antisymmetry gives
//! `C1 = −β U0`, `C2 = −β U0 sin(π/η)/(1+cos(π/η))`, `sin θ = −β U / V`
//! and `x0 = V U0 cos θ = U0 sqrt(V² − β² U²)`, `U = sin(π/η)/(η(1+cos(π/η)))`.
//! The block leaves the turning point at once only while
//! `x0 − U0 cos θ > β U0`, i.e. `β < η² |V| / sqrt(1 + η⁴ U²)`: the no-stop threshold.

use crate::engine::oscillator::InitialState;

/// Frictionless steady amplitude ratio `x0/U0 = 1/sqrt((1−η²)² + (2ζη)²)`.
pub fn linear_amplitude_ratio(eta: f64, zeta: f64) -> f64 {
    1.0 / ((1.0 - eta * eta).powi(2) + (2.0 * zeta * eta).powi(2)).sqrt()
}

/// Den Hartog's steady solution for one frequency ratio and friction level.
#[derive(Clone, Copy, Debug)]
pub struct DenHartog {
    /// Frequency ratio `η = Ω/ω0`.
    pub eta: f64,
    /// Friction ratio `β = F0/(k U0)`.
    pub beta: f64,
}

impl DenHartog {
    /// `V = 1/(1−η²)`.
    pub fn v_factor(&self) -> f64 {
        1.0 / (1.0 - self.eta * self.eta)
    }

    /// `U = sin(π/η) / (η (1 + cos(π/η)))`.
    pub fn u_factor(&self) -> f64 {
        let a = std::f64::consts::PI / self.eta;
        a.sin() / (self.eta * (1.0 + a.cos()))
    }

    /// Largest `β` with continuous (non-stop) motion at this `η`.
    pub fn stop_threshold(eta: f64) -> f64 {
        let dh = DenHartog { eta, beta: 0.0 };
        eta * eta * dh.v_factor().abs() / (1.0 + eta.powi(4) * dh.u_factor().powi(2)).sqrt()
    }

    /// `x0/U0 = sqrt(V² − β² U²)`; `None` where no non-stop solution exists.
    pub fn amplitude_ratio(&self) -> Option<f64> {
        let (v, u) = (self.v_factor(), self.u_factor());
        let arg = v * v - self.beta * self.beta * u * u;
        (u.is_finite() && u != 0.0 && arg > 0.0 && self.beta < Self::stop_threshold(self.eta)).then(|| arg.sqrt())
    }

    /// The steady solution's state at the time `t = 0` of a simulation whose
    /// base moves as `U0 cos(Ω t)`, for natural angular frequency `w0` (rad/s)
    /// and base amplitude `u0` (m).
    pub fn state_at_zero(&self, w0: f64, u0: f64) -> Option<InitialState> {
        self.amplitude_ratio()?;
        let (eta, beta) = (self.eta, self.beta);
        let (v, u) = (self.v_factor(), self.u_factor());
        let sin_theta = -beta * u / v;
        let cos_theta = v.signum() * (1.0 - sin_theta * sin_theta).sqrt();
        let theta = sin_theta.atan2(cos_theta);
        let omega = eta * w0;
        let period = std::f64::consts::TAU / omega;
        let c1 = -beta * u0;
        let c2 = eta * v * u0 * sin_theta;
        // Descending half period, t' in [0, T/2).
        let descending = |tp: f64| {
            let x = c1 * (w0 * tp).cos() + c2 * (w0 * tp).sin() + v * u0 * (omega * tp + theta).cos() + beta * u0;
            let xd =
                -c1 * w0 * (w0 * tp).sin() + c2 * w0 * (w0 * tp).cos() - v * u0 * omega * (omega * tp + theta).sin();
            (x, xd)
        };
        let tp = (-theta / omega).rem_euclid(period);
        let (x, xd) = if tp < 0.5 * period {
            descending(tp)
        } else {
            let (x, xd) = descending(tp - 0.5 * period);
            (-x, -xd)
        };
        Some(InitialState { x_m: x, v_m_per_s: xd })
    }
}
