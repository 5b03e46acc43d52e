//! The pixel filter on the GPU against its definition: a camera looks at the straight edge of an emitter of radiance
//! 1 that lies exactly on a column boundary, so a pixel whose centre is d pixels from the edge sees the fraction of
//! the filter (normalised, along x) that lies over the emitter: 1 − CDF(−d). Box, triangle and gaussian, each with
//! the radius pbrt-v4 gives it and one more; the filter comes from the scene file's `PixelFilter`.

mod common;
mod scratch;

use mislab::render::pixel_filter;
use mislab::render::settings::{Mode, PixelFilter, Settings};
use mislab::scene::{self, LoadOptions, Scene};

const WIDTH: u32 = 32;
const HEIGHT: u32 = 8;
const SPP: u32 = 1024;

/// An emitter over x > 0 at z = 1 (radiance 1, two-sided), seen from the origin along +z, with `filter`'s
/// PixelFilter statement.
fn load(filter: &str) -> Scene {
    let dir = scratch::unique("pixel-filter");
    let path = dir.join(format!("edge-{}.pbrt", filter.replace(|c: char| !c.is_ascii_alphanumeric(), "_")));
    let text = format!(
        r#"LookAt 0 0 0  0 0 1  0 1 0
Camera "perspective" "float fov" [ 10 ]
{filter}
Film "rgb" "integer xresolution" [ {WIDTH} ] "integer yresolution" [ {HEIGHT} ]
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 1 1 1 ] "bool twosided" true
  Material "diffuse" "rgb reflectance" [ 0 0 0 ]
  Shape "trianglemesh" "point3 P" [ 0 -10 1  10 -10 1  10 10 1  0 10 1 ] "integer indices" [ 0 1 2 0 2 3 ]
AttributeEnd
"#
    );
    std::fs::write(&path, text).unwrap();
    scene::load(path.to_str().unwrap(), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

/// The fraction of the normalised filter over [−d, ∞): what a pixel whose centre is d pixels inside the emitter sees.
fn covered(filter: PixelFilter, radius: f64, sigma: f64, d: f64) -> f64 {
    let n = 20_000;
    let h = 2.0 * radius / n as f64;
    let (mut inside, mut all) = (0.0, 0.0);
    for k in 0..n {
        let x = -radius + (k as f64 + 0.5) * h;
        let f = pixel_filter::value(filter, radius, sigma, x);
        all += f;
        if x > -d {
            inside += f;
        }
    }
    inside / all
}

#[test]
fn a_straight_edge_is_seen_through_each_filter_as_pbrt_v4_defines_it() {
    let ctx = common::gpu();
    let cases: [(&str, PixelFilter, f64, f64); 6] = [
        ("", PixelFilter::Box, 0.5, 0.5),
        (r#"PixelFilter "box" "float xradius" [ 1.5 ] "float yradius" [ 1.5 ]"#, PixelFilter::Box, 1.5, 0.5),
        (r#"PixelFilter "triangle""#, PixelFilter::Triangle, 2.0, 0.5),
        (r#"PixelFilter "triangle" "float xradius" [ 1 ] "float yradius" [ 1 ]"#, PixelFilter::Triangle, 1.0, 0.5),
        (r#"PixelFilter "gaussian""#, PixelFilter::Gaussian, 1.5, 0.5),
        (
            r#"PixelFilter "gaussian" "float xradius" [ 3 ] "float yradius" [ 3 ] "float sigma" [ 1 ]"#,
            PixelFilter::Gaussian,
            3.0,
            1.0,
        ),
    ];
    for (statement, filter, radius, sigma) in cases {
        let s = load(statement);
        let mut settings = Settings { mode: Mode::Direct, ..common::small(WIDTH, HEIGHT) };
        match &s.file_settings.filter {
            Some((f, source)) => {
                assert!(source.contains("PixelFilter"), "{source}");
                assert_eq!((f.shape, f.radius as f64, f.sigma as f64), (filter.name(), radius, sigma), "{statement}");
                settings.filter = filter;
                settings.filter_radius = Some(f.radius);
                settings.filter_sigma = f.sigma;
            }
            None => assert!(statement.is_empty(), "{statement} was not imported"),
        }
        let film = common::render(ctx, &s, &settings, SPP);
        assert_eq!(film.nonfinite_total, 0, "{statement}");
        // Column means over the rows; which side of the image the emitter falls on is the camera's convention.
        let column =
            |i: u32| (0..HEIGHT).map(|y| film.mean[(y * WIDTH + i) as usize][1] as f64).sum::<f64>() / HEIGHT as f64;
        let bright_right = column(WIDTH - 1) > column(0);
        for i in 0..WIDTH {
            let centre = i as f64 + 0.5 - (WIDTH / 2) as f64; // pixels right of the edge
            let d = if bright_right { centre } else { -centre };
            let want = covered(filter, radius, sigma, d);
            let got = column(i);
            assert!(
                (got - want).abs() < 0.025,
                "{filter} r {radius} σ {sigma}: column {i} ({d} px inside the emitter) is {got}, the filter says {want}"
            );
        }
    }
}
