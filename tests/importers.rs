//! The pbrt-v4 and Mitsuba 3 importers: malformed files (tests/data/bad-import) end with exit 2 and an error
//! naming the file and line, every Bitterli scene in ../shared loads (counts, camera, film size), and a small
//! render of an imported scene has no NaN/Inf samples.

use std::path::{Path, PathBuf};
use std::process::Command;

fn bad_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bad-import")
}

fn bitterli(rel: &str) -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/testdata/scenes/bitterli")).join(rel)
}

/// Runs `mislab render FILE` (the scene is read before any device is needed) and returns (exit code, stderr).
fn render(file: &Path, extra: &[&str]) -> (Option<i32>, String) {
    let out = std::env::temp_dir().join(format!("mislab-importers-{}.png", std::process::id()));
    let o = Command::new(env!("CARGO_BIN_EXE_mislab"))
        .arg("render")
        .arg(file)
        .args(["-o", out.to_str().unwrap()])
        .args(extra)
        .output()
        .expect("run mislab");
    let _ = std::fs::remove_file(&out);
    (o.status.code(), String::from_utf8_lossy(&o.stderr).into_owned())
}

#[test]
fn malformed_files_name_file_and_line() {
    // (file, where the error must point, what it must say)
    let cases: &[(&str, &str, &str)] = &[
        ("truncated.pbrt", "truncated.pbrt: line 3", "ends before ']'"),
        ("unclosed.pbrt", "unclosed.pbrt: line 2", "never closed"),
        ("unknown-directive.pbrt", "unknown-directive.pbrt: line 3", "unknown directive 'Frobnicate'"),
        ("wrong-type.pbrt", "wrong-type.pbrt: line 3", "expected a quoted string"),
        ("wrong-count.pbrt", "wrong-count.pbrt: line 3", "multiple of 3"),
        ("lookat-count.pbrt", "lookat-count.pbrt: line 1", "LookAt expects 9 numbers"),
        ("missing-ply.pbrt", "missing-ply.pbrt: line 2", "missing.ply: file not found"),
        ("missing-texture.pbrt", "missing-texture.pbrt: line 2", "texture file not found"),
        ("bad-indices.pbrt", "bad-indices.pbrt: line 3", "out of range"),
        ("inline-indices.pbrt", "inline-indices.pbrt: line 2", "out of range"),
        ("circular-a.pbrt", "circular-b.pbrt: line 2", "circular Include"),
        ("truncated.xml", "truncated.xml: line 2", "never closed"),
        ("unknown-element.xml", "unknown-element.xml: line 3", "unknown element <teapot>"),
        ("wrong-value.xml", "wrong-value.xml: line 3", "not a list of finite numbers"),
        ("missing-obj.xml", "missing-obj.xml: line 2", "missing.obj: file not found"),
        ("circular.xml", "circular.xml: line 2", "circular include"),
        ("missing-ref.xml", "missing-ref.xml: line 3", "no <bsdf id=\"nothing\">"),
    ];
    let mut failures = vec![];
    for (file, at, what) in cases {
        let (code, err) = render(&bad_dir().join(file), &["--spp", "1", "--width", "8", "--height", "8"]);
        let ok = code == Some(2) && err.contains(at) && err.contains(what) && !err.contains("panicked");
        if !ok {
            failures.push(format!("{file}: exit {code:?}, wanted '{at}' and '{what}' in:\n{err}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn every_bitterli_scene_loads() {
    // (scene file, minimum triangles, film size)
    let scenes: &[(&str, usize, [u32; 2])] = &[
        ("living-room/pbrt-v4/scene-v4.pbrt", 100_000, [1280, 720]),
        ("dining-room/pbrt-v4/scene-v4.pbrt", 10_000, [960, 540]),
        ("staircase2/pbrt-v4/scene-v4.pbrt", 10_000, [1024, 1024]),
        ("veach-ajar/pbrt-v4/scene-v4.pbrt", 10_000, [1280, 720]),
        ("material-testball/pbrt-v4/scene-v4.pbrt", 1_000, [1280, 720]),
        ("cornell-box/pbrt-v4/scene-v4.pbrt", 30, [1024, 1024]),
        ("cornell-box/mitsuba3/scene_v3.xml", 30, [1024, 1024]),
        ("veach-mis/pbrt-v4/scene-v4.pbrt", 40, [1280, 720]),
        ("veach-mis/mitsuba3/scene.xml", 40, [1280, 720]),
    ];
    for (rel, min_tris, film) in scenes {
        let path = bitterli(rel);
        let s =
            mislab::scene::load(path.to_str().unwrap(), &Default::default()).unwrap_or_else(|e| panic!("{rel}: {e}"));
        assert!(s.triangle_count() >= *min_tris, "{rel}: {} triangles", s.triangle_count());
        assert!(s.has_lights(), "{rel}: no lights");
        assert_eq!(s.film_size, Some(*film), "{rel}");
        assert!(s.camera.position.is_finite() && (s.camera.forward.length() - 1.0).abs() < 1e-4, "{rel}");
        assert!(s.camera.vfov > 0.05 && s.camera.vfov < 3.0, "{rel}: vfov {}", s.camera.vfov);
        assert!(s.import_report.iter().any(|l| l.starts_with("imported from")), "{rel}");
        for m in &s.meshes {
            assert_eq!(m.normals.len(), m.positions.len(), "{rel}: {}", m.name);
            let n = m.positions.len() as u32;
            assert!(m.indices.iter().flatten().all(|&i| i < n), "{rel}: {}", m.name);
        }
    }
    // Both formats of the Cornell box give the same camera and the same geometry.
    let a = mislab::scene::load(bitterli("cornell-box/pbrt-v4/scene-v4.pbrt").to_str().unwrap(), &Default::default())
        .unwrap();
    let b = mislab::scene::load(bitterli("cornell-box/mitsuba3/scene_v3.xml").to_str().unwrap(), &Default::default())
        .unwrap();
    assert!((a.camera.position - b.camera.position).length() < 1e-3, "{:?} vs {:?}", a.camera, b.camera);
    assert!((a.camera.forward - b.camera.forward).length() < 1e-3);
    assert!((a.camera.vfov - b.camera.vfov).abs() < 1e-4);
    assert_eq!(a.triangle_count(), b.triangle_count());
}

#[test]
fn imported_render_has_no_nan() {
    let (code, err) =
        render(&bitterli("veach-mis/pbrt-v4/scene-v4.pbrt"), &["--spp", "4", "--width", "32", "--height", "18"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(err.contains(" 0 NaN/Inf samples"), "{err}");
}

/// Mitsuba's veach-mis plates are `roughconductor`s with the default (Beckmann) distribution and
/// `specular_reflectance` 0.3: both reach the conductor (its GGX twin, pbrt's, stays GGX and untinted).
#[test]
fn mitsuba_rough_conductors_keep_beckmann_and_tint() {
    use mislab::scene::{load, LoadOptions, MaterialKind};
    let conductors = |rel: &str| -> Vec<(glam::Vec3, bool)> {
        let s = load(bitterli(rel).to_str().unwrap(), &LoadOptions::default()).unwrap();
        s.materials
            .iter()
            .filter_map(|m| match m.kind {
                MaterialKind::Conductor { tint, beckmann, .. } => Some((tint, beckmann)),
                _ => None,
            })
            .collect()
    };
    let xml = conductors("veach-mis/mitsuba3/scene.xml");
    assert_eq!(xml.len(), 4, "{xml:?}");
    assert!(xml.iter().all(|(t, b)| *b && (*t - glam::Vec3::splat(0.3)).abs().max_element() < 1e-6), "{xml:?}");
    let pbrt = conductors("veach-mis/pbrt-v4/scene-v4.pbrt");
    assert!(!pbrt.is_empty() && pbrt.iter().all(|(t, b)| !*b && *t == glam::Vec3::ONE), "{pbrt:?}");
}

/// Mitsuba 3 gives a shape without a BSDF diffuse 0.5, but an emitting one a black diffuse (a lamp reflects
/// nothing): with 0.5 on a disk lamp over a floor the floor was relit, +0.9 % against Mitsuba 3 itself.
#[test]
fn mitsuba_emitters_without_a_bsdf_reflect_nothing() {
    use mislab::scene::{load, LoadOptions};
    let dir = std::env::temp_dir().join(format!("mislab-xml-emitter-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("lamp.xml");
    std::fs::write(
        &file,
        r#"<scene version="3.0.0">
    <shape type="rectangle"/>
    <shape type="disk">
        <transform name="to_world"><rotate x="1" angle="90"/><translate y="3"/></transform>
        <emitter type="area"><rgb name="radiance" value="10"/></emitter>
    </shape>
</scene>"#,
    )
    .unwrap();
    let s = load(file.to_str().unwrap(), &LoadOptions::default()).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let lamp: Vec<_> = s.materials.iter().filter(|m| m.emission != glam::Vec3::ZERO).collect();
    let plain: Vec<_> = s.materials.iter().filter(|m| m.emission == glam::Vec3::ZERO).collect();
    assert_eq!((lamp.len(), plain.len()), (1, 1), "{:?}", s.materials.iter().map(|m| &m.name).collect::<Vec<_>>());
    assert_eq!(lamp[0].base_color, glam::Vec3::ZERO, "{}", lamp[0].name);
    assert_eq!(plain[0].base_color, glam::Vec3::splat(0.5), "{}", plain[0].name);
}

/// Mitsuba 3's envmap lat-long (u = atan2(x, −z)/2π, v = acos(y)/π in the emitter's frame, then its to_world) is
/// mislab's turned half a turn: one bright texel must land where Mitsuba's formula puts it, rotation included.
#[test]
fn mitsuba_envmap_orientation_follows_mitsuba() {
    use mislab::scene::{envmap::equirect_direction, load, Environment, LoadOptions};
    let dir = std::env::temp_dir().join(format!("mislab-xml-envmap-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (w, h, bx, by) = (64u32, 32u32, 10u32, 9u32);
    let img = image::RgbImage::from_fn(w, h, |x, y| image::Rgb(if (x, y) == (bx, by) { [255; 3] } else { [0; 3] }));
    img.save(dir.join("dot.png")).unwrap();
    let file = dir.join("env.xml");
    std::fs::write(
        &file,
        r#"<scene version="3.0.0">
    <emitter type="envmap">
        <string name="filename" value="dot.png"/>
        <transform name="to_world"><rotate y="1" angle="90"/></transform>
    </emitter>
</scene>"#,
    )
    .unwrap();
    let s = load(file.to_str().unwrap(), &LoadOptions::default()).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let Environment::Map { map, .. } = &s.environment else { panic!("no environment map") };
    let brightest = (0..map.texels.len()).max_by(|&a, &b| map.texels[a][0].total_cmp(&map.texels[b][0])).unwrap();
    let (x, y) = (brightest as u32 % map.width, brightest as u32 / map.width);
    let found = equirect_direction((x as f32 + 0.5) / map.width as f32, (y as f32 + 0.5) / map.height as f32);
    // Mitsuba's direction of the dot's centre, in the emitter's frame and then in the world.
    let (phi, theta) = (
        2.0 * std::f32::consts::PI * (bx as f32 + 0.5) / w as f32,
        std::f32::consts::PI * (by as f32 + 0.5) / h as f32,
    );
    let local = glam::Vec3::new(phi.sin() * theta.sin(), theta.cos(), -phi.cos() * theta.sin());
    let expected = glam::Mat3::from_rotation_y(std::f32::consts::FRAC_PI_2) * local;
    let degrees = found.dot(expected).clamp(-1.0, 1.0).acos().to_degrees();
    assert!(degrees < 6.0, "the dot is {degrees:.1}° from Mitsuba's direction ({found} vs {expected})");
}
