//! Truevision TGA images (the format of the Bitterli scenes' textures), decoded by the image crate under its
//! `image::Limits` (`import_texture::decode_limited`: the header's size is checked before anything is allocated)
//! to RGBA8 top row first. Our own reader was replaced: it allocated what any header declared.

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

/// Decodes a TGA file's bytes (true-colour, grey and colour-mapped, uncompressed or run-length encoded).
pub fn decode(b: &[u8]) -> Result<Tga, String> {
    let image = super::import_texture::decode_limited(b, image::ImageFormat::Tga)?.to_rgba8();
    let (width, height) = image.dimensions();
    Ok(Tga { width, height, texels: image.pixels().map(|p| p.0).collect() })
}

#[cfg(test)]
mod tests {
    /// An 18-byte header: image type `kind`, `w`×`h`, `bpp` bits per pixel, bottom-left origin.
    fn header(kind: u8, w: u16, h: u16, bpp: u8) -> Vec<u8> {
        let mut f = vec![0u8; 18];
        f[2] = kind;
        f[12..14].copy_from_slice(&w.to_le_bytes());
        f[14..16].copy_from_slice(&h.to_le_bytes());
        f[16] = bpp;
        f
    }

    #[test]
    fn bottom_up_bgr_and_rle() {
        // 1×2, bottom-left origin: the first stored pixel is the bottom row.
        let mut f = header(2, 1, 2, 24);
        f.extend([1, 2, 3, 4, 5, 6]);
        let t = super::decode(&f).unwrap();
        assert_eq!(t.texels, vec![[6, 5, 4, 255], [3, 2, 1, 255]]);
        let mut f = header(10, 1, 2, 24);
        f.extend([0x81, 7, 8, 9]);
        let t = super::decode(&f).unwrap();
        assert_eq!(t.texels, vec![[9, 8, 7, 255]; 2]);
        assert!(super::decode(&f[..19]).is_err());
    }

    #[test]
    fn a_huge_declared_size_is_refused_before_it_is_allocated() {
        for kind in [2, 10] {
            let mut f = header(kind, 65535, 65535, 32);
            f.extend([0x81, 1, 2, 3, 4]);
            let e = super::decode(&f).unwrap_err();
            assert!(e.contains("65535×65535 is too large"), "{e}");
        }
    }
}
