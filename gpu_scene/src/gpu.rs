//! The GPU buffers of a [`SceneData`], uploaded only where something changed, and their
//! declaration as imported graph resources.

use crate::data::SceneData;
use crate::names;
use crate::stream_upload::{Part, StreamUpload};
use crate::streaming::{StreamBuffer, StreamWrite};
use meshlight_graph::{Buffer, BufferDesc, Element, GpuContext, GraphBuilder, Handle, Imports};
use meshlight_scene::asset::format::{GroupRecord, MeshletRecord, NodeRecord};
use meshlight_shaders::cpu::layout;
use std::borrow::Cow;

const USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_DST)
    .union(wgpu::BufferUsages::COPY_SRC);

/// Element types of the scene buffers, as graph dumps name them.
pub mod elements {
    use super::*;
    /// The asset's `MeshletRecord`, WGSL `meshlet::Meshlet`.
    pub const MESHLET: Element = Element::named("Meshlet", size_of::<MeshletRecord>() as u32);
    /// The asset's `GroupRecord`, WGSL `meshlet::MeshletGroup`.
    pub const GROUP: Element = Element::named("MeshletGroup", size_of::<GroupRecord>() as u32);
    /// WGSL `meshlet::Mesh`: one per added asset.
    pub const MESH: Element = Element::named("Mesh", size_of::<layout::Mesh>() as u32);
    /// WGSL `instance::Instance`.
    pub const INSTANCE: Element = Element::named("Instance", size_of::<layout::Instance>() as u32);
    /// WGSL `instance::Material`.
    pub const MATERIAL: Element = Element::named("Material", size_of::<layout::Material>() as u32);
    /// WGSL `meshlet::Cluster`: the (instance, meshlet) pairs the culling lists hold.
    pub const CLUSTER: Element = Element::named("Cluster", size_of::<layout::Cluster>() as u32);
    /// WGSL `view::View`, when a pass reads the view from a buffer.
    pub const VIEW: Element = Element::named("View", size_of::<layout::View>() as u32);
    /// The asset's `NodeRecord`, WGSL `HierarchyNode` (fill_clusters' walk).
    pub const HIERARCHY_NODE: Element =
        Element::named("HierarchyNode", size_of::<NodeRecord>() as u32);
}

/// The graph handles of the scene buffers, returned by [`GpuScene::import`].
#[derive(Clone, Copy, Debug)]
pub struct SceneHandles {
    /// Bound to the `meshlets` slots.
    pub meshlets: Handle<Buffer>,
    /// Bound to the `meshlet_groups` slots.
    pub groups: Handle<Buffer>,
    /// Bound to the `payload` slots.
    pub payload: Handle<Buffer>,
    /// Bound to the `meshes` slots.
    pub meshes: Handle<Buffer>,
    /// Bound to the `instances` slots (the first binding's worth when split).
    pub instances: Handle<Buffer>,
    /// The instances past one binding's limit, when the scene has that many.
    pub instances_high: Option<Handle<Buffer>>,
    /// Bound to the `materials` slots.
    pub materials: Handle<Buffer>,
    /// Bound to the `textures` slots.
    pub textures: Handle<Buffer>,
}

impl SceneHandles {
    /// The handles `import` gives each scene buffer, by name (the one place that pairs
    /// fields with names); `instances_high` is imported only when the instances are
    /// `split` over two bindings.
    fn import_each(split: bool, mut import: impl FnMut(&str) -> Handle<Buffer>) -> Self {
        Self {
            meshlets: import(names::MESHLETS),
            groups: import(names::GROUPS),
            payload: import(names::PAYLOAD),
            meshes: import(names::MESHES),
            instances: import(names::INSTANCES),
            instances_high: split.then(|| import(names::INSTANCES_HIGH)),
            materials: import(names::MATERIALS),
            textures: import(names::TEXTURES),
        }
    }
}

/// The graph handles of the culling-hierarchy buffers, returned by
/// [`GpuScene::import_hierarchy`] and [`import_hierarchy_for`].
#[derive(Clone, Copy, Debug)]
pub struct HierarchyHandles {
    /// Bound to the `hierarchy_nodes` slot.
    pub nodes: Handle<Buffer>,
    /// Bound to the `hierarchy_clusters` slot.
    pub clusters: Handle<Buffer>,
    /// Bound to the `hierarchy_roots` slot.
    pub roots: Handle<Buffer>,
}

struct SceneBuffer {
    name: &'static str,
    element: Element,
    buffer: wgpu::Buffer,
    /// Elements the buffer can hold.
    capacity: u64,
}

/// Bytes written by one [`GpuScene::upload`], to show that unchanged data stays put.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UploadStats {
    /// Bytes copied to the GPU.
    pub bytes: u64,
    /// Buffers created (first upload, or a buffer outgrown).
    pub created: u32,
}

