//! Equirectangular environment maps: loading `.hdr` / `.exr` into a sanitised linear-RGB [`EnvMap`], and the lat-long mapping.

use super::{EnvMap, SceneError};
use glam::Vec3;
use std::f32::consts::PI;
use std::io::BufReader;
use std::path::Path;

/// Largest accepted width or height, in texels.
pub const MAX_SIDE: u32 = 16384;

/// Texel components above this are treated as corrupt. The Radiance decoder turns the (invalid) RGBE exponent 255
/// into ~1.7e38, which is finite but overflows any f32 sum (and so the luminance CDF) built over the map.
const ABSURD: f32 = 1e30;

/// Loads an equirectangular environment map (`.hdr` Radiance RGBE or `.exr` OpenEXR, chosen by extension) as
/// linear RGB with the top row looking up (+Y), and the mapping of [`equirect_direction`].
///
/// Non-finite, negative and absurdly large (> 1e30) components are set to 0; when any are, the second value holds
/// one warning saying how many texels were repaired. Errors name the file and say what is wrong with it.
pub fn load_envmap(path: &Path) -> Result<(EnvMap, Vec<String>), SceneError> {
    let err = |message: String| SceneError::new(path, message);
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
    let format = match ext.as_str() {
        "hdr" => image::ImageFormat::Hdr,
        "exr" => image::ImageFormat::OpenExr,
        _ => {
            return Err(err(format!(
                "unknown environment map format '.{ext}' (expected an equirectangular .hdr or .exr)"
            )))
        }
    };
    let limit = crate::io::input_file::MAX_ENVMAP_BYTES;
    let too_large = |len: u64| err(format!("environment map is {len} bytes, over the limit of {limit} bytes"));
    let not_readable = |m: crate::io::input_file::InputError| match m {
        crate::io::input_file::InputError::NotFound => err("environment map not found".into()),
        _ => err(format!("environment map {m}")),
    };
    // Decoders can panic on corrupt data (an overflowing run-length multiplier in the Radiance decoder, for
    // one): that is an error about this file, not a crash.
    let decoded = if let Some(held) = crate::io::memory_files::lookup(path) {
        // A file given in memory (a web page's dropped file).
        let bytes = held.map_err(not_readable)?;
        let len = bytes.len() as u64;
        if len > limit {
            return Err(too_large(len));
        }
        check_size_and_header(&bytes[..bytes.len().min(HDR_HEADER_SCAN as usize)], len, format).map_err(err)?;
        super::catch_quietly(|| decode(path, std::io::Cursor::new(&bytes[..]), format))
    } else {
        // A regular file only (a FIFO would block, /dev/zero never ends), and within the documented size limit.
        let (file, len) = crate::io::input_file::open_regular(path).map_err(not_readable)?;
        if len > limit {
            return Err(too_large(len));
        }
        // Only a Radiance file's header is looked at: an EXR is not read twice.
        let head = if format == image::ImageFormat::Hdr { file_head(&file).map_err(err)? } else { Vec::new() };
        check_size_and_header(&head, len, format).map_err(err)?;
        super::catch_quietly(|| decode(path, BufReader::new(file), format))
    };
    decoded.unwrap_or_else(|panic| Err(err(format!("corrupt {} file (the decoder failed: {panic})", name(format)))))
}

/// How much of a Radiance file is searched for the end of its header.
const HDR_HEADER_SCAN: u64 = 64 << 10;

/// A Radiance header is the signature line, attribute lines, an empty line, then the resolution line. A file
/// that starts like one but ends before the resolution line is cut short; the decoder would report the first
/// partial line it meets as a bad attribute or dimension instead.
fn check_size_and_header(head: &[u8], len: u64, format: image::ImageFormat) -> Result<(), String> {
    if len == 0 {
        return Err("empty file (0 bytes)".into());
    }
    if format != image::ImageFormat::Hdr {
        return Ok(());
    }
    if !head.starts_with(b"#?RADIANCE") || len > HDR_HEADER_SCAN {
        return Ok(()); // not a Radiance file at all, or too long to be a cut header: the decoder says what is wrong
    }
    let complete = match head.windows(2).position(|w| w == b"\n\n") {
        Some(end) => head[end + 2..].contains(&b'\n'),
        None => false,
    };
    if complete {
        return Ok(());
    }
    Err(format!(
        "truncated or malformed header: the file ({len} bytes) ends before the empty line that closes the Radiance header and the resolution line after it"
    ))
}

