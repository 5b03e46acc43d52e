//! SceneData: the scene flattened, on the CPU, into the tables the shaders read (geometry + BVH, shading
//! data, light table, textures, environment distribution); `gpu_scene` uploads them.

use crate::accel::bvh;
use crate::accel::light_tree::GpuLightNode;
use crate::gpu::types::*;
use crate::render::shading_data::{material_word, word_material, ShadingTable};
use crate::scene::{Scene, TextureRef, Wrap};
use glam::{Vec2, Vec3};

mod light_table;

/// Largest primitive count rendered without a BVH (`Features::flat`, `render::baked`).
pub const FLAT_MAX_PRIMS: usize = 32;
/// `tri_lights` of a scene where no triangle emits. Four words, not one: a storage buffer is at least 16 bytes
/// (`GpuContext::storage_buffer_bytes` pads with zeros), and the shader clamps its index to the buffer's length, so
/// every word the shader can reach must say INVALID (a zero padding word would read as light 0).
pub const NO_TRI_LIGHTS: [u32; 4] = [INVALID; 4];

/// `prim_refs` of a scene whose leaf order is its triangle order (a triangle-only scene: `into_leaf_order` makes
/// `prim_refs[j] == j`). The identity is not uploaded (4 bytes per triangle); the shader reads any INVALID word as
/// "entry j is triangle j" (shaders/bvh.wgsl `bvh_leaf_test`), and the specialised triangle-only pipelines do not
/// read `prim_refs` at all.
pub const IDENTITY_PRIM_REFS: [u32; 4] = [INVALID; 4];

