//! Occlusion that pays for itself: a two-pass frame leaves its second pass and its depth
//! pyramid out while the occlusion test hides little, and tries again now and then.
//!
//! Two-pass occlusion costs a depth pyramid and a second walk, cull and raster every
//! frame, whatever they find (about 0.13 ms a frame on an NVIDIA H200 at 2240×1260). On
//! a view that hides little (a see-through lattice of instances hides 3 % of its cut) that
//! is more than the raster it saves. So the renderer watches the counters the frame
//! reads back anyway and, where the share of the cut occlusion culled for good stays
//! below [`OcclusionPolicy::min_hidden`] for [`LOW_FRAMES`] tested frames in a row, stops
//! testing: each frame then runs as a frame
//! without occlusion would (its first pass tests nothing, as after a camera cut), and
//! the second pass and the pyramid are left out of it ([`FrameData::skip`]). Every
//! [`OcclusionPolicy::probe_every`] frames it probes: one frame builds a pyramid, the
//! next tests against it (two-pass, as always), and the frames after it test nothing
//! until that frame's counters come back and decide whether testing resumes. A probe
//! costs about one pyramid and one second pass.
//!
//! Lossless by construction: a frame tests against last frame's pyramid only when last
//! frame built one, and a frame that tests nothing hides nothing, so its second pass has
//! nothing to draw and can be left out. The image is the frame without occlusion's
//! (test `adaptive_occlusion_*` in `tests/occlusion.rs`).
//!
//! [`FrameData::skip`]: meshlight::graph::FrameData::skip

use crate::counts::FrameCounts;
use crate::frame_graph::is_second_pass;
use meshlight::graph::file::Pipeline;
use meshlight::graph::{Plan, READBACK_STAGE};
use std::collections::BTreeSet;

/// When a two-pass frame tests occlusion ([`crate::FrameSettings::occlusion_policy`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OcclusionPolicy {
    /// Keep testing while the clusters occlusion culls for good are at least this share
    /// of the cut (culled and drawn together), as the counters of a frame that tested
    /// report it. The renderer estimates whole instances the walk culled at the cut of
    /// an average visible instance. 0 tests every frame.
    pub min_hidden: f32,
    /// Frames without testing before the renderer builds a pyramid and tests again.
    pub probe_every: u32,
}

impl OcclusionPolicy {
    /// Test while occlusion culls at least a tenth of the cut; look again every 60
    /// frames (a second at 60 Hz) when it does not.
    ///
    /// Why a tenth: on an NVIDIA H200 a frame's occlusion costs about a quarter of its
    /// raster (0.13 ms against 0.47 on the 15³ bunnies). The default scene culls 35 %
    /// and the bunny lattice 3 %, so both sit far from the line. The share counts
    /// clusters, not the raster they cost: along the default scene's moving path,
    /// stretches that culled under a tenth saved about as much raster as occlusion cost
    /// there (docs/BENCHMARKS.md, "Adaptive occlusion").
    pub const DEFAULT: Self = Self {
        min_hidden: 0.1,
        probe_every: 60,
    };

    /// Tests every frame: the two-pass frame as written.
    pub const ALWAYS: Self = Self {
        min_hidden: 0.0,
        probe_every: 1,
    };

    /// `always`, `adaptive` (the default), or `MIN_HIDDEN/PROBE_EVERY` (`0.1/60`); the
    /// value of [`crate::settings::env::OCCLUSION_POLICY`].
    pub fn parse(text: &str) -> Option<Self> {
        match text.trim() {
            "always" => Some(Self::ALWAYS),
            "adaptive" => Some(Self::DEFAULT),
            other => {
                let (share, frames) = other.split_once('/')?;
                let policy = Self {
                    min_hidden: share.trim().parse().ok()?,
                    probe_every: frames.trim().parse().ok()?,
                };
                ((0.0..=1.0).contains(&policy.min_hidden) && policy.probe_every > 0)
                    .then_some(policy)
            }
        }
    }

    /// Never stops testing.
    pub fn always(&self) -> bool {
        self.min_hidden <= 0.0
    }
}

impl Default for OcclusionPolicy {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What one frame runs of the two-pass frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FramePlan {
    /// The first pass tests against last frame's pyramid (the `camera_cut` input is 0).
    pub test: bool,
    /// The depth pyramid is built (the next frame may test against it).
    pub pyramid: bool,
    /// The second pass runs and its counters come back.
    pub second: bool,
}

impl FramePlan {
    /// The whole two-pass frame.
    pub const FULL: Self = Self {
        test: true,
        pyramid: true,
        second: true,
    };
}

/// The passes of a frame's graph that only its second pass needs, and its pyramid.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SecondPass {
    /// The second walk and cull (`mode = "second"`), every pass that reads what only they
    /// (and passes already here) write, and those passes' readbacks.
    pub passes: Vec<String>,
    /// The `depth_pyramid` pass.
    pub pyramid: String,
}