/// The first `HDR_HEADER_SCAN` bytes of `file`, which is rewound after.
fn file_head(file: &std::fs::File) -> Result<Vec<u8>, String> {
    use std::io::{Read, Seek};
    let unreadable = |e: std::io::Error| format!("cannot read environment map: {e}");
    let mut head = Vec::new();
    let mut reader = file; // `Read` and `Seek` are implemented for `&File`: the caller's handle is rewound
    reader.take(HDR_HEADER_SCAN).read_to_end(&mut head).map_err(unreadable)?;
    reader.rewind().map_err(unreadable)?;
    Ok(head)
}

fn decode(
    path: &Path,
    input: impl std::io::BufRead + std::io::Seek,
    format: image::ImageFormat,
) -> Result<(EnvMap, Vec<String>), SceneError> {
    let err = |message: String| SceneError::new(path, message);
    let mut reader = image::ImageReader::with_format(input, format);
    // The default 512 MiB cap would refuse a legitimate 8k×4k RGBA f32 EXR; MAX_SIDE already bounds the size, so
    // allow what a MAX_SIDE×MAX_SIDE/2 RGBA f32 map needs (2 GiB) and refuse larger ones by size, with a clear message.
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_SIDE);
    limits.max_image_height = Some(MAX_SIDE);
    limits.max_alloc = Some(2 << 30);
    reader.limits(limits);
    let decoder = reader.into_decoder().map_err(|e| err(describe(&e, format)))?;
    let (width, height) = image::ImageDecoder::dimensions(&decoder);
    if width == 0 || height == 0 {
        return Err(err(format!("empty image ({width}×{height})")));
    }
    if width > MAX_SIDE || height > MAX_SIDE {
        return Err(err(format!("{width}×{height} is too large (at most {MAX_SIDE} texels on a side)")));
    }
    let image = image::DynamicImage::from_decoder(decoder).map_err(|e| err(describe(&e, format)))?;

    let mut warnings = Vec::new();
    if width != 2 * height {
        // Not fatal: the mapping stretches any size over the sphere, but a non-2:1 map is usually not lat-long.
        warnings.push(format!(
            "{}: {width}×{height} is not 2:1; is it really an equirectangular (lat-long) map?",
            path.display()
        ));
    }

    let rgb = image.into_rgb32f();
    // Count each kind of bad texel so that the one warning tells a corrupt file (NaN, Inf, RGBE exponent 255) from
    // harmless lossy-codec undershoot (DWAA/DWAB EXRs decode with a few slightly negative texels).
    let (mut nan, mut inf, mut negative, mut huge, mut repaired) = (0usize, 0usize, 0usize, 0usize, 0usize);
    let mut most_negative = 0.0f32;
    let texels: Vec<[f32; 3]> = rgb
        .pixels()
        .map(|p| {
            let mut t = p.0;
            let mut bad = false;
            for c in &mut t {
                // `!(x >= 0 && x <= ABSURD)` also catches NaN, which every ordered comparison rejects.
                if !(*c >= 0.0 && *c <= ABSURD) {
                    if c.is_nan() {
                        nan += 1;
                    } else if c.is_infinite() {
                        inf += 1;
                    } else if *c < 0.0 {
                        negative += 1;
                        most_negative = most_negative.min(*c);
                    } else {
                        huge += 1;
                    }
                    *c = 0.0;
                    bad = true;
                }
            }
            repaired += bad as usize;
            t
        })
        .collect();
    if repaired > 0 {
        let mut kinds = Vec::new();
        if nan > 0 {
            kinds.push(format!("{nan} NaN"));
        }
        if inf > 0 {
            kinds.push(format!("{inf} infinite"));
        }
        if negative > 0 {
            kinds.push(format!("{negative} negative, down to {most_negative:.3e}"));
        }
        if huge > 0 {
            kinds.push(format!("{huge} above 1e30"));
        }
        warnings.push(format!(
            "{}: repaired {repaired} of {} texels ({} bad components set to 0: {})",
            path.display(),
            texels.len(),
            nan + inf + negative + huge,
            kinds.join("; ")
        ));
    }
    Ok((EnvMap { path: path.to_path_buf(), width, height, texels }, warnings))
}

