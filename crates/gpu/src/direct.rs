//! The `direct` and `path` integrators on the GPU: the resolved scene packed into
//! buffers, wavefront kernels (shaders/direct.wgsl: camera rays with their nearest hits,
//! the techniques' draws with every pdf, shadow rays, the paths' continuation rays), and
//! the CPU's per-pixel records filled from them (GPU.md §7–§8, first version).
//!
//! **Bands and waves.** The image is rendered in bands of consecutive pixels, each
//! through all its samples before the next, so that the buffers hold one band whatever
//! the image's size. A wave is m sample indices of every pixel of a band (m × band
//! slots, at most [`WAVE_DRAWS`] draws over all depths). Its passes (the camera trace, then per depth
//! shade, shadow rays and, but at the last depth, the continuation trace) run in one
//! submission without a CPU wait.
//!
//! **Sums.** Two more passes of the same submission keep the per-pixel sums on the GPU
//! ([`crate::record`]): each slot's f32 terms, then the sums in f64 (`SHADER_F64`) or
//! double-float, pixel by pixel in sample order; only a small tally (ray counts,
//! overflowing slots) is read back per wave, and the sums once at the end, into the
//! same [`RenderState`] as the CPU's. The progressive estimators' second pass applies
//! α and stops each pixel where its schedule re-solves α, which the CPU does between
//! passes ([`crate::progressive`]). Otherwise (`FREPRAY_GPU_SUMS=off`; sums too large
//! for one binding or the loop budget) the hits and draws are read back and added by
//! [`render::integrator::Accumulator`], the CPU integrator's own bookkeeping, in f64.
//! Either way the optimal estimators' solves are the CPU's and a GPU sample range
//! merges with a CPU one.
//!
//! **Same numbers, not the same image.** The kernels draw the CPU's random numbers
//! (`render::sampler`, truncated to 24 bits) in the CPU's dimension layout, Russian
//! roulette included, so a GPU render follows the CPU's paths closely, but in f32:
//! images agree statistically (GPU.md §9), tested by `tests/direct_image.rs`.
//!
//! **Overflow.** A ray whose perturbed-quadric scan runs past its fixed capacity
//! (K = 32 active perturbations after 4 halvings), whose tape trace stays undecided, or
//! whose CSG spans overflow, is never taken as a miss: the CPU renders that whole sample
//! instead, and the statistics count it.
//!
//! **Scope.** Objects that are one perturbed or plain quadric, a CSG tree (boxes,
//! capped cylinders, unions, differences: by inside spans along the ray, the nodes in
//! post-order from the root; a perturbed or expression part's spans from its crossings
//! found one by one, as frep's `Solid::combine` finds them), or an expression solid (up to
//! [`MAX_GPU_TAPES`] per scene: their tapes share one interpreter compiled into the
//! kernels, GPU.md §6.2); diffuse, conductor, dielectric and plastic materials
//! rough or smooth (delta lobes outside MIS, as the CPU), with constant or point-space checker colours; sphere,
//! rectangle and disk lights, point and spot lights, a constant or mapped environment
//! ([`crate::env`]); the techniques `bsdf`, `light`, `light-uniform`, `light-area`,
//! `light-spatial`, `light-trained` (the table the CPU trained), `light#k` and
//! `environment`; every MIS method, per light too; AOVs and the AOV integrators; `path` up to depth
//! [`MAX_GPU_DEPTH`]. Anything else is a
//! [`GpuError::Unsupported`] naming it, before any work.

use crate::bsdf::{GpuBsdf, BSDF_STRUCT_WGSL, BSDF_WGSL, COAT_TABLE_LEN};
use crate::env::{GpuEnv, ENV_WGSL};
use crate::layout::{outward, GpuObject, GpuPerturbation, GpuQuadric, LAYOUT_WGSL};
use crate::layout::{GpuBvhNode, GpuItemBox};
use crate::light::{self, GpuAreaLight, GPU_AREA_LIGHT_WGSL, LIGHT_WGSL};
use crate::perturbed::{PerturbedPack, PERTURBED_WGSL};
use crate::quadric::QUADRIC_WGSL;
use crate::readback::read_back;
use crate::record::GpuSums;
pub use crate::record::{DRAW_WORDS, HIT_WORDS};
use crate::sampler::PHILOX_WGSL;
pub use crate::stats::{GpuStats, StageTimes, SumsOn};
use crate::tape::GpuTape;
use crate::tape_trace::TapeSolid;
use crate::{f4, Gpu, GpuError, FLOAT_WGSL};
use bytemuck::{Pod, Zeroable};
use frep::flat::CsgOp;
use frep::LeafView;
use render::bsdf::CoatTable;
use render::integrator::{
    Accumulator, IntegratorKind, RayCounts, RenderOptions, ShadedDraw, ShadedVertex,
};
use render::light::TrainedSelection;
use render::scene::Scene;
use render::{RenderState, RenderStats, StateHeader, Technique};
use scene::{CameraKind, LightKind, MaterialData, SceneData, TextureData, TextureSpace};
use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use wgpu::util::DeviceExt;

/// The WGSL of the three kernels (without the helpers they include), by stage: the
/// bindings and record layout, random numbers and frames, shapes, CSG, the scene query
/// and normals, lights and pdfs, the trace kernel, the shade and prepare kernels.
pub const DIRECT_WGSL: &str = concat!(
    include_str!("shaders/direct_bindings.wgsl"),
    "\n",
    include_str!("shaders/direct_sampling.wgsl"),
    "\n",
    include_str!("shaders/direct_shapes.wgsl"),
    "\n",
    include_str!("shaders/direct_csg.wgsl"),
    "\n",
    include_str!("shaders/direct_scene.wgsl"),
    "\n",
    include_str!("shaders/direct_lights.wgsl"),
    "\n",
    include_str!("shaders/direct_trace.wgsl"),
    "\n",
    include_str!("shaders/direct_shade.wgsl"),
);

/// At most this many draws (slots × draws per slot) per wave: 40 MiB of draw records.
pub const WAVE_DRAWS: u32 = 1 << 19;

/// Techniques the kernels can hold.
pub const MAX_GPU_TECHNIQUES: usize = 8;

/// Expression solids a scene may hold on the GPU (their tapes share one interpreter,
/// GPU.md §6.2).
pub const MAX_GPU_TAPES: usize = 16;

/// The deepest `path` the GPU renders (a uniform block per depth and pass).
pub const MAX_GPU_DEPTH: u32 = 16;

/// One object: a leaf or an intersection of plain-quadric leaves (the WGSL `GpuShape`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuShape {
    /// 0: one leaf; 1: an intersection of `count` plain-quadric leaves.
    pub kind: u32,
    /// The first leaf (`GpuObject`).
    pub first: u32,
    /// Leaves.
    pub count: u32,
    /// The material.
    pub material: u32,
    /// Bounds minimum, rounded down (w unused).
    pub lo: [f32; 4],
    /// Bounds maximum, rounded up (w unused).
    pub hi: [f32; 4],
}

/// A material: its BSDF with constant colours, and a point-space checker in place of
/// `bsdf.rgb` where `tex_kind` is 1 (`a.xyz`, `b.xyz`, the scale in `a.w`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    /// The BSDF.
    pub bsdf: GpuBsdf,
    /// 0 constant, 1 point checker.
    pub tex_kind: u32,
    /// Padding.
    pub pad: [u32; 3],
    /// Even cells' colour and the scale.
    pub a: [f32; 4],
    /// Odd cells' colour.
    pub b: [f32; 4],
}

