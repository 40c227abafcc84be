//! Friction with a memory: hysteresis (build-up, lag, slip and ageing laws) and stiction.

use super::*;

/// Where the released stiction's slip length starts when the baseline's
/// law has absorbed a stiction (see the stiction candidates), m: the
/// search's first step of that length (a tenth of a millimetre). It is also
/// the length over which the benchmark's withheld `decaying` stiction
/// releases its excess, so on the benchmark this start is near the truth; a
/// rig's release length may differ, and the search moves it in such steps.
const STICTION_RELEASE_START_M: f64 = 1e-4;

/// The shortest slip distance a friction memory over slip is searched at,
/// m: the integrator's steps per period grow as the inverse of it (about
/// 440 at 7 Hz and 0.1 mm on the paper's rig).
const SLIP_MEMORY_MIN_M: f64 = 5e-5;

/// The largest state coefficient B of the ageing law searched, –. Rock and
/// metal friction experiments put b between a few thousandths and a few
/// hundredths (Dieterich 1979; Marone 1998, Annu. Rev. Earth Planet. Sci.
/// 26); 0.05 leaves room above those. The term moves by B ln(θ/θ_ss), a few
/// B through a slip of the rig, so a B of tenths would turn a few
/// millimetres of slip into a friction change larger than μ itself.
const AGEING_STRENGTH_MAX: f64 = 0.05;

/// The forms of a friction memory searched, started where the data point.
pub(super) fn friction_hysteresis(effect: Effect, ctx: &Context<'_>) -> Vec<Variant> {
    let friction = ctx.has(Observable::FrictionMuMean);
    let interval = ctx.data.sample_interval_s;
    if !friction {
        return Vec::new();
    }
    let memory = |form: HysteresisForm, length_m: f64, strength: f64| FrictionHysteresis {
        form,
        length_m,
        time_constant_s: 0.0,
        strength,
    };
    // Friction that builds up after each slip start is lower while
    // the block speeds up; friction that lags a falling law in time
    // is higher then. Both are searched, the likelier first. Beside the
    // build-up, pre-sliding friction that is continuous through a
    // reversal (Dahl; the bristles of LuGre and the elasto-plastic
    // models), over the same displacements, with a rigid stick and with
    // the bristles' elastic one (a stuck block creeps with the base by a
    // share that falls with the load, which the rigid stick cannot give).
    let over_displacement = |searched: SearchedForm, form: HysteresisForm| Variant {
        effect,
        form: searched,
        params: vec![Param::log("length_m", 1.5e-4, 2.5, 1e-6, 5e-3)],
        apply: Box::new(move |m, p| {
            let mut m = m.clone();
            m.effects.friction_hysteresis = Some(memory(form, p[0], 0.0));
            m
        }),
    };
    let build_up = over_displacement(SearchedForm::BuildUp, HysteresisForm::Exponential);
    let dahl = over_displacement(SearchedForm::Dahl, HysteresisForm::Dahl);
    let bristle = over_displacement(SearchedForm::Bristle, HysteresisForm::Bristle);
    // A memory time shorter than one sample interval is not searched:
    // the branches it separates differ by less than μ moves within
    // one sample, which the records cannot resolve, and integrating
    // it stably takes a step per memory time (20 times the usual
    // steps at 0.1 ms, the bulk of a diagnosis's time).
    let lag = Variant {
        effect,
        form: SearchedForm::Lag,
        params: vec![Param::log("time_constant_s", 6.0e-3_f64.max(interval), 2.5, interval, 0.2)],
        apply: Box::new(|m, p| {
            let mut m = m.clone();
            m.effects.friction_hysteresis = Some(FrictionHysteresis {
                form: HysteresisForm::Lag,
                length_m: 0.0,
                time_constant_s: p[0],
                strength: 0.0,
            });
            m
        }),
    };
    // A memory that relaxes over a slip distance (the rate-and-state
    // laws, Ruina 1983, Dieterich 1979): the distance a lag of the
    // lag form's start would cover at the records' median slipping
    // speed.
    let median_speed = ctx.data.measured_law.map_or(0.1, |l| l.anchors_m_per_s[5]).max(1e-3);
    let length = (6.0e-3 * median_speed).clamp(SLIP_MEMORY_MIN_M, 1e-2);
    let slip = Variant {
        effect,
        form: SearchedForm::Slip,
        params: vec![Param::log("length_m", length, 2.5, SLIP_MEMORY_MIN_M, 1e-2)],
        apply: Box::new(move |m, p| {
            let mut m = m.clone();
            m.effects.friction_hysteresis = Some(memory(HysteresisForm::Slip, p[0], 0.0));
            m
        }),
    };
    let ageing = Variant {
        effect,
        form: SearchedForm::Ageing,
        params: vec![
            Param::log("strength", 0.01, 2.0, -AGEING_STRENGTH_MAX, AGEING_STRENGTH_MAX),
            Param::log("length_m", length, 2.5, SLIP_MEMORY_MIN_M, 1e-2),
        ],
        apply: Box::new(move |m, p| {
            let mut m = m.clone();
            m.effects.friction_hysteresis = Some(memory(HysteresisForm::Ageing, p[1], p[0]));
            m
        }),
    };
    if ctx.excess(Observable::FrictionHysteresis).unwrap_or(0.0) < 0.0 {
        vec![lag, slip, build_up, dahl, bristle, ageing]
    } else {
        vec![build_up, dahl, bristle, slip, lag, ageing]
    }
}

/// The forms of a stiction searched, started where the data point.
pub(super) fn stiction(effect: Effect, ctx: &Context<'_>) -> Vec<Variant> {
    let friction = ctx.has(Observable::FrictionMuMean);
    if !(friction || ctx.has(Observable::StickFraction)) {
        return Vec::new();
    }
    // A breakaway excess measured above the model's is where the
    // constant form starts. One measured *below* it says the law
    // itself has absorbed a stiction that is released while the
    // block speeds up (a steep Stribeck drop that overshoots the
    // breakaway): the search then starts from the measured excess,
    // released over a slip length, so that the law's steps can give
    // back the drop it took.
    let signature = ctx.excess(Observable::FrictionStictionExcess).unwrap_or(0.1);
    let absorbed = signature < 0.0;
    let excess = if absorbed { ctx.measured(Observable::FrictionStictionExcess).unwrap_or(0.1) } else { signature }
        .clamp(0.02, 0.6);
    let release = if absorbed { STICTION_RELEASE_START_M } else { 0.0 };
    let stiction = |form: StictionForm, excess: f64, release: f64, dwell: f64| Stiction {
        form,
        excess,
        release_length_m: release,
        dwell_time_s: dwell,
    };
    vec![
        Variant {
            effect,
            form: SearchedForm::Constant,
            params: vec![
                Param::log("excess", excess, 1.6, 0.005, 1.5),
                Param::linear("release_length_m", release, 1e-4, 0.0, 1e-3),
            ],
            apply: Box::new(move |m, p| {
                let mut m = m.clone();
                m.effects.stiction = Some(stiction(StictionForm::Constant, p[0], p[1], 0.0));
                m
            }),
        },
        Variant {
            effect,
            form: SearchedForm::Dwell,
            params: vec![
                Param::log("excess", excess, 1.6, 0.005, 1.5),
                Param::log("dwell_time_s", 0.01, 3.0, 1e-4, 1.0),
            ],
            apply: Box::new(move |m, p| {
                let mut m = m.clone();
                m.effects.stiction = Some(stiction(StictionForm::Dwell, p[0], 0.0, p[1]));
                m
            }),
        },
    ]
}
