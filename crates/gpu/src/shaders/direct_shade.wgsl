// A textured plastic's coat tables (gpu::bsdf::COAT_STEPS per unit of α, COAT_WORDS
// words each: r_int and gpu::bsdf::COAT_TABLE_LEN albedos).
const COAT_STEPS: f32 = 32.0;
const COAT_WORDS: u32 = 66u;

// Draw j of the vertex of slot q / nd at depth 0 (every slot, in slot order: coherent
// rays), else of the live slot queued at q / nd: technique k's (j < Σ n_k), or the
// extra BSDF draw that only extends the path (j = Σ n_k). The draws of slots not
// queued keep the zeros the wave began with (status 0: no vertex).
@compute @workgroup_size(64)
fn shade(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    let q = gid.x + gid.y * nw.x * 64u;
    let nd = frame.per_slot;
    var slot = q / nd;
    if (frame.depth == 0u) {
        if (q >= frame.slots * nd) { return; }
    } else {
        if (q >= atomicLoad(&stats[LIVE_LEN]) * nd) { return; }
        slot = atomicLoad(&stats[frame.wave.x + q / nd]);
    }
    loops = 0u;
    let j = q % nd;
    let i = slot * nd + j;
    let at = draw_at(slot, j);
    let ha = slot * HIT_WORDS;
    let hp = hits[ha];
    if (hp.w != S_SURFACE) {
        draws[at + 1u] = vec4<f32>(0.0, 0.0, 0.0, 0.0);
        return;
    }
    let extend = frame.depth + 1u < frame.max_depth;
    let carries = extend && j == frame.carry;
    let hn = hits[ha + 1u];
    let mat = materials[bitcast<u32>(hn.w)];
    let px = slot_pixel(slot);
    let p = hp.xyz;
    let n = hn.xyz;
    let wo = hits[ha + 2u].xyz;
    let beta = hits[ha + 4u].xyz;
    var m = mat.bsdf;
    m.zero = frame.zero;
    // The textured parameters (render::texture), each slot through one evaluation.
    for (var s = 0u; s < 3u; s++) {
        let t = mat.tex[s];
        if (t.kind == 0u) { continue; }
        let rgb = texture_rgb(t, mat, p, n);
        if (s == 0u) {
            m.rgb = vec4<f32>(rgb, 0.0);
        } else if (s == 1u) {
            m.k = vec4<f32>(rgb, 0.0);
        } else {
            // α (Material::bsdf_rough): a plastic's coat at the nearest k/32, whose
            // tables were made for it; a delta lobe below α = 10⁻³ (k = 0).
            let alpha = clamp(rgb.x, 0.0, 1.0);
            if (m.kind == 3u) {
                let c = floor(alpha * COAT_STEPS + 0.5);
                let at = mat.coats.x + u32(c) * COAT_WORDS;
                m.r_int = sel_buf[at];
                m.table = at + 1u;
                m.alpha_x = c / COAT_STEPS;
                m.delta = select(0u, 1u, c == 0.0);
            } else if (m.kind != 0u) {
                m.alpha_x = alpha;
                m.delta = select(0u, 1u, alpha < 1e-3 || (m.kind == 2u && m.eta == 1.0));
            }
            m.alpha_y = m.alpha_x;
        }
    }
    // Delta lobes (render::bsdf::Bxdf::has_specular) and nothing else but them.
    let spec_mat = m.delta != 0u;
    let pure = spec_mat && (m.kind == 1u || m.kind == 2u);
    let vflags = select(0.0, F_PURE, pure);
    // The extra BSDF draw serves the continuation and, without a BSDF technique, the
    // delta lobes (Integrator::shade).
    let extra_used = carries || (frame.carry == frame.n_draws && spec_mat);
    // A point inside a medium: its phase function in a frame about wo (Bsdf::phase), no
    // cosine factor (Bsdf::cos).
    let phase = m.kind == K_PHASE;
    let f = basis(select(n, wo, phase));
    let wo_l = to_local(f, wo);
    // The normal turned toward the viewer (Technique::CosineHemisphere's axis).
    let nf = select(n, -n, dot(n, wo) < 0.0);
    if (frame.depth == 0u && j == 0u && (frame.flags & FLAG_AOVS) != 0u) {
        // The albedo AOV: one BSDF draw's weight, from its own dimensions
        // (integrator/aov.rs, dims::ALBEDO).
        let s = bsdf_sample_f(m, wo_l, rnd(px.x, px.y, px.z, 2u),
            vec2<f32>(rnd(px.x, px.y, px.z, 3u), rnd(px.x, px.y, px.z, 4u)));
        var albedo = vec3<f32>(0.0);
        if ((s.flags & 1u) != 0u) { albedo = s.weight; }
        hits[ha + 9u] = vec4<f32>(albedo, 0.0);
    }
    if (j == frame.n_draws && !extra_used) {
        draws[at + 1u] = vec4<f32>(0.0, 0.0, 0.0, 0.0);
        return;
    }
    if (j > frame.n_draws) {
        shade_delta(i, at, j - frame.n_draws - 1u, p, n, f, wo_l, m, beta);
        atomicMax(&stats[2], loops);
        return;
    }
    // Technique k of draw j (the extra draw samples the BSDF).
    var k = 0u;
    var first = 0u;
    var code = T_BSDF;
    if (j < frame.n_draws) {
        for (var t = 0u; t < frame.n_tech; t++) {
            loops++;
            let c = frame.count[t / 4u][t % 4u];
            if (j < first + c) { k = t; break; }
            first += c;
        }
        code = tech_code(k);
    }
    if (pure && code != T_BSDF) {
        draws[at + 1u] = vec4<f32>(0.0, 0.0, 0.0, D_SKIP);
        draws[at + 2u] = vec4<f32>(0.0, 0.0, 0.0, vflags);
        return;
    }
    let base = 8u + frame.depth * frame.stride;
    let dim = base + 3u * j;
    let uc = rnd(px.x, px.y, px.z, dim);
    let u = vec2<f32>(rnd(px.x, px.y, px.z, dim + 1u), rnd(px.x, px.y, px.z, dim + 2u));
    var wi = vec3<f32>(0.0);
    var ok = false;
    var weight = vec3<f32>(0.0);
    var spec = false;
    if (code == T_BSDF) {
        let s = bsdf_sample_f(m, wo_l, uc, u);
        ok = (s.flags & 1u) != 0u;
        spec = ok && (s.flags & 2u) != 0u;
        wi = from_local(f, s.wi);
        weight = s.weight;
    } else if (code == T_ENV) {
        let es = env_sample(frame.env, u);
        ok = es.ok != 0u;
        wi = es.wi;
    } else if (code == T_AREA) {
        if (frame.n_lights > 0u) {
            let sel = light_select(frame.area_off, true, frame.n_lights, uc);
            let ls = light_sample_area(lights[bitcast<u32>(sel.x)], p, u);
            ok = ls.ok != 0u;
            wi = ls.wi;
        }
    } else if (code == T_COSINE) {
        // Cosine-weighted about the normal on the viewer's side, in that normal's own
        // frame (Technique::CosineHemisphere, Malley's method); it fails where the
        // density is 0.
        let d = disk_concentric(u);
        wi = from_local(basis(nf), vec3<f32>(d, sqrt(max(0.0, 1.0 - dot(d, d)))));
        ok = dot(nf, wi) > 0.0;
    } else if (n_mis() > 0u) {
        var li = tech_light(k);
        if (code == T_SPATIAL) {
            li = spatial_select(p, n, uc);
        } else if (code == T_TRAINED) {
            li = trained_select(p, uc);
        } else if (code == T_BVH) {
            li = bvh_select(p, n, uc);
        } else if (code != T_ONE) {
            let sel = light_select(frame.power_off, code == T_POWER, n_mis(), uc);
            li = bitcast<u32>(sel.x);
        }
        if (li == 0xffffffffu) {
            ok = false;
        } else if (li == frame.n_lights) {
            // The environment, the last MIS light.
            let es = env_sample(frame.env, u);
            ok = es.ok != 0u;
            wi = es.wi;
        } else {
            let ls = light_sample_li(lights[li], p, u);
            ok = ls.ok != 0u;
            wi = ls.wi;
        }
    }
    let o = spawn(p, n, wi);
    // The nearest light along the draw (one call site: llvmpipe inlines each): for a
    // shadow ray's Li and t_max, or the MIS light reached in per-light mode. With
    // emitting objects the shadow pass finds Li by a nearest-hit ray (trace_shadow), so
    // no walk is needed here.
    let emitters = (frame.flags & FLAG_EMITTERS) != 0u;
    let per_light = (frame.flags & FLAG_PER_LIGHT) != 0u;
    var wants_light = false;
    if (ok && spec) {
        wants_light = !carries && !emitters;
    } else if (ok && j != frame.n_draws) {
        wants_light = per_light || (!carries && !emitters);
    }
    var lh = LightHit(inf(), 0u, vec3<f32>(0.0), vec3<f32>(0.0));
    if (wants_light) { lh = nearest_light(o, wi, inf()); }
    if (carries) {
        // The path's next ray, β after it, and roulette (render::integrator::path).
        var next = beta * weight;
        var survives = ok && all(next == next) && any(next != vec3<f32>(0.0)) && is_finite(max(next.x, max(next.y, next.z)));
        // Through media the continuation's trace weighs the free flight in first, then
        // plays the roulette (finish_continuation).
        if (!MEDIA && survives && frame.depth + 1u >= frame.rr_depth) {
            let q = max(0.05, 1.0 - max(next.x, max(next.y, next.z)));
            if (rnd(px.x, px.y, px.z, base + 3u * (frame.n_draws + 1u)) < q) {
                survives = false;
            } else {
                next = next / (1.0 - q);
            }
        }
        hits[ha + 5u] = vec4<f32>(o, select(0.0, 1.0, ok));
        hits[ha + 6u] = vec4<f32>(wi, select(0.0, 1.0, survives));
        hits[ha + 7u] = vec4<f32>(next, 0.0);
        // Traced for the draw's Li even where roulette ends the path there.
        if (ok) { push(CONT_LEN, frame.wave.y, slot); }
    }
    if (spec) {
        // A delta lobe: outside MIS, weight·Li/n (n the BSDF technique's draws, 1 for the
        // extra draw), Li from the continuation's trace or a shadow ray.
        var nk = 1u;
        if (j < frame.n_draws) { nk = frame.count[k / 4u][k % 4u]; }
        let gw = beta * weight / f32(nk);
        if (carries) {
            write_carried(at, o, wi, gw, F_OUTSIDE + vflags);
        } else {
            var le = incoming(lh, wi);
            // With emitting objects the shadow pass finds Li (trace_shadow).
            if (emitters) { le = vec3<f32>(1.0); }
            let traced = any(le != vec3<f32>(0.0));
            write_shadow(i, at, o, wi, lh.t, gw * le, F_OUTSIDE + vflags, traced);
        }
        atomicMax(&stats[2], loops);
        return;
    }
    if (carries) {
        if (j == frame.n_draws) {
            draws[at + 1u] = vec4<f32>(wi, select(0.0, D_CARRIED, ok));
            draws[at + 2u] = vec4<f32>(0.0, 0.0, 0.0, vflags);
            atomicMax(&stats[2], loops);
            return;
        }
    }
    var pdfs: array<f32, MAX_TECH>;
    var fc = vec3<f32>(0.0);
    if (ok) {
        let wi_l = to_local(f, wi);
        let ev = bsdf_eval(m, wo_l, wi_l);
        fc = ev.xyz * select(abs(dot(wi, n)), 1.0, phase);
        pdfs = tech_pdfs(p, n, nf, wi, ev.w);
        // A light draw's own density is the mixture's, and it fails where that is not
        // positive (Lights::sample_selected, sample_by_area).
        let own = pdfs[k];
        if (code != T_BSDF) { ok = own > 0.0 && is_finite(own); }
    }
    if (!ok || j == frame.n_draws) {
        // (The extra draw, when it neither extends the path nor hit a delta lobe, adds
        // nothing.)
        draws[at + 1u] = vec4<f32>(0.0, 0.0, 0.0, select(D_FAILED, 0.0, j == frame.n_draws));
        draws[at + 2u] = vec4<f32>(0.0, 0.0, 0.0, vflags);
        atomicMax(&stats[2], loops);
        return;
    }
    for (var c = 0u; c < (frame.n_tech + 3u) / 4u; c++) {
        loops++;
        let k = 4u * c;
        draws[at + DRAW_HEAD + c] = vec4<f32>(pdfs[k], pdfs[k + 1u], pdfs[k + 2u], pdfs[k + 3u]);
    }
    // Per-light mode: the MIS light the draw's ray reaches, objects ignored (the nearest
    // area light, else the environment; render::integrator::vertex::light_reached),
    // as 4 × (1 + index) in the flags (0: none).
    var reached = vflags;
    if (per_light) {
        if (lh.t < inf()) {
            reached += 4.0 * f32(lh.index + 1u);
        } else if (frame.env.kind != ENV_NONE) {
            reached += 4.0 * f32(frame.n_lights + 1u);
        }
    }
    if (carries) {
        write_carried(at, o, wi, beta * fc, reached);
    } else {
        // render::integrator::vertex::incident (with emitting objects, the shadow pass
        // finds Li: trace_shadow).
        var le = incoming(lh, wi);
        if (emitters) { le = vec3<f32>(1.0); }
        let traced = any(fc != vec3<f32>(0.0)) && any(le != vec3<f32>(0.0));
        write_shadow(i, at, o, wi, lh.t, beta * fc * le, reached, traced);
    }
    atomicMax(&stats[2], loops);
}

