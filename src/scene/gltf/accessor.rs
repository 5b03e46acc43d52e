//! Accessors: what each is read for ([`Usage`]), format and count checks, validated strided views of buffer
//! views, component conversion, sparse accessors, and the loader's typed reads.

use super::{json, Loader, Res, MAX_ELEMENTS};
use glam::Vec3;
use json::accessor::{ComponentType, GenericComponentType, IndexComponentType, Type};
use json::validation::Checked;

/// What an accessor is read for; decides the accepted type and component types.
#[derive(Clone, Copy)]
pub(super) enum Usage {
    Position,
    Normal,
    TexCoord,
    Indices,
}

impl Usage {
    fn name(self) -> &'static str {
        match self {
            Usage::Position => "POSITION",
            Usage::Normal => "NORMAL",
            Usage::TexCoord => "TEXCOORD_0",
            Usage::Indices => "indices",
        }
    }
    fn ty(self) -> Type {
        match self {
            Usage::Position | Usage::Normal => Type::Vec3,
            Usage::TexCoord => Type::Vec2,
            Usage::Indices => Type::Scalar,
        }
    }
    /// The component types the core spec allows (no KHR_mesh_quantization).
    fn accepts(self, comp: ComponentType, normalized: bool) -> bool {
        use ComponentType::*;
        match self {
            Usage::Position | Usage::Normal => comp == F32 && !normalized,
            Usage::TexCoord => (comp == F32 && !normalized) || (normalized && matches!(comp, U8 | U16)),
            Usage::Indices => !normalized && matches!(comp, U8 | U16 | U32),
        }
    }
    fn expected(self) -> &'static str {
        match self {
            Usage::Position | Usage::Normal => "FLOAT",
            Usage::TexCoord => "FLOAT, or normalized UNSIGNED_BYTE / UNSIGNED_SHORT",
            Usage::Indices => "UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT",
        }
    }
}

fn type_name(ty: Type) -> &'static str {
    match ty {
        Type::Scalar => "SCALAR",
        Type::Vec2 => "VEC2",
        Type::Vec3 => "VEC3",
        Type::Vec4 => "VEC4",
        Type::Mat2 => "MAT2",
        Type::Mat3 => "MAT3",
        Type::Mat4 => "MAT4",
    }
}

/// Checks an accessor's type and component type for `usage`; returns the component type and count.
fn check_format(acc: &json::Accessor, usage: Usage) -> Res<(ComponentType, usize)> {
    let Checked::Valid(ty) = acc.type_ else { return Err("invalid accessor type".into()) };
    let Checked::Valid(GenericComponentType(comp)) = acc.component_type else {
        return Err("invalid componentType".into());
    };
    if ty != usage.ty() {
        let (got, want) = (type_name(ty), type_name(usage.ty()));
        return Err(format!("type {got} is not valid for {} (expected {want})", usage.name()));
    }
    if !usage.accepts(comp, acc.normalized) {
        let norm = if acc.normalized { "normalized " } else { "" };
        return Err(format!(
            "componentType {} ({norm}{comp:?}) is not valid for {} (expected {})",
            comp.as_gl_enum(),
            usage.name(),
            usage.expected()
        ));
    }
    Ok((comp, ty.multiplicity()))
}

/// Rejects absurd element counts before anything is allocated for them.
fn check_count(acc: &json::Accessor) -> Res<()> {
    if acc.count.0 > MAX_ELEMENTS {
        return Err(format!("count {} exceeds the limit of {MAX_ELEMENTS} elements", acc.count.0));
    }
    Ok(())
}

/// A validated strided view of `count` elements: element i is `bytes[i*stride .. i*stride+elem]`.
struct Layout<'b> {
    bytes: &'b [u8],
    stride: usize,
    elem: usize,
}

impl Layout<'_> {
    fn element(&self, i: usize) -> &[u8] {
        &self.bytes[i * self.stride..i * self.stride + self.elem]
    }
}

