//! The clustering loop: the graph compiled for the adapter, the objects uploaded, one
//! `execute_frame` per view, the counters taken back without waiting, and z_slice's list
//! or the froxel lists grown when a frame reports it ran out of room.

use super::frame_graph::{
    self, ClusteringSettings, ENTRIES_PARAM, LIST_COUNTS_READBACK, OBJECT_USAGE,
    SLICE_COUNTS_READBACK, SLICE_INSTANCES_PARAM,
};
use super::growth::{self, Growth, Want};
use meshlight::graph::{
    CompileOptions, CompiledGraph, Executor, FrameData, FrameStats, GpuAdapter, GraphBuilder,
    GraphError, Imports, Result,
};
use meshlight::populate::cpu::ClusterLists;
use meshlight::shaders::cpu::layout::{ClusterGrid, ClusterableObject, View};
use meshlight::z_slice::cpu::{
    COUNT_WORDS, WORD_CAPACITY, WORD_CULLED, WORD_INVALID, WORD_REQUESTED, WORD_VISIBLE,
};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// Frames [`Clusterer::cluster_still`] runs, at most, to reach one that lost nothing:
/// the froxel lists can only see what z_slice's list let through, so two grows may be
/// needed one after the other.
pub const MAX_STILL_FRAMES: u32 = 4;

/// Where the graph comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ClusteringSource {
    /// The shipped frame, `pipelines/light_clustering.toml`.
    Code,
    /// A pipeline file of the caller's.
    File(PathBuf),
}

/// One frame's counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ClusteringCounts {
    /// The frame they were counted in.
    pub frame: u64,
    /// z_slice: instances asked for and the list's capacity.
    pub slice_requested: u32,
    /// See `slice_requested`.
    pub slice_capacity: u32,
    /// Objects skipped as invalid (NaN position, negative range, …) and culled.
    pub invalid: u32,
    /// See `invalid`.
    pub culled: u32,
    /// Objects given slices, per kind.
    pub visible: [u32; 4],
    /// populate: entries all lists needed, and the capacity.
    pub entries_needed: u32,
    /// See `entries_needed`.
    pub entries_capacity: u32,
}

impl ClusteringCounts {
    /// Whether the frame lost pairs or entries to a list too small: its lists are
    /// incomplete, and the clusterer grows them for the next frame.
    pub fn overflowed(&self) -> bool {
        self.slice_requested > self.slice_capacity || self.entries_needed > self.entries_capacity
    }
}

/// Something a frame's counters reported that the caller should know.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ClusteringWarning {
    /// Objects with a NaN or infinite position, a NaN or negative range, an unknown kind
    /// or an unusable direction were skipped.
    InvalidObjects {
        /// The frame that skipped them.
        frame: u64,
        /// How many.
        count: u32,
    },
}

/// The lists of a frame the CPU waited for.
pub struct Clustered {
    /// The froxel grid the lists index.
    pub grid: ClusterGrid,
    /// Per froxel and kind, an offset and a count into one index list.
    pub lists: ClusterLists,
    /// The frame's counters.
    pub counts: ClusteringCounts,
    /// What the frame cost.
    pub stats: FrameStats,
    /// Frames run to get there (more than one when a list grew).
    pub frames: u32,
}

/// Light clustering on its own device: the frame compiled for the adapter, the objects
/// uploaded every frame, the lists grown when a frame ran out of room.
pub struct Clusterer {
    /// What the clustering was asked for.
    pub settings: ClusteringSettings,
    /// The frame, compiled for the device.
    pub compiled: CompiledGraph,
    /// The device and what runs on it.
    pub executor: Executor,
    objects: wgpu::Buffer,
    object_count: wgpu::Buffer,
    /// The counters that came back, the grows and the warnings.
    pub counters: Counters,
}

impl Clusterer {
    /// Builds the graph (in code or from a file), compiles it for the adapter and opens
    /// the device.
    pub fn new(settings: ClusteringSettings, source: &ClusteringSource) -> Result<Self> {
        let graph = match source {
            ClusteringSource::Code => frame_graph::build(&settings)?,
            ClusteringSource::File(path) => frame_graph::load(path, &settings)?,
        };
        Self::with_graph(settings, graph)
    }

