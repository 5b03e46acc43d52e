//! Wavefront OBJ meshes (Mitsuba's `obj` shape): `v`, `vt`, `vn` and polygon `f` records (1-based or negative
//! indices, `v`, `v/vt`, `v//vn`, `v/vt/vn`), fanned into triangles; other records are skipped.
//!
//! Our own rather than `tobj`: its `LoadError` is a bare kind (`PositionParseError`, `FaceParseError`, …) with no
//! line, and an error must name the line; and `tobj::load_obj` opens `mtllib` files itself, outside the scene-folder
//! containment every other referenced file goes through (Mitsuba ignores OBJ materials anyway).

use super::ply::PlyMesh;
use glam::{Vec2, Vec3};
use std::collections::HashMap;

/// Decodes OBJ text into one mesh (all groups together). Errors carry the line number.
pub fn decode(text: &str) -> Result<PlyMesh, String> {
    let (mut v, mut vt, mut vn) = (Vec::<Vec3>::new(), Vec::<Vec2>::new(), Vec::<Vec3>::new());
    let mut out = PlyMesh::default();
    let mut seen: HashMap<(usize, Option<usize>, Option<usize>), u32> = HashMap::new();
    let (mut any_vt, mut any_vn, mut all_vt, mut all_vn) = (false, false, true, true);
    let mut corners = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let ln = n + 1;
        let mut w = line.split_whitespace();
        let nums = |w: std::str::SplitWhitespace, k: usize| -> Result<Vec<f32>, String> {
            let v: Vec<f32> = w
                .take(k)
                .map(|s| s.parse::<f32>())
                .collect::<Result<_, _>>()
                .map_err(|_| format!("line {ln}: bad number"))?;
            if v.len() < k.min(2) || v.iter().any(|x| !x.is_finite()) {
                return Err(format!("line {ln}: expected {k} finite numbers"));
            }
            Ok(v)
        };
        match w.next() {
            Some("v") => {
                let c = nums(w, 3)?;
                if c.len() < 3 {
                    return Err(format!("line {ln}: a vertex needs 3 coordinates"));
                }
                v.push(Vec3::new(c[0], c[1], c[2]));
            }
            Some("vt") => {
                let c = nums(w, 2)?;
                vt.push(Vec2::new(c[0], c[1]));
            }
            Some("vn") => {
                let c = nums(w, 3)?;
                if c.len() < 3 {
                    return Err(format!("line {ln}: a normal needs 3 coordinates"));
                }
                vn.push(Vec3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                corners.clear();
                for c in w {
                    let mut parts = c.split('/');
                    let resolve = |s: Option<&str>, len: usize, what: &str| -> Result<Option<usize>, String> {
                        match s {
                            None | Some("") => Ok(None),
                            Some(s) => {
                                let i: i64 = s.parse().map_err(|_| {
                                    format!("line {ln}: bad {what} index '{}'", crate::io::input_file::clip(s, 24))
                                })?;
                                let r = if i > 0 { i - 1 } else { len as i64 + i };
                                if i == 0 || r < 0 || r >= len as i64 {
                                    return Err(format!(
                                        "line {ln}: {what} index {i} is out of range (there are {len})"
                                    ));
                                }
                                Ok(Some(r as usize))
                            }
                        }
                    };
                    let pi =
                        resolve(parts.next(), v.len(), "vertex")?.ok_or(format!("line {ln}: empty face corner"))?;
                    let ti = resolve(parts.next(), vt.len(), "uv")?;
                    let ni = resolve(parts.next(), vn.len(), "normal")?;
                    (any_vt, any_vn, all_vt, all_vn) =
                        (any_vt | ti.is_some(), any_vn | ni.is_some(), all_vt & ti.is_some(), all_vn & ni.is_some());
                    let key = (pi, ti, ni);
                    let index = *seen.entry(key).or_insert_with(|| {
                        out.positions.push(v[pi]);
                        out.uvs.push(ti.map_or(Vec2::ZERO, |t| vt[t]));
                        out.normals.push(ni.map_or(Vec3::ZERO, |t| vn[t]));
                        out.positions.len() as u32 - 1
                    });
                    corners.push(index);
                }
                if corners.len() < 3 {
                    return Err(format!("line {ln}: a face needs at least 3 corners"));
                }
                for k in 2..corners.len() {
                    out.indices.push([corners[0], corners[k - 1], corners[k]]);
                }
            }
            _ => {}
        }
    }
    if out.indices.is_empty() {
        // Text with no face at all is no mesh (and most likely no OBJ file): an error, not an empty shape.
        return Err("no faces ('f' records): is this an OBJ file?".into());
    }
    if !(any_vn && all_vn) {
        out.normals.clear();
    }
    if !(any_vt && all_vt) {
        out.uvs.clear();
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    #[test]
    fn quad_with_uv_and_bad_index() {
        let m = super::decode("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1 -1/1\n").unwrap();
        assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.uvs.len(), 4);
        assert!(m.normals.is_empty());
        let e = super::decode("v 0 0 0\nf 1 2 3\n").unwrap_err();
        assert!(e.contains("line 2") && e.contains("out of range"), "{e}");
        let e = super::decode("root:x:0:0:root:/root:/bin/bash\n").unwrap_err();
        assert!(e.contains("no faces") && !e.contains("root"), "{e}");
    }
}
