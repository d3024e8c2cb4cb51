//! meshlight as a library: spot on the field, one frame rendered, its size and counters.
//! The README shows this file; `tests/readme.rs` checks the two agree and runs it.
use meshlight::gpu_scene::SceneData;
use meshlight_virtual_geometry::{FrameSettings, GraphSource, Renderer, scenes};

pub fn main() -> Result<(), Box<dyn std::error::Error>> {
    let asset = scenes::load_asset("assets/meshes/spot.obj".as_ref(), 0)?;
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