/// The kernels' uniform block (the WGSL `Frame`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
struct Frame {
    width: u32,
    height: u32,
    pixels: u32,
    slots: u32,
    sample: u32,
    n_shapes: u32,
    seed_lo: u32,
    seed_hi: u32,
    n_tech: u32,
    n_draws: u32,
    n_lights: u32,
    power_off: u32,
    area_off: u32,
    flags: u32,
    mode: u32,
    zero: u32,
    depth: u32,
    max_depth: u32,
    rr_depth: u32,
    stride: u32,
    carry: u32,
    n_delta: u32,
    per_slot: u32,
    spatial_off: u32,
    eye: [f32; 4],
    right: [f32; 4],
    up: [f32; 4],
    forward: [f32; 4],
    tech: [[u32; 4]; 2],
    count: [[u32; 4]; 2],
    env: GpuEnv,
    /// The trained selection's table in `tables` (u32::MAX: none), cells per axis, MIS
    /// lights covered.
    trained: [u32; 4],
    /// Where the live and continuation queues' entries start in `stats` (words), and
    /// the first pixel of the wave's band.
    wave: [u32; 4],
}

const _: () = assert!(size_of::<GpuShape>() == 48);
const _: () = assert!(size_of::<GpuMaterial>() == 112);
const _: () = assert!(size_of::<Frame>() == 352);

/// The scene and options as the kernels read them.
#[derive(Clone, Debug, Default)]
pub struct DirectScene {
    /// Objects.
    pub shapes: Vec<GpuShape>,
    /// Leaves (perturbed or plain quadrics), as the perturbed scan reads them.
    pub leaves: Vec<GpuObject>,
    /// Base quadrics.
    pub quadrics: Vec<GpuQuadric>,
    /// Perturbations.
    pub perturbations: Vec<GpuPerturbation>,
    /// Support BVH nodes (escape layout).
    pub nodes: Vec<GpuBvhNode>,
    /// Support item boxes.
    pub items: Vec<GpuItemBox>,
    /// Materials.
    pub materials: Vec<GpuMaterial>,
    /// Area lights.
    pub lights: Vec<GpuAreaLight>,
    /// The scene's expression solids (at most [`MAX_GPU_TAPES`]: their tapes are
    /// compiled into the kernels' source, GPU.md §6.2), in the order of their leaves'
    /// `first_op`.
    pub tapes: Vec<TapeSolid>,
    /// CSG nodes of kind-2 shapes, post-order: (op, leaf or part count, 0, 0).
    pub csg: Vec<[u32; 4]>,
    /// Light-selection tables (by power at 0, by area at `frame.area_off`) and plastic
    /// coat tables.
    pub tables: Vec<f32>,
    frame: Frame,
}

/// The most CSG nodes one object may have on the GPU (after shared parts are copied).
const MAX_CSG_NODES: u32 = 256;

fn unsupported(what: impl Into<String>) -> GpuError {
    GpuError::Unsupported(what.into())
}

fn f3(v: [f64; 3]) -> [f32; 3] {
    [v[0] as f32, v[1] as f32, v[2] as f32]
}

impl DirectScene {
    /// Packs `data` for a `direct` render with `o` (and the light selection trained
    /// for it, if any), or says what the GPU cannot do.
    pub fn new(
        data: &SceneData,
        o: &RenderOptions,
        trained: Option<&TrainedSelection>,
    ) -> Result<Self, GpuError> {
        let mut s = DirectScene::default();
        s.pack_lights(data)?;
        s.pack_materials(data)?;
        for obj in &data.objects {
            s.pack_object(data, obj)?;
        }
        s.pack_frame(data, o)?;
        s.pack_trained(trained);
        Ok(s)
    }

    fn pack_leaf(&mut self, view: &frep::PerturbedView, material: u32) -> u32 {
        let p = PerturbedPack::new(view);
        let mut ob = p.object;
        ob.kind = u32::from(!view.perturbations.is_empty());
        ob.material = material;
        ob.first_node = self.nodes.len() as u32;
        ob.first_item = self.items.len() as u32;
        ob.first_op = self.quadrics.len() as u32;
        ob.op_count = self.perturbations.len() as u32;
        self.quadrics.extend(p.quadrics);
        self.perturbations.extend(p.perturbations);
        self.nodes.extend(p.nodes);
        self.items.extend(p.items);
        self.leaves.push(ob);
        self.leaves.len() as u32 - 1
    }

    fn pack_expr(
        &mut self,
        flat: &frep::Flat,
        leaf: usize,
        view: &frep::ExprView,
        name: &str,
        material: u32,
    ) -> Result<(), GpuError> {
        if self.tapes.len() >= MAX_GPU_TAPES {
            return Err(unsupported(format!(
                "object '{name}': more than {MAX_GPU_TAPES} expression solids"
            )));
        }
        let frep::Leaf::Expr {
            code, registers, ..
        } = flat.leaves[leaf]
        else {
            unreachable!("an expression leaf");
        };
        let words = flat.bytecode[code.range()].to_vec();
        let bytecode = frep::Bytecode::from_words(words, registers as usize)
            .map_err(|e| unsupported(format!("object '{name}': {e}")))?;
        let tape =
            GpuTape::new(&bytecode).map_err(|e| unsupported(format!("object '{name}': {e}")))?;
        if !view.bounds.is_finite() {
            return Err(unsupported(format!(
                "object '{name}' is an unbounded expression"
            )));
        }
        let solid = TapeSolid::new(tape, &view.bounds);
        let (lo, hi) = (solid.lo, solid.hi);
        self.tapes.push(solid);
        self.leaves.push(GpuObject {
            kind: 2,
            material,
            lo,
            hi,
            // Which of the scene's tapes (`use_tape`).
            first_op: self.tapes.len() as u32 - 1,
            ..GpuObject::default()
        });
        Ok(())
    }

