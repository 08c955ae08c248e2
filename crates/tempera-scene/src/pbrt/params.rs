//! Typed parameter lists of pbrt-v4 directives (`"float fov" [30]`, `"rgb L" [1 1 1]`, …):
//! parsing with type and arity checks, typed lookups that record which parameters were used,
//! and the list of unused ones for warnings.

use super::lexer::{Lexer, TokenKind, unescape};
use crate::LoadError;
use crate::diagnostics::Loc;
use std::cell::Cell;

#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    Num(Vec<f64>),
    Str(Vec<String>),
    Bool(Vec<bool>),
}

impl Values {
    fn kind(&self) -> &'static str {
        match self {
            Values::Num(_) => "numbers",
            Values::Str(_) => "strings",
            Values::Bool(_) => "booleans",
        }
    }
}

#[derive(Debug)]
pub struct Param {
    pub ty: String,
    pub name: String,
    pub values: Values,
    pub loc: Loc,
    used: Cell<bool>,
}

impl Param {
    pub fn mark_used(&self) {
        self.used.set(true);
    }
}

const TYPES: &[&str] = &[
    "integer",
    "float",
    "point2",
    "vector2",
    "point3",
    "vector3",
    "point",
    "vector",
    "normal",
    "normal3",
    "color",
    "rgb",
    "spectrum",
    "blackbody",
    "bool",
    "string",
    "texture",
];

#[derive(Debug, Default)]
pub struct ParamSet {
    pub params: Vec<Param>,
}

/// Reads one value group: `[ v v v ]` or a single bare value.
fn read_values(lx: &mut Lexer, loc: &Loc) -> Result<Values, LoadError> {
    let Some(first) = lx.next_token()? else {
        return Err(lx.error(lx.here(), "expected a parameter value, found end of file"));
    };
    let single = |kind: TokenKind| -> Option<Values> {
        match kind {
            TokenKind::Number(v) => Some(Values::Num(vec![v])),
            TokenKind::Str(s) => Some(Values::Str(vec![unescape(s)])),
            TokenKind::Ident("true") => Some(Values::Bool(vec![true])),
            TokenKind::Ident("false") => Some(Values::Bool(vec![false])),
            _ => None,
        }
    };
    if first.kind != TokenKind::Open {
        let at = lx.loc_of(&first);
        return single(first.kind).ok_or_else(|| lx.error(at, "expected a parameter value or '['"));
    }
    let mut values: Option<Values> = None;
    loop {
        let Some(t) = lx.next_token()? else {
            return Err(lx.error(loc.clone(), "unterminated '[' in parameter list"));
        };
        let at = lx.loc_of(&t);
        if t.kind == TokenKind::Close {
            return Ok(values.unwrap_or(Values::Num(Vec::new())));
        }
        let v = single(t.kind).ok_or_else(|| lx.error(at.clone(), "expected a number, string or bool inside '[ ]'"))?;
        match (&mut values, v) {
            (None, v) => values = Some(v),
            (Some(Values::Num(a)), Values::Num(b)) => a.extend(b),
            (Some(Values::Str(a)), Values::Str(b)) => a.extend(b),
            (Some(Values::Bool(a)), Values::Bool(b)) => a.extend(b),
            (Some(existing), v) => {
                return Err(lx.error(at, format!("cannot mix {} and {} in one parameter", existing.kind(), v.kind())));
            }
        }
    }
}

fn check(ty: &str, values: &Values, loc: &Loc, lx: &Lexer) -> Result<(), LoadError> {
    let err = |m: String| Err(lx.error(loc.clone(), m));
    let numeric = matches!(
        ty,
        "integer"
            | "float"
            | "point2"
            | "vector2"
            | "point3"
            | "vector3"
            | "point"
            | "vector"
            | "normal"
            | "normal3"
            | "color"
            | "rgb"
            | "blackbody"
    );
    match values {
        Values::Num(v) if numeric => {
            let arity = match ty {
                "point2" | "vector2" => 2,
                "point3" | "vector3" | "point" | "vector" | "normal" | "normal3" => 3,
                _ => 1,
            };
            if matches!(ty, "rgb" | "color") && v.len() != 3 {
                return err(format!("\"{ty}\" needs exactly 3 values, found {}", v.len()));
            }
            if v.len() % arity != 0 {
                return err(format!("\"{ty}\" needs a multiple of {arity} values, found {}", v.len()));
            }
            if ty == "integer" && v.iter().any(|x| x.fract() != 0.0) {
                return err("\"integer\" values must be whole numbers".into());
            }
            if v.iter().any(|x| !x.is_finite()) {
                return err("parameter values must be finite".into());
            }
            Ok(())
        }
        Values::Num(v) if ty == "spectrum" => {
            if v.len() % 2 != 0 || v.is_empty() {
                return err("\"spectrum\" needs wavelength–value pairs, or a name or file".into());
            }
            Ok(())
        }
        Values::Str(_) if matches!(ty, "string" | "texture" | "spectrum") => Ok(()),
        Values::Bool(_) if ty == "bool" => Ok(()),
        Values::Str(s) if ty == "bool" && s.iter().all(|x| x == "true" || x == "false") => Ok(()),
        Values::Num(v) if v.is_empty() => Ok(()),
        other => err(format!("\"{ty}\" parameter cannot hold {}", other.kind())),
    }
}

