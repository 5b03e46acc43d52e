//! Fuzzes the importers of the field's scene formats: pbrt-v4 and Mitsuba 3 XML scenes through their loaders,
//! and the PLY, OBJ, TGA and PFM readers they use. The first byte picks the format; the rest is the file. A
//! loader may return an error — it must never panic, hang or allocate without bound. Seed it with
//! tests/data/bad-import/ and the scene files under ../shared/testdata/scenes/; tests/fuzz_parsers.rs runs a
//! short deterministic mutation loop of the same entry points in CI.
#![no_main]

use libfuzzer_sys::fuzz_target;

const FORMATS: [&str; 6] = ["pbrt", "xml", "ply", "obj", "tga", "pfm"];

fuzz_target!(|data: &[u8]| {
    let Some((&selector, body)) = data.split_first() else { return };
    match FORMATS[selector as usize % FORMATS.len()] {
        // The scene loaders read files (and what they include) by name.
        ext @ ("pbrt" | "xml") => {
            let dir = std::env::temp_dir().join(format!("mislab-fuzz-importers-{}", std::process::id()));
            let _ = std::fs::create_dir_all(&dir);
            let path = dir.join(format!("case.{ext}"));
            std::fs::write(&path, body).expect("temp file");
            let _ = if ext == "pbrt" {
                mislab::scene::pbrt::load(&path)
            } else {
                mislab::scene::mitsuba::load(&path)
            };
        }
        "ply" => {
            let _ = mislab::scene::ply::decode(body);
        }
        "obj" => {
            let _ = mislab::scene::obj::decode(&String::from_utf8_lossy(body));
        }
        "tga" => {
            let _ = mislab::scene::tga::decode(body);
        }
        _ => {
            let _ = mislab::scene::pfm::decode(body);
        }
    }
});
