//! Reading glTF accessors from the raw JSON and the loaded buffers. Everything the file
//! says (indices into the accessor, view and buffer lists, component types, offsets,
//! strides, counts) is checked before a byte is read, so a damaged file gives an error
//! naming the accessor and never a panic inside a reader.

use gltf::json::Root;
use gltf::json::accessor::{ComponentType, Type};
use gltf::json::validation::Checked;

/// What a primitive attribute may hold, as glTF 2.0 allows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    Position,
    Normal,
    TexCoord,
    Color,
    Indices,
}

impl Role {
    fn name(self) -> &'static str {
        match self {
            Role::Position => "POSITION",
            Role::Normal => "NORMAL",
            Role::TexCoord => "TEXCOORD_0",
            Role::Color => "COLOR_0",
            Role::Indices => "indices",
        }
    }

    fn allowed(self) -> &'static str {
        match self {
            Role::Position => {
                "VEC3 of FLOAT, or (KHR_mesh_quantization) of BYTE, UNSIGNED_BYTE, SHORT or \
                 UNSIGNED_SHORT, normalized or not"
            }
            Role::Normal => "VEC3 of FLOAT, or (KHR_mesh_quantization) of normalized BYTE or SHORT",
            Role::TexCoord => {
                "VEC2 of FLOAT, of normalized UNSIGNED_BYTE or UNSIGNED_SHORT, or \
                 (KHR_mesh_quantization) of BYTE, UNSIGNED_BYTE, SHORT or UNSIGNED_SHORT, \
                 normalized or not"
            }
            Role::Color => {
                "VEC3 or VEC4 of FLOAT, or of normalized UNSIGNED_BYTE or UNSIGNED_SHORT"
            }
            Role::Indices => "SCALAR of UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT",
        }
    }

    fn accepts(self, ty: Type, ct: ComponentType, normalized: bool) -> bool {
        use ComponentType as C;
        // KHR_mesh_quantization's widening of the core types: a file may use it without
        // listing the extension, and reading it costs nothing.
        let small_int = matches!(ct, C::I8 | C::U8 | C::I16 | C::U16);
        match self {
            Role::Position => ty == Type::Vec3 && (ct == C::F32 || small_int),
            Role::Normal => {
                ty == Type::Vec3 && (ct == C::F32 || (normalized && matches!(ct, C::I8 | C::I16)))
            }
            Role::TexCoord => ty == Type::Vec2 && (ct == C::F32 || small_int),
            Role::Color => {
                matches!(ty, Type::Vec3 | Type::Vec4)
                    && (ct == C::F32 || (normalized && matches!(ct, C::U8 | C::U16)))
            }
            Role::Indices => ty == Type::Scalar && matches!(ct, C::U8 | C::U16 | C::U32),
        }
    }
}

/// A checked accessor: where its elements lie and how to decode them.
pub struct CheckedAccessor {
    pub count: usize,
    components: usize,
    component: ComponentType,
    normalized: bool,
    data: (usize, usize),
    offset: usize,
    stride: usize,
}

/// The declared element count of accessor `index` (for sizing before reading), or an
/// error when the index is out of range.
pub fn declared_count(root: &Root, index: usize, role: Role) -> Result<u64, String> {
    root.accessors
        .get(index)
        .map(|a| a.count.0)
        .ok_or_else(|| missing(root, index, role))
}

fn missing(root: &Root, index: usize, role: Role) -> String {
    format!(
        "{} refers to accessor {index}, but the file has only {} accessors",
        role.name(),
        root.accessors.len()
    )
}

