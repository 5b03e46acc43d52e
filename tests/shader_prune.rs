//! The pruned module the driver compiles (`render::shader_prune`) computes what the module as written computes: on
//! the GPU, renders through a pipeline built from the unpruned module with its override constants give the same
//! image bit for bit; on the CPU, the pruner folds what the settings fix and keeps what they leave open.

mod common;

use mislab::render::settings::{Heuristic, LightSampling, Mode, Settings, Strategy};
use mislab::render::shader_prune::specialized_wgsl;
use mislab::render::{gpu_scene::GpuScene, scene_data::SceneData, shaders, Renderer};
use mislab::scene::Scene;

/// The film of `spp` samples through the renderer's own (pruned) pipeline, and through one built from the
/// module as written with the key's override constants.
fn pruned_and_as_written(scene: &Scene, settings: &Settings, spp: u32) -> [Vec<[f32; 3]>; 2] {
    let ctx = common::gpu();
    let gs = GpuScene::upload(ctx, SceneData::build(scene)).expect("upload");
    let mut pruned = Renderer::new(ctx, &gs, scene.camera.clone(), settings.clone()).expect("renderer");
    pruned.render(ctx, spp).expect("render");
    let mut written = Renderer::new(ctx, &gs, scene.camera.clone(), settings.clone()).expect("renderer");
    let key = written.key();
    let source = shaders::for_device(written.source_for(&key), ctx.device.features()).into_owned();
    let module = ctx.device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("render as written"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let constants = key.constants();
    let pipeline = ctx.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("render as written"),
        layout: Some(written.pipeline_layout()),
        module: &module,
        entry_point: Some("render_main"),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants: &constants,
            zero_initialize_workgroup_memory: false,
        },
        cache: None,
    });
    written.insert_pipeline(key, pipeline);
    written.render(ctx, spp).expect("render");
    [pruned.film(ctx).expect("readback").mean, written.film(ctx).expect("readback").mean]
}

fn assert_same_bits(name: &str, [a, b]: [Vec<[f32; 3]>; 2]) {
    assert_eq!(a.len(), b.len());
    let differing = a.iter().zip(&b).filter(|(x, y)| x.map(f32::to_bits) != y.map(f32::to_bits)).count();
    assert_eq!(
        differing,
        0,
        "{name}: {differing} of {} pixels differ between the pruned and the written module",
        a.len()
    );
    assert!(a.iter().any(|p| p.iter().any(|c| *c > 0.0)), "{name}: the image is black, which proves nothing");
}

#[test]
fn pruned_pipelines_render_the_same_bits_as_the_module_as_written() {
    let base = Settings { width: 48, height: 36, seed: 7, ..Settings::default() };
    let cases: Vec<(&str, Settings)> = vec![
        ("cornell-box", Settings { mode: Mode::Path, max_depth: 6, ..base.clone() }),
        ("veach-mis", Settings { strategy: Strategy::Mis, heuristic: Heuristic::Balance, ..base.clone() }),
        ("veach-mis", Settings { strategy: Strategy::Light, light_sampling: LightSampling::Area, ..base.clone() }),
        ("area-vs-cosine", Settings { strategy: Strategy::Cosine, ..base.clone() }),
        ("furnace", Settings { mode: Mode::Path, ..base.clone() }),
    ];
    for (name, settings) in cases {
        let scene = common::scene(name);
        assert_same_bits(name, pruned_and_as_written(&scene, &settings, 8));
    }
    // A BVH scene (more than the baked limit of primitives) with textures, under an environment map.
    let scene = common::helmet_under_sky();
    let settings = Settings { mode: Mode::Path, max_depth: 4, ..base.clone() };
    assert_same_bits("DamagedHelmet", pruned_and_as_written(&scene, &settings, 4));
}

/// A small module in the shape of the renderer's: settings as overrides read through functions, features joined
/// by `&&` (after a runtime operand too: `a && HAS_GLASS && f()` is false on both branches of `a`), a dispatcher,
/// a switch on a setting.
const MODULE: &str = r#"
struct Params { mode: u32 }
@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> out: array<f32>;
override SPEC_MODE: u32 = 0xffffffffu;
override HAS_GLASS: bool = true;
fn cfg_mode() -> u32 { return select(params.mode, SPEC_MODE, SPEC_MODE != 0xffffffffu); }
fn glass_eval(x: f32) -> f32 { return x * 0.5; }
fn glass_cut(x: f32) -> bool { return x > 2.0; }
fn diffuse_eval(x: f32) -> f32 { return x * 0.25; }
fn path_only(x: f32) -> f32 { return x + 1.0; }
fn direct_only(x: f32) -> f32 { return x + 2.0; }
fn eval(kind: u32, x: f32) -> f32 {
    if (HAS_GLASS && kind == 1u) { return glass_eval(x); }
    return diffuse_eval(x);
}
override SPEC_SELECT: u32 = 0xffffffffu;
fn cfg_select() -> u32 { return select(params.mode, SPEC_SELECT, SPEC_SELECT != 0xffffffffu); }
fn by_tree() -> bool { return cfg_select() == 2u || cfg_select() == 3u; }
fn tree_pick(x: f32) -> f32 { return x * 3.0; }
fn pick(x: f32) -> f32 {
    if (cfg_select() == 0u) { return x; }
    if (by_tree()) { return tree_pick(x); }
    return x + 0.125;
}
@compute @workgroup_size(1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    var v = eval(id.x, f32(id.y));
    v += pick(v);
    if (v != 0.0 && HAS_GLASS && glass_cut(v)) { v = 0.0; }
    if (cfg_mode() == 1u) { v = path_only(v); } else { v = direct_only(v); }
    switch cfg_mode() {
        case 0u: { v += 3.0; }
        default: { v += 4.0; }
    }
    out[id.x] = v;
}
"#;

