// --- lights ------------------------------------------------------------------------

// The nearest area light along the ray: (t, index bits) with the radiance it sends back
// along −d (0 from a non-emitting side); t = ∞ when none. Emitting objects' bounding
// spheres (pad0 = 1) are not met.
struct LightHit { t: f32, index: u32, le: vec3<f32>, n: vec3<f32> }

// Whether o + t·d, t ∈ [0, t_max], meets the box (the f32 slab test, ignoring the NaN
// of a zero direction component as frep's does; inv = 1/d).
fn lbox_hit(lo: vec3<f32>, hi: vec3<f32>, o: vec3<f32>, inv: vec3<f32>, t_max: f32) -> bool {
    var near = 0.0;
    var far = t_max;
    let a = (lo - o) * inv;
    let b = (hi - o) * inv;
    near = rmax(near, rmin(a.x, b.x)); far = rmin(far, rmax(a.x, b.x));
    near = rmax(near, rmin(a.y, b.y)); far = rmin(far, rmax(a.y, b.y));
    near = rmax(near, rmin(a.z, b.z)); far = rmin(far, rmax(a.z, b.z));
    return near <= far;
}

// A walk over the area lights whose box a ray crosses, in the light BVH's leaf order
// (frame.lbvh, escape layout, GPU.md §6.1): a cursor, so that each light query keeps
// its own loop body. `t_max` may shrink as a nearest-hit query finds lights.
struct LightWalk { node: u32, item: u32, end: u32, t_max: f32, o: vec3<f32>, inv: vec3<f32> }

fn light_walk(o: vec3<f32>, d: vec3<f32>, t_max: f32) -> LightWalk {
    return LightWalk(0u, 0u, 0u, t_max, o, vec3<f32>(1.0 / d.x, 1.0 / d.y, 1.0 / d.z));
}

// The next light of the walk (its index), or 0xffffffff at its end.
fn light_next(w: ptr<function, LightWalk>) -> u32 {
    loop {
        loops++;
        if ((*w).item < (*w).end) {
            let b = items[frame.lbvh.z + (*w).item];
            (*w).item += 1u;
            if (lbox_hit(vec3<f32>(b.lo_x, b.lo_y, b.lo_z), vec3<f32>(b.hi_x, b.hi_y, b.hi_z), (*w).o, (*w).inv, (*w).t_max)) {
                return b.item;
            }
            continue;
        }
        if ((*w).node >= frame.lbvh.y) { return 0xffffffffu; }
        let n = nodes[frame.lbvh.x + (*w).node];
        let count = n.count_axis & 0x3fffffffu;
        let hit = lbox_hit(vec3<f32>(n.lo_x, n.lo_y, n.lo_z), vec3<f32>(n.hi_x, n.hi_y, n.hi_z), (*w).o, (*w).inv, (*w).t_max);
        if (hit && count > 0u) {
            (*w).item = n.offset;
            (*w).end = n.offset + count;
        }
        if (hit || count > 0u) { (*w).node += 1u; } else { (*w).node = n.offset; }
    }
    return 0xffffffffu;
}

fn nearest_light(o: vec3<f32>, d: vec3<f32>, t_max: f32) -> LightHit {
    var h = LightHit(inf(), 0u, vec3<f32>(0.0), vec3<f32>(0.0));
    var best = t_max;
    var w = light_walk(o, d, t_max);
    for (var i = light_next(&w); i != 0xffffffffu; i = light_next(&w)) {
        let l = lights[i];
        // An emitting object's bounding sphere is no surface (Lights::intersect).
        if (l.pad0 != 0u) { continue; }
        let c = light_intersect(l, o, d, 0.0, best);
        if (c.x > 0.0) {
            best = c.x;
            w.t_max = best;
            var le = vec3<f32>(0.0);
            if (light_emits(l, c.yzw, -d)) { le = l.radiance.xyz; }
            h = LightHit(c.x, i, le, c.yzw);
        }
    }
    return h;
}

