//! glTF 2.0 loader: `.gltf` (external files or base64 `data:` URIs) and `.glb`.
//!
//! The JSON is parsed into `gltf::json` types, but buffers, accessors and images are read here rather than
//! through `gltf::import` / `gltf::Document`: gltf 1.4.1 panics on some dangling indices and silently reads
//! garbage for bad strides or ranges. So every index, byte range, count and format is checked first, and
//! errors name the accessor, mesh and primitive they belong to.
//!
//! Conventions of the result:
//! - One `Mesh` per primitive per node instance, in world space; mirrored transforms (negative determinant)
//!   swap two indices per triangle so the counter-clockwise geometric normal stays outward.
//! - Missing normals, and zero or non-finite ones, are generated per vertex as the area-weighted sum of the
//!   adjacent face normals (smooth shading; shared vertices across hard edges are averaged).
//! - UVs keep glTF's convention: (0, 0) is the top-left texel, i.e. the first row of `Texture::texels`.
//! - Materials and textures appear in first-use order; only what the chosen scene uses is loaded.

use super::{Camera, LoadOptions, Material, Mesh, PunctualLight, Scene, SceneError, Texture, TextureRef, Wrap};
use glam::{Mat3, Mat4, Quat, Vec2, Vec3};
use gltf::json;
use json::accessor::{ComponentType, GenericComponentType, IndexComponentType, Type};
use json::extensions::scene::khr_lights_punctual as punctual;
use json::mesh::{Mode, Semantic};
use json::validation::Checked;
use std::collections::{HashMap, HashSet};
use std::io::Cursor;
use std::path::Path;
use std::rc::Rc;

/// Largest texture side we accept (the GPU texture limit we design for).
const MAX_TEXTURE_SIZE: u32 = 16384;
/// Largest accessor element count; rejects absurd counts before anything is allocated.
const MAX_ELEMENTS: u64 = 1 << 26;
/// Deepest node hierarchy we follow (bounds the recursion).
const MAX_DEPTH: usize = 512;
/// Most node instances one scene may expand to (a node shared by many parents can multiply).
const MAX_NODE_VISITS: usize = 1 << 20;
/// Extensions that we implement.
const SUPPORTED: &[&str] =
    &["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_specular", "KHR_texture_transform"];
/// GLB chunk types.
const GLB_JSON: u32 = 0x4E4F_534A;
const GLB_BIN: u32 = 0x004E_4942;

type Res<T> = Result<T, String>;

/// Loads a glTF 2.0 file (`.gltf` or `.glb`) into a world-space [`Scene`].
///
/// Uses the file's default scene, or `options.gltf_scene`, or scene 0 when the file names no default. Errors
/// name the file and the offending object; repairs and skipped content are listed in `Scene::warnings`.
pub fn load(path: &Path, options: &LoadOptions) -> Result<Scene, SceneError> {
    load_inner(path, options).map_err(|message| SceneError::new(path, message))
}

fn load_inner(path: &Path, options: &LoadOptions) -> Res<Scene> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read the file: {e}"))?;
    let (json_bytes, bin) = split_container(path, &bytes)?;
    let is_glb = bytes.starts_with(b"glTF");
    let root = parse_json(json_bytes)?;
    let mut notes = Notes::default();
    check_extensions(&root, &mut notes)?;
    check_node_graph(&root)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let buffers = load_buffers(&root, bin, is_glb, base)?;
    let mut loader = Loader::new(&root, base, buffers, notes);
    loader.scene.name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let roots = loader.scene_roots(options)?;
    let mut on_path = vec![false; root.nodes.len()];
    for node in roots {
        loader.visit(node, &Mat4::IDENTITY, &mut on_path, 0)?;
    }
    Ok(loader.finish())
}

// ---------------------------------------------------------------------------------------------------------
// Container, JSON, extensions, buffers

/// Splits a file into its JSON text and, for GLB, the binary chunk.
fn split_container<'b>(path: &Path, bytes: &'b [u8]) -> Res<(&'b [u8], Option<&'b [u8]>)> {
    if bytes.starts_with(b"glTF") {
        return parse_glb(bytes);
    }
    let is_glb = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    let looks_like_json = bytes.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'{');
    if is_glb && !looks_like_json {
        let head = &bytes[..bytes.len().min(4)];
        return Err(format!("not a binary glTF file: expected the magic bytes \"glTF\", found {head:02x?}"));
    }
    // A UTF-8 byte-order mark is not allowed by the spec, but harmless; serde_json would reject it.
    Ok((bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes), None))
}

fn read_u32(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]])
}

/// Parses the GLB header and chunks, checking every declared length against the actual file size.
fn parse_glb(bytes: &[u8]) -> Res<(&[u8], Option<&[u8]>)> {
    if bytes.len() < 12 {
        return Err(format!("truncated GLB: {} bytes, shorter than the 12-byte header", bytes.len()));
    }
    let version = read_u32(bytes, 4);
    if version != 2 {
        return Err(format!("GLB container version {version} is not supported (expected 2)"));
    }
    let total = read_u32(bytes, 8) as usize;
    if total > bytes.len() {
        return Err(format!("truncated GLB: the header declares {total} bytes but the file has {}", bytes.len()));
    }
    if total < 12 {
        return Err(format!(
            "invalid GLB header: it declares a total length of {total} bytes, less than the header's own 12"
        ));
    }
    let (mut json, mut bin, mut at) = (None, None, 12usize);
    while at < total {
        if total - at < 8 {
            return Err(format!("truncated GLB: incomplete chunk header at byte {at}"));
        }
        let (len, kind, start) = (read_u32(bytes, at) as usize, read_u32(bytes, at + 4), at + 8);
        if len > total - start {
            let left = total - start;
            return Err(format!("truncated GLB: a chunk at byte {at} declares {len} bytes but only {left} remain"));
        }
        let data = &bytes[start..start + len];
        match kind {
            GLB_JSON if json.is_none() => json = Some(data),
            GLB_BIN if bin.is_none() => bin = Some(data),
            _ => {} // unknown chunk types must be ignored (spec)
        }
        at = start + len;
    }
    Ok((json.ok_or("GLB file has no JSON chunk")?, bin))
}

fn parse_json(bytes: &[u8]) -> Res<json::Root> {
    let root: json::Root = match json::deserialize::from_slice(bytes) {
        Ok(root) => root,
        // Keep the first error: it has a line and column, the retry's would not.
        Err(e) => parse_lenient(bytes).ok_or_else(|| format!("invalid glTF JSON: {e}"))?,
    };
    if !root.asset.version.starts_with("2.") {
        return Err(format!("glTF version '{}' is not supported (only 2.x)", root.asset.version));
    }
    Ok(root)
}

/// Retries after filling in what the spec makes optional but gltf-json 1.4.1 requires (`scene.nodes`).
fn parse_lenient(bytes: &[u8]) -> Option<json::Root> {
    let mut value: json::Value = json::deserialize::from_slice(bytes).ok()?;
    for scene in value.get_mut("scenes")?.as_array_mut()? {
        if let Some(scene) = scene.as_object_mut() {
            scene.entry("nodes").or_insert_with(|| json::Value::Array(Vec::new()));
        }
    }
    json::deserialize::from_value(value).ok()
}

