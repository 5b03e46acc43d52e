//! Time to an image, end to end: whole `mislab render` processes (process start → image written), each scene rendered
//! twice — first with empty caches (a fresh cache directory: Mesa's shader cache and mislab's pipeline store both
//! live under `XDG_CACHE_HOME`), then again with what the first run left there. The start-up line each run prints
//! splits its start-up into scene load, BVH (built or read from the store), device, upload, pipeline (naga, the
//! pruner, creation) and the first dispatch (where lavapipe compiles the kernel).
//! `cargo bench --bench startup` (MISLAB_BENCH_SIZE, default 512; MISLAB_BENCH_SPP, default 16; MISLAB_BENCH_ROUNDS,
//! default 2, interleaving the scenes so machine load hits all alike).

#[allow(dead_code)] // this bench runs the CLI; it uses only the environment helper
mod common;

use common::env_or;
use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

/// The start-up line's total and parts, by the words before each number.
const STARTUP_PARTS: [&str; 7] =
    ["start-up: ", "scene load ", "BVH ", "device ", "upload ", "pipeline ", "first dispatch "];

/// The measurements of one process.
struct Run {
    wall: f64,
    /// Start-up, then its parts as the start-up line names them (`STARTUP_PARTS`).
    startup: [f64; 7],
    render: f64,
}

/// The number before " s" after `key` in `text`.
fn seconds_after(text: &str, key: &str) -> Option<f64> {
    let at = text.find(key)? + key.len();
    text[at..].split_whitespace().next()?.parse().ok()
}

fn run(scene: &str, size: u32, spp: u32, cache: &PathBuf, out: &PathBuf) -> Run {
    let t = Instant::now();
    let o = Command::new(env!("CARGO_BIN_EXE_mislab"))
        .args(["render", scene, "--mode", "path", "--max-depth", "8", "--strategy", "mis", "--heuristic", "power"])
        .args(["--sampler", "sobol", "--spp", &spp.to_string(), "--width", &size.to_string()])
        .args(["--height", &size.to_string(), "--filter", "box", "-o"])
        .arg(out)
        .env("XDG_CACHE_HOME", cache)
        .output()
        .expect("mislab runs");
    let wall = t.elapsed().as_secs_f64();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "mislab render {scene} failed:\n{err}");
    let get = |text: &str, k: &str| seconds_after(text, k).unwrap_or_else(|| panic!("no '{k}' in:\n{err}"));
    // The parts from the start-up line alone: the scene line also says "BVH".
    let line = err.lines().find(|l| l.starts_with("start-up: ")).unwrap_or_else(|| panic!("no start-up line:\n{err}"));
    Run { wall, startup: STARTUP_PARTS.map(|k| get(line, k)), render: get(&err, &format!("{spp} spp in ")) }
}

fn main() {
    let size: u32 = env_or("MISLAB_BENCH_SIZE", 512);
    let spp: u32 = env_or("MISLAB_BENCH_SPP", 16);
    let rounds: u32 = env_or("MISLAB_BENCH_ROUNDS", 2);
    let shared = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/bench-scenes");
    let scenes: Vec<String> = ["cornell-box".to_string(), "veach-mis".to_string()]
        .into_iter()
        .chain(["damagedhelmet_grey", "staircase2_grey"].iter().map(|s| format!("{shared}/{s}/{s}.toml")))
        .collect();
    let dir = std::env::temp_dir().join(format!("mislab-bench-startup-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("image.exr");
    println!(
        "whole `mislab render` processes, {size}x{size}, {spp} spp, path depth 8, MIS power, Sobol; {rounds} rounds"
    );
    println!(
        "{:<22} {:>9} {:>9} {:>9} {:>6} {:>6} {:>6} {:>6} {:>8} {:>8} {:>8}",
        "scene", "run", "process s", "start-up", "load", "BVH", "device", "upload", "pipeline", "dispatch", "render"
    );
    for round in 0..rounds {
        for scene in &scenes {
            let cache = dir.join(format!("cache-{round}-{}", scene.len()));
            let _ = std::fs::remove_dir_all(&cache);
            let name = std::path::Path::new(scene).file_stem().and_then(|s| s.to_str()).unwrap_or(scene);
            for which in ["first", "repeated"] {
                let r = run(scene, size, spp, &cache, &out);
                let [start, load, bvh, device, upload, pipeline, dispatch] = r.startup;
                println!(
                    "{:<22} {:>9} {:>9.2} {:>9.2} {:>6.2} {:>6.2} {:>6.2} {:>6.2} {:>8.2} {:>8.2} {:>8.2}",
                    name, which, r.wall, start, load, bvh, device, upload, pipeline, dispatch, r.render
                );
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