impl SecondPass {
    /// The second pass of `plan`, compiled from `pipeline`, whose second walk and cull
    /// start it ([`is_second_pass`]). `Err` says why the frame's second pass cannot be
    /// left out on its own (a pass of another kind reads what it writes, or the pyramid
    /// is not one pass), and the renderer then tests every frame.
    pub fn of(plan: &Plan, pipeline: &Pipeline) -> Result<Self, String> {
        let mut set: BTreeSet<usize> = (pipeline.passes.iter())
            .filter(|e| is_second_pass(e))
            .filter_map(|e| plan.pass_index(&e.name))
            .filter(|&p| !plan.is_culled(p))
            .collect();
        if set.is_empty() {
            return Err("the frame has no second walk or cull".into());
        }
        let writers = |r: usize| {
            plan.order.iter().copied().filter(move |&p| {
                plan.passes[p]
                    .slots
                    .iter()
                    .any(|s| s.resource == r && s.writes_version.is_some())
            })
        };
        loop {
            // Resources only the set writes: what a pass reading them needs the second
            // pass for.
            let own: BTreeSet<usize> = set
                .iter()
                .flat_map(|&p| plan.passes[p].slots.iter())
                .filter(|s| s.writes_version.is_some())
                .map(|s| s.resource)
                .filter(|&r| writers(r).all(|p| set.contains(&p)))
                .collect();
            let readers: Vec<usize> = plan
                .order
                .iter()
                .copied()
                .filter(|p| !set.contains(p))
                .filter(|&p| {
                    plan.passes[p]
                        .slots
                        .iter()
                        .any(|s| own.contains(&s.resource) && s.reads())
                })
                .collect();
            if readers.is_empty() {
                break;
            }
            for p in readers {
                let pass = &plan.passes[p];
                const SECOND_PASS_STAGES: [&str; 5] = [
                    meshlight::fill_clusters::STAGE,
                    meshlight::cull_lod::STAGE,
                    meshlight::remap_dispatch::STAGE,
                    meshlight::sw_raster::STAGE,
                    meshlight::hw_raster::STAGE,
                ];
                if !(SECOND_PASS_STAGES.contains(&pass.stage) || pass.stage == READBACK_STAGE) {
                    return Err(format!(
                        "`{}` ({}) reads what the second pass writes",
                        pass.name, pass.stage
                    ));
                }
                set.insert(p);
            }
        }
        let pyramids: Vec<usize> = (plan.order.iter().copied())
            .filter(|&p| plan.passes[p].stage == meshlight::depth_pyramid::STAGE)
            .collect();
        let [pyramid] = pyramids[..] else {
            return Err(format!(
                "the frame builds {} depth pyramids, not one",
                pyramids.len()
            ));
        };
        Ok(Self {
            passes: set.iter().map(|&p| plan.passes[p].name.clone()).collect(),
            pyramid: plan.passes[pyramid].name.clone(),
        })
    }
}

/// The share of a tested frame's cut that occlusion culled for good: clusters the
/// second cull found still hidden, and whole nodes the second walk did (each counted as
/// the cut of an average instance the walk went on into), against those and the
/// clusters drawn. `None` when the frame tested nothing (no history, a cut).
pub fn hidden_share(c: &FrameCounts) -> Option<f32> {
    let o = c.occlusion?;
    let walk = c.hierarchy;
    let hidden_nodes = walk.map_or(0, |h| h.hidden_nodes);
    if o.first_tested == 0 && hidden_nodes == 0 {
        return None;
    }
    let still_hidden = walk.and_then(|h| h.second).map_or(0, |s| s.still_hidden);
    let instances = walk
        .and_then(|h| h.instances)
        .map_or(1, |i| i.visible.max(1));
    let per_node = (o.first_cut as f32 / instances as f32).max(1.0);
    let hidden = o.second_occluded as f32 + still_hidden as f32 * per_node;
    let total = hidden + c.visible as f32;
    Some(if total > 0.0 { hidden / total } else { 0.0 })
}

/// Tested frames in a row that must cull too little before testing stops: one frame
/// after a jump the renderer was not told of tests against a pyramid of another view and
/// culls little, though the frames after it cull as much as before.
pub const LOW_FRAMES: u32 = 3;

/// Where the renderer is in its cycle of testing and probing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    /// Every frame tests (its pyramid permitting).
    Testing,
    /// No frame tests; `frames` since testing stopped or the last probe.
    Idle { frames: u32 },
    /// The next frame builds a pyramid for the probe.
    ProbePyramid,
    /// The next frame tests against it; then frames idle until its counters decide.
    ProbeTest,
}

