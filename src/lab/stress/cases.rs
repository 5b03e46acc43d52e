//! The stress cases: scenes built in code at extreme scales, angles, sizes and radiances, with their analytic
//! answers where they have one.

use super::{Case, Check, F32_FLOOR};
use crate::lab::LabError;
use crate::render::settings::{EnvSampling, LightSampling, Mode, SamplerKind, Settings, Strategy};
use crate::scene::{self, Camera, Environment, Material, Mesh, PunctualLight, Quad, Scene, Sphere};
use glam::{DVec3, Vec3};
use std::collections::HashMap;
use std::f64::consts::PI;
use std::sync::Arc;

/// Film side of most cases.
const SIZE: u32 = 24;
/// ρ of the Lambert receivers.
const RHO: f64 = 0.5;

fn settings(strategy: Strategy) -> Settings {
    Settings { width: SIZE, height: SIZE, strategy, ..Settings::default() }
}

fn case(
    group: &'static str,
    name: impl Into<String>,
    scene: Scene,
    settings: Settings,
    spp: u32,
    check: Check,
) -> Case {
    Case { group, name: name.into(), scene, settings, spp, dispatch_spp: None, check }
}

/// A mesh from positions and triangles, with per-vertex normals averaged from the faces (any unit vector for
/// vertices of degenerate faces only).
fn mesh(name: &str, positions: Vec<Vec3>, indices: Vec<[u32; 3]>, material: u32) -> Mesh {
    let mut normals = vec![Vec3::ZERO; positions.len()];
    for t in &indices {
        let [a, b, c] = t.map(|i| positions[i as usize].as_dvec3());
        let n = (b - a).cross(c - a).as_vec3();
        if n.is_finite() {
            for &i in t {
                normals[i as usize] += n;
            }
        }
    }
    let normals = normals.into_iter().map(|n| n.try_normalize().unwrap_or(Vec3::Y)).collect();
    Mesh { name: name.into(), positions, normals, uvs: Vec::new(), indices, material }
}

/// Maps every position of `s` by p ↦ p·k + offset (radii and edges by k); point-light intensities scale by k²
/// so that the image stays the same.
fn transformed(mut s: Scene, k: f32, offset: Vec3) -> Scene {
    let map = |p: Vec3| p * k + offset;
    for m in &mut s.meshes {
        m.positions.iter_mut().for_each(|p| *p = map(*p));
    }
    for sp in &mut s.spheres {
        sp.center = map(sp.center);
        sp.radius *= k;
    }
    for q in &mut s.quads {
        q.corner = map(q.corner);
        q.edge_u *= k;
        q.edge_v *= k;
    }
    for l in &mut s.punctual_lights {
        match l {
            PunctualLight::Point { position, intensity } | PunctualLight::Spot { position, intensity, .. } => {
                *position = map(*position);
                *intensity *= k * k;
            }
            PunctualLight::Directional { .. } => {}
        }
    }
    s.camera.position = map(s.camera.position);
    s
}

fn builtin(name: &str) -> Scene {
    scene::builtin::by_name(name).expect("built-in scene")
}

/// A large Lambert ρ floor (y = 0, facing up, side `half`·2 around the origin), seen by a camera at `eye` that
/// looks at `target` with a narrow field of view (so every pixel sees about the same floor point).
fn floor_scene(name: &str, half: f32, eye: Vec3, target: Vec3, vfov_degrees: f32) -> Scene {
    let mut s = Scene { name: name.into(), ..Default::default() };
    s.camera = Camera::look_at(
        eye,
        target,
        if (eye - target).cross(Vec3::Y).length() < 1e-6 * (eye - target).length() { Vec3::Z } else { Vec3::Y },
        vfov_degrees,
    );
    s.materials.push(Material::lambert("floor", Vec3::splat(RHO as f32)));
    s.quads.push(Quad {
        corner: Vec3::new(-half, 0.0, -half),
        edge_u: Vec3::new(0.0, 0.0, 2.0 * half),
        edge_v: Vec3::new(2.0 * half, 0.0, 0.0),
        material: 0,
    });
    s
}

