// Test kernel (src/engine/gpu/check.rs): raw Philox words and Gaussians for a range of keys, so the
// Rust and WGSL generators can be compared bit for bit.

struct CheckParams {
    seed_lo: u32,
    seed_hi: u32,
    first: u32,
    count: u32,
}

@group(0) @binding(0) var<uniform> check: CheckParams;
@group(0) @binding(1) var<storage, read_write> words: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read_write> normals: array<f32>;

// The counter/key of check index i; src/engine/gpu/check.rs::philox_check_input is the same.
fn check_counter(i: u32) -> vec4<u32> {
    return vec4<u32>(i, i * 0x9E3779B9u, ~i, i ^ 0x85EBCA6Bu);
}

@compute @workgroup_size(WORKGROUP_SIZE)
fn philox_check(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = gid.x + gid.y * MAX_WORKGROUPS_PER_DIMENSION * WORKGROUP_SIZE;
    if (n >= check.count) {
        return;
    }
    let i = check.first + n;
    let key = vec2<u32>(check.seed_lo ^ i, check.seed_hi + (i >> 3u));
    words[n] = philox4x32_10(check_counter(i), key);
    normals[n] = gaussian(vec2<u32>(check.seed_lo, check.seed_hi), i, i & 3u, i >> 2u);
}
