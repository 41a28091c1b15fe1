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

// Each mode of the `trace` kernel in three parts: its ray (set up before the query), the
// one query every mode shares, and what it does with the answer. llvmpipe inlines every
// call site, so `scene_trace`, `nearest_light` and `leaf_normal` each have one call site
// in the kernel, whatever the mode (four calls of `scene_trace` were four inlined copies
// of every intersector).
struct TraceRay {
    o: vec3<f32>,
    d: vec3<f32>,
    t_max: f32,
    // Whether any hit in (0, t_max) will do (a shadow ray without emitting objects).
    any_hit: bool,
    // Whether the nearest light before the object hit is wanted.
    lights: bool,
    // Whether the ray is traced at all.
    live: bool,
    // The slot (camera, continuation), draw record (shadow) or ray (probe) it is for.
    at: u32,
}

fn no_ray() -> TraceRay {
    return TraceRay(vec3<f32>(0.0), vec3<f32>(0.0), inf(), false, false, false, 0u);
}

fn camera_ray_of(slot: u32) -> TraceRay {
    let ray = camera_ray(slot_pixel(slot));
    return TraceRay(ray[0], ray[1], inf(), false, true, true, slot);
}

// The continuation of a slot's path from vertex `depth`: its nearest hit is the extending
// draw's Li (a light) and the next vertex (an object), if roulette kept the path.
fn continuation_ray(slot: u32) -> TraceRay {
    let at = slot * HIT_WORDS;
    let c = hits[at + 5u];
    if (hits[at].w != S_SURFACE) { return no_ray(); }
    if (c.w != 1.0) {
        hits[at].w = S_NONE;
        return no_ray();
    }
    return TraceRay(c.xyz, hits[at + 6u].xyz, inf(), false, true, true, slot);
}

// A queued draw's shadow ray. With emitting objects a draw's record holds its integrand
// without Li, which a nearest-hit ray finds: the nearest light's or the environment's
// where no object comes first, else the emission of the surface met
// (render::integrator::medium::transmitted); the objects are queried first and the
// lights up to the object's t, the same answer but for exact ties. Point and spot
// lights' records (after the draws) keep their any-hit rays.
fn shadow_ray(q: u32) -> TraceRay {
    if (q >= atomicLoad(&stats[QUEUE_LEN])) { return no_ray(); }
    let i = atomicLoad(&stats[QUEUE_ITEMS + q]);
    let at = (frame.depth * frame.slots * frame.per_slot + i) * draw_vec4s(frame.n_tech);
    let emitters = (frame.flags & FLAG_EMITTERS) != 0u && i % frame.per_slot <= frame.n_draws;
    let t_max = select(draws[at].w, inf(), emitters);
    return TraceRay(draws[at].xyz, draws[at + 1u].xyz, t_max, !emitters, emitters, true, at);
}

// A ray batch for tests (mode 3): ray i from draw record i's [o, ·] (origin) and
// [wi, ·] (direction).
fn probe_ray(i: u32) -> TraceRay {
    let at = i * draw_vec4s(frame.n_tech);
    return TraceRay(draws[at].xyz, draws[at + 1u].xyz, inf(), false, false, true, i);
}

fn finish_camera(r: TraceRay, h: SceneHit, lh: LightHit, n: vec3<f32>) {
    let at = r.at * HIT_WORDS;
    hits[at + 3u] = vec4<f32>(0.0);
    // The first hit's AOVs: nothing where the ray escapes (integrator/aov.rs).
    hits[at + 8u] = vec4<f32>(0.0);
    hits[at + 9u] = vec4<f32>(0.0);
    if (h.status == 2u) {
        hits[at] = vec4<f32>(0.0, 0.0, 0.0, S_OVERFLOW);
        return;
    }
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
        var le = env_radiance(frame.env, r.d);
        if ((frame.flags & FLAG_HIDE) != 0u) { le = vec3<f32>(0.0); }
        hits[at] = vec4<f32>(0.0, 0.0, 0.0, S_NONE);
        hits[at + 3u] = vec4<f32>(le, 0.0);
        return;
    }
    let p = r.o + h.t * r.d;
    write_vertex(at, p, h.leaf, n, -r.d, vec3<f32>(1.0));
    hits[at + 8u] = vec4<f32>(n, h.t);
    if ((frame.flags & (FLAG_EMITTERS | FLAG_HIDE)) == FLAG_EMITTERS) {
        // An emitting object seen directly, outside MIS.
        hits[at + 3u] = vec4<f32>(surface_emission(h.leaf, n, r.d), 0.0);
    }
}

