//! HyperFun syntax: models, statements and expressions, parsed into a small AST.
//!
//! Precedence follows HyperFun's interpreter (lowest first): `and`/`or` (one level,
//! left to right); comparisons `< > <= >= = /=` (a chain `a < b < c` means both); `not`;
//! `+ - | & \ @` (one level, left to right: the set operators bind like `+`); `* /`;
//! `^` (left to right); unary `- + ~`. Names are case-insensitive; `--` starts a comment.

use crate::read::lex::{tokenize, Cursor, Lexicon, Tok, Token};
use crate::read::sym::Cmp;
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

/// A binary operator at the additive or multiplicative level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
    /// `|`: R-union.
    Union,
    /// `&` and `@`: R-intersection.
    Inter,
    /// `\`: R-subtraction.
    Diff,
    And,
    Or,
}

/// A unary operator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum UnOp {
    Neg,
    Plus,
    /// `~`: complement (negation).
    Tilde,
    Not,
}

/// An expression.
#[derive(Clone, Debug)]
pub(crate) enum Expr {
    Num(f64, Pos),
    /// A scalar variable, or an array passed whole to a function.
    Name(String, Pos),
    /// An array element `name[index]` (1-based).
    Index(String, Box<Expr>, Pos),
    /// A call of a built-in, a library function or another model.
    Call(String, Vec<Expr>, Pos),
    Unary(UnOp, Box<Expr>, Pos),
    /// A left-to-right chain of operators of one precedence level.
    Chain(Box<Expr>, Vec<(BinOp, Pos, Expr)>),
    /// A chain of comparisons, true when every link holds.
    Compare(Box<Expr>, Vec<(Cmp, Pos, Expr)>),
}

impl Expr {
    /// Where the expression starts.
    pub(crate) fn pos(&self) -> Pos {
        match self {
            Expr::Num(_, p)
            | Expr::Name(_, p)
            | Expr::Index(_, _, p)
            | Expr::Call(_, _, p)
            | Expr::Unary(_, _, p) => *p,
            Expr::Chain(a, _) | Expr::Compare(a, _) => a.pos(),
        }
    }
}

/// A statement.
#[derive(Clone, Debug)]
pub(crate) enum Stmt {
    /// `array b[5], c[2];`
    Array(Vec<(String, usize, Pos)>),
    /// `v = expr;`
    Assign(String, Pos, Expr),
    /// `b[i] = expr;`
    AssignIndex(String, Pos, Expr, Expr),
    /// `b = [1, 2, 3];`
    AssignList(String, Pos, Vec<f64>),
    /// `if c then … else … endif;`
    If(Expr, Vec<Stmt>, Vec<Stmt>),
    /// `while c loop … endloop;`
    While(Expr, Vec<Stmt>, Pos),
}

/// One model: `name(x[n], a[m]) { … }`.
#[derive(Clone, Debug)]
pub(crate) struct ModelDef {
    pub name: String,
    pub pos: Pos,
    pub x_dim: usize,
    pub a_dim: usize,
    /// The optional third header array `s[k]`: absent, `s` is an ordinary name.
    pub s_dim: Option<usize>,
    pub body: Vec<Stmt>,
    /// The closing brace (where a missing result is reported).
    pub end: Pos,
}

const LEXICON: Lexicon = Lexicon {
    comment: "--",
    symbols: &[
        "<=", ">=", "/=", "^", "+", "-", "~", "/", "*", "&", "|", "\\", "@", ",", ";", "=", "(",
        ")", "[", "]", "{", "}", "<", ">",
    ],
    fold_case: true,
};

const KEYWORDS: &[&str] = &[
    "array", "if", "then", "else", "endif", "while", "loop", "endloop", "and", "or", "not",
];

/// Parses every model of a program.
pub(crate) fn parse(text: &str, file: &str) -> Result<Vec<ModelDef>, ReadError> {
    let mut c = Cursor::new(tokenize(text, &LEXICON, file)?, file);
    let mut models = Vec::new();
    while c.peek().tok != Tok::Eof {
        models.push(model(&mut c)?);
    }
    if models.is_empty() {
        return Err(c.expected("a model 'name(x[3], a[1]) { … }'"));
    }
    Ok(models)
}

fn size(c: &mut Cursor) -> Result<usize, ReadError> {
    let t = c.peek().clone();
    match t.tok {
        Tok::Num(v) if v >= 1.0 && v.fract() == 0.0 && v <= 1e6 => {
            c.next();
            Ok(v as usize)
        }
        _ => Err(c.expected("an array size (a whole number from 1)")),
    }
}

