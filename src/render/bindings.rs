//! The render pipeline's bindings, declared once: group 0 (the scene's storage buffers) and group 1 (the per-render
//! state). The WGSL declarations (`geometry_bindings.wgsl`, `shading_bindings.wgsl` in `shaders::compose`), the
//! bind-group layouts, the scene's upload and its size check against the device limit all come from these tables;
//! tests/layout.rs checks them against what naga reads in the composed module.

use crate::accel::bvh::GpuBvhNode;
use crate::accel::light_tree::GpuLightNode;
use crate::accel::wide_bvh::GpuWideNode;
use crate::gpu::types::*;
use crate::render::scene_data::SceneData;

/// How a shader reaches a binding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// `var<uniform>`.
    Uniform,
    /// `var<storage, read>`.
    Read,
    /// `var<storage, read_write>`.
    ReadWrite,
}

/// One binding of the render pipeline.
#[derive(Clone, Copy)]
pub struct Binding {
    /// Bind group.
    pub group: u32,
    /// Binding index within the group.
    pub binding: u32,
    /// The WGSL variable.
    pub name: &'static str,
    /// Its WGSL type.
    pub wgsl_type: &'static str,
    /// How the shader reaches it.
    pub access: Access,
    /// Bytes of one element (of the array, or of the uniform struct): the Rust side of the WGSL type.
    pub element_size: usize,
    /// What it holds, for people: error messages name the buffer by it.
    pub label: &'static str,
    /// A comment for the WGSL declaration ("" = none).
    pub note: &'static str,
}

/// A group-0 binding and where its contents are in `SceneData`.
#[derive(Clone, Copy)]
pub struct SceneBinding {
    /// The binding.
    pub binding: Binding,
    /// Its bytes in a flattened scene.
    pub bytes: fn(&SceneData) -> &[u8],
}

const fn scene(
    binding: u32,
    name: &'static str,
    wgsl_type: &'static str,
    element_size: usize,
    label: &'static str,
) -> Binding {
    Binding { group: 0, binding, name, wgsl_type, access: Access::Read, element_size, label, note: "" }
}

/// Bindings 0–4 of group 0, [`WIDE_NODES`] and the [`TRI_VERTS_HI`] bindings are the geometry (what BVH traversal
/// reads; the probe kernels bind these alone).
pub const GEOMETRY_BINDINGS: u32 = 5;
/// The binding (and `SCENE` index) of the wide BVH's nodes, a geometry binding added after the shading ones.
pub const WIDE_NODES: usize = 14;
/// The first of the bindings (and `SCENE` indices) of the vertices beyond the first vertex binding: `tri_verts_hi`,
/// `tri_verts_hi2`, `tri_verts_hi3`, geometry bindings.
pub const TRI_VERTS_HI: usize = 17;
/// How many storage bindings the triangle vertices may take (`tri_verts` and the `TRI_VERTS_HI` ones): a scene's
/// vertices fill 48 bytes per triangle, so on a device whose bindings hold 128 MiB (lavapipe) four bindings take
/// 11.2M triangles, about where the wide BVH's nodes (8–10 bytes per triangle) reach one binding themselves.
pub const VERTEX_BINDINGS: usize = 4;

fn is_geometry(i: usize) -> bool {
    i < GEOMETRY_BINDINGS as usize || i == WIDE_NODES || (TRI_VERTS_HI..TRI_VERTS_HI + VERTEX_BINDINGS - 1).contains(&i)
}

/// The bytes of the k-th part of the vertices beyond the first binding (none where there is no such part).
fn vertex_part(d: &SceneData, k: usize) -> &[u8] {
    d.tri_verts_hi.get(k).map_or(&[], |p| bytemuck::cast_slice(p))
}

/// The geometry bindings of group 0, in binding order.
pub fn geometry() -> impl Iterator<Item = &'static SceneBinding> {
    SCENE.iter().enumerate().filter(|(i, _)| is_geometry(*i)).map(|(_, b)| b)
}

/// The other bindings of group 0 (materials, lights, textures, environment).
pub fn shading() -> impl Iterator<Item = &'static SceneBinding> {
    SCENE.iter().enumerate().filter(|(i, _)| !is_geometry(*i)).map(|(_, b)| b)
}

