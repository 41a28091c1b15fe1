//! Where frepray's ray time goes: evaluations per ray, counted and timed.
//!
//! `frep::ExprSurface` keeps no counters, so this is a line-for-line replica of its
//! `first_crossing` as of commit 6ab0d6c (crates/frep/src/interval_trace.rs: segments
//! bounded by `Dual<Interval, 1>` with min/max choices recorded, a mean-value test at the
//! midpoint, the tape simplified before splitting, safeguarded Newton to locate the
//! crossing), with counters and a clock around each evaluation (two clock reads, tens of
//! ns, against evaluations of µs). The replica's depths are checked against the real
//! renderer's, and the real renderer is timed on the same rays, so a drift of the copy
//! from the original shows up in the report.

use crate::args::Args;
use crate::render::{cast, quantise};
use crate::{sig3, Model};
use frep::interval_trace::RESOLUTION;
use frep::{Aabb, Choice, Dual, Expr, Interval, Ray, Solid, Surface};
use glam::DVec3;
use std::error::Error;
use std::sync::Arc;
use std::time::Instant;

/// Expressions shorter than this are not simplified (as in interval_trace.rs).
const SIMPLIFY_MIN_LEN: usize = 24;

/// Evaluations made, the wall time spent in each kind, and the tape lengths seen.
#[derive(Default)]
struct Counts {
    segments: u64,
    points: u64,
    newton: u64,
    simplify: u64,
    t_segments: f64,
    t_points: f64,
    t_newton: f64,
    t_simplify: f64,
    /// Sum over segment evaluations of the tape's length.
    seg_nodes: u64,
}

struct Counter {
    expr: Arc<Expr>,
    bounds: Aabb,
    eps: f64,
    c: Counts,
    sd: Vec<Dual<Interval, 1>>,
    sf: Vec<f64>,
    st: Vec<Dual<f64, 1>>,
    choices: Vec<Choice>,
}

impl Counter {
    fn value_at(&mut self, tape: &Expr, ray: &Ray, t: f64) -> f64 {
        self.c.points += 1;
        let p = ray.at(t);
        let clock = Instant::now();
        let v = tape.eval_with(p.x, p.y, p.z, &mut self.sf);
        self.c.t_points += clock.elapsed().as_secs_f64();
        v
    }

    fn segment(&mut self, tape: &Expr, ray: &Ray, a: f64, b: f64) -> (Interval, Interval) {
        self.c.segments += 1;
        self.c.seg_nodes += tape.len() as u64;
        let t = Interval::new(a, b);
        let c = |k: usize| {
            let v = Interval::point(ray.o[k]) + t * Interval::point(ray.d[k]);
            Dual::new(v, [Interval::point(ray.d[k])])
        };
        let clock = Instant::now();
        let r = tape.eval_choices(c(0), c(1), c(2), &mut self.sd, &mut self.choices);
        self.c.t_segments += clock.elapsed().as_secs_f64();
        (r.v, r.d[0])
    }

    #[allow(clippy::too_many_arguments)]
    fn refine(
        &mut self,
        tape: &Expr,
        ray: &Ray,
        mut a: f64,
        mut b: f64,
        inside_a: bool,
        tol: f64,
    ) -> f64 {
        let mut x = 0.5 * (a + b);
        for _ in 0..100 {
            let p = ray.at(x);
            let c = |k: usize| Dual::<f64, 1>::new(p[k], [ray.d[k]]);
            self.c.newton += 1;
            let clock = Instant::now();
            let r = tape.eval_with(c(0), c(1), c(2), &mut self.st);
            self.c.t_newton += clock.elapsed().as_secs_f64();
            if (r.v >= 0.0) == inside_a {
                a = x;
            } else {
                b = x;
            }
            if b - a <= tol {
                return b;
            }
            let step = r.v / r.d[0];
            let newton = x - step;
            if step.is_finite() && newton > a && newton < b {
                if step.abs() <= tol {
                    return newton;
                }
                x = newton;
            } else {
                x = 0.5 * (a + b);
            }
        }
        b
    }