/// The scene's GPU buffers. Create once, then call [`Self::upload`] whenever the
/// [`SceneData`] may have changed; it writes only what did.
pub struct GpuScene {
    buffers: Vec<SceneBuffer>,
    /// Whether `instances_high` holds instances (then graphs import it).
    instances_split: bool,
    geometry_version: u64,
    materials_version: u64,
    textures_version: u64,
    /// The dispatch that writes streaming's changes, made on the first.
    stream_upload: Option<StreamUpload>,
}

/// The element count of each scene buffer as [`GpuScene::new`] would create it for
/// `data`, by buffer name. A graph can then be declared and compiled (which picks the
/// device's features) before the device, and so the buffers, exist.
pub fn buffer_lengths(data: &SceneData) -> [(&'static str, Element, u64); 8] {
    let count = |n: usize| (n as u64).max(1);
    let split = data.instance_split();
    [
        (
            names::MESHLETS,
            elements::MESHLET,
            count(data.meshlets.len()),
        ),
        (names::GROUPS, elements::GROUP, count(data.groups.len())),
        // The padding words of `contents`.
        (
            names::PAYLOAD,
            Element::U32,
            data.payload.len() as u64 + u64::from(crate::data::PAYLOAD_PADDING),
        ),
        (names::MESHES, elements::MESH, count(data.meshes.len())),
        (names::INSTANCES, elements::INSTANCE, count(split)),
        (
            names::INSTANCES_HIGH,
            elements::INSTANCE,
            count(data.instances.len() - split),
        ),
        (
            names::MATERIALS,
            elements::MATERIAL,
            count(data.materials.len()),
        ),
        (names::TEXTURES, Element::U32, count(data.textures.len())),
    ]
}

/// The element count of each culling-hierarchy buffer as [`GpuScene::new`] would create
/// it for `data`, by buffer name (kept apart from [`buffer_lengths`], whose names a
/// pipeline file declares as parameters).
pub fn hierarchy_lengths(data: &SceneData) -> [(&'static str, Element, u64); 3] {
    let count = |n: usize| (n as u64).max(1);
    [
        (
            names::HIERARCHY_NODES,
            elements::HIERARCHY_NODE,
            count(data.hierarchy_nodes.len()),
        ),
        (
            names::HIERARCHY_CLUSTERS,
            Element::U32,
            count(data.hierarchy_clusters.len()),
        ),
        (
            names::HIERARCHY_ROOTS,
            Element::U32,
            count(data.hierarchy_roots.len()),
        ),
    ]
}

/// Declares the culling-hierarchy buffers `data` will need as imported resources of a
/// graph, sized by [`hierarchy_lengths`]; [`GpuScene::imports`] binds them.
pub fn import_hierarchy_for(data: &SceneData, g: &mut GraphBuilder) -> HierarchyHandles {
    let [nodes, clusters, roots] = hierarchy_lengths(data).map(|(name, element, count)| {
        g.import_buffer(name, BufferDesc::array(element, count), USAGE)
    });
    HierarchyHandles {
        nodes,
        clusters,
        roots,
    }
}

/// Declares the scene buffers `data` will need as imported resources of a graph, sized
/// by [`buffer_lengths`]; bind them later with [`GpuScene::imports`]. `instances_high`
/// is declared only when the instances need it.
pub fn import_for(data: &SceneData, g: &mut GraphBuilder) -> SceneHandles {
    let lengths = buffer_lengths(data);
    SceneHandles::import_each(data.instances_split(), |name| {
        let (_, element, count) = lengths
            .iter()
            .find(|(n, ..)| *n == name)
            .expect("every name has a length")
            .clone();
        g.import_buffer(name, BufferDesc::array(element, count), USAGE)
    })
}

/// The buffers in their order in [`GpuScene`].
const ORDER: [&str; 12] = [
    names::MESHLETS,
    names::GROUPS,
    names::PAYLOAD,
    names::MESHES,
    names::INSTANCES,
    names::INSTANCES_HIGH,
    names::MATERIALS,
    names::TEXTURES,
    names::HIERARCHY_NODES,
    names::HIERARCHY_CLUSTERS,
    names::HIERARCHY_ROOTS,
    names::STREAM_ERRORS,
];

/// What buffer `name` holds, borrowed from `data` (only the payload is copied, to append
/// its padding): a frame that changed nothing copies nothing. Every buffer holds at
/// least one element (wgpu refuses empty bindings); the payload carries
/// [`PAYLOAD_PADDING`](crate::data::PAYLOAD_PADDING) words of padding so a read of a
/// field's words never leaves it.
fn content<'a>(data: &'a SceneData, name: &str) -> (Element, Cow<'a, [u8]>) {
    fn borrowed<T: bytemuck::Pod>(items: &[T]) -> Cow<'_, [u8]> {
        Cow::Borrowed(bytemuck::cast_slice(items))
    }
    let split = data.instance_split();
    match name {
        names::MESHLETS => (elements::MESHLET, borrowed(&data.meshlets)),
        names::GROUPS => (elements::GROUP, borrowed(&data.groups)),
        names::PAYLOAD => {
            let mut payload = bytemuck::cast_slice::<u32, u8>(&data.payload).to_vec();
            payload.resize(payload.len() + 4 * crate::data::PAYLOAD_PADDING as usize, 0);
            (Element::U32, Cow::Owned(payload))
        }
        names::MESHES => (elements::MESH, borrowed(&data.meshes)),
        names::INSTANCES => (elements::INSTANCE, borrowed(&data.instances[..split])),
        names::INSTANCES_HIGH => (elements::INSTANCE, borrowed(&data.instances[split..])),
        names::HIERARCHY_NODES => (elements::HIERARCHY_NODE, borrowed(&data.hierarchy_nodes)),
        names::HIERARCHY_CLUSTERS => (Element::U32, borrowed(&data.hierarchy_clusters)),
        names::HIERARCHY_ROOTS => (Element::U32, borrowed(&data.hierarchy_roots)),
        names::TEXTURES => (Element::U32, borrowed(&data.textures)),
        names::STREAM_ERRORS => (
            Element::F32,
            data.streaming()
                .map_or(Cow::Borrowed(&[][..]), |s| borrowed(&s.stream_errors)),
        ),
        _ => (elements::MATERIAL, borrowed(&data.materials)),
    }
}

