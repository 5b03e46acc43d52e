//! Built-in scenes, defined number for number (see `shared/scenes/*/README.md` and the lecture's area-vs-cosine slide).

mod many_lights;

use super::{Camera, Environment, Material, Mesh, Quad, Scene, Sphere};
use glam::Vec3;

/// Names of the built-in scenes; the first is the renderer's default.
pub const NAMES: &[&str] =
    &["veach-mis", "cornell-box", "furnace", "area-vs-cosine", "many-lights", "veach-mis-triangles"];

/// A built-in scene by name, or None for an unknown name.
pub fn by_name(name: &str) -> Option<Scene> {
    let scene = match name {
        "veach-mis" => veach_mis(),
        "cornell-box" => cornell_box(),
        "furnace" => furnace(),
        "area-vs-cosine" => area_vs_cosine(),
        "many-lights" => many_lights::many_lights(),
        "veach-mis-triangles" => many_lights::veach_mis_triangles(),
        _ => return None,
    };
    Some(scene)
}

/// Collects materials and hands out their indices while a scene is being built.
pub(super) struct Builder {
    pub(super) scene: Scene,
}

impl Builder {
    pub(super) fn new(name: &str, camera: Camera) -> Self {
        Builder { scene: Scene { name: name.into(), camera, ..Default::default() } }
    }
    pub(super) fn material(&mut self, m: Material) -> u32 {
        self.scene.materials.push(m);
        (self.scene.materials.len() - 1) as u32
    }
    pub(super) fn quad(&mut self, corner: Vec3, edge_u: Vec3, edge_v: Vec3, material: u32) {
        self.scene.quads.push(Quad { corner, edge_u, edge_v, material });
    }
    fn sphere(&mut self, center: Vec3, radius: f32, material: u32) {
        self.scene.spheres.push(Sphere { center, radius, material });
    }
}

/// Vertices of the four veach-mis plates as listed in the README (counter-clockwise seen from the front), with α.
pub const VEACH_PLATES: [(f32, [[f32; 3]; 4]); 4] = [
    (
        0.005,
        [[4.0, -2.70651, 0.25609], [4.0, -2.08375, -0.526323], [-4.0, -2.08375, -0.526323], [-4.0, -2.70651, 0.25609]],
    ),
    (
        0.02,
        [[4.0, -3.28825, 1.36972], [4.0, -2.83856, 0.476536], [-4.0, -2.83856, 0.476536], [-4.0, -3.28825, 1.36972]],
    ),
    (0.05, [[4.0, -3.73096, 2.70046], [4.0, -3.43378, 1.74564], [-4.0, -3.43378, 1.74564], [-4.0, -3.73096, 2.70046]]),
    (0.1, [[4.0, -3.99615, 4.0667], [4.0, -3.82069, 3.08221], [-4.0, -3.82069, 3.08221], [-4.0, -3.99615, 4.0667]]),
];

/// The veach-mis sphere lights: centre, radius, radiance (grey).
pub const VEACH_LIGHTS: [([f32; 3], f32, f32); 5] = [
    ([-3.75, 0.0, 0.0], 0.03333, 901.803),
    ([-1.25, 0.0, 0.0], 0.1, 100.0),
    ([1.25, 0.0, 0.0], 0.3, 11.1111),
    ([3.75, 0.0, 0.0], 0.9, 1.23457),
    ([10.0, 10.0, 4.0], 0.5, 800.0),
];

