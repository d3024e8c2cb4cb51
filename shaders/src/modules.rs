//! The list of shared WGSL modules, in the order they must be added (imports first).

use naga::valid::Capabilities;

/// One shared WGSL module, imported by pass shaders as `#import <name>`.
#[derive(Clone, Copy, Debug)]
pub struct SharedModule {
    /// The import path, e.g. `meshlight::view`; equals the file's `#define_import_path`.
    pub name: &'static str,
    /// Where the source lives in the repository, for diagnostics.
    pub file_path: &'static str,
    /// The WGSL source.
    pub source: &'static str,
    /// What the device must support for this module to be offered at all.
    pub capabilities: Capabilities,
}

macro_rules! shared {
    ($name:literal, $file:literal) => {
        shared!($name, $file, Capabilities::empty())
    };
    ($name:literal, $file:literal, $caps:expr) => {
        SharedModule {
            name: $name,
            file_path: concat!("shaders/src/wgsl/", $file),
            source: include_str!(concat!("wgsl/", $file)),
            capabilities: $caps,
        }
    };
}

static SHARED_MODULES: [SharedModule; 16] = [
    shared!("meshlight::math", "math.wgsl"),
    shared!("meshlight::dispatch", "dispatch.wgsl"),
    shared!("meshlight::view", "view.wgsl"),
    shared!("meshlight::octahedral", "octahedral.wgsl"),
    shared!("meshlight::meshlet", "meshlet.wgsl"),
    shared!("meshlight::instance", "instance.wgsl"),
    shared!("meshlight::instance_table", "instance_table.wgsl"),
    shared!("meshlight::scene_buffers", "scene_buffers.wgsl"),
    shared!("meshlight::cluster_triangle", "cluster_triangle.wgsl"),
    shared!("meshlight::texture", "texture.wgsl"),
    shared!("meshlight::surface", "surface.wgsl"),
    shared!("meshlight::occlusion", "occlusion.wgsl"),
    shared!("meshlight::visbuffer", "visbuffer.wgsl"),
    shared!(
        "meshlight::visbuffer64",
        "visbuffer64.wgsl",
        Capabilities::SHADER_INT64
    ),
    shared!("meshlight::light", "light.wgsl"),
    shared!("meshlight::froxel", "froxel.wgsl"),
];

/// Every shared module, imports before importers.
pub fn shared_modules() -> &'static [SharedModule] {
    &SHARED_MODULES
}