// The MIS lights: the area lights, then the environment (render::light::Lights::count).
fn n_mis() -> u32 {
    return frame.n_lights + select(0u, 1u, frame.env.kind != ENV_NONE);
}

// Radiance arriving along d from the nearest light `lh` found, or from the environment
// where the ray escapes (render::light::Lights::radiance_along over (0, ∞)).
fn incoming(lh: LightHit, d: vec3<f32>) -> vec3<f32> {
    if (lh.t < inf()) { return lh.le; }
    return env_radiance(frame.env, d);
}

// The spatial selection (render::light::Selection::Spatial): the environment with
// probability ½ (1 without area lights), the area lights with the rest ∝ their
// importance at (p, n).
fn spatial_env() -> f32 {
    if (frame.env.kind == ENV_NONE) { return 0.0; }
    if (frame.n_lights == 0u) { return 1.0; }
    return 0.5;
}

fn importance_of(i: u32, p: vec3<f32>, n: vec3<f32>) -> f32 {
    return light_importance(frame.spatial_off + 12u * i, p, n);
}

fn importance_total(p: vec3<f32>, n: vec3<f32>) -> f32 {
    var total = 0.0;
    for (var i = 0u; i < frame.n_lights; i++) {
        loops++;
        total += importance_of(i, p, n);
    }
    return total;
}

// The MIS light the spatial selection picks with uc, as bits (n_lights: the
// environment), or 0xffffffff when none has probability (Lights::select).
fn spatial_select(p: vec3<f32>, n: vec3<f32>, uc: f32) -> u32 {
    let pe = spatial_env();
    if (uc < pe) { return frame.n_lights; }
    let total = importance_total(p, n);
    if (!(total > 0.0)) { return 0xffffffffu; }
    let aim = (uc - pe) / (1.0 - pe) * total;
    var acc = 0.0;
    var last = 0xffffffffu;
    for (var i = 0u; i < frame.n_lights; i++) {
        loops++;
        let w = importance_of(i, p, n);
        if (w > 0.0) {
            acc += w;
            last = i;
            if (aim < acc) { return i; }
        }
    }
    return last;
}

// The light BVH's selection (render::light::Selection::Bvh): the environment as the
// spatial selection has it, the area lights with the rest by the tree's descent.
fn bvh_select(p: vec3<f32>, n: vec3<f32>, uc: f32) -> u32 {
    let pe = spatial_env();
    if (uc < pe) { return frame.n_lights; }
    if (frame.tree.x == 0xffffffffu) { return 0xffffffffu; }
    let u = min((uc - pe) / (1.0 - pe), l_one_minus_eps());
    return bitcast<u32>(tree_sample(frame.tree.x, p, n, u).x);
}

// The trained selection (state::TrainedSelection), a sparse table in sel_buf from
// frame.trained.x: lo.xyz, scale.xyz, the floor ε, res³ + 1 entry offsets (cell c's
// entries are [start_c, start_c+1)), then per entry (light, running share, share), in
// light order within its cell. trained_usable: whether it covers the MIS lights.
fn trained_usable() -> bool {
    return frame.trained.x != 0xffffffffu && frame.trained.z == n_mis();
}

// The cell of p (points outside the grid go to the nearest cell).
fn trained_cell(p: vec3<f32>) -> u32 {
    let off = frame.trained.x;
    let res = frame.trained.y;
    let lo = vec3<f32>(sel_buf[off], sel_buf[off + 1u], sel_buf[off + 2u]);
    let sc = vec3<f32>(sel_buf[off + 3u], sel_buf[off + 4u], sel_buf[off + 5u]);
    let q = floor((p - lo) * sc);
    let m = f32(res - 1u);
    var c = vec3<u32>(0u);
    for (var k = 0u; k < 3u; k++) {
        if (q[k] == q[k]) { c[k] = u32(clamp(q[k], 0.0, m)); }
    }
    return (c.z * res + c.y) * res + c.x;
}