/// Veach's MIS scene (thesis fig. 9.2, CS667 layout) exactly as `shared/scenes/veach-mis/README.md` gives it:
/// four GGX perfect-conductor plates (Fresnel 1, α = 0.005, 0.02, 0.05, 0.1), four sphere lights of equal power
/// (r²·L ≈ 1) plus a fill light, a Lambert 0.4 floor and back wall, black background.
///
/// Each plate is the quad `v0 + s(v1 − v0) + t(v3 − v0)`; its vertices form an exact parallelogram
/// (v0 + v2 = v1 + v3) and `(v1 − v0) × (v3 − v0)` points up and towards the camera, i.e. the listed
/// counter-clockwise order's front. Floor and wall face +Y and +Z (into the scene).
fn veach_mis() -> Scene {
    let camera = Camera::look_at(Vec3::new(0.0, 2.0, 15.0), Vec3::new(0.0, -2.0, 2.5), Vec3::Y, 41.0108);
    let mut b = Builder::new("veach-mis", camera);
    for (i, (alpha, v)) in VEACH_PLATES.iter().enumerate() {
        let m = b.material(Material::conductor(&format!("plate{}", i + 1), Vec3::ONE, *alpha));
        let [v0, v1, _, v3] = v.map(Vec3::from);
        b.quad(v0, v1 - v0, v3 - v0, m);
    }
    let diffuse = b.material(Material::lambert("diffuse", Vec3::splat(0.4)));
    let floor_y = -4.14615;
    // Floor: edges +Z then +X, so the front (Z × X = +Y) faces up.
    b.quad(Vec3::new(-10.0, floor_y, -10.0), Vec3::new(0.0, 0.0, 20.0), Vec3::new(20.0, 0.0, 0.0), diffuse);
    // Back wall: edges +X then +Y, front +Z (towards the camera).
    b.quad(Vec3::new(-10.0, -10.0, -2.0), Vec3::new(20.0, 0.0, 0.0), Vec3::new(0.0, 20.0, 0.0), diffuse);
    for (i, (c, r, l)) in VEACH_LIGHTS.iter().enumerate() {
        let m = b.material(Material::emitter(&format!("light{}", i + 1), Vec3::splat(*l)));
        b.sphere(Vec3::from(*c), *r, m);
    }
    b.scene
}

/// Positions of the Cornell box's `shortbox` (24 vertices: 4 per face, so flat normals need no splitting).
pub const CORNELL_SHORTBOX: [[f32; 3]; 24] = [
    [-0.0460751, 0.6, 0.573007],
    [-0.0460751, 0.0, 0.573007],
    [0.124253, 0.0, 0.00310463],
    [0.124253, 0.6, 0.00310463],
    [0.533009, 0.0, 0.746079],
    [0.533009, 0.6, 0.746079],
    [0.703337, 0.6, 0.176177],
    [0.703337, 0.0, 0.176177],
    [0.533009, 0.6, 0.746079],
    [-0.0460751, 0.6, 0.573007],
    [0.124253, 0.6, 0.00310463],
    [0.703337, 0.6, 0.176177],
    [0.703337, 0.0, 0.176177],
    [0.124253, 0.0, 0.00310463],
    [-0.0460751, 0.0, 0.573007],
    [0.533009, 0.0, 0.746079],
    [0.533009, 0.0, 0.746079],
    [-0.0460751, 0.0, 0.573007],
    [-0.0460751, 0.6, 0.573007],
    [0.533009, 0.6, 0.746079],
    [0.703337, 0.6, 0.176177],
    [0.124253, 0.6, 0.00310463],
    [0.124253, 0.0, 0.00310463],
    [0.703337, 0.0, 0.176177],
];

/// Positions of the Cornell box's `tallbox` (the README's values, including its 0.0906493 / 0.0906492 mismatch).
pub const CORNELL_TALLBOX: [[f32; 3]; 24] = [
    [-0.720444, 1.2, -0.473882],
    [-0.720444, 0.0, -0.473882],
    [-0.146892, 0.0, -0.673479],
    [-0.146892, 1.2, -0.673479],
    [-0.523986, 0.0, 0.0906493],
    [-0.523986, 1.2, 0.0906492],
    [0.0495656, 1.2, -0.108948],
    [0.0495656, 0.0, -0.108948],
    [-0.523986, 1.2, 0.0906492],
    [-0.720444, 1.2, -0.473882],
    [-0.146892, 1.2, -0.673479],
    [0.0495656, 1.2, -0.108948],
    [0.0495656, 0.0, -0.108948],
    [-0.146892, 0.0, -0.673479],
    [-0.720444, 0.0, -0.473882],
    [-0.523986, 0.0, 0.0906493],
    [-0.523986, 0.0, 0.0906493],
    [-0.720444, 0.0, -0.473882],
    [-0.720444, 1.2, -0.473882],
    [-0.523986, 1.2, 0.0906492],
    [0.0495656, 1.2, -0.108948],
    [-0.146892, 1.2, -0.673479],
    [-0.146892, 0.0, -0.673479],
    [0.0495656, 0.0, -0.108948],
];

