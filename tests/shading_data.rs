//! The compact shading data (src/render/shading_data.rs): the WGSL octahedral decode equals its CPU twin, a
//! flattened scene keeps every triangle's uvs bit for bit and its normals within the encoding's bound, and scenes
//! beyond the packing's limits are refused naming the file.

mod common;

use glam::{Vec2, Vec3};
use mislab::render::scene_data::SceneData;
use mislab::render::shading_data::{decode, oct_decode, oct_encode, NO_NORMAL};
use mislab::testkit::probe::Probe;
use std::collections::HashMap;

const TESTDATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/testdata/gltf/khronos");

fn angle(a: Vec3, b: Vec3) -> f64 {
    let (a, b) = (a.as_dvec3().normalize(), b.as_dvec3().normalize());
    a.cross(b).length().atan2(a.dot(b))
}

const PROBE: &str = "
fn probe_oct(code: u32) -> vec4<f32> { return vec4<f32>(oct_decode(code), 0.0); }
";

#[test]
fn gpu_octahedral_decode_matches_the_cpu_twin() {
    let ctx = common::gpu();
    let mut codes = vec![NO_NORMAL, 0, 0x7fff_7fff, 0x8001_8001, 0x8000_0000, 0x0000_8000, 0x7fff_8001, 0x8001_7fff];
    // Directions on and near the fold edges, the axes, and a spread over the sphere.
    for k in 0..4096u32 {
        let a = k as f32 * 0.618_034 * std::f32::consts::TAU;
        let z = 1.0 - 2.0 * (k as f32 + 0.5) / 4096.0;
        let r = (1.0 - z * z).sqrt();
        codes.push(oct_encode(Vec3::new(r * a.cos(), r * a.sin(), z)));
        codes.push(oct_encode(Vec3::new(a.cos(), a.sin(), if k % 2 == 0 { 1e-6 } else { -1e-6 })));
    }
    for n in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
        codes.push(oct_encode(n));
    }
    let lib = mislab::render::shaders::compose(&["common.wgsl"], PROBE);
    let gpu: Vec<[f32; 4]> = Probe::new(&ctx).map(&lib, "u32", "vec4<f32>", "probe_oct", &codes, None).expect("probe");
    for (&code, g) in codes.iter().zip(&gpu) {
        let (g, c) = (Vec3::new(g[0], g[1], g[2]), oct_decode(code));
        if code == NO_NORMAL {
            assert_eq!(g, Vec3::ZERO, "NO_NORMAL decodes to {g} on the GPU");
            continue;
        }
        assert!((g - c).abs().max_element() < 2e-6, "code {code:#010x}: GPU {g} vs CPU {c}");
    }
}

/// (mesh, triangle) of each flattened triangle, found by its positions' bits.
fn original_triangles(scene: &mislab::scene::Scene, data: &SceneData) -> Vec<(usize, usize)> {
    let key = |p: [Vec3; 3]| p.map(|v| v.to_array().map(f32::to_bits));
    let mut by_positions = HashMap::new();
    for (m, mesh) in scene.meshes.iter().enumerate() {
        for (t, tri) in mesh.indices.iter().enumerate() {
            by_positions.insert(key(tri.map(|i| mesh.positions[i as usize] - data.origin)), (m, t));
        }
    }
    (0..data.tri_shading.len())
        .map(|i| {
            let p = [0, 1, 2].map(|k| Vec3::from_slice(&data.tri_verts[3 * i + k][..3]));
            by_positions[&key(p)]
        })
        .collect()
}

#[test]
fn flattened_scenes_keep_uvs_exactly_and_normals_within_5e5_rad() {
    for file in ["BoxTextured/glTF/BoxTextured.gltf", "TextureTransformTest/glTF/TextureTransformTest.gltf"] {
        let scene = common::scene(&format!("{TESTDATA}/{file}"));
        let data = SceneData::build(&scene);
        assert!(data.shading_verts.len() <= 3 * data.tri_shading.len(), "{file}: shading vertices are not shared");
        let mut worst = 0.0f64;
        for (i, (m, t)) in original_triangles(&scene, &data).into_iter().enumerate() {
            let mesh = &scene.meshes[m];
            let d = decode(&data.tri_shading[i], &data.shading_verts);
            assert_eq!(d.material, mesh.material, "{file}: triangle {i} material");
            for (k, &v) in mesh.indices[t].iter().enumerate() {
                let uv = mesh.uvs.get(v as usize).copied().unwrap_or(Vec2::ZERO);
                assert_eq!(d.uv[k].to_array().map(f32::to_bits), uv.to_array().map(f32::to_bits), "{file}: uv");
                let n = mesh.normals.get(v as usize).copied().unwrap_or(Vec3::ZERO);
                if n.length() > 0.0 {
                    worst = worst.max(angle(d.n[k], n));
                } else {
                    assert_eq!(d.n[k], Vec3::ZERO);
                }
            }
        }
        assert!(worst < 5e-5, "{file}: normal error {worst:e} rad");
    }
}

