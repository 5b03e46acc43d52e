//! Linear images as EXR files: writing a film with text attributes (references, merged parts, `--output x.exr`)
//! and reading any EXR back with its attributes.

use std::collections::BTreeMap;
use std::path::Path;

pub use crate::io::error::ImageReadError;
use crate::io::error::OutputError;

fn text(s: &str) -> exr::meta::attribute::Text {
    use exr::meta::attribute::Text;
    Text::new_or_none(s).unwrap_or_else(|| {
        Text::new_or_panic(s.chars().map(|c| if (c as u32) < 256 { c } else { '?' }).collect::<String>())
    })
}

/// Row-major linear RGB pixels of a `width`×`height` image.
pub struct Pixels<'a> {
    pub width: u32,
    pub height: u32,
    pub rgb: &'a [[f32; 3]],
}

/// Writes linear RGB float32 EXR with `attributes` as text attributes of the layer (written to a temporary
/// file and renamed; see `output_file`).
pub fn write(path: &Path, image: Pixels, attributes: &[(String, String)]) -> Result<(), OutputError> {
    crate::io::output_file::check(path, true)?.write(|tmp| encode(tmp, image, attributes))
}

/// Encodes `image` as linear RGB float32 EXR at `path`, with `attributes` as text attributes of the layer.
pub fn encode(path: &Path, image: Pixels, attributes: &[(String, String)]) -> Result<(), exr::error::Error> {
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    encode_into(file, image, attributes)
}

/// `encode` into any seekable writer (a `Cursor` over the bytes of a browser download).
pub fn encode_into(
    out: impl std::io::Write + std::io::Seek,
    image: Pixels,
    attributes: &[(String, String)],
) -> Result<(), exr::error::Error> {
    use exr::prelude::*;
    let (w, h) = (image.width as usize, image.height as usize);
    let mut layer_attributes = LayerAttributes::named("mislab");
    layer_attributes.software_name = Some(text("mislab"));
    for (k, v) in attributes {
        layer_attributes.other.insert(text(k), AttributeValue::Text(text(v)));
    }
    let pixels = image.rgb;
    let layer = Layer::new(
        (w, h),
        layer_attributes,
        Encoding::FAST_LOSSLESS,
        SpecificChannels::rgb(|p: Vec2<usize>| {
            let c = pixels[p.y() * w + p.x()];
            (c[0], c[1], c[2])
        }),
    );
    Image::from_layer(layer).write().to_buffered(out)
}

/// A reference read back: size, linear RGB pixels, and its text attributes.
#[derive(Clone, Debug)]
pub struct ReferenceImage {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Row-major RGB.
    pub pixels: Vec<[f32; 3]>,
    /// Text attributes of the first layer (empty for EXRs from elsewhere).
    pub attributes: BTreeMap<String, String>,
}

/// Reads a linear image from an OpenEXR file (any writer) and, where present, the text attributes `write`
/// records. Anything else is refused: an 8-bit PNG or JPEG is tonemapped and clipped, and an error measured
/// against it would be silently meaningless.
pub fn read(path: &Path) -> Result<ReferenceImage, ImageReadError> {
    let bytes = crate::io::input_file::read_bounded(path, crate::io::input_file::MAX_ENVMAP_BYTES)
        .map_err(|source| ImageReadError::Input { path: path.into(), source })?;
    if !bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        return Err(ImageReadError::NotExr { path: path.into() });
    }
    let img = image::load_from_memory_with_format(&bytes, image::ImageFormat::OpenExr)
        .map_err(|e| ImageReadError::Decode { path: path.into(), message: e.to_string() })?
        .into_rgb32f();
    let (width, height) = img.dimensions();
    let pixels: Vec<[f32; 3]> = img.pixels().map(|p| p.0).collect();
    let mut attributes = BTreeMap::new();
    if let Ok(meta) = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(&bytes), false) {
        if let Some(header) = meta.headers.first() {
            for (k, v) in &header.own_attributes.other {
                if let exr::meta::attribute::AttributeValue::Text(t) = v {
                    attributes.insert(k.to_string(), t.to_string());
                }
            }
        }
    }
    Ok(ReferenceImage { width, height, pixels, attributes })
}
