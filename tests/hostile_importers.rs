//! Hostile and careless pbrt-v4 / Mitsuba 3 / PLY / texture inputs (issue 47): each must end in a clear error
//! that names the file (and the line, for scene text) — or load — with no crash, no unbounded allocation, no file
//! outside the scene's folder read, and no content of a file that is not a scene file echoed.
//!
//! Most cases call `mislab::scene::load` (an import never needs the device); `cli_*` tests run the binary for the
//! exit code. Every case writes its files into a fresh folder of its own under the system's temp directory.

mod scratch;
use mislab::scene::{load, LoadOptions, Scene};
use scratch::Scratch;
use std::path::Path;
use std::process::Command;

/// A fresh folder for one case.
fn case_dir(name: &str) -> Scratch {
    Scratch::new("hostile", name)
}

/// Writes `files` (name, content) into a fresh folder and loads the first one.
fn load_files(case: &str, files: &[(&str, &[u8])], allow_outside: bool) -> (Scratch, Result<Scene, String>) {
    let dir = case_dir(case);
    for (name, content) in files {
        let p = dir.join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, content).unwrap();
    }
    let main = dir.join(files[0].0);
    let options = LoadOptions { allow_outside_paths: allow_outside, ..Default::default() };
    let r = load(main.to_str().unwrap(), &options).map_err(|e| e.to_string());
    (dir, r)
}

/// Loads a one-file scene and returns its error, which must contain every one of `wanted`.
fn error_of(case: &str, file: &str, text: &str, wanted: &[&str]) -> String {
    let (dir, r) = load_files(case, &[(file, text.as_bytes())], false);
    let e = match r {
        Ok(_) => panic!("{case}: loaded, wanted an error with {wanted:?}"),
        Err(e) => e,
    };
    for w in wanted {
        assert!(e.contains(w), "{case}: wanted '{w}' in: {e}");
    }
    assert!(e.contains(&dir.join(file).display().to_string()), "{case}: the error names no file: {e}");
    e
}

/// An 18-byte TGA header: image type `kind`, `w`×`h`, 32 bits per pixel.
fn tga_header(kind: u8, w: u16, h: u16) -> Vec<u8> {
    let mut f = vec![0u8; 18];
    f[2] = kind;
    f[12..14].copy_from_slice(&w.to_le_bytes());
    f[14..16].copy_from_slice(&h.to_le_bytes());
    f[16] = 32;
    f
}

const CAMERA: &str = "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [ 40 ]\n";
const LIGHT: &str = "LightSource \"point\" \"rgb I\" [ 1 1 1 ]\n";
const TRIANGLE: &str = "Shape \"trianglemesh\" \"point3 P\" [ 0 0 0 1 0 0 0 1 0 ] \"integer indices\" [ 0 1 2 ]\n";

/// A pbrt scene: camera, WorldBegin, a light, then `world`.
fn pbrt(world: &str) -> String {
    format!("{CAMERA}WorldBegin\n{LIGHT}{world}")
}

#[test]
fn a_tga_declaring_65535_squared_is_refused_before_allocating() {
    for (case, kind) in [("tga-raw", 2u8), ("tga-rle", 10)] {
        let mut tga = tga_header(kind, 65535, 65535);
        tga.extend([0x81, 1, 2, 3, 4]);
        let scene = pbrt(&format!(
            "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"huge.tga\"\n\
             Material \"diffuse\" \"texture reflectance\" \"t\"\n{TRIANGLE}"
        ));
        let (dir, r) = load_files(case, &[("scene.pbrt", scene.as_bytes()), ("huge.tga", &tga)], false);
        let e = r.expect_err(case);
        let tex = dir.join("huge.tga").display().to_string();
        let by = format!("referenced by {}: line 5", dir.join("scene.pbrt").display());
        assert!(e.contains(&tex) && e.contains("65535×65535 is too large") && e.contains(&by), "{case}: {e}");
    }
}

