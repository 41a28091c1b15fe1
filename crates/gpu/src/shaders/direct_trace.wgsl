// --- kernels -------------------------------------------------------------------------

fn slot_pixel(slot: u32) -> vec3<u32> {
    let pix = frame.wave.z + slot % frame.pixels;
    return vec3<u32>(pix % frame.width, pix / frame.width, frame.sample + slot / frame.pixels);
}

fn camera_ray(px: vec3<u32>) -> array<vec3<f32>, 2> {
    var ox = rnd(px.x, px.y, px.z, 0u);
    var oy = rnd(px.x, px.y, px.z, 1u);
    if ((frame.flags & FLAG_CENTER) != 0u) { ox = 0.5; oy = 0.5; }
    let scale = frame.eye.w;
    let aspect = frame.right.w;
    let sx = (2.0 * (f32(px.x) + ox) / f32(frame.width) - 1.0) * scale * aspect;
    let sy = (1.0 - 2.0 * (f32(px.y) + oy) / f32(frame.height)) * scale;
    if ((frame.flags & FLAG_ORTHO) != 0u) {
        return array<vec3<f32>, 2>(frame.eye.xyz + sx * frame.right.xyz + sy * frame.up.xyz, frame.forward.xyz);
    }
    let d = normalize(frame.forward.xyz + sx * frame.right.xyz + sy * frame.up.xyz);
    if (frame.up.w > 0.0) {
        // A thin lens (render::camera::Camera::ray_through_lens): from the lens point of
        // dimensions 5 and 6 toward where the pinhole ray meets the plane in focus.
        let focus = frame.eye.xyz + d * (frame.forward.w / dot(d, frame.forward.xyz));
        let l = frame.up.w * disk_concentric(vec2<f32>(rnd(px.x, px.y, px.z, 5u), rnd(px.x, px.y, px.z, 6u)));
        let o = frame.eye.xyz + l.x * frame.right.xyz + l.y * frame.up.xyz;
        return array<vec3<f32>, 2>(o, normalize(focus - o));
    }
    return array<vec3<f32>, 2>(frame.eye.xyz, d);
}

// Draw records per slot and depth: the techniques' Σ n_k, the extra BSDF draw, then one
// per point or spot light (frame.per_slot in all).
fn draw_at(slot: u32, j: u32) -> u32 {
    return ((frame.depth * frame.slots + slot) * frame.per_slot + j) * draw_vec4s(frame.n_tech);
}

fn write_vertex(at: u32, p: vec3<f32>, leaf: u32, n: vec3<f32>, wo: vec3<f32>, beta: vec3<f32>) {
    hits[at] = vec4<f32>(p, S_SURFACE);
    hits[at + 1u] = vec4<f32>(n, bitcast<f32>(objects[leaf & 0x7fffffffu].material));
    hits[at + 2u] = vec4<f32>(wo, 0.0);
    hits[at + 4u] = vec4<f32>(beta, 0.0);
}

// The radiance the surface of leaf `leaf` (outward normal n there) sends back along −d:
// its material's emission where d arrives on the outer side, else 0
// (Scene::surface_emission). The callers find n (leaf_normal, which runs a tape's
// interpreter, once per kernel path: llvmpipe inlines every call site).
fn surface_emission(leaf: u32, n: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    let e = materials[objects[leaf & 0x7fffffffu].material].emission.xyz;
    if (all(e == vec3<f32>(0.0)) || !(dot(d, n) < 0.0)) { return vec3<f32>(0.0); }
    return e;
}

fn trace_camera(slot: u32) {
    let px = slot_pixel(slot);
    let ray = camera_ray(px);
    let o = ray[0];
    let d = ray[1];
    let h = scene_trace(o, d, inf(), false);
    let at = slot * HIT_WORDS;
    hits[at + 3u] = vec4<f32>(0.0);
    // The first hit's AOVs: nothing where the ray escapes (integrator/aov.rs).
    hits[at + 8u] = vec4<f32>(0.0);
    hits[at + 9u] = vec4<f32>(0.0);
    if (h.status == 2u) {
        hits[at] = vec4<f32>(0.0, 0.0, 0.0, S_OVERFLOW);
        return;
    }
    let lh = nearest_light(o, d, h.t);
    if (lh.t < inf()) {
        // A light: its depth and normal, albedo 0.
        hits[at + 8u] = vec4<f32>(lh.n, lh.t);
        var le = lh.le;
        if ((frame.flags & FLAG_HIDE) != 0u) { le = vec3<f32>(0.0); }
        hits[at] = vec4<f32>(0.0, 0.0, 0.0, S_NONE);
        hits[at + 3u] = vec4<f32>(le, 0.0);
        return;
    }
    if (h.status == 0u) {
        // Escaped: the environment seen directly, outside MIS.
        var le = env_radiance(frame.env, d);
        if ((frame.flags & FLAG_HIDE) != 0u) { le = vec3<f32>(0.0); }
        hits[at] = vec4<f32>(0.0, 0.0, 0.0, S_NONE);
        hits[at + 3u] = vec4<f32>(le, 0.0);
        return;
    }
    let p = o + h.t * d;
    let n = leaf_normal(h.leaf, p);
    write_vertex(at, p, h.leaf, n, -d, vec3<f32>(1.0));
    hits[at + 8u] = vec4<f32>(n, h.t);
    if ((frame.flags & (FLAG_EMITTERS | FLAG_HIDE)) == FLAG_EMITTERS) {
        // An emitting object seen directly, outside MIS.
        hits[at + 3u] = vec4<f32>(surface_emission(h.leaf, n, d), 0.0);
    }
}