/// Irradiance at p (normal n) from a Lambertian polygon of radiance L wholly above p's horizon and facing it
/// (Lambert's formula; Arvo 1995 eq. 3).
pub fn polygon_irradiance(p: DVec3, n: DVec3, verts: &[DVec3], l: f64) -> f64 {
    let k = verts.len();
    let mut sum = 0.0;
    for i in 0..k {
        let a = (verts[i] - p).normalize();
        let b = (verts[(i + 1) % k] - p).normalize();
        let c = a.cross(b);
        sum += a.dot(b).clamp(-1.0, 1.0).acos() * n.dot(c) / c.length();
    }
    0.5 * l * sum.abs()
}

/// A sphere light of radius r and radiance L whose centre is d above the foot point of a Lambert floor:
/// the floor there reflects ρ/π·E with E = π·L·(r/d)² (the π·L·sin²θmax). The camera looks at the
/// foot point from the side through a 0.5° field of view.
fn sphere_over_floor(r: f64, l: f64, d: f64) -> (Scene, f64) {
    let df = d as f32;
    let mut s = floor_scene("sphere-over-floor", 10.0 * df, Vec3::new(1.5 * df, df, 0.0), Vec3::ZERO, 0.5);
    s.materials.push(Material::emitter("light", Vec3::splat(l as f32)));
    s.spheres.push(Sphere { center: Vec3::new(0.0, df, 0.0), radius: r as f32, material: 1 });
    let e = sphere_floor_mean(&s, l);
    (s, e)
}

/// The exact image mean of a Lambert ρ floor (y = 0) under the scene's first sphere light of radiance `l`
/// (wholly above the floor): ρ/π·E with E = π·L·(r/D)²·cosβ at each point the pixels see. Not the foot point's
/// value: across the 0.5° view E falls by ~1.3e-4, which the old foot-point answer called a bias.
fn sphere_floor_mean(s: &Scene, l: f64) -> f64 {
    let (c, r) = (s.spheres[0].center.as_dvec3(), s.spheres[0].radius as f64);
    floor_image_mean(s, |p| {
        let v = c - p;
        RHO * l * r * r * v.y / v.length().powi(3)
    })
}

/// The mean over the film (SIZE², pixel jitter uniform over each pixel, as the renderer's camera) of `f` at the
/// floor (y = 0) point each camera ray meets: a 6×6 midpoint rule per pixel, exact to ~1e-9 for smooth `f`.
fn floor_image_mean(s: &Scene, f: impl Fn(DVec3) -> f64) -> f64 {
    let cam = &s.camera;
    let (fw, up0) = (cam.forward.as_dvec3().normalize(), cam.up.as_dvec3());
    let right = fw.cross(up0).normalize();
    let up = right.cross(fw);
    let o = cam.position.as_dvec3();
    let tan_half = (0.5 * cam.vfov as f64).tan();
    let k = 6;
    let mut sum = 0.0;
    for py in 0..SIZE {
        for px in 0..SIZE {
            for j in 0..k * k {
                let jx = ((j % k) as f64 + 0.5) / k as f64;
                let jy = ((j / k) as f64 + 0.5) / k as f64;
                let x = (2.0 * (px as f64 + jx) / SIZE as f64 - 1.0) * tan_half;
                let y = (1.0 - 2.0 * (py as f64 + jy) / SIZE as f64) * tan_half;
                let d = fw + x * right + y * up;
                let t = -o.y / d.y;
                sum += if t > 0.0 { f(o + t * d) } else { 0.0 };
            }
        }
    }
    sum / (SIZE * SIZE * k * k) as f64
}