    /// The WGSL that defines `use_tape`, `trace_tape` and `tape_normal`: the tape
    /// tracer with this scene's tapes, or stubs. The tracer's helpers share names with
    /// the perturbed scan's: the duplicates go, and its ε becomes `TAPE_EPS`.
    fn tape_wgsl(&self) -> String {
        if self.tapes.is_empty() {
            return "struct TraceResult { status: u32, t: f32 }
fn use_tape(k: u32) {}
fn trace_tape(o: vec3<f32>, d: vec3<f32>, t_min: f32, t_max: f32) -> TraceResult { return TraceResult(0u, 0.0); }
fn tape_normal(p: vec3<f32>) -> vec3<f32> { return vec3<f32>(0.0, 0.0, 1.0); }
"
            .into();
        }
        let src = TapeSolid::scene_wgsl(&self.tapes)
            .replacen(FLOAT_WGSL, "", 1)
            .replacen("var<private> loops: u32;", "", 1)
            .replacen(
                "const MIN_POS: f32 = 0x1p-126f; // f32::MIN_POSITIVE",
                "",
                1,
            );
        let word = |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric() || c == '_');
        let mut out = String::with_capacity(src.len());
        let mut rest = src.as_str();
        while let Some(i) = rest.find("EPS") {
            let whole = !word(rest[..i].chars().next_back()) && !word(rest[i + 3..].chars().next());
            out.push_str(&rest[..i]);
            out.push_str(if whole { "TAPE_EPS" } else { "EPS" });
            rest = &rest[i + 3..];
        }
        out.push_str(rest);
        out + "
// The outward normal −∇F/|∇F| by central differences of 10³ ε (the tape has no
// derivative code at points; F is smooth where a ray meets it).
fn tape_normal(p: vec3<f32>) -> vec3<f32> {
    let h = 500.0 * TAPE_EPS;
    var v: array<f32, 6>;
    for (var k = 0u; k < 6u; k++) {
        loops++;
        var q = p;
        q[k / 2u] += select(-h, h, (k & 1u) == 0u);
        v[k] = eval_point(q);
    }
    let g = vec3<f32>(v[0] - v[1], v[2] - v[3], v[4] - v[5]);
    let l = length(g);
    if (l > 0.0 && is_finite(l)) { return -g / l; }
    return vec3<f32>(0.0, 0.0, 1.0);
}
"
    }

    fn pack_object(&mut self, data: &SceneData, obj: &scene::ObjectData) -> Result<(), GpuError> {
        let flat = data.solids.solid(obj.solid).flat();
        let root = flat.nodes.len() - 1;
        let node = &flat.nodes[root];
        let material = obj.material.0;
        let first = self.leaves.len() as u32;
        let plain = |k: u32| -> Option<frep::PerturbedView> {
            let n = &flat.nodes[k as usize];
            match (n.op, flat.leaf(n.operands.first as usize)) {
                (CsgOp::Leaf, LeafView::Perturbed(v)) if v.perturbations.is_empty() => Some(v),
                _ => None,
            }
        };
        // (kind, first leaf or CSG node, leaves or nodes)
        let (kind, first, count) = match node.op {
            CsgOp::Leaf => match flat.leaf(node.operands.first as usize) {
                LeafView::Perturbed(v) => {
                    self.pack_leaf(&v, material);
                    (0, first, 1)
                }
                LeafView::Expr(v) => {
                    self.pack_expr(flat, node.operands.first as usize, &v, &obj.name, material)?;
                    (0, first, 1)
                }
            },
            CsgOp::Intersection if flat.parts(root).iter().all(|&k| plain(k).is_some()) => {
                for &k in flat.parts(root) {
                    let v = plain(k).expect("checked");
                    self.pack_leaf(&v, material);
                }
                (1, first, flat.parts(root).len() as u32)
            }
            _ => {
                // Any other CSG tree: its nodes in post-order from the root, so that
                // each op's parts are the last lists on the kernel's stack (a part
                // shared by two nodes is emitted under each). Plain quadrics give their
                // ends in closed form, perturbed and expression parts by repeated
                // crossing searches (`general_ends` in the kernel).
                let first_node = self.csg.len() as u32;
                let mut todo = vec![(root as u32, false)];
                while let Some((i, expanded)) = todo.pop() {
                    let n = &flat.nodes[i as usize];
                    if n.op == CsgOp::Leaf {
                        let k = n.operands.first as usize;
                        let leaf = match flat.leaf(k) {
                            LeafView::Perturbed(v) => self.pack_leaf(&v, material),
                            LeafView::Expr(v) => {
                                self.pack_expr(flat, k, &v, &obj.name, material)?;
                                self.leaves.len() as u32 - 1
                            }
                        };
                        self.csg.push([0, leaf, 0, 0]);
                    } else if expanded {
                        let op = match n.op {
                            CsgOp::Union => 1,
                            CsgOp::Intersection => 2,
                            _ => 3,
                        };
                        self.csg
                            .push([op, flat.parts(i as usize).len() as u32, 0, 0]);
                    } else {
                        todo.push((i, true));
                        todo.extend(flat.parts(i as usize).iter().rev().map(|&k| (k, false)));
                    }
                    if self.csg.len() as u32 - first_node > MAX_CSG_NODES {
                        break;
                    }
                }
                let count = self.csg.len() as u32 - first_node;
                if count > MAX_CSG_NODES {
                    return Err(unsupported(format!(
                        "object '{}' has more than {MAX_CSG_NODES} CSG nodes",
                        obj.name
                    )));
                }
                (2, first_node, count)
            }
        };
        let (lo, hi) = outward(&node.bounds);
        self.shapes.push(GpuShape {
            kind,
            first,
            count,
            material,
            lo: [lo[0], lo[1], lo[2], 0.0],
            hi: [hi[0], hi[1], hi[2], 0.0],
        });
        Ok(())
    }

    fn pack_materials(&mut self, data: &SceneData) -> Result<(), GpuError> {
        for (m, name) in data.materials.iter().zip(&data.material_names) {
            let constant = |id: scene::TextureId| -> Result<[f64; 3], GpuError> {
                match &data.textures[id.index()] {
                    TextureData::Constant { rgb } => Ok(*rgb),
                    _ => Err(unsupported(format!(
                        "material '{name}' has a textured parameter other than its colour"
                    ))),
                }
            };
            // The colour slot may be a point-space checker.
            let (colour, clamp) = match m {
                MaterialData::Diffuse { reflectance } => (Some(*reflectance), false),
                MaterialData::Plastic { diffuse, .. } => (Some(*diffuse), true),
                _ => (None, false),
            };
            let mut tex = (0, [0.0; 4], [0.0; 4]);
            if let Some(id) = colour {
                match &data.textures[id.index()] {
                    TextureData::Constant { .. } => {}
                    TextureData::Checker {
                        a,
                        b,
                        scale,
                        space: TextureSpace::Point,
                    } => {
                        let c = |v: [f64; 3]| {
                            if clamp {
                                v.map(|x| x.clamp(0.0, 1.0))
                            } else {
                                v
                            }
                        };
                        tex = (1, f4(c(*a), *scale), f4(c(*b), 0.0));
                    }
                    TextureData::Checker { .. } => {
                        return Err(unsupported(format!(
                            "material '{name}' has a uv-space checker"
                        )))
                    }
                }
            }
            let rgb = |id: scene::TextureId| match &data.textures[id.index()] {
                TextureData::Constant { rgb } => *rgb,
                // The checker's colours are written per hit; any value serves here.
                TextureData::Checker { a, .. } => *a,
            };
            let bsdf = match *m {
                MaterialData::Diffuse { reflectance } => GpuBsdf::diffuse(rgb(reflectance)),
                MaterialData::Conductor { eta, k, roughness } => {
                    GpuBsdf::conductor(constant(eta)?, constant(k)?, roughness)
                }
                MaterialData::Dielectric { eta, roughness } => GpuBsdf::dielectric(eta, roughness),
                MaterialData::Plastic {
                    diffuse,
                    eta,
                    roughness,
                } => {
                    let coat = CoatTable::new(eta, roughness);
                    let at = self.tables.len() as u32;
                    self.tables.extend(
                        (0..COAT_TABLE_LEN).map(|j| coat.albedo((j as f64 / 64.0).powi(2)) as f32),
                    );
                    GpuBsdf::plastic(rgb(diffuse), eta, roughness, coat.r_int, at)
                }
            };
            self.materials.push(GpuMaterial {
                bsdf,
                tex_kind: tex.0,
                pad: [0; 3],
                a: tex.1,
                b: tex.2,
            });
        }
        Ok(())
    }

    fn pack_lights(&mut self, data: &SceneData) -> Result<(), GpuError> {
        for l in &data.lights.area {
            let (rad, area) = (f3(l.emission), l.area as f32);
            self.lights.push(match l.kind {
                LightKind::Sphere => GpuAreaLight::sphere(f3(l.p0), l.radius as f32, rad, area),
                LightKind::Rect => {
                    GpuAreaLight::rect(f3(l.p0), f3(l.e1), f3(l.e2), l.two_sided, rad, area)
                }
                LightKind::Disk => {
                    GpuAreaLight::disk(f3(l.p0), f3(l.e1), l.radius as f32, l.two_sided, rad, area)
                }
                LightKind::Point | LightKind::Spot => unreachable!("area lights only"),
            });
        }
        // Point and spot lights after them (shape 3 and 4; the kernel's shade_delta).
        for l in &data.lights.delta {
            let spot = l.kind == LightKind::Spot;
            self.lights.push(GpuAreaLight {
                shape: if spot { 4 } else { 3 },
                two_sided: 0,
                pad: [0; 2],
                radiance: f4(l.emission, 0.0),
                p0: f4(l.p0, 0.0),
                e1: f4(l.e1, l.cos_falloff_start),
                e2: [l.cos_falloff_end as f32, 0.0, 0.0, 0.0],
            });
        }
        self.frame.n_delta = data.lights.delta.len() as u32;
        Ok(())
    }

    /// The trained selection's grid (low corner, cells per unit) and pmfs after the
    /// other tables.
    fn pack_trained(&mut self, trained: Option<&TrainedSelection>) {
        self.frame.trained = [u32::MAX, 0, 0, 0];
        if let Some(t) = trained {
            let (lo, scale, res) = t.grid();
            self.frame.trained = [self.tables.len() as u32, res as u32, t.lights() as u32, 0];
            self.tables.extend(lo.as_vec3().to_array());
            self.tables.extend(scale.as_vec3().to_array());
            self.tables.extend(t.table().iter().map(|&p| p as f32));
        }
    }

    fn pack_frame(&mut self, data: &SceneData, o: &RenderOptions) -> Result<(), GpuError> {
        let f = &mut self.frame;
        f.power_off = self.tables.len() as u32;
        if let Some(d) = &data.lights.by_power {
            self.tables.extend(light::table(d));
        }
        f.area_off = self.tables.len() as u32;
        if let Some(d) = &data.lights.by_area {
            self.tables.extend(light::table(d));
        }
        // The spatial selection's importance records, then the environment's map and
        // tables after the selection tables (`sel_buf`).
        f.spatial_off = self.tables.len() as u32;
        for l in &data.lights.area {
            if let Some(a) = render::light::AreaLight::from_data(l) {
                self.tables.extend(light::importance_record(&a));
            }
        }
        f.env = GpuEnv::pack(data, &mut self.tables);
        if self.tables.is_empty() {
            self.tables.push(0.0);
        }
        f.n_lights = data.lights.area.len() as u32;
        // The MIS lights: the area lights, then the environment.
        let n_mis = data.lights.area.len() + usize::from(data.environment.is_some());
        f.n_shapes = self.shapes.len() as u32;
        let c = &data.camera;
        let (w, h) = (c.width, c.height);
        (f.width, f.height, f.pixels) = (w, h, w * h);
        f.seed_lo = o.seed as u32;
        f.seed_hi = (o.seed >> 32) as u32;
        // render::camera::Camera::look_at / orthographic, in f64, then rounded.
        let v = |a: [f64; 3]| glam::DVec3::from_array(a);
        let (eye, target, up) = (v(c.eye), v(c.target), v(c.up));
        let forward = (target - eye).normalize();
        let right = forward.cross(up).normalize();
        let up = right.cross(forward);
        let scale = match c.kind {
            CameraKind::Perspective => (c.fov.to_radians() / 2.0).tan(),
            CameraKind::Orthographic => 0.5 * c.scale.unwrap_or(1.0),
        };
        f.eye = f4(eye.to_array(), scale);
        f.right = f4(right.to_array(), f64::from(w) / f64::from(h));
        f.up = f4(up.to_array(), 0.0);
        f.forward = f4(forward.to_array(), 0.0);
        f.flags = u32::from(o.hide_emitters)
            | (u32::from(o.pixel_center) << 1)
            | (u32::from(c.kind == CameraKind::Orthographic) << 2)
            | (u32::from(o.per_light > 0) << 3)
            | (u32::from(
                !o.aovs.is_empty()
                    || !matches!(o.integrator, IntegratorKind::Direct | IntegratorKind::Path),
            ) << 4);
        if o.techniques.len() > MAX_GPU_TECHNIQUES {
            return Err(unsupported(format!(
                "{} techniques (at most {MAX_GPU_TECHNIQUES})",
                o.techniques.len()
            )));
        }
        f.max_depth = match o.integrator {
            IntegratorKind::Path => o.max_depth,
            _ => 1,
        };
        if f.max_depth > MAX_GPU_DEPTH {
            return Err(unsupported(format!(
                "max depth {} (at most {MAX_GPU_DEPTH})",
                f.max_depth
            )));
        }
        f.rr_depth = o.rr_depth;
        f.n_tech = o.techniques.len() as u32;
        for (k, &(t, n)) in o.techniques.iter().enumerate() {
            let code = match t {
                Technique::Bsdf => 0,
                Technique::LightPower => 1,
                Technique::LightUniform => 2,
                Technique::LightArea => 3,
                Technique::Light(l) if l < n_mis => 4 | (l as u32) << 8,
                Technique::Environment => 5,
                Technique::LightSpatial => 6,
                Technique::LightTrained => 7,
                t => return Err(unsupported(format!("technique {}", t.name()))),
            };
            f.tech[k / 4][k % 4] = code;
            f.count[k / 4][k % 4] = n;
            f.n_draws += n;
        }
        // render::integrator::dims: the vertex stride, and the draw that extends a path
        // (the BSDF technique's first, else the extra draw).
        f.stride = (3 * (f.n_draws + 1) + 1).div_ceil(4) * 4;
        f.per_slot = f.n_draws + 1 + f.n_delta;
        f.carry = f.n_draws;
        let mut slot = 0;
        for &(t, n) in &o.techniques {
            if t == Technique::Bsdf {
                f.carry = slot;
            }
            slot += n;
        }
        Ok(())
    }
}

