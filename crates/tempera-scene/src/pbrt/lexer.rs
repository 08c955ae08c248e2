//! Tokeniser for the pbrt-v4 scene format (pbrt-v4 file format reference, "Scene Description
//! Files"): `#` comments, quoted strings with escapes, numbers, brackets and bare identifiers.
//! Tokens borrow from the source text; positions are tracked for error messages.

use crate::LoadError;
use crate::diagnostics::Loc;
use std::path::PathBuf;
use std::sync::Arc;

#[derive(Clone, Debug, PartialEq)]
pub enum TokenKind<'a> {
    /// A directive or bare word such as `Shape`, `true`.
    Ident(&'a str),
    /// A quoted string, with the raw (unescaped) contents.
    Str(&'a str),
    Number(f64),
    Open,
    Close,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Token<'a> {
    pub kind: TokenKind<'a>,
    pub line: u32,
    pub col: u32,
}

pub struct Lexer<'a> {
    src: &'a [u8],
    text: &'a str,
    pos: usize,
    line: u32,
    line_start: usize,
    pub file: Arc<PathBuf>,
    peeked: Option<Token<'a>>,
}

impl<'a> Lexer<'a> {
    pub fn new(text: &'a str, file: Arc<PathBuf>) -> Self {
        Self { src: text.as_bytes(), text, pos: 0, line: 1, line_start: 0, file, peeked: None }
    }

    pub fn loc_of(&self, t: &Token) -> Loc {
        Loc::new(&self.file, t.line, t.col)
    }

    /// Location of the next unread character (for "unexpected end of file").
    pub fn here(&self) -> Loc {
        Loc::new(&self.file, self.line, (self.pos - self.line_start) as u32 + 1)
    }

    pub fn error(&self, loc: Loc, message: impl Into<String>) -> LoadError {
        LoadError::Syntax { loc, message: message.into() }
    }

    fn skip_space_and_comments(&mut self) {
        while let Some(&c) = self.src.get(self.pos) {
            match c {
                b'\n' => {
                    self.pos += 1;
                    self.line += 1;
                    self.line_start = self.pos;
                }
                b' ' | b'\t' | b'\r' | 0x0c => self.pos += 1,
                b'#' => {
                    while self.src.get(self.pos).is_some_and(|&c| c != b'\n') {
                        self.pos += 1;
                    }
                }
                _ => break,
            }
        }
    }

    pub fn peek(&mut self) -> Result<Option<&Token<'a>>, LoadError> {
        if self.peeked.is_none() {
            self.peeked = self.scan()?;
        }
        Ok(self.peeked.as_ref())
    }

    pub fn next_token(&mut self) -> Result<Option<Token<'a>>, LoadError> {
        match self.peeked.take() {
            Some(t) => Ok(Some(t)),
            None => self.scan(),
        }
    }

    fn scan(&mut self) -> Result<Option<Token<'a>>, LoadError> {
        self.skip_space_and_comments();
        let Some(&c) = self.src.get(self.pos) else { return Ok(None) };
        let (line, col) = (self.line, (self.pos - self.line_start) as u32 + 1);
        let start = self.pos;
        let kind = match c {
            b'[' => {
                self.pos += 1;
                TokenKind::Open
            }
            b']' => {
                self.pos += 1;
                TokenKind::Close
            }
            b'"' => {
                self.pos += 1;
                loop {
                    match self.src.get(self.pos) {
                        None | Some(b'\n') => {
                            return Err(self.error(Loc::new(&self.file, line, col), "unterminated string"));
                        }
                        Some(b'\\') => self.pos += 2,
                        Some(b'"') => break,
                        Some(_) => self.pos += 1,
                    }
                }
                let s = self.text.get(start + 1..self.pos).unwrap_or("");
                self.pos += 1;
                TokenKind::Str(s)
            }
            _ => {
                while self
                    .src
                    .get(self.pos)
                    .is_some_and(|&c| !c.is_ascii_whitespace() && !matches!(c, b'"' | b'[' | b']' | b'#'))
                {
                    self.pos += 1;
                }
                let word = self.text.get(start..self.pos).unwrap_or("");
                if c.is_ascii_digit() || matches!(c, b'-' | b'+' | b'.') {
                    let v = word.parse::<f64>().map_err(|_| {
                        self.error(Loc::new(&self.file, line, col), format!("expected a number, found '{word}'"))
                    })?;
                    TokenKind::Number(v)
                } else if c.is_ascii_alphabetic() || c == b'_' {
                    TokenKind::Ident(word)
                } else {
                    let shown: String = word.chars().take(20).collect();
                    return Err(
                        self.error(Loc::new(&self.file, line, col), format!("unexpected character sequence '{shown}'"))
                    );
                }
            }
        };
        Ok(Some(Token { kind, line, col }))
    }
}

/// Resolves the escapes pbrt allows inside quoted strings.
pub fn unescape(raw: &str) -> String {
    if !raw.contains('\\') {
        return raw.to_owned();
    }
    let mut out = String::with_capacity(raw.len());
    let mut chars = raw.chars();
    while let Some(c) = chars.next() {
        if c != '\\' {
            out.push(c);
            continue;
        }
        match chars.next() {
            Some('n') => out.push('\n'),
            Some('t') => out.push('\t'),
            Some('b') => out.push('\u{8}'),
            Some('f') => out.push('\u{c}'),
            Some('r') => out.push('\r'),
            Some(other) => out.push(other),
            None => {}
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinds(src: &str) -> Vec<TokenKind<'_>> {
        let mut lx = Lexer::new(src, Arc::new(PathBuf::from("t.pbrt")));
        let mut out = Vec::new();
        while let Some(t) = lx.next_token().unwrap() {
            out.push(t.kind);
        }
        out
    }

    #[test]
    fn tokens_comments_and_positions() {
        let src = "Shape \"sphere\" # a comment\n  \"float radius\" [ 2.5e0 -1 .5 ]";
        assert_eq!(
            kinds(src),
            vec![
                TokenKind::Ident("Shape"),
                TokenKind::Str("sphere"),
                TokenKind::Str("float radius"),
                TokenKind::Open,
                TokenKind::Number(2.5),
                TokenKind::Number(-1.0),
                TokenKind::Number(0.5),
                TokenKind::Close
            ]
        );
        let mut lx = Lexer::new(src, Arc::new(PathBuf::from("t.pbrt")));
        let toks: Vec<_> = std::iter::from_fn(|| lx.next_token().unwrap()).collect();
        assert_eq!((toks[2].line, toks[2].col), (2, 3));
    }

    #[test]
    fn errors_carry_file_line_and_column() {
        let mut lx = Lexer::new("Shape\n \"abc", Arc::new(PathBuf::from("x.pbrt")));
        lx.next_token().unwrap();
        let err = lx.next_token().unwrap_err().to_string();
        assert!(err.starts_with("x.pbrt:2:2: unterminated string"), "{err}");
        let mut lx = Lexer::new("Translate 1 2x 3", Arc::new(PathBuf::from("x.pbrt")));
        lx.next_token().unwrap();
        lx.next_token().unwrap();
        let err = lx.next_token().unwrap_err().to_string();
        assert!(err.starts_with("x.pbrt:1:13: expected a number, found '2x'"), "{err}");
    }

    #[test]
    fn escapes() {
        assert_eq!(unescape(r#"a\"b\\c\n"#), "a\"b\\c\n");
    }
}
