//! Warnings collected while loading ([`Notes`]); repeated problems are counted and reported once.

use std::collections::HashSet;

/// Warnings collected while loading; repeated problems are counted and reported once.
#[derive(Default)]
pub(super) struct Notes {
    lines: Vec<String>,
    seen: HashSet<String>,
    pub(super) skipped_primitives: usize,
    pub(super) dropped_triangles: usize,
    pub(super) repaired_normals: usize,
    pub(super) repaired_uvs: usize,
}

impl Notes {
    pub(super) fn push(&mut self, line: String) {
        if self.seen.insert(line.clone()) {
            self.lines.push(line);
        }
    }
    /// Adds `line` unless a warning with the same `key` was already added.
    pub(super) fn once(&mut self, key: &str, line: impl FnOnce() -> String) {
        if self.seen.insert(format!("\u{0}{key}")) {
            self.lines.push(line());
        }
    }
    pub(super) fn finish(mut self) -> Vec<String> {
        let counted = [
            (
                self.skipped_primitives,
                "skipped point/line primitive(s) (POINTS, LINES, LINE_LOOP, LINE_STRIP): only triangles are rendered",
            ),
            (self.dropped_triangles, "dropped triangle(s) that use non-finite (NaN/Inf) vertex positions"),
            (self.repaired_normals, "zero or non-finite vertex normal(s) regenerated from the geometry"),
            (self.repaired_uvs, "non-finite texture coordinate(s) replaced with 0"),
        ];
        for (n, what) in counted.into_iter().filter(|(n, _)| *n > 0) {
            self.lines.push(format!("{n} {what}"));
        }
        self.lines
    }
}
