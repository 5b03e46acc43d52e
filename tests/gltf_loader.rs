//! Tests of the glTF 2.0 loader on the shared sample models, the comparison scenes, the robustness corpus and
//! hand-made malformed files. Expected counts come from parsing the JSON independently (serde_json `Value`s
//! via `gltf::json`, never the loader's code path) or from the files' READMEs.

mod scratch;
use glam::{Vec2, Vec3};
use gltf::json::Value;
use mislab::scene::{self, load, LoadOptions, Material, Mesh, PunctualLight, Scene, Texture, Wrap};
use scratch::Scratch;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

const TESTDATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/testdata/gltf");
const SCENES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/scenes");

// ------------------------------------------------------------------------------------------------------
// Helpers

fn khronos(rel: &str) -> String {
    format!("{TESTDATA}/khronos/{rel}")
}

fn load_ok(path: &str) -> Scene {
    load(path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{path} should load: {e}"))
}

fn load_err(path: &str) -> String {
    match load(path, &LoadOptions::default()) {
        Ok(s) => panic!("{path} should fail, loaded {} triangles, warnings {:?}", s.triangle_count(), s.warnings),
        Err(e) => e.to_string(),
    }
}

fn material<'a>(scene: &'a Scene, name: &str) -> &'a Material {
    scene.materials.iter().find(|m| m.name == name).unwrap_or_else(|| panic!("no material '{name}'"))
}

fn base_texture<'a>(scene: &'a Scene, material_name: &str) -> &'a Texture {
    let r = material(scene, material_name).base_color_texture.as_ref().expect("base colour texture");
    &scene.textures[r.texture as usize]
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
}

fn close3(a: Vec3, b: Vec3, tol: f32) -> bool {
    (0..3).all(|i| close(a[i], b[i], tol))
}