#[test]
fn texture_errors_name_the_file_and_where_it_is_referenced() {
    let wide = include_bytes!("data/bad/aux/wide-16385x1.png");
    let scene = pbrt(&format!(
        "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"tex.png\"\n\
         Material \"diffuse\" \"texture reflectance\" \"t\"\n{TRIANGLE}"
    ));
    let (dir, r) = load_files("texture-by", &[("scene.pbrt", scene.as_bytes()), ("tex.png", wide)], false);
    let e = r.unwrap_err();
    let want = format!(
        "{}: PNG image 16385×1 is too large (at most 16384 texels on a side) (referenced by {}: line 5)",
        dir.join("tex.png").display(),
        dir.join("scene.pbrt").display()
    );
    assert!(e.contains(&want), "{e}");
    // Mitsuba: the same, with the <texture>'s line.
    let xml = "<scene version=\"3.0.0\">\n<shape type=\"rectangle\">\n<bsdf type=\"diffuse\">\n\
               <texture type=\"bitmap\" name=\"reflectance\">\n<string name=\"filename\" value=\"tex.png\"/>\n\
               </texture>\n</bsdf>\n</shape>\n<emitter type=\"constant\"/>\n</scene>\n";
    let (dir, r) = load_files("texture-by-xml", &[("scene.xml", xml.as_bytes()), ("tex.png", wide)], false);
    let e = r.unwrap_err();
    let by = format!("(referenced by {}: line 4)", dir.join("scene.xml").display());
    assert!(e.contains("16385×1 is too large") && e.contains(&by), "{e}");
}

#[test]
fn errors_in_included_files_say_where_they_were_included() {
    let main = pbrt("Include \"part.pbrt\"\n");
    let part = "# a part\nShape \"sphere\" \"string radius\" [ 1 ]\n";
    let (dir, r) = load_files("include-by", &[("scene.pbrt", main.as_bytes()), ("part.pbrt", part.as_bytes())], false);
    let e = r.unwrap_err();
    let want = format!("{}: line 2", dir.join("part.pbrt").display());
    let by = format!("(included by {}: line 5)", dir.join("scene.pbrt").display());
    assert!(e.contains(&want) && e.contains(&by), "{e}");
}

#[test]
fn a_gzip_bomb_ply_is_an_error_not_unbounded_memory() {
    use std::io::Write;
    // 2.25 GiB of zeros after a PLY header, a few MB compressed: past the 2 GiB limit on inflated bytes.
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n").unwrap();
    let zeros = vec![0u8; 1 << 20];
    for _ in 0..2304 {
        gz.write_all(&zeros).unwrap();
    }
    let bomb = gz.finish().unwrap();
    let scene = pbrt("Shape \"plymesh\" \"string filename\" \"bomb.ply.gz\"\n");
    let (dir, r) = load_files("gz-bomb", &[("scene.pbrt", scene.as_bytes()), ("bomb.ply.gz", &bomb)], false);
    let e = r.unwrap_err();
    assert!(e.contains(&dir.join("bomb.ply.gz").display().to_string()), "{e}");
    assert!(e.contains("inflates to more than 2048.0 MiB") && e.contains("referenced by"), "{e}");
}

