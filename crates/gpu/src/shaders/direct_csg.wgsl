// --- CSG by inside spans ------------------------------------------------------------------
//
// Each leaf's inside set along the ray is a sorted list of ends; a node's is the boolean
// combination of its parts' (a sweep over their sorted ends), so the post-order node list
// runs on a stack of span lists in a fixed pool. An end keeps the leaf whose root it is,
// and a flip bit (bit 31) where a difference turns that leaf's outside in (its normal
// then points the other way, as frep's combine). The crossing is the first end in
// (t_min, t_max). A pool or stack overflow is reported (status 2), never a miss.
//
// A plain quadric's ends are its positive set on the whole line (≤ 2 intervals, closed
// form). A perturbed or expression part has no closed form: its ends are its crossings
// found one by one, as frep's combine finds them, from a nudge before its box (where it
// is outside) to the window's end (the shape's box grown, on (t_min, t_max)), each search
// starting a nudge past the last end. Those searches are the scene's costly crossing
// functions, which llvmpipe inlines at every call site (GPU.md, compile time), so the
// walk is resumable: `csg_run` stops at a general part and asks `scene_trace`, whose one
// call site runs every search, then `csg_feed` takes each answer.

const SPAN_POOL: u32 = 64u;
const SPAN_LISTS: u32 = 16u;
// Past this many loop iterations a CSG walk reports overflow (the CPU renders the
// sample), so that its repeated searches keep the invocation's budget (GPU.md §3.1).
const CSG_BUDGET: u32 = 28000u;
var<private> sp_t: array<f32, SPAN_POOL>;
var<private> sp_k: array<u32, SPAN_POOL>;
var<private> tmp_t: array<f32, SPAN_POOL>;
var<private> tmp_k: array<u32, SPAN_POOL>;
var<private> ls_at: array<u32, SPAN_LISTS>;

// The walk of one CSG shape: its nodes, the next one, the pool and stack in use, the
// segment and window, and the general part being searched (from cs_ta to cs_tb).
var<private> cs_first: u32;
var<private> cs_count: u32;
var<private> cs_i: u32;
var<private> cs_top: u32;
var<private> cs_nl: u32;
var<private> cs_tmin: f32;
var<private> cs_tmax: f32;
var<private> cs_w: vec2<f32>;
var<private> cs_general: bool;
var<private> cs_pending: bool;
var<private> cs_leaf: u32;
var<private> cs_ta: f32;
var<private> cs_tb: f32;
var<private> cs_nudge: f32;

fn csg_inside(op: u32, first: bool, inside: u32, count: u32) -> bool {
    if (op == 1u) { return inside > 0u; }
    if (op == 2u) { return inside == count; }
    // Difference: inside the first part, outside every other.
    return first && inside == 1u;
}

