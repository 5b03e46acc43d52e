//! Features: what a scene uses, derived from its flattened data, and the pipeline constants that compile
//! out everything else. `Settings` decide which techniques run; `Features` decide which code exists.

use crate::gpu::types::*;
use crate::render::materials;
use crate::render::scene_data::SceneData;
use crate::render::settings::Settings;

/// `Features::occluders` of the generic pipeline: whatever `FrameParams::occluder_count` says at run time.
pub const GENERIC_OCCLUDERS: u32 = u32::MAX;

/// Whether a device of `backend` gets scenes baked into its shaders (`render::baked`). Not a browser's WebGPU:
/// Chromium's SwiftShader never finished the first dispatch of a baked kernel (veach-mis, cornell-box) in minutes,
/// while the buffer-reading path renders the native means there (docs/web.md).
pub fn bakes(backend: wgpu::Backend) -> bool {
    backend != wgpu::Backend::BrowserWebGpu
}

/// What kind of environment the scene has.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EnvKind {
    /// Black.
    None = 0,
    /// Constant radiance.
    Constant = 1,
    /// Equirectangular map.
    Map = 2,
    /// Decided at run time (the generic pipeline).
    Any = 3,
}

/// The scene's features. `Features::generic()` has everything on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Features {
    /// Triangles in the BVH.
    pub triangles: bool,
    /// Analytic spheres.
    pub spheres: bool,
    /// Analytic quads.
    pub quads: bool,
    /// Emissive triangles.
    pub triangle_lights: bool,
    /// Emissive spheres.
    pub sphere_lights: bool,
    /// Emissive quads.
    pub quad_lights: bool,
    /// Point, spot or directional lights.
    pub delta_lights: bool,
    /// Convex lamps (`accel::convex_lamps`).
    pub convex_lamps: bool,
    /// Environment kind.
    pub env: EnvKind,
    /// Any texture.
    pub textures: bool,
    /// Any pbrt checkerboard texture (`TEX_CHECKERBOARD`).
    pub checkerboard: bool,
    /// Texels over two bindings (`gpu_scene::split_texels`): texel reads look at `TEXEL_HI`.
    pub texel_split: bool,
    /// Vertices over two to four bindings (`gpu_scene::split_vertices`): vertex reads past `tri_verts` go to
    /// `tri_verts_hi` and the bindings after it.
    pub geometry_split: bool,
    /// Any metallic-roughness material with a GGX lobe.
    pub specular: bool,
    /// Any metallic-roughness material with a diffuse lobe.
    pub diffuse: bool,
    /// The material kinds the scene uses, one bit per `render::materials::MATERIALS` index (each sets its HAS_*).
    pub materials: u32,
    /// More than one entry in the light table (light selection needed).
    pub many_lights: bool,
    /// Any triangle with a cut-out mask (shaders/alpha.wgsl): the traversal tests alpha at triangle hits.
    pub alpha: bool,
    /// The scene's BVH is the 8-wide compressed one (shaders/bvh_wide.wgsl), not the BVH2.
    pub wide_bvh: bool,
    /// For scenes of at most `FLAT_MAX_PRIMS` primitives: (triangles, spheres, quads), baked into the shader
    /// (src/render/baked.rs): every primitive tested, unrolled, with its data as literals, instead of a BVH walk (no
    /// stack, no divergent traversal, no buffer reads). None = BVH.
    pub flat: Option<(u32, u32, u32)>,
    /// Triangles tested as literals before the BVH, which holds the rest (`SceneData::occluders`); 0 = none;
    /// `GENERIC_OCCLUDERS`: read from the frame parameters and tested in a loop (the generic pipeline).
    pub occluders: u32,
    /// The wide BVH's root children are tested against their exact boxes as literals (`baked::baked_root`).
    pub baked_root: bool,
    /// For flat scenes, a hash of the scene data baked into its pipelines' source (src/render/baked.rs), so that a
    /// pipeline cache never hands one scene's baked pipeline to another; 0 otherwise.
    pub baked: u64,
    /// The scene's tables are bound as one packed buffer (`render::packed_scene`): not a code path of the
    /// renderer but its module's reads, so pipelines of the two layouts never mix.
    pub packed_scene: bool,
}

impl Features {
    /// Everything compiled in.
    pub fn generic() -> Features {
        Features {
            triangles: true,
            spheres: true,
            quads: true,
            triangle_lights: true,
            sphere_lights: true,
            quad_lights: true,
            delta_lights: true,
            convex_lamps: true,
            env: EnvKind::Any,
            textures: true,
            checkerboard: true,
            texel_split: true,
            geometry_split: true,
            specular: true,
            diffuse: true,
            materials: materials::all(),
            many_lights: true,
            // Not a code path but the layout every scene is built with (SceneData::build).
            wide_bvh: true,
            alpha: true,
            flat: None,
            // The generic pipeline tests a scene's occluders in a loop over their buffer slots (baked_geometry.wgsl).
            occluders: GENERIC_OCCLUDERS,
            baked_root: false,
            baked: 0,
            packed_scene: false,
        }
    }

