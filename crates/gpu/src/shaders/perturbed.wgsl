// Perturbed quadrics: the first t in (t_min, t_max) where F' = F + Σ f_i·max(q_i, 0)³
// changes sign (GPU.md §6.1). A statement-for-statement port of frep's f32 scan
// (frep::perturbed::scan, poly, along; the twin is PerturbedView::first_crossing_f32_gpu):
// clip to the object's bounds, candidates from a stack-free escape-index BVH walk (pre-order,
// so ascending leaf position), an active set of at most K, breakpoints taken by repeated
// min-selection, each piece as a degree ≤ 6 polynomial with its rounding bound, converted to
// Bernstein form and searched left first with an explicit interval stack. An overflowing
// range is halved, left first, at most MAX_SPLITS deep; past that the ray is reported as
// overflowing (status 2), never as a miss. Every loop iteration adds to `loops` (§3.1);
// fixed-size work on 3, 7 or 10 values is written out, not looped. Each costly function
// (piece, first_negative_bounded, refine) has one call site: llvmpipe inlines every call,
// and a shader with several took minutes to compile.
// Needs the structs of layout.rs and these bindings, declared by the kernel:
//   objects: array<GpuObject>, quadrics: array<GpuQuadric>,
//   perturbations: array<GpuPerturbation>, nodes: array<GpuBvhNode>, items: array<GpuItemBox>.

const K: u32 = 32u;            // frep::perturbed::GPU_ACTIVE
const MAX_SPLITS: u32 = 4u;    // frep::perturbed::GPU_SPLITS
const MAX_BREAKS: u32 = 64u;   // 2·K: a quadratic has at most two real roots
const MAX_DEPTH: u32 = 48u;    // frep::poly::MAX_DEPTH
const EPS: f32 = 0x1p-23f;     // f32::EPSILON
const MIN_POS: f32 = 0x1p-126f; // f32::MIN_POSITIVE
const GROWTH: f32 = 8.0;       // scan.rs GROWTH
const ROUNDING: f32 = 32.0;    // scan.rs ROUNDING
const GROWTH_CAP: u32 = 64u;   // sub-pieces of an unbounded piece (f32 reaches ∞ within 44)

// C(j,k)/C(n,k) at [49n + 7j + k], the f64 table of poly.rs rounded to f32 (Farouki &
// Rajan 1987, eq. 9).
const RATIO = array<f32, 343>(
    0x1.000000p+0f, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0x1.000000p+0f, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0x1.000000p-1f, 0.0, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0x1.000000p+0f, 0x1.000000p+0f, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0x1.555556p-2f, 0.0, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0x1.555556p-1f, 0x1.555556p-2f, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0x1.000000p+0f, 0x1.000000p+0f, 0x1.000000p+0f, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0x1.000000p-2f, 0.0, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0x1.000000p-1f, 0x1.555556p-3f, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0x1.800000p-1f, 0x1.000000p-1f, 0x1.000000p-2f, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0x1.000000p+0f, 0x1.000000p+0f, 0x1.000000p+0f, 0x1.000000p+0f, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0x1.99999ap-3f, 0.0, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0x1.99999ap-2f, 0x1.99999ap-4f, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0x1.333334p-1f, 0x1.333334p-2f, 0x1.99999ap-4f, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0x1.99999ap-1f, 0x1.333334p-1f, 0x1.99999ap-2f, 0x1.99999ap-3f, 0.0, 0.0,
    0x1.000000p+0f, 0x1.000000p+0f, 0x1.000000p+0f, 0x1.000000p+0f, 0x1.000000p+0f, 0x1.000000p+0f, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0x1.555556p-3f, 0.0, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0x1.555556p-2f, 0x1.111112p-4f, 0.0, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0x1.000000p-1f, 0x1.99999ap-3f, 0x1.99999ap-5f, 0.0, 0.0, 0.0,
    0x1.000000p+0f, 0x1.555556p-1f, 0x1.99999ap-2f, 0x1.99999ap-3f, 0x1.111112p-4f, 0.0, 0.0,
    0x1.000000p+0f, 0x1.aaaaaap-1f, 0x1.555556p-1f, 0x1.000000p-1f, 0x1.555556p-2f, 0x1.555556p-3f, 0.0,
    0x1.000000p+0f, 0x1.000000p+0f, 0x1.000000p+0f, 0x1.000000p+0f, 0x1.000000p+0f, 0x1.000000p+0f, 0x1.000000p+0f,
);

