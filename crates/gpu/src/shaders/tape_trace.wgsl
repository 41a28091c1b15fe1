// Rays against an expression solid (GPU.md §6.2.4), a port of frep's interval tracer
// (crates/frep/src/interval_trace.rs) to f32 with fixed capacities; the CPU twin is
// gpu::tape_trace::TapeSolid::trace (its module docs say why each rule is there). Clip to
// the bounds grown by the resolution EPS; the signs at both ends; then segments from a
// ring of STACK, left half first: a segment whose F interval excludes 0 is dropped, one
// whose dF/dt excludes 0 (or shorter than EPS/|d|) is decided by its end signs and
// bisected on the sign (by the interval's middle where the sign turns open, within
// OPEN_ZONE·EPS of the proven crossing), else the mean-value test, then halving (in three, half an EPS to
// either side of the midpoint, where the midpoint's sign is open). Every sign comes from
// an interval evaluation of the point; an open sign (within f32 rounding of F = 0), an
// evaluation that would pass BUDGET, or a ring that dropped a farther segment before
// anything nearer was found end the ray with status 2 (undecided: the CPU traces it),
// never a wrong answer. One state machine with one call of `eval_interval` (llvmpipe
// inlines every call). Every eval adds eval_loops() to `loops`.
// Needs tape.wgsl, EPS and the bounds BLO, BHI (per object, prepended by the kernel).

const STACK: u32 = 32u;
// GPU.md §3.1: < 30 000 of llvmpipe's 65 535 (40 000 decided 5 more of colonnade.vm's
// 62 208 pixel centres than 24 000: the rays past it need many times more).
const BUDGET: u32 = 24000u;
const MAX_BISECT: u32 = 64u;
const OPEN_ZONE: f32 = 256.0;

struct TraceResult { status: u32, t: f32 }

