//! The streamer's rules as properties, on random DAGs under random views, reads that
//! finish late or fail, and pools far smaller than the mesh; and the cut on a real
//! mesh's DAG under a tiny pool.

use std::collections::BTreeMap;

use meshlight_scene::asset::format::NO_GROUP;
use meshlight_shaders::cpu::layout::View;
use meshlight_shaders::cpu::lod::{error_perceptible, project_error_to_pixels};
use meshlight_shaders::cpu::rng::Rng;
use meshlight_stream::cut::{check, select};
use meshlight_stream::pressure::LodPressure;
use meshlight_stream::streamer::{PageState, StreamError};
use meshlight_stream::{Budget, FramePlan, MeshDag, PageGraph, PageId, Request, Streamer};
use proptest::prelude::*;

/// A random meshlet DAG shaped like the builder's: LOD-0 meshlets grouped by one to four,
/// each group producing one or two meshlets of the next level, until at most two roots
/// are left; group errors grow up the DAG.
fn random_dag(rng: &mut Rng, lod0: u32) -> (MeshDag, Vec<f32>) {
    let mut dag = MeshDag::default();
    let mut errors = Vec::new();
    let mut level: Vec<(u32, f32)> = Vec::new(); // (meshlet, its own error)
    for _ in 0..lod0 {
        level.push((dag.source.len() as u32, 0.0));
        dag.source.push(NO_GROUP);
        dag.parent.push(NO_GROUP);
        dag.payload_bytes.push(100 + rng.below(2000));
    }
    while level.len() > 2 {
        let mut next = Vec::new();
        let mut i = 0;
        while i < level.len() {
            let take = (1 + rng.below(4) as usize).min(level.len() - i);
            let group = errors.len() as u32;
            let children = &level[i..i + take];
            let error = children.iter().map(|c| c.1).fold(0.0, f32::max) + rng.range(0.5, 2.0);
            errors.push(error);
            for &(m, _) in children {
                dag.parent[m as usize] = group;
            }
            // A group of one that keeps one meshlet would never shrink: make it merge.
            let outputs = if take == 1 { 1 } else { 1 + rng.below(2) };
            for _ in 0..outputs {
                next.push((dag.source.len() as u32, error));
                dag.source.push(group);
                dag.parent.push(NO_GROUP);
                dag.payload_bytes.push(100 + rng.below(2000));
            }
            i += take;
        }
        if next.len() >= level.len() {
            // No progress this round (all singles): merge everything left into one group.
            let group = errors.len() as u32;
            let error = next.iter().map(|c| c.1).fold(0.0, f32::max) + 1.0;
            errors.push(error);
            for &(m, _) in &next {
                dag.parent[m as usize] = group;
            }
            let root = dag.source.len() as u32;
            dag.source.push(group);
            dag.parent.push(NO_GROUP);
            dag.payload_bytes.push(100);
            next = vec![(root, error)];
        }
        level = next;
    }
    dag.group_count = errors.len() as u32;
    (dag, errors)
}

/// What the renderer keeps of the streamer's plans: the page table, and reads in flight
/// with the frame each finishes in.
struct Renderer {
    resident: Vec<bool>,
    reads: BTreeMap<u64, Vec<PageId>>,
}

