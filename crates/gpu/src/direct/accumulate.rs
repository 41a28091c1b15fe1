//! The render's sums on the CPU: a read-back wave's hit and draw records added to the
//! pixels' records through the render's [`Tally`].

use crate::record::{draw_words, DRAW_HEAD_WORDS};
use state::{RayCounts, ShadedDraw, ShadedVertex, Tally};

/// Adds one slot's hit record `hw` and its draw records (`vertex(depth)`: the
/// `per_slot` records of that depth) to its pixel's record `rec` through the render's
/// [`Tally`] (the render's sums on the CPU), and counts its rays. `pdfs` is
/// scratch of `depths · n_draws · T` words. The slot must not have overflowed.
#[allow(clippy::too_many_arguments)]
pub fn add_slot<'v>(
    acc: &Tally,
    rec: &mut [f64],
    index: u32,
    hw: &[f32],
    vertex: &dyn Fn(u32) -> &'v [f32],
    n_draws: u32,
    depths: u32,
    pdfs: &mut [f64],
    rays: &mut RayCounts,
) {
    let t_count = acc.techniques.len();
    let words = draw_words(t_count as u32);
    rays.camera += 1;
    // The first hit's depth, normal and albedo (words 8 and 9).
    let aovs = [hw[35], hw[32], hw[33], hw[34], hw[36], hw[37], hw[38]].map(f64::from);
    if acc.aov_integrator() {
        acc.add_aov_sample(rec, index, &aovs);
        return;
    }
    let outside = [hw[12], hw[13], hw[14]].map(f64::from);
    // Vertices shaded: draw 0 of each has a status until the path ended.
    let shaded = (0..depths)
        .take_while(|&k| n_draws > 0 && vertex(k)[7] != 0.0)
        .count();
    for k in 0..shaded {
        for (j, d) in vertex(k as u32).chunks_exact(words).enumerate() {
            match d[7] {
                4.0 | 5.0 => rays.shadow += 1,
                6.0 => rays.secondary += 1,
                _ => {}
            }
            if j < n_draws as usize {
                let at = (k * n_draws as usize + j) * t_count;
                for (t, p) in pdfs[at..at + t_count].iter_mut().enumerate() {
                    *p = f64::from(d[DRAW_HEAD_WORDS + t]);
                }
            }
        }
    }
    let mut vertices: Vec<Vec<ShadedDraw>> = Vec::with_capacity(shaded);
    let mut vertex_outside = vec![[0.0f64; 3]; shaded];
    let mut mis = vec![true; shaded];
    for k in 0..shaded {
        let records = vertex(k as u32);
        // Word 11 of a record: 1 a delta-lobe draw (outside MIS), 2 a purely
        // specular vertex (no MIS at all); in per-light mode, 4 × (1 + the MIS
        // light the draw's ray reaches) added.
        let flags = |d: &[f32]| d[11] as u32;
        mis[k] = flags(records) & 2 == 0;
        let sum = &mut vertex_outside[k];
        for (j, d) in records.chunks_exact(words).enumerate() {
            // Outside MIS: point and spot lights (j > Σ n_k) and delta lobes,
            // where their light arrived.
            let outside = j > n_draws as usize || flags(d) & 1 != 0;
            if outside && (d[7] == 4.0 || d[7] == 6.0) {
                for c in 0..3 {
                    sum[c] += f64::from(d[8 + c]);
                }
            }
        }
        let draws = records
            .chunks_exact(words)
            .take(if mis[k] { n_draws as usize } else { 0 })
            .enumerate()
            .map(|(j, d)| {
                if d[7] == 1.0 || flags(d) & 1 != 0 {
                    return ShadedDraw::Failed;
                }
                let f = if d[7] == 4.0 || d[7] == 6.0 {
                    [d[8], d[9], d[10]].map(f64::from)
                } else {
                    [0.0; 3]
                };
                let at = (k * n_draws as usize + j) * t_count;
                ShadedDraw::Sample {
                    f,
                    pdfs: &pdfs[at..at + t_count],
                    light: (flags(d) >> 2).checked_sub(1).map(|l| l as usize),
                }
            })
            .collect();
        vertices.push(draws);
    }
    let refs: Vec<ShadedVertex> = vertices
        .iter()
        .zip(&vertex_outside)
        .zip(&mis)
        .map(|((draws, &outside), &mis)| ShadedVertex {
            outside,
            draws,
            mis,
        })
        .collect();
    acc.add(rec, index, outside, &refs, &aovs);
}
