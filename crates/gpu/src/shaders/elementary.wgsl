// The tapes' remaining operations (gpu::elementary, operation for operation): exp and ln
// as polynomials, tan, asin, acos and atan on TRIG_WGSL's, rounding, mod, compare and
// logic, as point values and as sound intervals. Uses tape.wgsl's up/down and interval
// helpers, FLOAT_WGSL and TRIG_WGSL. A derivative lane where the operand may cross a
// jump is (−∞, ∞).

const EXP_LO: f32 = -87.0;
const EXP_HI: f32 = 88.72;

fn pow2(n: i32) -> f32 { return bitcast<f32>(u32(n + 127) << 23u); }

// e^x: Cody & Waite's reduction by ln 2 in two parts, Taylor to r⁷, 2^k in two factors.
fn t_exp(x: f32) -> f32 {
    if (is_nan(x)) { return nan(); }
    if (x > EXP_HI) { return inf(); }
    if (x < EXP_LO) { return 0.0; }
    let k = floor(x * bitcast<f32>(0x3fb8aa3bu) + 0.5);
    let r = (x - k * bitcast<f32>(0x3f318000u)) - k * bitcast<f32>(0xb95e8083u);
    let p = 1.0 + r * (1.0 + r * (0.5 + r * (bitcast<f32>(0x3e2aaaabu)
        + r * (bitcast<f32>(0x3d2aaaabu) + r * (bitcast<f32>(0x3c088889u)
        + r * (bitcast<f32>(0x3ab60b61u) + r * bitcast<f32>(0x39500d01u)))))));
    let ki = i32(k);
    let h = ki / 2;
    return p * pow2(h) * pow2(ki - h);
}

// ln x: x = m·2^e, m ∈ [√½, √2), ln m = 2 atanh((m − 1)/(m + 1)) to s¹¹.
fn t_ln(x: f32) -> f32 {
    if (is_nan(x) || x < 0.0) { return nan(); }
    if (x < MIN_POS) { return -inf(); }
    if (x == inf()) { return x; }
    let b = bitcast<u32>(x);
    var e = i32(b >> 23u) - 127;
    var m = bitcast<f32>((b & 0x007fffffu) | 0x3f800000u);
    if (m > bitcast<f32>(0x3fb504f3u)) {
        m = m * 0.5;
        e = e + 1;
    }
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let lnm = s * (2.0 + s2 * (bitcast<f32>(0x3f2aaaabu) + s2 * (bitcast<f32>(0x3ecccccdu)
        + s2 * (bitcast<f32>(0x3e924925u) + s2 * (bitcast<f32>(0x3e638e39u)
        + s2 * bitcast<f32>(0x3e3a2e8cu))))));
    let ef = f32(e);
    return ef * bitcast<f32>(0x3f318000u) + (ef * bitcast<f32>(0xb95e8083u) + lnm);
}

fn cosine_side(x: f32) -> f32 {
    if (!(abs(x) <= 1.0)) { return nan(); }
    return sqrt((1.0 - x) * (1.0 + x));
}
fn t_asin(x: f32) -> f32 {
    let c = cosine_side(x);
    if (is_nan(c)) { return c; }
    return env_atan2(x, c);
}
fn t_acos(x: f32) -> f32 {
    let c = cosine_side(x);
    if (is_nan(c)) { return c; }
    return env_atan2(c, x);
}
fn t_atan(x: f32) -> f32 {
    if (is_nan(x)) { return x; }
    return env_atan2(x, 1.0);
}
// Half away from zero, as Rust's f32::round (WGSL's round goes to even).
fn t_round(x: f32) -> f32 {
    let t = trunc(x);
    if (abs(x - t) >= 0.5) { return t + select(-1.0, 1.0, x > 0.0); }
    return t;
}
fn t_mod(a: f32, b: f32) -> f32 {
    let c = abs(b);
    var r = a - c * floor(a / c);
    if (r < 0.0) { r = r + c; }
    if (r >= c) { r = r - c; }
    return r;
}
fn t_compare(a: f32, b: f32) -> f32 {
    if (is_nan(a) || is_nan(b)) { return nan(); }
    if (a < b) { return -1.0; }
    if (a > b) { return 1.0; }
    return 0.0;
}

fn entire() -> vec2<f32> { return vec2<f32>(-inf(), inf()); }
fn up8(x: f32) -> f32 { return up4(up4(x)); }
fn down8(x: f32) -> f32 { return down4(down4(x)); }

