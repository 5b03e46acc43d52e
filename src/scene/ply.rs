//! PLY meshes (ASCII, binary little- and big-endian; gzip'd `.ply.gz`): vertex positions, normals and UVs, and
//! polygon faces fanned into triangles. Elements and properties we do not use are read past.
//!
//! Our own rather than `ply-rs-bw`: the parser it forks from ply-rs reports errors as `io::Error` strings that quote
//! the offending line verbatim (`Line N: … String: '…'`), which would echo a file's content (a referenced file may be
//! anything a scene names); it reads no gzip'd `.ply.gz` (which pbrt-v4 scenes may name), so the inflated-size limit
//! would still be ours; and its ready-made element type is a map of properties per vertex.

use crate::io::input_file::clip;
use glam::{Vec2, Vec3};

/// A PLY mesh in its own (object) space.
#[derive(Debug, Default)]
pub struct PlyMesh {
    /// Positions.
    pub positions: Vec<Vec3>,
    /// Normals (empty when the file has none).
    pub normals: Vec<Vec3>,
    /// UVs (empty when the file has none).
    pub uvs: Vec<Vec2>,
    /// Triangles.
    pub indices: Vec<[u32; 3]>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

struct Property {
    name: String,
    /// `Some(count type)` for lists.
    list: Option<Scalar>,
    ty: Scalar,
}

struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

#[derive(PartialEq)]
enum Format {
    Ascii,
    Little,
    Big,
}

/// Reads values in the file's encoding.
struct Reader<'a> {
    data: &'a [u8],
    pos: usize,
    format: Format,
    /// ASCII: the remaining whitespace-separated words.
    words: std::str::SplitAsciiWhitespace<'a>,
}

impl Reader<'_> {
    fn value(&mut self, ty: Scalar) -> Result<f64, String> {
        if self.format == Format::Ascii {
            let w = self.words.next().ok_or("the file ends before all elements are read (truncated?)")?;
            return w.parse::<f64>().map_err(|_| format!("'{}' is not a number", clip(w, 40)));
        }
        let n = ty.size();
        let b =
            self.data.get(self.pos..self.pos + n).ok_or("the file ends before all elements are read (truncated?)")?;
        self.pos += n;
        let mut a = [0u8; 8];
        a[..n].copy_from_slice(b);
        if self.format == Format::Big {
            a[..n].reverse();
        }
        Ok(match ty {
            Scalar::I8 => a[0] as i8 as f64,
            Scalar::U8 => a[0] as f64,
            Scalar::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(a),
        })
    }
}