var<private> loops: u32;
var<private> ro: vec3<f32>;
var<private> rd: vec3<f32>;
var<private> rinv: vec3<f32>;
var<private> ray_tmin: f32;
var<private> ray_tmax: f32;
var<private> obj: GpuObject;
var<private> base_c: array<f32, 10>;

// The active set: perturbation index, positive set (≤ 2 intervals), interval count.
var<private> act_p: array<u32, K>;
var<private> act_set: array<vec4<f32>, K>;
var<private> act_n: array<u32, K>;
var<private> n_act: u32;
var<private> brk: array<f32, MAX_BREAKS>;
var<private> n_brk: u32;
// The sign of F' before the current piece (0 while unknown).
var<private> scan_s: f32;

// The piece under construction: power-form polynomial and rounding bound, degree n.
var<private> pc: array<f32, 7>;
var<private> pm: array<f32, 7>;
var<private> pn: u32;

// first_negative_bounded's pending right halves.
var<private> st_b: array<array<f32, 7>, 49>;
var<private> st_e: array<array<f32, 7>, 49>;
var<private> st_u0: array<f32, 49>;
var<private> st_u1: array<f32, 49>;
var<private> st_d: array<u32, 49>;

// Rust's f32::signum: ±1 by the sign bit (so ±0 → ±1), NaN stays.
fn signum(x: f32) -> f32 {
    if (is_nan(x)) { return x; }
    return select(1.0, -1.0, (bitcast<u32>(x) & 0x80000000u) != 0u);
}
// Rust's f32::next_up / next_down (denormals kept, as lavapipe keeps them).
fn next_up(x: f32) -> f32 {
    if (is_nan(x) || x == inf()) { return x; }
    let b = bitcast<u32>(x);
    if ((b & 0x7fffffffu) == 0u) { return bitcast<f32>(1u); }
    if ((b & 0x80000000u) == 0u) { return bitcast<f32>(b + 1u); }
    return bitcast<f32>(b - 1u);
}
fn next_down(x: f32) -> f32 { return -next_up(-x); }

// One axis of the slab test: (near, far) narrowed by the slab [lo, hi].
fn slab_axis(nf: vec2<f32>, lo: f32, hi: f32, o: f32, inv: f32) -> vec2<f32> {
    let a = (lo - o) * inv;
    let b = (hi - o) * inv;
    return vec2<f32>(rmax(nf.x, rmin(a, b)), rmin(nf.y, rmax(a, b)));
}

// The f32 slab test (frep::ray::slab_f32): (1, near, far) when o + t·d, t ∈ [t0, t1],
// meets the box, else x = 0.
fn slab(lo: vec3<f32>, hi: vec3<f32>, t0: f32, t1: f32) -> vec3<f32> {
    var nf = vec2<f32>(t0, t1);
    nf = slab_axis(nf, lo.x, hi.x, ro.x, rinv.x);
    nf = slab_axis(nf, lo.y, hi.y, ro.y, rinv.y);
    nf = slab_axis(nf, lo.z, hi.z, ro.z, rinv.z);
    return vec3<f32>(select(0.0, 1.0, nf.x <= nf.y), nf.x, nf.y);
}

// Element-wise helpers on 7 coefficients, written out (fixed-size work is no loop).
fn add7(a: array<f32, 7>, b: array<f32, 7>) -> array<f32, 7> {
    return array<f32, 7>(a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3], a[4] + b[4], a[5] + b[5], a[6] + b[6]);
}
fn mul7(a: array<f32, 7>, k: f32) -> array<f32, 7> {
    return array<f32, 7>(a[0] * k, a[1] * k, a[2] * k, a[3] * k, a[4] * k, a[5] * k, a[6] * k);
}

// --- along.rs ---------------------------------------------------------------------

fn q_eval(c: array<f32, 10>, p: vec3<f32>) -> f32 {
    let x = p.x;
    let y = p.y;
    let z = p.z;
    return x * (c[0] * x + c[3] * y + c[5] * z + c[6]) + y * (c[1] * y + c[4] * z + c[7]) + z * (c[2] * z + c[8]) + c[9];
}