/// CPU-side arrays exactly as uploaded, plus statistics. Built without a device so tests can inspect it.
#[derive(Clone, Debug, Default)]
pub struct SceneData {
    /// Three vec4 per triangle: a vertex position in xyz and, in w, the bits of that corner's shading-vertex index
    /// (`tri_shading[i].corners[k]`; `pack_triangle_records`), so triangles need no separate index record.
    pub tri_verts: Vec<[f32; 4]>,
    /// Vertices moved out of `tri_verts` because they exceed one binding (`gpu_scene::split_vertices`): one part per
    /// further vertex binding, at most `bindings::VERTEX_BINDINGS` − 1, each a whole number of triangles; empty
    /// unless split.
    pub tri_verts_hi: Vec<Vec<[f32; 4]>>,
    /// Triangles in the scene. The per-triangle arrays hold one copy per BVH reference (a pre-split triangle,
    /// `crate::accel::presplit`, is in several leaves), so they can be longer.
    pub triangles: usize,
    /// Per-triangle shading data: shading-vertex indices and light (src/render/shading_data.rs). The CPU's view:
    /// it is uploaded as the w of `tri_verts` and as `tri_lights`.
    pub tri_shading: Vec<GpuTriShading>,
    /// Each triangle's light (index in the light table, or INVALID), or `NO_TRI_LIGHTS` when no triangle emits: 4
    /// bytes per triangle only in scenes with emissive triangles.
    pub tri_lights: Vec<u32>,
    /// Distinct shading vertices (normal, material, uv), indexed by `tri_shading`. In a scene without textures
    /// nothing reads a uv, so every uv is zero (more vertices are shared) and none is uploaded.
    pub shading_verts: Vec<GpuShadingVertex>,
    /// The upload form of `shading_verts` (`pack_triangle_records`): per vertex one record (normal, material
    /// word) and, where the scene has textures, a second one with its uv's bits; a triangle corner's w holds the
    /// index of its vertex's first record. 8 bytes per vertex in a scene without textures, 16 with.
    pub shading_records: Vec<[u32; 2]>,
    /// Spheres.
    pub spheres: Vec<GpuSphere>,
    /// Quads.
    pub quads: Vec<GpuQuad>,
    /// Materials.
    pub materials: Vec<GpuMaterial>,
    /// Light table: the lights that selection chooses among, then the `lamp_faces` faces of the convex lamps
    /// (`accel::convex_lamps`), which rays find but only their lamps are chosen.
    pub lights: Vec<GpuLight>,
    /// How many entries at the end of `lights` are convex lamps' faces.
    pub lamp_faces: usize,
    /// Alias table for power-proportional light selection.
    pub light_alias: Vec<GpuAliasEntry>,
    /// The light tree over the lights with a position (`--light-select tree`), depth-first; empty if none.
    pub light_tree: Vec<GpuLightNode>,
    /// Texture table.
    pub tex_info: Vec<GpuTextureInfo>,
    /// All texels, RGBA8 packed.
    pub tex_texels: Vec<u32>,
    /// Texels moved out of `tex_texels` because they exceed one binding (`gpu_scene::split_texels`); empty
    /// unless split.
    pub tex_texels_hi: Vec<u32>,
    /// Environment texels (rgb + density), empty for none/constant.
    pub env_texels: Vec<[f32; 4]>,
    /// Environment alias table.
    pub env_alias: Vec<GpuAliasEntry>,
    /// Environment width/height (0 for none/constant).
    pub env_size: (u32, u32),
    /// Constant environment radiance (when no map).
    pub env_constant: [f32; 3],
    /// Map scale / rotation.
    pub env_scale: f32,
    /// Rotation about +Y, radians.
    pub env_rotation: f32,
    /// Index of the environment in the light table.
    pub env_light: Option<u32>,
    /// BVH nodes.
    pub bvh_nodes: Vec<bvh::GpuBvhNode>,
    /// BVH primitive references.
    pub prim_refs: Vec<u32>,
    /// The 8-wide compressed BVH's nodes; empty where the scene uses the BVH2 (`bvh_nodes`). When not empty,
    /// `bvh_nodes` is one empty root and `prim_refs` follow the wide tree's leaves.
    pub wide_nodes: Vec<crate::accel::wide_bvh::GpuWideNode>,
    /// BVH build time, seconds (or the time to read it back from `render::bvh_store`).
    pub bvh_seconds: f64,
    /// BVH SAH cost.
    pub bvh_sah: f32,
    /// Number of delta lights (reachable by light sampling only).
    pub delta_lights: u32,
    /// World position of the render origin: every position above is relative to it (see `render_origin`).
    pub origin: Vec3,
    /// Triangles outside the BVH, baked into the scene's pipeline as literals (`occluder_split`): `count` slots of
    /// the per-triangle arrays from `first`, after the BVH's triangles. (0, 0) where the BVH holds every primitive.
    pub occluders: (u32, u32),
    /// Whether this scene's own pipelines test its wide BVH's root children against their exact boxes as literals
    /// (`baked::baked_root`). A choice, kept here with the scene it was made for: `BuildOptions::baked_root`.
    pub baked_root: bool,
    /// Largest |coordinate| of the geometry around `origin`, clamped to [1e-30, 1]: the length scale of
    /// ray-origin offsets near the origin (`FrameParams::offset_scale`).
    pub offset_scale: f32,
}

/// Beyond this distance of the camera from the world origin, scenes are rendered relative to the camera.
pub const RECENTER_DISTANCE: f32 = 1024.0;

/// Where positions are measured from on the device. f32 positions 1e5 from the origin are 2^-7 apart, and
/// ray-origin offsets (256 ULPs) grow to 2 units there, jumping through the walls of a 2-unit Cornell box.
/// Subtracting the camera position (exact for f32 values within a factor 2 of each other, Sterbenz) keeps
/// what the camera sees at small magnitudes. Scenes near the origin keep world coordinates unchanged.
pub fn render_origin(scene: &Scene) -> Vec3 {
    let c = scene.camera.position;
    if c.is_finite() && c.abs().max_element() > RECENTER_DISTANCE {
        c
    } else {
        Vec3::ZERO
    }
}

impl SceneData {
    /// Flattens a scene. Pure CPU work; `GpuScene::upload` sends it to a device. Convex lamps are made unless the
    /// scene keeps its emitter triangles.
    pub fn build(scene: &Scene) -> SceneData {
        SceneData::build_with(scene, !scene.emitter_triangles_kept)
    }

