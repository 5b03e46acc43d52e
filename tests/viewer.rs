//! The viewer, tested as a person uses it: egui_kittest drives the real UI (its wgpu renderer on
//! lavapipe), finds controls by their labels through AccessKit, clicks and selects them, and checks
//! that the render engine's settings changed and its accumulation restarted. Plus the display pass
//! against its CPU twin, its shared layouts, the camera controller and snapshots of the panel.

mod common;
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use mislab::gpu::types::GpuAccum;
use mislab::render::display::{self, DisplayInputs, DisplayParams, DisplayPass, View};
use mislab::render::film::{linear_to_srgb, tonemap, Tonemap};
use mislab::render::settings::*;
use mislab::viewer::app::Viewer;
use mislab::viewer::engine::{Command, Shared};
use mislab::viewer::widgets::settings_grid;
use mislab::viewer::{self, ViewArgs};
use std::sync::Arc;
use std::time::Duration;

/// How long a test waits for the engine: a cold Mesa shader cache compiles the first specialised
/// pipeline in ~7 s on an idle 2-core machine, several times that on a loaded one.
const WAIT: Duration = Duration::from_secs(240);

/// Every setting the CLI has, by its flag name.
const SETTING_NAMES: &[&str] = &[
    "mode",
    "strategy",
    "light-sampling",
    "env-sampling",
    "light-select",
    "heuristic",
    "power-beta",
    "mis",
    "light-samples",
    "bsdf-samples",
    "first-hit-light-split",
    "sampler",
    "max-depth",
    "seed",
];

/// A small film keeps every test fast on lavapipe. Without the generic pipeline: its first compile
/// costs tens of seconds of CPU on a cold Mesa shader cache, and only the toggle test needs it.
fn args() -> ViewArgs {
    ViewArgs { width: 64, height: 64, no_generic: true, ..ViewArgs::default() }
}

/// One viewer at a time: each has a render thread and a pipeline compiler, and the machine has 2 cores.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn harness(args: ViewArgs) -> (Harness<'static, Viewer>, std::sync::MutexGuard<'static, ()>) {
    let guard = ONE_AT_A_TIME.lock().unwrap_or_else(|p| p.into_inner());
    let viewer = viewer::start(&args, Arc::new(|| {})).unwrap_or_else(|e| panic!("starting the viewer: {e}"));
    (Harness::builder().with_size([900.0, 1000.0]).build_ui_state(|ui, v: &mut Viewer| v.ui(ui), viewer), guard)
}

