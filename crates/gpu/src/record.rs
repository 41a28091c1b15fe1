//! Per-pixel records summed on the GPU (GPU.md §8): each sample's terms of its pixel's
//! record, in f32 (`shaders/record.wgsl`, one invocation per slot), then added to the
//! per-pixel sums in f64 or double-float by [`crate::sums`]' kernels, so that the
//! integrators hand the CPU a finished record instead of every draw.
//!
//! The terms are what `state::Tally::add` adds for the same hits and
//! draws, for every record that is a plain sum of per-sample terms
//! ([`state::LinearRecord`]: the heuristics, optimal-direct and
//! optimal-uncorrelated, per light too, AOVs and the AOV integrators), and the
//! progressive estimators' α-free terms, to which [`crate::progressive`] applies α. The optimal
//! estimators' moments are formed as `Â_ij += r_i r_j` and `b̂_ci += (f_c/s) r_i` with
//! `r_i = p_i/s ≤ 1/n_i` (Kondapaneni et al. 2019, eqs. 15–16), so no f32 term
//! overflows where `p_i p_j / s²` would. [`slot_terms`] is the kernel's CPU twin,
//! operation for operation.

use crate::progressive::{Blocks, ProgressiveSums};
use crate::{Gpu, GpuError};
use bytemuck::{Pod, Zeroable};
use state::{LinearMis, LinearRecord, Record};

/// The terms kernel (after [`record_consts_wgsl`]).
pub const RECORD_WGSL: &str = include_str!("shaders/record.wgsl");

/// f32 words of a slot's hit record in the wave's `hits` buffer (the `direct` kernels'
/// layout, `shaders/direct_bindings.wgsl`).
pub const HIT_WORDS: usize = 40;
/// f32 words of a draw record before its techniques' pdfs: [o, t_max], [wi, status],
/// [f or g, flags].
pub const DRAW_HEAD_WORDS: usize = 12;

/// The most techniques a draw record holds pdfs for: as many as a render may list
/// (`state::MAX_TECHNIQUES`).
pub const MAX_DRAW_TECHNIQUES: usize = state::MAX_TECHNIQUES;

/// f32 words of one draw record in the wave's `draws` buffer for `n_tech` techniques:
/// the head and the pdfs, padded to whole vec4s (the kernels' `draw_vec4s`).
pub const fn draw_words(n_tech: u32) -> usize {
    DRAW_HEAD_WORDS + 4 * n_tech.div_ceil(4) as usize
}

/// Where the overflow list starts in the tally buffer (in u32 words).
pub const TALLY_LIST: usize = 8;

/// WGSL constants of the wave's records, from [`HIT_WORDS`], [`DRAW_HEAD_WORDS`] and
/// [`draw_words`]: the vec4s of a hit record (`HIT_WORDS`), of a draw record's head
/// (`DRAW_HEAD`), the most techniques (`MAX_TECH`) and a draw record's vec4s for
/// `n_tech` techniques (`draw_vec4s`), prepended to the kernels that read or write them
/// so that no shader repeats them by hand.
pub fn wave_consts_wgsl() -> String {
    format!(
        "const HIT_WORDS: u32 = {}u;\nconst DRAW_HEAD: u32 = {}u;\nconst MAX_TECH: u32 = {}u;\n\
         fn draw_vec4s(n_tech: u32) -> u32 {{ return DRAW_HEAD + (n_tech + 3u) / 4u; }}\n",
        HIT_WORDS / 4,
        DRAW_HEAD_WORDS / 4,
        MAX_DRAW_TECHNIQUES,
    )
}

/// The terms kernel's WGSL constants from this module's and the record's: the wave's
/// records ([`wave_consts_wgsl`]), the record's words `OUTSIDE` and `AOV`
/// ([`Record`]), [`TALLY_LIST`], how draws enter the record (`C_AOV`, …) and the
/// heuristics (`H_BALANCE`, …).
pub fn record_consts_wgsl() -> String {
    let u = |name: &str, v: usize| format!("const {name}: u32 = {v}u;\n");
    let codes = [
        ("C_AOV", code::AOV),
        ("C_OUTSIDE", code::OUTSIDE),
        ("C_WEIGHTED", code::WEIGHTED),
        ("C_DIRECT", code::DIRECT),
        ("C_UNCORRELATED", code::UNCORRELATED),
        ("C_PROGRESSIVE", code::PROGRESSIVE),
        ("H_BALANCE", heuristic::BALANCE),
        ("H_POWER", heuristic::POWER),
        ("H_MAXIMUM", heuristic::MAXIMUM),
        ("H_CUTOFF", heuristic::CUTOFF),
    ];
    let mut s = wave_consts_wgsl();
    s += &u("OUTSIDE", Record::OUTSIDE);
    s += &u("AOV", Record::AOV);
    s += &u("TALLY_LIST", TALLY_LIST);
    for (name, v) in codes {
        s += &u(name, v as usize);
    }
    s
}

