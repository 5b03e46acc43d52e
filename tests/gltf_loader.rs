use mislab::scene::{load, LoadOptions};
#[test]
fn dump() {
    let mut files = vec![];
    for root in ["/work/shared/testdata/gltf", "/work/shared/scenes"] {
        let mut stack = vec![std::path::PathBuf::from(root)];
        while let Some(d) = stack.pop() {
            for e in std::fs::read_dir(&d).unwrap() {
                let p = e.unwrap().path();
                if p.is_dir() { stack.push(p) } else if matches!(p.extension().and_then(|e| e.to_str()), Some("gltf" | "glb")) { files.push(p) }
            }
        }
    }
    files.sort();
    for f in files {
        let t = std::time::Instant::now();
        match load(f.to_str().unwrap(), &LoadOptions::default()) {
            Ok(s) => println!("OK {} tris {} meshes {} mats {} tex {} lights {} cam {:?} warn {:?} ({:?})", f.display(), s.triangle_count(), s.meshes.len(), s.materials.len(), s.textures.len(), s.punctual_lights.len(), s.camera, s.warnings, t.elapsed()),
            Err(e) => println!("ERR {e}"),
        }
    }
}