// q about p along d, as a quadratic in s = t − t₀: [q(p), ∇q(p)·d, dᵀAd].
fn q_local(c: array<f32, 10>, p: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    let x = p.x;
    let y = p.y;
    let z = p.z;
    let gx = 2.0 * c[0] * x + c[3] * y + c[5] * z + c[6];
    let gy = 2.0 * c[1] * y + c[3] * x + c[4] * z + c[7];
    let gz = 2.0 * c[2] * z + c[4] * y + c[5] * x + c[8];
    let u = d.x;
    let v = d.y;
    let w = d.z;
    let curv = c[0] * u * u + c[1] * v * v + c[2] * w * w + c[3] * u * v + c[4] * v * w + c[5] * u * w;
    return vec3<f32>(q_eval(c, p), gx * u + gy * v + gz * w, curv);
}

// The same sums with every term made positive (q_local_mag).
fn q_local_mag(c: array<f32, 10>, p: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    let a = array<f32, 10>(abs(c[0]), abs(c[1]), abs(c[2]), abs(c[3]), abs(c[4]), abs(c[5]), abs(c[6]), abs(c[7]), abs(c[8]), abs(c[9]));
    return q_local(a, abs(p), abs(d));
}

struct PosSet { s: vec4<f32>, n: u32 }

// {t : a0 + a1·t + a2·t² ≥ 0} as ≤ 2 intervals, isolated points dropped (positive_set;
// Numerical Recipes §5.6).
fn positive_set(a: vec3<f32>) -> PosSet {
    let a0 = a.x;
    let a1 = a.y;
    let a2 = a.z;
    let big = inf();
    if (a2 == 0.0) {
        if (a1 == 0.0) {
            if (a0 >= 0.0) { return PosSet(vec4<f32>(-big, big, 0.0, 0.0), 1u); }
            return PosSet(vec4<f32>(0.0), 0u);
        }
        let r = -a0 / a1;
        if (a1 > 0.0) { return PosSet(vec4<f32>(r, big, 0.0, 0.0), 1u); }
        return PosSet(vec4<f32>(-big, r, 0.0, 0.0), 1u);
    }
    let disc = a1 * a1 - 4.0 * a2 * a0;
    if (is_nan(disc) || disc <= 0.0) {
        if (a2 > 0.0) { return PosSet(vec4<f32>(-big, big, 0.0, 0.0), 1u); }
        return PosSet(vec4<f32>(0.0), 0u);
    }
    let q = -0.5 * (a1 + signum(a1) * sqrt(disc));
    var r1: f32;
    var r2: f32;
    if (q == 0.0) {
        let r = sqrt(-a0 / a2);
        r1 = -r;
        r2 = r;
    } else {
        let x = q / a2;
        let y = a0 / q;
        r1 = rmin(x, y);
        r2 = rmax(x, y);
    }
    if (a2 < 0.0) { return PosSet(vec4<f32>(r1, r2, 0.0, 0.0), 1u); }
    return PosSet(vec4<f32>(-big, r1, r2, big), 2u);
}

// --- scan.rs: candidates ------------------------------------------------------------

// Active::on and its breaks for perturbation p on (lo, hi); false when the set is full.
fn offer(p: u32, lo: f32, hi: f32) -> bool {
    let pert = perturbations[p];
    if (pert.f == 0.0) { return true; }
    let ps = positive_set(q_local(pert.q, ro, rd));
    var kept = vec4<f32>(0.0);
    var k = 0u;
    for (var j = 0u; j < ps.n; j++) {
        loops++;
        let a = ps.s[2u * j];
        let b = ps.s[2u * j + 1u];
        if (a < hi && b > lo) {
            kept[2u * k] = a;
            kept[2u * k + 1u] = b;
            k++;
        }
    }
    if (k == 0u) { return true; }
    if (n_act == K) { return false; }
    act_p[n_act] = p;
    act_set[n_act] = kept;
    act_n[n_act] = k;
    n_act++;
    for (var j = 0u; j < 2u * k; j++) {
        loops++;
        let e = kept[j];
        if (e > lo && e < hi) {
            brk[n_brk] = e;
            n_brk++;
        }
    }
    return true;
}