/// How draws enter the record (`LinearMis`, and the AOV integrators).
mod code {
    pub const AOV: u32 = 0;
    pub const OUTSIDE: u32 = 1;
    pub const WEIGHTED: u32 = 2;
    pub const DIRECT: u32 = 3;
    pub const UNCORRELATED: u32 = 4;
    pub const PROGRESSIVE: u32 = 5;
}

/// The heuristic of a heuristic record (`RecordParams::heuristic`; `H_*` in the shader).
mod heuristic {
    pub const BALANCE: u32 = 0;
    pub const POWER: u32 = 1;
    pub const MAXIMUM: u32 = 2;
    pub const CUTOFF: u32 = 3;
}

/// The kernel's uniform block (`RecordParams` in record.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RecordParams {
    /// Slots in the wave.
    pub slots: u32,
    /// Pixels of the image (slot = sample · pixels + pixel).
    pub pixels: u32,
    /// Sample indices in the wave.
    pub samples: u32,
    /// Words of one record.
    pub stride: u32,
    /// How draws enter the record: 0 the AOV integrators, 1 a heuristic into the
    /// outside sum (`path`), 2 heuristic blocks, 3 optimal-direct, 4
    /// optimal-uncorrelated, 5 the progressive estimators' α-free terms
    /// ([`LinearMis::Progressive`]).
    pub code: u32,
    /// 0 balance, 1 power, 2 maximum, 3 cutoff.
    pub heuristic: u32,
    /// AOV words (7 or 0).
    pub aov: u32,
    /// Depths with MIS blocks.
    pub depths: u32,
    /// MIS blocks per depth.
    pub lights: u32,
    /// Words of one MIS block.
    pub block: u32,
    /// Vertices shallower than this add nothing.
    pub min_depth: u32,
    /// Techniques T.
    pub n_tech: u32,
    /// Σ n_k draws per vertex.
    pub n_draws: u32,
    /// Draw records per slot and depth (the techniques', the extra draw, point lights).
    pub per_slot: u32,
    /// Vertex depths in the draws buffer.
    pub max_depth: u32,
    /// The wave's first sample index.
    pub start: u32,
    /// The AOV integrators' image: 0 depth, 1 normal, 2 albedo.
    pub aov_image: u32,
    /// β of the power heuristic, c of the cutoff.
    pub param: f32,
    /// Words of one set of moments, `T(T+1)/2 + 3T`.
    pub moments: u32,
    /// Padding.
    pub pad: u32,
    /// n_k, as f32.
    pub counts: [[f32; 4]; MAX_DRAW_TECHNIQUES / 4],
}

impl RecordParams {
    /// The parameters of `linear` for a wave's draws: `n_draws` technique draws among
    /// `per_slot` records per vertex, `max_depth` vertices. The wave's own fields
    /// (`slots`, `pixels`, `samples`, `start`) are left 0.
    pub fn new(linear: &LinearRecord, n_draws: u32, per_slot: u32, max_depth: u32) -> Self {
        let t = linear.counts.len() as u32;
        let (code, h) = match (linear.aov_image, linear.mis) {
            (Some(_), _) => (code::AOV, None),
            (None, LinearMis::Outside(h)) => (code::OUTSIDE, Some(h)),
            (None, LinearMis::Weighted(h)) => (code::WEIGHTED, Some(h)),
            (None, LinearMis::Direct) => (code::DIRECT, None),
            (None, LinearMis::Uncorrelated) => (code::UNCORRELATED, None),
            (None, LinearMis::Progressive(_)) => (code::PROGRESSIVE, None),
        };
        let (heuristic, param) = match h {
            None | Some(mis::Heuristic::Balance) => (heuristic::BALANCE, 0.0),
            Some(mis::Heuristic::Power { beta }) => (heuristic::POWER, beta as f32),
            Some(mis::Heuristic::Maximum) => (heuristic::MAXIMUM, 0.0),
            Some(mis::Heuristic::Cutoff { c }) => (heuristic::CUTOFF, c as f32),
        };
        let mut counts = [[0.0; 4]; MAX_DRAW_TECHNIQUES / 4];
        for (k, &n) in linear.counts.iter().enumerate() {
            counts[k / 4][k % 4] = n as f32;
        }
        let r = &linear.record;
        RecordParams {
            stride: r.stride() as u32,
            code,
            heuristic,
            aov: r.aov as u32,
            depths: r.depths as u32,
            lights: r.lights as u32,
            block: r.block as u32,
            min_depth: linear.min_depth,
            n_tech: t,
            n_draws,
            per_slot,
            max_depth,
            aov_image: linear.aov_image.unwrap_or(0),
            param,
            moments: t * (t + 1) / 2 + 3 * t,
            counts,
            ..Default::default()
        }
    }

