//! The observables the diagnosis compares: one name each, the motion phase
//! it describes, and whether it is scored. The same [`Observable`] keys the
//! features of measured and simulated records, the scores and the report.

use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// One observable of a record or a summary row. Names carry units (`_m`,
/// `_n`, `_per_s`, …); dimensionless ones have none.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Observable {
    PeakCount,
    PeakMeanM,
    PeakVarM2,
    PeakSkewness,
    PeakTrendPerS,
    PhaseMeanDeg,
    PhaseVarDeg2,
    NormalForceMeanN,
    NormalForceVarN2,
    NormalForceHarmonic1N,
    NormalForceHarmonic2N,
    NormalForceHarmonic3N,
    NormalForceHarmonic4N,
    NormalForceResidualVarN2,
    NormalForceDriftNPerS,
    NormalForceDriftPerS,
    NormalForceCurvaturePerS2,
    FrictionSlipSamples,
    FrictionMuMean,
    FrictionResidualStd,
    FrictionResidualSkewness,
    FrictionResidualTailWeight,
    FrictionResidualAutocorrLag1,
    FrictionResidualAutocorrLag10,
    FrictionHysteresis,
    FrictionBreakawayMean,
    FrictionLowSpeedMuMean,
    FrictionStictionExcess,
    StickFraction,
}

/// Which part of the motion an observable describes (for `locations`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MotionPhase {
    /// The per-period peak amplitude, over whole cycles.
    Peak,
    /// The phase of the response's fundamental behind the base, per cycle.
    Fundamental,
    /// The normal force, over whole cycles.
    NormalForce,
    /// Sliding: accelerating against decelerating branch.
    SlipBranches,
    /// The transition from stick to slip.
    Breakaway,
    /// Sliding just above zero velocity.
    LowSpeedSlip,
    /// At rest.
    Stick,
    /// Sliding: the friction coefficient's random part.
    SlipNoise,
}

impl MotionPhase {
    /// How the report describes the phase.
    pub fn describe(self) -> &'static str {
        match self {
            MotionPhase::Peak => "whole cycle: per-period peak amplitude",
            MotionPhase::Fundamental => "whole cycle: phase of the response's fundamental behind the base",
            MotionPhase::NormalForce => "whole cycle: normal force",
            MotionPhase::SlipBranches => "slip: accelerating against decelerating branch",
            MotionPhase::Breakaway => "stick to slip: breakaway",
            MotionPhase::LowSpeedSlip => "slip: just above zero velocity",
            MotionPhase::Stick => "stick",
            MotionPhase::SlipNoise => "slip: random part of the friction coefficient",
        }
    }
}

impl Observable {
    /// Whether it is a statistic of the response itself (the peak amplitude's
    /// mean and variance, the phase's mean and variance): what a fitted
    /// model is for predicting, as opposed to the friction and normal-force
    /// features that attribute a gap to an effect.
    pub fn is_response(self) -> bool {
        matches!(
            self,
            Observable::PeakMeanM | Observable::PeakVarM2 | Observable::PhaseMeanDeg | Observable::PhaseVarDeg2
        )
    }

    /// Every observable, in the order of a record's features.
    pub const ALL: [Observable; 29] = [
        Observable::PeakCount,
        Observable::PeakMeanM,
        Observable::PeakVarM2,
        Observable::PeakSkewness,
        Observable::PeakTrendPerS,
        Observable::PhaseMeanDeg,
        Observable::PhaseVarDeg2,
        Observable::NormalForceMeanN,
        Observable::NormalForceVarN2,
        Observable::NormalForceHarmonic1N,
        Observable::NormalForceHarmonic2N,
        Observable::NormalForceHarmonic3N,
        Observable::NormalForceHarmonic4N,
        Observable::NormalForceResidualVarN2,
        Observable::NormalForceDriftNPerS,
        Observable::NormalForceDriftPerS,
        Observable::NormalForceCurvaturePerS2,
        Observable::FrictionSlipSamples,
        Observable::FrictionMuMean,
        Observable::FrictionResidualStd,
        Observable::FrictionResidualSkewness,
        Observable::FrictionResidualTailWeight,
        Observable::FrictionResidualAutocorrLag1,
        Observable::FrictionResidualAutocorrLag10,
        Observable::FrictionHysteresis,
        Observable::FrictionBreakawayMean,
        Observable::FrictionLowSpeedMuMean,
        Observable::FrictionStictionExcess,
        Observable::StickFraction,
    ];