fn i_exp(a: vec2<f32>) -> vec2<f32> {
    if (any_nan(a)) { return nan2(); }
    var lo = 0.0;
    if (a.x >= EXP_LO) { lo = max(down8(t_exp(min(a.x, EXP_HI))), 0.0); }
    var hi = inf();
    if (a.y <= EXP_HI) { hi = up8(t_exp(max(a.y, EXP_LO))); }
    return vec2<f32>(lo, hi);
}
fn i_ln(a: vec2<f32>) -> vec2<f32> {
    if (any_nan(a) || a.y < 0.0) { return nan2(); }
    var lo = -inf();
    if (a.x >= MIN_POS) { lo = down8(t_ln(a.x)); }
    return vec2<f32>(lo, up8(t_ln(max(a.y, MIN_POS))));
}
fn i_asin_acos(a: vec2<f32>, cosine: bool) -> vec2<f32> {
    if (any_nan(a) || a.y < -1.0 || a.x > 1.0) { return nan2(); }
    let lo = max(a.x, -1.0);
    let hi = min(a.y, 1.0);
    if (cosine) { return vec2<f32>(t_acos(hi) - 1.0e-6, t_acos(lo) + 1.0e-6); }
    return vec2<f32>(t_asin(lo) - 1.0e-6, t_asin(hi) + 1.0e-6);
}
fn i_atan(a: vec2<f32>) -> vec2<f32> {
    if (any_nan(a)) { return nan2(); }
    return vec2<f32>(t_atan(a.x) - 1.0e-6, t_atan(a.y) + 1.0e-6);
}
fn flat_or_jump(flat: bool) -> vec2<f32> {
    if (flat) { return vec2<f32>(0.0, 0.0); }
    return entire();
}

// mod: a − k|c| with da − k·db where b is one nonzero constant c, k = ⌊a/|c|⌋ is the
// same at both ends and that interval proves itself within [0, |c|); else [0, max |b|]
// or (−∞, ∞), with a derivative of (−∞, ∞). Returns (value, derivative).
fn i_mod(a: vec2<f32>, ad: vec2<f32>, b: vec2<f32>, bd: vec2<f32>) -> vec4<f32> {
    if (any_nan(a) || any_nan(b)) { return vec4<f32>(nan2(), nan2()); }
    if (b.x == b.y && b.x != 0.0 && is_finite(b.x)) {
        let c = abs(b.x);
        if (is_finite(a.x) && is_finite(a.y)) {
            let k = floor(a.x / c);
            if (k == floor(a.y / c)) {
                let v = i_sub(a, i_mul(vec2<f32>(k, k), vec2<f32>(c, c)));
                if (v.x >= 0.0 && v.y < c) {
                    return vec4<f32>(v, i_sub(ad, i_mul(bd, vec2<f32>(k, k))));
                }
            }
        }
        return vec4<f32>(0.0, c, entire());
    }
    if (b.x > 0.0 || b.y < 0.0) { return vec4<f32>(0.0, max(abs(b.x), abs(b.y)), entire()); }
    return vec4<f32>(entire(), entire());
}
// Where a mod b's first wrap along the ray lies within a, as a fraction of a (2: none).
fn wrap_fraction(a: vec2<f32>, ad: vec2<f32>, b: vec2<f32>) -> f32 {
    if (!(b.x == b.y && b.x != 0.0 && is_finite(b.x) && is_finite(a.x) && is_finite(a.y))) { return 2.0; }
    let c = abs(b.x);
    let k0 = floor(a.x / c);
    let k1 = floor(a.y / c);
    if (!(k1 > k0 && a.y > a.x)) { return 2.0; }
    var f = 2.0;
    if (ad.x > 0.0) { f = ((k0 + 1.0) * c - a.x) / (a.y - a.x); }
    else if (ad.y < 0.0) { f = (a.y - k1 * c) / (a.y - a.x); }
    if (f > 0.0 && f < 1.0) { return f; }
    return 2.0;
}
fn i_compare(a: vec2<f32>, b: vec2<f32>) -> vec4<f32> {
    if (any_nan(a) || any_nan(b)) { return vec4<f32>(nan2(), nan2()); }
    var v = 0.0;
    if (a.y < b.x) { v = -1.0; }
    else if (a.x > b.y) { v = 1.0; }
    else if (!(a.x == a.y && b.x == b.y)) { return vec4<f32>(-1.0, 1.0, entire()); }
    return vec4<f32>(v, v, 0.0, 0.0);
}
// frep's Zero: 1 the point 0, 0 excluding 0, 2 maybe (NaN too).
fn zero_of(a: vec2<f32>) -> u32 {
    if (a.x == 0.0 && a.y == 0.0) { return 1u; }
    if (a.x > 0.0 || a.y < 0.0) { return 0u; }
    return 2u;
}
fn i_not(a: vec2<f32>) -> vec4<f32> {
    let z = zero_of(a);
    if (z == 1u) { return vec4<f32>(1.0, 1.0, 0.0, 0.0); }
    if (z == 0u) { return vec4<f32>(0.0, 0.0, 0.0, 0.0); }
    return vec4<f32>(0.0, 1.0, entire());
}
// and (or false) / or: the operand a decides, else the hull (with 0 for and).
fn i_and_or(a: vec2<f32>, ad: vec2<f32>, b: vec2<f32>, bd: vec2<f32>, is_or: bool) -> vec4<f32> {
    let z = zero_of(a);
    if (z == 2u) {
        if (is_or) { return vec4<f32>(hull(a, b), entire()); }
        return vec4<f32>(hull(vec2<f32>(0.0, 0.0), b), entire());
    }
    if ((z == 1u) != is_or) { return vec4<f32>(a, ad); }
    return vec4<f32>(b, bd);
}

