//! pbrt-v4 parameter lists (`"float radius" [ 2 ]`): parsed once with their declared type and line, then read
//! through typed accessors that check the type and the value count, and remember which were used so that the
//! unused ones can be reported as ignored.

use super::tokenizer::{Tok, Token};
use crate::scene::SceneError;
use glam::Vec3;
use std::cell::Cell;
use std::path::{Path, PathBuf};

/// A parameter's values.
#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    /// Numbers (float, integer, point*, normal, rgb, ...).
    Nums(Vec<f64>),
    /// Strings (string, texture, spectrum names).
    Strs(Vec<String>),
    /// Booleans.
    Bools(Vec<bool>),
}

/// One declared parameter.
#[derive(Clone, Debug)]
pub struct Param {
    /// Declared type (`float`, `rgb`, `texture`, ...).
    pub ty: String,
    /// Name.
    pub name: String,
    /// Values.
    pub values: Values,
    /// Line of the declaration.
    pub line: usize,
    used: Cell<bool>,
}

/// A directive's parameters, with the file and line they came from.
#[derive(Clone, Debug)]
pub struct Params {
    /// The file.
    pub file: PathBuf,
    /// The directive's line.
    pub line: usize,
    /// In declaration order.
    pub list: Vec<Param>,
}

const TYPES: &[&str] = &[
    "integer",
    "float",
    "point2",
    "vector2",
    "point3",
    "vector3",
    "normal",
    "normal3",
    "point",
    "vector",
    "rgb",
    "color",
    "blackbody",
    "spectrum",
    "string",
    "texture",
    "bool",
];

/// Reads parameters starting at `tokens[*i]` until the next directive (a bare word that is not a value).
pub fn parse(file: &Path, line: usize, tokens: &[Token], i: &mut usize) -> Result<Params, SceneError> {
    let err = |line: usize, m: String| SceneError::new(file, format!("line {line}: {m}"));
    let mut list = Vec::new();
    while let Some(t) = tokens.get(*i) {
        let Tok::Str(decl) = &t.tok else { break };
        let pline = t.line;
        let mut parts = decl.split_whitespace();
        let (Some(ty), Some(name), None) = (parts.next(), parts.next(), parts.next()) else {
            let decl = crate::io::input_file::clip(decl, 60);
            return Err(err(pline, format!("expected a parameter declaration \"type name\", found \"{decl}\"")));
        };
        if !TYPES.contains(&ty) {
            let decl = crate::io::input_file::clip(decl, 60);
            return Err(err(
                pline,
                format!("unknown parameter type '{}' in \"{decl}\"", crate::io::input_file::clip(ty, 30)),
            ));
        }
        *i += 1;
        let mut raw = Vec::new();
        match tokens.get(*i).map(|t| &t.tok) {
            Some(Tok::Open) => {
                *i += 1;
                loop {
                    match tokens.get(*i).map(|t| &t.tok) {
                        Some(Tok::Close) => {
                            *i += 1;
                            break;
                        }
                        Some(Tok::Open) => return Err(err(tokens[*i].line, "nested '[' in a parameter value".into())),
                        Some(tok) => {
                            raw.push(tok.clone());
                            *i += 1;
                        }
                        None => return Err(err(pline, format!("parameter \"{decl}\": the file ends before ']'"))),
                    }
                }
            }
            Some(Tok::Num(_)) | Some(Tok::Str(_)) => {
                raw.push(tokens[*i].tok.clone());
                *i += 1;
            }
            Some(Tok::Word(w)) if w == "true" || w == "false" => {
                raw.push(tokens[*i].tok.clone());
                *i += 1;
            }
            _ => return Err(err(pline, format!("parameter \"{decl}\" has no value"))),
        }
        let values = convert(ty, &raw).map_err(|m| err(pline, format!("parameter \"{decl}\": {m}")))?;
        if let (Values::Nums(v), "rgb" | "color") = (&values, ty) {
            // pbrt-v4 refuses every negative RGB value (paramdict.cpp): no spectrum, reflectance or light is negative.
            if let Some(x) = v.iter().find(|x| **x < 0.0) {
                return Err(err(
                    pline,
                    format!("parameter \"{decl}\": negative RGB component {x} (pbrt-v4 refuses it)"),
                ));
            }
        }
        list.push(Param { ty: ty.into(), name: name.into(), values, line: pline, used: Cell::new(false) });
    }
    Ok(Params { file: file.to_path_buf(), line, list })
}

fn convert(ty: &str, raw: &[Tok]) -> Result<Values, String> {
    match ty {
        "string" | "texture" => raw
            .iter()
            .map(|t| match t {
                Tok::Str(s) => Ok(s.clone()),
                other => Err(format!("expected a quoted string, found {}", show(other))),
            })
            .collect::<Result<_, _>>()
            .map(Values::Strs),
        "bool" => raw
            .iter()
            .map(|t| match t {
                Tok::Word(w) | Tok::Str(w) if w == "true" => Ok(true),
                Tok::Word(w) | Tok::Str(w) if w == "false" => Ok(false),
                other => Err(format!("expected true or false, found {}", show(other))),
            })
            .collect::<Result<_, _>>()
            .map(Values::Bools),
        "spectrum" if raw.iter().all(|t| matches!(t, Tok::Str(_))) => convert("string", raw),
        _ => raw
            .iter()
            .map(|t| match t {
                Tok::Num(v) => Ok(*v),
                other => Err(format!("expected a number, found {}", show(other))),
            })
            .collect::<Result<_, _>>()
            .map(Values::Nums),
    }
}

