//! The light table a scene's emitters become (`SceneData::lights`): one entry per emissive triangle, sphere and
//! quad, per punctual light and for the environment; convex lamps in place of their faces' triangles, whose
//! entries follow the lights that selection chooses among; each entry's power and selection probabilities, the
//! power alias table and the light tree.

use crate::accel::convex_lamps::{convex_lamp, ConvexLamp};
use crate::accel::isolated_emitters::{isolated_emitters, IsolatedEmitter};
use crate::accel::light_tree::{LightBounds, LightTree};
use crate::gpu::types::*;
use crate::render::lights::{self, luminance};
use crate::render::scene_data::SceneData;
use crate::scene::{Environment, PunctualLight, Scene};
use glam::Vec3;
use std::f64::consts::PI;

/// Radius of a sphere bounding every finite primitive (for the power of distant lights).
fn scene_radius(d: &SceneData) -> f64 {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    let mut add = |p: Vec3, r: f32| {
        if p.is_finite() {
            lo = lo.min(p - r);
            hi = hi.max(p + r);
        }
    };
    for v in &d.tri_verts {
        add(Vec3::new(v[0], v[1], v[2]), 0.0);
    }
    for s in &d.spheres {
        add(Vec3::from(s.center), s.radius);
    }
    for q in &d.quads {
        let c = Vec3::from(q.corner);
        add(c, 0.0);
        add(c + Vec3::from(q.edge_u) + Vec3::from(q.edge_v), 0.0);
    }
    if lo.x > hi.x {
        return 1.0;
    }
    (0.5 * (hi - lo).length() as f64).max(1e-3)
}

/// Gives the triangle lights of isolated emitter meshes their stop box (`accel::isolated_emitters`): a shadow ray
/// towards one may end where it enters that box (measured in docs/estimators.md, "Shadow rays that stop at an
/// isolated emitter").
fn mark_isolated_emitters(tris: &[[Vec3; 3]], d: &SceneData, lights: &mut [GpuLight]) -> Vec<IsolatedEmitter> {
    let light_of = |i: usize| d.tri_shading.get(i).map_or(INVALID, |s| s.light);
    let emitter = |i: usize| {
        let l = light_of(i);
        (l != INVALID).then(|| lights[l as usize].two_sided == 1)
    };
    let spheres = d.spheres.iter().map(|s| {
        let (c, r) = (Vec3::from(s.center), Vec3::splat(s.radius));
        (c - r, c + r)
    });
    let quads = d.quads.iter().map(|q| {
        let c = Vec3::from(q.corner);
        let (u, v) = (Vec3::from(q.edge_u), Vec3::from(q.edge_v));
        let ps = [c, c + u, c + v, c + u + v];
        (ps.iter().fold(Vec3::INFINITY, |a, &p| a.min(p)), ps.iter().fold(Vec3::NEG_INFINITY, |a, &p| a.max(p)))
    });
    let others: Vec<(Vec3, Vec3)> = spheres.chain(quads).collect();
    let meshes = isolated_emitters(tris, emitter, &others);
    for mesh in &meshes {
        for &t in &mesh.triangles {
            let l = &mut lights[light_of(t) as usize];
            (l.position, l.direction, l.shadow_box) = (mesh.lo.into(), mesh.hi.into(), 1);
        }
    }
    meshes
}