    /// What `data` needs.
    pub fn of(data: &SceneData) -> Features {
        let (specular, diffuse) = materials::metallic_roughness_lobes(&data.materials);
        let kinds = |k: u32| data.lights.iter().any(|l| l.kind == k);
        let alpha = data.has_alpha_cutouts();
        let env = match (data.env_light.is_some(), data.env_size.0 > 0) {
            (false, _) => EnvKind::None,
            (true, false) => EnvKind::Constant,
            (true, true) => EnvKind::Map,
        };
        Features {
            triangles: !data.tri_shading.is_empty(),
            spheres: !data.spheres.is_empty(),
            quads: !data.quads.is_empty(),
            // A lamp's faces are triangle lights to every ray that finds one.
            triangle_lights: kinds(LIGHT_TRIANGLE) || kinds(LIGHT_LAMP_FACE),
            sphere_lights: kinds(LIGHT_SPHERE),
            quad_lights: kinds(LIGHT_QUAD),
            delta_lights: kinds(LIGHT_POINT) || kinds(LIGHT_SPOT) || kinds(LIGHT_DIRECTIONAL),
            convex_lamps: kinds(LIGHT_CONVEX_LAMP),
            env,
            textures: !data.tex_info.is_empty(),
            checkerboard: data.tex_info.iter().any(|t| t.tex_kind == TEX_CHECKERBOARD),
            texel_split: data.tex_info.iter().any(|t| t.offset & TEXEL_HI != 0),
            geometry_split: !data.tri_verts_hi.is_empty(),
            specular,
            diffuse,
            materials: materials::used(&data.materials),
            many_lights: data.selectable_lights() > 1,
            wide_bvh: !data.wide_nodes.is_empty(),
            alpha,
            // The baked traversal has no alpha test: scenes with cut-outs take the BVH.
            flat: crate::render::baked::flat_counts(data).filter(|_| !alpha),
            occluders: if crate::render::baked::baked_occluders(data) { data.occluders.1 } else { 0 },
            baked_root: crate::render::baked::baked_root(data),
            baked: crate::render::render_module::baked_sources(data).map_or(0, |src| {
                use std::hash::{Hash, Hasher};
                let mut h = std::collections::hash_map::DefaultHasher::new();
                src.hash(&mut h);
                h.finish() | 1
            }),
            packed_scene: false,
        }
    }

    /// `of` for a device of `backend`: without the baked paths where it does not bake (`bakes`).
    pub fn for_backend(data: &SceneData, backend: wgpu::Backend) -> Features {
        let f = Features::of(data);
        if bakes(backend) {
            return f;
        }
        Features { flat: None, occluders: 0, baked_root: false, baked: 0, ..f }
    }

    /// The WGSL override constants for these features.
    pub fn constants(&self) -> Vec<(&'static str, f64)> {
        let b = |x: bool| if x { 1.0 } else { 0.0 };
        let mut c = vec![
            ("HAS_TRIANGLES", b(self.triangles)),
            ("HAS_SPHERES", b(self.spheres)),
            ("HAS_QUADS", b(self.quads)),
            ("HAS_TRIANGLE_LIGHTS", b(self.triangle_lights)),
            ("HAS_SPHERE_LIGHTS", b(self.sphere_lights)),
            ("HAS_QUAD_LIGHTS", b(self.quad_lights)),
            ("HAS_DELTA_LIGHTS", b(self.delta_lights)),
            ("HAS_CONVEX_LAMPS", b(self.convex_lamps)),
            ("ENV_KIND", self.env as u32 as f64),
            ("HAS_TEXTURES", b(self.textures)),
            ("HAS_CHECKERBOARD", b(self.checkerboard)),
            ("HAS_TEXEL_SPLIT", b(self.texel_split)),
            ("HAS_GEOMETRY_SPLIT", b(self.geometry_split)),
            ("HAS_SPECULAR", b(self.specular)),
            ("HAS_DIFFUSE", b(self.diffuse)),
            ("MANY_LIGHTS", b(self.many_lights)),
            ("HAS_ALPHA", b(self.alpha)),
            ("FLAT_SCENE", b(self.flat.is_some())),
            ("WIDE_BVH", b(self.wide_bvh)),
            ("BAKED_OCCLUDERS", b(self.occluders > 0)),
            ("BAKED_ROOT", b(self.baked_root)),
            // Not in the generic pipeline: its compilation is minutes already, and this changes no pixel.
            ("LAMP_SIGHTING", b(self.convex_lamps && self.occluders != GENERIC_OCCLUDERS)),
        ];
        c.extend(materials::MATERIALS.iter().enumerate().map(|(i, e)| (e.feature, b(self.has_material(i)))));
        c
    }