// A draw whose light arrives along a shadow ray from o along wi up to t_max: its record,
// with g the integrand before visibility, and, where `traced`, the ray queued for the
// shadow pass (which runs over the queue alone: compaction, GPU.md §7.4).
fn write_shadow(i: u32, at: u32, o: vec3<f32>, wi: vec3<f32>, t_max: f32, g: vec3<f32>, flags: f32, traced: bool) {
    draws[at] = vec4<f32>(o, t_max);
    draws[at + 1u] = vec4<f32>(wi, select(D_ZERO, D_SHADOW, traced));
    draws[at + 2u] = vec4<f32>(g, flags);
    if (traced) { push(QUEUE_LEN, QUEUE_ITEMS, i); }
}

// The draw that extends the path: Li comes from the continuation's trace (mode 2),
// which multiplies it into g.
fn write_carried(at: u32, o: vec3<f32>, wi: vec3<f32>, g: vec3<f32>, flags: f32) {
    draws[at] = vec4<f32>(o, 0.0);
    draws[at + 1u] = vec4<f32>(wi, D_CARRIED);
    draws[at + 2u] = vec4<f32>(g, flags);
}

// render::integrator::vertex::spawn, with an offset for f32: the CPU's 10⁻⁷ (for f64)
// left 2.7 % of a test image's pixels darker by over 30 % (shadow rays finding the
// surface they leave); 10⁻⁵ left none (docs/gpu.md).
fn spawn(p: vec3<f32>, n: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    var side = n;
    if (dot(wi, n) < 0.0) { side = -n; }
    return p + side * (1e-5 * (1.0 + max(abs(p.x), max(abs(p.y), abs(p.z)))));
}

