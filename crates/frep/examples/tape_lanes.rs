//! Measures what evaluating several rays per pass over a tape would save, for planning
//! (docs/benchmarks.md, "frepray against Fidget"): over every occupied cell of a
//! model's 64³ grid, the tape simplified for that cell, and 8 vertical ray segments
//! through the cell, it times
//!
//! - the segment evaluation a ray's search does (F and dF/dt over [t0, t1] as
//!   `Dual<Interval, 1>`) and the point evaluation of its Newton steps
//!   (`Dual<f64, 1>`), one segment or point at a time, as the renderer does now;
//! - the same evaluations N at a time, the tape read once per N (`Lanes`, each lane
//!   computed by the same code as one at a time: the results are checked bit for bit).
//!
//! ```text
//! cargo run --release -p frep --example tape_lanes -- MODEL
//! ```

use frep::dual::Dual;
use frep::expr::{eval_choices_nodes, eval_nodes, Expr};
use frep::interval::Interval;
use frep::scalar::{Scalar, Zero};
use frep::{Aabb, Shape};
use glam::DVec3;
use std::error::Error;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// N values evaluated side by side, lane by lane.
#[derive(Clone, Copy, Debug)]
struct Lanes<T, const N: usize>([T; N]);

impl<T: Scalar, const N: usize> Lanes<T, N> {
    #[inline(always)]
    fn map(self, f: impl Fn(T) -> T) -> Self {
        Lanes(self.0.map(f))
    }
    #[inline(always)]
    fn zip(self, b: Self, f: impl Fn(T, T) -> T) -> Self {
        Lanes(std::array::from_fn(|i| f(self.0[i], b.0[i])))
    }
}

macro_rules! operator {
    ($($trait:ident $f:ident),*) => {$(
        impl<T: Scalar, const N: usize> $trait for Lanes<T, N> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, b: Self) -> Self {
                self.zip(b, T::$f)
            }
        }
    )*};
}
operator!(Add add, Sub sub, Mul mul, Div div);

impl<T: Scalar, const N: usize> Neg for Lanes<T, N> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        self.map(T::neg)
    }
}

macro_rules! unary {
    ($($f:ident),*) => {$(
        #[inline(always)]
        fn $f(self) -> Self {
            self.map(T::$f)
        }
    )*};
}

macro_rules! binary {
    ($($f:ident),*) => {$(
        #[inline(always)]
        fn $f(self, b: Self) -> Self {
            self.zip(b, T::$f)
        }
    )*};
}

impl<T: Scalar, const N: usize> Scalar for Lanes<T, N> {
    const R_BOUND: bool = T::R_BOUND;
    fn constant(v: f64) -> Self {
        Lanes([T::constant(v); N])
    }
    unary!(abs, sqrt, square, exp, ln, sin, cos, tan, asin, acos, atan, floor, ceil, round, not);
    binary!(atan2, min, max, modulo, compare, hull, and, or);
    fn powi(self, n: i32) -> Self {
        self.map(|v| v.powi(n))
    }
    fn r_bound(v: Self, a: Self, b: Self, union: bool) -> Self {
        Lanes(std::array::from_fn(|i| {
            T::r_bound(v.0[i], a.0[i], b.0[i], union)
        }))
    }
    /// What every lane says, else unknown (`not`, `and`, `or` go lane by lane).
    fn zero(self) -> Zero {
        let z = self.0.map(T::zero);
        if z.iter().all(|z| matches!(z, Zero::Yes)) {
            Zero::Yes
        } else if z.iter().all(|z| matches!(z, Zero::No)) {
            Zero::No
        } else {
            Zero::Maybe
        }
    }
    /// Undecided unless every lane agrees.
    fn less(self, b: Self) -> Option<bool> {
        let first = self.0[0].less(b.0[0])?;
        (1..N)
            .all(|i| self.0[i].less(b.0[i]) == Some(first))
            .then_some(first)
    }
}

/// A vertical ray segment: x, y, the top of its cell and the cell's height.
type Segment = [f64; 4];

/// The inputs of a segment evaluation ([`frep::interval_trace`]'s `segment`) and of a
/// Newton step at its middle, for coordinate k of a ray going down −z.
fn inputs(s: &Segment, k: usize) -> (Dual<Interval, 1>, Dual<f64, 1>) {
    let (o, d) = if k == 2 { (s[2], -1.0) } else { (s[k], 0.0) };
    let t = Interval::new(0.0, s[3]);
    let segment = Dual::new(
        Interval::point(o) + t * Interval::point(d),
        [Interval::point(d)],
    );
    (segment, Dual::new(o + 0.5 * s[3] * d, [d]))
}

