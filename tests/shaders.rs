//! Every composed shader module parses and validates with naga (no GPU needed), so a WGSL error is a
//! test failure with a readable message rather than a device error at run time.

#[test]
fn render_module_validates() {
    let src = mislab::render::render_source();
    if let Err(e) = mislab::render::shaders::validate(&src) {
        panic!("render module:\n{e}");
    }
}

#[test]
fn every_file_is_embedded_and_nonempty() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        if name.ends_with(".wgsl") {
            let embedded = mislab::render::shaders::FILES.iter().any(|(n, s)| *n == name && !s.trim().is_empty())
                || mislab::render::materials::MATERIALS.iter().any(|e| e.file == name && !e.source.trim().is_empty());
            assert!(embedded, "{name} is not embedded in src/render/shaders.rs nor a render::materials entry's file");
        }
    }
}

/// Every built-in scene small enough to bake gets a module with its data as literals that validates, and a
/// pipeline key of its own (a cache must never hand one scene's baked pipeline to another).
#[test]
fn baked_scene_modules_validate_and_have_their_own_keys() {
    use mislab::render::features::Features;
    use mislab::render::scene_data::SceneData;
    let mut keys = std::collections::HashSet::new();
    for name in ["veach-mis", "cornell-box", "furnace", "area-vs-cosine"] {
        let scene = mislab::scene::load(name, &Default::default()).unwrap();
        let data = SceneData::build(&scene);
        let f = Features::of(&data);
        assert!(f.flat.is_some() && f.baked != 0, "{name} should be baked");
        let src = mislab::render::render_source_for(&data);
        assert!(src.contains("tri_hit(") || data.tri_shading.is_empty(), "{name}: no unrolled triangle tests");
        if let Err(e) = mislab::render::shaders::validate(&src) {
            panic!("{name}: baked module:\n{e}");
        }
        assert!(keys.insert(f.baked), "{name} shares a baked key with another scene");
    }
    assert_eq!(Features::generic().baked, 0);
}

/// The light contract (shaders/lights.wgsl's header; docs/adding-a-light.md): every light kind `LIGHT_K` of
/// common.wgsl has exactly `k_measure`, `k_sample_li`, `k_pdf_li` and `k_eval`, each dispatcher has one `case` per kind
/// calling its function, and nothing else in the shaders names a kind or switches on one. On the Rust side a kind's
/// tag is named only where the light table is built and where the scene's features are read.
#[test]
fn every_light_kind_is_its_section_one_tag_and_one_case_per_dispatcher() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    // WGSL without its comments, so that prose may name kinds freely.
    let code = |name: &str| -> String {
        let text = std::fs::read_to_string(dir.join("shaders").join(name)).unwrap();
        text.lines().map(|l| l.split("//").next().unwrap()).collect::<Vec<_>>().join("\n")
    };
    let common = code("common.wgsl");
    let kinds: Vec<String> = common
        .lines()
        .filter_map(|l| l.trim().strip_prefix("const LIGHT_"))
        .map(|l| l.split(':').next().unwrap().to_string())
        .filter(|k| !k.starts_with("SAMPLING_") && !k.starts_with("SELECT_"))
        .collect();
    assert!(kinds.len() >= 7, "light kinds in common.wgsl: {kinds:?}");
    let lights = code("lights.wgsl");
    let count = |hay: &str, needle: &str| hay.matches(needle).count();
    // The body of `fn name(`, up to the next top-level `fn`.
    let body = |name: &str| -> String {
        let start = lights.find(&format!("fn {name}(")).unwrap_or_else(|| panic!("no dispatcher {name}"));
        let rest = &lights[start + 3..];
        rest[..rest.find("\nfn ").unwrap_or(rest.len())].to_string()
    };
    let ops = [
        ("light_measure", "measure"),
        ("light_sample_li", "sample_li"),
        ("light_pdf_li", "pdf_li"),
        ("light_eval", "eval"),
    ];
    for k in &kinds {
        let lower = k.to_lowercase();
        for (dispatcher, op) in ops {
            let f = format!("{lower}_{op}(");
            assert_eq!(count(&lights, &format!("fn {f}")), 1, "lights.wgsl must define {f}…) once");
            let b = body(dispatcher);
            assert_eq!(count(&b, &format!("case LIGHT_{k}:")), 1, "{dispatcher} needs one case LIGHT_{k}");
            assert_eq!(count(&b, &f), 1, "{dispatcher}'s case LIGHT_{k} must call {f}…)");
        }
    }
    // Nothing else names a kind or switches on one: each kind's tag appears in the shaders only in its cases (and
    // its definition), and `.kind` is read only by the dispatchers.
    let mut all = String::new();
    for (name, _) in mislab::render::shaders::FILES {
        if *name != "common.wgsl" {
            all += &code(name);
        }
    }
    for k in &kinds {
        assert_eq!(count(&all, &format!("LIGHT_{k}")), ops.len(), "LIGHT_{k} is named outside the light dispatchers");
    }
    assert_eq!(count(&all, ".kind"), ops.len(), "something besides the dispatchers reads a light's kind");
    // Rust: the tag is defined in gpu/types.rs, turned into table entries in render/scene_data/light_table.rs (and
    // counted in render/scene_data/mod.rs) and into HAS_* flags in render/features.rs, and named in no other file.
    for (name, text) in rust_sources(dir) {
        if kinds.iter().any(|k| text.contains(&format!("LIGHT_{k}"))) {
            assert!(
                ["gpu/types.rs", "render/scene_data/mod.rs", "render/scene_data/light_table.rs", "render/features.rs"]
                    .contains(&name.as_str()),
                "src/{name} names a light kind: adding one would have to touch it too"
            );
        }
    }
}

