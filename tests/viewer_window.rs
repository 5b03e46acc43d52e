//! `mislab view SCENE --screenshot out.png --frames N` opens a real window (eframe, wgpu surface on
//! lavapipe) under Xvfb, renders, toggles the estimator, saves the whole window and exits. The test
//! checks the exit status, what it printed, and the screenshot's size and content.

use std::path::PathBuf;
use std::process::Command;

fn have(program: &str) -> bool {
    Command::new("sh").args(["-c", &format!("command -v {program}")]).output().is_ok_and(|o| o.status.success())
}

#[test]
fn screenshot_of_a_real_window_with_toggles() {
    assert!(have("xvfb-run"), "this test needs Xvfb: apt-get install xvfb xauth (.ci/run installs it)");
    let dir = std::env::temp_dir().join(format!("mislab-viewer-window-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let shot: PathBuf = dir.join("window.png");
    let runtime = dir.join("xdg");
    std::fs::create_dir_all(&runtime).unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&runtime, std::fs::Permissions::from_mode(0o700)).unwrap();
    }
    // `timeout` bounds the whole run: a hang is a failure, never a stuck CI job.
    let out = Command::new("timeout")
        .args([
            "900",
            "xvfb-run",
            "-a",
            "-s",
            "-screen 0 1280x800x24",
            env!("CARGO_BIN_EXE_mislab"),
            "view",
            "veach-mis",
        ])
        .args([
            "--width",
            "256",
            "--height",
            "256",
            "--compare",
            "bsdf",
            "--toggles",
            "2",
            // Few frames: the first frames are bands of the first pass, and the screenshot must still wait for a
            // whole sample per pixel (it once captured "0 spp").
            "--frames",
            "2",
            "--screenshot",
        ])
        .arg(&shot)
        .env("XDG_RUNTIME_DIR", &runtime)
        .output()
        .expect("running xvfb-run");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "mislab view failed ({}):\n{stderr}", out.status);
    assert!(stderr.contains("UI while rendering"), "it reports the UI frame rate:\n{stderr}");
    assert!(stderr.contains("first image of the new estimator"), "it reports the toggle latency:\n{stderr}");
    let spp: u32 = stderr
        .lines()
        .find_map(|l| l.split_once(" (")?.1.strip_suffix(" spp on side A)")?.parse().ok())
        .unwrap_or_else(|| panic!("it says how many spp the screenshot shows:\n{stderr}"));
    assert!(spp >= 1, "the screenshot shows {spp} spp:\n{stderr}");
    let img = image::open(&shot).expect("the screenshot was written").to_rgb8();
    let panel = mislab::viewer::app::PANEL_WIDTH as u32;
    assert!(
        img.width() >= panel + 256 && img.height() >= 256,
        "the window holds the panel and the image: {}x{}",
        img.width(),
        img.height()
    );
    // The panel has text (bright pixels on the dark theme) and the image area has a rendered,
    // non-uniform picture.
    let bright = |x0: u32, x1: u32| {
        (x0..x1)
            .flat_map(|x| (0..img.height()).map(move |y| (x, y)))
            .filter(|&(x, y)| img.get_pixel(x, y).0.iter().any(|&c| c > 150))
            .count()
    };
    assert!(bright(0, panel) > 500, "the panel shows text");
    assert!(bright(panel + 10, img.width()) > 200, "the image area shows a rendered image");
    let _ = std::fs::remove_dir_all(&dir);
}
