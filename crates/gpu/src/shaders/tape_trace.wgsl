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
// With a walk grid (GRID_AT != 0, and the ray's magnitudes in cells within WALK_REACH)
// the window is walked cell by cell (Amanatides & Woo 1987): empty cells give F's sign,
// each run of occupied cells that share a tape is searched as above with that tape,
// the signs at its ends from the empty cells beside it, else from its tape.
// Needs tape.wgsl, EPS, the bounds BLO, BHI and GRID_AT (per object, set by use_tape).

const STACK: u32 = 32u;
// GPU.md §3.1: < 30 000 of llvmpipe's 65 535 (40 000 decided 5 more of colonnade.vm's
// 62 208 pixel centres than 24 000: the rays past it need many times more).
const BUDGET: u32 = 24000u;
const MAX_BISECT: u32 = 64u;
const OPEN_ZONE: f32 = 256.0;
const WALK_REACH: f32 = 2048.0;
const NO_TAPE: u32 = 0xffffffffu;
const INSIDE: u32 = 0xfffffffeu;
var<private> table_at: u32;

// Points the interpreter at cell tape j of the walk grid.
fn use_cell(j: u32) {
    tape_base = tape[table_at + 2u * j];
    tape_ops = tape[table_at + 2u * j + 1u];
}

struct TraceResult { status: u32, t: f32 }

