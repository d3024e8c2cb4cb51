//! What the fill tests share: buffer usage, the sentinel guarding unwritten slots, the
//! adapter, the test meshes baked once, a seeded generator and cluster sets.
#![allow(dead_code)]

use meshlight_scene::{BuildOptions, MeshletAsset, build_asset};
use meshlight_shaders::cpu::layout::Cluster;
use std::collections::BTreeSet;
use std::sync::OnceLock;

pub const USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_DST)
    .union(wgpu::BufferUsages::COPY_SRC);

/// What the GPU leaves in slots nothing may write.
pub const SENTINEL: Cluster = Cluster {
    instance: 0xdead_beef,
    meshlet: 0xfeed_f00d,
};

/// Slots after the capacity (or the list) that must keep the sentinel.
pub const GUARD: u32 = 64;

#[allow(unused_imports)] // not every test binary that includes this module opens a GPU
pub use meshlight_testing::gpu;

/// A mesh of assets/meshes baked with the default options.
fn bake_file(name: &str) -> MeshletAsset {
    let path = format!("{}/../../assets/meshes/{name}", env!("CARGO_MANIFEST_DIR"));
    let mesh = meshlight_scene::load::load_mesh(std::path::Path::new(&path)).unwrap();
    build_asset(&mesh, &BuildOptions::default(), &mut |_| {})
        .unwrap()
        .asset
}

pub fn bunny() -> &'static MeshletAsset {
    static ASSET: OnceLock<MeshletAsset> = OnceLock::new();
    ASSET.get_or_init(|| bake_file("stanford-bunny.obj"))
}

pub fn spot() -> &'static MeshletAsset {
    static ASSET: OnceLock<MeshletAsset> = OnceLock::new();
    ASSET.get_or_init(|| bake_file("spot.obj"))
}

/// xorshift64*: seeded, reproducible views.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    pub fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }
    pub fn below(&mut self, n: u32) -> u32 {
        (self.next() % n as u64) as u32
    }
}

pub fn set(clusters: &[Cluster]) -> BTreeSet<(u32, u32)> {
    clusters.iter().map(|c| (c.instance, c.meshlet)).collect()
}