/// `NAME [ SIZE ]` where NAME must be `want` (x, a or s).
fn header_array(c: &mut Cursor, want: &str) -> Result<usize, ReadError> {
    c.expect_word(want)?;
    c.expect("[")?;
    let n = size(c)?;
    c.expect("]")?;
    Ok(n)
}

fn model(c: &mut Cursor) -> Result<ModelDef, ReadError> {
    let (name, t) = c.ident("a model name")?;
    if KEYWORDS.contains(&name.as_str()) {
        return Err(c.error_at(
            &t,
            format!("expected a model name, found the keyword '{name}'"),
        ));
    }
    c.expect("(")?;
    let x_dim = header_array(c, "x")?;
    c.expect(",")?;
    let a_dim = header_array(c, "a")?;
    let s_dim = if c.eat(",") {
        Some(header_array(c, "s")?)
    } else {
        None
    };
    c.expect(")")?;
    c.expect("{")?;
    let body = block(c, &["}"])?;
    let end = Pos::from(&c.expect("}")?);
    Ok(ModelDef {
        name,
        pos: Pos::from(&t),
        x_dim,
        a_dim,
        s_dim,
        body,
        end,
    })
}

/// Statements up to (not including) one of the closing keywords or symbols.
fn block(c: &mut Cursor, end: &[&str]) -> Result<Vec<Stmt>, ReadError> {
    c.enter()?;
    let mut out = Vec::new();
    loop {
        // Any closing word ends a block; the caller then checks it is the right one.
        let stop = match &c.peek().tok {
            Tok::Sym(s) => *s == "}",
            Tok::Ident(w) => matches!(w.as_str(), "else" | "endif" | "endloop"),
            Tok::Eof => true,
            _ => false,
        };
        if stop {
            break;
        }
        out.push(statement(c, end)?);
    }
    c.leave();
    Ok(out)
}

fn statement(c: &mut Cursor, end: &[&str]) -> Result<Stmt, ReadError> {
    let t = c.peek().clone();
    let expected = format!(
        "a statement (assignment, 'array', 'if' or 'while') or {}",
        end.iter()
            .map(|e| format!("'{e}'"))
            .collect::<Vec<_>>()
            .join(" or ")
    );
    let Tok::Ident(word) = &t.tok else {
        return Err(c.expected(&expected));
    };
    let pos = Pos::from(&t);
    let st = match word.as_str() {
        "array" => {
            c.next();
            let mut decls = Vec::new();
            loop {
                let (n, nt) = c.ident("an array name")?;
                c.expect("[")?;
                let k = size(c)?;
                c.expect("]")?;
                decls.push((n, k, Pos::from(&nt)));
                if !c.eat(",") {
                    break;
                }
            }
            Stmt::Array(decls)
        }
        "if" => {
            c.next();
            let cond = expr(c)?;
            c.expect_word("then")?;
            let then = block(c, &["else", "endif"])?;
            let other = if c.is_word("else") {
                c.next();
                block(c, &["endif"])?
            } else {
                Vec::new()
            };
            c.expect_word("endif")?;
            Stmt::If(cond, then, other)
        }
        "while" => {
            c.next();
            let cond = expr(c)?;
            c.expect_word("loop")?;
            let body = block(c, &["endloop"])?;
            c.expect_word("endloop")?;
            Stmt::While(cond, body, pos)
        }
        w if KEYWORDS.contains(&w) => return Err(c.expected(&expected)),
        _ => {
            let name = word.clone();
            c.next();
            if c.eat("[") {
                let index = expr(c)?;
                c.expect("]")?;
                c.expect("=")?;
                Stmt::AssignIndex(name, pos, index, expr(c)?)
            } else {
                c.expect("=")?;
                if c.eat("[") {
                    let mut vals = Vec::new();
                    loop {
                        let neg = c.eat("-");
                        if !neg {
                            c.eat("+");
                        }
                        match c.peek().tok {
                            Tok::Num(v) => {
                                c.next();
                                vals.push(if neg { -v } else { v });
                            }
                            _ => return Err(c.expected("a number")),
                        }
                        if !c.eat(",") {
                            break;
                        }
                    }
                    c.expect("]")?;
                    Stmt::AssignList(name, pos, vals)
                } else {
                    Stmt::Assign(name, pos, expr(c)?)
                }
            }
        }
    };
    c.expect(";")?;
    Ok(st)
}

/// A full expression (the lowest precedence level).
pub(crate) fn expr(c: &mut Cursor) -> Result<Expr, ReadError> {
    c.enter()?;
    let first = comparison(c)?;
    let mut rest = Vec::new();
    loop {
        let op = if c.is_word("and") {
            BinOp::And
        } else if c.is_word("or") {
            BinOp::Or
        } else {
            break;
        };
        let p = Pos::from(&c.next());
        rest.push((op, p, comparison(c)?));
    }
    c.leave();
    Ok(chain(first, rest))
}

