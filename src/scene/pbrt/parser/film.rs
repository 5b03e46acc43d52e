//! pbrt-v4's film crop: `integer pixelbounds [x0 x1 y0 y1]` and `float cropwindow [x0 x1 y0 y1]` on `Film`, read
//! as pbrt-v4 reads them (film.cpp, `FilmBaseParameters`): pixel bounds intersected with the full film; a crop
//! window clamped to [0, 1] per axis (either order), its pixel bounds rounded up (`ceil(resolution · crop)`), and
//! taking precedence over pixel bounds, with a warning, when both are given. An empty crop is an error.

use super::super::params::Params;
use crate::scene::SceneError;

/// The pixels of a `w`×`h` film the image keeps, `[x0, x1, y0, y1]` (x1, y1 exclusive), or None for all of them;
/// and a warning when both forms were given.
pub(super) fn pixel_bounds(p: &Params, w: u32, h: u32) -> Result<(Option<[u32; 4]>, Option<String>), SceneError> {
    let full = [0, w, 0, h];
    let mut bounds = full;
    if let Some(pb) = p.nums("pixelbounds", &["integer"], 4)? {
        if pb.len() != 4 {
            return Err(p.error(format!("\"pixelbounds\" has {} values; expected 4", pb.len())));
        }
        let clamp = |v: f64, max: u32| v.clamp(0.0, max as f64) as u32;
        let (x0, x1) = (pb[0].min(pb[1]), pb[0].max(pb[1]));
        let (y0, y1) = (pb[2].min(pb[3]), pb[2].max(pb[3]));
        bounds = [clamp(x0, w), clamp(x1, w), clamp(y0, h), clamp(y1, h)];
        if bounds[0] >= bounds[1] || bounds[2] >= bounds[3] {
            return Err(p.error(format!("\"pixelbounds\" {pb:?} leaves no pixel of the {w}x{h} film")));
        }
    }
    let mut warning = None;
    if let Some(cr) = p.nums("cropwindow", &["float", "integer"], 4)? {
        if cr.len() != 4 {
            return Err(p.error(format!("\"cropwindow\" has {} values; expected 4", cr.len())));
        }
        if bounds != full {
            warning = Some(
                "Film: both \"pixelbounds\" and \"cropwindow\" given; the crop window is used (as pbrt-v4 does)".into(),
            );
        }
        let unit = |v: f64| v.clamp(0.0, 1.0);
        let (cx0, cx1) = (unit(cr[0].min(cr[1])), unit(cr[0].max(cr[1])));
        let (cy0, cy1) = (unit(cr[2].min(cr[3])), unit(cr[2].max(cr[3])));
        let px = |f: f64, n: u32| (n as f64 * f).ceil() as u32;
        bounds = [px(cx0, w), px(cx1, w), px(cy0, h), px(cy1, h)];
        if bounds[0] >= bounds[1] || bounds[2] >= bounds[3] {
            return Err(p.error(format!("\"cropwindow\" {cr:?} leaves no pixel of the {w}x{h} film")));
        }
    }
    Ok(((bounds != full).then_some(bounds), warning))
}
