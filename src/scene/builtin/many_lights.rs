//! The many-light scenes, built in: `many-lights` (thousands of small emitters over a floor) and
//! `veach-mis-triangles` (the lecture's Veach scene with its sphere lights tessellated, as the glTF version in
//! `shared/scenes/veach-mis` has them), where which light a sample picks decides the noise.

use super::{self as builtin, Builder};
use crate::scene::{Camera, Material, Mesh, Scene};
use glam::Vec3;

/// The light tree's scene: 4096 small emissive triangles (0.12 units across) over a 40 × 40 Lambert 0.5 floor, on a
/// jittered 64 × 64 grid at heights 0.15–1.5, their radiance log-uniform over three decades in eight colours, and
/// their normals anywhere on the sphere, so that about half face away from the floor and light only the black sky.
/// The camera looks down on the field from 22 units up, so that every pixel sees the floor: looking across it from
/// a corner (as it first did), the far half of the field was a band of sub-pixel emitters at the horizon whose
/// pixel-coverage noise, which no light selection touches, was half of the tree's error at 64 spp (measured).
/// Picking by power, a shading point gets its light from any of
/// the 4096 — mostly far ones, or ones facing away — while only the few dozen around it matter: the case a light
/// tree (position, orientation) and RIS (unshadowed contribution) are for.
pub fn many_lights() -> Scene {
    let camera = Camera::look_at(Vec3::new(-4.0, 22.0, -4.0), Vec3::new(1.0, 0.0, 1.0), Vec3::Y, 45.0);
    let mut b = Builder::new("many-lights", camera);
    let floor = b.material(Material::lambert("floor", Vec3::splat(0.5)));
    b.quad(Vec3::new(-20.0, 0.0, -20.0), Vec3::new(0.0, 0.0, 40.0), Vec3::new(40.0, 0.0, 0.0), floor);
    // A small integer hash (deterministic: the scene is the same on every machine).
    let hash = |i: u32, k: u32| {
        let mut x = i.wrapping_mul(0x9e37_79b9) ^ k.wrapping_mul(0x85eb_ca6b);
        x ^= x >> 16;
        x = x.wrapping_mul(0x7feb_352d);
        x ^= x >> 15;
        x = x.wrapping_mul(0x846c_a68b);
        x ^= x >> 16;
        (x >> 8) as f32 / (1u32 << 24) as f32
    };
    const COLOURS: [[f32; 3]; 8] = [
        [1.0, 0.9, 0.7],
        [1.0, 0.5, 0.2],
        [0.3, 0.6, 1.0],
        [1.0, 0.3, 0.5],
        [0.5, 1.0, 0.4],
        [0.9, 0.9, 1.0],
        [1.0, 0.8, 0.3],
        [0.6, 0.4, 1.0],
    ];
    // 8 colours × 6 intensity steps over three decades (0.3 … 300).
    let mut emitters = Vec::new();
    for (c, rgb) in COLOURS.iter().enumerate() {
        for step in 0..6 {
            let l = 10f32.powf(-0.5 + 3.0 * step as f32 / 5.0);
            emitters.push(b.material(Material::emitter(&format!("emitter {c}.{step}"), l * Vec3::from(*rgb))));
        }
    }
    // One mesh per emitter material; each triangle has its own three vertices.
    let mut meshes: Vec<Mesh> =
        emitters.iter().map(|&m| Mesh { name: format!("emitters {m}"), material: m, ..Default::default() }).collect();
    for i in 0..4096u32 {
        let (gx, gz) = ((i % 64) as f32, (i / 64) as f32);
        let c = Vec3::new(
            -19.0 + 38.0 * (gx + hash(i, 0)) / 64.0,
            0.15 + 1.35 * hash(i, 1),
            -19.0 + 38.0 * (gz + hash(i, 2)) / 64.0,
        );
        let z = 2.0 * hash(i, 3) - 1.0;
        let phi = std::f32::consts::TAU * hash(i, 4);
        let r = (1.0 - z * z).max(0.0).sqrt();
        let n = Vec3::new(r * phi.cos(), z, r * phi.sin());
        let t = n.any_orthonormal_vector();
        let bt = n.cross(t);
        let mesh = &mut meshes[((hash(i, 5) * emitters.len() as f32) as usize).min(emitters.len() - 1)];
        let k = mesh.positions.len() as u32;
        // Counter-clockwise about n (t × bt = n): n is the emitting side.
        mesh.positions.extend([c + 0.07 * t, c + 0.07 * (-0.5 * t + 0.866 * bt), c + 0.07 * (-0.5 * t - 0.866 * bt)]);
        mesh.normals.extend([n; 3]);
        mesh.indices.push([k, k + 1, k + 2]);
    }
    b.scene.meshes.extend(meshes.into_iter().filter(|m| !m.indices.is_empty()));
    b.scene
}

/// Stacks × slices of each tessellated sphere light: 2 · 128 · 63 = 16,128 triangles, 80,640 for the five lights,
/// the count of the glTF version.
const STACKS: u32 = 64;
const SLICES: u32 = 128;

/// The built-in veach-mis scene with every sphere light replaced by a UV sphere of 16,128 flat emissive triangles
/// (counter-clockwise seen from outside: they emit outwards), inscribed in the sphere. The same image up to the
/// tessellation (the inscribed lights are up to 0.03 % smaller), and 80,640 lights instead of five, kept as
/// triangles (`Scene::emitter_triangles_kept`).
pub fn veach_mis_triangles() -> Scene {
    let mut s = builtin::by_name("veach-mis").expect("veach-mis is built in");
    s.name = "veach-mis-triangles".into();
    // Its point is choosing among the 80,640 triangles: no convex lamps (the glTF file of the scene gets them).
    s.emitter_triangles_kept = true;
    let lights: Vec<_> =
        s.spheres.iter().filter(|x| s.materials[x.material as usize].emission != Vec3::ZERO).cloned().collect();
    s.spheres.retain(|x| s.materials[x.material as usize].emission == Vec3::ZERO);
    for (i, l) in lights.iter().enumerate() {
        let point = |stack: u32, slice: u32| {
            let theta = std::f32::consts::PI * stack as f32 / STACKS as f32;
            let phi = std::f32::consts::TAU * slice as f32 / SLICES as f32;
            Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
        };
        let mut mesh = Mesh { name: format!("sphere light {i}"), material: l.material, ..Default::default() };
        for stack in 0..STACKS {
            for slice in 0..SLICES {
                let (a, b) = (point(stack, slice), point(stack, slice + 1));
                let (c, d) = (point(stack + 1, slice), point(stack + 1, slice + 1));
                // Seen from outside, (a, b, d) and (a, d, c) run counter-clockwise; the poles' degenerate halves
                // are left out.
                let quads: [[Vec3; 3]; 2] = [[a, b, d], [a, d, c]];
                for (k, t) in quads.iter().enumerate() {
                    if (stack == 0 && k == 0) || (stack == STACKS - 1 && k == 1) {
                        continue;
                    }
                    let base = mesh.positions.len() as u32;
                    let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
                    mesh.positions.extend(t.iter().map(|&p| l.center + l.radius * p));
                    mesh.normals.extend([n; 3]);
                    mesh.indices.push([base, base + 1, base + 2]);
                }
            }
        }
        s.meshes.push(mesh);
    }
    s
}