/// Replaces the triangle lights of every convex lamp among `meshes` by one lamp light (appended) and returns the
/// lamps, each with the lights of its faces (moved out of `lights`; `tri_shading` is repointed in
/// `append_lamp_faces`). A lamp needs one emission on every face: one material without an emission texture,
/// one-sided.
fn make_convex_lamps(
    tris: &[[Vec3; 3]],
    d: &mut SceneData,
    meshes: &[IsolatedEmitter],
    lights: &mut Vec<GpuLight>,
    power: &mut Vec<f64>,
) -> Vec<(u32, Vec<(usize, GpuLight)>)> {
    let lamps: Vec<ConvexLamp> = meshes
        .iter()
        .filter(|m| {
            let mat = d.tri_material(m.triangles[0]);
            let gm = &d.materials[mat as usize];
            gm.emissive_tex == INVALID
                && m.triangles
                    .iter()
                    .all(|&t| d.tri_material(t) == mat && lights[d.tri_shading[t].light as usize].two_sided == 0)
        })
        .filter_map(|m| convex_lamp(tris, m))
        .collect();
    if lamps.is_empty() {
        return vec![];
    }
    let mut face_of = vec![false; lights.len()];
    for lamp in &lamps {
        for &t in &lamp.mesh.triangles {
            face_of[d.tri_shading[t].light as usize] = true;
        }
    }
    // Keep the other lights in order and repoint their triangles.
    let mut index = vec![INVALID; lights.len()];
    let (mut kept, mut kept_power) = (Vec::new(), Vec::new());
    for (i, (l, p)) in lights.iter().zip(power.iter()).enumerate() {
        if !face_of[i] {
            index[i] = kept.len() as u32;
            kept.push(*l);
            kept_power.push(*p);
        }
    }
    let old = std::mem::replace(lights, kept);
    *power = kept_power;
    for s in d.tri_shading.iter_mut().filter(|s| s.light != INVALID) {
        if !face_of[s.light as usize] {
            s.light = index[s.light as usize];
        }
    }
    for l in d.spheres.iter_mut().map(|s| &mut s.light).chain(d.quads.iter_mut().map(|q| &mut q.light)) {
        if *l != INVALID {
            *l = index[*l as usize];
        }
    }
    let mut out = Vec::new();
    for lamp in lamps {
        let faces: Vec<(usize, GpuLight)> =
            lamp.mesh.triangles.iter().map(|&t| (t, old[d.tri_shading[t].light as usize])).collect();
        let area: f64 = faces.iter().map(|(_, l)| l.area as f64).sum();
        let emission = d.materials[d.tri_material(lamp.mesh.triangles[0]) as usize].emission;
        power.push(PI * area * luminance(emission));
        out.push((lights.len() as u32, faces));
        lights.push(GpuLight {
            kind: LIGHT_CONVEX_LAMP,
            position: lamp.mesh.lo.into(),
            direction: lamp.mesh.hi.into(),
            shadow_box: 1,
            radiance: emission,
            cos_inner: lamp.r_in,
            cos_outer: lamp.rim,
            area: lamp.mesh.triangles.len() as f32,
            ..Default::default()
        });
    }
    out
}

/// Appends the convex lamps' faces after every light that selection chooses among: each lamp learns where its
/// faces start (`prim`), each face its lamp (`tree_trail`), each face's triangle its light.
fn append_lamp_faces(d: &mut SceneData, lights: &mut Vec<GpuLight>, lamps: Vec<(u32, Vec<(usize, GpuLight)>)>) {
    for (lamp, faces) in lamps {
        lights[lamp as usize].prim = lights.len() as u32;
        d.lamp_faces += faces.len();
        for (t, face) in faces {
            d.tri_shading[t].light = lights.len() as u32;
            lights.push(GpuLight { kind: LIGHT_LAMP_FACE, tree_trail: lamp, pmf_power: 0.0, pmf_uniform: 0.0, ..face });
        }
    }
}

