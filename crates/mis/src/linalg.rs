//! Small dense linear algebra for the T×T technique matrix of optimal MIS.
//!
//! The matrix `Â` is symmetric positive semi-definite and often singular (two proportional
//! pdfs, a technique that never fires, b = 0; Kondapaneni et al. 2019, §6). [`solve`] adds a
//! ridge `μ = ρ·tr(Â)/T` to the diagonal (the estimators use ρ = [`relative_ridge`]) and
//! factors with Cholesky; when a pivot collapses (ρ = 0 on a singular matrix) it falls back to the minimum-norm least-squares solution from
//! a cyclic Jacobi eigen-decomposition (a pseudo-inverse). Sizes are tiny (T ≲ 8), so
//! everything is plain loops over packed storage.

/// Words of stack scratch (4.1 KiB): the pseudo-inverse's `T + 2T²` at T = 16; longer
/// buffers go to the heap.
const STACK_WORDS: usize = 16 + 2 * 16 * 16;

/// Runs `f` on a zeroed scratch buffer of `len` words, on the stack where it fits: the
/// solves run once per pixel (and per re-solve) and must not allocate for usual T.
/// Sizes come in tiers so that zeroing costs what the solve needs, not 4 KiB (T = 3
/// needs at most 21 words).
#[inline]
pub(crate) fn with_scratch<R>(len: usize, f: impl FnOnce(&mut [f64]) -> R) -> R {
    if len <= 32 {
        f(&mut [0.0; 32][..len])
    } else if len <= 128 {
        f(&mut [0.0; 128][..len])
    } else if len <= STACK_WORDS {
        f(&mut [0.0; STACK_WORDS][..len])
    } else {
        f(&mut vec![0.0; len])
    }
}

/// Number of entries of a packed symmetric `t × t` matrix (lower triangle, row by row).
#[inline]
pub const fn packed_len(t: usize) -> usize {
    t * (t + 1) / 2
}

/// Index of entry `(i, j)` of a packed symmetric matrix; either order of `i, j`.
#[inline]
pub const fn packed_index(i: usize, j: usize) -> usize {
    if i >= j {
        i * (i + 1) / 2 + j
    } else {
        j * (j + 1) / 2 + i
    }
}

/// Relative pivot (and eigenvalue) threshold below which the matrix counts as singular:
/// a pivot `d_j ≤ PIVOT_TOL · M_jj` would amplify rounding by more than 1/PIVOT_TOL.
pub const PIVOT_TOL: f64 = 1e-10;

/// The relative ridge for [`solve`] after `iterations` iterations: `λ/N`.
///
/// Â is a sum over N iterations, so `μ = (λ/N)·tr(Â)/T` is a constant `λ·tr(Ā)/T` in the units
/// of one iteration's mean `Ā = Â/N`: a prior worth λ iterations of an isotropic `Ā`. It
/// regularises the first iterations, when `Â` is noisy and nearly singular, and fades as data
/// accrue, so the estimator tends to the unregularised optimum. A constant relative ridge
/// (μ ∝ tr(Â)) costs up to 20× RMSE at N = 64 on near-degenerate problems (`docs/mis.md`).
#[inline]
pub fn relative_ridge(lambda: f64, iterations: u64) -> f64 {
    lambda / iterations.max(1) as f64
}

/// How [`solve`] obtained α.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolveMethod {
    /// Cholesky of `Â + μI` succeeded.
    Cholesky,
    /// Cholesky failed; minimum-norm least squares through the eigen-decomposition.
    PseudoInverse,
    /// No information (zero or non-finite trace): α = 0, the balance heuristic.
    Zero,
}

/// Solves `(Â + μI) α = b` for every right-hand side, `μ = ridge · tr(Â)/T` (ridge = ρ).
///
/// `a` is packed symmetric (see [`packed_index`]), `rhs` and `alpha` hold one length-`t`
/// column per channel (`rhs[c·t + i]`). Always writes finite values to `alpha`.
pub fn solve(a: &[f64], t: usize, ridge: f64, rhs: &[f64], alpha: &mut [f64]) -> SolveMethod {
    // The common sizes with constant bounds, so that the factorisation's loops unroll
    // (the same operations in the same order: bit for bit).
    match t {
        2 => solve_sized(a, 2, ridge, rhs, alpha),
        3 => solve_sized(a, 3, ridge, rhs, alpha),
        4 => solve_sized(a, 4, ridge, rhs, alpha),
        _ => solve_sized(a, t, ridge, rhs, alpha),
    }
}

