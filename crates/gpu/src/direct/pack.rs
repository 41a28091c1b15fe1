//! The scene and render options packed as the kernels read them: objects (leaves,
//! intersections, CSG trees, expression solids), materials, lights, the selection
//! tables and the uniform [`Frame`].

use super::{MAX_GPU_DEPTH, MAX_GPU_TECHNIQUES};
use crate::adapter::KernelCache;
use crate::bsdf::{GpuBsdf, COAT_STEPS, COAT_TABLE_LEN};
use crate::env::GpuEnv;
use crate::layout::{outward, GpuBvhNode, GpuItemBox, GpuObject, GpuPerturbation, GpuQuadric};
use crate::light::{self, GpuAreaLight};
use crate::perturbed::PerturbedPack;
use crate::tape::GpuTape;
use crate::tape_trace::TapeSolid;
use crate::{f4, GpuError};
use bytemuck::{Pod, Zeroable};
use frep::flat::CsgOp;
use frep::LeafView;
use scene::{CameraKind, LightKind, MaterialData, SceneData, TextureData, TextureSpace};
use state::{Host, IntegratorKind, RenderOptions, Technique, TrainedSelection};

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

/// A texture in place of one of a BSDF's parameters: a point-space checker (`kind` 1:
/// `a.xyz`, `b.xyz`, the scale in `a.w`), a solid pattern (2) or an image by triplanar
/// projection (3), both read in the object's own space; 0: none (the BSDF's constant).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTexture {
    /// 0 none, 1 point checker, 2 solid pattern, 3 image.
    pub kind: u32,
    /// The pattern ([`crate::noise::pattern_code`]), or the image's first word in the
    /// tables (RGB f32 per pixel, row-major).
    pub code: u32,
    /// The pattern's octaves, or the image's width.
    pub size: u32,
    /// 1: the value is clamped to [0, 1] (plastic's diffuse colour).
    pub clamp: u32,
    /// The checker's even cells' colour (the pattern's colour at 0); the scale in `w`.
    pub a: [f32; 4],
    /// The odd cells' colour (the pattern's colour at 1); an image's height and
    /// sharpness in `x` and `y`.
    pub b: [f32; 4],
}

/// Which BSDF parameter each of [`GpuMaterial::tex`] replaces: the colour (diffuse
/// reflectance, plastic's base, a conductor's η), a conductor's k, and the GGX α (its
/// first channel, clamped to [0, 1]).
pub const TEX_SLOTS: usize = 3;

/// A material: its BSDF with constant parameters, and textures in place of some of them.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    /// The BSDF.
    pub bsdf: GpuBsdf,
    /// The textures of the colour, k and α ([`TEX_SLOTS`]).
    pub tex: [GpuTexture; TEX_SLOTS],
    /// World to the object's own space, where patterns and images are read: rows
    /// (m_i, t_i) of `p ↦ m·p + t` (the identity, but for the copy of a textured
    /// material that the packing makes for each object with a transform).
    pub to_local: [[f32; 4]; 3],
    /// The normals' matrix to the object's space, by rows (w unused): the normal there
    /// is this times the world normal, normalised.
    pub normals: [[f32; 4]; 3],
    /// The radiance its surface emits on the outer side (rgb; 0: none), as the CPU's
    /// `Scene::surface_emission`.
    pub emission: [f32; 4],
    /// A plastic with a textured α: in `x` the first word of its coat tables at
    /// α = k/32, k = 0…32 (`render::material::RoughnessMap`), each its internal
    /// reflectance then [`COAT_TABLE_LEN`] albedos; else unused. In `y` and `z` the
    /// media inside and around the object that wears it ([`NO_MEDIUM`]: vacuum): an
    /// object bounding a medium wears a copy of its material that names them.
    pub coats: [u32; 4],
}

/// No medium (vacuum) in [`GpuMaterial::coats`] and the frame's camera medium.
pub const NO_MEDIUM: u32 = u32::MAX;

/// The BSDF kind of an index-matched boundary (`interface`): never shaded, since the
/// kernels' walks pass through it (render::integrator::medium).
pub const INTERFACE: u32 = 5;

/// Rows of the identity as [`GpuMaterial::to_local`] and [`GpuMaterial::normals`].
const IDENTITY_ROWS: [[f32; 4]; 3] = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
];