// Phases: 0 sign at t0, 1 sign at t1, 2 next segment, 3 sign at a segment's midpoint,
// 4 bisection, 5 and 6 signs half an EPS below and above the midpoint.
fn trace_tape(o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32) -> TraceResult {
    let glo = BLO - vec3<f32>(EPS);
    let ghi = BHI + vec3<f32>(EPS);
    let inv = vec3<f32>(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
    let ta = (glo - o) * inv;
    let tb = (ghi - o) * inv;
    var t0 = rmax(rmax(rmax(t_min, rmin(ta.x, tb.x)), rmin(ta.y, tb.y)), rmin(ta.z, tb.z));
    var t1 = rmin(rmin(rmin(t_max, rmax(ta.x, tb.x)), rmax(ta.y, tb.y)), rmax(ta.z, tb.z));
    if (!(t0 < t1) || !is_finite(t0) || !is_finite(t1)) { return TraceResult(0u, 0.0); }
    let len = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    let eps_t = EPS / max(len, MIN_POS);
    var st_a: array<f32, STACK>;
    var st_b: array<f32, STACK>;
    var st_s: array<u32, STACK>; // bit 0: inside at a, bit 1: inside at b
    var n = 0u;
    var base = 0u;
    var lost = false;
    var phase = 0u;
    var pt = t0;
    var ia0 = false;
    var ib0 = false;
    var a = 0.0;
    var b = 0.0;
    var ia = false;
    var ib = false;
    var m = 0.0;
    var slope = vec2<f32>(0.0, 0.0);
    var steps = 0u;
    var s_lo = false;
    var retried = false;
    var retried_end = false;
    // Whether the window starts where the ray enters the bounds and ends where it leaves
    // them (before t_max), fixed before either end moves in by EPS.
    let entered = t0 > t_min;
    let exits = t1 < t_max;
    // Up to three pushes per iteration (ring order: pushed last, popped first).
    var push_n = 0u;
    var pa: array<f32, 3>;
    var pb: array<f32, 3>;
    var ps: array<u32, 3>;
    loop {
        loops++;
        for (var k = 0u; k < push_n; k++) {
            if (n == STACK) {
                base = (base + 1u) % STACK;
                n--;
                lost = true;
            }
            let at = (base + n) % STACK;
            st_a[at] = pa[k];
            st_b[at] = pb[k];
            st_s[at] = ps[k];
            n++;
        }
        loops += push_n;
        push_n = 0u;
        var lo = pt;
        var hi = pt;
        if (phase == 2u) {
            if (n == 0u) {
                if (lost) { return TraceResult(2u, 0.0); }
                if (exits && ib0) { return TraceResult(1u, t1); }
                return TraceResult(0u, 0.0);
            }
            n--;
            let at = (base + n) % STACK;
            a = st_a[at];
            b = st_b[at];
            ia = (st_s[at] & 1u) != 0u;
            ib = (st_s[at] & 2u) != 0u;
            lo = a;
            hi = b;
        } else if (phase == 4u) {
            let mid = a + (b - a) * 0.5;
            if (!(mid > a && mid < b) || steps >= MAX_BISECT) { return TraceResult(1u, b); }
            steps++;
            pt = mid;
            lo = mid;
            hi = mid;
        }
        // Room for this evaluation and the next iteration's start (1 + 3 pushes).
        if (loops + eval_loops() + 4u > BUDGET) { return TraceResult(2u, 0.0); }
        // o + t·d over [lo, hi], rounded outward: the product within an ulp, then the sum.
        let pa_lo = o + vec3<f32>(down(lo * d.x), down(lo * d.y), down(lo * d.z));
        let pa_hi = o + vec3<f32>(up(lo * d.x), up(lo * d.y), up(lo * d.z));
        let pb_lo = o + vec3<f32>(down(hi * d.x), down(hi * d.y), down(hi * d.z));
        let pb_hi = o + vec3<f32>(up(hi * d.x), up(hi * d.y), up(hi * d.z));
        let cx = vec4<f32>(down(rmin(pa_lo.x, pb_lo.x)), up(rmax(pa_hi.x, pb_hi.x)), d.x, d.x);
        let cy = vec4<f32>(down(rmin(pa_lo.y, pb_lo.y)), up(rmax(pa_hi.y, pb_hi.y)), d.y, d.y);
        let cz = vec4<f32>(down(rmin(pa_lo.z, pb_lo.z)), up(rmax(pa_hi.z, pb_hi.z)), d.z, d.z);
        let r = eval_interval(cx, cy, cz);
        if (phase == 2u) {
            if (r.x > 0.0 || r.y < 0.0) { continue; }
            slope = r.zw;
            if (r.z > 0.0 || r.w < 0.0 || b - a <= eps_t) {
                if (ia != ib) {
                    phase = 4u;
                    steps = 0u;
                }
            } else {
                // At a mod's wrap where one lies inside (a jump, which halving would
                // close in on only at ε), kept ε from the ends; else at the middle.
                m = a + (b - a) * 0.5;
                if (wrap_hint < 1.0 && b - a > 4.0 * eps_t) {
                    m = min(max(a + (b - a) * wrap_hint, a + eps_t), b - eps_t);
                }
                pt = m;
                phase = 3u;
            }
            continue;
        }
        // The point's sign where its interval decides it (NaN: outside, as F ≥ 0 is
        // false on the CPU).
        let nan_r = is_nan(r.x) || is_nan(r.y);
        let known = r.x >= 0.0 || r.y < 0.0 || nan_r;
        let inside = r.x >= 0.0;
        if (!known) {
            if (phase == 4u) {
                // Within f32 rounding of the proven crossing: on by the interval's
                // middle, unless the zone may reach farther than OPEN_ZONE·EPS.
                // The zone's reach: the bracket, or for a monotone segment the Newton
                // bound |F(pt)|/min|F'| (Moore 1966, §7).
                let monotone = slope.x > 0.0 || slope.y < 0.0;
                let reach = rmax(abs(r.x), abs(r.y)) / select(-slope.y, slope.x, slope.x > 0.0);
                if (b - a > OPEN_ZONE * eps_t && !(monotone && reach <= OPEN_ZONE * eps_t)) {
                    return TraceResult(2u, 0.0);
                }
                if ((r.x + r.y >= 0.0) == ia) { a = pt; } else { b = pt; }
                continue;
            }
            if (phase == 3u) {
                phase = 5u;
                pt = m - 0.5 * eps_t;
                continue;
            }
            // A window end within rounding of the surface: one ε in, once (the first
            // and last ε lie below the resolution).
            if (phase == 0u && !retried && t0 + eps_t < t1 && t0 + eps_t > t0) {
                t0 += eps_t;
                pt = t0;
                retried = true;
                continue;
            }
            if (phase == 1u && !retried_end && t1 - eps_t > t0 && t1 - eps_t < t1) {
                t1 -= eps_t;
                pt = t1;
                retried_end = true;
                continue;
            }
            return TraceResult(2u, 0.0);
        }
        if (phase == 0u) {
            ia0 = inside;
            // Inside where the ray enters the bounds: a crossing there (not where the
            // window starts at t_min, even one moved in by EPS).
            if (entered && ia0) { return TraceResult(1u, t0); }
            phase = 1u;
            pt = t1;
        } else if (phase == 1u) {
            ib0 = inside;
            pa[0] = t0;
            pb[0] = t1;
            ps[0] = select(0u, 1u, ia0) | select(0u, 2u, ib0);
            push_n = 1u;
            phase = 2u;
        } else if (phase == 3u) {
            phase = 2u;
            // The mean-value form F(m) + F'·([a, b] − m) (Moore 1966, §6).
            let mv = i_add(r.xy, i_mul(slope, w1(a - m, b - m)));
            if (ia == ib && (mv.x > 0.0 || mv.y < 0.0)) { continue; }
            let sm = select(0u, 1u, inside);
            pa[0] = m;
            pb[0] = b;
            ps[0] = sm | select(0u, 2u, ib);
            pa[1] = a;
            pb[1] = m;
            ps[1] = select(0u, 1u, ia) | (sm << 1u);
            push_n = 2u;
        } else if (phase == 5u) {
            s_lo = inside;
            phase = 6u;
            pt = split_hi(m, eps_t);
        } else if (phase == 6u) {
            phase = 2u;
            let lo3 = m - 0.5 * eps_t;
            let hi3 = split_hi(m, eps_t);
            let sl = select(0u, 1u, s_lo);
            let sh = select(0u, 1u, inside);
            pa[0] = hi3;
            pb[0] = b;
            ps[0] = sh | select(0u, 2u, ib);
            pa[1] = lo3;
            pb[1] = hi3;
            ps[1] = sl | (sh << 1u);
            pa[2] = a;
            pb[2] = lo3;
            ps[2] = select(0u, 1u, ia) | (sl << 1u);
            push_n = 3u;
        } else {
            if (inside == ia) { a = pt; } else { b = pt; }
        }
    }
    return TraceResult(0u, 0.0);
}

// The upper end of the piece of at most ε around an open split point m (the lower is
// m − ε/2): below (m − ε/2) + ε, so that rounding never makes the piece longer than ε
// and it is decided by its end signs, not split about the same open point again.
fn split_hi(m: f32, eps_t: f32) -> f32 { return down((m - 0.5 * eps_t) + eps_t); }
