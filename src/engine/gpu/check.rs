//! The generator check kernel (`shaders/check.wgsl`): raw Philox words and
//! Gaussians computed by the WGSL generator, for comparison with
//! [`crate::engine::rng`] bit for bit.

use wgpu::util::DeviceExt;

use crate::engine::gpu::shared::CheckParams;
use crate::engine::gpu::{
    Kernels, MAX_WORKGROUPS_PER_DIMENSION, WORKGROUP_SIZE, read_back, storage_buffer, workgroups,
};
use crate::engine::rng;
use crate::error::{Error, Result};

/// The Philox counter of check index `i`, as `check.wgsl` builds it.
fn check_counter(i: u32) -> [u32; 4] {
    [i, i.wrapping_mul(0x9E37_79B9), !i, i ^ 0x85EB_CA6B]
}

/// The Philox key and counter that check index `i` uses in `check.wgsl`.
pub fn philox_check_input(seed: u64, i: u32) -> ([u32; 4], [u32; 2]) {
    let [lo, hi] = rng::seed_key(seed);
    (check_counter(i), [lo ^ i, hi.wrapping_add(i >> 3)])
}

/// Raw Philox words and Gaussians for check indices `first..first+count`,
/// computed by the WGSL generator.
pub fn philox_check(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    kernels: &Kernels,
    seed: u64,
    first: u32,
    count: u32,
) -> Result<(Vec<[u32; 4]>, Vec<f32>)> {
    if count == 0 || workgroups(count) > MAX_WORKGROUPS_PER_DIMENSION {
        return Err(Error::setting(
            "philox check",
            format!("count {count} must be in 1..={}", MAX_WORKGROUPS_PER_DIMENSION * WORKGROUP_SIZE),
        ));
    }
    let [seed_lo, seed_hi] = rng::seed_key(seed);
    let params = CheckParams { seed_lo, seed_hi, first, count };
    let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("check params"),
        contents: bytemuck::bytes_of(&params),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let words = storage_buffer(device, "words", u64::from(count) * 16);
    let normals = storage_buffer(device, "normals", u64::from(count) * 4);
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("philox check"),
        layout: &kernels.check_layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: words.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 2, resource: normals.as_entire_binding() },
        ],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&kernels.philox_check);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(workgroups(count), 1, 1);
    }
    queue.submit([encoder.finish()]);
    let w = read_back(device, queue, &words, u64::from(count) * 16)?;
    let n = read_back(device, queue, &normals, u64::from(count) * 4)?;
    Ok((bytemuck::cast_slice(&w).to_vec(), bytemuck::cast_slice(&n).to_vec()))
}