/// [`solve`], inlined where `t` is a constant.
#[inline(always)]
fn solve_sized(a: &[f64], t: usize, ridge: f64, rhs: &[f64], alpha: &mut [f64]) -> SolveMethod {
    assert_eq!(a.len(), packed_len(t), "packed matrix length");
    assert_eq!(rhs.len(), alpha.len(), "rhs and alpha lengths");
    assert!(
        t > 0 && rhs.len().is_multiple_of(t),
        "rhs holds whole columns"
    );
    assert!(ridge >= 0.0, "ridge must be non-negative");
    let trace: f64 = (0..t).map(|i| a[packed_index(i, i)]).sum();
    if !(trace > 0.0 && trace.is_finite()) || rhs.iter().any(|v| !v.is_finite()) {
        alpha.fill(0.0);
        return SolveMethod::Zero;
    }
    let mu = ridge * trace / t as f64;
    // Up to T = 4 on the stack here, not through `with_scratch`'s closure: compiled once
    // for every T, that closure kept the loops general.
    if a.len() <= packed_len(4) {
        let mut m = [0.0; packed_len(4)];
        return factor_and_solve(&mut m[..a.len()], a, t, mu, rhs, alpha);
    }
    with_scratch(a.len(), |m| factor_and_solve(m, a, t, mu, rhs, alpha))
}

/// [`solve`]'s factorisation of `Â + μI` in scratch `m` (`a.len()` words), with the
/// pseudo-inverse where Cholesky fails.
#[inline(always)]
fn factor_and_solve(
    m: &mut [f64],
    a: &[f64],
    t: usize,
    mu: f64,
    rhs: &[f64],
    alpha: &mut [f64],
) -> SolveMethod {
    let ridged = |m: &mut [f64]| {
        m.copy_from_slice(a);
        for i in 0..t {
            m[packed_index(i, i)] += mu;
        }
    };
    ridged(m);
    if cholesky_in_place(m, t) {
        if rhs.len() == 3 * t {
            cholesky_solve_3(m, t, rhs, alpha);
        } else {
            for (col, out) in rhs.chunks_exact(t).zip(alpha.chunks_exact_mut(t)) {
                cholesky_solve(m, t, col, out);
            }
        }
        if alpha.iter().all(|v| v.is_finite()) {
            return SolveMethod::Cholesky;
        }
    }
    // The factorisation overwrote `m` (fully or up to the failing pivot): rebuild it.
    ridged(m);
    if pseudo_inverse_solve(m, t, rhs, alpha) {
        SolveMethod::PseudoInverse
    } else {
        alpha.fill(0.0);
        SolveMethod::Zero
    }
}

/// Overwrites packed `m` with its Cholesky factor L (lower, `m = L Lᵀ`). Returns false
/// when a pivot falls below [`PIVOT_TOL`] times its diagonal entry (numerically singular).
#[inline(always)]
fn cholesky_in_place(m: &mut [f64], t: usize) -> bool {
    // Row i of the packed lower triangle is m[i(i+1)/2 ..][..=i]: the sums run over the
    // rows' leading parts as slices, in the same order as indexed loops would.
    let mut rj = 0;
    for j in 0..t {
        let diag = m[rj + j];
        let mut d = diag;
        for &l in &m[rj..rj + j] {
            d -= l * l;
        }
        if !(d > PIVOT_TOL * diag && d.is_finite()) {
            return false;
        }
        let l_jj = d.sqrt();
        m[rj + j] = l_jj;
        // Row i + 1 starts i + 1 words after row i.
        let mut ri = rj + j + 1;
        for i in j + 1..t {
            let (head, tail) = m.split_at_mut(ri);
            let (lj, li) = (&head[rj..rj + j], &mut tail[..=j]);
            let mut v = li[j];
            for k in 0..j {
                v -= li[k] * lj[k];
            }
            li[j] = v / l_jj;
            ri += i + 1;
        }
        rj += j + 1;
    }
    true
}

