//! The bad-input corpus (`tests/data/bad`, written by `generate.py`, expectations in `MANIFEST.tsv`), run
//! through the real `mislab` binary as a user would: `mislab render FILE -o OUT.png --spp 1 --width 16
//! --height 16` (environment maps: `mislab render furnace --env FILE ...`).
//!
//! Every `error` case must end with exit code 2 and one `error:` line that names the file and contains the
//! expected description of the problem, never a panic, never a hang (each run is killed after `TIMEOUT`), and
//! leave nothing behind where the image would have gone (no `OUT.png`, no `OUT.png.partial`). `warning` cases
//! (repaired content, scenes with nothing lit) and `ok` cases render (exit 0) a readable 16×16 image.
//!
//! Also: a scene larger than the device's storage-buffer binding limit is refused with an error naming the
//! limit, end to end with a generated texture, and at the unit level with a synthetic `SceneData`.

mod common;

use mislab::render::{gpu_scene::check_binding_sizes, scene_data::SceneData};
use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// A run that takes longer than this is a hang.
const TIMEOUT: Duration = Duration::from_secs(60);
/// Parallel runs (error cases are CPU-light; renders share the CPU with lavapipe).
const THREADS: usize = 3;
/// The issue asks for at least this many cases.
const MIN_CASES: usize = 300;

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Expect {
    Error,
    Warning,
    Ok,
}

#[derive(Debug)]
struct Case {
    /// Relative to the corpus directory.
    file: String,
    /// `mislab render furnace --env FILE` instead of `mislab render FILE`.
    env: bool,
    expect: Expect,
    substring: String,
    args: Vec<String>,
}

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bad")
}

fn manifest() -> Vec<Case> {
    let text = std::fs::read_to_string(corpus().join("MANIFEST.tsv")).expect("tests/data/bad/MANIFEST.tsv");
    let mut cases = Vec::new();
    for (n, line) in text.lines().enumerate() {
        if line.trim().is_empty() || line.starts_with('#') {
            continue;
        }
        let cols: Vec<&str> = line.split('\t').collect();
        assert!(
            cols.len() >= 4,
            "MANIFEST.tsv line {}: expected file, mode, expect, substring[, args]: {line:?}",
            n + 1
        );
        let expect = match cols[2] {
            "error" => Expect::Error,
            "warning" => Expect::Warning,
            "ok" => Expect::Ok,
            other => panic!("MANIFEST.tsv line {}: unknown outcome {other:?}", n + 1),
        };
        let env = match cols[1] {
            "scene" => false,
            "env" => true,
            other => panic!("MANIFEST.tsv line {}: unknown mode {other:?}", n + 1),
        };
        let line_no = n + 1;
        assert!(
            expect != Expect::Error || !cols[3].is_empty(),
            "MANIFEST.tsv line {line_no}: an error case needs a substring"
        );
        let args = cols.get(4).map(|a| a.split_whitespace().map(String::from).collect()).unwrap_or_default();
        cases.push(Case { file: cols[0].to_string(), env, expect, substring: cols[3].to_string(), args });
    }
    cases
}

/// Every file of the corpus except the generator, the manifest, aux/ (files the cases refer to) and hidden or
/// Python cache files.
fn corpus_files() -> Vec<String> {
    let root = corpus();
    let mut out = Vec::new();
    let mut stack = vec![root.clone()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            let rel = path.strip_prefix(&root).unwrap().to_string_lossy().replace('\\', "/");
            let hidden = path.file_name().is_some_and(|n| n.to_string_lossy().starts_with('.') || n == "__pycache__");
            if hidden {
                continue;
            }
            if path.is_dir() {
                if rel != "aux" {
                    stack.push(path);
                }
            } else if !matches!(rel.as_str(), "MANIFEST.tsv" | "generate.py") {
                out.push(rel);
            }
        }
    }
    out.sort();
    out
}

/// What one run of the binary did.
struct Outcome {
    code: Option<i32>,
    stderr: String,
    seconds: f64,
}

