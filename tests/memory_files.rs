//! Scene files given as bytes (a web page's dropped files, `io::memory_files`) load into the same scene as the
//! same files on disk, in every format, with their meshes, textures, includes and environment maps; named with
//! their folders or, as a browser drops them, without; and a missing reference names itself.

use mislab::io::memory_files::MemoryFiles;
use mislab::render::{packed_scene, scene_data::SceneData};
use mislab::scene::{load, load_from_files, LoadOptions};
use std::path::{Path, PathBuf};

fn shared(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared").join(rel)
}

/// Every file under `dir` (skipping reference renders), named relative to it, or by its file name alone.
fn files_of(dir: &Path, flat: bool) -> MemoryFiles {
    let mut files = MemoryFiles::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if !path.file_name().unwrap().to_str().unwrap().starts_with("TungstenRender") {
                let name = if flat { path.file_name().unwrap().into() } else { path.strip_prefix(dir).unwrap().into() };
                let name: PathBuf = name;
                files.insert(name.to_str().unwrap(), std::fs::read(&path).unwrap());
            }
        }
    }
    files
}

/// The scene's GPU tables, word for word: what the renderer would upload.
fn tables(scene: &mislab::scene::Scene) -> Vec<u32> {
    packed_scene::pack(&SceneData::build(scene))
}

fn same_from_memory(dir: &Path, main: &str) {
    let options = LoadOptions::default();
    let from_disk = load(dir.join(main).to_str().unwrap(), &options).unwrap();
    for flat in [false, true] {
        let files = files_of(dir, flat);
        let name = if flat { Path::new(main).file_name().unwrap().to_str().unwrap() } else { main };
        let from_memory = load_from_files(name, &files, &options)
            .unwrap_or_else(|e| panic!("{main} from memory (flat names: {flat}): {e}"));
        assert!(
            tables(&from_memory) == tables(&from_disk),
            "{main} (flat names: {flat}): the scene from memory differs from the scene on disk"
        );
        assert_eq!(from_memory.camera.position, from_disk.camera.position);
    }
}

#[test]
fn gltf_with_external_buffer_and_texture() {
    same_from_memory(&shared("testdata/gltf/khronos/BoxTextured/glTF"), "BoxTextured.gltf");
    same_from_memory(&shared("testdata/gltf/khronos/BoxTextured/glTF-Binary"), "BoxTextured.glb");
}

#[test]
fn pbrt_with_meshes_and_textures() {
    same_from_memory(&shared("testdata/scenes/bitterli/material-testball/pbrt-v4"), "scene-v4.pbrt");
}

#[test]
fn mitsuba_with_includes_and_meshes() {
    same_from_memory(&shared("testdata/scenes/mitsuba-data/cbox"), "cbox.xml");
    same_from_memory(&shared("testdata/scenes/mitsuba-data/cbox"), "cbox-rgb.xml");
}

#[test]
fn toml_with_a_gltf_include_and_an_environment_map() {
    let mut files = MemoryFiles::new();
    let scene = "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\n\n[[include]]\ngltf = \"models/box.glb\"\n\n\
                 [environment]\nmap = \"sky/noon.hdr\"\n";
    files.insert("scene.toml", scene.as_bytes().to_vec());
    files.insert(
        "models/box.glb",
        std::fs::read(shared("testdata/gltf/khronos/BoxTextured/glTF-Binary/BoxTextured.glb")).unwrap(),
    );
    files.insert("sky/noon.hdr", std::fs::read(shared("testdata/env/hdr/noon_grass_1k.hdr")).unwrap());
    let scene = load_from_files("scene.toml", &files, &LoadOptions::default()).unwrap();
    assert!(!scene.meshes.is_empty(), "the included glTF's mesh");
    let env = format!("{:?}", scene.environment);
    assert!(env.contains("width: 1024"), "the environment map was read: {}", &env[..env.len().min(200)]);
}

#[test]
fn a_missing_reference_is_named_and_nothing_is_read_from_disk() {
    let dir = shared("testdata/scenes/mitsuba-data/cbox");
    let mut files = files_of(&dir, false);
    let mut without = MemoryFiles::new();
    for name in files.names() {
        if name != "meshes/cbox_floor.obj" {
            let bytes = files.get(Path::new(&name)).unwrap().clone();
            without.insert(&name, bytes);
        }
    }
    files = without;
    let e = load_from_files("cbox.xml", &files, &LoadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("cbox_floor.obj") && e.contains("not found"), "{e}");
    // The scene's own file exists on disk, but only the given files count.
    let e = load_from_files(dir.join("cbox.xml").to_str().unwrap(), &MemoryFiles::new(), &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("no such file among the files given"), "{e}");
}
