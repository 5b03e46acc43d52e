//! Environment maps of imported scenes: pbrt-v4's equal-area octahedral squares (Clarberg's mapping, as pbrt's
//! `imgtool makeequiarea` writes them) and Mitsuba's lat-long maps, with the light's full rotation, resampled
//! once at load into mislab's equirectangular [`EnvMap`] (so the renderer's env lookup and sampling are unchanged).

use super::envmap::{direction_to_equirect, equirect_direction};
use super::EnvMap;
use glam::{Mat3, Vec2, Vec3};
use std::f32::consts::PI;
use std::path::PathBuf;

/// How the source image maps to directions (in the light's own space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Layout {
    /// pbrt-v4 equal-area octahedral square, +Z at the centre.
    EqualArea,
    /// mislab's / Mitsuba's lat-long layout (`equirect_direction`).
    Equirect,
}

/// pbrt-v4's equal-area square → unit direction (`p` ∈ [0,1]², x right, y down the image).
pub fn equal_area_square_to_sphere(p: Vec2) -> Vec3 {
    let (u, v) = (2.0 * p.x - 1.0, 2.0 * p.y - 1.0);
    let (up, vp) = (u.abs(), v.abs());
    let signed = 1.0 - (up + vp);
    let r = 1.0 - signed.abs();
    let phi = if r == 0.0 { 1.0 } else { (vp - up) / r + 1.0 } * PI / 4.0;
    let z = (1.0 - r * r).copysign(signed);
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    Vec3::new(phi.cos().copysign(u) * s, phi.sin().copysign(v) * s, z)
}

/// The inverse of [`equal_area_square_to_sphere`] (exact atan instead of pbrt's polynomial).
pub fn equal_area_sphere_to_square(d: Vec3) -> Vec2 {
    let (x, y, z) = (d.x.abs(), d.y.abs(), d.z.abs());
    let r = (1.0 - z).max(0.0).sqrt();
    let (a, b) = (x.max(y), x.min(y));
    let mut phi = if a == 0.0 { 0.0 } else { (b / a).atan() * 2.0 / PI };
    if x < y {
        phi = 1.0 - phi;
    }
    let mut v = phi * r;
    let mut u = r - v;
    if d.z < 0.0 {
        std::mem::swap(&mut u, &mut v);
        u = 1.0 - u;
        v = 1.0 - v;
    }
    Vec2::new((u.copysign(d.x) + 1.0) * 0.5, (v.copysign(d.y) + 1.0) * 0.5)
}

/// Resamples `texels` (`w`×`h`, top row first) into an equirectangular map `2·out_h`×`out_h` in which direction
/// `d` (mislab world) shows the source at `light_from_world · d`. Each output texel averages 2×2 bilinear taps.
pub fn resample(
    path: PathBuf,
    texels: &[[f32; 3]],
    w: u32,
    h: u32,
    layout: Layout,
    light_from_world: Mat3,
    out_h: u32,
) -> EnvMap {
    let (ow, oh) = (out_h * 2, out_h);
    let fetch = |x: i64, y: i64| -> Vec3 {
        let x = x.clamp(0, w as i64 - 1) as usize;
        let y = y.clamp(0, h as i64 - 1) as usize;
        Vec3::from_array(texels[y * w as usize + x])
    };
    let bilinear = |st: Vec2| -> Vec3 {
        let (fx, fy) = (st.x * w as f32 - 0.5, st.y * h as f32 - 0.5);
        let (x0, y0) = (fx.floor(), fy.floor());
        let (tx, ty) = (fx - x0, fy - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let wrap = |x: i64| if layout == Layout::Equirect { x.rem_euclid(w as i64) } else { x };
        let a = fetch(wrap(x0), y0).lerp(fetch(wrap(x0 + 1), y0), tx);
        let b = fetch(wrap(x0), y0 + 1).lerp(fetch(wrap(x0 + 1), y0 + 1), tx);
        a.lerp(b, ty)
    };
    let mut out = Vec::with_capacity((ow * oh) as usize);
    for y in 0..oh {
        for x in 0..ow {
            let mut sum = Vec3::ZERO;
            for (sx, sy) in [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)] {
                let d = equirect_direction((x as f32 + sx) / ow as f32, (y as f32 + sy) / oh as f32);
                let l = (light_from_world * d).normalize_or(Vec3::Z);
                let st = match layout {
                    Layout::EqualArea => equal_area_sphere_to_square(l),
                    Layout::Equirect => {
                        let (u, v) = direction_to_equirect(l);
                        Vec2::new(u, v)
                    }
                };
                sum += bilinear(st);
            }
            let c = sum / 4.0;
            let c = if c.is_finite() { c.max(Vec3::ZERO) } else { Vec3::ZERO };
            out.push(c.to_array());
        }
    }
    EnvMap { path, width: ow, height: oh, texels: out }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_area_round_trip_and_axes() {
        assert!((equal_area_square_to_sphere(Vec2::new(0.5, 0.5)) - Vec3::Z).length() < 1e-5);
        assert!(equal_area_square_to_sphere(Vec2::new(0.0, 0.0)).z < -0.999);
        for i in 0..40 {
            for j in 0..40 {
                let p = Vec2::new((i as f32 + 0.5) / 40.0, (j as f32 + 0.5) / 40.0);
                let d = equal_area_square_to_sphere(p);
                assert!((d.length() - 1.0).abs() < 1e-4);
                let q = equal_area_sphere_to_square(d);
                assert!((p - q).length() < 1e-4, "{p} -> {d} -> {q}");
            }
        }
    }

    #[test]
    fn rotated_resample_moves_a_bright_texel() {
        // An equirect source bright only at +X; light_from_world maps world +Z to light +X.
        let (w, h) = (64u32, 32u32);
        let mut t = vec![[0.0f32; 3]; (w * h) as usize];
        let (u, v) = direction_to_equirect(Vec3::X);
        let (x, y) = ((u * w as f32) as usize, (v * h as f32) as usize);
        t[y * w as usize + x.min(w as usize - 1)] = [100.0; 3];
        let rot = Mat3::from_rotation_y(std::f32::consts::FRAC_PI_2); // maps +Z to +X
        assert!((rot * Vec3::Z - Vec3::X).length() < 1e-5);
        let m = resample("t".into(), &t, w, h, Layout::Equirect, rot, 32);
        let brightest = (0..m.texels.len()).max_by(|&a, &b| m.texels[a][0].total_cmp(&m.texels[b][0])).unwrap();
        let (bx, by) = (brightest % 64, brightest / 64);
        let d = equirect_direction((bx as f32 + 0.5) / 64.0, (by as f32 + 0.5) / 32.0);
        assert!(d.dot(Vec3::Z) > 0.95, "brightest at {d}");
    }
}
