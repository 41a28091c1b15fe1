//! The tables: points averaged over repeats, comparisons against the baseline
//! (DESIGN.md §4), `results.csv` and `summary.md`.

use super::manifest::{Comparison, Manifest, ReferenceSource, Row};
use super::metrics::{REL_EPSILON, TRIM_FRACTION};
use super::stats;
use super::ExperimentError;
use std::fmt::Write as _;
use std::path::Path;

/// The complete points of the sweep, in the order of `spp` then `estimators`: those
/// whose every seed has a finished render in `m`. `noise` is the reference's own
/// variance per value, when known.
pub fn rows(
    m: &Manifest,
    estimators: &[String],
    spp: &[u32],
    seeds: &[u64],
    noise: Option<f64>,
) -> Vec<Row> {
    let mut out = Vec::new();
    for &n in spp {
        for est in estimators {
            let recs: Option<Vec<_>> = seeds.iter().map(|&s| m.find(est, n, s)).collect();
            let Some(recs) = recs else { continue };
            let mses: Vec<f64> = recs.iter().map(|r| r.mse).collect();
            let rels: Vec<f64> = recs.iter().map(|r| r.relmse).collect();
            let trimmed: Vec<f64> = recs.iter().map(|r| r.trimmed_mse).collect();
            let mse = stats::mean(&mses);
            let mse_ci = stats::mean_ci(&mses);
            let cpu: Option<Vec<f64>> = recs.iter().map(|r| r.cpu_s).collect();
            out.push(Row {
                estimator: est.clone(),
                spp: n,
                seeds: seeds.to_vec(),
                time_s: stats::mean(&recs.iter().map(|r| r.time_s).collect::<Vec<_>>()),
                mse,
                rmse: mse.sqrt(),
                relmse: stats::mean(&rels),
                mse_ci,
                rmse_ci: mse_ci.map(|c| c.map(|v| v.max(0.0).sqrt())),
                relmse_ci: stats::mean_ci(&rels),
                trimmed_mse: stats::mean(&trimmed),
                net_mse: noise.map(|v| mse - v),
                cpu_s: cpu.map(|c| c.into_iter().fold(f64::INFINITY, f64::min)),
                variance: None,
            });
        }
    }
    out
}

/// `a / b` where both are finite and positive, else `None`.
fn ratio(a: f64, b: f64) -> Option<f64> {
    let ok = |v: f64| v.is_finite() && v > 0.0;
    (ok(a) && ok(b)).then(|| a / b)
}

/// The cost of a row: its least processor time where known, else its mean wall time.
fn cost(r: &Row, other: &Row) -> (f64, f64) {
    match (r.cpu_s, other.cpu_s) {
        (Some(a), Some(b)) => (a, b),
        _ => (r.time_s, other.time_s),
    }
}

/// Each row against the baseline's row at the same spp (rows without one are left
/// out); the per-seed renders of `m` pair the seeds for the intervals. With the
/// reference's `noise` known, the MSEs compared are net of it.
pub fn compare(m: &Manifest, rows: &[Row], baseline: &str, noise: Option<f64>) -> Vec<Comparison> {
    compare_by(m, rows, noise, |r| {
        rows.iter()
            .find(|b| b.estimator == baseline && b.spp == r.spp)
    })
}

