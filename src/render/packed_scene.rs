//! The packed scene layout: every table of group 0 in one storage buffer of words, for devices that bind fewer
//! storage buffers per shader stage than the scene's twenty plus the frame's five (WebGPU guarantees 8).
//!
//! The buffer starts with a header, two words per binding of `bindings::SCENE` in its order: where the table's
//! words begin and how many elements it has (at least one: an empty table is one zero element, as its own buffer
//! would be). Each table follows, whole 16-byte groups. Shaders never name a scene binding: they call
//! `load_<name>(i)` and `len_<name>()` (`bindings::scene_accessors`), which [`packed_source`] rewrites to read
//! the words — each struct rebuilt member by member from the layout naga computes for it — so every kernel runs
//! on either layout unchanged.

use crate::render::bindings::{self, Access, Binding, SCENE};
use crate::render::scene_data::SceneData;
use naga::{Scalar, ScalarKind, TypeInner};
use std::fmt::Write;

/// The binding of the packed buffer in group 0 (after the twenty it replaces, so a module can declare both).
pub const PACKED_BINDING: u32 = SCENE.len() as u32;

/// The packed buffer's binding.
pub const PACKED: Binding = Binding {
    group: 0,
    binding: PACKED_BINDING,
    name: "scene_words",
    wgsl_type: "array<u32>",
    access: Access::Read,
    element_size: 4,
    label: "packed scene tables",
    note: "Every scene table in one buffer (src/render/packed_scene.rs): a header, then the tables.",
};

/// How a scene's tables are bound.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SceneLayout {
    /// One storage buffer per table (`bindings::SCENE`): the fastest reads.
    Separate,
    /// One buffer of words holding every table, for devices with few storage-buffer bindings.
    Packed,
}

/// Whether a composed module reads the packed layout.
pub fn is_packed(source: &str) -> bool {
    source.contains(&bindings::wgsl_declaration(&PACKED))
}

/// The words of the packed buffer for `data`.
pub fn pack(data: &SceneData) -> Vec<u32> {
    let mut words = vec![0u32; 2 * SCENE.len()];
    for (k, b) in SCENE.iter().enumerate() {
        let bytes = (b.bytes)(data);
        let size = b.binding.element_size;
        let count = (bytes.len() / size).max(1);
        words[2 * k] = words.len() as u32;
        words[2 * k + 1] = count as u32;
        words.extend(bytes.chunks_exact(4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])));
        let end = words[2 * k] as usize + (count * size).div_ceil(16) * 4;
        words.resize(end, 0);
    }
    words
}

/// A composed module (written for the separate layout) as `layout` needs it.
pub fn for_layout(source: String, layout: SceneLayout) -> Result<String, String> {
    match layout {
        SceneLayout::Separate => Ok(source),
        SceneLayout::Packed => packed_source(&source),
    }
}

/// `source` (a composed module on the separate layout) rewritten for the packed one: the scene bindings' declarations
/// and accessors replaced by the packed buffer and accessors that read it.
pub fn packed_source(source: &str) -> Result<String, String> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| e.emit_to_string(source))?;
    let mut out = source.to_string();
    let mut accessors = format!(
        "\n// ---- the packed scene layout (src/render/packed_scene.rs) ----\n{}",
        bindings::wgsl_declaration(&PACKED)
    );
    for (k, scene_binding) in SCENE.iter().enumerate() {
        let b = &scene_binding.binding;
        let declaration = bindings::wgsl_declaration(b);
        if !out.contains(&declaration) {
            continue;
        }
        out = out.replace(&declaration, "").replace(&bindings::scene_accessors(b), "");
        let global = module.global_variables.iter().find(|(_, g)| g.name.as_deref() == Some(b.name));
        let ty = global.map(|(_, g)| g.ty).ok_or_else(|| format!("no binding {} in the module", b.name))?;
        let TypeInner::Array { base, stride, .. } = module.types[ty].inner else {
            return Err(format!("binding {} is not an array", b.name));
        };
        let value = from_words(&module, base, 0)?;
        let (name, ty_name) = (b.name, bindings::element_type(b));
        let _ = writeln!(
            accessors,
            "fn load_{name}(i: u32) -> {ty_name} {{ let o = scene_words[{}u] + i * {}u; return {value}; }}\n\
             fn len_{name}() -> u32 {{ return scene_words[{}u]; }}",
            2 * k,
            stride / 4,
            2 * k + 1
        );
    }
    Ok(out + &accessors)
}

/// A WGSL expression building a value of type `ty` from the words at `o + word` of `scene_words` (struct members
/// at the offsets naga's layout gives them).
fn from_words(module: &naga::Module, ty: naga::Handle<naga::Type>, word: u32) -> Result<String, String> {
    let scalar = |s: Scalar, w: u32| -> Result<String, String> {
        let load = format!("scene_words[o + {w}u]");
        match (s.kind, s.width) {
            (ScalarKind::Uint, 4) => Ok(load),
            (ScalarKind::Float, 4) => Ok(format!("bitcast<f32>({load})")),
            (ScalarKind::Sint, 4) => Ok(format!("bitcast<i32>({load})")),
            _ => Err(format!("no packed read for {s:?}")),
        }
    };
    let scalar_name = |s: Scalar| match s.kind {
        ScalarKind::Float => "f32",
        ScalarKind::Sint => "i32",
        _ => "u32",
    };
    match module.types[ty].inner {
        TypeInner::Scalar(s) => scalar(s, word),
        TypeInner::Vector { size, scalar: s } => {
            let parts: Result<Vec<_>, _> = (0..size as u32).map(|c| scalar(s, word + c)).collect();
            Ok(format!("vec{}<{}>({})", size as u32, scalar_name(s), parts?.join(", ")))
        }
        TypeInner::Struct { ref members, .. } => {
            let name = module.types[ty].name.clone().ok_or("an unnamed struct")?;
            let parts: Result<Vec<_>, _> =
                members.iter().map(|m| from_words(module, m.ty, word + m.offset / 4)).collect();
            Ok(format!("{name}({})", parts?.join(", ")))
        }
        ref other => Err(format!("no packed read for {other:?}")),
    }
}
