//! The noise generator: the WGSL Philox against the Rust one, and the
//! statistics of the Gaussians both produce.
//!
//! The GPU test needs a wgpu adapter; a software one (Mesa's lavapipe) is
//! enough and is what it runs on where there is no GPU.

use std::time::Instant;

use statrs::distribution::{ContinuousCDF, Normal};
use stickslip::engine::gpu::GpuContext;
use stickslip::engine::gpu::check::{philox_check, philox_check_input};
use stickslip::engine::rng::{gaussian, noise_counter, philox4x32_10, seed_key, uniform_open};

const SEED: u64 = 0x5EED_1234_ABCD_0042;

/// Realisations × intervals of the CPU sample: 400 × 500 = 200 000 values.
const CPU_REALISATIONS: u32 = 400;
const CPU_INTERVALS: u64 = 500;

/// Keys per `philox_check` call (the kernel takes at most 65 535 × 64).
const GPU_BLOCK: u32 = 1 << 20;

/// The f32 uniform the WGSL `uniform_open` computes.
fn uniform_open_f32(word: u32) -> f32 {
    ((word >> 9) as f32 + 0.5) * (1.0 / 8_388_608.0)
}

/// Kolmogorov–Smirnov statistic `D = sup |F_n − Φ|` of a sample against N(0, 1).
fn ks_statistic(sample: &[f64]) -> f64 {
    let normal = Normal::new(0.0, 1.0).unwrap();
    let mut sorted = sample.to_vec();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len() as f64;
    sorted.iter().enumerate().fold(0.0_f64, |d, (i, &x)| {
        let f = normal.cdf(x);
        d.max((i + 1) as f64 / n - f).max(f - i as f64 / n)
    })
}

/// KS critical value at α = 0.01 (asymptotic, 1.63 / √n).
fn ks_critical(n: usize) -> f64 {
    1.63 / (n as f64).sqrt()
}

fn mean_var(sample: &[f64]) -> (f64, f64) {
    let n = sample.len() as f64;
    let mean = sample.iter().sum::<f64>() / n;
    let var = sample.iter().map(|z| (z - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var)
}

fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let (ma, va) = mean_var(a);
    let (mb, vb) = mean_var(b);
    let cov = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum::<f64>() / (a.len() as f64 - 1.0);
    cov / (va * vb).sqrt()
}

/// `gaussian(key, r, stream, j)` over r in 0..400, j in 0..500, realisation-major.
fn cpu_sample(stream: u32) -> Vec<f64> {
    let key = seed_key(SEED);
    (0..CPU_REALISATIONS).flat_map(|r| (0..CPU_INTERVALS).map(move |j| gaussian(key, r, stream, j))).collect()
}

/// The Box–Muller radius `r = √(−2 ln u1)` of the CPU Gaussian of check index `i`.
fn box_muller_radius(key: [u32; 2], i: u32) -> f64 {
    let w = philox4x32_10(noise_counter(i, i & 3, u64::from(i >> 2)), key);
    (-2.0 * uniform_open(w[0]).ln()).sqrt()
}

/// How far the WGSL (f32) Gaussian may be from the Rust (f64) one.
///
/// `2e-5·max(1, |z|)` covers f32 `log`, `sqrt`, `cos` and the f32 angle.
/// It is not enough on its own when `u1` is near 1 (`r` near 0): the uniform
/// itself is exact in f32 (see [`uniform_f32_identity_is_exhaustive`]), but
/// f32 `log` near 1 has an absolute error of a few 1e-8, and an error ε in
/// `−2 ln u1 = r²` moves z by about ε/(2r); the bound adds 2e-7/r. That term
/// only matters for r ≲ 0.01 (about one key in 20 000). (Measured on lavapipe
/// over 2^24 keys with the earlier 24-bit uniform, which f32 rounded: 20 keys
/// exceeded the plain bound, none this one.)
fn gaussian_tolerance(cpu_z: f64, r: f64) -> f64 {
    2e-5 * cpu_z.abs().max(1.0) + 2e-7 / r
}