/// Runs `cmd` with a deadline; its output pipes are drained on threads so a chatty child cannot block.
fn run(mut cmd: Command) -> Result<Outcome, String> {
    let start = Instant::now();
    cmd.stdin(Stdio::null()).stdout(Stdio::piped()).stderr(Stdio::piped());
    let mut child = cmd.spawn().map_err(|e| format!("spawn: {e}"))?;
    let drain = |mut pipe: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut buf = Vec::new();
            let _ = pipe.read_to_end(&mut buf);
            String::from_utf8_lossy(&buf).into_owned()
        })
    };
    let out = drain(Box::new(child.stdout.take().unwrap()));
    let err = drain(Box::new(child.stderr.take().unwrap()));
    loop {
        if let Some(status) = child.try_wait().map_err(|e| e.to_string())? {
            let _ = out.join();
            let stderr = err.join().unwrap_or_default();
            return Ok(Outcome { code: status.code(), stderr, seconds: start.elapsed().as_secs_f64() });
        }
        if start.elapsed() > TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            let stderr = err.join().unwrap_or_default();
            return Err(format!("did not finish within {TIMEOUT:?} (killed); stderr so far:\n{stderr}"));
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Runs one case in its own scratch directory and checks everything the manifest and the issue require.
fn check(case: &Case, scratch: &Path) -> Result<f64, String> {
    std::fs::create_dir_all(scratch).map_err(|e| e.to_string())?;
    let out = scratch.join("out.png");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mislab"));
    cmd.current_dir(corpus()).arg("render");
    if case.env {
        cmd.args(["furnace", "--env", &case.file]);
    } else {
        cmd.arg(&case.file);
    }
    cmd.arg("-o").arg(&out).args(["--spp", "1", "--width", "16", "--height", "16"]).args(&case.args);
    let o = run(cmd)?;
    let err = &o.stderr;
    let name = Path::new(&case.file).file_name().unwrap().to_string_lossy().into_owned();
    let mut problems = Vec::new();
    if err.contains("panicked") || err.contains("RUST_BACKTRACE") {
        problems.push("panicked".to_string());
    }
    let leftovers: Vec<String> = std::fs::read_dir(scratch)
        .map_err(|e| e.to_string())?
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    match case.expect {
        Expect::Error => {
            if o.code != Some(2) {
                problems.push(format!("exit code {:?}, expected 2", o.code));
            }
            let line =
                err.lines().find(|l| l.starts_with("error:") && l.contains(&name) && l.contains(&case.substring));
            if line.is_none() {
                problems.push(format!("no `error:` line names `{name}` and says `{}`", case.substring));
            }
            if !leftovers.is_empty() {
                problems.push(format!("failed but left files where the image would go: {leftovers:?}"));
            }
            // Echoed input is cut (a 100 000-character key or URI must not come back in full).
            if let Some(long) = err.lines().find(|l| l.chars().count() > 1000) {
                problems
                    .push(format!("a stderr line of {} characters (echoed input is not cut)", long.chars().count()));
            }
        }
        Expect::Warning | Expect::Ok => {
            if o.code != Some(0) {
                problems.push(format!("exit code {:?}, expected 0", o.code));
            }
            let warned = err.lines().any(|l| l.starts_with("warning:"));
            let warned_it = err.lines().any(|l| l.starts_with("warning:") && l.contains(&case.substring));
            if case.expect == Expect::Warning && !warned_it {
                problems.push(format!("no `warning:` line says `{}`", case.substring));
            }
            if case.expect == Expect::Ok && warned {
                problems.push("rendered with a warning, expected none".into());
            }
            match image::open(&out) {
                Ok(img) if (img.width(), img.height()) == (16, 16) => {}
                Ok(img) => problems.push(format!("wrote a {}×{} image, expected 16×16", img.width(), img.height())),
                Err(e) => problems.push(format!("no readable image: {e}")),
            }
            if leftovers.iter().any(|f| f != "out.png") {
                problems.push(format!("left extra files: {leftovers:?}"));
            }
        }
    }
    let _ = std::fs::remove_dir_all(scratch);
    if problems.is_empty() {
        Ok(o.seconds)
    } else {
        Err(format!("{}\n--- stderr ---\n{}", problems.join("; "), err.trim_end()))
    }
}

#[test]
fn corpus_of_bad_inputs() {
    let start = Instant::now();
    let mut cases = manifest();
    // The manifest and the directory must agree: no unlisted file, no listed file missing.
    let files = corpus_files();
    let listed: Vec<String> = {
        let mut l: Vec<String> = cases.iter().map(|c| c.file.clone()).collect();
        l.sort();
        l
    };
    let unlisted: Vec<&String> = files.iter().filter(|f| listed.binary_search(f).is_err()).collect();
    let missing: Vec<&String> = listed.iter().filter(|f| files.binary_search(f).is_err()).collect();
    assert!(unlisted.is_empty(), "files in tests/data/bad not in MANIFEST.tsv (re-run generate.py): {unlisted:?}");
    assert!(missing.is_empty(), "MANIFEST.tsv lists files that do not exist (re-run generate.py): {missing:?}");
    assert!(cases.len() >= MIN_CASES, "the corpus has {} cases; at least {MIN_CASES} are required", cases.len());

    // Renders (ok / warning) are the slow ones: start them first so the fast error cases fill in around them.
    cases.sort_by_key(|c| std::cmp::Reverse(c.expect));
    let scratch = std::env::temp_dir().join(format!("mislab-bad-input-{}", std::process::id()));
    let next = AtomicUsize::new(0);
    let failures = Mutex::new(Vec::new());
    let timings = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..THREADS {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some(case) = cases.get(i) else { break };
                match check(case, &scratch.join(i.to_string())) {
                    Ok(seconds) => timings.lock().unwrap().push((seconds, case.file.clone())),
                    Err(why) => failures.lock().unwrap().push(format!("{} ({:?}): {why}", case.file, case.expect)),
                }
            });
        }
    });
    let _ = std::fs::remove_dir_all(&scratch);

    let mut summary: BTreeMap<(String, Expect), usize> = BTreeMap::new();
    for c in &cases {
        let category = c.file.split('/').next().unwrap_or("").to_string();
        *summary.entry((category, c.expect)).or_default() += 1;
    }
    println!("bad-input corpus: {} cases in {:.1} s ({THREADS} threads)", cases.len(), start.elapsed().as_secs_f64());
    for ((category, expect), n) in &summary {
        println!("  {category:18} {:8} {n}", format!("{expect:?}").to_lowercase());
    }
    let mut timings = timings.into_inner().unwrap();
    timings.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (seconds, file) in timings.iter().take(3) {
        println!("  slowest: {file} {seconds:.2} s");
    }
    let failures = failures.into_inner().unwrap();
    assert!(failures.is_empty(), "{} of {} cases failed:\n\n{}", failures.len(), cases.len(), failures.join("\n\n"));
}

