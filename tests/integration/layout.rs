//! The host structs in `src/engine/gpu/shared.rs` must have exactly the memory layout of
//! the WGSL structs of the same name, as naga lays them out: same size, same
//! members in the same order at the same offsets. Shared structs hold only
//! 4-byte scalars (f32/u32/i32), so `#[repr(C)]` and WGSL agree without
//! implicit padding; this test checks that rule too.

use std::mem::{align_of, offset_of, size_of};

use naga::proc::Layouter;
use naga::{Module, Scalar, ScalarKind, TypeInner};
use stickslip::engine::gpu::shared::{CheckParams, EffectParams, GridPoint, Params, PathState};
use stickslip::engine::gpu::source::{check_wgsl, ensemble_wgsl};

/// One Rust field: name, byte offset, byte size.
struct RustField {
    name: &'static str,
    offset: usize,
    size: usize,
}

/// A Rust struct as the test sees it.
struct RustStruct {
    name: &'static str,
    size: usize,
    align: usize,
    fields: Vec<RustField>,
}

fn field_size<T, F>(_: fn(&T) -> &F) -> usize {
    size_of::<F>()
}

/// Lists the fields of a `#[repr(C)]` struct with offsets and sizes. The
/// field list is written by hand, so `check_rust_fields_tile` verifies that
/// the listed fields cover the struct with no gap, which catches a field added
/// on the Rust side but missing here.
macro_rules! rust_struct {
    ($ty:ident { $($field:ident),* $(,)? }) => {
        RustStruct {
            name: stringify!($ty),
            size: size_of::<$ty>(),
            align: align_of::<$ty>(),
            fields: vec![$(RustField {
                name: stringify!($field),
                offset: offset_of!($ty, $field),
                size: field_size(|s: &$ty| &s.$field),
            }),*],
        }
    };
}

/// Each host struct and the shader constant that defines its WGSL twin.
fn rust_structs() -> Vec<(RustStruct, &'static str)> {
    vec![
        (
            rust_struct!(Params {
                mass_kg,
                stiffness_n_per_m,
                damping_n_s_per_m,
                base_amplitude_m,
                friction_a,
                friction_b,
                friction_c_s_per_m,
                friction_d_s2_per_m2,
                friction_sigma,
                normal_force_sigma_n,
                warmup_cycles,
                seed_lo,
                seed_hi,
                invocations,
                realisations_per_point,
                realisation_offset,
                first_cycle,
                cycles,
                point_offset,
                record_peaks,
                record_samples,
                sample_slots,
            }),
            "ensemble.wgsl",
        ),
        (
            rust_struct!(GridPoint {
                omega_rad_per_s,
                period_s,
                normal_force_mean_n,
                noise_interval_whole,
                noise_interval_frac,
                initial_x_m,
                initial_v_m_per_s,
                peak_centre_m,
                inv_quantum_per_m,
                histogram_lo_m,
                histogram_bins_per_m,
                friction_offset,
                non_gaussian_strength,
                non_gaussian_cubic,
                phase_ref_rad,
                harmonic_amplitude_1_n,
                harmonic_amplitude_2_n,
                harmonic_amplitude_3_n,
                harmonic_amplitude_4_n,
                friction_scale,
                steps_per_period,
                realisation_offset,
                drift_start_s,
            }),
            "ensemble.wgsl",
        ),
        (
            rust_struct!(PathState {
                x_m,
                v_m_per_s,
                mode,
                period,
                interval,
                next_boundary_whole,
                next_boundary_frac,
                friction_noise,
                normal_force_n,
                stick_time_s,
                slip_start_x_m,
                colour_state,
                interval_phase,
                stiction_excess,
                colour_state_1,
                colour_state_2,
                memory,
                stick_since_s,
                ageing_excess,
                drift_walk,
            }),
            "ensemble.wgsl",
        ),
        (
            rust_struct!(EffectParams {
                harmonic_form,
                harmonic_shape,
                harmonic_shape_mean,
                non_gaussian_form,
                harmonic_phase_1_rad,
                harmonic_phase_2_rad,
                harmonic_phase_3_rad,
                harmonic_phase_4_rad,
                hysteresis_form,
                hysteresis_length_m,
                hysteresis_lag_s,
                colour_form,
                colour_rho,
                colour_share,
                colour_rho_1,
                colour_rho_2,
                colour_rho_3,
                colour_hold_intervals,
                stiction_form,
                stiction_excess,
                stiction_release_m,
                stiction_dwell_s,
                drift_form,
                drift_rate_per_s,
                noise_interval_s,
                drift_curvature_per_s2,
                hysteresis_strength,
                adhesion_force_n,
            }),
            "ensemble.wgsl",
        ),
        (rust_struct!(CheckParams { seed_lo, seed_hi, first, count }), "check.wgsl"),
    ]
}