// The point value of one of these operations (tape.wgsl's point_op, for ELEMENTARY tapes).
fn elementary_point(op: u32, a: f32, b: f32) -> f32 {
    switch op {
        case OP_EXP: { return t_exp(a); }
        case OP_LN: { return t_ln(a); }
        case OP_TAN: { return t_sin_cos(a, false) / t_sin_cos(a, true); }
        case OP_ASIN: { return t_asin(a); }
        case OP_ACOS: { return t_acos(a); }
        case OP_ATAN: { return t_atan(a); }
        case OP_FLOOR: { return floor(a); }
        case OP_CEIL: { return ceil(a); }
        case OP_ROUND: { return t_round(a); }
        case OP_NOT: { return select(0.0, 1.0, a == 0.0); }
        case OP_MOD: { return t_mod(a, b); }
        case OP_COMPARE: { return t_compare(a, b); }
        case OP_AND: { return select(b, a, a == 0.0); }
        case OP_OR: { return select(b, a, is_nan(a) || a != 0.0); }
        default: { return nan(); }
    }
}

// The value and derivative intervals (lo, hi, dlo, dhi) of one of these operations over
// the operands a, b (each (lo, hi, dlo, dhi)): tape.wgsl's interval_op, for ELEMENTARY
// tapes. A mod also lowers wrap_hint to its wrap_fraction.
fn elementary_interval(op: u32, a: vec4<f32>, b: vec4<f32>) -> vec4<f32> {
    var v = nan2();
    var d = nan2();
    switch op {
        case OP_EXP: { v = i_exp(a.xy); d = i_mul(v, a.zw); }
        case OP_LN: { v = i_ln(a.xy); d = i_div(a.zw, a.xy); }
        case OP_TAN: {
            v = i_div(i_sin_cos(a.xy, false), i_sin_cos(a.xy, true));
            d = i_mul(i_add(vec2<f32>(1.0, 1.0), i_square(v)), a.zw);
        }
        case OP_ASIN, OP_ACOS: {
            v = i_asin_acos(a.xy, op == OP_ACOS);
            d = i_div(a.zw, i_sqrt(i_sub(vec2<f32>(1.0, 1.0), i_square(a.xy))));
            if (op == OP_ACOS) { d = i_neg(d); }
        }
        case OP_ATAN: { v = i_atan(a.xy); d = i_div(a.zw, i_add(vec2<f32>(1.0, 1.0), i_square(a.xy))); }
        case OP_FLOOR: { v = vec2<f32>(floor(a.x), floor(a.y)); d = flat_or_jump(v.x == v.y); }
        case OP_CEIL: { v = vec2<f32>(ceil(a.x), ceil(a.y)); d = flat_or_jump(v.x == v.y); }
        case OP_ROUND: { v = vec2<f32>(t_round(a.x), t_round(a.y)); d = flat_or_jump(v.x == v.y); }
        case OP_NOT: { return i_not(a.xy); }
        case OP_MOD: {
            wrap_hint = min(wrap_hint, wrap_fraction(a.xy, a.zw, b.xy));
            return i_mod(a.xy, a.zw, b.xy, b.zw);
        }
        case OP_COMPARE: { return i_compare(a.xy, b.xy); }
        case OP_AND, OP_OR: { return i_and_or(a.xy, a.zw, b.xy, b.zw, op == OP_OR); }
        default: {}
    }
    return vec4<f32>(v, d);
}