impl ParamSet {
    /// Parses `"type name" value` pairs until the next directive.
    pub fn parse(lx: &mut Lexer) -> Result<ParamSet, LoadError> {
        let mut set = ParamSet::default();
        while let Some(t) = lx.peek()? {
            let TokenKind::Str(decl) = t.kind else { break };
            let t = lx.next_token()?.expect("peeked");
            let loc = lx.loc_of(&t);
            let mut words = decl.split_whitespace();
            let (Some(ty), Some(name), None) = (words.next(), words.next(), words.next()) else {
                return Err(lx.error(loc, format!("expected a parameter declaration \"type name\", found \"{decl}\"")));
            };
            if !TYPES.contains(&ty) {
                return Err(lx.error(loc, format!("unknown parameter type '{ty}' (in \"{decl}\")")));
            }
            let mut values = read_values(lx, &loc)?;
            check(ty, &values, &loc, lx)?;
            if ty == "bool"
                && let Values::Str(s) = &values
            {
                values = Values::Bool(s.iter().map(|x| x == "true").collect());
            }
            if set.params.iter().any(|p| p.name == name) {
                return Err(lx.error(loc, format!("parameter \"{name}\" given twice")));
            }
            set.params.push(Param { ty: ty.to_owned(), name: name.to_owned(), values, loc, used: Cell::new(false) });
        }
        Ok(set)
    }

    pub fn find(&self, name: &str) -> Option<&Param> {
        let p = self.params.iter().find(|p| p.name == name)?;
        p.mark_used();
        Some(p)
    }

    fn wrong_type(p: &Param, want: &str) -> LoadError {
        LoadError::Syntax {
            loc: p.loc.clone(),
            message: format!("parameter \"{}\" must be {want}, found \"{}\"", p.name, p.ty),
        }
    }

    pub fn floats(&self, name: &str) -> Result<Option<&[f64]>, LoadError> {
        match self.find(name) {
            None => Ok(None),
            Some(p) => match (&p.values, p.ty.as_str()) {
                (Values::Num(v), "float" | "integer") => Ok(Some(v)),
                _ => Err(Self::wrong_type(p, "\"float\"")),
            },
        }
    }

    pub fn float(&self, name: &str, default: f64) -> Result<f64, LoadError> {
        Ok(self.floats(name)?.and_then(|v| v.first().copied()).unwrap_or(default))
    }

    pub fn ints(&self, name: &str) -> Result<Option<Vec<i64>>, LoadError> {
        match self.find(name) {
            None => Ok(None),
            Some(p) => match (&p.values, p.ty.as_str()) {
                (Values::Num(v), "integer") => Ok(Some(v.iter().map(|&x| x as i64).collect())),
                _ => Err(Self::wrong_type(p, "\"integer\"")),
            },
        }
    }

    pub fn int(&self, name: &str, default: i64) -> Result<i64, LoadError> {
        Ok(self.ints(name)?.and_then(|v| v.first().copied()).unwrap_or(default))
    }

    pub fn bool(&self, name: &str, default: bool) -> Result<bool, LoadError> {
        match self.find(name) {
            None => Ok(default),
            Some(p) => match &p.values {
                Values::Bool(v) if !v.is_empty() => Ok(v[0]),
                _ => Err(Self::wrong_type(p, "\"bool\"")),
            },
        }
    }

    pub fn string(&self, name: &str) -> Result<Option<&str>, LoadError> {
        match self.find(name) {
            None => Ok(None),
            Some(p) => match (&p.values, p.ty.as_str()) {
                (Values::Str(v), "string" | "texture") if !v.is_empty() => Ok(Some(&v[0])),
                _ => Err(Self::wrong_type(p, "\"string\"")),
            },
        }
    }

    /// Values of a `point3`/`vector3`/`normal` (or 2D) parameter, in groups of `n`.
    pub fn points(&self, name: &str, n: usize) -> Result<Option<Vec<Vec<f64>>>, LoadError> {
        let allowed: &[&str] = if n == 2 {
            &["point2", "vector2"]
        } else {
            &["point3", "vector3", "point", "vector", "normal", "normal3"]
        };
        match self.find(name) {
            None => Ok(None),
            Some(p) => match &p.values {
                Values::Num(v) if allowed.contains(&p.ty.as_str()) => {
                    Ok(Some(v.chunks(n).map(<[f64]>::to_vec).collect()))
                }
                _ => Err(Self::wrong_type(p, &format!("one of {allowed:?}"))),
            },
        }
    }

    pub fn unused(&self) -> impl Iterator<Item = &Param> {
        self.params.iter().filter(|p| !p.used.get())
    }
}