/// Decodes a PLY file (gzip'd when it starts with the gzip magic: inflated up to `input_file::MAX_IMPORT_BYTES`,
/// the limit of a plain file, counted on the inflated bytes so that a "zip bomb" stops there).
pub fn decode(bytes: &[u8]) -> Result<PlyMesh, String> {
    if bytes.starts_with(&[0x1f, 0x8b]) {
        return decode_gz(bytes, crate::io::input_file::MAX_IMPORT_BYTES);
    }
    let end = find_header_end(bytes).ok_or("not a PLY file, or its header has no 'end_header' line")?;
    let header = std::str::from_utf8(&bytes[..end.0]).map_err(|_| "PLY header is not text")?;
    let mut lines = header.lines().map(str::trim);
    if lines.next() != Some("ply") {
        return Err("not a PLY file (the first line is not 'ply')".into());
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    for (n, line) in lines.enumerate() {
        let hl = n + 2;
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] | ["end_header"] => {}
            ["format", f, _] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Little,
                    "binary_big_endian" => Format::Big,
                    _ => return Err(format!("header line {hl}: unknown format '{}'", clip(f, 40))),
                })
            }
            ["element", name, count] => {
                let count =
                    count.parse().map_err(|_| format!("header line {hl}: bad element count '{}'", clip(count, 40)))?;
                elements.push(Element { name: name.to_string(), count, props: vec![] });
            }
            ["property", "list", c, t, name] => {
                let (Some(c), Some(t)) = (Scalar::parse(c), Scalar::parse(t)) else {
                    return Err(format!("header line {hl}: unknown list types in '{}'", clip(line, 80)));
                };
                let e = elements.last_mut().ok_or(format!("header line {hl}: property before any element"))?;
                e.props.push(Property { name: name.to_string(), list: Some(c), ty: t });
            }
            ["property", t, name] => {
                let t = Scalar::parse(t).ok_or(format!("header line {hl}: unknown property type '{}'", clip(t, 40)))?;
                let e = elements.last_mut().ok_or(format!("header line {hl}: property before any element"))?;
                e.props.push(Property { name: name.to_string(), list: None, ty: t });
            }
            _ => return Err(format!("header line {hl}: cannot read '{}'", clip(line, 80))),
        }
    }
    let format = format.ok_or("PLY header has no 'format' line")?;
    let body = &bytes[end.1..];
    let text =
        if format == Format::Ascii { std::str::from_utf8(body).map_err(|_| "ASCII PLY body is not text")? } else { "" };
    let mut r = Reader { data: body, pos: 0, format, words: text.split_ascii_whitespace() };
    let mut mesh = PlyMesh::default();
    for e in &elements {
        // Bound the allocation by what the file can hold (each element is at least one byte or word).
        if e.count > bytes.len() {
            return Err(format!(
                "element '{}' claims {} entries, more than the file can hold",
                clip(&e.name, 40),
                e.count
            ));
        }
        let idx = |n: &[&str]| e.props.iter().position(|p| n.contains(&p.name.as_str()));
        let (px, py, pz) = (idx(&["x"]), idx(&["y"]), idx(&["z"]));
        let (nx, ny, nz) = (idx(&["nx"]), idx(&["ny"]), idx(&["nz"]));
        let (u, v) = (idx(&["u", "s", "texture_u", "texture_s"]), idx(&["v", "t", "texture_v", "texture_t"]));
        let faces = idx(&["vertex_indices", "vertex_index"]);
        let is_vertex = e.name == "vertex";
        let is_face = e.name == "face";
        if is_vertex && (px.is_none() || py.is_none() || pz.is_none()) {
            return Err("vertex element lacks x, y or z".into());
        }
        let mut vals = vec![0.0f64; e.props.len()];
        let mut list = Vec::new();
        for _ in 0..e.count {
            for (k, p) in e.props.iter().enumerate() {
                if let Some(ct) = p.list {
                    let n = r.value(ct)?;
                    if !(0.0..=1024.0).contains(&n) || n.fract() != 0.0 {
                        return Err(format!("element '{}': list length {n} is out of range", clip(&e.name, 40)));
                    }
                    list.clear();
                    for _ in 0..n as usize {
                        list.push(r.value(p.ty)?);
                    }
                    if is_face && Some(k) == faces {
                        fan(&list, &mut mesh.indices)?;
                    }
                } else {
                    vals[k] = r.value(p.ty)?;
                }
            }
            if is_vertex {
                let g = |i: Option<usize>| i.map_or(0.0, |i| vals[i] as f32);
                mesh.positions.push(Vec3::new(g(px), g(py), g(pz)));
                if nx.is_some() && ny.is_some() && nz.is_some() {
                    mesh.normals.push(Vec3::new(g(nx), g(ny), g(nz)));
                }
                if u.is_some() && v.is_some() {
                    mesh.uvs.push(Vec2::new(g(u), g(v)));
                }
            }
        }
    }
    let n = mesh.positions.len() as u32;
    if let Some((f, t)) = mesh.indices.iter().enumerate().find(|(_, t)| t.iter().any(|&i| i >= n)) {
        return Err(format!(
            "face {f} has vertex index {} out of range (the file has {n} vertices)",
            t.iter().max().unwrap()
        ));
    }
    // Values are read as f64 and stored as f32: 1e39 (ASCII) or a double out of range becomes an infinity.
    if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("vertex {i}: its position is not a finite 32-bit float"));
    }
    if let Some(i) = mesh.normals.iter().position(|n| !n.is_finite()) {
        return Err(format!("vertex {i}: its normal is not a finite 32-bit float"));
    }
    if let Some(i) = mesh.uvs.iter().position(|t| !t.is_finite()) {
        return Err(format!("vertex {i}: its texture coordinate is not a finite 32-bit float"));
    }
    Ok(mesh)
}

