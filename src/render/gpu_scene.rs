//! GpuScene: a scene's flattened tables (`SceneData`) uploaded as the storage buffers of the binding table,
//! with size checks against the device's limits.

use crate::gpu::types::TEXEL_HI;
use crate::gpu::{GpuContext, GpuError};
use crate::render::bindings;
use crate::render::packed_scene::{self, SceneLayout};
use crate::render::scene_data::SceneData;

/// The scene's buffers on a device, bound as group 0 of the render pipeline.
pub struct GpuScene {
    /// The CPU copy (statistics, light counts, environment parameters).
    pub data: SceneData,
    /// How the tables are bound: separate buffers, or one packed buffer where the device binds too few.
    pub layout: SceneLayout,
    /// Group-0 buffers in binding order (`bindings::SCENE`), or the one packed buffer.
    pub buffers: Vec<wgpu::Buffer>,
}

/// Bytes of each group-0 buffer of `data`, in binding order (`bindings::SCENE`).
pub fn binding_sizes(data: &SceneData) -> [u64; bindings::SCENE.len()] {
    bindings::SCENE.map(|b| (b.bytes)(data).len() as u64)
}

/// Device memory per triangle (bytes) of what scales with the triangles, as `mislab info` reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleMemory {
    /// BVH: nodes (binary and 8-wide) and primitive references.
    pub bvh: f64,
    /// Vertices (carrying each corner's shading-vertex record index).
    pub geometry: f64,
    /// The triangles' lights (where some emit) and the shared shading-vertex records.
    pub shading: f64,
}

impl TriangleMemory {
    pub fn total(&self) -> f64 {
        self.bvh + self.geometry + self.shading
    }
}

/// [`TriangleMemory`] of a scene (counts with one triangle where it has none).
pub fn memory_per_triangle(data: &SceneData) -> TriangleMemory {
    let sizes = binding_sizes(data);
    let size = |names: &[&str]| -> f64 {
        let table = bindings::SCENE.iter().zip(sizes);
        table.filter(|(b, _)| names.contains(&b.binding.name)).map(|(_, s)| s).sum::<u64>() as f64
    };
    let tris = data.triangles.max(1) as f64;
    TriangleMemory {
        bvh: size(&["bvh_nodes", "prim_refs", "wide_nodes"]) / tris,
        geometry: size(&["tri_verts", "tri_verts_hi", "tri_verts_hi2", "tri_verts_hi3"]) / tris,
        shading: size(&["tri_lights", "shading_verts"]) / tris,
    }
}

/// Checks every group-0 buffer against a device's storage-buffer binding limit (bytes). The error names the
/// buffer, its size and the limit, so that the user knows what to shrink.
pub fn check_binding_sizes(data: &SceneData, limit: u64) -> Result<(), GpuError> {
    for (b, bytes) in bindings::SCENE.iter().zip(binding_sizes(data)) {
        if bytes > limit {
            return Err(GpuError::SceneTooLarge { buffer: b.binding.label, bytes, limit });
        }
    }
    Ok(())
}

/// Texels beyond one storage binding of `limit` bytes move to the second texel binding (`tex_texels_hi`), split at
/// a texture boundary: the first texture that does not end within the limit and every later one go there, their
/// offsets counted from its start and marked `TEXEL_HI` (so `Features::texel_split` compiles the second read
/// in). Texels that fit are left as they are. Past two bindings: `GpuError::TexelsTooLarge`.
pub fn split_texels(data: &mut SceneData, limit: u64) -> Result<(), GpuError> {
    let words = data.tex_texels.len() as u64;
    if 4 * words <= limit || !data.tex_texels_hi.is_empty() {
        return Ok(());
    }
    // Textures lie in offset order (scene_data::build_textures); each ends where the next begins.
    let ends: Vec<u64> = data.tex_info.iter().skip(1).map(|t| t.offset as u64).chain([words]).collect();
    let first = ends.iter().position(|&e| 4 * e > limit).unwrap_or(data.tex_info.len());
    let cut = data.tex_info.get(first).map_or(words, |t| t.offset as u64);
    let second = 4 * (words - cut);
    if second > limit || words >= TEXEL_HI as u64 {
        return Err(GpuError::TexelsTooLarge { bytes: 4 * words, second, limit });
    }
    data.tex_texels_hi = data.tex_texels.split_off(cut as usize);
    for t in &mut data.tex_info[first..] {
        t.offset = (t.offset - cut as u32) | TEXEL_HI;
    }
    Ok(())
}

