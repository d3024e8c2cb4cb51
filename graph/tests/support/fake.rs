//! A pass with any contract and no GPU work, for compile tests.
#![allow(dead_code)]

use meshlight_graph::*;

pub struct Fake {
    pub stage: &'static str,
    pub slots: Vec<Slot>,
    pub required: wgpu::Features,
    pub side_effect: bool,
    pub scratch: Option<u64>,
}

impl Fake {
    pub fn new(stage: &'static str, slots: Vec<Slot>) -> Self {
        Self {
            stage,
            slots,
            required: wgpu::Features::empty(),
            side_effect: false,
            scratch: None,
        }
    }
    /// Reads each of `inputs`, writes each of `outputs` (u32 buffers).
    pub fn rw(inputs: &[&'static str], outputs: &[&'static str]) -> Self {
        let mut slots: Vec<Slot> = inputs
            .iter()
            .map(|n| Slot::buffer(n, Access::StorageRead, Element::U32, ""))
            .collect();
        slots.extend(
            outputs
                .iter()
                .map(|n| Slot::buffer(n, Access::StorageWrite, Element::U32, "")),
        );
        Self::new("fake", slots)
    }
}

impl Pass for Fake {
    fn contract(&self) -> StageContract {
        StageContract {
            stage: self.stage,
            slots: self.slots.clone(),
        }
    }
    fn implementation(&self) -> &'static str {
        "fake"
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        ctx.require_features(self.required);
        if self.side_effect {
            ctx.side_effect();
        }
        if let Some(bytes) = self.scratch {
            ctx.scratch_buffer(
                "tmp",
                BufferDesc::bytes(Element::BYTES, bytes),
                &[Access::StorageReadWrite],
            );
        }
        Ok(())
    }
    fn record(&self, _: &mut RecordContext<'_>) -> Result<()> {
        Ok(())
    }
}

pub fn u32s(n: u64) -> BufferDesc {
    BufferDesc::array(Element::U32, n)
}

pub const IMPORT_USAGE: wgpu::BufferUsages =
    wgpu::BufferUsages::STORAGE.union(wgpu::BufferUsages::COPY_SRC);

pub fn opts() -> CompileOptions {
    CompileOptions::new(wgpu::Features::empty())
}