    /// `build`, making convex lamps of the emitter meshes that qualify (`accel::convex_lamps`) or keeping every
    /// emissive triangle a light of its own.
    pub fn build_with(scene: &Scene, convex_lamps: bool) -> SceneData {
        SceneData::build_options(scene, BuildOptions { convex_lamps, baked_occluders: true, baked_root: true })
    }

    /// `build` with each choice given (tests and A/B runs compare them on one scene).
    pub fn build_options(scene: &Scene, options: BuildOptions) -> SceneData {
        let convex_lamps = options.convex_lamps;
        let mut d = SceneData { origin: render_origin(scene), baked_root: options.baked_root, ..SceneData::default() };
        let o = d.origin;
        d.materials = scene.materials.iter().map(gpu_material).collect();
        if d.materials.is_empty() {
            d.materials.push(gpu_material(&Default::default()));
        }
        let mat_index = |m: u32| if (m as usize) < d.materials.len() { m } else { 0 };
        // A cut-out mask is read per triangle during traversal (shaders/alpha.wgsl): 0 = none, else texture + 1.
        let alpha_of = |m: u32| {
            let t = scene.materials.get(m as usize).and_then(|m| m.alpha_texture);
            t.filter(|&t| (t as usize) < scene.textures.len()).map_or(0, |t| t + 1)
        };
        let mut tris: Vec<[Vec3; 3]> = Vec::with_capacity(scene.triangle_count());
        let mut shading = ShadingTable::default();
        // Only textures read uvs (shaders/surface.wgsl): without any, uvs are dropped (SceneData::shading_records).
        let keep_uvs = !scene.textures.is_empty();
        for mesh in &scene.meshes {
            let word = material_word(mat_index(mesh.material), alpha_of(mesh.material));
            // Each mesh vertex's shading vertex, encoded once (INVALID: not yet).
            let mut shared = vec![INVALID; mesh.positions.len()];
            for t in &mesh.indices {
                let p = t.map(|i| mesh.positions[i as usize] - o);
                tris.push(p);
                for v in p {
                    d.tri_verts.push([v.x, v.y, v.z, 0.0]);
                }
                let corners = t.map(|i| {
                    let i = i as usize;
                    if shared[i] == INVALID {
                        let n = mesh.normals.get(i).copied().unwrap_or(Vec3::ZERO);
                        let uv = if keep_uvs { mesh.uvs.get(i).copied().unwrap_or_default() } else { Vec2::ZERO };
                        shared[i] = shading.vertex(n, uv, word);
                    }
                    shared[i]
                });
                shading.triangle(corners);
            }
        }
        d.tri_shading = shading.tris;
        d.shading_verts = shading.verts;
        d.spheres = scene
            .spheres
            .iter()
            .map(|s| GpuSphere {
                center: (s.center - o).into(),
                radius: s.radius,
                material: mat_index(s.material),
                light: INVALID,
                ..Default::default()
            })
            .collect();
        d.quads = scene
            .quads
            .iter()
            .map(|q| GpuQuad {
                corner: (q.corner - o).into(),
                edge_u: q.edge_u.into(),
                edge_v: q.edge_v.into(),
                material: mat_index(q.material),
                light: INVALID,
                ..Default::default()
            })
            .collect();
        let mut extent = 0.0f32;
        for v in tris.iter().flatten() {
            extent = extent.max(v.abs().max_element());
        }
        for s in &scene.spheres {
            extent = extent.max((s.center - o).abs().max_element() + s.radius);
        }
        for q in &scene.quads {
            let c = q.corner - o;
            for p in [c, c + q.edge_u, c + q.edge_v, c + q.edge_u + q.edge_v] {
                extent = extent.max(p.abs().max_element());
            }
        }
        d.offset_scale = if extent.is_finite() && extent > 0.0 { extent.clamp(1e-30, 1.0) } else { 1.0 };
        // Large triangles in pieces, except in scenes small enough to render without a BVH (one copy of each
        // triangle) and emitters (a shadow ray towards one skips it by its index).
        let emits = |i: usize| d.materials[d.tri_material(i) as usize].emission.iter().any(|&c| c > 0.0);
        let keep_whole: Vec<bool> = (0..tris.len()).map(emits).collect();
        let presplit = if tris.len() + d.spheres.len() + d.quads.len() > FLAT_MAX_PRIMS {
            bvh::Presplit::Large { keep_whole: &keep_whole }
        } else {
            bvh::Presplit::Off
        };
        // A few occluders among many emitter triangles: the occluders are baked into the scene's pipeline and the
        // BVH holds the emitters alone (`occluder_split`).
        let any_alpha = scene.materials.iter().any(|m| m.alpha_texture.is_some());
        let split = occluder_split(&keep_whole, d.spheres.len() + d.quads.len(), any_alpha, options.baked_occluders);
        let in_bvh: Vec<usize> = match &split {
            Some(occluders) => (0..tris.len()).filter(|i| !occluders.contains(i)).collect(),
            None => (0..tris.len()).collect(),
        };
        // The BVH's triangles: all of them unless some are baked occluders.
        let bvh_tris: std::borrow::Cow<[[Vec3; 3]]> = match &split {
            Some(_) => in_bvh.iter().map(|&i| tris[i]).collect::<Vec<_>>().into(),
            None => tris.as_slice().into(),
        };
        let presplit = if split.is_some() { bvh::Presplit::Off } else { presplit };
        // Built, or read back from an earlier run's build of the same input (`bvh_store`).
        let mut bvh = crate::render::bvh_store::build(&bvh_tris, &d.spheres, &d.quads, presplit);
        // Triangles in leaf order: traversal reads a triangle-only leaf's vertices without prim_refs. The baked
        // occluders follow the BVH's triangles.
        d.triangles = tris.len();
        let mut order: Vec<u32> =
            bvh::into_leaf_order(&mut bvh, bvh_tris.len()).into_iter().map(|j| in_bvh[j as usize] as u32).collect();
        drop(bvh_tris);
        if let Some(occluders) = &split {
            d.occluders = (order.len() as u32, occluders.len() as u32);
            order.extend(occluders.iter().map(|&i| i as u32));
        }
        tris = order.iter().map(|&i| tris[i as usize]).collect();
        let mut verts = Vec::with_capacity(3 * order.len());
        for &i in &order {
            verts.extend_from_slice(&d.tri_verts[3 * i as usize..3 * i as usize + 3]);
        }
        d.tri_verts = verts;
        d.tri_shading = order.iter().map(|&i| d.tri_shading[i as usize]).collect();
        d.bvh_seconds = bvh.build_seconds;
        d.bvh_sah = bvh.sah_cost;
        d.bvh_nodes = bvh.nodes;
        let identity = bvh.prim_refs.iter().enumerate().all(|(j, &r)| r == make_prim(PRIM_TRIANGLE, j as u32));
        d.prim_refs = if identity && !bvh.prim_refs.is_empty() { IDENTITY_PRIM_REFS.to_vec() } else { bvh.prim_refs };
        d.wide_nodes = bvh.wide;
        build_textures(scene, &mut d);
        light_table::build_lights(scene, &tris, &mut d, convex_lamps);
        d.pack_triangle_records();
        d
    }