/// Rejects files that require an extension we do not implement; notes used-but-ignored ones.
fn check_extensions(root: &json::Root, notes: &mut Notes) -> Res<()> {
    if let Some(ext) = root.extensions_required.iter().find(|e| !SUPPORTED.contains(&e.as_str())) {
        return Err(format!(
            "the file requires the glTF extension {ext}, which is not supported (supported: {})",
            SUPPORTED.join(", ")
        ));
    }
    let ignored: Vec<&str> =
        root.extensions_used.iter().map(String::as_str).filter(|e| !SUPPORTED.contains(e)).collect();
    if !ignored.is_empty() {
        notes.push(format!("ignoring unsupported glTF extension(s): {}", ignored.join(", ")));
    }
    Ok(())
}

/// Checks the whole node graph before anything is instantiated: every child index exists, and no node is its
/// own ancestor. Nodes that no scene uses are checked too (a cycle makes the file invalid wherever it is), and
/// the error shows the cycle. Iterative, so arbitrarily deep (valid) hierarchies cannot overflow the stack.
fn check_node_graph(root: &json::Root) -> Res<()> {
    let nodes = &root.nodes;
    let label = |i: usize| format!("node {i}{}", quoted(&nodes[i].name));
    // 0 = not visited, 1 = on the current path, 2 = done.
    let mut state = vec![0u8; nodes.len()];
    for start in 0..nodes.len() {
        if state[start] != 0 {
            continue;
        }
        // (node, index of the next child to visit)
        let mut stack = vec![(start, 0usize)];
        state[start] = 1;
        while let Some(top) = stack.last_mut() {
            let (node, next) = *top;
            let children = nodes[node].children.as_deref().unwrap_or(&[]);
            let Some(child) = children.get(next).map(|c| c.value()) else {
                state[node] = 2;
                stack.pop();
                continue;
            };
            top.1 += 1;
            if child >= nodes.len() {
                let count = nodes.len();
                return Err(format!("{}: child node {child} does not exist (the file has {count} nodes)", label(node)));
            }
            match state[child] {
                0 => {
                    state[child] = 1;
                    stack.push((child, 0));
                }
                1 => {
                    let from = stack.iter().position(|&(n, _)| n == child).unwrap_or(0);
                    let path: Vec<String> =
                        stack[from..].iter().map(|&(n, _)| n.to_string()).chain([child.to_string()]).collect();
                    return Err(format!(
                        "{} is its own ancestor: the node hierarchy contains a cycle (nodes {})",
                        label(child),
                        path.join(" → ")
                    ));
                }
                _ => {}
            }
        }
    }
    Ok(())
}

/// Reads every buffer (GLB chunk, external file or data URI) and checks it against its declared byteLength.
fn load_buffers(root: &json::Root, bin: Option<&[u8]>, is_glb: bool, base: &Path) -> Res<Vec<Vec<u8>>> {
    let mut out = Vec::with_capacity(root.buffers.len());
    for (i, buffer) in root.buffers.iter().enumerate() {
        let what = format!("buffer {i}{}", quoted(&buffer.name));
        let mut data = match (&buffer.uri, bin) {
            (Some(uri), _) => fetch_uri(base, uri).map_err(|m| format!("{what}: {m}"))?,
            (None, Some(bin)) if i == 0 => bin.to_vec(),
            (None, None) if i == 0 && is_glb => {
                return Err(format!("{what} has no uri, and the GLB file has no BIN chunk to hold its data"))
            }
            (None, _) => return Err(format!("{what} has no uri (only a .glb's first buffer may omit it)")),
        };
        let declared = buffer.byte_length.0;
        if (data.len() as u64) < declared {
            return Err(format!("{what}: byteLength is {declared} but only {} bytes of data are present", data.len()));
        }
        data.truncate(declared as usize);
        out.push(data);
    }
    Ok(out)
}

/// Bytes behind a URI: a base64 `data:` URI or a file path relative to the glTF file.
fn fetch_uri(base: &Path, uri: &str) -> Res<Vec<u8>> {
    if let Some(rest) = uri.strip_prefix("data:") {
        return decode_data_uri(rest);
    }
    let scheme = uri.split_once(':').map(|(s, _)| s).unwrap_or("");
    if scheme.len() > 1 && scheme.chars().all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c)) {
        return Err(format!("URI '{uri}' is neither a relative file path nor a data: URI (nothing is downloaded)"));
    }
    let decoded = base.join(percent_decode(uri).unwrap_or_else(|| uri.to_string()));
    match std::fs::read(&decoded) {
        Ok(bytes) => Ok(bytes),
        // Some exporters write file names without percent-encoding; try the URI as written too.
        Err(_) if base.join(uri).is_file() => std::fs::read(base.join(uri)).map_err(|e| e.to_string()),
        Err(e) => Err(format!("cannot read '{}': {e}", decoded.display())),
    }
}

fn decode_data_uri(rest: &str) -> Res<Vec<u8>> {
    use base64::Engine;
    let (header, payload) = rest.split_once(',').ok_or("malformed data URI (no ',')")?;
    if !header.ends_with(";base64") {
        return Err(format!("data URI 'data:{header},…' is not base64-encoded (glTF requires ';base64')"));
    }
    let config = base64::engine::GeneralPurposeConfig::new()
        .with_decode_padding_mode(base64::engine::DecodePaddingMode::Indifferent);
    let engine = base64::engine::GeneralPurpose::new(&base64::alphabet::STANDARD, config);
    engine.decode(payload.trim()).map_err(|e| format!("invalid base64 in data URI: {e}"))
}

/// Decodes `%XX` escapes; None when an escape is malformed or the result is not UTF-8.
fn percent_decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let (mut out, mut i) = (Vec::with_capacity(bytes.len()), 0);
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// `" 'name'"` or nothing, for messages.
fn quoted(name: &Option<String>) -> String {
    name.as_ref().map(|n| format!(" '{n}'")).unwrap_or_default()
}

// ---------------------------------------------------------------------------------------------------------
// Warnings

/// Warnings collected while loading; repeated problems are counted and reported once.
#[derive(Default)]
struct Notes {
    lines: Vec<String>,
    seen: HashSet<String>,
    skipped_primitives: usize,
    dropped_triangles: usize,
    repaired_normals: usize,
    repaired_uvs: usize,
}

impl Notes {
    fn push(&mut self, line: String) {
        if self.seen.insert(line.clone()) {
            self.lines.push(line);
        }
    }
    /// Adds `line` unless a warning with the same `key` was already added.
    fn once(&mut self, key: &str, line: impl FnOnce() -> String) {
        if self.seen.insert(format!("\u{0}{key}")) {
            self.lines.push(line());
        }
    }
    fn finish(mut self) -> Vec<String> {
        let counted = [
            (
                self.skipped_primitives,
                "skipped point/line primitive(s) (POINTS, LINES, LINE_LOOP, LINE_STRIP): only triangles are rendered",
            ),
            (self.dropped_triangles, "dropped triangle(s) that use non-finite (NaN/Inf) vertex positions"),
            (self.repaired_normals, "zero or non-finite vertex normal(s) regenerated from the geometry"),
            (self.repaired_uvs, "non-finite texture coordinate(s) replaced with 0"),
        ];
        for (n, what) in counted.into_iter().filter(|(n, _)| *n > 0) {
            self.lines.push(format!("{n} {what}"));
        }
        self.lines
    }
}