/// Each row against the row `base` pairs it with (rows without one are left out); the
/// per-seed renders of `m` pair the seeds for the intervals.
fn compare_by<'a>(
    m: &Manifest,
    rows: &'a [Row],
    noise: Option<f64>,
    base: impl Fn(&Row) -> Option<&'a Row>,
) -> Vec<Comparison> {
    rows.iter()
        .filter_map(|r| {
            let b = base(r)?;
            let per_seed = |row: &Row| -> Vec<f64> {
                row.seeds
                    .iter()
                    .filter_map(|&s| m.find(&row.estimator, row.spp, s).map(|x| x.mse))
                    .collect()
            };
            let noise = noise.unwrap_or(0.0);
            let (mb, mr) = (b.mse - noise, r.mse - noise);
            let (sb, sr): (Vec<f64>, Vec<f64>) = (
                per_seed(b).iter().map(|v| v - noise).collect(),
                per_seed(r).iter().map(|v| v - noise).collect(),
            );
            let (tr, tb) = cost(r, b);
            let time_ratio = ratio(tr, tb);
            let speed_up = ratio(mb * tb, mr * tr);
            // Speed Up's interval from the seeds' own costs, MSE × time paired by seed,
            // so that it widens with the timing noise as with the MSEs'; placed around
            // the point (whose time is the least over the seeds) by its relative width.
            let both_cpu = r.cpu_s.is_some() && b.cpu_s.is_some();
            let per_seed_cost = |row: &Row| -> Vec<f64> {
                row.seeds
                    .iter()
                    .filter_map(|&s| m.find(&row.estimator, row.spp, s))
                    .map(|x| match (both_cpu, x.cpu_s) {
                        (true, Some(c)) => c,
                        _ => x.time_s,
                    })
                    .collect()
            };
            let effort = |mse: &[f64], t: &[f64]| -> Vec<f64> {
                mse.iter().zip(t).map(|(a, b)| a * b).collect()
            };
            let (eb, er) = (
                effort(&sb, &per_seed_cost(b)),
                effort(&sr, &per_seed_cost(r)),
            );
            let centre = ratio(stats::mean(&eb), stats::mean(&er));
            let speed_up_ci = match (speed_up, centre, stats::ratio_ci(&eb, &er)) {
                (Some(p), Some(c), Some([lo, hi])) => Some([p * lo / c, p * hi / c]),
                _ => None,
            };
            Some(Comparison {
                estimator: r.estimator.clone(),
                spp: r.spp,
                improvement: ratio(mb, mr).map(f64::sqrt),
                improvement_ci: stats::ratio_ci(&sb, &sr).map(|c| c.map(f64::sqrt)),
                improvement_trimmed: ratio(b.trimmed_mse, r.trimmed_mse).map(f64::sqrt),
                median_pixel_ratio: None,
                overhead: time_ratio.map(|q| q - 1.0),
                speed_up,
                speed_up_ci,
            })
        })
        .collect()
}

/// Each row against the baseline's at equal time (`experiment --budget`: every
/// estimator at the samples that fill the budget, [`super::budget`]): Improvement is
/// the RMSE ratio at equal time (its square the MSE ratio), with intervals from the
/// seeds paired; Overhead says how far the measured times came out from equal, and
/// Speed Up corrects the MSE ratio by it.
pub fn compare_at_budget(
    m: &Manifest,
    rows: &[Row],
    baseline: &str,
    noise: Option<f64>,
) -> Vec<Comparison> {
    compare_by(m, rows, noise, |_| {
        rows.iter().find(|b| b.estimator == baseline)
    })
}

/// Writes `results.csv`: one line per point; floats in shortest round-trip form.
pub fn write_csv(path: &Path, rows: &[Row]) -> Result<(), ExperimentError> {
    let mut s = String::from(
        "estimator,spp,repeats,seeds,time_s,mse,rmse,relmse,mse_lo,mse_hi,relmse_lo,\
         relmse_hi,trimmed_mse,net_mse,cpu_s\n",
    );
    let num = |v: Option<f64>| v.map(|x| format!("{x:e}")).unwrap_or_default();
    for r in rows {
        let seeds: Vec<String> = r.seeds.iter().map(u64::to_string).collect();
        let _ = writeln!(
            s,
            "{},{},{},{},{:e},{:e},{:e},{:e},{},{},{},{},{:e},{},{}",
            r.estimator,
            r.spp,
            r.seeds.len(),
            seeds.join(";"),
            r.time_s,
            r.mse,
            r.rmse,
            r.relmse,
            num(r.mse_ci.map(|c| c[0])),
            num(r.mse_ci.map(|c| c[1])),
            num(r.relmse_ci.map(|c| c[0])),
            num(r.relmse_ci.map(|c| c[1])),
            r.trimmed_mse,
            num(r.net_mse),
            num(r.cpu_s),
        );
    }
    write_text(path, &s)
}

/// Writes `text` to `path`, whole or not at all.
pub fn write_text(path: &Path, text: &str) -> Result<(), ExperimentError> {
    render::output::write_atomically(path, |w| std::io::Write::write_all(w, text.as_bytes()))
        .map_err(ExperimentError::io("write", path))
}