/// The renderer's state: what its frames test, and whether last frame left a pyramid.
#[derive(Clone, Debug)]
pub struct Adaptive {
    policy: OcclusionPolicy,
    mode: Mode,
    /// Last frame built the pyramid this frame would test against.
    pyramid_fresh: bool,
    /// Tested frames in a row that culled too little.
    low: u32,
}

impl Adaptive {
    /// Testing, with no pyramid yet.
    pub fn new(policy: OcclusionPolicy) -> Self {
        Self {
            policy,
            mode: Mode::Testing,
            pyramid_fresh: false,
            low: 0,
        }
    }

    /// Whether the frames test occlusion now (the next may still be one that only builds
    /// a pyramid); `false` while idle or probing.
    pub fn testing(&self) -> bool {
        self.mode == Mode::Testing
    }

    /// What the next frame runs; `cut`: the caller said the camera jumped.
    pub fn next_frame(&mut self, cut: bool) -> FramePlan {
        if self.policy.always() {
            return FramePlan {
                test: !cut,
                ..FramePlan::FULL
            };
        }
        let fresh = std::mem::replace(&mut self.pyramid_fresh, true);
        match self.mode {
            Mode::Testing | Mode::ProbeTest => {
                if self.mode == Mode::ProbeTest {
                    self.mode = Mode::Idle { frames: 0 };
                }
                // A frame that tests nothing hides nothing: no second pass.
                let test = !cut && fresh;
                FramePlan {
                    test,
                    pyramid: true,
                    second: test,
                }
            }
            Mode::ProbePyramid => {
                self.mode = Mode::ProbeTest;
                FramePlan {
                    test: false,
                    pyramid: true,
                    second: false,
                }
            }
            Mode::Idle { frames } => {
                self.mode = match frames + 1 >= self.policy.probe_every {
                    true => Mode::ProbePyramid,
                    false => Mode::Idle { frames: frames + 1 },
                };
                self.pyramid_fresh = false;
                FramePlan {
                    test: false,
                    pyramid: false,
                    second: false,
                }
            }
        }
    }

