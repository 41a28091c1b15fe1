//! The tokenizer and token cursor shared by the `.frep` and HyperFun readers.
//!
//! The two languages differ only in their comment marker, their symbol set and whether
//! names are case-sensitive; everything else (numbers, names, positions, the wording of
//! "expected …, found …" errors) is common.

use super::{ReadError, MAX_DEPTH};
use std::fmt;

/// One lexical element.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Tok {
    /// A name (lower-cased when the language is case-insensitive).
    Ident(String),
    /// A number literal.
    Num(f64),
    /// A double-quoted string.
    Str(String),
    /// An operator or punctuation mark.
    Sym(&'static str),
    /// The end of the input.
    Eof,
}

impl fmt::Display for Tok {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Tok::Ident(s) => write!(f, "'{s}'"),
            Tok::Num(v) => write!(f, "the number {v}"),
            Tok::Str(s) => write!(f, "the string \"{s}\""),
            Tok::Sym(s) => write!(f, "'{s}'"),
            Tok::Eof => write!(f, "the end of the file"),
        }
    }
}

/// A token and where it starts (1-based line and character column).
#[derive(Clone, Debug)]
pub(crate) struct Token {
    pub tok: Tok,
    pub line: usize,
    pub col: usize,
}

/// What distinguishes one language's tokens.
pub(crate) struct Lexicon {
    /// The marker that starts a comment running to the end of the line.
    pub comment: &'static str,
    /// Symbols, longest first where one is a prefix of another.
    pub symbols: &'static [&'static str],
    /// Whether names are case-insensitive (then they are lower-cased).
    pub fold_case: bool,
}

/// Splits `text` into tokens (the last is `Eof`).
pub(crate) fn tokenize(text: &str, lex: &Lexicon, file: &str) -> Result<Vec<Token>, ReadError> {
    let chars: Vec<char> = text.chars().collect();
    let comment: Vec<char> = lex.comment.chars().collect();
    let mut out = Vec::new();
    let (mut i, mut line, mut col) = (0usize, 1usize, 1usize);
    while i < chars.len() {
        let c = chars[i];
        if c == '\n' {
            i += 1;
            line += 1;
            col = 1;
            continue;
        }
        if c.is_whitespace() {
            i += 1;
            col += 1;
            continue;
        }
        if chars[i..].starts_with(&comment) {
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
            }
            continue;
        }
        let (start_line, start_col) = (line, col);
        let push = |out: &mut Vec<Token>, tok| {
            out.push(Token {
                tok,
                line: start_line,
                col: start_col,
            })
        };
        if c.is_ascii_digit() || (c == '.' && chars.get(i + 1).is_some_and(|d| d.is_ascii_digit()))
        {
            let s = i;
            while i < chars.len() && chars[i].is_ascii_digit() {
                i += 1;
            }
            if i < chars.len() && chars[i] == '.' {
                i += 1;
                while i < chars.len() && chars[i].is_ascii_digit() {
                    i += 1;
                }
            }
            if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
                let mut j = i + 1;
                if j < chars.len() && (chars[j] == '+' || chars[j] == '-') {
                    j += 1;
                }
                if j < chars.len() && chars[j].is_ascii_digit() {
                    i = j;
                    while i < chars.len() && chars[i].is_ascii_digit() {
                        i += 1;
                    }
                }
            }
            // A number running into letters, digits or another point is malformed.
            let mut e = i;
            while e < chars.len()
                && (chars[e].is_alphanumeric() || chars[e] == '_' || chars[e] == '.')
            {
                e += 1;
            }
            let word: String = chars[s..e].iter().collect();
            if e > i {
                return Err(ReadError::at(
                    file,
                    start_line,
                    start_col,
                    format!("expected a number, found the malformed number '{word}'"),
                ));
            }
            let v: f64 = word.parse().map_err(|_| {
                ReadError::at(
                    file,
                    start_line,
                    start_col,
                    format!("expected a number, found '{word}'"),
                )
            })?;
            col += e - s;
            push(&mut out, Tok::Num(v));
            continue;
        }
        if c.is_alphabetic() || c == '_' {
            let s = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            let mut word: String = chars[s..i].iter().collect();
            if lex.fold_case {
                word = word.to_lowercase();
            }
            col += i - s;
            push(&mut out, Tok::Ident(word));
            continue;
        }
        if c == '"' {
            let s = i + 1;
            i += 1;
            while i < chars.len() && chars[i] != '"' && chars[i] != '\n' {
                i += 1;
            }
            if i >= chars.len() || chars[i] != '"' {
                return Err(ReadError::at(
                    file,
                    start_line,
                    start_col,
                    "expected a closing '\"' on the same line, found none",
                ));
            }
            let s_val: String = chars[s..i].iter().collect();
            i += 1;
            col += i - s + 1;
            push(&mut out, Tok::Str(s_val));
            continue;
        }
        let sym = lex
            .symbols
            .iter()
            .find(|s| chars[i..].starts_with(&s.chars().collect::<Vec<_>>()));
        match sym {
            Some(s) => {
                let n = s.chars().count();
                i += n;
                col += n;
                push(&mut out, Tok::Sym(s));
            }
            None => {
                return Err(ReadError::at(
                    file,
                    start_line,
                    start_col,
                    format!("expected a name, number or operator, found the character '{c}'"),
                ))
            }
        }
    }
    out.push(Token {
        tok: Tok::Eof,
        line,
        col,
    });
    Ok(out)
}

