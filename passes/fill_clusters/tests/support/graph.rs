//! The graphs the GPU tests and the `walk_vs_flat` example build: a fill over the GPU
//! scene's imports, and `cull_lod` after it. Every slot binds to the resource of its
//! name, so only the buffers are declared here.

use meshlight_gpu_scene::GpuScene;
use meshlight_gpu_scene::gpu::elements;
use meshlight_graph::{Bindings, BufferDesc, Element, GraphBuilder, Pass, PassOutputs, Result};
use meshlight_pass_cull_lod::CullLod;
use meshlight_pass_fill_clusters::hierarchy;

/// Adds `fill` (pass `fill`) over the scene's imports, writing the `clusters` the caller
/// declared and a `cluster_count`; the `hierarchy` implementation also gets the
/// hierarchy's buffers and a 4-word `hierarchy_counts`. Exports the count words and
/// returns whether the fill walks the hierarchy.
pub fn add_fill(g: &mut GraphBuilder, scene: &GpuScene, fill: Box<dyn Pass>) -> Result<bool> {
    let walks = fill.implementation().name == hierarchy::IMPLEMENTATION;
    scene.import(g);
    g.create_buffer("cluster_count", BufferDesc::array(Element::U32, 2));
    if walks {
        scene.import_hierarchy(g);
        g.create_buffer(hierarchy::COUNTS_SLOT, BufferDesc::array(Element::U32, 4));
    }
    let out = g.add_boxed_pass("fill", fill, Bindings::new())?;
    g.export(out.buffer("cluster_count")?);
    if walks {
        g.export(out.buffer(hierarchy::COUNTS_SLOT)?);
    }
    Ok(walks)
}

/// Adds `cull` (pass `cull`) after the fill, with a raster list of `slots` clusters.
/// Exports the raster counts.
pub fn add_cull(g: &mut GraphBuilder, cull: CullLod, slots: u64) -> Result<PassOutputs> {
    g.create_buffer(
        "raster_clusters",
        BufferDesc::array(elements::CLUSTER, slots),
    );
    g.create_buffer("raster_counts", BufferDesc::array(Element::U32, 8));
    g.create_buffer("hw_args", BufferDesc::array(Element::DRAW_ARGS, 1));
    let culled = g.add_pass("cull", cull, Bindings::new())?;
    g.export(culled.buffer("raster_counts")?);
    Ok(culled)
}