// Cell c's entries [x, y), and where entry 0 starts in sel_buf (z).
fn trained_entries(c: u32) -> vec3<u32> {
    let at = frame.trained.x + 7u;
    let res = frame.trained.y;
    return vec3<u32>(bitcast<u32>(sel_buf[at + c]), bitcast<u32>(sel_buf[at + c + 1u]), at + res * res * res + 1u);
}

// P(MIS light k) in cell c: (1 − ε)·share_k + ε/L, uniform in a cell that measured
// nothing (TrainedSelection::pmf); a binary search over the cell's lights.
fn trained_pmf(c: u32, k: u32) -> f32 {
    let r = trained_entries(c);
    let n = f32(frame.trained.z);
    if (r.x == r.y) { return 1.0 / n; }
    var lo = r.x;
    var hi = r.y;
    while (lo < hi) {
        loops++;
        let mid = (lo + hi) / 2u;
        if (bitcast<u32>(sel_buf[r.z + 3u * mid]) < k) { lo = mid + 1u; } else { hi = mid; }
    }
    var share = 0.0;
    if (lo < r.y && bitcast<u32>(sel_buf[r.z + 3u * lo]) == k) { share = sel_buf[r.z + 3u * lo + 2u]; }
    let eps = sel_buf[frame.trained.x + 6u];
    return (1.0 - eps) * share + eps / n;
}

// The MIS light the trained pmf at p picks with uc (0xffffffff: none): uniformly for
// uc < ε or in a cell that measured nothing, else the first entry whose running share
// exceeds (uc − ε)/(1 − ε) (TrainedSelection::select).
fn trained_select(p: vec3<f32>, uc: f32) -> u32 {
    if (!trained_usable()) { return 0xffffffffu; }
    let r = trained_entries(trained_cell(p));
    let n = frame.trained.z;
    let eps = sel_buf[frame.trained.x + 6u];
    if (r.x == r.y) { return min(u32(uc * f32(n)), n - 1u); }
    if (uc < eps) { return min(u32(uc / eps * f32(n)), n - 1u); }
    let u = (uc - eps) / (1.0 - eps);
    var lo = r.x;
    var hi = r.y - 1u;
    while (lo < hi) {
        loops++;
        let mid = (lo + hi) / 2u;
        if (sel_buf[r.z + 3u * mid + 1u] <= u) { lo = mid + 1u; } else { hi = mid; }
    }
    return bitcast<u32>(sel_buf[r.z + 3u * lo]);
}

fn pmf_at(off: u32, i: u32) -> f32 {
    let n = bitcast<u32>(sel_buf[off]);
    return sel_buf[off + 1u + (n + 1u) + i];
}

// Whether technique `code` mixes over the area lights: its pdf sums over the lights a
// direction crosses (render::technique::mixes).
fn mixes(code: u32) -> bool {
    return code == T_POWER || code == T_UNIFORM || code == T_AREA || code == T_SPATIAL
        || code == T_TRAINED || code == T_BVH;
}