/// Group 0: the scene, in binding order.
pub const SCENE: [SceneBinding; 20] = [
    SceneBinding {
        binding: scene(0, "bvh_nodes", "array<BvhNode>", size_of::<GpuBvhNode>(), "BVH nodes"),
        bytes: |d| bytemuck::cast_slice(&d.bvh_nodes),
    },
    SceneBinding {
        binding: scene(1, "prim_refs", "array<u32>", 4, "primitive references"),
        bytes: |d| bytemuck::cast_slice(&d.prim_refs),
    },
    SceneBinding {
        binding: scene(2, "tri_verts", "array<vec4<u32>>", 16, "triangle vertices"),
        bytes: |d| bytemuck::cast_slice(&d.tri_verts),
    },
    SceneBinding {
        binding: scene(3, "spheres", "array<Sphere>", size_of::<GpuSphere>(), "spheres"),
        bytes: |d| bytemuck::cast_slice(&d.spheres),
    },
    SceneBinding {
        binding: scene(4, "quads", "array<Quad>", size_of::<GpuQuad>(), "quads"),
        bytes: |d| bytemuck::cast_slice(&d.quads),
    },
    SceneBinding {
        binding: scene(5, "tri_lights", "array<u32>", 4, "triangle lights"),
        bytes: |d| bytemuck::cast_slice(&d.tri_lights),
    },
    SceneBinding {
        binding: scene(6, "materials", "array<Material>", size_of::<GpuMaterial>(), "materials"),
        bytes: |d| bytemuck::cast_slice(&d.materials),
    },
    SceneBinding {
        binding: scene(7, "lights", "array<Light>", size_of::<GpuLight>(), "lights"),
        bytes: |d| bytemuck::cast_slice(&d.lights),
    },
    SceneBinding {
        binding: scene(8, "light_alias", "array<AliasEntry>", size_of::<GpuAliasEntry>(), "light alias table"),
        bytes: |d| bytemuck::cast_slice(&d.light_alias),
    },
    SceneBinding {
        binding: scene(9, "tex_info", "array<TextureInfo>", size_of::<GpuTextureInfo>(), "texture table"),
        bytes: |d| bytemuck::cast_slice(&d.tex_info),
    },
    SceneBinding {
        binding: scene(10, "tex_texels", "array<u32>", 4, "texels"),
        bytes: |d| bytemuck::cast_slice(&d.tex_texels),
    },
    SceneBinding {
        binding: Binding {
            note: "Environment texels: rgb radiance (unscaled) and, in w, the texel's sampling density in (u, v).",
            ..scene(11, "env_texels", "array<vec4<f32>>", 16, "environment texels")
        },
        bytes: |d| bytemuck::cast_slice(&d.env_texels),
    },
    SceneBinding {
        binding: scene(12, "env_alias", "array<AliasEntry>", size_of::<GpuAliasEntry>(), "environment alias table"),
        bytes: |d| bytemuck::cast_slice(&d.env_alias),
    },
    SceneBinding {
        binding: scene(13, "light_tree", "array<LightNode>", size_of::<GpuLightNode>(), "light tree"),
        bytes: |d| bytemuck::cast_slice(&d.light_tree),
    },
    SceneBinding {
        binding: Binding {
            note: "8-wide compressed BVH nodes (src/accel/wide_bvh.rs); one zero node where the scene uses bvh_nodes.",
            ..scene(14, "wide_nodes", "array<WideNode>", size_of::<GpuWideNode>(), "wide BVH nodes")
        },
        bytes: |d| bytemuck::cast_slice(&d.wide_nodes),
    },
    SceneBinding {
        binding: Binding {
            note: "Per shading vertex (normal, material word) and, where the scene has textures, its uv's bits \
                   (SceneData::shading_records).",
            ..scene(15, "shading_verts", "array<vec2<u32>>", 8, "shading vertex records")
        },
        bytes: |d| bytemuck::cast_slice(&d.shading_records),
    },
    SceneBinding {
        binding: Binding {
            note: "Texels of the textures whose offset has TEXEL_HI set, where the texels exceed one binding.",
            ..scene(16, "tex_texels_hi", "array<u32>", 4, "texels beyond the first binding")
        },
        bytes: |d| bytemuck::cast_slice(&d.tex_texels_hi),
    },
    SceneBinding {
        binding: Binding {
            note: "Vertices beyond tri_verts when they exceed one binding (src/render/gpu_scene.rs split_vertices); \
                   one zero vertex otherwise.",
            ..scene(17, "tri_verts_hi", "array<vec4<u32>>", 16, "triangle vertices beyond the first binding")
        },
        bytes: |d| vertex_part(d, 0),
    },
    SceneBinding {
        binding: Binding {
            note: "Vertices beyond tri_verts_hi when they exceed two bindings; one zero vertex otherwise.",
            ..scene(18, "tri_verts_hi2", "array<vec4<u32>>", 16, "triangle vertices beyond the second binding")
        },
        bytes: |d| vertex_part(d, 1),
    },
    SceneBinding {
        binding: Binding {
            note: "Vertices beyond tri_verts_hi2 when they exceed three bindings; one zero vertex otherwise.",
            ..scene(19, "tri_verts_hi3", "array<vec4<u32>>", 16, "triangle vertices beyond the third binding")
        },
        bytes: |d| vertex_part(d, 2),
    },
];

