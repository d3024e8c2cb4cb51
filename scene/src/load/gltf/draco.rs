//! Primitives compressed with `KHR_draco_mesh_compression` (what Blender, glTF-Transform
//! and many scanning tools write), decoded once after the buffers are loaded by the
//! pure-Rust `draco-core` decoder. Each compressed primitive's accessors are replaced by
//! plain ones over the decoded values (FLOAT attributes, UNSIGNED_INT indices, appended as
//! a new buffer), so every reader after this step sees an ordinary file and applies its
//! ordinary checks: counts, finiteness, index range.
//!
//! The stream is untrusted. The extension object is checked against the file before the
//! decoder runs; what the decoder returns is checked against what the accessors declare
//! (count, component count) and against the loader's input limit; the decoder itself
//! runs behind a panic guard, so a stream that trips a bug in it is an error naming the
//! primitive, never an abort.

use std::collections::HashMap;

use draco_core::{DataType, DecoderBuffer, MeshDecoder, PointAttribute, PointIndex};
use gltf::json::Root;
use gltf::json::Value;
use gltf::json::accessor::{ComponentType, GenericComponentType};
use gltf::json::validation::{Checked, USize64};

use super::accessor::integer_component;
use crate::load::MAX_INPUT_BYTES;

/// The extension's name, as files list it.
pub const EXTENSION: &str = "KHR_draco_mesh_compression";

/// A primitive's `KHR_draco_mesh_compression` object, checked.
struct Compressed {
    view: usize,
    /// glTF attribute name → the Draco attribute's unique id.
    attributes: Vec<(String, u32)>,
}

/// What one Draco stream decodes to, in glTF's terms.
struct Decoded {
    points: usize,
    indices: Vec<u32>,
    /// By Draco unique id: components per value and the values as floats, one element
    /// per point.
    attributes: HashMap<u32, (usize, Vec<f32>)>,
}

/// Decodes every Draco-compressed primitive of `root`, pointing its accessors at plain
/// data appended to `buffers`. Primitives sharing one stream decode it once. The error
/// names the mesh, the primitive and what is wrong.
pub fn decode_primitives(root: &mut Root, buffers: &mut Vec<Vec<u8>>) -> Result<(), String> {
    let mut decoded_total = 0usize;
    // Accessor → (stream view, Draco id) it was replaced from: an accessor shared by
    // two compressed primitives must come from the same attribute of the same stream.
    let mut replaced: HashMap<usize, (usize, Option<u32>)> = HashMap::new();
    let mut streams: HashMap<usize, Decoded> = HashMap::new();
    // The file's own views (decoded data is appended after them).
    let views = root.buffer_views.len();
    for mi in 0..root.meshes.len() {
        for pi in 0..root.meshes[mi].primitives.len() {
            let Some(ext) = root.meshes[mi].primitives[pi]
                .extensions
                .as_ref()
                .and_then(|e| e.others.get(EXTENSION))
            else {
                continue;
            };
            let name = root.meshes[mi]
                .name
                .clone()
                .unwrap_or_else(|| format!("#{mi}"));
            let what = format!("mesh {name:?} primitive {pi} ({EXTENSION})");
            let compressed = parse(ext, views).map_err(|e| format!("{what}: {e}"))?;
            if let std::collections::hash_map::Entry::Vacant(slot) = streams.entry(compressed.view)
            {
                let bytes = view_bytes(root, buffers, compressed.view)
                    .map_err(|e| format!("{what}: {e}"))?;
                let decoded = decode(bytes).map_err(|e| format!("{what}: {e}"))?;
                let size = decoded.indices.len() * 4
                    + decoded
                        .attributes
                        .values()
                        .map(|(_, v)| v.len() * 4)
                        .sum::<usize>();
                decoded_total = decoded_total.saturating_add(size);
                if decoded_total as u64 > MAX_INPUT_BYTES {
                    return Err(format!(
                        "{what}: the compressed primitives decode to more than \
                         {MAX_INPUT_BYTES} bytes, the loader's input limit; split the scene \
                         into smaller files"
                    ));
                }
                slot.insert(decoded);
            }
            let decoded = &streams[&compressed.view];
            let primitive = &root.meshes[mi].primitives[pi];
            let mut plan: Vec<(usize, Option<u32>)> = Vec::new();
            for (semantic, id) in &compressed.attributes {
                let Some(accessor) = primitive
                    .attributes
                    .iter()
                    .find(|(s, _)| semantic_name(s).as_deref() == Some(semantic.as_str()))
                    .map(|(_, a)| a.value())
                else {
                    // The stream holds an attribute the primitive does not use.
                    continue;
                };
                if !decoded.attributes.contains_key(id) {
                    return Err(format!(
                        "{what}: its {semantic} is Draco attribute {id}, which the stream \
                         does not hold; the file is damaged"
                    ));
                }
                plan.push((accessor, Some(*id)));
            }
            match primitive.indices {
                Some(i) => plan.push((i.value(), None)),
                None => {
                    return Err(format!(
                        "{what}: it has no indices accessor, which the extension requires"
                    ));
                }
            }
            for (accessor, id) in plan {
                if let Some(&(view, was)) = replaced.get(&accessor) {
                    if (view, was) != (compressed.view, id) {
                        return Err(format!(
                            "{what}: accessor {accessor} is also decoded from another \
                             Draco stream or attribute; give each compressed primitive \
                             accessors of its own"
                        ));
                    }
                    continue;
                }
                replace(root, buffers, accessor, decoded, id)
                    .map_err(|e| format!("{what}: {e}"))?;
                replaced.insert(accessor, (compressed.view, id));
            }
        }
    }
    Ok(())
}

