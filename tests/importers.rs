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
        ("truncated.xml", "truncated.xml: line 3", "never closed"),
        ("unknown-element.xml", "unknown-element.xml: line 3", "unknown element <teapot>"),
        ("wrong-value.xml", "wrong-value.xml: line 3", "not a list of finite numbers"),
        ("missing-obj.xml", "missing-obj.xml: line 2", "missing.obj: file not found"),
        ("circular.xml", "circular.xml: line 2", "circular include"),
        ("missing-ref.xml", "missing-ref.xml: line 3", "no <bsdf> or area <emitter> with id=\"nothing\""),
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

/// Mitsuba 3 resolves `<ref id>` across the whole scene and lets a shape take a named area emitter by reference:
/// mitsuba-data's `cbox-rgb.xml` includes shapes that refer to an `<emitter type="area" id="area-emitter">` its main
/// file declares after the include. It loads as `cbox.xml` does (same meshes), with that radiance on the luminaire.
#[test]
fn mitsuba_references_reach_forward_and_take_named_area_emitters() {
    use mislab::scene::{load, LoadOptions};
    let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/testdata/scenes/mitsuba-data/cbox"));
    let rgb =
        load(dir.join("cbox-rgb.xml").to_str().unwrap(), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let plain = load(dir.join("cbox.xml").to_str().unwrap(), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(rgb.meshes.len(), plain.meshes.len());
    assert_eq!(rgb.triangle_count(), plain.triangle_count());
    let lamps: Vec<_> = rgb.materials.iter().filter(|m| m.emission != glam::Vec3::ZERO).collect();
    assert_eq!(lamps.len(), 1, "{:?}", rgb.materials.iter().map(|m| &m.name).collect::<Vec<_>>());
    let want = glam::Vec3::new(18.387, 10.9873, 2.75357);
    assert!((lamps[0].emission - want).abs().max_element() < 1e-4, "{} vs {want}", lamps[0].emission);
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

/// pbrt-v4's `EqualAreaSquareToSphere` (Clarberg's octahedral mapping), written out again here in f64 so the
/// importer is checked against the formula, not against itself.
fn pbrt_equal_area_square_to_sphere(px: f64, py: f64) -> [f64; 3] {
    let (u, v) = (2.0 * px - 1.0, 2.0 * py - 1.0);
    let (up, vp) = (u.abs(), v.abs());
    let signed_distance = 1.0 - (up + vp);
    let r = 1.0 - signed_distance.abs();
    let phi = if r == 0.0 { 1.0 } else { (vp - up) / r + 1.0 } * std::f64::consts::FRAC_PI_4;
    let z = (1.0 - r * r).copysign(signed_distance);
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    [phi.cos().copysign(u) * s, phi.sin().copysign(v) * s, z]
}

/// The dining room's infinite light as its pbrt-v4 file writes it (a 7° rotation about z, then the basis change
/// that puts the map's +z up), with a 64×64 equal-area map dark but for one texel. pbrt-v4 shows that texel in
/// world direction `Rotate · ConcatTransform · EqualAreaSquareToSphere(texel centre)` (the PFM's rows flipped to
/// top-first, as pbrt's ReadPFM does). The imported map must put it there, and a render looking along that
/// direction must see it at the image centre (the device's env lookup); without the 7° rotation it lands 11 px off.
#[test]
fn pbrt_infinite_light_follows_pbrt_v4_equal_area_mapping() {
    let dir = std::env::temp_dir().join(format!("mislab-infinite-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (n, bx, by) = (64usize, 40usize, 20usize); // bright texel, x right, y down from the top row
    let mut pfm = format!("PF\n{n} {n}\n-1.0\n").into_bytes();
    for row in (0..n).rev() {
        for x in 0..n {
            let v: f32 = if (x, row) == (bx, by) { 1000.0 } else { 0.0 };
            for _ in 0..3 {
                pfm.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    std::fs::write(dir.join("sky.pfm"), pfm).unwrap();

    // The expected direction: pbrt's Rotate(-7°, z) · ConcatTransform (numbers are columns) · d.
    let d = pbrt_equal_area_square_to_sphere((bx as f64 + 0.5) / n as f64, (by as f64 + 0.5) / n as f64);
    let cols = [[-1.0, 0.0, 8.74228e-8], [-8.74228e-8, 0.0, -1.0], [0.0, 1.0, 0.0]];
    let m: Vec<f64> = (0..3).map(|i| (0..3).map(|j| cols[j][i] * d[j]).sum()).collect();
    let (s, c) = (-7f64).to_radians().sin_cos();
    let want = [c * m[0] - s * m[1], s * m[0] + c * m[1], m[2]];
    let light = "AttributeBegin\n    Rotate -7 0 0 1\n    ConcatTransform [ -1 0 8.74228e-8 0 -8.74228e-8 0 -1 0 0 1 0 0 0 0 0 1 ]\n    LightSource \"infinite\" \"string filename\" \"sky.pfm\"\nAttributeEnd\n";

    // 1. The imported map (CPU): the radiance-weighted mean direction of its texels.
    std::fs::write(dir.join("map.pbrt"), format!("WorldBegin\n{light}")).unwrap();
    let path = dir.join("map.pbrt");
    let scene = mislab::scene::load(path.to_str().unwrap(), &Default::default()).expect("load");
    let mislab::scene::Environment::Map { map, .. } = &scene.environment else { panic!("no environment map") };
    let mut sum = [0.0f64; 3];
    for y in 0..map.height {
        for x in 0..map.width {
            let (u, v) = ((x as f32 + 0.5) / map.width as f32, (y as f32 + 0.5) / map.height as f32);
            let w = map.texels[(y * map.width + x) as usize][0] as f64 * (std::f64::consts::PI * v as f64).sin();
            let dir = mislab::scene::envmap::equirect_direction(u, v);
            for k in 0..3 {
                sum[k] += w * dir[k] as f64;
            }
        }
    }
    let len = sum.iter().map(|a| a * a).sum::<f64>().sqrt();
    let cos = (0..3).map(|k| sum[k] / len * want[k]).sum::<f64>();
    let degrees = cos.clamp(-1.0, 1.0).acos().to_degrees();
    assert!(degrees < 0.5, "the bright texel lands {degrees:.2}° from pbrt-v4's direction {want:?}");

    // 2. The device: a narrow camera (16° over 33 px) looking along `want` sees the spot at its centre.
    let camera = format!(
        "LookAt 0 0 0  {} {} {}  0 1 0\nCamera \"perspective\" \"float fov\" [ 16 ]\nFilm \"rgb\" \"integer xresolution\" [ 33 ] \"integer yresolution\" [ 33 ]\n",
        want[0], want[1], want[2]
    );
    std::fs::write(dir.join("view.pbrt"), format!("{camera}WorldBegin\n{light}")).unwrap();
    let exr = dir.join("view.exr");
    let o = Command::new(env!("CARGO_BIN_EXE_mislab"))
        .arg("render")
        .arg(dir.join("view.pbrt"))
        .args(["--mode", "direct", "--spp", "16", "-o", exr.to_str().unwrap()])
        .output()
        .expect("run mislab");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let img = mislab::io::exr_image::read(&exr).expect("read the render");
    assert_eq!((img.width, img.height), (33, 33));
    let (mut total, mut cx, mut cy) = (0.0f64, 0.0f64, 0.0f64);
    for (i, p) in img.pixels.iter().enumerate() {
        let w = p[0] as f64;
        total += w;
        cx += w * (i % 33) as f64;
        cy += w * (i / 33) as f64;
    }
    assert!(total > 0.0, "the render saw nothing of the bright texel: {err}");
    let (cx, cy) = (cx / total, cy / total);
    assert!(
        (cx - 16.0).abs() < 1.0 && (cy - 16.0).abs() < 1.0,
        "the spot's centroid is at ({cx:.2}, {cy:.2}), not (16, 16)"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// pbrt-v4's `checkerboard` texture (tex1 where ⌊s⌋ + ⌊t⌋ is even, tex2 where odd, (s, t) = (uscale·u + udelta,
/// vscale·v + vdelta)) on a quad facing the camera, evaluated on the device: Lambert under a constant white sky,
/// direct mode with BSDF sampling, so each sample is exactly the reflectance at its point. Every pixel whose
/// footprint lies inside one check (its corners' (s, t), from the camera model on the CPU, share a cell) must be
/// that check's colour; pixels across an edge lie between the two colours.
#[test]
fn pbrt_checkerboard_matches_cpu() {
    let dir = std::env::temp_dir().join(format!("mislab-checkerboard-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (tex1, tex2) = ([0.8f32, 0.2, 0.1], [0.1f32, 0.3, 0.9]);
    let (us, vs, ud, vd) = (4.0f64, 3.0f64, 0.25f64, 0.5f64);
    let n = 48u32;
    // `Scale -1 1 1` makes the camera frame right-handed like mislab's, so world +x is the image's right.
    let file = format!(
        "Scale -1 1 1\nLookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [ 30 ]\n\
         Film \"rgb\" \"integer xresolution\" [ {n} ] \"integer yresolution\" [ {n} ]\nWorldBegin\n\
         LightSource \"infinite\" \"rgb L\" [ 1 1 1 ]\n\
         Texture \"checks\" \"spectrum\" \"checkerboard\" \"rgb tex1\" [ {} {} {} ] \"rgb tex2\" [ {} {} {} ]\n\
         \"float uscale\" [ {us} ] \"float vscale\" [ {vs} ] \"float udelta\" [ {ud} ] \"float vdelta\" [ {vd} ]\n\
         Material \"diffuse\" \"texture reflectance\" \"checks\"\n\
         Shape \"trianglemesh\" \"point3 P\" [ -1 -1 0  1 -1 0  1 1 0  -1 1 0 ] \"point2 uv\" [ 0 0 1 0 1 1 0 1 ]\n\
         \"integer indices\" [ 0 1 2 0 2 3 ]\n",
        tex1[0], tex1[1], tex1[2], tex2[0], tex2[1], tex2[2]
    );
    std::fs::write(dir.join("checks.pbrt"), file).unwrap();
    let exr = dir.join("checks.exr");
    let o = Command::new(env!("CARGO_BIN_EXE_mislab"))
        .arg("render")
        .arg(dir.join("checks.pbrt"))
        .args(["--mode", "direct", "--strategy", "bsdf", "--spp", "16", "-o", exr.to_str().unwrap()])
        .output()
        .expect("run mislab");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(!err.contains("Texture class"), "the checkerboard was not imported: {err}");
    let img = mislab::io::exr_image::read(&exr).expect("read the render");
    assert_eq!((img.width, img.height), (n, n));

    // The camera ray through film point (fx, fy) ∈ [0, n]² meets z = 0 at 5·(sx, sy); pbrt's uv there.
    let tan = 15f64.to_radians().tan();
    let st = |fx: f64, fy: f64| {
        let (x, y) = (5.0 * (2.0 * fx / n as f64 - 1.0) * tan, 5.0 * (1.0 - 2.0 * fy / n as f64) * tan);
        let (u, v) = ((x + 1.0) / 2.0, (y + 1.0) / 2.0);
        (us * u + ud, vs * v + vd, (0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v))
    };
    let (mut exact, mut seen) = (0usize, [0usize; 2]);
    for y in 0..n {
        for x in 0..n {
            let corners: Vec<(f64, f64, bool)> = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .iter()
                .map(|(a, b)| st(x as f64 + a, y as f64 + b))
                .collect();
            if !corners.iter().all(|c| c.2) {
                continue; // (partly) off the quad
            }
            let px = img.pixels[(y * n + x) as usize];
            let cell = |c: &(f64, f64, bool)| (c.0.floor() as i64, c.1.floor() as i64);
            if corners.iter().all(|c| cell(c) == cell(&corners[0])) {
                let (i, j) = cell(&corners[0]);
                let odd = (i + j).rem_euclid(2) == 1;
                let want = if odd { tex2 } else { tex1 };
                let (s0, t0) = (corners[0].0 as f32 + 1e-3, corners[0].1 as f32 + 1e-3);
                let twin = mislab::scene::checkerboard(tex1.into(), tex2.into(), s0, t0).to_array();
                assert_eq!(twin, want, "the CPU twin disagrees at ({s0}, {t0})");
                for c in 0..3 {
                    assert!((px[c] - want[c]).abs() < 1e-5, "pixel ({x}, {y}) = {px:?}, its check is {want:?}");
                }
                exact += 1;
                seen[odd as usize] += 1;
            } else {
                for c in 0..3 {
                    let (lo, hi) = (tex1[c].min(tex2[c]), tex1[c].max(tex2[c]));
                    assert!(px[c] >= lo - 1e-5 && px[c] <= hi + 1e-5, "edge pixel ({x}, {y}) = {px:?}");
                }
            }
        }
    }
    assert!(exact > 300 && seen[0] > 100 && seen[1] > 100, "{exact} pixels inside one check ({seen:?})");
    let _ = std::fs::remove_dir_all(&dir);
}

/// pbrt's camera space is left-handed (x = up × forward is the image's right): `LookAt 0 0 5  0 0 0  0 1 0` shows
/// world +x on the LEFT, and `Scale -1 1 1` before it (the usual fix, and what the Bitterli files' `Transform`s
/// contain) puts it on the right. mislab's camera is right-handed, so the importer mirrors the world under a
/// proper-rotation camera; a sphere at pbrt's x = +1 must land on the side pbrt shows it.
#[test]
fn pbrt_lookat_camera_keeps_pbrt_left_and_right() {
    let dir = std::env::temp_dir().join(format!("mislab-handedness-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (prefix, left) in [("", true), ("Scale -1 1 1\n", false)] {
        let text = format!(
            "{prefix}LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [ 40 ]\nWorldBegin\n\
             LightSource \"infinite\" \"rgb L\" [ 1 1 1 ]\n\
             AttributeBegin\n  Translate 1 0.5 0\n  Shape \"sphere\" \"float radius\" [ 0.3 ]\nAttributeEnd\n"
        );
        let path = dir.join("side.pbrt");
        std::fs::write(&path, text).unwrap();
        let s = mislab::scene::load(path.to_str().unwrap(), &Default::default()).expect("load");
        let (right, up, forward) = s.camera.frame();
        let to = s.spheres[0].center - s.camera.position;
        let (x, y) = (to.dot(right) / to.dot(forward), to.dot(up) / to.dot(forward));
        assert!((x.abs() - 0.2).abs() < 1e-5 && (y - 0.1).abs() < 1e-5, "{prefix:?}: the sphere at ({x}, {y})");
        assert_eq!(x < 0.0, left, "{prefix:?}: pbrt shows the sphere on the {}", if left { "left" } else { "right" });
    }
    let _ = std::fs::remove_dir_all(&dir);
}