#[test]
fn numbers_out_of_f32_range_are_caught_at_import_with_their_line() {
    let e = error_of(
        "pbrt-1e39",
        "scene.pbrt",
        &pbrt("Shape \"trianglemesh\"\n \"point3 P\" [ 1e39 0 0 1 0 0 0 1 0 ] \"integer indices\" [ 0 1 2 ]\n"),
        &["line 6", "'1e39' is out of the range of 32-bit floats"],
    );
    assert!(!e.contains("shader"), "{e}");
    // A product that overflows: finite numbers, an infinite vertex once transformed.
    error_of(
        "pbrt-overflow",
        "scene.pbrt",
        &pbrt("Scale 3e38 3e38 3e38\nShape \"trianglemesh\" \"point3 P\" [ 0 0 0 10 0 0 0 10 0 ] \"integer indices\" [ 0 1 2 ]\n"),
        &["line 6", "out of the range of 32-bit floats once transformed"],
    );
    error_of(
        "pbrt-light-overflow",
        "scene.pbrt",
        &pbrt("LightSource \"point\" \"rgb I\" [ 3e38 1 1 ] \"float scale\" [ 10 ]\n"),
        &["line 5", "out of the range of 32-bit floats"],
    );
    error_of(
        "xml-1e39",
        "scene.xml",
        "<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n<point name=\"center\" x=\"1e39\" y=\"0\" z=\"0\"/>\n\
         </shape>\n</scene>\n",
        &["line 3", "finite numbers"],
    );
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
               element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 1e39 0\n0 1 0\n3 0 1 2\n";
    let scene = pbrt("Shape \"plymesh\" \"string filename\" \"m.ply\"\n");
    let (dir, r) = load_files("ply-1e39", &[("scene.pbrt", scene.as_bytes()), ("m.ply", ply.as_bytes())], false);
    let e = r.unwrap_err();
    assert!(e.contains(&dir.join("m.ply").display().to_string()) && e.contains("vertex 1"), "{e}");
}

#[test]
fn pbrt_v4_rule_violations_are_errors_with_file_and_line() {
    let cases: &[(&str, String, &[&str])] = &[
        (
            "area-negative",
            pbrt(&format!("AreaLightSource \"diffuse\" \"rgb L\" [ -1 1 1 ]\n{TRIANGLE}")),
            &["line 5", "negative RGB component -1"],
        ),
        (
            "area-negative-scale",
            pbrt(&format!("AreaLightSource \"diffuse\" \"rgb L\" [ 1 1 1 ] \"float scale\" -2\n{TRIANGLE}")),
            &["line 5", "\"scale\" must be a finite number ≥ 0"],
        ),
        ("infinite-negative", pbrt("LightSource \"infinite\" \"rgb L\" [ 1 -0.5 1 ]\n"), &["line 5", "negative RGB"]),
        ("infinite-negative-scale", pbrt("LightSource \"infinite\" \"float scale\" [ -1 ]\n"), &["line 5", "scale"]),
        (
            "transform-zero",
            pbrt(&format!("Transform [ 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 ]\n{TRIANGLE}")),
            &["line 6", "singular"],
        ),
        (
            "camera-scale-zero",
            format!("Scale 0 0 0\n{CAMERA}WorldBegin\n{LIGHT}{TRIANGLE}"),
            &["line 3", "camera's transform is singular"],
        ),
        (
            "camera-after-world",
            pbrt(&format!("{TRIANGLE}Camera \"perspective\"\n")),
            &["line 6", "Camera after WorldBegin"],
        ),
        ("film-after-world", pbrt("Film \"rgb\"\n"), &["line 5", "Film after WorldBegin"]),
        ("sampler-after-world", pbrt("Sampler \"halton\"\n"), &["line 5", "Sampler after WorldBegin"]),
        ("second-world", pbrt("WorldBegin\n"), &["line 5", "a second WorldBegin"]),
        (
            "shape-before-world",
            format!("{CAMERA}{TRIANGLE}WorldBegin\n{LIGHT}"),
            &["line 3", "Shape before WorldBegin"],
        ),
        (
            "object-before-world",
            format!("{CAMERA}ObjectBegin \"o\"\nObjectEnd\nWorldBegin\n{LIGHT}"),
            &["line 3", "ObjectBegin before WorldBegin"],
        ),
        ("no-world", format!("{CAMERA}"), &["the file ends before WorldBegin"]),
        (
            "instance-in-object",
            pbrt(&format!(
                "ObjectBegin \"a\"\n{TRIANGLE}ObjectEnd\nObjectBegin \"b\"\nObjectInstance \"a\"\nObjectEnd\n"
            )),
            &["line 9", "ObjectInstance inside an object definition"],
        ),
        (
            "unknown-camera",
            format!("Camera \"fisheye\"\nWorldBegin\n{LIGHT}"),
            &["line 1", "unknown camera type \"fisheye\""],
        ),
        ("unknown-film", format!("Film \"png\"\nWorldBegin\n{LIGHT}"), &["line 1", "unknown film type \"png\""]),
        (
            "unknown-spectrum",
            pbrt(&format!("Material \"conductor\" \"spectrum eta\" \"metal-Unobtainium-eta\"\n{TRIANGLE}")),
            &["line 5", "unknown named spectrum \"metal-Unobtainium-eta\""],
        ),
        (
            "unknown-light-spectrum",
            pbrt("LightSource \"infinite\" \"spectrum L\" \"stdillum-D99\"\n"),
            &["line 5", "unknown named spectrum"],
        ),
    ];
    for (case, text, wanted) in cases {
        error_of(case, "scene.pbrt", text, wanted);
    }
}

