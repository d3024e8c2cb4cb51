//! Where clusters switch from the software to the hardware rasteriser, per adapter class.
//!
//! The split is a cluster's screen-box size (`cull_lod`'s `sw_threshold_px`): smaller
//! clusters go to the compute rasteriser. Where it pays to switch depends on how many of
//! the GPU's units run graphics work. The NVIDIA H100 and H200 run vertex and fragment
//! work on 2 of their TPCs only, so the compute rasteriser wins up to large clusters;
//! GPUs built for graphics rasterise big triangles faster in hardware. The defaults here
//! come from split sweeps on an H200 (the 3,375-bunny scene and the default scene at
//! 1080p and 4K, with `sw_raster` tiling big triangles; docs/BENCHMARKS.md has the
//! numbers).

/// Adapters grouped by how their rasterisers compare.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AdapterClass {
    /// Data-centre GPUs on which few units run graphics (NVIDIA H100, H200, A100, …).
    FewGraphicsUnits,
    /// A CPU implementation (lavapipe): both rasterisers run on the CPU.
    Cpu,
    /// Every other GPU.
    Graphics,
}

const NVIDIA: u32 = 0x10de;
/// Name fragments of NVIDIA's compute-first data-centre parts.
const FEW_GRAPHICS_UNITS: [&str; 6] = ["H100", "H200", "H800", "H20", "A100", "A800"];

/// A split larger than any viewport: every cluster to software but those crossing the
/// near plane.
pub const EVERY_CLUSTER_PX: f32 = 16384.0;

impl AdapterClass {
    pub fn of(info: &wgpu::AdapterInfo) -> Self {
        Self::classify(&info.name, info.vendor, info.device_type)
    }

    /// The class of an adapter with this name, PCI vendor id and device type.
    pub fn classify(name: &str, vendor: u32, device_type: wgpu::DeviceType) -> Self {
        if device_type == wgpu::DeviceType::Cpu {
            return Self::Cpu;
        }
        let name = name.to_uppercase();
        if vendor == NVIDIA && FEW_GRAPHICS_UNITS.iter().any(|n| name.contains(n)) {
            return Self::FewGraphicsUnits;
        }
        Self::Graphics
    }

    /// The default `sw_threshold_px` for this class, and why.
    /// [`EVERY_CLUSTER_PX`]: every cluster not crossing the near plane to software.
    pub fn sw_threshold_px(self) -> (f32, &'static str) {
        match self {
            // Measured on an H200 (docs/BENCHMARKS.md): with big triangles tiled in
            // software, sending every cluster there (all but those crossing the near
            // plane, which `hardware_raster` below decides) took the default scene at
            // 3840×2160 from 3.49 to 1.62 ms and at 1920×1080 from 1.28 to 0.87 ms.
            Self::FewGraphicsUnits => (
                EVERY_CLUSTER_PX,
                "measured on an H200: hardware raster runs on 2 TPCs, and software with big triangles tiled wins at every cluster size, so only clusters crossing the near plane go to hardware",
            ),
            Self::Cpu => (
                EVERY_CLUSTER_PX,
                "a CPU adapter runs both rasterisers on the CPU; the data-centre default keeps its images comparable",
            ),
            // Not measured here: Nanite's rule of thumb sends clusters whose triangles
            // are about a pixel or smaller to software; a 128-triangle cluster under 32 px
            // has triangles of a few pixels.
            Self::Graphics => (
                32.0,
                "not measured on such a GPU: hardware raster is fast where every unit runs graphics, so only small clusters go to software",
            ),
        }
    }

    /// Whether the frame has a hardware rasteriser at all, and why. Without one,
    /// culling sends every cluster to software, which clips clusters crossing the near
    /// plane itself.
    /// `hw_raster`'s implementations in `auto`'s order of preference on this class.
    pub fn hardware_feeds(self) -> [meshlight::hw_raster::Feed; 2] {
        use meshlight::hw_raster::Feed;
        match self {
            // Measured on an H100 (docs/BENCHMARKS.md, rasterisers): the indirect draw
            // ran the same clusters 1.19× faster than mesh shaders on the 2 TPCs that
            // run graphics there.
            Self::FewGraphicsUnits => [Feed::IndirectDraw, Feed::MeshShader],
            Self::Cpu | Self::Graphics => [Feed::MeshShader, Feed::IndirectDraw],
        }
    }

