//! pbrt shapes as object-space meshes: `trianglemesh`, `bilinearmesh`, `plymesh` (through our PLY reader) and
//! `disk` (a fan whose area matches the disk's). Spheres stay analytic (see the parser).

use super::params::Params;
use crate::scene::import_build::ObjectMesh;
use crate::scene::read_input::{at, read_bytes, SceneDir};
use crate::scene::SceneError;
use glam::{Vec2, Vec3};

fn vec3s(v: Vec<f64>) -> Vec<Vec3> {
    v.chunks_exact(3).map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32)).collect()
}

/// `trianglemesh` / `bilinearmesh` from inline arrays, indices checked against the vertex count.
pub fn inline_mesh(p: &Params, name: &str, bilinear: bool) -> Result<ObjectMesh, SceneError> {
    let positions =
        vec3s(p.nums("P", &["point3", "point"], 3)?.ok_or_else(|| p.error(format!("{name}: no \"point3 P\"")))?);
    let normals = p.nums("N", &["normal", "normal3"], 3)?.map(vec3s).unwrap_or_default();
    let uvs: Vec<Vec2> = p
        .nums("uv", &["point2", "float"], 2)?
        .or(p.nums("st", &["point2", "float"], 2)?)
        .map(|v| v.chunks_exact(2).map(|c| Vec2::new(c[0] as f32, c[1] as f32)).collect())
        .unwrap_or_default();
    let k = if bilinear { 4 } else { 3 };
    let raw = match p.nums("indices", &["integer"], k)? {
        Some(i) => i,
        None if positions.len() == k => (0..k as u32).map(f64::from).collect(),
        None => {
            return Err(p.error(format!("{name}: no \"integer indices\" (needed for {} vertices)", positions.len())))
        }
    };
    let n = positions.len();
    if let Some(bad) = raw.iter().find(|&&i| i < 0.0 || i >= n as f64 || i.fract() != 0.0) {
        return Err(p.error(format!("{name}: vertex index {bad} is out of range (the mesh has {n} vertices)")));
    }
    for (what, len) in [("N", normals.len()), ("uv", uvs.len())] {
        if len != 0 && len != n {
            return Err(p.error(format!("{name}: \"{what}\" has {len} entries but \"P\" has {n}")));
        }
    }
    let idx: Vec<u32> = raw.iter().map(|&i| i as u32).collect();
    let indices = if bilinear {
        idx.chunks_exact(4).flat_map(|q| [[q[0], q[1], q[3]], [q[0], q[3], q[2]]]).collect()
    } else {
        idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect()
    };
    Ok(ObjectMesh { name: name.into(), positions, normals, uvs, indices })
}

/// `plymesh`: the file named by `"string filename"`, relative to the scene's folder (and inside it, unless allowed).
pub fn ply_mesh(p: &Params, dir: &SceneDir) -> Result<ObjectMesh, SceneError> {
    let file = p.string("filename")?.ok_or_else(|| p.error("plymesh: no \"string filename\""))?;
    let path = dir.resolve(&file, &p.file, p.line)?;
    let by = at(&p.file, p.line);
    let bytes = read_bytes(&path, &by)?;
    let m =
        crate::scene::ply::decode(&bytes).map_err(|e| SceneError::new(&path, format!("{e} (referenced by {by})")))?;
    Ok(ObjectMesh { name: file, positions: m.positions, normals: m.normals, uvs: m.uvs, indices: m.indices })
}

/// `disk` at z = `height` facing +z (−z when `reverse`).
pub fn disk(p: &Params, reverse: bool) -> Result<ObjectMesh, SceneError> {
    Ok(crate::scene::import_build::disk(p.float("radius", 1.0)?, p.float("height", 0.0)?, reverse))
}
