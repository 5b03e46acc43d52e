//! What a compute pipeline is built from, compared whole: a pipeline built ahead of need from a forecast
//! (`render::pipeline_forecast`) is used only by a builder whose request is equal to it in every byte, so it is
//! exactly the pipeline that builder would have made.

/// The inputs of one compute pipeline: WGSL source, entry point, override constants and the layout's tag (which
/// binding layout the pipeline layout was made from; the caller names them).
#[derive(Clone, Debug, PartialEq)]
pub struct PipelineRequest {
    pub source: String,
    pub entry: String,
    pub constants: Vec<(String, f64)>,
    pub layout: String,
}

impl PipelineRequest {
    /// The request as bytes (`decode` reads them back): each field as a little-endian length and its bytes, a
    /// constant as its name and the f64's bits.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.source.len() + 256);
        let text = |out: &mut Vec<u8>, s: &str| {
            out.extend_from_slice(&(s.len() as u64).to_le_bytes());
            out.extend_from_slice(s.as_bytes());
        };
        text(&mut out, &self.source);
        text(&mut out, &self.entry);
        text(&mut out, &self.layout);
        out.extend_from_slice(&(self.constants.len() as u64).to_le_bytes());
        for (name, value) in &self.constants {
            text(&mut out, name);
            out.extend_from_slice(&value.to_bits().to_le_bytes());
        }
        out
    }

    /// The request `encode` wrote, or why these bytes are not one.
    pub fn decode(bytes: &[u8]) -> Result<PipelineRequest, &'static str> {
        let mut r = Reader(bytes);
        let (source, entry, layout) = (r.text()?, r.text()?, r.text()?);
        let mut constants = Vec::new();
        for _ in 0..r.word()? {
            let name = r.text()?;
            constants.push((name, f64::from_bits(r.word()?)));
        }
        if !r.0.is_empty() {
            return Err("bytes after the request");
        }
        Ok(PipelineRequest { source, entry, constants, layout })
    }
}

/// The bytes of an encoded request not read yet.
struct Reader<'a>(&'a [u8]);

impl<'a> Reader<'a> {
    fn take(&mut self, n: u64) -> Result<&'a [u8], &'static str> {
        let n = usize::try_from(n).ok().filter(|&n| n <= self.0.len()).ok_or("truncated")?;
        let (head, tail) = self.0.split_at(n);
        self.0 = tail;
        Ok(head)
    }

    fn word(&mut self) -> Result<u64, &'static str> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes")))
    }

    fn text(&mut self) -> Result<String, &'static str> {
        let len = self.word()?;
        String::from_utf8(self.take(len)?.to_vec()).map_err(|_| "text not UTF-8")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_request_reads_back_equal_and_damage_is_refused() {
        let r = PipelineRequest {
            source: "fn main() {}".into(),
            entry: "main".into(),
            constants: vec![("A".into(), 1.0), ("B".into(), -0.5)],
            layout: "separate".into(),
        };
        let bytes = r.encode();
        assert_eq!(PipelineRequest::decode(&bytes), Ok(r));
        assert!(PipelineRequest::decode(&bytes[..bytes.len() - 1]).is_err());
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(PipelineRequest::decode(&longer).is_err());
        let mut huge = bytes;
        huge[..8].copy_from_slice(&u64::MAX.to_le_bytes());
        assert!(PipelineRequest::decode(&huge).is_err());
    }
}