fn opt(v: Option<f64>, f: impl Fn(f64) -> String) -> String {
    v.map(f).unwrap_or_else(|| "—".into())
}

/// ` [lo, hi]`, or nothing without an interval.
fn ci_cell(ci: Option<[f64; 2]>, f: impl Fn(f64) -> String) -> String {
    ci.map(|[a, b]| format!(" [{}, {}]", f(a), f(b)))
        .unwrap_or_default()
}

fn ratio_cell(v: Option<f64>) -> String {
    opt(v, |x| format!("{x:.4}"))
}

fn overhead_cell(v: Option<f64>) -> String {
    opt(v, |x| format!("{:+.2} %", 100.0 * x))
}

/// The Markdown of `summary.md`.
pub fn summary_markdown(m: &Manifest, rows: &[Row], cmp: &[Comparison], done: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Experiment: {}\n", m.scene);
    let _ = writeln!(s, "```\n{}\n```\n", m.command);
    let reference = match &m.reference.source {
        ReferenceSource::File { path } => format!("loaded from `{path}`"),
        ReferenceSource::Rendered {
            estimator,
            spp,
            seed,
            parts,
        } => format!(
            "rendered with {estimator} at {spp} spp from seed {seed} in {parts} independent \
             part(s) (`reference.exr`)"
        ),
    };
    let noise = match m.reference.noise_mse {
        Some(v) => {
            let worst = rows
                .iter()
                .filter_map(|r| r.net_mse)
                .fold(f64::INFINITY, f64::min);
            let warn = if worst <= 0.0 {
                " **Some renders are no less noisy than the reference: their ratios are left \
                 out (—); render the reference with more samples.**"
            } else {
                ""
            };
            format!(
                "- Reference noise: {v:.4e} per value (MSE of its two parts' difference, \
                 scaled); ratios use each MSE less this (net MSE).{warn}\n"
            )
        }
        None => "- Reference noise: unknown (a loaded reference, or 1 spp); ratios use the \
                 measured MSE, which includes it.\n"
            .into(),
    };
    let repeats = rows.first().map_or(1, |r| r.seeds.len());
    let _ = writeln!(
        s,
        "- Reference: {reference}; {}x{} pixels.\n{noise}- Baseline: {}. Renderer: {}.\n- {done}\n",
        m.reference.width,
        m.reference.height,
        m.baseline,
        if m.renderer.is_empty() {
            "—"
        } else {
            &m.renderer
        },
    );
    let cost = if rows.iter().all(|r| r.cpu_s.is_some()) {
        "processor time (the least over the seeds, whose renders interleave with the other \
         estimators')"
    } else {
        "wall time (mean over the seeds)"
    };
    let _ = writeln!(
        s,
        "Improvement = RMSE_baseline / RMSE_method and Overhead = time_method / \
         time_baseline − 1 at equal spp; Speed Up = efficiency_method / \
         efficiency_baseline, efficiency = 1 / (MSE × time) (DESIGN.md §4), with time = \
         {cost}. RMSE and relMSE = mean (x − ref)² / (ref² + {REL_EPSILON}) over all \
         pixels and channels, unclamped; MSE and wall time are means over {repeats} seed(s) \
         per point; [a, b] are 95 % intervals over the seeds (Student's t; ratios by the \
         delta method on paired seeds, Speed Up's on each seed's MSE × time, so that timing \
         noise widens it; none with one seed). Trimmed: without the worst \
         {trim} % of pixels. Pixel ratio: the median over pixels of the squared-error ratio \
         baseline / method (maps in `maps/`).\n",
        trim = 100.0 * TRIM_FRACTION
    );
    let head = "| Estimator | spp | RMSE [95 % CI] | relMSE | Wall (s) | CPU (s) | Improvement \
                [95 % CI] | Impr. trimmed | Pixel ratio | Speed Up [95 % CI] | Overhead |\n\
                |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    let line = |s: &mut String, r: &Row| {
        let c = cmp
            .iter()
            .find(|c| c.estimator == r.estimator && c.spp == r.spp);
        let _ = writeln!(
            s,
            "| {} | {} | {:.4e}{} | {:.4e} | {:.4} | {} | {}{} | {} | {} | {}{} | {} |",
            r.estimator,
            r.spp,
            r.rmse,
            ci_cell(r.rmse_ci, |v| format!("{v:.3e}")),
            r.relmse,
            r.time_s,
            opt(r.cpu_s, |v| format!("{v:.3}")),
            ratio_cell(c.and_then(|c| c.improvement)),
            ci_cell(c.and_then(|c| c.improvement_ci), |v| format!("{v:.3}")),
            ratio_cell(c.and_then(|c| c.improvement_trimmed)),
            ratio_cell(c.and_then(|c| c.median_pixel_ratio)),
            ratio_cell(c.and_then(|c| c.speed_up)),
            ci_cell(c.and_then(|c| c.speed_up_ci), |v| format!("{v:.3}")),
            overhead_cell(c.and_then(|c| c.overhead)),
        );
    };
    if let Some(b) = &m.budget {
        let _ = write!(
            s,
            "## At equal time\n\nEvery estimator rendered the samples per pixel that fill \
             {} s of processor time: its cost was calibrated as t₀ + n·c from renders at 1 \
             and {} spp, then at about an eighth of the budget (each the least of {} \
             interleaved rounds), and n = ⌊(budget − t₀)/c⌋. \
             MSE ratio = MSE_baseline / MSE_method at equal time, RMSE ratio its square root \
             (the Improvement of the tables below, here at equal time); Overhead: how far the \
             measured time came from the baseline's.\n\n\
             | Estimator | spp | t₀ (s) | c (s/spp) | CPU (s) | RMSE | MSE ratio [95 % CI] | \
             RMSE ratio [95 % CI] | Overhead |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
            b.seconds,
            super::budget::CALIBRATION_SPP,
            super::budget::CALIBRATION_ROUNDS
        );
        for e in &b.estimators {
            let Some(r) = rows.iter().find(|r| r.estimator == e.estimator) else {
                continue;
            };
            let c = cmp.iter().find(|c| c.estimator == r.estimator);
            let improvement = c.and_then(|c| c.improvement);
            let ci = c.and_then(|c| c.improvement_ci);
            let _ = writeln!(
                s,
                "| {} | {} | {:.4} | {:.3e} | {} | {:.4e} | {}{} | {}{} | {} |",
                r.estimator,
                r.spp,
                e.fixed_s,
                e.per_sample_s,
                opt(r.cpu_s, |v| format!("{v:.3}")),
                r.rmse,
                ratio_cell(improvement.map(|v| v * v)),
                ci_cell(ci.map(|c| c.map(|v| v * v)), |v| format!("{v:.3}")),
                ratio_cell(improvement),
                ci_cell(ci, |v| format!("{v:.3}")),
                overhead_cell(c.and_then(|c| c.overhead)),
            );
        }
        s.push('\n');
    }
    let _ = write!(s, "## Every sample count\n\n{head}");
    for r in rows {
        line(&mut s, r);
    }
    if rows.iter().any(|r| r.variance.is_some()) {
        let _ = write!(
            s,
            "\n## Variance: pixel footprint and directions\n\nThe same seeds rendered with \
             every camera ray through its pixel's centre: the variance left is the \
             directions' (what MIS weights act on), the rest the pixel footprint's \
             (`experiment::decompose`). Sums over pixels and channels of the per-pixel \
             variance over the seeds.\n\n\
             | Estimator | spp | jittered | centred | direction share | footprint share |\n\
             |---|---:|---:|---:|---:|---:|\n"
        );
        for r in rows {
            if let Some(v) = r.variance {
                let _ = writeln!(
                    s,
                    "| {} | {} | {:.4e} | {:.4e} | {:.1} % | {:.1} % |",
                    r.estimator,
                    r.spp,
                    v.jittered,
                    v.centered,
                    100.0 * v.direction_share,
                    100.0 * (1.0 - v.direction_share)
                );
            }
        }
    }
    if let Some(max) = rows.iter().map(|r| r.spp).max() {
        let _ = write!(s, "\n## At the largest sample count ({max} spp)\n\n{head}");
        for r in rows.iter().filter(|r| r.spp == max) {
            line(&mut s, r);
        }
    }
    s
}