    /// The name used in reports.
    pub fn name(self) -> &'static str {
        match self {
            Observable::PeakCount => "peak_count",
            Observable::PeakMeanM => "peak_mean_m",
            Observable::PeakVarM2 => "peak_var_m2",
            Observable::PeakSkewness => "peak_skewness",
            Observable::PeakTrendPerS => "peak_trend_per_s",
            Observable::PhaseMeanDeg => "phase_mean_deg",
            Observable::PhaseVarDeg2 => "phase_var_deg2",
            Observable::NormalForceMeanN => "normal_force_mean_n",
            Observable::NormalForceVarN2 => "normal_force_var_n2",
            Observable::NormalForceHarmonic1N => "normal_force_harmonic1_n",
            Observable::NormalForceHarmonic2N => "normal_force_harmonic2_n",
            Observable::NormalForceHarmonic3N => "normal_force_harmonic3_n",
            Observable::NormalForceHarmonic4N => "normal_force_harmonic4_n",
            Observable::NormalForceResidualVarN2 => "normal_force_residual_var_n2",
            Observable::NormalForceDriftNPerS => "normal_force_drift_n_per_s",
            Observable::NormalForceDriftPerS => "normal_force_drift_per_s",
            Observable::NormalForceCurvaturePerS2 => "normal_force_curvature_per_s2",
            Observable::FrictionSlipSamples => "friction_slip_samples",
            Observable::FrictionMuMean => "friction_mu_mean",
            Observable::FrictionResidualStd => "friction_residual_std",
            Observable::FrictionResidualSkewness => "friction_residual_skewness",
            Observable::FrictionResidualTailWeight => "friction_residual_tail_weight",
            Observable::FrictionResidualAutocorrLag1 => "friction_residual_autocorr_lag1",
            Observable::FrictionResidualAutocorrLag10 => "friction_residual_autocorr_lag10",
            Observable::FrictionHysteresis => "friction_hysteresis",
            Observable::FrictionBreakawayMean => "friction_breakaway_mean",
            Observable::FrictionLowSpeedMuMean => "friction_low_speed_mu_mean",
            Observable::FrictionStictionExcess => "friction_stiction_excess",
            Observable::StickFraction => "stick_fraction",
        }
    }

    /// The normal-force harmonic at `k`× the excitation frequency (`k` in 1..=4).
    pub fn normal_force_harmonic(k: usize) -> Observable {
        match k {
            1 => Observable::NormalForceHarmonic1N,
            2 => Observable::NormalForceHarmonic2N,
            3 => Observable::NormalForceHarmonic3N,
            _ => Observable::NormalForceHarmonic4N,
        }
    }

    /// Whether the observable is scored. Counts are not, nor what the
    /// calibration sets by construction (the normal force's level, spread
    /// and drift in newtons).
    pub fn scored(self) -> bool {
        !matches!(
            self,
            Observable::PeakCount
                | Observable::FrictionSlipSamples
                | Observable::NormalForceMeanN
                | Observable::NormalForceVarN2
                | Observable::NormalForceDriftNPerS
        )
    }

    /// Whether the observable is an angle in degrees (compared modulo 360°).
    pub fn is_angle_deg(self) -> bool {
        self == Observable::PhaseMeanDeg
    }

    /// The motion phase the observable describes.
    pub fn phase(self) -> MotionPhase {
        match self {
            Observable::PeakCount
            | Observable::PeakMeanM
            | Observable::PeakVarM2
            | Observable::PeakSkewness
            | Observable::PeakTrendPerS => MotionPhase::Peak,
            Observable::PhaseMeanDeg | Observable::PhaseVarDeg2 => MotionPhase::Fundamental,
            Observable::NormalForceMeanN
            | Observable::NormalForceVarN2
            | Observable::NormalForceHarmonic1N
            | Observable::NormalForceHarmonic2N
            | Observable::NormalForceHarmonic3N
            | Observable::NormalForceHarmonic4N
            | Observable::NormalForceResidualVarN2
            | Observable::NormalForceDriftNPerS
            | Observable::NormalForceDriftPerS
            | Observable::NormalForceCurvaturePerS2 => MotionPhase::NormalForce,
            Observable::FrictionHysteresis => MotionPhase::SlipBranches,
            Observable::FrictionBreakawayMean | Observable::FrictionStictionExcess => MotionPhase::Breakaway,
            Observable::FrictionLowSpeedMuMean => MotionPhase::LowSpeedSlip,
            Observable::StickFraction => MotionPhase::Stick,
            Observable::FrictionSlipSamples
            | Observable::FrictionMuMean
            | Observable::FrictionResidualStd
            | Observable::FrictionResidualSkewness
            | Observable::FrictionResidualTailWeight
            | Observable::FrictionResidualAutocorrLag1
            | Observable::FrictionResidualAutocorrLag10 => MotionPhase::SlipNoise,
        }
    }
}

impl std::fmt::Display for Observable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Ordered by name, so maps keyed by observables iterate alphabetically.
impl Ord for Observable {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.name().cmp(other.name())
    }
}

impl PartialOrd for Observable {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Serialize for Observable {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.name())
    }
}

impl<'de> Deserialize<'de> for Observable {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Observable, D::Error> {
        let name = String::deserialize(deserializer)?;
        Observable::ALL
            .into_iter()
            .find(|o| o.name() == name)
            .ok_or_else(|| serde::de::Error::custom(format!("unknown observable `{name}`")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_phases_cover_every_observable() {
        let mut names: Vec<&str> = Observable::ALL.iter().map(|o| o.name()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), Observable::ALL.len());
        assert_eq!(Observable::ALL.iter().filter(|o| !o.scored()).count(), 5);
        assert_eq!(Observable::normal_force_harmonic(2).name(), "normal_force_harmonic2_n");
    }
}