#[test]
fn scenes_beyond_the_packing_are_refused_naming_the_file() {
    use mislab::scene::{check_packing_limits, Material, Scene, MAX_MASK_TEXTURE, MAX_MATERIALS};
    let path = std::path::Path::new("dir/many.gltf");
    let mut scene = Scene { materials: vec![Material::default(); MAX_MATERIALS], ..Scene::default() };
    assert!(check_packing_limits(path, &scene).is_ok(), "{MAX_MATERIALS} materials fit");
    scene.materials.push(Material::default());
    let err = check_packing_limits(path, &scene).expect_err("one material too many");
    assert!(
        err.path.ends_with("many.gltf") && err.message.contains("65537 materials"),
        "{}: {}",
        err.path,
        err.message
    );
    scene.materials.truncate(2);
    scene.materials[1].alpha_texture = Some(MAX_MASK_TEXTURE);
    assert!(check_packing_limits(path, &scene).is_ok(), "mask {MAX_MASK_TEXTURE} fits");
    scene.materials[1].alpha_texture = Some(MAX_MASK_TEXTURE + 1);
    let err = check_packing_limits(path, &scene).expect_err("mask index too large");
    assert!(err.message.contains("cut-out mask"), "{}", err.message);
}

/// Three quads side by side, each with its own 64² texture, under a white sky (small: a short compile).
fn three_textured_quads() -> mislab::scene::Scene {
    use mislab::scene::{Camera, Environment, Material, Quad, Scene, Texture, TextureKind, TextureRef, Wrap};
    let mut scene = Scene {
        camera: Camera::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y, 50.0),
        environment: Environment::Constant(Vec3::ONE),
        ..Scene::default()
    };
    for k in 0..3u32 {
        let texels = (0..64 * 64u32).map(|i| [(i * (k + 3)) as u8, (i / 64 * 4) as u8, (40 * k) as u8, 255]).collect();
        scene.textures.push(Texture {
            name: format!("t{k}"),
            width: 64,
            height: 64,
            texels,
            srgb: true,
            wrap_s: Wrap::Repeat,
            wrap_t: Wrap::Repeat,
            nearest: false,
            kind: TextureKind::Image,
        });
        let mut m = Material::lambert(&format!("m{k}"), Vec3::ONE);
        m.base_color_texture = Some(TextureRef::identity(k));
        scene.materials.push(m);
        let corner = Vec3::new(k as f32 - 1.5, -0.5, 0.0);
        scene.quads.push(Quad { corner, edge_u: Vec3::X, edge_v: Vec3::Y, material: k });
    }
    scene
}

/// Two samples per pixel of an uploaded scene at `size`², read back (the split tests compare uploads with it).
fn two_samples(
    ctx: &mislab::gpu::GpuContext,
    gs: &mislab::render::gpu_scene::GpuScene,
    scene: &mislab::scene::Scene,
    size: u32,
) -> mislab::render::film::Film {
    let settings = common::small(size, size);
    let mut r = mislab::render::Renderer::new(ctx, gs, scene.camera.clone(), settings).expect("renderer");
    r.render(ctx, 2).expect("render");
    r.film(ctx).expect("readback")
}