/// Compiled kernels by the tape part of their source, kept by [`Gpu`].
pub(crate) type PipelineCache = std::sync::Mutex<Vec<(String, std::sync::Arc<Pipelines>)>>;

/// The compiled kernels, kept by [`Gpu`] for every later render.
pub(crate) struct Pipelines {
    trace: wgpu::ComputePipeline,
    shade: wgpu::ComputePipeline,
    prepare: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

fn pipelines(gpu: &Gpu, tape_wgsl: &str) -> Result<Pipelines, GpuError> {
    let d = &gpu.device;
    let need = 14u32;
    let have = d.limits().max_storage_buffers_per_shader_stage;
    if have < need {
        return Err(GpuError::Limit {
            limit: "max_storage_buffers_per_shader_stage",
            have: u64::from(have),
            need: u64::from(need),
        });
    }
    let source = [
        FLOAT_WGSL,
        LAYOUT_WGSL,
        PERTURBED_WGSL,
        QUADRIC_WGSL,
        PHILOX_WGSL,
        BSDF_STRUCT_WGSL,
        BSDF_WGSL,
        GPU_AREA_LIGHT_WGSL,
        LIGHT_WGSL,
        ENV_WGSL,
        tape_wgsl,
        DIRECT_WGSL,
    ]
    .join("\n");
    let scope = d.push_error_scope(wgpu::ErrorFilter::Validation);
    let entry = |binding: u32, ty: wgpu::BufferBindingType| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let mut entries = vec![entry(0, wgpu::BufferBindingType::Uniform)];
    for b in 1..=9 {
        entries.push(entry(
            b,
            wgpu::BufferBindingType::Storage { read_only: true },
        ));
    }
    for b in 10..=12 {
        entries.push(entry(
            b,
            wgpu::BufferBindingType::Storage { read_only: false },
        ));
    }
    for b in 13..=14 {
        entries.push(entry(
            b,
            wgpu::BufferBindingType::Storage { read_only: true },
        ));
    }
    let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("direct"),
        entries: &entries,
    });
    let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("direct"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    // SAFETY: every index of the kernels is bounded by construction (fixed arrays with
    // guarded counters, buffers sized from the packed scene and the wave) and every loop
    // is bounded; GPU.md §3.4 measured naga's checks at up to 20× on lavapipe.
    let module = unsafe {
        d.create_shader_module_trusted(
            wgpu::ShaderModuleDescriptor {
                label: Some("direct"),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            },
            wgpu::ShaderRuntimeChecks::unchecked(),
        )
    };
    let make = |entry: &str| {
        d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&pl),
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        })
    };
    let (trace, shade, prepare) = (make("trace"), make("shade"), make("prepare"));
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(GpuError::Run(format!("direct kernels: {e}")));
    }
    Ok(Pipelines {
        trace,
        shade,
        prepare,
        layout,
    })
}