/// Decodes gzip'd PLY bytes that inflate to at most `limit` bytes (`decode` with the plain files' limit).
pub fn decode_gz(bytes: &[u8], limit: u64) -> Result<PlyMesh, String> {
    let inflated = crate::io::input_file::read_limited(flate2::read::GzDecoder::new(bytes), limit)
        .map_err(|e| format!("gzip data: {e}"))?;
    if inflated.starts_with(&[0x1f, 0x8b]) {
        return Err("gzip data that inflates to more gzip data (a PLY is compressed once)".into());
    }
    decode(&inflated)
}

/// Triangulates a polygon as a fan from its first vertex.
fn fan(list: &[f64], out: &mut Vec<[u32; 3]>) -> Result<(), String> {
    if list.iter().any(|&i| i < 0.0 || i > u32::MAX as f64 || i.fract() != 0.0) {
        return Err(format!("face has an invalid vertex index in {}", clip(&format!("{list:?}"), 80)));
    }
    for k in 2..list.len() {
        out.push([list[0] as u32, list[k - 1] as u32, list[k] as u32]);
    }
    Ok(())
}

/// (end of the header text, start of the body): the byte after the `end_header` line's newline.
fn find_header_end(bytes: &[u8]) -> Option<(usize, usize)> {
    let limit = bytes.len().min(1 << 16);
    let key = b"end_header";
    let at = bytes[..limit].windows(key.len()).position(|w| w == key)?;
    let mut body = at + key.len();
    if bytes.get(body) == Some(&b'\r') {
        body += 1;
    }
    if bytes.get(body) == Some(&b'\n') {
        body += 1;
    }
    Some((at, body))
}

#[cfg(test)]
mod tests {
    use super::*;

    const ASCII: &str =
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
        property float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
        0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n4 0 1 2 3\n";

    #[test]
    fn ascii_quad_and_binary_big_endian() {
        let m = decode(ASCII.as_bytes()).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.uvs[2], Vec2::new(1.0, 1.0));
        assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3]]);
        let mut b = b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n".to_vec();
        for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 2.0, 0.0] {
            b.extend(v.to_be_bytes());
        }
        b.push(3);
        for i in [0u32, 1, 2] {
            b.extend(i.to_be_bytes());
        }
        let m = decode(&b).unwrap();
        assert_eq!(m.positions[2], Vec3::new(0.0, 2.0, 0.0));
        assert_eq!(m.indices, vec![[0, 1, 2]]);
        let n = b.len();
        b[n - 1] = 9;
        assert!(decode(&b).unwrap_err().contains("out of range"));
        assert!(decode(&b[..n - 2]).unwrap_err().contains("truncated"));
    }

    #[test]
    fn a_gzip_bomb_stops_at_the_limit() {
        use std::io::Write;
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
        gz.write_all(ASCII.as_bytes()).unwrap();
        gz.write_all(&vec![b' '; 8 << 20]).unwrap();
        let bytes = gz.finish().unwrap();
        assert!(bytes.len() < 64 << 10);
        let e = decode_gz(&bytes, 1 << 20).unwrap_err();
        assert!(e.contains("inflates to more than 1.0 MiB"), "{e}");
        assert_eq!(decode_gz(&bytes, 16 << 20).unwrap().positions.len(), 4);
    }

    #[test]
    fn values_out_of_f32_range_are_errors() {
        let e = decode(ASCII.replace("1 1 0 1 1", "1 1e39 0 1 1").as_bytes()).unwrap_err();
        assert!(e.contains("vertex 2") && e.contains("finite"), "{e}");
        let e = decode(ASCII.replace("1 1 0 1 1", "1 1 0 1e39 1").as_bytes()).unwrap_err();
        assert!(e.contains("texture coordinate"), "{e}");
    }
}