    /// Writes `tri_shading` and `shading_verts` into the upload form: the shading vertices as `shading_records`
    /// (a second record with the uv only where the scene has textures, the predicate of `Features::textures`,
    /// which is what makes shaders/scene_data.wgsl read it), corner k's first record index into the w of vertex k
    /// of the triangle (a vertex is a vec4 for alignment, so this costs nothing), the lights into `tri_lights`.
    /// Shading a hit then reads the index with the positions it already loads.
    pub fn pack_triangle_records(&mut self) {
        let stride = self.shading_record_stride();
        self.shading_records = self
            .shading_verts
            .iter()
            .flat_map(|v| [[v.normal, v.material], v.uv.map(f32::to_bits)].into_iter().take(stride as usize))
            .collect();
        if stride == 1 {
            // The generic pipeline (HAS_TEXTURES) reads the record after a vertex's as its uv: the next vertex's
            // words (unused: no texture reads a uv here), and for the last vertex this zero record.
            self.shading_records.push([0, 0]);
        }
        for (i, t) in self.tri_shading.iter().enumerate() {
            for (k, &c) in t.corners.iter().enumerate() {
                self.tri_verts[3 * i + k][3] = f32::from_bits(c * stride);
            }
        }
        self.tri_lights = if self.tri_shading.iter().any(|t| t.light != INVALID) {
            self.tri_shading.iter().map(|t| t.light).collect()
        } else {
            NO_TRI_LIGHTS.to_vec()
        };
    }