// The continuation of a slot's path from vertex `depth`: its nearest hit is the extending
// draw's Li (a light) and the next vertex (an object), if roulette kept the path.
fn trace_continuation(slot: u32) {
    let at = slot * HIT_WORDS;
    let c = hits[at + 5u];
    if (hits[at].w != S_SURFACE) { return; }
    if (c.w != 1.0) {
        hits[at].w = S_NONE;
        return;
    }
    let o = c.xyz;
    let cd = hits[at + 6u];
    let d = cd.xyz;
    let h = scene_trace(o, d, inf(), false);
    if (h.status == 2u) {
        hits[at].w = S_OVERFLOW;
        return;
    }
    let lh = nearest_light(o, d, h.t);
    let r = draw_at(slot, frame.carry);
    let w2 = draws[r + 2u];
    var g = vec3<f32>(0.0);
    let p = o + h.t * d;
    let emitters = (frame.flags & FLAG_EMITTERS) != 0u;
    let object = lh.t == inf() && h.status == 1u;
    // The surface met: its normal for its emission and the next vertex.
    var n = vec3<f32>(0.0);
    if (object && (emitters || cd.w == 1.0)) { n = leaf_normal(h.leaf, p); }
    if (!object) {
        g = w2.xyz * incoming(lh, d);
    } else if (emitters) {
        g = w2.xyz * surface_emission(h.leaf, n, d);
    }
    draws[r + 2u] = vec4<f32>(g, w2.w);
    if (!object || cd.w != 1.0) {
        hits[at].w = S_NONE;
        return;
    }
    write_vertex(at, p, h.leaf, n, -d, hits[at + 7u].xyz);
    push(LIVE_LEN, frame.wave.x, slot);
}

fn trace_shadow(q: u32) {
    if (q >= atomicLoad(&stats[QUEUE_LEN])) { return; }
    let i = atomicLoad(&stats[QUEUE_ITEMS + q]);
    let at = (frame.depth * frame.slots * frame.per_slot + i) * draw_vec4s(frame.n_tech);
    let o = draws[at].xyz;
    let d = draws[at + 1u].xyz;
    // With emitting objects a draw's record holds its integrand without Li, which a
    // nearest-hit ray finds: the nearest light's or the environment's where no object
    // comes first, else the emission of the surface met
    // (render::integrator::medium::transmitted). Point and spot lights' records (after
    // the draws) keep their any-hit rays. (One call of scene_trace: llvmpipe inlines
    // every call site of the intersectors.)
    let emitters = (frame.flags & FLAG_EMITTERS) != 0u && i % frame.per_slot <= frame.n_draws;
    var lh = LightHit(inf(), 0u, vec3<f32>(0.0), vec3<f32>(0.0));
    var t_max = draws[at].w;
    if (emitters) {
        lh = nearest_light(o, d, inf());
        t_max = lh.t;
    }
    let h = scene_trace(o, d, t_max, !emitters);
    if (h.status == 2u) {
        draws[at + 1u].w = S_OVERFLOW + 10.0;
    } else if (emitters) {
        var li = incoming(lh, d);
        if (h.status == 1u) {
            let p = o + h.t * d;
            li = surface_emission(h.leaf, leaf_normal(h.leaf, p), d);
        }
        let g = draws[at + 2u];
        draws[at + 2u] = vec4<f32>(g.xyz * li, g.w);
        draws[at + 1u].w = select(D_OCCLUDED, D_VISIBLE, any(li != vec3<f32>(0.0)));
    } else if (h.status == 1u) {
        draws[at + 1u].w = D_OCCLUDED;
    } else {
        draws[at + 1u].w = D_VISIBLE;
    }
}

// A ray batch for tests (mode 3): ray i from draw record i's [o, ·] (origin) and
// [wi, ·] (direction); the nearest object hit into hits[8i] = (t, leaf key, status, loops) and
// hits[8i + 1] = its normal.
fn probe(i: u32) {
    let o = draws[i * draw_vec4s(frame.n_tech)].xyz;
    let d = draws[i * draw_vec4s(frame.n_tech) + 1u].xyz;
    let h = scene_trace(o, d, inf(), false);
    var n = vec3<f32>(0.0);
    if (h.status == 1u) { n = leaf_normal(h.leaf, o + h.t * d); }
    hits[i * HIT_WORDS] = vec4<f32>(h.t, bitcast<f32>(h.leaf), f32(h.status), f32(loops));
    hits[i * HIT_WORDS + 1u] = vec4<f32>(n, 0.0);
}

@compute @workgroup_size(64)
fn trace(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    let i = gid.x + gid.y * nw.x * 64u;
    loops = 0u;
    if (frame.mode == 1u) {
        trace_shadow(i);
    } else {
        if (i >= frame.slots) { return; }
        if (frame.mode == 0u) {
            trace_camera(i);
        } else if (frame.mode == 2u) {
            // The slots the shade pass queued, and no other.
            if (i < atomicLoad(&stats[CONT_LEN])) {
                trace_continuation(atomicLoad(&stats[frame.wave.y + i]));
            }
        } else {
            probe(i);
        }
    }
    atomicMax(&stats[select(0u, 1u, frame.mode == 1u)], loops);
}