/// Group 1: the per-render state, in binding order.
pub const FRAME: [Binding; 6] = [
    Binding {
        group: 1,
        binding: 0,
        name: "params",
        wgsl_type: "FrameParams",
        access: Access::Uniform,
        element_size: size_of::<GpuFrameParams>(),
        label: "frame parameters",
        note: "",
    },
    Binding {
        group: 1,
        binding: 1,
        name: "accum",
        wgsl_type: "array<Accum>",
        access: Access::ReadWrite,
        element_size: size_of::<GpuAccum>(),
        label: "accumulation",
        note: "",
    },
    Binding {
        group: 1,
        binding: 2,
        name: "counters",
        wgsl_type: "array<atomic<u32>>",
        access: Access::ReadWrite,
        element_size: 4,
        label: "counters",
        note: "counters[0]: non-finite samples; counters[1]: rays traced (both read and cleared by the host after \
               each submission, which sums them in 64 bits).",
    },
    Binding {
        group: 1,
        binding: 3,
        name: "sampler_data",
        wgsl_type: "array<u32>",
        access: Access::Read,
        element_size: 4,
        label: "sampler tables",
        note:
            "The samplers' constant tables (src/render/samplers.rs `sampler_data`: Sobol matrices, primes, blue-noise mask).",
    },
    Binding {
        group: 1,
        binding: 4,
        name: "guide_cdf",
        wgsl_type: "array<f32>",
        access: Access::Read,
        element_size: 4,
        label: "environment guide",
        note: "The environment guide: per slot, the CDF over its direction bins (src/render/env_guide.rs).",
    },
    Binding {
        group: 1,
        binding: 5,
        name: "guide_counts",
        wgsl_type: "array<atomic<u32>>",
        access: Access::ReadWrite,
        element_size: 4,
        label: "environment guide counts",
        note: "What the guide's training dispatch counts: unblocked sky directions per slot and bin.",
    },
];

/// Every binding of the render pipeline.
pub fn all() -> impl Iterator<Item = Binding> {
    SCENE.iter().map(|s| s.binding).chain(FRAME)
}

/// The bindings a device with 64-bit integers reads 32 bytes a load, as `array<vec4<u64>>` (src/render/shaders.rs
/// `for_device`, shaders/*_int64.wgsl), with the file whose accessors read each (grouped by file): their buffers are
/// padded to whole 32-byte elements ([`pad_for_32_byte_reads`]).
pub const READ_32_BYTES_AT_A_TIME: [(&str, &str); 3] = [
    ("tri_verts", "geometry_loads.wgsl"),
    ("wide_nodes", "geometry_loads.wgsl"),
    ("light_tree", "light_tree_loads.wgsl"),
];

