//! WGSL composition: every shader file is embedded in the binary (the product never reads `shaders/` at
//! run time); an entry point is an ordered list of files concatenated into one module.

use crate::gpu::PipelineStore;
use crate::render::shader_prune;

/// Every WGSL file but the materials', by name, embedded at compile time (each material kind's file is embedded by
/// its entry in `crate::render::materials::MATERIALS`).
pub const FILES: &[(&str, &str)] = &[
    ("common.wgsl", include_str!("../../shaders/common.wgsl")),
    ("bvh.wgsl", include_str!("../../shaders/bvh.wgsl")),
    ("bvh_wide.wgsl", include_str!("../../shaders/bvh_wide.wgsl")),
    ("geometry_loads.wgsl", include_str!("../../shaders/geometry_loads.wgsl")),
    ("geometry_loads_int64.wgsl", include_str!("../../shaders/geometry_loads_int64.wgsl")),
    ("baked_geometry.wgsl", include_str!("../../shaders/baked_geometry.wgsl")),
    ("scene_data.wgsl", include_str!("../../shaders/scene_data.wgsl")),
    ("specialize.wgsl", include_str!("../../shaders/specialize.wgsl")),
    ("rng.wgsl", include_str!("../../shaders/rng.wgsl")),
    ("samplers.wgsl", include_str!("../../shaders/samplers.wgsl")),
    ("warps.wgsl", include_str!("../../shaders/warps.wgsl")),
    ("pixel_filter.wgsl", include_str!("../../shaders/pixel_filter.wgsl")),
    ("bsdf.wgsl", include_str!("../../shaders/bsdf.wgsl")),
    ("surface.wgsl", include_str!("../../shaders/surface.wgsl")),
    ("alpha.wgsl", include_str!("../../shaders/alpha.wgsl")),
    ("lights.wgsl", include_str!("../../shaders/lights.wgsl")),
    ("env_guide.wgsl", include_str!("../../shaders/env_guide.wgsl")),
    ("light_tree.wgsl", include_str!("../../shaders/light_tree.wgsl")),
    ("light_tree_loads.wgsl", include_str!("../../shaders/light_tree_loads.wgsl")),
    ("light_tree_loads_int64.wgsl", include_str!("../../shaders/light_tree_loads_int64.wgsl")),
    ("mis.wgsl", include_str!("../../shaders/mis.wgsl")),
    ("estimators.wgsl", include_str!("../../shaders/estimators.wgsl")),
    ("integrator.wgsl", include_str!("../../shaders/integrator.wgsl")),
    ("display.wgsl", include_str!("../../shaders/display.wgsl")),
];

/// Modules generated from Rust tables rather than embedded: the binding declarations (`crate::render::bindings`)
/// and the material kinds with their dispatchers (`crate::render::materials`).
pub const GENERATED: &[&str] = &["geometry_bindings.wgsl", "shading_bindings.wgsl", "bsdf_materials.wgsl"];

/// The source of one embedded or generated file.
pub fn file(name: &str) -> std::borrow::Cow<'static, str> {
    match name {
        "geometry_bindings.wgsl" => crate::render::bindings::geometry_wgsl().into(),
        "shading_bindings.wgsl" => crate::render::bindings::shading_wgsl().into(),
        "bsdf_materials.wgsl" => crate::render::materials::dispatch_wgsl().into(),
        _ => FILES
            .iter()
            .copied()
            .chain(crate::render::materials::MATERIALS.iter().map(|e| (e.file, e.source)))
            .find(|(n, _)| *n == name)
            .map(|(_, s)| s.into())
            .unwrap_or_else(|| panic!("no embedded shader file named {name}")),
    }
}

/// Concatenates files (in order) and extra source into one module, with a marker line per file so
/// naga's error positions can be traced back.
pub fn compose(files: &[&str], extra: &str) -> String {
    let mut out = String::new();
    for f in files {
        out += &format!("// ---- {f} ----\n");
        out += &file(f);
        out += "\n";
    }
    out += extra;
    out
}

/// `compose` with some files' text replaced (a scene's generated `scene_data.wgsl` and `baked_geometry.wgsl`).
pub fn compose_replacing(files: &[&str], replacements: &[(&str, &str)]) -> String {
    let mut out = String::new();
    for f in files {
        out += &format!("// ---- {f} ----\n");
        match replacements.iter().find(|(n, _)| n == f) {
            Some((_, text)) => out += text,
            None => out += &file(f),
        }
        out += "\n";
    }
    out
}

/// Parses and validates a composed module with naga, returning the module or a readable error.
pub fn validate(source: &str) -> Result<naga::Module, String> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| e.emit_to_string(source))?;
    let mut validator =
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all());
    validator.validate(&module).map_err(|e| e.emit_to_string(source))?;
    Ok(module)
}