    pub fn hardware_raster(self) -> (bool, &'static str) {
        match self {
            // Measured on an H100 (docs/BENCHMARKS.md): the default scene at 1920×1080
            // takes 0.852 ms with the near clusters clipped in software, 0.901 ms with
            // them and both hw_raster passes on the 2 TPCs that run graphics (3840×2160:
            // 1.589 and 1.653 ms).
            Self::FewGraphicsUnits => (
                false,
                "measured on an H100: clipping the near clusters in software and dropping both hardware passes saves 4-5% of the default frame",
            ),
            // Both rasterisers run on the CPU; the frame keeps both halves of the split
            // (near clusters to hardware), so the default frame exercises both.
            Self::Cpu => (
                true,
                "a CPU adapter: clusters crossing the near plane go to the hardware rasteriser, so the default frame runs both",
            ),
            Self::Graphics => (
                true,
                "hardware raster is fast where every unit runs graphics: large clusters and those crossing the near plane go there",
            ),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::FewGraphicsUnits => "data-centre GPU with few graphics units",
            Self::Cpu => "CPU adapter",
            Self::Graphics => "graphics GPU",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_follow_the_adapter() {
        let discrete = wgpu::DeviceType::DiscreteGpu;
        assert_eq!(
            AdapterClass::classify("NVIDIA H100 80GB HBM3", NVIDIA, discrete),
            AdapterClass::FewGraphicsUnits
        );
        assert_eq!(
            AdapterClass::classify("NVIDIA H200", NVIDIA, discrete),
            AdapterClass::FewGraphicsUnits
        );
        assert_eq!(
            AdapterClass::classify("NVIDIA GeForce RTX 4090", NVIDIA, discrete),
            AdapterClass::Graphics
        );
        assert_eq!(
            AdapterClass::classify(
                "llvmpipe (LLVM 15.0.6, 256 bits)",
                0x10005,
                wgpu::DeviceType::Cpu
            ),
            AdapterClass::Cpu
        );
        assert!(
            AdapterClass::Graphics.sw_threshold_px().0
                < AdapterClass::FewGraphicsUnits.sw_threshold_px().0
        );
    }

    /// `auto` takes the indirect draw where few units run graphics and mesh shaders
    /// elsewhere, on an adapter that has both.
    #[test]
    fn auto_orders_the_hardware_rasterisers_by_class() {
        use crate::frame_graph::{FrameSettings, build};
        let asset = meshlight::scene::build_asset(
            &meshlight::scene::procedural_mesh(6),
            &meshlight::scene::BuildOptions::default(),
            &mut |_| {},
        )
        .unwrap()
        .asset;
        let placed = crate::scenes::field(
            meshlight::gpu_scene::SceneData::new(Default::default()),
            &asset,
            4,
        )
        .unwrap();
        for (class, want) in [
            (AdapterClass::FewGraphicsUnits, "indirect_draw"),
            (AdapterClass::Graphics, "mesh_shader"),
        ] {
            let settings = FrameSettings {
                hardware: Some(true),
                adapter_class: Some(class),
                ..FrameSettings::new(64, 64)
            };
            let shipped = std::path::Path::new(concat!(
                concat!(env!("CARGO_MANIFEST_DIR"), "/../.."),
                "/pipelines/virtual_geometry.toml"
            ));
            // The frame built in code and the shipped file (whose hw_raster is `auto`).
            for g in [
                build(&placed.data, &settings).unwrap(),
                crate::frame_graph::load(shipped, &placed.data, &settings)
                    .unwrap_or_else(|e| panic!("{e}")),
            ] {
                let compiled = g
                    .compile(&meshlight::graph::CompileOptions::new(wgpu::Features::all()))
                    .unwrap_or_else(|e| panic!("{e}"));
                let hw = compiled
                    .plan
                    .passes
                    .iter()
                    .find(|p| p.name == "hw_raster")
                    .expect("a hw_raster pass");
                assert_eq!(hw.implementation, want, "{class:?}");
            }
        }
    }
}
