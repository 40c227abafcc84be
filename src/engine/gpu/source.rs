//! The WGSL the kernels are compiled from: a preamble of constants
//! generated from the Rust ones (so the two sides cannot drift apart), then
//! the shader files, which mirror the Rust files function for function
//! under the same names (`tests/integration/twins.rs` checks it):
//!
//! | shader | Rust |
//! | --- | --- |
//! | `shaders/rng.wgsl` | `engine/rng.rs` |
//! | `shaders/effects.wgsl` | `engine/cpu/effects.rs` |
//! | `shaders/oscillator.wgsl` | `engine/cpu/oscillator/` |
//! | `shaders/reduce.wgsl` | `engine/reduce.rs` |
//! | `shaders/ensemble.wgsl` | `engine/gpu/shared.rs`, `engine/gpu/ensemble.rs` |
//! | `shaders/check.wgsl` | `engine/gpu/check.rs` |

use std::fmt::Write;

use crate::engine::effects::{
    AGEING_CUTOFF_SPEED_M_PER_S, AGEING_FLOOR_SPEED_M_PER_S, ColourForm, DRIFT_SATURATION_S, DRIFT_WANDER_S, DriftForm,
    Form, HarmonicForm, HysteresisForm, LoadForm, MIXTURE_OUTLIER_QUANTILE, MIXTURE_OUTLIER_SHARE, Memory,
    NonGaussianForm, STICTION_DECAY_M, StictionForm,
};
use crate::engine::gpu::shared::EffectParams;
use crate::engine::gpu::{MAX_WORKGROUPS_PER_DIMENSION, WORKGROUP_SIZE};
use crate::engine::reduce::{HISTOGRAM_BINS, PHASE_QUANTA, QUANTISE_LIMIT, STICK_UNITS_PER_PERIOD};
use crate::engine::rng;

// The kernel's own settings, written into the preamble (where they differ
// from the f64 reference's, on purpose: the table in `engine/cpu/oscillator/mod.rs`).

/// Events one invocation handles within a segment before it forces progress
/// (the CPU allows 64; see the table in `engine/cpu/oscillator/mod.rs`).
pub const MAX_EVENTS_PER_SEGMENT: u32 = 16;
/// Halvings of the step that probe for motion after a start from rest (CPU: 60).
pub const PROBE_HALVINGS: u32 = 30;
/// Illinois iterations locating a velocity zero (CPU: 100).
pub const ILLINOIS_ITERATIONS: u32 = 40;
/// Illinois stops when the bracket is below this fraction of the step (CPU: 1e-15).
pub const ILLINOIS_TOLERANCE: f64 = 2e-7;
/// Within a span, the base's trig is recomputed exactly every this many
/// steps (the CPU carries it through the whole span: f32 rotations drift).
pub const TRIG_REFRESH_STEPS: u32 = 16;
/// Words of one point's accumulator in `reduce.wgsl`.
pub const ACCUMULATOR_WORDS: usize = 18;

const RNG: &str = include_str!("../../../shaders/rng.wgsl");
const EFFECTS: &str = include_str!("../../../shaders/effects.wgsl");
const OSCILLATOR: &str = include_str!("../../../shaders/oscillator.wgsl");
const REDUCE: &str = include_str!("../../../shaders/reduce.wgsl");
const ENSEMBLE: &str = include_str!("../../../shaders/ensemble.wgsl");
const CHECK: &str = include_str!("../../../shaders/check.wgsl");

/// The ensemble kernel: constants, noise, effects, oscillator, reduction
/// and the entry points.
pub fn ensemble_wgsl() -> String {
    [constants().as_str(), RNG, EFFECTS, OSCILLATOR, REDUCE, ENSEMBLE].join("\n")
}

/// The declaration of the effects' uniform in `ensemble.wgsl`.
const EFFECTS_BINDING: &str = "@group(0) @binding(6) var<uniform> effects: EffectParams;";

/// The ensemble kernel for a model without effects: every field of the
/// effects' uniform but the noise interval is a constant of
/// [`EffectParams::without_effects`], so the shader compiler drops the
/// effects' branches and their registers. On lavapipe the throughput
/// bench's noisy workload runs about twice as fast in it (29.7 M against
/// 13.3 M realisation-steps/s); the answers are the same bit for bit (the
/// zero-strength forms, which take the general kernel, are checked path by
/// path against the baseline, which takes this one).
pub fn ensemble_wgsl_without_effects() -> String {
    let general = ensemble_wgsl();
    assert!(general.contains(EFFECTS_BINDING), "ensemble.wgsl declares the effects' uniform as expected");
    let off = EffectParams::without_effects();
    let values = bytemuck::bytes_of(&off).chunks_exact(4).map(|w| {
        let word = [w[0], w[1], w[2], w[3]];
        (u32::from_ne_bytes(word), f32::from_ne_bytes(word))
    });
    let literals: Vec<String> = struct_fields(ENSEMBLE, "EffectParams")
        .into_iter()
        .zip(values)
        .map(|((_, ty), (word, float))| if ty == "f32" { format!("{float:?}f") } else { format!("{word}u") })
        .collect();
    let constant = format!(
        "@group(0) @binding(6) var<uniform> effects_in: EffectParams;\nconst effects = EffectParams({});",
        literals.join(", ")
    );
    general.replace(EFFECTS_BINDING, &constant).replace("effects.noise_interval_s", "effects_in.noise_interval_s")
}

