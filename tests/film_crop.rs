//! A film crop (pbrt-v4's `cropwindow` and `pixelbounds`, Mitsuba 3's `crop_*`) is that rectangle of the full
//! image: the file's crop is read as its renderer reads it, and on the GPU the cropped render matches the same
//! pixels of the uncropped one.

mod common;
mod scratch;

use mislab::render::settings::{Mode, Settings};
use mislab::scene::{self, Camera, LoadOptions, Scene};

const W: u32 = 64;
const H: u32 = 48;

/// A scene file written into a scratch folder of its own, removed with it.
struct Written(#[allow(dead_code)] scratch::Scratch, std::path::PathBuf);

impl std::ops::Deref for Written {
    type Target = std::path::Path;
    fn deref(&self) -> &std::path::Path {
        &self.1
    }
}

fn write(name: &str, text: &str) -> Written {
    let dir = scratch::unique("film-crop");
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    Written(dir, path)
}

fn load(path: &std::path::Path) -> Scene {
    scene::load(path.to_str().unwrap(), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

/// A pattern of emitting squares of radiance 1 on black, seen from the origin along +z, with `film`'s extra
/// parameters on the Film statement.
fn pbrt(name: &str, film: &str) -> Scene {
    let mut quads = String::new();
    for (k, (x, y)) in
        [(-0.3, -0.2), (0.05, -0.15), (0.2, 0.1), (-0.15, 0.12), (0.32, -0.25), (-0.05, 0.3)].into_iter().enumerate()
    {
        let s = 0.06 + 0.02 * k as f64;
        quads += &format!(
            "AttributeBegin\n AreaLightSource \"diffuse\" \"rgb L\" [ 1 1 1 ] \"bool twosided\" true\n \
             Shape \"bilinearmesh\" \"point3 P\" [ {} {} 1  {} {} 1  {} {} 1  {} {} 1 ]\nAttributeEnd\n",
            x,
            y,
            x + s,
            y,
            x,
            y + s,
            x + s,
            y + s
        );
    }
    let text = format!(
        "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\" \"float fov\" [ 50 ]\n\
         Film \"rgb\" \"integer xresolution\" [ {W} ] \"integer yresolution\" [ {H} ] {film}\n\
         WorldBegin\nMaterial \"diffuse\" \"rgb reflectance\" [ 0 0 0 ]\n{quads}"
    );
    load(&write(name, &text))
}

#[test]
fn pbrt_and_mitsuba_crops_are_read_as_their_renderers_read_them() {
    let full = pbrt("full.pbrt", "");
    assert_eq!((full.film_size, full.camera.window), (Some([W, H]), Camera::FULL_WINDOW));
    // pbrt-v4: ceil(resolution · crop), either order, clamped to [0, 1].
    let window = pbrt("window.pbrt", r#""float cropwindow" [ 0.75 0.25 0.5 1.2 ]"#);
    assert_eq!(window.film_size, Some([32, 24]));
    assert_eq!(window.camera.window, [0.25, 0.75, 0.5, 1.0]);
    let bounds = pbrt("bounds.pbrt", r#""integer pixelbounds" [ 16 48 24 48 ]"#);
    assert_eq!((bounds.film_size, bounds.camera.window), (window.film_size, window.camera.window));
    // The crop window wins over pixel bounds, with a warning; an empty crop is an error that names the file.
    let both = pbrt("both.pbrt", r#""integer pixelbounds" [ 0 8 0 8 ] "float cropwindow" [ 0.25 0.75 0.5 1 ]"#);
    assert_eq!(both.camera.window, window.camera.window);
    assert!(both.warnings.iter().any(|w| w.contains("cropwindow")), "{:?}", both.warnings);
    let empty = write(
        "empty.pbrt",
        &format!(
            "Camera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" [ {W} ] \"integer yresolution\" [ {H} ] \
         \"float cropwindow\" [ 0.5 0.5 0 1 ]\nWorldBegin\n"
        ),
    );
    let e = scene::load(empty.to_str().unwrap(), &LoadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("empty.pbrt") && e.contains("leaves no pixel"), "{e}");

    // Mitsuba 3: crop_offset_x/y and crop_width/height in pixels.
    let xml = |crop: &str| {
        format!(
            r#"<scene version="3.0.0">
  <sensor type="perspective">
    <float name="fov" value="45"/>
    <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{W}"/><integer name="height" value="{H}"/>{crop}</film>
  </sensor>
  <shape type="sphere"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
</scene>"#
        )
    };
    let m = load(&write(
        "crop.xml",
        &xml(
            r#"<integer name="crop_offset_x" value="16"/><integer name="crop_offset_y" value="24"/><integer name="crop_width" value="32"/><integer name="crop_height" value="24"/>"#,
        ),
    ));
    assert_eq!((m.film_size, m.camera.window), (Some([32, 24]), [0.25, 0.75, 0.5, 1.0]));
    let bad = write(
        "bad-crop.xml",
        &xml(r#"<integer name="crop_offset_x" value="40"/><integer name="crop_width" value="32"/>"#),
    );
    let e = scene::load(bad.to_str().unwrap(), &LoadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("bad-crop.xml") && e.contains("does not fit"), "{e}");
}

#[test]
fn a_cropped_render_is_the_same_pixels_of_the_full_render() {
    let ctx = common::gpu();
    let spp = 256;
    let full_scene = pbrt("full.pbrt", "");
    let crop_scene = pbrt("window.pbrt", r#""float cropwindow" [ 0.25 0.75 0.5 1 ]"#);
    let render = |s: &Scene, w: u32, h: u32| {
        let settings = Settings { mode: Mode::Direct, ..common::small(w, h) };
        let film = common::render(ctx, s, &settings, spp);
        assert_eq!(film.nonfinite_total, 0);
        film.mean.iter().map(|c| c[1] as f64).collect::<Vec<f64>>()
    };
    let full = render(&full_scene, W, H);
    let crop = render(&crop_scene, 32, 24);
    // 4×4-pixel block means: the crop's block (i, j) against the full image's block (i + 4, j + 6), and, so that
    // the comparison can tell, against the block a crop of the wrong place would show.
    let block = |img: &[f64], width: u32, bx: u32, by: u32| {
        let mut sum = 0.0;
        for y in by * 4..by * 4 + 4 {
            for x in bx * 4..bx * 4 + 4 {
                sum += img[(y * width + x) as usize];
            }
        }
        sum / 16.0
    };
    let (mut worst, mut misplaced, mut lit) = (0.0f64, 0.0f64, 0);
    for j in 0..6 {
        for i in 0..8 {
            let c = block(&crop, 32, i, j);
            worst = worst.max((c - block(&full, W, i + 4, j + 6)).abs());
            misplaced = misplaced.max((c - block(&full, W, i, j)).abs());
            lit += (c > 0.05) as u32;
        }
    }
    assert!(lit >= 3, "the crop should see some of the emitters ({lit} lit blocks)");
    assert!(worst < 0.03, "a cropped block differs from the full render's by {worst}");
    assert!(
        misplaced > 0.2,
        "the full render's top-left corner looks like the crop ({misplaced}): the test cannot tell"
    );
}