// Point or spot light l (after the area lights in `lights`: shape 3 point, 4 spot;
// radiance = intensity, p0 = position, e1 = axis and cos of the falloff's start,
// e2.x = cos of the cone) at the vertex, outside MIS (Integrator::delta_lights): its
// shadow ray is queued with β·f·|cos|·I/d², unless nothing could arrive.
fn shade_delta(i: u32, at: u32, l: u32, p: vec3<f32>, n: vec3<f32>, f: Basis, wo_l: vec3<f32>, m: GpuBsdf, beta: vec3<f32>) {
    draws[at + 1u] = vec4<f32>(0.0, 0.0, 0.0, 0.0);
    let dl = lights[frame.n_lights + l];
    let v = dl.p0.xyz - p;
    let d2 = dot(v, v);
    if (d2 == 0.0) { return; }
    let wi = v / sqrt(d2);
    var intensity = dl.radiance.xyz;
    if (dl.shape == 4u) {
        // smoothstep(axis·(−wi), cos_end, cos_start), as render::light::delta.
        let a = dl.e2.x;
        let b = dl.e1.w;
        let x = dot(dl.e1.xyz, -wi);
        var s = 0.0;
        if (a == b) {
            s = select(1.0, 0.0, x < a);
        } else {
            let t = clamp((x - a) / (b - a), 0.0, 1.0);
            s = t * t * (3.0 - 2.0 * t);
        }
        intensity = intensity * s;
    }
    let radiance = intensity / d2;
    let fc = bsdf_eval(m, wo_l, to_local(f, wi)).xyz * select(abs(dot(wi, n)), 1.0, m.kind == K_PHASE);
    if (all(fc == vec3<f32>(0.0)) || all(radiance == vec3<f32>(0.0))) { return; }
    let o = spawn(p, n, wi);
    let dist = length(dl.p0.xyz - o);
    if (nearest_light(o, wi, dist).t < inf()) { return; }
    write_shadow(i, at, o, wi, dist, beta * fc * radiance, 0.0, true);
}