/// The line of `bvh_all_lanes` (shaders/bvh.wgsl) that a device with subgroup operations replaces.
const BVH_VOTE_FALLBACK: &str = "return b; // BVH_VOTE";

/// A composed module as `device` compiles it. The one place a device changes shader text, so every pipeline
/// (render, viewer, probes) gets the same code:
/// - with subgroup operations (wgpu's `Features::SUBGROUP`, which `GpuContext` requests where offered) the BVH2
///   traversal's vote becomes `subgroupAll`; without them each lane votes alone (a plain while-while loop). The
///   wide traversal, the default, has no vote.
/// - with 64-bit integers (`Features::SHADER_INT64`, requested where offered) each file of 16-byte loads in
///   [`bindings::READ_32_BYTES_AT_A_TIME`] gives way to its `_int64` twin, and the bindings it reads are declared
///   `array<vec4<u64>>`: 32 bytes a load (docs/profile-bvh.md has the measurement).
pub fn for_device(source: &str, features: wgpu::Features) -> std::borrow::Cow<'_, str> {
    let mut out = std::borrow::Cow::Borrowed(source);
    if features.contains(wgpu::Features::SUBGROUP) && source.contains(BVH_VOTE_FALLBACK) {
        // (naga 30 takes subgroup builtins without WGSL's `enable subgroups;`, which it rejects as unimplemented.)
        out = out.replace(BVH_VOTE_FALLBACK, "return subgroupAll(b);").into();
    }
    // The packed scene layout reads every table as words (`packed_scene`): its loads have no 32-byte twin.
    if features.contains(wgpu::Features::SHADER_INT64) && !crate::render::packed_scene::is_packed(&out) {
        out = with_32_byte_loads(&out).map_or(out, Into::into);
    }
    out
}

/// `source` with its 16-byte load files swapped for their `_int64` twins and the bindings they read redeclared
/// (see [`for_device`]), or None where it has none of those files. A binding is redeclared only with the file that
/// reads it, and only these files read those bindings.
pub fn with_32_byte_loads(source: &str) -> Option<String> {
    use crate::render::bindings;
    let mut out = source.to_string();
    let mut changed = false;
    let mut files: Vec<&str> = bindings::READ_32_BYTES_AT_A_TIME.iter().map(|(_, f)| *f).collect();
    files.dedup();
    for portable in files {
        let text = file(portable);
        if !out.contains(text.as_ref()) {
            continue;
        }
        let twin = file(&portable.replace(".wgsl", "_int64.wgsl"));
        out = out.replace(text.as_ref(), &twin);
        for b in bindings::all().filter(|b| bindings::READ_32_BYTES_AT_A_TIME.contains(&(b.name, portable))) {
            let wide = bindings::Binding { wgsl_type: bindings::WGSL_32_BYTE_ELEMENTS, ..b };
            out = out.replace(&bindings::wgsl_declaration(&b), &bindings::wgsl_declaration(&wide));
            // Only the twin reads the redeclared binding: the portable accessors go with the portable file.
            out = out.replace(&bindings::scene_accessors(&b), "");
        }
        changed = true;
    }
    changed.then_some(out)
}

/// Builds a compute pipeline from a composed module (validated by naga first so errors are readable), specialised
/// to `constants` and pruned before the driver sees it (`shader_prune`), through the driver's on-disk pipeline
/// cache where there is one (`store`; saved as soon as the pipeline is built).
pub fn compute_pipeline(
    device: &wgpu::Device,
    store: Option<&PipelineStore>,
    label: &str,
    source: &str,
    entry: &str,
    constants: &[(&str, f64)],
    layout: Option<&wgpu::PipelineLayout>,
) -> Result<wgpu::ComputePipeline, String> {
    let source = for_device(source, device.features());
    let parsed = validate(&source).map_err(|e| format!("shader '{label}' failed to validate:\n{e}"))?;
    // The driver gets the module specialised and pruned (`shader_prune`): start-up is its compilation. Should the
    // pruner ever fail on a valid module, the driver still gets the module as written, with its overrides.
    let pruned = shader_prune::specialized_wgsl(&parsed, entry, constants)
        .map_err(|e| eprintln!("warning: shader '{label}' compiled unpruned (slower start-up): {e}"))
        .ok();
    let (source, constants): (std::borrow::Cow<str>, &[(&str, f64)]) = match pruned {
        Some(p) => (p.into(), &[]),
        None => (source, constants),
    };
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout,
        module: &module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions { constants, zero_initialize_workgroup_memory: false },
        cache: store.map(PipelineStore::cache),
    });
    if let Some(store) = store {
        store.save_or_warn();
    }
    Ok(pipeline)
}