/// A polygon light (quad or triangle, facing down) centred `h` above the foot point; `size` its side. The
/// camera sits under it at half its height.
fn polygon_over_floor(triangle: bool, size: f64, h: f64, l: f64) -> (Scene, f64) {
    let (hf, sf) = (h as f32, size as f32);
    let cam_h = 0.5 * hf.min(sf.max(hf));
    let mut s = floor_scene(
        "polygon-over-floor",
        (10.0 * sf).max(10.0 * hf),
        Vec3::new(1.5 * cam_h, cam_h, 0.0),
        Vec3::ZERO,
        0.5,
    );
    s.materials.push(Material::emitter("light", Vec3::splat(l as f32)));
    let corner = Vec3::new(-0.5 * sf, hf, -0.5 * sf);
    let (eu, ev) = (Vec3::new(sf, 0.0, 0.0), Vec3::new(0.0, 0.0, sf));
    let verts: Vec<DVec3> = if triangle {
        // Counter-clockwise seen from below: front faces −Y.
        let p = vec![corner, corner + eu, corner + ev];
        s.meshes.push(mesh("light", p.clone(), vec![[0, 1, 2]], 1));
        p.iter().map(|v| v.as_dvec3()).collect()
    } else {
        s.quads.push(Quad { corner, edge_u: eu, edge_v: ev, material: 1 });
        vec![corner, corner + eu, corner + eu + ev, corner + ev].iter().map(|v| v.as_dvec3()).collect()
    };
    let e = floor_image_mean(&s, |p| RHO / PI * polygon_irradiance(p, DVec3::Y, &verts, l));
    (s, e)
}

/// A closed sphere mesh (an octahedron subdivided `levels` times, normalised) of radius r around c, its
/// triangles facing inwards, Lambert ρ and emitting Le, with the camera inside. Path tracing converges to
/// Le·Σ ρ^k over the path lengths traced; a ray that slipped through a shared vertex or edge would escape to
/// the black outside, and one that re-hit its own triangle would break the count.
fn closed_emitting_sphere(c: DVec3, r: f64, levels: u32) -> Scene {
    let mut verts: Vec<DVec3> = vec![DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y, DVec3::Z, -DVec3::Z];
    let mut tris: Vec<[u32; 3]> =
        vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
    for _ in 0..levels {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut next = Vec::new();
        for t in &tris {
            let mut m = [0u32; 3];
            for e in 0..3 {
                let (a, b) = (t[e], t[(e + 1) % 3]);
                let key = (a.min(b), a.max(b));
                m[e] = *mid.entry(key).or_insert_with(|| {
                    verts.push((verts[a as usize] + verts[b as usize]).normalize());
                    verts.len() as u32 - 1
                });
            }
            next.extend([[t[0], m[0], m[2]], [m[0], t[1], m[1]], [m[2], m[1], t[2]], [m[0], m[1], m[2]]]);
        }
        tris = next;
    }
    // Outward counter-clockwise above; reverse for inward-facing fronts.
    let tris: Vec<[u32; 3]> = tris.into_iter().map(|[a, b, c]| [a, c, b]).collect();
    let positions: Vec<Vec3> = verts.iter().map(|v| (c + *v * r).as_vec3()).collect();
    let mut s = Scene { name: "closed-sphere".into(), ..Default::default() };
    let mut m = Material::lambert("inside", Vec3::splat(RHO as f32));
    m.emission = Vec3::ONE;
    s.materials.push(m);
    s.meshes.push(mesh("sphere", positions, tris, 0));
    let eye = (c + DVec3::new(0.1, 0.2, 0.3) * r).as_vec3();
    s.camera = Camera::look_at(eye, (c + DVec3::new(0.0, -0.3, -1.0) * r).as_vec3(), Vec3::Y, 70.0);
    s
}

/// Expected radiance inside the closed emitting sphere with `max_depth` bounces: Le·(1 − ρ^(D+1))/(1 − ρ).
fn closed_sphere_expected(max_depth: u32) -> f64 {
    (1.0 - RHO.powi(max_depth as i32 + 1)) / (1.0 - RHO)
}

/// A constant-environment furnace around a sphere of `material`.
fn furnace_with(material: Material) -> Scene {
    let mut s = builtin("furnace");
    s.materials[0] = material;
    s
}

