//! What kind of adapter a graph is planned for, beyond its features: how many of its
//! units run graphics work. Two adapters with the same features can want different
//! implementations of a stage; the NVIDIA H100 and H200 run vertex and fragment work on
//! 2 of their TPCs only, so there a compute path wins where a graphics GPU would
//! rasterise in hardware. Compile plans for one class ([`crate::CompileOptions`]), so
//! every tool that compiles a pipeline for the same adapter picks the same
//! implementations, and the dumps say which class decided.

use serde::Serialize;

/// Adapters grouped by how their rasterisers compare.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum AdapterClass {
    /// A GPU whose every unit runs graphics work (the class planned for without an
    /// adapter).
    #[default]
    Graphics,
    /// A data-centre GPU on which few units run graphics (NVIDIA H100, H200, A100, …).
    FewGraphicsUnits,
    /// A CPU implementation (lavapipe): both rasterisers run on the CPU.
    Cpu,
}

/// PCI vendor id of NVIDIA.
const NVIDIA: u32 = 0x10de;
/// Name fragments of NVIDIA's compute-first data-centre parts.
const FEW_GRAPHICS_UNITS: [&str; 6] = ["H100", "H200", "H800", "H20", "A100", "A800"];

impl AdapterClass {
    /// Every class, for tools that list or sweep them.
    pub const ALL: [AdapterClass; 3] = [
        AdapterClass::Graphics,
        AdapterClass::FewGraphicsUnits,
        AdapterClass::Cpu,
    ];

    /// The class of the adapter `info` describes.
    pub fn of(info: &wgpu::AdapterInfo) -> Self {
        Self::classify(&info.name, info.vendor, info.device_type)
    }

    /// The class of an adapter by its name, PCI vendor id and device type.
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

    /// How reports name the class.
    pub fn name(self) -> &'static str {
        match self {
            Self::FewGraphicsUnits => "data-centre GPU with few graphics units",
            Self::Cpu => "CPU adapter",
            Self::Graphics => "graphics GPU",
        }
    }

    /// The short name tools take on the command line: `graphics`,
    /// `few-graphics-units`, `cpu`.
    pub fn key(self) -> &'static str {
        match self {
            Self::FewGraphicsUnits => "few-graphics-units",
            Self::Cpu => "cpu",
            Self::Graphics => "graphics",
        }
    }

    /// The class whose [`Self::key`] is `key`.
    pub fn parse(key: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.key() == key)
    }

    /// Whether a frame should rasterise in hardware at all on this class, and why: where
    /// it does not, clusters crossing the near plane are clipped by the software
    /// rasteriser and the hardware passes have nothing to draw. Culling and the hardware
    /// rasteriser both follow this one rule, so they always agree.
    pub fn hardware_raster(self) -> (bool, &'static str) {
        match self {
            // Measured on an H100 (docs/BENCHMARKS.md): the default scene at 1920×1080
            // takes 0.852 ms with the near clusters clipped in software, 0.901 ms with
            // them and both hw_raster passes on the 2 TPCs that run graphics (3840×2160:
            // 1.589 and 1.653 ms).
            Self::FewGraphicsUnits => (
                false,
                "on a data-centre GPU with few graphics units, clipping the near clusters in software and running no hardware raster saved 4-5% of the default frame (measured on an H100)",
            ),
            Self::Cpu => (
                true,
                "on a CPU adapter clusters crossing the near plane go to the hardware rasteriser, so a frame runs both rasterisers",
            ),
            Self::Graphics => (
                true,
                "hardware raster is fast where every unit runs graphics: large clusters and those crossing the near plane go there",
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_follow_the_adapter() {
        let discrete = wgpu::DeviceType::DiscreteGpu;
        for (name, vendor, device_type, class) in [
            (
                "NVIDIA H100 80GB HBM3",
                NVIDIA,
                discrete,
                AdapterClass::FewGraphicsUnits,
            ),
            (
                "NVIDIA H200",
                NVIDIA,
                discrete,
                AdapterClass::FewGraphicsUnits,
            ),
            (
                "NVIDIA GeForce RTX 4090",
                NVIDIA,
                discrete,
                AdapterClass::Graphics,
            ),
            // A name alone does not make the class: the vendor must be NVIDIA.
            ("H100 lookalike", 0x1002, discrete, AdapterClass::Graphics),
            (
                "llvmpipe (LLVM 15.0.6, 256 bits)",
                0x10005,
                wgpu::DeviceType::Cpu,
                AdapterClass::Cpu,
            ),
        ] {
            assert_eq!(
                AdapterClass::classify(name, vendor, device_type),
                class,
                "{name}"
            );
        }
    }

    #[test]
    fn keys_round_trip_and_unknown_ones_are_refused() {
        for c in AdapterClass::ALL {
            assert_eq!(AdapterClass::parse(c.key()), Some(c));
        }
        assert_eq!(AdapterClass::parse("h200"), None);
    }
}