/// A scene whose texels exceed the binding limit the renderer believes takes them over two bindings
/// (gpu_scene::split_texels) and renders bit for bit as with one; past two bindings it is a clear error.
#[test]
fn texels_split_over_two_bindings_render_as_one() {
    use mislab::render::{features::Features, gpu_scene::GpuScene};
    let ctx = common::gpu();
    let scene = three_textured_quads();
    let data = SceneData::build(&scene);
    let (bytes, n) = (4 * data.tex_texels.len() as u64, data.tex_info.len());
    assert_eq!(n, 3);
    let render = |gs: &GpuScene| two_samples(&ctx, gs, &scene, 40);
    let whole = GpuScene::upload(&ctx, data.clone()).expect("upload");
    assert!(whole.data.tex_texels_hi.is_empty() && !Features::of(&whole.data).texel_split);
    // A limit that cuts the texture list in the middle.
    let mid = 4 * data.tex_info[n / 2].offset as u64;
    let split = GpuScene::upload_with_limit(&ctx, data.clone(), mid.max(bytes - mid)).expect("split upload");
    let moved = split.data.tex_info.iter().filter(|t| t.offset & mislab::gpu::types::TEXEL_HI != 0).count();
    assert!(moved >= 1 && moved < n && Features::of(&split.data).texel_split, "{moved} of {n} textures moved");
    let (a, b) = (render(&whole), render(&split));
    assert!(a.mean.iter().flatten().any(|&c| c > 0.0), "black render");
    assert_eq!(a.mean, b.mean, "split texels render differently");
    let err = GpuScene::upload_with_limit(&ctx, data, bytes / 4).err().expect("texels in four bindings' worth");
    let msg = err.to_string();
    assert!(msg.contains("texels") && msg.contains(&format!("({bytes} bytes)")), "{msg}");
}

/// A scene whose vertices exceed the binding limit the renderer believes takes them over two, three or four bindings
/// (gpu_scene::split_vertices, whole triangles per binding) and renders bit for bit as with one; past four bindings
/// it is a clear error.
#[test]
fn vertices_split_over_up_to_four_bindings_render_as_one() {
    use mislab::render::{bindings::VERTEX_BINDINGS, features::Features, gpu_scene::GpuScene};
    let ctx = common::gpu();
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/bench-scenes/scaling_1k/scaling_1k.toml");
    let scene = common::scene(file);
    let data = SceneData::build(&scene);
    let bytes = 16 * data.tri_verts.len() as u64;
    let render = |gs: &GpuScene| two_samples(&ctx, gs, &scene, 32);
    let whole = GpuScene::upload(&ctx, data.clone()).expect("upload");
    assert!(whole.data.tri_verts_hi.is_empty() && !Features::of(&whole.data).geometry_split);
    let a = render(&whole);
    assert!(a.mean.iter().flatten().any(|&c| c > 0.0), "black render");
    assert_eq!(VERTEX_BINDINGS, 4);
    // Limits that cut the vertices in the middle of a triangle's three, into 2, 3 and 4 bindings.
    for (parts, limit) in [(2, bytes * 3 / 5 + 16), (3, bytes * 2 / 5 + 16), (4, bytes * 3 / 10 + 16)] {
        let split = GpuScene::upload_with_limit(&ctx, data.clone(), limit).expect("split upload");
        let d = &split.data;
        let sizes: Vec<usize> = std::iter::once(d.tri_verts.len()).chain(d.tri_verts_hi.iter().map(Vec::len)).collect();
        assert_eq!(sizes.len(), parts, "{parts} bindings at limit {limit}: {sizes:?}");
        assert!(sizes.iter().all(|&n| n % 3 == 0 && n > 0 && 16 * n as u64 <= limit), "{sizes:?}");
        assert_eq!(sizes.iter().sum::<usize>(), data.tri_verts.len());
        let joined: Vec<[f32; 4]> = d.tri_verts.iter().chain(d.tri_verts_hi.iter().flatten()).copied().collect();
        assert!(joined == data.tri_verts, "the parts are not the vertices in order");
        assert!(Features::of(d).geometry_split);
        assert_eq!(a.mean, render(&split).mean, "vertices over {parts} bindings render differently");
    }
    let err = GpuScene::upload_with_limit(&ctx, data, bytes / 5).err().expect("vertices in five bindings' worth");
    let msg = err.to_string();
    assert!(msg.contains("triangle vertices") && msg.contains(&format!("({bytes} bytes)")), "{msg}");
    assert!(msg.contains("4 bindings"), "{msg}");
}

const RECORD_PROBE: &str = "
@group(2) @binding(0) var<uniform> probe_count: vec4<u32>;
@group(2) @binding(1) var<storage, read_write> probe_out: array<vec4<u32>>;
@group(2) @binding(2) var<storage, read> probe_in: array<vec4<f32>>;

