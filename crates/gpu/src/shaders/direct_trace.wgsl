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

// The media on the two sides of a vertex packed into one word (hits' word 2), 0xffff
// for vacuum.
fn pack_media(inside: u32, outside: u32) -> f32 {
    return bitcast<f32>((inside & 0xffffu) | (outside << 16u));
}

fn write_vertex(at: u32, p: vec3<f32>, leaf: u32, n: vec3<f32>, wo: vec3<f32>, beta: vec3<f32>) {
    let material = objects[leaf & 0x7fffffffu].material;
    let sides = materials[material].coats;
    hits[at] = vec4<f32>(p, S_SURFACE);
    hits[at + 1u] = vec4<f32>(n, bitcast<f32>(material));
    hits[at + 2u] = vec4<f32>(wo, pack_media(sides.y, sides.z));
    hits[at + 4u] = vec4<f32>(beta, 0.0);
}

// A scattering point inside medium `medium` (Vertex::in_medium): no normal, the medium's
// phase function as its material, the medium on both sides.
fn write_medium_vertex(at: u32, p: vec3<f32>, medium: u32, wo: vec3<f32>, beta: vec3<f32>) {
    hits[at] = vec4<f32>(p, S_SURFACE);
    hits[at + 1u] = vec4<f32>(vec3<f32>(0.0), bitcast<f32>(frame.media.x + medium));
    hits[at + 2u] = vec4<f32>(wo, pack_media(medium, medium));
    hits[at + 4u] = vec4<f32>(beta, 0.0);
}

// The medium a ray along `wi` leaves the vertex at hits[ha] in (Vertex::medium_toward):
// the inside against the normal, else the outside (the same at a medium point).
fn medium_toward(ha: u32, wi: vec3<f32>) -> u32 {
    let sides = bitcast<u32>(hits[ha + 2u].w);
    var m = sides >> 16u;
    if (dot(wi, hits[ha + 1u].xyz) < 0.0) { m = sides & 0xffffu; }
    return select(m, NO_MEDIUM, m == 0xffffu);
}

// The medium a ray along d enters at a boundary of leaf `leaf` with outward normal n
// (render::integrator::medium::medium_entered): the object's inside where d goes against
// n, else its outside.
fn medium_entered(leaf: u32, n: vec3<f32>, d: vec3<f32>) -> u32 {
    let sides = materials[objects[leaf & 0x7fffffffu].material].coats;
    return select(sides.z, sides.y, dot(d, n) < 0.0);
}

// exp(−σ·d) per channel, 1 where σ = 0 (render::medium::optical_transmittance), 0 for
// d = ∞ where σ > 0.
fn transmittance(sigma: vec3<f32>, d: f32) -> vec3<f32> {
    var t = vec3<f32>(0.0);
    for (var c = 0u; c < 3u; c++) {
        if (sigma[c] == 0.0) {
            t[c] = 1.0;
        } else if (d < inf()) {
            t[c] = exp(-sigma[c] * d);
        }
    }
    return t;
}

// The albedo of medium material `mm` at p: its colour, or its texture read in world
// space (render::medium::Medium::sigma_s).
fn medium_albedo(mm: GpuMaterial, p: vec3<f32>) -> vec3<f32> {
    if (mm.tex[0].kind == 0u) { return mm.bsdf.rgb.xyz; }
    return texture_rgb(mm.tex[0], mm, p, vec3<f32>(0.0));
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
    // The medium it starts in (NO_MEDIUM: vacuum).
    medium: u32,
}

fn no_ray() -> TraceRay {
    return TraceRay(vec3<f32>(0.0), vec3<f32>(0.0), inf(), false, false, false, 0u, NO_MEDIUM);
}

fn camera_ray_of(slot: u32) -> TraceRay {
    let ray = camera_ray(slot_pixel(slot));
    return TraceRay(ray[0], ray[1], inf(), false, true, true, slot, frame.media.y);
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
    let wi = hits[at + 6u].xyz;
    var medium = NO_MEDIUM;
    if (MEDIA) { medium = medium_toward(at, wi); }
    return TraceRay(c.xyz, wi, inf(), false, true, true, slot, medium);
}

