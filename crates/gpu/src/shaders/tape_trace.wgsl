// Rays against an expression solid (GPU.md §6.2.4), a port of frep's interval tracer
// (crates/frep/src/interval_trace.rs) to f32 with fixed capacities; the CPU twin is
// gpu::tape_trace::TapeSolid::trace. Clip to the bounds grown by the resolution EPS; the
// sign at both ends; then segments from an explicit stack of STACK, left half first: a
// segment whose F interval excludes 0 is dropped, one whose dF/dt excludes 0 (or shorter
// than EPS/|d|) is decided by its end signs and bisected on the sign down to adjacent
// f32, else the mean-value test, then halving. One state machine, so that `eval_point`
// and `eval_interval` each have a single call site (llvmpipe inlines every call).
// Every eval adds EVAL_LOOPS to `loops`. Once an eval would pass SOFT = BUDGET minus
// a reserve for one bisection and the stack, the segments left are decided by their end
// signs (as frep past MAX_SEGMENTS) and status gets bit 2 (4: late); an eval that would
// pass BUDGET, or a full stack, ends the ray with status 2 (undecided), never a silent
// miss.
// Needs tape.wgsl, EPS and the bounds BLO, BHI (per object, prepended by the kernel).

const STACK: u32 = 32u;
const BUDGET: u32 = 24000u;
const MAX_BISECT: u32 = 64u;

struct TraceResult { status: u32, t: f32 }

fn soft_budget() -> u32 {
    let reserve = (MAX_BISECT + 2u) * (EVAL_LOOPS + 1u) + STACK;
    return select(0u, BUDGET - reserve, BUDGET > reserve);
}

fn trace_tape(o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32) -> TraceResult {
    let glo = BLO - vec3<f32>(EPS);
    let ghi = BHI + vec3<f32>(EPS);
    let inv = vec3<f32>(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
    let ta = (glo - o) * inv;
    let tb = (ghi - o) * inv;
    let t0 = rmax(rmax(rmax(t_min, rmin(ta.x, tb.x)), rmin(ta.y, tb.y)), rmin(ta.z, tb.z));
    let t1 = rmin(rmin(rmin(t_max, rmax(ta.x, tb.x)), rmax(ta.y, tb.y)), rmax(ta.z, tb.z));
    if (!(t0 < t1) || !is_finite(t0) || !is_finite(t1)) { return TraceResult(0u, 0.0); }
    let len = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    let eps_t = EPS / max(len, MIN_POS);
    var st_a: array<f32, STACK>;
    var st_b: array<f32, STACK>;
    var st_s: array<u32, STACK>; // bit 0: inside at a, bit 1: inside at b
    var n = 0u;
    // Phases: 0 sign at t0, 1 sign at t1, 2 next segment, 3 sign at a segment's midpoint,
    // 4 bisection.
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
    var late = 0u;
    let soft = soft_budget();
    loop {
        loops++;
        if (phase == 2u) {
            if (n == 0u) {
                if (t1 < t_max && ib0) { return TraceResult(1u | late, t1); }
                return TraceResult(late, 0.0);
            }
            n--;
            a = st_a[n];
            b = st_b[n];
            ia = (st_s[n] & 1u) != 0u;
            ib = (st_s[n] & 2u) != 0u;
            if (late != 0u || loops + EVAL_LOOPS > soft) {
                late = 4u;
                if (ia == ib) { continue; }
                phase = 4u;
                steps = 0u;
            }
        }
        if (phase == 2u) {
            // o + t·d over [a, b], rounded outward: the product within an ulp, then the sum.
            let pa_lo = o + vec3<f32>(down(a * d.x), down(a * d.y), down(a * d.z));
            let pa_hi = o + vec3<f32>(up(a * d.x), up(a * d.y), up(a * d.z));
            let pb_lo = o + vec3<f32>(down(b * d.x), down(b * d.y), down(b * d.z));
            let pb_hi = o + vec3<f32>(up(b * d.x), up(b * d.y), up(b * d.z));
            let cx = vec4<f32>(down(rmin(pa_lo.x, pb_lo.x)), up(rmax(pa_hi.x, pb_hi.x)), d.x, d.x);
            let cy = vec4<f32>(down(rmin(pa_lo.y, pb_lo.y)), up(rmax(pa_hi.y, pb_hi.y)), d.y, d.y);
            let cz = vec4<f32>(down(rmin(pa_lo.z, pb_lo.z)), up(rmax(pa_hi.z, pb_hi.z)), d.z, d.z);
            let r = eval_interval(cx, cy, cz);
            if (r.x > 0.0 || r.y < 0.0) { continue; }
            if (r.z > 0.0 || r.w < 0.0 || b - a <= eps_t) {
                if (ia != ib) {
                    phase = 4u;
                    steps = 0u;
                } else {
                    continue;
                }
            } else {
                slope = r.zw;
                m = a + (b - a) * 0.5;
                pt = m;
                phase = 3u;
            }
        }
        if ((phase == 3u || phase < 2u) && loops + EVAL_LOOPS > soft) {
            if (phase < 2u) { return TraceResult(2u, 0.0); }
            late = 4u;
            if (ia == ib) {
                phase = 2u;
                continue;
            }
            phase = 4u;
            steps = 0u;
        }
        if (phase == 4u) {
            let mid = a + (b - a) * 0.5;
            if (!(mid > a && mid < b) || steps >= MAX_BISECT) { return TraceResult(1u | late, b); }
            steps++;
            pt = mid;
        }
        if (loops + EVAL_LOOPS > BUDGET) { return TraceResult(2u, 0.0); }
        let f = eval_point(o + pt * d);
        let inside = f >= 0.0;
        if (phase == 0u) {
            ia0 = inside;
            if (t0 > t_min && ia0) { return TraceResult(1u, t0); }
            phase = 1u;
            pt = t1;
        } else if (phase == 1u) {
            ib0 = inside;
            st_a[0] = t0;
            st_b[0] = t1;
            st_s[0] = select(0u, 1u, ia0) | select(0u, 2u, ib0);
            n = 1u;
            phase = 2u;
        } else if (phase == 3u) {
            phase = 2u;
            // The mean-value form F(m) + F'·([a, b] − m) (Moore 1966, §6).
            let mv = i_add(vec2<f32>(f, f), i_mul(slope, w1(a - m, b - m)));
            if (ia == ib && (mv.x > 0.0 || mv.y < 0.0)) { continue; }
            if (n + 2u > STACK) { return TraceResult(2u, 0.0); }
            let sm = select(0u, 1u, inside);
            st_a[n] = m;
            st_b[n] = b;
            st_s[n] = sm | select(0u, 2u, ib);
            st_a[n + 1u] = a;
            st_b[n + 1u] = m;
            st_s[n + 1u] = select(0u, 1u, ia) | (sm << 1u);
            n += 2u;
        } else {
            if (inside == ia) { a = pt; } else { b = pt; }
        }
    }
    return TraceResult(0u, 0.0);
}