/// The material contract (docs/adding-a-material.md): every kind is one entry of `render::materials::MATERIALS` and
/// one file, `shaders/bsdf_<name>.wgsl`, with its parameter struct and the contract's functions; the generated
/// dispatchers have one line per kind each; no other shader names a kind's tag or override or reads the kind, and
/// in Rust only the registry names a tag (the scene's `MaterialKind` is the scene description and its importers').
#[test]
fn every_material_kind_is_its_file_and_its_registry_entry() {
    use mislab::render::materials::{dispatch_wgsl, MATERIALS};
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let strip =
        |text: &str| -> String { text.lines().map(|l| l.split("//").next().unwrap()).collect::<Vec<_>>().join("\n") };
    let count = |hay: &str, needle: &str| hay.matches(needle).count();
    let ops = ["eval", "pdf", "sample", "is_delta", "has_delta_lobe"];
    let generated = strip(&dispatch_wgsl());
    let body = |name: &str| -> String {
        let start = generated.find(&format!("fn {name}(")).unwrap_or_else(|| panic!("no dispatcher {name}"));
        let rest = &generated[start + 3..];
        rest[..rest.find("\nfn ").unwrap_or(rest.len())].to_string()
    };
    assert!(MATERIALS.len() >= 5, "material kinds: {}", MATERIALS.len());
    for e in MATERIALS {
        let upper = e.name.to_uppercase();
        assert_eq!(e.file, format!("bsdf_{}.wgsl", e.name), "{}: its file", e.name);
        assert_eq!(e.tag_const, format!("MATERIAL_{upper}"), "{}: its tag's name", e.name);
        assert_eq!(e.feature, format!("HAS_{upper}"), "{}: its override's name", e.name);
        let on_disk = std::fs::read_to_string(dir.join("shaders").join(e.file)).unwrap();
        assert_eq!(on_disk, e.source, "{}: the entry embeds another file", e.name);
        let code = strip(e.source);
        let camel: String = e.name.split('_').map(|w| w[..1].to_uppercase() + &w[1..]).collect();
        let params = format!("{camel}Params");
        assert_eq!(count(&code, &format!("struct {params} {{")), 1, "{} must define struct {params}", e.file);
        let unpack = format!("fn {}_params(p: BsdfParams) -> {params} {{", e.name);
        assert_eq!(count(&code, &unpack), 1, "{} must define `{unpack}`", e.file);
        for op in ops {
            let f = format!("fn {}_{op}(q: {params}", e.name);
            assert_eq!(count(&code, &f), 1, "{} must define `{f}…`", e.file);
            let b = body(&format!("bsdf_{op}"));
            let line = format!(
                "if ({} && p.bsdf_kind == {}) {{ return {}_{op}({}_params(p)",
                e.feature, e.tag_const, e.name, e.name
            );
            assert_eq!(count(&b, &line), 1, "bsdf_{op} needs one line for {}", e.name);
        }
        let transmits = format!("({} && p.bsdf_kind == {})", e.feature, e.tag_const);
        assert_eq!(count(&body("bsdf_transmits"), &transmits), usize::from(e.transmits), "bsdf_transmits: {}", e.name);
        // A kind's file names no kind's tag or override and reads no kind: the dispatchers chose it already.
        for other in MATERIALS {
            assert_eq!(count(&code, other.tag_const), 0, "{} names {}", e.file, other.tag_const);
            assert_eq!(count(&code, other.feature), 0, "{} names {}", e.file, other.feature);
        }
        assert_eq!(count(&code, ".bsdf_kind"), 0, "{} reads a kind", e.file);
    }
    // Each dispatcher reads the kind once per kind.
    for op in ops {
        assert_eq!(count(&body(&format!("bsdf_{op}")), ".bsdf_kind"), MATERIALS.len(), "bsdf_{op}");
    }
    // Every bsdf_*.wgsl but the shared bsdf.wgsl is a registry entry's file.
    for entry in std::fs::read_dir(dir.join("shaders")).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        if name.starts_with("bsdf_") {
            assert!(MATERIALS.iter().any(|e| e.file == name), "{name} is no entry of render::materials::MATERIALS");
        }
    }
    // The other shaders name no kind's tag or override, and only material_bsdf (surface.wgsl) reads the kind, to
    // copy it into BsdfParams.
    let mut all = String::new();
    for (name, text) in mislab::render::shaders::FILES {
        all += &strip(text);
        for e in MATERIALS {
            assert!(!strip(text).contains(e.tag_const), "{name} names {}", e.tag_const);
            assert!(!strip(text).contains(e.feature), "{name} names {}", e.feature);
        }
    }
    assert_eq!(count(&all, "MATERIAL_"), 0, "a shader names a material tag outside the generated dispatchers");
    assert_eq!(
        count(&all, ".bsdf_kind"),
        1,
        "something besides material_bsdf and the dispatchers reads a material's kind"
    );
    // Rust: the tags, their overrides and the kinds' words are named in render/materials.rs alone; `MaterialKind`
    // (the scene description) in scene/ (its importers) and the registry's `pack_*`.
    for (name, text) in rust_sources(dir) {
        if name == "render/materials.rs" {
            continue;
        }
        for e in MATERIALS {
            for word in [e.tag_const, e.feature] {
                assert!(!text.contains(word), "{name} names {word}: adding a material kind would have to touch it too");
            }
        }
        if text.contains("MaterialKind::") {
            assert!(name.starts_with("scene/"), "{name} names a MaterialKind: only the scene and its importers may");
        }
    }
}