    /// The clusterer of `graph` (a frame holding the clustering's passes under their
    /// resources' names), compiled for the selected adapter.
    pub fn with_graph(settings: ClusteringSettings, graph: GraphBuilder) -> Result<Self> {
        let adapter = GpuAdapter::select()?;
        let limits = adapter.adapter.limits();
        let compiled = graph.compile(&CompileOptions::for_adapter(&adapter))?;
        let gpu = adapter.open(compiled.plan.enabled_features)?;
        let object_bytes = settings.objects * size_of::<ClusterableObject>() as u64;
        let objects = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("objects"),
            size: object_bytes,
            usage: OBJECT_USAGE,
            mapped_at_creation: false,
        });
        let object_count = gpu.buffer_with_data("object_count", &[0; 4], OBJECT_USAGE);
        let max_entries = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size)
            / 8;
        Ok(Self {
            settings,
            compiled,
            executor: Executor::new(gpu),
            objects,
            object_count,
            counters: Counters::new(max_entries),
        })
    }

    /// Uploads `objects`, records and submits one frame; never waits for the GPU.
    pub fn frame(&mut self, view: &View, objects: &[ClusterableObject]) -> Result<FrameStats> {
        let limit = self.settings.objects;
        if objects.len() as u64 > limit {
            return Err(GraphError::Setting {
                setting: "ClusteringSettings::objects".into(),
                message: format!(
                    "{} clusterable objects, but the object buffer holds {limit}; raise `objects` (ClusteringSettings::objects, or `objects` in the pipeline's [params]) or cluster fewer",
                    objects.len()
                ),
            });
        }
        let queue = &self.executor.gpu.queue;
        if !objects.is_empty() {
            queue.write_buffer(&self.objects, 0, bytemuck::cast_slice(objects));
        }
        queue.write_buffer(&self.object_count, 0, &(objects.len() as u32).to_le_bytes());
        let imports = Imports::new()
            .buffer("objects", &self.objects)
            .buffer("object_count", &self.object_count);
        let frame = FrameData::new().with("view", bytemuck::bytes_of(view));
        let stats = self
            .executor
            .execute_frame(&self.compiled, &imports, &frame)?;
        self.take_counts()?;
        Ok(stats)
    }

    /// The newest frame whose counters are back.
    pub fn latest_counts(&self) -> Option<ClusteringCounts> {
        self.counters.latest
    }

    /// Clusters until a frame loses nothing (at most [`MAX_STILL_FRAMES`]), waiting for
    /// each, and reads that frame's lists back.
    pub fn cluster_still(
        &mut self,
        view: &View,
        objects: &[ClusterableObject],
    ) -> Result<Clustered> {
        let mut attempt = 0;
        loop {
            attempt += 1;
            let submitted = self.frame(view, objects)?.frame;
            let stats = meshlight::still::finish(&mut self.executor, submitted)?;
            self.take_counts()?;
            let counts =
                meshlight::still::counters_of(self.counters.latest, |c| c.frame, submitted)?;
            if !counts.overflowed() || attempt == MAX_STILL_FRAMES {
                return Ok(Clustered {
                    grid: self.read_grid()?,
                    lists: self.read_lists(counts.entries_needed)?,
                    counts,
                    stats,
                    frames: attempt,
                });
            }
        }
    }

    fn words(&mut self, name: &str) -> Result<Vec<u32>> {
        Ok(bytemuck::pod_collect_to_vec(
            &self.executor.read_buffer(name)?,
        ))
    }

    fn read_grid(&mut self) -> Result<ClusterGrid> {
        let bytes = self.executor.read_buffer("cluster_grid")?;
        Ok(bytemuck::pod_read_unaligned(
            &bytes[..size_of::<ClusterGrid>()],
        ))
    }

    /// The exported lists of the last frame run.
    pub fn read_lists(&mut self, needed: u32) -> Result<ClusterLists> {
        let mut objects = self.words("cluster_objects")?;
        objects.truncate(needed as usize);
        Ok(ClusterLists {
            offsets: self.words("cluster_offsets")?,
            counts: self.words("cluster_counts")?,
            objects,
            needed,
        })
    }

    fn take_counts(&mut self) -> Result<()> {
        self.counters.take(&mut self.executor, &mut self.compiled)
    }
}