/// The start of the kernel's `memory_form()`.
const MEMORY_FORM_FN: &str = "fn memory_form() -> i32 {";

/// The ensemble kernel with its friction memory fixed: `memory_form()`
/// returns `memory`'s constant instead of deciding from the effects'
/// uniform (which gives the same code: [`EffectParams::memory`]), so the
/// shader compiler drops the other memories' branches. lavapipe executes
/// both sides of a branch, uniform or not: with the memories decided at run
/// time a model with stiction alone took 36% longer than before the slip
/// and ageing forms (7.7 s of CPU against 5.6 s on a 2 × 2 grid of 512
/// realisations); with the memory fixed, as long as before (5.6–6.0 s).
pub(crate) fn ensemble_wgsl_with_memory(memory: Memory) -> String {
    let general = ensemble_wgsl();
    let start = general.find(MEMORY_FORM_FN).expect("oscillator.wgsl defines memory_form()");
    let end = start + general[start..].find("\n}\n").expect("memory_form() ends") + 3;
    let name = Memory::ALL.iter().find(|(m, _)| *m == memory).map(|(_, name)| *name).expect("every memory is named");
    format!("{}{MEMORY_FORM_FN}\n    return MEMORY_{name};\n}}\n{}", &general[..start], &general[end..])
}

/// The (name, type) of each field of WGSL struct `name` in `source`.
fn struct_fields(source: &str, name: &str) -> Vec<(String, String)> {
    let start = source.find(&format!("struct {name} {{")).unwrap_or_else(|| panic!("struct {name} in the WGSL"));
    source[start..]
        .lines()
        .skip(1)
        .take_while(|line| !line.trim_start().starts_with('}'))
        .filter_map(|line| {
            let (field, ty) = line.trim().trim_end_matches(',').split_once(':')?;
            Some((field.trim().to_string(), ty.trim().to_string()))
        })
        .collect()
}

/// The generator check kernel: constants, noise and a kernel writing raw words.
pub fn check_wgsl() -> String {
    [constants().as_str(), RNG, CHECK].join("\n")
}

/// An f32 literal that parses back to exactly `value as f32` (the same
/// rounding naga applies to an abstract float).
fn f32_literal(value: f64) -> String {
    format!("{:?}f", value as f32)
}

/// `const PREFIX_VARIANT: u32 = code;` for every form of `F`, the variant
/// named as in model files (`tukey_h` → `NON_GAUSSIAN_FORM_TUKEY_H`).
fn form_constants<F: Form>(out: &mut String, prefix: &str) {
    for &form in F::ALL {
        let name = serde_json::to_value(form).ok().and_then(|v| v.as_str().map(str::to_uppercase)).unwrap_or_default();
        writeln!(out, "const {prefix}_{name}: u32 = {}u;", form.code()).expect("writing to a String");
    }
}