#[test]
fn what_pbrt_v4_accepts_still_loads() {
    // Named spectra, a named illuminant, orthographic (approximated, with the line), Transform, ObjectInstance.
    let text = format!(
        "Film \"rgb\" \"integer xresolution\" [ 64 ] \"integer yresolution\" [ 32 ]\nSampler \"halton\"\n{CAMERA}\
         WorldBegin\nLightSource \"infinite\" \"spectrum L\" \"stdillum-D65\" \"float scale\" [ 0.5 ]\n\
         Material \"conductor\" \"spectrum eta\" \"metal-Au-eta\" \"spectrum k\" \"metal-Au-k\"\n\
         ObjectBegin \"o\"\n{TRIANGLE}ObjectEnd\nAttributeBegin\nTranslate 1 0 0\nObjectInstance \"o\"\nAttributeEnd\n\
         Shape \"curve\" \"point3 P\" [ 0 0 0 1 1 1 2 2 2 3 3 3 ]\n"
    );
    let (dir, r) = load_files("accepted", &[("scene.pbrt", text.as_bytes())], false);
    let s = r.unwrap();
    assert_eq!(s.triangle_count(), 1);
    // The unknown shape's warning (and `mislab info`'s report) names its line.
    let at = format!("Shape \"curve\" (at {}: line 15)", dir.join("scene.pbrt").display());
    assert!(s.warnings.iter().any(|w| w.contains(&at)), "{:?}", s.warnings);
    assert!(s.import_report.iter().any(|w| w.contains(&at)), "{:?}", s.import_report);
}

#[test]
fn mitsuba_rule_violations_are_errors_with_file_and_line() {
    error_of(
        "xml-negative-radiance",
        "scene.xml",
        "<scene version=\"3.0.0\">\n<shape type=\"sphere\">\n<emitter type=\"area\">\n\
         <rgb name=\"radiance\" value=\"1, -2, 1\"/>\n</emitter>\n</shape>\n</scene>\n",
        &["line 4", "negative"],
    );
    error_of(
        "xml-negative-constant",
        "scene.xml",
        "<scene version=\"3.0.0\">\n<emitter type=\"constant\">\n<rgb name=\"radiance\" value=\"-1\"/>\n</emitter>\n</scene>\n",
        &["line 3", "negative"],
    );
    error_of(
        "xml-singular-sensor",
        "scene.xml",
        "<scene version=\"3.0.0\">\n<sensor type=\"perspective\">\n<transform name=\"to_world\">\n\
         <matrix value=\"0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 1\"/>\n</transform>\n</sensor>\n\
         <emitter type=\"constant\"/>\n</scene>\n",
        &["line 2", "singular"],
    );
}

