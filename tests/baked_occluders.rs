//! Baked occluders (src/render/scene_data/mod.rs `occluder_split`): a scene of a few occluders among many emitter
//! triangles has its occluders as literals in its pipeline and only the emitters in the BVH, and a ray traced only
//! for its emission towards a convex lamp's inner sphere is traced no further than the lamp's box
//! (shaders/lights.wgsl `lamp_in_sight`). Neither may change what a ray finds: BSDF samples give the same pixels
//! with and without them, in the scene's own pipeline and in the generic one (which tests the occluders in a loop
//! over their buffer slots), and light sampling converges to the same image. The same holds for the baked BVH root
//! of any triangle scene (src/render/baked.rs `baked_root`): its children's exact boxes as literals.

mod common;

use glam::Vec3;
use mislab::accel::wide_bvh::{WideChild, WIDTH};
use mislab::render::features::Features;
use mislab::render::film::Film;
use mislab::render::gpu_scene::GpuScene;
use mislab::render::scene_data::{BuildOptions, SceneData};
use mislab::render::settings::{LightSelect, Mode, Settings, Strategy};
use mislab::render::Renderer;
use mislab::scene::{Camera, Environment, Material, Quad, Scene, Sphere};

use common::{mesh_of, rect, uv_sphere};

/// Two sphere lamps (one of 1,152 faces, one of 120) over a floor, in front of a wall, with a shelf between the
/// large lamp and the floor that shadows part of it: eight occluder triangles.
fn lamps_and_shelf() -> Scene {
    let floor = rect(Vec3::new(-3.0, 0.0, 2.0), Vec3::new(6.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -4.0));
    let wall = rect(Vec3::new(-3.0, 0.0, -2.0), Vec3::new(6.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 0.0));
    let shelf = rect(Vec3::new(0.05, 0.4, -0.35), Vec3::new(0.5, 0.0, 0.0), Vec3::new(0.0, 0.0, -0.5));
    let block = rect(Vec3::new(-1.2, 0.3, 0.2), Vec3::new(0.4, 0.0, 0.0), Vec3::new(0.0, 0.5, 0.0));
    Scene {
        name: "lamps-and-shelf".into(),
        materials: vec![
            Material::emitter("lamp", Vec3::splat(6.0)),
            Material::lambert("grey", Vec3::splat(0.5)),
            Material::emitter("small lamp", Vec3::new(20.0, 12.0, 4.0)),
        ],
        meshes: vec![
            mesh_of("lamp", &uv_sphere(Vec3::new(0.3, 0.9, -0.6), 0.35, 24, 48, true), 0),
            mesh_of("small lamp", &uv_sphere(Vec3::new(-1.0, 1.0, 0.0), 0.12, 6, 12, true), 2),
            mesh_of("floor", &floor, 1),
            mesh_of("wall", &wall, 1),
            mesh_of("shelf", &shelf, 1),
            mesh_of("block", &block, 1),
        ],
        camera: Camera::look_at(Vec3::new(0.0, 1.6, 4.0), Vec3::new(0.0, 0.7, -0.5), Vec3::Y, 45.0),
        ..Default::default()
    }
}

fn data(scene: &Scene, baked_occluders: bool) -> SceneData {
    SceneData::build_options(scene, BuildOptions { convex_lamps: true, baked_occluders, baked_root: true })
}

#[test]
fn a_few_occluders_among_emitters_are_baked_and_the_bvh_holds_the_emitters() {
    let scene = lamps_and_shelf();
    let d = data(&scene, true);
    let emitters = 2 * 24 * 48 - 2 * 48 + 2 * 6 * 12 - 2 * 12;
    assert_eq!(d.triangles, emitters + 8);
    assert_eq!(d.occluders, (emitters as u32, 8), "the occluders follow the BVH's triangles");
    assert_eq!(d.convex_lamps(), 2);
    let f = Features::of(&d);
    assert!(f.flat.is_none() && f.occluders == 8, "{}", f.describe());
    // The occluders' slots hold the floor, wall, shelf and block: none emits.
    for i in emitters..emitters + 8 {
        assert_eq!(d.tri_shading[i].light, mislab::gpu::types::INVALID, "slot {i} is an occluder");
    }
    let whole = data(&scene, false);
    assert_eq!((whole.occluders, Features::of(&whole).occluders), ((0, 0), 0));
    assert!(whole.wide_nodes.len() > d.wide_nodes.len(), "the occluders' nodes are gone from the BVH");

    // Not where more than FLAT_MAX_PRIMS triangles do not emit, nor where nothing but a few occluders is left.
    let mut crowded = scene.clone();
    crowded.meshes.push(mesh_of("many", &uv_sphere(Vec3::new(2.0, 0.5, 0.0), 0.3, 4, 8, true), 1));
    assert_eq!(data(&crowded, true).occluders, (0, 0));
}

