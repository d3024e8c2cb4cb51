// Depth and material-depth resolve: a fullscreen triangle whose fragments write
// `frag_depth` from the visibility buffer. `cpu::depth` and `cpu::material_depth` are
// the references.

#import meshlight::instance::Instance
#import meshlight::instance_table::instance_at
#import meshlight::meshlet::meshlet_material
#import meshlight::scene_buffers::meshlets
#import meshlight::visbuffer::{visbuffer_is_empty, visbuffer_depth, visbuffer_cluster}
#import resolve::visibility::{raster_clusters, visibility_at}

// The uniform block, declared once for Rust and WGSL by `DepthParams` in lib.rs.
#import resolve::depth_params::Params

// Bindings 0 and 1: the visibility buffer and `raster_clusters` (resolve::visibility).
// The instances: `instance_at` (meshlight::instance_table, bindings 30 and 31); the
// meshlets, for their material slots (meshlight::scene_buffers).
@group(0) @binding(3) var<uniform> params: Params;

// 2^-24: material ids map to multiples of it, exact in f32 below 2^24.
const MATERIAL_DEPTH_STEP: f32 = 5.9604644775390625e-8;
const MATERIAL_DEPTH_MAX_ID: u32 = 0xfffffeu;

// The depth a material pass tests with Equal: (material + 1) · 2^-24, never 0 (empty).
fn material_depth(material: u32) -> f32 {
    return f32(min(material, MATERIAL_DEPTH_MAX_ID) + 1u) * MATERIAL_DEPTH_STEP;
}

@vertex
fn fullscreen_vs(@builtin(vertex_index) v: u32) -> @builtin(position) vec4<f32> {
    // One triangle covering the viewport: (-1, -1), (3, -1), (-1, 3).
    let xy = vec2(f32((v << 1u) & 2u), f32(v & 2u)) * 2.0 - 1.0;
    return vec4(xy, 0.0, 1.0);
}

fn value_at(position: vec4<f32>) -> vec2<u32> {
    let x = min(u32(position.x), params.width - 1u);
    let y = min(u32(position.y), params.height - 1u);
    return visibility_at(vec2(x, y), params.width);
}

@fragment
fn depth_fs(@builtin(position) position: vec4<f32>) -> @builtin(frag_depth) f32 {
    let value = value_at(position);
    return select(visbuffer_depth(value), 0.0, visbuffer_is_empty(value));
}

@fragment
fn material_depth_fs(@builtin(position) position: vec4<f32>) -> @builtin(frag_depth) f32 {
    let value = value_at(position);
    if visbuffer_is_empty(value) {
        return 0.0;
    }
    let cluster = raster_clusters[visbuffer_cluster(value)];
    return material_depth(instance_at(cluster.instance).material + meshlet_material(meshlets[cluster.meshlet]));
}