    /// Records per shading vertex in `shading_records`: 2 (normal and material, uv) where the scene has textures,
    /// else 1.
    pub fn shading_record_stride(&self) -> u32 {
        if self.tex_info.is_empty() {
            1
        } else {
            2
        }
    }

    /// Vertex `k` of the per-triangle arrays (triangle k / 3), wherever it is: in `tri_verts` or, past one binding,
    /// in a part of `tri_verts_hi`.
    pub fn tri_vertex(&self, k: usize) -> [f32; 4] {
        let mut rest = k;
        for part in std::iter::once(&self.tri_verts).chain(&self.tri_verts_hi) {
            if rest < part.len() {
                return part[rest];
            }
            rest -= part.len();
        }
        panic!("vertex {k} is past the scene's {} vertices", k - rest)
    }

    /// Nodes of the BVH in use, and its kind ("8-wide" or "binary").
    pub fn bvh_node_count(&self) -> String {
        match self.wide_nodes.len() {
            0 => format!("{} binary", self.bvh_nodes.len()),
            n => format!("{n} 8-wide"),
        }
    }

    /// How many convex lamps (`accel::convex_lamps`) the light table holds.
    pub fn convex_lamps(&self) -> usize {
        self.lights.iter().filter(|l| l.kind == LIGHT_CONVEX_LAMP).count()
    }

    /// The convex lamps' entries in the light table, (first, count, whether they are the only lights): they follow
    /// each other. (0, 0, false) for none.
    pub fn lamp_range(&self) -> (u32, u32, bool) {
        let n = self.convex_lamps();
        let first = self.lights.iter().position(|l| l.kind == LIGHT_CONVEX_LAMP);
        first.map_or((0, 0, false), |f| (f as u32, n as u32, n == self.selectable_lights()))
    }

    /// The lights that selection chooses among: the first this many of `lights`.
    pub fn selectable_lights(&self) -> usize {
        self.lights.len() - self.lamp_faces
    }

    /// Material index of triangle `i`.
    pub fn tri_material(&self, i: usize) -> u32 {
        word_material(self.shading_verts[self.tri_shading[i].corners[0] as usize].material)
    }

    /// Whether some triangle has a cut-out mask (shaders/alpha.wgsl).
    pub fn has_alpha_cutouts(&self) -> bool {
        self.shading_verts.iter().any(|v| crate::render::shading_data::word_alpha_texture(v.material) != 0)
    }

    /// Bytes of geometry + BVH per triangle (0 without triangles).
    pub fn bvh_bytes(&self) -> usize {
        self.bvh_nodes.len() * std::mem::size_of::<bvh::GpuBvhNode>()
            + self.prim_refs.len() * 4
            + std::mem::size_of_val(self.wide_nodes.as_slice())
    }
}