/// A position in a token list, with the helpers every recursive-descent parser needs.
pub(crate) struct Cursor<'a> {
    toks: Vec<Token>,
    pos: usize,
    /// The file name for errors.
    pub file: &'a str,
    depth: usize,
}

impl<'a> Cursor<'a> {
    /// A cursor at the first token.
    pub fn new(toks: Vec<Token>, file: &'a str) -> Self {
        Self {
            toks,
            pos: 0,
            file,
            depth: 0,
        }
    }
    /// The current token.
    pub fn peek(&self) -> &Token {
        &self.toks[self.pos.min(self.toks.len() - 1)]
    }
    /// The token after the current one.
    pub fn peek2(&self) -> &Token {
        &self.toks[(self.pos + 1).min(self.toks.len() - 1)]
    }
    /// Moves on, returning the token passed.
    pub fn next(&mut self) -> Token {
        let t = self.peek().clone();
        if self.pos < self.toks.len() - 1 {
            self.pos += 1;
        }
        t
    }
    /// Whether the current token is the symbol `s`.
    pub fn is(&self, s: &str) -> bool {
        matches!(&self.peek().tok, Tok::Sym(x) if *x == s)
    }
    /// Whether the current token is the name `s`.
    pub fn is_word(&self, s: &str) -> bool {
        matches!(&self.peek().tok, Tok::Ident(x) if x == s)
    }
    /// Consumes the symbol `s` if it is next.
    pub fn eat(&mut self, s: &str) -> bool {
        if self.is(s) {
            self.next();
            true
        } else {
            false
        }
    }
    /// An error at the current token: "expected WHAT, found …".
    pub fn expected(&self, what: &str) -> ReadError {
        let t = self.peek();
        ReadError::at(
            self.file,
            t.line,
            t.col,
            format!("expected {what}, found {}", t.tok),
        )
    }
    /// An error at a given token.
    pub fn error_at(&self, t: &Token, message: impl Into<String>) -> ReadError {
        ReadError::at(self.file, t.line, t.col, message)
    }
    /// Consumes the symbol `s` or fails naming it.
    pub fn expect(&mut self, s: &str) -> Result<Token, ReadError> {
        if self.is(s) {
            Ok(self.next())
        } else {
            Err(self.expected(&format!("'{s}'")))
        }
    }
    /// Consumes the keyword `w` or fails naming it.
    pub fn expect_word(&mut self, w: &str) -> Result<Token, ReadError> {
        if self.is_word(w) {
            Ok(self.next())
        } else {
            Err(self.expected(&format!("'{w}'")))
        }
    }
    /// Consumes a name.
    pub fn ident(&mut self, what: &str) -> Result<(String, Token), ReadError> {
        match &self.peek().tok {
            Tok::Ident(s) => {
                let s = s.clone();
                Ok((s, self.next()))
            }
            _ => Err(self.expected(what)),
        }
    }
    /// Enters one nesting level, failing past [`MAX_DEPTH`].
    pub fn enter(&mut self) -> Result<(), ReadError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            let t = self.peek();
            return Err(ReadError::at(
                self.file,
                t.line,
                t.col,
                format!("expected at most {MAX_DEPTH} levels of nesting, found more"),
            ));
        }
        Ok(())
    }
    /// Leaves a nesting level.
    pub fn leave(&mut self) {
        self.depth -= 1;
    }
}