impl Renderer {
    /// Applies a plan as the renderer would (evictions, then installs), checking every
    /// rule a plan must keep.
    fn apply(&mut self, streamer: &Streamer, plan: &FramePlan, budget: &Budget) {
        let graph = streamer.graph();
        assert!(plan.install.len() <= budget.installs_per_frame as usize);
        assert!(plan.evict.len() <= budget.evictions_per_frame as usize);
        let bytes: u64 = plan.install.iter().map(|i| i.data.len() as u64).sum();
        assert!(
            plan.install.len() <= 1 || bytes <= budget.upload_bytes_per_frame,
            "{bytes} bytes in {} installs",
            plan.install.len()
        );
        assert!(plan.stats.in_flight <= budget.loads_in_flight);
        for &page in &plan.evict {
            assert!(
                self.resident[page as usize],
                "page {page} evicted but not resident"
            );
            self.resident[page as usize] = false;
        }
        for install in &plan.install {
            let page = install.page as usize;
            assert!(!self.resident[page]);
            for &q in graph.parents(install.page) {
                assert!(
                    self.resident[q as usize],
                    "page {page} installed before parent {q}"
                );
            }
            assert_eq!(install.data, page_bytes(graph, install.page));
            self.resident[page] = true;
        }
        // Never evict a dependency: nothing resident or being read needs an evicted page.
        for &page in &plan.evict {
            for &d in graph.dependents(page) {
                let state = streamer.state(d);
                assert!(
                    matches!(state, PageState::Absent | PageState::Failed),
                    "page {page} evicted while page {d}, which needs it, is {state:?}"
                );
            }
        }
        // The page table is the streamer's, closed under parents.
        for page in 0..graph.len() as PageId {
            assert_eq!(self.resident[page as usize], streamer.is_resident(page));
            if self.resident[page as usize] {
                for &q in graph.parents(page) {
                    assert!(self.resident[q as usize]);
                }
            }
        }
        // Room reserved for every page read or resident, none overlapping, within the pool.
        let mut ranges: Vec<(u64, u64)> = (0..graph.len() as PageId)
            .filter_map(|p| {
                streamer
                    .allocation(p)
                    .map(|a| (a.offset, a.offset + a.bytes))
            })
            .collect();
        ranges.sort();
        assert!(
            ranges.windows(2).all(|w| w[0].1 <= w[1].0),
            "overlapping pages"
        );
        assert!(ranges.last().is_none_or(|r| r.1 <= streamer.pool_bytes()));
        assert_eq!(
            ranges.iter().map(|r| r.1 - r.0).sum::<u64>(),
            streamer.pool_used()
        );
    }
}

/// A page's bytes as the reader returns them: recognisable per page.
fn page_bytes(graph: &PageGraph, page: PageId) -> Vec<u8> {
    (0..graph.bytes(page))
        .map(|i| (page as u64 * 31 + i) as u8)
        .collect()
}

fn length(v: [f32; 3]) -> f32 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// The groups whose error shows at `threshold`.
fn perceptible(errors: &[f32], threshold: f32) -> Vec<bool> {
    errors.iter().map(|&e| e > threshold).collect()
}

