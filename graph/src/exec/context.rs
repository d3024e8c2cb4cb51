//! The headless device: adapter selection, feature negotiation, small blocking helpers.

use crate::compile::CompileOptions;
use crate::error::{GraphError, Result};

/// The environment variable that picks an adapter by a substring of its name.
pub const ADAPTER_ENV: &str = "MESHLIGHT_ADAPTER";

/// The environment variable that turns wgpu's indirect-call validation off (`off`, `0`).
///
/// wgpu checks the arguments of every indirect dispatch and draw on the GPU with an extra
/// dispatch of its own (and clamps out-of-range ones). A graph whose indirect arguments
/// are all written by its own passes, which bound them with the limits in mind (as
/// `remap_dispatch` does), may turn it off; it stays on by default.
pub const INDIRECT_VALIDATION_ENV: &str = "MESHLIGHT_INDIRECT_VALIDATION";

/// Features the executor itself uses when the adapter has them (per-pass GPU timing).
pub const TIMING_FEATURES: wgpu::Features = wgpu::Features::TIMESTAMP_QUERY
    .union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS)
    .union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES);

/// Every feature wgpu marks experimental (the ones that need the opt-in).
pub fn experimental_features() -> wgpu::Features {
    wgpu::Features::all()
        .iter_names()
        .filter(|(n, _)| n.starts_with("EXPERIMENTAL_"))
        .fold(wgpu::Features::empty(), |acc, (_, f)| acc | f)
}

/// Which adapter [`GpuAdapter::select_with`] opens, and how.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AdapterOptions {
    /// The backends searched. Default: the native ones this build has (Vulkan, Metal,
    /// DX12, as the crate's `vulkan`, `metal` and `dx12` features enable them).
    pub backends: wgpu::Backends,
    /// Part of the adapter's name, case-insensitive; `None`: the best adapter found (a
    /// discrete GPU before an integrated one, a GPU before a CPU implementation).
    pub name: Option<String>,
    /// wgpu's indirect-call validation (see [`INDIRECT_VALIDATION_ENV`]).
    pub indirect_validation: bool,
}

impl Default for AdapterOptions {
    fn default() -> Self {
        Self {
            backends: Self::native_backends(),
            name: None,
            indirect_validation: true,
        }
    }
}

impl AdapterOptions {
    /// The primary native backends this build of wgpu has: those of Vulkan, Metal and
    /// DX12 its features enabled and the target supports.
    pub fn native_backends() -> wgpu::Backends {
        wgpu::Backends::PRIMARY & wgpu::Instance::enabled_backend_features()
    }

    /// The defaults with the environment's choices: `WGPU_BACKEND` (wgpu's own list,
    /// e.g. `vulkan` or `metal,dx12`), [`ADAPTER_ENV`] and [`INDIRECT_VALIDATION_ENV`].
    pub fn from_env() -> Self {
        let off = std::env::var(INDIRECT_VALIDATION_ENV).is_ok_and(|v| {
            matches!(
                v.trim().to_ascii_lowercase().as_str(),
                "0" | "off" | "false" | "no"
            )
        });
        Self {
            backends: wgpu::Backends::from_env().unwrap_or_else(Self::native_backends),
            name: std::env::var(ADAPTER_ENV).ok().filter(|s| !s.is_empty()),
            indirect_validation: !off,
        }
    }
}