fn render(scene: &Scene, d: SceneData, settings: &Settings, specialise: bool, spp: u32) -> Film {
    let ctx = common::gpu();
    let gs = GpuScene::upload(ctx, d).expect("upload");
    let mut r = Renderer::new(ctx, &gs, scene.camera.clone(), settings.clone()).expect("renderer");
    r.set_specialize(specialise).expect("pipeline");
    r.render(ctx, spp).expect("render");
    r.film(ctx).expect("readback")
}

/// Largest relative difference between two films' pixels, and where: (difference, pixel, a's value, b's value).
fn worst(a: &Film, b: &Film) -> (f32, usize, [f32; 3], [f32; 3]) {
    let mut worst = (0.0f32, 0, [0.0; 3], [0.0; 3]);
    for (i, (x, y)) in a.mean.iter().zip(&b.mean).enumerate() {
        for c in 0..3 {
            let d = (x[c] - y[c]).abs() / x[c].abs().max(y[c].abs()).max(1e-3);
            if d > worst.0 {
                worst = (d, i, *x, *y);
            }
        }
    }
    worst
}

/// The same samples give the same pixels: baked occluders against every primitive in the BVH, and the scene's own
/// pipeline against the generic one, with BSDF sampling (every direction sample traced for its emission alone, most
/// of them only up to a lamp's box, in direct lighting; the last ray of each path in path tracing). Light sampling
/// is left to `light_sampling_agrees_in_distribution`: the two builds order the lamps' faces differently (each
/// BVH's leaf order), and a light sample that picks a face by index picks another one.
#[test]
fn same_pixels_with_baked_occluders_and_lamp_sighting() {
    let scene = lamps_and_shelf();
    for mode in [Mode::Direct, Mode::Path] {
        let settings = Settings { mode, max_depth: 3, rr_depth: 8, strategy: Strategy::Bsdf, ..common::small(40, 28) };
        let baked = render(&scene, data(&scene, true), &settings, true, 32);
        let in_bvh = render(&scene, data(&scene, false), &settings, true, 32);
        assert!(baked.nonfinite.iter().all(|&n| n == 0), "{mode:?}: no NaN/Inf samples");
        let lit = baked.mean.iter().filter(|p| p[0] > 0.0).count();
        assert!(lit > baked.mean.len() / 4, "{mode:?}: BSDF samples find the lamps ({lit} pixels lit)");
        // Direct: the same hits, so equal up to float rounding. Path: a tie between the floor's two triangles
        // may go the other way and move a later vertex by an ulp, so a few pixels may differ a little more.
        let tol = if mode == Mode::Direct { 1e-4 } else { 2e-2 };
        let b = worst(&baked, &in_bvh);
        assert!(b.0 < tol, "{mode:?}: baked occluders change the image by {b:?} (relative, pixel, values)");
        // The generic pipeline takes minutes to compile on lavapipe: once, in direct mode.
        if mode == Mode::Direct {
            let generic = render(&scene, data(&scene, true), &settings, false, 32);
            let g = worst(&baked, &generic);
            assert!(g.0 < tol, "{mode:?}: the generic pipeline differs by {g:?} (relative, pixel, values)");
        }
    }
}

/// With light sampling (MIS, the light tree) the baked build and the BVH-only build converge to the same image:
/// per-pixel z-tests of the difference of their means (Šidák-corrected, family-wise 1e-3).
#[test]
fn light_sampling_agrees_in_distribution() {
    let scene = lamps_and_shelf();
    let settings = Settings {
        mode: Mode::Direct,
        strategy: Strategy::Mis,
        light_select: LightSelect::Tree,
        ..common::small(40, 28)
    };
    let a = render(&scene, data(&scene, true), &settings, true, 256);
    let b = render(&scene, data(&scene, false), &settings, true, 256);
    let limit = common::sidak_z(1e-3, 3 * a.mean.len());
    let mut worst = (0.0f64, 0);
    for i in 0..a.mean.len() {
        for c in 0..3 {
            let var = |f: &Film| f.m2[i][c] as f64 / ((f.count[i] as f64 - 1.0) * f.count[i] as f64);
            let z = (a.mean[i][c] as f64 - b.mean[i][c] as f64).abs() / (var(&a) + var(&b) + 1e-12).sqrt();
            if z > worst.0 {
                worst = (z, i);
            }
        }
    }
    assert!(worst.0 < limit, "pixel {} differs by z = {:.2} (limit {limit:.2})", worst.1, worst.0);
}