fn functions(wgsl: &str) -> Vec<String> {
    wgsl.lines().filter_map(|l| l.strip_prefix("fn ")).map(|l| l.split('(').next().unwrap().to_string()).collect()
}

#[test]
fn fixed_settings_and_features_fold_and_open_ones_stay() {
    let module = mislab::render::shaders::validate(MODULE).unwrap();
    let fixed = specialized_wgsl(&module, "main", &[("SPEC_MODE", 1.0), ("HAS_GLASS", 0.0)]).unwrap();
    // SPEC_SELECT is open: `pick` and what it calls stay.
    assert_eq!(
        functions(&fixed),
        ["diffuse_eval", "path_only", "eval", "cfg_select", "by_tree", "tree_pick", "pick", "main"],
        "{fixed}"
    );
    assert!(!fixed.contains("override") && fixed.contains("4f"), "{fixed}");
    let open = specialized_wgsl(&module, "main", &[]).unwrap();
    for f in ["cfg_mode", "glass_eval", "glass_cut", "diffuse_eval", "path_only", "direct_only"] {
        assert!(functions(&open).iter().any(|g| g == f), "{f} is missing from the generic module:\n{open}");
    }
    let direct = specialized_wgsl(&module, "main", &[("SPEC_MODE", 0.0)]).unwrap();
    assert!(functions(&direct).iter().any(|g| g == "direct_only") && !direct.contains("path_only"), "{direct}");
    assert!(direct.contains("glass_eval") && direct.contains("3f"), "{direct}");
}

/// `||` (which naga lowers to a local variable set in an `if`) folds through constant functions, and code after a
/// branch that now always returns goes.
#[test]
fn short_circuits_and_code_after_a_return_fold() {
    let module = mislab::render::shaders::validate(MODULE).unwrap();
    let kept = |select: f64| {
        let wgsl = specialized_wgsl(&module, "main", &[("SPEC_MODE", 0.0), ("SPEC_SELECT", select)]).unwrap();
        let fns = functions(&wgsl);
        (["by_tree", "tree_pick", "cfg_select"].map(|f| fns.iter().any(|g| g == f)), wgsl.contains("0.125f"), wgsl)
    };
    let (fns, half, wgsl) = kept(0.0);
    assert!(fns == [false; 3] && !half, "uniform: everything after the first return goes\n{wgsl}");
    let (fns, half, wgsl) = kept(3.0);
    assert!(fns == [false, true, false] && !half, "tree (the second operand of ||)\n{wgsl}");
    let (fns, half, wgsl) = kept(1.0);
    assert!(fns == [false; 3] && half, "power: neither the first return nor the tree\n{wgsl}");
    let open = specialized_wgsl(&module, "main", &[("SPEC_MODE", 0.0)]).unwrap();
    assert!(["by_tree", "tree_pick", "cfg_select"].iter().all(|f| functions(&open).iter().any(|g| g == f)), "{open}");
}

/// Every pipeline the renderer specialises prunes (no fallback to the module as written), for every built-in scene
/// in both modes.
#[test]
fn every_specialised_render_module_prunes() {
    let ctx = common::gpu();
    for name in ["veach-mis", "cornell-box", "furnace", "area-vs-cosine"] {
        let scene = common::scene(name);
        let gs = GpuScene::upload(ctx, SceneData::build(&scene)).expect("upload");
        for mode in [Mode::Direct, Mode::Path] {
            let settings = Settings { mode, width: 8, height: 8, ..Settings::default() };
            let r = Renderer::new(ctx, &gs, scene.camera.clone(), settings).expect("renderer");
            let key = r.key();
            let source = shaders::for_device(r.source_for(&key), ctx.device.features()).into_owned();
            let module = shaders::validate(&source).unwrap();
            let pruned = specialized_wgsl(&module, "render_main", &key.constants())
                .unwrap_or_else(|e| panic!("{name} {mode:?}: {e}"));
            assert!(
                pruned.len() < source.len() * 3 / 4,
                "{name} {mode:?}: pruned to only {} of {} bytes",
                pruned.len(),
                source.len()
            );
        }
    }
}
