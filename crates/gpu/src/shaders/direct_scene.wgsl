// Nearest (or, with `any`, some) object crossing in (0, t_max): (status, t, leaf) with
// status 0 none, 1 hit, 2 overflow. One loop over the shapes and the CSG walks' searches,
// so that each costly search has one call site.
struct SceneHit { status: u32, t: f32, leaf: u32 }

fn scene_trace(o: vec3<f32>, d: vec3<f32>, t_max: f32, any_hit: bool) -> SceneHit {
    let inv = vec3<f32>(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
    var res = SceneHit(0u, t_max, 0u);
    var s = 0u;
    var in_csg = false;
    loop {
        loops++;
        var search = false;
        var leaf = 0u;
        var ta = 0.0;
        var tb = res.t;
        if (in_csg) {
            search = cs_pending;
            leaf = cs_leaf;
            ta = cs_ta;
            tb = cs_tb;
        } else {
            if (s >= frame.n_shapes) { break; }
            let sh = shapes[s];
            s++;
            let c = clip_box(sh.lo.xyz, sh.hi.xyz, o, inv, 0.0, res.t);
            if (!(c.x <= c.y)) { continue; }
            leaf = sh.first;
            var found = false;
            var t = 0.0;
            if (sh.kind == 1u) {
                let r = plain_intersection(sh, o, d, 0.0, res.t);
                if (r.z == 2.0) { return SceneHit(2u, 0.0, 0u); }
                found = r.z == 1.0;
                t = r.x;
                leaf = bitcast<u32>(r.y);
            } else if (sh.kind == 2u) {
                csg_start(sh, o, d, 0.0, res.t);
                in_csg = true;
            } else if (objects[leaf].kind == 0u) {
                let r = quadric_first_crossing(quadrics[objects[leaf].first_op], o, d, 0.0, res.t);
                if (r.y == 2.0) { return SceneHit(2u, 0.0, 0u); }
                found = r.y == 1.0;
                t = r.x;
            } else {
                search = true;
            }
            if (found && t < res.t) {
                res = SceneHit(1u, t, leaf);
                if (any_hit) { return res; }
            }
            if (!search && !in_csg) { continue; }
        }
        var status = 0u;
        var t = 0.0;
        if (search) {
            if (objects[leaf].kind == 2u) {
                use_tape(objects[leaf].first_op);
                let r = trace_tape(o, d, ta, tb);
                status = r.status & 3u;
                t = r.t;
            } else {
                let r = perturbed_scan(leaf, o, d, ta, tb);
                status = r.status;
                t = r.t;
            }
        }
        if (!in_csg) {
            if (status == 2u) { return SceneHit(2u, 0.0, 0u); }
            if (status == 1u && t < res.t) {
                res = SceneHit(1u, t, leaf);
                if (any_hit) { return res; }
            }
            continue;
        }
        if (search) {
            let f = csg_feed(status, t);
            if (f == 2u) { return SceneHit(2u, 0.0, 0u); }
            if (f == 0u) { continue; }
        }
        let r = csg_run(o, d);
        if (r.z == 3.0) { continue; }
        in_csg = false;
        if (r.z == 2.0) { return SceneHit(2u, 0.0, 0u); }
        if (r.z == 1.0 && r.x < res.t) {
            res = SceneHit(1u, r.x, bitcast<u32>(r.y));
            if (any_hit) { return res; }
        }
    }
    return res;
}

fn q_grad(c: array<f32, 10>, p: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(
        2.0 * c[0] * p.x + c[3] * p.y + c[5] * p.z + c[6],
        2.0 * c[1] * p.y + c[3] * p.x + c[4] * p.z + c[7],
        2.0 * c[2] * p.z + c[4] * p.y + c[5] * p.x + c[8]);
}

// The outward unit normal of leaf `leaf` at p: −∇F'/|∇F'| (frep::outward), with
// ∇F' = ∇q + Σ 3 f_i q_i² ∇q_i over the perturbations positive at p.
fn leaf_normal(key: u32, p: vec3<f32>) -> vec3<f32> {
    let leaf = key & 0x7fffffffu;
    let sign = select(-1.0, 1.0, (key & 0x80000000u) != 0u);
    let ob = objects[leaf];
    if (ob.kind == 2u) {
        use_tape(ob.first_op);
        return -sign * tape_normal(p);
    }
    var g = q_grad(quadrics[ob.first_op].c, p);
    if (ob.kind == 1u) {
        let n = ob.item_count + ob.unbounded;
        for (var k = 0u; k < n; k++) {
            loops++;
            let pert = perturbations[ob.op_count + items[ob.first_item + k].item];
            let q = q_eval(pert.q, p);
            if (q > 0.0) { g += (3.0 * pert.f * q * q) * q_grad(pert.q, p); }
        }
    }
    let l = length(g);
    if (l > 0.0 && is_finite(l)) { return sign * g / l; }
    return vec3<f32>(0.0, 0.0, 1.0);
}
