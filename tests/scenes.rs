//! Scene tests: built-in scenes against their READMEs, the TOML format and its errors, and environment-map loading.

mod scratch;
use glam::{Vec3, Vec4Swizzles};
use mislab::scene::envmap::{direction_to_equirect, equirect_direction, load_envmap};
use mislab::scene::{self, builtin, Environment, LoadOptions, Material, PunctualLight, Quad, Scene};
use scratch::Scratch;
use std::path::{Path, PathBuf};

const TESTDATA_ENV: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/testdata/env");
const GLTF_SCENES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/scenes");

fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes")
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol
}

fn quad_normal(q: &Quad) -> Vec3 {
    q.edge_u.cross(q.edge_v).normalize()
}

fn quad_vertices(q: &Quad) -> [Vec3; 4] {
    [q.corner, q.corner + q.edge_u, q.corner + q.edge_u + q.edge_v, q.corner + q.edge_v]
}

fn quad_center(q: &Quad) -> Vec3 {
    q.corner + 0.5 * (q.edge_u + q.edge_v)
}

/// A scratch directory unique to this test process and `name`.
fn scratch(name: &str) -> Scratch {
    Scratch::new("scenes", name)
}

// ---------------------------------------------------------------------------------------------------------------
// Built-in scenes.

#[test]
fn every_builtin_loads() {
    assert_eq!(builtin::NAMES[0], "veach-mis", "veach-mis is the default scene");
    for &name in builtin::NAMES {
        let s = builtin::by_name(name).unwrap_or_else(|| panic!("{name} is listed but does not load"));
        assert_eq!(s.name, name);
        assert!(s.has_lights(), "{name} has no lights");
        assert!(s.warnings.is_empty(), "{name}: {:?}", s.warnings);
        // Through the public entry point too.
        assert_eq!(scene::load(name, &LoadOptions::default()).unwrap().name, name);
        // Every material index is valid.
        let n = s.materials.len() as u32;
        assert!(s.quads.iter().all(|q| q.material < n) && s.spheres.iter().all(|q| q.material < n));
        assert!(s.meshes.iter().all(|m| m.material < n && m.normals.len() == m.positions.len()));
    }
    assert!(builtin::by_name("no-such-scene").is_none());
    assert!(builtin::by_name("").is_none());
}

#[test]
fn veach_mis_matches_readme() {
    let s = builtin::by_name("veach-mis").unwrap();
    assert_eq!((s.quads.len(), s.spheres.len(), s.meshes.len()), (6, 5, 0));
    assert!(matches!(s.environment, Environment::None));
    assert!(s.punctual_lights.is_empty());

    let c = &s.camera;
    assert_eq!(c.position, Vec3::new(0.0, 2.0, 15.0));
    assert!(close(c.forward, (Vec3::new(0.0, -2.0, 2.5) - c.position).normalize(), 1e-6));
    assert_eq!(c.up, Vec3::Y);
    assert!((c.vfov.to_degrees() - 41.0108).abs() < 1e-4);
    assert!((c.vfov - 2.0 * (1.5 * 14f32.to_radians().tan()).atan()).abs() < 1e-5);

    // Plates: the README's vertices, in its counter-clockwise order, within 1e-5; fronts face camera and lights.
    for (i, (alpha, verts)) in builtin::VEACH_PLATES.iter().enumerate() {
        let q = &s.quads[i];
        for (got, want) in quad_vertices(q).iter().zip(verts) {
            assert!(close(*got, Vec3::from(*want), 1e-5), "plate{}: {got} vs {want:?}", i + 1);
        }
        let [v0, v1, v2, v3] = verts.map(Vec3::from);
        assert!(close(v0 + v2, v1 + v3, 1e-5), "plate{} is not a parallelogram", i + 1);
        let n = quad_normal(q);
        assert!(n.dot(c.position - quad_center(q)) > 0.0, "plate{} faces away from the camera", i + 1);
        for l in &s.spheres[..4] {
            assert!(n.dot(l.center - quad_center(q)) > 0.0, "plate{} faces away from a light", i + 1);
        }
        let m = &s.materials[q.material as usize];
        assert_eq!((m.base_color, m.metallic, m.emission), (Vec3::ONE, 1.0, Vec3::ZERO));
        assert!((m.alpha() - alpha).abs() < 1e-6 * alpha.max(1e-3), "plate{} α {} vs {alpha}", i + 1, m.alpha());
    }
    let (floor, wall) = (&s.quads[4], &s.quads[5]);
    assert!(close(quad_normal(floor), Vec3::Y, 1e-6) && close(quad_normal(wall), Vec3::Z, 1e-6));
    assert!(quad_vertices(floor).iter().all(|v| v.y == -4.14615 && v.x.abs() == 10.0 && v.z.abs() == 10.0));
    assert!(quad_vertices(wall).iter().all(|v| v.z == -2.0 && v.x.abs() == 10.0 && v.y.abs() == 10.0));
    for q in [floor, wall] {
        assert_eq!(s.materials[q.material as usize], Material::lambert("diffuse", Vec3::splat(0.4)));
    }

    for (sphere, (center, radius, radiance)) in s.spheres.iter().zip(builtin::VEACH_LIGHTS) {
        assert_eq!((sphere.center, sphere.radius), (Vec3::from(center), radius));
        let m = &s.materials[sphere.material as usize];
        assert_eq!((m.emission, m.base_color), (Vec3::splat(radiance), Vec3::ZERO));
    }
    // The four small lights have equal power (L·r² ≈ 1).
    for (_, r, l) in &builtin::VEACH_LIGHTS[..4] {
        assert!((l * r * r - 1.0).abs() < 2e-3);
    }
}