// A queued draw's shadow ray. With emitting objects (or media) a draw's record holds its
// integrand without Li, which a nearest-hit ray finds: the nearest light's or the
// environment's where no object comes first, else the emission of the surface met
// (render::integrator::medium::transmitted); the objects are queried first and the
// lights up to the object's t, the same answer but for exact ties. Point and spot
// lights' records (after the draws) keep their any-hit rays, but for walks through
// media, which need the nearest boundary.
fn shadow_ray(q: u32) -> TraceRay {
    if (q >= atomicLoad(&stats[QUEUE_LEN])) { return no_ray(); }
    let i = atomicLoad(&stats[QUEUE_ITEMS + q]);
    let at = (frame.depth * frame.slots * frame.per_slot + i) * draw_vec4s(frame.n_tech);
    let emitters = (frame.flags & FLAG_EMITTERS) != 0u && i % frame.per_slot <= frame.n_draws;
    let t_max = select(draws[at].w, inf(), emitters);
    let wi = draws[at + 1u].xyz;
    var medium = NO_MEDIUM;
    if (MEDIA) { medium = medium_toward((i / frame.per_slot) * HIT_WORDS, wi); }
    return TraceRay(draws[at].xyz, wi, t_max, !emitters && !MEDIA, emitters, true, at, medium);
}

// A ray batch for tests (mode 3): ray i from draw record i's [o, ·] (origin) and
// [wi, ·] (direction).
fn probe_ray(i: u32) -> TraceRay {
    let at = i * draw_vec4s(frame.n_tech);
    return TraceRay(draws[at].xyz, draws[at + 1u].xyz, inf(), false, false, true, i, NO_MEDIUM);
}

// What a walk through index-matched boundaries and media adds to a ray's answer
// (render::integrator::medium): the origin of its last stretch (the query's answer is
// along it), the transmittance to its end and, for a ray that extends a path, the free
// flight's stop: a scattering point (`p` in `medium`) with weight σ_s·Tr/p, or the
// walk's end with weight Tr/P(pass). Without media: the ray's origin, 1, no stop, 1.
struct Walk {
    o: vec3<f32>,
    tr: vec3<f32>,
    scattered: bool,
    p: vec3<f32>,
    medium: u32,
    weight: vec3<f32>,
}

fn finish_camera(r: TraceRay, h: SceneHit, lh: LightHit, n: vec3<f32>, wk: Walk) {
    let at = r.at * HIT_WORDS;
    // The first hit's AOVs: nothing where the ray escapes (integrator/aov.rs).
    hits[at + 8u] = vec4<f32>(0.0);
    hits[at + 9u] = vec4<f32>(0.0);
    if (h.status == 2u) {
        hits[at + 3u] = vec4<f32>(0.0);
        hits[at] = vec4<f32>(0.0, 0.0, 0.0, S_OVERFLOW);
        return;
    }
    // What the camera sees at the walk's end, outside MIS: a light (its depth and normal,
    // albedo 0), the environment where the ray escapes, or an emitting object.
    var le = vec3<f32>(0.0);
    let surface = lh.t == inf() && h.status == 1u;
    if (lh.t < inf()) {
        hits[at + 8u] = vec4<f32>(lh.n, lh.t);
        le = lh.le;
    } else if (h.status == 0u) {
        le = env_radiance(frame.env, r.d);
    } else {
        hits[at + 8u] = vec4<f32>(n, h.t);
        if ((frame.flags & FLAG_EMITTERS) != 0u) { le = surface_emission(h.leaf, n, r.d); }
    }
    if ((frame.flags & FLAG_HIDE) != 0u) { le = vec3<f32>(0.0); }
    hits[at + 3u] = vec4<f32>(le * wk.tr, 0.0);
    hits[at] = vec4<f32>(0.0, 0.0, 0.0, S_NONE);
    // The first vertex: the free flight's stop (render::integrator::path).
    if (any(wk.weight != vec3<f32>(0.0))) {
        if (wk.scattered) {
            write_medium_vertex(at, wk.p, wk.medium, -r.d, wk.weight);
        } else if (surface) {
            write_vertex(at, wk.o + h.t * r.d, h.leaf, n, -r.d, wk.weight);
        }
    }
}