fn finish_continuation(r: TraceRay, h: SceneHit, lh: LightHit, n: vec3<f32>) {
    let slot = r.at;
    let at = slot * HIT_WORDS;
    if (h.status == 2u) {
        hits[at].w = S_OVERFLOW;
        return;
    }
    let rec = draw_at(slot, frame.carry);
    let w2 = draws[rec + 2u];
    var g = vec3<f32>(0.0);
    let object = lh.t == inf() && h.status == 1u;
    if (!object) {
        g = w2.xyz * incoming(lh, r.d);
    } else if ((frame.flags & FLAG_EMITTERS) != 0u) {
        g = w2.xyz * surface_emission(h.leaf, n, r.d);
    }
    draws[rec + 2u] = vec4<f32>(g, w2.w);
    if (!object || hits[at + 6u].w != 1.0) {
        hits[at].w = S_NONE;
        return;
    }
    write_vertex(at, r.o + h.t * r.d, h.leaf, n, -r.d, hits[at + 7u].xyz);
    push(LIVE_LEN, frame.wave.x, slot);
}

fn finish_shadow(r: TraceRay, h: SceneHit, lh: LightHit, n: vec3<f32>) {
    let at = r.at;
    if (h.status == 2u) {
        draws[at + 1u].w = S_OVERFLOW + 10.0;
    } else if (r.lights) {
        var li = incoming(lh, r.d);
        if (lh.t == inf() && h.status == 1u) {
            li = surface_emission(h.leaf, n, r.d);
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

// The nearest object hit into hits[8i] = (t, leaf key, status, loops) and hits[8i + 1] =
// its normal.
fn finish_probe(r: TraceRay, h: SceneHit, n: vec3<f32>) {
    hits[r.at * HIT_WORDS] = vec4<f32>(h.t, bitcast<f32>(h.leaf), f32(h.status), f32(loops));
    hits[r.at * HIT_WORDS + 1u] = vec4<f32>(n, 0.0);
}

@compute @workgroup_size(64)
fn trace(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    let i = gid.x + gid.y * nw.x * 64u;
    loops = 0u;
    var r = no_ray();
    if (frame.mode == 1u) {
        r = shadow_ray(i);
    } else if (i < frame.slots) {
        if (frame.mode == 0u) {
            r = camera_ray_of(i);
        } else if (frame.mode == 2u) {
            // The slots the shade pass queued, and no other.
            if (i < atomicLoad(&stats[CONT_LEN])) {
                r = continuation_ray(atomicLoad(&stats[frame.wave.y + i]));
            }
        } else {
            r = probe_ray(i);
        }
    }
    if (r.live) {
        let h = scene_trace(r.o, r.d, r.t_max, r.any_hit);
        var lh = LightHit(inf(), 0u, vec3<f32>(0.0), vec3<f32>(0.0));
        if (r.lights && h.status != 2u) { lh = nearest_light(r.o, r.d, h.t); }
        // The surface met, where its normal is wanted: the next vertex, an emission, or
        // the probe's answer.
        let object = h.status == 1u && lh.t == inf();
        var wants = object;
        if (frame.mode == 1u) {
            wants = object && r.lights;
        } else if (frame.mode == 2u) {
            wants = object && ((frame.flags & FLAG_EMITTERS) != 0u || hits[r.at * HIT_WORDS + 6u].w == 1.0);
        }
        var n = vec3<f32>(0.0);
        if (wants) { n = leaf_normal(h.leaf, r.o + h.t * r.d); }
        if (frame.mode == 0u) {
            finish_camera(r, h, lh, n);
        } else if (frame.mode == 1u) {
            finish_shadow(r, h, lh, n);
        } else if (frame.mode == 2u) {
            finish_continuation(r, h, lh, n);
        } else {
            finish_probe(r, h, n);
        }
    }
    atomicMax(&stats[select(0u, 1u, frame.mode == 1u)], loops);
}