fn files_under(dir: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![PathBuf::from(dir)];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let p = entry.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if matches!(p.extension().and_then(|e| e.to_str()), Some("gltf" | "glb")) {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// A fresh, empty scratch directory for one test.
fn scratch(name: &str) -> Scratch {
    Scratch::new("gltf", name)
}

/// Loads through `scene::load` and directly, asserting the loader itself never panics (scene::load would
/// turn a panic into an error, hiding it).
fn load_no_panic(path: &Path) -> Result<Scene, String> {
    let direct = std::panic::catch_unwind(|| scene::gltf::load(path, &LoadOptions::default()));
    let direct = direct.unwrap_or_else(|_| panic!("the glTF loader panicked on {}", path.display()));
    let via = load(path.to_str().unwrap(), &LoadOptions::default()).map_err(|e| e.to_string());
    assert_eq!(direct.is_ok(), via.is_ok(), "{}", path.display());
    via
}

// ------------------------------------------------------------------------------------------------------
// Independent JSON reading

/// The JSON of a .gltf, or the JSON chunk of a .glb.
fn json_of(path: &Path) -> Value {
    let bytes = std::fs::read(path).unwrap();
    let text = if bytes.starts_with(b"glTF") {
        let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        bytes[20..20 + len].to_vec()
    } else {
        bytes
    };
    gltf::json::deserialize::from_slice(&text).unwrap()
}

/// What a scene of a glTF file should produce, counted from the JSON.
#[derive(Debug, Default, PartialEq)]
struct Expected {
    triangles: usize,
    materials: usize,
    lights: usize,
    first_perspective_yfov: Option<f32>,
}

fn expected(v: &Value, scene: Option<usize>) -> Expected {
    let scene = scene.or(v["scene"].as_u64().map(|s| s as usize)).unwrap_or(0);
    let mut e = Expected::default();
    let mut materials = HashSet::new();
    let mut stack: Vec<u64> =
        v["scenes"][scene]["nodes"].as_array().unwrap().iter().rev().map(|n| n.as_u64().unwrap()).collect();
    while let Some(n) = stack.pop() {
        let node = &v["nodes"][n as usize];
        if let Some(mesh) = node["mesh"].as_u64() {
            for p in v["meshes"][mesh as usize]["primitives"].as_array().unwrap() {
                let acc = p["indices"].as_u64().or(p["attributes"]["POSITION"].as_u64()).unwrap();
                let count = v["accessors"][acc as usize]["count"].as_u64().unwrap() as usize;
                let tris = match p["mode"].as_u64().unwrap_or(4) {
                    4 => count / 3,
                    5 | 6 => count.saturating_sub(2),
                    _ => continue,
                };
                e.triangles += tris;
                materials.insert(p["material"].as_u64());
            }
        }
        if let Some(c) = node["camera"].as_u64() {
            let cam = &v["cameras"][c as usize];
            if cam["type"] == "perspective" && e.first_perspective_yfov.is_none() {
                e.first_perspective_yfov = Some(cam["perspective"]["yfov"].as_f64().unwrap() as f32);
            }
        }
        if node["extensions"]["KHR_lights_punctual"].is_object() {
            e.lights += 1;
        }
        if let Some(children) = node["children"].as_array() {
            stack.extend(children.iter().rev().map(|c| c.as_u64().unwrap()));
        }
    }
    e.materials = materials.len();
    e
}

// ------------------------------------------------------------------------------------------------------
// Sample models

#[test]
fn every_sample_model_matches_its_json() {
    let mut files = files_under(&format!("{TESTDATA}/khronos"));
    files.extend(files_under(&format!("{TESTDATA}/bevy")));
    files.retain(|f| !f.to_string_lossy().contains("glTF-Draco"));
    assert!(files.len() >= 28, "expected the whole sample set, found {}", files.len());
    for f in files {
        let scene = load_no_panic(&f).unwrap_or_else(|e| panic!("{e}"));
        let want = expected(&json_of(&f), None);
        let got = Expected {
            triangles: scene.triangle_count(),
            materials: scene.materials.len(),
            lights: scene.punctual_lights.len(),
            first_perspective_yfov: want.first_perspective_yfov.map(|_| scene.camera.vfov),
        };
        assert_eq!(got, want, "{}", f.display());
        assert_eq!(scene.name, f.file_stem().unwrap().to_string_lossy());
        for m in &scene.meshes {
            assert_mesh_sane(m, &f);
        }
    }
}

fn assert_mesh_sane(m: &Mesh, file: &Path) {
    assert_eq!(m.normals.len(), m.positions.len(), "{}", file.display());
    assert!(m.uvs.is_empty() || m.uvs.len() == m.positions.len());
    assert!(m.positions.iter().all(|p| p.is_finite()));
    assert!(m.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-3), "non-unit normal in {}", file.display());
    assert!(m.indices.iter().flatten().all(|&i| (i as usize) < m.positions.len()));
}

#[test]
fn box_has_twelve_triangles_and_frames_a_default_camera() {
    let s = load_ok(&khronos("Box/glTF-Binary/Box.glb"));
    assert_eq!(s.triangle_count(), 12);
    assert_eq!(s.materials.len(), 1);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    // No camera in the file: look from +Z at the centre of the bounds (the unit cube at the origin).
    assert!(close3(s.camera.forward, Vec3::NEG_Z, 1e-6));
    assert!(s.camera.position.z > 1.0 && s.camera.position.x.abs() < 1e-4);
    assert!(close(s.camera.vfov, 45f32.to_radians(), 1e-6));
    // The interleaved variant is the same box.
    let b = load_ok(&khronos("BoxInterleaved/glTF-Binary/BoxInterleaved.glb"));
    assert_eq!(b.triangle_count(), 12);
    let bounds = |s: &Scene| s.meshes[0].positions.iter().fold(Vec3::ZERO, |m, p| m.max(p.abs()));
    assert!(close3(bounds(&b), Vec3::splat(0.5), 1e-5), "{}", bounds(&b));
}

#[test]
fn damaged_helmet_textures_and_emission() {
    let s = load_ok(&khronos("DamagedHelmet/glTF-Binary/DamagedHelmet.glb"));
    // 46356 indices = 15452 triangles (the JSON: accessor count 46356, mode TRIANGLES).
    assert_eq!(s.triangle_count(), 15452);
    assert_eq!(s.materials.len(), 1);
    let m = &s.materials[0];
    let (base, mr, emissive) = (
        m.base_color_texture.as_ref().unwrap(),
        m.metallic_roughness_texture.as_ref().unwrap(),
        m.emissive_texture.as_ref().unwrap(),
    );
    assert!(s.textures[base.texture as usize].srgb);
    assert!(!s.textures[mr.texture as usize].srgb);
    assert!(s.textures[emissive.texture as usize].srgb);
    // Normal and occlusion maps are not used by the renderer and not loaded.
    assert_eq!(s.textures.len(), 3);
    for t in &s.textures {
        assert_eq!(t.texels.len(), (t.width * t.height) as usize);
        assert_eq!((t.width, t.height), (2048, 2048));
    }
    assert!(m.is_emissive() && s.has_lights());
    assert_eq!(s.meshes[0].uvs.len(), s.meshes[0].positions.len());
}

#[test]
fn box_textured_external_and_embedded_agree() {
    let a = load_ok(&khronos("BoxTextured/glTF/BoxTextured.gltf"));
    let b = load_ok(&khronos("BoxTextured/glTF-Binary/BoxTextured.glb"));
    for s in [&a, &b] {
        assert_eq!(s.textures.len(), 1);
        assert_eq!(s.triangle_count(), 12);
        assert!(s.textures[0].srgb && s.textures[0].width > 1);
    }
    assert_eq!(a.textures[0].texels, b.textures[0].texels);
    assert_eq!(a.meshes[0].uvs, b.meshes[0].uvs);
}

#[test]
fn punctual_lights_of_the_lamp() {
    let path = khronos("LightsPunctualLamp/glTF/LightsPunctualLamp.gltf");
    let s = load_ok(&path);
    assert_eq!(s.punctual_lights.len(), 5);
    // Light 0 ("Point"): colour (1, 0.631875, 0.2390998) × intensity 15, from the JSON.
    let want = Vec3::new(1.0, 0.631_875, 0.239_099_76) * 15.0;
    let found = s
        .punctual_lights
        .iter()
        .any(|l| matches!(l, PunctualLight::Point { intensity, .. } if close3(*intensity, want, 1e-5)));
    assert!(found, "{:?}", s.punctual_lights);
    for l in &s.punctual_lights {
        let PunctualLight::Point { position, .. } = l else { panic!("all lamp lights are points") };
        assert!(position.is_finite());
    }
    // KHR_materials_transmission is only "used": ignored with a warning.
    assert!(s.warnings.iter().any(|w| w.contains("KHR_materials_transmission")), "{:?}", s.warnings);
}

#[test]
fn perspective_camera_is_taken_and_orthographic_skipped() {
    let s = load_ok(&khronos("Cameras/glTF-Embedded/Cameras.gltf"));
    // Node 1: translation (0.5, 0.5, 3), camera 0 (perspective, yfov 0.7); node 2 is orthographic.
    assert!(close3(s.camera.position, Vec3::new(0.5, 0.5, 3.0), 1e-6));
    assert!(close3(s.camera.forward, Vec3::NEG_Z, 1e-6));
    assert!(close3(s.camera.up, Vec3::Y, 1e-6));
    assert!(close(s.camera.vfov, 0.7, 1e-6));
    assert!(s.warnings.iter().any(|w| w.contains("orthographic")), "{:?}", s.warnings);
    // The mesh node is rotated about X: all its vertices moved off the z = 0 plane of the file.
    assert!(s.meshes[0].positions.iter().any(|p| p.z.abs() > 0.1));
}

#[test]
fn multiple_scenes_and_scene_option() {
    let path = khronos("MultipleScenes/glTF-Embedded/MultipleScenes.gltf");
    let v = json_of(Path::new(&path));
    assert_eq!(v["scene"].as_u64(), Some(1));
    let default = load_ok(&path);
    assert_eq!(default.triangle_count(), expected(&v, Some(1)).triangles);
    assert_eq!(default.triangle_count(), 2);
    let first = load(&path, &LoadOptions { gltf_scene: Some(0), ..Default::default() }).unwrap();
    assert_eq!(first.triangle_count(), expected(&v, Some(0)).triangles);
    assert_eq!(first.triangle_count(), 1);
    let err = load(&path, &LoadOptions { gltf_scene: Some(2), ..Default::default() }).unwrap_err().to_string();
    assert!(err.contains("MultipleScenes.gltf") && err.contains("scene 2") && err.contains("2 scene"), "{err}");
}

/// Decodes buffer 0 of an embedded .gltf (a base64 data URI).
fn embedded_buffer(v: &Value) -> Vec<u8> {
    use base64::Engine;
    let uri = v["buffers"][0]["uri"].as_str().unwrap();
    base64::engine::general_purpose::STANDARD.decode(uri.split_once(',').unwrap().1).unwrap()
}

#[test]
fn sparse_accessor_values_are_applied() {
    let path = khronos("SimpleSparseAccessor/glTF-Embedded/SimpleSparseAccessor.gltf");
    let v = json_of(Path::new(&path));
    let buf = embedded_buffer(&v);
    let acc = &v["accessors"][1];
    let view = |i: u64| v["bufferViews"][i as usize]["byteOffset"].as_u64().unwrap() as usize;
    let sparse = &acc["sparse"];
    let (ind, val) = (
        view(sparse["indices"]["bufferView"].as_u64().unwrap()),
        view(sparse["values"]["bufferView"].as_u64().unwrap()),
    );
    let base = view(acc["bufferView"].as_u64().unwrap());
    let f = |at: usize| f32::from_le_bytes(buf[at..at + 4].try_into().unwrap());
    let s = load_ok(&path);
    let positions = &s.meshes[0].positions;
    let mut moved = 0;
    for k in 0..sparse["count"].as_u64().unwrap() as usize {
        let i = u16::from_le_bytes(buf[ind + 2 * k..ind + 2 * k + 2].try_into().unwrap()) as usize;
        let value = Vec3::new(f(val + 12 * k), f(val + 12 * k + 4), f(val + 12 * k + 8));
        let original = Vec3::new(f(base + 12 * i), f(base + 12 * i + 4), f(base + 12 * i + 8));
        assert_eq!(positions[i], value, "vertex {i}");
        moved += (value != original) as usize;
    }
    assert!(moved > 0, "the sparse values should move some vertices");
}

#[test]
fn triangle_without_indices() {
    let s = load_ok(&khronos("TriangleWithoutIndices/glTF-Embedded/TriangleWithoutIndices.gltf"));
    assert_eq!(s.triangle_count(), 1);
    assert_eq!(s.meshes[0].indices, vec![[0, 1, 2]]);
    // No NORMAL in the file: generated, unit, facing the CCW side (+Z for this triangle in the XY plane).
    assert!(s.meshes[0].normals.iter().all(|n| close3(*n, Vec3::Z, 1e-6)));
}

#[test]
fn primitive_modes_only_triangles_and_one_warning() {
    let path = khronos("MeshPrimitiveModes/glTF-Embedded/MeshPrimitiveModes.gltf");
    let v = json_of(Path::new(&path));
    let s = load_ok(&path);
    assert_eq!(s.triangle_count(), expected(&v, None).triangles);
    assert_eq!(s.meshes.len(), 3, "TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN");
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    assert!(s.warnings[0].contains("point/line"), "{:?}", s.warnings);
    // Strips and fans keep one consistent winding: all faces of each planar mesh point the same way.
    for m in &s.meshes {
        let normals: Vec<Vec3> = m.indices.iter().map(|t| geometric_normal(m, t)).collect();
        assert!(normals.iter().all(|n| n.dot(normals[0]) > 0.99), "{}: {normals:?}", m.name);
    }
}

fn geometric_normal(m: &Mesh, t: &[u32; 3]) -> Vec3 {
    let [a, b, c] = t.map(|i| m.positions[i as usize]);
    (b - a).cross(c - a).normalize_or_zero()
}

#[test]
fn negative_scale_flips_winding() {
    let s = load_ok(&khronos("NegativeScaleTest/glTF-Binary/NegativeScaleTest.glb"));
    let (mut checked, mut bad) = (0, 0);
    for m in &s.meshes {
        for t in &m.indices {
            let g = geometric_normal(m, t);
            if g == Vec3::ZERO {
                continue;
            }
            let average: Vec3 = t.iter().map(|&i| m.normals[i as usize]).sum();
            checked += 1;
            bad += (g.dot(average) <= 0.0) as usize;
        }
    }
    assert!(checked > 7000);
    assert_eq!(bad, 0, "{bad} of {checked} triangles face away from their vertex normals");
}

#[test]
fn emissive_strength_multiplies() {
    let s = load_ok(&khronos("EmissiveStrengthTest/glTF-Binary/EmissiveStrengthTest.glb"));
    let factor = Vec3::new(0.1, 0.5, 0.9);
    for (name, strength) in [("Emit1", 1.0), ("Emit2", 2.0), ("Emit4", 4.0), ("Emit8", 8.0), ("Emit16", 16.0)] {
        assert!(close3(material(&s, name).emission, factor * strength, 1e-6), "{name}");
    }
    assert_eq!(material(&s, "FlatBackdrop").emission, Vec3::ZERO);
}

/// 3×3 product of row-major affine matrices.
fn mul(a: [[f32; 3]; 3], b: [[f32; 3]; 3]) -> [[f32; 3]; 3] {
    let mut c = [[0.0; 3]; 3];
    for (i, row) in c.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

/// KHR_texture_transform's matrix built literally as the extension's README does: T * R * S.
fn trs(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> [[f32; 3]; 2] {
    let (s, c) = rotation.sin_cos();
    let t = [[1.0, 0.0, offset[0]], [0.0, 1.0, offset[1]], [0.0, 0.0, 1.0]];
    let r = [[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]];
    let sc = [[scale[0], 0.0, 0.0], [0.0, scale[1], 0.0], [0.0, 0.0, 1.0]];
    let m = mul(mul(t, r), sc);
    [m[0], m[1]]
}

#[test]
fn texture_transforms() {
    let s = load_ok(&khronos("TextureTransformTest/glTF/TextureTransformTest.gltf"));
    let transform = |name: &str| material(&s, name).base_color_texture.as_ref().unwrap().transform;
    // Values from the JSON (rotation 0.39269908169872414 = π/8).
    let cases = [
        ("Offset U", trs([0.5, 0.0], 0.0, [1.0, 1.0])),
        ("Offset V", trs([0.0, 0.5], 0.0, [1.0, 1.0])),
        ("Offset UV", trs([0.5, 0.5], 0.0, [1.0, 1.0])),
        ("Rotation", trs([0.0, 0.0], std::f32::consts::FRAC_PI_8, [1.0, 1.0])),
        ("Scale", trs([0.0, 0.0], 0.0, [1.5, 1.5])),
        ("All", trs([-0.2, -0.1], 0.3, [1.5, 1.5])),
        ("Correct", trs([0.0, 0.0], 0.0, [1.0, 1.0])),
    ];
    for (name, want) in cases {
        let got = transform(name);
        let ok = (0..2).all(|r| (0..3).all(|c| close(got[r][c], want[r][c], 1e-6)));
        assert!(ok, "{name}: {got:?} != {want:?}");
    }
    assert_ne!(transform("All"), trs([0.0, 0.0], 0.0, [1.0, 1.0]));
    // Sampler 0 clamps both axes; textures without a sampler repeat.
    assert_eq!(base_texture(&s, "Offset U").wrap_s, Wrap::Clamp);
    assert_eq!(base_texture(&s, "Correct").wrap_t, Wrap::Repeat);
}

#[test]
fn texture_settings_wrap_modes() {
    let s = load_ok(&khronos("TextureSettingsTest/glTF-Binary/TextureSettingsTest.glb"));
    let wraps = |name: &str| {
        let t = base_texture(&s, name);
        (t.wrap_s, t.wrap_t)
    };
    assert_eq!(wraps("TextureMirrorMaterialT"), (Wrap::Repeat, Wrap::Mirror));
    assert_eq!(wraps("TextureMirrorMaterialS"), (Wrap::Mirror, Wrap::Repeat));
    assert_eq!(wraps("TextureClampMaterialT"), (Wrap::Repeat, Wrap::Clamp));
    assert_eq!(wraps("TextureClampMaterialS"), (Wrap::Clamp, Wrap::Repeat));
    assert_eq!(wraps("TextureRepeatMaterialT"), (Wrap::Clamp, Wrap::Repeat));
    assert_eq!(wraps("DoubleSidedMaterial"), (Wrap::Repeat, Wrap::Repeat));
    // 9 glTF textures over 3 images and 5 samplers; two share image 1 and sampler 0.
    assert_eq!(s.textures.len(), 8);
    assert!(s.textures.iter().all(|t| !t.nearest));
}

#[test]
fn nearest_filter_and_embedded_image() {
    let s = load_ok(&format!("{TESTDATA}/robustness/atteneder/FormatVariants/glTF-Embedded/FormatVariants.gltf"));
    assert_eq!(s.textures.len(), 1);
    assert!(s.textures[0].nearest, "magFilter 9728 = NEAREST");
}

#[test]
fn unicode_file_name() {
    let s = load_ok(&khronos("Unicode❤♻Test/glTF-Binary/Unicode❤♻Test.glb"));
    assert_eq!(s.name, "Unicode❤♻Test");
    assert_eq!(s.triangle_count(), 2);
    assert_eq!(s.textures.len(), 1);
}

// ------------------------------------------------------------------------------------------------------
// The comparison scenes (numbers from ../shared/scenes/*/README.md)

#[test]
fn veach_mis_scene() {
    let s = load_ok(&format!("{SCENES}/veach-mis/veach_mis.gltf"));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let floor = material(&s, "floor");
    assert_eq!((floor.specular, floor.metallic, floor.base_color), (0.0, 0.0, Vec3::splat(0.4)));
    for (name, alpha) in [("plate1", 0.005f32), ("plate2", 0.02), ("plate3", 0.05), ("plate4", 0.1)] {
        let m = material(&s, name);
        assert_eq!((m.metallic, m.base_color), (1.0, Vec3::ONE), "{name}");
        assert!(close(m.roughness, alpha.sqrt(), 1e-6) && close(m.alpha(), alpha, 1e-5), "{name}");
    }
    for (name, radiance) in [
        ("light_r0.03333_emitter", 901.803),
        ("light_r0.1_emitter", 100.0),
        ("light_r0.3_emitter", 11.1111),
        ("light_r0.9_emitter", 1.23457),
        ("fill_light_emitter", 800.0),
    ] {
        let m = material(&s, name);
        assert!(close3(m.emission, Vec3::splat(radiance), 1e-6), "{name}: {}", m.emission);
        assert_eq!((m.base_color, m.specular), (Vec3::ZERO, 0.0));
    }
    let forward = (Vec3::new(0.0, -2.0, 2.5) - Vec3::new(0.0, 2.0, 15.0)).normalize();
    assert!(close3(s.camera.position, Vec3::new(0.0, 2.0, 15.0), 1e-6));
    assert!(close3(s.camera.forward, forward, 1e-5), "{}", s.camera.forward);
    assert!(close(s.camera.vfov.to_degrees(), 41.0108, 1e-5), "{}", s.camera.vfov.to_degrees());
    // Plate 1's first vertex, counter-clockwise from the front.
    let plate1 = s.meshes.iter().find(|m| m.name == "plate1").unwrap();
    assert!(plate1.positions.iter().any(|p| close3(*p, Vec3::new(4.0, -2.70651, 0.25609), 1e-5)));
}

#[test]
fn cornell_box_scene() {
    let s = load_ok(&format!("{SCENES}/cornell-box/cbox.gltf"));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    for (name, rgb) in [("white", [0.725, 0.71, 0.68]), ("red", [0.63, 0.065, 0.05]), ("green", [0.14, 0.45, 0.091])] {
        let m = material(&s, name);
        assert_eq!((m.base_color, m.specular, m.metallic), (Vec3::from(rgb), 0.0, 0.0), "{name}");
        assert!(!m.is_emissive());
    }
    let light = material(&s, "light_emitter");
    assert!(close3(light.emission, Vec3::new(17.0, 12.0, 4.0), 1e-6), "{}", light.emission);
    assert!(close3(s.camera.position, Vec3::new(0.0, 1.0, 6.8), 1e-6));
    assert!(close3(s.camera.forward, Vec3::NEG_Z, 1e-6));
    assert!(close(s.camera.vfov.to_degrees(), 19.5, 1e-5));
    // The light quad at y = 1.98 emits downward: its triangles' CCW normal is -Y.
    let quad = s.meshes.iter().find(|m| m.name == "light").unwrap();
    assert!(quad.positions.iter().all(|p| close(p.y, 1.98, 1e-6)));
    assert!(quad.indices.iter().all(|t| close3(geometric_normal(quad, t), Vec3::NEG_Y, 1e-5)));
    assert_eq!(s.triangle_count(), 36);
}

// ------------------------------------------------------------------------------------------------------
// Robustness corpus: every file either fails with a specific message naming it, or loads with warnings.

#[test]
fn robustness_corpus() {
    // (file name, Err substring or None for Ok, substring of a warning when Ok).
    let table: &[(&str, Option<&str>, &str)] = &[
        ("BoxBadNormals.glb", None, "normal"),
        ("BoxWithInfinites.glb", Some("non-finite vertex position"), ""),
        ("IndexOutOfRange.gltf", Some("index 255 at position 0 is out of range"), ""),
        ("AllIndicesOutOfRange.gltf", Some("out of range (the primitive has 24 vertices)"), ""),
        ("texcoord_crash.gltf", None, "no TEXCOORD_0"),
        ("RecursiveNodes.gltf", Some("cycle"), ""),
        ("MissingBin/BoxTextured.gltf", Some("BoxTextured0.bin"), ""),
        ("TestNoRootNode/NoScene.gltf", None, "no scenes"),
        ("SceneWithoutNodes.gltf", None, "nothing to render"),
        ("Empty.gltf", None, "nothing to render"),
        ("OnlyAccessors.gltf", None, "nothing to render"),
        ("EmbedBufferInvalid.gltf", Some("not base64-encoded"), ""),
        // atteneder's NoScene has a scene but no default: scene 0 is used, with a warning.
        ("atteneder/NoScene/NoScene.gltf", None, "no default scene"),
        // A valid file (embedded image + buffer); it loads cleanly: an Ok without warnings is right here.
        ("FormatVariants.gltf", None, ""),
    ];
    let files = files_under(&format!("{TESTDATA}/robustness"));
    assert_eq!(files.len(), table.len(), "update the table: {files:?}");
    for f in files {
        let shown = f.to_string_lossy();
        let (_, err, warning) =
            table.iter().find(|(name, ..)| shown.ends_with(name)).unwrap_or_else(|| panic!("{shown} not in the table"));
        let file_name = f.file_name().unwrap().to_string_lossy();
        match (load_no_panic(&f), err) {
            (Err(e), Some(want)) => assert!(e.contains(&*file_name) && e.contains(want), "{e}"),
            (Ok(s), None) if warning.is_empty() => {
                assert!(s.warnings.is_empty() && s.triangle_count() > 0, "{shown}: {:?}", s.warnings)
            }
            (Ok(s), None) => assert!(s.warnings.iter().any(|w| w.contains(warning)), "{shown}: {:?}", s.warnings),
            (result, _) => panic!("{shown}: unexpected {:?}", result.map(|s| s.warnings)),
        }
    }
}

/// A missing buffer's message keeps the file name however long the directory path is (CI's checkout lies
/// deeper than a developer's).
#[test]
fn missing_buffer_named_under_a_long_path() {
    let deep =
        std::env::temp_dir().join(format!("mislab-{}-{}", std::process::id(), "d".repeat(120))).join("e".repeat(100));
    std::fs::create_dir_all(&deep).unwrap();
    let gltf = deep.join("BoxTextured.gltf");
    std::fs::copy(format!("{TESTDATA}/robustness/assimp/MissingBin/BoxTextured.gltf"), &gltf).unwrap();
    let e = load_no_panic(&gltf).unwrap_err();
    std::fs::remove_dir_all(deep.parent().unwrap()).unwrap();
    assert!(e.contains("BoxTextured0.bin") && e.contains("no such file"), "{e}");
}

#[test]
fn repaired_content_of_the_robustness_files() {
    let bad_normals = load_ok(&format!("{TESTDATA}/robustness/assimp/BoxBadNormals-glTF-Binary/BoxBadNormals.glb"));
    assert_eq!(bad_normals.triangle_count(), 12);
    assert_mesh_sane(&bad_normals.meshes[0], Path::new("BoxBadNormals"));
    // Every position has an infinite x: corrupt data is refused, naming the vertex.
    let infinites = load_no_panic(Path::new(&format!(
        "{TESTDATA}/robustness/assimp/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb"
    )));
    let e = infinites.expect_err("a NaN/Inf position must be an error");
    assert!(e.contains("BoxWithInfinites.glb") && e.contains("non-finite vertex position: vertex 0"), "{e}");
}

#[test]
fn draco_is_rejected_by_name() {
    let e = load_err(&khronos("Box/glTF-Draco/Box.gltf"));
    assert!(e.contains("Box.gltf") && e.contains("KHR_draco_mesh_compression"), "{e}");
}

#[test]
fn missing_truncated_and_garbage_files() {
    let dir = scratch("files");
    let missing = dir.join("missing.gltf");
    let e = load_err(missing.to_str().unwrap());
    assert!(e.contains("missing.gltf"), "{e}");
    let e = scene::gltf::load(&missing, &LoadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("missing.gltf") && e.contains("no such file"), "{e}");

    let glb = std::fs::read(khronos("Box/glTF-Binary/Box.glb")).unwrap();
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("cut.glb", glb[..1000].to_vec(), "truncated GLB"),
        ("header-only.glb", glb[..10].to_vec(), "truncated GLB"),
        ("magic.glb", [b"gLTF", &glb[4..]].concat(), "magic"),
        ("version.glb", [&glb[..4], &[1, 0, 0, 0], &glb[8..]].concat(), "version 1"),
        ("short-bin.glb", shorten_bin_chunk(&glb, 100), "only 100 bytes of data"),
        ("garbage.glb", (0..777u32).map(|i| ((i * 2654435761u32) >> 13) as u8).collect(), "magic"),
        ("garbage.gltf", (0..777u32).map(|i| ((i * 2654435761u32) >> 13) as u8).collect(), "invalid glTF JSON"),
        ("empty.gltf", Vec::new(), "invalid glTF JSON"),
        ("not-an-object.gltf", b"[1, 2, 3]".to_vec(), "invalid glTF JSON"),
        ("version1.gltf", br#"{"asset": {"version": "1.0"}}"#.to_vec(), "version '1.0'"),
    ];
    for (name, bytes, want) in cases {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let e = load_no_panic(&path).expect_err(name);
        assert!(e.contains(name) && e.contains(want), "{name}: {e}");
    }
}

/// A copy of a GLB whose BIN chunk (and declared lengths) were cut to `keep` bytes.
fn shorten_bin_chunk(glb: &[u8], keep: usize) -> Vec<u8> {
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let bin_header = 20 + json_len;
    let mut out = glb[..bin_header + 8 + keep].to_vec();
    out[bin_header..bin_header + 4].copy_from_slice(&(keep as u32).to_le_bytes());
    let total = out.len() as u32;
    out[8..12].copy_from_slice(&total.to_le_bytes());
    out
}

// ------------------------------------------------------------------------------------------------------
// Hand-made files: one valid triangle, then one defect at a time.

fn parse(text: &str) -> Value {
    gltf::json::deserialize::from_str(text).unwrap()
}

fn b64(bytes: &[u8]) -> String {
    use base64::Engine;
    format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes))
}

/// Bytes of f32 positions then u16 indices (padded to 4).
fn triangle_buffer(positions: &[[f32; 3]], indices: &[u16]) -> Vec<u8> {
    let mut bytes: Vec<u8> = positions.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    bytes.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    while !bytes.len().is_multiple_of(4) {
        bytes.push(0);
    }
    bytes
}

/// A valid glTF with one CCW triangle in the XY plane (normal +Z), indexed, with NORMALs.
fn triangle_gltf() -> Value {
    let positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let normals = [[0.0, 0.0, 1.0]; 3];
    let mut bytes = triangle_buffer(&positions, &[0, 1, 2]);
    bytes.extend(normals.iter().flatten().flat_map(|x: &f32| x.to_le_bytes()));
    let mut v = parse(
        r#"{
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "tri"}],
        "meshes": [{"name": "Tri", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 2}, "indices": 1}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 6},
            {"buffer": 0, "byteOffset": 44, "byteLength": 36}
        ],
        "buffers": [{"byteLength": 80}]
    }"#,
    );
    v["buffers"][0]["uri"] = b64(&bytes).into();
    v
}