// Every technique's solid-angle pdf at wi (render::technique::pdfs), the BSDF's being
// `bsdf_pdf`, `nf` the normal on the viewer's side. One walk over the lights wi crosses
// serves every mixture, each light's own pdf found once; each mixture sums its terms
// P(k | p, n) p_k(wi) in the walk's order, then the environment's
// (Lights::pdf_selected_over).
fn tech_pdfs(p: vec3<f32>, n: vec3<f32>, nf: vec3<f32>, wi: vec3<f32>, bsdf_pdf: f32) -> array<f32, MAX_TECH> {
    var out: array<f32, MAX_TECH>;
    var mixing = false;
    var spatial = false;
    var by_li = false;
    for (var t = 0u; t < frame.n_tech; t++) {
        loops++;
        let code = tech_code(t);
        if (mixes(code)) {
            mixing = true;
            spatial = spatial || code == T_SPATIAL;
            by_li = by_li || code != T_AREA;
        } else if (code == T_BSDF) {
            out[t] = bsdf_pdf;
        } else if (code == T_COSINE) {
            out[t] = max(dot(nf, wi), 0.0) * BSDF_INV_PI;
        } else if (code == T_ENV) {
            out[t] = env_pdf(frame.env, wi);
        } else if (code == T_ONE) {
            let one = tech_light(t);
            if (one == frame.n_lights) {
                out[t] = env_pdf(frame.env, wi);
            } else {
                out[t] = light_pdf_li(lights[one], p, wi);
            }
        }
    }
    if (!mixing) { return out; }
    // What the point-dependent selections read once: the environment's share, the
    // spatial selection's total, the trained selection's cell.
    let pe = spatial_env();
    var total = 0.0;
    if (spatial) { total = importance_total(p, n); }
    let trained = trained_usable();
    var cell = 0u;
    if (trained) { cell = trained_cell(p); }
    let tree = frame.tree.x != 0xffffffffu;
    var w = light_walk(p, wi, inf());
    for (var i = light_next(&w); i != 0xffffffffu; i = light_next(&w)) {
        let l = lights[i];
        var pl = 0.0;
        if (by_li) { pl = light_pdf_li(l, p, wi); }
        for (var t = 0u; t < frame.n_tech; t++) {
            loops++;
            let code = tech_code(t);
            if (code == T_AREA) {
                let pm = pmf_at(frame.area_off, i);
                if (pm > 0.0) { out[t] += pm * light_pdf_area(l, p, wi); }
            } else if (code == T_BVH) {
                // The tree's pmf only where the light has density (a descent per light).
                if (tree && pl > 0.0) {
                    let pm = (1.0 - pe) * tree_pmf(frame.tree.x, frame.tree.y, p, n, i);
                    if (pm > 0.0) { out[t] += pm * pl; }
                }
            } else if (code == T_SPATIAL) {
                if (total > 0.0) {
                    let pm = (1.0 - pe) * importance_of(i, p, n) / total;
                    if (pm > 0.0) { out[t] += pm * pl; }
                }
            } else if (code == T_TRAINED) {
                if (trained) {
                    let pm = trained_pmf(cell, i);
                    if (pm > 0.0) { out[t] += pm * pl; }
                }
            } else if (code == T_POWER || code == T_UNIFORM) {
                var pm = 1.0 / f32(n_mis());
                if (code == T_POWER) { pm = pmf_at(frame.power_off, i); }
                if (pm > 0.0) { out[t] += pm * pl; }
            }
        }
    }
    // The environment last (not a by-area light).
    if (frame.env.kind != ENV_NONE) {
        let pd = env_pdf(frame.env, wi);
        for (var t = 0u; t < frame.n_tech; t++) {
            loops++;
            let code = tech_code(t);
            if (code == T_SPATIAL || code == T_BVH) {
                if (pe > 0.0) { out[t] += pe * pd; }
            } else if (code == T_TRAINED) {
                if (trained) {
                    let pm = trained_pmf(cell, frame.n_lights);
                    if (pm > 0.0) { out[t] += pm * pd; }
                }
            } else if (code == T_POWER || code == T_UNIFORM) {
                var pm = 1.0 / f32(n_mis());
                if (code == T_POWER) { pm = pmf_at(frame.power_off, frame.n_lights); }
                if (pm > 0.0) { out[t] += pm * pd; }
            }
        }
    }
    return out;
}

fn tech_code(k: u32) -> u32 { return frame.tech[k / 4u][k % 4u] & 0xffu; }
fn tech_light(k: u32) -> u32 { return frame.tech[k / 4u][k % 4u] >> 8u; }
