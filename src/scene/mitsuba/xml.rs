//! A small XML reader for Mitsuba scene files: elements with attributes and line numbers; comments, the
//! `<?xml ?>` prolog and text content are skipped (Mitsuba keeps everything in attributes). Entities are decoded.

use crate::scene::SceneError;
use std::path::Path;

/// One element.
#[derive(Clone, Debug, Default)]
pub struct Element {
    /// Tag name.
    pub tag: String,
    /// Attributes in file order.
    pub attrs: Vec<(String, String)>,
    /// Child elements.
    pub children: Vec<Element>,
    /// Line of the opening tag.
    pub line: usize,
}

impl Element {
    /// An attribute's value.
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs.iter().find(|(k, _)| k == name).map(|(_, v)| v.as_str())
    }
}

/// Nesting depth beyond which a file is refused (a hostile file must not overflow the stack).
const MAX_DEPTH: usize = 256;

/// Parses a whole document and returns its root element.
pub fn parse(path: &Path, text: &str) -> Result<Element, SceneError> {
    let b = text.as_bytes();
    let err = |pos: usize, m: String| {
        let line = 1 + b[..pos.min(b.len())].iter().filter(|&&c| c == b'\n').count();
        SceneError::new(path, format!("line {line}: {m}"))
    };
    let line_of = |pos: usize| 1 + b[..pos].iter().filter(|&&c| c == b'\n').count();
    let mut stack: Vec<Element> = vec![Element { tag: "#document".into(), ..Default::default() }];
    let mut i = 0;
    while i < b.len() {
        if b[i] != b'<' {
            i += 1;
            continue;
        }
        if text[i..].starts_with("<!--") {
            let end = text[i..].find("-->").ok_or_else(|| err(i, "unterminated comment".into()))?;
            i += end + 3;
            continue;
        }
        if text[i..].starts_with("<?") || text[i..].starts_with("<!") {
            let end = text[i..].find('>').ok_or_else(|| err(i, "unterminated declaration".into()))?;
            i += end + 1;
            continue;
        }
        if text[i..].starts_with("</") {
            let end = text[i..].find('>').ok_or_else(|| err(i, "unterminated closing tag".into()))?;
            let name = text[i + 2..i + end].trim();
            let open = stack.pop().filter(|e| e.tag != "#document");
            match open {
                Some(e) if e.tag == name => stack.last_mut().expect("document").children.push(e),
                Some(e) => {
                    return Err(err(i, format!("</{name}> closes <{}> opened on line {}", e.tag, e.line)));
                }
                None => return Err(err(i, format!("</{name}> without an opening tag"))),
            }
            i += end + 1;
            continue;
        }
        // An opening tag: name, attributes, then '>' or '/>'.
        let start = i;
        i += 1;
        let name_end =
            i + text[i..].find(|c: char| c.is_whitespace() || c == '>' || c == '/').unwrap_or(text.len() - i);
        let tag = text[i..name_end].to_string();
        if tag.is_empty() {
            return Err(err(start, "'<' without a tag name".into()));
        }
        i = name_end;
        let mut e = Element { tag, line: line_of(start), ..Default::default() };
        loop {
            while i < b.len() && b[i].is_ascii_whitespace() {
                i += 1;
            }
            if i >= b.len() {
                return Err(err(start, format!("<{}> is never closed (is the file truncated?)", e.tag)));
            }
            if b[i] == b'>' {
                i += 1;
                if stack.len() > MAX_DEPTH {
                    return Err(err(start, format!("elements nested more than {MAX_DEPTH} deep")));
                }
                stack.push(e);
                break;
            }
            if text[i..].starts_with("/>") {
                i += 2;
                stack.last_mut().expect("document").children.push(e);
                break;
            }
            let eq = text[i..].find('=').ok_or_else(|| err(i, format!("malformed attribute in <{}>", e.tag)))?;
            let key = text[i..i + eq].trim().to_string();
            if key.is_empty() || key.contains(|c: char| c.is_whitespace() || c == '<' || c == '>') {
                return Err(err(i, format!("malformed attribute in <{}>", e.tag)));
            }
            i += eq + 1;
            while i < b.len() && b[i].is_ascii_whitespace() {
                i += 1;
            }
            let q = *b.get(i).ok_or_else(|| err(i, "the file ends inside a tag".into()))?;
            if q != b'"' && q != b'\'' {
                return Err(err(i, format!("attribute '{key}' of <{}> is not quoted", e.tag)));
            }
            let close = text[i + 1..]
                .find(q as char)
                .ok_or_else(|| err(i, format!("unterminated value of attribute '{key}'")))?;
            let value = decode_entities(&text[i + 1..i + 1 + close]);
            i += close + 2;
            e.attrs.push((key, value));
        }
    }
    if stack.len() > 1 {
        let e = stack.last().expect("non-empty");
        return Err(SceneError::new(
            path,
            format!("line {}: <{}> is never closed (is the file truncated?)", e.line, e.tag),
        ));
    }
    let doc = stack.pop().expect("document");
    let mut roots = doc.children.into_iter();
    match (roots.next(), roots.next()) {
        (Some(root), None) => Ok(root),
        (None, _) => Err(SceneError::new(path, "no XML element in the file")),
        (Some(_), Some(second)) => {
            Err(SceneError::new(path, format!("line {}: a second root element <{}>", second.line, second.tag)))
        }
    }
}

fn decode_entities(s: &str) -> String {
    if !s.contains('&') {
        return s.to_string();
    }
    s.replace("&lt;", "<").replace("&gt;", ">").replace("&quot;", "\"").replace("&apos;", "'").replace("&amp;", "&")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elements_attributes_lines() {
        let t = "<?xml version=\"1.0\"?>\n<!-- c -->\n<scene version=\"3.0.0\">\n  <float name=\"fov\" value='45'/>\n  <shape type=\"obj\">\n  </shape>\n</scene>\n";
        let r = parse(Path::new("s.xml"), t).unwrap();
        assert_eq!(r.tag, "scene");
        assert_eq!(r.children.len(), 2);
        assert_eq!(r.children[0].attr("value"), Some("45"));
        assert_eq!(r.children[1].line, 5);
        let e = parse(Path::new("s.xml"), "<scene>\n<shape type=\"obj\">\n</scene>").unwrap_err().to_string();
        assert!(e.contains("s.xml: line 3") && e.contains("opened on line 2"), "{e}");
        let e = parse(Path::new("s.xml"), "<scene>\n<shape").unwrap_err().to_string();
        assert!(e.contains("truncated"), "{e}");
    }
}