// ---------------------------------------------------------------------------------------------------------
// Scenes larger than the device's storage-buffer binding limit

/// The limit `GpuScene::upload` checks against, from `mislab info` (which opens the same device).
fn device_storage_limit() -> u64 {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mislab"));
    cmd.arg("info").stdout(Stdio::piped()).stderr(Stdio::piped());
    let o = cmd.output().expect("run mislab info");
    let text = String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "mislab info failed (no Vulkan adapter? apt-get install mesa-vulkan-drivers):\n{text}");
    let mib = |key: &str| -> u64 {
        let line = text.lines().find(|l| l.trim_start().starts_with(key));
        let line = line.unwrap_or_else(|| panic!("no `{key}` in:\n{text}"));
        let value = line.split(':').nth(1).map(|v| v.trim().trim_end_matches("MiB").trim());
        value.and_then(|v| v.parse().ok()).unwrap_or_else(|| panic!("cannot read the limit from: {line}"))
    };
    mib("max storage buffer binding").min(mib("max buffer size")) << 20
}

#[test]
fn scene_over_the_storage_buffer_limit_is_refused_by_name() {
    let limit = device_storage_limit();
    // One RGBA8 texture just over the limit; textures are at most 16384 texels on a side (1 GiB).
    let side = ((limit / 4) as f64).sqrt().ceil() as u32 + 1;
    if side > 16384 {
        // A device with bindings above 1 GiB (most discrete GPUs allow 2-4 GiB) would need several GiB of
        // texture decoded on the host to overflow one; `binding_size_check_names_the_buffer_and_the_limit`
        // tests the same check with a synthetic scene instead.
        let mib = limit >> 20;
        println!("the device's storage-buffer binding limit ({mib} MiB) is beyond one 16384² texture: end-to-end check not run");
        return;
    }
    let dir = std::env::temp_dir().join(format!("mislab-over-limit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A grey PNG compresses to almost nothing; it decodes to side² RGBA8 texels = one storage buffer.
    image::GrayImage::from_pixel(side, side, image::Luma([128])).save(dir.join("big.png")).unwrap();
    let gltf = r#"{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "scene": 0, "nodes": [{"mesh": 0}],
        "meshes": [{"name": "Tri", "primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
        "materials": [{"emissiveFactor": [1, 1, 1], "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0}], "images": [{"uri": "big.png"}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}]}"#;
    let scene = dir.join("over-limit.gltf");
    std::fs::write(&scene, gltf).unwrap();
    let out = dir.join("out.png");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mislab"));
    cmd.arg("render").arg(&scene).arg("-o").arg(&out).args(["--spp", "1", "--width", "16", "--height", "16"]);
    let o = run(cmd).unwrap_or_else(|e| panic!("over-limit.gltf: {e}"));
    let _ = std::fs::remove_dir_all(&dir);
    let err = &o.stderr;
    println!("{side}×{side} texture against a {} MiB limit: {:.1} s", limit >> 20, o.seconds);
    assert_eq!(o.code, Some(2), "expected exit code 2:\n{err}");
    assert!(!err.contains("panicked"), "{err}");
    let line = err.lines().find(|l| l.starts_with("error:")).unwrap_or_else(|| panic!("no error line:\n{err}"));
    for want in ["over-limit.gltf", "texels", "max_storage_buffer_binding_size", &format!("{} MiB", limit >> 20)] {
        assert!(line.contains(want), "the error must name {want:?}: {line}");
    }
    assert!(!out.exists());
}

#[test]
fn binding_size_check_names_the_buffer_and_the_limit() {
    let limit = 1 << 20;
    // Exactly at the limit fits.
    let data = SceneData { tex_texels: vec![0; (limit / 4) as usize], ..Default::default() };
    check_binding_sizes(&data, limit).unwrap();
    // One texel more does not, and the message says which buffer, how large, and the limit.
    let data = SceneData { tex_texels: vec![0; (limit / 4) as usize + 1], ..Default::default() };
    let e = check_binding_sizes(&data, limit).unwrap_err().to_string();
    for want in ["its texels need 1.0 MiB (1048580 bytes)", "max_storage_buffer_binding_size of 1 MiB (1048576 bytes)"]
    {
        assert!(e.contains(want), "{e}");
    }
    // Triangles: 16 bytes per vertex, three per triangle.
    let data = SceneData { tri_verts: vec![[0.0; 4]; 3 * 30_000], ..Default::default() };
    let e = check_binding_sizes(&data, limit).unwrap_err().to_string();
    assert!(e.contains("triangle vertices") && e.contains("1440000 bytes"), "{e}");
}

// ---------------------------------------------------------------------------------------------------------
// Special files (which git cannot hold): FIFOs, /dev/zero, directories, symlink loops, as every kind of input

/// One special-file case: the arguments after `mislab render`, the file the error must name, and what it says.
struct Special {
    args: Vec<String>,
    names: &'static str,
    says: &'static str,
}

fn special(args: &[&str], names: &'static str, says: &'static str) -> Special {
    Special { args: args.iter().map(|a| a.to_string()).collect(), names, says }
}

#[cfg(unix)]
#[test]
fn special_files_are_clear_errors_not_hangs() {
    use std::os::unix::fs::symlink;
    let dir = std::env::temp_dir().join(format!("mislab-special-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("dir.gltf")).unwrap();
    for fifo in ["fifo.gltf", "fifo.glb", "fifo.toml", "fifo.hdr", "fifo.bin", "fifo.png"] {
        let status = Command::new("mkfifo").arg(dir.join(fifo)).status().expect("run mkfifo");
        assert!(status.success(), "mkfifo {fifo}");
    }
    for link in ["zero.gltf", "zero.glb", "zero.toml", "zero.hdr", "zero.exr", "zero.bin"] {
        symlink("/dev/zero", dir.join(link)).unwrap();
    }
    symlink("loop-b.gltf", dir.join("loop-a.gltf")).unwrap();
    symlink("loop-a.gltf", dir.join("loop-b.gltf")).unwrap();
    symlink("missing.gltf", dir.join("dangling.gltf")).unwrap();
    let tri = |uri: &str, image: Option<&str>| {
        let images =
            image.map(|i| format!(r#","textures":[{{"source":0}}],"images":[{{"uri":"{i}"}}]"#)).unwrap_or_default();
        let material = if image.is_some() { r#","pbrMetallicRoughness":{"baseColorTexture":{"index":0}}"# } else { "" };
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scenes":[{{"nodes":[0]}}],"scene":0,"nodes":[{{"mesh":0}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"material":0}}]}}],
            "materials":[{{"emissiveFactor":[1,1,1]{material}}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}}],
            "bufferViews":[{{"buffer":0,"byteLength":36}}],"buffers":[{{"byteLength":36,"uri":"{uri}"}}]{images}}}"#
        )
    };
    let embedded = "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA";
    std::fs::write(dir.join("buffer-fifo.gltf"), tri("fifo.bin", None)).unwrap();
    std::fs::write(dir.join("buffer-zero.gltf"), tri("zero.bin", None)).unwrap();
    std::fs::write(dir.join("buffer-dir.gltf"), tri("dir.gltf", None)).unwrap();
    std::fs::write(dir.join("image-fifo.gltf"), tri(embedded, Some("fifo.png"))).unwrap();
    std::fs::write(dir.join("image-zero.gltf"), tri(embedded, Some("zero.png"))).unwrap();
    symlink("/dev/zero", dir.join("zero.png")).unwrap();
    let toml = |body: &str| format!("[camera]\nposition = [0, 0, 5]\n{body}");
    std::fs::write(dir.join("env-fifo.toml"), toml("[environment]\nmap = \"fifo.hdr\"\n")).unwrap();
    std::fs::write(dir.join("env-zero.toml"), toml("[environment]\nmap = \"zero.exr\"\n")).unwrap();
    std::fs::write(dir.join("include-fifo.toml"), toml("[[include]]\ngltf = \"fifo.gltf\"\n")).unwrap();
    std::fs::write(dir.join("include-zero.toml"), toml("[[include]]\ngltf = \"zero.gltf\"\n")).unwrap();
    std::fs::write(dir.join("include-dir.toml"), toml("[[include]]\ngltf = \"dir.gltf\"\n")).unwrap();

    let fifo = "is a FIFO (named pipe), not a regular file";
    let zero = "is a character device (through a symbolic link), not a regular file";
    let cases = [
        special(&["fifo.gltf"], "fifo.gltf", fifo),
        special(&["fifo.glb"], "fifo.glb", fifo),
        special(&["fifo.toml"], "fifo.toml", fifo),
        special(&["zero.gltf"], "zero.gltf", zero),
        special(&["zero.glb"], "zero.glb", zero),
        special(&["zero.toml"], "zero.toml", zero),
        special(&["dir.gltf"], "dir.gltf", "is a directory, not a regular file"),
        special(&["loop-a.gltf"], "loop-a.gltf", "is a symbolic link loop"),
        special(&["dangling.gltf"], "dangling.gltf", "is a symbolic link to a file that does not exist"),
        special(&["furnace", "--env", "fifo.hdr"], "fifo.hdr", fifo),
        special(&["furnace", "--env", "zero.hdr"], "zero.hdr", zero),
        special(&["furnace", "--env", "zero.exr"], "zero.exr", zero),
        special(&["buffer-fifo.gltf"], "buffer-fifo.gltf", fifo),
        special(&["buffer-dir.gltf"], "buffer-dir.gltf", "is a directory"),
        // A symlink out of the asset's directory is refused as such; allowed, it is still not a regular file.
        special(
            &["buffer-zero.gltf"],
            "buffer-zero.gltf",
            "leads outside the glTF file's directory through a symbolic link",
        ),
        special(&["buffer-zero.gltf", "--allow-outside-paths"], "buffer-zero.gltf", zero),
        special(&["image-fifo.gltf"], "image-fifo.gltf", fifo),
        special(&["image-zero.gltf", "--allow-outside-paths"], "image-zero.gltf", zero),
        special(&["env-fifo.toml"], "env-fifo.toml", fifo),
        special(&["env-zero.toml"], "env-zero.toml", zero),
        special(&["include-fifo.toml"], "include-fifo.toml", fifo),
        special(&["include-zero.toml"], "include-zero.toml", zero),
        special(&["include-dir.toml"], "include-dir.toml", "is a directory"),
    ];
    let start = Instant::now();
    let mut failures = Vec::new();
    for c in &cases {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_mislab"));
        cmd.current_dir(&dir).arg("render").args(&c.args).arg("-o").arg(dir.join("out.png"));
        cmd.args(["--spp", "1", "--width", "16", "--height", "16"]);
        match run(cmd) {
            Err(e) => failures.push(format!("{:?}: {e}", c.args)),
            Ok(o) => {
                let line =
                    o.stderr.lines().find(|l| l.starts_with("error:") && l.contains(c.names) && l.contains(c.says));
                if o.code != Some(2) || line.is_none() || dir.join("out.png").exists() {
                    failures.push(format!(
                        "{:?}: exit {:?}, expected 2 and an error naming {} that says {:?}:\n{}",
                        c.args,
                        o.code,
                        c.names,
                        c.says,
                        o.stderr.trim_end()
                    ));
                }
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    println!("{} special-file cases in {:.1} s", cases.len(), start.elapsed().as_secs_f64());
    assert!(failures.is_empty(), "{} of {} cases failed:\n\n{}", failures.len(), cases.len(), failures.join("\n\n"));
}

// ---------------------------------------------------------------------------------------------------------
// Numeric flags: refused like their TOML twins, at parse time (exit 2, the flag named), before any work

#[test]
fn numeric_flags_are_validated_like_their_toml_twins() {
    let cases: &[(&[&str], &str)] = &[
        (&["--exposure", "nan"], "--exposure"),
        (&["--exposure", "inf"], "--exposure"),
        (&["--exposure", "128"], "--exposure"),
        (&["--env-scale", "inf"], "--env-scale"),
        (&["--env-scale", "nan"], "--env-scale"),
        (&["--env-scale", "-1"], "--env-scale"),
        (&["--env-scale", "1e39"], "--env-scale"),
        (&["--env-rotation", "nan"], "--env-rotation"),
        (&["--time", "nan"], "--time"),
        (&["--time", "0"], "--time"),
        (&["--spp", "0"], "an integer from 1 to 4294967295"),
        (&["--spp", "4294967296"], "an integer from 1 to 4294967295"),
        (&["--seed", "4294967296"], "--seed"),
        (&["-o", "/nonexistent-dir/x.png"], "the output directory /nonexistent-dir does not exist"),
        (&["-o", "/"], "/"),
    ];
    let mut failures = Vec::new();
    for (args, says) in cases {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_mislab"));
        cmd.args(["render", "furnace", "--width", "8", "--height", "8"]).args(*args);
        let o = run(cmd).unwrap_or_else(|e| panic!("{args:?}: {e}"));
        let line = o.stderr.lines().find(|l| l.starts_with("error:") && l.contains(says));
        // Refused before start-up: nothing was loaded or compiled.
        if o.code != Some(2) || line.is_none() || o.stderr.contains("start-up") {
            failures
                .push(format!("{args:?}: exit {:?}, expected 2 and an error saying {says:?}:\n{}", o.code, o.stderr));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

// ---------------------------------------------------------------------------------------------------------
// A signal during start-up (before any sample): nothing to write, and it says so (exit 130, no file)

#[test]
fn a_signal_during_start_up_writes_nothing_and_says_so() {
    let dir = std::env::temp_dir().join(format!("mislab-startup-signal-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("x.png");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mislab"));
    // Path tracing of the Cornell box, with empty caches (its own XDG_CACHE_HOME: no stored pipeline, no Mesa
    // shader cache), so that the shader compilation after the "adapter:" line takes most of a second or more.
    cmd.args(["render", "cornell-box", "--mode", "path", "--spp", "100000", "--width", "64", "--height", "64", "-o"])
        .arg(&out)
        .env("XDG_CACHE_HOME", dir.join("cache"))
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    let mut child = cmd.spawn().unwrap();
    // The signal goes once the process says which adapter it opened: its handler is installed (right after the
    // flags are parsed) and its pipeline not yet compiled, whatever this machine's speed.
    let (rx, reader) = common::watch_stderr(&mut child, "adapter:");
    let opened = rx.recv_timeout(TIMEOUT);
    // SAFETY: kill(2) on our own child's pid.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGTERM) }, 0);
    let start = Instant::now();
    let o = child.wait().unwrap();
    let err = reader.join().unwrap();
    opened.unwrap_or_else(|_| panic!("no adapter line within {TIMEOUT:?}:\n{err}"));
    println!("exit {:?} {:.1} s after SIGTERM:\n{err}", o.code(), start.elapsed().as_secs_f64());
    assert_eq!(o.code(), Some(130), "{err}");
    assert!(err.contains("interrupted during start-up") && err.contains("no image was written"), "{err}");
    assert!(!out.exists(), "a signal before any sample must not leave an (empty) image");
    let _ = std::fs::remove_dir_all(&dir);
}