// The active set and breaks of [lo, hi], queried widened by an ulp: unbounded items,
// then the escape-index walk (GPU.md §6.1). False on overflow.
fn collect(lo: f32, hi: f32) -> bool {
    n_act = 0u;
    n_brk = 0u;
    let t0 = next_down(lo);
    let t1 = next_up(hi);
    let first_p = obj.op_count;
    let unb = obj.first_item + obj.item_count;
    for (var k = 0u; k < obj.unbounded; k++) {
        loops++;
        if (!offer(first_p + items[unb + k].item, lo, hi)) { return false; }
    }
    var i = 0u;
    while (i < obj.node_count) {
        loops++;
        let n = nodes[obj.first_node + i];
        let count = n.count_axis & 0x3fffffffu;
        let hit = slab(vec3<f32>(n.lo_x, n.lo_y, n.lo_z), vec3<f32>(n.hi_x, n.hi_y, n.hi_z), t0, t1).x == 1.0;
        if (hit && count > 0u) {
            for (var k = 0u; k < count; k++) {
                loops++;
                let b = items[obj.first_item + n.offset + k];
                if (slab(vec3<f32>(b.lo_x, b.lo_y, b.lo_z), vec3<f32>(b.hi_x, b.hi_y, b.hi_z), t0, t1).x == 1.0) {
                    if (!offer(first_p + b.item, lo, hi)) { return false; }
                }
            }
        }
        if (hit || count > 0u) { i = i + 1u; } else { i = n.offset; }
    }
    return true;
}

// The least break above ta, else hi: the sorted walk of the CPU by selection.
fn next_break(ta: f32, hi: f32) -> f32 {
    var best = hi;
    var found = false;
    for (var j = 0u; j < n_brk; j++) {
        loops++;
        let e = brk[j];
        if (e > ta && (!found || e < best)) {
            best = e;
            found = true;
        }
    }
    return best;
}

fn holds(j: u32, t: f32) -> bool {
    let s = act_set[j];
    for (var k = 0u; k < act_n[j]; k++) {
        loops++;
        if (s[2u * k] < t && t < s[2u * k + 1u]) { return true; }
    }
    return false;
}

// --- poly.rs: power form ------------------------------------------------------------

// f·(a0 + a1·x + a2·x²)³ added to c (Poly::add_scaled_cube).
fn scaled_cube(f: f32, q: vec3<f32>) -> array<f32, 7> {
    let a = q.x;
    let b = q.y;
    let c = q.z;
    let a2 = a * a;
    let b2 = b * b;
    let c2 = c * c;
    let v = array<f32, 7>(
        a2 * a,
        3.0 * a2 * b,
        3.0 * a * (a * c + b2),
        b2 * b + 6.0 * a * b * c,
        3.0 * c * (b2 + a * c),
        3.0 * b * c2,
        c2 * c,
    );
    return array<f32, 7>(f * v[0], f * v[1], f * v[2], f * v[3], f * v[4], f * v[5], f * v[6]);
}

// The piece [ta, tb] about ta, its active perturbations read at `inside` (Piece::new).
fn build_piece(ta: f32, tb: f32, inside: f32) {
    let h = tb - ta;
    let p = vec3<f32>(ro.x + ta * rd.x, ro.y + ta * rd.y, ro.z + ta * rd.z);
    let q0 = q_local(base_c, p, rd);
    let m0 = q_local_mag(base_c, p, rd);
    pc = array<f32, 7>(q0.x, q0.y, q0.z, 0.0, 0.0, 0.0, 0.0);
    pm = array<f32, 7>(m0.x, m0.y, m0.z, 0.0, 0.0, 0.0, 0.0);
    pn = 2u;
    for (var j = 0u; j < n_act; j++) {
        loops++;
        if (!holds(j, inside)) { continue; }
        let pert = perturbations[act_p[j]];
        let q = q_local(pert.q, p, rd);
        pc = add7(pc, scaled_cube(pert.f, q));
        // |q| on [ta, tb]: the largest Bernstein coefficient of the quadratic.
        let mid = q.x + q.y * h * 0.5;
        let end = q.x + (q.y + q.z * h) * h;
        let q_max = rmax(rmax(abs(q.x), abs(mid)), abs(end));
        // Poly::add_cube_error: |f|·(|q|³ coefficient-wise + 3·q_max²·m).
        let fa = abs(pert.f);
        let m = q_local_mag(pert.q, p, rd);
        // (0 + |f|·v: the CPU's zero polynomial plus non-negative terms, equal to them.)
        var err = scaled_cube(fa, abs(q));
        let kk = fa * 3.0 * q_max * q_max;
        err[0] = err[0] + kk * m.x;
        err[1] = err[1] + kk * m.y;
        err[2] = err[2] + kk * m.z;
        pm = add7(pm, err);
        pn = 6u;
    }
}