    /// The most iterations of the terms kernel's innermost loops one slot can run (each
    /// technique's draw visiting every light's block and its moments): kept far below
    /// llvmpipe's 65 535 (GPU.md §3.1) by the integrator's choice of where sums run.
    pub fn loop_bound(&self) -> u64 {
        let t = u64::from(self.n_tech);
        // The progressive terms add G (3) and Q (T) to the moments' T² + 4T.
        let extra = if self.code == code::PROGRESSIVE {
            t + 3
        } else {
            0
        };
        let per_draw = u64::from(self.lights) * (t * t + 4 * t + extra);
        let per_vertex = u64::from(self.per_slot) * 2 + u64::from(self.n_draws) * per_draw;
        u64::from(self.max_depth) * (u64::from(self.per_slot) + per_vertex) + 16
    }
}

/// What one slot traced, and whether it overflowed (then it adds nothing: the CPU renders
/// it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SlotTally {
    /// A ray ran past a fixed capacity.
    pub overflow: bool,
    /// Camera rays (1, or 0 on overflow).
    pub camera: u32,
    /// Shadow rays.
    pub shadow: u32,
    /// Continuation rays.
    pub secondary: u32,
}

/// The twin's view of one slot, as the kernel's private state.
struct Slot<'a> {
    p: &'a RecordParams,
    slot: u32,
    draws: &'a [f32],
    out: &'a mut [f32],
    set: u32,
}

fn is_finite(x: f32) -> bool {
    x.to_bits() & 0x7f80_0000 != 0x7f80_0000
}

impl Slot<'_> {
    fn add(&mut self, w: u32, v: f32) {
        self.out[w as usize] += v;
    }
    fn add3(&mut self, w: u32, v: [f32; 3]) {
        for (c, x) in v.into_iter().enumerate() {
            self.add(w + c as u32, x);
        }
    }
    fn draw_at(&self, depth: u32, j: u32) -> usize {
        ((depth * self.p.slots + self.slot) * self.p.per_slot + j) as usize
            * draw_words(self.p.n_tech)
    }
    fn n(&self, k: u32) -> f32 {
        self.p.counts[k as usize / 4][k as usize % 4]
    }
    fn pdf(&self, at: usize, k: u32) -> f32 {
        self.draws[at + DRAW_HEAD_WORDS + k as usize]
    }
    fn q(&self, at: usize, k: u32) -> f32 {
        self.n(k) * self.pdf(at, k)
    }
    fn mixture(&self, at: usize, k: u32) -> f32 {
        let mut s = 0.0f32;
        for t in 0..self.p.n_tech {
            s += self.q(at, t);
        }
        if self.pdf(at, k) > 0.0 && is_finite(s) {
            s
        } else {
            -1.0
        }
    }
    fn power(&self, x: f32) -> f32 {
        if self.p.param == 2.0 {
            x * x
        } else {
            x.powf(self.p.param)
        }
    }
    fn scale(&self, at: usize, k: u32, s: f32) -> f32 {
        if self.p.heuristic == heuristic::BALANCE {
            return 1.0 / s;
        }
        let qt = self.q(at, k);
        let tt = self.p.n_tech;
        let mut w = 0.0f32;
        if qt.is_nan() || qt <= 0.0 {
            w = 0.0;
        } else if self.p.heuristic == heuristic::MAXIMUM {
            w = 1.0;
            for t in 0..tt {
                let below = if t < k {
                    self.q(at, t) < qt
                } else {
                    self.q(at, t) <= qt
                };
                if !below {
                    w = 0.0;
                }
            }
        } else {
            let mut m = 0.0f32;
            for t in 0..tt {
                m = m.max(self.q(at, t));
            }
            if self.p.heuristic == heuristic::POWER {
                let mut sum = 0.0f32;
                for t in 0..tt {
                    sum += self.power(self.q(at, t) / m);
                }
                w = self.power(qt / m) / sum;
            } else {
                let floor = self.p.param * m;
                // As the kernel's `!(qt < floor)`.
                if qt.partial_cmp(&floor) != Some(std::cmp::Ordering::Less) {
                    let mut sum = 0.0f32;
                    for t in 0..tt {
                        if self.q(at, t) >= floor {
                            sum += self.q(at, t);
                        }
                    }
                    w = qt / sum;
                }
            }
        }
        w / (self.n(k) * self.pdf(at, k))
    }
    fn moments_failed(&mut self, m: u32, k: u32) {
        let n = self.n(k);
        self.add(m + k * (k + 1) / 2 + k, 1.0 / (n * n));
    }
    fn moments_add(&mut self, m: u32, k: u32, f: [f32; 3], at: usize) {
        let s = self.mixture(at, k);
        if s < 0.0 {
            self.moments_failed(m, k);
            return;
        }
        let tt = self.p.n_tech;
        let mut idx = m;
        for i in 0..tt {
            let ri = self.pdf(at, i) / s;
            for j in 0..=i {
                let v = ri * (self.pdf(at, j) / s);
                self.add(idx, v);
                idx += 1;
            }
        }
        for (c, fc) in f.into_iter().enumerate() {
            if fc != 0.0 {
                let fs = fc / s;
                for i in 0..tt {
                    let v = fs * (self.pdf(at, i) / s);
                    self.add(idx + c as u32 * tt + i, v);
                }
            }
        }
    }
    fn block_at(&self, depth: u32, light: u32) -> u32 {
        Record::AOV as u32 + self.p.aov + (depth * self.p.lights + light) * self.p.block
    }
    fn block_sample(&mut self, b: u32, k: u32, f: [f32; 3], at: usize) {
        match self.p.code {
            code::WEIGHTED => {
                let s = self.mixture(at, k);
                if s < 0.0 {
                    return;
                }
                let w = self.scale(at, k, s);
                if w != 0.0 {
                    self.add3(b + 1, f.map(|x| x * w));
                }
            }
            code::DIRECT => self.moments_add(b + 1, k, f, at),
            code::PROGRESSIVE => {
                let tt = self.p.n_tech;
                self.moments_add(b + 4 + 3 * tt, k, f, at);
                let s = self.mixture(at, k);
                if s < 0.0 {
                    self.add(b + 4 + k, 1.0 / self.n(k));
                    return;
                }
                for (c, fc) in f.into_iter().enumerate() {
                    self.add(b + 1 + c as u32, fc / s);
                }
                for i in 0..tt {
                    let r = self.pdf(at, i) / s;
                    self.add(b + 4 + i, r);
                }
            }
            _ => self.moments_add(b + 2 + self.set * self.p.moments, k, f, at),
        }
    }
    fn block_failed(&mut self, b: u32, k: u32) {
        match self.p.code {
            code::DIRECT => self.moments_failed(b + 1, k),
            code::UNCORRELATED => self.moments_failed(b + 2 + self.set * self.p.moments, k),
            code::PROGRESSIVE => {
                self.moments_failed(b + 4 + 3 * self.p.n_tech, k);
                self.add(b + 4 + k, 1.0 / self.n(k));
            }
            _ => {}
        }
    }
    fn block_end(&mut self, b: u32) {
        if self.p.code == code::UNCORRELATED {
            self.add(b + self.set, 1.0);
        } else {
            self.add(b, 1.0);
        }
        if self.p.code == code::PROGRESSIVE {
            for i in 0..self.p.n_tech {
                self.add(b + 4 + i, -1.0);
            }
        }
    }
    fn add_draw(&mut self, depth: u32, k: u32, f: [f32; 3], at: usize, light: u32) {
        if self.p.code == code::OUTSIDE {
            let s = self.mixture(at, k);
            if s < 0.0 {
                return;
            }
            let w = self.scale(at, k, s);
            if w != 0.0 {
                self.add3(Record::OUTSIDE as u32, f.map(|x| x * w));
            }
            return;
        }
        if self.p.lights == 1 {
            self.block_sample(self.block_at(depth, 0), k, f, at);
            return;
        }
        for l in 0..self.p.lights {
            if l == light {
                self.block_sample(self.block_at(depth, l), k, f, at);
            } else {
                self.block_failed(self.block_at(depth, l), k);
            }
        }
    }
}

