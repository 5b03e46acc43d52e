//! Render state files (issue 15): a render killed with SIGKILL at random moments and resumed equals the
//! uninterrupted render bit for bit; parts merged in any order match the single render within 1e-5 relative;
//! bad state files and foreign parts are refused by name with exit code 2. The GPU tests run the real binary.

use mislab::gpu::types::GpuAccum;
use mislab::render::settings::Settings;
use mislab::state::merge::{check_parts, merge_accum, Part};
use mislab::state::session::part_range;
use mislab::state::{RenderState, StateHeader};
use rand::{Rng, SeedableRng};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Duration;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mislab"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mislab-state-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// Runs to completion; a missing adapter or any failure panics with the command's output.
fn run_ok(c: &mut Command) -> String {
    let o = c.output().expect("spawn mislab");
    let t = text(&o);
    assert!(
        o.status.success(),
        "mislab failed ({:?}); GPU tests need a Vulkan adapter (apt-get install mesa-vulkan-drivers):\n{t}",
        o.status
    );
    t
}

fn run_code(c: &mut Command) -> (i32, String) {
    let o = c.output().expect("spawn mislab");
    (o.status.code().unwrap_or(-1), text(&o))
}

// A path-traced Cornell box that renders for a few seconds on lavapipe (start-up ~2 s).
const SCENE: &[&str] = &["render", "cornell-box", "--mode", "path", "--width", "64", "--height", "64"];

