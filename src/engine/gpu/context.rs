//! One GPU: adapter selection, device and queue, and the compiled
//! pipelines. Functions elsewhere take the device, queue and [`Kernels`]
//! (as wgpu's compute examples take `&Device, &Queue`), so tests can pass a
//! device of their own.

use crate::engine::gpu::shared::EffectParams;
use crate::engine::gpu::source;
use crate::error::{Error, Result};

/// Compiled pipelines and their bind-group layouts.
pub struct Kernels {
    pub(crate) ensemble_layout: wgpu::BindGroupLayout,
    pub(crate) init_paths: wgpu::ComputePipeline,
    /// `run_cycles` of the kernel with each friction memory fixed
    /// (`source::ensemble_wgsl_with_memory`, by `Memory` code), each
    /// compiled on first use.
    run_cycles_with_memory: [std::sync::OnceLock<wgpu::ComputePipeline>; 4],
    /// `run_cycles` of the kernel specialised for models without effects
    /// (`source::ensemble_wgsl_without_effects`), compiled on first use.
    run_cycles_without_effects: std::sync::OnceLock<wgpu::ComputePipeline>,
    pub(crate) check_layout: wgpu::BindGroupLayout,
    pub(crate) philox_check: wgpu::ComputePipeline,
}

fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn compute_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    module: &wgpu::ShaderModule,
    entry_point: &str,
) -> wgpu::ComputePipeline {
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(entry_point),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry_point),
        layout: Some(&pipeline_layout),
        module,
        entry_point: Some(entry_point),
        compilation_options: Default::default(),
        cache: None,
    })
}

impl Kernels {
    /// Compiles the WGSL and builds the pipelines.
    pub fn new(device: &wgpu::Device) -> Kernels {
        let ensemble = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("ensemble.wgsl"),
            source: wgpu::ShaderSource::Wgsl(source::ensemble_wgsl().into()),
        });
        let ensemble_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("ensemble"),
            entries: &[
                uniform_entry(0),
                storage_entry(1, true),
                storage_entry(2, false),
                storage_entry(3, false),
                storage_entry(4, false),
                storage_entry(5, false),
                uniform_entry(6),
                storage_entry(7, false),
            ],
        });
        let check = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("check.wgsl"),
            source: wgpu::ShaderSource::Wgsl(source::check_wgsl().into()),
        });
        let check_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("philox_check"),
            entries: &[uniform_entry(0), storage_entry(1, false), storage_entry(2, false)],
        });
        Kernels {
            init_paths: compute_pipeline(device, &ensemble_layout, &ensemble, "init_paths"),
            run_cycles_with_memory: Default::default(),
            run_cycles_without_effects: std::sync::OnceLock::new(),
            philox_check: compute_pipeline(device, &check_layout, &check, "philox_check"),
            ensemble_layout,
            check_layout,
        }
    }

    /// The `run_cycles` pipeline for a dispatch whose effects' uniform is
    /// `effects`: the one specialised for no effects where it applies,
    /// otherwise the one with the uniform's friction memory fixed.
    pub(crate) fn run_cycles_for(&self, device: &wgpu::Device, effects: &EffectParams) -> &wgpu::ComputePipeline {
        if !effects.is_without_effects() {
            let memory = effects.memory();
            return self.run_cycles_with_memory[memory as usize].get_or_init(|| {
                let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("ensemble.wgsl with its friction memory fixed"),
                    source: wgpu::ShaderSource::Wgsl(source::ensemble_wgsl_with_memory(memory).into()),
                });
                compute_pipeline(device, &self.ensemble_layout, &module, "run_cycles")
            });
        }
        self.run_cycles_without_effects.get_or_init(|| {
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("ensemble.wgsl without effects"),
                source: wgpu::ShaderSource::Wgsl(source::ensemble_wgsl_without_effects().into()),
            });
            compute_pipeline(device, &self.ensemble_layout, &module, "run_cycles")
        })
    }
}

/// When the machine has a GPU (an NVIDIA driver in `/proc/driver/nvidia`
/// or `/dev/nvidia0`, or an AMD or Intel card in `/sys/class/drm`) but
/// Vulkan offered no hardware adapter: what to check, as a clause to append
/// to the message that says so. `None` on a machine without a GPU.
pub fn driver_hint() -> Option<String> {
    driver_hint_in(std::path::Path::new("/"))
}

