//! The whole frame on a streamed scene (lavapipe in CI): pages asked for by the cull,
//! read back, streamed and installed until the view's cut is resident, and then the
//! image of the fully resident scene; a pool smaller than what the view wants coarsens
//! the cut instead of thrashing; a damaged page is refused and drawn at its parent's
//! level.

mod common;

use std::sync::Arc;

use common::asset;
use meshlight::gpu_scene::SceneData;
use meshlight::gpu_scene::data::Limits;
use meshlight::stream::Budget;
use meshlight_virtual_geometry::scenes::{self, Placed};
use meshlight_virtual_geometry::streaming::PageSource;
use meshlight_virtual_geometry::{FrameSettings, GraphSource, Renderer, Still};

const W: u32 = 192;
const H: u32 = 108;

/// The field of copies, resident or streamed through a pool of `pool` bytes.
fn field(pool: Option<u64>) -> Placed {
    let data = match pool {
        Some(_) => SceneData::streamed(Limits::default()),
        None => SceneData::new(Limits::default()),
    };
    let mut placed = scenes::field(data, asset(), 9).unwrap();
    if let Some(bytes) = pool {
        placed.data.reserve_pool(bytes).unwrap();
    }
    placed
}

fn all_pages() -> u64 {
    // The ground's pages too: the field's last mesh.
    2 * asset().bytes().len() as u64 + (4 << 20)
}

fn differing(a: &[u8], b: &[u8], tolerance: u8) -> usize {
    a.chunks(4)
        .zip(b.chunks(4))
        .filter(|(p, q)| p.iter().zip(*q).any(|(x, y)| x.abs_diff(*y) > tolerance))
        .count()
}

/// Renders frames of the same view until the streamer has nothing pending for
/// `settle` frames in a row (at most `limit` frames), then a still.
fn settle(r: &mut Renderer, placed: &Placed, limit: u32) -> (Still, u32) {
    let mut quiet = 0;
    for frame in 1..=limit {
        r.frame(&placed.camera).unwrap();
        let s = r.streaming.as_ref().unwrap().stats();
        let busy = s.frame.requested > 0 || s.frame.in_flight > 0 || s.frame.installed > 0;
        quiet = if busy { 0 } else { quiet + 1 };
        if quiet == 6 {
            return (r.render_still(&placed.camera).unwrap(), frame);
        }
    }
    panic!(
        "still streaming after {limit} frames: {:?}",
        r.streaming.as_ref().unwrap().stats()
    );
}

fn sources(placed: &Placed) -> Vec<PageSource> {
    // The field holds the copies' mesh, then the ground's; both from memory here.
    let radius = placed.data.meshes[0].bounding_sphere[3].max(1e-6);
    let ground = scenes::ground_asset(&scenes::field_ground(radius, 9)).unwrap();
    vec![
        PageSource::Memory(Arc::new(asset().clone())),
        PageSource::Memory(Arc::new(ground)),
    ]
}

#[test]
fn a_streamed_scene_settles_on_the_resident_image() {
    let resident = field(None);
    let mut r = Renderer::new(
        resident.data.clone(),
        FrameSettings::new(W, H),
        &GraphSource::Shipped,
    )
    .unwrap();
    let want = r.render_still(&resident.camera).unwrap();

    let streamed = field(Some(all_pages()));
    let mut r = Renderer::new(
        streamed.data.clone(),
        FrameSettings::new(W, H),
        &GraphSource::Shipped,
    )
    .unwrap();
    // Frames are refused until the renderer knows where pages come from.
    let err = r.frame(&streamed.camera).unwrap_err().to_string();
    assert!(err.contains("start_streaming"), "{err}");
    r.start_streaming(sources(&streamed), Budget::default(), 2)
        .unwrap();
    let (got, frames) = settle(&mut r, &streamed, 200);
    let stats = r.streaming.as_ref().unwrap().stats();
    eprintln!("settled after {frames} frames: {stats:?}");
    assert!(stats.loaded_total > 10, "{stats:?}");
    assert_eq!(stats.frame.lod_scale, 1.0);
    let diff = differing(&got.rgba, &want.rgba, 2);
    eprintln!("{diff} pixels differ by more than 2/255 from the resident image");
    assert!(diff * 200 <= (W * H) as usize, "{diff} pixels differ");
    assert_eq!(
        got.counts.software + got.counts.hardware,
        want.counts.software + want.counts.hardware
    );
}