/// Runs `frames` frames of random views over a random DAG, checking the plan and the cut
/// every frame; returns how many pages were refused and how many evicted.
fn fly(seed: u64, frames: u64, pool_fraction: f32, failure_rate: f32) -> (u32, usize) {
    let mut rng = Rng(seed | 1);
    let lod0 = 20 + rng.below(200);
    let (dag, errors) = random_dag(&mut rng, lod0);
    let graph = dag.pages();
    let largest = (0..graph.len() as PageId)
        .map(|p| graph.bytes(p))
        .max()
        .unwrap();
    let pool = ((graph.total_bytes() as f32 * pool_fraction) as u64).max(largest + 256);
    let budget = Budget {
        installs_per_frame: 1 + rng.below(8),
        upload_bytes_per_frame: 1000 + u64::from(rng.below(20_000)),
        loads_in_flight: 1 + rng.below(16),
        evictions_per_frame: 1 + rng.below(8),
        keep_frames: u64::from(rng.below(4)),
        prefetch_levels: (seed % 4) as u32,
    };
    let mut streamer = Streamer::new(graph.clone(), pool, budget).unwrap();
    let mut renderer = Renderer {
        resident: vec![false; graph.len()],
        reads: BTreeMap::new(),
    };
    let top = errors.iter().cloned().fold(0.0, f32::max);
    let mut threshold = rng.range(0.0, top);
    let mut evicted = 0;
    for frame in 1..=frames {
        // The view drifts, now and then jumps.
        threshold = if rng.below(20) == 0 {
            rng.range(0.0, top)
        } else {
            (threshold + rng.range(-0.5, 0.5)).clamp(0.0, top)
        };
        let wanted_at = threshold * streamer.lod_scale();
        let shows = perceptible(&errors, wanted_at);
        // The GPU asks for the groups whose error shows, some of its words lost to
        // the frustum or late.
        let wanted: Vec<Request> = (0..dag.group_count)
            .filter(|&g| shows[g as usize] && rng.below(8) != 0)
            .map(|g| Request {
                page: g,
                priority: errors[g as usize] - wanted_at,
            })
            .collect();
        let plan = streamer.frame(frame, Some(&wanted));
        evicted += plan.evict.len();
        renderer.apply(&streamer, &plan, &budget);
        for load in &plan.load {
            let due = frame + u64::from(rng.below(5));
            renderer.reads.entry(due).or_default().push(load.page);
        }
        // Reads finishing by now, in any order, some failing or short.
        let due: Vec<u64> = renderer.reads.range(..=frame).map(|(&f, _)| f).collect();
        for f in due {
            let mut pages = renderer.reads.remove(&f).unwrap();
            if rng.below(2) == 0 {
                pages.reverse();
            }
            for page in pages {
                let result = if rng.unit() < failure_rate {
                    if rng.below(2) == 0 {
                        Err(format!("page {page}: checksum mismatch"))
                    } else {
                        Ok(vec![0; 3])
                    }
                } else {
                    Ok(page_bytes(&graph, page))
                };
                streamer.complete(page, result);
            }
        }
        // The cut the GPU draws with this page table is complete.
        let drawn = select(&dag, &shows, |g| renderer.resident[g as usize]);
        if let Err(hole) = check(&dag, &drawn, |g| renderer.resident[g as usize]) {
            panic!("frame {frame}: {hole}");
        }
    }
    let failures = streamer.take_failures();
    assert!(failures.iter().all(|f| !f.reason.is_empty()));
    (failures.len() as u32, evicted)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Parents before children, never evicting a dependency, budgets and the pool kept,
    /// and a complete cut every frame, whatever the views, delays and failures.
    #[test]
    fn every_frame_keeps_the_rules_and_draws_a_complete_cut(
        seed in any::<u64>(),
        pool_fraction in 0.02f32..1.2,
        failure_rate in prop_oneof![Just(0.0f32), 0.0f32..0.2],
    ) {
        fly(seed, 150, pool_fraction, failure_rate);
    }
}

#[test]
fn failed_reads_are_counted_and_the_cut_keeps_the_coarser_level() {
    let (mut refused, mut evicted) = (0, 0);
    for seed in 1..20 {
        let (r, e) = fly(seed, 100, 0.3, 0.3);
        refused += r;
        evicted += e;
    }
    assert!(
        refused > 0,
        "no read was refused: the test did not test refusal"
    );
    assert!(
        evicted > 0,
        "no page was evicted: the pool was not exercised"
    );
}

/// With a pool that holds the whole mesh, a view that stops moving settles: every page it
/// wants becomes resident, and the cut is the fully resident one.
#[test]
fn a_still_view_settles_on_the_fully_resident_cut() {
    for seed in 1..30 {
        let mut rng = Rng(seed);
        let lod0 = 50 + rng.below(300);
        let (dag, errors) = random_dag(&mut rng, lod0);
        let graph = dag.pages();
        let budget = Budget {
            installs_per_frame: 4,
            upload_bytes_per_frame: 16 << 10,
            loads_in_flight: 8,
            evictions_per_frame: 4,
            keep_frames: 2,
            prefetch_levels: 1,
        };
        let mut streamer = Streamer::new(graph.clone(), graph.total_bytes() * 2, budget).unwrap();
        let shows = perceptible(&errors, rng.range(0.0, 4.0));
        let wanted: Vec<Request> = (0..dag.group_count)
            .filter(|&g| shows[g as usize])
            .map(|page| Request {
                page,
                priority: 1.0,
            })
            .collect();
        let mut settled_at = None;
        for frame in 1..=400 {
            let plan = streamer.frame(frame, Some(&wanted));
            for load in plan.load {
                streamer.complete(load.page, Ok(page_bytes(&graph, load.page)));
            }
            if plan.stats.requested == 0 && plan.stats.in_flight == 0 {
                settled_at = Some(frame);
                break;
            }
        }
        let settled_at = settled_at.unwrap_or_else(|| panic!("seed {seed}: never settled"));
        let wanted_pages = wanted.len() as u64;
        // Reads and installs are budgeted: settling takes about pages / 4 frames.
        assert!(
            settled_at <= wanted_pages / 4 + 4,
            "seed {seed}: {settled_at} frames for {wanted_pages} pages"
        );
        let streamed = select(&dag, &shows, |g| streamer.is_resident(g));
        let resident = select(&dag, &shows, |_| true);
        assert_eq!(streamed, resident, "seed {seed}");
    }
}

