//! Container, JSON, extensions, buffers: splitting `.glb` into its chunks, parsing the JSON (leniently where
//! gltf-json is stricter than the spec), rejecting unsupported required extensions, and reading buffers from
//! the GLB chunk, external files or base64 `data:` URIs.

use super::notes::Notes;
use super::{json, quoted, Res};
use std::path::Path;

/// Extensions that we implement.
const SUPPORTED: &[&str] =
    &["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_specular", "KHR_texture_transform"];
/// GLB chunk types.
const GLB_JSON: u32 = 0x4E4F_534A;
const GLB_BIN: u32 = 0x004E_4942;

/// Splits a file into its JSON text and, for GLB, the binary chunk.
pub(super) fn split_container<'b>(path: &Path, bytes: &'b [u8]) -> Res<(&'b [u8], Option<&'b [u8]>)> {
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

pub(super) fn parse_json(bytes: &[u8]) -> Res<json::Root> {
    let root: json::Root = match json::deserialize::from_slice(bytes) {
        Ok(root) => root,
        // Keep the first error: it has a line and column, the retry's would not.
        Err(e) => parse_lenient(bytes).ok_or_else(|| format!("invalid glTF JSON: {e}"))?,
    };
    // gltf-json reads indices as u64 and keeps the low 32 bits: range-check them as the JSON numbers they are.
    if let Ok(value) = json::deserialize::from_slice::<json::Value>(bytes) {
        check_index_range(&value, &mut String::new())?;
    }
    if !root.asset.version.starts_with("2.") {
        return Err(format!("glTF version '{}' is not supported (only 2.x)", root.asset.version));
    }
    Ok(root)
}

/// Keys whose values (a number, an array of numbers, or for `attributes`/`targets` an object of numbers) are
/// indices into one of the root's arrays.
const INDEX_KEYS: &[&str] = &[
    "scene",
    "nodes",
    "camera",
    "children",
    "skin",
    "mesh",
    "indices",
    "material",
    "bufferView",
    "buffer",
    "source",
    "sampler",
    "index",
    "joints",
    "skeleton",
    "inverseBindMatrices",
    "input",
    "output",
    "node",
    "light",
    "attributes",
    "targets",
    "texCoord",
];

/// Refuses any index of 2^32 or more (which gltf-json would wrap to a small, valid-looking one), naming where.
fn check_index_range(v: &json::Value, at: &mut String) -> Res<()> {
    fn numbers(v: &json::Value, at: &str) -> Res<()> {
        match v {
            json::Value::Number(n) if n.as_u64().is_some_and(|i| i > u32::MAX as u64) => Err(format!(
                "{at}: index {n} does not exist (glTF indices are below 2^32; the file's arrays are far shorter)"
            )),
            json::Value::Array(items) => {
                items.iter().enumerate().try_for_each(|(i, item)| numbers(item, &format!("{at}[{i}]")))
            }
            json::Value::Object(map) => map.iter().try_for_each(|(k, item)| match item {
                json::Value::Number(_) => numbers(item, &format!("{at}.{}", crate::io::input_file::clip(k, 40))),
                _ => Ok(()),
            }),
            _ => Ok(()),
        }
    }
    match v {
        json::Value::Object(map) => {
            for (k, item) in map {
                if k == "extras" {
                    continue; // free-form application data
                }
                let len = at.len();
                if !at.is_empty() {
                    at.push('.');
                }
                at.push_str(&crate::io::input_file::clip(k, 40));
                if INDEX_KEYS.contains(&k.as_str()) {
                    numbers(item, at)?;
                }
                check_index_range(item, at)?;
                at.truncate(len);
            }
        }
        json::Value::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                let len = at.len();
                at.push_str(&format!("[{i}]"));
                check_index_range(item, at)?;
                at.truncate(len);
            }
        }
        _ => {}
    }
    Ok(())
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
pub(super) fn check_extensions(root: &json::Root, notes: &mut Notes) -> Res<()> {
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

/// Where a glTF file's URIs may lead: files under its own directory, unless the user allows others
/// (`--allow-outside-paths`).
#[derive(Clone, Copy)]
pub(super) struct Uris<'p> {
    /// The glTF file's directory.
    pub base: &'p Path,
    /// Follow absolute paths, `..` and symlinks out of `base`.
    pub allow_outside: bool,
}