/// The WGSL type of the bindings in [`READ_32_BYTES_AT_A_TIME`] on a device with 64-bit integers.
pub const WGSL_32_BYTE_ELEMENTS: &str = "array<vec4<u64>>";

/// `bytes` of binding `name` as uploaded: zero-padded to whole 32-byte elements (at least one) where the binding is in
/// [`READ_32_BYTES_AT_A_TIME`] (the last triangle or node may end in the middle of one), unchanged otherwise
/// (elsewhere a padding word could be read: `tri_lights` is read with a clamped index).
pub fn pad_for_32_byte_reads<'a>(name: &str, bytes: &'a [u8]) -> std::borrow::Cow<'a, [u8]> {
    let padded = bytes.len().next_multiple_of(32).max(32);
    if READ_32_BYTES_AT_A_TIME.iter().any(|(n, _)| *n == name) && bytes.len() != padded {
        let mut v = bytes.to_vec();
        v.resize(padded, 0);
        v.into()
    } else {
        bytes.into()
    }
}

/// The WGSL declaration of `b`, with its note as a comment above it.
pub fn wgsl_declaration(b: &Binding) -> String {
    let var = match b.access {
        Access::Uniform => "var<uniform>",
        Access::Read => "var<storage, read>",
        Access::ReadWrite => "var<storage, read_write>",
    };
    let note = if b.note.is_empty() { String::new() } else { format!("// {}\n", b.note) };
    format!("{note}@group({}) @binding({}) {var} {}: {};\n", b.group, b.binding, b.name, b.wgsl_type)
}

/// The element type of an `array<T>` binding.
pub fn element_type(b: &Binding) -> &'static str {
    b.wgsl_type.strip_prefix("array<").and_then(|t| t.strip_suffix('>')).unwrap_or(b.wgsl_type)
}

/// How shaders read scene binding `b`: `load_<name>(i)` (element i) and `len_<name>()` (its element count), never
/// the binding itself, so the same code runs on the packed layout (`render::packed_scene`), where these read the
/// one buffer that holds every table.
pub fn scene_accessors(b: &Binding) -> String {
    let (name, ty) = (b.name, element_type(b));
    format!(
        "fn load_{name}(i: u32) -> {ty} {{ return {name}[i]; }}\nfn len_{name}() -> u32 {{ return arrayLength(&{name}); }}\n"
    )
}

/// `geometry_bindings.wgsl`: the geometry bindings (group 0: 0–4, 14 and 17), for BVH traversal.
pub fn geometry_wgsl() -> String {
    let mut s =
        String::from("// geometry_bindings.wgsl — generated from src/render/bindings.rs: the scene's geometry.\n\n");
    for b in geometry() {
        s += &wgsl_declaration(&b.binding);
        s += &scene_accessors(&b.binding);
    }
    s
}

/// `shading_bindings.wgsl`: the rest of group 0 (materials, lights, textures, environment) and group 1.
pub fn shading_wgsl() -> String {
    let mut s = String::from(
        "// shading_bindings.wgsl — generated from src/render/bindings.rs: materials, lights, textures, environment\n\
         // (group 0) and the per-render state (group 1).\n\n",
    );
    for b in shading() {
        s += &wgsl_declaration(&b.binding);
        s += &scene_accessors(&b.binding);
    }
    s += "\n";
    for b in &FRAME {
        s += &wgsl_declaration(b);
    }
    s += "\n/// Rays traced by this invocation (summed into counters[1] once per invocation).\nvar<private> rays_traced: u32;\n";
    s
}

/// The bind-group layout entry of `b` (compute stage).
pub fn layout_entry(b: &Binding) -> wgpu::BindGroupLayoutEntry {
    let ty = match b.access {
        Access::Uniform => wgpu::BufferBindingType::Uniform,
        Access::Read => wgpu::BufferBindingType::Storage { read_only: true },
        Access::ReadWrite => wgpu::BufferBindingType::Storage { read_only: false },
    };
    let min_binding_size = match b.access {
        Access::Uniform => wgpu::BufferSize::new(b.element_size as u64),
        _ => None,
    };
    wgpu::BindGroupLayoutEntry {
        binding: b.binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size },
        count: None,
    }
}
