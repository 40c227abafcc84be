//! Code compiled for the vector units the processor has, chosen at run
//! time: the release binary targets baseline x86-64 (SSE2, two f64 a
//! register), and most machines it runs on have AVX2 (four) or AVX-512
//! (eight).

/// Defines a function whose body is compiled three times — for AVX-512,
/// for AVX2 and for the baseline target — and runs the widest the
/// processor has. The body is the same in each: the compiler only chooses
/// wider vector instructions for the same operations (it never reorders
/// floating-point arithmetic or fuses a multiply and an add on its own), so
/// every copy's answers are the same, bit for bit.
macro_rules! widest_vectors {
    ($(#[$meta:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty $body:block) => {
        $(#[$meta])*
        $vis fn $name($($arg: $ty),*) -> $ret {
            #[inline(always)]
            fn portable($($arg: $ty),*) -> $ret $body
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx512f")]
                fn avx512($($arg: $ty),*) -> $ret {
                    portable($($arg),*)
                }
                #[target_feature(enable = "avx2")]
                fn avx2($($arg: $ty),*) -> $ret {
                    portable($($arg),*)
                }
                if std::arch::is_x86_feature_detected!("avx512f") {
                    // SAFETY: the processor has AVX-512F, checked just above.
                    return unsafe { avx512($($arg),*) };
                }
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: the processor has AVX2, checked just above.
                    return unsafe { avx2($($arg),*) };
                }
            }
            portable($($arg),*)
        }
    };
}

pub(crate) use widest_vectors;