/// Vertices beyond one storage binding of `limit` bytes move to the further vertex bindings (`tri_verts_hi`,
/// `tri_verts_hi2`, `tri_verts_hi3`), each filled with whole triangles before the next; the shader reads vertex k from
/// the part its index falls in (and `Features::geometry_split` compiles those reads in). Past
/// `bindings::VERTEX_BINDINGS` bindings: `GpuError::VerticesTooLarge`.
pub fn split_vertices(data: &mut SceneData, limit: u64) -> Result<(), GpuError> {
    if 16 * data.tri_verts.len() as u64 <= limit || !data.tri_verts_hi.is_empty() {
        return Ok(());
    }
    let bytes = 16 * data.tri_verts.len() as u64;
    // Whole triangles, and an even number of vertices: a device with 64-bit integers reads two vertices a load
    // (shaders/geometry_loads_int64.wgsl), so the first binding must end at the end of one of its elements.
    let per_binding = 6 * (limit / 96) as usize;
    let needed = if per_binding == 0 { usize::MAX } else { data.tri_verts.len().div_ceil(per_binding) };
    if needed > bindings::VERTEX_BINDINGS {
        return Err(GpuError::VerticesTooLarge { bytes, bindings: bindings::VERTEX_BINDINGS, limit });
    }
    let rest = data.tri_verts.split_off(per_binding);
    data.tri_verts_hi = rest.chunks(per_binding).map(<[[f32; 4]]>::to_vec).collect();
    Ok(())
}

/// Fits a flattened scene to a device's storage-binding limit as the upload does: texels and vertices past one
/// binding take a second (`split_texels`, `split_vertices`); any buffer still over the limit is an error.
pub fn fit_to_binding_limit(data: &mut SceneData, limit: u64) -> Result<(), GpuError> {
    split_texels(data, limit)?;
    split_vertices(data, limit)?;
    check_binding_sizes(data, limit)
}

impl GpuScene {
    /// Uploads a flattened scene, refusing (with the buffer, its size and the limit named) anything
    /// larger than the device's storage-buffer binding limit; texels may take two bindings, vertices four
    /// (`split_texels`, `split_vertices`). On a device that binds fewer storage buffers per shader stage than the
    /// scene and the frame together (WebGPU's guaranteed 8), the tables are packed into one buffer.
    pub fn upload(ctx: &GpuContext, data: SceneData) -> Result<GpuScene, GpuError> {
        if (ctx.limits().max_storage_buffers_per_shader_stage as usize) < storage_bindings_needed() {
            return Self::upload_packed(ctx, data);
        }
        Self::upload_with_limit(ctx, data, u64::MAX)
    }

    /// `upload` as if the device's binding limit were `limit` bytes (when lower than the real one): tests take
    /// the split path with small scenes through it.
    pub fn upload_with_limit(ctx: &GpuContext, mut data: SceneData, limit: u64) -> Result<GpuScene, GpuError> {
        let limit = limit.min(ctx.max_storage_binding());
        fit_to_binding_limit(&mut data, limit)?;
        let buffers = bindings::SCENE
            .iter()
            .map(|b| {
                let bytes = bindings::pad_for_32_byte_reads(b.binding.name, (b.bytes)(&data));
                ctx.storage_buffer_bytes(b.binding.name, &bytes, b.binding.element_size)
            })
            .collect();
        Ok(GpuScene { data, layout: SceneLayout::Separate, buffers })
    }

    /// Uploads with every table in one buffer (`packed_scene`), whatever the device offers: the web's layout, which
    /// tests check natively against the separate one.
    pub fn upload_packed(ctx: &GpuContext, data: SceneData) -> Result<GpuScene, GpuError> {
        let words = packed_scene::pack(&data);
        let (bytes, limit) = (4 * words.len() as u64, ctx.max_storage_binding());
        if bytes > limit {
            return Err(GpuError::SceneTooLarge { buffer: packed_scene::PACKED.label, bytes, limit });
        }
        let buffer = ctx.storage_buffer("scene_words", &words, wgpu::BufferUsages::empty());
        Ok(GpuScene { data, layout: SceneLayout::Packed, buffers: vec![buffer] })
    }

    /// The bindings of group 0 for this layout.
    pub fn bindings(&self) -> Vec<&'static bindings::Binding> {
        Self::bindings_of(self.layout)
    }

    /// The bindings of group 0 for `layout`.
    pub fn bindings_of(layout: SceneLayout) -> Vec<&'static bindings::Binding> {
        match layout {
            SceneLayout::Separate => bindings::SCENE.iter().map(|b| &b.binding).collect(),
            SceneLayout::Packed => vec![&packed_scene::PACKED],
        }
    }

    /// Group 0's bind-group layout entries for `layout`.
    pub fn layout_entries_of(layout: SceneLayout) -> Vec<wgpu::BindGroupLayoutEntry> {
        Self::bindings_of(layout).into_iter().map(bindings::layout_entry).collect()
    }

    /// Group 0's bind-group entries: the buffers at their bindings.
    pub fn bind_group_entries(&self) -> Vec<wgpu::BindGroupEntry<'_>> {
        let bindings = self.bindings().into_iter().map(|b| b.binding);
        bindings
            .zip(&self.buffers)
            .map(|(binding, b)| wgpu::BindGroupEntry { binding, resource: b.as_entire_binding() })
            .collect()
    }
}

/// Storage buffers one render kernel binds on the separate layout: the scene's and the frame's.
pub fn storage_bindings_needed() -> usize {
    let frame = bindings::FRAME.iter().filter(|b| b.access != bindings::Access::Uniform).count();
    bindings::SCENE.len() + frame
}