pub(super) fn to_f32(b: &[u8], comp: ComponentType, normalized: bool) -> f32 {
    use ComponentType::*;
    let (value, scale) = match comp {
        F32 => return f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        U8 => (b[0] as f32, 255.0),
        I8 => (b[0] as i8 as f32, 127.0),
        U16 => (u16::from_le_bytes([b[0], b[1]]) as f32, 65535.0),
        I16 => (i16::from_le_bytes([b[0], b[1]]) as f32, 32767.0),
        U32 => (u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32, u32::MAX as f32),
    };
    if normalized {
        (value / scale).max(-1.0)
    } else {
        value
    }
}

fn to_u32(b: &[u8], comp: ComponentType, _normalized: bool) -> u32 {
    match comp {
        ComponentType::U8 | ComponentType::I8 => b[0] as u32,
        ComponentType::U16 | ComponentType::I16 => u16::from_le_bytes([b[0], b[1]]) as u32,
        _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    }
}

/// Converts one component (the bytes start at it) of the given type to the output type.
pub(super) type Convert<T> = fn(&[u8], ComponentType, bool) -> T;

impl Loader<'_> {
    pub(super) fn read_vec3(&self, index: usize, usage: Usage, what: &str) -> Res<Vec<Vec3>> {
        let flat = self.read(index, usage, what, to_f32)?;
        Ok(flat.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect())
    }

    /// Whether accessor `index` is implicitly all zeros (neither a bufferView nor sparse values), after checking
    /// its format and count as `read` does (a missing accessor is left for `read` to report).
    pub(super) fn all_zeros(&self, index: usize, usage: Usage, what: &str) -> Res<bool> {
        let Some(acc) = self.root.accessors.get(index) else { return Ok(false) };
        let label = format!("accessor {index} ({} of {what})", usage.name());
        check_format(acc, usage).and_then(|_| check_count(acc)).map_err(|m| format!("{label}: {m}"))?;
        Ok(acc.buffer_view.is_none() && acc.sparse.is_none())
    }

    /// Reads an index accessor and checks every index against the vertex count.
    pub(super) fn read_indices(&self, index: usize, vertex_count: usize, what: &str) -> Res<Vec<u32>> {
        let indices = self.read(index, Usage::Indices, what, to_u32)?;
        if let Some((at, bad)) = indices.iter().enumerate().find(|(_, &i)| i as usize >= vertex_count) {
            return Err(format!(
                "accessor {index} (indices of {what}): index {bad} at position {at} is out of range (the primitive has {vertex_count} vertices)"
            ));
        }
        Ok(indices)
    }

    /// Reads accessor `index` as a flat list of converted components, after validating everything.
    pub(super) fn read<T: Copy + Default>(
        &self,
        index: usize,
        usage: Usage,
        what: &str,
        convert: Convert<T>,
    ) -> Res<Vec<T>> {
        let label = format!("accessor {index} ({} of {what})", usage.name());
        let count_all = self.root.accessors.len();
        let acc = self
            .root
            .accessors
            .get(index)
            .ok_or_else(|| format!("{label} does not exist (the file has {count_all} accessors)"))?;
        self.read_checked(acc, usage, convert).map_err(|m| format!("{label}: {m}"))
    }

    fn read_checked<T: Copy + Default>(&self, acc: &json::Accessor, usage: Usage, convert: Convert<T>) -> Res<Vec<T>> {
        let (comp, n) = check_format(acc, usage)?;
        check_count(acc)?;
        let (count, size) = (acc.count.0 as usize, comp.size());
        let mut out = Vec::new();
        match acc.buffer_view {
            Some(view) => {
                let offset = acc.byte_offset.map_or(0, |o| o.0);
                let layout = self.layout(view.value(), offset, count, size * n)?;
                out.reserve_exact(count * n);
                for i in 0..count {
                    let e = layout.element(i);
                    out.extend((0..n).map(|c| convert(&e[c * size..], comp, acc.normalized)));
                }
            }
            // Without a bufferView the accessor starts as zeros (spec), usually with sparse values on top.
            None => out.resize(count * n, T::default()),
        }
        if let Some(sparse) = &acc.sparse {
            self.apply_sparse(sparse, &mut out, (comp, n, acc.normalized), convert)?;
        }
        Ok(out)
    }

    /// The bytes of buffer view `view` (checked against its buffer) and its byteStride.
    pub(super) fn view(&self, view: usize) -> Res<(&[u8], Option<usize>)> {
        let views = &self.root.buffer_views;
        let v = views
            .get(view)
            .ok_or_else(|| format!("bufferView {view} does not exist (the file has {} bufferViews)", views.len()))?;
        let buffer = v.buffer.value();
        let data = self
            .buffers
            .get(buffer)
            .ok_or_else(|| format!("bufferView {view} names buffer {buffer}, which does not exist"))?;
        let (start, len) = (v.byte_offset.map_or(0, |o| o.0), v.byte_length.0);
        match start.checked_add(len) {
            Some(end) if end <= data.len() as u64 => {
                Ok((&data[start as usize..end as usize], v.byte_stride.map(|s| s.0)))
            }
            _ => Err(format!(
                "bufferView {view} (bytes {start}..{}) extends past the end of buffer {buffer} ({} bytes)",
                start.saturating_add(len),
                data.len()
            )),
        }
    }

    /// Validates that `count` elements of `elem` bytes at `offset` fit in buffer view `view`.
    fn layout(&self, view: usize, offset: u64, count: usize, elem: usize) -> Res<Layout<'_>> {
        let (bytes, stride) = self.view(view)?;
        let stride = stride.unwrap_or(elem);
        if stride < elem {
            return Err(format!("byteStride {stride} is smaller than the element size {elem}"));
        }
        if count == 0 {
            return Ok(Layout { bytes: &[], stride, elem });
        }
        let len = bytes.len() as u64;
        let need =
            (stride as u64).checked_mul(count as u64 - 1).and_then(|x| x.checked_add(elem as u64)?.checked_add(offset));
        match need {
            Some(need) if need <= len => Ok(Layout { bytes: &bytes[offset as usize..need as usize], stride, elem }),
            _ => Err(format!(
                "{count} elements of {elem} bytes (stride {stride}) from byteOffset {offset} do not fit in bufferView {view} ({len} bytes)"
            )),
        }
    }

    /// Overwrites the elements named by a sparse accessor's indices.
    fn apply_sparse<T>(
        &self,
        sparse: &json::accessor::sparse::Sparse,
        out: &mut [T],
        (comp, n, normalized): (ComponentType, usize, bool),
        convert: Convert<T>,
    ) -> Res<()> {
        let count = out.len() / n.max(1);
        let k = sparse.count.0;
        if k > count as u64 {
            return Err(format!("sparse count {k} exceeds the accessor count {count}"));
        }
        let Checked::Valid(IndexComponentType(icomp)) = sparse.indices.component_type else {
            return Err("sparse indices have an invalid componentType".into());
        };
        let (ind, val) = (&sparse.indices, &sparse.values);
        let indices = self
            .layout(ind.buffer_view.value(), ind.byte_offset.0, k as usize, icomp.size())
            .map_err(|m| format!("sparse indices: {m}"))?;
        let values = self
            .layout(val.buffer_view.value(), val.byte_offset.0, k as usize, comp.size() * n)
            .map_err(|m| format!("sparse values: {m}"))?;
        for j in 0..k as usize {
            let i = to_u32(indices.element(j), icomp, false) as usize;
            if i >= count {
                return Err(format!("sparse index {i} (entry {j}) is out of range: the accessor has {count} elements"));
            }
            let e = values.element(j);
            for c in 0..n {
                out[i * n + c] = convert(&e[c * comp.size()..], comp, normalized);
            }
        }
        Ok(())
    }
}

pub(super) fn same_count<T>(values: Vec<T>, n: usize, accessor: usize, semantic: &str, what: &str) -> Res<Vec<T>> {
    if values.len() != n {
        let got = values.len();
        return Err(format!(
            "accessor {accessor} ({semantic} of {what}): count {got} differs from the POSITION count {n}"
        ));
    }
    Ok(values)
}
