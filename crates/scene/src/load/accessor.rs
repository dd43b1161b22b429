//! glTF accessors (glTF 2.0 §3.6.2) read by the toolkit instead of the `gltf` crate's reader,
//! so that a hostile file is an error, never a panic or a silent cut: the element type must be
//! one the attribute allows, `byteStride` at least the element's size, every byte inside its
//! buffer view and the view inside its buffer (checked arithmetic: no size wraps), sparse
//! indices strictly increasing and below the count, and the count bounded.

use gltf::accessor::{DataType, Dimensions, sparse::IndexType};

use crate::SceneErrorKind;

/// The most elements one accessor may hold: 2^26 (a mesh of 64 M vertices). A sparse accessor
/// without a buffer view (zeros that come from no bytes) may besides hold no more elements
/// than the file's buffers hold bytes.
pub const MAX_ELEMENTS: usize = 1 << 26;

/// The element types an attribute allows: its dimensions, the component types, and whether
/// integer components must be normalized.
pub struct Allowed {
    /// SCALAR, VEC2, VEC3, ...
    pub dimensions: Dimensions,
    /// The component types.
    pub types: &'static [DataType],
    /// Integer components are normalized to \[0, 1\] / \[−1, 1\] (texture coordinates), or
    /// must not be (indices).
    pub normalized: bool,
}

/// POSITION and NORMAL: VEC3 of FLOAT.
pub const VEC3_F32: Allowed = Allowed {
    dimensions: Dimensions::Vec3,
    types: &[DataType::F32],
    normalized: false,
};

/// TANGENT: VEC4 of FLOAT.
pub const VEC4_F32: Allowed = Allowed {
    dimensions: Dimensions::Vec4,
    types: &[DataType::F32],
    normalized: false,
};

/// COLOR_0 as RGB: VEC3 of FLOAT, normalized UNSIGNED_BYTE or normalized UNSIGNED_SHORT.
pub const COLOR_RGB: Allowed = Allowed {
    dimensions: Dimensions::Vec3,
    types: &[DataType::F32, DataType::U8, DataType::U16],
    normalized: true,
};

/// COLOR_0 as RGBA: VEC4 of the same types.
pub const COLOR_RGBA: Allowed = Allowed {
    dimensions: Dimensions::Vec4,
    ..COLOR_RGB
};

/// TEXCOORD_n: VEC2 of FLOAT, normalized UNSIGNED_BYTE or normalized UNSIGNED_SHORT.
pub const TEXCOORD: Allowed = Allowed {
    dimensions: Dimensions::Vec2,
    types: &[DataType::F32, DataType::U8, DataType::U16],
    normalized: true,
};

/// Indices: SCALAR of UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT.
pub const INDICES: Allowed = Allowed {
    dimensions: Dimensions::Scalar,
    types: &[DataType::U8, DataType::U16, DataType::U32],
    normalized: false,
};

/// JOINTS_0: VEC4 of UNSIGNED_BYTE or UNSIGNED_SHORT, not normalized.
pub const JOINTS: Allowed = Allowed {
    dimensions: Dimensions::Vec4,
    types: &[DataType::U8, DataType::U16],
    normalized: false,
};

/// WEIGHTS_0: VEC4 of FLOAT, normalized UNSIGNED_BYTE or normalized UNSIGNED_SHORT.
pub const WEIGHTS: Allowed = Allowed {
    dimensions: Dimensions::Vec4,
    ..TEXCOORD
};

/// Inverse bind matrices: MAT4 of FLOAT.
pub const MAT4_F32: Allowed = Allowed {
    dimensions: Dimensions::Mat4,
    types: &[DataType::F32],
    normalized: false,
};

/// Animation key times and morph weights: SCALAR of FLOAT.
pub const SCALAR_F32: Allowed = Allowed {
    dimensions: Dimensions::Scalar,
    types: &[DataType::F32],
    normalized: false,
};

/// Animated rotations: VEC4 of FLOAT or of normalized (UNSIGNED_)BYTE/SHORT.
pub const ROTATION: Allowed = Allowed {
    dimensions: Dimensions::Vec4,
    types: &[
        DataType::F32,
        DataType::I8,
        DataType::U8,
        DataType::I16,
        DataType::U16,
    ],
    normalized: true,
};