/// The triangle list shared by both boxes. Its winding is counter-clockwise seen from outside: every face's
/// `(b − a) × (c − a)` points away from its box's centre (checked by the tests), so geometric normals face out.
pub const CORNELL_BOX_INDICES: [[u32; 3]; 12] = [
    [0, 2, 1],
    [0, 3, 2],
    [4, 6, 5],
    [4, 7, 6],
    [8, 10, 9],
    [8, 11, 10],
    [12, 14, 13],
    [12, 15, 14],
    [16, 18, 17],
    [16, 19, 18],
    [20, 22, 21],
    [20, 23, 22],
];

/// Bitterli's Cornell box as `shared/scenes/cornell-box/README.md` gives it: five Lambert walls (quads facing
/// inward), two white boxes (triangle meshes with the README's vertices and indices) and a one-sided area light at
/// y = 1.98 emitting (17, 12, 4) downward.
fn cornell_box() -> Scene {
    let camera = Camera {
        position: Vec3::new(0.0, 1.0, 6.8),
        forward: Vec3::NEG_Z,
        up: Vec3::Y,
        vfov: 19.5f32.to_radians(),
        window: Camera::FULL_WINDOW,
    };
    let mut b = Builder::new("cornell-box", camera);
    let white = b.material(Material::lambert("white", Vec3::new(0.725, 0.71, 0.68)));
    let red = b.material(Material::lambert("red", Vec3::new(0.63, 0.065, 0.05)));
    let green = b.material(Material::lambert("green", Vec3::new(0.14, 0.45, 0.091)));
    let light = b.material(Material::emitter("light", Vec3::new(17.0, 12.0, 4.0)));
    let (x2, y2, z2) = (Vec3::X * 2.0, Vec3::Y * 2.0, Vec3::Z * 2.0);
    // Edge order picks the front side: Z×X = +Y, X×Z = −Y, X×Y = +Z, Y×Z = +X, Z×Y = −X.
    b.quad(Vec3::new(-1.0, 0.0, -1.0), z2, x2, white); // floor, faces up
    b.quad(Vec3::new(-1.0, 2.0, -1.0), x2, z2, white); // ceiling, faces down
    b.quad(Vec3::new(-1.0, 0.0, -1.0), x2, y2, white); // back wall, faces +Z
    b.quad(Vec3::new(-1.0, 0.0, -1.0), y2, z2, red); // left wall, faces +X
    b.quad(Vec3::new(1.0, 0.0, -1.0), z2, y2, green); // right wall, faces −X
    for (name, positions) in [("shortbox", &CORNELL_SHORTBOX), ("tallbox", &CORNELL_TALLBOX)] {
        let positions: Vec<Vec3> = positions.iter().map(|p| Vec3::from(*p)).collect();
        let indices = CORNELL_BOX_INDICES.to_vec();
        let normals = vertex_normals(&positions, &indices);
        b.scene.meshes.push(Mesh { name: name.into(), positions, normals, uvs: Vec::new(), indices, material: white });
    }
    // The light, 0.47 × 0.38, edges +X then +Z so that its emitting front faces −Y.
    b.quad(Vec3::new(-0.24, 1.98, -0.22), Vec3::new(0.47, 0.0, 0.0), Vec3::new(0.0, 0.0, 0.38), light);
    b.scene
}