/// How much an adapter of this type is preferred when none is named: lower first.
fn rank(device_type: wgpu::DeviceType) -> u8 {
    match device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

/// A chosen adapter, before a device is created for it.
pub struct GpuAdapter {
    /// The instance the adapter came from; surfaces are made from it.
    pub instance: wgpu::Instance,
    /// The adapter picked by [`AdapterOptions`].
    pub adapter: wgpu::Adapter,
}

impl GpuAdapter {
    /// The adapter the environment asks for ([`AdapterOptions::from_env`]).
    pub fn select() -> Result<Self> {
        Self::select_with(&AdapterOptions::from_env())
    }

    /// The adapter `options` ask for: named, or the best of the backends searched.
    pub fn select_with(options: &AdapterOptions) -> Result<Self> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = options.backends;
        desc.flags.set(
            wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL,
            options.indirect_validation,
        );
        let instance = wgpu::Instance::new(desc);
        let adapters = crate::exec::quiet::without_runtime_dir_alarm(|| {
            pollster::block_on(instance.enumerate_adapters(options.backends))
        });
        let names: Vec<String> = adapters
            .iter()
            .map(|a| {
                let info = a.get_info();
                format!("{} ({:?})", info.name, info.backend)
            })
            .collect();
        let searched = match options
            .backends
            .iter_names()
            .map(|(n, _)| n.to_lowercase())
            .collect::<Vec<_>>()
        {
            names if names.is_empty() => {
                "no backend (enable meshlight's `vulkan`, `metal` or `dx12` feature)".to_string()
            }
            names => names.join(", "),
        };
        let adapter = match &options.name {
            Some(w) => adapters
                .into_iter()
                .find(|a| a.get_info().name.to_lowercase().contains(&w.to_lowercase()))
                .ok_or_else(|| GraphError::NoAdapter {
                    backends: searched,
                    detail: format!(
                        " matching {ADAPTER_ENV}={w:?} (found: {})",
                        if names.is_empty() {
                            "none".to_string()
                        } else {
                            names.join(", ")
                        }
                    ),
                })?,
            None => adapters
                .into_iter()
                .enumerate()
                .min_by_key(|(i, a)| (rank(a.get_info().device_type), *i))
                .map(|(_, a)| a)
                .ok_or_else(|| GraphError::NoAdapter {
                    backends: searched,
                    detail: String::new(),
                })?,
        };
        Ok(Self { instance, adapter })
    }

    /// What the adapter supports; [`crate::CompileOptions::for_adapter`] plans for it.
    pub fn features(&self) -> wgpu::Features {
        self.adapter.features()
    }
    /// Name, driver and backend, for logs and reports.
    pub fn info(&self) -> wgpu::AdapterInfo {
        self.adapter.get_info()
    }

    /// Creates the device with `features` (what the compiled graphs need) plus timing
    /// features where the adapter has them, and the adapter's own limits so large
    /// buffers work.
    pub fn open(self, features: wgpu::Features) -> Result<GpuContext> {
        let have = self.adapter.features();
        let missing = features - have;
        if !missing.is_empty() {
            return Err(GraphError::Device(format!(
                "the adapter lacks {}",
                missing
                    .iter_names()
                    .map(|(n, _)| n)
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
        let enabled = features | (TIMING_FEATURES & have);
        // wgpu's experimental features (mesh shaders) need an explicit opt-in on top of
        // the feature bit; it is given only when a pass asked for one.
        let experimental = if enabled.intersects(experimental_features()) {
            // SAFETY: the only experimental feature meshlight enables is mesh shading, and
            // only for passes that declared it; its programs are validated by naga.
            unsafe { wgpu::ExperimentalFeatures::enabled() }
        } else {
            wgpu::ExperimentalFeatures::disabled()
        };
        let desc = wgpu::DeviceDescriptor {
            label: Some("meshlight"),
            required_features: enabled,
            required_limits: self.adapter.limits(),
            experimental_features: experimental,
            ..Default::default()
        };
        let (device, queue) = pollster::block_on(self.adapter.request_device(&desc))
            .map_err(|e| GraphError::Device(e.to_string()))?;
        let info = self.adapter.get_info();
        Ok(GpuContext {
            instance: self.instance,
            adapter: self.adapter,
            device,
            queue,
            features: enabled,
            info,
        })
    }
}

/// An open device and its queue.
pub struct GpuContext {
    /// The instance the device came from; surfaces are made from it.
    pub instance: wgpu::Instance,
    /// The adapter the device was opened on.
    pub adapter: wgpu::Adapter,
    /// The device resources and pipelines are made on.
    pub device: wgpu::Device,
    /// The queue frames are submitted to.
    pub queue: wgpu::Queue,
    /// Features enabled on the device.
    pub features: wgpu::Features,
    /// The adapter's name, driver and backend.
    pub info: wgpu::AdapterInfo,
}

impl GpuContext {
    /// A host application's own device: meshlight records and submits on it, creates its
    /// resources and pipelines there, and opens no device or surface of its own. The
    /// features it can use are those the device was created with; ask
    /// `meshlight_virtual_geometry::Renderer::required_features` (or compile your graph
    /// with [`crate::CompileOptions::for_adapter`] and read `plan.enabled_features`)
    /// before creating it.
    pub fn from_host(
        instance: wgpu::Instance,
        adapter: wgpu::Adapter,
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Self {
        let info = adapter.get_info();
        Self {
            features: device.features(),
            instance,
            adapter,
            device,
            queue,
            info,
        }
    }

    /// Selects an adapter and opens it with every feature the adapter has out of `wanted`,
    /// leaving out mappable primary buffers, which slow discrete GPUs down, and wgpu's
    /// experimental features other than mesh shading, which no meshlight pass uses.
    pub fn with_available(wanted: wgpu::Features) -> Result<Self> {
        let adapter = GpuAdapter::select()?;
        let f = wanted & adapter.features();
        let unused_experimental =
            experimental_features() - wgpu::Features::EXPERIMENTAL_MESH_SHADER;
        adapter.open(f - unused_experimental - wgpu::Features::MAPPABLE_PRIMARY_BUFFERS)
    }

    /// Copies `size` bytes at `offset` of `buffer` (which needs COPY_SRC) to the CPU.
    pub fn read_buffer(&self, buffer: &wgpu::Buffer, offset: u64, size: u64) -> Result<Vec<u8>> {
        if size == 0 {
            return Ok(Vec::new());
        }
        self.copy_to_cpu("readback", size, |enc, staging| {
            enc.copy_buffer_to_buffer(buffer, offset, staging, 0, size);
        })
    }

    /// Records `copy` into a `size`-byte staging buffer, submits it and waits for the
    /// bytes; a validation error of the copy is a readback error.
    fn copy_to_cpu(
        &self,
        label: &str,
        size: u64,
        copy: impl FnOnce(&mut wgpu::CommandEncoder, &wgpu::Buffer),
    ) -> Result<Vec<u8>> {
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(&format!("meshlight {label}")),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut enc = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
        copy(&mut enc, &staging);
        self.queue.submit([enc.finish()]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GraphError::Readback(e.to_string()));
        }
        self.map_and_read(&staging)
    }

    /// Copies mip 0, layer 0 of `texture` (which needs COPY_SRC) to the CPU, rows tightly
    /// packed (the copy's 256-byte row alignment removed).
    pub fn read_texture(&self, texture: &wgpu::Texture) -> Result<Vec<u8>> {
        let format = texture.format();
        let texel = format
            .block_copy_size(Some(wgpu::TextureAspect::All))
            .ok_or_else(|| {
                GraphError::Readback(format!("{format:?} cannot be copied whole to a buffer"))
            })?;
        let (width, height) = (texture.width(), texture.height());
        let row = width * texel;
        let padded_row = row.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let size = (padded_row as u64 * height as u64).max(4);
        let padded = self.copy_to_cpu("texture readback", size, |enc, staging| {
            enc.copy_texture_to_buffer(
                texture.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer: staging,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(padded_row),
                        rows_per_image: Some(height),
                    },
                },
                wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
            );
        })?;
        Ok(padded
            .chunks(padded_row as usize)
            .take(height as usize)
            .flat_map(|r| &r[..row as usize])
            .copied()
            .collect())
    }

    /// Waits for a MAP_READ buffer and returns its bytes.
    pub fn map_and_read(&self, staging: &wgpu::Buffer) -> Result<Vec<u8>> {
        let (tx, rx) = std::sync::mpsc::channel();
        staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GraphError::Readback(e.to_string()))?;
        rx.recv()
            .map_err(|e| GraphError::Readback(e.to_string()))?
            .map_err(|e| GraphError::Readback(e.to_string()))?;
        let bytes = staging
            .get_mapped_range(..)
            .map_err(|e| GraphError::Readback(e.to_string()))?
            .to_vec();
        staging.unmap();
        Ok(bytes)
    }

    /// Creates a buffer holding `data`.
    pub fn buffer_with_data(
        &self,
        label: &str,
        data: &[u8],
        usage: wgpu::BufferUsages,
    ) -> wgpu::Buffer {
        let size = (data.len() as u64).max(4).next_multiple_of(4);
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: usage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        if !data.is_empty() {
            let mut padded = data.to_vec();
            padded.resize(size as usize, 0);
            self.queue.write_buffer(&buffer, 0, &padded);
        }
        buffer
    }
}

impl CompileOptions {
    /// The features enabled on an open device and its limits.
    pub fn for_gpu(gpu: &GpuContext) -> Self {
        Self {
            adapter_features: gpu.features,
            limits: gpu.device.limits(),
            class: crate::AdapterClass::of(&gpu.info),
        }
    }
    /// The features and limits of `adapter`.
    pub fn for_adapter(adapter: &GpuAdapter) -> Self {
        Self {
            adapter_features: adapter.features(),
            limits: adapter.adapter.limits(),
            class: crate::AdapterClass::of(&adapter.info()),
        }
    }
}