// ---------------------------------------------------------------------------------------------------------
// Accessors

/// What an accessor is read for; decides the accepted type and component types.
#[derive(Clone, Copy)]
enum Usage {
    Position,
    Normal,
    TexCoord,
    Indices,
}

impl Usage {
    fn name(self) -> &'static str {
        match self {
            Usage::Position => "POSITION",
            Usage::Normal => "NORMAL",
            Usage::TexCoord => "TEXCOORD_0",
            Usage::Indices => "indices",
        }
    }
    fn ty(self) -> Type {
        match self {
            Usage::Position | Usage::Normal => Type::Vec3,
            Usage::TexCoord => Type::Vec2,
            Usage::Indices => Type::Scalar,
        }
    }
    /// The component types the core spec allows (no KHR_mesh_quantization).
    fn accepts(self, comp: ComponentType, normalized: bool) -> bool {
        use ComponentType::*;
        match self {
            Usage::Position | Usage::Normal => comp == F32 && !normalized,
            Usage::TexCoord => (comp == F32 && !normalized) || (normalized && matches!(comp, U8 | U16)),
            Usage::Indices => !normalized && matches!(comp, U8 | U16 | U32),
        }
    }
    fn expected(self) -> &'static str {
        match self {
            Usage::Position | Usage::Normal => "FLOAT",
            Usage::TexCoord => "FLOAT, or normalized UNSIGNED_BYTE / UNSIGNED_SHORT",
            Usage::Indices => "UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT",
        }
    }
}

fn type_name(ty: Type) -> &'static str {
    match ty {
        Type::Scalar => "SCALAR",
        Type::Vec2 => "VEC2",
        Type::Vec3 => "VEC3",
        Type::Vec4 => "VEC4",
        Type::Mat2 => "MAT2",
        Type::Mat3 => "MAT3",
        Type::Mat4 => "MAT4",
    }
}

/// Checks an accessor's type and component type for `usage`; returns the component type and count.
fn check_format(acc: &json::Accessor, usage: Usage) -> Res<(ComponentType, usize)> {
    let Checked::Valid(ty) = acc.type_ else { return Err("invalid accessor type".into()) };
    let Checked::Valid(GenericComponentType(comp)) = acc.component_type else {
        return Err("invalid componentType".into());
    };
    if ty != usage.ty() {
        let (got, want) = (type_name(ty), type_name(usage.ty()));
        return Err(format!("type {got} is not valid for {} (expected {want})", usage.name()));
    }
    if !usage.accepts(comp, acc.normalized) {
        let norm = if acc.normalized { "normalized " } else { "" };
        return Err(format!(
            "componentType {} ({norm}{comp:?}) is not valid for {} (expected {})",
            comp.as_gl_enum(),
            usage.name(),
            usage.expected()
        ));
    }
    Ok((comp, ty.multiplicity()))
}

/// Rejects absurd element counts before anything is allocated for them.
fn check_count(acc: &json::Accessor) -> Res<()> {
    if acc.count.0 > MAX_ELEMENTS {
        return Err(format!("count {} exceeds the limit of {MAX_ELEMENTS} elements", acc.count.0));
    }
    Ok(())
}

/// A validated strided view of `count` elements: element i is `bytes[i*stride .. i*stride+elem]`.
struct Layout<'b> {
    bytes: &'b [u8],
    stride: usize,
    elem: usize,
}

impl Layout<'_> {
    fn element(&self, i: usize) -> &[u8] {
        &self.bytes[i * self.stride..i * self.stride + self.elem]
    }
}

fn to_f32(b: &[u8], comp: ComponentType, normalized: bool) -> f32 {
    use ComponentType::*;
    let (value, scale) = match comp {
        F32 => return f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        U8 => (b[0] as f32, 255.0),
        I8 => (b[0] as i8 as f32, 127.0),
        U16 => (u16::from_le_bytes([b[0], b[1]]) as f32, 65535.0),
        I16 => (i16::from_le_bytes([b[0], b[1]]) as f32, 32767.0),
        U32 => (u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32, u32::MAX as f32),
    };
    if normalized {
        (value / scale).max(-1.0)
    } else {
        value
    }
}

fn to_u32(b: &[u8], comp: ComponentType, _normalized: bool) -> u32 {
    match comp {
        ComponentType::U8 | ComponentType::I8 => b[0] as u32,
        ComponentType::U16 | ComponentType::I16 => u16::from_le_bytes([b[0], b[1]]) as u32,
        _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    }
}

/// Converts one component (the bytes start at it) of the given type to the output type.
type Convert<T> = fn(&[u8], ComponentType, bool) -> T;

// ---------------------------------------------------------------------------------------------------------
// The loader

/// Texture cache key: image, wrap S, wrap T, nearest, sRGB.
type TexKey = (usize, u8, u8, bool, bool);

/// A decoded RGBA8 image, shared by the textures that sample it.
struct Decoded {
    width: u32,
    height: u32,
    texels: Vec<[u8; 4]>,
}

/// One primitive's vertex data in its mesh's local space.
struct Geometry {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Vec<Vec2>,
    indices: Vec<u32>,
}

struct Loader<'a> {
    root: &'a json::Root,
    base: &'a Path,
    buffers: Vec<Vec<u8>>,
    notes: Notes,
    scene: Scene,
    camera: Option<Camera>,
    materials: HashMap<Option<usize>, u32>,
    textures: HashMap<TexKey, u32>,
    images: HashMap<usize, Rc<Decoded>>,
    visits: usize,
}

impl<'a> Loader<'a> {
    fn new(root: &'a json::Root, base: &'a Path, buffers: Vec<Vec<u8>>, notes: Notes) -> Self {
        Loader {
            root,
            base,
            buffers,
            notes,
            scene: Scene::default(),
            camera: None,
            materials: HashMap::new(),
            textures: HashMap::new(),
            images: HashMap::new(),
            visits: 0,
        }
    }

    /// The root nodes to instantiate: the requested scene, the default one, scene 0, or (no scenes) all
    /// parentless nodes.
    fn scene_roots(&mut self, options: &LoadOptions) -> Res<Vec<usize>> {
        let scenes = &self.root.scenes;
        let index = match (options.gltf_scene, self.root.scene) {
            (Some(i), _) => i,
            (None, _) if scenes.is_empty() => return Ok(self.orphan_roots()),
            (None, Some(i)) => i.value(),
            (None, None) => {
                self.notes.push("the file names no default scene; using scene 0".into());
                0
            }
        };
        let scene = scenes.get(index).ok_or_else(|| {
            let source = if options.gltf_scene.is_some() { "was requested" } else { "is the default scene" };
            format!("scene {index} {source}, but the file has {} scene(s)", scenes.len())
        })?;
        Ok(scene.nodes.iter().map(|n| n.value()).collect())
    }

