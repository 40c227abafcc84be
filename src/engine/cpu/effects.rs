//! The effects' arithmetic on the CPU, in f64. `shaders/effects.wgsl` is the
//! same functions in f32, under the same names and in the same order.
//!
//! Every function reduces to the baseline's arithmetic at zero strength
//! (`tests/integration/effects.rs` checks paths bit for bit).

use crate::engine::effects::{
    DRIFT_SATURATION_S, DRIFT_WANDER_S, DriftForm, HarmonicForm, HysteresisForm, NonGaussianForm,
};

/// Harmonic waveform g(c) of a form, c = cos(kθ + φ).
pub fn harmonic_wave(form: HarmonicForm, c: f64, shape: f64, shape_mean: f64) -> f64 {
    match form {
        HarmonicForm::Bumps => c.max(0.0).powf(shape) - shape_mean,
        HarmonicForm::Square => (shape * c).tanh() / shape.tanh(),
        HarmonicForm::Fourier => c,
    }
}

/// Standardised non-Gaussian transform of a standard normal `g`, with an
/// independent standard normal `g2`; strength `s` (–).
pub fn non_gaussian(form: NonGaussianForm, s: f64, g: f64, g2: f64) -> f64 {
    match form {
        NonGaussianForm::Lognormal => {
            if s == 0.0 {
                g
            } else {
                let v = s * s;
                ((s * g).exp() - (0.5 * v).exp()) / ((v.exp() - 1.0) * v.exp()).sqrt()
            }
        }
        NonGaussianForm::TukeyH => g * (0.5 * s * g * g).exp() * (1.0 - 2.0 * s).powf(0.75),
        NonGaussianForm::Skew => (g + s * (g2 * g2 - 1.0) * std::f64::consts::FRAC_1_SQRT_2) / (1.0 + s * s).sqrt(),
        NonGaussianForm::Mixture => {
            if s == 0.0 {
                return g;
            }
            // With probability p (g2 below its p-quantile) the outlier
            // component N(3s, (1 + s)²), else N(0, 1); standardised.
            let p = MIXTURE_OUTLIER_SHARE;
            let (shift, width) = (3.0 * s, 1.0 + s);
            let x = if g2 < MIXTURE_OUTLIER_QUANTILE { shift + width * g } else { g };
            let mean = p * shift;
            let variance = p * (width * width + shift * shift) + (1.0 - p) - mean * mean;
            (x - mean) / variance.sqrt()
        }
    }
}

/// Share of `mixture` non-Gaussian noise drawn from its outlier component.
pub const MIXTURE_OUTLIER_SHARE: f64 = 0.1;
/// The standard normal's quantile at [`MIXTURE_OUTLIER_SHARE`].
pub const MIXTURE_OUTLIER_QUANTILE: f64 = -1.281_551_565_544_600_4;

/// Excess of the static coefficient after `dwell_s` seconds stuck, with
/// ageing time `ageing_s` (stiction `dwell`): `Δ (1 − e^(−t_d/τ_d))`, the
/// full `Δ` at once when `τ_d` is 0.
pub fn dwell_excess(excess: f64, dwell_s: f64, ageing_s: f64) -> f64 {
    if ageing_s == 0.0 { excess } else { excess * (1.0 - (-dwell_s.max(0.0) / ageing_s).exp()) }
}

/// Build-up of sliding friction with displacement `d` (m) since slip start,
/// over the characteristic displacement `length` (m); 1 when `length` is 0
/// and for the `lag` form (which acts through its own state).
pub fn hysteresis_factor(form: HysteresisForm, d: f64, length: f64) -> f64 {
    if length == 0.0 {
        return 1.0;
    }
    let r = d / length;
    match form {
        HysteresisForm::Tanh => r.tanh(),
        HysteresisForm::Rational => r / (r + 1.0),
        HysteresisForm::Exponential => 1.0 - (-r).exp(),
        HysteresisForm::Lag => 1.0,
    }
}

/// Drift factor of N0 at time `t` (s) from the run's start, initial
/// relative rate `rate` (1/s), relative curvature `curvature` (1/s², the
/// quadratic form's).
pub fn drift_factor(form: DriftForm, rate: f64, curvature: f64, t: f64) -> f64 {
    match form {
        DriftForm::Quadratic => (1.0 + (rate + curvature * t) * t).max(0.0),
        DriftForm::Saturating => 1.0 + rate * DRIFT_SATURATION_S * (1.0 - (-t / DRIFT_SATURATION_S).exp()),
        DriftForm::Wander => 1.0 + rate * DRIFT_WANDER_S * (t / DRIFT_WANDER_S).sin(),
        DriftForm::Linear => 1.0 + rate * t,
    }
}
