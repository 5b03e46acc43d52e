//! Every composed shader module parses and validates with naga (no GPU needed), so a WGSL error is a
//! test failure with a readable message rather than a device error at run time.

#[test]
fn render_module_validates() {
    let src = mislab::render::render_source();
    if let Err(e) = mislab::shaders::validate(&src) {
        panic!("render module:\n{e}");
    }
}

#[test]
fn every_file_is_embedded_and_nonempty() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        if name.ends_with(".wgsl") {
            assert!(
                mislab::shaders::FILES.iter().any(|(n, s)| *n == name && !s.trim().is_empty()),
                "{name} is not embedded in src/shaders.rs"
            );
        }
    }
}

/// Every built-in scene small enough to bake gets a module with its data as literals that validates, and a
/// pipeline key of its own (a cache must never hand one scene's baked pipeline to another).
#[test]
fn baked_scene_modules_validate_and_have_their_own_keys() {
    use mislab::features::Features;
    use mislab::gpu_scene::SceneData;
    let mut keys = std::collections::HashSet::new();
    for name in ["veach-mis", "cornell-box", "furnace", "area-vs-cosine"] {
        let scene = mislab::scene::load(name, &Default::default()).unwrap();
        let data = SceneData::build(&scene);
        let f = Features::of(&data);
        assert!(f.flat.is_some() && f.baked != 0, "{name} should be baked");
        let src = mislab::render::render_source_for(&data);
        assert!(src.contains("tri_hit(") || data.tri_shading.is_empty(), "{name}: no unrolled triangle tests");
        if let Err(e) = mislab::shaders::validate(&src) {
            panic!("{name}: baked module:\n{e}");
        }
        assert!(keys.insert(f.baked), "{name} shares a baked key with another scene");
    }
    assert_eq!(Features::generic().baked, 0);
}