#[test]
fn cornell_box_matches_readme() {
    let s = builtin::by_name("cornell-box").unwrap();
    assert_eq!((s.quads.len(), s.spheres.len(), s.meshes.len(), s.triangle_count()), (6, 0, 2, 24));
    assert!(matches!(s.environment, Environment::None));
    let c = &s.camera;
    assert_eq!((c.position, c.forward, c.up), (Vec3::new(0.0, 1.0, 6.8), Vec3::NEG_Z, Vec3::Y));
    assert!((c.vfov.to_degrees() - 19.5).abs() < 1e-5);

    let mat = |q: &Quad| s.materials[q.material as usize].clone();
    let white = Vec3::new(0.725, 0.71, 0.68);
    // Walls: inside the box, facing its centre.
    let box_center = Vec3::new(0.0, 1.0, 0.0);
    for q in &s.quads[..5] {
        assert!(quad_normal(q).dot(box_center - quad_center(q)) > 0.9, "a wall faces outward");
        assert!(quad_vertices(q).iter().all(|v| v.abs().max_element() <= 2.0 && v.x.abs() <= 1.0 && v.z.abs() <= 1.0));
    }
    let wall_at = |n: Vec3| s.quads[..5].iter().find(|q| close(quad_normal(q), n, 1e-6)).unwrap();
    assert_eq!(mat(wall_at(Vec3::X)).base_color, Vec3::new(0.63, 0.065, 0.05), "left wall (x = −1) is red");
    assert_eq!(mat(wall_at(Vec3::NEG_X)).base_color, Vec3::new(0.14, 0.45, 0.091), "right wall is green");
    for n in [Vec3::Y, Vec3::NEG_Y, Vec3::Z] {
        assert_eq!(mat(wall_at(n)).base_color, white);
    }
    assert!(quad_vertices(wall_at(Vec3::X)).iter().all(|v| v.x == -1.0));
    assert!(quad_vertices(wall_at(Vec3::NEG_Y)).iter().all(|v| v.y == 2.0));

    // Light: y = 1.98, x ∈ [−0.24, 0.23], z ∈ [−0.22, 0.16], front −Y, radiance (17, 12, 4), one quad.
    let light = &s.quads[5];
    assert!(close(quad_normal(light), Vec3::NEG_Y, 1e-6));
    let vs = quad_vertices(light);
    let (lo, hi) = vs.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), v| (lo.min(*v), hi.max(*v)));
    assert!(close(lo, Vec3::new(-0.24, 1.98, -0.22), 1e-6) && close(hi, Vec3::new(0.23, 1.98, 0.16), 1e-6));
    assert_eq!(mat(light).emission, Vec3::new(17.0, 12.0, 4.0));
    assert_eq!(s.quads.iter().filter(|q| mat(q).is_emissive()).count(), 1);

    // Boxes: the README's vertices and indices, outward winding, flat unit normals equal to the face normals.
    for (mesh, (name, verts)) in
        s.meshes.iter().zip([("shortbox", &builtin::CORNELL_SHORTBOX), ("tallbox", &builtin::CORNELL_TALLBOX)])
    {
        assert_eq!(mesh.name, name);
        assert_eq!(mesh.positions, verts.map(Vec3::from).to_vec());
        assert_eq!(mesh.indices, builtin::CORNELL_BOX_INDICES.to_vec());
        assert_eq!(s.materials[mesh.material as usize].base_color, white);
        let centroid = mesh.positions.iter().sum::<Vec3>() / mesh.positions.len() as f32;
        for t in &mesh.indices {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let n = (b - a).cross(c - a).normalize();
            assert!(n.dot((a + b + c) / 3.0 - centroid) > 0.0, "{name}: triangle {t:?} winds inward");
            for &i in t {
                assert!(close(mesh.normals[i as usize], n, 1e-4), "{name}: normal of vertex {i}");
            }
        }
    }
}

#[test]
fn furnace_is_a_white_furnace() {
    let s = builtin::by_name("furnace").unwrap();
    assert_eq!((s.spheres.len(), s.quads.len(), s.meshes.len()), (1, 0, 0));
    let sphere = &s.spheres[0];
    assert_eq!((sphere.center, sphere.radius), (Vec3::ZERO, 1.0));
    let m = &s.materials[sphere.material as usize];
    assert_eq!((m.base_color, m.metallic, m.specular, m.emission), (Vec3::ONE, 0.0, 0.0, Vec3::ZERO));
    assert!(matches!(s.environment, Environment::Constant(c) if c == Vec3::ONE));
    // The whole sphere is in view, with background around it.
    let c = &s.camera;
    let angular_radius = (sphere.radius / (sphere.center - c.position).length()).asin();
    assert!(c.forward.dot((sphere.center - c.position).normalize()) > 0.9999);
    assert!(angular_radius < 0.5 * c.vfov && angular_radius > 0.25 * c.vfov);
}