/// The triangles to bake into the pipeline instead of putting them in the BVH, or None: in a scene of more than
/// `FLAT_MAX_PRIMS` primitives where at most that many triangles do not emit (`emits[i]`) and the rest are emitter
/// triangles — Veach's plates and walls under 80,640 triangles of tessellated lamps — the non-emitters are tested
/// as literals before the BVH (shaders/bvh.wgsl `bvh_traverse`), and the BVH holds the emitters alone. A camera ray
/// or a shadow ray that meets no lamp's box then reads no node at all (baking removes the loads, which is what a
/// ray costs on lavapipe: docs/profile-bvh.md). Not with spheres or quads (kept simple: the BVH stays
/// triangle-only), cut-out masks (the baked tests have no alpha test), or without `on`.
pub fn occluder_split(emits: &[bool], analytic_prims: usize, alpha: bool, on: bool) -> Option<Vec<usize>> {
    let occluders: Vec<usize> = (0..emits.len()).filter(|&i| !emits[i]).collect();
    let fits = !occluders.is_empty() && occluders.len() <= FLAT_MAX_PRIMS;
    (on && fits && !alpha && analytic_prims == 0 && emits.len() > FLAT_MAX_PRIMS).then_some(occluders)
}

/// The choices `SceneData::build_options` makes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BuildOptions {
    /// Make convex lamps of the emitter meshes that qualify (`accel::convex_lamps`).
    pub convex_lamps: bool,
    /// Bake a few occluders among many emitter triangles into the pipeline (`occluder_split`).
    pub baked_occluders: bool,
    /// Test the wide BVH root's children against literal boxes in the scene's own pipelines (`baked::baked_root`).
    pub baked_root: bool,
}

fn xform(t: &Option<TextureRef>) -> ([f32; 4], [f32; 4], u32) {
    match t {
        Some(r) => {
            let m = r.transform;
            ([m[0][0], m[0][1], m[0][2], 0.0], [m[1][0], m[1][1], m[1][2], 0.0], r.texture)
        }
        None => ([1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], INVALID),
    }
}

fn gpu_material(m: &crate::scene::Material) -> GpuMaterial {
    let (b0, b1, bt) = xform(&m.base_color_texture);
    let (m0, m1, mt) = xform(&m.metallic_roughness_texture);
    let (e0, e1, et) = xform(&m.emissive_texture);
    let finite = |v: f32, def: f32| if v.is_finite() { v } else { def };
    let (bsdf_kind, [params0, params1, params2]) = crate::render::materials::pack(m);
    GpuMaterial {
        emission: m.emission.to_array().map(|c| finite(c, 0.0).max(0.0)),
        bsdf_kind,
        base_tex: bt,
        mr_tex: mt,
        emissive_tex: et,
        _pad0: 0,
        base_xform0: b0,
        base_xform1: b1,
        mr_xform0: m0,
        mr_xform1: m1,
        em_xform0: e0,
        em_xform1: e1,
        params0,
        params1,
        params2,
    }
}

fn wrap_tag(w: Wrap) -> u32 {
    match w {
        Wrap::Repeat => WRAP_REPEAT,
        Wrap::Clamp => WRAP_CLAMP,
        Wrap::Mirror => WRAP_MIRROR,
    }
}

fn build_textures(scene: &Scene, d: &mut SceneData) {
    for t in &scene.textures {
        let tex_kind = match t.kind {
            crate::scene::TextureKind::Image => TEX_IMAGE,
            crate::scene::TextureKind::Checkerboard { .. } => TEX_CHECKERBOARD,
        };
        d.tex_info.push(GpuTextureInfo {
            offset: d.tex_texels.len() as u32,
            width: t.width,
            height: t.height,
            wrap_s: wrap_tag(t.wrap_s),
            wrap_t: wrap_tag(t.wrap_t),
            srgb: t.srgb as u32,
            nearest: t.nearest as u32,
            tex_kind,
        });
        match t.kind {
            crate::scene::TextureKind::Image => d.tex_texels.extend(t.texels.iter().map(|c| u32::from_le_bytes(*c))),
            // The two colours as f32 bits: full precision, and values above 1 (a `scale`d checkerboard) survive.
            crate::scene::TextureKind::Checkerboard { tex1, tex2 } => {
                d.tex_texels.extend(tex1.to_array().iter().chain(&tex2.to_array()).map(|v| v.to_bits()))
            }
        }
    }
}
