//! Portable float maps (`PF` RGB / `Pf` grey, 32-bit floats, either byte order by the sign of the scale line),
//! as pbrt and Tungsten store environment maps. Rows are stored bottom to top; we return them top row first.

/// A decoded PFM: width, height and RGB texels, top row first.
#[derive(Debug)]
pub struct Pfm {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Row-major RGB, top row first (grey files repeat the value).
    pub texels: Vec<[f32; 3]>,
}

/// Decodes a PFM file's bytes.
pub fn decode(bytes: &[u8]) -> Result<Pfm, String> {
    // Header: three whitespace-separated tokens after the magic, then one whitespace byte, then the data.
    let mut pos = 0;
    let mut token = || -> Result<String, String> {
        while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        if start == pos || pos - start > 32 {
            return Err("truncated or malformed PFM header".into());
        }
        Ok(String::from_utf8_lossy(&bytes[start..pos]).into_owned())
    };
    let magic = token()?;
    let channels = match magic.as_str() {
        "PF" => 3,
        "Pf" => 1,
        _ => return Err(format!("not a PFM file (magic '{magic}', expected 'PF' or 'Pf')")),
    };
    let width: u32 = token()?.parse().map_err(|_| "bad PFM width".to_string())?;
    let height: u32 = token()?.parse().map_err(|_| "bad PFM height".to_string())?;
    let scale: f32 = token()?.parse().map_err(|_| "bad PFM scale".to_string())?;
    pos += 1; // the single whitespace byte after the scale
    if width == 0 || height == 0 || width > 16384 || height > 16384 {
        return Err(format!("PFM size {width}x{height} is out of range (1..=16384 per side)"));
    }
    let little = scale < 0.0;
    let n = width as usize * height as usize * channels;
    let data = bytes.get(pos..pos + n * 4).ok_or_else(|| {
        format!("truncated PFM data: {width}x{height}x{channels} floats need {} bytes after the header", n * 4)
    })?;
    let floats: Vec<f32> = data
        .chunks_exact(4)
        .map(|c| {
            let b = [c[0], c[1], c[2], c[3]];
            if little {
                f32::from_le_bytes(b)
            } else {
                f32::from_be_bytes(b)
            }
        })
        .collect();
    let (w, h) = (width as usize, height as usize);
    let mut texels = vec![[0.0f32; 3]; w * h];
    for y in 0..h {
        let src_row = h - 1 - y;
        for x in 0..w {
            let i = (src_row * w + x) * channels;
            texels[y * w + x] = if channels == 3 { [floats[i], floats[i + 1], floats[i + 2]] } else { [floats[i]; 3] };
        }
    }
    Ok(Pfm { width, height, texels })
}

#[cfg(test)]
mod tests {
    #[test]
    fn two_by_one_flipped_rows() {
        let mut f = b"PF\n1 2\n-1.0\n".to_vec();
        for v in [1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0] {
            f.extend(v.to_le_bytes());
        }
        let p = super::decode(&f).unwrap();
        assert_eq!((p.width, p.height), (1, 2));
        assert_eq!(p.texels, vec![[4.0, 5.0, 6.0], [1.0, 2.0, 3.0]]);
        assert!(super::decode(&f[..f.len() - 1]).unwrap_err().contains("truncated"));
    }
}