// An indirect dispatch of n invocations at stats[at..at + 3], split over y where x
// would pass 65 535 workgroups.
fn dispatch_args(at: u32, n: u32) {
    let groups = max((n + 63u) / 64u, 1u);
    let x = min(groups, 65535u);
    atomicStore(&stats[at], x);
    atomicStore(&stats[at + 1u], (groups + x - 1u) / x);
    atomicStore(&stats[at + 2u], 1u);
}

// The queued passes' indirect dispatches from their queues' lengths (one invocation):
// the shadow rays, the live slots' draws, the continuations.
@compute @workgroup_size(1)
fn prepare() {
    dispatch_args(QUEUE_ARGS, atomicLoad(&stats[QUEUE_LEN]));
    dispatch_args(LIVE_ARGS, atomicLoad(&stats[LIVE_LEN]) * frame.per_slot);
    dispatch_args(CONT_ARGS, atomicLoad(&stats[CONT_LEN]));
}

// Texture t at point p with normal n (render::texture; 0 where unknown) of a material
// `mat`: a point-space checker, cells of p·scale − n·10⁻³, a where their index sum is
// even; else in the object's own space, a·(1 − t) + b·t with t the pattern at p·scale,
// or the image's triplanar projection at p·scale; clamped to [0, 1] where t says so.
fn texture_rgb(t: GpuTexture, mat: GpuMaterial, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    var rgb = vec3<f32>(0.0);
    if (t.kind == 1u) {
        let q = floor(p * t.a.w - n * 1e-3);
        let cells = q.x + q.y + q.z;
        let r = cells - 2.0 * floor(cells * 0.5);
        rgb = select(t.b, t.a, r < 0.5).xyz;
    } else {
        let q = vec3<f32>(dot(mat.lx.xyz, p) + mat.lx.w, dot(mat.ly.xyz, p) + mat.ly.w,
            dot(mat.lz.xyz, p) + mat.lz.w) * t.a.w;
        if (t.kind == 2u) {
            let v = pattern_value(t.code, q, t.size);
            rgb = t.a.xyz * (1.0 - v) + t.b.xyz * v;
        } else {
            var nl = vec3<f32>(dot(mat.nx.xyz, n), dot(mat.ny.xyz, n), dot(mat.nz.xyz, n));
            let len = length(nl);
            nl = select(vec3<f32>(0.0), nl / len, len > 0.0);
            rgb = triplanar(t.code, t.size, u32(t.b.x), q, nl, t.b.y);
        }
    }
    if (t.clamp != 0u) { rgb = clamp(rgb, vec3<f32>(0.0), vec3<f32>(1.0)); }
    return rgb;
}