/// The words of elements `first .. first + count` of `buffer`, and the word they
/// start at, for a streaming write (see [`crate::streaming`]).
fn stream_words(
    data: &SceneData,
    buffer: StreamBuffer,
    first: usize,
    count: usize,
) -> (u32, &[u32]) {
    fn part<T: bytemuck::Pod>(items: &[T], first: usize, count: usize) -> (u32, &[u32]) {
        let per = size_of::<T>() / 4;
        (
            (first * per) as u32,
            bytemuck::cast_slice(&items[first..first + count]),
        )
    }
    match buffer {
        StreamBuffer::Payload => part(&data.payload, first, count),
        StreamBuffer::Meshlets => part(&data.meshlets, first, count),
        StreamBuffer::Groups => part(&data.groups, first, count),
        StreamBuffer::HierarchyNodes => part(&data.hierarchy_nodes, first, count),
        StreamBuffer::StreamErrors => data
            .streaming()
            .map_or((0, &[][..]), |s| part(&s.stream_errors, first, count)),
    }
}

impl GpuScene {
    /// Creates the buffers and uploads everything.
    pub fn new(gpu: &GpuContext, data: &mut SceneData) -> Self {
        let buffers = ORDER
            .iter()
            .map(|name| {
                let (element, bytes) = content(data, name);
                create(gpu, name, element, &bytes)
            })
            .collect();
        data.dirty_instances = None;
        Self {
            buffers,
            instances_split: data.instances_split(),
            geometry_version: data.geometry_version,
            materials_version: data.materials_version,
            textures_version: data.textures_version,
            stream_upload: None,
        }
    }

    /// Writes what changed since the last upload: geometry when meshes were added, the
    /// dirty instance range, materials. A buffer too small is replaced (then the graph
    /// must be recompiled with the new [`Self::import`] sizes).
    pub fn upload(&mut self, gpu: &GpuContext, data: &mut SceneData) -> UploadStats {
        let mut stats = UploadStats::default();
        let geometry = data.geometry_version != self.geometry_version;
        let materials = data.materials_version != self.materials_version;
        let textures = data.textures_version != self.textures_version;
        let dirty = data.dirty_instances.take();
        for (i, &name) in ORDER.iter().enumerate() {
            let changed = match name {
                names::INSTANCES | names::INSTANCES_HIGH => dirty.is_some(),
                names::MATERIALS => materials,
                names::TEXTURES => textures,
                _ => geometry,
            };
            if !changed {
                continue;
            }
            let (element, bytes) = content(data, name);
            let slot = &mut self.buffers[i];
            let elements = (bytes.len() / element.size as usize).max(1) as u64;
            if elements > slot.capacity {
                *slot = create(gpu, name, element, &bytes);
                stats.created += 1;
                stats.bytes += bytes.len() as u64;
                continue;
            }
            let range = match (name, &dirty) {
                (names::INSTANCES | names::INSTANCES_HIGH, Some(r)) => {
                    // The dirty range in this binding's own indices.
                    let split = data.instance_split();
                    let (first, end) = match name {
                        names::INSTANCES => (0, split),
                        _ => (split, data.instances.len()),
                    };
                    let size = element.size as usize;
                    let start = r.start.clamp(first, end) - first;
                    let stop = r.end.clamp(first, end) - first;
                    start * size..stop.max(start) * size
                }
                _ => 0..bytes.len(),
            };
            if !range.is_empty() {
                gpu.queue
                    .write_buffer(&slot.buffer, range.start as u64, &bytes[range.clone()]);
                stats.bytes += range.len() as u64;
            }
        }
        // Pages installed and evicted since: a few small ranges each, unless the
        // geometry went up whole above.
        let writes = data.take_stream_writes();
        if !geometry && !writes.is_empty() {
            stats.bytes += self.write_stream(gpu, data, &writes);
        }
        self.geometry_version = data.geometry_version;
        self.materials_version = data.materials_version;
        self.textures_version = data.textures_version;
        self.instances_split = data.instances_split();
        stats
    }

