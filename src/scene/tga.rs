//! Truevision TGA images (uncompressed and run-length encoded; true-colour 24/32-bit and 8-bit grey), the format
//! of the Bitterli scenes' textures, decoded to RGBA8 top row first.

/// A decoded TGA: width, height, RGBA8 texels top row first.
#[derive(Debug)]
pub struct Tga {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Row-major RGBA8, top row first.
    pub texels: Vec<[u8; 4]>,
}

/// Decodes a TGA file's bytes.
pub fn decode(b: &[u8]) -> Result<Tga, String> {
    if b.len() < 18 {
        return Err("truncated TGA header (under 18 bytes)".into());
    }
    let (id_len, cmap_type, kind) = (b[0] as usize, b[1], b[2]);
    let cmap_len = u16::from_le_bytes([b[5], b[6]]) as usize;
    let cmap_bits = b[7] as usize;
    let width = u16::from_le_bytes([b[12], b[13]]) as u32;
    let height = u16::from_le_bytes([b[14], b[15]]) as u32;
    let bpp = b[16] as usize;
    let top_first = b[17] & 0x20 != 0;
    let rle = match kind {
        2 | 3 => false,
        10 | 11 => true,
        _ => return Err(format!("unsupported TGA image type {kind} (expected true-colour or grey, 2/3/10/11)")),
    };
    let grey = kind == 3 || kind == 11;
    let px = match (grey, bpp) {
        (false, 24) => 3,
        (false, 32) => 4,
        (true, 8) => 1,
        _ => return Err(format!("unsupported TGA pixel depth {bpp} for image type {kind}")),
    };
    if width == 0 || height == 0 {
        return Err(format!("TGA size {width}x{height} is empty"));
    }
    let skip = if cmap_type != 0 { cmap_len * cmap_bits.div_ceil(8) } else { 0 };
    let mut pos = 18 + id_len + skip;
    let n = width as usize * height as usize;
    let mut raw: Vec<u8> = Vec::with_capacity(n * px);
    let truncated = || "truncated TGA pixel data".to_string();
    if rle {
        while raw.len() < n * px {
            let h = *b.get(pos).ok_or_else(truncated)? as usize;
            pos += 1;
            let count = (h & 0x7f) + 1;
            if h & 0x80 != 0 {
                let p = b.get(pos..pos + px).ok_or_else(truncated)?;
                for _ in 0..count {
                    raw.extend_from_slice(p);
                }
                pos += px;
            } else {
                raw.extend_from_slice(b.get(pos..pos + count * px).ok_or_else(truncated)?);
                pos += count * px;
            }
        }
        raw.truncate(n * px);
    } else {
        raw.extend_from_slice(b.get(pos..pos + n * px).ok_or_else(truncated)?);
    }
    let (w, h) = (width as usize, height as usize);
    let mut texels = vec![[0u8; 4]; n];
    for y in 0..h {
        let src = if top_first { y } else { h - 1 - y };
        for x in 0..w {
            let p = &raw[(src * w + x) * px..][..px];
            texels[y * w + x] = match px {
                1 => [p[0], p[0], p[0], 255],
                3 => [p[2], p[1], p[0], 255],
                _ => [p[2], p[1], p[0], p[3]],
            };
        }
    }
    Ok(Tga { width, height, texels })
}

#[cfg(test)]
mod tests {
    #[test]
    fn bottom_up_bgr_and_rle() {
        // 1×2, bottom-left origin: the first stored pixel is the bottom row.
        let mut f = vec![0u8; 18];
        f[2] = 2;
        f[12] = 1;
        f[14] = 2;
        f[16] = 24;
        f.extend([1, 2, 3, 4, 5, 6]);
        let t = super::decode(&f).unwrap();
        assert_eq!(t.texels, vec![[6, 5, 4, 255], [3, 2, 1, 255]]);
        f[2] = 10;
        f.truncate(18);
        f.extend([0x81, 7, 8, 9]);
        let t = super::decode(&f).unwrap();
        assert_eq!(t.texels, vec![[9, 8, 7, 255]; 2]);
        assert!(super::decode(&f[..19]).unwrap_err().contains("truncated"));
    }
}