/// The clustering's counters as they come back, frame by frame, and what they caused:
/// grown lists and warnings. The [`Clusterer`] and the virtual-geometry renderer (when
/// its frame clusters lights) share it.
#[derive(Debug, Default)]
pub struct Counters {
    /// The largest list a binding holds, in 4-byte entries.
    max_entries: u64,
    pending: BTreeMap<u64, [Option<Vec<u8>>; 2]>,
    /// The newest frame's counters that came back.
    pub latest: Option<ClusteringCounts>,
    /// Every grow of a list so far.
    pub growths: Vec<Growth>,
    /// What frames reported that the caller should know.
    pub warnings: Vec<ClusteringWarning>,
}

impl Counters {
    /// Counters for lists that may grow up to `max_entries` entries (the device's
    /// binding limit).
    pub fn new(max_entries: u64) -> Self {
        Self {
            max_entries,
            ..Self::default()
        }
    }

    /// Takes every counter readback that has come back; grows the lists for frames
    /// that overflowed and records skipped objects.
    pub fn take(&mut self, executor: &mut Executor, compiled: &mut CompiledGraph) -> Result<()> {
        for (slot, name) in [SLICE_COUNTS_READBACK, LIST_COUNTS_READBACK]
            .into_iter()
            .enumerate()
        {
            while let Some(r) = executor.take_readback(name)? {
                self.pending.entry(r.frame).or_default()[slot] = Some(r.bytes);
            }
        }
        let complete: Vec<u64> = self
            .pending
            .iter()
            .filter(|(_, p)| p.iter().all(Option::is_some))
            .map(|(f, _)| *f)
            .collect();
        for frame in complete {
            let [Some(slices), Some(lists)] = self.pending.remove(&frame).expect("listed above")
            else {
                unreachable!("only complete frames are listed");
            };
            let s: Vec<u32> = bytemuck::pod_collect_to_vec(&slices);
            let l: Vec<u32> = bytemuck::pod_collect_to_vec(&lists);
            if s.len() < COUNT_WORDS || l.len() < 2 {
                return Err(GraphError::Readback(format!(
                    "frame {frame}'s counters are short"
                )));
            }
            let counts = ClusteringCounts {
                frame,
                slice_requested: s[WORD_REQUESTED],
                slice_capacity: s[WORD_CAPACITY],
                invalid: s[WORD_INVALID],
                culled: s[WORD_CULLED],
                visible: std::array::from_fn(|k| s[WORD_VISIBLE + k]),
                entries_needed: l[0],
                entries_capacity: l[1],
            };
            if counts.invalid > 0 {
                log::warn!(
                    "frame {frame}: {} clusterable objects skipped: a NaN or infinite position, a NaN or negative range, an unknown kind or a direction of length 0",
                    counts.invalid
                );
                self.warnings.push(ClusteringWarning::InvalidObjects {
                    frame,
                    count: counts.invalid,
                });
            }
            self.grow_for(compiled, &counts)?;
            if self.latest.is_none_or(|l| l.frame < frame) {
                self.latest = Some(counts);
            }
        }
        while self.pending.len() > 16 {
            self.pending.pop_first();
        }
        Ok(())
    }

    /// Raises a list's size to the next power of two above what a frame asked for.
    fn grow_for(&mut self, compiled: &mut CompiledGraph, counts: &ClusteringCounts) -> Result<()> {
        let wants = [
            (SLICE_INSTANCES_PARAM, u64::from(counts.slice_requested)),
            (ENTRIES_PARAM, u64::from(counts.entries_needed)),
        ];
        for (param, wanted) in wants {
            let want = Want {
                frame: counts.frame,
                param,
                wanted,
                limit: self.max_entries,
                when_full: "lights are dropped from froxels (use fewer or smaller lights, or a coarser grid)",
                also_set_by: "ClusteringSettings",
            };
            self.growths.extend(growth::grow(compiled, want)?);
        }
        Ok(())
    }
}