/// The generated preamble.
fn constants() -> String {
    let mut s = String::from("// Generated by src/engine/gpu/source.rs from the Rust constants.\n");
    let mut u32s = |name: &str, value: u32| writeln!(s, "const {name}: u32 = {value}u;").expect("writing to a String");
    u32s("WORKGROUP_SIZE", WORKGROUP_SIZE);
    u32s("MAX_WORKGROUPS_PER_DIMENSION", MAX_WORKGROUPS_PER_DIMENSION);
    u32s("PHILOX_M0", rng::PHILOX_M0);
    u32s("PHILOX_M1", rng::PHILOX_M1);
    u32s("PHILOX_W0", rng::PHILOX_W0);
    u32s("PHILOX_W1", rng::PHILOX_W1);
    u32s("STREAM_MAIN", rng::STREAM_MAIN);
    u32s("STREAM_COLOUR", rng::STREAM_COLOUR);
    u32s("STREAM_DRIFT", rng::STREAM_DRIFT);
    u32s("HISTOGRAM_BINS", HISTOGRAM_BINS);
    u32s("ACCUMULATOR_WORDS", ACCUMULATOR_WORDS as u32);
    u32s("MAX_EVENTS_PER_SEGMENT", MAX_EVENTS_PER_SEGMENT);
    u32s("PROBE_HALVINGS", PROBE_HALVINGS);
    u32s("ILLINOIS_ITERATIONS", ILLINOIS_ITERATIONS);
    u32s("TRIG_REFRESH_STEPS", TRIG_REFRESH_STEPS);
    for (name, value) in [
        ("ILLINOIS_TOLERANCE", ILLINOIS_TOLERANCE),
        ("QUANTISE_LIMIT", f64::from(QUANTISE_LIMIT)),
        ("STICK_UNITS_PER_PERIOD", STICK_UNITS_PER_PERIOD),
        ("PHASE_QUANTA", PHASE_QUANTA),
        ("DRIFT_SATURATION_S", DRIFT_SATURATION_S),
        ("DRIFT_WANDER_S", DRIFT_WANDER_S),
        ("STICTION_DECAY_M", STICTION_DECAY_M),
        ("AGEING_CUTOFF_SPEED_M_PER_S", AGEING_CUTOFF_SPEED_M_PER_S),
        ("AGEING_FLOOR_SPEED_M_PER_S", AGEING_FLOOR_SPEED_M_PER_S),
        ("MIXTURE_OUTLIER_SHARE", MIXTURE_OUTLIER_SHARE),
        ("MIXTURE_OUTLIER_QUANTILE", MIXTURE_OUTLIER_QUANTILE),
    ] {
        writeln!(s, "const {name}: f32 = {};", f32_literal(value)).expect("writing to a String");
    }
    form_constants::<HarmonicForm>(&mut s, "HARMONIC_FORM");
    form_constants::<NonGaussianForm>(&mut s, "NON_GAUSSIAN_FORM");
    form_constants::<HysteresisForm>(&mut s, "HYSTERESIS_FORM");
    form_constants::<ColourForm>(&mut s, "COLOUR_FORM");
    form_constants::<StictionForm>(&mut s, "STICTION_FORM");
    form_constants::<LoadForm>(&mut s, "LOAD_FORM");
    form_constants::<DriftForm>(&mut s, "DRIFT_FORM");
    for (memory, name) in Memory::ALL {
        writeln!(s, "const MEMORY_{name}: i32 = {};", memory as i32).expect("writing to a String");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_kernel_without_effects_has_every_field_of_their_uniform_as_a_constant() {
        let fields = struct_fields(ENSEMBLE, "EffectParams");
        assert_eq!(fields.len() * 4, std::mem::size_of::<EffectParams>());
        assert!(fields.iter().all(|(_, ty)| ty == "u32" || ty == "f32"), "{fields:?}");
        let source = ensemble_wgsl_without_effects();
        let constant = source.lines().find(|l| l.starts_with("const effects = ")).expect("the constant");
        assert_eq!(constant.matches(", ").count() + 1, fields.len(), "{constant}");
        // The off uniform: colour share 1, hold interval 1, bump shape 2.
        assert!(constant.starts_with("const effects = EffectParams(0u, 2.0f, "), "{constant}");
        assert!(!source.contains("var<uniform> effects: "));
        assert!(source.contains("effects_in.noise_interval_s"));
    }

    #[test]
    fn a_kernel_with_its_memory_fixed_returns_it_and_is_otherwise_the_kernel() {
        let general = ensemble_wgsl();
        for (memory, name) in Memory::ALL {
            let fixed = ensemble_wgsl_with_memory(memory);
            let body = format!("{MEMORY_FORM_FN}\n    return MEMORY_{name};\n}}\n");
            assert!(fixed.contains(&body), "{name}");
            let start = general.find(MEMORY_FORM_FN).unwrap();
            assert_eq!(fixed[..start], general[..start]);
            let rest = |s: &str| s[s.find(MEMORY_FORM_FN).unwrap()..].split_once("\n}\n").unwrap().1.to_string();
            assert_eq!(rest(&fixed), rest(&general));
        }
        assert!(constants().contains("const MEMORY_AGEING: i32 = 3;"));
    }

    #[test]
    fn constants_name_every_form_and_round_trip_floats() {
        let c = constants();
        assert!(c.contains("const NON_GAUSSIAN_FORM_TUKEY_H: u32 = 2u;"), "{c}");
        assert!(c.contains("const COLOUR_FORM_TWO_SCALE: u32 = 2u;"), "{c}");
        assert!(c.contains("const HYSTERESIS_FORM_SLIP: u32 = 4u;"), "{c}");
        assert!(c.contains("const HYSTERESIS_FORM_AGEING: u32 = 5u;"), "{c}");
        assert!(c.contains("const LOAD_FORM_ADHESION: u32 = 5u;"), "{c}");
        assert!(c.contains("const LOAD_FORM_SCALED: u32 = 6u;"), "{c}");
        assert!(c.contains("const HISTOGRAM_BINS: u32 = 2048u;"), "{c}");
        let literal = f32_literal(STICTION_DECAY_M);
        let parsed: f32 = literal.trim_end_matches('f').parse().unwrap();
        assert_eq!(parsed, STICTION_DECAY_M as f32);
    }
}
