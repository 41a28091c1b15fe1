// Expression tapes (GPU.md §6.2): frep's register bytecode (frep::bytecode, two words per
// op: opcode | out << 8 | a << 16 | b << 24, then an immediate; register 255 reads the
// immediate) run by a loop over a switch, in two flavours: `eval_point` (F at a point in
// f32, Bytecode::eval_f32's twin) and `eval_interval` (F and dF/dt as intervals, a vec4
// (lo, hi, dlo, dhi), widened outward after every op, §6.2.3). The CPU twins are in
// gpu::tape. Every op of frep's bytecode: var, const, powi (|n| ≤ 255), neg, abs, sqrt,
// square, add, sub, mul, div, min, max, sin, cos, atan2 (TRIG_WGSL's polynomials), and
// exp, ln, tan, asin, acos, atan, floor, ceil, round, not, mod, compare, and, or
// (elementary.wgsl, appended).
// The kernel prepends the opcodes (OP_VAR, …) and IMM from frep's encoding
// (gpu::tape::tape_consts_wgsl) and REG_COUNT (per pipeline, §3.4), declares `tape_ops`
// (the tape's length in instructions) and binds `tape: array<u32>`. Each loop iteration runs four instructions and adds one to `loops` (§3.1):
// an evaluation costs eval_loops().

var<private> loops: u32;
// Where the tape starts in `tape` (words): 0, or the scene's tape of the object traced
// where a kernel holds several (gpu::tape_trace::scene_wgsl).
var<private> tape_base: u32;
// Its length in instructions: a run-time trip count, so that tapes of every length (a
// scene's solids, and later a solid's per-cell tapes) share one compiled interpreter.
// Set by the kernel's preamble or `use_tape`.
fn eval_loops() -> u32 { return (tape_ops + 3u) / 4u; }

const MIN_POS: f32 = 0x1p-126f; // f32::MIN_POSITIVE

// The next f32 above x, where zero and subnormals step to the smallest normal, so that a
// GPU flushing subnormals still widens (§6.2.3). NaN and +∞ stay.
fn up(x: f32) -> f32 {
    if (is_nan(x) || x == inf()) { return x; }
    if (x >= -MIN_POS && x < MIN_POS) { return MIN_POS; }
    let b = bitcast<u32>(x);
    return bitcast<f32>(select(b - 1u, b + 1u, x > 0.0));
}
fn down(x: f32) -> f32 { return -up(-x); }
fn up4(x: f32) -> f32 { return up(up(up(up(x)))); }
fn down4(x: f32) -> f32 { return down(down(down(down(x)))); }
fn w1(lo: f32, hi: f32) -> vec2<f32> { return vec2<f32>(down(lo), up(hi)); }
fn w4(lo: f32, hi: f32) -> vec2<f32> { return vec2<f32>(down4(lo), up4(hi)); }
fn nan2() -> vec2<f32> { return vec2<f32>(nan(), nan()); }
fn any_nan(a: vec2<f32>) -> bool { return is_nan(a.x) || is_nan(a.y); }

// x^n, 0 ≤ n ≤ 255, by compiler-rt's __powisf2 (what Rust's f32::powi calls): square and
// multiply from the lowest bit, eight bits.
fn powi(x: f32, n: u32) -> f32 {
    var a = x;
    var r = 1.0;
    for (var bit = 0u; bit < 8u; bit++) {
        if ((n & (1u << bit)) != 0u) { r = r * a; }
        if (n < (2u << bit)) { break; }
        a = a * a;
    }
    return r;
}
// x^n for |n| ≤ 255 (the tape's immediate as i32 bits): 1/x^|n| for n < 0.
fn powi_signed(x: f32, n: i32) -> f32 {
    let r = powi(x, u32(abs(n)));
    if (n < 0) { return 1.0 / r; }
    return r;
}