#[test]
fn sigkill_at_random_moments_then_resume_equals_the_uninterrupted_render_bit_for_bit() {
    let d = tmp("kill");
    let spp = "2048";
    let full = d.join("full.exr");
    run_ok(bin().args(SCENE).args(["--spp", spp, "-o"]).arg(&full).arg("--state").arg(d.join("full.state")));

    let out = d.join("resumed.exr");
    let state = d.join("resumed.state");
    let mut rng = rand_pcg::Pcg64::seed_from_u64(15);
    let (mut kills, mut resumes) = (0, 0);
    let mut checkpoints = Vec::new();
    for attempt in 0..12 {
        let mut c = bin();
        c.args(SCENE).args(["--spp", spp, "--checkpoint-every", "0.1", "-o"]).arg(&out);
        if state.exists() {
            c.arg("--resume").arg(&state);
            resumes += 1;
        } else {
            c.arg("--state").arg(&state);
        }
        let mut child = c.stdout(std::process::Stdio::null()).stderr(std::process::Stdio::null()).spawn().unwrap();
        // Kill the first runs: once during start-up at a random moment, then each at a random moment after its
        // first checkpoint (mid-render, possibly while a checkpoint is being written); let the last run finish.
        if attempt < 4 {
            let spawned = std::time::SystemTime::now();
            if attempt > 0 {
                let checkpointed = || std::fs::metadata(&state).and_then(|m| m.modified()).is_ok_and(|t| t > spawned);
                let t0 = std::time::Instant::now();
                while !checkpointed() && child.try_wait().unwrap().is_none() && t0.elapsed().as_secs() < 60 {
                    std::thread::sleep(Duration::from_millis(20));
                }
            }
            // Short enough that a run of ~1.5 s of rendering (this machine, quiet) is still going when it lands.
            let range = if attempt == 0 { 200..1500 } else { 0..300 };
            std::thread::sleep(Duration::from_millis(rng.random_range(range)));
            if child.try_wait().unwrap().is_none() {
                child.kill().unwrap(); // SIGKILL on Unix
                kills += 1;
            }
        }
        let status = child.wait().unwrap();
        if attempt >= 4 {
            assert!(status.success(), "the resumed render failed: {status:?}");
        }
        if status.success() {
            break;
        }
        // Whatever the moment of the kill, the last checkpoint is readable.
        if state.exists() {
            let h = RenderState::read(&state)
                .unwrap_or_else(|e| panic!("after a SIGKILL the checkpoint is unreadable: {e}"))
                .header;
            checkpoints.push(h.next);
        }
    }
    assert!(kills >= 3 && resumes >= 2, "the test must kill and resume for real: {kills} kills, {resumes} resumes");
    eprintln!("{kills} kills, {resumes} resumes; checkpoints found after the kills at samples {checkpoints:?}");
    assert!(
        checkpoints.iter().any(|&n| n > 0 && n < 2048),
        "no kill landed mid-render (checkpoints at {checkpoints:?})"
    );
    // The pixels bit for bit (the EXR headers differ: they record each run's render time).
    let pixels = |p: &std::path::Path| -> Vec<u32> {
        image::open(p).unwrap().to_rgba32f().into_raw().iter().map(|v| v.to_bits()).collect()
    };
    assert!(
        pixels(&full) == pixels(&out),
        "the resumed image differs from the uninterrupted one ({kills} kills, {resumes} resumes)"
    );
    let (sa, sb) = (RenderState::read(&d.join("full.state")).unwrap(), RenderState::read(&state).unwrap());
    assert_eq!(bytemuck::cast_slice::<_, u8>(&sa.accum), bytemuck::cast_slice::<_, u8>(&sb.accum));
    assert_eq!((sb.header.range, sb.header.next), ((0, 2048), 2048));

    // Resuming with other settings is refused, naming what differs.
    let (code, t) =
        run_code(bin().args(SCENE).args(["--spp", spp, "--seed", "7", "-o"]).arg(&out).arg("--resume").arg(&state));
    assert_eq!(code, 2, "{t}");
    assert!(t.contains("resumed.state") && t.contains("seed: 0 vs 7"), "{t}");
    let (code, t) = run_code(
        bin()
            .args(["render", "veach-mis", "--mode", "path", "--width", "64", "--height", "64", "--spp", spp, "-o"])
            .arg(&out)
            .arg("--resume")
            .arg(&state),
    );
    assert_eq!(code, 2, "{t}");
    assert!(t.contains("scene content hash"), "{t}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn four_parts_merged_in_shuffled_order_match_the_single_render() {
    let d = tmp("parts");
    let args = ["render", "veach-mis", "--width", "64", "--height", "48", "--spp", "60"];
    run_ok(bin().args(args).arg("-o").arg(d.join("single.exr")).arg("--state").arg(d.join("single.state")));
    for k in 0..4 {
        run_ok(bin().args(args).arg("--part").arg(format!("{k}/4")).arg("-o").arg(d.join(format!("p{k}.exr"))));
    }
    let part = |k: u32| d.join(format!("p{k}.state"));
    run_ok(bin().arg("merge").args([part(2), part(0), part(3), part(1)]).arg("-o").arg(d.join("m1.exr")));
    run_ok(bin().arg("merge").args([part(1), part(3), part(0), part(2)]).arg("-o").arg(d.join("m2.exr")));
    let (m1, m2) = (RenderState::read(&d.join("m1.state")).unwrap(), RenderState::read(&d.join("m2.state")).unwrap());
    assert_eq!(m1.accum, m2.accum, "the order of the files changes the merged result");
    let single = RenderState::read(&d.join("single.state")).unwrap();
    let mut worst = 0f64;
    for (a, b) in single.accum.iter().zip(&m1.accum) {
        assert_eq!((a.count, a.nonfinite), (b.count, b.nonfinite));
        for c in 0..3 {
            let (x, y) = (a.mean[c] as f64, b.mean[c] as f64);
            let rel = (x - y).abs() / x.abs().max(y.abs()).max(1e-30);
            if x != y {
                worst = worst.max(rel);
            }
        }
    }
    assert!(worst <= 1e-5, "merged parts differ from the single render by {worst:e} relative");
    eprintln!("worst relative difference merged vs single: {worst:e}");
    // The merged EXR is a reference: its header says spp.
    let r = mislab::lab::reference::read_exr(&d.join("m1.exr")).unwrap();
    assert_eq!(r.attributes.get("spp").map(String::as_str), Some("60"));
    // `mislab bench --ref` reads the merged state as a reference too.
    let r = mislab::lab::reference::read_exr(&d.join("m1.state")).unwrap();
    assert_eq!(r.pixels, m1.accum.iter().map(|a| a.mean).collect::<Vec<_>>());
    assert_eq!(r.attributes.get("spp").map(String::as_str), Some("60"));
    // Status of the directory: complete; then with a part gone, incomplete and naming it.
    let (code, t) = run_code(bin().args(["merge", "--status"]).arg(&d));
    assert_eq!(code, 0, "{t}");
    std::fs::remove_file(part(2)).unwrap();
    for f in ["single.state", "m1.state", "m2.state"] {
        std::fs::remove_file(d.join(f)).unwrap();
    }
    let (code, t) = run_code(bin().args(["merge", "--status"]).arg(&d));
    assert_eq!(code, 1, "{t}");
    assert!(t.contains("45 of 60") && t.contains("30..45") && t.contains("--part 2/4"), "{t}");
    let (code, t) = run_code(bin().arg("merge").args([part(0), part(1), part(3)]).arg("-o").arg(d.join("m3.exr")));
    assert_eq!(code, 2, "{t}");
    assert!(t.contains("missing parts") && t.contains("30..45"), "{t}");
    let _ = std::fs::remove_dir_all(&d);
}

// ---- CPU only: the file format, refusals and the merge arithmetic ----

fn header(seed: u32, part: Option<(u32, u32)>, total: u32, w: u32, h: u32) -> StateHeader {
    let range = part.map_or((0, total), |(k, n)| part_range(k, n, total));
    StateHeader {
        scene: "test".into(),
        scene_hash: "0123456789abcdef".into(),
        settings: Settings { width: w, height: h, seed, ..Settings::default() },
        seed,
        spp_total: total,
        sampler_spp: total,
        part,
        range,
        next: range.1,
        nonfinite_total: 0,
        rays_total: 0,
        seconds: 0.0,
        mislab_version: "test".into(),
    }
}

fn write_state(path: &Path, h: StateHeader) {
    let n = (h.settings.width * h.settings.height) as usize;
    let count = h.next - h.range.0;
    let accum = vec![GpuAccum { mean: [0.5; 3], count, m2: [0.1; 3], nonfinite: 0 }; n];
    RenderState { header: h, accum }.write(path).unwrap();
}

#[test]
fn corrupted_truncated_and_foreign_state_files_are_refused_with_exit_2() {
    let d = tmp("bad");
    let good = d.join("good.state");
    write_state(&good, header(0, None, 16, 8, 4));
    let bytes = std::fs::read(&good).unwrap();
    assert!(RenderState::read(&good).is_ok());
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("truncated.state", bytes[..bytes.len() - 40].to_vec(), "truncated"),
        ("short.state", bytes[..30].to_vec(), "truncated"),
        (
            "flipped.state",
            {
                let mut b = bytes.clone();
                let i = b.len() - 100;
                b[i] ^= 0x10;
                b
            },
            "checksum",
        ),
        (
            "header.state",
            {
                let mut b = bytes.clone();
                b[40] ^= 0x01;
                b
            },
            "corrupted",
        ),
        ("foreign.state", b"P6 not a state file at all, just some bytes".to_vec(), "MISLABST"),
        ("empty.state", Vec::new(), "MISLABST"),
    ];
    for (name, data, why) in cases {
        let p = d.join(name);
        std::fs::write(&p, data).unwrap();
        let e = RenderState::read(&p).unwrap_err();
        assert!(e.to_string().contains(name) && e.to_string().contains(why), "{name}: {e}");
        // The binary refuses it before it needs a GPU or the scene: exit 2, the file named.
        let (code, t) =
            run_code(bin().args(["render", "--width", "8", "--height", "4", "--spp", "16", "--resume"]).arg(&p));
        assert_eq!(code, 2, "{t}");
        assert!(t.contains(name) && !t.contains("panicked"), "{t}");
        let (code, t) = run_code(bin().arg("merge").arg(&good).arg(&p).arg("-o").arg(d.join("m.exr")));
        assert_eq!(code, 2, "{t}");
        assert!(t.contains(name), "{t}");
    }
    // Foreign, duplicate and overlapping parts, by name.
    let p = |n: &str| d.join(n);
    write_state(&p("a0.state"), header(0, Some((0, 2)), 16, 8, 4));
    write_state(&p("a1.state"), header(0, Some((1, 2)), 16, 8, 4));
    write_state(&p("s1.state"), header(9, Some((1, 2)), 16, 8, 4));
    write_state(&p("b1.state"), header(0, Some((1, 3)), 16, 8, 4));
    let mut inc = header(0, Some((1, 2)), 16, 8, 4);
    inc.next = inc.range.0 + 3;
    write_state(&p("i1.state"), inc);
    let merge = |files: &[&str]| {
        let mut c = bin();
        c.arg("merge");
        for f in files {
            c.arg(p(f));
        }
        run_code(c.arg("-o").arg(p("m.exr")))
    };
    let (code, t) = merge(&["a0.state", "a1.state"]);
    assert_eq!(code, 0, "{t}");
    for (files, expect) in [
        (&["a0.state", "s1.state"][..], "s1.state: a foreign part"),
        (&["a0.state", "a1.state", "a1.state"][..], "a1.state: given twice"),
        (&["a0.state", "a1.state", "b1.state"][..], "overlapping parts"),
        (&["a0.state", "i1.state"][..], "i1.state: an incomplete part"),
        (&["a1.state"][..], "missing parts: samples 0..8"),
    ] {
        let (code, t) = merge(files);
        assert_eq!(code, 2, "{files:?}: {t}");
        assert!(t.contains(expect), "{files:?}: expected '{expect}' in: {t}");
    }
    std::fs::copy(p("a1.state"), p("copy-of-a1.state")).unwrap();
    let (code, t) = merge(&["a0.state", "a1.state", "copy-of-a1.state"]);
    assert_eq!(code, 2, "{t}");
    assert!(t.contains("duplicate parts") && t.contains("copy-of-a1.state"), "{t}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn parts_cover_every_sample_index_once() {
    for total in [1u32, 7, 64, 1000, 4097] {
        for n in 1..=total.min(9) {
            let mut next = 0;
            for k in 0..n {
                let (s, e) = part_range(k, n, total);
                assert_eq!(s, next);
                assert!(e > s, "part {k}/{n} of {total} is empty");
                next = e;
            }
            assert_eq!(next, total);
        }
    }
}

#[test]
fn chan_merge_equals_the_statistics_of_all_samples() {
    // Welford in f64 per part (what the device does in f32), merged, against the two-pass mean and M2.
    let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
    let samples: Vec<f64> =
        (0..200).map(|_| if rng.random::<f64>() < 0.05 { 50.0 } else { rng.random::<f64>() }).collect();
    let welford = |xs: &[f64]| {
        let (mut mean, mut m2) = (0f64, 0f64);
        for (i, &x) in xs.iter().enumerate() {
            let d = x - mean;
            mean += d / (i + 1) as f64;
            m2 += d * (x - mean);
        }
        GpuAccum { mean: [mean as f32; 3], count: xs.len() as u32, m2: [m2 as f32; 3], nonfinite: 1 }
    };
    let cuts = [0, 13, 60, 61, 150, 200];
    let parts: Vec<Vec<GpuAccum>> = cuts.windows(2).map(|w| vec![welford(&samples[w[0]..w[1]])]).collect();
    let merged = merge_accum(&parts.iter().map(|p| p.as_slice()).collect::<Vec<_>>())[0];
    let mean = samples.iter().sum::<f64>() / samples.len() as f64;
    let m2: f64 = samples.iter().map(|x| (x - mean) * (x - mean)).sum();
    assert_eq!(merged.count, 200);
    assert_eq!(merged.nonfinite, 5);
    assert!((merged.mean[0] as f64 - mean).abs() <= 1e-6 * mean, "{} vs {mean}", merged.mean[0]);
    assert!((merged.m2[0] as f64 - m2).abs() <= 1e-5 * m2, "{} vs {m2}", merged.m2[0]);
    // check_parts sorts: any file order gives the same parts order.
    let d = tmp("order");
    let mk = |k: u32| {
        let path = d.join(format!("q{k}.state"));
        write_state(&path, header(0, Some((k, 3)), 30, 2, 2));
        Part { path: path.clone(), state: RenderState::read(&path).unwrap() }
    };
    let sorted = check_parts(vec![mk(2), mk(0), mk(1)]).unwrap();
    let ranges: Vec<_> = sorted.iter().map(|p| p.state.header.range).collect();
    assert_eq!(ranges, vec![(0, 10), (10, 20), (20, 30)]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn reference_parts_merge_to_the_whole_reference() {
    let d = tmp("ref");
    let args = ["reference", "veach-mis", "--width", "48", "--height", "32", "--spp", "16"];
    run_ok(bin().args(args).arg("-o").arg(d.join("whole.exr")).arg("--state").arg(d.join("whole.state")));
    for k in 0..3 {
        run_ok(bin().args(args).arg("--part").arg(format!("{k}/3")).arg("-o").arg(d.join(format!("r{k}.exr"))));
    }
    let part = |k: u32| d.join(format!("r{k}.state"));
    run_ok(bin().arg("merge").args([part(1), part(2), part(0)]).arg("-o").arg(d.join("merged.exr")));
    let whole = RenderState::read(&d.join("whole.state")).unwrap();
    let merged = mislab::lab::reference::read_exr(&d.join("merged.exr")).unwrap();
    assert_eq!(merged.attributes.get("spp").map(String::as_str), Some("16"));
    for (a, b) in whole.accum.iter().zip(&merged.pixels) {
        for c in 0..3 {
            let (x, y) = (a.mean[c] as f64, b[c] as f64);
            assert!((x - y).abs() <= 1e-5 * x.abs().max(y.abs()), "{x} vs {y}");
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}

// Issue 47: a state path that the image would overwrite, or that cannot hold a file, is refused before rendering;
// `--resume S` alone takes the sample count and every setting from the state, and a bad state is reported as such.
#[test]
fn state_paths_are_checked_and_a_resume_alone_takes_its_settings_from_the_state() {
    let d = tmp("resume-alone");
    let refused = |args: &[&str], want: &str| {
        let (code, t) = run_code(bin().current_dir(&d).args(args));
        assert_eq!(code, 2, "{args:?}: {t}");
        assert!(t.contains(want) && !t.contains("start-up") && !t.contains("panicked"), "{args:?}: {t}");
    };
    refused(&["render", "--spp", "4", "--state", "x.exr", "-o", "x.exr"], "same file");
    std::fs::create_dir_all(d.join("sub")).unwrap();
    refused(&["render", "--spp", "4", "--state", "./sub/../x.exr", "-o", "x.exr"], "same file");
    std::fs::create_dir_all(d.join("dir.state")).unwrap();
    refused(&["render", "--spp", "4", "--state", "dir.state", "-o", "y.exr"], "is a directory");
    let fifo = d.join("fifo.state");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "mkfifo");
    refused(&["render", "--spp", "4", "--state", "fifo.state", "-o", "y.exr"], "not a regular file");
    // A FIFO given to --resume is refused, not read (reading would block).
    refused(&["render", "--resume", "fifo.state", "-o", "y.exr"], "not a regular file");
    std::fs::write(d.join("bad.state"), b"MISLABST but then nothing sensible").unwrap();
    refused(&["render", "--resume", "bad.state", "-o", "y.exr"], "bad.state");

    // A whole render with settings far from the defaults, then `--resume` with nothing else: the same image.
    let settings = ["--width", "40", "--height", "24", "--seed", "7", "--strategy", "light", "--sampler", "sobol"];
    run_ok(
        bin()
            .current_dir(&d)
            .args(["render", "veach-mis", "--spp", "8"])
            .args(settings)
            .args(["--state", "a.state", "-o", "a.exr"]),
    );
    let t = run_ok(bin().current_dir(&d).args(["render", "veach-mis", "--resume", "a.state", "-o", "b.exr"]));
    assert!(t.contains("resuming"), "{t}");
    let a = RenderState::read(&d.join("a.state")).unwrap();
    assert_eq!((a.header.settings.seed, a.header.spp_total, a.header.next), (7, 8, 8));
    // The EXRs hold the same pixels (their headers differ only in the render time).
    let pixels = |n: &str| mislab::lab::compare::read(&d.join(n)).unwrap().pixels;
    assert_eq!(pixels("a.exr"), pixels("b.exr"));
    // A flag given with another value than the state's is refused by name.
    let (code, t) = run_code(bin().current_dir(&d).args([
        "render",
        "veach-mis",
        "--resume",
        "a.state",
        "--seed",
        "8",
        "-o",
        "c.exr",
    ]));
    assert_eq!(code, 2, "{t}");
    assert!(t.contains("a.state") && t.contains("seed: 7 vs 8"), "{t}");
    let _ = std::fs::remove_dir_all(&d);
}
