//! The `mislab` binary as a user runs it: built-in scenes render with zero NaN/Inf, bad input ends in a
//! clear error naming the file with exit code 2 (never a panic or a hang, never a half-written image),
//! a missing adapter is exit code 2 with instructions, and Ctrl-C still writes the image.

mod common;
mod scratch;

use scratch::Scratch;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn mislab() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_mislab"));
    c.stdin(Stdio::null());
    c
}

/// Runs with a deadline: a hang is a failure, not a stuck CI.
fn run(mut cmd: Command, timeout: Duration) -> Output {
    let mut child = cmd.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().expect("spawn mislab");
    let start = Instant::now();
    loop {
        if child.try_wait().expect("wait").is_some() {
            return child.wait_with_output().expect("output");
        }
        if start.elapsed() > timeout {
            let _ = child.kill();
            panic!("mislab did not finish within {timeout:?}: {cmd:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// This test's scratch folder (removed when it passes).
fn tmp(test: &str) -> Scratch {
    Scratch::new("cli", test)
}

fn shared(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared").join(rel)
}

#[test]
fn every_builtin_renders_without_nan() {
    let dir = tmp("builtins");
    for (scene, mode) in
        [("veach-mis", "direct"), ("cornell-box", "path"), ("furnace", "path"), ("area-vs-cosine", "direct")]
    {
        let out = dir.join(format!("{scene}.png"));
        let mut c = mislab();
        c.args(["render", scene, "--spp", "4", "--width", "64", "--height", "64", "--mode", mode, "-o"]).arg(&out);
        let o = run(c, Duration::from_secs(180));
        let err = stderr(&o);
        assert!(o.status.success(), "{scene}: {err}");
        assert!(err.contains(" 0 NaN/Inf samples"), "{scene}: expected zero NaN/Inf samples in:\n{err}");
        let img = image::open(&out).expect("the PNG must be readable");
        assert_eq!((img.width(), img.height()), (64, 64));
    }
}

#[test]
fn exr_output_is_linear_float() {
    let dir = tmp("exr");
    let out = dir.join("furnace.exr");
    let mut c = mislab();
    c.args(["render", "furnace", "--spp", "16", "--width", "16", "--height", "16", "-o"]).arg(&out);
    let o = run(c, Duration::from_secs(120));
    assert!(o.status.success(), "{}", stderr(&o));
    let img = image::open(&out).unwrap().into_rgb32f();
    let mean: f32 = img.pixels().flat_map(|p| p.0).sum::<f32>() / (16.0 * 16.0 * 3.0);
    assert!((mean - 1.0).abs() < 0.05, "the furnace's EXR holds raw radiance ≈ 1, got {mean}");
}

/// Expects exit code 2, a message naming `name`, and no output image.
fn assert_clean_failure(dir: &Path, args: &[&str], scene: &Path, name_in_message: &str) {
    let out = dir.join(format!("fail-{}.png", name_in_message.replace(['/', ' '], "_")));
    let _ = std::fs::remove_file(&out);
    let mut c = mislab();
    c.arg("render").arg(scene).args(args).args(["--spp", "1", "--width", "8", "--height", "8", "-o"]).arg(&out);
    let o = run(c, Duration::from_secs(60));
    let err = stderr(&o);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}: expected exit code 2, got {:?}:\n{err}",
        scene.display(),
        o.status.code()
    );
    assert!(err.contains(name_in_message), "{}: the message must name '{name_in_message}':\n{err}", scene.display());
    assert!(!err.contains("panicked"), "{}: panicked:\n{err}", scene.display());
    assert!(!out.exists(), "a failed render must not leave an image behind");
}

#[test]
fn bad_scenes_fail_cleanly() {
    let dir = tmp("bad-scenes");
    assert_clean_failure(&dir, &[], Path::new("no/such/scene.gltf"), "no/such/scene.gltf");
    assert_clean_failure(
        &dir,
        &[],
        &shared("testdata/gltf/khronos/Box/glTF-Draco/Box.gltf"),
        "KHR_draco_mesh_compression",
    );
    // A truncated .glb.
    let full = std::fs::read(shared("testdata/gltf/khronos/Box/glTF-Binary/Box.glb")).unwrap();
    let cut = dir.join("truncated.glb");
    std::fs::write(&cut, &full[..full.len() / 2]).unwrap();
    assert_clean_failure(&dir, &[], &cut, "truncated.glb");
    // Garbage and a wrong extension.
    let junk = dir.join("junk.glb");
    std::fs::write(&junk, b"this is not a glb at all").unwrap();
    assert_clean_failure(&dir, &[], &junk, "junk.glb");
    let toml = dir.join("bad.toml");
    std::fs::write(&toml, "[camera\nposition = 1").unwrap();
    assert_clean_failure(&dir, &[], &toml, "bad.toml");
    // A missing environment map.
    assert_clean_failure(&dir, &["--env", "missing.hdr"], Path::new("furnace"), "missing.hdr");
}

/// Every file in the shared robustness corpus: a clean error (exit 2) or a render with a warning.
#[test]
fn robustness_corpus_never_panics() {
    let root = shared("testdata/gltf/robustness");
    let mut files = vec![];
    let mut stack = vec![root];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if matches!(p.extension().and_then(|e| e.to_str()), Some("gltf" | "glb")) {
                files.push(p);
            }
        }
    }
    assert!(files.len() >= 10, "the corpus should have at least 10 files");
    let dir = tmp("robustness");
    for f in files {
        let out = dir.join("robust.png");
        let _ = std::fs::remove_file(&out);
        let mut c = mislab();
        c.arg("render").arg(&f).args(["--spp", "1", "--width", "8", "--height", "8", "-o"]).arg(&out);
        let o = run(c, Duration::from_secs(60));
        let err = stderr(&o);
        assert!(!err.contains("panicked"), "{}: panicked:\n{err}", f.display());
        match o.status.code() {
            Some(0) => assert!(err.contains("warning"), "{}: rendered without a warning:\n{err}", f.display()),
            Some(2) => {
                let name = f.file_name().unwrap().to_string_lossy();
                assert!(err.contains(&*name), "{}: the error must name the file:\n{err}", f.display());
                assert!(!out.exists(), "{}: failed but left an image", f.display());
            }
            other => panic!("{}: exit code {other:?}:\n{err}", f.display()),
        }
    }
}

