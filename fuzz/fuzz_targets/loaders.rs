//! Fuzzes every scene and image loader through the same entry points the CLI uses. The first byte
//! picks the format; the rest is the file. A loader may return an error — it must never panic, hang
//! or allocate without bound.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::io::Write;

const EXTENSIONS: [&str; 5] = ["glb", "gltf", "toml", "hdr", "exr"];

fuzz_target!(|data: &[u8]| {
    let Some((&selector, body)) = data.split_first() else { return };
    let ext = EXTENSIONS[selector as usize % EXTENSIONS.len()];
    let dir = std::env::temp_dir().join(format!("mislab-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join(format!("input.{ext}"));
    let mut f = std::fs::File::create(&path).expect("temp file");
    f.write_all(body).expect("write");
    drop(f);
    match ext {
        "hdr" | "exr" => {
            let _ = mislab::scene::envmap::load_envmap(&path);
        }
        // The format loaders directly: scene::load would catch a panic, and the fuzzer must see it.
        "toml" => {
            let _ = mislab::scene::toml::load(&path, &Default::default());
        }
        _ => {
            let _ = mislab::scene::gltf::load(&path, &Default::default());
        }
    }
});