/// The white furnace: a Lambert sphere of albedo 1 (radius 1 at the origin) inside a uniform environment of
/// radiance 1, seen from (0, 0, 4) with a 40° vertical field of view (the sphere fills about 70% of the height).
/// With energy conservation and no absorption every pixel, sphere or background, converges to exactly 1; any
/// deviation (beyond noise) is a bias in the estimator.
fn furnace() -> Scene {
    let camera = Camera::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, 40.0);
    let mut b = Builder::new("furnace", camera);
    let white = b.material(Material::lambert("white", Vec3::ONE));
    b.sphere(Vec3::ZERO, 1.0, white);
    b.scene.environment = Environment::Constant(Vec3::ONE);
    b.scene
}

/// The lecture's "area-vs-cosine" slide: a large Lambert 0.5 floor (20 × 20 at y = 0) under a 4 × 4 area light of
/// radiance 2 hanging only 0.5 above it (x ∈ [−5, −1], z ∈ [−2, 2], facing down). The camera at (4, 3.5, 6) looks at
/// (0, 0, −0.5) with a 60° vertical field of view: the light sits on the left, the floor away from it fills the right.
///
/// One-sample relative standard deviations for these numbers (computed by quadrature over the light):
/// - Left, under and just in front of the light: the light is 8× wider than it is high, so light-area sampling's
///   estimator `L·ρ/π·cosθ·cosθ'·A/r²` swings from 64·ρL/π (light point straight above) to ~0 (far corners): the
///   r⁻² term gives relative std 2.5–3.6, while cosine sampling hits the light 30–95% of the time (0.2–1.5).
/// - Right, 3–6 units from the light: the light covers ~0.1% of the projected hemisphere, so cosine sampling almost
///   never hits it (relative std 30–45: black with rare fireflies of value ρL = 1), while area sampling is smooth
///   (0.7–0.8 of a tiny value, ~0.001).
/// - Radiance 2 keeps the floor under the light just below 1 (≈ 0.95), so the area-sampling noise is not clipped.
///
/// At 16 spp in a 512² render both effects are plain to see (checked with a small CPU reference of both estimators).
/// The light's back is black (emitters are one-sided) and hides the floor directly beneath it; the floor around its
/// near edges shows the r⁻² problem.
fn area_vs_cosine() -> Scene {
    let camera = Camera::look_at(Vec3::new(4.0, 3.5, 6.0), Vec3::new(0.0, 0.0, -0.5), Vec3::Y, 60.0);
    let mut b = Builder::new("area-vs-cosine", camera);
    let floor = b.material(Material::lambert("floor", Vec3::splat(0.5)));
    let light = b.material(Material::emitter("light", Vec3::splat(2.0)));
    // Floor: edges +Z then +X → front +Y.
    b.quad(Vec3::new(-10.0, 0.0, -10.0), Vec3::new(0.0, 0.0, 20.0), Vec3::new(20.0, 0.0, 0.0), floor);
    // Light: edges +X then +Z → front −Y (emitting onto the floor).
    b.quad(Vec3::new(-5.0, 0.5, -2.0), Vec3::new(4.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 4.0), light);
    b.scene
}

/// Area-weighted vertex normals from the triangles' winding (each triangle's normal points to the side it is
/// counter-clockwise from). Unshared vertices therefore get flat face normals. Vertices used by no triangle, or only
/// by degenerate ones, get +Y so that every normal stays unit length.
pub(super) fn vertex_normals(positions: &[Vec3], indices: &[[u32; 3]]) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; positions.len()];
    for t in indices {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        // Unnormalised cross product = 2 × area × unit normal, i.e. area weighting for free.
        let face = (b - a).cross(c - a);
        for &i in t {
            n[i as usize] += face;
        }
    }
    n.into_iter().map(|v| v.try_normalize().unwrap_or(Vec3::Y)).collect()
}