// An image's pixel (i, j), both wrapped into the image (rem_euclid), from its RGB f32
// pixels at sel_buf[off], w × h of them, row-major.
fn image_at(off: u32, w: u32, h: u32, i: f32, j: f32) -> vec3<f32> {
    let fw = f32(w);
    let fh = f32(h);
    let ii = min(u32(i - fw * floor(i / fw)), w - 1u);
    let jj = min(u32(j - fh * floor(j / fh)), h - 1u);
    let at = off + 3u * (jj * w + ii);
    return vec3<f32>(sel_buf[at], sel_buf[at + 1u], sel_buf[at + 2u]);
}

// The image at (u, v), one repeat per unit, v down the rows, bilinear between pixel
// centres, repeating (render::texture::bilinear).
fn bilinear(off: u32, w: u32, h: u32, u: f32, v: f32) -> vec3<f32> {
    let x = (u - floor(u)) * f32(w) - 0.5;
    let y = (v - floor(v)) * f32(h) - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let top = image_at(off, w, h, x0, y0) * (1.0 - fx) + image_at(off, w, h, x0 + 1.0, y0) * fx;
    let bottom = image_at(off, w, h, x0, y0 + 1.0) * (1.0 - fx) + image_at(off, w, h, x0 + 1.0, y0 + 1.0) * fx;
    return top * (1.0 - fy) + bottom * fy;
}

// Triplanar mapping at p (scaled) with the unit normal n (0: unknown, the z
// projection), the projections weighted by |n_i|^k (render::texture::triplanar).
fn triplanar(off: u32, w: u32, h: u32, p: vec3<f32>, n: vec3<f32>, k: f32) -> vec3<f32> {
    let wt = pow(abs(n), vec3<f32>(k));
    let sum = wt.x + wt.y + wt.z;
    if (!(sum > 0.0)) { return bilinear(off, w, h, p.x, -p.y); }
    let ws = wt / sum;
    var c = vec3<f32>(0.0);
    if (ws.x > 0.0) { c += bilinear(off, w, h, p.y, -p.z) * ws.x; }
    if (ws.y > 0.0) { c += bilinear(off, w, h, p.x, -p.z) * ws.y; }
    if (ws.z > 0.0) { c += bilinear(off, w, h, p.x, -p.y) * ws.z; }
    return c;
}
