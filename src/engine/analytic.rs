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

/// Frictionless steady phase lag of the response behind the base,
/// `atan2(2ζη, 1 − η²)`, rad.
pub fn linear_phase_rad(eta: f64, zeta: f64) -> f64 {
    (2.0 * zeta * eta).atan2(1.0 - eta * eta)
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

    /// `U = sin(π/η) / (η (1 + cos(π/η)))`, computed as `tan(π/(2η)) / η`
    /// (the same by the half-angle identity): near η = 1, where both grow
    /// without bound, `1 + cos(π/η)` rounds to 0 long before the tangent
    /// stops being exact.
    pub fn u_factor(&self) -> f64 {
        (std::f64::consts::FRAC_PI_2 / self.eta).tan() / self.eta
    }

    /// Largest `β` with continuous (non-stop) motion at this `η`: at
    /// resonance (η = 1, where V and U are both unbounded) the formula's
    /// limit, π/4; near η = 1/3, 1/5, … it falls to 0 (the block stops at
    /// every load).
    pub fn stop_threshold(eta: f64) -> f64 {
        if eta == 1.0 {
            return std::f64::consts::FRAC_PI_4;
        }
        let dh = DenHartog { eta, beta: 0.0 };
        eta * eta * dh.v_factor().abs() / (1.0 + eta.powi(4) * dh.u_factor().powi(2)).sqrt()
    }

    /// `x0/U0 = sqrt(V² − β² U²)`; `None` where no non-stop solution exists.
    pub fn amplitude_ratio(&self) -> Option<f64> {
        let (v, u) = (self.v_factor(), self.u_factor());
        let arg = v * v - self.beta * self.beta * u * u;
        (u.is_finite() && u != 0.0 && arg > 0.0 && self.beta < Self::stop_threshold(self.eta)).then(|| arg.sqrt())
    }

    /// Den Hartog's phase angle θ of the displacement maximum (the turning
    /// point) behind the base, rad: `sin θ = −β U / V`, `cos θ = sqrt(V² −
    /// β² U²) / V` (near π above resonance, where `V < 0`). This is the
    /// formula `model.md` gives; `None` where no non-stop solution exists.
    pub fn turning_point_phase_rad(&self) -> Option<f64> {
        let ratio = self.amplitude_ratio()?;
        let (v, u) = (self.v_factor(), self.u_factor());
        Some((-self.beta * u / v).atan2(ratio / v))
    }

    /// The phase lag of the exact solution's fundamental behind the base,
    /// rad: `atan2(b, a)` with `a`, `b` its Fourier coefficients against the
    /// base's `cos` and `sin` (`interfaces.md`). Den Hartog's solution is not
    /// a sinusoid, so with friction this differs from the turning point's
    /// angle θ (by 0.28 rad at η = 0.6 and 80% of the no-stop threshold, by
    /// nothing without friction). The coefficients are integrals of the
    /// closed form, taken by composite Gauss–Legendre quadrature (8 points on
    /// each of 256 panels of the half period: exact to rounding).
    pub fn phase_rad(&self) -> Option<f64> {
        let theta = self.turning_point_phase_rad()?;
        let (eta, beta) = (self.eta, self.beta);
        let (v, u) = (self.v_factor(), self.u_factor());
        // Units: ω0 = 1, U0 = 1; the phase does not depend on them.
        let omega = eta;
        let half_period = std::f64::consts::PI / omega;
        let (c1, c2) = (-beta, eta * v * (-beta * u / v));
        let x = |tp: f64| c1 * tp.cos() + c2 * tp.sin() + v * (omega * tp + theta).cos() + beta;
        // Half-wave antisymmetry: the second half period doubles the first.
        let (mut a, mut b) = (0.0, 0.0);
        let panels = 256;
        let width = half_period / f64::from(panels);
        for panel in 0..panels {
            let centre = (f64::from(panel) + 0.5) * width;
            for (node, weight) in GAUSS_LEGENDRE_8 {
                let tp = centre + 0.5 * width * node;
                let psi = omega * tp + theta;
                a += weight * x(tp) * psi.cos();
                b += weight * x(tp) * psi.sin();
            }
        }
        Some(b.atan2(a))
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

/// Nodes and weights of 8-point Gauss–Legendre quadrature on [−1, 1].
const GAUSS_LEGENDRE_8: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (-0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
];

#[cfg(test)]
mod tests {
    use super::*;

    /// Without friction the fundamental and the turning point have the same
    /// phase (0 below resonance, π above); with friction the fundamental's
    /// is the quadrature of the closed form, here against a fine midpoint sum.
    #[test]
    fn fundamental_phase_of_the_closed_form() {
        for eta in [0.6, 1.5] {
            let free = DenHartog { eta, beta: 0.0 };
            let (f, t) = (free.phase_rad().unwrap(), free.turning_point_phase_rad().unwrap());
            assert!((f - t).abs() < 1e-12, "eta {eta}: {f} vs {t}");
        }
        let dh = DenHartog { eta: 0.6, beta: 0.8 * DenHartog::stop_threshold(0.6) };
        let phase = dh.phase_rad().unwrap();
        assert!((phase - 0.546_875_416_650_5).abs() < 1e-8, "{phase}");
        assert!((dh.turning_point_phase_rad().unwrap() - 0.264_950_471_540_2).abs() < 1e-9);
    }

    /// The no-stop threshold is continuous through resonance, where the
    /// formula is 0/0: its limit there is π/4, and it stays near π/4 a
    /// hair either side, where `1 + cos(π/η)` rounds to 0 (within 1e-6 at
    /// 1 ± 1e-7; within 1e-3 at 1 ± 1e-12, where the rounding of η itself
    /// moves 1 − η² and π/(2η)'s distance from the pole by 1e-4 of
    /// themselves); at η = 1/3 it is (about) 0.
    #[test]
    fn the_stop_threshold_is_continuous_through_resonance() {
        let quarter = std::f64::consts::FRAC_PI_4;
        for (eta, within) in
            [(1.0, 0.0), (1.0 - 1e-7, 1e-6), (1.0 + 1e-7, 1e-6), (1.0 - 1e-12, 1e-3), (1.0 + 1e-12, 1e-3)]
        {
            let t = DenHartog::stop_threshold(eta);
            assert!((t - quarter).abs() <= within, "eta {eta}: {t}");
        }
        let near = DenHartog::stop_threshold(0.999);
        assert!((near - 0.785_790_733_181_75).abs() < 1e-9, "{near}");
        assert!(DenHartog::stop_threshold(1.0 / 3.0) < 1e-12);
    }
}