/// Solves `L Lᵀ x = b` with the packed factor from [`cholesky_in_place`].
#[inline(always)]
fn cholesky_solve(l: &[f64], t: usize, b: &[f64], x: &mut [f64]) {
    for i in 0..t {
        let ri = packed_index(i, 0);
        let row = &l[ri..=ri + i];
        let mut v = b[i];
        for (a, xk) in row[..i].iter().zip(&x[..i]) {
            v -= a * xk;
        }
        x[i] = v / row[i];
    }
    for i in (0..t).rev() {
        let mut v = x[i];
        // Down column i: entry (k, i) is i past row k's start, and row k + 1 starts
        // k + 1 words after row k.
        let mut at = packed_index(i + 1, i);
        for (k, xk) in x.iter().enumerate().take(t).skip(i + 1) {
            v -= l[at] * xk;
            at += k + 1;
        }
        x[i] = v / l[packed_index(i, i)];
    }
}

/// [`cholesky_solve`] for three right-hand sides (RGB) at once: each entry of L loaded
/// once for the three, and a third of the loops; each column's operations in the same
/// order as on its own, so the same values bit for bit.
#[inline(always)]
fn cholesky_solve_3(l: &[f64], t: usize, b: &[f64], x: &mut [f64]) {
    let (b, x) = (&b[..3 * t], &mut x[..3 * t]);
    let (x0, rest) = x.split_at_mut(t);
    let (x1, x2) = rest.split_at_mut(t);
    for i in 0..t {
        let ri = packed_index(i, 0);
        let row = &l[ri..=ri + i];
        let (mut v0, mut v1, mut v2) = (b[i], b[t + i], b[2 * t + i]);
        for k in 0..i {
            let a = row[k];
            v0 -= a * x0[k];
            v1 -= a * x1[k];
            v2 -= a * x2[k];
        }
        let d = row[i];
        (x0[i], x1[i], x2[i]) = (v0 / d, v1 / d, v2 / d);
    }
    for i in (0..t).rev() {
        let (mut v0, mut v1, mut v2) = (x0[i], x1[i], x2[i]);
        let mut at = packed_index(i + 1, i);
        for k in i + 1..t {
            let a = l[at];
            v0 -= a * x0[k];
            v1 -= a * x1[k];
            v2 -= a * x2[k];
            at += k + 1;
        }
        let d = l[packed_index(i, i)];
        (x0[i], x1[i], x2[i]) = (v0 / d, v1 / d, v2 / d);
    }
}

/// Eigen-decomposition of a packed symmetric matrix by cyclic Jacobi rotations (Golub &
/// Van Loan, §8.5). Returns (eigenvalues, eigenvectors as columns of a row-major t×t).
pub fn symmetric_eigen(m: &[f64], t: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut values, mut vectors) = (vec![0.0; t], vec![0.0; t * t]);
    with_scratch(t * t, |a| {
        symmetric_eigen_in(m, t, a, &mut values, &mut vectors)
    });
    (values, vectors)
}

/// [`symmetric_eigen`] into caller storage: `a` (t², scratch), `values` (t), `v` (t²).
fn symmetric_eigen_in(m: &[f64], t: usize, a: &mut [f64], values: &mut [f64], v: &mut [f64]) {
    for i in 0..t {
        for j in 0..t {
            a[i * t + j] = m[packed_index(i, j)];
        }
    }
    v.fill(0.0);
    for i in 0..t {
        v[i * t + i] = 1.0;
    }
    let scale: f64 = a.iter().map(|x| x * x).sum();
    for _sweep in 0..64 {
        let off: f64 = (0..t)
            .flat_map(|i| (0..t).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i * t + j] * a[i * t + j])
            .sum();
        if off <= 1e-32 * scale || off == 0.0 {
            break;
        }
        for p in 0..t {
            for q in p + 1..t {
                let apq = a[p * t + q];
                if apq == 0.0 {
                    continue;
                }
                let theta = (a[q * t + q] - a[p * t + p]) / (2.0 * apq);
                let tan = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let c = 1.0 / (tan * tan + 1.0).sqrt();
                let s = tan * c;
                for k in 0..t {
                    let (akp, akq) = (a[k * t + p], a[k * t + q]);
                    a[k * t + p] = c * akp - s * akq;
                    a[k * t + q] = s * akp + c * akq;
                }
                for k in 0..t {
                    let (apk, aqk) = (a[p * t + k], a[q * t + k]);
                    a[p * t + k] = c * apk - s * aqk;
                    a[q * t + k] = s * apk + c * aqk;
                }
                for k in 0..t {
                    let (vkp, vkq) = (v[k * t + p], v[k * t + q]);
                    v[k * t + p] = c * vkp - s * vkq;
                    v[k * t + q] = s * vkp + c * vkq;
                }
            }
        }
    }
    for (i, value) in values.iter_mut().enumerate() {
        *value = a[i * t + i];
    }
}