// Phases: 0 sign at t0, 1 sign at t1, 2 next segment, 3 sign at a segment's midpoint,
// 4 bisection, 5 and 6 signs half an EPS below and above the midpoint; walking: 7 the
// next cell, 8 sign where a run meets a run of another tape, 9 sign at t1 ending a run.
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
    var short_seg = false;
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
    // The walk: the grid's cells per unit, the ray in cell units (g0 + t·gd), the cell,
    // the t of its next face per axis; where the walk stands (tw) and F's sign there;
    // the open run (its start, tape, sign at its start); phase 8's next tape.
    var walk = false;
    var gn = 0u;
    var cells_at = 0u;
    var g0 = vec3<f32>(0.0, 0.0, 0.0);
    var gd = vec3<f32>(0.0, 0.0, 0.0);
    var cc = vec3<i32>(0, 0, 0);
    var nx = vec3<f32>(0.0, 0.0, 0.0);
    var tw = t0;
    var last_in = false;
    var run_open = false;
    var run_a = 0.0;
    var run_tape = 0u;
    var run_in = false;
    var pending = 0u;
    var walk_done = false;
    if (GRID_AT != 0u) {
        let gw = GRID_AT;
        gn = tape[gw];
        let glo = vec3<f32>(bitcast<f32>(tape[gw + 1u]), bitcast<f32>(tape[gw + 2u]), bitcast<f32>(tape[gw + 3u]));
        let gs = vec3<f32>(bitcast<f32>(tape[gw + 4u]), bitcast<f32>(tape[gw + 5u]), bitcast<f32>(tape[gw + 6u]));
        g0 = (o - glo) * gs;
        gd = d * gs;
        let mag = rmax(rmax(abs(g0.x), abs(g0.y)), abs(g0.z)) + bitcast<f32>(tape[gw + 7u]);
        if (mag <= WALK_REACH) {
            walk = true;
            table_at = tape[gw + 8u];
            cells_at = gw + 9u;
            let u = g0 + t0 * gd;
            let top = f32(gn - 1u);
            cc = vec3<i32>(i32(rmin(rmax(floor(u.x), 0.0), top)), i32(rmin(rmax(floor(u.y), 0.0), top)), i32(rmin(rmax(floor(u.z), 0.0), top)));
            nx = vec3<f32>(walk_face(cc.x, g0.x, gd.x), walk_face(cc.y, g0.y, gd.y), walk_face(cc.z, g0.z, gd.z));
            let s0 = tape[cells_at + (u32(cc.z) * gn + u32(cc.y)) * gn + u32(cc.x)];
            if (s0 >= INSIDE) {
                // An empty cell at t0: its sign, no evaluation.
                ia0 = s0 == INSIDE;
                if (entered && ia0) { return TraceResult(1u, t0); }
                last_in = ia0;
                phase = 7u;
            } else {
                use_cell(s0);
            }
        }
    }
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
        if (phase == 7u) {
            // The cell cc over [tw, its exit].
            if (loops + 4u > BUDGET) { return TraceResult(2u, 0.0); }
            let s = tape[cells_at + (u32(cc.z) * gn + u32(cc.y)) * gn + u32(cc.x)];
            var ax = 0;
            var tf = nx.x;
            if (nx.y < tf) { ax = 1; tf = nx.y; }
            if (nx.z < tf) { ax = 2; tf = nx.z; }
            let t_out = rmin(tf, t1);
            if (s >= INSIDE) {
                let s_in = s == INSIDE;
                if (run_open) {
                    // The run ends where this empty cell starts, with its sign.
                    pa[0] = run_a;
                    pb[0] = tw;
                    ps[0] = select(0u, 1u, run_in) | select(0u, 2u, s_in);
                    push_n = 1u;
                    run_open = false;
                    use_cell(run_tape);
                    phase = 2u;
                }
                last_in = s_in;
            } else if (run_open && s != run_tape) {
                // Another tape: the sign here by the run's own, then this cell again.
                pending = s;
                use_cell(run_tape);
                pt = tw;
                phase = 8u;
                continue;
            } else if (!run_open) {
                run_open = true;
                run_a = tw;
                run_tape = s;
                run_in = last_in;
            }
            if (t_out >= t1) {
                walk_done = true;
            } else {
                cc[ax] += select(-1, 1, gd[ax] > 0.0);
                if (cc[ax] < 0 || cc[ax] >= i32(gn)) {
                    walk_done = true;
                } else {
                    nx[ax] = walk_face(cc[ax], g0[ax], gd[ax]);
                    tw = rmax(t_out, tw);
                }
            }
            if (walk_done && phase == 7u) {
                if (run_open) {
                    use_cell(run_tape);
                    pt = t1;
                    phase = 9u;
                } else if (exits && last_in) {
                    return TraceResult(1u, t1);
                } else {
                    return TraceResult(0u, 0.0);
                }
            }
            continue;
        }
        var lo = pt;
        var hi = pt;
        if (phase == 2u) {
            if (n == 0u) {
                if (lost) { return TraceResult(2u, 0.0); }
                if (walk) {
                    if (!walk_done) {
                        phase = 7u;
                        continue;
                    }
                    if (exits && last_in) { return TraceResult(1u, t1); }
                    return TraceResult(0u, 0.0);
                }
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
            let monotone = r.z > 0.0 || r.w < 0.0;
            if (monotone || b - a <= eps_t) {
                if (ia != ib) {
                    phase = 4u;
                    steps = 0u;
                } else if (!monotone && is_finite(r.z) && is_finite(r.w)) {
                    // Shorter than ε, the same sign at both ends, F continuous and
                    // turning in between: the sign at the middle and the mean-value test
                    // decide it, else it may hold a sliver thinner than f32 resolves (a
                    // letter's corner in prospero was 0.3 ε thick), for the CPU. (A
                    // piece holding a jump of F, a mod's wrap or an `if`, is decided by
                    // its end signs: f32 places the jump no closer.)
                    short_seg = true;
                    m = a + (b - a) * 0.5;
                    pt = m;
                    phase = 3u;
                }
            } else {
                short_seg = false;
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
                if (short_seg) { return TraceResult(2u, 0.0); }
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
            if (phase == 9u && !retried_end && t1 - eps_t > run_a && t1 - eps_t < t1) {
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
            if (walk) {
                last_in = ia0;
                tw = t0;
                phase = 7u;
            } else {
                phase = 1u;
                pt = t1;
            }
        } else if (phase == 8u || phase == 9u) {
            // The run ends here (at tw, or at t1 ending the walk); in phase 8 the next
            // starts here (its cell examined again).
            pa[0] = run_a;
            pb[0] = select(t1, tw, phase == 8u);
            ps[0] = select(0u, 1u, run_in) | select(0u, 2u, inside);
            push_n = 1u;
            run_open = phase == 8u;
            run_a = tw;
            run_tape = pending;
            run_in = inside;
            last_in = inside;
            phase = 2u;
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
            if (short_seg && inside == ia) { return TraceResult(2u, 0.0); }
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

// The t where the walk leaves cell c along an axis (∞ where the ray does not move
// along it), from the ray in cell units g0 + t·gd: computed afresh, not accumulated.
fn walk_face(c: i32, g0: f32, gd: f32) -> f32 {
    if (gd == 0.0) { return inf(); }
    return (f32(c + select(0, 1, gd > 0.0)) - g0) / gd;
}

// The upper end of the piece of at most ε around an open split point m (the lower is
// m − ε/2): below (m − ε/2) + ε, so that rounding never makes the piece longer than ε
// and it is decided by its end signs, not split about the same open point again.
fn split_hi(m: f32, eps_t: f32) -> f32 { return down((m - 0.5 * eps_t) + eps_t); }