    /// Takes the counters of a frame that ran `plan`: a tested frame that culled enough
    /// keeps (or, a probe's, starts) testing; [`LOW_FRAMES`] in a row that did not stop
    /// it.
    pub fn observe(&mut self, plan: FramePlan, counts: &FrameCounts) {
        if self.policy.always() || !plan.second {
            return;
        }
        let Some(share) = hidden_share(counts) else {
            return;
        };
        log::debug!(
            "frame {}: occlusion culled {:.1} % of the cut ({:?}); testing {}",
            counts.frame,
            share * 100.0,
            counts.occlusion,
            share >= self.policy.min_hidden
        );
        if share >= self.policy.min_hidden {
            self.mode = Mode::Testing;
            self.low = 0;
            return;
        }
        self.low += 1;
        // A probe's one frame decides; while testing, `LOW_FRAMES` in a row.
        if self.mode == Mode::Testing && self.low >= LOW_FRAMES {
            self.mode = Mode::Idle { frames: 0 };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::counts::{HierarchyCounts, InstanceCounts, OcclusionCounts, SecondWalkCounts};

    fn tested(visible: u32, second_occluded: u32, still_hidden: u32) -> FrameCounts {
        FrameCounts {
            visible,
            occlusion: Some(OcclusionCounts {
                first_cut: 1000,
                first_tested: 1000,
                second_occluded,
                ..Default::default()
            }),
            hierarchy: Some(HierarchyCounts {
                hidden_nodes: still_hidden,
                instances: Some(InstanceCounts {
                    tested: 20,
                    visible: 10,
                }),
                second: Some(SecondWalkCounts {
                    still_hidden,
                    ..Default::default()
                }),
                ..Default::default()
            }),
            ..Default::default()
        }
    }

    #[test]
    fn the_share_counts_clusters_and_whole_instances_culled_for_good() {
        // 100 clusters still hidden, 2 instances of 100 clusters each: 300 of 1300.
        let share = hidden_share(&tested(1000, 100, 2)).unwrap();
        assert!((share - 300.0 / 1300.0).abs() < 1e-6, "{share}");
        assert_eq!(hidden_share(&tested(1000, 0, 0)), Some(0.0));
        // A frame that tested nothing says nothing.
        let mut untested = tested(1000, 0, 0);
        untested.occlusion.as_mut().unwrap().first_tested = 0;
        assert_eq!(hidden_share(&untested), None);
        assert_eq!(hidden_share(&FrameCounts::default()), None);
    }

    /// Runs frames, feeding back each frame's counters `latency` frames later with the
    /// share `share(frame)`; returns the plans.
    fn run(
        policy: OcclusionPolicy,
        frames: usize,
        latency: usize,
        cuts: &[usize],
        hidden: impl Fn(usize) -> u32,
    ) -> Vec<FramePlan> {
        let mut a = Adaptive::new(policy);
        let mut plans = Vec::new();
        for f in 0..frames {
            plans.push(a.next_frame(cuts.contains(&f)));
            if f >= latency {
                let g = f - latency;
                a.observe(plans[g], &tested(1000, hidden(g), 0));
            }
        }
        plans
    }

    #[test]
    fn a_frame_tests_only_against_the_pyramid_of_the_frame_before() {
        for hidden in [0, 50, 200, 1000] {
            for latency in [0, 2, 3] {
                let plans = run(OcclusionPolicy::DEFAULT, 400, latency, &[7, 130], |f| {
                    // Alternating long stretches of little and much hidden.
                    if (f / 90) % 2 == 0 {
                        hidden
                    } else {
                        1000 - hidden
                    }
                });
                for (f, p) in plans.iter().enumerate() {
                    if p.test {
                        assert!(f > 0 && plans[f - 1].pyramid, "frame {f}: {plans:?}");
                        assert!(p.second && p.pyramid, "frame {f}");
                    }
                    assert!(
                        !p.second || p.test,
                        "frame {f}: a second pass with nothing hidden"
                    );
                }
                assert!(!plans[7].test && !plans[130].test, "a cut frame tested");
            }
        }
    }

    #[test]
    fn testing_stops_where_little_is_hidden_and_probes_again() {
        let policy = OcclusionPolicy {
            min_hidden: 0.1,
            probe_every: 20,
        };
        // 5 % hidden: testing stops once three tested frames' counters are in, then a
        // probe every 20 frames (a pyramid frame, then one tested frame).
        let plans = run(policy, 200, 2, &[], |_| 50);
        let tests: Vec<usize> = (0..200).filter(|&f| plans[f].test).collect();
        // The first tested frames' counters come back two frames late, and
        // `LOW_FRAMES` of them stop testing.
        assert_eq!(&tests[..5], &[1, 2, 3, 4, 5], "{tests:?}");
        assert!(!plans[6].test && !plans[6].pyramid, "{plans:?}");
        let skipped = plans.iter().filter(|p| !p.pyramid).count();
        assert!(
            skipped > 150,
            "{skipped} frames without a pyramid: {plans:?}"
        );
        // A probe is a pyramid frame and one tested frame; the frames after it wait
        // for its counters without testing.
        let second_passes = plans.iter().filter(|p| p.second).count();
        assert!(second_passes <= 6 + 200 / 20, "{second_passes}: {plans:?}");
        // Probes keep coming.
        assert!(tests.iter().any(|&f| f > 150), "{tests:?}");
        // 30 % hidden: every frame after the first tests.
        let plans = run(policy, 200, 2, &[], |_| 300);
        assert!(
            plans[1..].iter().all(|p| *p == FramePlan::FULL),
            "{plans:?}"
        );
        // Two frames that cull little (after a jump) among many that cull much do not
        // stop testing.
        let plans = run(policy, 100, 2, &[], |f| {
            if f == 30 || f == 31 { 0 } else { 300 }
        });
        assert!(
            plans[1..].iter().all(|p| *p == FramePlan::FULL),
            "{plans:?}"
        );
        // Hidden again after a stretch of nothing: testing resumes within a probe.
        let plans = run(policy, 200, 2, &[], |f| if f < 60 { 0 } else { 300 });
        let back = (60..200).find(|&f| plans[f].test).unwrap();
        assert!(back <= 60 + 20 + 2, "testing resumed at {back}");
        assert!(plans[back + 5..].iter().all(|p| p.test), "{plans:?}");
    }

    #[test]
    fn always_tests_every_frame_but_cuts() {
        let plans = run(OcclusionPolicy::ALWAYS, 50, 2, &[10], |_| 0);
        for (f, p) in plans.iter().enumerate() {
            let test = f != 10;
            assert_eq!(
                *p,
                FramePlan {
                    test,
                    ..FramePlan::FULL
                },
                "frame {f}"
            );
        }
    }

    #[test]
    fn the_policy_parses_from_its_names_and_numbers() {
        assert_eq!(
            OcclusionPolicy::parse("always"),
            Some(OcclusionPolicy::ALWAYS)
        );
        assert_eq!(
            OcclusionPolicy::parse(" adaptive "),
            Some(OcclusionPolicy::DEFAULT)
        );
        assert_eq!(
            OcclusionPolicy::parse("0.25/30"),
            Some(OcclusionPolicy {
                min_hidden: 0.25,
                probe_every: 30
            })
        );
        for bad in ["", "sometimes", "2/30", "0.1/0", "0.1", "-0.1/5"] {
            assert_eq!(OcclusionPolicy::parse(bad), None, "{bad}");
        }
    }
}
