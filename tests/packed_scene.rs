//! The packed scene layout (`render::packed_scene`, for devices with few storage-buffer bindings such as WebGPU's
//! 8) holds every table where its header says, its modules bind one scene buffer, and on this device it renders
//! the same image as the separate layout, bit for bit.

mod common;

use mislab::render::bindings::SCENE;
use mislab::render::gpu_scene::{storage_bindings_needed, GpuScene};
use mislab::render::packed_scene::{self, SceneLayout};
use mislab::render::render_module::{render_source, render_source_for};
use mislab::render::settings::{LightSelect, Mode, Settings, Strategy};
use mislab::render::{scene_data::SceneData, Renderer};
use mislab::scene::Scene;

#[test]
fn the_header_says_where_each_table_is() {
    let data = SceneData::build(&common::scene("cornell-box"));
    let words = packed_scene::pack(&data);
    for (k, b) in SCENE.iter().enumerate() {
        let (first, count) = (words[2 * k] as usize, words[2 * k + 1] as usize);
        let bytes = (b.bytes)(&data);
        assert_eq!(count, (bytes.len() / b.binding.element_size).max(1), "{}", b.binding.name);
        assert_eq!(first % 4, 0, "{}: tables start on 16 bytes", b.binding.name);
        let table: Vec<u32> = bytes.chunks_exact(4).map(|w| u32::from_le_bytes(w.try_into().unwrap())).collect();
        assert_eq!(&words[first..first + table.len()], &table[..], "{}", b.binding.name);
        let end = first + count * b.binding.element_size / 4;
        assert!(
            words[first + table.len()..end].iter().all(|w| *w == 0),
            "{}: an empty table is one zero element",
            b.binding.name
        );
    }
}

/// Storage buffers a composed module's entry point binds once specialised (naga's reflection of the pruned module).
fn storage_buffers_bound(source: &str) -> usize {
    let module = mislab::render::shaders::validate(source).unwrap();
    let pruned = mislab::render::shader_prune::specialized_wgsl(&module, "render_main", &[]).unwrap();
    let module = mislab::render::shaders::validate(&pruned).unwrap();
    module.global_variables.iter().filter(|(_, g)| matches!(g.space, naga::AddressSpace::Storage { .. })).count()
}

#[test]
fn the_packed_module_fits_webgpu_s_eight_storage_buffers() {
    assert!(storage_bindings_needed() > 8, "the separate layout needs {}", storage_bindings_needed());
    for source in [render_source(), render_source_for(&SceneData::build(&common::scene("cornell-box")))] {
        let packed = packed_scene::packed_source(&source).unwrap();
        assert!(packed_scene::is_packed(&packed));
        for b in SCENE {
            let declared = format!("var<storage, read> {}:", b.binding.name);
            assert!(!packed.contains(&declared), "{} is still declared", b.binding.name);
        }
        let bound = storage_buffers_bound(&packed);
        assert!(bound <= 8, "the packed render kernel binds {bound} storage buffers");
        assert!(storage_buffers_bound(&source) > 8);
    }
}

fn film(scene: &Scene, settings: &Settings, layout: SceneLayout, spp: u32) -> Vec<[f32; 3]> {
    let ctx = common::gpu();
    let data = SceneData::build(scene);
    let gs = match layout {
        SceneLayout::Separate => GpuScene::upload(ctx, data),
        SceneLayout::Packed => GpuScene::upload_packed(ctx, data),
    }
    .expect("upload");
    assert_eq!(gs.layout, layout);
    let mut r = Renderer::new(ctx, &gs, scene.camera.clone(), settings.clone()).expect("renderer");
    r.render(ctx, spp).expect("render");
    r.film(ctx).expect("readback").mean
}

fn assert_same(name: &str, scene: &Scene, settings: &Settings, spp: u32) {
    let a = film(scene, settings, SceneLayout::Separate, spp);
    let b = film(scene, settings, SceneLayout::Packed, spp);
    let differing = a.iter().zip(&b).filter(|(x, y)| x.map(f32::to_bits) != y.map(f32::to_bits)).count();
    assert_eq!(differing, 0, "{name}: {differing} of {} pixels differ between the layouts", a.len());
    assert!(a.iter().any(|p| p.iter().any(|c| *c > 0.0)), "{name}: a black image proves nothing");
}

#[test]
fn packed_and_separate_layouts_render_the_same_bits() {
    let base = Settings { width: 40, height: 30, seed: 3, ..Settings::default() };
    for (name, settings) in [
        ("cornell-box", Settings { mode: Mode::Path, max_depth: 5, ..base.clone() }),
        ("veach-mis", Settings { strategy: Strategy::Mis, ..base.clone() }),
        ("many-lights", Settings { light_select: LightSelect::Tree, ..base.clone() }),
        ("veach-mis-triangles", Settings { light_select: LightSelect::Power, ..base.clone() }),
    ] {
        assert_same(name, &common::scene(name), &settings, 4);
    }
    // The BVH, textures and an environment map: every table of the layout read.
    let scene = common::helmet_under_sky();
    assert_same("DamagedHelmet", &scene, &Settings { mode: Mode::Path, max_depth: 4, ..base.clone() }, 4);
}