#[test]
fn unknown_adapter_is_exit_2_with_instructions() {
    let dir = tmp("no-adapter");
    let mut c = mislab();
    c.env("WGPU_ADAPTER_NAME", "no-such-adapter-xyz").args(["render", "--spp", "1", "-o"]).arg(dir.join("never.png"));
    let o = run(c, Duration::from_secs(60));
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("no-such-adapter-xyz"));
    // No Vulkan driver at all: point the loader at a driver list that does not exist.
    let mut c = mislab();
    c.env("VK_ICD_FILENAMES", "/nonexistent/icd.json").env("VK_DRIVER_FILES", "/nonexistent/icd.json").args(["info"]);
    let o = run(c, Duration::from_secs(60));
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("apt-get install mesa-vulkan-drivers"), "{}", stderr(&o));
}

#[test]
fn interrupt_writes_what_has_accumulated() {
    let dir = tmp("interrupt");
    let out = dir.join("interrupted.png");
    let _ = std::fs::remove_file(&out);
    let mut c = mislab();
    c.args(["render", "cornell-box", "--mode", "path", "--time", "120", "--width", "64", "--height", "64", "-o"])
        .arg(&out);
    let mut child = c.stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    let pid = child.id();
    // Wait until rendering has started (start-up compiles the pipeline), then interrupt.
    let (rx, reader) = common::watch_stderr(&mut child, "start-up:");
    rx.recv_timeout(Duration::from_secs(120)).expect("rendering never started");
    std::thread::sleep(Duration::from_secs(2));
    let status = Command::new("kill").args(["-INT", &pid.to_string()]).status().unwrap();
    assert!(status.success());
    let start = Instant::now();
    let o = child.wait_with_output().unwrap();
    assert!(start.elapsed() < Duration::from_secs(30), "did not stop promptly after Ctrl-C");
    let o = Output { stderr: reader.join().unwrap().into_bytes(), ..o };
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted"), "{err}");
    assert!(out.exists(), "the partial image must be written");
}

/// The forecast files in a cache directory (`render::pipeline_forecast`), oldest first.
fn forecasts(cache: &Path) -> Vec<PathBuf> {
    let Ok(dir) = std::fs::read_dir(cache.join("mislab/forecast")) else { return Vec::new() };
    let mut files: Vec<_> = dir
        .filter_map(Result::ok)
        .filter(|e| e.path().extension().is_some_and(|x| x == "forecast"))
        .map(|e| (e.metadata().unwrap().modified().unwrap(), e.path()))
        .collect();
    files.sort();
    files.into_iter().map(|(_, p)| p).collect()
}

#[test]
fn a_repeated_render_takes_its_forecast_pipeline_and_no_other() {
    const TAKEN: &str = "note: the render pipeline was built while the scene loaded";
    let dir = tmp("forecast");
    let cache = dir.join("cache");
    let render = |scene: &str, out: &str| {
        let out = dir.join(out);
        let mut c = mislab();
        c.env("XDG_CACHE_HOME", &cache);
        c.args(["render", scene, "--spp", "2", "--width", "16", "--height", "16", "-o"]).arg(&out);
        let o = run(c, Duration::from_secs(300));
        let err = stderr(&o);
        assert!(o.status.success(), "{scene}: {err}");
        (err, image::open(&out).expect("the EXR reads back").into_rgb32f().into_raw())
    };
    // A first run records its pipeline; the same command again builds it while the scene loads and takes it.
    let (err, furnace) = render("furnace", "fc-a1.exr");
    assert!(!err.contains(TAKEN), "nothing to take on a first run:\n{err}");
    let a = forecasts(&cache);
    assert_eq!(a.len(), 1, "one forecast per command");
    let (err, again) = render("furnace", "fc-a2.exr");
    assert!(err.contains(TAKEN), "a repeated render takes the forecast pipeline:\n{err}");
    assert_eq!(again, furnace, "the forecast pipeline is the pipeline: the same pixels");
    // Another command gets a file of its own; given the first command's forecast, it builds its own pipeline.
    let (err, cornell) = render("cornell-box", "fc-b1.exr");
    assert!(!err.contains(TAKEN), "{err}");
    let files = forecasts(&cache);
    assert_eq!(files.len(), 2);
    let b = files.into_iter().find(|f| *f != a[0]).expect("the second command's forecast");
    std::fs::copy(&a[0], &b).unwrap();
    let (err, cornell_again) = render("cornell-box", "fc-b2.exr");
    assert!(!err.contains(TAKEN), "another command's pipeline is never taken:\n{err}");
    assert_eq!(cornell_again, cornell);
    // A damaged forecast is reported and ignored, and rewritten by the run.
    std::fs::write(&a[0], b"MISLPF01 not a forecast").unwrap();
    let (err, damaged) = render("furnace", "fc-a3.exr");
    assert!(err.contains("warning: pipeline forecast") && err.contains("ignored"), "{err}");
    assert!(!err.contains(TAKEN), "{err}");
    assert_eq!(damaged, furnace);
    let (err, _) = render("furnace", "fc-a4.exr");
    assert!(err.contains(TAKEN), "the damaged forecast was rewritten:\n{err}");
}