/// A pool that wants more than it has raises the LOD scale; once the view wants less, the
/// scale relaxes to 1.
#[test]
fn pressure_raises_the_lod_scale_and_relaxes_it() {
    let mut rng = Rng(7);
    let (dag, errors) = random_dag(&mut rng, 400);
    let graph = dag.pages();
    let mut streamer =
        Streamer::new(graph.clone(), graph.total_bytes() / 4, Budget::default()).unwrap();
    let mut scales = Vec::new();
    for frame in 1..=300u64 {
        // Everything wanted for 150 frames, then only the roots' groups.
        let threshold = if frame <= 150 { 0.0 } else { f32::MAX };
        let wanted: Vec<Request> = (0..dag.group_count)
            .filter(|&g| errors[g as usize] > threshold * streamer.lod_scale())
            .map(|page| Request {
                page,
                priority: 1.0,
            })
            .collect();
        let plan = streamer.frame(frame, Some(&wanted));
        for load in plan.load {
            streamer.complete(load.page, Ok(page_bytes(&graph, load.page)));
        }
        scales.push(streamer.lod_scale());
    }
    assert!(scales[149] > 1.5, "{:?}", &scales[..150]);
    assert_eq!(scales[299], 1.0);
}

#[test]
fn a_pool_smaller_than_a_page_is_refused_with_both_sizes() {
    let graph = PageGraph::new(vec![100, 5000, 300], vec![vec![], vec![0], vec![0]]).unwrap();
    let err = Streamer::new(graph, 4096, Budget::default()).unwrap_err();
    assert_eq!(
        err,
        StreamError::PoolTooSmall {
            pool: 4096,
            page: 1,
            page_bytes: 5000
        }
    );
    assert_eq!(
        err.to_string(),
        "the page pool of 4096 bytes cannot hold page 1 of 5000 bytes: give the pool at least 5000 bytes"
    );
}

/// The LOD test on a real mesh's DAG: a camera flying around the bunny at random, near
/// and far, a pool of a third of the mesh (one LOD-0 page needs up to a fifth of it:
/// its ancestors), reads finishing a frame late. Every frame's cut, with the real
/// projected errors, is complete: with the pressure coupling, and without it (so that
/// the pool thrashes), prefetching no level below a request, one, or three.
#[test]
fn the_bunny_under_a_small_pool_never_shows_a_hole() {
    let flight = fly_around_the_bunny(LodPressure::default(), 1);
    assert!(
        flight.max_scale > 2.0,
        "the pressure never coarsened the cut: {flight:?}"
    );
    for prefetch in [0, 1, 3] {
        let flight = fly_around_the_bunny(LodPressure::new(0.70, 0.85, 1.05, 1.0), prefetch);
        assert_eq!(flight.max_scale, 1.0);
        assert!(
            flight.evicted > 20,
            "prefetch {prefetch}: the pool was not exercised: {flight:?}"
        );
        assert!(
            flight.detailed_frames > 0,
            "prefetch {prefetch}: LOD 0 was never drawn: {flight:?}"
        );
    }
}

/// What a flight did.
#[derive(Debug)]
struct Flight {
    evicted: usize,
    max_scale: f32,
    detailed_frames: usize,
}