// p(h·x) (Poly::scaled); a zero coefficient stays zero where h^k overflows.
fn scaled(c0: array<f32, 7>, n: u32, h: f32) -> array<f32, 7> {
    var c = c0;
    var hk = 1.0;
    for (var k = 1u; k <= n; k++) {
        loops++;
        hk = hk * h;
        if (c[k] != 0.0) { c[k] = c[k] * hk; }
    }
    return c;
}

// The Bernstein form on [0, 1] (Poly::to_bernstein).
fn to_bernstein(c: array<f32, 7>, n: u32) -> array<f32, 7> {
    var b = array<f32, 7>(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for (var j = 0u; j <= n; j++) {
        var s = 0.0;
        for (var k = 0u; k <= j; k++) {
            loops++;
            s = s + RATIO[49u * n + 7u * j + k] * c[k];
        }
        b[j] = s;
    }
    return b;
}

// --- poly.rs: Bernstein form --------------------------------------------------------

// (p(u), p'(u)) by de Casteljau (eval_d).
fn eval_d(b: array<f32, 7>, n: u32, u: f32) -> vec2<f32> {
    if (n == 0u) { return vec2<f32>(b[0], 0.0); }
    let v = 1.0 - u;
    var w = b;
    for (var k = 1u; k < n; k++) {
        for (var j = 0u; j <= n - k; j++) {
            loops++;
            w[j] = v * w[j] + u * w[j + 1u];
        }
    }
    return vec2<f32>(v * w[0] + u * w[1], f32(n) * (w[1] - w[0]));
}

struct Halves { bl: array<f32, 7>, br: array<f32, 7>, el: array<f32, 7>, er: array<f32, 7> }

// The halves on [0, ½] and [½, 1] of b and of its bounds e, by de Casteljau (split_half,
// twice).
fn split_half(b: array<f32, 7>, e: array<f32, 7>, n: u32) -> Halves {
    var w = b;
    var we = e;
    var h: Halves;
    h.bl[0] = w[0];
    h.br[n] = w[n];
    h.el[0] = we[0];
    h.er[n] = we[n];
    for (var k = 1u; k <= n; k++) {
        for (var j = 0u; j <= n - k; j++) {
            loops++;
            w[j] = (w[j] + w[j + 1u]) * 0.5;
            we[j] = (we[j] + we[j + 1u]) * 0.5;
        }
        h.bl[k] = w[0];
        h.br[n - k] = w[n - k];
        h.el[k] = we[0];
        h.er[n - k] = we[n - k];
    }
    return h;
}

fn significant_sign_changes(b: array<f32, 7>, e: array<f32, 7>, n: u32) -> u32 {
    var count = 0u;
    var prev = 0.0;
    for (var j = 0u; j <= n; j++) {
        loops++;
        let v = b[j];
        if (abs(v) > e[j]) {
            if (prev != 0.0 && (v < 0.0) != (prev < 0.0)) { count++; }
            prev = v;
        }
    }
    return count;
}

// The root in [lo, hi] where p goes from ≥ 0 to < 0: Newton safeguarded by bisection
// (Numerical Recipes `rtsafe`).
fn refine(b: array<f32, 7>, n: u32, lo0: f32, hi0: f32) -> f32 {
    let tol = EPS * 2.0;
    var lo = lo0;
    var hi = hi0;
    var g_ends = vec2<f32>(0.0);
    for (var i = 0u; i < 2u; i++) {
        loops++;
        g_ends[i] = eval_d(b, n, select(lo, hi, i == 1u)).x;
    }
    let glo = g_ends.x;
    let ghi = g_ends.y;
    var x = lo + (hi - lo) * (glo / (glo - ghi));
    if (!(x > lo && x < hi)) { x = (lo + hi) * 0.5; }
    var step_old = hi - lo;
    for (var i = 0u; i < 100u; i++) {
        loops++;
        let gd = eval_d(b, n, x);
        let g = gd.x;
        let dg = gd.y;
        if (g == 0.0) { return x; }
        if (g > 0.0) { lo = x; } else { hi = x; }
        let newton = x - g / dg;
        let close = tol * rmax(abs(x), 1.0);
        var next = (lo + hi) * 0.5;
        if (newton > lo && newton < hi && abs(g + g) <= abs(step_old * dg)) {
            next = newton;
        } else if (dg < 0.0 && abs(newton - x) <= close) {
            // Converged on the bracket's end: the far side of the root (see poly.rs).
            if (g < 0.0) { return x; }
            return rmin(x + close, hi);
        }
        step_old = abs(next - x);
        x = next;
        if (step_old <= tol * rmax(abs(x), 1.0) || hi - lo <= tol) { break; }
    }
    return x;
}

// The first u ∈ [0, 1] where p turns negative given coefficient error bounds e:
// (1, u), or (0, 0) (Bernstein::first_negative_bounded). Every exit that refines a root
// leaves the loop with its bracket, so that `refine` (and `polish`) appear once.
fn first_negative_bounded(b0: array<f32, 7>, e0: array<f32, 7>, n: u32) -> vec2<f32> {
    let tol = EPS * 8.0;
    var top = 0u;
    var cb = b0;
    var ce = e0;
    var u0 = 0.0;
    var u1 = 1.0;
    var depth = 0u;
    // 1: polish left of pu on b0 (step pw); 2: refine cb on [0, rhi], mapped by u0 + w·x.
    var outcome = 0u;
    var pu = 0.0;
    var pw = 0.0;
    var rhi = 1.0;
    var w = 0.0;
    loop {
        loops++;
        if (cb[0] < -ce[0]) {
            outcome = 1u;
            pu = u0;
            pw = u1 - u0;
            break;
        }
        var any_negative = false;
        for (var j = 0u; j <= n; j++) {
            loops++;
            if (cb[j] < -ce[j]) { any_negative = true; break; }
        }
        if (any_negative) {
            w = u1 - u0;
            let last_negative = cb[n] < -ce[n];
            if (cb[0] >= 0.0 && last_negative && significant_sign_changes(cb, ce, n) == 1u) {
                outcome = 2u;
                break;
            }
            if (depth >= MAX_DEPTH || w <= tol) {
                if (cb[0] < 0.0) {
                    outcome = 1u;
                    pu = u0;
                    pw = w;
                    break;
                }
                if (last_negative) {
                    outcome = 2u;
                    break;
                }
                var big_e = 0.0;
                for (var j = 0u; j <= n; j++) {
                    loops++;
                    big_e = rmax(big_e, ce[j]);
                }
                if (eval_d(cb, n, 0.5).x < -big_e) {
                    outcome = 2u;
                    rhi = 0.5;
                    break;
                }
            } else {
                let h = split_half(cb, ce, n);
                let mid = u0 + w * 0.5;
                st_b[top] = h.br;
                st_e[top] = h.er;
                st_u0[top] = mid;
                st_u1[top] = u1;
                st_d[top] = depth + 1u;
                top++;
                cb = h.bl;
                ce = h.el;
                u1 = mid;
                depth = depth + 1u;
                continue;
            }
        }
        if (top == 0u) { return vec2<f32>(0.0, 0.0); }
        top--;
        cb = st_b[top];
        ce = st_e[top];
        u0 = st_u0[top];
        u1 = st_u1[top];
        depth = st_d[top];
    }
    var rb = cb;
    var rlo = 0.0;
    var mapped = true;
    if (outcome == 1u) {
    // Bernstein::polish: step left of pu by pw, 2·pw, 4·pw, … until p ≥ 0, then refine
    // between; pu itself when p stays negative as far as 0 or for 40 doublings.
    var step = pw;
    var bracketed = false;
    for (var i = 0u; i < 40u; i++) {
        loops++;
        rlo = rmax(pu - step, 0.0);
        if (eval_d(b0, n, rlo).x >= 0.0) {
            bracketed = true;
            break;
        }
        if (rlo == 0.0) { break; }
        step = step + step;
    }
    if (!bracketed) { return vec2<f32>(1.0, pu); }
    rb = b0;
    rhi = pu;
    mapped = false;
    }
    let x = refine(rb, n, rlo, rhi);
    if (mapped) { return vec2<f32>(1.0, u0 + w * x); }
    return vec2<f32>(1.0, x);
}

// The sign of p just after 0, reading coefficients within ±e as zero.
fn sign_after_zero_bounded(b: array<f32, 7>, e: array<f32, 7>, n: u32) -> f32 {
    for (var j = 0u; j <= n; j++) {
        loops++;
        if (abs(b[j]) > e[j]) { return signum(b[j]); }
    }
    for (var j = 0u; j <= n; j++) {
        loops++;
        if (b[j] != 0.0) { return signum(b[j]); }
    }
    return 0.0;
}

// --- scan.rs: pieces ----------------------------------------------------------------

// A piece's outcome: state 0 undecided, 1 decided miss, 2 hit at t.
struct Found { state: u32, t: f32 }

fn piece(ta: f32, tb: f32) -> Found {
    build_piece(ta, tb, (ta + tb) * 0.5);
    let h = tb - ta;
    let n = pn;
    let b = to_bernstein(scaled(pc, n, h), n);
    let e = mul7(to_bernstein(scaled(pm, n, h), n), EPS * ROUNDING);
    for (var j = 0u; j <= n; j++) {
        loops++;
        if (!is_finite(b[j])) { return Found(1u, 0.0); }
    }
    if (scan_s == 0.0) {
        scan_s = sign_after_zero_bounded(b, e, n);
        if (scan_s == 0.0) { return Found(0u, 0.0); }
    }
    let r = first_negative_bounded(mul7(b, scan_s), e, n);
    if (r.x == 0.0) { return Found(0u, 0.0); }
    let t = rmin(rmax(ta + (tb - ta) * r.y, ta), tb);
    if (t >= ray_tmax) { return Found(1u, 0.0); }
    let above = ray_tmin + rmax(abs(ray_tmin) * EPS, MIN_POS);
    return Found(2u, rmax(t, above));
}

// Cauchy's bound on the roots of the piece about `at` read at `inside`: (1, R) or (0, 0).
fn root_bound(at: f32, inside: f32) -> vec2<f32> {
    build_piece(at, at, inside);
    var n = pn;
    while (n > 0u && pc[n] == 0.0) {
        loops++;
        n--;
    }
    if (n == 0u) { return vec2<f32>(0.0, 0.0); }
    let lead = abs(pc[n]);
    var m = 0.0;
    for (var k = 0u; k < n; k++) {
        loops++;
        m = rmax(m, abs(pc[k]) / lead);
    }
    return vec2<f32>(1.0, 1.0 + m);
}

// The pieces of [lo, hi] left to right (Scan::run): decided, or state 0 with scan_s the
// sign at hi. An unbounded interval is cut at Cauchy's bound R about its finite end `at`
// into sub-pieces: [ta, ∞) growing ×GROWTH up to ta + R (Scan::right_unbounded), (−∞, tb]
// from tb − R shrinking ÷GROWTH towards tb (Scan::left_unbounded). One loop hands every
// piece and sub-piece to the one call of `piece`.
fn run(lo: f32, hi: f32, any: bool) -> Found {
    let split_at_zero = lo == -inf() && hi == inf() && !any;
    var ta = lo;
    loop {
        loops++;
        var tb: f32;
        if (split_at_zero && ta == lo) { tb = 0.0; } else { tb = next_break(ta, hi); }
        if (is_nan(tb) || tb <= ta) { return Found(0u, 0.0); }
        // mode 0: the piece [pa, pb]; 1: growing from pa to end; 2: `count` pieces from
        // pa shrinking towards tb, then [pa, tb].
        var mode = 0u;
        var pa = ta;
        var pb = tb;
        var w = 0.0;
        var end = 0.0;
        var largest = 0.0;
        var count = 0u;
        if (ta == -inf() || tb == inf()) {
            let right = tb == inf();
            let at = select(tb, ta, right);
            let width = max(abs(at), 1.0);
            let inside = select(at - width, at + width, right);
            let rb = root_bound(at, inside);
            if (rb.x == 0.0) {
                pa = select(at - width, at, right);
                pb = select(at, at + width, right);
            } else if (right) {
                mode = 1u;
                end = ta + rb.y;
                w = rmin(width, rb.y);
            } else {
                mode = 2u;
                let r = rb.y;
                w = rmin(width, r);
                while (w < r && count < GROWTH_CAP) {
                    loops++;
                    largest = w;
                    count++;
                    w = w * GROWTH;
                }
                pa = tb - r;
            }
        }
        var i = 0u;
        loop {
            loops++;
            if (mode == 0u && i > 0u) { break; }
            if (mode == 1u) {
                if (!(pa < end) || i >= GROWTH_CAP) { break; }
                pb = rmin(pa + w, end);
            }
            if (mode == 2u) {
                if (i > count) { break; }
                pb = select(tb, tb - largest, i < count);
            }
            let f = piece(pa, pb);
            if (f.state != 0u) { return f; }
            pa = pb;
            w = w * GROWTH;
            largest = largest / GROWTH;
            i++;
        }
        if (tb >= hi) { return Found(0u, 0.0); }
        ta = tb;
    }
    return Found(0u, 0.0);
}

// A point strictly inside (lo, hi) to split at: (1, m), or (0, 0).
fn split_point(lo: f32, hi: f32) -> vec2<f32> {
    var m: f32;
    if (lo == -inf() && hi == inf()) {
        m = 0.0;
    } else if (lo == -inf()) {
        m = hi - max(abs(hi), 1.0);
    } else if (hi == inf()) {
        m = lo + max(abs(lo), 1.0);
    } else {
        m = lo + (hi - lo) / 2.0;
    }
    return vec2<f32>(select(0.0, 1.0, m > lo && m < hi), m);
}

// Status 0 miss, 1 hit at t, 2 overflow (more than K active after MAX_SPLITS halvings).
struct ScanResult { status: u32, t: f32 }

// The first t in (t_min, t_max) where F' of object `oi` changes sign.
fn perturbed_first_crossing(oi: u32, o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32) -> ScanResult {
    obj = objects[oi];
    ro = o;
    rd = d;
    rinv = vec3<f32>(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
    ray_tmin = t_min;
    ray_tmax = t_max;
    let blo = vec3<f32>(obj.lo_x, obj.lo_y, obj.lo_z);
    let bhi = vec3<f32>(obj.hi_x, obj.hi_y, obj.hi_z);
    if (is_nan(t_min) || is_nan(t_max) || t_min >= t_max || any(blo > bhi)) { return ScanResult(0u, 0.0); }
    let c = slab(blo, bhi, t_min, t_max);
    if (c.x == 0.0) { return ScanResult(0u, 0.0); }
    var lo = c.y;
    var hi = c.z;
    if (is_nan(lo) || is_nan(hi) || lo >= hi) { return ScanResult(0u, 0.0); }
    base_c = quadrics[obj.first_op].c;
    scan_s = select(0.0, -1.0, lo > t_min);
    // Pending right halves of split chunks (Along::chunk, left first).
    var pend_hi: array<f32, 8>;
    var pend_depth: array<u32, 8>;
    var np = 0u;
    var depth = 0u;
    loop {
        loops++;
        if (!collect(lo, hi)) {
            let sp = split_point(lo, hi);
            if (depth < MAX_SPLITS && sp.x == 1.0) {
                pend_hi[np] = hi;
                pend_depth[np] = depth + 1u;
                np++;
                hi = sp.y;
                depth++;
                continue;
            }
            return ScanResult(2u, 0.0);
        }
        let f = run(lo, hi, n_brk > 0u);
        if (f.state == 2u) { return ScanResult(1u, f.t); }
        if (f.state == 1u) { return ScanResult(0u, 0.0); }
        if (np == 0u) {
            // The range ends at the bounds of {F' ≥ 0}: F' ≥ 0 there within rounding,
            // the crossing is at that end; its sign unknown, for the CPU.
            if (scan_s > 0.0 && hi < t_max) { return ScanResult(1u, hi); }
            if (scan_s == 0.0 && hi < t_max) { return ScanResult(2u, 0.0); }
            return ScanResult(0u, 0.0);
        }
        np--;
        lo = hi;
        hi = pend_hi[np];
        depth = pend_depth[np];
    }
    return ScanResult(0u, 0.0);
}