/// The terms of slot `slot` of a wave (record.wgsl's `record_terms`, operation for
/// operation): `hits` and `draws` are the wave's buffers as f32 words, `out` the slot's
/// `stride` terms, zero on entry.
pub fn slot_terms(
    p: &RecordParams,
    slot: u32,
    hits: &[f32],
    draws: &[f32],
    out: &mut [f32],
) -> SlotTally {
    let sample = slot / p.pixels;
    let mut s = Slot {
        p,
        slot,
        draws,
        out,
        set: (p.start + sample) & 1,
    };
    let h = &hits[slot as usize * HIT_WORDS..(slot as usize + 1) * HIT_WORDS];
    let mut tally = SlotTally::default();
    let overflow = h[3] == 2.0
        || (0..p.max_depth).any(|d| (0..p.per_slot).any(|j| draws[s.draw_at(d, j) + 7] == 12.0));
    if overflow {
        tally.overflow = true;
        return tally;
    }
    tally.camera = 1;
    let (normal, depth, albedo) = ([h[32], h[33], h[34]], h[35], [h[36], h[37], h[38]]);
    let outside = Record::OUTSIDE as u32;
    if p.code == code::AOV {
        s.add3(
            outside,
            match p.aov_image {
                0 => [depth; 3],
                1 => normal,
                _ => albedo,
            },
        );
    }
    if p.aov != 0 {
        let aov = Record::AOV as u32;
        s.add(aov, depth);
        s.add3(aov + 1, normal);
        s.add3(aov + 4, albedo);
    }
    if p.code == code::AOV {
        s.add(0, 1.0);
        return tally;
    }
    if p.min_depth == 0 {
        s.add3(outside, [h[12], h[13], h[14]]);
    }
    let mut shaded = 0;
    while shaded < p.max_depth && p.n_draws > 0 && draws[s.draw_at(shaded, 0) + 7] != 0.0 {
        shaded += 1;
    }
    for d in 0..shaded {
        let mute = d + 1 < p.min_depth;
        let mut vo = [0.0f32; 3];
        for j in 0..p.per_slot {
            let at = s.draw_at(d, j);
            let status = draws[at + 7];
            if status == 4.0 || status == 5.0 {
                tally.shadow += 1;
            }
            if status == 6.0 {
                tally.secondary += 1;
            }
            let flags = draws[at + 11] as u32;
            if (j > p.n_draws || flags & 1 != 0) && (status == 4.0 || status == 6.0) {
                for c in 0..3 {
                    vo[c] += draws[at + 8 + c];
                }
            }
        }
        if mute {
            continue;
        }
        s.add3(outside, vo);
        if draws[s.draw_at(d, 0) + 11] as u32 & 2 != 0 {
            continue;
        }
        let mut j = 0;
        for k in 0..p.n_tech {
            for _ in 0..s.n(k) as u32 {
                let at = s.draw_at(d, j);
                let status = draws[at + 7];
                let flags = draws[at + 11] as u32;
                if status == 1.0 || flags & 1 != 0 {
                    if p.code != code::OUTSIDE {
                        for l in 0..p.lights {
                            s.block_failed(s.block_at(d, l), k);
                        }
                    }
                } else {
                    let f = if status == 4.0 || status == 6.0 {
                        [draws[at + 8], draws[at + 9], draws[at + 10]]
                    } else {
                        [0.0; 3]
                    };
                    s.add_draw(d, k, f, at, ((flags >> 2) + p.lights) % (p.lights + 1));
                }
                j += 1;
            }
        }
        if p.code != code::OUTSIDE {
            for l in 0..p.lights {
                s.block_end(s.block_at(d, l));
            }
        }
    }
    s.add(0, 1.0);
    tally
}