    /// Without scenes the spec leaves the content undefined; rendering every parentless node is the
    /// most useful reading (and says so).
    fn orphan_roots(&mut self) -> Vec<usize> {
        let mut is_child = vec![false; self.root.nodes.len()];
        for child in self.root.nodes.iter().flat_map(|n| n.children.iter().flatten()) {
            if let Some(flag) = is_child.get_mut(child.value()) {
                *flag = true;
            }
        }
        let roots: Vec<usize> = (0..is_child.len()).filter(|&i| !is_child[i]).collect();
        match roots.len() {
            0 => self.notes.push("the file has no scenes".into()),
            n => self.notes.push(format!("the file has no scenes; instantiating all {n} root node(s)")),
        }
        roots
    }

    /// Instantiates node `index` and its subtree under the `parent` transform.
    fn visit(&mut self, index: usize, parent: &Mat4, on_path: &mut [bool], depth: usize) -> Res<()> {
        let root = self.root;
        let count = root.nodes.len();
        let node =
            root.nodes.get(index).ok_or_else(|| format!("node {index} does not exist (the file has {count} nodes)"))?;
        let label = format!("node {index}{}", quoted(&node.name));
        if on_path[index] {
            return Err(format!("{label} is its own ancestor: the node hierarchy contains a cycle"));
        }
        if depth >= MAX_DEPTH {
            return Err(format!("{label}: the node hierarchy is deeper than {MAX_DEPTH} levels"));
        }
        self.visits += 1;
        if self.visits > MAX_NODE_VISITS {
            return Err(format!(
                "the scene expands to more than {MAX_NODE_VISITS} node instances (nodes shared by many parents?)"
            ));
        }
        let world = *parent * local_transform(node).map_err(|m| format!("{label}: {m}"))?;
        self.place_node(node, &label, &world)?;
        on_path[index] = true;
        for child in node.children.iter().flatten() {
            self.visit(child.value(), &world, on_path, depth + 1)?;
        }
        on_path[index] = false;
        Ok(())
    }