/// Steps the UI until the engine state satisfies `cond` (the engine runs on its own thread).
fn step_until(h: &mut Harness<'static, Viewer>, what: &str, mut cond: impl FnMut(&Shared) -> bool) {
    let start = std::time::Instant::now();
    loop {
        h.step();
        {
            let s = h.state().engine().shared();
            if let Some(f) = &s.fatal {
                panic!("the engine stopped while waiting for {what}: {f}");
            }
            if cond(&s) {
                return;
            }
        }
        assert!(start.elapsed() < WAIT, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Opens the combo box of `setting` (side `side`) and clicks `option`.
fn select(h: &mut Harness<'static, Viewer>, setting: &str, side: usize, option: &str) {
    h.get_all_by_label(setting).nth(side).unwrap_or_else(|| panic!("no control '{setting}' for side {side}")).click();
    h.step();
    h.step();
    // The option in the open popup (not a closed combo box that happens to share the name, like "mis").
    let by = egui_kittest::kittest::By::new().label(option).predicate(|n| {
        !matches!(n.role(), eframe::egui::accesskit::Role::ComboBox | eframe::egui::accesskit::Role::Label)
    });
    h.get_all(by).last().unwrap_or_else(|| panic!("'{setting}' offers no '{option}'")).click();
    h.step();
    h.step();
}

#[test]
fn the_panel_has_every_cli_setting_and_every_choice() {
    let (mut h, _one) = harness(args());
    h.step();
    for name in SETTING_NAMES {
        assert_eq!(h.get_all_by_label(name).count(), 1, "one control named '{name}' without a comparison");
    }
    // Every value of every enum setting can be chosen, by its CLI name, and lands in the settings.
    macro_rules! every {
        ($label:literal, $ty:ty, $field:ident) => {
            for v in <$ty>::ALL {
                select(&mut h, $label, 0, v.name());
                assert_eq!(h.state().settings[0].$field, *v, "{} = {}", $label, v.name());
            }
        };
    }
    every!("mode", Mode, mode);
    every!("strategy", Strategy, strategy);
    every!("light-sampling", LightSampling, light_sampling);
    every!("env-sampling", EnvSampling, env_sampling);
    every!("light-select", LightSelect, light_select);
    every!("heuristic", Heuristic, heuristic);
    every!("mis", MisKind, mis);
    every!("sampler", SamplerKind, sampler);
    // The engine received the last choice of each.
    let want = h.state().settings[0].clone();
    step_until(&mut h, "the engine to take the settings", |s| {
        let got = &s.stats[0].settings;
        got.mode == want.mode && got.strategy == want.strategy && got.sampler == want.sampler && got.mis == want.mis
    });
}

#[test]
fn toggling_the_strategy_changes_the_renderer_and_restarts_its_samples() {
    // With the generic pipeline: the first image of the new estimator comes from it when the
    // specialised one is not built yet.
    let (mut h, _one) = harness(ViewArgs { no_generic: false, ..args() });
    step_until(&mut h, "two complete samples per pixel", |s| s.stats[0].spp >= 2);
    let (generation, spp_before) = {
        let s = h.state().engine().shared();
        (s.stats[0].generation, s.stats[0].spp)
    };
    select(&mut h, "strategy", 0, "light");
    assert_eq!(h.state().settings[0].strategy, Strategy::Light);
    step_until(&mut h, "the engine to restart with strategy light", |s| s.stats[0].generation > generation);
    {
        let s = h.state().engine().shared();
        assert_eq!(s.stats[0].settings.strategy, Strategy::Light, "the renderer's settings changed");
        assert!(
            s.stats[0].spp < spp_before,
            "the sample count restarted ({} spp before, {} after)",
            spp_before,
            s.stats[0].spp
        );
        assert_eq!(s.stats[0].generation, generation + 1, "exactly one restart");
    }
    // The first image of the new estimator reaches the UI.
    step_until(&mut h, "a frame of the new estimator", |s| {
        s.frame.as_ref().is_some_and(|f| f.generations[0] > generation && f.shown[0])
    });
    h.step();
    assert_eq!(h.state().toggle_latencies_ms.len(), 1, "the toggle was timed to its first image");
}

#[test]
fn exposure_and_view_do_not_restart_but_compare_renders_both_sides() {
    let (mut h, _one) = harness(args());
    step_until(&mut h, "the first full pass", |s| s.stats[0].spp >= 1);
    let generation = h.state().engine().shared().stats[0].generation;
    select(&mut h, "view", 0, "std-error");
    assert_eq!(h.state().display.view, View::StdErr);
    // The false-colour legend appears with the error views.
    assert!(h.query_by_label_contains("standard error of the pixel mean").is_some(), "the legend is shown");
    select(&mut h, "tonemap", 0, "aces");
    assert_eq!(h.state().display.tonemap, Tonemap::Aces);
    for _ in 0..10 {
        h.step();
    }
    assert_eq!(
        h.state().engine().shared().stats[0].generation,
        generation,
        "display options never restart the accumulation"
    );

    h.get_by_label("compare A | B").click();
    h.step();
    h.step();
    assert!(h.state().compare);
    assert_eq!(h.get_all_by_label("strategy").count(), 2, "side B has its own settings column");
    select(&mut h, "strategy", 1, "cosine");
    assert_eq!(h.state().settings[1].strategy, Strategy::Cosine);
    assert_eq!(h.state().settings[0].strategy, Strategy::Mis, "side A keeps its settings");
    step_until(&mut h, "side B to render with cosine", |s| {
        s.compare && s.stats[1].settings.strategy == Strategy::Cosine && s.stats[1].spp >= 1
    });
    let s = h.state().engine().shared();
    assert!(s.stats[0].spp >= 1 && s.stats[1].samples_per_s > 0.0, "both sides have statistics");
    assert_eq!(s.stats[0].generation, generation, "side A was not restarted by side B's change");
}

#[test]
fn camera_reset_and_device_loss_recover() {
    let (mut h, _one) = harness(args());
    step_until(&mut h, "the first frame", |s| s.frames >= 1);
    // Zoom with the wheel over the image moves the camera; reset brings back the scene's camera.
    let home = h.state().engine().shared().home_camera.clone();
    h.state().engine().send(Command::Camera(mislab::scene::Camera {
        position: home.position + glam::Vec3::new(0.5, 0.0, 0.0),
        ..home.clone()
    }));
    step_until(&mut h, "the moved camera", |s| s.camera.position != home.position);
    h.get_by_label("reset camera").click();
    h.step();
    step_until(&mut h, "the camera reset", |s| s.camera.position == home.position);
    // A lost device is recreated and rendering carries on.
    let frames = h.state().engine().shared().frames;
    h.state().engine().send(Command::LoseDevice);
    step_until(&mut h, "the device to be recreated", |s| s.recoveries >= 1);
    step_until(&mut h, "frames after the recovery", |s| s.frames > frames && s.stats[0].spp >= 1);
    assert!(
        h.state().engine().shared().message.as_deref().unwrap_or("").contains("recreated"),
        "the status line says what happened"
    );
}

#[test]
fn save_png_and_exr_and_open_files() {
    let dir = std::env::temp_dir().join(format!("mislab-viewer-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (mut h, _one) = harness(args());
    step_until(&mut h, "the first full pass", |s| s.stats[0].spp >= 1);
    h.step();
    let png = dir.join("shown.png");
    h.state_mut().save(png.clone());
    let img = image::open(&png).expect("the PNG was written").to_rgb8();
    assert_eq!((img.width(), img.height()), (64, 64));
    let exr = dir.join("film.exr");
    h.state_mut().save(exr.clone());
    step_until(&mut h, "the EXR to be written", |s| s.message.as_deref().is_some_and(|m| m.contains("film.exr")));
    let film = image::open(&exr).expect("the EXR was written").to_rgb32f();
    assert_eq!((film.width(), film.height()), (64, 64));
    // The EXR has the film's size, so dropping it loads it as the reference: RMSE appears (≈ the
    // difference of this render from itself a little later).
    h.state_mut().open_path(exr.clone());
    step_until(&mut h, "the reference", |s| s.has_reference && s.stats[0].image.rmse.is_some());
    assert!(h.query_by_label("RMSE vs reference").is_some());
    // Typing a built-in scene name and pressing the button opens it.
    h.get_by_label("Files").click();
    h.step();
    let field = h.get_by_label("scene path");
    field.focus();
    h.step();
    h.state_mut().scene_path = "cornell-box".into();
    h.step();
    h.get_by_label("open scene").click();
    h.step();
    step_until(&mut h, "the new scene", |s| s.scene == "cornell-box" && s.frames > 0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Snapshot of the estimator panel (A | B). Threshold: kittest's default per-pixel YIQ distance 0.6
/// with up to 40 differing pixels — the image is drawn by egui's own rasterisation on one software
/// device, so it is reproducible bit for bit on lavapipe; the allowance covers font anti-aliasing on
/// other drivers. Update with UPDATE_SNAPSHOTS=1.
#[test]
fn snapshot_of_the_estimator_panel() {
    let mut settings = [Settings::default(), Settings { strategy: Strategy::Bsdf, ..Settings::default() }];
    settings[0].strategy = Strategy::Light;
    let mut h = Harness::builder().with_size([330.0, 330.0]).build_ui_state(
        |ui, s: &mut [Settings; 2]| {
            settings_grid(ui, s, 2);
        },
        settings,
    );
    h.run();
    h.snapshot_options(
        "viewer_estimator_panel",
        &egui_kittest::SnapshotOptions::new().threshold(0.6).max_failed_pixels(40),
    );
}

/// The display pass against its CPU twins: tonemapping as `film::tonemap`, the false-colour scale as
/// `display::false_colour`, the preview fallback, the NaN/Inf mask and the statistics sums.
/// Tolerance: 1/255 + the 8-bit rounding for display values (the GPU's `pow` differs from Rust's by a
/// few ulps, and the output is quantised to 8 bits), 1e-5 relative for the sums.
#[test]
fn display_pass_matches_its_cpu_twin() {
    let ctx = common::gpu();
    let (w, h) = (16u32, 16u32);
    let n = (w * h) as usize;
    let mut accum = vec![GpuAccum::default(); n];
    for (i, a) in accum.iter_mut().enumerate() {
        let v = i as f32 / n as f32 * 1.5;
        *a = GpuAccum {
            mean: [v, 0.5 * v, 0.25],
            count: 4 + (i as u32 % 3),
            m2: [0.01 * (i as f32 + 1.0); 3],
            nonfinite: 0,
        };
    }
    accum[5] = GpuAccum::default(); // no samples yet: shows the preview
    accum[7].nonfinite = 2;
    let preview = vec![GpuAccum { mean: [0.3, 0.6, 0.9], count: 1, m2: [0.0; 3], nonfinite: 0 }; 4];
    let a = ctx.storage_buffer("a", &accum, wgpu::BufferUsages::empty());
    let p = ctx.storage_buffer("p", &preview, wgpu::BufferUsages::empty());
    let pass = DisplayPass::new(&ctx, w, h).unwrap();
    let run = |view: View, tm: Tonemap, exposure: f32| {
        let params = DisplayParams {
            width: w,
            height: h,
            view: view.tag(),
            tonemap: display::tonemap_tag(tm),
            exposure_scale: exposure.exp2(),
            split_x: w,
            preview_scale: 8,
            preview_width: 2,
            preview_height: 2,
            log_min: -3.0,
            log_max: 0.0,
            row_offset: 0,
            row_count: h,
            ..Default::default()
        };
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        pass.encode(
            &mut enc,
            &params,
            &DisplayInputs { accum: [&a, &a], preview: [&p, &p], reference: None },
            true,
            None,
        );
        ctx.queue.submit([enc.finish()]);
        pass.read(&ctx, true).unwrap()
    };
    let px = |rgba: &[u8], i: usize| [rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]];
    let close = |got: [u8; 3], want: [f32; 3], what: &str| {
        for c in 0..3 {
            assert!(
                (got[c] as f32 - want[c] * 255.0).abs() <= 1.5,
                "{what}: channel {c} is {} , want {}",
                got[c],
                want[c] * 255.0
            );
        }
    };
    for (tm, exposure) in [(Tonemap::Clamp, 0.0), (Tonemap::Aces, 1.0)] {
        let out = run(View::Image, tm, exposure);
        for i in [0usize, 17, 100, 255] {
            let want = accum[i].mean.map(|v| linear_to_srgb(tonemap(v, exposure, tm)));
            close(px(&out.rgba, i), want, &format!("image pixel {i} ({tm:?})"));
        }
        let want = preview[0].mean.map(|v| linear_to_srgb(tonemap(v, exposure, tm)));
        close(px(&out.rgba, 5), want, "a pixel without samples shows its preview");
    }
    let out = run(View::StdErr, Tonemap::Clamp, 0.0);
    for i in [0usize, 33, 200] {
        let a = accum[i];
        let nn = a.count as f32;
        let se = ((a.m2[0] + a.m2[1] + a.m2[2]) / 3.0 / ((nn - 1.0) * nn)).sqrt();
        let t = (se.log10() + 3.0) / 3.0;
        close(px(&out.rgba, i), display::false_colour(t), &format!("stderr pixel {i}"));
    }
    let out = run(View::NonFinite, Tonemap::Clamp, 0.0);
    assert_eq!(px(&out.rgba, 7), [255, 0, 255], "a pixel with NaN/Inf samples is magenta");
    assert_ne!(px(&out.rgba, 8), [255, 0, 255]);
    // Statistics: mean relative standard error over pixels with ≥ 2 samples and a positive mean.
    let mut sum = 0f64;
    let mut count = 0f64;
    for a in &accum {
        let m = (a.mean[0] + a.mean[1] + a.mean[2]) as f64 / 3.0;
        if a.count >= 2 && m > 1e-6 {
            let nn = a.count as f64;
            let se = ((a.m2.iter().map(|&x| x as f64).sum::<f64>() / 3.0) / ((nn - 1.0) * nn)).sqrt();
            sum += se / m;
            count += 1.0;
        }
    }
    let stats = out.stats.expect("statistics were summed");
    let got = stats[0].mean_rel_se.expect("pixels with samples");
    assert!((got - sum / count).abs() <= 1e-5 * (sum / count), "mean rel. std. error {got} vs {}", sum / count);
    assert_eq!(stats[0].nonfinite_px, 1);
}

/// Every struct display.wgsl shares with Rust has the same layout on both sides (naga's layout).
#[test]
fn display_layouts_match() {
    let src = display::display_source();
    let m = mislab::render::shaders::validate(&src).unwrap_or_else(|e| panic!("display module:\n{e}"));
    let layout = |name: &str| -> (u32, Vec<(String, u32)>) {
        for (_, ty) in m.types.iter() {
            if ty.name.as_deref() == Some(name) {
                if let naga::TypeInner::Struct { members, span } = &ty.inner {
                    return (*span, members.iter().map(|x| (x.name.clone().unwrap_or_default(), x.offset)).collect());
                }
            }
        }
        panic!("no WGSL struct {name}");
    };
    macro_rules! check {
        ($wgsl:literal, $rust:ty, [$($f:ident),+]) => {{
            let (size, members) = layout($wgsl);
            assert_eq!(size as usize, std::mem::size_of::<$rust>(), "size of {}", $wgsl);
            let rust = vec![$((stringify!($f), std::mem::offset_of!($rust, $f))),+];
            assert_eq!(members.len(), rust.len(), "{}", $wgsl);
            for ((wn, wo), (rn, ro)) in members.iter().zip(rust) {
                assert_eq!((wn.as_str(), *wo as usize), (rn, ro), "{}", $wgsl);
            }
        }};
    }
    check!("Accum", GpuAccum, [mean, count, m2, nonfinite]);
    check!(
        "DisplayParams",
        DisplayParams,
        [
            width,
            height,
            view,
            tonemap,
            exposure_scale,
            split_x,
            compare,
            has_reference,
            preview_scale,
            preview_width,
            preview_height,
            log_min,
            log_max,
            row_offset,
            row_count,
            _pad0
        ]
    );
    check!("SideSums", display::SideSums, [rel_se, rel_se_n, sq_err, rel_mse, err_n, nonfinite_px, sampled_px, _pad0]);
    check!("Partial", display::Partial, [a, b]);
    for v in View::ALL {
        let name = format!(
            "VIEW_{}",
            match v {
                View::Image => "IMAGE",
                View::StdErr => "STDERR",
                View::RelMse => "RELMSE",
                View::NonFinite => "NONFINITE",
            }
        );
        let c = m.constants.iter().find(|(_, c)| c.name.as_deref() == Some(&name)).unwrap_or_else(|| panic!("{name}"));
        match m.global_expressions[c.1.init] {
            naga::Expression::Literal(naga::Literal::U32(x)) => assert_eq!(x, v.tag(), "{name}"),
            _ => panic!("{name} is not a u32"),
        }
    }
}

/// Orbiting keeps the pivot and the distance to it; panning moves across the view; zooming moves
/// towards the pivot.
#[test]
fn camera_controls() {
    use mislab::viewer::camera::Orbit;
    let cam = mislab::scene::Camera::look_at(glam::Vec3::new(0.0, 1.0, 5.0), glam::Vec3::ZERO, glam::Vec3::Y, 40.0);
    let mut o = Orbit::new(cam.clone(), glam::Vec3::ZERO);
    let pivot = o.pivot();
    assert!((pivot - glam::Vec3::ZERO).length() < 1e-4, "the pivot is the centre on the view axis");
    o.orbit(0.7, 0.3);
    assert!((o.pivot() - pivot).length() < 1e-4);
    assert!(((o.camera.position - pivot).length() - o.distance).abs() < 1e-4);
    o.orbit(0.0, 10.0);
    assert!(o.camera.forward.dot(glam::Vec3::Y).abs() < 0.9999, "pitch stops short of the pole");
    let before = o.clone();
    o.pan(10.0, 0.0, 100.0);
    assert!(
        (o.camera.position - before.camera.position).dot(before.camera.forward).abs() < 1e-4,
        "pan stays in the image plane"
    );
    let d = o.distance;
    o.zoom(0.5);
    assert!((o.distance - 0.5 * d).abs() < 1e-4);
}

/// The viewer on a sky-lit room (tests/data/scenes/window_room.toml): under `env-sampling auto` (the default, which
/// the sky probe makes guided here) a restart's first pass also learns the
/// environment guide (`Renderer::ensure_guide`, called by the engine before a side's band); rendering goes on past
/// it with no NaN/Inf, and after a settings change (here the mode, which resets the guide) likewise.
#[test]
fn a_sky_lit_room_learns_its_guide_and_renders_on() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/scenes/window_room.toml");
    let mut a = args();
    a.scene.scene = path.display().to_string();
    let (mut h, _one) = harness(a);
    // The image statistics follow the samples at the engine's cadence (STATS_INTERVAL), so wait for both.
    step_until(&mut h, "three samples per pixel and their image statistics", |s| {
        s.stats[0].spp >= 3 && s.stats[0].image.mean_rel_se.is_some()
    });
    {
        let s = h.state().engine().shared();
        assert_eq!(s.stats[0].settings.env_sampling, EnvSampling::Auto, "auto is the default");
        assert_eq!(s.stats[0].env_sampling, EnvSampling::Guided, "auto guides the room lit through a window");
        assert_eq!(s.stats[0].nonfinite_samples, 0, "NaN/Inf samples in the guided room");
        assert!(s.stats[0].image.mean_rel_se.is_some_and(f64::is_finite), "{:?}", s.stats[0].image);
    }
    select(&mut h, "mode", 0, "path");
    step_until(&mut h, "path samples after the restart", |s| {
        s.stats[0].settings.mode == Mode::Path && s.stats[0].spp >= 3
    });
    assert_eq!(h.state().engine().shared().stats[0].nonfinite_samples, 0, "NaN/Inf samples in path mode");
}