fn show(t: &Tok) -> String {
    match t {
        Tok::Word(w) => format!("'{w}'"),
        Tok::Str(s) => format!("\"{s}\""),
        Tok::Num(v) => format!("{v}"),
        Tok::Open => "'['".into(),
        Tok::Close => "']'".into(),
    }
}

impl Params {
    /// An error about parameter `p` (its own line).
    pub fn error_at(&self, p: &Param, m: impl std::fmt::Display) -> SceneError {
        SceneError::new(&self.file, format!("line {}: parameter \"{} {}\": {m}", p.line, p.ty, p.name))
    }
    /// An error about the directive.
    pub fn error(&self, m: impl std::fmt::Display) -> SceneError {
        SceneError::new(&self.file, format!("line {}: {m}", self.line))
    }
    fn find(&self, name: &str) -> Option<&Param> {
        let p = self.list.iter().rev().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p)
    }
    /// Whether a parameter of this name is present (marks it used).
    pub fn has(&self, name: &str) -> bool {
        self.find(name).is_some()
    }
    /// The declared type of `name`, if present (does not mark it used).
    pub fn type_of(&self, name: &str) -> Option<&str> {
        self.list.iter().rev().find(|p| p.name == name).map(|p| p.ty.as_str())
    }
    /// All numbers of a numeric parameter, checking its type is one of `types` and the count is a multiple of `k`.
    pub fn nums(&self, name: &str, types: &[&str], k: usize) -> Result<Option<Vec<f64>>, SceneError> {
        let Some(p) = self.find(name) else { return Ok(None) };
        if !types.contains(&p.ty.as_str()) {
            return Err(self.error_at(p, format!("wrong type (expected {})", types.join(" or "))));
        }
        let Values::Nums(v) = &p.values else { return Err(self.error_at(p, "expected numbers")) };
        if v.is_empty() || v.len() % k != 0 {
            return Err(self.error_at(p, format!("has {} values; expected a non-empty multiple of {k}", v.len())));
        }
        Ok(Some(v.clone()))
    }
    /// One float (`float` or `integer`).
    pub fn float(&self, name: &str, default: f32) -> Result<f32, SceneError> {
        self.single(name, &["float", "integer"]).map(|v| v.map_or(default, |v| v as f32))
    }
    /// One integer.
    pub fn int(&self, name: &str, default: i64) -> Result<i64, SceneError> {
        match self.single(name, &["integer"])? {
            Some(v) if v.fract() == 0.0 => Ok(v as i64),
            Some(v) => Err(self.error(format!("parameter \"{name}\": {v} is not an integer"))),
            None => Ok(default),
        }
    }
    fn single(&self, name: &str, types: &[&str]) -> Result<Option<f64>, SceneError> {
        let Some(v) = self.nums(name, types, 1)? else { return Ok(None) };
        if v.len() != 1 {
            let p = self.find(name).expect("found above");
            return Err(self.error_at(p, format!("has {} values; expected 1", v.len())));
        }
        Ok(Some(v[0]))
    }
    /// A 3-vector (`point3`, `vector3`, `normal`, `rgb`...).
    pub fn vec3(&self, name: &str, types: &[&str]) -> Result<Option<Vec3>, SceneError> {
        let Some(v) = self.nums(name, types, 3)? else { return Ok(None) };
        if v.len() != 3 {
            let p = self.find(name).expect("found above");
            return Err(self.error_at(p, format!("has {} values; expected 3", v.len())));
        }
        Ok(Some(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)))
    }
    /// One string (`string`, or `texture` / `spectrum` when listed in `types`).
    pub fn string_of(&self, name: &str, types: &[&str]) -> Result<Option<String>, SceneError> {
        let Some(p) = self.find(name) else { return Ok(None) };
        if !types.contains(&p.ty.as_str()) {
            return Err(self.error_at(p, format!("wrong type (expected {})", types.join(" or "))));
        }
        match &p.values {
            Values::Strs(s) if s.len() == 1 => Ok(Some(s[0].clone())),
            Values::Strs(s) => Err(self.error_at(p, format!("has {} values; expected 1", s.len()))),
            _ => Err(self.error_at(p, "expected a string")),
        }
    }
    /// One `string`.
    pub fn string(&self, name: &str) -> Result<Option<String>, SceneError> {
        self.string_of(name, &["string"])
    }
    /// One `bool`.
    pub fn bool(&self, name: &str, default: bool) -> Result<bool, SceneError> {
        let Some(p) = self.find(name) else { return Ok(default) };
        match &p.values {
            Values::Bools(b) if b.len() == 1 && p.ty == "bool" => Ok(b[0]),
            _ => Err(self.error_at(p, "expected one bool (true or false)")),
        }
    }
    /// Parameters never read, as `"type name"` strings.
    pub fn unused(&self) -> Vec<String> {
        self.list.iter().filter(|p| !p.used.get()).map(|p| format!("\"{} {}\"", p.ty, p.name)).collect()
    }
}