/// The kernels for `pack`'s tape, compiled on first use and kept by `gpu`.
fn kernels(gpu: &Gpu, pack: &DirectScene) -> Result<std::sync::Arc<Pipelines>, GpuError> {
    let tape_wgsl = pack.tape_wgsl();
    let mut cache = gpu
        .direct
        .lock()
        .map_err(|e| GpuError::Run(e.to_string()))?;
    if let Some((_, p)) = cache.iter().find(|(src, _)| *src == tape_wgsl) {
        return Ok(p.clone());
    }
    let p = std::sync::Arc::new(pipelines(gpu, &tape_wgsl)?);
    cache.push((tape_wgsl, p.clone()));
    Ok(p)
}

/// The scene's read-only buffers in binding order (1–9, then 14–15: CSG and tape).
fn scene_buffers(gpu: &Gpu, pack: &DirectScene) -> Result<Vec<wgpu::Buffer>, GpuError> {
    let tape_words = TapeSolid::scene_words(&pack.tapes);
    Ok(vec![
        storage(gpu, "shapes", bytemuck::cast_slice(&pack.shapes))?,
        storage(gpu, "objects", bytemuck::cast_slice(&pack.leaves))?,
        storage(gpu, "quadrics", bytemuck::cast_slice(&pack.quadrics))?,
        storage(
            gpu,
            "perturbations",
            bytemuck::cast_slice(&pack.perturbations),
        )?,
        storage(gpu, "nodes", bytemuck::cast_slice(&pack.nodes))?,
        storage(gpu, "items", bytemuck::cast_slice(&pack.items))?,
        storage(gpu, "materials", bytemuck::cast_slice(&pack.materials))?,
        storage(gpu, "lights", bytemuck::cast_slice(&pack.lights))?,
        storage(gpu, "tables", bytemuck::cast_slice(&pack.tables))?,
        storage(gpu, "csg", bytemuck::cast_slice(&pack.csg))?,
        storage(gpu, "tape", bytemuck::cast_slice(&tape_words))?,
    ])
}

/// The bind group of one pass: its frame block, the scene, and the wave's hits, draws
/// and loop counters.
fn bind(
    gpu: &Gpu,
    p: &Pipelines,
    scene: &[wgpu::Buffer],
    frame: &wgpu::Buffer,
    wave: [&wgpu::Buffer; 3],
) -> wgpu::BindGroup {
    let all = std::iter::once(frame)
        .chain(&scene[..9])
        .chain(wave)
        .chain(&scene[9..]);
    crate::bind_buffers(gpu, "direct", &p.layout, all)
}

/// One ray of [`probe`]: what the kernels' nearest-hit query found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Probe {
    /// 0 miss, 1 hit, 2 overflow (a fixed capacity ran out: the renderer hands such
    /// samples to the CPU).
    pub status: u32,
    /// The ray parameter of the hit.
    pub t: f32,
    /// The outward unit normal there.
    pub normal: [f32; 3],
    /// Loop iterations the query took (GPU.md §3.1).
    pub loops: u32,
}

/// The nearest object hit of each ray `(origin, direction)` against the objects of
/// `data`, by the render kernels' own query (a ray batch, GPU.md §9).
pub fn probe(
    gpu: &Gpu,
    data: &SceneData,
    rays: &[([f32; 3], [f32; 3])],
) -> Result<Vec<Probe>, GpuError> {
    let mut pack = DirectScene::new(data, &RenderOptions::default(), None)?;
    let p = kernels(gpu, &pack)?;
    let scene = scene_buffers(gpu, &pack)?;
    let n = rays.len().max(1) as u32;
    pack.frame.slots = n;
    pack.frame.mode = 3;
    let d = &gpu.device;
    let mut input = vec![[0f32; 4]; n as usize * DRAW_WORDS / 4];
    for (i, (o, dir)) in rays.iter().enumerate() {
        input[i * DRAW_WORDS / 4] = [o[0], o[1], o[2], 0.0];
        input[i * DRAW_WORDS / 4 + 1] = [dir[0], dir[1], dir[2], 0.0];
    }
    let draws = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("rays"),
        contents: bytemuck::cast_slice(&input),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let bytes = u64::from(n) * HIT_WORDS as u64 * 4;
    gpu.check_binding(bytes)?;
    let hits = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("probe hits"),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let loops = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("stats"),
        size: 16,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let readback = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("probe readback"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let frame = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("frame"),
        contents: bytemuck::bytes_of(&pack.frame),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let group = bind(gpu, &p, &scene, &frame, [&hits, &draws, &loops]);
    let mut enc = d.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(&p.trace);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(n.div_ceil(64), 1, 1);
    }
    enc.copy_buffer_to_buffer(&hits, 0, &readback, 0, bytes);
    gpu.queue.submit([enc.finish()]);
    let out = read_back(gpu, &readback, bytes)?;
    let v: &[f32] = bytemuck::cast_slice(&out);
    Ok(rays
        .iter()
        .enumerate()
        .map(|(i, _)| {
            let h = &v[i * HIT_WORDS..];
            Probe {
                status: h[2] as u32,
                t: h[0],
                normal: [h[4], h[5], h[6]],
                loops: h[3] as u32,
            }
        })
        .collect())
}

fn storage(gpu: &Gpu, label: &str, bytes: &[u8]) -> Result<wgpu::Buffer, GpuError> {
    gpu.check_binding(bytes.len() as u64)?;
    // Empty bindings are invalid: give an empty pool one zeroed 16-byte element.
    let data: &[u8] = if bytes.is_empty() { &[0; 128] } else { bytes };
    Ok(gpu
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: data,
            usage: wgpu::BufferUsages::STORAGE,
        }))
}

