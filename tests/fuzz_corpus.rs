//! Replays the committed fuzz corpus (fuzz/corpus/loaders-min: the inputs under 512 bytes of a set-cover
//! minimisation of a 31-minute `cargo fuzz` run, and fuzz/corpus/loaders/seed*) through the loaders exactly as
//! the fuzz target feeds them (first byte = format): none may panic, and every error must name the file.

use std::io::Write;
use std::path::Path;

const EXTENSIONS: [&str; 5] = ["glb", "gltf", "toml", "hdr", "exr"];

fn replay(input: &Path, dir: &Path) -> Result<(), String> {
    let data = std::fs::read(input).map_err(|e| format!("{}: {e}", input.display()))?;
    let Some((&selector, body)) = data.split_first() else { return Ok(()) };
    let ext = EXTENSIONS[selector as usize % EXTENSIONS.len()];
    let path = dir.join(format!("input.{ext}"));
    std::fs::File::create(&path).and_then(|mut f| f.write_all(body)).map_err(|e| format!("{}: {e}", path.display()))?;
    let name = path.display().to_string();
    let result = std::panic::catch_unwind(|| match ext {
        "hdr" | "exr" => mislab::scene::envmap::load_envmap(&path).map(|_| ()).map_err(|e| e.to_string()),
        "toml" => mislab::scene::toml::load(&path, &Default::default()).map(|_| ()).map_err(|e| e.to_string()),
        _ => mislab::scene::gltf::load(&path, &Default::default()).map(|_| ()).map_err(|e| e.to_string()),
    });
    match result {
        Err(_) => Err(format!("{}: the {ext} loader panicked", input.display())),
        Ok(Err(msg)) if !msg.contains(&name) && !msg.contains("input.") => {
            Err(format!("{}: the {ext} error does not name the file: {msg}", input.display()))
        }
        Ok(_) => Ok(()),
    }
}

#[test]
fn committed_fuzz_corpus_never_panics() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus");
    let mut inputs = vec![];
    for sub in ["loaders-min", "loaders"] {
        for e in std::fs::read_dir(root.join(sub)).expect("the committed fuzz corpus") {
            let p = e.expect("entry").path();
            let name = p.file_name().unwrap().to_string_lossy().to_string();
            if sub == "loaders-min" || name.starts_with("seed") {
                inputs.push(p);
            }
        }
    }
    inputs.sort();
    assert!(inputs.len() >= 1000, "expected the committed corpus (≥ 1000 inputs), found {}", inputs.len());
    let dir = std::env::temp_dir().join(format!("mislab-fuzz-replay-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::panic::set_hook(Box::new(|_| {}));
    let failures: Vec<String> = inputs.iter().filter_map(|p| replay(p, &dir).err()).collect();
    let _ = std::panic::take_hook();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        failures.is_empty(),
        "{} of {} corpus inputs failed:\n{}",
        failures.len(),
        inputs.len(),
        failures.join("\n")
    );
    eprintln!("{} corpus inputs replayed: no panic, every error names its file", inputs.len());
}