fn chain(first: Expr, rest: Vec<(BinOp, Pos, Expr)>) -> Expr {
    if rest.is_empty() {
        first
    } else {
        Expr::Chain(Box::new(first), rest)
    }
}

fn comparison(c: &mut Cursor) -> Result<Expr, ReadError> {
    let first = negation(c)?;
    let mut rest = Vec::new();
    loop {
        let op = match &c.peek().tok {
            Tok::Sym("<") => Cmp::Lt,
            Tok::Sym("<=") => Cmp::Le,
            Tok::Sym(">") => Cmp::Gt,
            Tok::Sym(">=") => Cmp::Ge,
            Tok::Sym("=") => Cmp::Eq,
            Tok::Sym("/=") => Cmp::Ne,
            _ => break,
        };
        let p = Pos::from(&c.next());
        rest.push((op, p, negation(c)?));
    }
    Ok(if rest.is_empty() {
        first
    } else {
        Expr::Compare(Box::new(first), rest)
    })
}

fn negation(c: &mut Cursor) -> Result<Expr, ReadError> {
    if c.is_word("not") {
        let p = Pos::from(&c.next());
        c.enter()?;
        let e = negation(c)?;
        c.leave();
        return Ok(Expr::Unary(UnOp::Not, Box::new(e), p));
    }
    sum(c)
}

fn sum(c: &mut Cursor) -> Result<Expr, ReadError> {
    let first = product(c)?;
    let mut rest = Vec::new();
    loop {
        let op = match &c.peek().tok {
            Tok::Sym("+") => BinOp::Add,
            Tok::Sym("-") => BinOp::Sub,
            Tok::Sym("|") => BinOp::Union,
            Tok::Sym("&") | Tok::Sym("@") => BinOp::Inter,
            Tok::Sym("\\") => BinOp::Diff,
            _ => break,
        };
        let p = Pos::from(&c.next());
        rest.push((op, p, product(c)?));
    }
    Ok(chain(first, rest))
}

fn product(c: &mut Cursor) -> Result<Expr, ReadError> {
    let first = power(c)?;
    let mut rest = Vec::new();
    loop {
        let op = match &c.peek().tok {
            Tok::Sym("*") => BinOp::Mul,
            Tok::Sym("/") => BinOp::Div,
            _ => break,
        };
        let p = Pos::from(&c.next());
        rest.push((op, p, power(c)?));
    }
    Ok(chain(first, rest))
}

fn power(c: &mut Cursor) -> Result<Expr, ReadError> {
    let first = unary(c)?;
    let mut rest = Vec::new();
    while c.is("^") {
        let p = Pos::from(&c.next());
        rest.push((BinOp::Pow, p, unary(c)?));
    }
    Ok(chain(first, rest))
}

fn unary(c: &mut Cursor) -> Result<Expr, ReadError> {
    let op = match &c.peek().tok {
        Tok::Sym("-") => UnOp::Neg,
        Tok::Sym("+") => UnOp::Plus,
        Tok::Sym("~") => UnOp::Tilde,
        _ => return primary(c),
    };
    let p = Pos::from(&c.next());
    c.enter()?;
    let e = unary(c)?;
    c.leave();
    Ok(Expr::Unary(op, Box::new(e), p))
}

fn primary(c: &mut Cursor) -> Result<Expr, ReadError> {
    let t = c.peek().clone();
    match &t.tok {
        Tok::Num(v) => {
            c.next();
            Ok(Expr::Num(*v, Pos::from(&t)))
        }
        Tok::Sym("(") => {
            c.next();
            let e = expr(c)?;
            c.expect(")")?;
            Ok(e)
        }
        Tok::Ident(name) if !KEYWORDS.contains(&name.as_str()) => {
            let name = name.clone();
            let pos = Pos::from(&c.next());
            if c.eat("[") {
                let i = expr(c)?;
                c.expect("]")?;
                Ok(Expr::Index(name, Box::new(i), pos))
            } else if c.eat("(") {
                let mut args = Vec::new();
                if !c.is(")") {
                    loop {
                        args.push(expr(c)?);
                        if !c.eat(",") {
                            break;
                        }
                    }
                }
                c.expect(")")?;
                Ok(Expr::Call(name, args, pos))
            } else {
                Ok(Expr::Name(name, pos))
            }
        }
        _ => Err(c.expected("an expression")),
    }
}