/// Ns per evaluation of `f` (which does `per` evaluations), best of 5 runs of `reps`.
fn ns(reps: usize, per: f64, mut f: impl FnMut()) -> f64 {
    (0..5)
        .map(|_| {
            let start = std::time::Instant::now();
            for _ in 0..reps {
                f();
            }
            start.elapsed().as_secs_f64() * 1e9 / (reps as f64 * per)
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [path] = &args[..] else {
        return Err("usage: tape_lanes MODEL".into());
    };
    let model = frep::read::read_file(std::path::Path::new(path))?;
    let Shape::Function { tree, .. } = &model.shape else {
        return Err(format!("{path}: not an expression solid").into());
    };
    let e = Expr::new(tree);
    // The bounds `Solid::build` finds (its grid is built over them, grown by 10⁻⁷).
    let d = frep::bounds::DEFAULT_DOMAIN;
    let domain = model
        .domain
        .unwrap_or(Aabb::new(DVec3::splat(-d), DVec3::splat(d)));
    let b = frep::bounds::expr_bounds(&e, domain);
    let g = 64;
    let size = (b.hi - b.lo) / g as f64;
    // xorshift64: reproducible positions in each cell.
    let mut state = 0x1234_5678_9abc_def0u64;
    let mut unit = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut cells, mut scratch, mut choices) = (Vec::new(), Vec::new(), Vec::new());
    for n in 0..g * g * g {
        let lo = b.lo + size * DVec3::new((n % g) as f64, (n / g % g) as f64, (n / g / g) as f64);
        let hi = lo + size;
        let box_of = |k: usize| Interval::new(lo[k], hi[k]);
        let (x, y, z) = (box_of(0), box_of(1), box_of(2));
        let v = eval_choices_nodes(e.nodes(), x, y, z, &mut scratch, &mut choices);
        if v.lo > 0.0 || v.hi < 0.0 {
            continue;
        }
        let tape = e.simplify(&choices).unwrap_or_else(|| e.clone());
        let segments: [Segment; 8] =
            std::array::from_fn(|_| [lo.x + size.x * unit(), lo.y + size.y * unit(), hi.z, size.z]);
        cells.push((tape, segments));
    }
    let nodes = cells.iter().map(|(t, _)| t.len()).sum::<usize>() as f64 / cells.len() as f64;
    println!(
        "{path}: {} cells of 64³ may hold the surface; their tapes have {nodes:.1} nodes on average (whole tape {})",
        cells.len(),
        e.len()
    );
    let evals = (cells.len() * 8) as f64;
    let cells = &cells[..];
    // One at a time, as the renderer evaluates.
    let (mut sd, mut sp) = (Vec::new(), Vec::new());
    // Results are kept for the check, not in the timed runs.
    let mut one = |keep: bool| {
        let (mut seg, mut pt) = (Vec::new(), Vec::new());
        for (tape, segments) in cells {
            for s in segments {
                let (x, y, z) = (inputs(s, 0), inputs(s, 1), inputs(s, 2));
                let v = eval_nodes(tape.nodes(), x.0, y.0, z.0, &mut sd);
                let p = eval_nodes(tape.nodes(), x.1, y.1, z.1, &mut sp);
                if keep {
                    seg.push(v);
                    pt.push(p);
                }
            }
        }
        (seg, pt)
    };
    let (seg1, pt1) = one(true);
    macro_rules! lanes {
        ($n:literal) => {{
            let (mut sd, mut sp) = (Vec::new(), Vec::new());
            let mut run = move |keep: bool| {
                let (mut seg, mut pt) = (Vec::new(), Vec::new());
                for (tape, segments) in cells {
                    for group in segments.chunks($n) {
                        let lane = |k: usize| {
                            let v: [_; $n] = std::array::from_fn(|i| inputs(&group[i], k));
                            (Lanes(v.map(|v| v.0)), Lanes(v.map(|v| v.1)))
                        };
                        let (x, y, z) = (lane(0), lane(1), lane(2));
                        let s = eval_nodes(tape.nodes(), x.0, y.0, z.0, &mut sd);
                        let p = eval_nodes(tape.nodes(), x.1, y.1, z.1, &mut sp);
                        if keep {
                            seg.extend(s.0);
                            pt.extend(p.0);
                        }
                    }
                }
                (seg, pt)
            };
            let (seg, pt) = run(true);
            let same = seg.len() == seg1.len()
                && seg.iter().zip(&seg1).all(|(a, b)| {
                    [a.v.lo, a.v.hi, a.d[0].lo, a.d[0].hi].map(f64::to_bits)
                        == [b.v.lo, b.v.hi, b.d[0].lo, b.d[0].hi].map(f64::to_bits)
                })
                && pt.iter().zip(&pt1).all(|(a, b)| {
                    (a.v.to_bits(), a.d[0].to_bits()) == (b.v.to_bits(), b.d[0].to_bits())
                });
            if !same {
                return Err(format!("{} lanes: not the values of one at a time", $n).into());
            }
            move || {
                std::hint::black_box(run(false));
            }
        }};
    }
    let mut two = lanes!(2);
    let mut four = lanes!(4);
    let mut eight = lanes!(8);
    let t1 = ns(3, evals, || {
        std::hint::black_box(one(false));
    });
    let t2 = ns(3, evals, &mut two);
    let t4 = ns(3, evals, &mut four);
    let t8 = ns(3, evals, &mut eight);
    println!("ns per segment and point evaluation (best of 5), lanes equal to one at a time bit for bit:");
    println!("| one at a time | 2 lanes | 4 lanes | 8 lanes |");
    println!("| ---: | ---: | ---: | ---: |");
    println!("| {t1:.1} | {t2:.1} | {t4:.1} | {t8:.1} |");
    Ok(())
}