    fn first_crossing(&mut self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        let grown = Aabb::new(self.bounds.lo - self.eps, self.bounds.hi + self.eps);
        let (t0, t1) = grown.clip(ray, t_min, t_max)?;
        if !(t1 > t0) || !t1.is_finite() || !t0.is_finite() {
            return None;
        }
        let eps_t = self.eps / ray.d.length().max(f64::MIN_POSITIVE);
        let tol = eps_t * 1e-5;
        let root = self.expr.clone();
        let ia = self.value_at(&root, ray, t0) >= 0.0;
        let ib = self.value_at(&root, ray, t1) >= 0.0;
        let mut stack = vec![(t0, t1, ia, ib, root)];
        while let Some((a, b, ia, ib, tape)) = stack.pop() {
            let (v, slope) = self.segment(&tape, ray, a, b);
            if v.lo > 0.0 || v.hi < 0.0 {
                continue;
            }
            if slope.lo > 0.0 || slope.hi < 0.0 || b - a <= eps_t {
                if ia != ib {
                    return Some(self.refine(&tape, ray, a, b, ia, tol));
                }
                continue;
            }
            let m = 0.5 * (a + b);
            let fm = self.value_at(&tape, ray, m);
            let mv = Interval::point(fm) + slope * Interval::new(a - m, b - m);
            if ia == ib && (mv.lo > 0.0 || mv.hi < 0.0) {
                continue;
            }
            let tape = if tape.len() >= SIMPLIFY_MIN_LEN {
                self.c.simplify += 1;
                let clock = Instant::now();
                let s = tape.simplify(&self.choices).map(Arc::new).unwrap_or(tape);
                self.c.t_simplify += clock.elapsed().as_secs_f64();
                s
            } else {
                tape
            };
            let im = fm >= 0.0;
            stack.push((m, b, im, ib, tape.clone()));
            stack.push((a, m, ia, im, tape));
        }
        None
    }
}

/// Counts and times evaluations on every `stride`-th pixel of the N² view.
pub fn run(m: &Model, n: usize, frep_depth: &[f32], args: &Args) -> Result<String, Box<dyn Error>> {
    let solid = Solid::build(&m.shape)?;
    let flat = solid.flat();
    let one_expr = flat.nodes.len() == 1 && matches!(flat.leaf(0), frep::LeafView::Expr(_));
    if !one_expr {
        return Ok(format!(
            "| {} | {n}² | (not one expression leaf: profile skipped) | | | | | |",
            m.name
        ));
    }
    let bounds = solid.bounds();
    let diag = if bounds.is_finite() && !bounds.is_empty() {
        bounds.extent().length()
    } else {
        1.0
    };
    // The same expression `Solid::build` compiles (identity transform).
    let expr = Arc::new(Expr::new(&m.shape.to_tree()?));
    let full_len = expr.len();
    let mut c = Counter {
        expr,
        bounds,
        eps: RESOLUTION * diag.max(1e-12),
        c: Counts::default(),
        sd: vec![],
        sf: vec![],
        st: vec![],
        choices: vec![],
    };
    let h = m.half;
    let s = 2.0 / n as f64;
    let half = (n / 2) as f64;
    let pixels: Vec<(usize, usize)> = (0..n)
        .step_by(args.stride)
        .flat_map(|j| (0..n).step_by(args.stride).map(move |i| (i, j)))
        .collect();
    let (mut mismatches, mut hits) = (0u64, 0u64);
    let clock = Instant::now();
    for &(i, j) in &pixels {
        let o = DVec3::new(
            (i as f64 - half) * s * h,
            (half - 1.0 - j as f64) * s * h,
            h,
        );
        let ray = Ray::new(o, -DVec3::Z);
        // As the renderer: one point test at the top, then the first crossing.
        let root = c.expr.clone();
        let zeta = if c.value_at(&root, &ray, 0.0) >= 0.0 {
            n as f32
        } else {
            match c.first_crossing(&ray, 0.0, 2.0 * h) {
                Some(t) => (((h - t) / h + 1.0) * half) as f32,
                None => f32::NAN,
            }
        };
        hits += !zeta.is_nan() as u64;
        if quantise(zeta, n) != quantise(frep_depth[j * n + i], n) {
            mismatches += 1;
        }
    }
    let t_replica = clock.elapsed().as_secs_f64();
    // The real renderer on the same rays (it also computes the normal at each hit).
    let clock = Instant::now();
    for &(i, j) in &pixels {
        std::hint::black_box(cast(&solid, n, h, i, j));
    }
    let t_real = clock.elapsed().as_secs_f64();

    let r = pixels.len() as f64;
    let k = &c.c;
    let us = |t: f64| sig3(t / r * 1e6);
    let per = |x: u64| format!("{:.1}", x as f64 / r);
    let mean_len = k.seg_nodes as f64 / k.segments.max(1) as f64;
    let mut note = format!(
        "{} µs per ray in the replica (evaluations {} µs), real renderer {} µs per ray on the same rays",
        us(t_replica),
        us(k.t_segments + k.t_points + k.t_newton + k.t_simplify),
        us(t_real)
    );
    if mismatches > 0 {
        note += &format!(
            "; replica depth differs on {mismatches} of {} rays",
            pixels.len()
        );
    }
    eprintln!(
        "   profile {n}²: {} rays ({hits} hits), {note}",
        pixels.len()
    );
    Ok(format!(
        "| {} | {n}² | {} ({} µs) | {mean_len:.0} of {full_len} | {} ({} µs) | {} ({} µs) | {} ({} µs) | {note} |",
        m.name,
        per(k.segments),
        us(k.t_segments),
        per(k.points),
        us(k.t_points),
        per(k.newton),
        us(k.t_newton),
        per(k.simplify),
        us(k.t_simplify),
    ))
}