/// The start of /etc/passwd's first line on every Unix ("root:x:0:0" or "root:*:0:0"), which no error may echo.
fn passwd_content() -> Vec<String> {
    let text = std::fs::read_to_string("/etc/passwd").unwrap_or_default();
    text.lines().filter(|l| l.len() > 8).map(|l| l[..8].to_string()).take(20).collect()
}

fn echoes_passwd(e: &str) -> bool {
    passwd_content().iter().any(|l| e.contains(l.as_str()))
}

#[test]
fn pbrt_file_names_outside_the_scene_folder_are_refused() {
    let outside = "(scene files may name only files under their own folder; allow it with --allow-outside-paths)";
    for (case, name, why) in [
        ("include-abs", "/etc/passwd", "is an absolute path"),
        ("include-up", "../../../../../../../../etc/passwd", "leads outside the scene's folder"),
    ] {
        for directive in ["Include", "Import"] {
            let e = error_of(
                &format!("{case}-{directive}"),
                "scene.pbrt",
                &pbrt(&format!("{directive} \"{name}\"\n")),
                &["line 5", why, outside],
            );
            assert!(!echoes_passwd(&e), "{e}");
        }
    }
    let tex = format!("Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"/etc/passwd\"\n{TRIANGLE}");
    error_of("texture-abs", "scene.pbrt", &pbrt(&tex), &["line 5", "is an absolute path"]);
    error_of(
        "ply-up",
        "scene.pbrt",
        &pbrt("Shape \"plymesh\" \"string filename\" \"../x/../../mesh.ply\"\n"),
        &["line 5", "leads outside the scene's folder"],
    );
    error_of(
        "map-abs",
        "scene.pbrt",
        &pbrt("LightSource \"infinite\" \"string filename\" \"/etc/passwd.exr\"\n"),
        &["line 5", "is an absolute path"],
    );
    // A symbolic link inside the folder that points out of it.
    let dir = case_dir("symlink");
    std::os::unix::fs::symlink("/etc", dir.join("etc")).unwrap();
    std::fs::write(dir.join("scene.pbrt"), pbrt("Include \"etc/passwd\"\n")).unwrap();
    let e = load(dir.join("scene.pbrt").to_str().unwrap(), &LoadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("line 5") && e.contains("through a symbolic link") && !echoes_passwd(&e), "{e}");
    // Allowed, /etc/passwd is read, and still never echoed: it is no pbrt text.
    let allowed = LoadOptions { allow_outside_paths: true, ..Default::default() };
    let e = load(dir.join("scene.pbrt").to_str().unwrap(), &allowed).unwrap_err().to_string();
    assert!(e.contains("/etc/passwd") && e.contains("included by") && !echoes_passwd(&e), "{e}");
}

#[test]
fn mitsuba_file_names_outside_the_scene_folder_are_refused() {
    for ty in ["obj", "ply"] {
        let xml = format!(
            "<scene version=\"3.0.0\">\n<shape type=\"{ty}\">\n<string name=\"filename\" value=\"/etc/passwd\"/>\n\
             </shape>\n<emitter type=\"constant\"/>\n</scene>\n"
        );
        let e = error_of(&format!("xml-{ty}-abs"), "scene.xml", &xml, &["line 2", "is an absolute path"]);
        assert!(!echoes_passwd(&e), "{e}");
    }
    let xml = "<scene version=\"3.0.0\">\n<include filename=\"../../../../../../etc/passwd\"/>\n</scene>\n";
    let e = error_of("xml-include-up", "scene.xml", xml, &["line 2", "leads outside the scene's folder"]);
    assert!(!echoes_passwd(&e), "{e}");
    let xml =
        "<scene version=\"3.0.0\">\n<emitter type=\"envmap\">\n<string name=\"filename\" value=\"/etc/passwd\"/>\n\
               </emitter>\n</scene>\n";
    error_of("xml-envmap-abs", "scene.xml", xml, &["line 3", "is an absolute path"]);
}

