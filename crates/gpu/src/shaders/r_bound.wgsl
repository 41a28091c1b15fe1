// R-functions in tapes (gpu::r_bound, operation for operation): a sum a + b marked in
// its immediate word (bit 31; bit 30 clear) stores the R-function's corners in a side
// register; the final ± (bits 31 and 30) narrows its interval to them. Compiled in
// where RBOUND (a tape has such a mark).

var<private> rside: array<vec2<f32>, 16>;

// The R-function's value interval at the point (x, y), without cancellation: the union
// as −2xy/(r − x − y) where x + y < 0, the intersection as 2xy/(x + y + r) where x + y > 0.
fn r_at(x: f32, y: f32, is_union: bool) -> vec2<f32> {
    let px = vec2<f32>(x, x);
    let py = vec2<f32>(y, y);
    let root = i_sqrt(i_add(i_square(px), i_square(py)));
    let sum = i_add(px, py);
    let two_xy = i_mul(vec2<f32>(2.0, 2.0), i_mul(px, py));
    let s = x + y;
    if (is_union) {
        if (s < 0.0) { return i_div(vec2<f32>(-two_xy.y, -two_xy.x), i_sub(root, sum)); }
        return i_add(sum, root);
    }
    if (s > 0.0) { return i_div(two_xy, i_add(sum, root)); }
    return i_sub(sum, root);
}

fn r_corners(a: vec2<f32>, b: vec2<f32>, is_union: bool) -> vec2<f32> {
    if (!(is_finite(a.x) && is_finite(a.y) && is_finite(b.x) && is_finite(b.y))) {
        return vec2<f32>(-inf(), inf());
    }
    return vec2<f32>(r_at(a.x, b.x, is_union).x, r_at(a.y, b.y, is_union).y);
}

fn r_narrow(v: vec2<f32>, c: vec2<f32>) -> vec2<f32> {
    if (any_nan(v)) { return v; }
    let lo = max(v.x, c.x);
    let hi = min(v.y, c.y);
    if (lo <= hi) { return vec2<f32>(lo, hi); }
    return v;
}

// The sum or difference v of a and b, with the mark w (the immediate word of a
// register-register sum): stashes or narrows.
fn r_mark(w: u32, a: vec2<f32>, b: vec2<f32>, v: vec2<f32>) -> vec2<f32> {
    if ((w & 0x80000000u) == 0u) { return v; }
    let slot = w & 0xffu;
    if ((w & 0x40000000u) != 0u) { return r_narrow(v, rside[slot]); }
    rside[slot] = r_corners(a, b, (w & 0x20000000u) != 0u);
    return v;
}