/// On a device with 64-bit integers the render module reads vertices, wide nodes and light-tree nodes 32 bytes a
/// load: each 16-byte load file gives way to its `_int64` twin and exactly the bindings those read become
/// `array<vec4<u64>>`; the result validates. Without the feature the module is unchanged. No other code reads those
/// bindings (so redeclaring them cannot break a reader the twins do not replace).
#[test]
fn int64_devices_get_32_byte_loads_and_others_the_module_unchanged() {
    use mislab::render::bindings::{self, READ_32_BYTES_AT_A_TIME, WGSL_32_BYTE_ELEMENTS};
    use mislab::render::shaders::{file, for_device};
    let src = mislab::render::render_source();
    assert_eq!(for_device(&src, wgpu::Features::empty()), src.as_str());
    let wide = for_device(&src, wgpu::Features::SHADER_INT64);
    for f in ["geometry_loads", "light_tree_loads"] {
        assert!(!wide.contains(file(&format!("{f}.wgsl")).as_ref()), "{f}.wgsl still in the int64 module");
        assert!(wide.contains(file(&format!("{f}_int64.wgsl")).as_ref()), "{f}_int64.wgsl missing");
    }
    let declared_wide: Vec<&str> = bindings::all()
        .filter(|b| {
            wide.contains(&bindings::wgsl_declaration(&bindings::Binding { wgsl_type: WGSL_32_BYTE_ELEMENTS, ..*b }))
        })
        .map(|b| b.name)
        .collect();
    let mut expected: Vec<&str> = READ_32_BYTES_AT_A_TIME.iter().map(|(n, _)| *n).collect();
    expected.sort_by_key(|n| bindings::all().position(|b| b.name == *n));
    assert_eq!(declared_wide, expected);
    if let Err(e) = mislab::render::shaders::validate(&wide) {
        panic!("int64 render module:\n{e}");
    }
    // Only the load files index these bindings.
    for (name, _) in READ_32_BYTES_AT_A_TIME {
        for (f, text) in mislab::render::shaders::FILES {
            if !f.contains("_loads") {
                assert!(
                    !text.contains(&format!("{name}[")),
                    "{f} reads {name} directly: read it through its load file"
                );
            }
        }
    }
}