/// Checks accessor `index` for `role` against the file and the loaded `buffers`.
pub fn check(
    root: &Root,
    buffers: &[Vec<u8>],
    index: usize,
    role: Role,
) -> Result<CheckedAccessor, String> {
    let a = root
        .accessors
        .get(index)
        .ok_or_else(|| missing(root, index, role))?;
    let what = format!("{} accessor {index}", role.name());
    let (Checked::Valid(ty), Checked::Valid(ct)) = (a.type_, a.component_type) else {
        return Err(format!(
            "{what} has an unknown type or component type; glTF allows {}",
            role.allowed()
        ));
    };
    let ct = ct.0;
    if !role.accepts(ty, ct, a.normalized) {
        return Err(format!(
            "{what} holds {ty:?} of {ct:?}{}; {} must be {}",
            if a.normalized { " (normalized)" } else { "" },
            role.name(),
            role.allowed()
        ));
    }
    if a.sparse.is_some() {
        return Err(format!(
            "{what} is sparse, which this loader does not read; re-export without sparse accessors"
        ));
    }
    let count = usize::try_from(a.count.0).map_err(|_| format!("{what}: count too large"))?;
    let components = ty.multiplicity();
    let size = ct.size();
    let element = components * size;
    let Some(view_index) = a.buffer_view else {
        return Err(format!(
            "{what} has no buffer view; give it one with the data"
        ));
    };
    let view = root.buffer_views.get(view_index.value()).ok_or_else(|| {
        format!(
            "{what} refers to buffer view {}, but the file has only {}",
            view_index.value(),
            root.buffer_views.len()
        )
    })?;
    let buffer = buffers.get(view.buffer.value()).ok_or_else(|| {
        format!(
            "buffer view {} refers to buffer {}, but the file has only {}",
            view_index.value(),
            view.buffer.value(),
            buffers.len()
        )
    })?;
    let view_start = view.byte_offset.map_or(0, |o| o.0);
    let view_len = view.byte_length.0;
    if view_start
        .checked_add(view_len)
        .is_none_or(|end| end > buffer.len() as u64)
    {
        return Err(format!(
            "buffer view {} (bytes {view_start} + {view_len}) lies outside its buffer of {} bytes",
            view_index.value(),
            buffer.len()
        ));
    }
    let stride = match view.byte_stride {
        Some(s) if s.0 < element => {
            return Err(format!(
                "{what}: byte stride {} is smaller than its {element}-byte elements",
                s.0
            ));
        }
        Some(s) => s.0,
        None => element,
    };
    let offset = a.byte_offset.map_or(0, |o| o.0);
    if !offset.is_multiple_of(size as u64) || !(stride as u64).is_multiple_of(size as u64) {
        return Err(format!(
            "{what}: offset {offset} or stride {stride} is not a multiple of its {size}-byte components"
        ));
    }
    let needed = if count == 0 {
        0
    } else {
        (count as u64 - 1)
            .checked_mul(stride as u64)
            .and_then(|n| n.checked_add(offset))
            .and_then(|n| n.checked_add(element as u64))
            .unwrap_or(u64::MAX)
    };
    if needed > view_len {
        return Err(format!(
            "{what}: {count} elements need {needed} bytes of its buffer view, which has {view_len}"
        ));
    }
    Ok(CheckedAccessor {
        count,
        components,
        component: ct,
        normalized: a.normalized,
        data: (view.buffer.value(), view_start as usize),
        offset: offset as usize,
        stride,
    })
}

/// An integer component `v`, `bytes` wide, as glTF decodes it: with `normalized`, an 8- or
/// 16-bit value divided by the largest its type holds (signed values clamped at -1, so
/// both -128 and -127 read -1); otherwise, and for wider types, as it is. Plain accessors
/// and Draco's decoded attributes both read through this.
pub(super) fn integer_component(v: f32, bytes: usize, signed: bool, normalized: bool) -> f32 {
    if !normalized {
        return v;
    }
    let max = match (bytes, signed) {
        (1, false) => 255.0,
        (1, true) => 127.0,
        (2, false) => 65535.0,
        (2, true) => 32767.0,
        _ => return v,
    };
    if signed { (v / max).max(-1.0) } else { v / max }
}

impl CheckedAccessor {
    /// Component `k` of element `i`, as `f32`: normalized integers scaled to 0..1
    /// (unsigned) or -1..1 (signed, as glTF decodes them), others converted as they are.
    fn float(&self, buffers: &[Vec<u8>], i: usize, k: usize) -> f32 {
        let raw = self.raw(buffers, i, k);
        let n = self.normalized;
        match self.component {
            ComponentType::F32 => f32::from_bits(raw),
            ComponentType::U8 => integer_component(raw as f32, 1, false, n),
            ComponentType::U16 => integer_component(raw as f32, 2, false, n),
            ComponentType::I8 => integer_component(raw as u8 as i8 as f32, 1, true, n),
            ComponentType::I16 => integer_component(raw as u16 as i16 as f32, 2, true, n),
            _ => raw as f32,
        }
    }

    /// The little-endian bits of component `k` of element `i` (in range: checked).
    fn raw(&self, buffers: &[Vec<u8>], i: usize, k: usize) -> u32 {
        let size = self.component.size();
        let at = self.data.1 + self.offset + i * self.stride + k * size;
        let b = &buffers[self.data.0][at..at + size];
        match size {
            1 => b[0] as u32,
            2 => u16::from_le_bytes([b[0], b[1]]) as u32,
            _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        }
    }

    pub fn read_vec3(&self, buffers: &[Vec<u8>]) -> Vec<[f32; 3]> {
        debug_assert_eq!(self.components, 3);
        (0..self.count)
            .map(|i| [0, 1, 2].map(|k| self.float(buffers, i, k)))
            .collect()
    }

    pub fn read_vec2(&self, buffers: &[Vec<u8>]) -> Vec<[f32; 2]> {
        debug_assert_eq!(self.components, 2);
        (0..self.count)
            .map(|i| [0, 1].map(|k| self.float(buffers, i, k)))
            .collect()
    }

    /// RGBA, alpha 1 where the accessor holds RGB.
    pub fn read_rgba(&self, buffers: &[Vec<u8>]) -> Vec<[f32; 4]> {
        debug_assert!(self.components == 3 || self.components == 4);
        (0..self.count)
            .map(|i| {
                [0, 1, 2, 3].map(|k| {
                    if k < self.components {
                        self.float(buffers, i, k)
                    } else {
                        1.0
                    }
                })
            })
            .collect()
    }

    pub fn read_indices(&self, buffers: &[Vec<u8>]) -> Vec<u32> {
        (0..self.count).map(|i| self.raw(buffers, i, 0)).collect()
    }
}
