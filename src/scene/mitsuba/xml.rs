//! Mitsuba scene files as a tree of elements with attributes and line numbers, read by `roxmltree` (strict,
//! well-fuzzed, with positions; DTDs refused, entity expansion bounded). Comments, the prolog and text content are
//! dropped (Mitsuba keeps everything in attributes). Errors name the file and line and never quote more of the file
//! than a clipped tag or entity name.

use crate::io::input_file::clip;
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

/// Nesting depth beyond which a file is refused (the loader walks the tree recursively).
const MAX_DEPTH: usize = 256;
/// Elements, attributes and text nodes a file may hold (a 16 M-node file would take gigabytes as a tree).
const MAX_NODES: u32 = 4_000_000;

/// Parses a whole document and returns its root element.
pub fn parse(path: &Path, text: &str) -> Result<Element, SceneError> {
    let options = roxmltree::ParsingOptions { allow_dtd: false, nodes_limit: MAX_NODES, ..Default::default() };
    let doc = roxmltree::Document::parse_with_options(text, options).map_err(|e| {
        let last_line = text.lines().count().max(1);
        SceneError::new(path, describe(&e, last_line))
    })?;
    element(path, &doc, doc.root_element(), 0)
}

fn element(path: &Path, doc: &roxmltree::Document, n: roxmltree::Node, depth: usize) -> Result<Element, SceneError> {
    let line = doc.text_pos_at(n.range().start).row as usize;
    if depth > MAX_DEPTH {
        return Err(SceneError::new(path, format!("line {line}: elements nested more than {MAX_DEPTH} deep")));
    }
    let children = n.children().filter(|c| c.is_element()).map(|c| element(path, doc, c, depth + 1));
    Ok(Element {
        tag: n.tag_name().name().to_string(),
        attrs: n.attributes().map(|a| (a.name().to_string(), a.value().to_string())).collect(),
        children: children.collect::<Result<_, _>>()?,
        line,
    })
}

/// The parser's error in our words: its line, and what is wrong without quoting the file.
fn describe(e: &roxmltree::Error, last_line: usize) -> String {
    use roxmltree::Error as E;
    let line = e.pos().row;
    let what = match e {
        E::UnexpectedCloseTag(open, close, _) => format!("</{}> closes <{}>", clip(close, 40), clip(open, 40)),
        E::UnclosedRootNode | E::UnexpectedEndOfStream => {
            return format!("line {last_line}: the file ends here and an element is never closed (is it truncated?)");
        }
        E::NoRootNode => return "no XML element in the file".into(),
        E::DtdDetected => "a DTD (<!DOCTYPE …>) is not allowed in a scene file".into(),
        E::NodesLimitReached => return format!("more than {MAX_NODES} XML nodes"),
        E::UnknownEntityReference(name, _) => format!("unknown entity '&{};'", clip(name, 40)),
        E::EntityReferenceLoop(_) => "entities that refer to each other".into(),
        E::DuplicatedAttribute(name, _) => format!("attribute '{}' given twice", clip(name, 40)),
        E::UnknownNamespace(prefix, _) => format!("unknown namespace prefix '{}'", clip(prefix, 40)),
        E::InvalidAttributeValue(_) => "malformed attribute value".into(),
        E::InvalidName(_) => "malformed element or attribute name".into(),
        E::NonXmlChar(..) | E::InvalidChar(..) | E::InvalidChar2(..) => "a character XML does not allow here".into(),
        E::UnknownToken(_) => "not XML here (a tag, comment or text was expected)".into(),
        _ => "not well-formed XML".into(),
    };
    format!("line {line}: {what}")
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
        assert!(e.contains("s.xml: line 3") && e.contains("</scene> closes <shape>"), "{e}");
        let e = parse(Path::new("s.xml"), "<!DOCTYPE s [<!ENTITY a \"aaaa\">]>\n<scene/>").unwrap_err().to_string();
        assert!(e.contains("DTD"), "{e}");
        let e = parse(Path::new("s.xml"), "root:x:0:0:root:/root:/bin/bash\n").unwrap_err().to_string();
        assert!(e.contains("line 1") && !e.contains("bash"), "{e}");
        let deep = "<a>".repeat(300) + &"</a>".repeat(300);
        let e = parse(Path::new("s.xml"), &deep).unwrap_err().to_string();
        assert!(e.contains("nested more than"), "{e}");
        let e = parse(Path::new("s.xml"), "<scene/>\n<scene/>").unwrap_err().to_string();
        assert!(e.contains("s.xml: line 2"), "{e}");
        let e = parse(Path::new("s.xml"), "<scene>\n<shape").unwrap_err().to_string();
        assert!(e.contains("truncated"), "{e}");
    }
}