/// The kernels' uniform block (the WGSL `Frame`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub(super) struct Frame {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) pixels: u32,
    pub(super) slots: u32,
    pub(super) sample: u32,
    pub(super) n_shapes: u32,
    pub(super) seed_lo: u32,
    pub(super) seed_hi: u32,
    pub(super) n_tech: u32,
    pub(super) n_draws: u32,
    pub(super) n_lights: u32,
    pub(super) power_off: u32,
    pub(super) area_off: u32,
    pub(super) flags: u32,
    pub(super) mode: u32,
    pub(super) zero: u32,
    pub(super) depth: u32,
    pub(super) max_depth: u32,
    pub(super) rr_depth: u32,
    pub(super) stride: u32,
    pub(super) carry: u32,
    pub(super) n_delta: u32,
    pub(super) per_slot: u32,
    pub(super) spatial_off: u32,
    pub(super) eye: [f32; 4],
    pub(super) right: [f32; 4],
    pub(super) up: [f32; 4],
    pub(super) forward: [f32; 4],
    pub(super) tech: [[u32; 4]; MAX_GPU_TECHNIQUES / 4],
    pub(super) count: [[u32; 4]; MAX_GPU_TECHNIQUES / 4],
    pub(super) env: GpuEnv,
    /// The trained selection's table in `tables` (u32::MAX: none), cells per axis, MIS
    /// lights covered.
    pub(super) trained: [u32; 4],
    /// Where the live and continuation queues' entries start in `stats` (words), and
    /// the first pixel of the wave's band.
    pub(super) wave: [u32; 4],
    /// The light BVH's nodes and trails in `tables` (u32::MAX: none; `light::tree_records`).
    pub(super) tree: [u32; 4],
    /// The BVH over the area lights' boxes in `nodes` and `items`: its first node, node
    /// count, first item ([`DirectScene::pack_light_boxes`]).
    pub(super) lbvh: [u32; 4],
    /// The media: the material of the first (they follow the scene's materials, one
    /// phase-function material each: σ_t in its `k`, the albedo in its colour), the
    /// camera's medium ([`NO_MEDIUM`]: vacuum), whether the scene has media or
    /// index-matched boundaries at all (1: the kernels walk through them), and the depth
    /// after whose vertices `state::dims` puts the free flights' numbers.
    pub(super) media: [u32; 4],
}

const _: () = assert!(size_of::<GpuShape>() == 48);
const _: () = assert!(size_of::<GpuMaterial>() == 64 + 48 * TEX_SLOTS + 128);
const _: () = assert!(size_of::<Frame>() == 592);

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
    /// The scene's expression solids, in the order of their leaves' `first_op`: their
    /// tapes share one interpreter (GPU.md §6.2), which runs each for its own length,
    /// in one binding checked against the device's limit.
    pub tapes: Vec<TapeSolid>,
    /// CSG nodes of kind-2 shapes, post-order: (op, leaf or part count, 0, 0).
    pub csg: Vec<[u32; 4]>,
    /// Light-selection tables (by power at 0, by area at `frame.area_off`) and plastic
    /// coat tables.
    pub tables: Vec<f32>,
    pub(super) frame: Frame,
}

/// The most walk grids a device keeps for later renders (the solids rendered last):
/// the test scenes' three, with room for a few scenes of a session.
const KEPT_WALKS: usize = 8;

/// The most CSG nodes one object may have on the GPU (after shared parts are copied).
const MAX_CSG_NODES: u32 = 256;

fn unsupported(what: impl Into<String>) -> GpuError {
    GpuError::Unsupported(what.into())
}

/// A textured parameter's constant, which the texture replaces per hit: any value
/// serves; the checker's or pattern's `a` where it has one.
fn constant_of(data: &SceneData, id: scene::TextureId) -> [f64; 3] {
    match &data.textures[id.index()] {
        TextureData::Constant { rgb } => *rgb,
        TextureData::Checker { a, .. } | TextureData::Pattern { a, .. } => *a,
        TextureData::Image { .. } => [0.5; 3],
    }
}

fn f3(v: [f64; 3]) -> [f32; 3] {
    [v[0] as f32, v[1] as f32, v[2] as f32]
}

impl DirectScene {
    /// Packs `data` for a render with `o`, with the tables of `host` (the CPU renderer
    /// of the same scene and options: coat albedos, light bounds, the trained light
    /// selection), or says what the GPU cannot do.
    pub fn new(data: &SceneData, o: &RenderOptions, host: &dyn Host) -> Result<Self, GpuError> {
        Self::packed(data, o, host, None)
    }