fn fly_around_the_bunny(pressure: LodPressure, prefetch: u32) -> Flight {
    let asset = meshlight_testing::meshes::bunny();
    let dag = MeshDag::of_asset(asset);
    let graph = dag.pages();
    let pool = graph.total_bytes() / 3;
    let budget = Budget {
        prefetch_levels: prefetch,
        ..Budget::default()
    };
    let mut streamer = Streamer::new(graph.clone(), pool, budget)
        .unwrap()
        .with_pressure(pressure);
    let mut max_scale = 1.0f32;
    let groups = asset.groups();
    let header = asset.header();
    let centre: Vec<f32> = (0..3)
        .map(|i| (header.bounds_min[i] + header.bounds_max[i]) / 2.0)
        .collect();
    let extent = (0..3)
        .map(|i| header.bounds_max[i] - header.bounds_min[i])
        .fold(0.0, f32::max);
    let mut rng = Rng(11);
    let mut pending: Vec<PageId> = Vec::new();
    let (mut evicted, mut detailed_frames) = (0, 0);
    let (mut distance, mut a, mut b) = (2.0f32, 0.0f32, 0.0f32);
    let mut target = centre.clone();
    for frame in 1..=3000 {
        // Looking at a point that wanders over the mesh, from near and far.
        distance = if rng.below(100) == 0 {
            rng.range(0.1, 4.0)
        } else {
            (distance * rng.range(0.95, 1.05)).clamp(0.1, 4.0)
        };
        for (t, c) in target.iter_mut().zip(&centre) {
            *t = (*t + rng.range(-0.02, 0.02) * extent).clamp(c - extent / 2.0, c + extent / 2.0);
        }
        a += rng.range(-0.1, 0.1);
        b = (b + rng.range(-0.05, 0.05)).clamp(-1.5, 1.5);
        let d = distance * extent;
        let view = View {
            camera_position: [
                target[0] + d * a.cos() * b.cos(),
                target[1] + d * b.sin(),
                target[2] + d * a.sin() * b.cos(),
            ],
            near: 0.01,
            lod_scale: 540.0,
            ..View::default()
        };
        let threshold = streamer.lod_scale();
        max_scale = max_scale.max(threshold);
        let px: Vec<f32> = groups
            .iter()
            .map(|g| {
                let s = g.lod_sphere;
                project_error_to_pixels(&view, [s[0], s[1], s[2]], s[3], g.error)
            })
            .collect();
        let shows: Vec<bool> = px
            .iter()
            .map(|&p| error_perceptible(p, threshold))
            .collect();
        // The GPU asks only for what its frustum sees: a 40° cone towards the target.
        let eye = view.camera_position;
        let forward = [target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]];
        let seen = |s: [f32; 4]| {
            let to = [s[0] - eye[0], s[1] - eye[1], s[2] - eye[2]];
            let dot = to[0] * forward[0] + to[1] * forward[1] + to[2] * forward[2];
            let (lt, lf) = (length(to), length(forward));
            lt <= s[3]
                || (dot / (lt * lf)).clamp(-1.0, 1.0).acos() - (s[3] / lt).min(1.0).asin() < 0.35
        };
        let wanted: Vec<Request> = (0..groups.len() as PageId)
            .filter(|&g| shows[g as usize] && seen(groups[g as usize].lod_sphere))
            .map(|page| Request {
                page,
                priority: px[page as usize],
            })
            .collect();
        for page in pending.drain(..) {
            streamer.complete(page, Ok(page_bytes(&graph, page)));
        }
        let plan = streamer.frame(frame, Some(&wanted));
        evicted += plan.evict.len();
        pending.extend(plan.load.iter().map(|l| l.page));
        let drawn = select(&dag, &shows, |g| streamer.is_resident(g));
        if let Err(hole) = check(&dag, &drawn, |g| streamer.is_resident(g)) {
            panic!("frame {frame}: {hole}");
        }
        let lod0 = drawn
            .iter()
            .zip(&dag.source)
            .filter(|&(&d, &s)| d && s == NO_GROUP)
            .count();
        detailed_frames += usize::from(lod0 > 0);
    }
    Flight {
        evicted,
        max_scale,
        detailed_frames,
    }
}