/// Writes an equirectangular EXR of `texels` (w×h) to the temp directory and loads it through the same
/// loader as `--env` (which sanitises it); returns the environment and the loader's warnings.
fn env_from_texels(name: &str, w: u32, h: u32, texels: &[[f32; 3]]) -> Result<(Environment, Vec<String>), LabError> {
    let dir = std::env::temp_dir().join(format!("mislab-stress-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| LabError::Input(format!("{}: {e}", dir.display())))?;
    let path = dir.join(format!("{name}.exr"));
    let img = image::Rgb32FImage::from_fn(w, h, |x, y| image::Rgb(texels[(y * w + x) as usize]));
    let loaded = img
        .save_with_format(&path, image::ImageFormat::OpenExr)
        .map_err(|e| LabError::Input(format!("{}: {e}", path.display())))
        .and_then(|()| scene::envmap::load_envmap(&path).map_err(LabError::from));
    // Nothing is left behind, whether or not it loaded (the folder goes once it is empty).
    let _ = std::fs::remove_file(&path);
    let _ = std::fs::remove_dir(&dir);
    let (map, warnings) = loaded?;
    Ok((Environment::Map { map: Arc::new(map), scale: 1.0, rotation: 0.0 }, warnings))
}

/// A camera-facing emitter of radiance `l` that fills the view (for accumulation cases).
fn emitter_wall(l: f32) -> Scene {
    let mut s = Scene { name: "wall".into(), ..Default::default() };
    s.camera = Camera::look_at(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, Vec3::Y, 10.0);
    s.materials.push(Material::emitter("wall", Vec3::splat(l)));
    s.quads.push(Quad {
        corner: Vec3::new(-1.0, -1.0, 0.0),
        edge_u: Vec3::new(2.0, 0.0, 0.0),
        edge_v: Vec3::new(0.0, 2.0, 0.0),
        material: 0,
    });
    s
}

/// Every stress case, in the order they run (twins before the cases that compare with them).
pub fn cases() -> Result<Vec<Case>, LabError> {
    let mut out = Vec::new();
    let mis = settings(Strategy::Mis);
    let path = Settings { mode: Mode::Path, max_depth: 4, ..mis.clone() };

    // Scale 1e-4 … 1e5 and an offset of 1e5: the same image as at scale 1 (same seed, so the same samples).
    for (mode_name, st) in [("direct", &mis), ("path", &path)] {
        let twin = format!("cornell {mode_name} scale 1");
        out.push(case("scale", &twin, builtin("cornell-box"), st.clone(), 32, Check::Finite));
        let scales: &[f32] =
            if mode_name == "direct" { &[1e-4, 1e-3, 1e-2, 1e-1, 1e1, 1e2, 1e3, 1e4, 1e5] } else { &[1e-4, 1e5] };
        for &k in scales {
            let sc = transformed(builtin("cornell-box"), k, Vec3::ZERO);
            out.push(case(
                "scale",
                format!("cornell {mode_name} scale {k:e}"),
                sc,
                st.clone(),
                32,
                Check::SameAs { twin: twin.clone(), rel_tol: 0.01 },
            ));
        }
        let sc = transformed(builtin("cornell-box"), 1.0, Vec3::splat(1e5));
        out.push(case(
            "scale",
            format!("cornell {mode_name} offset 1e5"),
            sc,
            st.clone(),
            32,
            Check::SameAs { twin: twin.clone(), rel_tol: 0.02 },
        ));
    }

    // Sphere lights of radius 1e-5 … 1e3 and radiance 1e-3 … 1e7 over a floor: ρ·L·(r/d)² at the foot point.
    for (r, l) in [
        (1e-5, 1e7),
        (1e-4, 1e5),
        (1e-3, 1e3),
        (1e-2, 1e1),
        (1e-1, 1.0),
        (1.0, 1e-1),
        (1e1, 1e-2),
        (1e2, 1e-3),
        (1e3, 1e-3),
        (1e3, 1e7),
    ] {
        let d = if r < 0.4 { 1.0 } else { 2.5 * r };
        for (label, st) in [
            ("mis solid-angle", mis.clone()),
            ("light area", Settings { light_sampling: LightSampling::Area, ..settings(Strategy::Light) }),
        ] {
            if label == "light area" && !(r == 1e-5 || r == 1e3) {
                continue;
            }
            let (sc, e) = sphere_over_floor(r, l, d);
            out.push(case(
                "sphere light",
                format!("r {r:e} L {l:e} {label}"),
                sc,
                st,
                16,
                Check::Exact { expected: e, floor: F32_FLOOR },
            ));
        }
    }
    // Solid-angle sampling's fallbacks: tiny triangles and quads (area sampling), and a huge quad nearly
    // touching the floor (a solid angle near 2π).
    for triangle in [true, false] {
        let kind = if triangle { "triangle" } else { "quad" };
        for (size, h, l) in [(1e-5, 1.0, 1e9), (1e-3, 1.0, 1e5), (1e3, 1e-3, 1.0)] {
            let (sc, e) = polygon_over_floor(triangle, size, h, l);
            // A light 1e-5 the size of its distance is 2.4e-5 (relative) off in f32, steadily (z ≈ 1300 at 16
            // spp): its own allowance, 1e-4, still far below the 1% that hid the sphere's 1.3e-4.
            let floor = if size / h < 1e-4 { 1e-4 } else { F32_FLOOR };
            out.push(case(
                "fallbacks",
                format!("{kind} light {size:e} at {h:e}"),
                sc,
                mis.clone(),
                16,
                Check::Exact { expected: e, floor },
            ));
        }
    }
    // A sphere light subtending 1e-6 sr-ish and one enclosing a large solid angle, by cone sampling only.
    let (sc, e) = sphere_over_floor(5e-4, 1e4, 1.0);
    out.push(case(
        "fallbacks",
        "sphere 5e-4 light solid-angle",
        sc,
        settings(Strategy::Light),
        16,
        Check::Exact { expected: e, floor: F32_FLOOR },
    ));
    // A sphere filling most of the sky (its cone half-angle 64°), seen from low down between it and the floor.
    let (mut sc, _) = sphere_over_floor(0.9, 1.0, 1.0);
    sc.camera = Camera::look_at(Vec3::new(1.5, 0.05, 0.0), Vec3::ZERO, Vec3::Y, 0.05);
    let e = sphere_floor_mean(&sc, 1.0);
    out.push(case(
        "fallbacks",
        "sphere light filling the sky, light solid-angle",
        sc,
        settings(Strategy::Light),
        16,
        Check::Exact { expected: e, floor: F32_FLOOR },
    ));

    // Grazing light and view (89.9°): a directional light on the Lambert floor, E = E0·cos θ.
    let graze = 89.9f64.to_radians();
    for (label, light_angle, view_grazing) in
        [("light 89.9°", graze, false), ("view 89.9°", 0.25 * PI, true), ("both 89.9°", graze, true)]
    {
        let (eye, target, fov) = if view_grazing {
            let dist = 1.0 / (0.5 * PI - graze).tan();
            (Vec3::new(0.0, 1.0, dist as f32), Vec3::ZERO, 0.01)
        } else {
            (Vec3::new(0.0, 5.0, 0.0), Vec3::ZERO, 5.0)
        };
        let mut sc = floor_scene("grazing", 1e4, eye, target, fov);
        let dir = DVec3::new(light_angle.sin(), -light_angle.cos(), 0.0).as_vec3();
        sc.punctual_lights.push(PunctualLight::Directional { direction: dir, irradiance: Vec3::splat(1000.0) });
        let e = RHO / PI * 1000.0 * light_angle.cos();
        // E is the same at every floor point: the answer is exact for the whole image.
        out.push(case("grazing", label, sc, mis.clone(), 8, Check::Exact { expected: e, floor: F32_FLOOR }));
    }
    // A quad light seen edge-on by the camera, and lit at grazing incidence from below its plane.
    let mut sc = builtin("area-vs-cosine");
    sc.camera = Camera::look_at(Vec3::new(8.0, 0.5, 0.0), Vec3::new(-3.0, 0.5, 0.0), Vec3::Y, 30.0);
    out.push(case("grazing", "quad light edge-on", sc.clone(), mis.clone(), 16, Check::Finite));
    out.push(case("grazing", "quad light edge-on, path", sc, path.clone(), 8, Check::Finite));

    // GGX roughness 0 (clamped to α = 1e-4), 1e-4 and 1 on a Fresnel-1 conductor in a white furnace: a
    // near-mirror reflects the white environment exactly; at roughness 1 light and BSDF sampling agree.
    for (label, alpha) in [("roughness 0", 0.0f32), ("roughness 1e-2", 1e-4)] {
        out.push(case(
            "ggx",
            label,
            furnace_with(Material::conductor("metal", Vec3::ONE, alpha)),
            mis.clone(),
            16,
            Check::Mean { expected: 1.0, rel_tol: 0.01 },
        ));
    }
    out.push(case(
        "ggx",
        "roughness 1e-4, path",
        furnace_with(Material::conductor("metal", Vec3::ONE, 1e-8)),
        path.clone(),
        8,
        Check::Mean { expected: 1.0, rel_tol: 0.01 },
    ));
    let rough = furnace_with(Material::conductor("metal", Vec3::ONE, 1.0));
    out.push(case("ggx", "roughness 1, mis", rough.clone(), mis.clone(), 64, Check::Finite));
    out.push(case(
        "ggx",
        "roughness 1, light",
        rough.clone(),
        settings(Strategy::Light),
        256,
        Check::SameAs { twin: "roughness 1, mis".into(), rel_tol: 0.005 },
    ));
    out.push(case(
        "ggx",
        "roughness 1, bsdf",
        rough,
        settings(Strategy::Bsdf),
        64,
        Check::SameAs { twin: "roughness 1, mis".into(), rel_tol: 0.005 },
    ));

    // Lights touching and intersecting surfaces; shading points on a light.
    for (label, center_y) in
        [("sphere light touching the floor", 0.3f32), ("sphere light half sunk into the floor", 0.0)]
    {
        let mut sc = floor_scene("touching", 5.0, Vec3::new(0.0, 2.0, 3.0), Vec3::ZERO, 40.0);
        sc.materials.push(Material::emitter("light", Vec3::splat(5.0)));
        sc.spheres.push(Sphere { center: Vec3::new(0.0, center_y, 0.0), radius: 0.3, material: 1 });
        out.push(case("contact", label, sc.clone(), mis.clone(), 16, Check::Finite));
        out.push(case("contact", format!("{label}, path"), sc, path.clone(), 8, Check::Finite));
    }
    {
        // An emissive Lambert quad lying on the floor (coplanar): its points shade themselves and sample
        // their own light at distance 0.
        let mut sc = floor_scene("on-light", 5.0, Vec3::new(0.0, 2.0, 3.0), Vec3::ZERO, 40.0);
        let mut m = Material::lambert("glowing floor", Vec3::splat(0.5));
        m.emission = Vec3::splat(2.0);
        sc.materials.push(m);
        sc.quads.push(Quad {
            corner: Vec3::new(-1.0, 0.0, -1.0),
            edge_u: Vec3::new(0.0, 0.0, 2.0),
            edge_v: Vec3::new(2.0, 0.0, 0.0),
            material: 1,
        });
        sc.materials.push(Material::emitter("light", Vec3::splat(4.0)));
        sc.spheres.push(Sphere { center: Vec3::new(0.0, 1.5, 0.0), radius: 0.2, material: 2 });
        out.push(case("contact", "shading points on a light", sc.clone(), mis.clone(), 16, Check::Finite));
        out.push(case("contact", "shading points on a light, path", sc, path.clone(), 8, Check::Finite));
    }

    // Degenerate triangles: zero-area, collinear, duplicate vertices, huge and tiny triangles side by side, in a
    // floor under a white environment (ρ everywhere the camera looks) and as emitters.
    {
        let p = |x: f32, z: f32| Vec3::new(x, 0.0, z);
        let mut positions = vec![p(-1e5, -1e5), p(1e5, -1e5), p(0.0, 1e5)]; // huge
        let mut indices = vec![[0, 2, 1]];
        for i in 0..50 {
            let x = -1.0 + 0.04 * i as f32;
            let b = positions.len() as u32;
            positions.extend([p(x, 0.0), p(x + 1e-5, 0.0), p(x, 1e-5)]); // tiny (1e-5), lying on the huge one
            positions.extend([p(x, 0.5), p(x + 0.01, 0.5), p(x + 0.02, 0.5)]); // collinear
            positions.extend([p(x, 0.7), p(x, 0.7), p(x, 0.7)]); // one point three times
            indices.extend([[b, b + 2, b + 1], [b + 3, b + 5, b + 4], [b + 6, b + 8, b + 7], [b, b, b + 1]]);
        }
        let mut sc = Scene { name: "degenerate".into(), ..Default::default() };
        sc.camera = Camera::look_at(Vec3::new(0.0, 2.0, 2.0), Vec3::ZERO, Vec3::Y, 40.0);
        sc.materials.push(Material::lambert("floor", Vec3::splat(RHO as f32)));
        sc.meshes.push(mesh("floor", positions.clone(), indices.clone(), 0));
        sc.environment = Environment::Constant(Vec3::ONE);
        out.push(case(
            "degenerate",
            "degenerate triangles in a floor",
            sc.clone(),
            mis.clone(),
            16,
            Check::Mean { expected: RHO, rel_tol: 0.01 },
        ));
        out.push(case(
            "degenerate",
            "degenerate triangles in a floor, path",
            sc.clone(),
            path.clone(),
            8,
            Check::Mean { expected: RHO, rel_tol: 0.01 },
        ));
        // The same triangles (bar the huge one) as emitters above the floor: zero-area lights get no samples.
        let mut lit = floor_scene("degenerate-lights", 5.0, Vec3::new(0.0, 2.0, 3.0), Vec3::ZERO, 40.0);
        lit.materials.push(Material::emitter("degenerate light", Vec3::splat(10.0)));
        let lifted: Vec<Vec3> =
            positions.iter().map(|v| Vec3::new(v.x, 1.0 + v.z * 1e-3, v.z.clamp(-2.0, 2.0))).collect();
        lit.meshes.push(mesh("lights", lifted, indices[1..].to_vec(), 1));
        out.push(case(
            "degenerate",
            "degenerate emissive triangles",
            lit,
            Settings { light_select: crate::render::settings::LightSelect::Power, ..mis.clone() },
            16,
            Check::Finite,
        ));
    }

    // Closed meshes at coordinates 10^U(−8, 8): rays never slip through shared vertices or re-hit their own
    // triangle. Radius ≥ 1e-3·|centre| keeps the sphere representable in f32.
    let mut rng = SplitMix(20261122);
    for k in 0..6 {
        let mag = |r: &mut SplitMix| 10f64.powf(-8.0 + 16.0 * r.next_f64());
        let c = DVec3::new(mag(&mut rng), -mag(&mut rng), mag(&mut rng)) * if k % 2 == 0 { 1.0 } else { 0.0 };
        let radius = mag(&mut rng).max(1e-3 * c.length());
        let sc = closed_emitting_sphere(c, radius, 3);
        let st = Settings { max_depth: 3, ..path.clone() };
        out.push(case(
            "watertight",
            format!("closed sphere r {radius:.1e} at |c| {:.1e}", c.length()),
            sc,
            st,
            16,
            Check::Mean { expected: closed_sphere_expected(3), rel_tol: 0.005 },
        ));
    }

    // Environment maps: Inf/NaN/negative texels (sanitised with one warning), all power in one texel, all zero.
    {
        let (w, h) = (64u32, 32u32);
        let mut bad = vec![[1.0f32; 3]; (w * h) as usize];
        bad[5] = [f32::NAN, 1.0, 1.0];
        bad[77] = [f32::INFINITY, f32::INFINITY, 0.0];
        bad[300] = [-4.0, 1.0, 1.0];
        bad[1000] = [f32::NEG_INFINITY, f32::NAN, -0.0];
        let (env, warnings) = env_from_texels("bad-texels", w, h, &bad)?;
        if warnings.len() != 1 {
            return Err(LabError::Input(format!(
                "a map with NaN/Inf/negative texels should give exactly one warning, got {warnings:?}"
            )));
        }
        let mut sc = builtin("furnace");
        sc.environment = env;
        out.push(case(
            "environment",
            "NaN/Inf/negative texels, importance",
            sc.clone(),
            mis.clone(),
            16,
            Check::Finite,
        ));
        out.push(case("environment", "NaN/Inf/negative texels, path", sc, path.clone(), 8, Check::Finite));

        let mut one = vec![[0.0f32; 3]; (w * h) as usize];
        one[(h / 3 * w + 10) as usize] = [1e6, 1e6, 1e6];
        let (env, _) = env_from_texels("one-texel", w, h, &one)?;
        let mut sc = builtin("furnace");
        sc.environment = env;
        out.push(case(
            "environment",
            "all power in one texel, importance",
            sc.clone(),
            mis.clone(),
            256,
            Check::Finite,
        ));
        out.push(case(
            "environment",
            "all power in one texel, uniform",
            sc.clone(),
            Settings { env_sampling: EnvSampling::Uniform, ..mis.clone() },
            256,
            Check::SameAs { twin: "all power in one texel, importance".into(), rel_tol: 0.02 },
        ));
        out.push(case("environment", "all power in one texel, path", sc, path.clone(), 16, Check::Finite));

        let (env, _) = env_from_texels("zero", w, h, &vec![[0.0f32; 3]; (w * h) as usize])?;
        let mut sc = builtin("furnace");
        sc.environment = env;
        out.push(case("environment", "all-zero map", sc.clone(), mis.clone(), 8, Check::Black));
        out.push(case("environment", "all-zero map, path", sc, path.clone(), 4, Check::Black));
    }

    // Accumulation: 2^24 samples of a constant pixel; a pixel whose samples span 1e-6 … 1e6.
    {
        let st = Settings { width: 1, height: 1, strategy: Strategy::Bsdf, ..Settings::default() };
        let mut c = case(
            "accumulation",
            "2^24 samples of a constant pixel",
            emitter_wall(0.7),
            st,
            1 << 24,
            Check::ExactEverywhere { value: 0.7f32 as f64, rel_tol: 1e-6 },
        );
        c.dispatch_spp = Some(1 << 10);
        out.push(c);

        let mut sc = emitter_wall(1e6);
        sc.materials.push(Material::emitter("dim", Vec3::splat(1e-6)));
        // The right half of the view is the dim emitter, just in front of the bright one.
        sc.quads.push(Quad {
            corner: Vec3::new(0.0, -1.0, 1e-3),
            edge_u: Vec3::new(1.0, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 2.0, 0.0),
            material: 1,
        });
        let st = Settings {
            width: 1,
            height: 1,
            strategy: Strategy::Bsdf,
            sampler: SamplerKind::Independent,
            ..Settings::default()
        };
        let mut c = case(
            "accumulation",
            "samples spanning 1e-6 … 1e6",
            sc,
            st,
            1 << 16,
            Check::Mean { expected: 0.5 * (1e6 + 1e-6), rel_tol: 0.0 },
        );
        c.dispatch_spp = Some(1 << 10);
        out.push(c);
    }
    Ok(out)
}

/// SplitMix64, for the reproducible random placements above.
struct SplitMix(u64);

impl SplitMix {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        (z ^ (z >> 31)) as f64 / 2f64.powi(64)
    }
}
