//! Prints an expression model's occupancy grid (`frep::occupancy`): its build time,
//! cells per axis, the occupied cells and the lengths of their simplified tapes. A model
//! with no grid (n = 0) is searched along its whole tape by every ray.
//!
//! ```text
//! cargo run --release -p frep --example grid_stats -- MODEL H
//! ```
//! (the grid over the box [-H, H]³, as `bench/fidget-compare` views the model).

use frep::occupancy;
use frep::ray::Aabb;
use frep::shape::Shape;
use glam::DVec3;
use std::error::Error;

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [path, h] = &args[..] else {
        return Err("usage: grid_stats MODEL H (the grid over [-H, H]³)".into());
    };
    let h: f64 = h
        .parse()
        .map_err(|_| format!("H: expected a number, found '{h}'"))?;
    let model = frep::read::read_file(std::path::Path::new(path))?;
    let Shape::Function { tree, .. } = &model.shape else {
        return Err(format!("{path}: not one expression").into());
    };
    let expr = frep::Expr::new(tree);
    let start = std::time::Instant::now();
    let g = occupancy::build(expr.nodes(), &Aabb::new(DVec3::splat(-h), DVec3::splat(h)));
    let secs = start.elapsed().as_secs_f64();
    println!(
        "tape {} nodes; grid built in {secs:.3} s, {} cells per axis",
        expr.len(),
        g.n
    );
    let cells = g.n.pow(3);
    let mut lens: Vec<u32> = (0..cells)
        .filter(|&i| g.words[i / 64] >> (i % 64) & 1 == 1)
        .map(|i| g.cells[i][1] - g.cells[i][0])
        .collect();
    lens.sort_unstable();
    if let (Some(min), Some(max)) = (lens.first(), lens.last()) {
        let mean = lens.iter().map(|&l| f64::from(l)).sum::<f64>() / lens.len() as f64;
        println!(
            "occupied {} of {cells} cells; their tapes: min {min}, median {}, 90th percentile {}, max {max}, mean {mean:.1} nodes; {} nodes in all",
            lens.len(),
            lens[lens.len() / 2],
            lens[lens.len() * 9 / 10],
            g.nodes.len()
        );
    }
    Ok(())
}
