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

/// A chosen adapter, before a device is created for it.
pub struct GpuAdapter {
    /// The instance the adapter came from; surfaces are made from it.
    pub instance: wgpu::Instance,
    /// The adapter picked by [`crate::ADAPTER_ENV`], or the first Vulkan one.
    pub adapter: wgpu::Adapter,
}

impl GpuAdapter {
    /// The adapter named by `MESHLIGHT_ADAPTER`, else the first Vulkan adapter, with
    /// indirect-call validation as `MESHLIGHT_INDIRECT_VALIDATION` says (on by default).
    pub fn select() -> Result<Self> {
        let off = std::env::var(INDIRECT_VALIDATION_ENV).is_ok_and(|v| {
            matches!(
                v.trim().to_ascii_lowercase().as_str(),
                "0" | "off" | "false" | "no"
            )
        });
        Self::select_with_indirect_validation(!off)
    }

    /// [`Self::select`] with wgpu's indirect-call validation on or off (see
    /// [`INDIRECT_VALIDATION_ENV`]).
    pub fn select_with_indirect_validation(indirect_validation: bool) -> Result<Self> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::VULKAN;
        desc.flags.set(
            wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL,
            indirect_validation,
        );
        let instance = wgpu::Instance::new(desc);
        let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN));
        let names: Vec<String> = adapters.iter().map(|a| a.get_info().name).collect();
        let wanted = std::env::var(ADAPTER_ENV).ok().filter(|s| !s.is_empty());
        let adapter = match &wanted {
            Some(w) => adapters
                .into_iter()
                .find(|a| a.get_info().name.to_lowercase().contains(&w.to_lowercase()))
                .ok_or_else(|| GraphError::NoAdapter {
                    detail: format!(
                        " matching {ADAPTER_ENV}={w:?} (found: {})",
                        names.join(", ")
                    ),
                })?,
            None => adapters
                .into_iter()
                .next()
                .ok_or_else(|| GraphError::NoAdapter {
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
