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
    NormalForceWander,
    FrictionSlipSamples,
    FrictionMuMean,
    FrictionResidualStd,
    FrictionResidualSkewness,
    FrictionResidualTailWeight,
    FrictionResidualAutocorrLag1,
    FrictionResidualAutocorrLag10,
    FrictionTrendPerS,
    FrictionHysteresis,
    FrictionBreakawayMean,
    FrictionLowSpeedMuMean,
    FrictionStictionExcess,
    StickFraction,
}

/// The unit an observable is measured in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unit {
    /// m (shown in mm).
    Metre,
    /// m² (shown in mm²).
    SquareMetre,
    /// Degrees.
    Degree,
    /// Degrees².
    SquareDegree,
    /// N.
    Newton,
    /// N².
    SquareNewton,
    /// N/s.
    NewtonPerSecond,
    /// 1/s.
    PerSecond,
    /// 1/s².
    PerSecondSquared,
    /// A count.
    Count,
    /// A dimensionless number.
    Dimensionless,
}

impl Unit {
    /// A value in this unit as a person reads it: lengths in mm, their
    /// squares in mm², with the unit's symbol; `sig` formats the number.
    pub fn show(self, v: f64, sig: impl Fn(f64) -> String) -> String {
        match self {
            Unit::Metre => format!("{} mm", sig(v * 1e3)),
            Unit::SquareMetre => format!("{} mm²", sig(v * 1e6)),
            Unit::Degree => format!("{}°", sig(v)),
            Unit::SquareDegree => format!("{} deg²", sig(v)),
            Unit::Newton => format!("{} N", sig(v)),
            Unit::SquareNewton => format!("{} N²", sig(v)),
            Unit::NewtonPerSecond => format!("{} N/s", sig(v)),
            Unit::PerSecond => format!("{} 1/s", sig(v)),
            Unit::PerSecondSquared => format!("{} 1/s²", sig(v)),
            Unit::Count | Unit::Dimensionless => sig(v),
        }
    }
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
    pub const ALL: [Observable; 31] = [
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
        Observable::NormalForceWander,
        Observable::FrictionSlipSamples,
        Observable::FrictionMuMean,
        Observable::FrictionResidualStd,
        Observable::FrictionResidualSkewness,
        Observable::FrictionResidualTailWeight,
        Observable::FrictionResidualAutocorrLag1,
        Observable::FrictionResidualAutocorrLag10,
        Observable::FrictionTrendPerS,
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
            Observable::NormalForceWander => "normal_force_wander",
            Observable::FrictionSlipSamples => "friction_slip_samples",
            Observable::FrictionMuMean => "friction_mu_mean",
            Observable::FrictionResidualStd => "friction_residual_std",
            Observable::FrictionResidualSkewness => "friction_residual_skewness",
            Observable::FrictionResidualTailWeight => "friction_residual_tail_weight",
            Observable::FrictionResidualAutocorrLag1 => "friction_residual_autocorr_lag1",
            Observable::FrictionResidualAutocorrLag10 => "friction_residual_autocorr_lag10",
            Observable::FrictionTrendPerS => "friction_trend_per_s",
            Observable::FrictionHysteresis => "friction_hysteresis",
            Observable::FrictionBreakawayMean => "friction_breakaway_mean",
            Observable::FrictionLowSpeedMuMean => "friction_low_speed_mu_mean",
            Observable::FrictionStictionExcess => "friction_stiction_excess",
            Observable::StickFraction => "stick_fraction",
        }
    }

    /// Its unit.
    pub fn unit(self) -> Unit {
        use Observable as O;
        match self {
            O::PeakMeanM => Unit::Metre,
            O::PeakVarM2 => Unit::SquareMetre,
            O::PhaseMeanDeg => Unit::Degree,
            O::PhaseVarDeg2 => Unit::SquareDegree,
            O::NormalForceMeanN
            | O::NormalForceHarmonic1N
            | O::NormalForceHarmonic2N
            | O::NormalForceHarmonic3N
            | O::NormalForceHarmonic4N => Unit::Newton,
            O::NormalForceVarN2 | O::NormalForceResidualVarN2 => Unit::SquareNewton,
            O::NormalForceDriftNPerS => Unit::NewtonPerSecond,
            O::NormalForceDriftPerS | O::PeakTrendPerS | O::FrictionTrendPerS => Unit::PerSecond,
            O::NormalForceCurvaturePerS2 => Unit::PerSecondSquared,
            O::NormalForceWander => Unit::Dimensionless,
            O::PeakCount | O::FrictionSlipSamples => Unit::Count,
            O::PeakSkewness
            | O::FrictionMuMean
            | O::FrictionResidualStd
            | O::FrictionResidualSkewness
            | O::FrictionResidualTailWeight
            | O::FrictionResidualAutocorrLag1
            | O::FrictionResidualAutocorrLag10
            | O::FrictionHysteresis
            | O::FrictionBreakawayMean
            | O::FrictionLowSpeedMuMean
            | O::FrictionStictionExcess
            | O::StickFraction => Unit::Dimensionless,
        }
    }

    /// What it is, in words a reader of a report understands.
    pub fn label(self) -> &'static str {
        use Observable as O;
        match self {
            O::PeakCount => "number of peaks",
            O::PeakMeanM => "mean peak amplitude",
            O::PeakVarM2 => "variance of the peak amplitude",
            O::PeakSkewness => "skewness of the peak amplitude",
            O::PeakTrendPerS => "trend of the peaks over the record",
            O::PhaseMeanDeg => "phase lag behind the base",
            O::PhaseVarDeg2 => "variance of the phase lag",
            O::NormalForceMeanN => "mean normal force",
            O::NormalForceVarN2 => "variance of the normal force",
            O::NormalForceHarmonic1N => "normal force at 1× the excitation",
            O::NormalForceHarmonic2N => "normal force at 2× the excitation",
            O::NormalForceHarmonic3N => "normal force at 3× the excitation",
            O::NormalForceHarmonic4N => "normal force at 4× the excitation",
            O::NormalForceResidualVarN2 => "normal force's random variance",
            O::NormalForceDriftNPerS => "normal force's drift",
            O::NormalForceDriftPerS => "normal force's relative drift",
            O::NormalForceCurvaturePerS2 => "normal force's drift curvature",
            O::NormalForceWander => "normal force's slow wander",
            O::FrictionSlipSamples => "slipping samples",
            O::FrictionMuMean => "mean friction coefficient while slipping",
            O::FrictionResidualStd => "spread of the friction coefficient's random part",
            O::FrictionResidualSkewness => "skewness of the friction's random part",
            O::FrictionResidualTailWeight => "tail weight of the friction's random part",
            O::FrictionResidualAutocorrLag1 => "friction noise's correlation over one sample",
            O::FrictionResidualAutocorrLag10 => "friction noise's correlation over ten samples",
            O::FrictionTrendPerS => "trend of the friction over the record",
            O::FrictionHysteresis => "friction speeding up less slowing down",
            O::FrictionBreakawayMean => "friction coefficient at breakaway",
            O::FrictionLowSpeedMuMean => "friction coefficient at low sliding speed",
            O::FrictionStictionExcess => "breakaway above low-speed friction",
            O::StickFraction => "share of time stuck",
        }
    }

    /// The observable whose [`Observable::name`] is `name`, if any.
    pub fn named(name: &str) -> Option<Observable> {
        Observable::ALL.into_iter().find(|o| o.name() == name)
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
            | Observable::NormalForceCurvaturePerS2
            | Observable::NormalForceWander => MotionPhase::NormalForce,
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
            | Observable::FrictionResidualAutocorrLag10
            | Observable::FrictionTrendPerS => MotionPhase::SlipNoise,
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