    /// Adds what a node carries: mesh primitives, a camera, a punctual light.
    fn place_node(&mut self, node: &json::Node, label: &str, world: &Mat4) -> Res<()> {
        if let Some(mesh) = node.mesh {
            if node.skin.is_some() {
                self.notes
                    .once("skin", || "skinning is ignored: skinned meshes are rendered in their bind pose".into());
            }
            self.place_mesh(mesh.value(), world)?;
        }
        // Every camera is checked (so that skipped ones are reported); the first usable one wins.
        if let Some(camera) = node.camera {
            let camera = self.camera(camera.value(), world)?;
            self.camera = self.camera.take().or(camera);
        }
        let light = node.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref());
        if let Some(light) = light {
            self.light(light.light.value(), world, label)?;
        }
        Ok(())
    }

    fn place_mesh(&mut self, mesh_index: usize, world: &Mat4) -> Res<()> {
        let root = self.root;
        let count = root.meshes.len();
        let mesh = root
            .meshes
            .get(mesh_index)
            .ok_or_else(|| format!("mesh {mesh_index} does not exist (the file has {count} meshes)"))?;
        let name = mesh.name.clone().unwrap_or_else(|| format!("mesh {mesh_index}"));
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let what = format!("mesh '{name}' primitive {p}");
            if let Some(built) = self.primitive(primitive, &name, &what, world)? {
                self.scene.meshes.push(built);
            }
        }
        Ok(())
    }

    /// One primitive instance as a world-space mesh; None when it has nothing to render.
    fn primitive(&mut self, prim: &json::mesh::Primitive, name: &str, what: &str, world: &Mat4) -> Res<Option<Mesh>> {
        let Checked::Valid(mode) = prim.mode else { return Err(format!("{what}: invalid primitive mode")) };
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            self.notes.skipped_primitives += 1;
            return Ok(None);
        }
        if prim.targets.as_ref().is_some_and(|t| !t.is_empty()) {
            self.notes.once("morph", || "morph targets are ignored: meshes are rendered in their base shape".into());
        }
        let Some(geometry) = self.geometry(prim, what)? else { return Ok(None) };
        let (triangles, leftover) = assemble(mode, &geometry.indices);
        if leftover > 0 {
            self.notes.push(format!("{what}: {leftover} trailing index(es) do not form a triangle and were ignored"));
        }
        let material = self.material(prim.material.map(|m| m.value()))?;
        let m = &self.scene.materials[material as usize];
        let textured =
            m.base_color_texture.is_some() || m.metallic_roughness_texture.is_some() || m.emissive_texture.is_some();
        if textured && geometry.uvs.is_empty() {
            self.notes
                .push(format!("{what} has a textured material but no TEXCOORD_0; its textures are sampled at (0, 0)"));
        }
        // A NaN or Inf position is corrupt data, not something to guess around: refuse the file, naming the vertex.
        let used = triangles.iter().flatten().map(|&i| (i, world.transform_point3(geometry.positions[i as usize])));
        let bad: Vec<(u32, Vec3)> = used.filter(|(_, p)| !p.is_finite()).collect();
        if let Some(&(i, p)) = bad.first() {
            let file_value = geometry.positions[i as usize];
            let (source, p) = if file_value.is_finite() {
                ("its node transform makes it non-finite", p)
            } else {
                ("POSITION holds NaN/Inf", file_value)
            };
            return Err(format!(
                "{what}: non-finite vertex position: vertex {i} is ({}, {}, {}) ({source}; {} use(s) by triangles in all)",
                p.x,
                p.y,
                p.z,
                bad.len()
            ));
        }
        let mesh = Mesh { name: name.to_string(), material, ..Default::default() };
        Ok(build_mesh(mesh, geometry, triangles, world, &mut self.notes))
    }

    /// Reads and cross-checks a primitive's attributes and indices.
    fn geometry(&mut self, prim: &json::mesh::Primitive, what: &str) -> Res<Option<Geometry>> {
        let attribute = |s: Semantic| prim.attributes.get(&Checked::Valid(s)).map(|a| a.value());
        let Some(position) = attribute(Semantic::Positions) else {
            self.notes.push(format!("{what} has no POSITION attribute and was skipped"));
            return Ok(None);
        };
        // An accessor with neither a bufferView nor sparse values is all zeros (spec): zero positions, or indices
        // that are all 0, make every triangle degenerate. Skip it before allocating: a few bytes of JSON can
        // declare tens of millions of them.
        let zero_positions = self.all_zeros(position, Usage::Position, what)?;
        let zero_indices = match prim.indices {
            Some(a) => self.all_zeros(a.value(), Usage::Indices, what)?,
            None => false,
        };
        if zero_positions || zero_indices {
            let (which, a) = match prim.indices {
                Some(a) if zero_indices => ("indices", a.value()),
                _ => ("POSITION", position),
            };
            self.notes.push(format!(
                "{what}: its {which} accessor {a} has neither a bufferView nor sparse values, so it is all zeros and every triangle is degenerate; skipped"
            ));
            return Ok(None);
        }
        let positions = self.read_vec3(position, Usage::Position, what)?;
        let n = positions.len();
        let normals = match attribute(Semantic::Normals) {
            Some(a) => Some(self.read_vec3(a, Usage::Normal, what).and_then(|v| same_count(v, n, a, "NORMAL", what))?),
            None => None,
        };
        let uvs = match attribute(Semantic::TexCoords(0)) {
            Some(a) => {
                let flat = self.read(a, Usage::TexCoord, what, to_f32)?;
                let uvs = flat.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])).collect();
                same_count(uvs, n, a, "TEXCOORD_0", what)?
            }
            None => Vec::new(),
        };
        let indices = match prim.indices {
            Some(a) => self.read_indices(a.value(), n, what)?,
            None => (0..n as u32).collect(),
        };
        Ok(Some(Geometry { positions, normals, uvs, indices }))
    }

    fn read_vec3(&self, index: usize, usage: Usage, what: &str) -> Res<Vec<Vec3>> {
        let flat = self.read(index, usage, what, to_f32)?;
        Ok(flat.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect())
    }

    /// Whether accessor `index` is implicitly all zeros (neither a bufferView nor sparse values), after checking
    /// its format and count as `read` does (a missing accessor is left for `read` to report).
    fn all_zeros(&self, index: usize, usage: Usage, what: &str) -> Res<bool> {
        let Some(acc) = self.root.accessors.get(index) else { return Ok(false) };
        let label = format!("accessor {index} ({} of {what})", usage.name());
        check_format(acc, usage).and_then(|_| check_count(acc)).map_err(|m| format!("{label}: {m}"))?;
        Ok(acc.buffer_view.is_none() && acc.sparse.is_none())
    }

    /// Reads an index accessor and checks every index against the vertex count.
    fn read_indices(&self, index: usize, vertex_count: usize, what: &str) -> Res<Vec<u32>> {
        let indices = self.read(index, Usage::Indices, what, to_u32)?;
        if let Some((at, bad)) = indices.iter().enumerate().find(|(_, &i)| i as usize >= vertex_count) {
            return Err(format!(
                "accessor {index} (indices of {what}): index {bad} at position {at} is out of range (the primitive has {vertex_count} vertices)"
            ));
        }
        Ok(indices)
    }

    /// Reads accessor `index` as a flat list of converted components, after validating everything.
    fn read<T: Copy + Default>(&self, index: usize, usage: Usage, what: &str, convert: Convert<T>) -> Res<Vec<T>> {
        let label = format!("accessor {index} ({} of {what})", usage.name());
        let count_all = self.root.accessors.len();
        let acc = self
            .root
            .accessors
            .get(index)
            .ok_or_else(|| format!("{label} does not exist (the file has {count_all} accessors)"))?;
        self.read_checked(acc, usage, convert).map_err(|m| format!("{label}: {m}"))
    }

    fn read_checked<T: Copy + Default>(&self, acc: &json::Accessor, usage: Usage, convert: Convert<T>) -> Res<Vec<T>> {
        let (comp, n) = check_format(acc, usage)?;
        check_count(acc)?;
        let (count, size) = (acc.count.0 as usize, comp.size());
        let mut out = Vec::new();
        match acc.buffer_view {
            Some(view) => {
                let offset = acc.byte_offset.map_or(0, |o| o.0);
                let layout = self.layout(view.value(), offset, count, size * n)?;
                out.reserve_exact(count * n);
                for i in 0..count {
                    let e = layout.element(i);
                    out.extend((0..n).map(|c| convert(&e[c * size..], comp, acc.normalized)));
                }
            }
            // Without a bufferView the accessor starts as zeros (spec), usually with sparse values on top.
            None => out.resize(count * n, T::default()),
        }
        if let Some(sparse) = &acc.sparse {
            self.apply_sparse(sparse, &mut out, (comp, n, acc.normalized), convert)?;
        }
        Ok(out)
    }

    /// The bytes of buffer view `view` (checked against its buffer) and its byteStride.
    fn view(&self, view: usize) -> Res<(&[u8], Option<usize>)> {
        let views = &self.root.buffer_views;
        let v = views
            .get(view)
            .ok_or_else(|| format!("bufferView {view} does not exist (the file has {} bufferViews)", views.len()))?;
        let buffer = v.buffer.value();
        let data = self
            .buffers
            .get(buffer)
            .ok_or_else(|| format!("bufferView {view} names buffer {buffer}, which does not exist"))?;
        let (start, len) = (v.byte_offset.map_or(0, |o| o.0), v.byte_length.0);
        match start.checked_add(len) {
            Some(end) if end <= data.len() as u64 => {
                Ok((&data[start as usize..end as usize], v.byte_stride.map(|s| s.0)))
            }
            _ => Err(format!(
                "bufferView {view} (bytes {start}..{}) extends past the end of buffer {buffer} ({} bytes)",
                start.saturating_add(len),
                data.len()
            )),
        }
    }

    /// Validates that `count` elements of `elem` bytes at `offset` fit in buffer view `view`.
    fn layout(&self, view: usize, offset: u64, count: usize, elem: usize) -> Res<Layout<'_>> {
        let (bytes, stride) = self.view(view)?;
        let stride = stride.unwrap_or(elem);
        if stride < elem {
            return Err(format!("byteStride {stride} is smaller than the element size {elem}"));
        }
        if count == 0 {
            return Ok(Layout { bytes: &[], stride, elem });
        }
        let len = bytes.len() as u64;
        let need =
            (stride as u64).checked_mul(count as u64 - 1).and_then(|x| x.checked_add(elem as u64)?.checked_add(offset));
        match need {
            Some(need) if need <= len => Ok(Layout { bytes: &bytes[offset as usize..need as usize], stride, elem }),
            _ => Err(format!(
                "{count} elements of {elem} bytes (stride {stride}) from byteOffset {offset} do not fit in bufferView {view} ({len} bytes)"
            )),
        }
    }

    /// Overwrites the elements named by a sparse accessor's indices.
    fn apply_sparse<T>(
        &self,
        sparse: &json::accessor::sparse::Sparse,
        out: &mut [T],
        (comp, n, normalized): (ComponentType, usize, bool),
        convert: Convert<T>,
    ) -> Res<()> {
        let count = out.len() / n.max(1);
        let k = sparse.count.0;
        if k > count as u64 {
            return Err(format!("sparse count {k} exceeds the accessor count {count}"));
        }
        let Checked::Valid(IndexComponentType(icomp)) = sparse.indices.component_type else {
            return Err("sparse indices have an invalid componentType".into());
        };
        let (ind, val) = (&sparse.indices, &sparse.values);
        let indices = self
            .layout(ind.buffer_view.value(), ind.byte_offset.0, k as usize, icomp.size())
            .map_err(|m| format!("sparse indices: {m}"))?;
        let values = self
            .layout(val.buffer_view.value(), val.byte_offset.0, k as usize, comp.size() * n)
            .map_err(|m| format!("sparse values: {m}"))?;
        for j in 0..k as usize {
            let i = to_u32(indices.element(j), icomp, false) as usize;
            if i >= count {
                return Err(format!("sparse index {i} (entry {j}) is out of range: the accessor has {count} elements"));
            }
            let e = values.element(j);
            for c in 0..n {
                out[i * n + c] = convert(&e[c * comp.size()..], comp, normalized);
            }
        }
        Ok(())
    }

    // ----- materials and textures

    /// The scene material index for a glTF material (None = the default material), converting on first use.
    fn material(&mut self, index: Option<usize>) -> Res<u32> {
        if let Some(&id) = self.materials.get(&index) {
            return Ok(id);
        }
        let material = match index {
            None => Material::default(),
            Some(i) => self.convert_material(i)?,
        };
        let id = self.scene.materials.len() as u32;
        self.scene.materials.push(material);
        self.materials.insert(index, id);
        Ok(id)
    }

    fn convert_material(&mut self, index: usize) -> Res<Material> {
        let root = self.root;
        let count = root.materials.len();
        let m = root
            .materials
            .get(index)
            .ok_or_else(|| format!("material {index} does not exist (the file has {count} materials)"))?;
        let label = format!("material {index}{}", quoted(&m.name));
        let mut material = material_factors(m, &label, &mut self.notes);
        let pbr = &m.pbr_metallic_roughness;
        material.base_color_texture = self.texture_opt(&pbr.base_color_texture, true, &label)?;
        material.metallic_roughness_texture = self.texture_opt(&pbr.metallic_roughness_texture, false, &label)?;
        // glTF emission is factor × texture: with a zero factor the texture cannot contribute.
        if material.emission.max_element() > 0.0 {
            material.emissive_texture = self.texture_opt(&m.emissive_texture, true, &label)?;
        }
        let specular = m.extensions.as_ref().and_then(|e| e.specular.as_ref());
        if specular.is_some_and(|s| {
            s.specular_texture.is_some() || s.specular_color_texture.is_some() || s.specular_color_factor.0 != [1.0; 3]
        }) {
            self.notes.once("specular", || {
                format!("KHR_materials_specular colour and textures are ignored; only specularFactor is used ({label})")
            });
        }
        if m.alpha_mode != Checked::Valid(json::material::AlphaMode::Opaque) {
            self.notes.once("alpha", || {
                format!("alphaMode MASK/BLEND is ignored: surfaces are rendered opaque (first seen in {label})")
            });
        }
        Ok(material)
    }

    fn texture_opt(&mut self, info: &Option<json::texture::Info>, srgb: bool, label: &str) -> Res<Option<TextureRef>> {
        info.as_ref().map(|info| self.texture_ref(info, srgb, label)).transpose()
    }

    /// A texture reference with its sampler settings and `KHR_texture_transform`.
    fn texture_ref(&mut self, info: &json::texture::Info, srgb: bool, label: &str) -> Res<TextureRef> {
        let root = self.root;
        let ti = info.index.value();
        let count = root.textures.len();
        let texture = root
            .textures
            .get(ti)
            .ok_or_else(|| format!("{label}: texture {ti} does not exist (the file has {count} textures)"))?;
        let (wrap_s, wrap_t, nearest) = self.sampler(texture.sampler, label)?;
        // gltf-json fills a missing (required) "source" with u32::MAX, for the texture extensions that carry
        // their own source; we support none of those.
        let image = texture.source.value();
        if image == u32::MAX as usize {
            return Err(format!("{label}: texture {ti} has no source image (its \"source\" is missing)"));
        }
        let key = (image, wrap_s as u8, wrap_t as u8, nearest, srgb);
        let id = match self.textures.get(&key) {
            Some(&id) => id,
            None => {
                let decoded = self.image(image, label)?;
                let name = texture.name.clone().unwrap_or_else(|| image_name(root, image));
                let (width, height, texels) = (decoded.width, decoded.height, decoded.texels.clone());
                let id = self.scene.textures.len() as u32;
                self.scene.textures.push(Texture { name, width, height, texels, srgb, wrap_s, wrap_t, nearest });
                self.textures.insert(key, id);
                id
            }
        };
        let mut reference = TextureRef::identity(id);
        let mut texcoord = info.tex_coord;
        if let Some(t) = info.extensions.as_ref().and_then(|e| e.texture_transform.as_ref()) {
            let transform = texture_transform(t.offset.0, t.rotation.0, t.scale.0);
            if transform.iter().flatten().all(|x| x.is_finite()) {
                reference.transform = transform;
            } else {
                // Non-finite UVs would turn every texel lookup into NaN; the untransformed texture is the repair.
                let (offset, rotation, scale) = (t.offset.0, t.rotation.0, t.scale.0);
                self.notes.push(format!(
                    "{label}: non-finite KHR_texture_transform ignored (offset {offset:?}, rotation {rotation}, scale {scale:?})"
                ));
            }
            texcoord = t.tex_coord.unwrap_or(texcoord);
        }
        if texcoord != 0 {
            self.notes.once("texcoord", || {
                format!("{label}: a texture uses TEXCOORD_{texcoord}; only TEXCOORD_0 is loaded and is used instead")
            });
        }
        Ok(reference)
    }

    fn sampler(&self, sampler: Option<json::Index<json::texture::Sampler>>, label: &str) -> Res<(Wrap, Wrap, bool)> {
        let Some(index) = sampler.map(|s| s.value()) else { return Ok((Wrap::Repeat, Wrap::Repeat, false)) };
        let count = self.root.samplers.len();
        let s = self
            .root
            .samplers
            .get(index)
            .ok_or_else(|| format!("{label}: sampler {index} does not exist (the file has {count} samplers)"))?;
        let nearest = s.mag_filter == Some(Checked::Valid(json::texture::MagFilter::Nearest));
        Ok((wrap(s.wrap_s), wrap(s.wrap_t), nearest))
    }

    /// Decodes image `index` once (textures with different samplers or colour spaces share it).
    fn image(&mut self, index: usize, label: &str) -> Res<Rc<Decoded>> {
        if let Some(image) = self.images.get(&index) {
            return Ok(image.clone());
        }
        let root = self.root;
        let count = root.images.len();
        let image = root
            .images
            .get(index)
            .ok_or_else(|| format!("{label}: image {index} does not exist (the file has {count} images)"))?;
        let what = format!("image {index} ({})", image_name(root, index));
        let bytes = match (&image.uri, image.buffer_view) {
            (Some(uri), _) => fetch_uri(self.base, uri),
            (None, Some(view)) => self.view(view.value()).map(|(bytes, _)| bytes.to_vec()),
            (None, None) => Err("has neither a uri nor a bufferView".into()),
        }
        .map_err(|m| format!("{what}: {m}"))?;
        let decoded = Rc::new(decode_image(&bytes).map_err(|m| format!("{what}: {m}"))?);
        self.images.insert(index, decoded.clone());
        Ok(decoded)
    }

    // ----- cameras and lights

    /// A perspective camera at the node's world transform; None (with a warning) when it cannot be used.
    fn camera(&mut self, index: usize, world: &Mat4) -> Res<Option<Camera>> {
        let count = self.root.cameras.len();
        let camera = self
            .root
            .cameras
            .get(index)
            .ok_or_else(|| format!("camera {index} does not exist (the file has {count} cameras)"))?;
        let label = format!("camera {index}{}", quoted(&camera.name));
        let perspective = match (camera.type_, &camera.perspective) {
            (Checked::Valid(json::camera::Type::Perspective), Some(p)) => p,
            (Checked::Valid(json::camera::Type::Orthographic), _) => {
                self.notes.push(format!("{label}: orthographic cameras are not supported; skipped"));
                return Ok(None);
            }
            _ => {
                self.notes.push(format!("{label}: no valid perspective projection; skipped"));
                return Ok(None);
            }
        };
        let vfov = perspective.yfov;
        let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
        if !(vfov > 0.0 && vfov < std::f32::consts::PI) || forward == Vec3::ZERO || up == Vec3::ZERO {
            self.notes.push(format!("{label}: unusable yfov {vfov} or degenerate node transform; skipped"));
            return Ok(None);
        }
        Ok(Some(Camera { position: world.transform_point3(Vec3::ZERO), forward, up, vfov }))
    }

    /// Adds a KHR_lights_punctual light placed by a node (lights shine down the node's -Z).
    fn light(&mut self, index: usize, world: &Mat4, node: &str) -> Res<()> {
        let lights = self.root.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref());
        let lights = lights.map_or(&[][..], |l| &l.lights[..]);
        let light = lights.get(index).ok_or_else(|| {
            format!("{node}: KHR_lights_punctual light {index} does not exist (the file has {})", lights.len())
        })?;
        let label = format!("{node}: light {index}{}", quoted(&light.name));
        let power = Vec3::from(light.color) * light.intensity;
        let position = world.transform_point3(Vec3::ZERO);
        let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        if !power.is_finite() || power.min_element() < 0.0 || !position.is_finite() {
            self.notes.push(format!("{label}: negative or non-finite colour × intensity or position; skipped"));
            return Ok(());
        }
        let needs_direction = !matches!(light.type_, Checked::Valid(punctual::Type::Point));
        if needs_direction && direction == Vec3::ZERO {
            self.notes.push(format!("{label}: degenerate node transform gives no direction; skipped"));
            return Ok(());
        }
        let built = match light.type_ {
            Checked::Valid(punctual::Type::Point) => PunctualLight::Point { position, intensity: power },
            Checked::Valid(punctual::Type::Directional) => PunctualLight::Directional { direction, irradiance: power },
            Checked::Valid(punctual::Type::Spot) => {
                let (inner_cone, outer_cone) = self.cone(light.spot.as_ref(), &label);
                PunctualLight::Spot { position, direction, intensity: power, inner_cone, outer_cone }
            }
            Checked::Invalid => {
                self.notes.push(format!("{label}: unknown light type; skipped"));
                return Ok(());
            }
        };
        self.scene.punctual_lights.push(built);
        Ok(())
    }

    /// Spot cone angles (spec defaults 0 and π/4), clamped to 0 ≤ inner < outer ≤ π/2.
    fn cone(&mut self, spot: Option<&punctual::Spot>, label: &str) -> (f32, f32) {
        let quarter = std::f32::consts::FRAC_PI_4;
        let (inner, outer) = spot.map_or((0.0, quarter), |s| (s.inner_cone_angle, s.outer_cone_angle));
        let valid = inner.is_finite()
            && outer.is_finite()
            && inner >= 0.0
            && inner < outer
            && outer <= std::f32::consts::FRAC_PI_2;
        if valid {
            return (inner, outer);
        }
        self.notes.push(format!("{label}: invalid spot cone angles ({inner}, {outer}); using 0 and π/4"));
        (0.0, quarter)
    }

    /// The finished scene: camera (from the file or framing the bounds) and warnings.
    fn finish(mut self) -> Scene {
        if self.scene.meshes.is_empty() && self.scene.punctual_lights.is_empty() {
            self.notes.push("the scene contains nothing to render (no triangles and no lights)".into());
        }
        self.scene.camera = self.camera.take().unwrap_or_else(|| frame_meshes(&self.scene.meshes));
        self.scene.warnings = self.notes.finish();
        self.scene
    }
}

