// Philox4x32-10 and Box–Muller, word for word as src/engine/rng.rs (its
// multipliers, Weyl constants and stream numbers are generated constants).
// A random value is a function of (seed, realisation, stream, interval) only.

// 32 × 32 → 64-bit product as (hi, lo), from 16-bit halves.
fn mulhilo(a: u32, b: u32) -> vec2<u32> {
    let a_lo = a & 0xFFFFu;
    let a_hi = a >> 16u;
    let b_lo = b & 0xFFFFu;
    let b_hi = b >> 16u;
    let lo_lo = a_lo * b_lo;
    let hi_lo = a_hi * b_lo;
    let lo_hi = a_lo * b_hi;
    let hi_hi = a_hi * b_hi;
    let cross = (lo_lo >> 16u) + (hi_lo & 0xFFFFu) + lo_hi;
    let hi = hi_hi + (hi_lo >> 16u) + (cross >> 16u);
    let lo = (cross << 16u) | (lo_lo & 0xFFFFu);
    return vec2<u32>(hi, lo);
}

fn philox_round(c: vec4<u32>, k: vec2<u32>) -> vec4<u32> {
    let p0 = mulhilo(PHILOX_M0, c.x);
    let p1 = mulhilo(PHILOX_M1, c.z);
    return vec4<u32>(p1.x ^ c.y ^ k.x, p1.y, p0.x ^ c.w ^ k.y, p0.y);
}

// Ten rounds, unrolled: llvmpipe (lavapipe) ends every loop of an invocation
// after 65535 iterations in total, so hot paths avoid loops.
fn philox4x32_10(counter: vec4<u32>, key: vec2<u32>) -> vec4<u32> {
    let bump = vec2<u32>(PHILOX_W0, PHILOX_W1);
    var c = philox_round(counter, key);
    var k = key + bump;
    c = philox_round(c, k);
    k = k + bump;
    c = philox_round(c, k);
    k = k + bump;
    c = philox_round(c, k);
    k = k + bump;
    c = philox_round(c, k);
    k = k + bump;
    c = philox_round(c, k);
    k = k + bump;
    c = philox_round(c, k);
    k = k + bump;
    c = philox_round(c, k);
    k = k + bump;
    c = philox_round(c, k);
    k = k + bump;
    return philox_round(c, k);
}

// Uniform on (0, 1) from the top 23 bits: 24 significant bits, exact in f32.
fn uniform_open(word: u32) -> f32 {
    return (f32(word >> 9u) + 0.5) * (1.0 / 8388608.0);
}

fn box_muller(u1: f32, u2: f32) -> f32 {
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}

// Standard Gaussian of key (seed, realisation, stream, interval); the
// interval index's high word is 0 on the GPU (runs are kept below 2^32 intervals).
fn gaussian(key: vec2<u32>, realisation: u32, stream: u32, interval: u32) -> f32 {
    let w = philox4x32_10(vec4<u32>(interval, 0u, realisation, stream), key);
    return box_muller(uniform_open(w.x), uniform_open(w.y));
}

// Two independent standard Gaussians from two uniforms: Box–Muller's cosine
// and sine branches.
fn box_muller_pair(u1: f32, u2: f32) -> vec2<f32> {
    let r = sqrt(-2.0 * log(u1));
    let theta = 6.283185307179586 * u2;
    return vec2<f32>(r * cos(theta), r * sin(theta));
}

// The Philox block of key (seed, realisation, stream, interval).
fn noise_block(key: vec2<u32>, realisation: u32, stream: u32, interval: u32) -> vec4<u32> {
    return philox4x32_10(vec4<u32>(interval, 0u, realisation, stream), key);
}

// Pair A of a block: the Gaussians of words 0 and 1.
fn pair_a(words: vec4<u32>) -> vec2<f32> {
    return box_muller_pair(uniform_open(words.x), uniform_open(words.y));
}

// Pair B of a block: the Gaussians of words 2 and 3.
fn pair_b(words: vec4<u32>) -> vec2<f32> {
    return box_muller_pair(uniform_open(words.z), uniform_open(words.w));
}