/// Adds one slot's hit record `hw` and its draw records (`vertex(depth)`: the
/// `per_slot` records of that depth) to its pixel's record `rec` through the CPU's
/// [`Accumulator`] (the render's sums on the CPU), and counts its rays. `pdfs` is
/// scratch of `depths · n_draws · T` words. The slot must not have overflowed.
#[allow(clippy::too_many_arguments)]
pub fn add_slot<'v>(
    acc: &Accumulator,
    rec: &mut [f64],
    index: u32,
    hw: &[f32],
    vertex: &dyn Fn(u32) -> &'v [f32],
    n_draws: u32,
    depths: u32,
    pdfs: &mut [f64],
    rays: &mut RayCounts,
) {
    let t_count = acc.techniques().len();
    rays.camera += 1;
    // The first hit's depth, normal and albedo (words 8 and 9).
    let aovs = [hw[35], hw[32], hw[33], hw[34], hw[36], hw[37], hw[38]].map(f64::from);
    if acc.aov_integrator() {
        acc.add_aov_sample(rec, index, &aovs);
        return;
    }
    let outside = [hw[12], hw[13], hw[14]].map(f64::from);
    // Vertices shaded: draw 0 of each has a status until the path ended.
    let shaded = (0..depths)
        .take_while(|&k| n_draws > 0 && vertex(k)[7] != 0.0)
        .count();
    for k in 0..shaded {
        for (j, d) in vertex(k as u32).chunks_exact(DRAW_WORDS).enumerate() {
            match d[7] {
                4.0 | 5.0 => rays.shadow += 1,
                6.0 => rays.secondary += 1,
                _ => {}
            }
            if j < n_draws as usize {
                let at = (k * n_draws as usize + j) * t_count;
                for (t, p) in pdfs[at..at + t_count].iter_mut().enumerate() {
                    *p = f64::from(d[12 + t]);
                }
            }
        }
    }
    let mut vertices: Vec<Vec<ShadedDraw>> = Vec::with_capacity(shaded);
    let mut vertex_outside = vec![[0.0f64; 3]; shaded];
    let mut mis = vec![true; shaded];
    for k in 0..shaded {
        let records = vertex(k as u32);
        // Word 11 of a record: 1 a delta-lobe draw (outside MIS), 2 a purely
        // specular vertex (no MIS at all); in per-light mode, 4 × (1 + the MIS
        // light the draw's ray reaches) added.
        let flags = |d: &[f32]| d[11] as u32;
        mis[k] = flags(records) & 2 == 0;
        let sum = &mut vertex_outside[k];
        for (j, d) in records.chunks_exact(DRAW_WORDS).enumerate() {
            // Outside MIS: point and spot lights (j > Σ n_k) and delta lobes,
            // where their light arrived.
            let outside = j > n_draws as usize || flags(d) & 1 != 0;
            if outside && (d[7] == 4.0 || d[7] == 6.0) {
                for c in 0..3 {
                    sum[c] += f64::from(d[8 + c]);
                }
            }
        }
        let draws = records
            .chunks_exact(DRAW_WORDS)
            .take(if mis[k] { n_draws as usize } else { 0 })
            .enumerate()
            .map(|(j, d)| {
                if d[7] == 1.0 || flags(d) & 1 != 0 {
                    return ShadedDraw::Failed;
                }
                let f = if d[7] == 4.0 || d[7] == 6.0 {
                    [d[8], d[9], d[10]].map(f64::from)
                } else {
                    [0.0; 3]
                };
                let at = (k * n_draws as usize + j) * t_count;
                ShadedDraw::Sample {
                    f,
                    pdfs: &pdfs[at..at + t_count],
                    light: (flags(d) >> 2).checked_sub(1).map(|l| l as usize),
                }
            })
            .collect();
        vertices.push(draws);
    }
    let refs: Vec<ShadedVertex> = vertices
        .iter()
        .zip(&vertex_outside)
        .zip(&mis)
        .map(|((draws, &outside), &mis)| ShadedVertex {
            outside,
            draws,
            mis,
        })
        .collect();
    acc.add(rec, index, outside, &refs, &aovs);
}

/// Renders samples `samples` of every pixel of `scene` (resolved as `data`) with the
/// `direct` integrator on `gpu`, into a [`RenderState`] that merges with CPU ones.
/// `progress(done, total)` is called after each wave; `stop` is read between waves (a
/// stopped render keeps its whole waves and is marked partial). Errors, before any
/// work, on what the GPU back end does not implement ([`GpuError::Unsupported`]).
pub fn render_range(
    gpu: &Gpu,
    data: &SceneData,
    scene: &Scene,
    options: &RenderOptions,
    samples: Range<u32>,
    stop: &AtomicBool,
    progress: &dyn Fn(u64, u64),
) -> Result<(RenderState, RenderStats, GpuStats), GpuError> {
    let how = WaveOptions::for_device(gpu);
    render_range_with(gpu, data, scene, options, samples, stop, progress, &how)
}

/// How [`render_range_with`] runs its waves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WaveOptions {
    /// Where the per-pixel sums are kept: on the CPU, or on the GPU in f64 (where the
    /// device has it, else double-float) or double-float. The GPU falls back to the
    /// CPU's sums for records whose terms pass the loop budget (bands shrink so that
    /// their sums fit one binding);
    /// [`GpuStats::sums`] says where they were kept.
    pub sums: SumsOn,
    /// The most pixels a band covers (the image is rendered in bands of consecutive
    /// pixels, each through all its samples); None: as many as a wave of one sample
    /// index may hold ([`WAVE_DRAWS`] draws).
    pub band_pixels: Option<u32>,
}

impl WaveOptions {
    /// The device's choice ([`GpuOptions`](crate::GpuOptions)' `f64` and `sums`),
    /// bands as large as a wave allows.
    pub fn for_device(gpu: &Gpu) -> Self {
        let sums = match (gpu.info().sums, gpu.info().f64) {
            (false, _) => SumsOn::Cpu,
            (true, true) => SumsOn::GpuF64,
            (true, false) => SumsOn::GpuDoubleFloat,
        };
        Self {
            sums,
            band_pixels: None,
        }
    }
}

/// [`render_range`] with the waves run as `how` says.
#[allow(clippy::too_many_arguments)]
pub fn render_range_with(
    gpu: &Gpu,
    data: &SceneData,
    scene: &Scene,
    options: &RenderOptions,
    samples: Range<u32>,
    stop: &AtomicBool,
    progress: &dyn Fn(u64, u64),
    how: &WaveOptions,
) -> Result<(RenderState, RenderStats, GpuStats), GpuError> {
    // A device error (validation, memory) becomes this render's error, not a panic of
    // wgpu's default handler.
    let invalid = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let memory = gpu.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let out = render_waves(gpu, data, scene, options, samples, stop, progress, how);
    let errors = [memory.pop(), invalid.pop()].map(pollster::block_on);
    match errors.into_iter().flatten().next() {
        Some(e) => Err(GpuError::Run(e.to_string())),
        None => out,
    }
}