/// A page is what the asset stores as one: the graph's sizes are the page records'.
#[test]
fn the_page_graph_matches_the_assets_page_records() {
    let asset = meshlight_testing::meshes::spot();
    let graph = MeshDag::of_asset(asset).pages();
    assert_eq!(graph.len(), asset.pages().len());
    for (g, page) in asset.pages().iter().enumerate() {
        assert_eq!(
            graph.bytes(g as PageId),
            u64::from(page.words) * 4,
            "page {g}"
        );
    }
    assert_eq!(
        graph.total_bytes() + asset.resident_bytes(),
        asset.bytes().len() as u64,
        "the pages and the resident part are the whole file"
    );
}

/// The GPU lists the pages in use (the pages of the drawn meshlets) and the missing
/// pages whose error shows, not the ancestors of resident pages: those are held by their
/// children. A still view wanting every detail, through a pool that holds the pages it
/// lists but not their ancestors too, must coarsen the cut until what it needs fits and
/// nothing stays pending, rather than wait for room that never comes.
#[test]
fn a_pool_full_of_held_ancestors_coarsens_the_cut_rather_than_waiting() {
    let mut rng = Rng(11);
    let (dag, errors) = random_dag(&mut rng, 600);
    let graph = dag.pages();
    // The finest pages alone: the pages of the LOD-0 meshlets.
    let finest: std::collections::BTreeSet<u32> = (0..dag.parent.len())
        .filter(|&m| dag.source[m] == NO_GROUP && dag.parent[m] != NO_GROUP)
        .map(|m| dag.parent[m])
        .collect();
    let finest_bytes: u64 = finest.iter().map(|&p| graph.bytes(p)).sum();
    // The finest pages are 80 % of the pool: inside the dead band, with no room for
    // their ancestors.
    let pool = finest_bytes * 5 / 4;
    assert!(
        pool < graph.total_bytes(),
        "{pool} of {}",
        graph.total_bytes()
    );
    let mut streamer = Streamer::new(graph.clone(), pool, Budget::default()).unwrap();
    let mut resident = vec![false; graph.len()];
    // Just below the smallest error: at scale 1 every group's error shows.
    let threshold = 0.9 * errors.iter().cloned().fold(f32::MAX, f32::min);
    let mut quiet = 0;
    for frame in 1..=600u64 {
        let shows = perceptible(&errors, threshold * streamer.lod_scale());
        let drawn = select(&dag, &shows, |g| resident[g as usize]);
        let mut wanted: BTreeMap<u32, f32> = BTreeMap::new();
        for (m, _) in drawn.iter().enumerate().filter(|(_, d)| **d) {
            if dag.parent[m] != NO_GROUP {
                wanted.insert(dag.parent[m], 0.0);
            }
            let s = dag.source[m];
            if s != NO_GROUP && shows[s as usize] && !resident[s as usize] {
                wanted.insert(s, errors[s as usize]);
            }
        }
        let requests: Vec<Request> = (wanted.iter())
            .map(|(&page, &priority)| Request { page, priority })
            .collect();
        let plan = streamer.frame(frame, Some(&requests));
        for &p in &plan.evict {
            resident[p as usize] = false;
        }
        for i in &plan.install {
            resident[i.page as usize] = true;
        }
        for load in &plan.load {
            streamer.complete(load.page, Ok(page_bytes(&graph, load.page)));
        }
        for i in streamer.publish_ready() {
            resident[i.page as usize] = true;
        }
        let pending = (wanted.keys()).any(|&p| !resident[p as usize]);
        quiet = if pending { 0 } else { quiet + 1 };
        if quiet == 10 {
            break;
        }
    }
    assert_eq!(
        quiet,
        10,
        "still waiting for room at scale {}",
        streamer.lod_scale()
    );
    assert!(streamer.lod_scale() > 1.0);
}
