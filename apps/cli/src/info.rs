//! `meshlight info`: the adapter, what of it meshlight uses, and what `auto` picks there.
//!
//! The choices are not predicted here: the shipped virtual-geometry pipeline is compiled
//! for the adapter, and its plan says what compile picked and why, exactly as a render
//! on that adapter would.

use meshlight::graph::{AdapterClass, CompileOptions, GpuAdapter};
use std::fmt::Write;

/// Features that decide which implementations run, or how fast.
const FEATURES: [(wgpu::Features, &str); 11] = [
    (
        wgpu::Features::SHADER_INT64,
        "64-bit integers in shaders (every rasteriser)",
    ),
    (
        wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX,
        "64-bit buffer atomics (sw_raster `buffer`, hw_raster)",
    ),
    (
        wgpu::Features::TEXTURE_ATOMIC,
        "texture atomics (sw_raster `texture`)",
    ),
    (
        wgpu::Features::TEXTURE_INT64_ATOMIC,
        "64-bit texture atomics (sw_raster `texture`)",
    ),
    (
        wgpu::Features::CLEAR_TEXTURE,
        "texture clears (sw_raster `texture`)",
    ),
    (
        wgpu::Features::EXPERIMENTAL_MESH_SHADER,
        "mesh shaders (hw_raster `mesh_shader`)",
    ),
    (wgpu::Features::SUBGROUP, "subgroup operations (scan_fan)"),
    (
        wgpu::Features::TIMESTAMP_QUERY,
        "GPU timestamps (timings, bench)",
    ),
    (
        wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS,
        "timestamps between passes (per-pass timings)",
    ),
    (
        wgpu::Features::INDIRECT_FIRST_INSTANCE,
        "indirect draws with a first instance (count_raster `raster`)",
    ),
    (
        wgpu::Features::MULTI_DRAW_INDIRECT_COUNT,
        "indirect draw counts",
    ),
];

/// `(name, value)` for each named field of a `wgpu::Limits`: the report names a limit by
/// its field, so the name is the field's own and cannot drift from it.
macro_rules! limit_rows {
    ($limits:expr; $($field:ident),* $(,)?) => {
        [$((stringify!($field), u64::from($limits.$field))),*]
    };
}

/// The report `meshlight info` prints.
pub fn report() -> Result<String, Box<dyn std::error::Error>> {
    let adapter = GpuAdapter::select()?;
    let info = adapter.info();
    let features = adapter.features();
    let limits = adapter.adapter.limits();
    let mut out = String::new();
    writeln!(
        out,
        "adapter: {} ({:?}, {:?}; driver {} {})",
        info.name, info.backend, info.device_type, info.driver, info.driver_info
    )?;
    let class = AdapterClass::of(&info);
    let (threshold, why) = meshlight::cull_lod::sw_threshold_on(class);
    writeln!(out, "class: {}", class.name())?;
    writeln!(
        out,
        "software/hardware split: clusters under {threshold} px go to sw_raster ({why})"
    )?;
    let (hardware, why) = class.hardware_raster();
    if hardware {
        writeln!(out, "hw_raster: in the frame ({why})")?;
    } else {
        writeln!(
            out,
            "hw_raster: not in the frame; sw_raster clips clusters crossing the near plane ({why})"
        )?;
    }
    writeln!(out, "\nfeatures:")?;
    for (feature, what) in FEATURES {
        let mark = if features.contains(feature) {
            "yes"
        } else {
            "no "
        };
        let name = feature.iter_names().next().map(|(n, _)| n).unwrap_or("?");
        writeln!(out, "  {mark}  {name:<34} {what}")?;
    }
    writeln!(out, "\nlimits:")?;
    for (name, value) in limit_rows!(
        limits;
        max_compute_workgroups_per_dimension,
        max_storage_buffer_binding_size,
        max_buffer_size,
        max_texture_dimension_2d,
        max_compute_workgroup_storage_size,
        max_mesh_output_vertices,
        max_mesh_output_primitives,
        max_mesh_workgroups_per_dimension,
        max_mesh_workgroup_total_count,
    ) {
        writeln!(out, "  {name:<38} {value}")?;
    }
    let scene = meshlight::gpu_scene::data::Limits::for_device(&limits);
    writeln!(
        out,
        "\nscene budget (each scene buffer is bound whole, so one storage binding bounds it):"
    )?;
    writeln!(
        out,
        "  textures: {} MiB ({} RGBA8 texels, mips included; each texture square, at most {} a side)",
        (scene.max_texture_words as u64 * 4) >> 20,
        scene.max_texture_words,
        1u32 << meshlight::shaders::cpu::layout::MAX_TEXTURE_SIZE_LOG2
    )?;
    writeln!(
        out,
        "  meshlets: {}, payload words: {}, instances: {}",
        scene.max_meshlets, scene.max_payload_words, scene.max_instances
    )?;
    writeln!(
        out,
        "  streaming pool: {} MiB by default (a quarter of the payload binding; baked assets \
         whose payload is larger stream through it, --pool-mb chooses another size)",
        meshlight_virtual_geometry::streaming::default_pool_bytes(&scene) >> 20
    )?;
    writeln!(
        out,
        "\nrender bounds (what the renderer holds with wgpu's default limits, which every device meets; checked before a render bakes a mesh or asks for the adapter):"
    )?;
    for line in crate::render_bounds::lines() {
        writeln!(out, "  {line}")?;
    }
    let registry = meshlight::registry();
    writeln!(
        out,
        "\nstages and their implementations (the registry pipeline files and --sw-raster/--hw-raster name them from):"
    )?;
    for stage in registry.stage_names() {
        writeln!(
            out,
            "  {stage:<16} {}",
            registry.implementations(&stage).join(", ")
        )?;
    }
    writeln!(
        out,
        "\nauto picks (pipelines/virtual_geometry.toml compiled for this adapter):"
    )?;
    use meshlight_virtual_geometry::frame_graph::{SHIPPED, SHIPPED_FILE};
    let graph = meshlight::graph::file::parse_pipeline(SHIPPED, SHIPPED_FILE, &registry)?;
    let plan = graph.compile(&CompileOptions::for_adapter(&adapter))?.plan;
    for p in &plan.passes {
        if let Some(decision) = p.decision() {
            writeln!(
                out,
                "  {:<18} {:<22} {decision}",
                p.name,
                p.implementation_label()
            )?;
        }
    }
    Ok(out)
}
