//! The pass behind `GraphBuilder::readback`: copies a buffer (or a byte range of it) into
//! the executor's ring of map-read buffers, to be taken frames later without waiting.

use crate::access::Access;
use crate::contract::{Slot, SlotKind, StageContract};
use crate::error::{GraphError, Result};
use crate::pass::{Implementation, Pass, SetupContext};
use crate::record::RecordContext;

/// Stage name of readback passes in plans and dumps.
pub const STAGE: &str = "readback";

pub struct ReadbackPass {
    name: String,
    range: Option<std::ops::Range<u64>>,
    latency: u32,
}

impl ReadbackPass {
    pub fn new(name: &str, range: Option<std::ops::Range<u64>>, latency: u32) -> Self {
        Self {
            name: name.to_string(),
            range,
            latency,
        }
    }
}

impl Pass for ReadbackPass {
    fn implementation(&self) -> Implementation {
        Implementation::new(
            "ring",
            StageContract {
                stage: STAGE,
                slots: vec![Slot {
                    name: "source",
                    access: Access::CopySrc,
                    also: Vec::new(),
                    kind: SlotKind::Buffer { element: None },
                    doc: "the buffer copied to the CPU",
                    optional: false,
                }],
            },
        )
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        if self.latency == 0 {
            return Err(GraphError::parameter(format!(
                "readback `{}` has latency 0, which would make the CPU wait for the GPU; use 1 or more frames",
                self.name
            )));
        }
        if let Some(r) = &self.range {
            if r.start % 4 != 0 || r.end % 4 != 0 || r.end <= r.start {
                return Err(GraphError::parameter(format!(
                    "readback `{}` range {r:?} must be non-empty and start and end on multiples of 4 bytes",
                    self.name
                )));
            }
            ctx.min_bytes("source", r.end);
        }
        ctx.side_effect();
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        ctx.readback_copy(&self.name, self.latency, "source", self.range.clone())
    }
}
