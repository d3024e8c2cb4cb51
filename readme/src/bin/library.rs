//! The README's "Use it as a library": a field of procedural meshes rendered to an image,
//! with no file to find.
use meshlight::gpu_scene::SceneData;
use meshlight_virtual_geometry::{FrameSettings, GraphSource, Renderer, scenes};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // The procedural mesh (16 × 64² triangles), baked on first use and cached.
    let asset = scenes::load_asset("procedural".as_ref(), 64)?;
    let placed = scenes::field(SceneData::new(Default::default()), &asset, 64)?;
    let settings = FrameSettings::new(640, 360);
    let mut renderer = Renderer::new(placed.data, settings, &GraphSource::Shipped)?;
    let still = renderer.render_still(&placed.camera)?;
    println!("{} × {} RGBA pixels", still.width, still.height);
    for (counter, value) in still.counts.rows() {
        println!("{counter:<30} {value}");
    }
    Ok(())
}