#[allow(clippy::too_many_arguments)]
fn render_waves(
    gpu: &Gpu,
    data: &SceneData,
    scene: &Scene,
    options: &RenderOptions,
    samples: Range<u32>,
    stop: &AtomicBool,
    progress: &dyn Fn(u64, u64),
    how: &WaveOptions,
) -> Result<(RenderState, RenderStats, GpuStats), GpuError> {
    let sums_on = how.sums;
    let o = RenderOptions {
        spp: samples.end.saturating_sub(samples.start),
        ..options.clone()
    };
    let acc = Accumulator::new(scene, &o).map_err(GpuError::Unsupported)?;
    let mut pack = DirectScene::new(data, &o, acc.trained())?;
    let started = Instant::now();
    let p = kernels(gpu, &pack)?;
    let mut stats = GpuStats::default();
    let (w, h) = (data.camera.width, data.camera.height);
    let header = StateHeader::new(w, h, &o);
    let mut state = RenderState::new(header, samples.clone())
        .map_err(|e| GpuError::Unsupported(e.to_string()))?;
    let pixels = w * h;
    let n_draws = pack.frame.n_draws;
    // Draw records per slot and depth: the techniques', the extra BSDF draw, and one per
    // point or spot light.
    let nd1 = pack.frame.per_slot;
    let depths = pack.frame.max_depth;
    let per_slot_draws = nd1 * depths.max(1);
    // The image in bands of consecutive pixels (raster order), each rendered through all
    // its samples before the next: the buffers hold one band's waves, whatever the
    // image's size.
    let stride = acc.stride();
    // Sums on the GPU: a band's (pixels × stride f64 words) within one binding.
    let linear = acc.linear().filter(|_| sums_on != SumsOn::Cpu);
    let sums_fit = if linear.is_some() {
        gpu.info().max_storage_binding / (stride as u64 * 8)
    } else {
        u64::MAX
    };
    let band = how
        .band_pixels
        .unwrap_or(u32::MAX)
        .min((WAVE_DRAWS / per_slot_draws).max(1))
        .min(sums_fit.min(u64::from(u32::MAX)) as u32)
        .clamp(1, pixels);
    let per_wave = (WAVE_DRAWS / (band * per_slot_draws)).max(1);
    let max_slots = u64::from(per_wave * band);
    let d = &gpu.device;
    let buffers = scene_buffers(gpu, &pack)?;
    let hit_bytes = max_slots * HIT_WORDS as u64 * 4;
    let draw_bytes = max_slots * u64::from(per_slot_draws) * DRAW_WORDS as u64 * 4;
    gpu.check_binding(draw_bytes)?;
    let rw = |label, size| {
        d.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    };
    let read = |label, size| {
        d.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    };
    let (hits, draws) = (rw("hits", hit_bytes), rw("draws", draw_bytes));
    // Loop maxima, the three queues' lengths and indirect arguments, then the shadow
    // queue's entries (a draw each), the live queue's and the continuation queue's (a
    // slot each).
    let live_at = 16 + max_slots * u64::from(nd1);
    let stats_bytes = (live_at + 2 * max_slots) * 4;
    pack.frame.wave = [live_at as u32, (live_at + max_slots) as u32, 0, 0];
    gpu.check_binding(stats_bytes)?;
    let loops = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("stats and queues"),
        size: stats_bytes,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    // The queued passes' indirect arguments (shadow, shade, continuation at 0, 16, 32),
    // copied out of `stats` (a buffer bound for storage cannot also drive a dispatch).
    let args = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("queued dispatches"),
        size: 48,
        usage: wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    // The per-pixel sums on the GPU where the record is a sum of per-sample terms and
    // fits; else every wave's hits and draws are read back and added by the CPU.
    let mut sums = match linear {
        Some(linear) => GpuSums::new(
            gpu,
            &linear,
            acc.kernel(),
            band,
            max_slots as u32,
            (n_draws, nd1, depths),
            &hits,
            &draws,
            sums_on == SumsOn::GpuF64,
        )?,
        None => None,
    };
    stats.sums = match &sums {
        None => SumsOn::Cpu,
        Some(s) if s.is_f64() => SumsOn::GpuF64,
        Some(_) => SumsOn::GpuDoubleFloat,
    };
    let per_wave = sums
        .as_ref()
        .map_or(per_wave, |s| per_wave.min(s.max_samples));
    let readbacks = sums.is_none().then(|| {
        (
            read("hits readback", hit_bytes),
            read("draws readback", draw_bytes),
        )
    });
    let loops_r = read("stats readback", 16);
    // One uniform block and bind group per (depth, pass mode): 0 camera, 1 shadow,
    // 2 continuation.
    let n_frames = 3 * depths.max(1) as usize;
    let frames: Vec<wgpu::Buffer> = (0..n_frames)
        .map(|_| {
            d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("frame"),
                size: size_of::<Frame>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        })
        .collect();
    let groups: Vec<wgpu::BindGroup> = frames
        .iter()
        .map(|f| bind(gpu, &p, &buffers, f, [&hits, &draws, &loops]))
        .collect();
    // Passes per wave: the camera trace, then per depth shade, shadow and (but the last)
    // the continuation. Stage k of each: 0 camera, 1 shade, 2 shadow, 3 continuation.
    let mut passes: Vec<(usize, u32, u32)> = vec![(0, 0, 0)];
    for depth in 0..depths {
        passes.push((1, depth, 0));
        passes.push((2, depth, 1));
        if depth + 1 < depths {
            passes.push((3, depth, 2));
        }
    }
    // Two timestamps per pass, and for the terms and sums passes.
    let n_queries = 2 * (passes.len() as u32 + 2);
    let timestamps = gpu.info().timestamps.then(|| {
        d.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("stages"),
            ty: wgpu::QueryType::Timestamp,
            count: n_queries,
        })
    });
    let ts_bytes = 8 * u64::from(n_queries);
    let ts_buf = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("timestamps"),
        size: ts_bytes,
        usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let ts_read = read("timestamps readback", ts_bytes);
    let period = f64::from(gpu.queue.get_timestamp_period());
    stats.stages.setup = started.elapsed();

    let t_count = acc.techniques().len();
    let total = u64::from(pixels) * u64::from(o.spp);
    let mut done = 0u64;
    let mut rays = RayCounts::default();
    let mut base = 0;
    while base < pixels {
        let band_len = band.min(pixels - base);
        pack.frame.pixels = band_len;
        pack.frame.wave[2] = base;
        let mut start = samples.start;
        while start < samples.end && !stop.load(Ordering::Relaxed) {
            let m = per_wave.min(samples.end - start);
            let slots = m * band_len;
            pack.frame.sample = start;
            pack.frame.slots = slots;
            for (k, f) in frames.iter().enumerate() {
                pack.frame.depth = (k / 3) as u32;
                pack.frame.mode = (k % 3) as u32;
                gpu.queue
                    .write_buffer(f, 0, bytemuck::bytes_of(&pack.frame));
            }
            let mut enc = d.create_command_encoder(&Default::default());
            // Draw records of slots no shade pass visits stay zero (status 0: no vertex), and
            // the queues start empty.
            let db = u64::from(slots) * u64::from(per_slot_draws) * DRAW_WORDS as u64 * 4;
            if depths > 0 {
                enc.clear_buffer(&draws, 0, Some(db));
            }
            enc.clear_buffer(&loops, 16, Some(48));
            for (q, &(stage, depth, mode)) in passes.iter().enumerate() {
                let group = &groups[3 * depth as usize + mode as usize];
                let pipe = if stage == 1 { &p.shade } else { &p.trace };
                if stage > 1 || (stage == 1 && depth > 0) {
                    // The queued passes: their dispatch from their queue's length. (Byte
                    // offsets in `stats`: the shadow, live and continuation queues' args at
                    // 20, 36 and 52.)
                    {
                        let mut pass = enc.begin_compute_pass(&Default::default());
                        pass.set_pipeline(&p.prepare);
                        pass.set_bind_group(0, group, &[]);
                        pass.dispatch_workgroups(1, 1, 1);
                    }
                    let (from, to) = match stage {
                        1 => (36, 16),
                        2 => (20, 0),
                        _ => (52, 32),
                    };
                    enc.copy_buffer_to_buffer(&loops, from, &args, to, 12);
                }
                match stage {
                    // Empty shadow and continuation queues for the shade pass to fill.
                    1 => {
                        enc.clear_buffer(&loops, 16, Some(4));
                        enc.clear_buffer(&loops, 48, Some(4));
                    }
                    // An empty live queue for the continuations' new vertices.
                    3 => enc.clear_buffer(&loops, 32, Some(4)),
                    _ => {}
                }
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: None,
                    timestamp_writes: timestamps.as_ref().map(|qs| {
                        wgpu::ComputePassTimestampWrites {
                            query_set: qs,
                            beginning_of_pass_write_index: Some(2 * q as u32),
                            end_of_pass_write_index: Some(2 * q as u32 + 1),
                        }
                    }),
                });
                pass.set_pipeline(pipe);
                pass.set_bind_group(0, group, &[]);
                match stage {
                    0 => {
                        let (gx, gy) = crate::workgroups(slots);
                        pass.dispatch_workgroups(gx, gy, 1);
                    }
                    // Depth 0: every slot's draws, in slot order (coherent rays).
                    1 if depth == 0 => {
                        let (gx, gy) = crate::workgroups(slots * nd1);
                        pass.dispatch_workgroups(gx, gy, 1);
                    }
                    // The live slots' draws, the shadow rays and the continuations queued
                    // by the pass before, and no other.
                    1 => pass.dispatch_workgroups_indirect(&args, 16),
                    2 => pass.dispatch_workgroups_indirect(&args, 0),
                    _ => pass.dispatch_workgroups_indirect(&args, 32),
                }
            }
            if let Some(sums) = sums.as_mut() {
                let at = 2 * passes.len() as u32;
                let writes = |k: u32| {
                    timestamps
                        .as_ref()
                        .map(|qs| wgpu::ComputePassTimestampWrites {
                            query_set: qs,
                            beginning_of_pass_write_index: Some(at + 2 * k),
                            end_of_pass_write_index: Some(at + 2 * k + 1),
                        })
                };
                sums.encode(gpu, &mut enc, band_len, start, m, &writes);
            }
            // The passes run: the wave's, and the terms and sums passes.
            let run = passes.len() + if sums.is_some() { 2 } else { 0 };
            if let Some(qs) = &timestamps {
                enc.resolve_query_set(qs, 0..2 * run as u32, &ts_buf, 0);
                enc.copy_buffer_to_buffer(&ts_buf, 0, &ts_read, 0, 16 * run as u64);
            }
            let hb = u64::from(slots) * HIT_WORDS as u64 * 4;
            if let Some((hits_r, draws_r)) = &readbacks {
                enc.copy_buffer_to_buffer(&hits, 0, hits_r, 0, hb);
                if depths > 0 {
                    enc.copy_buffer_to_buffer(&draws, 0, draws_r, 0, db);
                }
            }
            let t0 = Instant::now();
            gpu.queue.submit([enc.finish()]);
            let (mut hit_data, mut draw_data, mut tally) = (Vec::new(), Vec::new(), None);
            if let Some((hits_r, draws_r)) = &readbacks {
                hit_data = read_back(gpu, hits_r, hb)?;
                if depths > 0 {
                    draw_data = read_back(gpu, draws_r, db)?;
                }
            }
            if let Some(sums) = sums.as_mut() {
                tally = Some(sums.tally(gpu, slots)?);
                // The progressive estimators' solves within the wave.
                let t = Instant::now();
                sums.settle(gpu)?;
                stats.stages.accumulate += t.elapsed();
            }
            let mut passes_time = Duration::ZERO;
            if timestamps.is_some() {
                let ts = read_back(gpu, &ts_read, 16 * run as u64)?;
                let t: &[u64] = bytemuck::cast_slice(&ts);
                for q in 0..run {
                    let ns = t[2 * q + 1].saturating_sub(t[2 * q]) as f64 * period;
                    let span = Duration::from_nanos(ns as u64);
                    passes_time += span;
                    match passes.get(q).map_or(4, |p| p.0) {
                        0 => stats.stages.camera += span,
                        1 => stats.stages.shade += span,
                        2 => stats.stages.shadow += span,
                        3 => stats.stages.secondary += span,
                        _ => stats.stages.accumulate += span,
                    }
                }
            }
            stats.stages.readback += t0.elapsed().saturating_sub(passes_time);
            let t1 = Instant::now();
            let data_words = state.data_mut();
            if let Some(tally) = tally {
                rays.camera += tally.camera;
                rays.shadow += tally.shadow;
                rays.secondary += tally.secondary;
                for slot in tally.overflow {
                    // The CPU renders the whole sample (its rays counted there), into the
                    // record to which the GPU's sums are added at the end.
                    let pix = base + slot % band_len;
                    let index = start + slot / band_len;
                    let rec = &mut data_words[pix as usize * stride..(pix as usize + 1) * stride];
                    stats.cpu_fallbacks += 1;
                    acc.cpu_sample(scene, pix % w, pix / w, index, rec, &mut rays);
                }
            }
            // (An empty Vec<u8> need not be aligned for f32.)
            fn words(v: &[u8]) -> &[f32] {
                if v.is_empty() {
                    &[]
                } else {
                    bytemuck::cast_slice(v)
                }
            }
            let (hv, dv) = (words(&hit_data), words(&draw_data));
            let mut pdfs = vec![0.0f64; (depths * n_draws) as usize * t_count];
            let cpu_slots = if readbacks.is_some() {
                slots as usize
            } else {
                0
            };
            for slot in 0..cpu_slots {
                let pix = base as usize + slot % band_len as usize;
                let index = start + slot as u32 / band_len;
                let (x, y) = (pix as u32 % w, pix as u32 / w);
                let rec = &mut data_words[pix * stride..(pix + 1) * stride];
                let hw = &hv[slot * HIT_WORDS..(slot + 1) * HIT_WORDS];
                // The draws of vertex `depth`, the extra draw last.
                let vertex = |depth: u32| {
                    let at = ((depth * slots) as usize + slot) * nd1 as usize * DRAW_WORDS;
                    &dv[at..at + nd1 as usize * DRAW_WORDS]
                };
                let overflow = hw[3] == 2.0
                    || (0..depths)
                        .any(|k| vertex(k).chunks_exact(DRAW_WORDS).any(|d| d[7] == 12.0));
                if overflow {
                    // The CPU renders the whole sample (its rays counted there).
                    stats.cpu_fallbacks += 1;
                    acc.cpu_sample(scene, x, y, index, rec, &mut rays);
                    continue;
                }
                add_slot(
                    &acc, rec, index, hw, &vertex, n_draws, depths, &mut pdfs, &mut rays,
                );
            }
            stats.stages.accumulate += t1.elapsed();
            stats.waves += 1;
            done += u64::from(slots);
            progress(done, total);
            start += m;
        }
        if let Some(sums) = sums.as_mut() {
            // The band's sums into its pixels' records, and zero sums for the next band.
            let t = Instant::now();
            let range = base as usize * stride..(base + band_len) as usize * stride;
            sums.add_to(gpu, &mut state.data_mut()[range])?;
            sums.reset(gpu);
            stats.stages.accumulate += t.elapsed();
        }
        if stop.load(Ordering::Relaxed) {
            break;
        }
        base += band_len;
    }
    let mut enc = d.create_command_encoder(&Default::default());
    enc.copy_buffer_to_buffer(&loops, 0, &loops_r, 0, 16);
    gpu.queue.submit([enc.finish()]);
    let l = read_back(gpu, &loops_r, 16)?;
    let l: &[u32] = bytemuck::cast_slice(&l);
    stats.max_loops = [l[0], l[1], l[2]];
    if done < total {
        state.set_partial();
    }
    let render_stats = RenderStats {
        integrator: o.integrator,
        wall: started.elapsed(),
        samples: done,
        samples_requested: total,
        rays,
        stopped: done < total,
        threads: 0,
    };
    Ok((state, render_stats, stats))
}
