//! Reader of HyperFun (`.hf`) programs.
//!
//! A program holds one or more models `name(x[3], a[n]) { … }`; the last is the one read,
//! the others can be called from it as `other(xx, aa)`. The model is lowered to a
//! single expression tree by symbolic execution (see `exec`), with `x[1..3]` = x, y, z,
//! every parameter `a[i]` = 0 and coordinates beyond the third = 0.

mod exec;
mod lib;
mod parse;

use super::sym::Val;
use super::{Model, ReadError};
use crate::shape::Shape;
use crate::tree::Tree;

/// Reads a HyperFun program (see the module docs).
pub(crate) fn read(text: &str, file: &str) -> Result<Model, ReadError> {
    let models = parse::parse(text, file)?;
    for (i, m) in models.iter().enumerate() {
        if models[..i].iter().any(|o| o.name == m.name) {
            return Err(ReadError::at(
                file,
                m.pos.line,
                m.pos.col,
                format!(
                    "expected a new model name, found '{}' defined twice",
                    m.name
                ),
            ));
        }
        if lib::signature(&m.name).is_some() {
            return Err(ReadError::at(
                file,
                m.pos.line,
                m.pos.col,
                format!(
                    "expected a model name, found '{}', a built-in function",
                    m.name
                ),
            ));
        }
    }
    let main = models.last().expect("parse returns at least one model");
    let coords = [Tree::x(), Tree::y(), Tree::z()];
    let x: Vec<Val> = (0..main.x_dim)
        .map(|i| {
            coords
                .get(i)
                .map_or(Val::Num(0.0), |t| Val::Tree(t.clone()))
        })
        .collect();
    let a = vec![Val::Num(0.0); main.a_dim];
    let v = exec::Exec::new(&models, file).run(main, x, a)?;
    Ok(Model {
        name: Some(main.name.clone()),
        shape: Shape::function(v.tree()),
        domain: None,
    })
}