/// A URI as echoed in messages: cut (a hostile file can hold megabytes in one), never file content.
fn shown(uri: &str) -> String {
    crate::io::input_file::clip(uri, 80)
}

/// Reads every buffer (GLB chunk, external file or data URI) and checks it against its declared byteLength.
/// An external file is read only up to the declared length (itself checked against the limit first), so a
/// buffer naming a huge or endless file never reads more than it declared.
pub(super) fn load_buffers(root: &json::Root, bin: Option<&[u8]>, is_glb: bool, uris: Uris) -> Res<Vec<Vec<u8>>> {
    use crate::io::input_file::{read_prefix, MAX_GLTF_BYTES};
    let mut out = Vec::with_capacity(root.buffers.len());
    for (i, buffer) in root.buffers.iter().enumerate() {
        let what = format!("buffer {i}{}", quoted(&buffer.name));
        let declared = buffer.byte_length.0;
        if declared > MAX_GLTF_BYTES {
            return Err(format!("{what}: byteLength {declared} exceeds the limit of {MAX_GLTF_BYTES} bytes"));
        }
        let mut data = match (&buffer.uri, bin) {
            (Some(uri), _) => fetch_uri(uris, uri, |p| read_prefix(p, declared).map_err(|e| e.to_string()))
                .map_err(|m| format!("{what}: {m}"))?,
            (None, Some(bin)) if i == 0 => bin.to_vec(),
            (None, None) if i == 0 && is_glb => {
                return Err(format!("{what} has no uri, and the GLB file has no BIN chunk to hold its data"))
            }
            (None, _) => return Err(format!("{what} has no uri (only a .glb's first buffer may omit it)")),
        };
        if (data.len() as u64) < declared {
            return Err(format!("{what}: byteLength is {declared} but only {} bytes of data are present", data.len()));
        }
        data.truncate(declared as usize);
        out.push(data);
    }
    Ok(out)
}

/// Bytes behind a URI: a base64 `data:` URI, or a file path relative to the glTF file read with `read`.
pub(super) fn fetch_uri(uris: Uris, uri: &str, read: impl Fn(&Path) -> Res<Vec<u8>>) -> Res<Vec<u8>> {
    if let Some(rest) = uri.strip_prefix("data:") {
        return decode_data_uri(rest);
    }
    let scheme = uri.split_once(':').map(|(s, _)| s).unwrap_or("");
    if scheme.len() > 1 && scheme.chars().all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c)) {
        let uri = shown(uri);
        return Err(format!("URI '{uri}' is neither a relative file path nor a data: URI (nothing is downloaded)"));
    }
    let decoded = percent_decode(uri).unwrap_or_else(|| uri.to_string());
    // Some exporters write file names without percent-encoding; try the URI as written too.
    let path = match resolve(uris, &decoded)? {
        p if p.symlink_metadata().is_err() && decoded != uri => {
            let raw = resolve(uris, uri)?;
            if raw.symlink_metadata().is_ok() {
                raw
            } else {
                p
            }
        }
        p => p,
    };
    read(&path).map_err(|m| format!("cannot read '{}': {m}", crate::io::input_file::clip_path(&path, 160)))
}

/// The file a relative URI names, refusing (unless allowed) absolute paths and paths that climb out of the
/// glTF file's directory, by `..` or through a symbolic link.
fn resolve(uris: Uris, rel: &str) -> Res<std::path::PathBuf> {
    use crate::io::input_file::{resolve_inside, Outside};
    let hint = "(resolved relative to the glTF file; allow it with --allow-outside-paths)";
    resolve_inside(uris.base, Path::new(rel), uris.allow_outside).map_err(|why| match why {
        Outside::Absolute => format!("URI '{}' is an absolute path {hint}", shown(rel)),
        _ => format!("URI '{}' {} {hint}", shown(rel), why.describe("the glTF file's directory")),
    })
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
