//! Every WGSL sampling routine, run on the device in probe kernels and chi-square-tested against its own WGSL pdf
//! (evaluated on the device over the cells' quadrature points), with the pdf's integral; solid-angle sampling of
//! triangles and rectangles against area sampling and Lambert's polygon formula; the f32 precision of the spherical
//! warps against f64 references (which sets the fallback thresholds in lights.wgsl). The harness is
//! `mislab::testkit::chi2`; the tables in docs/sampling.md come from `cargo test --release --test sampling -- --nocapture`.
//!
//! All chi-square tests of this file form one family at α = 0.01 (Šidák-corrected per test). A missing GPU adapter
//! fails every test.

use glam::{DVec3, Vec3};
use mislab::gpu::types::*;
use mislab::gpu::GpuContext;
use mislab::render::materials::tag;
use mislab::render::settings::{EnvSampling, LightSampling, LightSelect};
use mislab::render::{gpu_scene::GpuScene, scene_data::SceneData};
use mislab::scene::{EnvMap, Environment, Material, Mesh, PunctualLight, Quad, Scene, Sphere};
use mislab::testkit::chi2::{self, Chi2Options, Chi2Report, Chi2Test, Equirect, PlaneWindow, Quadrature, SphereCap};
use mislab::testkit::scene_probe::{BoundScene, ScenePipelines};
use std::f64::consts::PI;
use std::sync::OnceLock;

mod common;

/// Samples per chi-square test and per integral (2²⁰ ≥ 10⁶).
const N: u32 = 1 << 20;
/// Family-wise significance level of all chi-square tests in this file.
const ALPHA: f64 = 0.01;
/// Number of chi-square tests in the family (checked against the case lists below).
const FAMILY: usize = 81;
/// Bins of the direction domains (rows × columns).
const GRID: (usize, usize) = (100, 200);
/// The pdf a sampler returns and its pdf function at the sample must agree to PDF_MATCH (relative) for all but a
/// fraction PDF_MATCH_OUTLIERS of the samples. Outliers are f32 effects on measure-small sets: area-sampled sphere
/// points near the silhouette, where pdf ∝ 1/cos and the normal is rebuilt from a rounded point.
const PDF_MATCH: f64 = 1e-4;
const PDF_MATCH_OUTLIERS: f64 = 1e-4;

fn alpha() -> f64 {
    chi2::sidak_alpha(ALPHA, FAMILY)
}

// ---------------------------------------------------------------------------------------------------------------
// Probe kernels

const PROBE_WGSL: &str = r#"
// Probe kernels of tests/sampling.rs: the sampling routines and their pdfs, one routine per dispatch.
struct ProbeJob {
    routine: u32,
    count: u32,
    seed: u32,
    light: u32,
    flags: u32,
    grid: u32,
    _pad0: u32,
    _pad1: u32,
    p: vec4<f32>,
    a: vec4<f32>,
    b: vec4<f32>,
}
@group(2) @binding(0) var<uniform> probe_job: ProbeJob;
@group(2) @binding(1) var<storage, read_write> probe_out: array<vec4<f32>>;
@group(2) @binding(2) var<storage, read> probe_in: array<vec4<f32>>;

const R_UNIFORM_HEMISPHERE: u32 = 0u;
const R_COSINE_HEMISPHERE: u32 = 1u;
const R_UNIFORM_SPHERE: u32 = 2u;
const R_CONE: u32 = 3u;
const R_LIGHT: u32 = 4u;
const R_BSDF: u32 = 5u;
const R_ENV: u32 = 6u;
const R_SELECT: u32 = 7u;
const R_SPHERICAL_TRIANGLE: u32 = 8u;
const R_SPHERICAL_RECT: u32 = 9u;
const FLAG_STRATIFIED: u32 = 1u;   // u jittered in a grid × grid stratification (grid² = count)
const FLAG_LATTICE: u32 = 2u;      // u on the grid × grid lattice {0, 1/(grid−1), …, 1⁻}

fn probe_index(gid: vec3<u32>, nwg: vec3<u32>) -> u32 { return gid.x + gid.y * nwg.x * 64u; }

fn probe_u(i: u32) -> vec4<f32> {
    let j = probe_job;
    let h = vec4<f32>(bits_to_unit(hash4(i, 0u, j.seed, j.routine)), bits_to_unit(hash4(i, 1u, j.seed, j.routine)),
                      bits_to_unit(hash4(i, 2u, j.seed, j.routine)), bits_to_unit(hash4(i, 3u, j.seed, j.routine)));
    let cell = vec2<f32>(f32(i % j.grid), f32(i / j.grid));
    if ((j.flags & FLAG_STRATIFIED) != 0u) {
        return vec4<f32>(min((cell + h.xy) / f32(j.grid), vec2<f32>(ONE_MINUS_EPSILON)), h.zw);
    }
    if ((j.flags & FLAG_LATTICE) != 0u) {
        return vec4<f32>(min(cell / f32(j.grid - 1u), vec2<f32>(ONE_MINUS_EPSILON)), h.zw);
    }
    return h;
}

// a = (α, specular, kind, α_v), b = (base colour, metallic); a conductor's η, k do not change where samples go.
// A dielectric's η does: p.w (0: 1.5). Diffuse transmission's transmittance k is b.w (its metallic is unused).
// For conductors, coats and dielectrics "specular" = 1 selects Beckmann. Packed into each kind's words as
// src/render/materials.rs packs them (the layouts are in the kinds' files).
fn probe_bsdf() -> BsdfParams {
    let a = probe_job.a;
    let b = probe_job.b;
    let kind = u32(a.z);
    let eta = select(vec3<f32>(1.5), vec3<f32>(probe_job.p.w, 0.0, 0.0), probe_job.p.w > 0.0);
    let none = vec4<f32>(0.0);
    switch (kind) {
        case MATERIAL_CONDUCTOR: { return bsdf_params(kind, vec4<f32>(b.xyz, a.x), vec4<f32>(eta, a.w), vec4<f32>(vec3<f32>(3.0), a.y)); }
        case MATERIAL_COATED_DIFFUSE: { return bsdf_params(kind, vec4<f32>(b.xyz, eta.x), vec4<f32>(a.x, a.w, a.y, 0.0), none); }
        case MATERIAL_DIELECTRIC: { return bsdf_params(kind, vec4<f32>(b.xyz, eta.x), vec4<f32>(a.x, a.w, select(0.0, 1.0, eta.y != 0.0), a.y), none); }
        case MATERIAL_DIFFUSE_TRANSMISSION: { return bsdf_params(kind, vec4<f32>(b.xyz, 0.0), vec4<f32>(vec3<f32>(b.w), 0.0), none); }
        default: { return bsdf_params(kind, b, vec4<f32>(a.x, a.y, 0.0, 0.0), none); }
    }
}

/// The light's geometric normal at y (either orientation), as surface_at computes it.
fn probe_light_normal(i: u32, y: vec3<f32>) -> vec3<f32> {
    let l = lights[i];
    if (l.kind == LIGHT_TRIANGLE) {
        let t = scene_tri_positions(l.prim);
        return normalize(cross(t.v1 - t.v0, t.v2 - t.v0));
    }
    if (l.kind == LIGHT_QUAD) { let q = quads[l.prim]; return normalize(cross(q.edge_u, q.edge_v)); }
    if (l.kind == LIGHT_SPHERE) { return normalize(y - load_spheres(l.prim).center); }
    return vec3<f32>(0.0, 0.0, 1.0);
}

/// out[2i] = (sample, pdf returned by the sampler); out[2i+1] = (pdf function at the sample, distance, luminance of
/// the radiance, 0).
@compute @workgroup_size(64)
fn probe_sample(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = probe_index(gid, nwg);
    if (i >= probe_job.count) { return; }
    let u = probe_u(i);
    let p = probe_job.p.xyz;
    var o0 = vec4<f32>(0.0);
    var o1 = vec4<f32>(0.0);
    switch (probe_job.routine) {
        case R_UNIFORM_HEMISPHERE: {
            let w = square_to_uniform_hemisphere(u.xy);
            o0 = vec4<f32>(w, square_to_uniform_hemisphere_pdf(w));
            o1.x = square_to_uniform_hemisphere_pdf(w);
        }
        case R_COSINE_HEMISPHERE: {
            let w = square_to_cosine_hemisphere(u.xy);
            o0 = vec4<f32>(w, square_to_cosine_hemisphere_pdf(w));
            o1.x = square_to_cosine_hemisphere_pdf(w);
        }
        case R_UNIFORM_SPHERE: {
            let w = square_to_uniform_sphere(u.xy);
            o0 = vec4<f32>(w, square_to_uniform_sphere_pdf());
            o1.x = square_to_uniform_sphere_pdf();
        }
        case R_CONE: {
            let w = square_to_uniform_cone(u.xy, probe_job.a.x);
            o0 = vec4<f32>(w, square_to_uniform_cone_pdf(probe_job.a.x));
            o1.x = square_to_uniform_cone_pdf(probe_job.a.x);
        }
        case R_LIGHT: {
            let s = light_sample_li(probe_job.light, p, vec3<f32>(0.0), u.xyz);
            o0 = vec4<f32>(s.wi, s.pdf);
            if (s.pdf > 0.0) {
                let y = p + s.dist * s.wi;
                // A convex lamp's pdf is its faces': the face the sample aimed at (any face inside the inner cone).
                var li = probe_job.light;
                if (lights[li].kind == LIGHT_CONVEX_LAMP) { li = scene_tri_light(s.prim & PRIM_INDEX_MASK); }
                o1 = vec4<f32>(light_pdf_li(li, light_measure(li, p), p, vec3<f32>(0.0), s.wi, y, probe_light_normal(li, y)), s.dist, luminance(s.radiance), 0.0);
            }
        }
        case R_BSDF: {
            let s = bsdf_sample(probe_bsdf(), p, u.z, u.xy);
            o0 = vec4<f32>(s.wi, s.pdf);
            if (s.pdf > 0.0) { o1.x = bsdf_pdf(probe_bsdf(), p, s.wi); }
            o1.z = s.f.x;    // f of the sample (red), for the f / eval consistency test
        }
        case R_ENV: {
            // probe_job.a.xyz: the receiver's normal (0: none), which a constant environment is sampled about;
            // probe_job.p.xyz: its position (the guide's slot, under `guided`).
            let s = env_sample(u.xyz, probe_job.p.xyz, probe_job.a.xyz);
            o0 = vec4<f32>(s.wi, s.pdf);
            if (s.pdf > 0.0) {
                o1 = vec4<f32>(env_pdf(s.wi, probe_job.p.xyz, probe_job.a.xyz), 0.0, luminance(s.radiance), 0.0);
            }
        }
        case R_SELECT: {
            let k = select_light(u.x, p, probe_job.a.xyz);
            o0 = vec4<f32>(f32(k.index), k.pmf, 0.0, 0.0);
        }
        case R_SPHERICAL_TRIANGLE: {
            let w = square_to_spherical_triangle(u.xy, p, probe_job.a.xyz, probe_job.b.xyz);
            o0 = vec4<f32>(w, square_to_spherical_triangle_pdf(p, probe_job.a.xyz, probe_job.b.xyz));
        }
        case R_SPHERICAL_RECT: {
            let r = spherical_rect_setup(probe_job.p.x, probe_job.p.y, probe_job.p.z, probe_job.p.w, probe_job.a.x);
            let xy = square_to_spherical_rectangle(u.xy, r);
            o0 = vec4<f32>(xy, r.h, square_to_spherical_rectangle_pdf(r));
        }
        default: {}
    }
    probe_out[2u * i] = o0;
    probe_out[2u * i + 1u] = o1;
}

/// in[2i] = (direction, inside flag), in[2i+1] = (light point y, 0 or the light found there + 1); out[i].x = the
/// routine's pdf there. The
/// flag carries the support that the pdf function does not see: the cone's rim, whether the ray hits the light.
@compute @workgroup_size(64)
fn probe_pdf(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = probe_index(gid, nwg);
    if (i >= probe_job.count) { return; }
    let w = probe_in[2u * i];
    let y = probe_in[2u * i + 1u].xyz;
    var pdf = 0.0;
    switch (probe_job.routine) {
        case R_UNIFORM_HEMISPHERE: { pdf = square_to_uniform_hemisphere_pdf(w.xyz); }
        case R_COSINE_HEMISPHERE: { pdf = square_to_cosine_hemisphere_pdf(w.xyz); }
        case R_UNIFORM_SPHERE: { pdf = square_to_uniform_sphere_pdf(); }
        case R_CONE: { if (w.w != 0.0) { pdf = square_to_uniform_cone_pdf(probe_job.a.x); } }
        case R_LIGHT: {
            // in[2i+1].w: the light found there where it is not the job's (a convex lamp's face), + 1.
            let found = u32(probe_in[2u * i + 1u].w);
            let li = select(probe_job.light, found - 1u, found > 0u);
            if (w.w != 0.0) { pdf = light_pdf_li(li, light_measure(li, probe_job.p.xyz), probe_job.p.xyz, vec3<f32>(0.0), w.xyz, y, probe_light_normal(li, y)); }
        }
        case R_BSDF: {
            pdf = bsdf_pdf(probe_bsdf(), probe_job.p.xyz, w.xyz);
            // f(wo, w) and f(w, wo) (red), for the reciprocity test.
            probe_out[i] = vec4<f32>(pdf, bsdf_eval(probe_bsdf(), probe_job.p.xyz, w.xyz).x, bsdf_eval(probe_bsdf(), w.xyz, probe_job.p.xyz).x, 0.0);
            return;
        }
        case R_ENV: { pdf = env_pdf(w.xyz, probe_job.p.xyz, probe_job.a.xyz); }
        case R_SELECT: { pdf = light_pmf(u32(w.x), probe_job.p.xyz, probe_job.a.xyz); }
        default: {}
    }
    probe_out[i] = vec4<f32>(pdf, 0.0, 0.0, 0.0);
}
"#;