@compute @workgroup_size(64)
fn probe_records(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= probe_count.x) { return; }
    let t = scene_tri_record(i);
    let k = i % 3u;
    // The corners as shading reads them (with the positions), the light, one corner alone (as alpha.wgsl does),
    // and that corner's shading vertex.
    probe_out[3u * i] = vec4<u32>(scene_tri_positions(i).corners, scene_tri_light(i));
    probe_out[3u * i + 1u] = vec4<u32>(t.corners, scene_tri_corner(i, k));
    let v = scene_shading_vertex(scene_tri_corner(i, k));
    probe_out[3u * i + 2u] = vec4<u32>(v.normal, v.material, bitcast<vec2<u32>>(v.uv));
}
";

/// Each triangle's shading-vertex records travel in the w of its vertices and its light in `tri_lights`
/// (`SceneData::pack_triangle_records`): the device must read back exactly the CPU's records and shading vertices,
/// in a scene without emissive triangles (where `tri_lights` is a few INVALID words and a zero padding word would
/// read as light 0), in one with 80,640 of them, and in a textured one (two records per vertex: the uv too).
#[test]
fn gpu_reads_every_triangle_record_as_the_cpu_wrote_it() {
    use mislab::render::gpu_scene::GpuScene;
    use mislab::testkit::scene_probe::ScenePipelines;
    let ctx = common::gpu();
    let files: Vec<&str> = mislab::render::RENDER_FILES.iter().copied().filter(|f| *f != "integrator.wgsl").collect();
    let source = mislab::render::shaders::compose(&files, RECORD_PROBE);
    let pipelines = ScenePipelines::new(&ctx, &source, &["probe_records"]).expect("probe pipelines");
    let helmet =
        concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/bench-scenes/damagedhelmet_grey/damagedhelmet_grey.toml");
    let textured = format!("{TESTDATA}/BoxTextured/glTF/BoxTextured.gltf");
    for (name, emitters) in [(helmet, false), ("veach-mis-triangles", true), (textured.as_str(), false)] {
        let data = SceneData::build(&common::scene(name));
        let stride = data.shading_record_stride();
        assert_eq!(stride, if name == textured { 2 } else { 1 }, "{name}: records per shading vertex");
        let n = data.tri_shading.len();
        assert_eq!(data.tri_shading.iter().any(|t| t.light != mislab::gpu::types::INVALID), emitters, "{name}");
        for (i, t) in data.tri_shading.iter().enumerate() {
            for k in 0..3 {
                let w = data.tri_verts[3 * i + k][3].to_bits();
                assert_eq!(w, stride * t.corners[k], "{name}: triangle {i} corner {k}");
            }
        }
        assert_eq!(data.tri_lights.len(), if emitters { n } else { 4 }, "{name}: tri_lights");
        let bound = pipelines.bind(&ctx, GpuScene::upload(&ctx, data.clone()).expect("upload"));
        let frame = Default::default();
        let job = [n as u32, 0, 0, 0];
        let out = pipelines
            .dispatch(&ctx, "probe_records", &bound, &frame, bytemuck::cast_slice(&job), &[], 48 * n as u64, n as u32)
            .expect("dispatch");
        let out: Vec<[u32; 4]> = bytemuck::pod_collect_to_vec(&out);
        for (i, t) in data.tri_shading.iter().enumerate() {
            let c = t.corners.map(|c| stride * c);
            assert_eq!(out[3 * i], [c[0], c[1], c[2], t.light], "{name}: triangle {i} (positions' corners, light)");
            assert_eq!(out[3 * i + 1], [c[0], c[1], c[2], c[i % 3]], "{name}: triangle {i} (record, one corner)");
            let v = data.shading_verts[t.corners[i % 3] as usize];
            let got = out[3 * i + 2];
            assert_eq!([got[0], got[1]], [v.normal, v.material], "{name}: triangle {i} shading vertex");
            if stride == 2 {
                assert_eq!([got[2], got[3]], v.uv.map(f32::to_bits), "{name}: triangle {i} uv");
            }
        }
    }
}