/// A semantic as files spell it (`POSITION`, `TEXCOORD_0`, …).
fn semantic_name(s: &Checked<gltf::Semantic>) -> Option<String> {
    match s {
        Checked::Valid(s) => Some(s.to_string()),
        Checked::Invalid => None,
    }
}

fn parse(ext: &Value, views: usize) -> Result<Compressed, String> {
    let view = match ext.get("bufferView") {
        None => return Err("it has no bufferView; the extension requires one".into()),
        Some(v) => v
            .as_u64()
            .and_then(|n| usize::try_from(n).ok())
            .ok_or_else(|| format!("its bufferView is {v}, not a whole number"))?,
    };
    if view >= views {
        return Err(format!(
            "its bufferView is {view}, but the file has only {views} buffer views"
        ));
    }
    let Some(map) = ext.get("attributes").and_then(Value::as_object) else {
        return Err("it has no attributes object; the extension requires one".into());
    };
    let mut attributes = Vec::with_capacity(map.len());
    for (semantic, id) in map {
        let id = id
            .as_u64()
            .and_then(|n| u32::try_from(n).ok())
            .ok_or_else(|| format!("its attribute {semantic} is {id}, not a Draco attribute id"))?;
        attributes.push((semantic.clone(), id));
    }
    Ok(Compressed { view, attributes })
}

/// The bytes of buffer view `view`, checked against its buffer.
fn view_bytes<'b>(root: &Root, buffers: &'b [Vec<u8>], view: usize) -> Result<&'b [u8], String> {
    let v = &root.buffer_views[view];
    let buffer = v.buffer.value();
    let data = buffers.get(buffer).ok_or_else(|| {
        format!(
            "its buffer view {view} names buffer {buffer}, but the file has only {}",
            buffers.len()
        )
    })?;
    let offset = v.byte_offset.map_or(0, |o| o.0) as usize;
    let length = v.byte_length.0 as usize;
    offset
        .checked_add(length)
        .filter(|&end| end <= data.len())
        .map(|end| &data[offset..end])
        .ok_or_else(|| {
            format!(
                "its buffer view {view} (bytes {offset} + {length}) lies outside buffer \
                 {buffer} of {} bytes",
                data.len()
            )
        })
}

/// Runs the Draco decoder on `bytes` and reads its attributes out as floats.
fn decode(bytes: &[u8]) -> Result<Decoded, String> {
    let outcome = std::panic::catch_unwind(|| {
        let mut buffer = DecoderBuffer::new(bytes);
        let mut mesh = draco_core::Mesh::new();
        MeshDecoder::new()
            .decode(&mut buffer, &mut mesh)
            .map(|()| mesh)
    });
    let mesh = match outcome {
        Ok(Ok(mesh)) => mesh,
        Ok(Err(e)) => {
            return Err(format!(
                "its Draco stream does not decode ({e}); the file is damaged or was written \
                 by a newer encoder"
            ));
        }
        Err(_) => {
            return Err(
                "the Draco decoder failed on its stream (it stopped on an internal \
                        check); the file is damaged"
                    .into(),
            );
        }
    };
    let points = mesh.num_points();
    let faces = mesh.num_faces();
    let mut indices = Vec::with_capacity(faces.saturating_mul(3));
    for f in 0..faces {
        for p in mesh.face(draco_core::FaceIndex(f as u32)) {
            if p.0 as usize >= points {
                return Err(format!(
                    "its Draco stream's face {f} names point {}, but it has {points} points",
                    p.0
                ));
            }
            indices.push(p.0);
        }
    }
    let mut attributes = HashMap::new();
    for a in 0..mesh.num_attributes() {
        let attribute = mesh.attribute(a);
        let values = floats(attribute, points).map_err(|e| {
            format!(
                "its Draco attribute {} ({:?}): {e}",
                attribute.unique_id(),
                attribute.attribute_type()
            )
        })?;
        attributes.insert(
            attribute.unique_id(),
            (attribute.num_components() as usize, values),
        );
    }
    Ok(Decoded {
        points,
        indices,
        attributes,
    })
}