/// The terms kernel, compiled (entry `record_terms`, bindings: the params, the wave's
/// hits and draws, the terms, the tally).
pub struct RecordTerms {
    pub(crate) pipeline: wgpu::ComputePipeline,
}

impl RecordTerms {
    /// Compiles the kernel.
    pub fn new(gpu: &Gpu) -> Result<Self, GpuError> {
        let source = [crate::FLOAT_WGSL, &record_consts_wgsl(), RECORD_WGSL].join("\n");
        let pipeline = crate::kernel::compute_pipeline(gpu, &source, "record_terms", false)?;
        Ok(Self { pipeline })
    }

    /// The bind group over `params` (uniform), `hits`, `draws`, `terms` and `tally`.
    pub(crate) fn bind(&self, gpu: &Gpu, buffers: [&wgpu::Buffer; 5]) -> wgpu::BindGroup {
        let layout = self.pipeline.get_bind_group_layout(0);
        crate::bind_buffers(gpu, "record_terms", &layout, buffers)
    }

    /// Runs the kernel over `p.slots` slots of `hits` and `draws` (f32 words) and reads
    /// back the terms (`p.pixels · p.samples · p.stride` words) and the tally
    /// ([`TALLY_LIST`] + `p.slots` words): for twin tests.
    pub fn run(
        &self,
        gpu: &Gpu,
        p: &RecordParams,
        hits: &[f32],
        draws: &[f32],
    ) -> Result<(Vec<f32>, Vec<u32>), GpuError> {
        use wgpu::util::DeviceExt;
        let d = &gpu.device;
        let init = |label, bytes: &[u8], usage| {
            d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytes,
                usage,
            })
        };
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let params = init("params", bytemuck::bytes_of(p), wgpu::BufferUsages::UNIFORM);
        let hits = init("hits", bytemuck::cast_slice(hits), storage);
        // An empty binding is invalid: give no draws one zero record.
        let draws = init(
            "draws",
            bytemuck::cast_slice(if draws.is_empty() {
                &[0.0; draw_words(MAX_DRAW_TECHNIQUES as u32)]
            } else {
                draws
            }),
            storage,
        );
        let n_terms = (p.pixels * p.samples * p.stride) as usize;
        let terms = init("terms", &vec![0; 4 * n_terms], storage);
        let n_tally = TALLY_LIST + p.slots as usize;
        let tally = init("tally", &vec![0; 4 * n_tally], storage);
        let group = self.bind(gpu, [&params, &hits, &draws, &terms, &tally]);
        let mut enc = d.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(p.slots.div_ceil(64), 1, 1);
        }
        let staging = |size: usize| {
            d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("readback"),
                size: 4 * size as u64,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let (terms_r, tally_r) = (staging(n_terms), staging(n_tally));
        enc.copy_buffer_to_buffer(&terms, 0, &terms_r, 0, 4 * n_terms as u64);
        enc.copy_buffer_to_buffer(&tally, 0, &tally_r, 0, 4 * n_tally as u64);
        gpu.queue.submit([enc.finish()]);
        let t = crate::readback::read_back(gpu, &terms_r, 4 * n_terms as u64)?;
        let y = crate::readback::read_back(gpu, &tally_r, 4 * n_tally as u64)?;
        Ok((
            bytemuck::cast_slice(&t).to_vec(),
            bytemuck::cast_slice(&y).to_vec(),
        ))
    }
}

