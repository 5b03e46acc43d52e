//! SceneData: the scene flattened, on the CPU, into the tables the shaders read (geometry + BVH, shading
//! data, light table, textures, environment distribution); `gpu_scene` uploads them.

use crate::accel::bvh;
use crate::accel::convex_lamps::{convex_lamp, ConvexLamp};
use crate::accel::isolated_emitters::{isolated_emitters, IsolatedEmitter};
use crate::accel::light_tree::{GpuLightNode, LightBounds, LightTree};
use crate::gpu::types::*;
use crate::render::lights::{self, luminance};
use crate::render::shading_data::{material_word, word_material, ShadingTable};
use crate::scene::{Environment, PunctualLight, Scene, TextureRef, Wrap};
use glam::{Vec2, Vec3};
use std::f64::consts::PI;

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
    /// BVH build time, seconds.
    pub bvh_seconds: f64,
    /// BVH SAH cost.
    pub bvh_sah: f32,
    /// Number of delta lights (reachable by light sampling only).
    pub delta_lights: u32,
    /// World position of the render origin: every position above is relative to it (see `render_origin`).
    pub origin: Vec3,
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
    /// Flattens a scene. Pure CPU work; `GpuScene::upload` sends it to a device. Convex lamps are made unless
    /// `MISLAB_CONVEX_LAMPS=0` ([`convex_lamps_on`]) or the scene keeps its emitter triangles.
    pub fn build(scene: &Scene) -> SceneData {
        SceneData::build_with(scene, convex_lamps_on() && !scene.emitter_triangles_kept)
    }

    /// `build`, making convex lamps of the emitter meshes that qualify (`accel::convex_lamps`) or keeping every
    /// emissive triangle a light of its own.
    pub fn build_with(scene: &Scene, convex_lamps: bool) -> SceneData {
        let mut d = SceneData { origin: render_origin(scene), ..SceneData::default() };
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
        let presplit = if tris.len() + d.spheres.len() + d.quads.len() > crate::render::baked::FLAT_MAX_PRIMS {
            bvh::Presplit::Large { keep_whole: &keep_whole }
        } else {
            bvh::Presplit::Off
        };
        let mut bvh = if bvh_layout_wide() {
            bvh::build_wide(&tris, &d.spheres, &d.quads, presplit)
        } else {
            bvh::build(&tris, &d.spheres, &d.quads, presplit)
        };
        // Triangles in leaf order: traversal reads a triangle-only leaf's vertices without prim_refs.
        d.triangles = tris.len();
        let order = bvh::into_leaf_order(&mut bvh, tris.len());
        tris = order.iter().map(|&i| tris[i as usize]).collect();
        d.tri_verts = order.iter().flat_map(|&i| d.tri_verts[3 * i as usize..3 * i as usize + 3].to_vec()).collect();
        d.tri_shading = order.iter().map(|&i| d.tri_shading[i as usize]).collect();
        d.bvh_seconds = bvh.build_seconds;
        d.bvh_sah = bvh.sah_cost;
        d.bvh_nodes = bvh.nodes;
        let identity = bvh.prim_refs.iter().enumerate().all(|(j, &r)| r == make_prim(PRIM_TRIANGLE, j as u32));
        d.prim_refs = if identity && !bvh.prim_refs.is_empty() { IDENTITY_PRIM_REFS.to_vec() } else { bvh.prim_refs };
        d.wide_nodes = bvh.wide;
        build_textures(scene, &mut d);
        build_lights(scene, &tris, &mut d, convex_lamps);
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

    /// Nodes of the BVH in use, and its kind ("8-wide" or "binary").
    pub fn bvh_node_count(&self) -> String {
        match self.wide_nodes.len() {
            0 => format!("{} binary", self.bvh_nodes.len()),
            n => format!("{n} 8-wide"),
        }
    }

    /// Material index of triangle `i`.
    /// How many convex lamps (`accel::convex_lamps`) the light table holds.
    pub fn convex_lamps(&self) -> usize {
        self.lights.iter().filter(|l| l.kind == LIGHT_CONVEX_LAMP).count()
    }

    /// The lights that selection chooses among: the first this many of `lights`.
    pub fn selectable_lights(&self) -> usize {
        self.lights.len() - self.lamp_faces
    }

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

/// Whether scenes get the 8-wide compressed BVH (the default) or the BVH2: `MISLAB_BVH=2` selects the BVH2, for
/// A/B runs and as the fallback to compare against (docs/profile-bvh.md).
pub fn bvh_layout_wide() -> bool {
    std::env::var("MISLAB_BVH").map_or(true, |v| v != "2")
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
    let kind = material_kind(m);
    GpuMaterial {
        // Kinds that carry their own colour (tint, reflectance) put it in base_color themselves.
        base_color: if matches!(
            kind.bsdf_kind,
            MATERIAL_CONDUCTOR | MATERIAL_DIELECTRIC | MATERIAL_DIFFUSE_TRANSMISSION
        ) {
            kind.base_color
        } else {
            m.base_color.to_array().map(|c| finite(c, 0.0).max(0.0))
        },
        metallic: if kind.bsdf_kind == MATERIAL_DIFFUSE_TRANSMISSION {
            kind.metallic
        } else {
            finite(m.metallic, 0.0).clamp(0.0, 1.0)
        },
        emission: m.emission.to_array().map(|c| finite(c, 0.0).max(0.0)),
        alpha: if kind.bsdf_kind == MATERIAL_METALLIC_ROUGHNESS { m.alpha() } else { kind.alpha },
        specular: if matches!(kind.bsdf_kind, MATERIAL_CONDUCTOR | MATERIAL_DIELECTRIC | MATERIAL_COATED_DIFFUSE) {
            kind.specular
        } else {
            finite(m.specular, 1.0).clamp(0.0, 1.0)
        },
        base_tex: bt,
        mr_tex: mt,
        emissive_tex: et,
        base_xform0: b0,
        base_xform1: b1,
        mr_xform0: m0,
        mr_xform1: m1,
        em_xform0: e0,
        em_xform1: e1,
        ..kind
    }
}

/// The kind tag and the kind's own parameters (sanitised: finite, η > 0, k ≥ 0, α ≥ ALPHA_MIN).
fn material_kind(m: &crate::scene::Material) -> GpuMaterial {
    use crate::scene::{MaterialKind, ALPHA_MIN};
    let finite = |v: f32, def: f32| if v.is_finite() { v } else { def };
    let alpha = |a: f32| finite(a, 1.0).clamp(ALPHA_MIN, 1.0);
    match &m.kind {
        MaterialKind::MetallicRoughness => GpuMaterial { bsdf_kind: MATERIAL_METALLIC_ROUGHNESS, ..Default::default() },
        MaterialKind::Conductor { eta, k, alpha_u, alpha_v, tint, beckmann } => GpuMaterial {
            bsdf_kind: MATERIAL_CONDUCTOR,
            // specular (unused by this kind): the microfacet distribution, 0 = GGX, 1 = Beckmann.
            specular: if *beckmann { 1.0 } else { 0.0 },
            base_color: tint.to_array().map(|c| finite(c, 1.0).max(0.0)),
            eta: eta.to_array().map(|c| finite(c, 1.0).max(1e-3)),
            k: k.to_array().map(|c| finite(c, 0.0).max(0.0)),
            alpha: alpha(*alpha_u),
            alpha_v: alpha(*alpha_v),
            ..Default::default()
        },
        // Reflectance: base_color / base_tex, as for metallic-roughness. η ≥ 1 + 1e-4 (the model has no
        // total internal reflection from outside; η = 1 would be no coat at all).
        // specular (unused by these kinds' parameters): the microfacet distribution, 0 = GGX, 1 = Beckmann.
        MaterialKind::CoatedDiffuse { eta, alpha_u, alpha_v, beckmann } => GpuMaterial {
            bsdf_kind: MATERIAL_COATED_DIFFUSE,
            specular: if *beckmann { 1.0 } else { 0.0 },
            eta: [finite(*eta, 1.5).clamp(1.0001, 10.0), 1.0, 1.0],
            alpha: alpha(*alpha_u),
            alpha_v: alpha(*alpha_v),
            ..Default::default()
        },
        MaterialKind::Dielectric { eta, alpha_u, alpha_v, tint, thin, beckmann } => GpuMaterial {
            bsdf_kind: MATERIAL_DIELECTRIC,
            specular: if *beckmann { 1.0 } else { 0.0 },
            // η = 1 has no interface to refract at; keep it off 1 so the Walter half vector stays defined.
            // eta[1]: the thin-slab flag.
            eta: {
                let e = finite(*eta, 1.5).clamp(1e-3, 1e3);
                [if (e - 1.0).abs() < 1e-4 { 1.0001 } else { e }, if *thin { 1.0 } else { 0.0 }, 0.0]
            },
            alpha: alpha(*alpha_u),
            alpha_v: alpha(*alpha_v),
            base_color: tint.to_array().map(|c| finite(c, 1.0).max(0.0)),
            ..Default::default()
        },
        MaterialKind::DiffuseTransmission { reflectance, transmittance, transmittance_textured } => GpuMaterial {
            bsdf_kind: MATERIAL_DIFFUSE_TRANSMISSION,
            // metallic (unused by this kind): 1 = the base texture multiplies the transmittance too.
            metallic: if *transmittance_textured { 1.0 } else { 0.0 },
            base_color: reflectance.to_array().map(|c| finite(c, 0.0).max(0.0)),
            k: transmittance.to_array().map(|c| finite(c, 0.0).max(0.0)),
            ..Default::default()
        },
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

/// Radius of a sphere bounding every finite primitive (for the power of distant lights).
fn scene_radius(d: &SceneData) -> f64 {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    let mut add = |p: Vec3, r: f32| {
        if p.is_finite() {
            lo = lo.min(p - r);
            hi = hi.max(p + r);
        }
    };
    for v in &d.tri_verts {
        add(Vec3::new(v[0], v[1], v[2]), 0.0);
    }
    for s in &d.spheres {
        add(Vec3::from(s.center), s.radius);
    }
    for q in &d.quads {
        let c = Vec3::from(q.corner);
        add(c, 0.0);
        add(c + Vec3::from(q.edge_u) + Vec3::from(q.edge_v), 0.0);
    }
    if lo.x > hi.x {
        return 1.0;
    }
    (0.5 * (hi - lo).length() as f64).max(1e-3)
}

/// Gives the triangle lights of isolated emitter meshes their stop box (`accel::isolated_emitters`): a shadow ray
/// towards one may end where it enters that box. `MISLAB_SHADOW_BOX=0` turns it off (for A/B runs).
fn mark_isolated_emitters(tris: &[[Vec3; 3]], d: &SceneData, lights: &mut [GpuLight]) -> Vec<IsolatedEmitter> {
    if std::env::var("MISLAB_SHADOW_BOX").is_ok_and(|v| v == "0") {
        return vec![];
    }
    let light_of = |i: usize| d.tri_shading.get(i).map_or(INVALID, |s| s.light);
    let emitter = |i: usize| {
        let l = light_of(i);
        (l != INVALID).then(|| lights[l as usize].two_sided == 1)
    };
    let spheres = d.spheres.iter().map(|s| {
        let (c, r) = (Vec3::from(s.center), Vec3::splat(s.radius));
        (c - r, c + r)
    });
    let quads = d.quads.iter().map(|q| {
        let c = Vec3::from(q.corner);
        let (u, v) = (Vec3::from(q.edge_u), Vec3::from(q.edge_v));
        let ps = [c, c + u, c + v, c + u + v];
        (ps.iter().fold(Vec3::INFINITY, |a, &p| a.min(p)), ps.iter().fold(Vec3::NEG_INFINITY, |a, &p| a.max(p)))
    });
    let others: Vec<(Vec3, Vec3)> = spheres.chain(quads).collect();
    let meshes = isolated_emitters(tris, emitter, &others);
    for mesh in &meshes {
        for &t in &mesh.triangles {
            let l = &mut lights[light_of(t) as usize];
            (l.position, l.direction, l.shadow_box) = (mesh.lo.into(), mesh.hi.into(), 1);
        }
    }
    meshes
}

/// Whether isolated emitter meshes that are closed, convex and round become convex lamps (`accel::convex_lamps`):
/// `MISLAB_CONVEX_LAMPS=0` keeps their triangles as lights (for A/B runs).
pub fn convex_lamps_on() -> bool {
    !std::env::var("MISLAB_CONVEX_LAMPS").is_ok_and(|v| v == "0")
}

/// Replaces the triangle lights of every convex lamp among `meshes` by one lamp light (appended) and returns the
/// lamps, each with the lights of its faces (moved out of `lights`; `tri_shading` is repointed in
/// `append_lamp_faces`). A lamp needs one emission on every face: one material without an emission texture,
/// one-sided.
fn make_convex_lamps(
    tris: &[[Vec3; 3]],
    d: &mut SceneData,
    meshes: &[IsolatedEmitter],
    lights: &mut Vec<GpuLight>,
    power: &mut Vec<f64>,
) -> Vec<(u32, Vec<(usize, GpuLight)>)> {
    let lamps: Vec<ConvexLamp> = meshes
        .iter()
        .filter(|m| {
            let mat = d.tri_material(m.triangles[0]);
            let gm = &d.materials[mat as usize];
            gm.emissive_tex == INVALID
                && m.triangles
                    .iter()
                    .all(|&t| d.tri_material(t) == mat && lights[d.tri_shading[t].light as usize].two_sided == 0)
        })
        .filter_map(|m| convex_lamp(tris, m))
        .collect();
    if lamps.is_empty() {
        return vec![];
    }
    let mut face_of = vec![false; lights.len()];
    for lamp in &lamps {
        for &t in &lamp.mesh.triangles {
            face_of[d.tri_shading[t].light as usize] = true;
        }
    }
    // Keep the other lights in order and repoint their triangles.
    let mut index = vec![INVALID; lights.len()];
    let (mut kept, mut kept_power) = (Vec::new(), Vec::new());
    for (i, (l, p)) in lights.iter().zip(power.iter()).enumerate() {
        if !face_of[i] {
            index[i] = kept.len() as u32;
            kept.push(*l);
            kept_power.push(*p);
        }
    }
    let old = std::mem::replace(lights, kept);
    *power = kept_power;
    for s in d.tri_shading.iter_mut().filter(|s| s.light != INVALID) {
        if !face_of[s.light as usize] {
            s.light = index[s.light as usize];
        }
    }
    for l in d.spheres.iter_mut().map(|s| &mut s.light).chain(d.quads.iter_mut().map(|q| &mut q.light)) {
        if *l != INVALID {
            *l = index[*l as usize];
        }
    }
    let mut out = Vec::new();
    for lamp in lamps {
        let faces: Vec<(usize, GpuLight)> =
            lamp.mesh.triangles.iter().map(|&t| (t, old[d.tri_shading[t].light as usize])).collect();
        let area: f64 = faces.iter().map(|(_, l)| l.area as f64).sum();
        let emission = d.materials[d.tri_material(lamp.mesh.triangles[0]) as usize].emission;
        power.push(PI * area * luminance(emission));
        out.push((lights.len() as u32, faces));
        lights.push(GpuLight {
            kind: LIGHT_CONVEX_LAMP,
            position: lamp.mesh.lo.into(),
            direction: lamp.mesh.hi.into(),
            shadow_box: 1,
            radiance: emission,
            cos_inner: lamp.r_in,
            cos_outer: lamp.rim,
            area: lamp.mesh.triangles.len() as f32,
            ..Default::default()
        });
    }
    out
}

/// Appends the convex lamps' faces after every light that selection chooses among: each lamp learns where its
/// faces start (`prim`), each face its lamp (`tree_trail`), each face's triangle its light.
fn append_lamp_faces(d: &mut SceneData, lights: &mut Vec<GpuLight>, lamps: Vec<(u32, Vec<(usize, GpuLight)>)>) {
    for (lamp, faces) in lamps {
        lights[lamp as usize].prim = lights.len() as u32;
        d.lamp_faces += faces.len();
        for (t, face) in faces {
            d.tri_shading[t].light = lights.len() as u32;
            lights.push(GpuLight { kind: LIGHT_LAMP_FACE, tree_trail: lamp, pmf_power: 0.0, pmf_uniform: 0.0, ..face });
        }
    }
}

/// Emissive triangles are never pre-split (`keep_whole` above), so each is one light with one copy.
fn build_lights(scene: &Scene, tris: &[[Vec3; 3]], d: &mut SceneData, convex_lamps: bool) {
    let mut lights: Vec<GpuLight> = Vec::new();
    let mut power: Vec<f64> = Vec::new();
    let emits = |m: u32| {
        let gm = &d.materials[m as usize];
        gm.emission.iter().any(|&c| c > 0.0)
    };
    // Faces that emit: 2 for a two-sided area emitter.
    let two_sided =
        |m: u32| if scene.materials.get(m as usize).is_some_and(|m| m.emission_two_sided) { 2u32 } else { 1 };
    for (i, t) in tris.iter().enumerate() {
        let m = d.tri_material(i);
        if !emits(m) {
            continue;
        }
        let area = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length();
        if !(area > 0.0 && area.is_finite()) {
            continue;
        }
        d.tri_shading[i].light = lights.len() as u32;
        // A two-sided emitter radiates π·A·L from each face.
        let sides = two_sided(m);
        power.push(PI * area as f64 * luminance(d.materials[m as usize].emission) * sides as f64);
        let two_sided = (sides == 2) as u32;
        lights.push(GpuLight { kind: LIGHT_TRIANGLE, prim: i as u32, area, two_sided, ..Default::default() });
    }
    for i in 0..d.spheres.len() {
        let s = d.spheres[i];
        if !emits(s.material) || !(s.radius > 0.0) {
            continue;
        }
        let area = 4.0 * std::f32::consts::PI * s.radius * s.radius;
        d.spheres[i].light = lights.len() as u32;
        power.push(PI * area as f64 * luminance(d.materials[s.material as usize].emission));
        lights.push(GpuLight { kind: LIGHT_SPHERE, prim: i as u32, area, position: s.center, ..Default::default() });
    }
    for i in 0..d.quads.len() {
        let q = d.quads[i];
        let area = Vec3::from(q.edge_u).cross(Vec3::from(q.edge_v)).length();
        if !emits(q.material) || !(area > 0.0 && area.is_finite()) {
            continue;
        }
        d.quads[i].light = lights.len() as u32;
        let sides = two_sided(q.material);
        power.push(PI * area as f64 * luminance(d.materials[q.material as usize].emission) * sides as f64);
        let two_sided = (sides == 2) as u32;
        lights.push(GpuLight { kind: LIGHT_QUAD, prim: i as u32, area, two_sided, ..Default::default() });
    }
    let isolated = mark_isolated_emitters(tris, d, &mut lights);
    let lamps = if convex_lamps { make_convex_lamps(tris, d, &isolated, &mut lights, &mut power) } else { vec![] };
    let r = scene_radius(d);
    // Lights with a position first, then the infinite ones (directional, environment): the light tree covers
    // the first `bounded` entries and the shader finds the infinite ones after them.
    let punctual = scene.punctual_lights.iter().filter(|l| !matches!(l, PunctualLight::Directional { .. }));
    let directional = scene.punctual_lights.iter().filter(|l| matches!(l, PunctualLight::Directional { .. }));
    for l in punctual.chain(directional) {
        let (g, p) = match *l {
            PunctualLight::Point { position, intensity } => (
                GpuLight {
                    kind: LIGHT_POINT,
                    position: (position - d.origin).into(),
                    radiance: intensity.into(),
                    ..Default::default()
                },
                4.0 * PI * luminance(intensity.into()),
            ),
            PunctualLight::Spot { position, direction, intensity, inner_cone, outer_cone } => {
                let (ci, co) = (inner_cone.cos(), outer_cone.cos());
                let g = GpuLight {
                    kind: LIGHT_SPOT,
                    position: (position - d.origin).into(),
                    direction: direction.normalize_or(Vec3::NEG_Z).into(),
                    radiance: intensity.into(),
                    cos_inner: ci.max(co + 1e-6).min(1.0),
                    cos_outer: co,
                    ..Default::default()
                };
                (g, 2.0 * PI * (1.0 - 0.5 * (ci + co) as f64) * luminance(intensity.into()))
            }
            PunctualLight::Directional { direction, irradiance } => (
                GpuLight {
                    kind: LIGHT_DIRECTIONAL,
                    direction: direction.normalize_or(Vec3::NEG_Y).into(),
                    radiance: irradiance.into(),
                    ..Default::default()
                },
                PI * r * r * luminance(irradiance.into()),
            ),
        };
        d.delta_lights += 1;
        power.push(p);
        lights.push(g);
    }
    match &scene.environment {
        Environment::None => {}
        Environment::Constant(c) => {
            d.env_constant = (*c).into();
            d.env_scale = 1.0;
            if c.max_element() > 0.0 {
                d.env_light = Some(lights.len() as u32);
                power.push(4.0 * PI * PI * r * r * luminance((*c).into()));
                lights.push(GpuLight { kind: LIGHT_ENVIRONMENT, ..Default::default() });
            }
        }
        Environment::Map { map, scale, rotation } => {
            let dist = lights::env_distribution(map);
            d.env_size = (map.width, map.height);
            d.env_scale = *scale;
            d.env_rotation = *rotation;
            if dist.mean_luminance * (*scale as f64) > 0.0 {
                d.env_light = Some(lights.len() as u32);
                power.push(4.0 * PI * PI * r * r * dist.mean_luminance * *scale as f64);
                lights.push(GpuLight { kind: LIGHT_ENVIRONMENT, ..Default::default() });
            }
            d.env_texels = dist.texels;
            d.env_alias = dist.alias;
        }
    }
    let table = lights::alias_table(&power);
    let n = lights.len();
    for (l, p) in lights.iter_mut().zip(&table.pmf) {
        l.pmf_power = *p as f32;
        l.pmf_uniform = 1.0 / n as f32;
    }
    let bounded = lights.iter().take_while(|l| !matches!(l.kind, LIGHT_DIRECTIONAL | LIGHT_ENVIRONMENT)).count();
    debug_assert!(lights[bounded..].iter().all(|l| matches!(l.kind, LIGHT_DIRECTIONAL | LIGHT_ENVIRONMENT)));
    let bounds: Vec<LightBounds> =
        lights[..bounded].iter().zip(&power).map(|(l, &p)| light_bounds(l, p, tris, d)).collect();
    let tree = LightTree::build(&bounds, &(0..bounded as u32).collect::<Vec<_>>());
    for (l, &trail) in lights.iter_mut().zip(&tree.trails) {
        l.tree_trail = trail;
    }
    d.light_tree = tree.nodes;
    append_lamp_faces(d, &mut lights, lamps);
    d.lights = lights;
    d.light_alias = table.entries;
}

/// Where light `l` (of power `power`) is and emits, for the light tree: area emitters emit from their front (the
/// side `*_sample_li` accepts) or, two-sided, from both faces; spheres and point lights emit everywhere, spots
/// into their outer cone.
fn light_bounds(l: &GpuLight, power: f64, tris: &[[Vec3; 3]], d: &SceneData) -> LightBounds {
    let everywhere = |lo: Vec3, hi: Vec3| LightBounds {
        lo,
        hi,
        phi: power as f32,
        axis: Vec3::Z,
        cos_o: -1.0,
        cos_e: 0.0,
        two_sided: false,
    };
    let facing = |pts: &[Vec3], normal: Vec3| {
        let lo = pts.iter().fold(Vec3::splat(f32::MAX), |a, &p| a.min(p));
        let hi = pts.iter().fold(Vec3::splat(f32::MIN), |a, &p| a.max(p));
        LightBounds {
            axis: normal.normalize_or(Vec3::Z),
            cos_o: 1.0,
            two_sided: l.two_sided != 0,
            ..everywhere(lo, hi)
        }
    };
    match l.kind {
        LIGHT_TRIANGLE => {
            let t = tris[l.prim as usize];
            facing(&t, (t[1] - t[0]).cross(t[2] - t[0]))
        }
        LIGHT_QUAD => {
            let q = d.quads[l.prim as usize];
            let (c, u, v) = (Vec3::from(q.corner), Vec3::from(q.edge_u), Vec3::from(q.edge_v));
            facing(&[c, c + u, c + v, c + u + v], u.cross(v))
        }
        LIGHT_SPHERE => {
            let s = d.spheres[l.prim as usize];
            let c = Vec3::from(s.center);
            everywhere(c - s.radius, c + s.radius)
        }
        LIGHT_CONVEX_LAMP => everywhere(l.position.into(), l.direction.into()),
        LIGHT_SPOT => {
            let p = Vec3::from(l.position);
            let (theta_i, theta_o) = (l.cos_inner.clamp(-1.0, 1.0).acos(), l.cos_outer.clamp(-1.0, 1.0).acos());
            LightBounds {
                axis: Vec3::from(l.direction),
                cos_o: l.cos_inner,
                cos_e: (theta_o - theta_i).max(0.0).cos(),
                ..everywhere(p, p)
            }
        }
        _ => {
            let p = Vec3::from(l.position);
            everywhere(p, p)
        }
    }
}