    /// [`Self::new`], the expression solids' walk grids kept in `walks` (a device's
    /// cache) for the later renders of the same solids.
    pub(crate) fn packed(
        data: &SceneData,
        o: &RenderOptions,
        host: &dyn Host,
        walks: Option<&KernelCache>,
    ) -> Result<Self, GpuError> {
        let mut s = DirectScene::default();
        // Perlin's permutation first: the noise patterns read it at tables[0..256].
        s.tables.extend(scene::PERLIN_PERM.map(f32::from));
        s.pack_lights(data)?;
        s.pack_materials(data, host)?;
        s.pack_media(data, o)?;
        for obj in &data.objects {
            s.pack_object(data, obj, walks)?;
        }
        s.pack_light_boxes(data);
        s.pack_frame(data, o, host)?;
        s.pack_trained(host.trained());
        Ok(s)
    }

    /// A copy of textured material `m` that reads its pattern or image in the space of
    /// an object placed by `pl` ([`scene::LocalFrame`], as the CPU reads it; the world
    /// where the transform is singular), and its index.
    fn local_material(&mut self, m: u32, pl: &scene::Placement) -> u32 {
        let mut copy = self.materials[m as usize];
        if let Some(f) = pl.local_frame() {
            for i in 0..3 {
                let (r, n) = (f.m.row(i), f.normals.row(i));
                copy.to_local[i] = [r.x as f32, r.y as f32, r.z as f32, f.t[i] as f32];
                copy.normals[i] = [n.x as f32, n.y as f32, n.z as f32, 0.0];
            }
        }
        self.materials.push(copy);
        self.materials.len() as u32 - 1
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
        walks: Option<&KernelCache>,
    ) -> Result<(), GpuError> {
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
        let mut solid = TapeSolid::new(tape, &view.bounds);
        if view.grid.is_some() {
            // Rays walk the cells with their tapes (prospero: 0.02 % of pixel centres
            // left to the CPU instead of 63 %); without cell tapes, the whole tape.
            // The grid depends on the expression and the window alone: a device's
            // later renders of the solid take the one its first made.
            let walk = || solid.clone().with_cells(view.tape).map(|s| s.walk);
            let walk = match walks {
                Some(cache) => {
                    let key = format!(
                        "{:?} {:?} {:?} {:?}",
                        view.tape, solid.lo, solid.hi, solid.eps
                    );
                    cache
                        .get_or_make_keeping(&key, KEPT_WALKS, walk)
                        .map(|w| (*w).clone())
                }
                None => walk(),
            };
            if let Ok(w) = walk {
                solid.walk = w;
            }
        }
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

    fn pack_object(
        &mut self,
        data: &SceneData,
        obj: &scene::ObjectData,
        walks: Option<&KernelCache>,
    ) -> Result<(), GpuError> {
        let Some(solid) = obj.geometry.solid() else {
            return Err(unsupported(format!(
                "object '{}' is a triangle mesh; meshes render on the CPU",
                obj.name
            )));
        };
        let flat = data.solids.solid(solid).flat();
        let root = flat.nodes.len() - 1;
        let node = &flat.nodes[root];
        let mut material = obj.material.0;
        if let Some(pl) = &obj.placement {
            if self.materials[material as usize]
                .tex
                .iter()
                .any(|t| matches!(t.kind, 2 | 3))
            {
                material = self.local_material(material, pl);
            }
        }
        if obj.interior.is_some() || obj.exterior.is_some() {
            // A copy that names the media on its two sides.
            let mut copy = self.materials[material as usize];
            copy.coats[1] = obj.interior.map_or(NO_MEDIUM, |m| m.0);
            copy.coats[2] = obj.exterior.map_or(NO_MEDIUM, |m| m.0);
            self.materials.push(copy);
            material = self.materials.len() as u32 - 1;
        }
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
                    self.pack_expr(
                        flat,
                        node.operands.first as usize,
                        &v,
                        &obj.name,
                        material,
                        walks,
                    )?;
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
                                self.pack_expr(flat, k, &v, &obj.name, material, walks)?;
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

    /// The texture record of `id` (a [`TextureData::Constant`] gives none: the BSDF's
    /// constant), each image's pixels added to the tables once (`images`: by image id).
    /// `clamp`: the value is clamped to [0, 1] (plastic's colour).
    fn texture(
        &mut self,
        data: &SceneData,
        id: scene::TextureId,
        clamp: bool,
        images: &mut std::collections::HashMap<usize, u32>,
    ) -> GpuTexture {
        let c = |v: [f64; 3]| {
            if clamp {
                v.map(|x| x.clamp(0.0, 1.0))
            } else {
                v
            }
        };
        let (kind, code, size, a, b) = match &data.textures[id.index()] {
            TextureData::Constant { .. } => return GpuTexture::default(),
            TextureData::Checker {
                a,
                b,
                scale,
                space: TextureSpace::Point,
            } => (1, 0, 0, f4(c(*a), *scale), f4(c(*b), 0.0)),
            // The GPU's geometry carries no surface parameters (uv = 0, as the CPU's
            // solids: only meshes have them), so a uv checker is its colour `a`
            // everywhere, as on the CPU: a checker of `a` in both cells.
            TextureData::Checker {
                a,
                scale,
                space: TextureSpace::Uv,
                ..
            } => (1, 0, 0, f4(c(*a), *scale), f4(c(*a), 0.0)),
            TextureData::Image {
                image,
                scale,
                sharpness,
            } => {
                let img = data.images.image(*image);
                let at = *images.entry(image.index()).or_insert_with(|| {
                    let at = self.tables.len() as u32;
                    self.tables.extend(img.pixels.iter().flatten());
                    at
                });
                let b = [img.height as f32, *sharpness as f32, 0.0, 0.0];
                (3, at, img.width as u32, f4([0.0; 3], *scale), b)
            }
            // Blended, then clamped as the CPU clamps plastic's colour.
            TextureData::Pattern {
                kind,
                a,
                b,
                scale,
                octaves,
            } => (
                2,
                crate::noise::pattern_code(*kind),
                *octaves,
                f4(*a, *scale),
                f4(*b, 0.0),
            ),
        };
        GpuTexture {
            kind,
            code,
            size,
            clamp: u32::from(clamp),
            a,
            b,
        }
    }

    fn pack_materials(&mut self, data: &SceneData, host: &dyn Host) -> Result<(), GpuError> {
        // Each image once in the tables, by image id.
        let mut images = std::collections::HashMap::new();
        let mu: Vec<f64> = (0..COAT_TABLE_LEN)
            .map(|j| (j as f64 / 64.0).powi(2))
            .collect();
        for (i, m) in data.materials.iter().enumerate() {
            let rgb = |id| constant_of(data, id);
            let mut tex = [GpuTexture::default(); TEX_SLOTS];
            let mut coats = [u32::MAX, NO_MEDIUM, NO_MEDIUM, 0];
            let bsdf = match *m {
                MaterialData::Diffuse { reflectance } => {
                    tex[0] = self.texture(data, reflectance, false, &mut images);
                    GpuBsdf::diffuse(rgb(reflectance))
                }
                MaterialData::Conductor { eta, k, roughness } => {
                    tex[0] = self.texture(data, eta, false, &mut images);
                    tex[1] = self.texture(data, k, false, &mut images);
                    GpuBsdf::conductor(rgb(eta), rgb(k), roughness)
                }
                MaterialData::Dielectric { eta, roughness } => GpuBsdf::dielectric(eta, roughness),
                MaterialData::Interface => GpuBsdf {
                    kind: INTERFACE,
                    ..GpuBsdf::default()
                },
                MaterialData::Plastic {
                    diffuse,
                    eta,
                    roughness,
                } => {
                    // Plastic's diffuse colour is clamped to [0, 1] (render::bsdf::plastic).
                    tex[0] = self.texture(data, diffuse, true, &mut images);
                    let coat = host.coat_albedo(eta, roughness, &mu);
                    let at = self.tables.len() as u32;
                    self.tables.extend(coat.albedo.iter().map(|&a| a as f32));
                    if data.roughness.get(i).is_some_and(Option::is_some) {
                        // The coats at α = k/32 (render::material::RoughnessMap).
                        coats[0] = self.tables.len() as u32;
                        for k in 0..=COAT_STEPS {
                            let c = host.coat_albedo(eta, k as f64 / COAT_STEPS as f64, &mu);
                            self.tables.push(c.r_int as f32);
                            self.tables.extend(c.albedo.iter().map(|&a| a as f32));
                        }
                    }
                    GpuBsdf::plastic(rgb(diffuse), eta, roughness, coat.r_int, at)
                }
            };
            if let Some(Some(id)) = data.roughness.get(i) {
                tex[2] = self.texture(data, *id, false, &mut images);
            }
            self.materials.push(GpuMaterial {
                bsdf,
                tex,
                to_local: IDENTITY_ROWS,
                normals: IDENTITY_ROWS,
                emission: f4(data.emission.get(i).copied().unwrap_or_default(), 0.0),
                coats,
            });
        }
        Ok(())
    }

    /// The media as phase-function materials after the scene's (σ_t in `k`, the albedo
    /// as the colour, a texture read in world space), and the frame's media block.
    fn pack_media(&mut self, data: &SceneData, o: &RenderOptions) -> Result<(), GpuError> {
        // render::scene::Scene::participating.
        let walks = data.camera_medium.is_some()
            || data.objects.iter().any(|ob| {
                ob.interior.is_some()
                    || ob.exterior.is_some()
                    || matches!(data.materials[ob.material.index()], MaterialData::Interface)
            });
        self.frame.media = [
            self.materials.len() as u32,
            data.camera_medium.map_or(NO_MEDIUM, |m| m.0),
            u32::from(walks),
            // state::dims places the free flights after `max_depth` vertices' numbers,
            // the options' depth whatever the integrator (`direct` shades one vertex).
            o.max_depth.max(1),
        ];
        if !walks {
            return Ok(());
        }
        if !o.aovs.is_empty()
            || !matches!(o.integrator, IntegratorKind::Direct | IntegratorKind::Path)
        {
            return Err(unsupported(
                "AOVs in a scene with participating media or index-matched boundaries \
                 (they render on the CPU)",
            ));
        }
        // Two 16-bit medium indices per vertex (the kernels' `hits`).
        if data.media.len() >= 0xffff {
            return Err(unsupported(format!(
                "{} media (at most {})",
                data.media.len(),
                0xffff - 1
            )));
        }
        let mut images = std::collections::HashMap::new();
        for m in &data.media {
            let mut bsdf = GpuBsdf::phase(m.g);
            bsdf.rgb = f4(constant_of(data, m.albedo), 0.0);
            bsdf.k = f4(m.sigma_t, 0.0);
            let mut tex = [GpuTexture::default(); TEX_SLOTS];
            tex[0] = self.texture(data, m.albedo, false, &mut images);
            self.materials.push(GpuMaterial {
                bsdf,
                tex,
                to_local: IDENTITY_ROWS,
                normals: IDENTITY_ROWS,
                emission: [0.0; 4],
                coats: [u32::MAX, NO_MEDIUM, NO_MEDIUM, 0],
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
                LightKind::Triangle => {
                    return Err(unsupported("mesh lights (triangles) render on the CPU"))
                }
                // An emitting object's bounding sphere: light draws sample directions
                // toward it as toward a sphere light, and the pdfs count it as one, but
                // no ray meets it (`pad[0]`: the kernels' nearest light skips it);
                // what a ray toward it receives is the emission of the surface it hits.
                LightKind::Solid => GpuAreaLight {
                    pad: [1, 0],
                    ..GpuAreaLight::sphere(f3(l.p0), l.radius as f32, rad, area)
                },
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

    /// A BVH over the area lights' boxes after the objects' nodes and items (escape
    /// layout, [`crate::layout::skip_nodes`]): the kernels' light queries (the nearest
    /// light along a ray, the mixtures' pdfs) visit only the lights whose box a ray
    /// crosses, as the CPU's do, instead of every light. A box holds its light's shape
    /// widened by 10⁻⁴ of its extent and distance from the origin: more than the f32
    /// rims and edges of `light::pdf_li` and `light::pdf_area` reach.
    fn pack_light_boxes(&mut self, data: &SceneData) {
        self.frame.lbvh = [0; 4];
        if data.lights.area.is_empty() {
            return;
        }
        let v = |a: [f64; 3]| glam::DVec3::from_array(a);
        let boxes: Vec<frep::Aabb> = data
            .lights
            .area
            .iter()
            .map(|l| {
                let (lo, hi) = match l.kind {
                    LightKind::Rect => {
                        let c = [v(l.p0), v(l.p0) + v(l.e1), v(l.p0) + v(l.e2)];
                        let far = c[1] + v(l.e2);
                        (
                            c[0].min(c[1]).min(c[2]).min(far),
                            c[0].max(c[1]).max(c[2]).max(far),
                        )
                    }
                    // Spheres and disks (a disk within the sphere of its radius).
                    _ => (v(l.p0) - l.radius, v(l.p0) + l.radius),
                };
                let pad =
                    1e-4 * ((hi - lo).max_element() + lo.abs().max(hi.abs()).max_element()) + 1e-6;
                frep::Aabb::new(lo - pad, hi + pad)
            })
            .collect();
        let bvh = frep::Bvh::new(&boxes);
        let view = bvh.as_ref();
        let (nodes, items) = (
            crate::layout::skip_nodes(&view),
            crate::layout::item_boxes(&view),
        );
        self.frame.lbvh = [
            self.nodes.len() as u32,
            nodes.len() as u32,
            self.items.len() as u32,
            0,
        ];
        self.nodes.extend(nodes);
        self.items.extend(items);
    }

    /// The trained selection after the other tables: its grid (low corner, cells per
    /// unit), floor, entry offsets per cell and entries (light, running share, share),
    /// the layout `direct_lights.wgsl`'s `trained_entries` reads.
    fn pack_trained(&mut self, trained: Option<&TrainedSelection>) {
        self.frame.trained = [u32::MAX, 0, 0, 0];
        if let Some(t) = trained {
            let (lo, scale, res) = t.grid();
            self.frame.trained = [self.tables.len() as u32, res as u32, t.lights() as u32, 0];
            self.tables.extend(lo.as_vec3().to_array());
            self.tables.extend(scale.as_vec3().to_array());
            self.tables.push(t.floor() as f32);
            let start = t.offsets();
            self.tables.extend(start.iter().map(|&s| f32::from_bits(s)));
            for (c, w) in start.windows(2).enumerate() {
                for e in w[0] as usize..w[1] as usize {
                    let (light, cum, share) = t.entry(c, e);
                    self.tables
                        .extend([f32::from_bits(light), cum as f32, share as f32]);
                }
            }
        }
    }

    fn pack_frame(
        &mut self,
        data: &SceneData,
        o: &RenderOptions,
        host: &dyn Host,
    ) -> Result<(), GpuError> {
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
            if let Some(b) = host.light_bounds(l) {
                self.tables.extend(light::importance_record(&b));
            }
        }
        // The light BVH of `light-bvh`, as the CPU built it.
        f.tree = [u32::MAX; 4];
        if let Some(t) = host.light_tree() {
            let at = self.tables.len();
            let (words, trails) = light::tree_records(&t);
            self.tables.extend(words);
            f.tree = [at as u32, (at + trails) as u32, t.nodes.len() as u32, 0];
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
        // A thin lens: its radius in up.w (0: a pinhole), its focus distance in forward.w.
        let (radius, focus) = c.lens.map_or((0.0, 0.0), |l| (l.radius, l.focus_distance));
        f.up = f4(up.to_array(), radius);
        f.forward = f4(forward.to_array(), focus);
        f.flags = u32::from(o.hide_emitters)
            | (u32::from(o.pixel_center) << 1)
            | (u32::from(c.kind == CameraKind::Orthographic) << 2)
            | (u32::from(o.per_light > 0) << 3)
            | (u32::from(
                !o.aovs.is_empty()
                    || !matches!(o.integrator, IntegratorKind::Direct | IntegratorKind::Path),
            ) << 4)
            // Emitting objects (render::scene::Scene::has_emitting_objects), or walks
            // through media and index-matched boundaries: light arriving along a draw
            // is found by a nearest-hit ray (render::integrator::medium::transmitted).
            | (u32::from(data.emission.iter().flatten().any(|&e| e != 0.0) || f.media[2] != 0)
                << 5);
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
                Technique::CosineHemisphere => 8,
                Technique::LightBvh => 9,
                t => return Err(unsupported(format!("technique {}", t.name()))),
            };
            f.tech[k / 4][k % 4] = code;
            f.count[k / 4][k % 4] = n;
            f.n_draws += n;
        }
        // state::dims: the vertex stride, and the draw that extends a path
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The shade kernel reads a textured plastic's coat tables with the stride and steps
    /// the packing writes them with.
    #[test]
    fn coat_table_constants_match_the_kernel() {
        let wgsl = super::super::DIRECT_WGSL;
        assert!(wgsl.contains(&format!("const COAT_STEPS: f32 = {COAT_STEPS}.0;")));
        assert!(wgsl.contains(&format!("const COAT_WORDS: u32 = {}u;", COAT_TABLE_LEN + 1)));
    }
}