fn write_json(dir: &Path, name: &str, v: &Value) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, gltf::json::serialize::to_string(v).unwrap()).unwrap();
    path
}

#[test]
fn hand_made_valid_triangle() {
    let dir = scratch("valid");
    let s = load_no_panic(&write_json(&dir, "tri.gltf", &triangle_gltf())).unwrap();
    assert_eq!(s.triangle_count(), 1);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.meshes[0].name, "Tri");
    assert_eq!(s.materials[0], Material::default());
}

#[test]
fn hand_made_defects_give_specific_errors() {
    type Edit = fn(&mut Value);
    let cases: &[(&str, Edit, &str)] = &[
        (
            "missing-accessor",
            |v| v["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 7.into(),
            "accessor 7 (POSITION of mesh 'Tri' primitive 0) does not exist",
        ),
        (
            "stride",
            |v| v["bufferViews"][0]["byteStride"] = 4.into(),
            "accessor 0 (POSITION of mesh 'Tri' primitive 0): byteStride 4 is smaller than the element size 12",
        ),
        ("past-view", |v| v["accessors"][0]["count"] = 10.into(), "do not fit in bufferView 0"),
        ("offset-past-view", |v| v["accessors"][0]["byteOffset"] = 4.into(), "do not fit in bufferView 0"),
        ("view-past-buffer", |v| v["bufferViews"][2]["byteLength"] = 400.into(), "extends past the end of buffer 0"),
        ("short-buffer", |v| v["buffers"][0]["byteLength"] = 1000.into(), "byteLength is 1000 but only 80 bytes"),
        (
            "index-range",
            |v| {
                v["accessors"][0]["count"] = 2.into();
                v["meshes"][0]["primitives"][0]["attributes"] = parse(r#"{"POSITION": 0}"#);
            },
            "index 2 at position 2 is out of range (the primitive has 2 vertices)",
        ),
        ("normal-count", |v| v["accessors"][2]["count"] = 2.into(), "count 2 differs from the POSITION count 3"),
        ("cycle", |v| v["nodes"] = parse(r#"[{"mesh": 0, "children": [1]}, {"children": [0]}]"#), "cycle"),
        ("self-cycle", |v| v["nodes"][0]["children"] = parse("[0]"), "cycle"),
        ("bad-node", |v| v["scenes"][0]["nodes"] = parse("[5]"), "node 5 does not exist"),
        ("bad-mesh", |v| v["nodes"][0]["mesh"] = 3.into(), "mesh 3 does not exist"),
        ("bad-material", |v| v["meshes"][0]["primitives"][0]["material"] = 3.into(), "material 3 does not exist"),
        ("bad-view", |v| v["accessors"][1]["bufferView"] = 9.into(), "bufferView 9 does not exist"),
        ("bad-buffer", |v| v["bufferViews"][0]["buffer"] = 4.into(), "names buffer 4"),
        ("component", |v| v["accessors"][0]["componentType"] = 5123.into(), "componentType 5123"),
        ("type", |v| v["accessors"][0]["type"] = "VEC2".into(), "type VEC2 is not valid for POSITION"),
        ("index-type", |v| v["accessors"][1]["componentType"] = 5126.into(), "not valid for indices"),
        (
            "huge-count",
            |v| v["accessors"][0] = parse(r#"{"componentType": 5126, "count": 4000000000, "type": "VEC3"}"#),
            "exceeds the limit",
        ),
        (
            "bad-base64",
            |v| v["buffers"][0]["uri"] = "data:application/octet-stream;base64,@@@@".into(),
            "invalid base64",
        ),
        (
            "plain-data-uri",
            |v| v["buffers"][0]["uri"] = "data:application/octet-stream,abc".into(),
            "not base64-encoded",
        ),
        ("remote-uri", |v| v["buffers"][0]["uri"] = "https://example.com/a.bin".into(), "nothing is downloaded"),
        ("missing-bin", |v| v["buffers"][0]["uri"] = "nothere.bin".into(), "nothere.bin"),
        ("bad-rotation", |v| v["nodes"][0]["rotation"] = parse("[0, 0, 0, 0]"), "not a valid quaternion"),
        ("bad-scene", |v| v["scene"] = 3.into(), "scene 3 is the default scene, but the file has 1 scene"),
        (
            "required-ext",
            |v| v["extensionsRequired"] = parse(r#"["EXT_meshopt_compression"]"#),
            "EXT_meshopt_compression",
        ),
        ("quantization", |v| v["extensionsRequired"] = parse(r#"["KHR_mesh_quantization"]"#), "KHR_mesh_quantization"),
        ("bad-mode", |v| v["meshes"][0]["primitives"][0]["mode"] = 9.into(), "invalid primitive mode"),
        (
            "sparse-range",
            |v| {
                // Two positions; the sparse index is read from the index view's third entry, 2.
                v["accessors"][0]["count"] = 2.into();
                v["accessors"][0]["sparse"] = parse(
                    r#"{"count": 1, "indices": {"bufferView": 1, "byteOffset": 4, "componentType": 5123}, "values": {"bufferView": 2}}"#,
                );
            },
            "sparse index 2 (entry 0) is out of range: the accessor has 2 elements",
        ),
        (
            "missing-light",
            |v| v["nodes"][0]["extensions"] = parse(r#"{"KHR_lights_punctual": {"light": 0}}"#),
            "KHR_lights_punctual light 0 does not exist",
        ),
    ];
    let dir = scratch("defects");
    for (name, edit, want) in cases {
        let mut v = triangle_gltf();
        edit(&mut v);
        let file = format!("{name}.gltf");
        let e = load_no_panic(&write_json(&dir, &file, &v)).expect_err(name);
        assert!(e.contains(&file) && e.contains(want), "{name}: {e}");
    }
}

#[test]
fn mirrored_node_keeps_normals_outward() {
    let dir = scratch("mirror");
    let mut v = triangle_gltf();
    v["nodes"][0]["scale"] = parse("[-1, 1, 1]");
    let s = load_no_panic(&write_json(&dir, "mirror.gltf", &v)).unwrap();
    let m = &s.meshes[0];
    // Mirroring x maps the +Z triangle to a +Z triangle with reversed vertex order; swapping restores CCW.
    assert_eq!(m.indices, vec![[0, 2, 1]]);
    assert!(close3(geometric_normal(m, &m.indices[0]), Vec3::Z, 1e-6));
    assert!(m.normals.iter().all(|n| close3(*n, Vec3::Z, 1e-6)));
    assert_eq!(m.positions[1], Vec3::new(-1.0, 0.0, 0.0));

    // A matrix with a non-uniform scale and a translation (column-major): normals use the inverse transpose.
    let mut v = triangle_gltf();
    v["nodes"][0]["matrix"] = parse("[2,0,0,0, 0,1,0,0, 0,0,1,0, 5,6,7,1]");
    v["accessors"][2]["bufferView"] = 3.into();
    v["bufferViews"].as_array_mut().unwrap().push(parse(r#"{"buffer": 1, "byteLength": 36}"#));
    let tilted: Vec<u8> = [[1.0f32, 0.0, 1.0]; 3].iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    v["buffers"].as_array_mut().unwrap().push(parse(r#"{"byteLength": 36}"#));
    v["buffers"][1]["uri"] = b64(&tilted).into();
    let s = load_no_panic(&write_json(&dir, "matrix.gltf", &v)).unwrap();
    let m = &s.meshes[0];
    assert_eq!(m.positions[1], Vec3::new(7.0, 6.0, 7.0));
    assert!(close3(m.normals[0], Vec3::new(0.5, 0.0, 1.0).normalize(), 1e-6), "{}", m.normals[0]);
}

#[test]
fn non_finite_vertices_are_refused_when_used_and_normals_generated() {
    let dir = scratch("nan");
    let positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [f32::NAN, 0.0, 0.0]];
    let gltf_with = |indices: &[u16]| {
        let bytes = triangle_buffer(&positions, indices);
        let mut v = triangle_gltf();
        v["buffers"][0] = parse(&format!(r#"{{"byteLength": {}}}"#, bytes.len()));
        v["buffers"][0]["uri"] = b64(&bytes).into();
        let ib = 2 * indices.len();
        v["bufferViews"] = parse(&format!(
            r#"[{{"buffer": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": {ib}}}]"#
        ));
        v["accessors"][0]["count"] = 4.into();
        v["accessors"][1]["count"] = indices.len().into();
        v["meshes"][0]["primitives"][0]["attributes"] = parse(r#"{"POSITION": 0}"#);
        v
    };
    // A triangle uses the NaN vertex: corrupt data, refused with the vertex named.
    let e =
        load_no_panic(&write_json(&dir, "nan.gltf", &gltf_with(&[0, 1, 2, 1, 3, 2]))).expect_err("NaN position in use");
    assert!(e.contains("nan.gltf") && e.contains("non-finite vertex position: vertex 3 is (NaN, 0, 0)"), "{e}");
    // No triangle uses it: nothing to refuse; the normals are generated from the geometry.
    let s = load_no_panic(&write_json(&dir, "unused.gltf", &gltf_with(&[0, 1, 2]))).unwrap();
    let m = &s.meshes[0];
    assert_eq!(m.indices.len(), 1);
    for t in &m.indices {
        assert!(t.iter().all(|&i| m.positions[i as usize].is_finite() && close3(m.normals[i as usize], Vec3::Z, 1e-6)));
    }
}

#[test]
fn strips_fans_and_normalized_uvs() {
    let dir = scratch("strip");
    // Five vertices zig-zagging along +X in the XY plane; as a strip or fan every face points the same way
    // (-Z for this vertex order).
    let positions = [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [2.0, 0.0, 0.0]];
    let mut bytes = triangle_buffer(&positions, &[]);
    bytes.extend([0u8, 0, 255, 255, 255, 0, 0, 255, 128, 128, 0, 0]); // 5 normalized UBYTE UV pairs + pad
    let mut v = triangle_gltf();
    v["buffers"][0] = parse(&format!(r#"{{"byteLength": {}}}"#, bytes.len()));
    v["buffers"][0]["uri"] = b64(&bytes).into();
    v["bufferViews"] = parse(r#"[{"buffer": 0, "byteLength": 60}, {"buffer": 0, "byteOffset": 60, "byteLength": 10}]"#);
    v["accessors"] = parse(
        r#"[{"bufferView": 0, "componentType": 5126, "count": 5, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5121, "normalized": true, "count": 5, "type": "VEC2"}]"#,
    );
    v["meshes"][0]["primitives"] = parse(r#"[{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "mode": 5}]"#);
    let s = load_no_panic(&write_json(&dir, "strip.gltf", &v)).unwrap();
    let m = &s.meshes[0];
    assert_eq!(m.indices.len(), 3);
    assert!(m.indices.iter().all(|t| close3(geometric_normal(m, t), Vec3::NEG_Z, 1e-6)), "{:?}", m.indices);
    assert_eq!(m.uvs[1], Vec2::new(1.0, 1.0));
    assert!(close(m.uvs[4].x, 128.0 / 255.0, 1e-6));
    // The same vertices as a fan around vertex 0.
    v["meshes"][0]["primitives"][0]["mode"] = 6.into();
    let s = load_no_panic(&write_json(&dir, "fan.gltf", &v)).unwrap();
    assert_eq!(s.meshes[0].indices, vec![[1, 2, 0], [2, 3, 0], [3, 4, 0]]);
}

/// A triangle with a textured material whose image is `uri`, plus extras applied by `edit`.
fn textured(dir: &Path, name: &str, uri: &str, edit: fn(&mut Value)) -> PathBuf {
    let mut v = triangle_gltf();
    v["materials"] = parse(r#"[{"name": "tex", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]"#);
    v["meshes"][0]["primitives"][0]["material"] = 0.into();
    v["textures"] = parse(r#"[{"source": 0}]"#);
    v["images"] = parse("[{}]");
    v["images"][0]["uri"] = uri.into();
    edit(&mut v);
    write_json(dir, name, &v)
}

#[test]
fn texture_files_sizes_and_errors() {
    let dir = scratch("textures");
    image::RgbaImage::from_pixel(1, 1, image::Rgba([10, 20, 30, 40])).save(dir.join("one.png")).unwrap();
    image::RgbaImage::new(16385, 1).save(dir.join("wide.png")).unwrap();
    std::fs::write(dir.join("junk.png"), b"definitely not a png").unwrap();

    let s = load_no_panic(&textured(&dir, "one.gltf", "one.png", |_| {})).unwrap();
    assert_eq!((s.textures[0].width, s.textures[0].height, &s.textures[0].texels[..]), (1, 1, &[[10, 20, 30, 40]][..]));
    assert!(s.warnings.iter().any(|w| w.contains("no TEXCOORD_0")), "{:?}", s.warnings);

    let e = load_no_panic(&textured(&dir, "wide.gltf", "wide.png", |_| {})).unwrap_err();
    assert!(e.contains("wide.png") && e.contains("16385×1") && e.contains("16384"), "{e}");
    let e = load_no_panic(&textured(&dir, "junk.gltf", "junk.png", |_| {})).unwrap_err();
    assert!(e.contains("junk.png") && e.contains("cannot decode"), "{e}");
    let e = load_no_panic(&textured(&dir, "absent.gltf", "absent%20file.png", |_| {})).unwrap_err();
    assert!(e.contains("absent file.png") && e.contains("cannot read"), "{e}");
    let e = load_no_panic(&textured(&dir, "bad-tex.gltf", "one.png", |v| v["textures"][0]["source"] = 4.into()))
        .unwrap_err();
    assert!(e.contains("image 4 does not exist"), "{e}");
    let e = load_no_panic(&textured(&dir, "bad-sampler.gltf", "one.png", |v| v["textures"][0]["sampler"] = 2.into()))
        .unwrap_err();
    assert!(e.contains("sampler 2 does not exist"), "{e}");
}

#[test]
fn one_image_two_colour_spaces_and_texcoord_override() {
    let dir = scratch("colourspaces");
    image::RgbaImage::from_pixel(2, 2, image::Rgba([1, 2, 3, 255])).save(dir.join("img.png")).unwrap();
    let path = textured(&dir, "both.gltf", "img.png", |v| {
        v["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"] = parse(r#"{"index": 0}"#);
        v["materials"][0]["emissiveFactor"] = parse("[1, 1, 1]");
        v["materials"][0]["emissiveTexture"] =
            parse(r#"{"index": 0, "extensions": {"KHR_texture_transform": {"texCoord": 1, "offset": [0.25, 0]}}}"#);
        v["samplers"] = parse(r#"[{"magFilter": 9728, "wrapS": 33648, "wrapT": 33071}]"#);
        v["textures"][0]["sampler"] = 0.into();
    });
    let s = load_no_panic(&path).unwrap();
    let m = &s.materials[0];
    // Base colour and emissive share the sRGB texture; metallic-roughness gets its own linear copy.
    assert_eq!(s.textures.len(), 2);
    let (base, mr, em) = (
        m.base_color_texture.as_ref().unwrap(),
        m.metallic_roughness_texture.as_ref().unwrap(),
        m.emissive_texture.as_ref().unwrap(),
    );
    assert_eq!(base.texture, em.texture);
    assert_ne!(base.texture, mr.texture);
    assert!(s.textures[base.texture as usize].srgb && !s.textures[mr.texture as usize].srgb);
    let t = &s.textures[mr.texture as usize];
    assert_eq!((t.wrap_s, t.wrap_t, t.nearest), (Wrap::Mirror, Wrap::Clamp, true));
    assert_eq!(em.transform, [[1.0, 0.0, 0.25], [0.0, 1.0, 0.0]]);
    assert_eq!(em.texcoord, 0);
    assert!(s.warnings.iter().any(|w| w.contains("TEXCOORD_1")), "{:?}", s.warnings);
}

#[test]
fn lights_cameras_and_scenes_from_hand_made_nodes() {
    let dir = scratch("lights");
    let mut v = triangle_gltf();
    v["extensionsUsed"] = parse(r#"["KHR_lights_punctual"]"#);
    v["extensions"] = parse(
        r#"{"KHR_lights_punctual": {"lights": [
            {"type": "spot", "color": [1, 0.5, 0.25], "intensity": 4},
            {"type": "directional", "intensity": 2},
            {"type": "point", "intensity": -1}
        ]}}"#,
    );
    v["cameras"] = parse(r#"[{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}]"#);
    v["nodes"] = parse(
        r#"[{"mesh": 0, "children": [1, 2, 3]},
            {"translation": [1, 2, 3], "rotation": [-0.7071068, 0, 0, 0.7071068], "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"extensions": {"KHR_lights_punctual": {"light": 1}}, "children": [4]},
            {"extensions": {"KHR_lights_punctual": {"light": 2}}},
            {"translation": [0, 0, 10], "camera": 0}]"#,
    );
    let s = load_no_panic(&write_json(&dir, "lights.gltf", &v)).unwrap();
    assert_eq!(s.punctual_lights.len(), 2, "the negative-intensity light is skipped");
    let PunctualLight::Spot { position, direction, intensity, inner_cone, outer_cone } = &s.punctual_lights[0] else {
        panic!()
    };
    // Rotating -90° about X turns the node's -Z into -Y: the spot points down.
    assert!(close3(*position, Vec3::new(1.0, 2.0, 3.0), 1e-6));
    assert!(close3(*direction, Vec3::NEG_Y, 1e-6), "{direction}");
    assert!(close3(*intensity, Vec3::new(4.0, 2.0, 1.0), 1e-6));
    assert_eq!((*inner_cone, *outer_cone), (0.0, std::f32::consts::FRAC_PI_4));
    assert_eq!(
        s.punctual_lights[1],
        PunctualLight::Directional { direction: Vec3::NEG_Z, irradiance: Vec3::splat(2.0) }
    );
    assert!(s.warnings.iter().any(|w| w.contains("light 2")), "{:?}", s.warnings);
    assert!(close3(s.camera.position, Vec3::new(0.0, 0.0, 10.0), 1e-6) && s.camera.vfov == 0.5);
}

#[test]
fn scenes_missing_or_empty() {
    let dir = scratch("noscene");
    // No scenes at all: every parentless node is instantiated, with a warning.
    let mut v = triangle_gltf();
    v.as_object_mut().unwrap().remove("scenes");
    v.as_object_mut().unwrap().remove("scene");
    let s = load_no_panic(&write_json(&dir, "noscenes.gltf", &v)).unwrap();
    assert_eq!(s.triangle_count(), 1);
    assert!(s.warnings.iter().any(|w| w.contains("no scenes")), "{:?}", s.warnings);
    // An empty scene is not an error.
    let mut v = triangle_gltf();
    v["scenes"][0]["nodes"] = parse("[]");
    let s = load_no_panic(&write_json(&dir, "empty.gltf", &v)).unwrap();
    assert_eq!(s.triangle_count(), 0);
    assert!(!s.warnings.is_empty());
    // A node shared by two parents (not a cycle) is instanced twice.
    let mut v = triangle_gltf();
    v["nodes"] = parse(r#"[{"children": [2]}, {"children": [2], "translation": [5, 0, 0]}, {"mesh": 0}]"#);
    v["scenes"][0]["nodes"] = parse("[0, 1]");
    let s = load_no_panic(&write_json(&dir, "shared.gltf", &v)).unwrap();
    assert_eq!(s.meshes.len(), 2);
    assert_eq!(s.meshes[1].positions[0], Vec3::new(5.0, 0.0, 0.0));
}

#[test]
fn deep_and_exploding_hierarchies_are_bounded() {
    let dir = scratch("deep");
    let chain = |n: usize| -> Value {
        let nodes: Vec<String> = (0..n)
            .map(|i| if i + 1 < n { format!(r#"{{"children": [{}]}}"#, i + 1) } else { r#"{"mesh": 0}"#.into() })
            .collect();
        parse(&format!("[{}]", nodes.join(",")))
    };
    // 400 levels load (and do not overflow the stack); 600 exceed the depth limit.
    let mut v = triangle_gltf();
    v["nodes"] = chain(400);
    assert_eq!(load_no_panic(&write_json(&dir, "deep400.gltf", &v)).unwrap().triangle_count(), 1);
    v["nodes"] = chain(600);
    let e = load_no_panic(&write_json(&dir, "deep600.gltf", &v)).unwrap_err();
    assert!(e.contains("deep600.gltf") && e.contains("deeper than"), "{e}");
    // Each node lists its successor twice: 2^40 instances if followed naively.
    let nodes: Vec<String> =
        (0..40).map(|i| format!(r#"{{"children": [{0}, {0}]}}"#, i + 1)).chain([r#"{"mesh": 0}"#.into()]).collect();
    v["nodes"] = parse(&format!("[{}]", nodes.join(",")));
    let e = load_no_panic(&write_json(&dir, "bomb.gltf", &v)).unwrap_err();
    assert!(e.contains("bomb.gltf") && e.contains("node instances"), "{e}");
}