// ---------------------------------------------------------------------------------------------------------
// Free helpers: geometry, materials, images

fn same_count<T>(values: Vec<T>, n: usize, accessor: usize, semantic: &str, what: &str) -> Res<Vec<T>> {
    if values.len() != n {
        let got = values.len();
        return Err(format!(
            "accessor {accessor} ({semantic} of {what}): count {got} differs from the POSITION count {n}"
        ));
    }
    Ok(values)
}

/// A node's local transform from its matrix or its translation / rotation / scale.
fn local_transform(node: &json::Node) -> Res<Mat4> {
    let matrix = match node.matrix {
        Some(m) => Mat4::from_cols_array(&m),
        None => {
            let rotation = Quat::from_array(node.rotation.as_ref().map_or([0.0, 0.0, 0.0, 1.0], |r| r.0));
            let length = rotation.length();
            if !(length.is_finite() && length > 1e-6) {
                return Err(format!("rotation {rotation} is not a valid quaternion"));
            }
            let scale = Vec3::from(node.scale.unwrap_or([1.0; 3]));
            let translation = Vec3::from(node.translation.unwrap_or([0.0; 3]));
            Mat4::from_scale_rotation_translation(scale, rotation / length, translation)
        }
    };
    if !matrix.is_finite() {
        return Err("the transform contains non-finite values".into());
    }
    Ok(matrix)
}