/// The kernels that keep a render's sums on the GPU, compiled once per device.
pub(crate) struct SumKernels {
    terms: RecordTerms,
    /// The double-float sums, and the f64 ones where the device has `SHADER_F64`.
    df: crate::sums::Accumulate,
    f64: Option<crate::sums::Accumulate>,
    /// The progressive estimators' pass.
    progressive: crate::progressive::Kernels,
}

impl SumKernels {
    fn add(&self, f64: bool) -> &crate::sums::Accumulate {
        match (f64, &self.f64) {
            (true, Some(k)) => k,
            _ => &self.df,
        }
    }
}

fn sum_kernels(gpu: &Gpu) -> Result<std::sync::Arc<SumKernels>, GpuError> {
    gpu.kernels.get_or_make("", || {
        Ok(SumKernels {
            terms: RecordTerms::new(gpu)?,
            df: crate::sums::Accumulate::with_f64(gpu, false)?,
            f64: match gpu.info().f64 {
                true => Some(crate::sums::Accumulate::with_f64(gpu, true)?),
                false => None,
            },
            progressive: crate::progressive::Kernels::new(gpu, gpu.info().f64)?,
        })
    })
}

/// What a wave's tally says: the slots the CPU must render (sorted) and the rays the
/// others traced.
pub(crate) struct WaveTally {
    pub overflow: Vec<u32>,
    pub camera: u64,
    pub shadow: u64,
    pub secondary: u64,
}

/// A render's per-pixel records kept on the GPU: each wave's terms (`record.wgsl`) added
/// into the sums (`sums.wgsl` or `sums_f64.wgsl`), which alternate between two buffers
/// (one read, one written per wave); only the tally is read back per wave, the sums once
/// at the end.
pub(crate) struct GpuSums {
    kernels: std::sync::Arc<SumKernels>,
    params: RecordParams,
    params_buf: wgpu::Buffer,
    add_params: wgpu::Buffer,
    terms: wgpu::Buffer,
    tally: wgpu::Buffer,
    tally_r: wgpu::Buffer,
    sums: [wgpu::Buffer; 2],
    terms_group: wgpu::BindGroup,
    add_groups: [wgpu::BindGroup; 2],
    /// Which of `sums` holds the sums so far.
    current: usize,
    /// Whether the sums are f64 (else double-float).
    f64: bool,
    /// The progressive estimators' pass, which replaces the sums kernel for them.
    progressive: Option<ProgressiveSums>,
    /// Sample indices per wave at most (the sums kernel loops samples × stride times).
    pub max_samples: u32,
}

/// The most loop iterations the terms and sums kernels may take per invocation (GPU.md
/// §3.1, with the margin the other kernels keep).
const LOOP_BUDGET: u64 = 30_000;