/// Emissive triangles are never pre-split (`keep_whole` above), so each is one light with one copy.
pub(super) fn build_lights(scene: &Scene, tris: &[[Vec3; 3]], d: &mut SceneData, convex_lamps: bool) {
    let mut lights: Vec<GpuLight> = Vec::new();
    let mut power: Vec<f64> = Vec::new();
    let emits = |m: u32| {
        let gm = &d.materials[m as usize];
        gm.emission.iter().any(|&c| c > 0.0)
    };
    // Faces that emit: 2 for a two-sided area emitter.
    let two_sided =
        |m: u32| if scene.materials.get(m as usize).is_some_and(|m| m.emission_two_sided) { 2u32 } else { 1 };
    for (i, t) in tris.iter().enumerate() {
        let m = d.tri_material(i);
        if !emits(m) {
            continue;
        }
        let area = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length();
        if !(area > 0.0 && area.is_finite()) {
            continue;
        }
        d.tri_shading[i].light = lights.len() as u32;
        // A two-sided emitter radiates π·A·L from each face.
        let sides = two_sided(m);
        power.push(PI * area as f64 * luminance(d.materials[m as usize].emission) * sides as f64);
        let two_sided = (sides == 2) as u32;
        lights.push(GpuLight { kind: LIGHT_TRIANGLE, prim: i as u32, area, two_sided, ..Default::default() });
    }
    for i in 0..d.spheres.len() {
        let s = d.spheres[i];
        if !emits(s.material) || !(s.radius > 0.0) {
            continue;
        }
        let area = 4.0 * std::f32::consts::PI * s.radius * s.radius;
        d.spheres[i].light = lights.len() as u32;
        power.push(PI * area as f64 * luminance(d.materials[s.material as usize].emission));
        lights.push(GpuLight { kind: LIGHT_SPHERE, prim: i as u32, area, position: s.center, ..Default::default() });
    }
    for i in 0..d.quads.len() {
        let q = d.quads[i];
        let area = Vec3::from(q.edge_u).cross(Vec3::from(q.edge_v)).length();
        if !emits(q.material) || !(area > 0.0 && area.is_finite()) {
            continue;
        }
        d.quads[i].light = lights.len() as u32;
        let sides = two_sided(q.material);
        power.push(PI * area as f64 * luminance(d.materials[q.material as usize].emission) * sides as f64);
        let two_sided = (sides == 2) as u32;
        lights.push(GpuLight { kind: LIGHT_QUAD, prim: i as u32, area, two_sided, ..Default::default() });
    }
    let isolated = mark_isolated_emitters(tris, d, &mut lights);
    let lamps = if convex_lamps { make_convex_lamps(tris, d, &isolated, &mut lights, &mut power) } else { vec![] };
    let r = scene_radius(d);
    // Lights with a position first, then the infinite ones (directional, environment): the light tree covers
    // the first `bounded` entries and the shader finds the infinite ones after them.
    let punctual = scene.punctual_lights.iter().filter(|l| !matches!(l, PunctualLight::Directional { .. }));
    let directional = scene.punctual_lights.iter().filter(|l| matches!(l, PunctualLight::Directional { .. }));
    for l in punctual.chain(directional) {
        let (g, p) = match *l {
            PunctualLight::Point { position, intensity } => (
                GpuLight {
                    kind: LIGHT_POINT,
                    position: (position - d.origin).into(),
                    radiance: intensity.into(),
                    ..Default::default()
                },
                4.0 * PI * luminance(intensity.into()),
            ),
            PunctualLight::Spot { position, direction, intensity, inner_cone, outer_cone } => {
                let (ci, co) = (inner_cone.cos(), outer_cone.cos());
                let g = GpuLight {
                    kind: LIGHT_SPOT,
                    position: (position - d.origin).into(),
                    direction: direction.normalize_or(Vec3::NEG_Z).into(),
                    radiance: intensity.into(),
                    cos_inner: ci.max(co + 1e-6).min(1.0),
                    cos_outer: co,
                    ..Default::default()
                };
                (g, 2.0 * PI * (1.0 - 0.5 * (ci + co) as f64) * luminance(intensity.into()))
            }
            PunctualLight::Directional { direction, irradiance } => (
                GpuLight {
                    kind: LIGHT_DIRECTIONAL,
                    direction: direction.normalize_or(Vec3::NEG_Y).into(),
                    radiance: irradiance.into(),
                    ..Default::default()
                },
                PI * r * r * luminance(irradiance.into()),
            ),
        };
        d.delta_lights += 1;
        power.push(p);
        lights.push(g);
    }
    match &scene.environment {
        Environment::None => {}
        Environment::Constant(c) => {
            d.env_constant = (*c).into();
            d.env_scale = 1.0;
            if c.max_element() > 0.0 {
                d.env_light = Some(lights.len() as u32);
                power.push(4.0 * PI * PI * r * r * luminance((*c).into()));
                lights.push(GpuLight { kind: LIGHT_ENVIRONMENT, ..Default::default() });
            }
        }
        Environment::Map { map, scale, rotation } => {
            let dist = lights::env_distribution(map);
            d.env_size = (map.width, map.height);
            d.env_scale = *scale;
            d.env_rotation = *rotation;
            if dist.mean_luminance * (*scale as f64) > 0.0 {
                d.env_light = Some(lights.len() as u32);
                power.push(4.0 * PI * PI * r * r * dist.mean_luminance * *scale as f64);
                lights.push(GpuLight { kind: LIGHT_ENVIRONMENT, ..Default::default() });
            }
            d.env_texels = dist.texels;
            d.env_alias = dist.alias;
        }
    }
    let table = lights::alias_table(&power);
    let n = lights.len();
    for (l, p) in lights.iter_mut().zip(&table.pmf) {
        l.pmf_power = *p as f32;
        l.pmf_uniform = 1.0 / n as f32;
    }
    let bounded = lights.iter().take_while(|l| !matches!(l.kind, LIGHT_DIRECTIONAL | LIGHT_ENVIRONMENT)).count();
    debug_assert!(lights[bounded..].iter().all(|l| matches!(l.kind, LIGHT_DIRECTIONAL | LIGHT_ENVIRONMENT)));
    let bounds: Vec<LightBounds> =
        lights[..bounded].iter().zip(&power).map(|(l, &p)| light_bounds(l, p, tris, d)).collect();
    let tree = LightTree::build(&bounds, &(0..bounded as u32).collect::<Vec<_>>());
    for (l, &trail) in lights.iter_mut().zip(&tree.trails) {
        l.tree_trail = trail;
    }
    d.light_tree = tree.nodes;
    append_lamp_faces(d, &mut lights, lamps);
    d.lights = lights;
    d.light_alias = table.entries;
}