/// Triangles from a triangle-list, strip or fan index sequence, using the spec's vertex orders (which keep
/// every strip triangle's winding consistent). Also returns the count of leftover list indices.
fn assemble(mode: Mode, idx: &[u32]) -> (Vec<[u32; 3]>, usize) {
    let n = idx.len();
    match mode {
        Mode::TriangleStrip => {
            let tris = (0..n.saturating_sub(2))
                .map(|i| if i % 2 == 0 { [idx[i], idx[i + 1], idx[i + 2]] } else { [idx[i], idx[i + 2], idx[i + 1]] })
                .collect();
            (tris, 0)
        }
        Mode::TriangleFan => ((0..n.saturating_sub(2)).map(|i| [idx[i + 1], idx[i + 2], idx[0]]).collect(), 0),
        _ => (idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(), n % 3),
    }
}

/// Transforms a primitive to world space, fixes winding for mirrors, drops non-finite triangles and makes
/// every normal unit length. None when no triangle survives.
fn build_mesh(
    mut mesh: Mesh,
    geo: Geometry,
    mut triangles: Vec<[u32; 3]>,
    world: &Mat4,
    notes: &mut Notes,
) -> Option<Mesh> {
    let linear = Mat3::from_mat4(*world);
    let det = linear.determinant();
    if det < 0.0 {
        triangles.iter_mut().for_each(|t| t.swap(1, 2));
    }
    mesh.positions = geo.positions.iter().map(|&p| world.transform_point3(p)).collect();
    let before = triangles.len();
    triangles.retain(|t| t.iter().all(|&i| mesh.positions[i as usize].is_finite()));
    let dropped = before - triangles.len();
    notes.dropped_triangles += dropped;
    // The cofactor matrix is the inverse-transpose times det; it exists even for singular transforms,
    // and the sign keeps normals on the side the (possibly mirrored) geometry faces.
    let (c0, c1, c2) = (linear.x_axis, linear.y_axis, linear.z_axis);
    let cofactor = Mat3::from_cols(c1.cross(c2), c2.cross(c0), c0.cross(c1)) * if det < 0.0 { -1.0 } else { 1.0 };
    let provided = geo.normals.is_some();
    mesh.normals = match geo.normals {
        Some(normals) => normals.iter().map(|&n| (cofactor * n).normalize_or_zero()).collect(),
        None => vec![Vec3::ZERO; mesh.positions.len()],
    };
    let repaired = repair_normals(&mesh.positions, &triangles, &mut mesh.normals);
    if provided {
        notes.repaired_normals += repaired;
    }
    mesh.uvs = geo.uvs;
    for uv in mesh.uvs.iter_mut().filter(|uv| !uv.is_finite()) {
        *uv = Vec2::ZERO;
        notes.repaired_uvs += 1;
    }
    mesh.indices = triangles;
    if dropped > 0 {
        compact(&mut mesh);
    }
    (!mesh.indices.is_empty()).then_some(mesh)
}