impl GpuSums {
    /// The sums of a render of `pixels` pixels whose record is `linear` (its blocks run
    /// by `kernel`), over the wave buffers `hits` and `draws` (waves of at most
    /// `max_slots` slots), in f64 if `f64` and the device has it, else in double-float;
    /// or None where they do not fit the device's bindings or the loop budget (the CPU
    /// then adds the draws).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        gpu: &Gpu,
        linear: &LinearRecord,
        kernel: Option<&mis::Kernel>,
        pixels: u32,
        max_slots: u32,
        (n_draws, per_slot, max_depth): (u32, u32, u32),
        hits: &wgpu::Buffer,
        draws: &wgpu::Buffer,
        f64: bool,
    ) -> Result<Option<Self>, GpuError> {
        let params = RecordParams::new(linear, n_draws, per_slot, max_depth);
        let stride = u64::from(params.stride);
        let max_binding = gpu.info().max_storage_binding;
        let sums_bytes = u64::from(pixels) * stride * 8;
        // The progressive pass also applies 3T α words per block and sample.
        let blocks = Blocks {
            first: (Record::AOV + linear.record.aov) as u32,
            count: linear.record.blocks() as u32,
            words: linear.record.block as u32,
            t: params.n_tech,
        };
        let progressive = match (params.code, kernel) {
            (code::PROGRESSIVE, Some(k)) => Some(k.clone()),
            (code::PROGRESSIVE, None) => return Ok(None),
            _ => None,
        };
        let per_sample = match progressive {
            Some(_) => stride + 3 * u64::from(blocks.count * blocks.t),
            None => stride,
        };
        let max_samples = (LOOP_BUDGET / per_sample)
            .min(max_binding / (u64::from(pixels) * stride * 4))
            .min(u64::from(max_slots / pixels)) as u32;
        if params.loop_bound() >= LOOP_BUDGET || sums_bytes > max_binding || max_samples == 0 {
            return Ok(None);
        }
        let kernels = sum_kernels(gpu)?;
        let f64 = f64 && kernels.f64.is_some();
        let d = &gpu.device;
        let buffer = |label, size: u64, usage| {
            d.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as U;
        let params_buf = buffer(
            "record params",
            size_of::<RecordParams>() as u64,
            U::UNIFORM | U::COPY_DST,
        );
        let add_params = buffer("sums params", 16, U::STORAGE | U::COPY_DST);
        let terms_bytes = u64::from(max_samples) * u64::from(pixels) * stride * 4;
        let terms = buffer("terms", terms_bytes, U::STORAGE | U::COPY_DST);
        let tally_bytes = (TALLY_LIST as u64 + u64::from(max_samples * pixels)) * 4;
        let tally = buffer("tally", tally_bytes, U::STORAGE | U::COPY_DST | U::COPY_SRC);
        let tally_r = buffer("tally readback", tally_bytes, U::MAP_READ | U::COPY_DST);
        let sum_usage = U::STORAGE | U::COPY_SRC | U::COPY_DST;
        let sums = [
            buffer("sums", sums_bytes, sum_usage),
            buffer("sums", sums_bytes, sum_usage),
        ];
        let terms_group = kernels
            .terms
            .bind(gpu, [&params_buf, hits, draws, &terms, &tally]);
        let add_layout = kernels.add(f64).pipeline().get_bind_group_layout(0);
        let add_group = |prev: &wgpu::Buffer, state: &wgpu::Buffer| {
            crate::bind_buffers(gpu, "sums", &add_layout, [&add_params, &terms, prev, state])
        };

        let add_groups = [add_group(&sums[0], &sums[1]), add_group(&sums[1], &sums[0])];
        let progressive = progressive.map(|k| {
            ProgressiveSums::new(
                gpu,
                &kernels.progressive,
                k,
                blocks,
                params.stride,
                pixels,
                &terms,
                &sums[0],
                f64,
            )
        });
        Ok(Some(Self {
            kernels,
            params: RecordParams { pixels, ..params },
            params_buf,
            add_params,
            terms,
            tally,
            tally_r,
            sums,
            terms_group,
            add_groups,
            current: 0,
            f64,
            progressive,
            max_samples,
        }))
    }

    /// Whether the sums are f64 (else double-float).
    pub fn is_f64(&self) -> bool {
        self.f64
    }

    /// Records the wave's two passes (terms, then sums) into `enc`, after the wave's
    /// own: `samples` sample indices from `start` of a band of `pixels` pixels (at most
    /// the `pixels` of [`Self::new`]); `timestamps(k)` gives pass k's timestamp writes.
    pub fn encode<'q>(
        &mut self,
        gpu: &Gpu,
        enc: &mut wgpu::CommandEncoder,
        pixels: u32,
        start: u32,
        samples: u32,
        timestamps: &dyn Fn(u32) -> Option<wgpu::ComputePassTimestampWrites<'q>>,
    ) {
        debug_assert!(pixels <= self.params.pixels && samples <= self.max_samples);
        let p = RecordParams {
            slots: samples * pixels,
            pixels,
            samples,
            start,
            ..self.params
        };
        gpu.queue
            .write_buffer(&self.params_buf, 0, bytemuck::bytes_of(&p));
        let terms_bytes = u64::from(p.slots) * u64::from(p.stride) * 4;
        enc.clear_buffer(&self.terms, 0, Some(terms_bytes));
        enc.clear_buffer(&self.tally, 0, Some(TALLY_LIST as u64 * 4));
        let terms = &self.kernels.terms.pipeline;
        crate::dispatch(enc, timestamps(0), terms, &self.terms_group, p.slots);
        match self.progressive.as_mut() {
            // The progressive pass over the sums in place.
            Some(prog) => prog.encode(gpu, enc, p.pixels, samples, timestamps(1)),
            None => {
                let add = [0u32, p.pixels, samples, p.stride];
                gpu.queue
                    .write_buffer(&self.add_params, 0, bytemuck::cast_slice(&add));
                let pipeline = self.kernels.add(self.f64).pipeline();
                let group = &self.add_groups[self.current];
                crate::dispatch(enc, timestamps(1), pipeline, group, p.pixels);
                self.current = 1 - self.current;
            }
        }
        let tally_bytes = (TALLY_LIST as u64 + u64::from(p.slots)) * 4;
        enc.copy_buffer_to_buffer(&self.tally, 0, &self.tally_r, 0, tally_bytes);
    }

    /// The tally of the wave of `slots` slots last submitted.
    pub fn tally(&self, gpu: &Gpu, slots: u32) -> Result<WaveTally, GpuError> {
        let bytes = (TALLY_LIST as u64 + u64::from(slots)) * 4;
        let words = crate::readback::read_back(gpu, &self.tally_r, bytes)?;
        let t: &[u32] = bytemuck::cast_slice(&words);
        let mut overflow = t[TALLY_LIST..TALLY_LIST + t[0] as usize].to_vec();
        // The atomics append in any order: sorted, the CPU adds them in one.
        overflow.sort_unstable();
        Ok(WaveTally {
            overflow,
            camera: u64::from(t[1]),
            shadow: u64::from(t[2]),
            secondary: u64::from(t[3]),
        })
    }

    /// After the wave's submission, for the progressive estimators: the solves their
    /// schedule asks for within the wave, each followed by the rest of the pass
    /// ([`ProgressiveSums::settle`]). Returns the extra passes run.
    pub fn settle(&mut self, gpu: &Gpu) -> Result<u32, GpuError> {
        let (sums, f64) = (&self.sums[self.current], self.f64);
        match self.progressive.as_mut() {
            Some(p) => p.settle(gpu, &|words| read_sums(gpu, sums, f64, words)),
            None => Ok(0),
        }
    }

    /// Adds the sums to `records` (the band's records, `stride` words each; for the
    /// progressive estimators, [`ProgressiveSums::add_to`]).
    pub fn add_to(&self, gpu: &Gpu, records: &mut [f64]) -> Result<(), GpuError> {
        let sums = read_sums(gpu, &self.sums[self.current], self.f64, records.len())?;
        match &self.progressive {
            Some(p) => p.add_to(sums, records),
            None => {
                for (r, v) in records.iter_mut().zip(sums) {
                    *r += v;
                }
            }
        }
        Ok(())
    }

    /// Zero sums, for the next band.
    pub fn reset(&mut self, gpu: &Gpu) {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        for b in &self.sums {
            enc.clear_buffer(b, 0, None);
        }
        gpu.queue.submit([enc.finish()]);
        self.current = 0;
        if let Some(p) = self.progressive.as_mut() {
            p.reset(gpu);
        }
    }
}