/// Attribute `a`'s value at every point, as floats (normalised integers mapped to 0..1
/// or -1..1 as glTF maps them).
fn floats(a: &PointAttribute, points: usize) -> Result<Vec<f32>, String> {
    let components = a.num_components() as usize;
    let width = a.data_type().byte_length();
    let stride = a.byte_stride();
    if width == 0 || components == 0 || stride < (width * components) as i64 {
        return Err(format!(
            "{components} components of {:?} in {stride}-byte elements cannot be read",
            a.data_type()
        ));
    }
    let stride = stride as usize;
    let data = a.buffer().data();
    let normalized = a.normalized();
    let mut out = Vec::with_capacity(points.saturating_mul(components));
    for p in 0..points {
        let value = a.mapped_index(PointIndex(p as u32)).0 as usize;
        let at = value
            .checked_mul(stride)
            .filter(|&o| o + width * components <= data.len())
            .ok_or_else(|| format!("point {p} maps to value {value}, outside its data"))?;
        for c in 0..components {
            let b = &data[at + c * width..at + (c + 1) * width];
            out.push(scalar(a.data_type(), b, normalized));
        }
    }
    Ok(out)
}

/// One scalar of type `ty` from its little-endian bytes, as glTF reads it
/// ([`integer_component`] for the integers).
fn scalar(ty: DataType, b: &[u8], normalized: bool) -> f32 {
    let n = normalized;
    match ty {
        DataType::Int8 => integer_component(b[0] as i8 as f32, 1, true, n),
        DataType::Uint8 | DataType::Bool => integer_component(b[0] as f32, 1, false, n),
        DataType::Int16 => integer_component(i16::from_le_bytes([b[0], b[1]]) as f32, 2, true, n),
        DataType::Uint16 => integer_component(u16::from_le_bytes([b[0], b[1]]) as f32, 2, false, n),
        DataType::Int32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
        DataType::Uint32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
        DataType::Int64 => i64::from_le_bytes(b[..8].try_into().unwrap_or_default()) as f32,
        DataType::Uint64 => u64::from_le_bytes(b[..8].try_into().unwrap_or_default()) as f32,
        DataType::Float32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        DataType::Float64 => f64::from_le_bytes(b[..8].try_into().unwrap_or_default()) as f32,
        DataType::Invalid => f32::NAN,
    }
}

/// Points accessor `index` at a new buffer holding the decoded attribute `id` (or, for
/// `None`, the indices), after checking its declared count and width against them.
fn replace(
    root: &mut Root,
    buffers: &mut Vec<Vec<u8>>,
    index: usize,
    decoded: &Decoded,
    id: Option<u32>,
) -> Result<(), String> {
    let Some(accessor) = root.accessors.get(index) else {
        return Err(format!(
            "it refers to accessor {index}, but the file has only {} accessors",
            root.accessors.len()
        ));
    };
    let (bytes, count, component) = match id {
        None => (
            decoded
                .indices
                .iter()
                .flat_map(|i| i.to_le_bytes())
                .collect::<Vec<u8>>(),
            decoded.indices.len(),
            ComponentType::U32,
        ),
        Some(id) => {
            let (components, values) = &decoded.attributes[&id];
            let declared = match accessor.type_ {
                Checked::Valid(t) => t.multiplicity(),
                Checked::Invalid => 0,
            };
            if declared != *components {
                return Err(format!(
                    "accessor {index} declares {declared} components per element, but its \
                     Draco attribute {id} has {components}"
                ));
            }
            (
                values.iter().flat_map(|v| v.to_le_bytes()).collect(),
                decoded.points,
                ComponentType::F32,
            )
        }
    };
    if accessor.count.0 != count as u64 {
        return Err(format!(
            "accessor {index} declares {} elements, but the Draco stream decodes to {count}",
            accessor.count.0
        ));
    }
    let view = gltf::json::buffer::View {
        buffer: gltf::json::Index::new(buffers.len() as u32),
        byte_length: USize64(bytes.len() as u64),
        byte_offset: None,
        byte_stride: None,
        name: None,
        target: None,
        extensions: None,
        extras: Default::default(),
    };
    buffers.push(bytes);
    let view_index = root.buffer_views.len() as u32;
    root.buffer_views.push(view);
    let accessor = &mut root.accessors[index];
    accessor.buffer_view = Some(gltf::json::Index::new(view_index));
    accessor.byte_offset = None;
    accessor.component_type = Checked::Valid(GenericComponentType(component));
    accessor.normalized = false;
    accessor.sparse = None;
    Ok(())
}
