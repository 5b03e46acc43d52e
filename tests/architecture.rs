//! The house drawn from the imports: the folders of `src/` are layers, each using only the ones docs/architecture.md
//! lists before it, and no module reaches a sibling that reaches back (no import circle anywhere). Read from the
//! source text (`crate::…` and `super::…` paths outside comments and test modules), so a new import that breaks
//! the rule fails here with the file that made it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The layers, bottom first, as docs/architecture.md lists them.
const LAYERS: &[&str] = &["io", "gpu", "scene", "accel", "render", "state", "api", "testkit", "lab", "viewer"];

type Module = Vec<String>;

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// `src/render/renderer/timed.rs` → ["render", "renderer", "timed"]; `mod.rs` names its folder.
fn module_of(src: &Path, file: &Path) -> Module {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut m: Module = rel.iter().map(|c| c.to_string_lossy().into_owned()).collect();
    if matches!(m.last().map(String::as_str), Some("mod" | "lib" | "main")) {
        m.pop();
    }
    m
}

/// The code of a file without comments and without its `#[cfg(test)] mod tests` (tests may reach anywhere).
fn code(text: &str) -> String {
    let text = match text.find("#[cfg(test)]\nmod tests") {
        Some(i) => &text[..i],
        None => text,
    };
    text.lines().map(|l| l.split("//").next().unwrap()).collect::<Vec<_>>().join("\n")
}

/// The paths a use-tree names: `a::{b, c::{d, e}}` → a::b, a::c::d, a::c::e (idents only; `self` keeps its parent).
fn expand(tree: &str) -> Vec<Vec<String>> {
    let tree = tree.trim();
    let Some(open) = tree.find('{') else {
        let path: Vec<String> = tree
            .split("::")
            .map(|s| s.trim().split(' ').next().unwrap_or("").to_string())
            .take_while(|s| !s.is_empty() && s != "self" && s != "*")
            .collect();
        return vec![path];
    };
    let prefix: Vec<String> =
        tree[..open].split("::").map(|s| s.trim().to_string()).filter(|s| !s.is_empty()).collect();
    let close = tree.rfind('}').unwrap_or(tree.len());
    let inner = &tree[open + 1..close];
    let (mut parts, mut depth, mut last) = (Vec::new(), 0, 0);
    for (i, c) in inner.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&inner[last..i]);
                last = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&inner[last..]);
    let mut out = vec![prefix.clone()];
    for p in parts.into_iter().filter(|p| !p.trim().is_empty()) {
        for tail in expand(p) {
            out.push(prefix.iter().cloned().chain(tail).collect());
        }
    }
    out
}

/// Every module a file's code names by path (`crate::…`, `super::…`), resolved to the longest prefix that is a
/// module; the file's own ancestors and descendants are left out (a module's children are part of it).
fn imports(module: &Module, text: &str, modules: &BTreeSet<Module>) -> BTreeSet<Module> {
    let mut out = BTreeSet::new();
    let is_ident = |c: char| c.is_ascii_alphanumeric() || c == '_';
    for root in ["crate::", "super::"] {
        for (start, _) in text.match_indices(root) {
            if text[..start].chars().next_back().is_some_and(is_ident) {
                continue;
            }
            // The path, with any use-tree braces it opens.
            let rest = &text[start + root.len()..];
            let (mut depth, mut end) = (0i32, rest.len());
            for (i, c) in rest.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth > 0 => depth -= 1,
                    c if depth == 0 && !(is_ident(c) || c == ':') => {
                        end = i;
                        break;
                    }
                    _ => {}
                }
            }
            let base: Module =
                if root == "crate::" { vec![] } else { module[..module.len().saturating_sub(1)].to_vec() };
            for path in expand(&rest[..end]) {
                let full: Module = base.iter().cloned().chain(path).collect();
                let target = (1..=full.len()).rev().map(|n| full[..n].to_vec()).find(|m| modules.contains(m));
                if let Some(t) = target {
                    if !t.starts_with(module) && !module.starts_with(&t) {
                        out.insert(t);
                    }
                }
            }
        }
    }
    out
}

fn graph() -> BTreeMap<Module, (PathBuf, BTreeSet<Module>)> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let modules: BTreeSet<Module> = files.iter().map(|f| module_of(&src, f)).collect();
    files
        .iter()
        .map(|f| {
            let m = module_of(&src, f);
            let deps = imports(&m, &code(&std::fs::read_to_string(f).unwrap()), &modules);
            (m, (f.strip_prefix(src.parent().unwrap()).unwrap().to_path_buf(), deps))
        })
        .collect()
}

#[test]
fn each_layer_uses_only_the_layers_below_it() {
    let rank = |m: &Module| m.first().and_then(|top| LAYERS.iter().position(|l| l == top));
    let mut wrong = Vec::new();
    for (m, (file, deps)) in graph() {
        let Some(r) = rank(&m) else { continue };
        for d in deps {
            if let Some(rd) = rank(&d) {
                if rd > r {
                    wrong.push(format!("{} uses {} (a layer above {})", file.display(), d.join("::"), m[0]));
                }
            }
        }
    }
    for top in ["io", "gpu", "scene", "render", "state", "api", "lab", "viewer"] {
        assert!(LAYERS.contains(&top));
    }
    assert!(wrong.is_empty(), "imports against the layers:\n{}", wrong.join("\n"));
}

#[test]
fn no_module_reaches_a_sibling_that_reaches_back() {
    let g = graph();
    // Edges between siblings: a dependency of a module inside folder F on another module inside F counts as
    // one between the two children of F that hold them.
    let mut edges: BTreeMap<Module, BTreeSet<Module>> = BTreeMap::new();
    for (m, (_, deps)) in &g {
        for d in deps {
            let common = m.iter().zip(d.iter()).take_while(|(a, b)| a == b).count();
            if common < m.len() && common < d.len() {
                edges.entry(m[..=common].to_vec()).or_default().insert(d[..=common].to_vec());
            }
        }
    }
    let reaches = |from: &Module, to: &Module| {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from.clone()];
        while let Some(x) = stack.pop() {
            if &x == to {
                return true;
            }
            for y in edges.get(&x).into_iter().flatten() {
                if seen.insert(y.clone()) {
                    stack.push(y.clone());
                }
            }
        }
        false
    };
    let mut circles = BTreeSet::new();
    for (a, outs) in &edges {
        for b in outs {
            if reaches(b, a) {
                let (x, y) = if a < b { (a, b) } else { (b, a) };
                circles.insert(format!("{} <-> {}", x.join("::"), y.join("::")));
            }
        }
    }
    assert!(circles.is_empty(), "import circles:\n{}", circles.into_iter().collect::<Vec<_>>().join("\n"));
}