const R_UNIFORM_HEMISPHERE: u32 = 0;
const R_COSINE_HEMISPHERE: u32 = 1;
const R_UNIFORM_SPHERE: u32 = 2;
const R_CONE: u32 = 3;
const R_LIGHT: u32 = 4;
const R_BSDF: u32 = 5;
const R_ENV: u32 = 6;
const R_SELECT: u32 = 7;
const R_SPHERICAL_TRIANGLE: u32 = 8;
const R_SPHERICAL_RECT: u32 = 9;
const FLAG_STRATIFIED: u32 = 1;
const FLAG_LATTICE: u32 = 2;

/// WGSL `ProbeJob`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct ProbeJob {
    routine: u32,
    count: u32,
    seed: u32,
    light: u32,
    flags: u32,
    grid: u32,
    _pad: [u32; 2],
    p: [f32; 4],
    a: [f32; 4],
    b: [f32; 4],
}

/// The probe module: the render module's files without the integrator, plus the probe kernels.
fn probe_source() -> String {
    let files: Vec<&str> = mislab::render::RENDER_FILES.iter().copied().filter(|f| *f != "integrator.wgsl").collect();
    mislab::render::shaders::compose(&files, PROBE_WGSL)
}

/// Scenes the probes bind as group 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum SceneId {
    Lights = 0,
    EnvPixel = 1,
    Env3x2 = 2,
    EnvHdr = 3,
    ManyLights = 4,
}

/// The probe pipelines (built once: lavapipe compiles for seconds) and the test scenes, in `SceneId` order.
struct Harness {
    ctx: &'static GpuContext,
    pipelines: ScenePipelines,
    scenes: Vec<BoundScene>,
}

fn harness() -> &'static Harness {
    static H: OnceLock<Harness> = OnceLock::new();
    H.get_or_init(Harness::new)
}

impl Harness {
    fn new() -> Harness {
        let ctx = common::gpu();
        let pipelines = ScenePipelines::new(ctx, &probe_source(), &["probe_sample", "probe_pdf"]).unwrap();
        let scenes =
            [lights_scene(), env_scene(pixel_map()), env_scene(map_3x2()), env_scene(hdr_map()), many_lights_scene()]
                .into_iter()
                .map(|s| pipelines.bind(&ctx, GpuScene::upload(&ctx, SceneData::build(&s)).expect("upload")))
                .collect();
        Harness { ctx, pipelines, scenes }
    }

    fn data(&self, id: SceneId) -> &SceneData {
        &self.scenes[id as usize].scene.data
    }

    /// One dispatch of `job.count` invocations; returns `out_len` vec4 of output.
    fn dispatch(
        &self,
        pdf: bool,
        scene: SceneId,
        frame: &GpuFrameParams,
        job: &ProbeJob,
        input: &[[f32; 4]],
        out_len: usize,
    ) -> Vec<[f32; 4]> {
        let entry = if pdf { "probe_pdf" } else { "probe_sample" };
        let bytes = self
            .pipelines
            .dispatch(
                &self.ctx,
                entry,
                &self.scenes[scene as usize],
                frame,
                bytemuck::bytes_of(job),
                bytemuck::cast_slice(input),
                (out_len * 16) as u64,
                job.count,
            )
            .unwrap_or_else(|e| panic!("{entry}: {e}"));
        bytemuck::pod_collect_to_vec(&bytes)
    }

    /// Runs a sampling routine: per sample (output, pdf returned), (pdf function at it, distance, luminance, 0).
    fn sample(&self, s: &Setup, count: u32, flags: u32, grid: u32, seed: u32) -> Vec<[[f32; 4]; 2]> {
        let job = ProbeJob { count, flags, grid, seed, ..s.job };
        let out = self.dispatch(false, s.scene, &s.frame, &job, &[], 2 * count as usize);
        out.chunks_exact(2).map(|c| [c[0], c[1]]).collect()
    }

    /// The routine's pdf at points (direction, flag) / light point, in chunks of at most 2²¹.
    fn pdf(&self, s: &Setup, points: &[[[f32; 4]; 2]]) -> Vec<f64> {
        let mut out = Vec::with_capacity(points.len());
        for chunk in points.chunks(1 << 21) {
            let input: Vec<[f32; 4]> = chunk.iter().flatten().copied().collect();
            let job = ProbeJob { count: chunk.len() as u32, ..s.job };
            out.extend(self.dispatch(true, s.scene, &s.frame, &job, &input, chunk.len()).iter().map(|v| v[0] as f64));
        }
        out
    }
}

/// What one dispatch runs: the scene, the frame uniform and the job (routine and its parameters).
#[derive(Clone)]
struct Setup {
    scene: SceneId,
    frame: GpuFrameParams,
    job: ProbeJob,
}

impl Setup {
    fn new(scene: SceneId, routine: u32) -> Setup {
        let h = harness();
        let d = h.data(scene);
        let frame = GpuFrameParams {
            num_lights: d.selectable_lights() as u32,
            env_light: d.env_light.unwrap_or(INVALID),
            env_width: d.env_size.0,
            env_height: d.env_size.1,
            env_scale: d.env_scale,
            env_rotation: d.env_rotation,
            env_constant: d.env_constant,
            light_sampling: LightSampling::Area.tag(),
            env_sampling: EnvSampling::Importance.tag(),
            light_select: LightSelect::Uniform.tag(),
            ..Default::default()
        };
        Setup { scene, frame, job: ProbeJob { routine, seed: 1 + routine * 7919, ..Default::default() } }
    }
}

fn v4(v: DVec3, w: f64) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w as f32]
}
fn d3(v: &[f32; 4]) -> DVec3 {
    DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64)
}
fn f32v(v: DVec3) -> DVec3 {
    v.as_vec3().as_dvec3()
}

// ---------------------------------------------------------------------------------------------------------------
// Test scenes

/// An orthonormal frame (x, y, normal) tilted away from the axes.
fn tilted_frame(yaw: f64, pitch: f64) -> [DVec3; 3] {
    let n = DVec3::new(pitch.sin() * yaw.cos(), pitch.cos(), pitch.sin() * yaw.sin()).normalize();
    let x = n.cross(DVec3::new(0.3, 0.1, 1.0)).normalize();
    [x, n.cross(x), n]
}

const TRI_ORIGIN: DVec3 = DVec3::new(0.5, 1.0, -0.7);
const TRI_2D: [[f64; 2]; 3] = [[0.0, 0.0], [1.0, 0.0], [0.3, 0.8]];
const RECT_ORIGIN: DVec3 = DVec3::new(-1.5, 0.25, 2.0);
const RECT_SIZE: [f64; 2] = [1.2, 0.7];
const PARA_ORIGIN: DVec3 = DVec3::new(3.0, -1.0, 0.5);
const SPHERE_C: DVec3 = DVec3::new(-2.0, 3.0, -1.0);
const SPHERE_R: f32 = 0.5;
const TINY_C: DVec3 = DVec3::new(2.0, -3.0, 1.5);
const TINY_R: f32 = 1e-3;

fn tri_frame() -> [DVec3; 3] {
    tilted_frame(0.4, 0.9)
}
fn rect_frame() -> [DVec3; 3] {
    tilted_frame(2.1, 0.5)
}
/// Triangle vertices as stored (f32).
fn tri_verts() -> [DVec3; 3] {
    let [x, y, _] = tri_frame();
    TRI_2D.map(|[s, t]| f32v(TRI_ORIGIN + s * x + t * y))
}
/// Rectangle (corner, edge_u, edge_v) as stored; the edges are perpendicular to f32 precision.
fn rect_geom() -> [DVec3; 3] {
    let [x, y, _] = rect_frame();
    [f32v(RECT_ORIGIN), f32v(RECT_SIZE[0] * x), f32v(RECT_SIZE[1] * y)]
}
fn para_geom() -> [DVec3; 3] {
    let [x, y, _] = tilted_frame(-0.7, 1.2);
    [f32v(PARA_ORIGIN), f32v(0.9 * x), f32v(0.4 * x + 0.8 * y)]
}

/// Lights: a triangle, a rectangle, a parallelogram (all L = 1 except the parallelogram), a sphere (L = 1), a
/// tiny sphere, a bright sphere and a point light (for power-proportional selection).
/// A convex lamp (src/accel/convex_lamps.rs): a 6 × 12 UV sphere, coarse enough that its rim, outside the inner
/// sphere's cone, is 13 % of its silhouette.
const LAMP_C: Vec3 = Vec3::new(6.0, 1.0, 0.0);
const LAMP_R: f32 = 0.5;
fn lamp_tris() -> Vec<[Vec3; 3]> {
    common::uv_sphere(LAMP_C, LAMP_R, 6, 12, true)
}

