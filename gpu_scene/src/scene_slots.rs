//! The GPU scene's buffers as a stage reads them: one slot description per buffer, so
//! every contract that reads the scene declares the same slots, and none declares
//! `instances` without the optional `instances_high` that `instance_at` may read.
//!
//! The WGSL side is the shared modules `meshlight::scene_buffers` and
//! `meshlight::instance_table`, whose globals carry these slot names, so a shader that
//! imports them binds these slots with no layout written by hand.

use crate::gpu::elements;
use crate::{instance_table, names};
use meshlight_graph::{Element, Slot};

/// A buffer of the GPU scene that a stage reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneBuffer {
    /// `instances`, with the optional `instances_high` after it.
    Instances,
    /// `meshes`: per asset its grids and bounds.
    Meshes,
    /// `meshlets`: the meshlet records.
    Meshlets,
    /// `meshlet_groups`: the simplification groups.
    Groups,
    /// `payload`: the packed vertices, UVs and triangles.
    Payload,
    /// `materials`: the material table.
    Materials,
    /// `textures`: every texture's mip chain.
    Textures,
}

impl SceneBuffer {
    fn read_slot(self) -> Slot {
        let (name, element, doc) = match self {
            Self::Instances => (
                names::INSTANCES,
                elements::INSTANCE,
                "the scene's instances",
            ),
            Self::Meshes => (names::MESHES, elements::MESH, "the scene's meshes"),
            Self::Meshlets => (names::MESHLETS, elements::MESHLET, "the scene's meshlets"),
            Self::Groups => (
                names::GROUPS,
                elements::GROUP,
                "the scene's simplification groups",
            ),
            Self::Payload => (names::PAYLOAD, Element::U32, "the scene's meshlet payload"),
            Self::Materials => (
                names::MATERIALS,
                elements::MATERIAL,
                "the scene's materials",
            ),
            Self::Textures => (
                names::TEXTURES,
                Element::U32,
                "the scene's textures: RGBA8 mip chains",
            ),
        };
        Slot::read(name, element, doc)
    }
}

/// Read-only slots for `buffers`, in their order; [`SceneBuffer::Instances`] brings
/// [`instance_table::high_slot`] right after `instances`.
pub fn scene_reads(buffers: &[SceneBuffer]) -> Vec<Slot> {
    let mut slots = Vec::with_capacity(buffers.len() + 1);
    for &buffer in buffers {
        slots.push(buffer.read_slot());
        if buffer == SceneBuffer::Instances {
            slots.push(instance_table::high_slot());
        }
    }
    slots
}
