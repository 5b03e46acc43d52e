//! pbrt-v4 tokens: quoted strings, numbers, bare words (directives, `true`/`false`) and brackets, each with its
//! line, so that every later error can name the file and line.

use crate::scene::SceneError;
use std::path::Path;

/// One token's kind.
#[derive(Clone, Debug, PartialEq)]
pub enum Tok {
    /// A directive name or a bare `true` / `false`.
    Word(String),
    /// A quoted string (without the quotes).
    Str(String),
    /// A number.
    Num(f64),
    /// `[`
    Open,
    /// `]`
    Close,
}

/// A token and the (1-based) line it starts on.
#[derive(Clone, Debug, PartialEq)]
pub struct Token {
    /// What it is.
    pub tok: Tok,
    /// Line number in its file.
    pub line: usize,
}

/// Splits a pbrt file's text into tokens. `#` starts a comment to the end of the line.
pub fn tokenize(path: &Path, text: &str) -> Result<Vec<Token>, SceneError> {
    let err = |line: usize, m: String| SceneError::new(path, format!("line {line}: {m}"));
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    let (mut i, mut line) = (0usize, 1usize);
    while i < bytes.len() {
        let c = bytes[i];
        match c {
            b'\n' => {
                line += 1;
                i += 1;
            }
            b' ' | b'\t' | b'\r' | b',' => i += 1,
            b'#' => {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
            }
            b'[' => {
                out.push(Token { tok: Tok::Open, line });
                i += 1;
            }
            b']' => {
                out.push(Token { tok: Tok::Close, line });
                i += 1;
            }
            b'"' => {
                let start = i + 1;
                let mut j = start;
                while j < bytes.len() && bytes[j] != b'"' {
                    if bytes[j] == b'\n' {
                        return Err(err(line, "unterminated string (a newline before the closing '\"')".into()));
                    }
                    j += 1;
                }
                if j >= bytes.len() {
                    return Err(err(line, "unterminated string (the file ends before the closing '\"')".into()));
                }
                out.push(Token { tok: Tok::Str(text[start..j].to_string()), line });
                i = j + 1;
            }
            _ => {
                let start = i;
                while i < bytes.len()
                    && !matches!(bytes[i], b' ' | b'\t' | b'\r' | b'\n' | b'[' | b']' | b'"' | b'#' | b',')
                {
                    i += 1;
                }
                let word = &text[start..i];
                let first = word.as_bytes()[0];
                // Messages show a bad word only when it is short and number-like: a file that is not pbrt text
                // (an Include of something else) is never echoed.
                let shown = |w: &str| {
                    if w.len() <= 24 && w.bytes().all(|b| b.is_ascii_alphanumeric() || b"+-.".contains(&b)) {
                        format!("'{w}' ")
                    } else {
                        String::new()
                    }
                };
                if first.is_ascii_digit() || matches!(first, b'-' | b'+' | b'.') {
                    let v: f64 = word.parse().map_err(|_| err(line, format!("{}is not a number", shown(word))))?;
                    // pbrt-v4 reads its numbers as 32-bit floats: 1e39 is no number there, and an infinity here
                    // would reach the renderer (and a baked shader) as a literal.
                    if !(v.is_finite() && v.abs() <= f32::MAX as f64) {
                        return Err(err(
                            line,
                            format!("{}is out of the range of 32-bit floats (±3.4e38)", shown(word)),
                        ));
                    }
                    out.push(Token { tok: Tok::Num(v), line });
                } else if first.is_ascii_alphabetic() && word.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_') {
                    out.push(Token { tok: Tok::Word(word.to_string()), line });
                } else {
                    let c = word.chars().find(|c| !(c.is_ascii_alphanumeric() || *c == '_')).unwrap_or('?');
                    let c = if c.is_ascii_graphic() { format!("'{c}'") } else { format!("U+{:04X}", c as u32) };
                    return Err(err(line, format!("unexpected character {c} (not pbrt-v4 text?)")));
                }
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_and_lines() {
        let t = tokenize(Path::new("x.pbrt"), "Shape \"sphere\" # c\n \"float radius\" [ 2 -1e-3 ]\ntrue").unwrap();
        let kinds: Vec<Tok> = t.iter().map(|t| t.tok.clone()).collect();
        assert_eq!(
            kinds,
            vec![
                Tok::Word("Shape".into()),
                Tok::Str("sphere".into()),
                Tok::Str("float radius".into()),
                Tok::Open,
                Tok::Num(2.0),
                Tok::Num(-1e-3),
                Tok::Close,
                Tok::Word("true".into())
            ]
        );
        assert_eq!(t[2].line, 2);
        assert_eq!(t[7].line, 3);
        let e = tokenize(Path::new("x.pbrt"), "\n\"abc").unwrap_err().to_string();
        assert!(e.contains("x.pbrt: line 2: unterminated"), "{e}");
    }
}