    /// Whether the scene uses the kind at `MATERIALS[index]`.
    pub fn has_material(&self, index: usize) -> bool {
        self.materials & 1 << index != 0
    }

    /// Whether the scene uses the material kind named `name` (`MaterialEntry::name`).
    pub fn has_kind(&self, name: &str) -> bool {
        materials::MATERIALS.iter().position(|e| e.name == name).is_some_and(|i| self.has_material(i))
    }

    /// Human-readable list of the code paths compiled in (for `mislab info`).
    pub fn describe(&self) -> String {
        let mut v = vec![];
        let mut on = |name: &str, x: bool| {
            if x {
                v.push(name.to_string())
            }
        };
        on("triangles", self.triangles);
        on("spheres", self.spheres);
        on("quads", self.quads);
        on("triangle lights", self.triangle_lights);
        on("sphere lights", self.sphere_lights);
        on("quad lights", self.quad_lights);
        on("point/spot/directional lights", self.delta_lights);
        on("convex lamps", self.convex_lamps);
        on("textures", self.textures);
        on("checkerboard textures", self.checkerboard);
        on("texels over two bindings", self.texel_split);
        on("vertices over several bindings", self.geometry_split);
        on("GGX lobe", self.specular);
        on("diffuse lobe", self.diffuse);
        for (i, e) in materials::MATERIALS.iter().enumerate() {
            on(e.describe, self.has_material(i) && !e.describe.is_empty());
        }
        on("light selection", self.many_lights);
        on("alpha cut-outs", self.alpha);
        on("8-wide compressed BVH", self.wide_bvh && self.flat.is_none());
        on("the BVH root's boxes as literals", self.baked_root);
        if let Some((t, s, q)) = self.flat {
            v.push(format!("scene baked into the shader ({t} triangles, {s} spheres, {q} quads as literals; no BVH)"));
        }
        if self.occluders > 0 && self.occluders != GENERIC_OCCLUDERS {
            v.push(format!("{} occluder triangles baked into the shader, the emitters in the BVH", self.occluders));
        }
        v.push(format!("environment: {:?}", self.env).to_lowercase());
        v.join(", ")
    }
}

/// Which pipeline to build: the scene's features, and the settings fixed at compile time (None = read at
/// run time from the uniform, for the viewer's generic pipeline).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PipelineKey {
    /// Scene features.
    pub features: Features,
    /// Fixed estimator choices, or dynamic.
    pub fixed: Option<FixedSettings>,
}

/// The enum-valued settings a specialised pipeline fixes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct FixedSettings {
    /// Tags, in the order of the `SPEC_*` constants.
    pub tags: [u32; 9],
}

/// Names of the settings constants, in `FixedSettings::tags` order.
pub const SETTINGS_CONSTANTS: [&str; 9] = [
    "SPEC_MODE",
    "SPEC_STRATEGY",
    "SPEC_LIGHT_SAMPLING",
    "SPEC_ENV_SAMPLING",
    "SPEC_LIGHT_SELECT",
    "SPEC_HEURISTIC",
    "SPEC_MIS_KIND",
    "SPEC_SAMPLER",
    "SPEC_ONE_DIRECTION",
];

impl FixedSettings {
    /// The enum choices of `s`.
    pub fn of(s: &Settings) -> FixedSettings {
        FixedSettings {
            tags: [
                s.mode.tag(),
                s.strategy.tag(),
                s.light_sampling.tag(),
                s.env_sampling.tag(),
                s.light_select.tag(),
                s.heuristic.tag(),
                s.mis.tag(),
                s.sampler.tag(),
                u32::from(s.bsdf_samples <= 1),
            ],
        }
    }
}

impl PipelineKey {
    /// Fully specialised to a scene and settings.
    pub fn specialized(features: Features, settings: &Settings) -> PipelineKey {
        PipelineKey { features, fixed: Some(FixedSettings::of(settings)) }
    }
    /// Everything decided at run time.
    pub fn generic() -> PipelineKey {
        PipelineKey { features: Features::generic(), fixed: None }
    }
    /// All override constants of this key.
    pub fn constants(&self) -> Vec<(&'static str, f64)> {
        let mut c = self.features.constants();
        if let Some(f) = self.fixed {
            c.extend(SETTINGS_CONSTANTS.iter().zip(f.tags).map(|(n, t)| (*n, t as f64)));
        }
        c
    }
}