fn csg_start(sh: GpuShape, o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32) {
    cs_first = sh.first;
    cs_count = sh.count;
    cs_i = 0u;
    cs_top = 0u;
    cs_nl = 0u;
    cs_tmin = t_min;
    cs_tmax = t_max;
    let grow = vec3<f32>(1e-5 * length(sh.hi.xyz - sh.lo.xyz));
    let inv = vec3<f32>(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
    cs_w = clip_box(sh.lo.xyz - grow, sh.hi.xyz + grow, o, inv, t_min, t_max);
    cs_general = false;
    cs_pending = false;
    csg_clip_window(o, d);
}

// Narrows the window to the hull of the inside set of each plain quadric that the
// shape's inside set lies in: a part whose ancestors are all intersections (or first
// parts of differences). The shape's crossings lie in that hull, so general parts are
// searched no farther (a 2-D model shown as a slab, prospero ∩ |z| ≤ h: a shadow ray
// leaving the slab no longer searches the text's tape up to its box, crossing letter
// after letter until the loop budget ran out). An empty hull empties the window.
fn csg_clip_window(o: vec3<f32>, d: vec3<f32>) {
    let root = csg[cs_first + cs_count - 1u];
    if (root.x != 2u && root.x != 3u) { return; }
    // Only a shape with a general part searches; the others keep their window.
    var general = false;
    for (var j = 0u; j < cs_count; j++) {
        loops++;
        let node = csg[cs_first + j];
        general = general || (node.x == 0u && objects[node.y].kind != 0u);
    }
    if (!general) { return; }
    // Per open op, its parts still to visit, whether its inside set lies in each of
    // them (an intersection) or in its first (a difference), and whether it lies in
    // every part above it.
    var left: array<u32, 16>;
    var op: array<u32, 16>;
    var within: array<bool, 16>;
    left[0] = root.y;
    op[0] = root.x;
    within[0] = true;
    var sp = 1u;
    // In reverse post-order each node is a part of the op on top whose parts are left.
    for (var j = cs_count - 1u; j > 0u; j--) {
        loops++;
        while (sp > 0u && left[sp - 1u] == 0u) { sp--; }
        if (sp == 0u) { return; }
        left[sp - 1u]--;
        // The last part visited is the first part.
        let lies = within[sp - 1u] && (op[sp - 1u] == 2u || left[sp - 1u] == 0u);
        let node = csg[cs_first + j - 1u];
        if (node.x != 0u) {
            if (sp == 16u) { return; }
            left[sp] = node.y;
            op[sp] = node.x;
            within[sp] = lies;
            sp++;
            continue;
        }
        if (!lies || objects[node.y].kind != 0u) { continue; }
        let cq = quadric_centred(quadrics[objects[node.y].first_op].c, o, d, cs_w.x, cs_w.y);
        if (cq.open) { continue; }
        let ps = positive_set(cq.k);
        if (ps.n == 0u) {
            cs_w = vec2<f32>(1.0, 0.0);
            return;
        }
        let a = ps.s.x + cq.tc;
        let b = select(ps.s.y, ps.s.w, ps.n == 2u) + cq.tc;
        // A margin for the f32 ends: the hull's own ends stay inside the window.
        let m = 1e-5 * (1.0 + max(abs(a), abs(b)));
        cs_w = vec2<f32>(rmax(cs_w.x, a - m), rmin(cs_w.y, b + m));
        if (!(cs_w.x <= cs_w.y)) { return; }
    }
}

// Takes a general part's search answer (status 0 none, 1 at t, 2 overflow): 0 when that
// part has more to search, 1 when it is done, 2 on overflow.
fn csg_feed(status: u32, t: f32) -> u32 {
    if (status == 2u || loops > CSG_BUDGET) { return 2u; }
    if (status == 1u) {
        if (cs_top == SPAN_POOL) { return 2u; }
        sp_t[cs_top] = t;
        sp_k[cs_top] = cs_leaf;
        cs_top++;
        cs_ta = t + cs_nudge + 1e-6 * abs(t);
        if (cs_ta < cs_tb) { return 0u; }
    }
    cs_pending = false;
    return 1u;
}

// Runs the walk on from node cs_i: (t, leaf | flip << 31 bits, status) with status 0
// miss, 1 hit, 2 overflow, 3 a general part's search wanted (cs_leaf, cs_ta, cs_tb).
fn csg_run(o: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    var top = cs_top;
    var nl = cs_nl;
    for (var i = cs_i; i < cs_count; i++) {
        loops++;
        let node = csg[cs_first + i];
        if (node.x == 0u && objects[node.y].kind != 0u) {
            if (nl == SPAN_LISTS) { return vec3<f32>(0.0, 0.0, 2.0); }
            if (!(cs_w.x <= cs_w.y)) { return vec3<f32>(0.0); }
            ls_at[nl] = top;
            nl++;
            cs_general = true;
            let ob = objects[node.y];
            let lo = vec3<f32>(ob.lo_x, ob.lo_y, ob.lo_z);
            let hi = vec3<f32>(ob.hi_x, ob.hi_y, ob.hi_z);
            let inv = vec3<f32>(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
            let c = clip_box(lo, hi, o, inv, -inf(), cs_w.y);
            if (!(c.x <= c.y)) { continue; }
            cs_nudge = 8e-6 * length(hi - lo) / length(d);
            cs_leaf = node.y;
            cs_ta = c.x - cs_nudge - 1e-6 * abs(c.x);
            cs_tb = c.y;
            cs_pending = true;
            cs_i = i + 1u;
            cs_top = top;
            cs_nl = nl;
            return vec3<f32>(0.0, 0.0, 3.0);
        }
        if (node.x == 0u) {
            if (nl == SPAN_LISTS || top + 4u > SPAN_POOL) { return vec3<f32>(0.0, 0.0, 2.0); }
            // About the ray's vertex (quadric_centred); open: for the CPU.
            let cq = quadric_centred(quadrics[objects[node.y].first_op].c, o, d, cs_w.x, cs_w.y);
            if (cq.open) { return vec3<f32>(0.0, 0.0, 2.0); }
            var ps = positive_set(cq.k);
            ps.s = ps.s + vec4<f32>(cq.tc);
            ls_at[nl] = top;
            nl++;
            for (var w = 0u; w < 2u * ps.n; w++) {
                loops++;
                sp_t[top] = ps.s[w];
                sp_k[top] = node.y;
                top++;
            }
            continue;
        }
        // Combine the last `node.y` lists: repeated selection of the least head.
        let k = node.y;
        let base = ls_at[nl - k];
        var head: array<u32, 8>;
        var end: array<u32, 8>;
        var inside_j: array<bool, 8>;
        for (var j = 0u; j < k; j++) {
            loops++;
            head[j] = ls_at[nl - k + j];
            end[j] = top;
            if (j + 1u < k) { end[j] = ls_at[nl - k + j + 1u]; }
            inside_j[j] = false;
        }
        var inside = 0u;
        var state = false;
        var n = 0u;
        loop {
            loops += 1u + k;
            var best = 8u;
            var bt = 0.0;
            for (var j = 0u; j < k; j++) {
                if (head[j] < end[j] && (best == 8u || sp_t[head[j]] < bt)) {
                    best = j;
                    bt = sp_t[head[j]];
                }
            }
            if (best == 8u) { break; }
            let e = head[best];
            head[best]++;
            inside_j[best] = !inside_j[best];
            if (inside_j[best]) { inside++; } else { inside--; }
            let now = csg_inside(node.x, inside_j[0], inside, k);
            if (now != state) {
                state = now;
                if (n == SPAN_POOL) { return vec3<f32>(0.0, 0.0, 2.0); }
                var key = sp_k[e];
                if (node.x == 3u && best > 0u) { key = key ^ 0x80000000u; }
                tmp_t[n] = sp_t[e];
                tmp_k[n] = key;
                n++;
            }
        }
        if (base + n > SPAN_POOL) { return vec3<f32>(0.0, 0.0, 2.0); }
        for (var j = 0u; j < n; j++) {
            loops++;
            sp_t[base + j] = tmp_t[j];
            sp_k[base + j] = tmp_k[j];
        }
        top = base + n;
        nl = nl - k + 1u;
    }
    // A general part's ends are known only up to the window's end; before the window
    // the shape is empty.
    for (var j = 0u; j < top; j++) {
        loops++;
        let t = sp_t[j];
        let in_window = !cs_general || (t > cs_w.x && t <= cs_w.y);
        if (t > cs_tmin && t < cs_tmax && is_finite(t) && in_window) {
            return vec3<f32>(t, bitcast<f32>(sp_k[j]), 1.0);
        }
    }
    return vec3<f32>(0.0);
}