/// Padding for 32-byte reads: whole elements (at least one) for those bindings, nothing for the others.
#[test]
fn only_32_byte_read_bindings_are_padded() {
    use mislab::render::bindings::pad_for_32_byte_reads;
    for (len, want) in [(0, 32), (16, 32), (32, 32), (48, 64), (80, 96), (160, 160)] {
        assert_eq!(pad_for_32_byte_reads("wide_nodes", &vec![7u8; len]).len(), want, "{len} bytes");
        assert_eq!(pad_for_32_byte_reads("tri_lights", &vec![7u8; len]).len(), len);
    }
    let p = pad_for_32_byte_reads("tri_verts", &[1u8; 48]);
    assert_eq!(&p[..48], &[1u8; 48]);
    assert!(p[48..].iter().all(|&b| b == 0));
}

/// A damaged pipeline cache file is reported and ignored (the run goes on with an empty cache) and the next save
/// rewrites it whole; a device without a pipeline cache has no store at all.
#[test]
fn a_damaged_pipeline_cache_is_a_note_and_is_rewritten_whole() {
    use mislab::gpu::pipeline_store::{file_for, unframe, PipelineStore};
    let ctx = common_gpu();
    let dir = std::env::temp_dir().join(format!("mislab-pcache-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let has_cache = ctx.device.features().contains(wgpu::Features::PIPELINE_CACHE);
    let Some(path) = file_for(&dir, &ctx.info).filter(|_| has_cache) else {
        assert!(ctx.pipelines.store().is_none(), "a device without a pipeline cache has no store");
        return;
    };
    std::fs::write(&path, b"MISLPC01 this is not what was written").unwrap();
    let (store, note) = PipelineStore::open(&ctx.device, &ctx.info, &dir);
    let note = note.expect("a damaged file is reported");
    assert!(note.contains("ignored") && note.contains(&path.display().to_string()), "{note}");
    let store = store.expect("the run goes on with an empty cache");
    drop(store); // saves what the driver holds
    let written = std::fs::read(&path).unwrap();
    assert!(unframe(&written).is_ok(), "the file was rewritten in a whole frame");
    let (again, note) = PipelineStore::open(&ctx.device, &ctx.info, &dir);
    assert!(again.is_some() && note.is_none(), "the rewritten file loads cleanly: {note:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

fn common_gpu() -> mislab::gpu::GpuContext {
    mislab::gpu::GpuContext::new().unwrap_or_else(|e| panic!("this test needs a Vulkan adapter and found none ({e})"))
}

/// Every `.rs` file of `src/`: its path below `src/` (with `/`) and its text.
fn rust_sources(dir: &std::path::Path) -> Vec<(String, String)> {
    let src = dir.join("src");
    let mut files = Vec::new();
    let mut stack = vec![src.clone()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let name = p.strip_prefix(&src).unwrap().to_str().unwrap().replace('\\', "/");
                files.push((name, std::fs::read_to_string(&p).unwrap()));
            }
        }
    }
    files
}