/// Where light `l` (of power `power`) is and emits, for the light tree: area emitters emit from their front (the
/// side `*_sample_li` accepts) or, two-sided, from both faces; spheres and point lights emit everywhere, spots
/// into their outer cone.
fn light_bounds(l: &GpuLight, power: f64, tris: &[[Vec3; 3]], d: &SceneData) -> LightBounds {
    let everywhere = |lo: Vec3, hi: Vec3| LightBounds {
        lo,
        hi,
        phi: power as f32,
        axis: Vec3::Z,
        cos_o: -1.0,
        cos_e: 0.0,
        two_sided: false,
    };
    let facing = |pts: &[Vec3], normal: Vec3| {
        let lo = pts.iter().fold(Vec3::splat(f32::MAX), |a, &p| a.min(p));
        let hi = pts.iter().fold(Vec3::splat(f32::MIN), |a, &p| a.max(p));
        LightBounds {
            axis: normal.normalize_or(Vec3::Z),
            cos_o: 1.0,
            two_sided: l.two_sided != 0,
            ..everywhere(lo, hi)
        }
    };
    match l.kind {
        LIGHT_TRIANGLE => {
            let t = tris[l.prim as usize];
            facing(&t, (t[1] - t[0]).cross(t[2] - t[0]))
        }
        LIGHT_QUAD => {
            let q = d.quads[l.prim as usize];
            let (c, u, v) = (Vec3::from(q.corner), Vec3::from(q.edge_u), Vec3::from(q.edge_v));
            facing(&[c, c + u, c + v, c + u + v], u.cross(v))
        }
        LIGHT_SPHERE => {
            let s = d.spheres[l.prim as usize];
            let c = Vec3::from(s.center);
            everywhere(c - s.radius, c + s.radius)
        }
        LIGHT_CONVEX_LAMP => everywhere(l.position.into(), l.direction.into()),
        LIGHT_SPOT => {
            let p = Vec3::from(l.position);
            let (theta_i, theta_o) = (l.cos_inner.clamp(-1.0, 1.0).acos(), l.cos_outer.clamp(-1.0, 1.0).acos());
            LightBounds {
                axis: Vec3::from(l.direction),
                cos_o: l.cos_inner,
                cos_e: (theta_o - theta_i).max(0.0).cos(),
                ..everywhere(p, p)
            }
        }
        _ => {
            let p = Vec3::from(l.position);
            everywhere(p, p)
        }
    }
}