/// [`driver_hint`] with `/proc`, `/dev` and `/sys` looked up under `root`.
pub fn driver_hint_in(root: &std::path::Path) -> Option<String> {
    let nvidia = std::fs::read_to_string(root.join("proc/driver/nvidia/version"))
        .ok()
        .and_then(|v| v.lines().next().map(|l| crate::text::excerpt(l.trim(), 120)))
        .or_else(|| root.join("dev/nvidia0").exists().then(|| "/dev/nvidia0".to_string()));
    let card = || {
        std::fs::read_dir(root.join("sys/class/drm")).ok()?.flatten().find_map(|e| {
            let vendor = std::fs::read_to_string(e.path().join("device/vendor")).ok()?;
            match vendor.trim() {
                "0x1002" => Some("an AMD GPU"),
                "0x8086" => Some("an Intel GPU"),
                "0x10de" => Some("an NVIDIA GPU"),
                _ => None,
            }
        })
    };
    let present = match nvidia {
        Some(driver) => format!("an NVIDIA GPU ({driver})"),
        None => card()?.to_string(),
    };
    Some(format!(
        "; but this machine has {present}: its Vulkan driver did not load. Check that its ICD file exists \
         (/usr/share/vulkan/icd.d/ or /etc/vulkan/icd.d/, e.g. nvidia_icd.json) and names a library that loads, \
         that VK_ICD_FILENAMES or VK_DRIVER_FILES, if set, point at it, that the Vulkan loader (libvulkan1) is \
         recent enough for the driver (`nvidia-smi` shows the driver's version), and what `vulkaninfo --summary` \
         lists"
    ))
}

/// What kind of adapter a context runs on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AdapterClass {
    /// A hardware GPU (discrete, integrated or virtual).
    Hardware,
    /// A software rasteriser such as Mesa's lavapipe.
    Software,
}

/// One GPU: device, queue, adapter description and compiled pipelines.
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter_info: wgpu::AdapterInfo,
    pub kernels: Kernels,
}

impl GpuContext {
    /// Opens the best adapter: a hardware GPU if there is one, otherwise a
    /// software one (lavapipe) when `allow_software` is set.
    pub fn new(allow_software: bool) -> Result<GpuContext> {
        pollster::block_on(Self::new_async(allow_software, None))
    }

    /// Like [`GpuContext::new`], but the device gets `limits` instead of
    /// everything the adapter offers (tests use this to force chunking).
    pub fn with_limits(allow_software: bool, limits: wgpu::Limits) -> Result<GpuContext> {
        pollster::block_on(Self::new_async(allow_software, Some(limits)))
    }

    async fn new_async(allow_software: bool, limits: Option<wgpu::Limits>) -> Result<GpuContext> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle());
        let mut adapters = instance.enumerate_adapters(wgpu::Backends::all()).await;
        let rank = |a: &wgpu::Adapter| match a.get_info().device_type {
            wgpu::DeviceType::DiscreteGpu => 0,
            wgpu::DeviceType::IntegratedGpu => 1,
            wgpu::DeviceType::VirtualGpu => 2,
            wgpu::DeviceType::Cpu => 3,
            wgpu::DeviceType::Other => 4,
        };
        adapters.retain(|a| a.get_info().backend != wgpu::Backend::Noop && (allow_software || rank(a) < 3));
        adapters.sort_by_key(|a| rank(a));
        let adapter = adapters.into_iter().next().ok_or_else(|| {
            let found = if allow_software {
                "no Vulkan, Metal or DX12 adapter found (install Mesa's lavapipe, package mesa-vulkan-drivers, for a software one)"
            } else {
                "no hardware GPU adapter found"
            };
            Error::NoGpu(format!("{found}{}", driver_hint().unwrap_or_default()))
        })?;
        let adapter_info = adapter.get_info();
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("stickslip"),
                required_limits: limits.unwrap_or_else(|| adapter.limits()),
                ..Default::default()
            })
            .await
            .map_err(|e| Error::NoGpu(format!("{}: {e}", adapter_info.name)))?;
        let kernels = Kernels::new(&device);
        Ok(GpuContext { device, queue, adapter_info, kernels })
    }

    /// Hardware or software adapter.
    pub fn adapter_class(&self) -> AdapterClass {
        match self.adapter_info.device_type {
            wgpu::DeviceType::Cpu | wgpu::DeviceType::Other => AdapterClass::Software,
            _ => AdapterClass::Hardware,
        }
    }

    /// A one-line description: name, type, backend, driver.
    pub fn describe(&self) -> String {
        let i = &self.adapter_info;
        format!("{} ({:?}, {:?}, {} {})", i.name, i.device_type, i.backend, i.driver, i.driver_info)
    }
}
