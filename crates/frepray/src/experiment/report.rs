//! The tables: points averaged over repeats, comparisons against the baseline
//! (DESIGN.md §4), `results.csv` and `summary.md`.

use super::manifest::{Comparison, Manifest, ReferenceSource, Row};
use super::metrics::REL_EPSILON;
use std::fmt::Write as _;
use std::path::Path;

/// The complete points of the sweep, in the order of `spp` then `estimators`: those
/// whose every seed has a finished render in `m`.
pub fn rows(m: &Manifest, estimators: &[String], spp: &[u32], seeds: &[u64]) -> Vec<Row> {
    let mut out = Vec::new();
    for &n in spp {
        for est in estimators {
            let recs: Option<Vec<_>> = seeds.iter().map(|&s| m.find(est, n, s)).collect();
            let Some(recs) = recs else { continue };
            let k = recs.len() as f64;
            let mse = recs.iter().map(|r| r.mse).sum::<f64>() / k;
            out.push(Row {
                estimator: est.clone(),
                spp: n,
                seeds: seeds.to_vec(),
                time_s: recs.iter().map(|r| r.time_s).sum::<f64>() / k,
                mse,
                rmse: mse.sqrt(),
                relmse: recs.iter().map(|r| r.relmse).sum::<f64>() / k,
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

/// Each row against the baseline's row at the same spp (rows without one are left out).
pub fn compare(rows: &[Row], baseline: &str) -> Vec<Comparison> {
    rows.iter()
        .filter_map(|r| {
            let b = rows
                .iter()
                .find(|b| b.estimator == baseline && b.spp == r.spp)?;
            Some(Comparison {
                estimator: r.estimator.clone(),
                spp: r.spp,
                improvement: ratio(b.rmse, r.rmse),
                overhead: ratio(r.time_s, b.time_s).map(|q| q - 1.0),
                speed_up: ratio(b.mse * b.time_s, r.mse * r.time_s),
            })
        })
        .collect()
}

/// Writes `results.csv`: one line per point; floats in shortest round-trip form.
pub fn write_csv(path: &Path, rows: &[Row]) -> Result<(), String> {
    let mut s = String::from("estimator,spp,repeats,seeds,time_s,mse,rmse,relmse\n");
    for r in rows {
        let seeds: Vec<String> = r.seeds.iter().map(u64::to_string).collect();
        let _ = writeln!(
            s,
            "{},{},{},{},{:e},{:e},{:e},{:e}",
            r.estimator,
            r.spp,
            r.seeds.len(),
            seeds.join(";"),
            r.time_s,
            r.mse,
            r.rmse,
            r.relmse
        );
    }
    write_text(path, &s)
}

/// Writes `text` to `path`, whole or not at all.
pub fn write_text(path: &Path, text: &str) -> Result<(), String> {
    render::output::write_atomically(path, |w| std::io::Write::write_all(w, text.as_bytes()))
        .map_err(|e| format!("cannot write {}: {e}", path.display()))
}

fn opt(v: Option<f64>, f: impl Fn(f64) -> String) -> String {
    v.map(f).unwrap_or_else(|| "—".into())
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
        } => format!("rendered with {estimator} at {spp} spp, seed {seed} (`reference.exr`)"),
    };
    let repeats = rows.first().map_or(1, |r| r.seeds.len());
    let _ = writeln!(
        s,
        "- Reference: {reference}; {}x{} pixels.\n- Baseline: {}. Renderer: {}.\n- {done}\n",
        m.reference.width,
        m.reference.height,
        m.baseline,
        if m.renderer.is_empty() {
            "—"
        } else {
            &m.renderer
        },
    );
    let _ = writeln!(
        s,
        "Improvement = RMSE_baseline / RMSE_method and Overhead = time_method / \
         time_baseline − 1 at equal spp; Speed Up = efficiency_method / \
         efficiency_baseline, efficiency = 1 / (MSE × time) (DESIGN.md §4). RMSE and \
         relMSE = mean (x − ref)² / (ref² + {REL_EPSILON}) over all pixels and channels, \
         unclamped; MSE and time are means over {repeats} seed(s) per point.\n"
    );
    let head =
        "| Estimator | spp | RMSE | relMSE | Time (s) | Improvement | Speed Up | Overhead |\n\
                |---|---:|---:|---:|---:|---:|---:|---:|\n";
    let line = |s: &mut String, r: &Row| {
        let c = cmp
            .iter()
            .find(|c| c.estimator == r.estimator && c.spp == r.spp);
        let _ = writeln!(
            s,
            "| {} | {} | {:.4e} | {:.4e} | {:.4} | {} | {} | {} |",
            r.estimator,
            r.spp,
            r.rmse,
            r.relmse,
            r.time_s,
            ratio_cell(c.and_then(|c| c.improvement)),
            ratio_cell(c.and_then(|c| c.speed_up)),
            overhead_cell(c.and_then(|c| c.overhead)),
        );
    };
    let _ = write!(s, "## Every sample count\n\n{head}");
    for r in rows {
        line(&mut s, r);
    }
    if let Some(max) = rows.iter().map(|r| r.spp).max() {
        let _ = write!(s, "\n## At the largest sample count ({max} spp)\n\n{head}");
        for r in rows.iter().filter(|r| r.spp == max) {
            line(&mut s, r);
        }
    }
    s
}