/// Issue 13's budget: BVH + geometry + shading data within 64 bytes per triangle on the bench scenes (grey
/// models and interiors, and the scaling series), as `mislab info` reports it.
#[test]
fn bench_scenes_fit_in_64_bytes_per_triangle() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/bench-scenes");
    for name in
        ["damagedhelmet_grey", "livingroom_grey", "diningroom_grey", "staircase2_grey", "scaling_1k", "scaling_100k"]
    {
        let data = SceneData::build(&common::scene(&format!("{dir}/{name}/{name}.toml")));
        let m = mislab::render::gpu_scene::memory_per_triangle(&data);
        eprintln!("{name}: {m:?}, total {:.1} B", m.total());
        assert!(data.tri_shading.len() > 900, "{name}: {} triangles", data.tri_shading.len());
        assert!(m.total() <= 64.0, "{name}: {:.1} bytes per triangle ({m:?})", m.total());
    }
}

/// Pre-split triangles (src/accel/presplit.rs) are uploaded once per BVH reference: every copy carries its
/// triangle's positions and shading records, emitters are never split (each stays one light), the memory per
/// triangle counts the scene's triangles, and scenes small enough to render without a BVH keep one copy each.
#[test]
fn presplit_copies_share_their_triangle_and_emitters_stay_whole() {
    use mislab::scene::{Material, Mesh, Scene};
    let mesh = |name: &str, tris: &[[Vec3; 3]], material: u32| Mesh {
        name: name.into(),
        positions: tris.iter().flatten().copied().collect(),
        normals: vec![],
        uvs: vec![],
        indices: (0..tris.len() as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect(),
        material,
    };
    // A floor of 800 small triangles, two long diagonal slivers (one grey, one emissive).
    let mut floor = Vec::new();
    for i in 0..20 {
        for j in 0..20 {
            let o = Vec3::new(i as f32, 0.0, j as f32) * 0.5;
            floor.push([o, o + Vec3::new(0.0, 0.0, 0.5), o + Vec3::new(0.5, 0.0, 0.0)]);
            floor.push([o + Vec3::new(0.5, 0.0, 0.0), o + Vec3::new(0.0, 0.0, 0.5), o + Vec3::new(0.5, 0.0, 0.5)]);
        }
    }
    let sliver = |y: f32| [Vec3::new(0.0, y, 0.0), Vec3::new(10.0, y + 5.0, 10.0), Vec3::new(10.0, y + 5.2, 10.0)];
    let light = Material { emission: Vec3::splat(5.0), ..Material::default() };
    let scene = |floor: &[[Vec3; 3]]| Scene {
        materials: vec![Material::default(), light.clone()],
        meshes: vec![mesh("floor", floor, 0), mesh("sliver", &[sliver(1.0)], 0), mesh("lamp", &[sliver(2.0)], 1)],
        ..Scene::default()
    };
    let big = scene(&floor);
    let data = SceneData::build(&big);
    assert_eq!(data.triangles, 802);
    let originals = original_triangles(&big, &data);
    let copies = |m: usize| originals.iter().filter(|o| o.0 == m).count();
    assert!(copies(1) > 2, "the grey sliver is split: {} copies", copies(1));
    assert_eq!(copies(2), 1, "the emissive sliver stays whole");
    assert_eq!(copies(0), 800, "the floor's small triangles are not split");
    assert_eq!(data.tri_shading.len(), 801 + copies(1));
    let first = |m: usize| originals.iter().position(|o| o.0 == m).unwrap();
    for (i, o) in originals.iter().enumerate().filter(|(_, o)| o.0 == 1) {
        assert_eq!(data.tri_shading[i], data.tri_shading[first(o.0)], "copy {i} of the sliver");
    }
    let lights = data.tri_shading.iter().filter(|t| t.light != mislab::gpu::types::INVALID).count();
    assert_eq!((lights, data.lights.len()), (1, 1), "one emissive triangle, one light");
    let m = mislab::render::gpu_scene::memory_per_triangle(&data);
    let vertex_bytes = 48.0 * data.tri_shading.len() as f64 / 802.0;
    assert!((m.geometry - vertex_bytes).abs() < 1e-9, "{m:?}: per scene triangle, copies included");
    // Below the flat limit: one copy per triangle, in any case.
    let small = scene(&floor[..20]);
    assert_eq!(SceneData::build(&small).tri_shading.len(), 22);
}