/// Replaces zero normals by the area-weighted average of the adjacent face normals; returns how many.
fn repair_normals(positions: &[Vec3], triangles: &[[u32; 3]], normals: &mut [Vec3]) -> usize {
    let missing = normals.iter().filter(|n| **n == Vec3::ZERO).count();
    if missing == 0 {
        return 0;
    }
    let mut sums = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let face = (b - a).cross(c - a); // length = twice the area: area weighting for free
        if face.is_finite() {
            t.iter().for_each(|&i| sums[i as usize] += face);
        }
    }
    for (n, sum) in normals.iter_mut().zip(&sums).filter(|(n, _)| **n == Vec3::ZERO) {
        // Vertices no triangle uses (or only degenerate ones) still need a unit normal.
        *n = sum.try_normalize().unwrap_or(Vec3::Z);
    }
    missing
}

/// Removes vertices that no triangle references (after dropping triangles with non-finite vertices).
fn compact(mesh: &mut Mesh) {
    let mut remap = vec![u32::MAX; mesh.positions.len()];
    let mut kept = Vec::new();
    for i in mesh.indices.iter_mut().flatten() {
        if remap[*i as usize] == u32::MAX {
            remap[*i as usize] = kept.len() as u32;
            kept.push(*i as usize);
        }
        *i = remap[*i as usize];
    }
    mesh.positions = kept.iter().map(|&i| mesh.positions[i]).collect();
    mesh.normals = kept.iter().map(|&i| mesh.normals[i]).collect();
    if !mesh.uvs.is_empty() {
        mesh.uvs = kept.iter().map(|&i| mesh.uvs[i]).collect();
    }
}

/// Material factors (no textures), sanitised: non-finite values fall back to the glTF defaults.
fn material_factors(m: &json::Material, label: &str, notes: &mut Notes) -> Material {
    let mut repaired = false;
    let mut clean = |x: f32, lo: f32, hi: f32, default: f32| {
        repaired |= !x.is_finite();
        if x.is_finite() {
            x.clamp(lo, hi)
        } else {
            default
        }
    };
    let pbr = &m.pbr_metallic_roughness;
    let [r, g, b, _alpha] = pbr.base_color_factor.0;
    let ext = m.extensions.as_ref();
    let strength = ext.and_then(|e| e.emissive_strength.as_ref()).map_or(1.0, |s| s.emissive_strength.0);
    let specular = ext.and_then(|e| e.specular.as_ref()).map_or(1.0, |s| s.specular_factor.0);
    let strength = clean(strength, 0.0, f32::MAX, 1.0);
    let emissive = m.emissive_factor.0.map(|e| clean(e, 0.0, f32::MAX, 0.0));
    let material = Material {
        name: m.name.clone().unwrap_or_else(|| label.to_string()),
        base_color: Vec3::new(clean(r, 0.0, 1.0, 1.0), clean(g, 0.0, 1.0, 1.0), clean(b, 0.0, 1.0, 1.0)),
        metallic: clean(pbr.metallic_factor.0, 0.0, 1.0, 1.0),
        roughness: clean(pbr.roughness_factor.0, 0.0, 1.0, 1.0),
        specular: clean(specular, 0.0, 1.0, 1.0),
        emission: Vec3::from(emissive) * strength,
        ..Material::default()
    };
    if repaired {
        notes.push(format!("{label}: non-finite factors replaced by the glTF defaults"));
    }
    material
}

fn wrap(mode: Checked<json::texture::WrappingMode>) -> Wrap {
    use json::texture::WrappingMode::*;
    match mode {
        Checked::Valid(ClampToEdge) => Wrap::Clamp,
        Checked::Valid(MirroredRepeat) => Wrap::Mirror,
        _ => Wrap::Repeat,
    }
}

/// `KHR_texture_transform` as the 2×3 matrix T·R·S of the extension. R maps (u, v) to
/// (u·cos + v·sin, −u·sin + v·cos): the sense the extension's worked example (offset [0, 1], rotation π/2,
/// scale 0.5 selects the lower-left quadrant) and the reference viewers use; its GLSL snippet, read as
/// column-major, would give the opposite sense.
fn texture_transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> [[f32; 3]; 2] {
    let (s, c) = rotation.sin_cos();
    let [sx, sy] = scale;
    let [ox, oy] = offset;
    [[c * sx, s * sy, ox], [-s * sx, c * sy, oy]]
}

fn image_name(root: &json::Root, index: usize) -> String {
    let image = &root.images[index];
    match (&image.name, &image.uri) {
        (Some(name), _) => name.clone(),
        (None, Some(uri)) if !uri.starts_with("data:") => uri.clone(),
        _ => format!("image {index}"),
    }
}

/// Decodes PNG/JPEG bytes to RGBA8, refusing images above the size limit before decoding them.
fn decode_image(bytes: &[u8]) -> Res<Decoded> {
    let reader = || image::ImageReader::new(Cursor::new(bytes)).with_guessed_format().map_err(|e| e.to_string());
    let (width, height) = reader()?.into_dimensions().map_err(|e| format!("cannot decode the image: {e}"))?;
    if width > MAX_TEXTURE_SIZE || height > MAX_TEXTURE_SIZE {
        return Err(format!(
            "{width}×{height} texels exceeds the texture size limit of {MAX_TEXTURE_SIZE} texels per side"
        ));
    }
    let image = reader()?.decode().map_err(|e| format!("cannot decode the image: {e}"))?;
    let rgba = image.to_rgba8();
    let texels = rgba.as_raw().chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
    Ok(Decoded { width, height, texels })
}

/// A camera that sees the whole scene: from +Z towards the bounding-box centre, 45° vertical field of view,
/// far enough that the bounding sphere fits.
fn frame_meshes(meshes: &[Mesh]) -> Camera {
    let mut points = meshes.iter().flat_map(|m| m.positions.iter().copied());
    let Some(first) = points.next() else { return Camera::default() };
    let (lo, hi) = points.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)));
    let center = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-3);
    let vfov = 45f32.to_radians();
    let distance = radius / (vfov * 0.5).sin();
    Camera { position: center + Vec3::Z * distance, forward: Vec3::NEG_Z, up: Vec3::Y, vfov }
}