fn finish_continuation(r: TraceRay, h: SceneHit, lh: LightHit, n: vec3<f32>, wk: Walk) {
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
    draws[rec + 2u] = vec4<f32>(g * wk.tr, w2.w);
    if (MEDIA) {
        // β after the draw and the free flight, then Russian roulette, which the shade
        // pass left to this one (render::integrator::path).
        var next = hits[at + 7u].xyz * wk.weight;
        var vertex = hits[at + 6u].w == 1.0 && (wk.scattered || object);
        vertex = vertex && all(next == next) && any(next != vec3<f32>(0.0)) && is_finite(max(next.x, max(next.y, next.z)));
        if (vertex && frame.depth + 1u >= frame.rr_depth) {
            let q = max(0.05, 1.0 - max(next.x, max(next.y, next.z)));
            let px = slot_pixel(slot);
            if (rnd(px.x, px.y, px.z, 8u + frame.depth * frame.stride + 3u * (frame.n_draws + 1u)) < q) {
                vertex = false;
            } else {
                next = next / (1.0 - q);
            }
        }
        if (!vertex) {
            hits[at].w = S_NONE;
            return;
        }
        if (wk.scattered) {
            write_medium_vertex(at, wk.p, wk.medium, -r.d, next);
        } else {
            write_vertex(at, wk.o + h.t * r.d, h.leaf, n, -r.d, next);
        }
        push(LIVE_LEN, frame.wave.x, slot);
        return;
    }
    if (!object || hits[at + 6u].w != 1.0) {
        hits[at].w = S_NONE;
        return;
    }
    write_vertex(at, r.o + h.t * r.d, h.leaf, n, -r.d, hits[at + 7u].xyz);
    push(LIVE_LEN, frame.wave.x, slot);
}