fn lights_scene() -> Scene {
    let t = tri_verts();
    let [rc, ru, rv] = rect_geom();
    let [pc, pu, pv] = para_geom();
    let v = |d: DVec3| d.as_vec3();
    Scene {
        name: "sampling-lights".into(),
        materials: vec![
            Material::emitter("L1", Vec3::ONE),
            Material::emitter("warm", Vec3::new(5.0, 3.0, 1.0)),
            Material::emitter("dim", Vec3::splat(0.2)),
        ],
        meshes: vec![
            Mesh {
                name: "tri".into(),
                positions: t.iter().map(|&p| v(p)).collect(),
                indices: vec![[0, 1, 2]],
                material: 0,
                ..Default::default()
            },
            Mesh {
                name: "lamp".into(),
                positions: lamp_tris().iter().flatten().copied().collect(),
                indices: (0..lamp_tris().len() as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect(),
                material: 1,
                ..Default::default()
            },
        ],
        quads: vec![
            Quad { corner: v(rc), edge_u: v(ru), edge_v: v(rv), material: 0 },
            Quad { corner: v(pc), edge_u: v(pu), edge_v: v(pv), material: 1 },
        ],
        spheres: vec![
            Sphere { center: v(SPHERE_C), radius: SPHERE_R, material: 0 },
            Sphere { center: v(TINY_C), radius: TINY_R, material: 2 },
            Sphere { center: Vec3::new(0.0, -4.0, 0.0), radius: 0.25, material: 1 },
        ],
        punctual_lights: vec![PunctualLight::Point { position: Vec3::new(0.0, 5.0, 0.0), intensity: Vec3::splat(3.0) }],
        ..Default::default()
    }
}

/// 1200 small emissive triangles of varied power and orientation over a 20 × 20 floor, a sphere, a spot, a
/// directional light and a constant sky: the light tree's test scene (infinite lights outside the tree).
fn many_lights_scene() -> Scene {
    let mut materials = Vec::new();
    let mut meshes = Vec::new();
    for i in 0..1200 {
        let f = i as f32;
        let c = Vec3::new(
            (f * 0.618_034).fract() * 20.0 - 10.0,
            0.2 + (f * 0.414_214).fract() * 3.0,
            (f * 0.732_051).fract() * 20.0 - 10.0,
        );
        let n = Vec3::new((f * 1.3).sin(), (f * 0.7).cos(), (f * 2.1).cos()).normalize();
        let t = n.any_orthonormal_vector();
        let b = n.cross(t);
        let size = 0.05 + 0.1 * (f * 0.27).fract();
        if i % 40 == 0 {
            materials.push(Material::emitter(&format!("e{i}"), Vec3::splat(0.1 + 20.0 * (f * 0.37).fract())));
        }
        meshes.push(Mesh {
            name: format!("t{i}"),
            positions: vec![c, c + size * t, c + size * b],
            indices: vec![[0, 1, 2]],
            material: (i / 40) as u32,
            ..Default::default()
        });
    }
    Scene {
        name: "sampling-many-lights".into(),
        spheres: vec![Sphere { center: Vec3::new(3.0, 2.0, -2.0), radius: 0.3, material: 0 }],
        materials,
        meshes,
        punctual_lights: vec![
            PunctualLight::Spot {
                position: Vec3::new(-4.0, 4.0, 1.0),
                direction: Vec3::new(0.3, -1.0, 0.1),
                intensity: Vec3::splat(40.0),
                inner_cone: 0.3,
                outer_cone: 0.5,
            },
            PunctualLight::Directional { direction: Vec3::new(0.2, -1.0, 0.3), irradiance: Vec3::splat(0.5) },
        ],
        environment: Environment::Constant(Vec3::splat(0.05)),
        ..Default::default()
    }
}

fn env_scene(map: EnvMap) -> Scene {
    let rotation = if map.width == 20 { 0.3 } else { 0.0 };
    Scene {
        name: "sampling-env".into(),
        environment: Environment::Map { map: std::sync::Arc::new(map), scale: 1.0, rotation },
        ..Default::default()
    }
}

/// 20×10, black but for texel (7, 2).
fn pixel_map() -> EnvMap {
    let mut texels = vec![[0.0f32; 3]; 200];
    texels[2 * 20 + 7] = [50.0, 40.0, 30.0];
    EnvMap { path: "pixel".into(), width: 20, height: 10, texels }
}

/// 3×2 with a 1:1000 range and one black texel.
fn map_3x2() -> EnvMap {
    let texels =
        vec![[1.0, 1.0, 1.0], [0.0, 0.0, 0.0], [10.0, 2.0, 0.5], [0.01, 0.02, 0.01], [3.0, 3.0, 3.0], [0.5, 0.1, 0.9]];
    EnvMap { path: "3x2".into(), width: 3, height: 2, texels }
}

const HDR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/testdata/env/hdr/noon_grass_1k.hdr");

fn hdr_map() -> EnvMap {
    mislab::scene::envmap::load_envmap(std::path::Path::new(HDR)).unwrap_or_else(|e| panic!("{HDR}: {e}")).0
}

/// Index in the light table of the light of `kind` with primitive index `prim`.
fn light_index(kind: u32, prim: u32) -> u32 {
    let d = harness().data(SceneId::Lights);
    d.lights.iter().position(|l| l.kind == kind && l.prim == prim).unwrap_or_else(|| panic!("no light {kind}/{prim}"))
        as u32
}

// ---------------------------------------------------------------------------------------------------------------
// f64 geometry (the ground truth of where a direction hits a light)

fn hit_triangle(p: DVec3, w: DVec3, v: &[DVec3; 3]) -> Option<DVec3> {
    let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
    let n = e1.cross(e2);
    let denom = w.dot(n);
    if denom == 0.0 {
        return None;
    }
    let t = (v[0] - p).dot(n) / denom;
    if !(t > 0.0) {
        return None;
    }
    let y = p + t * w;
    let nn = n.dot(n);
    let b1 = (y - v[0]).cross(e2).dot(n) / nn;
    let b2 = e1.cross(y - v[0]).dot(n) / nn;
    (b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0).then_some(y)
}

fn hit_parallelogram(p: DVec3, w: DVec3, g: &[DVec3; 3]) -> Option<DVec3> {
    let [c, u, v] = *g;
    let n = u.cross(v);
    let denom = w.dot(n);
    if denom == 0.0 {
        return None;
    }
    let t = (c - p).dot(n) / denom;
    if !(t > 0.0) {
        return None;
    }
    let y = p + t * w;
    let nn = n.dot(n);
    let s = (y - c).cross(v).dot(n) / nn;
    let r = u.cross(y - c).dot(n) / nn;
    ((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&r)).then_some(y)
}

fn hit_sphere(p: DVec3, w: DVec3, c: DVec3, r: f64) -> Option<DVec3> {
    let f = p - c;
    let b = -f.dot(w);
    let l = f + b * w;
    let disc = r * r - l.length_squared();
    if !(disc >= 0.0) || b <= 0.0 {
        return None;
    }
    let q = b + disc.sqrt();
    let t = (f.length_squared() - r * r) / q;
    (t > 0.0).then_some(p + t * w)
}

/// Lambert's formula for the irradiance (L = 1) at p with normal n from a polygon wholly above p's horizon:
/// E = ½ |Σ Θᵢ n·ĝᵢ|, Θᵢ the angle between vᵢ and vᵢ₊₁ (relative to p), ĝᵢ = normalize(vᵢ × vᵢ₊₁).
fn polygon_irradiance(p: DVec3, n: DVec3, verts: &[DVec3]) -> f64 {
    let mut sum = 0.0;
    for i in 0..verts.len() {
        let a = verts[i] - p;
        let b = verts[(i + 1) % verts.len()] - p;
        let c = a.cross(b);
        let theta = c.length().atan2(a.dot(b));
        sum += theta * n.dot(c.normalize());
    }
    0.5 * sum.abs()
}

// ---------------------------------------------------------------------------------------------------------------
// Chi-square cases

/// The domain a case is binned in.
enum Dom {
    Cap(SphereCap),
    Env(Equirect),
    Window(PlaneWindow),
}

/// One chi-square test.
struct Case {
    name: String,
    config: String,
    setup: Setup,
    dom: Dom,
    may_fail: bool,
    refine: Option<Quadrature>,
    base: Quadrature,
    /// Converts a returned sample (direction, distance) to the domain's sample (default: the direction).
    to_domain: Option<Box<dyn Fn(DVec3, f64) -> Option<DVec3> + Sync>>,
    /// The pdf input at a domain point: (direction, flag), light point, and a Jacobian factor (measure change).
    pdf_input: Box<dyn Fn(DVec3) -> ([[f32; 4]; 2], f64) + Sync>,
    /// (relative tolerance, allowed fraction of outliers) of returned pdf vs pdf function at the sample.
    pdf_match: (f64, f64),
}

/// A seed per case (FNV-1a of its name and configuration): the tests of the family use independent samples.
fn case_seed(name: &str, config: &str) -> u32 {
    let mut h: u32 = 0x811c_9dc5;
    for b in name.bytes().chain(config.bytes()) {
        h = (h ^ b as u32).wrapping_mul(0x0100_0193);
    }
    h
}

impl Case {
    fn new(name: &str, config: String, mut setup: Setup, dom: Dom) -> Case {
        setup.job.seed = case_seed(name, &config);
        Case {
            name: name.into(),
            config,
            setup,
            dom,
            may_fail: false,
            refine: Some(Quadrature { sub: 12, gauss: 2 }),
            base: Quadrature { sub: 1, gauss: 4 },
            to_domain: None,
            pdf_input: Box::new(|w| ([v4(w, 1.0), [0.0; 4]], 1.0)),
            pdf_match: (PDF_MATCH, PDF_MATCH_OUTLIERS),
        }
    }
}

/// A row of the report table.
struct Row {
    report: Chi2Report,
    config: String,
    /// Largest relative difference between the returned pdf and the pdf function at the sample.
    pdf_mismatch: f64,
    /// Fraction of samples whose difference exceeds the case's tolerance.
    pdf_outliers: f64,
    /// That tolerance and the fraction allowed.
    pdf_match: (f64, f64),
    seconds: f64,
}

fn run_case(c: &Case) -> Row {
    let h = harness();
    let t0 = std::time::Instant::now();
    let out = h.sample(&c.setup, N, 0, 1, c.setup.job.seed);
    let mut mismatch: f64 = 0.0;
    let mut outliers = 0usize;
    let samples: Vec<Option<DVec3>> = out
        .iter()
        .map(|[a, b]| {
            let pdf = a[3] as f64;
            if !(pdf > 0.0) {
                return None;
            }
            let m = ((b[0] as f64 - pdf) / pdf).abs();
            mismatch = mismatch.max(m);
            outliers += !(m <= c.pdf_match.0) as usize;
            let w = d3(a).normalize();
            match &c.to_domain {
                Some(f) => f(w, b[1] as f64),
                None => Some(w),
            }
        })
        .collect();
    let mut options =
        Chi2Options { may_fail: c.may_fail, alpha: alpha(), base: c.base, refine: c.refine, ..Default::default() };
    let mut pdf = |pts: &[DVec3]| -> Vec<f64> {
        let (inputs, jac): (Vec<[[f32; 4]; 2]>, Vec<f64>) = pts.iter().map(|&w| (c.pdf_input)(w)).unzip();
        h.pdf(&c.setup, &inputs).iter().zip(jac).map(|(p, j)| p * j).collect()
    };
    let report = match &c.dom {
        Dom::Cap(d) => {
            options.rest_grid = (50, 100);
            Chi2Test { name: c.name.clone(), domain: d, options }.run(&samples, &mut pdf)
        }
        Dom::Env(d) => Chi2Test { name: c.name.clone(), domain: d, options }.run(&samples, &mut pdf),
        Dom::Window(d) => Chi2Test { name: c.name.clone(), domain: d, options }.run(&samples, &mut pdf),
    };
    Row {
        report,
        config: c.config.clone(),
        pdf_mismatch: mismatch,
        pdf_outliers: outliers as f64 / N as f64,
        pdf_match: c.pdf_match,
        seconds: t0.elapsed().as_secs_f64(),
    }
}

/// Runs cases, prints and records their rows, and asserts they all passed.
fn run_all(group: &str, cases: &[Case]) {
    let mut rows = Vec::new();
    for c in cases {
        let row = run_case(c);
        eprintln!(
            "{}  [{} ; pdf mismatch max {:.1e}, > {:.0e} for {:.1e}; {:.1} s]",
            row.report.summary(),
            row.config,
            row.pdf_mismatch,
            row.pdf_match.0,
            row.pdf_outliers,
            row.seconds
        );
        rows.push(row);
    }
    record(group, &rows);
    let failed: Vec<String> = rows
        .iter()
        .filter(|r| !r.report.passed() || !(r.pdf_outliers <= r.pdf_match.1))
        .map(|r| {
            format!("{} (pdf mismatch max {:.2e}, outliers {:.1e})", r.report.summary(), r.pdf_mismatch, r.pdf_outliers)
        })
        .collect();
    assert!(failed.is_empty(), "{} of {} {group} tests failed:\n{}", failed.len(), rows.len(), failed.join("\n"));
}

/// Appends the rows as a markdown table to `$CARGO_TARGET_TMPDIR/sampling-report.md` (docs/sampling.md copies it).
fn record(group: &str, rows: &[Row]) {
    use std::io::Write;
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("sampling-{group}.md"));
    let mut s = String::from("| routine | configuration | samples | failed | bins | pooled | X² | dof | p | ∫pdf | pdf match (max; outliers) |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
    for r in rows {
        let p = &r.report.pearson;
        s += &format!(
            "| {} | {} | {} | {} | {} ({}) | {} | {:.1} | {} | {:.3} | {:.5} | {:.0e}; {:.0e} > {:.0e} |\n",
            r.report.name,
            r.config,
            r.report.samples,
            r.report.failed,
            r.report.cells,
            r.report.domain,
            p.pooled_cells,
            p.statistic,
            p.dof,
            p.p_value,
            r.report.integral,
            r.pdf_mismatch,
            r.pdf_outliers,
            r.pdf_match.0
        );
    }
    if let Ok(mut f) = std::fs::File::create(&path) {
        let _ = f.write_all(s.as_bytes());
    }
}

fn deg(x: f64) -> f64 {
    x.to_radians()
}

// ---------------------------------------------------------------------------------------------------------------
// Warps

fn warp_cases() -> Vec<Case> {
    let z = DVec3::Z;
    let mut v = vec![
        Case::new(
            "uniform hemisphere",
            "sphere around n".into(),
            Setup::new(SceneId::Lights, R_UNIFORM_HEMISPHERE),
            Dom::Cap(SphereCap::sphere(z, GRID)),
        ),
        Case::new(
            "cosine hemisphere",
            "sphere around n".into(),
            Setup::new(SceneId::Lights, R_COSINE_HEMISPHERE),
            Dom::Cap(SphereCap::sphere(z, GRID)),
        ),
        Case::new(
            "uniform sphere",
            "sphere".into(),
            Setup::new(SceneId::Lights, R_UNIFORM_SPHERE),
            Dom::Cap(SphereCap::sphere(z, GRID)),
        ),
    ];
    for theta in [deg(30.0), deg(120.0)] {
        let omc = 1.0 - theta.cos();
        let mut s = Setup::new(SceneId::Lights, R_CONE);
        s.job.a[0] = omc as f32;
        let omc32 = s.job.a[0] as f64;
        let mut c = Case::new(
            "uniform cone",
            format!("θmax = {:.0}°", theta.to_degrees()),
            s,
            Dom::Cap(SphereCap::cap(z, (omc32 / 0.505).min(2.0), GRID)),
        );
        // The pdf function has no direction argument: the support (1 − cosθ ≤ 1 − cosθmax) comes from here.
        c.pdf_input = Box::new(move |w| {
            let o = if w.z > 0.0 { (w.x * w.x + w.y * w.y) / (1.0 + w.z) } else { 1.0 - w.z };
            ([v4(w, (o <= omc32) as u32 as f64), [0.0; 4]], 1.0)
        });
        v.push(c);
    }
    v
}

#[test]
fn chi2_warps() {
    run_all("warps", &warp_cases());
}

// ---------------------------------------------------------------------------------------------------------------
// Lights

/// Where a light is, for the cases: its kind, primitive, f64 geometry.
#[derive(Clone, Copy)]
enum LightGeom {
    Triangle([DVec3; 3]),
    Quad([DVec3; 3]),
    Sphere(DVec3, f64),
}

impl LightGeom {
    fn hit(&self, p: DVec3, w: DVec3) -> Option<DVec3> {
        match self {
            LightGeom::Triangle(v) => hit_triangle(p, w, v),
            LightGeom::Quad(g) => hit_parallelogram(p, w, g),
            LightGeom::Sphere(c, r) => hit_sphere(p, w, *c, *r),
        }
    }
    /// Corners (polygons).
    fn verts(&self) -> Vec<DVec3> {
        match self {
            LightGeom::Triangle(v) => v.to_vec(),
            LightGeom::Quad([c, u, v]) => vec![*c, *c + *u, *c + *u + *v, *c + *v],
            LightGeom::Sphere(..) => vec![],
        }
    }
    /// A window of the polygon's plane: its bounding box along its first edge and the in-plane perpendicular,
    /// grown by 10 % on every side (so samples rounded across an edge still land in a cell the pdf reaches).
    fn window(&self, p: DVec3) -> PlaneWindow {
        let vs = self.verts();
        let x = (vs[1] - vs[0]).normalize();
        let n = (vs[1] - vs[0]).cross(vs[vs.len() - 1] - vs[0]).normalize();
        let y = n.cross(x);
        let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
        for v in &vs {
            let q = [(*v - vs[0]).dot(x), (*v - vs[0]).dot(y)];
            for k in 0..2 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
        }
        let m = [0.1 * (hi[0] - lo[0]), 0.1 * (hi[1] - lo[1])];
        PlaneWindow {
            p,
            origin: vs[0] + (lo[0] - m[0]) * x + (lo[1] - m[1]) * y,
            e1: (hi[0] - lo[0] + 2.0 * m[0]) * x,
            e2: (hi[1] - lo[1] + 2.0 * m[1]) * y,
            grid: GRID,
        }
    }
    /// A cap around the light as seen from p: axis, and 1 − cos of an angle enclosing it (with margin, the rim
    /// placed between rows).
    fn cap(&self, p: DVec3) -> SphereCap {
        match self {
            LightGeom::Sphere(c, r) => {
                let d2 = (*c - p).length_squared();
                let sin2 = r * r / d2;
                let omc = sin2 / (1.0 + (1.0 - sin2).sqrt());
                SphereCap::cap(*c - p, (omc / 0.505).min(2.0), GRID)
            }
            _ => {
                let vs = self.verts();
                let axis = vs.iter().map(|&v| (v - p).normalize()).sum::<DVec3>().normalize();
                let max_angle = vs.iter().map(|&v| (v - p).normalize().angle_between(axis)).fold(0.0, f64::max);
                SphereCap::cap_angle(axis, (max_angle * 1.13 + 1e-3).min(PI), GRID)
            }
        }
    }
}

fn tri_geom() -> LightGeom {
    LightGeom::Triangle(tri_verts())
}
fn rect_light() -> LightGeom {
    LightGeom::Quad(rect_geom())
}
fn para_light() -> LightGeom {
    LightGeom::Quad(para_geom())
}

/// A point in a light's local frame (s, t along its plane, h along its front normal), rounded to f32.
fn local_point(origin: DVec3, frame: [DVec3; 3], s: f64, t: f64, h: f64) -> DVec3 {
    f32v(origin + s * frame[0] + t * frame[1] + h * frame[2])
}

fn light_case(name: &str, config: &str, light: u32, geom: LightGeom, p: DVec3, mode: LightSampling) -> Case {
    let mut s = Setup::new(SceneId::Lights, R_LIGHT);
    s.job.light = light;
    s.job.p = v4(p, 0.0);
    s.frame.light_sampling = mode.tag();
    // Polygons: directions through a window of the light's plane around it (cells scale with the light, however
    // thin it looks from p); spheres: a cap around the cone.
    let dom = match geom {
        LightGeom::Sphere(..) => Dom::Cap(geom.cap(p)),
        _ => Dom::Window(geom.window(p)),
    };
    let mut c = Case::new(name, format!("{config}, {mode}"), s, dom);
    c.pdf_input = Box::new(move |w| match geom.hit(p, w) {
        Some(y) => ([v4(w, 1.0), v4(y, 0.0)], 1.0),
        None => ([v4(w, 0.0), [0.0; 4]], 1.0),
    });
    c
}

/// Solid angle of the triangle / quad / sphere from p (f64).
fn solid_angle(geom: &LightGeom, p: DVec3) -> f64 {
    let tri = |a: DVec3, b: DVec3, c: DVec3| {
        let (a, b, c) = (a - p, b - p, c - p);
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let det = a.dot((b - a).cross(c - a));
        2.0 * det.abs().atan2(la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb)
    };
    match geom {
        LightGeom::Triangle(v) => tri(v[0], v[1], v[2]),
        LightGeom::Quad(_) => {
            let v = geom.verts();
            tri(v[0], v[1], v[2]) + tri(v[0], v[2], v[3])
        }
        LightGeom::Sphere(c, r) => {
            let sin2 = r * r / (*c - p).length_squared();
            2.0 * PI * sin2 / (1.0 + (1.0 - sin2).sqrt())
        }
    }
}

/// Shading points of the polygon cases, in the light's local frame (s, t, height).
const TRI_POINTS: [(&str, [f64; 3]); 4] = [
    ("moderate", [0.4, 0.3, 1.5]),
    ("close", [0.45, 0.3, 0.1]),
    ("grazing", [2.5, 0.4, 0.08]),
    ("tiny", [0.4, 0.3, 300.0]),
];
const RECT_POINTS: [(&str, [f64; 3]); 4] = [
    ("moderate", [0.5, 0.2, 1.3]),
    ("close", [0.6, 0.35, 0.15]),
    ("grazing", [3.0, 0.35, 0.05]),
    ("grazing-y", [0.6, -2.5, 0.02]),
];

fn light_cases() -> Vec<Case> {
    let mut v = Vec::new();
    let tri = light_index(LIGHT_TRIANGLE, 0);
    for (name, [s, t, hgt]) in TRI_POINTS {
        let p = local_point(TRI_ORIGIN, tri_frame(), s, t, hgt);
        let cfg = format!("{name}, Ω = {:.2e} sr", solid_angle(&tri_geom(), p));
        v.push(light_case("triangle by area", &cfg, tri, tri_geom(), p, LightSampling::Area));
        v.push(light_case("spherical triangle", &cfg, tri, tri_geom(), p, LightSampling::SolidAngle));
    }
    let rect = light_index(LIGHT_QUAD, 0);
    for (name, [s, t, hgt]) in RECT_POINTS {
        let p = local_point(RECT_ORIGIN, rect_frame(), s, t, hgt);
        let cfg = format!("{name}, Ω = {:.2e} sr", solid_angle(&rect_light(), p));
        v.push(light_case("quad by area", &cfg, rect, rect_light(), p, LightSampling::Area));
        v.push(light_case("spherical rectangle", &cfg, rect, rect_light(), p, LightSampling::SolidAngle));
    }
    let para = light_index(LIGHT_QUAD, 1);
    let [pc, pu, pv] = para_geom();
    let p = f32v(pc + 0.5 * pu + 0.5 * pv + 0.9 * pu.cross(pv).normalize());
    let cfg = format!("parallelogram, Ω = {:.2e} sr", solid_angle(&para_light(), p));
    v.push(light_case("quad by area", &cfg, para, para_light(), p, LightSampling::Area));
    v.push(light_case("quad (not a rectangle)", &cfg, para, para_light(), p, LightSampling::SolidAngle));

    // Spheres: the cone (solid angle) in direction space; area sampling over the sphere's normals, where its pdf
    // is smooth (in direction space it has a 1/√ singularity at the silhouette).
    let sphere = light_index(LIGHT_SPHERE, 0);
    let tiny = light_index(LIGHT_SPHERE, 1);
    let big = LightGeom::Sphere(f32v(SPHERE_C), SPHERE_R as f64);
    let small = LightGeom::Sphere(f32v(TINY_C), TINY_R as f64);
    let tiny_p = f32v(TINY_C + DVec3::new(0.3, 0.5, -0.8).normalize() * (TINY_R as f64 * (PI / 1e-6).sqrt()));
    let cases = [
        ("sphere", sphere, big, f32v(SPHERE_C + DVec3::new(1.0, -0.5, 0.7).normalize() * 2.0), "d = 4r"),
        ("sphere", sphere, big, f32v(SPHERE_C + DVec3::new(-0.2, 0.5, 0.7).normalize() * 0.55), "d = 1.1r"),
        ("sphere (tiny)", tiny, small, tiny_p, "tiny"),
    ];
    for (name, index, geom, p, what) in cases {
        let cfg = format!("{what}, Ω = {:.2e} sr", solid_angle(&geom, p));
        v.push(light_case(&format!("{name} cone"), &cfg, index, geom, p, LightSampling::SolidAngle));
        v.push(sphere_area_case(&format!("{name} by area"), &cfg, index, geom, p));
    }
    v
}

/// Area sampling of a sphere, binned over the normal at the sampled point (cap around the direction to p).
fn sphere_area_case(name: &str, config: &str, light: u32, geom: LightGeom, p: DVec3) -> Case {
    let LightGeom::Sphere(c, r) = geom else { unreachable!() };
    let mut case = light_case(name, config, light, geom, p, LightSampling::Area);
    case.dom = Dom::Cap(SphereCap::sphere(p - c, GRID));
    case.may_fail = true;
    // pdf ∝ 1/cos_l, and the pdf function rebuilds the normal from the f32 point y = p + dist·wi: its relative
    // error is ~ε|y| / (r cos_l), 2e-4/cos_l for the tiny sphere (r = 1e-3 at |y| ≈ 3), 4e-7/cos_l for r = 0.5.
    case.pdf_match = if r < 0.01 { (1e-2, 0.05) } else { (PDF_MATCH, 2e-3) };
    case.to_domain = Some(Box::new(move |w, dist| Some(((p + dist * w) - c).normalize())));
    // pdf over the normals: pdf_ω · dω/dA · dA/dn = pdf_ω · cos_l / d² · r²; the far side gets 0.
    case.pdf_input = Box::new(move |n| {
        let y = c + r * n;
        let v = y - p;
        let d2 = v.length_squared();
        let w = v / d2.sqrt();
        let cos_l = -w.dot(n);
        if !(cos_l > 0.0) {
            return ([v4(w, 0.0), [0.0; 4]], 0.0);
        }
        ([v4(w, 1.0), v4(y, 0.0)], cos_l / d2 * r * r)
    });
    case
}

/// The convex lamp's faces as the device holds them: each face's light index and vertices.
fn lamp_faces() -> (u32, Vec<(u32, [DVec3; 3])>) {
    let d = harness().data(SceneId::Lights);
    let lamp = d.lights.iter().position(|l| l.kind == LIGHT_CONVEX_LAMP).expect("the sampling scene has a lamp");
    let (first, n) = (d.lights[lamp].prim as usize, d.lights[lamp].area as usize);
    let faces = (first..first + n)
        .map(|i| {
            let t = d.lights[i].prim as usize;
            (i as u32, std::array::from_fn(|k| d3(&d.tri_verts[3 * t + k])))
        })
        .collect();
    (lamp as u32, faces)
}

/// The first face a ray from p along w meets, from the front: the point and the face's light.
fn lamp_hit(faces: &[(u32, [DVec3; 3])], p: DVec3, w: DVec3) -> Option<(DVec3, u32)> {
    faces
        .iter()
        .filter(|(_, v)| (v[1] - v[0]).cross(v[2] - v[0]).dot(w) < 0.0)
        .filter_map(|(i, v)| hit_triangle(p, w, v).map(|y| (y, *i)))
        .min_by(|a, b| (a.0 - p).length().total_cmp(&(b.0 - p).length()))
}

/// A convex lamp seen from p, binned in a cap around the sphere its vertices lie on: the pdf function is asked
/// at the face each direction meets first.
fn lamp_case(config: &str, p: DVec3, mode: LightSampling) -> Case {
    let (lamp, faces) = lamp_faces();
    let mut s = Setup::new(SceneId::Lights, R_LIGHT);
    s.job.light = lamp;
    s.job.p = v4(p, 0.0);
    s.frame.light_sampling = mode.tag();
    let dom = Dom::Cap(LightGeom::Sphere(LAMP_C.as_dvec3(), LAMP_R as f64).cap(p));
    let mut c = Case::new("convex lamp", format!("{config}, {mode}"), s, dom);
    // Rim draws inside the cone and faces seen from behind are failed samples: the pdf integrates to the rest.
    c.may_fail = true;
    c.pdf_input = Box::new(move |w| match lamp_hit(&faces, p, w) {
        Some((y, face)) => ([v4(w, 1.0), v4(y, (face + 1) as f64)], 1.0),
        None => ([v4(w, 0.0), [0.0; 4]], 1.0),
    });
    c
}

#[test]
fn chi2_lights() {
    run_all("lights", &light_cases());
}

/// A convex lamp's two parts — the inner sphere's cone and the rim drawn by faces — against the density its faces
/// report, from far and from close by, and by area (every sample a face).
#[test]
fn chi2_convex_lamp() {
    let c = LAMP_C.as_dvec3();
    let r = LAMP_R as f64;
    let far = f32v(c + DVec3::new(-1.0, 0.4, 0.6).normalize() * 4.0 * r);
    let near = f32v(c + DVec3::new(0.3, -1.0, 0.5).normalize() * 1.3 * r);
    run_all(
        "convex lamp",
        &[
            lamp_case("d = 4r", far, LightSampling::SolidAngle),
            lamp_case("d = 1.3r", near, LightSampling::SolidAngle),
            lamp_case("d = 4r", far, LightSampling::Area),
        ],
    );
}

/// Back faces of one-sided emitters: no sample, pdf 0, in both modes.
#[test]
fn one_sided_emitters() {
    let h = harness();
    for (light, geom, p) in [
        (light_index(LIGHT_TRIANGLE, 0), tri_geom(), local_point(TRI_ORIGIN, tri_frame(), 0.4, 0.3, -1.0)),
        (light_index(LIGHT_QUAD, 0), rect_light(), local_point(RECT_ORIGIN, rect_frame(), 0.5, 0.2, -0.7)),
    ] {
        for mode in [LightSampling::Area, LightSampling::SolidAngle] {
            let c = light_case("back", "back", light, geom, p, mode);
            let out = h.sample(&c.setup, 4096, 0, 1, 5);
            assert!(out.iter().all(|[a, _]| a[3] == 0.0), "{mode}: a point behind light {light} got samples");
            // The pdf at directions that do hit the light (from behind) is 0.
            let vs = geom.verts();
            let centre = vs.iter().sum::<DVec3>() / vs.len() as f64;
            let w = (centre - p).normalize();
            let y = geom.hit(p, w).expect("the centre direction hits");
            let pdf = h.pdf(&c.setup, &[[v4(w, 1.0), v4(y, 0.0)]]);
            assert_eq!(pdf[0], 0.0, "{mode}: pdf from behind light {light}");
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
// BSDF

fn bsdf_case(
    name: &str,
    config: String,
    wo: DVec3,
    base: [f32; 3],
    metallic: f32,
    alpha: f32,
    specular: f32,
    dom: Dom,
) -> Case {
    let mut s = Setup::new(SceneId::Lights, R_BSDF);
    s.job.p = v4(wo, 0.0);
    s.job.a = [alpha, specular, 0.0, 0.0];
    s.job.b = [base[0], base[1], base[2], metallic];
    let mut c = Case::new(name, config, s, dom);
    c.may_fail = true;
    c.base = Quadrature { sub: 1, gauss: 6 };
    c
}

/// A GGX case binned over the half vector h = normalize(wo + wi) in a cap around the normal: at grazing incidence
/// the reflected lobe is 2α wide in the plane of incidence but only 2α·cosθo across it (under a bin for α = 0.01),
/// while the visible normals stay a round cap of width ~α. The pdf over h is bsdf_pdf(wi(h)) · 4 (wo·h).
fn ggx_half_vector_case(name: &str, config: String, wo: DVec3, alpha: f32, cap: f64) -> Case {
    // The cap's pole (where cells are thin wedges) is moved off the normal towards wo, so that the edge of the
    // support (wo·h = 0, wi.z = 0), which passes within ~α of the normal at grazing incidence, crosses rows.
    let side = DVec3::new(wo.x, wo.y, 0.0).normalize_or_zero();
    let axis = (DVec3::Z + 0.5 * (alpha as f64).min(0.6) * side).normalize();
    let dom = if cap >= PI {
        Dom::Cap(SphereCap::sphere(axis, GRID))
    } else {
        Dom::Cap(SphereCap::cap_angle(axis, cap, GRID))
    };
    let mut c = bsdf_case(name, config, wo, [1.0; 3], 1.0, alpha, 1.0, dom);
    c.to_domain = Some(Box::new(move |wi, _| Some((wo + wi).normalize())));
    c.pdf_input = Box::new(move |h| {
        let c = wo.dot(h);
        if !(c > 0.0) {
            return ([v4(DVec3::Z, 0.0), [0.0; 4]], 0.0);
        }
        (([v4(2.0 * c * h - wo, 1.0), [0.0; 4]]), 4.0 * c)
    });
    c
}

fn bsdf_cases() -> Vec<Case> {
    let mut v = Vec::new();
    for alpha in [0.01f32, 0.1, 0.5, 1.0] {
        for inc in [0.0f64, 30.0, 80.0, 89.0] {
            let t = deg(inc);
            let wo = DVec3::new(t.sin(), 0.0, t.cos());
            let cap = if alpha <= 0.1 { 12.0 * alpha as f64 } else { PI };
            v.push(ggx_half_vector_case("GGX conductor (VNDF)", format!("α = {alpha}, θo = {inc}°"), wo, alpha, cap));
        }
    }
    for (alpha, inc) in [(0.25f32, 30.0f64), (0.25, 75.0), (0.05, 45.0)] {
        let t = deg(inc);
        let wo = DVec3::new(t.sin() * 0.6, t.sin() * 0.8, t.cos());
        v.push(bsdf_case(
            "Lambert + GGX mixture",
            format!("metallic 0.5, specular 1, α = {alpha}, θo = {inc}°"),
            wo,
            [0.8, 0.5, 0.3],
            0.5,
            alpha,
            1.0,
            Dom::Cap(SphereCap::sphere(DVec3::Z, GRID)),
        ));
    }
    v
}

#[test]
fn chi2_bsdf() {
    run_all("bsdf", &bsdf_cases());
}

/// The anisotropic GGX conductor's visible-normal sampling (shaders/bsdf_conductor.wgsl), binned over the sphere of
/// wi, with wo off both frame axes so that the stretch in x and y both matter.
fn conductor_cases() -> Vec<Case> {
    let mut v = Vec::new();
    for (au, av, inc) in [(0.5f32, 0.2f32, 30.0f64), (0.3, 0.8, 75.0), (0.25, 0.5, 45.0), (0.6, 0.6, 60.0)] {
        let t = deg(inc);
        let wo = DVec3::new(t.sin() * 0.6, t.sin() * 0.8, t.cos());
        let mut c = bsdf_case(
            "anisotropic GGX conductor (VNDF)",
            format!("α_u = {au}, α_v = {av}, θo = {inc}°"),
            wo,
            [1.0; 3],
            0.0,
            au,
            0.0,
            Dom::Cap(SphereCap::sphere(DVec3::Z, GRID)),
        );
        c.setup.job.a = [au, 0.0, 1.0, av];
        v.push(c);
    }
    // Beckmann (specular = 1 selects it): h from D(h)·cosθh, so part of the lobe falls below the surface.
    for (au, av, inc) in [(0.4f32, 0.15f32, 50.0f64), (0.3, 0.3, 80.0)] {
        let t = deg(inc);
        let wo = DVec3::new(t.sin() * 0.6, t.sin() * 0.8, t.cos());
        let mut c = bsdf_case(
            "anisotropic Beckmann conductor (D·cos)",
            format!("α_u = {au}, α_v = {av}, θo = {inc}°"),
            wo,
            [1.0; 3],
            0.0,
            au,
            0.0,
            Dom::Cap(SphereCap::sphere(DVec3::Z, GRID)),
        );
        c.setup.job.a = [au, 1.0, 1.0, av];
        v.push(c);
    }
    v
}

#[test]
fn chi2_conductor() {
    run_all("conductor", &conductor_cases());
}

/// The rough dielectric (shaders/bsdf_dielectric.wgsl): visible normals, then reflection or refraction by Fresnel,
/// binned over the whole sphere of wi (both lobes), from outside (η = 1.5) and from inside (η = 1/1.5, where part
/// of the lobe is totally reflected), anisotropic and isotropic.
fn dielectric_cases() -> Vec<Case> {
    let mut v = Vec::new();
    // GGX (visible normals), then Beckmann (specular = 1, Mitsuba's roughdielectric default: wm from D·cos, so some
    // samples face away from wo and fail), from outside and from inside (with total internal reflection).
    for (au, av, inc, eta, beckmann) in [
        (0.3f32, 0.3f32, 30.0f64, 1.5f32, false),
        (0.5, 0.2, 60.0, 1.5, false),
        (0.3, 0.3, 45.0, 1.0 / 1.5, false),
        (0.25, 0.6, 70.0, 1.0 / 1.5, false),
        (0.3, 0.3, 40.0, 1.5, true),
        (0.4, 0.15, 65.0, 1.0 / 1.5, true),
    ] {
        let t = deg(inc);
        let wo = DVec3::new(t.sin() * 0.6, t.sin() * 0.8, t.cos());
        let (name, specular) = if beckmann {
            ("rough Beckmann dielectric (D·cos + Fresnel choice)", 1.0)
        } else {
            ("rough dielectric (VNDF + Fresnel choice)", 0.0)
        };
        let mut c = bsdf_case(
            name,
            format!("α_u = {au}, α_v = {av}, θo = {inc}°, η = {eta:.3}"),
            wo,
            [1.0; 3],
            0.0,
            au,
            specular,
            Dom::Cap(SphereCap::sphere(DVec3::Z, GRID)),
        );
        c.setup.job.a = [au, specular, tag("dielectric") as f32, av];
        c.setup.job.p[3] = eta;
        v.push(c);
    }
    v
}

#[test]
fn chi2_dielectric() {
    run_all("dielectric", &dielectric_cases());
}

/// Diffuse transmission (shaders/bsdf_diffuse_transmission.wgsl): a lobe by its largest channel, cosine on either
/// side, over the whole sphere; wo above and below the surface.
fn diffuse_transmission_cases() -> Vec<Case> {
    let mut v = Vec::new();
    for (r, t, inc) in [(0.8f32, 0.2f32, 30.0f64), (0.3, 0.6, -60.0)] {
        let th = deg(inc);
        let wo = DVec3::new(th.sin().abs() * 0.6, th.sin().abs() * 0.8, th.cos() * inc.signum());
        let mut c = bsdf_case(
            "diffuse transmission",
            format!("R = {r}, T = {t}, wo.z = {:.2}", wo.z),
            wo,
            [r, r * 0.5, r * 0.25],
            t,
            1.0,
            0.0,
            Dom::Cap(SphereCap::sphere(DVec3::Z, GRID)),
        );
        c.setup.job.a = [1.0, 0.0, tag("diffuse_transmission") as f32, 1.0];
        v.push(c);
    }
    v
}

#[test]
fn chi2_diffuse_transmission() {
    run_all("diffuse-transmission", &diffuse_transmission_cases());
}

/// Reciprocity and sample/eval consistency of the rough dielectric and diffuse transmission on the device: the f a
/// sample returns is bsdf_eval at its direction; reflection is symmetric, f(wo, wi) = f(wi, wo); and the
/// dielectric's transmission obeys f(wi, wo) = η'²·f(wo, wi) (η' = η from above: Veach 1997, eq. 5.14, with the
/// 1/η'² radiance scaling), diffuse transmission's f(wi, wo) = f(wo, wi).
#[test]
fn bsdf_reciprocity() {
    let h = harness();
    let count = 1u32 << 12;
    let mut checked = 0;
    for (kind, eta) in
        [(tag("dielectric"), 1.5f32), (tag("dielectric"), 1.0 / 1.33), (tag("diffuse_transmission"), 0.0)]
    {
        let wo = DVec3::new(0.5, 0.3, 0.8).normalize();
        let mut s = Setup::new(SceneId::Lights, R_BSDF);
        s.job.p = v4(wo, eta as f64);
        s.job.a = [0.35, 0.0, kind as f32, 0.2];
        s.job.b = [0.7, 0.7, 0.7, 0.3];
        let out = h.sample(&s, count, 0, 1, 11);
        let inputs: Vec<[[f32; 4]; 2]> = out.iter().map(|[a, _]| [[a[0], a[1], a[2], 1.0], [0.0; 4]]).collect();
        let job = ProbeJob { count, ..s.job };
        let flat: Vec<[f32; 4]> = inputs.iter().flatten().copied().collect();
        let evals = h.dispatch(true, s.scene, &s.frame, &job, &flat, count as usize);
        for ([a, b], e) in out.iter().zip(&evals) {
            if !(a[3] > 0.0) {
                continue;
            }
            let (f_sample, f_fwd, f_rev) = (b[2] as f64, e[1] as f64, e[2] as f64);
            assert!(
                (f_sample - f_fwd).abs() <= 1e-4 * f_fwd.abs() + 1e-7,
                "kind {kind}: sample f {f_sample} vs eval {f_fwd}"
            );
            let transmitted = a[2] < 0.0;
            let ratio = if transmitted && kind == tag("dielectric") { (eta * eta) as f64 } else { 1.0 };
            assert!(
                (f_rev - ratio * f_fwd).abs() <= 2e-3 * f_rev.abs().max(ratio * f_fwd.abs()) + 1e-6,
                "kind {kind}, η {eta}, wi {a:?}: f(wi, wo) {f_rev} vs {ratio}·f(wo, wi) {}",
                ratio * f_fwd
            );
            checked += 1;
        }
    }
    assert!(checked > 3 * count as usize / 2, "too few valid samples ({checked})");
}

/// Unpolarised Fresnel reflectance of a dielectric (CPU reference, f64): cosine c of incidence on the side the
/// relative index η = n_t / n_i refers to; 1 beyond the critical angle.
fn fresnel_dielectric_ref(c: f64, eta: f64) -> f64 {
    let sin2_t = (1.0 - c * c) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let ct = (1.0 - sin2_t).sqrt();
    let rs = (c - eta * ct) / (c + eta * ct);
    let rp = (eta * c - ct) / (eta * c + ct);
    0.5 * (rs * rs + rp * rp)
}

/// The smooth dielectric's delta lobes on the device against the CPU Fresnel: the reflection sample's probability
/// is F(θ), the refraction's 1 − F with Snell's direction, the fraction of reflected samples is F (binomial, 5σ),
/// and beyond the critical angle (η < 1) every sample reflects with probability 1.
#[test]
fn smooth_dielectric_fresnel() {
    let h = harness();
    let count = 1u32 << 14;
    for eta in [1.5f64, 1.0 / 1.5, 1.33] {
        let critical = if eta < 1.0 { eta.asin().to_degrees() } else { 90.0 };
        for inc in [0.0f64, 20.0, 40.0, 41.5, 41.9, 42.0, 60.0, 85.0] {
            let t = deg(inc);
            let wo = DVec3::new(t.sin(), 0.0, t.cos());
            let mut s = Setup::new(SceneId::Lights, R_BSDF);
            s.job.p = v4(wo, eta);
            s.job.a = [0.0, 0.0, tag("dielectric") as f32, 0.0];
            s.job.b = [1.0, 1.0, 1.0, 0.0];
            let f = fresnel_dielectric_ref(wo.z, eta);
            let out = h.sample(&s, count, 0, 1, 7 + inc as u32);
            let mut reflected = 0usize;
            for [a, _] in &out {
                let wi = d3(a);
                let p = a[3] as f64;
                if wi.z > 0.0 {
                    reflected += 1;
                    assert!((wi - DVec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-5, "mirror direction {wi:?}");
                    assert!((p - f).abs() < 2e-5, "η {eta}, θ {inc}°: reflection probability {p} vs Fresnel {f}");
                } else {
                    let sin_t = t.sin() / eta;
                    assert!(sin_t < 1.0, "η {eta}, θ {inc}° (critical {critical:.2}°): refraction under TIR");
                    assert!((wi.x + sin_t).abs() < 1e-5 && wi.y.abs() < 1e-6, "Snell: {wi:?} vs sinθt {sin_t}");
                    assert!(
                        (p - (1.0 - f)).abs() < 2e-5,
                        "η {eta}, θ {inc}°: refraction probability {p} vs {}",
                        1.0 - f
                    );
                }
            }
            let frac = reflected as f64 / count as f64;
            let sigma = (f * (1.0 - f) / count as f64).sqrt();
            assert!((frac - f).abs() <= 5.0 * sigma + 1e-9, "η {eta}, θ {inc}°: reflected {frac} vs F {f}");
            if inc > critical {
                assert_eq!(reflected, count as usize, "total internal reflection beyond {critical:.2}°");
            }
        }
    }
}

/// The coated diffuse BSDF's lobe mixture (shaders/bsdf_coated_diffuse.wgsl: the coat's visible normals with
/// its Fresnel weight, else cosine; η = 1.5 from probe_bsdf), binned over the sphere of wi: a strong and a weak
/// base, an anisotropic coat, grazing incidence.
fn coated_cases() -> Vec<Case> {
    let mut v = Vec::new();
    for (r, au, av, inc) in
        [(0.8f32, 0.1f32, 0.1f32, 30.0f64), (0.05, 0.2, 0.2, 60.0), (0.243, 0.1, 0.4, 45.0), (0.5, 0.3, 0.3, 80.0)]
    {
        let t = deg(inc);
        let wo = DVec3::new(t.sin() * 0.6, t.sin() * 0.8, t.cos());
        let mut c = bsdf_case(
            "coated diffuse (VNDF coat + cosine base)",
            format!("R = {r}, α_u = {au}, α_v = {av}, θo = {inc}°"),
            wo,
            [r, r * 0.5, r * 0.25],
            0.0,
            au,
            0.0,
            Dom::Cap(SphereCap::sphere(DVec3::Z, GRID)),
        );
        c.setup.job.a = [au, 0.0, 3.0, av];
        v.push(c);
    }
    // A Beckmann coat (specular = 1, Mitsuba's roughplastic default): h from D·cos.
    for (r, au, av, inc) in [(0.5f32, 0.3f32, 0.3f32, 35.0f64), (0.1, 0.1, 0.25, 70.0)] {
        let t = deg(inc);
        let wo = DVec3::new(t.sin() * 0.6, t.sin() * 0.8, t.cos());
        let mut c = bsdf_case(
            "coated diffuse, Beckmann coat (D·cos coat + cosine base)",
            format!("R = {r}, α_u = {au}, α_v = {av}, θo = {inc}°"),
            wo,
            [r, r * 0.5, r * 0.25],
            0.0,
            au,
            1.0,
            Dom::Cap(SphereCap::sphere(DVec3::Z, GRID)),
        );
        c.setup.job.a = [au, 1.0, 3.0, av];
        v.push(c);
    }
    v
}

#[test]
fn chi2_coated_diffuse() {
    run_all("coated diffuse", &coated_cases());
}

// ---------------------------------------------------------------------------------------------------------------
// Environment

fn env_case(
    name: &str,
    config: &str,
    scene: SceneId,
    grid: (usize, usize),
    base: Quadrature,
    refine: Option<Quadrature>,
    importance: bool,
) -> Case {
    let mut s = Setup::new(scene, R_ENV);
    if !importance {
        s.frame.env_sampling = EnvSampling::Uniform.tag();
    }
    let rotation = harness().data(scene).env_rotation as f64;
    let mut c = Case::new(name, config.into(), s, Dom::Env(Equirect { rotation, grid }));
    c.base = base;
    c.refine = refine;
    c
}

/// The many-light scene's constant sky seen from a surface with normal n: sampled by the cosine about n.
fn constant_env_cosine_case() -> Case {
    let n = DVec3::new(0.3, -0.5, 0.8).normalize();
    let mut s = Setup::new(SceneId::ManyLights, R_ENV);
    s.job.a = v4(n, 0.0);
    let mut c = Case::new(
        "environment cosine",
        "constant sky, receiver normal (0.3, −0.5, 0.8)".into(),
        s,
        Dom::Cap(SphereCap::sphere(n, GRID)),
    );
    c.base = Quadrature { sub: 1, gauss: 2 };
    c
}

/// The guide of `guided_env_cosine_case`: one cell, and in the slot of normals along +z a CDF over the bins whose
/// weights favour the upper bands and one sector (bins below the receiver's surface included, whose samples are
/// lost), its share alpha = 0.7 in the last entry. The other slots stay zero (the cosine alone).
fn probe_guide() -> Vec<f32> {
    use mislab::render::env_guide::{BINS, NORMAL_CLASSES, PHI_BINS};
    let mut cdf = vec![0f32; NORMAL_CLASSES * BINS];
    let slot = 4; // +z
    let weight = |b: usize| 1.0 + 20.0 * ((b / PHI_BINS) >= 5) as u32 as f64 + 8.0 * (b % PHI_BINS == 3) as u32 as f64;
    let total: f64 = (0..BINS).map(weight).sum();
    let mut run = 0.0;
    for b in 0..BINS {
        run += weight(b);
        cdf[slot * BINS + b] = (run / total) as f32;
    }
    cdf[slot * BINS + BINS - 1] = 0.7;
    cdf
}

/// The many-light scene's constant sky seen from a surface with normal n, `--env-sampling guided`: the cosine
/// about n mixed with `probe_guide` (the slot of normals along +z, the grid one cell).
fn guided_env_cosine_case() -> Case {
    let n = DVec3::new(0.3, -0.5, 0.8).normalize();
    let mut s = Setup::new(SceneId::ManyLights, R_ENV);
    s.job.a = v4(n, 0.0);
    s.frame.env_sampling = EnvSampling::Guided.tag();
    s.frame.guide_on = 1;
    s.frame.guide_dims = [1, 1, 1];
    s.frame.guide_min = [-1e4; 3];
    s.frame.guide_inv_cell = [1e-5; 3];
    s.frame.guide_slots = mislab::render::env_guide::NORMAL_CLASSES as u32;
    let mut c = Case::new(
        "environment guided",
        "constant sky, normal (0.3, −0.5, 0.8), a guide of alpha 0.7".into(),
        s,
        Dom::Cap(SphereCap::sphere(n, GRID)),
    );
    // The pdf steps at the bins' edges, which do not follow the cap's cells: 6×6 points a cell.
    c.base = Quadrature { sub: 3, gauss: 2 };
    // The guide's directions below the surface are lost samples (the pdf is 0 there): ∫pdf + failures/N = 1.
    c.may_fail = true;
    c
}

fn env_cases() -> Vec<Case> {
    // Texel edges fall inside cells (so an f32 sample on an edge never lands in a cell of pdf 0) but on sub-cell
    // boundaries of the quadrature; pdf·Jacobian is constant inside a texel, so one point per sub-cell is exact.
    vec![
        env_case(
            "environment importance",
            "single bright texel of 20×10, rotated 0.3",
            SceneId::EnvPixel,
            (104, 204),
            Quadrature { sub: 5, gauss: 1 },
            None,
            true,
        ),
        env_case(
            "environment importance",
            "3×2 map (1:1000, one black texel)",
            SceneId::Env3x2,
            (101, 202),
            Quadrature { sub: 6, gauss: 1 },
            None,
            true,
        ),
        env_case(
            "environment importance",
            "noon_grass_1k.hdr (1024×512)",
            SceneId::EnvHdr,
            (128, 256),
            Quadrature { sub: 4, gauss: 1 },
            None,
            true,
        ),
        env_case(
            "environment uniform",
            "noon_grass_1k.hdr (1024×512)",
            SceneId::EnvHdr,
            GRID,
            Quadrature { sub: 1, gauss: 2 },
            None,
            false,
        ),
        constant_env_cosine_case(),
        guided_env_cosine_case(),
    ]
}

#[test]
fn chi2_environment() {
    // Only the guided case reads the guide (the others' frames have guide_on = 0).
    harness().pipelines.write_guide(harness().ctx, &probe_guide());
    run_all("env", &env_cases());
}

// ---------------------------------------------------------------------------------------------------------------
// Light selection

/// N light selections of `s` (an R_SELECT setup) with `seed`: how often each of the `n_lights` was picked, the
/// device's pmf function of each, and the largest relative difference between the pmf a pick returned and that
/// function at its index (0: sampling and evaluation agree bit for bit).
fn selection_histogram(s: &Setup, n_lights: usize, seed: u32) -> (Vec<u64>, Vec<f64>, f64) {
    let h = harness();
    let out = h.sample(s, N, 0, 1, seed);
    let mut counts = vec![0u64; n_lights];
    for [a, _] in &out {
        counts[a[0] as usize] += 1;
    }
    let pts: Vec<[[f32; 4]; 2]> = (0..n_lights).map(|i| [[i as f32, 0.0, 0.0, 0.0], [0.0; 4]]).collect();
    let pmf = h.pdf(s, &pts);
    let mismatch =
        out.iter().map(|[a, _]| ((a[1] as f64 - pmf[a[0] as usize]) / pmf[a[0] as usize]).abs()).fold(0.0, f64::max);
    (counts, pmf, mismatch)
}

#[test]
fn chi2_light_selection() {
    let h = harness();
    let n_lights = h.data(SceneId::Lights).selectable_lights();
    let mut rows = Vec::new();
    for select in [LightSelect::Uniform, LightSelect::Power] {
        let mut s = Setup::new(SceneId::Lights, R_SELECT);
        s.frame.light_select = select.tag();
        let t0 = std::time::Instant::now();
        // The pmf the selection returned with each sample is light_pmf of that index.
        let (counts, pmf, mismatch) = selection_histogram(&s, n_lights, 77 + select.tag());
        let report = chi2::discrete_test(&format!("light selection ({select})"), &counts, &pmf, alpha());
        eprintln!("{}  [pmf {:?}]", report.summary(), pmf.iter().map(|p| format!("{p:.4}")).collect::<Vec<_>>());
        rows.push(Row {
            report,
            config: format!("{n_lights} lights"),
            pdf_mismatch: mismatch,
            pdf_outliers: 0.0,
            pdf_match: (0.0, 0.0),
            seconds: t0.elapsed().as_secs_f64(),
        });
    }
    record("selection", &rows);
    for r in &rows {
        assert!(r.report.passed() && r.pdf_mismatch == 0.0, "{}", r.report.summary());
    }
}

/// Shading points (p, n) where the light tree is tested: above the floor looking up, among the emitters, below
/// them facing away, far outside, and with no normal (n = 0, as a camera-side query would be).
const TREE_POINTS: [(&str, [f32; 3], [f32; 3]); 5] = [
    ("floor, n up", [0.5, 0.0, -1.0], [0.0, 1.0, 0.0]),
    ("among emitters", [2.0, 1.5, 3.0], [0.6, 0.0, 0.8]),
    ("below, n down", [-3.0, -1.0, 2.0], [0.0, -1.0, 0.0]),
    ("far away", [60.0, 30.0, -40.0], [-0.8, -0.6, 0.0]),
    ("no normal", [0.0, 2.0, 0.0], [0.0, 0.0, 0.0]),
];

/// The light tree (`--light-select tree`) on the device: for shading points across the many-light scene, the
/// sampled light indices pass a chi-square test against the tree's own pmf function, the pmf a sample returns is
/// that function's value bit for bit (so a light found by a BSDF sample gets the pmf of sampling it), Σ pmf = 1
/// over all lights, and the device's pmf of every light in the tree matches the CPU walk (light_tree::pmf).
#[test]
fn chi2_light_tree_selection() {
    let h = harness();
    let d = h.data(SceneId::ManyLights);
    let n_lights = d.lights.len();
    let bounded = d.light_tree[0].count() as usize;
    assert_eq!(bounded, n_lights - 2, "the tree covers every light but the directional and the sky");
    let mut rows = Vec::new();
    let mut failures = Vec::new();
    for (k, (name, p, n)) in TREE_POINTS.iter().enumerate() {
        let mut s = Setup::new(SceneId::ManyLights, R_SELECT);
        s.frame.light_select = LightSelect::Tree.tag();
        s.job.p = [p[0], p[1], p[2], 0.0];
        s.job.a = [n[0], n[1], n[2], 0.0];
        let t0 = std::time::Instant::now();
        let (counts, pmf, mismatch) = selection_histogram(&s, n_lights, 311 + k as u32);
        let sum: f64 = pmf.iter().sum();
        if (sum - 1.0).abs() > 1e-5 {
            failures.push(format!("{name}: Σ pmf = {sum}"));
        }
        let (pv, nv) = (Vec3::from(*p), Vec3::from(*n));
        let worst_cpu = (0..bounded)
            .map(|i| {
                let cpu = mislab::accel::light_tree::pmf(&d.light_tree, d.lights[i].tree_trail, pv, nv) as f64 / 3.0;
                (pmf[i] - cpu).abs() / cpu.max(1e-12)
            })
            .fold(0.0, f64::max);
        if worst_cpu > 5e-4 {
            failures.push(format!("{name}: device and CPU pmfs differ by {worst_cpu:.2e} (relative)"));
        }
        let report = chi2::discrete_test(&format!("light tree ({name})"), &counts, &pmf, alpha());
        eprintln!("{}  [Σ pmf {sum:.7}, CPU match {worst_cpu:.1e}]", report.summary());
        rows.push(Row {
            report,
            config: format!("{n_lights} lights, p {p:?}, n {n:?}"),
            pdf_mismatch: mismatch,
            pdf_outliers: 0.0,
            pdf_match: (0.0, 0.0),
            seconds: t0.elapsed().as_secs_f64(),
        });
    }
    record("tree selection", &rows);
    for r in &rows {
        if !(r.report.passed() && r.pdf_mismatch == 0.0) {
            failures.push(format!("{} (pmf mismatch {:.2e})", r.report.summary(), r.pdf_mismatch));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The number of chi-square tests equals the family size used for the Šidák correction.
#[test]
fn family_size() {
    let n = warp_cases().len()
        + light_cases().len()
        + bsdf_cases().len()
        + conductor_cases().len()
        + dielectric_cases().len()
        + diffuse_transmission_cases().len()
        + coated_cases().len()
        + env_cases().len()
        + 2
        + TREE_POINTS.len();
    assert_eq!(n, FAMILY, "update FAMILY to the number of chi-square tests");
}

// ---------------------------------------------------------------------------------------------------------------
// Spherical vs area sampling: irradiance integrals

/// Irradiance (L = 1) at p with normal n by `light_sample_li`, stratified 1024 × 1024.
fn irradiance(light: u32, p: DVec3, n: DVec3, mode: LightSampling) -> (f64, f64) {
    let mut s = Setup::new(SceneId::Lights, R_LIGHT);
    s.job.light = light;
    s.job.p = v4(p, 0.0);
    s.frame.light_sampling = mode.tag();
    let out = harness().sample(&s, N, FLAG_STRATIFIED, 1024, 99);
    let (mut sum, mut sum2) = (0.0, 0.0);
    for [a, b] in &out {
        let pdf = a[3] as f64;
        if pdf > 0.0 {
            let f = b[2] as f64 * d3(a).normalize().dot(n).max(0.0) / pdf;
            sum += f;
            sum2 += f * f;
        }
    }
    let m = sum / N as f64;
    (m, ((sum2 / N as f64 - m * m).max(0.0) / N as f64).sqrt())
}

#[test]
fn spherical_sampling_matches_area_sampling() {
    let mut table = String::from("| light | configuration | Ω (sr) | E exact | E spherical | E area | rel. diff |\n|---|---|---|---|---|---|---|\n");
    let mut failures = Vec::new();
    let tri = light_index(LIGHT_TRIANGLE, 0);
    let rect = light_index(LIGHT_QUAD, 0);
    let mut configs = Vec::new();
    for (name, [s, t, hgt]) in TRI_POINTS {
        if name != "tiny" {
            configs.push(("triangle", name, tri, tri_geom(), local_point(TRI_ORIGIN, tri_frame(), s, t, hgt)));
        }
    }
    for (name, [s, t, hgt]) in RECT_POINTS {
        configs.push(("rectangle", name, rect, rect_light(), local_point(RECT_ORIGIN, rect_frame(), s, t, hgt)));
    }
    for (light_name, name, light, geom, p) in configs {
        let verts = geom.verts();
        // A shading normal that keeps the whole light above the horizon: towards the light's centre, tilted.
        let centre = verts.iter().sum::<DVec3>() / verts.len() as f64;
        let n = ((centre - p).normalize() - geom_normal(&geom) * 0.5).normalize();
        assert!(verts.iter().all(|&v| (v - p).dot(n) > 0.0), "{light_name} {name}: light not above the horizon");
        let exact = polygon_irradiance(p, n, &verts);
        let (e_sph, sd_sph) = irradiance(light, p, n, LightSampling::SolidAngle);
        let (e_area, sd_area) = irradiance(light, p, n, LightSampling::Area);
        let omega = solid_angle(&geom, p);
        let rel = |e: f64| (e - exact).abs() / exact;
        eprintln!(
            "{light_name} {name}: Ω = {omega:.3e}, exact {exact:.6e}, spherical {e_sph:.6e} (±{:.1e}, {:.1e}), area {e_area:.6e} (±{:.1e}, {:.1e})",
            sd_sph / exact,
            rel(e_sph),
            sd_area / exact,
            rel(e_area)
        );
        table += &format!(
            "| {light_name} | {name} | {omega:.3e} | {exact:.6e} | {e_sph:.6e} | {e_area:.6e} | {:.1e} |\n",
            (e_sph - e_area).abs() / exact
        );
        for (what, e) in [("spherical", e_sph), ("area", e_area)] {
            if !(rel(e) <= 1e-3) {
                failures.push(format!("{light_name} {name}: {what} {e:.6e} vs exact {exact:.6e} ({:.1e})", rel(e)));
            }
        }
        if !((e_sph - e_area).abs() <= 1e-3 * exact) {
            failures.push(format!("{light_name} {name}: spherical {e_sph:.6e} vs area {e_area:.6e}"));
        }
    }
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("sampling-integrals.md");
    let _ = std::fs::write(path, table);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

fn geom_normal(g: &LightGeom) -> DVec3 {
    match g {
        LightGeom::Triangle(v) => (v[1] - v[0]).cross(v[2] - v[0]).normalize(),
        LightGeom::Quad([_, u, v]) => u.cross(*v).normalize(),
        LightGeom::Sphere(..) => DVec3::Z,
    }
}

// ---------------------------------------------------------------------------------------------------------------
// f32 precision of the spherical warps (sets the thresholds of lights.wgsl)

fn angle_between(a: DVec3, b: DVec3) -> f64 {
    if a.dot(b) < 0.0 {
        PI - 2.0 * ((a + b).length() / 2.0).min(1.0).asin()
    } else {
        2.0 * ((b - a).length() / 2.0).min(1.0).asin()
    }
}

fn gram_schmidt(v: DVec3, w: DVec3) -> DVec3 {
    v - v.dot(w) * w
}

/// pbrt-v4's SampleSphericalTriangle (Arvo's method) in f64: the reference direction for u.
fn reference_spherical_triangle(a: DVec3, b: DVec3, c: DVec3, u: [f64; 2]) -> DVec3 {
    let (a, b, c) = (a.normalize(), b.normalize(), c.normalize());
    let n_ab = a.cross(b).normalize();
    let n_bc = b.cross(c).normalize();
    let n_ca = c.cross(a).normalize();
    let alpha = angle_between(n_ab, -n_ca);
    let beta = angle_between(n_bc, -n_ab);
    let gamma = angle_between(n_ca, -n_bc);
    let a_pi = alpha + beta + gamma;
    let ap_pi = PI + u[0] * (a_pi - PI);
    let (cos_alpha, sin_alpha) = (alpha.cos(), alpha.sin());
    let sin_phi = ap_pi.sin() * cos_alpha - ap_pi.cos() * sin_alpha;
    let cos_phi = ap_pi.cos() * cos_alpha + ap_pi.sin() * sin_alpha;
    let k1 = cos_phi + cos_alpha;
    let k2 = sin_phi - sin_alpha * a.dot(b);
    let cos_bp = ((k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha) / ((k2 * sin_phi + k1 * cos_phi) * sin_alpha))
        .clamp(-1.0, 1.0);
    let sin_bp = (1.0 - cos_bp * cos_bp).max(0.0).sqrt();
    let cp = cos_bp * a + sin_bp * gram_schmidt(c, a).normalize();
    let cos_theta = 1.0 - u[1] * (1.0 - cp.dot(b));
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    cos_theta * b + sin_theta * gram_schmidt(cp, b).normalize()
}

/// pbrt-v4's SampleSphericalRectangle (Ureña et al.) in f64, in the rectangle's frame: the point (x, y).
fn reference_spherical_rect(x0: f64, y0: f64, w: f64, hgt: f64, h: f64, u: [f64; 2]) -> [f64; 2] {
    let z0 = -h;
    let (x1, y1) = (x0 + w, y0 + hgt);
    let v00 = DVec3::new(x0, y0, z0);
    let v01 = DVec3::new(x0, y1, z0);
    let v10 = DVec3::new(x1, y0, z0);
    let v11 = DVec3::new(x1, y1, z0);
    let n0 = v00.cross(v10).normalize();
    let n1 = v10.cross(v11).normalize();
    let n2 = v11.cross(v01).normalize();
    let n3 = v01.cross(v00).normalize();
    let g0 = angle_between(-n0, n1);
    let g1 = angle_between(-n1, n2);
    let g2 = angle_between(-n2, n3);
    let g3 = angle_between(-n3, n0);
    let (b0, b1) = (n0.z, n2.z);
    let au = u[0] * (g0 + g1 - 2.0 * PI) + (u[0] - 1.0) * (g2 + g3);
    let fu = (au.cos() * b0 - b1) / au.sin();
    let cu = (1.0 / (fu * fu + b0 * b0).sqrt()).copysign(fu).clamp(-1.0 + 1e-15, 1.0 - 1e-15);
    let xu = (-(cu * z0) / (1.0 - cu * cu).sqrt()).clamp(x0, x1);
    let dd = (xu * xu + z0 * z0).sqrt();
    let h0 = y0 / (dd * dd + y0 * y0).sqrt();
    let h1 = y1 / (dd * dd + y1 * y1).sqrt();
    let hv = h0 + u[1] * (h1 - h0);
    let yv = if hv * hv < 1.0 - 1e-14 { hv * dd / (1.0 - hv * hv).sqrt() } else { y1 };
    [xu, yv]
}

/// Barycentrics (b1, b2) of where direction w from the origin meets the plane of (a, b, c).
fn barycentrics(a: DVec3, b: DVec3, c: DVec3, w: DVec3) -> [f64; 2] {
    let (e1, e2) = (b - a, c - a);
    let n = e1.cross(e2);
    let y = w * (a.dot(n) / w.dot(n));
    let nn = n.dot(n);
    [(y - a).cross(e2).dot(n) / nn, e1.cross(y - a).dot(n) / nn]
}

/// A WGSL `const NAME: f32 = value;` of lights.wgsl.
fn wgsl_const(name: &str) -> f64 {
    let src = mislab::render::shaders::file("lights.wgsl");
    let line = src
        .lines()
        .find(|l| l.trim_start().starts_with(&format!("const {name}:")))
        .unwrap_or_else(|| panic!("{name} not in lights.wgsl"));
    line.split('=').nth(1).unwrap().trim().trim_end_matches(';').parse().unwrap()
}

/// The labelling of `square_to_spherical_triangle`: base a–c = the shortest side.
fn relabel([va, vb, vc]: [DVec3; 3]) -> [DVec3; 3] {
    let cos = |x: DVec3, y: DVec3| x.dot(y) / (x.length() * y.length());
    let (cab, cbc, cca) = (cos(va, vb), cos(vb, vc), cos(vc, va));
    if cab > cca && cab >= cbc {
        [va, vc, vb]
    } else if cbc > cca {
        [vb, va, vc]
    } else {
        [va, vb, vc]
    }
}

/// f64 twin of `square_to_rectangle`'s formulation (same axis choice), in the rectangle's frame: the point (x, y).
fn mine_spherical_rect(x0: f64, y0: f64, w: f64, hgt: f64, h: f64, u: [f64; 2]) -> [f64; 2] {
    let swap = x0.abs().max((x0 + w).abs()) > y0.abs().max((y0 + hgt).abs());
    let (a0, la, b0, lb) = if swap { (y0, hgt, x0, w) } else { (x0, w, y0, hgt) };
    let (a1, b1) = (a0 + la, b0 + lb);
    let psi_of = |a: f64| {
        let r0 = (a * a + b0 * b0 + h * h).sqrt();
        let r1 = (a * a + b1 * b1 + h * h).sqrt();
        (a * h * (b1 * r0 - b0 * r1)).atan2(h * h * r0 * r1 + a * a * b0 * b1)
    };
    let (psi0, psi1) = (psi_of(a0), psi_of(a1));
    let sigma = b0.atan2(h) + b1.atan2(h);
    let delta = (h * lb).atan2(h * h + b0 * b1);
    let psi = psi0 + u[0] * (psi1 - psi0);
    let q = (0.5 * (sigma + psi)).cos()
        * (0.5 * (sigma - psi)).cos()
        * (0.5 * (delta - psi)).sin()
        * (0.5 * (delta + psi)).sin();
    let a = (h * psi.sin() / (2.0 * q.max(0.0).sqrt())).clamp(a0, a1);
    let dd2 = a * a + h * h;
    let hh0 = b0 / (dd2 + b0 * b0).sqrt();
    let hh1 = b1 / (dd2 + b1 * b1).sqrt();
    let hv = hh0 + u[1] * (hh1 - hh0);
    let b = (hv * dd2.sqrt() / (1.0 - hv * hv).sqrt()).clamp(b0, b1);
    if swap {
        [b, a]
    } else {
        [a, b]
    }
}

/// Lattice of u used for the precision measurement: 65 × 65 including 0 and 1⁻ (as the kernel computes it).
const LATTICE: u32 = 65;
fn lattice_u(i: usize) -> [f64; 2] {
    let g = (LATTICE - 1) as f32;
    let one_minus = 1.0f32 - f32::EPSILON / 2.0;
    [((i as u32 % LATTICE) as f32 / g).min(one_minus) as f64, ((i as u32 / LATTICE) as f32 / g).min(one_minus) as f64]
}

/// The f64 references are the same formulas as the shaders; they agree with pbrt-v4's formulations (Arvo's and
/// Ureña et al.'s own trigonometry) where those are well conditioned in f64 — which validates the reformulation.
#[test]
fn spherical_warp_formulas_match_pbrt() {
    let tri = [DVec3::new(0.0, 0.0, 0.0), DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.3, 0.8, 0.0)];
    for p in
        [DVec3::new(0.7, 0.1, 0.9), DVec3::new(0.4, 0.3, 0.1), DVec3::new(-2.0, 1.0, 0.5), DVec3::new(0.4, 0.3, 30.0)]
    {
        let rel = tri.map(|v| v - p);
        let worst = (0..(LATTICE * LATTICE) as usize)
            .map(|i| {
                let u = lattice_u(i);
                let [a, b, c] = relabel(rel);
                let x = barycentrics(rel[0], rel[1], rel[2], reference_spherical_triangle(a, b, c, u));
                let y = barycentrics(rel[0], rel[1], rel[2], mine_spherical_triangle(rel[0], rel[1], rel[2], u));
                (x[0] - y[0]).abs().max((x[1] - y[1]).abs())
            })
            .fold(0.0, f64::max);
        assert!(worst < 1e-6, "triangle from {p}: pbrt and ours differ by {worst:.1e}");
    }
    for [x0, y0, h] in [[-0.3f64, -0.2, 0.7], [0.5, 0.4, 0.3], [-2.0, -0.3, 0.4], [0.2, -3.0, 1.0], [-0.5, 0.1, 0.01]] {
        let (w, hgt) = (1.0f64, 0.6f64);
        let swap = x0.abs().max((x0 + w).abs()) > y0.abs().max((y0 + hgt).abs());
        let worst = (0..(LATTICE * LATTICE) as usize)
            .map(|i| {
                let u = lattice_u(i);
                let want = if swap {
                    let [b, a] = reference_spherical_rect(y0, x0, hgt, w, h, u);
                    [a, b]
                } else {
                    reference_spherical_rect(x0, y0, w, hgt, h, u)
                };
                let got = mine_spherical_rect(x0, y0, w, hgt, h, u);
                ((got[0] - want[0]) / w).abs().max(((got[1] - want[1]) / hgt).abs())
            })
            .fold(0.0, f64::max);
        assert!(worst < 1e-6, "rectangle ({x0}, {y0}, h = {h}): pbrt and ours differ by {worst:.1e}");
    }
}

/// Measures, over solid angles from 1e-8 to ~2π, the largest error of the f32 spherical warps on this device
/// against their f64 twins: sample positions on the light (in units of its size) and the solid angle (relative).
/// Inside the thresholds of lights.wgsl both must stay below 1e-4 (1/100 of a chi-square bin, 1/10 of the
/// integral tolerance). Writes the table of docs/sampling.md.
#[test]
fn spherical_warps_precision() {
    let h = harness();
    let tri_min = wgsl_const("SPHERICAL_TRIANGLE_MIN_SR");
    let tri_max = wgsl_const("SPHERICAL_TRIANGLE_MAX_SR");
    let rect_min = wgsl_const("SPHERICAL_RECT_MIN_SR");
    let rect_max = wgsl_const("SPHERICAL_RECT_MAX_SR");
    const TOL: f64 = 1e-4;
    let mut table = String::from("| warp | configuration | Ω (sr) | max position error | Ω rel. error | sampled by |\n|---|---|---|---|---|---|\n");
    let mut failures = Vec::new();

    // Triangles: a regular one and a sliver; far along a tilted direction, close above the interior (centroid,
    // near an edge, near a vertex), and grazing (in the plane, beside the triangle).
    let shapes = [
        ("", [DVec3::new(0.0, 0.0, 0.0), DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.3, 0.8, 0.0)]),
        ("sliver ", [DVec3::new(0.0, 0.0, 0.0), DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.45, 0.01, 0.0)]),
    ];
    for (shape, tri2d) in shapes {
        let centroid = (tri2d[0] + tri2d[1] + tri2d[2]) / 3.0;
        let mut pts: Vec<(String, DVec3)> = Vec::new();
        for k in 0..=16 {
            let d = 0.5 * 10f64.powf(k as f64 / 4.0);
            pts.push((format!("{shape}far d = {d:.2e}"), centroid + DVec3::new(0.3, -0.2, 1.0).normalize() * d));
        }
        let interior = [
            ("centroid", centroid),
            ("near edge", 0.5 * (tri2d[0] + tri2d[1]) + DVec3::new(0.0, 0.002, 0.0)),
            ("near vertex", tri2d[0] * 0.98 + centroid * 0.02),
        ];
        for (what, q) in interior {
            for hh in [1e-1, 3e-2, 1e-2, 5e-3, 3e-3, 2e-3, 1e-3, 5e-4, 3e-4, 2e-4, 1e-4, 1e-6] {
                pts.push((format!("{shape}close ({what}) h = {hh:.0e}"), q + DVec3::new(0.0, 0.0, hh)));
            }
        }
        for k in 1..=7 {
            let hh = 10f64.powi(-k);
            pts.push((format!("{shape}grazing h = {hh:.0e}"), DVec3::new(2.5, 0.4 * centroid.y / 0.2667, hh)));
        }
        for (name, p) in &pts {
            // The vertices relative to p as the shader gets them (f32), and the f64 truth from the same numbers.
            let rel: Vec<DVec3> = tri2d.iter().map(|v| f32v(*v - *p)).collect();
            let mut s = Setup::new(SceneId::Lights, R_SPHERICAL_TRIANGLE);
            s.job.p = v4(rel[0], 0.0);
            s.job.a = v4(rel[1], 0.0);
            s.job.b = v4(rel[2], 0.0);
            let out = h.sample(&s, LATTICE * LATTICE, FLAG_LATTICE, LATTICE, 0);
            let omega = solid_angle(&LightGeom::Triangle([rel[0], rel[1], rel[2]]), DVec3::ZERO);
            let omega_err = ((1.0 / out[0][0][3] as f64) / omega - 1.0).abs();
            let mut pos_err: f64 = 0.0;
            for (i, [a, _]) in out.iter().enumerate() {
                let want =
                    barycentrics(rel[0], rel[1], rel[2], mine_spherical_triangle(rel[0], rel[1], rel[2], lattice_u(i)));
                let got = barycentrics(rel[0], rel[1], rel[2], d3(a));
                let e = (got[0] - want[0]).abs().max((got[1] - want[1]).abs());
                pos_err = pos_err.max(if e.is_finite() { e } else { f64::INFINITY });
            }
            let used = omega >= tri_min && omega <= tri_max;
            table += &format!(
                "| spherical triangle | {name} | {omega:.3e} | {pos_err:.1e} | {omega_err:.1e} | {} |\n",
                if used { "solid angle" } else { "area" }
            );
            if used && !(pos_err <= TOL && omega_err <= TOL) {
                failures.push(format!(
                    "triangle {name}: Ω = {omega:.3e}, position error {pos_err:.1e}, Ω error {omega_err:.1e}"
                ));
            }
        }
    }

    // Rectangles 1 × 0.6 and 1 × 0.01: far, close above the interior, grazing beside it along x and along y.
    for (shape, w, hgt) in [("", 1.0f64, 0.6f64), ("sliver ", 1.0, 0.01)] {
        let mut pts: Vec<(String, [f64; 3])> = Vec::new();
        for k in 0..=16 {
            let d = 0.5 * 10f64.powf(k as f64 / 4.0);
            let dir = DVec3::new(0.3, -0.2, 1.0).normalize() * d;
            pts.push((format!("{shape}far d = {d:.2e}"), [-0.5 * w - dir.x, -0.5 * hgt - dir.y, dir.z]));
        }
        for (what, x0, y0) in [
            ("centre", -0.5 * w, -0.5 * hgt),
            ("near edge", -0.5 * w, -0.002 * hgt),
            ("near corner", -0.01 * w, -0.01 * hgt),
        ] {
            for hh in [1e-1, 3e-2, 1e-2, 5e-3, 3e-3, 2e-3, 1e-3, 5e-4, 3e-4, 2e-4, 1e-4, 1e-6] {
                pts.push((format!("{shape}close ({what}) h = {hh:.0e}"), [x0, y0, hh]));
            }
        }
        for k in 1..=7 {
            let hh = 10f64.powi(-k);
            pts.push((format!("{shape}grazing-x h = {hh:.0e}"), [2.0, -0.5 * hgt, hh]));
            pts.push((format!("{shape}grazing-y h = {hh:.0e}"), [-0.3, 1.5, hh]));
        }
        for (name, [x0, y0, hh]) in &pts {
            let r = [*x0 as f32, *y0 as f32, w as f32, hgt as f32, *hh as f32].map(|x| x as f64);
            let mut s = Setup::new(SceneId::Lights, R_SPHERICAL_RECT);
            s.job.p = [r[0] as f32, r[1] as f32, r[2] as f32, r[3] as f32];
            s.job.a = [r[4] as f32, 0.0, 0.0, 0.0];
            let out = h.sample(&s, LATTICE * LATTICE, FLAG_LATTICE, LATTICE, 0);
            let corner = DVec3::new(r[0], r[1], -r[4]);
            let omega = solid_angle(
                &LightGeom::Quad([corner, DVec3::new(r[2], 0.0, 0.0), DVec3::new(0.0, r[3], 0.0)]),
                DVec3::ZERO,
            );
            let omega_err = ((1.0 / out[0][0][3] as f64) / omega - 1.0).abs();
            let mut pos_err: f64 = 0.0;
            for (i, [a, _]) in out.iter().enumerate() {
                let want = mine_spherical_rect(r[0], r[1], r[2], r[3], r[4], lattice_u(i));
                let e = ((a[0] as f64 - want[0]) / r[2]).abs().max(((a[1] as f64 - want[1]) / r[3]).abs());
                pos_err = pos_err.max(if e.is_finite() { e } else { f64::INFINITY });
            }
            let used = omega >= rect_min && omega <= rect_max;
            table += &format!(
                "| spherical rectangle | {name} | {omega:.3e} | {pos_err:.1e} | {omega_err:.1e} | {} |\n",
                if used { "solid angle" } else { "area" }
            );
            if used && !(pos_err <= TOL && omega_err <= TOL) {
                failures.push(format!(
                    "rectangle {name}: Ω = {omega:.3e}, position error {pos_err:.1e}, Ω error {omega_err:.1e}"
                ));
            }
        }
    }
    eprintln!("{table}");
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("sampling-precision.md");
    let _ = std::fs::write(path, &table);
    assert!(failures.is_empty(), "spherical warps exceed {TOL:e} inside the thresholds:\n{}", failures.join("\n"));
}

/// The formula of square_to_spherical_triangle (same labelling), in f64.
fn mine_spherical_triangle(va: DVec3, vb: DVec3, vc: DVec3, u: [f64; 2]) -> DVec3 {
    let cos = |x: DVec3, y: DVec3| x.dot(y) / (x.length() * y.length());
    let (cab, cbc, cca) = (cos(va, vb), cos(vb, vc), cos(vc, va));
    let (a, b, c) = if cab > cca && cab >= cbc {
        (va, vc, vb)
    } else if cbc > cca {
        (vb, va, vc)
    } else {
        (va, vb, vc)
    };
    let (la, lb) = (a.length(), b.length());
    let (e1, e2) = (b - a, c - a);
    let (an, bn) = (a / la, b / lb);
    let omega = solid_angle(&LightGeom::Triangle([a, b, c]), DVec3::ZERO);
    let w = a.cross(e2).cross(a).normalize();
    let d = a.cross(e1).dot(w).abs() / (la * lb);
    let e = e1.dot(w) / lb;
    let k = 1.0 + an.dot(bn);
    let half = 0.5 * u[0] * omega;
    let sh = half.sin();
    let half_phi = (k * sh).atan2(d * half.cos() - e * sh);
    let s_half = half_phi.sin();
    let delta = (an - bn) - (2.0 * s_half * s_half) * an + (2.0 * half_phi).sin() * w;
    let omc = u[1] * 0.5 * delta.dot(delta);
    let sin_theta = (omc * (2.0 - omc)).max(0.0).sqrt();
    let perp = (delta - delta.dot(bn) * bn).normalize();
    ((1.0 - omc) * bn + sin_theta * perp).normalize()
}
