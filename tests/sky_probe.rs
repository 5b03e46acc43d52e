//! The sky probe that decides `--env-sampling auto` (src/render/sky_probe.rs): on the CPU, no device. A room lit
//! through a window wants the guide, an object under the open sky does not; the bench's real scenes fall on the
//! sides the render measurements put them (docs/estimators.md, "Only where the sky is hidden").

mod common;

use common::scene;
use mislab::render::scene_data::SceneData;
use mislab::render::sky_probe::{self, SkyProbe, MIN_GUIDED_SHARE};
use mislab::scene::Scene;

fn probe(scene: &Scene, width: u32, height: u32) -> SkyProbe {
    let d = SceneData::build(scene);
    sky_probe::probe_view(&d, &scene.camera, width, height).expect("the probe sees this scene")
}

fn data(relative: &str) -> String {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(relative);
    p.to_str().expect("a UTF-8 path").to_string()
}

/// A flat scene (no BVH): inside the window room nearly every surface sees the sky through the window only.
#[test]
fn a_room_lit_through_a_window_wants_the_guide() {
    let p = probe(&scene(&data("tests/data/scenes/window_room.toml")), 96, 96);
    eprintln!("window room: {p:?}");
    assert!(p.hits >= p.rays * 95 / 100, "the camera is inside the room: a few rays leave through the window");
    assert!(p.guided_share > 0.8, "guided share {} in a room lit through a small window", p.guided_share);
    assert!(p.wants_guide());
}

/// What is left of the room when only its floor and the two walls that meet at the origin stand: the sky is
/// seen from most of it. (Without its ceiling alone it would still want the guide: 2.5-high walls around a 4 × 4
/// floor hide most of the sky from the walls and the floor's edges.)
#[test]
fn a_floor_in_the_open_does_not() {
    let mut room = scene(&data("tests/data/scenes/window_room.toml"));
    room.quads.retain(|q| q.corner == glam::Vec3::ZERO);
    assert_eq!(room.quads.len(), 3, "the window room's floor and walls moved: update this test");
    let p = probe(&room, 96, 96);
    eprintln!("floor and two walls: {p:?}");
    assert!(p.hits > p.rays / 4, "the camera still sees the floor");
    assert!(
        !p.wants_guide(),
        "guided share {} under an open sky (the guide is used from {MIN_GUIDED_SHARE})",
        p.guided_share
    );
}

/// Through the wide BVH, on the bench's grey scenes: the interior wants the guide (its guide guides 1,304 of 5,184
/// slots), the helmet under the open sky does not (its guide guides none).
#[test]
fn bench_scenes_fall_on_their_sides() {
    let bench = |s: &str| data(&format!("../shared/bench-scenes/{s}/{s}.toml"));
    let staircase = probe(&scene(&bench("staircase2_grey")), 512, 512);
    let helmet = probe(&scene(&bench("damagedhelmet_grey")), 512, 512);
    eprintln!("staircase2: {staircase:?}\nhelmet: {helmet:?}");
    assert!(staircase.wants_guide() && staircase.guided_share > 0.4, "staircase2: {staircase:?}");
    assert!(!helmet.wants_guide() && helmet.guided_share < 0.05, "helmet: {helmet:?}");
    assert!(helmet.hits > helmet.rays / 10 && helmet.hits < helmet.rays, "the helmet fills part of the frame");
}