fn finish_shadow(r: TraceRay, h: SceneHit, lh: LightHit, n: vec3<f32>, wk: Walk) {
    let at = r.at;
    if (h.status == 2u) {
        draws[at + 1u].w = S_OVERFLOW + 10.0;
    } else if (r.lights) {
        var li = incoming(lh, r.d);
        if (lh.t == inf() && h.status == 1u) {
            li = surface_emission(h.leaf, n, r.d);
        }
        li = li * wk.tr;
        let g = draws[at + 2u];
        draws[at + 2u] = vec4<f32>(g.xyz * li, g.w);
        draws[at + 1u].w = select(D_OCCLUDED, D_VISIBLE, any(li != vec3<f32>(0.0)));
    } else if (h.status == 1u) {
        draws[at + 1u].w = D_OCCLUDED;
    } else if (MEDIA) {
        // A point or spot light through media.
        let g = draws[at + 2u];
        draws[at + 2u] = vec4<f32>(g.xyz * wk.tr, g.w);
        draws[at + 1u].w = select(D_OCCLUDED, D_VISIBLE, any(wk.tr != vec3<f32>(0.0)));
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
        // Through index-matched boundaries and media (render::integrator::medium), one
        // query per stretch: `walks` (not probes), and `flies` for the rays that extend
        // a path, whose free flight spends an optical depth τ at channel c's σ_t
        // (channels chosen by the throughput, balance-weighted: Walk::fly).
        let walks = MEDIA && frame.mode < 3u;
        let flies = walks && frame.mode != 1u;
        var w = vec3<f32>(1.0 / 3.0);
        var c = 0u;
        var tau = 0.0;
        if (flies) {
            let px = slot_pixel(r.at);
            var beta = vec3<f32>(1.0);
            var depth = 0u;
            if (frame.mode == 2u) {
                beta = hits[r.at * HIT_WORDS + 7u].xyz;
                depth = frame.depth + 1u;
            }
            // state::dims: the free flight of the ray that reaches vertex `depth`.
            let fd = 8u + frame.media.w * frame.stride + 2u * depth;
            let uc = rnd(px.x, px.y, px.z, fd);
            let u = rnd(px.x, px.y, px.z, fd + 1u);
            let total = beta.x + beta.y + beta.z;
            if (total > 0.0 && is_finite(total)) { w = beta / total; }
            c = 2u;
            if (uc < w.x) {
                c = 0u;
            } else if (uc < w.x + w.y || w.z == 0.0) {
                c = 1u;
            }
            tau = -log(1.0 - u);
        }
        var wk = Walk(r.o, vec3<f32>(1.0), false, vec3<f32>(0.0), 0u, vec3<f32>(1.0));
        // A shadow ray toward a point (a point or spot light): each stretch ends there.
        let aim = r.o + r.t_max * r.d;
        var t_max = r.t_max;
        var medium = r.medium;
        var segments = 0u;
        var crossings = 0u;
        var blocked = false;
        var h = SceneHit(0u, inf(), 0u);
        var lh = LightHit(inf(), 0u, vec3<f32>(0.0), vec3<f32>(0.0));
        var n = vec3<f32>(0.0);
        loop {
            h = scene_trace(wk.o, r.d, t_max, r.any_hit);
            lh = LightHit(inf(), 0u, vec3<f32>(0.0), vec3<f32>(0.0));
            if (r.lights && h.status != 2u) { lh = nearest_light(wk.o, r.d, h.t); }
            // The surface met, where its normal is wanted: an index-matched boundary to
            // cross, the next vertex, an emission, or the probe's answer.
            let object = h.status == 1u && lh.t == inf();
            let crosses = walks && object && materials[objects[h.leaf & 0x7fffffffu].material].bsdf.kind == K_INTERFACE;
            var wants = object;
            if (frame.mode == 1u) {
                wants = object && r.lights;
            } else if (frame.mode == 2u) {
                wants = object && ((frame.flags & FLAG_EMITTERS) != 0u || hits[r.at * HIT_WORDS + 6u].w == 1.0);
            }
            n = vec3<f32>(0.0);
            if (wants || crosses) { n = leaf_normal(h.leaf, wk.o + h.t * r.d); }
            if (!walks || h.status == 2u) { break; }
            // The stretch to what the query met, inside `medium`.
            var len = t_max;
            if (lh.t < inf()) {
                len = lh.t;
            } else if (h.status == 1u) {
                len = h.t;
            }
            if (medium != NO_MEDIUM) {
                segments++;
                if (flies && segments > MAX_SEGMENTS) {
                    blocked = true;
                    break;
                }
                let mm = materials[frame.media.x + medium];
                let st = mm.bsdf.k.xyz;
                let sigma = st[c];
                if (flies && !wk.scattered && sigma > 0.0) {
                    let depth = sigma * len;
                    if (depth > tau) {
                        let t = tau / sigma;
                        let tr_t = wk.tr * transmittance(st, t);
                        let pdf = dot(w, st * tr_t);
                        wk.scattered = true;
                        wk.p = wk.o + r.d * t;
                        wk.medium = medium;
                        wk.weight = vec3<f32>(0.0);
                        if (pdf > 0.0) { wk.weight = medium_albedo(mm, wk.p) * st * tr_t / pdf; }
                    } else {
                        tau -= depth;
                    }
                }
                wk.tr = wk.tr * transmittance(st, len);
            }
            crossings++;
            if (!crosses) { break; }
            if (crossings == MAX_CROSSINGS || (!flies && all(wk.tr == vec3<f32>(0.0)))) {
                blocked = true;
                break;
            }
            loops++;
            medium = medium_entered(h.leaf, n, r.d);
            wk.o = spawn(wk.o + h.t * r.d, n, r.d);
            if (t_max < inf()) {
                t_max = dot(aim - wk.o, r.d);
                if (t_max <= 0.0) {
                    // The point is reached.
                    h = SceneHit(0u, t_max, 0u);
                    break;
                }
            }
        }
        if (blocked) {
            // Taken as blocked: nothing arrives, and the path ends (Walk::blocked).
            h = SceneHit(0u, inf(), 0u);
            lh = LightHit(inf(), 0u, vec3<f32>(0.0), vec3<f32>(0.0));
            wk.tr = vec3<f32>(0.0);
            wk.scattered = false;
        } else if (flies && !wk.scattered && segments > 0u) {
            let through = dot(w, wk.tr);
            wk.weight = select(vec3<f32>(0.0), wk.tr / through, through > 0.0);
        }
        if (frame.mode == 0u) {
            finish_camera(r, h, lh, n, wk);
        } else if (frame.mode == 1u) {
            finish_shadow(r, h, lh, n, wk);
        } else if (frame.mode == 2u) {
            finish_continuation(r, h, lh, n, wk);
        } else {
            finish_probe(r, h, n);
        }
    }
    atomicMax(&stats[select(0u, 1u, frame.mode == 1u)], loops);
}