    /// Writes the streaming changes `writes` (ranges of `data`'s buffers) to the GPU's
    /// copies by one dispatch ([`crate::stream_upload`]); returns the bytes written.
    fn write_stream(&mut self, gpu: &GpuContext, data: &SceneData, writes: &[StreamWrite]) -> u64 {
        let Some(targets) = StreamBuffer::ALL
            .map(|b| ORDER.iter().position(|&n| n == b.name()))
            .into_iter()
            .collect::<Option<Vec<usize>>>()
        else {
            return 0;
        };
        let buffers = &self.buffers;
        let parts: Vec<Part<'_>> = (writes.iter())
            .filter_map(|w| {
                let (first_word, words) = stream_words(data, w.buffer, w.first, w.count);
                let slot = &buffers[targets[w.buffer as usize]];
                let end = (u64::from(first_word) + words.len() as u64) * 4;
                (!words.is_empty() && end <= slot.buffer.size()).then_some(Part {
                    buffer: w.buffer,
                    first_word,
                    words,
                })
            })
            .collect();
        let upload = self
            .stream_upload
            .get_or_insert_with(|| StreamUpload::new(gpu));
        let targets = [0, 1, 2, 3, 4].map(|k| &buffers[targets[k]].buffer);
        upload.write(gpu, targets, &parts)
    }

    /// The uploaded buffer named `name` (one of [`crate::names`]), to import it into a graph
    /// built elsewhere or read it back in a test.
    pub fn buffer(&self, name: &str) -> Option<&wgpu::Buffer> {
        self.buffers
            .iter()
            .find(|b| b.name == name)
            .map(|b| &b.buffer)
    }

    /// Declares the buffers as imported resources of a graph.
    pub fn import(&self, g: &mut GraphBuilder) -> SceneHandles {
        SceneHandles::import_each(self.instances_split, |name| self.import_one(g, name))
    }

    /// True when the instances take two bindings (graphs must import `instances_high`).
    pub fn instances_split(&self) -> bool {
        self.instances_split
    }

    /// Declares the culling-hierarchy buffers as imported resources of a graph (for
    /// `fill_clusters`' `hierarchy` implementation).
    pub fn import_hierarchy(&self, g: &mut GraphBuilder) -> HierarchyHandles {
        let mut h = |name: &str| self.import_one(g, name);
        HierarchyHandles {
            nodes: h(names::HIERARCHY_NODES),
            clusters: h(names::HIERARCHY_CLUSTERS),
            roots: h(names::HIERARCHY_ROOTS),
        }
    }

    /// Declares a streamed scene's `stream_errors` buffer as an imported resource (for
    /// `cull_lod`'s streaming slots).
    pub fn import_stream_errors(&self, g: &mut GraphBuilder) -> Handle<Buffer> {
        self.import_one(g, names::STREAM_ERRORS)
    }

    /// Declares the buffer `name` (one of [`names`]) as an imported resource, sized as
    /// the scene holds it.
    fn import_one(&self, g: &mut GraphBuilder, name: &str) -> Handle<Buffer> {
        let b = self
            .buffers
            .iter()
            .find(|b| b.name == name)
            .expect("every name has a buffer");
        g.import_buffer(
            name,
            BufferDesc::array(b.element.clone(), b.capacity),
            USAGE,
        )
    }

    /// The buffers for [`meshlight_graph::Executor::execute`] (the hierarchy's too; a
    /// graph that does not declare them ignores them).
    pub fn imports(&self) -> Imports {
        self.buffers.iter().fold(Imports::new(), |imports, b| {
            imports.buffer(b.name, &b.buffer)
        })
    }
}

fn create(gpu: &GpuContext, name: &'static str, element: Element, bytes: &[u8]) -> SceneBuffer {
    let capacity = (bytes.len() / element.size as usize).max(1) as u64;
    let mut padded = bytes.to_vec();
    padded.resize((capacity * element.size as u64) as usize, 0);
    SceneBuffer {
        name,
        element,
        buffer: gpu.buffer_with_data(name, &padded, USAGE),
        capacity,
    }
}