/// Every component of `accessor` (element after element) as `f64` — exact for every integer
/// type — after checking it against `allowed` and `buffers`. `what` names the attribute in
/// errors.
pub fn read(
    accessor: &gltf::Accessor,
    buffers: &[Vec<u8>],
    what: &str,
    allowed: &Allowed,
) -> Result<Vec<f64>, SceneErrorKind> {
    let fail = |problem: String| {
        SceneErrorKind::Gltf(format!("accessor {} ({what}): {problem}", accessor.index()))
    };
    let (dims, ty) = (accessor.dimensions(), accessor.data_type());
    if dims != allowed.dimensions || !allowed.types.contains(&ty) {
        return Err(fail(format!(
            "{dims:?} of {ty:?}, but {what} must be {:?} of {:?}",
            allowed.dimensions, allowed.types
        )));
    }
    let integer = ty != DataType::F32;
    if integer && accessor.normalized() != allowed.normalized {
        return Err(fail(format!(
            "{ty:?} components must {}be normalized",
            if allowed.normalized { "" } else { "not " }
        )));
    }
    let count = accessor.count();
    if count > MAX_ELEMENTS {
        return Err(fail(format!(
            "{count} elements, more than the {MAX_ELEMENTS} allowed"
        )));
    }
    let components = dims.multiplicity();
    let element = components * ty.size();
    let decode = |bytes: &[u8]| -> Vec<f64> {
        bytes
            .chunks_exact(ty.size())
            .map(|c| component(c, ty, accessor.normalized()))
            .collect()
    };
    let mut values = match accessor.view() {
        Some(view) => {
            let stride = view.stride().unwrap_or(element);
            if stride < element {
                return Err(fail(format!(
                    "byteStride {stride} is smaller than the {element}-byte element"
                )));
            }
            let data = view_bytes(&view, buffers).map_err(fail)?;
            let start = accessor.offset();
            let end = (count > 0)
                .then(|| {
                    (count - 1)
                        .checked_mul(stride)
                        .and_then(|s| s.checked_add(start))
                        .and_then(|s| s.checked_add(element))
                })
                .unwrap_or(Some(start));
            match end {
                Some(end) if end <= data.len() => {}
                _ => {
                    return Err(fail(format!(
                        "{count} elements of {element} bytes at offset {start}, stride {stride} \
                         reach past the {} bytes of buffer view {}",
                        data.len(),
                        view.index()
                    )));
                }
            }
            (0..count)
                .flat_map(|i| decode(&data[start + i * stride..start + i * stride + element]))
                .collect()
        }
        None if accessor.sparse().is_some() => {
            let bytes: usize = buffers.iter().map(Vec::len).sum();
            if count > bytes {
                return Err(fail(format!(
                    "{count} elements without a buffer view, more than the {bytes} bytes of the \
                     file's buffers"
                )));
            }
            vec![0.0; count * components]
        }
        None => return Err(fail("no buffer view and not sparse".into())),
    };
    if let Some(sparse) = accessor.sparse() {
        let n = sparse.count();
        if n == 0 || n > count {
            return Err(fail(format!(
                "{n} sparse elements for an accessor of {count}"
            )));
        }
        let indices = sparse.indices();
        let index_size = match indices.index_type() {
            IndexType::U8 => 1,
            IndexType::U16 => 2,
            IndexType::U32 => 4,
        };
        let index_bytes = packed_bytes(&indices.view(), indices.offset(), n, index_size, buffers)
            .map_err(fail)?;
        let value_bytes = packed_bytes(
            &sparse.values().view(),
            sparse.values().offset(),
            n,
            element,
            buffers,
        )
        .map_err(fail)?;
        let mut previous = None;
        for (k, (index, value)) in index_bytes
            .chunks_exact(index_size)
            .zip(value_bytes.chunks_exact(element))
            .enumerate()
        {
            let i = index
                .iter()
                .rev()
                .fold(0usize, |i, &b| i << 8 | usize::from(b));
            if i >= count || previous.is_some_and(|p| i <= p) {
                return Err(fail(format!(
                    "sparse index {k} is {i}: indices must increase and stay below {count}"
                )));
            }
            previous = Some(i);
            values[i * components..(i + 1) * components].copy_from_slice(&decode(value));
        }
    }
    Ok(values)
}

/// The bytes of buffer view `view` inside its buffer.
fn view_bytes<'b>(view: &gltf::buffer::View, buffers: &'b [Vec<u8>]) -> Result<&'b [u8], String> {
    let buffer = buffers
        .get(view.buffer().index())
        .ok_or_else(|| format!("buffer view {} names a missing buffer", view.index()))?;
    view.offset()
        .checked_add(view.length())
        .and_then(|end| buffer.get(view.offset()..end))
        .ok_or_else(|| {
            format!(
                "buffer view {} ({} bytes at offset {}) reaches past the {} bytes of buffer {}",
                view.index(),
                view.length(),
                view.offset(),
                buffer.len(),
                view.buffer().index()
            )
        })
}

/// `count` tightly packed items of `size` bytes at `offset` in `view` (sparse indices/values).
fn packed_bytes<'b>(
    view: &gltf::buffer::View,
    offset: usize,
    count: usize,
    size: usize,
    buffers: &'b [Vec<u8>],
) -> Result<&'b [u8], String> {
    let data = view_bytes(view, buffers)?;
    count
        .checked_mul(size)
        .and_then(|n| n.checked_add(offset))
        .and_then(|end| data.get(offset..end))
        .ok_or_else(|| {
            format!(
                "{count} sparse items of {size} bytes at offset {offset} reach past the {} bytes \
                 of buffer view {}",
                data.len(),
                view.index()
            )
        })
}

/// One little-endian component; normalized integers map to \[0, 1\] or \[−1, 1\] (glTF 2.0
/// §3.11).
fn component(b: &[u8], ty: DataType, normalized: bool) -> f64 {
    let (v, max) = match ty {
        DataType::I8 => (f64::from(b[0] as i8), 127.0),
        DataType::U8 => (f64::from(b[0]), 255.0),
        DataType::I16 => (f64::from(i16::from_le_bytes([b[0], b[1]])), 32767.0),
        DataType::U16 => (f64::from(u16::from_le_bytes([b[0], b[1]])), 65535.0),
        DataType::U32 => (f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])), 1.0),
        DataType::F32 => (f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])), 1.0),
    };
    if normalized && ty != DataType::F32 {
        (v / max).max(-1.0)
    } else {
        v
    }
}