// Interval operations on (lo, hi), each containing every exact result (NaN: unknown).
fn i_add(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> { return w1(a.x + b.x, a.y + b.y); }
fn i_sub(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> { return w1(a.x - b.y, a.y - b.x); }
fn i_neg(a: vec2<f32>) -> vec2<f32> { return vec2<f32>(-a.y, -a.x); }
fn i_mul(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    let p = vec4<f32>(a.x * b.x, a.x * b.y, a.y * b.x, a.y * b.y);
    return w1(rmin(rmin(p.x, p.y), rmin(p.z, p.w)), rmax(rmax(p.x, p.y), rmax(p.z, p.w)));
}
fn i_div(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    if (b.x <= 0.0 && b.y >= 0.0) { return vec2<f32>(-inf(), inf()); }
    let p = vec4<f32>(a.x / b.x, a.x / b.y, a.y / b.x, a.y / b.y);
    return w4(rmin(rmin(p.x, p.y), rmin(p.z, p.w)), rmax(rmax(p.x, p.y), rmax(p.z, p.w)));
}
fn i_abs(a: vec2<f32>) -> vec2<f32> {
    if (a.x >= 0.0) { return a; }
    if (a.y <= 0.0) { return i_neg(a); }
    return vec2<f32>(0.0, rmax(-a.x, a.y));
}
fn i_square(a: vec2<f32>) -> vec2<f32> {
    if (any_nan(a)) { return nan2(); }
    let b = i_abs(a);
    return w1(b.x * b.x, b.y * b.y);
}
fn i_sqrt(a: vec2<f32>) -> vec2<f32> {
    if (any_nan(a) || a.y < 0.0) { return nan2(); }
    return w4(sqrt(rmax(a.x, 0.0)), sqrt(a.y));
}
fn i_powi(a: vec2<f32>, n: u32) -> vec2<f32> {
    if (any_nan(a)) { return nan2(); }
    if (n == 0u) { return vec2<f32>(1.0, 1.0); }
    var b = a;
    if ((n & 1u) == 0u) { b = i_abs(a); }
    // x^n by repeated products is monotone on b (rounding to nearest is), within n ulps.
    let lo = powi(b.x, n);
    let hi = powi(b.y, n);
    if (n <= 15u) { return vec2<f32>(down4(down4(down4(down4(lo)))), up4(up4(up4(up4(hi))))); }
    // n − 1 roundings: relative error below (n − 1)·2⁻²⁴, widened by n·2⁻²³ and an ulp.
    let f = f32(n) * bitcast<f32>(0x34000000u);
    return vec2<f32>(down(lo * select(1.0 + f, 1.0 - f, lo >= 0.0)), up(hi * select(1.0 - f, 1.0 + f, hi >= 0.0)));
}
fn i_powi_signed(a: vec2<f32>, n: i32) -> vec2<f32> {
    let v = i_powi(a, u32(abs(n)));
    if (n < 0) { return i_div(vec2<f32>(1.0, 1.0), v); }
    return v;
}
fn i_min(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> { return vec2<f32>(rmin(a.x, b.x), rmin(a.y, b.y)); }
fn i_max(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> { return vec2<f32>(rmax(a.x, b.x), rmax(a.y, b.y)); }
fn hull(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    if (any_nan(a) || any_nan(b)) { return nan2(); }
    return vec2<f32>(min(a.x, b.x), max(a.y, b.y));
}

// gpu::tape::i_sin_cos: the ends' values widened by TRIG_ERR, ±1 where an extremum lies
// within, [−1, 1] past a span of 6 or |x| ≥ 10⁴.
fn i_sin_cos(a: vec2<f32>, cosine: bool) -> vec2<f32> {
    if (any_nan(a)) { return nan2(); }
    let big = max(abs(a.x), abs(a.y));
    if (!(a.y - a.x < 6.0 && big < 1.0e4)) { return vec2<f32>(-1.0, 1.0); }
    let va = t_sin_cos(a.x, cosine);
    let vb = t_sin_cos(a.y, cosine);
    var lo = min(va, vb) - 1.0e-6;
    var hi = max(va, vb) + 1.0e-6;
    let two_pi = bitcast<f32>(0x40c90fdbu);
    let margin = 1.0e-6 * (1.0 + big);
    var p = bitcast<f32>(0x3fc90fdbu);
    if (cosine) { p = 0.0; }
    let m_hi = ceil((a.x - margin - p) / two_pi);
    if (p + two_pi * m_hi <= a.y + margin) { hi = 1.0; }
    let p_lo = p + bitcast<f32>(0x40490fdbu);
    let m_lo = ceil((a.x - margin - p_lo) / two_pi);
    if (p_lo + two_pi * m_lo <= a.y + margin) { lo = -1.0; }
    return vec2<f32>(max(lo, -1.0), min(hi, 1.0));
}

// gpu::tape::i_atan2: [−π, π] where the box meets x ≤ 0 with y spanning 0, else the
// corners' angles widened by TRIG_ERR.
fn i_atan2(y: vec2<f32>, x: vec2<f32>) -> vec2<f32> {
    if (any_nan(y) || any_nan(x)) { return nan2(); }
    let pi = bitcast<f32>(0x40490fdbu) + 1.0e-6;
    if (x.x <= 0.0 && y.x <= 0.0 && y.y >= 0.0) { return vec2<f32>(-pi, pi); }
    let c0 = env_atan2(y.x, x.x);
    let c1 = env_atan2(y.x, x.y);
    let c2 = env_atan2(y.y, x.x);
    let c3 = env_atan2(y.y, x.y);
    return vec2<f32>(rmin(rmin(c0, c1), rmin(c2, c3)) - 1.0e-6, rmax(rmax(c0, c1), rmax(c2, c3)) + 1.0e-6);
}

var<private> preg: array<f32, REG_COUNT>;

// Instruction k at p (Bytecode::eval_f32's arm); returns its output register.
fn point_op(k: u32, p: vec3<f32>) -> u32 {
        let w = tape[tape_base + 2u * k];
        let imm = bitcast<f32>(tape[tape_base + 2u * k + 1u]);
        let op = w & 0xffu;
        let o = (w >> 8u) & 0xffu;
        let ia = (w >> 16u) & 0xffu;
        let ib = w >> 24u;
        var a = imm;
        if (op != OP_VAR && ia != IMM) { a = preg[ia]; }
        var b = imm;
        if (ib != IMM) { b = preg[ib]; }
        var v = 0.0;
        switch op {
            case OP_VAR: { v = p[ia]; }
            case OP_CONST: { v = imm; }
            case OP_POWI: { v = powi_signed(a, bitcast<i32>(tape[tape_base + 2u * k + 1u])); }
            case OP_NEG: { v = -a; }
            case OP_ABS: { v = abs(a); }
            case OP_SQRT: { v = sqrt(a); }
            case OP_SQUARE: { v = a * a; }
            case OP_ADD: { v = a + b; }
            case OP_SUB: { v = a - b; }
            case OP_MUL: { v = a * b; }
            case OP_DIV: { v = a / b; }
            case OP_MIN: { v = rmin(a, b); }
            case OP_MAX: { v = rmax(a, b); }
            case OP_SIN: { v = t_sin_cos(a, false); }
            case OP_COS: { v = t_sin_cos(a, true); }
            case OP_ATAN2: { v = env_atan2(a, b); }
            case OP_EXP, OP_LN, OP_TAN, OP_ASIN, OP_ACOS, OP_ATAN, OP_FLOOR, OP_CEIL, OP_ROUND,
                OP_NOT, OP_MOD, OP_COMPARE, OP_AND, OP_OR: {
                v = nan();
                if (ELEMENTARY) { v = elementary_point(op, a, b); }
            }
            default: { v = nan(); }
        }
        preg[o] = v;
        return o;
}

// F at p: Bytecode::eval_f32 operation for operation, four ops per loop iteration
// (§6.2.2), so an evaluation costs eval_loops() iterations.
fn eval_point(p: vec3<f32>) -> f32 {
    var out = 0u;
    for (var k = 0u; k < tape_ops; k += 4u) {
        loops++;
        out = point_op(k, p);
        if (k + 1u < tape_ops) { out = point_op(k + 1u, p); }
        if (k + 2u < tape_ops) { out = point_op(k + 2u, p); }
        if (k + 3u < tape_ops) { out = point_op(k + 3u, p); }
    }
    return preg[out];
}

var<private> ireg: array<vec4<f32>, REG_COUNT>;
// Where along the box the nearest wrap of a `mod` lies, as a fraction (2: none), from
// the last eval_interval (gpu::elementary::wrap_fraction): the tracer splits there.
var<private> wrap_hint: f32;

// F and dF/dt over a box: x, y, z are (lo, hi, dlo, dhi) of each coordinate. Values
// widened by 1 ulp after each op, 4 after `/` and sqrt, 16 after powi (§6.2.3);
// derivatives by the same interval ops (frep's Dual<Interval, 1>).
fn interval_op(k: u32, x: vec4<f32>, y: vec4<f32>, z: vec4<f32>) -> u32 {
        let w = tape[tape_base + 2u * k];
        let imm = bitcast<f32>(tape[tape_base + 2u * k + 1u]);
        let op = w & 0xffu;
        let o = (w >> 8u) & 0xffu;
        let ia = (w >> 16u) & 0xffu;
        let ib = w >> 24u;
        var a = vec4<f32>(imm, imm, 0.0, 0.0);
        if (op != OP_VAR && ia != IMM) { a = ireg[ia]; }
        var b = vec4<f32>(imm, imm, 0.0, 0.0);
        if (ib != IMM) { b = ireg[ib]; }
        var v = vec2<f32>(0.0, 0.0);
        var d = vec2<f32>(0.0, 0.0);
        switch op {
            case OP_VAR: {
                var c = x;
                if (ia == 1u) { c = y; }
                if (ia == 2u) { c = z; }
                v = c.xy;
                d = c.zw;
            }
            case OP_CONST: { v = vec2<f32>(imm, imm); }
            case OP_POWI: {
                let n = bitcast<i32>(tape[tape_base + 2u * k + 1u]);
                v = i_powi_signed(a.xy, n);
                if (n != 0) {
                    let nf = f32(n);
                    d = i_mul(i_mul(vec2<f32>(nf, nf), i_powi_signed(a.xy, n - 1)), a.zw);
                }
            }
            case OP_NEG: { v = i_neg(a.xy); d = i_neg(a.zw); }
            case OP_ABS: {
                v = i_abs(a.xy);
                if (a.x >= 0.0) { d = a.zw; } else if (a.y <= 0.0) { d = i_neg(a.zw); } else { d = hull(a.zw, i_neg(a.zw)); }
            }
            case OP_SQRT: { v = i_sqrt(a.xy); d = i_div(a.zw, 2.0 * v); }
            case OP_SQUARE: { v = i_square(a.xy); d = i_mul(2.0 * a.xy, a.zw); }
            case OP_ADD, OP_SUB: {
                if (op == OP_ADD) {
                    v = i_add(a.xy, b.xy);
                    d = i_add(a.zw, b.zw);
                } else {
                    v = i_sub(a.xy, b.xy);
                    d = i_sub(a.zw, b.zw);
                }
                // An R-function's mark (gpu::r_bound), in a register-register sum's
                // immediate word.
                if (RBOUND && ia != IMM && ib != IMM) {
                    v = r_mark(tape[tape_base + 2u * k + 1u], a.xy, b.xy, v);
                }
            }
            case OP_MUL: { v = i_mul(a.xy, b.xy); d = i_add(i_mul(a.zw, b.xy), i_mul(a.xy, b.zw)); }
            case OP_DIV: { v = i_div(a.xy, b.xy); d = i_div(i_sub(a.zw, i_mul(v, b.zw)), b.xy); }
            case OP_MIN: {
                if (a.y <= b.x) { v = a.xy; d = a.zw; } else if (b.y <= a.x) { v = b.xy; d = b.zw; } else { v = i_min(a.xy, b.xy); d = hull(a.zw, b.zw); }
            }
            case OP_MAX: {
                if (a.x >= b.y) { v = a.xy; d = a.zw; } else if (b.x >= a.y) { v = b.xy; d = b.zw; } else { v = i_max(a.xy, b.xy); d = hull(a.zw, b.zw); }
            }
            case OP_SIN: { v = i_sin_cos(a.xy, false); d = i_mul(i_sin_cos(a.xy, true), a.zw); }
            case OP_COS: { v = i_sin_cos(a.xy, true); d = i_mul(i_neg(i_sin_cos(a.xy, false)), a.zw); }
            case OP_ATAN2: {
                v = i_atan2(a.xy, b.xy);
                d = i_div(i_sub(i_mul(b.xy, a.zw), i_mul(a.xy, b.zw)), i_add(i_square(a.xy), i_square(b.xy)));
            }
            case OP_EXP, OP_LN, OP_TAN, OP_ASIN, OP_ACOS, OP_ATAN, OP_FLOOR, OP_CEIL, OP_ROUND,
                OP_NOT, OP_MOD, OP_COMPARE, OP_AND, OP_OR: {
                v = nan2();
                d = nan2();
                if (ELEMENTARY) {
                    let r = elementary_interval(op, a, b);
                    v = r.xy;
                    d = r.zw;
                }
            }
            default: { v = nan2(); d = nan2(); }
        }
        ireg[o] = vec4<f32>(v, d);
        return o;
}

// F and dF/dt over a box, four ops per loop iteration.
fn eval_interval(x: vec4<f32>, y: vec4<f32>, z: vec4<f32>) -> vec4<f32> {
    wrap_hint = 2.0;
    var out = 0u;
    for (var k = 0u; k < tape_ops; k += 4u) {
        loops++;
        out = interval_op(k, x, y, z);
        if (k + 1u < tape_ops) { out = interval_op(k + 1u, x, y, z); }
        if (k + 2u < tape_ops) { out = interval_op(k + 2u, x, y, z); }
        if (k + 3u < tape_ops) { out = interval_op(k + 3u, x, y, z); }
    }
    return ireg[out];
}