fn parse(label: &str, source: &str) -> Module {
    naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{label} does not parse:\n{}", e.emit_to_string(source)))
}

/// The listed Rust fields are in order, contiguous, and cover the struct.
fn check_rust_fields_tile(s: &RustStruct) {
    let mut end = 0;
    for f in &s.fields {
        assert_eq!(
            f.offset, end,
            "{}: Rust field `{}` at offset {} but the previous field ends at {end} (padding or a field missing from the test's list)",
            s.name, f.name, f.offset
        );
        end = f.offset + f.size;
    }
    assert_eq!(
        end, s.size,
        "{}: the listed Rust fields end at byte {end} but size_of is {} (a Rust field is missing from the test's list)",
        s.name, s.size
    );
}

#[test]
fn rust_and_wgsl_structs_have_the_same_layout() {
    let modules: Vec<(&str, Module)> = vec![
        ("ensemble.wgsl", parse("ensemble.wgsl", &ensemble_wgsl())),
        ("check.wgsl", parse("check.wgsl", &check_wgsl())),
    ];
    for (rust, module_label) in rust_structs() {
        check_rust_fields_tile(&rust);
        let module = &modules.iter().find(|(l, _)| *l == module_label).unwrap().1;
        let mut layouter = Layouter::default();
        layouter.update(module.to_ctx()).expect("naga lays out the module's types");

        let matches: Vec<_> = module.types.iter().filter(|(_, ty)| ty.name.as_deref() == Some(rust.name)).collect();
        assert_eq!(matches.len(), 1, "{module_label} must define exactly one struct `{}`", rust.name);
        let (handle, ty) = matches[0];
        let TypeInner::Struct { members, span } = &ty.inner else {
            panic!("{module_label}: `{}` is not a struct: {:?}", rust.name, ty.inner);
        };
        let layout = &layouter[handle];
        let wgsl_align = layout.alignment * 1u32;

        assert_eq!(
            rust.size, *span as usize,
            "struct {}: Rust size_of = {} bytes but WGSL ({module_label}) span = {} bytes",
            rust.name, rust.size, span
        );
        assert_eq!(
            layout.size, *span,
            "struct {}: naga Layouter size {} differs from the struct span {}",
            rust.name, layout.size, span
        );
        assert_eq!(
            rust.fields.len(),
            members.len(),
            "struct {}: Rust has {} fields but WGSL has {} members (Rust size {} bytes, WGSL span {} bytes)",
            rust.name,
            rust.fields.len(),
            members.len(),
            rust.size,
            span
        );
        assert_eq!(
            rust.align, wgsl_align as usize,
            "struct {}: Rust align_of = {} but WGSL alignment = {}",
            rust.name, rust.align, wgsl_align
        );

        for (index, (f, m)) in rust.fields.iter().zip(members).enumerate() {
            let member_name = m.name.as_deref().unwrap_or("<unnamed>");
            assert_eq!(
                f.name, member_name,
                "struct {}: member {index} is `{}` in Rust but `{member_name}` in WGSL",
                rust.name, f.name
            );
            assert_eq!(
                f.offset, m.offset as usize,
                "struct {}: member `{}` is at offset {} in Rust but {} in WGSL",
                rust.name, f.name, f.offset, m.offset
            );
            let member_ty = &module.types[m.ty];
            let is_4_byte_scalar = matches!(
                member_ty.inner,
                TypeInner::Scalar(Scalar { kind: ScalarKind::Float | ScalarKind::Uint | ScalarKind::Sint, width: 4 })
            );
            assert!(
                is_4_byte_scalar,
                "struct {}: WGSL member `{member_name}` has type {:?}; shared structs may hold only 4-byte scalars (f32/u32/i32)",
                rust.name, member_ty.inner
            );
            assert_eq!(layouter[m.ty].size, 4, "struct {}: WGSL member `{member_name}` is not 4 bytes", rust.name);
            assert_eq!(f.size, 4, "struct {}: Rust field `{}` is {} bytes, not 4", rust.name, f.name, f.size);
        }
        println!(
            "{module_label}: struct {} matches: {} bytes, {} members of 4 bytes, alignment {}",
            rust.name,
            span,
            members.len(),
            wgsl_align
        );
    }
}