/// WGSL Philox words must equal the Rust ones bit for bit, and the WGSL
/// Gaussians must equal the Rust (f64) ones up to f32 rounding error (see
/// [`gaussian_tolerance`]).
///
/// 2^21 = 2 097 152 keys in two dispatches of 2^20: check indices 0..2^20 and
/// the last 2^20 below 2^32 (so counters and keys with the top bits set, and
/// `i >> 3` near its maximum, are covered). The normals from the same run,
/// n = 2^21, also go through mean, variance and KS tests (critical
/// D = 1.63/√n = 0.00113; a mean shift of 0.005 gives D ≈ 0.0020), which
/// validates the WGSL Box–Muller in f32 against N(0, 1).
#[test]
fn gpu_philox_matches_rust_bit_for_bit() {
    let start = Instant::now();
    let ctx = GpuContext::new(true).unwrap_or_else(|e| panic!("no wgpu adapter (lavapipe is enough): {e}"));
    println!("adapter: {}", ctx.describe());
    let key = seed_key(SEED);

    let mut keys = 0usize;
    let mut word_mismatches = Vec::new();
    let mut uniform_mismatches = Vec::new();
    let mut normal_failures = 0usize;
    let mut outside_plain = 0usize;
    let mut max_diff = 0.0_f64;
    let mut worst = (0u32, 0.0_f64, 0.0_f32);
    let mut gpu_normals = Vec::with_capacity(2 * GPU_BLOCK as usize);
    let mut gpu_time = 0.0;

    for first in [0u32, (u32::MAX - GPU_BLOCK) + 1] {
        let t = Instant::now();
        let (words, normals) = philox_check(&ctx.device, &ctx.queue, &ctx.kernels, SEED, first, GPU_BLOCK)
            .unwrap_or_else(|e| panic!("philox_check(first = {first}): {e}"));
        gpu_time += t.elapsed().as_secs_f64();
        assert_eq!(words.len(), GPU_BLOCK as usize);
        assert_eq!(normals.len(), GPU_BLOCK as usize);
        for (n, (gpu_words, &gpu_z)) in words.iter().zip(&normals).enumerate() {
            let i = first.wrapping_add(n as u32);
            let (counter, check_key) = philox_check_input(SEED, i);
            let cpu_words = philox4x32_10(counter, check_key);
            if *gpu_words != cpu_words && word_mismatches.len() < 8 {
                word_mismatches.push((i, *gpu_words, cpu_words));
            }
            for &w in gpu_words {
                let cpu_u = uniform_open(w) as f32;
                let gpu_u = uniform_open_f32(w);
                if cpu_u.to_bits() != gpu_u.to_bits() && uniform_mismatches.len() < 8 {
                    uniform_mismatches.push((w, cpu_u, gpu_u));
                }
            }
            let cpu_z = gaussian(key, i, i & 3, u64::from(i >> 2));
            let diff = (f64::from(gpu_z) - cpu_z).abs();
            let plain_tolerance = 2e-5 * cpu_z.abs().max(1.0);
            if diff.is_nan() || diff > plain_tolerance {
                outside_plain += 1;
            }
            if diff.is_nan() || diff > gaussian_tolerance(cpu_z, box_muller_radius(key, i)) {
                normal_failures += 1;
            }
            if diff > max_diff || (diff.is_nan() && !max_diff.is_nan()) {
                max_diff = diff;
                worst = (i, cpu_z, gpu_z);
            }
            gpu_normals.push(f64::from(gpu_z));
            keys += 1;
        }
    }

    println!("compared {keys} Philox keys (4 words each) and {keys} Gaussians; GPU time {gpu_time:.2} s");
    assert!(
        word_mismatches.is_empty(),
        "WGSL Philox differs from Rust; first mismatches (i, gpu, cpu): {word_mismatches:x?}"
    );
    assert!(
        uniform_mismatches.is_empty(),
        "f32 uniform differs from the f64 one rounded to f32; first mismatches (word, cpu, gpu): {uniform_mismatches:?}"
    );
    let (wi, wc, wg) = worst;
    println!("max |gpu − cpu| Gaussian difference: {max_diff:.3e} (index {wi}: cpu {wc:.9}, gpu {wg:.9})");
    println!("Gaussians outside the plain bound 2e-5·max(1,|z|): {outside_plain} of {keys}");
    assert_eq!(
        normal_failures, 0,
        "{normal_failures} of {keys} WGSL Gaussians differ from Rust by more than 2e-5·max(1,|z|) + 2e-7/r; \
         max difference {max_diff:.3e} at index {wi} (cpu {wc}, gpu {wg})"
    );

    let d = ks_statistic(&gpu_normals);
    let crit = ks_critical(gpu_normals.len());
    let (mean, var) = mean_var(&gpu_normals);
    println!(
        "GPU normals: n = {}, mean {mean:.5}, var {var:.5}, KS D = {d:.6} (critical {crit:.6})",
        gpu_normals.len()
    );
    let n = gpu_normals.len() as f64;
    assert!(mean.abs() < 4.0 / n.sqrt(), "mean {mean} of the WGSL Gaussians is outside ±4/√n");
    assert!((var - 1.0).abs() < 4.0 * (2.0 / n).sqrt(), "variance {var} of the WGSL Gaussians is outside 1 ± 4·√(2/n)");
    assert!(d <= crit, "KS rejects N(0,1) for the WGSL Gaussians: D = {d:.6} > {crit:.6} (n = {})", gpu_normals.len());
    println!("gpu_philox_matches_rust_bit_for_bit: {:.2} s", start.elapsed().as_secs_f64());
}

/// The uniform identity over every possible top-23-bit value, not just the
/// words the GPU test draws: the WGSL f32 formula gives exactly the f64
/// value the CPU uses (no rounding at all), strictly inside (0, 1).
#[test]
fn uniform_f32_identity_is_exhaustive() {
    for m in 0..1u32 << 23 {
        for low in [0x000, 0x0A5, 0x1FF] {
            let w = (m << 9) | low;
            let cpu = uniform_open(w);
            let gpu = uniform_open_f32(w);
            assert_eq!(cpu, f64::from(gpu), "word {w:#010x}: f64 {cpu:e} vs f32 {gpu:e}");
            assert!(gpu > 0.0 && gpu < 1.0, "word {w:#010x}: {gpu:e} outside (0, 1)");
        }
    }
    println!("uniform identity holds exactly for all 2^23 top-23-bit values");
}