/// Minimum-norm least-squares solution `x = M⁺ b` for each column of `rhs`, eigenvalues
/// below [`PIVOT_TOL`]·max treated as zero. Returns false if the result is not finite.
#[inline(never)]
fn pseudo_inverse_solve(m: &[f64], t: usize, rhs: &[f64], alpha: &mut [f64]) -> bool {
    with_scratch(t + 2 * t * t, |buf| {
        let (values, rest) = buf.split_at_mut(t);
        let (vectors, a) = rest.split_at_mut(t * t);
        symmetric_eigen_in(m, t, a, values, vectors);
        pseudo_inverse_apply(values, vectors, t, rhs, alpha)
    })
}

/// `x = V diag(1/λ) Vᵀ b` over the eigenvalues above the threshold.
fn pseudo_inverse_apply(
    values: &[f64],
    vectors: &[f64],
    t: usize,
    rhs: &[f64],
    alpha: &mut [f64],
) -> bool {
    let max = values.iter().fold(0.0f64, |acc, &v| acc.max(v));
    alpha.fill(0.0);
    if !(max > 0.0 && max.is_finite()) {
        return false;
    }
    for (col, out) in rhs.chunks_exact(t).zip(alpha.chunks_exact_mut(t)) {
        for (j, &value) in values.iter().enumerate() {
            if value <= PIVOT_TOL * max {
                continue;
            }
            let proj: f64 = (0..t).map(|k| vectors[k * t + j] * col[k]).sum::<f64>() / value;
            for k in 0..t {
                out[k] += proj * vectors[k * t + j];
            }
        }
    }
    alpha.iter().all(|v| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sizes `solve` unrolls (T = 2, 3, 4) give bit for bit the general loops' α.
    #[test]
    fn unrolled_sizes_solve_as_the_general_loops() {
        for t in 2..=4 {
            // A well-conditioned matrix and one whose Cholesky fails (rank one).
            for rank_one in [false, true] {
                let mut a = vec![0.0; packed_len(t)];
                for i in 0..t {
                    for j in 0..=i {
                        let v = if rank_one {
                            (i + 1) as f64 * (j + 1) as f64
                        } else {
                            1.0 / (1.0 + i as f64 + j as f64) + f64::from(u8::from(i == j))
                        };
                        a[packed_index(i, j)] = v;
                    }
                }
                let rhs: Vec<f64> = (0..3 * t).map(|i| (i as f64 * 0.37).sin()).collect();
                let (mut fast, mut general) = (vec![0.0; 3 * t], vec![0.0; 3 * t]);
                let m1 = solve(&a, t, 1e-3, &rhs, &mut fast);
                let m2 = solve_sized(&a, std::hint::black_box(t), 1e-3, &rhs, &mut general);
                assert_eq!(m1, m2);
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&fast), bits(&general), "T = {t}, rank one: {rank_one}");
            }
        }
    }

    /// Three right-hand sides solved together (RGB, `cholesky_solve_3`) give bit for
    /// bit what each gives solved alone, T = 1 to 12.
    #[test]
    fn three_columns_solve_as_each_alone() {
        for t in 1..=12 {
            let mut a = vec![0.0; packed_len(t)];
            for i in 0..t {
                for j in 0..=i {
                    let v = ((i * 7 + j * 3) as f64 * 0.61).cos() * 0.3;
                    a[packed_index(i, j)] = v + if i == j { t as f64 } else { 0.0 };
                }
            }
            let rhs: Vec<f64> = (0..3 * t).map(|i| (i as f64 * 0.37).sin()).collect();
            let mut together = vec![0.0; 3 * t];
            assert_eq!(
                solve(&a, t, 1e-3, &rhs, &mut together),
                SolveMethod::Cholesky
            );
            for c in 0..3 {
                let mut alone = vec![0.0; t];
                solve(&a, t, 1e-3, &rhs[c * t..(c + 1) * t], &mut alone);
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&together[c * t..(c + 1) * t]), bits(&alone), "T = {t}");
            }
        }
    }

    fn pack(full: &[&[f64]]) -> Vec<f64> {
        let t = full.len();
        let mut m = vec![0.0; packed_len(t)];
        for i in 0..t {
            for j in 0..=i {
                m[packed_index(i, j)] = full[i][j];
            }
        }
        m
    }

    #[test]
    fn cholesky_solves_a_known_system() {
        // [[4,2,0],[2,5,1],[0,1,3]] x = [2,3,4]: x = (18, 8, 56)/44 by Cramer's rule.
        let a = pack(&[&[4.0, 2.0, 0.0], &[2.0, 5.0, 1.0], &[0.0, 1.0, 3.0]]);
        let b = [2.0, 3.0, 4.0];
        let mut x = [0.0; 3];
        assert_eq!(solve(&a, 3, 0.0, &b, &mut x), SolveMethod::Cholesky);
        let expect = [18.0 / 44.0, 8.0 / 44.0, 56.0 / 44.0];
        for (v, e) in x.iter().zip(expect) {
            assert!((v - e).abs() < 1e-14, "{x:?}");
        }
    }

    #[test]
    fn jacobi_reconstructs_the_matrix() {
        let full: [&[f64]; 4] = [
            &[4.0, 1.0, -2.0, 0.5],
            &[1.0, 3.0, 0.0, 1.0],
            &[-2.0, 0.0, 5.0, 2.0],
            &[0.5, 1.0, 2.0, 1.0],
        ];
        let m = pack(&full);
        let (values, v) = symmetric_eigen(&m, 4);
        for i in 0..4 {
            for j in 0..4 {
                let r: f64 = (0..4)
                    .map(|k| v[i * 4 + k] * values[k] * v[j * 4 + k])
                    .sum();
                assert!((r - full[i][j]).abs() < 1e-12, "({i},{j}) {r}");
                let o: f64 = (0..4).map(|k| v[k * 4 + i] * v[k * 4 + j]).sum();
                assert!((o - f64::from(i == j)).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn singular_matrix_gives_the_minimum_norm_solution() {
        // Two identical rows (proportional pdfs): α₁ + α₂ is determined, the split is not;
        // the minimum-norm solution splits evenly. [[1,1],[1,1]] α = [2,2] → α = [1,1].
        let a = pack(&[&[1.0, 1.0], &[1.0, 1.0]]);
        let mut x = [0.0; 2];
        assert_eq!(
            solve(&a, 2, 0.0, &[2.0, 2.0], &mut x),
            SolveMethod::PseudoInverse
        );
        assert!(
            (x[0] - 1.0).abs() < 1e-12 && (x[1] - 1.0).abs() < 1e-12,
            "{x:?}"
        );
        // A zero row and column (a technique that never fired): its α is 0.
        let a = pack(&[&[2.0, 0.0], &[0.0, 0.0]]);
        assert_eq!(
            solve(&a, 2, 0.0, &[4.0, 0.0], &mut x),
            SolveMethod::PseudoInverse
        );
        assert_eq!(x, [2.0, 0.0]);
    }

    #[test]
    fn ridge_and_degenerate_inputs_stay_finite() {
        let a = pack(&[&[1.0, 1.0], &[1.0, 1.0]]);
        let mut x = [0.0; 4];
        // Ridge μ = 0.5·2/2 = 0.5: (A + μI) x = b, two channels.
        assert_eq!(
            solve(&a, 2, 0.5, &[2.0, 2.0, 0.0, 0.0], &mut x),
            SolveMethod::Cholesky
        );
        assert!(
            (x[0] - 0.8).abs() < 1e-14 && (x[1] - 0.8).abs() < 1e-14,
            "{x:?}"
        );
        assert_eq!(&x[2..], &[0.0, 0.0]);
        let zero = vec![0.0; 3];
        let mut y = [7.0; 2];
        assert_eq!(solve(&zero, 2, 0.0, &[1.0, 1.0], &mut y), SolveMethod::Zero);
        assert_eq!(y, [0.0, 0.0]);
        let nan = pack(&[&[f64::NAN, 0.0], &[0.0, 1.0]]);
        assert_eq!(solve(&nan, 2, 0.0, &[1.0, 1.0], &mut y), SolveMethod::Zero);
    }
}