#[test]
fn area_vs_cosine_shows_both_regions() {
    let s = builtin::by_name("area-vs-cosine").unwrap();
    assert_eq!((s.quads.len(), s.spheres.len(), s.meshes.len()), (2, 0, 0));
    let floor = s.quads.iter().find(|q| !s.materials[q.material as usize].is_emissive()).unwrap();
    let light = s.quads.iter().find(|q| s.materials[q.material as usize].is_emissive()).unwrap();
    assert!(close(quad_normal(floor), Vec3::Y, 1e-6) && close(quad_normal(light), Vec3::NEG_Y, 1e-6));
    assert_eq!(s.materials[floor.material as usize].base_color, Vec3::splat(0.5));
    let height = light.corner.y - floor.corner.y;
    let size = light.edge_u.length().min(light.edge_v.length());
    assert!(height > 0.0 && size / height >= 4.0, "the light must be large and close to the floor");

    // Project into a square film: the floor next to the light is on the left, the far floor on the right.
    let c = &s.camera;
    let (r, u, f) = c.frame();
    let t = (0.5 * c.vfov).tan();
    let film = |p: Vec3| {
        let d = p - c.position;
        (d.dot(r) / d.dot(f) / t, d.dot(u) / d.dot(f) / t)
    };
    let (x, y) = film(quad_center(light));
    assert!((-1.0..-0.2).contains(&x) && y.abs() < 1.0, "light centre at film ({x}, {y})");
    let near_light = Vec3::new(-2.0, 0.0, 2.5); // floor just in front of the light's near edge
    let (x, y) = film(near_light);
    assert!((-1.0..-0.2).contains(&x) && y.abs() < 1.0, "near-light floor at film ({x}, {y})");
    // The floor on the right of the frame is several light-heights away from the light.
    for (fx, fy) in [(0.7, 0.2), (0.7, -0.5)] {
        let d = (f + r * fx * t + u * fy * t).normalize();
        let p = c.position + d * (-c.position.y / d.y);
        assert!(d.y < 0.0 && p.x.abs() < 10.0 && p.z.abs() < 10.0, "film ({fx}, {fy}) misses the floor");
        assert!(
            p.x - (light.corner.x + light.edge_u.x) > 6.0 * height,
            "film ({fx}, {fy}) is floor at {p}, too near the light"
        );
    }
}

// ---------------------------------------------------------------------------------------------------------------
// TOML scenes.

/// Material properties a quad/sphere/mesh resolves to, for comparing scenes with differently ordered materials.
fn material_of(s: &Scene, index: u32) -> (Vec3, f32, f32, f32, Vec3) {
    let m = &s.materials[index as usize];
    (m.base_color, m.metallic, m.roughness, m.specular, m.emission)
}

/// A quad as a set of vertices plus its front normal, independent of which corner and edge order describe it.
fn same_quad(a: &Quad, b: &Quad) -> bool {
    let (va, vb) = (quad_vertices(a), quad_vertices(b));
    close(quad_normal(a), quad_normal(b), 1e-5) && va.iter().all(|p| vb.iter().any(|q| close(*p, *q, 1e-5)))
}

fn assert_same_scene(toml: &Scene, builtin: &Scene) {
    let who = &toml.name;
    assert_eq!(toml.camera.position, builtin.camera.position, "{who}: camera");
    assert!(
        close(toml.camera.forward, builtin.camera.forward, 1e-6)
            && (toml.camera.vfov - builtin.camera.vfov).abs() < 1e-6,
        "{who}: camera"
    );
    assert_eq!(
        (toml.quads.len(), toml.spheres.len(), toml.meshes.len()),
        (builtin.quads.len(), builtin.spheres.len(), builtin.meshes.len()),
        "{who}"
    );
    for b in &builtin.quads {
        let t = toml.quads.iter().find(|t| same_quad(t, b)).unwrap_or_else(|| panic!("{who}: no quad like {b:?}"));
        assert_eq!(material_of(toml, t.material), material_of(builtin, b.material), "{who}: material of {b:?}");
    }
    for (t, b) in toml.spheres.iter().zip(&builtin.spheres) {
        assert_eq!((t.center, t.radius), (b.center, b.radius), "{who}");
        assert_eq!(material_of(toml, t.material), material_of(builtin, b.material), "{who}");
    }
    for (t, b) in toml.meshes.iter().zip(&builtin.meshes) {
        assert_eq!((&t.name, &t.positions, &t.indices), (&b.name, &b.positions, &b.indices), "{who}");
        assert!(t.normals.iter().zip(&b.normals).all(|(x, y)| close(*x, *y, 1e-6)), "{who}");
        assert_eq!(material_of(toml, t.material), material_of(builtin, b.material), "{who}");
    }
    match (&toml.environment, &builtin.environment) {
        (Environment::None, Environment::None) => {}
        (Environment::Constant(a), Environment::Constant(b)) => assert_eq!(a, b),
        _ => panic!("{who}: environments differ"),
    }
}

