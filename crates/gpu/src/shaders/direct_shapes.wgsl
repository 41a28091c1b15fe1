// --- objects ---------------------------------------------------------------------------

// (t_near, t_far) of the box along the ray, clipped to (t0, t1); x > y when missed.
fn clip_box(lo: vec3<f32>, hi: vec3<f32>, o: vec3<f32>, inv: vec3<f32>, t0: f32, t1: f32) -> vec2<f32> {
    let a = (lo - o) * inv;
    let b = (hi - o) * inv;
    let near = min(a, b);
    let far = max(a, b);
    // NaN (0·∞ on an axis the ray runs along inside a face) keeps the other axes' bounds.
    var tn = t0;
    var tf = t1;
    for (var k = 0u; k < 3u; k++) {
        if (!is_nan(near[k])) { tn = max(tn, near[k]); }
        if (!is_nan(far[k])) { tf = min(tf, far[k]); }
    }
    return vec2<f32>(tn, tf);
}

// frep's Solid::plain_intersection in f32: the inside set along the ray is the
// intersection of the parts' positive sets; its first end in (t_min, t_max), with the
// leaf that makes it. (t, leaf bits, 1), (0, 0, 0), or (0, 0, 2) where a part's
// outcome lies within rounding (quadric_centred).
fn plain_intersection(sh: GpuShape, o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32) -> vec3<f32> {
    var a: array<f32, 10>;
    var b: array<f32, 10>;
    var ka: array<u32, 10>;
    var kb: array<u32, 10>;
    a[0] = -inf();
    b[0] = inf();
    ka[0] = sh.first;
    kb[0] = sh.first;
    var n = 1u;
    for (var k = 0u; k < sh.count; k++) {
        loops++;
        let leaf = sh.first + k;
        // About the ray's vertex, as quadric_first_crossing; open: for the CPU.
        let cq = quadric_centred(quadrics[objects[leaf].first_op].c, o, d, t_min, t_max);
        if (cq.open) { return vec3<f32>(0.0, 0.0, 2.0); }
        var ps = positive_set(cq.k);
        ps.s = ps.s + vec4<f32>(cq.tc);
        var na: array<f32, 10>;
        var nb: array<f32, 10>;
        var nka: array<u32, 10>;
        var nkb: array<u32, 10>;
        var m = 0u;
        for (var j = 0u; j < n; j++) {
            for (var w = 0u; w < ps.n; w++) {
                loops++;
                let c = ps.s[2u * w];
                let e = ps.s[2u * w + 1u];
                var lo = a[j];
                var klo = ka[j];
                if (c > lo) { lo = c; klo = leaf; }
                var hi = b[j];
                var khi = kb[j];
                if (e < hi) { hi = e; khi = leaf; }
                if (lo < hi && m < 10u) {
                    na[m] = lo; nb[m] = hi; nka[m] = klo; nkb[m] = khi;
                    m++;
                }
            }
        }
        if (m == 0u) { return vec3<f32>(0.0); }
        a = na; b = nb; ka = nka; kb = nkb;
        n = m;
    }
    var best = inf();
    var which = 0u;
    for (var j = 0u; j < n; j++) {
        loops++;
        if (a[j] > t_min && a[j] < t_max && is_finite(a[j]) && a[j] < best) { best = a[j]; which = ka[j]; }
        if (b[j] > t_min && b[j] < t_max && is_finite(b[j]) && b[j] < best) { best = b[j]; which = kb[j]; }
    }
    if (best == inf()) { return vec3<f32>(0.0); }
    return vec3<f32>(best, bitcast<f32>(which), 1.0);
}