/// The first `words` sums of `buffer` (f64 if `f64`, else double-float pairs) as f64.
fn read_sums(
    gpu: &Gpu,
    buffer: &wgpu::Buffer,
    f64: bool,
    words: usize,
) -> Result<Vec<f64>, GpuError> {
    let bytes = words as u64 * 8;
    let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("sums readback"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, bytes);
    gpu.queue.submit([enc.finish()]);
    let data = crate::readback::read_back(gpu, &staging, bytes)?;
    let w: &[u32] = bytemuck::cast_slice(&data);
    Ok(w.chunks_exact(2)
        .map(|w| match f64 {
            true => f64::from_bits(u64::from(w[0]) | u64::from(w[1]) << 32),
            false => crate::sums::df_value([f32::from_bits(w[0]), f32::from_bits(w[1])]),
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The constants the shaders share with Rust are prepended from Rust's, with the
    /// values the shaders once wrote by hand, and no shader defines them again.
    #[test]
    fn shared_constants_are_generated() {
        let wave = wave_consts_wgsl();
        assert!(wave.contains("const HIT_WORDS: u32 = 10u;"));
        assert!(wave.contains("const DRAW_HEAD: u32 = 3u;"));
        assert!(wave.contains("const MAX_TECH: u32 = 32u;"));
        assert_eq!((draw_words(8), draw_words(9), draw_words(32)), (20, 24, 44));
        let record = record_consts_wgsl();
        for line in [
            "const OUTSIDE: u32 = 1u;",
            "const AOV: u32 = 4u;",
            "const TALLY_LIST: u32 = 8u;",
            "const C_AOV: u32 = 0u;",
            "const C_PROGRESSIVE: u32 = 5u;",
            "const H_BALANCE: u32 = 0u;",
            "const H_POWER: u32 = 1u;",
            "const H_MAXIMUM: u32 = 2u;",
        ] {
            assert!(record.contains(line), "{line}");
        }
        let tape = crate::tape::tape_consts_wgsl();
        for line in [
            "const OP_VAR: u32 = 0u;",
            "const OP_POWI: u32 = 2u;",
            "const OP_NEG: u32 = 16u;",
            "const OP_SQUARE: u32 = 19u;",
            "const OP_ADD: u32 = 48u;",
            "const OP_MAX: u32 = 53u;",
            "const IMM: u32 = 255u;",
        ] {
            assert!(tape.contains(line), "{line}");
        }
        for (shader, consts) in [
            (RECORD_WGSL, &record),
            (crate::direct::DIRECT_WGSL, &wave),
            (crate::tape::TAPE_WGSL, &tape),
        ] {
            for line in consts.lines() {
                let declared = line.split(':').next().expect("a declaration");
                assert!(
                    !shader.contains(&format!("{declared}:")),
                    "the shader defines `{declared}` by hand"
                );
            }
        }
    }
}