/// Statistics of the CPU reference Gaussian (f64 Box–Muller of `uniform_open`):
/// n = 200 000 values `gaussian(key, r, 0, j)`, r in 0..400, j in 0..500.
///
/// - mean: |mean| < 4/√n = 0.00894;
/// - variance: |var − 1| < 4·√(2/n) = 0.01265;
/// - Kolmogorov–Smirnov against N(0, 1): reject if D > 1.63/√n = 0.003645
///   (α = 0.01).
///
/// Power of the KS test at this n: a shift of the mean by δ moves the CDF by
/// at most 2Φ(δ/2) − 1 ≈ 0.399 δ. For δ = 0.02 that is D ≈ 0.00798, 2.2× the
/// critical value; the empirical CDF at the point of largest difference has
/// a standard deviation of 0.5/√n = 0.00112, so the shift is detected with
/// probability > 0.9999 (the margin is 3.9 standard deviations). For δ = 0.01,
/// D ≈ 0.00399 is just above the critical value and is detected with
/// probability of only about 0.6 or more. A scale error σ = 1.02 gives D ≈ φ(1)·0.0196 ≈ 0.0047
/// (detected with probability ≈ 0.9), and the variance check alone rejects
/// it (|var − 1| ≈ 0.04). `ks_has_power_against_a_mean_shift` checks the
/// δ = 0.02 claim on this very sample.
#[test]
fn cpu_gaussian_quality() {
    let start = Instant::now();
    let z = cpu_sample(0);
    let n = z.len();
    assert_eq!(n, 200_000);
    let (mean, var) = mean_var(&z);
    let d = ks_statistic(&z);
    let crit = ks_critical(n);
    let mean_bound = 4.0 / (n as f64).sqrt();
    let var_bound = 4.0 * (2.0 / n as f64).sqrt();
    println!(
        "CPU normals: n = {n}, mean {mean:.5} (bound {mean_bound:.5}), var {var:.5} (bound ±{var_bound:.5}), KS D = {d:.6} (critical {crit:.6})"
    );
    assert!(mean.abs() < mean_bound, "mean {mean} of {n} Gaussians is outside ±{mean_bound}");
    assert!((var - 1.0).abs() < var_bound, "variance {var} of {n} Gaussians is outside 1 ± {var_bound}");
    assert!(d <= crit, "KS rejects N(0,1) for the Rust Gaussians: D = {d:.6} > {crit:.6} (n = {n})");
    println!("cpu_gaussian_quality: {:.2} s", start.elapsed().as_secs_f64());
}

/// The KS test above can see what its doc comment says it sees: the same
/// sample shifted by 0.02 is rejected (shifted by 0.01 it is reported only).
#[test]
fn ks_has_power_against_a_mean_shift() {
    let z = cpu_sample(0);
    let crit = ks_critical(z.len());
    let d_01: f64 = ks_statistic(&z.iter().map(|x| x + 0.01).collect::<Vec<_>>());
    let d_02: f64 = ks_statistic(&z.iter().map(|x| x + 0.02).collect::<Vec<_>>());
    println!("KS D of the sample shifted by 0.01: {d_01:.6}; by 0.02: {d_02:.6} (critical {crit:.6})");
    assert!(d_02 > crit, "KS fails to reject a mean shift of 0.02: D = {d_02:.6} <= {crit:.6}");
}

/// Streams are independent: the friction (0) and normal-force (1) noise at
/// the same (realisation, interval) are uncorrelated, |ρ| < 4/√n, and so are
/// consecutive intervals of one stream.
#[test]
fn streams_and_intervals_are_uncorrelated() {
    let s0 = cpu_sample(0);
    let s1 = cpu_sample(1);
    let n = s0.len();
    let bound = 4.0 / (n as f64).sqrt();
    let rho_streams = correlation(&s0, &s1);
    // Lag 1 in the interval index, within each realisation.
    let (a, b): (Vec<f64>, Vec<f64>) =
        s0.chunks(CPU_INTERVALS as usize).flat_map(|row| row.windows(2).map(|w| (w[0], w[1]))).unzip();
    let rho_lag1 = correlation(&a, &b);
    println!(
        "correlation stream 0 vs 1: {rho_streams:.5}; interval j vs j+1: {rho_lag1:.5} (bound {bound:.5}, n = {n})"
    );
    assert!(rho_streams.abs() < bound, "streams 0 and 1 are correlated: rho = {rho_streams} (bound {bound}, n = {n})");
    let lag_bound = 4.0 / (a.len() as f64).sqrt();
    assert!(rho_lag1.abs() < lag_bound, "consecutive intervals are correlated: rho = {rho_lag1} (bound {lag_bound})");
}
