//! Synthetic graphs for benchmarks and property tests: passes that record nothing, a pass
//! that copies a texture out for a test to read, and random layered DAGs of any size.

use crate::access::Access;
use crate::builder::{Bindings, GraphBuilder};
use crate::contract::{Slot, StageContract};
use crate::error::Result;
use crate::pass::{Implementation, Pass, SetupContext};
use crate::record::RecordContext;
use crate::resource::{AnyHandle, BufferDesc, Element};

/// A pass with any slots that records nothing: compile and CPU-overhead benchmarks.
pub struct NoopPass {
    /// The stage's slots; compile treats them like a real pass's.
    pub slots: Vec<Slot>,
}

impl Pass for NoopPass {
    fn implementation(&self) -> Implementation {
        Implementation::new(
            "noop",
            StageContract {
                stage: "noop",
                slots: self.slots.clone(),
            },
        )
    }
    fn setup(&self, _: &mut SetupContext) -> Result<()> {
        Ok(())
    }
    fn record(&self, _: &mut RecordContext<'_>) -> Result<()> {
        Ok(())
    }
}

/// Copies a whole 2-D texture (slot `texture`) into a buffer (slot `buffer`), rows packed,
/// so a test can read back what a pass wrote into a texture. A row must be a multiple of
/// 256 bytes, as texture copies require.
pub struct CopyTextureToBuffer {
    /// The texture's format; the buffer gets its texels as they are.
    pub format: wgpu::TextureFormat,
    /// Width, in texels; a row must be a multiple of 256 bytes.
    pub width: u32,
    /// Height, in texels.
    pub height: u32,
}

impl Pass for CopyTextureToBuffer {
    fn implementation(&self) -> Implementation {
        // Any buffer: the test reads it as whatever the texels are.
        let mut buffer = Slot::buffer("buffer", Access::CopyDst, Element::BYTES, "");
        buffer.kind = crate::contract::SlotKind::Buffer { element: None };
        Implementation::new(
            "copy",
            StageContract {
                stage: "copy_texture_to_buffer",
                slots: vec![
                    Slot::texture("texture", Access::CopySrc, Some(self.format), ""),
                    buffer,
                ],
            },
        )
    }
    fn setup(&self, _: &mut SetupContext) -> Result<()> {
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let texel = self.format.block_copy_size(None).unwrap_or(4);
        let (texture, _) = ctx.texture("texture")?;
        let (buffer, _) = ctx.buffer("buffer")?;
        ctx.encoder().copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.width * texel),
                    rows_per_image: Some(self.height),
                },
            },
            wgpu::Extent3d {
                width: self.width,
                height: self.height,
                depth_or_array_layers: 1,
            },
        );
        Ok(())
    }
}

/// A random layered graph of `n` passes: each writes its own transient and reads up to
/// three earlier ones; every tenth also accumulates into the imported output.
pub fn random_graph(n: usize, seed: u64) -> GraphBuilder {
    let mut state = seed | 1;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut g = GraphBuilder::new();
    let mut out = g
        .import_buffer(
            "out",
            BufferDesc::array(Element::U32, 16),
            wgpu::BufferUsages::STORAGE,
        )
        .erase();
    let names: Vec<String> = (0..n).map(|i| format!("t{i}")).collect();
    for name in &names {
        g.create_buffer(name, BufferDesc::array(Element::U32, 64 + next() % 4096));
    }
    for i in 0..n {
        let count = if i == 0 { 0 } else { (next() % 4) as usize };
        let reads: Vec<usize> = (0..count).map(|_| (next() % i as u64) as usize).collect();
        let accumulate = i % 10 == 9 || i == n - 1;
        out = add_layer_pass(&mut g, i, &reads, accumulate, out);
    }
    g
}

/// Adds pass `p{i}` of a layered graph of transients named `t{n}`: a [`NoopPass`] reading
/// `t{r}` for each of `reads` (three at most) through slots `in0`..`in2` and writing `t{i}`
/// through `w`; with `accumulate` it also reads and writes `out` through slot `out`.
/// Returns the version of `out` that later passes see.
///
/// [`random_graph`] builds its graphs of these passes, and a property test can build its
/// own from generated reads: both then check graphs of one shape.
pub fn add_layer_pass(
    g: &mut GraphBuilder,
    i: usize,
    reads: &[usize],
    accumulate: bool,
    out: AnyHandle,
) -> AnyHandle {
    const INPUTS: [&str; 3] = ["in0", "in1", "in2"];
    let mut slots = Vec::new();
    let mut b = Bindings::new();
    for (name, src) in INPUTS.iter().zip(reads) {
        slots.push(Slot::buffer(name, Access::StorageRead, Element::U32, ""));
        b = b.bind_named(name, &format!("t{src}"));
    }
    slots.push(Slot::buffer("w", Access::StorageWrite, Element::U32, ""));
    b = b.bind_named("w", &format!("t{i}"));
    if accumulate {
        slots.push(Slot::buffer(
            "out",
            Access::StorageReadWrite,
            Element::U32,
            "",
        ));
        b = b.bind("out", out);
    }
    let outputs = g
        .add_pass(&format!("p{i}"), NoopPass { slots }, b)
        .expect("layered graphs are well-formed");
    outputs
        .written()
        .iter()
        .find(|(s, _)| *s == "out")
        .map_or(out, |(_, h)| *h)
}