#[test]
fn toml_versions_of_builtins_match() {
    for name in ["veach-mis", "cornell-box", "furnace", "area-vs-cosine"] {
        let path = assets().join(format!("{name}.toml"));
        let t = scene::load(path.to_str().unwrap(), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(t.name, name);
        assert!(t.warnings.is_empty(), "{name}: {:?}", t.warnings);
        assert_same_scene(&t, &builtin::by_name(name).unwrap());
    }
}

#[test]
fn every_asset_scene_loads() {
    let mut n = 0;
    for entry in std::fs::read_dir(assets()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let s = scene::load(path.to_str().unwrap(), &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
            assert!(s.has_lights(), "{}", path.display());
            n += 1;
        }
    }
    assert!(n >= 5, "expected the built-in TOMLs and the environment-map example");
}

#[test]
fn env_map_example_loads() {
    let s = scene::load(assets().join("sky-spheres.toml").to_str().unwrap(), &LoadOptions::default()).unwrap();
    let Environment::Map { map, scale, rotation } = &s.environment else { panic!("no environment map") };
    assert_eq!((map.width, map.height), (SKY_SIZE.0, SKY_SIZE.1));
    assert_eq!(map.path, assets().join("sky.hdr"), "the map path is resolved against the TOML's directory");
    assert_eq!(*scale, 1.0);
    assert!((rotation.to_degrees() - 30.0).abs() < 1e-4);
    assert_eq!((s.spheres.len(), s.quads.len()), (3, 1));
    let kinds: Vec<_> =
        s.spheres.iter().map(|x| &s.materials[x.material as usize]).map(|m| (m.metallic, m.specular)).collect();
    assert_eq!(kinds, vec![(0.0, 0.0), (1.0, 1.0), (0.0, 1.0)], "diffuse, conductor, plastic");
}

/// Writes `text` as `name` in a fresh scratch directory and loads it.
fn load_text(dir: &Path, name: &str, text: &str) -> Result<Scene, scene::SceneError> {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    scene::load(path.to_str().unwrap(), &LoadOptions::default())
}

#[test]
fn toml_features() {
    let dir = scratch("features");
    let s = load_text(
        &dir,
        "features.toml",
        r#"
[camera]
position = [1, 2, 3]
forward = [0, 0, -2]
up = [0, 1, 0]

[materials.mr]
type = "metallic-roughness"
base_color = [0.9, 0.5, 0.1]
metallic = 0
roughness = 0.25
specular = 0.5
emission = [1, 2, 3]

[materials.plain]
type = "lambert"

[[rectangle]]
center = [0, 1, 0]
normal = [1, 0, 0]
size = [2, 4]
material = "mr"

[[rectangle]]
center = [0, 0, 0]
normal = [0, 0, 1]
size = 1
u_axis = [0, 1, 0]
material = "plain"

[[mesh]]
positions = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
indices = [[0, 1, 2]]
material = "plain"

[[light]]
type = "point"
position = [0, 5, 0]
intensity = 10

[[light]]
type = "spot"
position = [0, 5, 0]
direction = [0, -3, 0]
intensity = [1, 2, 3]
inner_cone = 10
outer_cone = 20

[[light]]
type = "directional"
direction = [0, -1, -1]
irradiance = 3

[environment]
constant = [0.1, 0.2, 0.3]
"#,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.name, "features");
    assert_eq!(
        (s.camera.position, s.camera.forward, s.camera.vfov),
        (Vec3::new(1.0, 2.0, 3.0), Vec3::NEG_Z, 45f32.to_radians())
    );
    let mr = s.materials.iter().find(|m| m.name == "mr").unwrap();
    assert_eq!(
        (mr.base_color, mr.metallic, mr.roughness, mr.specular, mr.emission),
        (Vec3::new(0.9, 0.5, 0.1), 0.0, 0.25, 0.5, Vec3::new(1.0, 2.0, 3.0))
    );
    assert_eq!(s.materials.iter().find(|m| m.name == "plain").unwrap(), &Material::lambert("plain", Vec3::splat(0.8)));
    // Rectangle: centred, front along the normal, sizes along (u, v).
    let r = &s.quads[0];
    assert!(close(quad_center(r), Vec3::new(0.0, 1.0, 0.0), 1e-6) && close(quad_normal(r), Vec3::X, 1e-6));
    assert!((r.edge_u.length() - 2.0).abs() < 1e-6 && (r.edge_v.length() - 4.0).abs() < 1e-6);
    let r = &s.quads[1];
    assert!(close(r.edge_u, Vec3::Y, 1e-6) && close(quad_normal(r), Vec3::Z, 1e-6));
    assert_eq!(s.meshes[0].normals, vec![Vec3::Z; 3]);
    assert_eq!(s.meshes[0].name, "mesh1");
    assert_eq!(
        s.punctual_lights[0],
        PunctualLight::Point { position: Vec3::new(0.0, 5.0, 0.0), intensity: Vec3::splat(10.0) }
    );
    let PunctualLight::Spot { direction, intensity, inner_cone, outer_cone, .. } = &s.punctual_lights[1] else {
        panic!()
    };
    assert_eq!((*direction, *intensity), (Vec3::NEG_Y, Vec3::new(1.0, 2.0, 3.0)));
    assert!((inner_cone.to_degrees() - 10.0).abs() < 1e-4 && (outer_cone.to_degrees() - 20.0).abs() < 1e-4);
    let PunctualLight::Directional { direction, irradiance } = &s.punctual_lights[2] else { panic!() };
    assert!(close(*direction, Vec3::new(0.0, -1.0, -1.0).normalize(), 1e-6) && *irradiance == Vec3::splat(3.0));
    assert!(matches!(s.environment, Environment::Constant(c) if c == Vec3::new(0.1, 0.2, 0.3)));

    // No lights and no environment is valid (the renderer warns), and so is an empty file.
    let dark = load_text(
        &dir,
        "dark.toml",
        "[materials.a]\ntype = \"lambert\"\n[[sphere]]\ncenter = [0,0,0]\nradius = 1\nmaterial = \"a\"\n",
    )
    .unwrap();
    assert!(!dark.has_lights());
    assert!(load_text(&dir, "empty.toml", "").is_ok());
    // Reflectance above 1 is allowed but warned about.
    let hot = load_text(&dir, "hot.toml", "[materials.a]\ntype = \"lambert\"\nreflectance = 1.5\n").unwrap();
    assert_eq!(hot.warnings.len(), 1, "{:?}", hot.warnings);
}

#[test]
fn toml_errors_name_the_file_and_place() {
    let dir = scratch("errors");
    let cases: &[(&str, &str, &[&str])] = &[
        ("malformed.toml", "[camera\nposition = [0, 0, 0]\n", &["line 1"]),
        ("unknown-top.toml", "[camra]\nposition = [0, 0, 0]\n", &["line 1", "camra"]),
        ("unknown-key.toml", "[camera]\nposition = [0, 0, 0]\nfov = 40\n", &["line 3", "fov"]),
        ("unknown-mat-key.toml", "[materials.a]\ntype = \"lambert\"\nalbedo = 0.5\n", &["albedo"]),
        ("wrong-type-key.toml", "[materials.a]\ntype = \"lambert\"\nalpha = 0.5\n", &["line 1", "'a'", "alpha"]),
        ("bad-mat-type.toml", "[materials.a]\ntype = \"glass\"\n", &["glass"]),
        ("no-alpha.toml", "[materials.a]\ntype = \"conductor\"\n", &["alpha"]),
        (
            "unknown-material.toml",
            "[materials.a]\ntype = \"lambert\"\n\n[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"b\"\n",
            &["line 4", "unknown material 'b'", "defined: a"],
        ),
        ("bad-vector.toml", "[[sphere]]\ncenter = [0, 0]\nradius = 1\nmaterial = \"a\"\n", &["line 2"]),
        ("bad-radius.toml", "[materials.a]\ntype = \"lambert\"\n[[sphere]]\ncenter = [0, 0, 0]\nradius = -1\nmaterial = \"a\"\n", &["radius"]),
        ("flat-quad.toml", "[materials.a]\ntype = \"lambert\"\n[[quad]]\ncorner = [0,0,0]\nedge_u = [1,0,0]\nedge_v = [2,0,0]\nmaterial = \"a\"\n", &["area"]),
        ("bad-index.toml", "[materials.a]\ntype = \"lambert\"\n[[mesh]]\npositions = [[0,0,0]]\nindices = [[0,1,2]]\nmaterial = \"a\"\n", &["out of range"]),
        ("bad-light.toml", "[[light]]\ntype = \"point\"\nposition = [0,0,0]\n", &["intensity"]),
        ("light-key.toml", "[[light]]\ntype = \"point\"\nposition = [0,0,0]\nintensity = 1\nirradiance = 1\n", &["irradiance"]),
        ("both-env.toml", "[environment]\nconstant = 1\nmap = \"x.hdr\"\n", &["either"]),
        ("missing-env.toml", "[environment]\nmap = \"nowhere/missing.hdr\"\n", &["line 1", "missing.hdr", "not found"]),
        ("bad-env-ext.toml", "[environment]\nmap = \"sky.png\"\n", &["sky.png", ".png"]),
        ("missing-include.toml", "[[include]]\ngltf = \"missing.glb\"\n", &["line 1", "missing.glb", "not found"]),
        ("bad-rotate.toml", "[[include]]\ngltf = \"x.glb\"\nrotate = { axis = [0, 1, 0] }\n", &["rotate"]),
        ("look-and-forward.toml", "[camera]\nposition = [0,0,0]\nlook_at = [0,0,-1]\nforward = [0,0,-1]\n", &["either"]),
        ("bad-vfov.toml", "[camera]\nposition = [0,0,0]\nvfov = 180\n", &["vfov"]),
    ];
    for (name, text, needles) in cases {
        let err = load_text(&dir, name, text).err().unwrap_or_else(|| panic!("{name} loaded"));
        let msg = err.to_string();
        assert!(msg.contains(&*dir.join(name).to_string_lossy()), "{name}: message does not name the file: {msg}");
        for needle in *needles {
            assert!(msg.contains(needle), "{name}: message lacks '{needle}': {msg}");
        }
        assert!(!msg.contains('\n'), "{name}: keep messages on one line: {msg}");
    }
    // Files that are not there, or not text.
    let missing = dir.join("absent.toml");
    assert!(scene::toml::load(&missing, &LoadOptions::default()).unwrap_err().to_string().contains("absent.toml"));
    std::fs::write(dir.join("binary.toml"), [0xff, 0xfe, 0x00, 0x80]).unwrap();
    let e = scene::load(dir.join("binary.toml").to_str().unwrap(), &LoadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("binary.toml") && e.contains("UTF-8"), "{e}");
}

#[test]
fn toml_environment_map_paths_resolve_relative_to_the_file() {
    let dir = scratch("envpath");
    std::fs::create_dir_all(dir.join("maps")).unwrap();
    std::fs::copy(Path::new(TESTDATA_ENV).join("hdr/peppermint_powerplant_1k.hdr"), dir.join("maps/room.hdr")).unwrap();
    let toml = "[environment]\nmap = \"maps/room.hdr\"\nscale = 2\nrotation = -90\n";
    let s = load_text(&dir, "room.toml", toml).unwrap();
    let Environment::Map { map, scale, rotation } = &s.environment else { panic!() };
    assert_eq!((map.width, map.height, *scale), (1024, 512, 2.0));
    assert!((rotation + std::f32::consts::FRAC_PI_2).abs() < 1e-6);
    // An absolute path works too.
    let abs = format!("[environment]\nmap = \"{TESTDATA_ENV}/exr/derived/noon_grass_1k_f32_zip.exr\"\n");
    assert!(load_text(&dir, "abs.toml", &abs).is_ok());
}

/// glTF includes: the comparison Cornell box placed twice, once moved, rotated and scaled, once mirrored.
#[test]
fn toml_gltf_include_is_transformed_and_merged() {
    let gltf = format!("{GLTF_SCENES}/cornell-box/cbox.gltf");
    let plain = scene::load(&gltf, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let dir = scratch("include");
    let toml = format!(
        r#"
[materials.own]
type = "lambert"

[[sphere]]
center = [0, 0, 0]
radius = 1
material = "own"

[[include]]
gltf = "{gltf}"
translate = [10, 0, 0]
rotate = {{ axis = [0, 1, 0], angle = 90 }}
scale = 2

[[include]]
gltf = "{gltf}"
scale = [-1, 1, 1]
use_camera = true
"#
    );
    let s = load_text(&dir, "include.toml", &toml).unwrap_or_else(|e| panic!("{e}"));
    let n = plain.meshes.len();
    assert_eq!(s.meshes.len(), 2 * n);
    assert_eq!(s.materials.len(), 1 + 2 * plain.materials.len());
    assert_eq!(s.triangle_count(), 2 * plain.triangle_count());
    assert_eq!(
        s.camera.position,
        Vec3::new(-plain.camera.position.x, plain.camera.position.y, plain.camera.position.z)
    );
    let m = glam::Mat4::from_scale_rotation_translation(
        Vec3::splat(2.0),
        glam::Quat::from_rotation_y(90f32.to_radians()),
        Vec3::new(10.0, 0.0, 0.0),
    );
    for (k, (a, b)) in plain.meshes.iter().zip(&s.meshes[..n]).enumerate() {
        assert_eq!(b.material, a.material + 1, "materials re-indexed after the TOML's own");
        assert_eq!(s.materials[b.material as usize], plain.materials[a.material as usize]);
        assert_eq!(a.indices, b.indices, "mesh {k}: a rotation keeps the winding");
        for (p, q) in a.positions.iter().zip(&b.positions) {
            assert!(close((m * p.extend(1.0)).xyz(), *q, 1e-4));
        }
        for (p, q) in a.normals.iter().zip(&b.normals) {
            assert!(close(glam::Quat::from_rotation_y(90f32.to_radians()) * *p, *q, 1e-5));
        }
    }
    for (a, b) in plain.meshes.iter().zip(&s.meshes[n..]) {
        assert_eq!(b.material, a.material + 1 + plain.materials.len() as u32);
        // Mirrored: winding flipped, so the geometric normal still agrees with the (mirrored) shading normal.
        for (ta, tb) in a.indices.iter().zip(&b.indices) {
            assert_eq!([ta[0], ta[2], ta[1]], *tb);
            let [p0, p1, p2] = tb.map(|i| b.positions[i as usize]);
            let geometric = (p1 - p0).cross(p2 - p0);
            if geometric.length() > 1e-6 {
                assert!(geometric.dot(b.normals[tb[0] as usize]) > 0.0);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Environment maps.

#[test]
fn every_test_env_map_loads() {
    let files = [
        "hdr/noon_grass_1k.hdr",
        "hdr/kloppenheim_05_1k.hdr",
        "hdr/peppermint_powerplant_1k.hdr",
        "hdr/phalzer_forest_01_1k.hdr",
        "hdr/studio_small_05_1k.hdr",
        "exr/derived/noon_grass_1k_f32_zip.exr",
        "exr/derived/peppermint_powerplant_1k_f16_piz.exr",
        // DWAB (lossy) EXRs: the exr crate (≥ 1.74) decodes them; their few slightly negative texels are
        // codec undershoot, repaired to 0 with a warning.
        "exr/blender/sunrise.exr",
        "exr/blender/courtyard.exr",
    ];
    for f in files {
        let path = Path::new(TESTDATA_ENV).join(f);
        let (map, warnings) = load_envmap(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((map.width, map.height, map.texels.len()), (1024, 512, 1024 * 512), "{f}");
        assert_eq!(map.path, path);
        assert!(map.texels.iter().flatten().all(|c| c.is_finite() && *c >= 0.0), "{f}");
        let mean = map.texels.iter().map(|t| (t[0] + t[1] + t[2]) as f64).sum::<f64>() / (3 * map.texels.len()) as f64;
        assert!(mean > 0.01 && mean < 100.0, "{f}: mean {mean}");
        if f.contains("blender") {
            assert!(warnings.len() <= 1 && warnings.iter().all(|w| w.contains("negative")), "{f}: {warnings:?}");
        } else {
            assert!(warnings.is_empty(), "{f}: {warnings:?}");
        }
    }
    // The lossless EXR re-encode decodes to the same texels as its source HDR.
    let (hdr, _) = load_envmap(&Path::new(TESTDATA_ENV).join("hdr/noon_grass_1k.hdr")).unwrap();
    let (exr, _) = load_envmap(&Path::new(TESTDATA_ENV).join("exr/derived/noon_grass_1k_f32_zip.exr")).unwrap();
    assert!(hdr
        .texels
        .iter()
        .zip(&exr.texels)
        .all(|(a, b)| (0..3).all(|i| (a[i] - b[i]).abs() <= 1e-6 * a[i].max(1.0))));
    // Top row is the sky: the noon map's brightest texel (the sun) is in the upper half.
    let brightest = hdr.texels.iter().enumerate().max_by(|a, b| a.1[1].total_cmp(&b.1[1])).unwrap().0;
    assert!(brightest / 1024 < 256);
}

#[test]
fn env_map_errors_name_the_file() {
    let dir = scratch("envmap-errors");
    let check = |path: &Path, needle: &str| {
        let e = load_envmap(path).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains(&*path.to_string_lossy()) && e.contains(needle), "{e}");
    };
    check(&dir.join("missing.hdr"), "not found");
    check(&Path::new(TESTDATA_ENV).join("exr/blender/license.txt"), "unknown environment map format");
    std::fs::write(dir.join("garbage.hdr"), b"this is not a radiance file").unwrap();
    check(&dir.join("garbage.hdr"), "cannot decode");
    std::fs::write(dir.join("garbage.exr"), b"neither is this an openexr file").unwrap();
    check(&dir.join("garbage.exr"), "cannot decode");
    // Truncated real data.
    let bytes = std::fs::read(Path::new(TESTDATA_ENV).join("hdr/studio_small_05_1k.hdr")).unwrap();
    std::fs::write(dir.join("truncated.hdr"), &bytes[..bytes.len() / 2]).unwrap();
    assert!(load_envmap(&dir.join("truncated.hdr")).is_err());
    let bytes = std::fs::read(Path::new(TESTDATA_ENV).join("exr/blender/sunrise.exr")).unwrap();
    std::fs::write(dir.join("truncated.exr"), &bytes[..bytes.len() / 2]).unwrap();
    check(&dir.join("truncated.exr"), "truncated.exr");
    // Too large: a header claiming 20000 texels across, rejected before anything big is allocated.
    std::fs::write(dir.join("huge.hdr"), b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 10 +X 20000\n").unwrap();
    let e = load_envmap(&dir.join("huge.hdr")).map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("huge.hdr") && (e.contains("large") || e.contains("16384")), "{e}");
}

#[test]
fn env_map_sanitises_bad_texels() {
    let dir = scratch("sanitise");
    // EXR with NaN, ±Inf, negative and huge values among good ones.
    let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -1.0, 1e35];
    let mut pixels = vec![0.5f32; 4 * 2 * 3];
    for (i, v) in bad.iter().enumerate() {
        pixels[3 * i + 1] = *v; // the green component of texels 0..5
    }
    let img = image::Rgb32FImage::from_raw(4, 2, pixels).unwrap();
    let path = dir.join("bad.exr");
    img.save(&path).unwrap();
    let (map, warnings) = load_envmap(&path).unwrap();
    assert_eq!(map.texels[..5], [[0.5, 0.0, 0.5]; 5]);
    assert!(map.texels[5..].iter().all(|t| *t == [0.5; 3]));
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    let w = &warnings[0];
    assert!(w.contains("bad.exr") && w.contains("repaired 5 of 8 texels"), "{w}");
    assert!(
        w.contains("1 NaN") && w.contains("2 infinite") && w.contains("1 negative") && w.contains("1 above 1e30"),
        "{w}"
    );

    // Radiance file with an exponent-255 texel, which the decoder turns into ~1.7e38: flat RGBE, 2×1.
    let mut hdr = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 2\n".to_vec();
    hdr.extend_from_slice(&[128, 128, 128, 129, 255, 255, 255, 255]);
    let path = dir.join("exp255.hdr");
    std::fs::write(&path, hdr).unwrap();
    let (map, warnings) = load_envmap(&path).unwrap();
    assert_eq!(map.texels, vec![[1.0; 3], [0.0; 3]]);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].contains("repaired 1 of 2") && warnings[0].contains("3 above 1e30"), "{}", warnings[0]);

    // Clean files give no warning.
    let clean = image::Rgb32FImage::from_raw(2, 1, vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0]).unwrap();
    clean.save(dir.join("clean.exr")).unwrap();
    let (map, warnings) = load_envmap(&dir.join("clean.exr")).unwrap();
    assert!(warnings.iter().all(|w| w.contains("2:1")), "{warnings:?}");
    assert_eq!(map.texels, vec![[0.0, 1.0, 2.0], [3.0, 4.0, 5.0]]);
}

#[test]
fn equirect_mapping_convention() {
    // u = ½ looks down −Z, v = 0 is up; unmirrored from inside (u = ¾ is +X, to the right when facing −Z).
    assert!(close(equirect_direction(0.5, 0.5), Vec3::NEG_Z, 1e-6));
    assert!(close(equirect_direction(0.75, 0.5), Vec3::X, 1e-6));
    assert!(close(equirect_direction(0.1, 0.0), Vec3::Y, 1e-6));
    assert!(close(equirect_direction(0.9, 1.0), Vec3::NEG_Y, 1e-6));
    for d in [Vec3::new(1.0, 2.0, 3.0), Vec3::new(-0.3, -0.9, 0.1), Vec3::new(0.0, 0.2, -5.0)] {
        let (u, v) = direction_to_equirect(d);
        assert!(close(equirect_direction(u, v), d.normalize(), 1e-5), "{d}");
    }
}

// ---------------------------------------------------------------------------------------------------------------
// The shipped procedural sky (assets/scenes/sky.hdr), our own data so that the environment-map example works
// out of the box without third-party files.

const SKY_SIZE: (u32, u32) = (256, 128);

/// The sky's radiance in direction `d`: a horizon-to-zenith gradient, a dim ground, and a 2°-radius sun of radiance
/// 1500 at 35° elevation (u = 0.1, i.e. behind-left of a camera looking down −Z).
fn sky(d: Vec3) -> Vec3 {
    let sun = equirect_direction(0.1, (90.0 - 35.0) / 180.0);
    if d.dot(sun) > 2f32.to_radians().cos() {
        return Vec3::new(1500.0, 1400.0, 1250.0);
    }
    if d.y < 0.0 {
        return Vec3::new(0.12, 0.10, 0.08);
    }
    let (horizon, zenith) = (Vec3::new(1.0, 0.95, 0.9), Vec3::new(0.2, 0.36, 0.72));
    horizon.lerp(zenith, d.y.sqrt())
}

/// Texel (x, y) of the sky: the average of 4×4 samples, so the sun's edge is anti-aliased and its power right.
fn sky_texel(x: u32, y: u32) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for i in 0..4 {
        for j in 0..4 {
            let u = (x as f32 + (i as f32 + 0.5) / 4.0) / SKY_SIZE.0 as f32;
            let v = (y as f32 + (j as f32 + 0.5) / 4.0) / SKY_SIZE.1 as f32;
            sum += sky(equirect_direction(u, v));
        }
    }
    sum / 16.0
}

/// Regenerates assets/scenes/sky.hdr: `cargo test --release --test scenes -- --ignored regenerate_sky`.
#[test]
#[ignore]
fn regenerate_sky_hdr() {
    let (w, h) = SKY_SIZE;
    let pixels: Vec<image::Rgb<f32>> =
        (0..h).flat_map(|y| (0..w).map(move |x| image::Rgb(sky_texel(x, y).to_array()))).collect();
    let file = std::fs::File::create(assets().join("sky.hdr")).unwrap();
    image::codecs::hdr::HdrEncoder::new(std::io::BufWriter::new(file)).encode(&pixels, w as usize, h as usize).unwrap();
}

#[test]
fn shipped_sky_matches_its_recipe() {
    let (map, warnings) = load_envmap(&assets().join("sky.hdr")).unwrap();
    assert!(warnings.is_empty());
    assert_eq!((map.width, map.height), SKY_SIZE);
    for y in 0..SKY_SIZE.1 {
        for x in 0..SKY_SIZE.0 {
            let want = sky_texel(x, y);
            let got = Vec3::from(map.texels[(y * SKY_SIZE.0 + x) as usize]);
            // RGBE keeps 8 mantissa bits of the largest component.
            assert!(
                (got - want).abs().max_element() <= 0.01 * want.max_element() + 1e-6,
                "({x}, {y}): {got} vs {want}"
            );
        }
    }
}
