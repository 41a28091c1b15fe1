//! `.frep` syntax (docs/frep-syntax.md): statements and expressions, parsed into an AST.
//!
//! ```text
//! program   := statement*
//! statement := 'let' NAME ['(' NAME, … ')'] '=' expr | 'bounds' '(' expr ',' expr ')'
//!            | 'output' expr                              (';' between statements optional)
//! expr      := product (('+' | '-') product)*
//! product   := unary (('*' | '/') unary)*
//! unary     := '-' unary | power
//! power     := primary ['^' unary]                        (right-associative)
//! primary   := NUMBER | NAME | NAME '(' [arg, …] ')' | '(' expr ')' | '[' [expr, …] ']'
//! arg       := [NAME '='] expr
//! ```

use crate::read::lex::{tokenize, Cursor, Lexicon, Tok, Token};
use crate::read::ReadError;

/// A source position.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Pos {
    pub line: usize,
    pub col: usize,
}

impl From<&Token> for Pos {
    fn from(t: &Token) -> Self {
        Pos {
            line: t.line,
            col: t.col,
        }
    }
}

/// An expression.
#[derive(Clone, Debug)]
pub(crate) enum Ast {
    Num(f64, Pos),
    Name(String, Pos),
    /// A call with positional (`None`) and named arguments.
    Call(String, Vec<(Option<String>, Ast)>, Pos),
    List(Vec<Ast>, Pos),
    Neg(Box<Ast>, Pos),
    /// A left-to-right chain of `+ -` or `* /`.
    Chain(Box<Ast>, Vec<(char, Pos, Ast)>),
    Pow(Box<Ast>, Box<Ast>, Pos),
}

impl Ast {
    /// Where the expression starts.
    pub fn pos(&self) -> Pos {
        match self {
            Ast::Num(_, p)
            | Ast::Name(_, p)
            | Ast::Call(_, _, p)
            | Ast::List(_, p)
            | Ast::Neg(_, p) => *p,
            Ast::Chain(a, _) | Ast::Pow(a, _, _) => a.pos(),
        }
    }
}

/// A statement.
#[derive(Clone, Debug)]
pub(crate) enum Stmt {
    /// `let name = expr` (params empty) or `let name(params) = expr`.
    Let(String, Vec<String>, Ast, Pos, bool),
    /// `bounds(lo, hi)`.
    Bounds(Ast, Ast, Pos),
    /// `output expr`.
    Output(Ast, Pos),
}

const LEXICON: Lexicon = Lexicon {
    comment: "#",
    symbols: &["+", "-", "*", "/", "^", "(", ")", "[", "]", ",", "=", ";"],
    fold_case: false,
};

/// Words that cannot name a value.
pub(crate) const KEYWORDS: &[&str] = &["let", "bounds", "output"];

/// Parses a program.
pub(crate) fn parse(text: &str, file: &str) -> Result<Vec<Stmt>, ReadError> {
    let mut c = Cursor::new(tokenize(text, &LEXICON, file)?, file);
    let mut out = Vec::new();
    loop {
        while c.eat(";") {}
        let t = c.peek().clone();
        let p = Pos::from(&t);
        match &t.tok {
            Tok::Eof => break,
            Tok::Ident(w) if w == "let" => {
                c.next();
                let (name, nt) = c.ident("a name after 'let'")?;
                if KEYWORDS.contains(&name.as_str()) {
                    return Err(c.error_at(
                        &nt,
                        format!("expected a name after 'let', found the keyword '{name}'"),
                    ));
                }
                let mut params = Vec::new();
                let is_fn = c.eat("(");
                if is_fn {
                    if !c.is(")") {
                        loop {
                            let (pn, _) = c.ident("a parameter name")?;
                            params.push(pn);
                            if !c.eat(",") {
                                break;
                            }
                        }
                    }
                    c.expect(")")?;
                }
                c.expect("=")?;
                let body = expr(&mut c)?;
                out.push(Stmt::Let(name, params, body, Pos::from(&nt), is_fn));
            }
            Tok::Ident(w) if w == "bounds" => {
                c.next();
                c.expect("(")?;
                let lo = expr(&mut c)?;
                c.expect(",")?;
                let hi = expr(&mut c)?;
                c.expect(")")?;
                out.push(Stmt::Bounds(lo, hi, p));
            }
            Tok::Ident(w) if w == "output" => {
                c.next();
                out.push(Stmt::Output(expr(&mut c)?, p));
            }
            _ => return Err(c.expected("'let', 'bounds' or 'output'")),
        }
    }
    Ok(out)
}

fn expr(c: &mut Cursor) -> Result<Ast, ReadError> {
    c.enter()?;
    let r = chain(c, &["+", "-"], product);
    c.leave();
    r
}

fn product(c: &mut Cursor) -> Result<Ast, ReadError> {
    chain(c, &["*", "/"], unary)
}

fn chain(
    c: &mut Cursor,
    ops: &[&str],
    next: fn(&mut Cursor) -> Result<Ast, ReadError>,
) -> Result<Ast, ReadError> {
    let first = next(c)?;
    let mut rest = Vec::new();
    while let Some(op) = ops.iter().find(|o| c.is(o)) {
        let t = c.next();
        let ch = op.chars().next().unwrap_or('+');
        rest.push((ch, Pos::from(&t), next(c)?));
    }
    Ok(if rest.is_empty() {
        first
    } else {
        Ast::Chain(Box::new(first), rest)
    })
}

fn unary(c: &mut Cursor) -> Result<Ast, ReadError> {
    if c.is("-") {
        let p = Pos::from(&c.next());
        c.enter()?;
        let e = unary(c)?;
        c.leave();
        return Ok(Ast::Neg(Box::new(e), p));
    }
    let base = primary(c)?;
    if c.is("^") {
        let p = Pos::from(&c.next());
        c.enter()?;
        let e = unary(c)?;
        c.leave();
        return Ok(Ast::Pow(Box::new(base), Box::new(e), p));
    }
    Ok(base)
}

fn primary(c: &mut Cursor) -> Result<Ast, ReadError> {
    let t = c.peek().clone();
    let p = Pos::from(&t);
    match &t.tok {
        Tok::Num(v) => {
            c.next();
            Ok(Ast::Num(*v, p))
        }
        Tok::Sym("(") => {
            c.next();
            let e = expr(c)?;
            c.expect(")")?;
            Ok(e)
        }
        Tok::Sym("[") => {
            c.next();
            let mut items = Vec::new();
            if !c.is("]") {
                loop {
                    items.push(expr(c)?);
                    if !c.eat(",") {
                        break;
                    }
                }
            }
            c.expect("]")?;
            Ok(Ast::List(items, p))
        }
        Tok::Ident(name) if !KEYWORDS.contains(&name.as_str()) => {
            let name = name.clone();
            c.next();
            if !c.eat("(") {
                return Ok(Ast::Name(name, p));
            }
            let mut args = Vec::new();
            if !c.is(")") {
                loop {
                    let named = match (&c.peek().tok, &c.peek2().tok) {
                        (Tok::Ident(n), Tok::Sym("=")) => Some(n.clone()),
                        _ => None,
                    };
                    if named.is_some() {
                        c.next();
                        c.next();
                    }
                    args.push((named, expr(c)?));
                    if !c.eat(",") {
                        break;
                    }
                }
            }
            c.expect(")")?;
            Ok(Ast::Call(name, args, p))
        }
        _ => Err(c.expected("an expression")),
    }
}