/// A small bumpy object on a floor forty times its size under a white sky (the bench's scaling scenes in small):
/// the root's 8-bit boxes are coarse around the object, its exact ones are not. With `analytic`, an analytic
/// sphere and quad beside it (the BVH's entries then reach their primitives through references).
fn object_on_a_floor(analytic: bool) -> Scene {
    let floor = rect(Vec3::new(-20.0, 0.0, 20.0), Vec3::new(40.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -40.0));
    Scene {
        name: "object-on-a-floor".into(),
        materials: vec![Material::lambert("grey", Vec3::splat(0.5))],
        meshes: vec![
            mesh_of("floor", &floor, 0),
            mesh_of("ball", &uv_sphere(Vec3::new(0.0, 0.5, 0.0), 0.5, 12, 24, true), 0),
            mesh_of("pebble", &uv_sphere(Vec3::new(0.8, 0.15, 0.3), 0.15, 6, 12, true), 0),
        ],
        spheres: if analytic {
            vec![Sphere { center: Vec3::new(-0.7, 0.25, 0.4), radius: 0.25, material: 0 }]
        } else {
            vec![]
        },
        quads: if analytic {
            let (corner, edge_u, edge_v) = (Vec3::new(-0.6, 0.0, -0.6), Vec3::new(0.5, 0.0, -0.2), Vec3::Y * 0.6);
            vec![Quad { corner, edge_u, edge_v, material: 0 }]
        } else {
            vec![]
        },
        camera: Camera::look_at(Vec3::new(1.5, 1.2, 2.5), Vec3::new(0.0, 0.4, 0.0), Vec3::Y, 40.0),
        environment: Environment::Constant(Vec3::ONE),
        ..Default::default()
    }
}

/// The root's children tested against their exact boxes as literals give the pixels that loading the root node
/// gives, in path tracing with MIS (closest hits and shadow rays) and with BSDF samples alone, in a triangle scene
/// and in one with an analytic sphere and quad.
#[test]
fn same_pixels_with_the_bvh_root_as_literals() {
    for analytic in [false, true] {
        same_pixels_with_the_root_as_literals_in(object_on_a_floor(analytic));
    }
}

fn same_pixels_with_the_root_as_literals_in(scene: Scene) {
    let build = |baked_root| {
        SceneData::build_options(&scene, BuildOptions { convex_lamps: true, baked_occluders: true, baked_root })
    };
    let (on, off) = (build(true), build(false));
    let analytic = !scene.spheres.is_empty();
    assert_eq!(
        on.prim_refs != mislab::render::scene_data::IDENTITY_PRIM_REFS,
        analytic,
        "references where not all triangles"
    );
    let children = (0..WIDTH).filter(|&i| !matches!(on.wide_nodes[0].child(i), WideChild::Empty)).count();
    assert!(children > 1, "the root has children to test");
    assert!(Features::of(&on).baked_root && !Features::of(&off).baked_root);
    let source = mislab::render::render_module::render_source_for(&on);
    assert!(source.contains("fn baked_root_hits") && !source.contains("wide_node_hits(r, oct, wide_node(0u), t)"));
    for strategy in [Strategy::Mis, Strategy::Bsdf] {
        let settings = Settings { mode: Mode::Path, max_depth: 4, rr_depth: 8, strategy, ..common::small(48, 32) };
        let a = render(&scene, on.clone(), &settings, true, 16);
        let b = render(&scene, off.clone(), &settings, true, 16);
        assert!(a.nonfinite.iter().all(|&n| n == 0), "analytic {analytic}, {strategy:?}: no NaN/Inf samples");
        let shadowed = a.mean.iter().filter(|p| p[0] > 0.0 && p[0] < 0.4).count();
        assert!(shadowed > 20, "{strategy:?}: the objects shadow the floor ({shadowed} pixels)");
        // A tie between two triangles at one t may go the other way in another visiting order and move a later
        // vertex by an ulp: a few pixels may differ a little.
        let w = worst(&a, &b);
        assert!(
            w.0 < 2e-2,
            "analytic {analytic}, {strategy:?}: the literal root changes the image by {w:?} (relative, pixel, values)"
        );
    }
}