#[test]
fn content_of_a_file_that_is_not_pbrt_is_never_echoed() {
    // A file in the scene's folder that is not pbrt text, included: its words are not repeated in the error.
    let secret = "_apt:x:42:65534::/nonexistent:/usr/sbin/nologin\nroot:x:0:0:root:/root:/bin/bash\n";
    let main = pbrt("Include \"notes.txt\"\n");
    let (_, r) = load_files("no-echo", &[("scene.pbrt", main.as_bytes()), ("notes.txt", secret.as_bytes())], false);
    let e = r.unwrap_err();
    assert!(e.contains("notes.txt: line 1") && !e.contains("_apt") && !e.contains("nologin"), "{e}");
    // Named as an OBJ mesh by a Mitsuba scene: no faces, so an error (not an empty shape), and nothing echoed.
    let xml = "<scene version=\"3.0.0\">\n<shape type=\"obj\">\n<string name=\"filename\" value=\"notes.obj\"/>\n\
               </shape>\n<emitter type=\"constant\"/>\n</scene>\n";
    let (dir, r) = load_files("no-echo-obj", &[("scene.xml", xml.as_bytes()), ("notes.obj", secret.as_bytes())], false);
    let e = r.unwrap_err();
    let by = format!("(referenced by {}: line 2)", dir.join("scene.xml").display());
    assert!(e.contains("notes.obj: no faces") && e.contains(&by) && !e.contains("_apt"), "{e}");
}

/// Runs `mislab render FILE` and returns (exit code, stderr).
fn render(file: &Path, extra: &[&str]) -> (Option<i32>, String) {
    let out = file.with_extension("out.png");
    let o = Command::new(env!("CARGO_BIN_EXE_mislab"))
        .arg("render")
        .arg(file)
        .args(["-o", out.to_str().unwrap(), "--spp", "1", "--width", "8", "--height", "8"])
        .args(extra)
        .output()
        .expect("run mislab");
    assert!(!out.exists(), "{}: an image was written", file.display());
    (o.status.code(), String::from_utf8_lossy(&o.stderr).into_owned())
}

#[test]
fn cli_hostile_scenes_exit_2_with_one_clear_error() {
    let dir = case_dir("cli");
    let mut tga = tga_header(10, 65535, 65535);
    tga.extend([0x81, 1, 2, 3, 4]);
    std::fs::write(dir.join("huge.tga"), tga).unwrap();
    let cases = [
        (
            "tga.pbrt",
            pbrt(&format!(
                "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"huge.tga\"\n\
                       Material \"diffuse\" \"texture reflectance\" \"t\"\n{TRIANGLE}"
            )),
            "too large",
        ),
        ("inf.pbrt", pbrt(&format!("Translate 1e39 0 0\n{TRIANGLE}")), "out of the range of 32-bit floats"),
        ("passwd.pbrt", pbrt("Include \"/etc/passwd\"\n"), "is an absolute path"),
        (
            "obj.xml",
            "<scene version=\"3.0.0\">\n<shape type=\"obj\">\n<string name=\"filename\" value=\"/etc/passwd\"/>\n\
         </shape>\n<emitter type=\"constant\"/>\n</scene>\n"
                .to_string(),
            "is an absolute path",
        ),
    ];
    for (name, text, want) in cases {
        let file = dir.join(name);
        std::fs::write(&file, text).unwrap();
        let (code, err) = render(&file, &[]);
        assert_eq!(code, Some(2), "{name}: {err}");
        assert!(err.contains(&file.display().to_string()) && err.contains(want), "{name}: {err}");
        assert!(!err.contains("panicked") && !echoes_passwd(&err), "{name}: {err}");
    }
    // --allow-outside-paths lets the pbrt Include read /etc/passwd, which is then an error that does not echo it.
    let (code, err) = render(&dir.join("passwd.pbrt"), &["--allow-outside-paths"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("/etc/passwd") && !echoes_passwd(&err), "{err}");
}