/// Turns a decoder error into a sentence, recognising the cases users can act on.
fn describe(e: &image::ImageError, format: image::ImageFormat) -> String {
    let text = e.to_string();
    let lower = text.to_ascii_lowercase();
    match e {
        image::ImageError::Limits(_) => format!("too large to decode ({text}; at most {MAX_SIDE} texels on a side)"),
        image::ImageError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            format!("truncated file ({text})")
        }
        // The exr crate names DWAA/DWAB in its errors when it meets a DWA variant it cannot decode.
        _ if format == image::ImageFormat::OpenExr && lower.contains("dwa") => {
            format!("cannot decode this DWAA/DWAB-compressed EXR ({text}); re-save it with ZIP or PIZ compression")
        }
        image::ImageError::Unsupported(_) => format!("unsupported {} variant: {text}", name(format)),
        // The exr crate's words for a chunk or attribute that reaches past the end of the file.
        _ if format == image::ImageFormat::OpenExr && lower.contains("missing bytes") => {
            format!("truncated or corrupt file: it refers to bytes past its end ({text})")
        }
        // A chunk whose scan line (or tile) lies outside the data window.
        _ if format == image::ImageFormat::OpenExr && lower.contains("block position") => {
            format!("corrupt file: a chunk lies outside the image's data window ({text})")
        }
        // A chunk offset so large that seeking to it fails (EINVAL).
        _ if format == image::ImageFormat::OpenExr
            && (lower.contains("os error 22") || lower.contains("invalid argument")) =>
        {
            format!("corrupt file: a chunk offset points outside the file ({text})")
        }
        _ if format == image::ImageFormat::OpenExr && lower.contains("rgb channels") => {
            format!("no R, G, B channels found ({text}); an environment map needs an RGB(A) layer")
        }
        _ => format!("cannot decode {} data: {text}", name(format)),
    }
}

fn name(format: image::ImageFormat) -> &'static str {
    if format == image::ImageFormat::Hdr {
        "Radiance .hdr"
    } else {
        "OpenEXR"
    }
}

/// The direction a lat-long texture coordinate looks along (unit vector), before the renderer's rotation about +Y
/// (which adds `rotation` to φ; see `env_uv_to_direction` in `shaders/lights.wgsl`).
///
/// `u ∈ [0,1]` runs left to right, `v ∈ [0,1]` top to bottom; with φ = 2π(u − ½) and θ = πv,
/// `d = (sin θ sin φ, cos θ, −sin θ cos φ)`. So v = 0 is straight up (+Y), v = 1 straight down (−Y), the image
/// centre (u = ½, v = ½) looks down −Z, u = ¾ looks along +X and u = 0 / 1 along +Z. Seen from inside the sphere
/// (looking down −Z with +Y up, +X to the right) the map appears unmirrored, as in most renderers' lat-long
/// convention. The map's texel (x, y) covers u ∈ [x/W, (x+1)/W], v ∈ [y/H, (y+1)/H].
pub fn equirect_direction(u: f32, v: f32) -> Vec3 {
    let phi = 2.0 * PI * (u - 0.5);
    let theta = PI * v;
    let (sin_t, cos_t) = theta.sin_cos();
    let (sin_p, cos_p) = phi.sin_cos();
    Vec3::new(sin_t * sin_p, cos_t, -sin_t * cos_p)
}

/// The lat-long texture coordinate `(u, v)` ∈ [0,1]² of a direction (need not be unit length); the inverse of
/// [`equirect_direction`]. Straight up or down gives u = ½.
pub fn direction_to_equirect(d: Vec3) -> (f32, f32) {
    let d = d.normalize_or(Vec3::NEG_Z);
    let phi = d.x.atan2(-d.z); // ∈ [−π, π], 0 along −Z
    let u = (phi / (2.0 * PI) + 0.5).clamp(0.0, 1.0);
    let v = (d.y.clamp(-1.0, 1.0).acos() / PI).clamp(0.0, 1.0);
    (u, v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cardinal_directions() {
        let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
        assert!(close(equirect_direction(0.5, 0.5), Vec3::NEG_Z));
        assert!(close(equirect_direction(0.75, 0.5), Vec3::X));
        assert!(close(equirect_direction(0.25, 0.5), Vec3::NEG_X));
        assert!(close(equirect_direction(0.0, 0.5), Vec3::Z));
        assert!(close(equirect_direction(0.3, 0.0), Vec3::Y));
        assert!(close(equirect_direction(0.3, 1.0), Vec3::NEG_Y));
    }

    #[test]
    fn round_trip() {
        for i in 0..64 {
            for j in 1..32 {
                let (u, v) = ((i as f32 + 0.5) / 64.0, j as f32 / 32.0);
                let d = equirect_direction(u, v);
                assert!((d.length() - 1.0).abs() < 1e-5);
                let (u2, v2) = direction_to_equirect(d);
                assert!((u - u2).abs() < 1e-4 && (v - v2).abs() < 1e-4, "({u},{v}) -> {d} -> ({u2},{v2})");
                // And direction → uv → direction, scale-independent.
                let d2 = equirect_direction(u2, v2);
                assert!((d - d2).length() < 1e-4);
                let (u3, v3) = direction_to_equirect(d * 3.0);
                assert!((u3 - u2).abs() < 1e-6 && (v3 - v2).abs() < 1e-6);
            }
        }
    }
}
