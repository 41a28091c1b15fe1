//! The same heightmap by both systems, and how well the two agree.
//!
//! The view: an orthographic camera looking down −z over the box [-h, h]³ (model units),
//! N × N pixels, N voxels deep. Fidget's voxel renderer samples F at integer screen
//! positions (i, j, k), which map to model coordinates
//! `x = h·(i − N/2)·2/N`, `y = h·(N/2 − 1 − j)·2/N`, `z = h·(k − N/2)·2/N`
//! (`RegionSize::screen_to_world` then `world_to_model = h·I`); a pixel's depth is
//! `k + 1` for the highest inside sample k (0 = empty, N = inside at the top).
//! frepray casts a ray from `z = h` along −z through each pixel's (x, y) and converts
//! the first crossing to the same continuous depth ζ = (z/h + 1)·N/2, so that Fidget's
//! depth should be ⌊ζ⌋ + 1 (the surface lies between sample k and k + 1).

use crate::args::Args;
use crate::{best_of, sig3, Model};
use fidget::jit::JitShape;
use fidget::raster::voxel::{render, EvalConfig, RenderConfig};
use fidget::render::{CancelToken, RenderHints, ThreadPool, VoxelSize};
use fidget::shape::{Shape, ShapeVars};
use fidget::vm::VmShape;
use frep::{Ray, Solid};
use glam::DVec3;
use rayon::prelude::*;
use std::error::Error;
use std::path::Path;

/// Render rows plus frepray's depth image (for the profile) and its 1-thread time.
pub struct Rendered {
    /// Markdown table rows.
    pub rows: Vec<String>,
    /// frepray's continuous depth ζ per pixel (NaN: miss), row-major from the top.
    pub frep_depth: Vec<f32>,
}

fn fidget_render<F>(
    shape: &Shape<F>,
    cfg: &RenderConfig,
    threads: Option<&ThreadPool>,
    reps: usize,
) -> Result<(f64, Vec<u32>), Box<dyn Error>>
where
    F: fidget::eval::Function + RenderHints + Clone,
{
    let vars = ShapeVars::new();
    let eval = EvalConfig {
        tile_sizes: None,
        threads,
        cancel: CancelToken::new(),
    };
    let mut err = None;
    let (secs, img) = best_of(reps, || match shape.bind(&vars) {
        Ok(b) => render(b, cfg, &eval),
        Err(e) => {
            err = Some(format!("{e:?}"));
            None
        }
    });
    if let Some(e) = err {
        return Err(format!("fidget: cannot bind the shape: {e}").into());
    }
    let img = img.ok_or("fidget render was cancelled")?;
    Ok((secs, img.iter().map(|p| p.depth).collect()))
}

/// One ray through pixel (i, j): the continuous depth ζ, N when the top is inside, NaN
/// on a miss.
pub fn cast(solid: &Solid, n: usize, h: f64, i: usize, j: usize) -> f32 {
    let s = 2.0 / n as f64;
    let half = (n / 2) as f64;
    let x = (i as f64 - half) * s * h;
    let y = (half - 1.0 - j as f64) * s * h;
    let o = DVec3::new(x, y, h);
    if solid.inside(o) {
        return n as f32;
    }
    match solid.intersect(&Ray::new(o, -DVec3::Z), 0.0, 2.0 * h) {
        Some(hit) => {
            let z = h - hit.t;
            ((z / h + 1.0) * half) as f32
        }
        None => f32::NAN,
    }
}

/// Fidget's depth expected for a continuous depth ζ (0 for a miss).
pub fn quantise(zeta: f32, n: usize) -> u32 {
    if zeta.is_nan() {
        0
    } else {
        ((zeta.floor() as i64 + 1).clamp(1, n as i64)) as u32
    }
}

fn frep_render(solid: &Solid, n: usize, h: f64, parallel: bool, reps: usize) -> (f64, Vec<f32>) {
    let mut depth = vec![0f32; n * n];
    let (secs, ()) = best_of(reps, || {
        let row = |(j, r): (usize, &mut [f32])| {
            for (i, d) in r.iter_mut().enumerate() {
                *d = cast(solid, n, h, i, j);
            }
        };
        if parallel {
            depth.par_chunks_mut(n).enumerate().for_each(row);
        } else {
            depth.chunks_mut(n).enumerate().for_each(row);
        }
    });
    (secs, depth)
}

/// How thick (in voxels, along the ray) the solid is below frepray's crossing at pixel
/// (i, j): the distance to the ray's next crossing, the exit.
fn thickness(solid: &Solid, n: usize, h: f64, i: usize, j: usize, zeta: f32) -> f64 {
    let s = 2.0 / n as f64;
    let half = (n / 2) as f64;
    let o = DVec3::new(
        (i as f64 - half) * s * h,
        (half - 1.0 - j as f64) * s * h,
        h,
    );
    let t = h - (zeta as f64 / half - 1.0) * h;
    let voxel = s * h;
    match solid.intersect(&Ray::new(o, -DVec3::Z), t + 1e-9 * h, 2.0 * h) {
        Some(exit) => (exit.t - t) / voxel,
        None => f64::INFINITY,
    }
}

/// Hit/miss agreement and depth error of frepray (continuous ζ) against Fidget (voxels).
fn agreement(fid: &[u32], frep: &[f32], n: usize, solid: &Solid, h: f64) -> String {
    let (mut both_miss, mut fid_only, mut frep_only) = (0usize, 0usize, 0usize);
    let (mut both, mut same, mut one, mut worst, mut sum) = (0usize, 0usize, 0usize, 0i64, 0f64);
    // Pixels more than one voxel apart: frepray's crossing nearer the camera (a feature
    // thinner than a voxel that Fidget's samples stepped over) or farther.
    let (mut nearer, mut farther) = (0usize, 0usize);
    // The thickest solid below frepray's crossing among pixels nearer in frepray (or
    // hit only by frepray): below one voxel, Fidget's samples can step over it.
    let mut thickest = 0f64;
    for (k, (&d, &z)) in fid.iter().zip(frep).enumerate() {
        let thick = || thickness(solid, n, h, k % n, k / n, z);
        match (d > 0, !z.is_nan()) {
            (false, false) => both_miss += 1,
            (true, false) => fid_only += 1,
            (false, true) => {
                frep_only += 1;
                thickest = thickest.max(thick());
            }
            (true, true) => {
                both += 1;
                let signed = quantise(z, n) as i64 - d as i64;
                if signed > 1 {
                    nearer += 1;
                    thickest = thickest.max(thick());
                }
                farther += (signed < -1) as usize;
                let delta = signed.abs();
                same += (delta == 0) as usize;
                one += (delta <= 1) as usize;
                worst = worst.max(delta);
                // Fidget's depth d stands for the voxel [d − 1, d): its centre is d − ½.
                sum += (z as f64 - (d as f64 - 0.5)).abs();
            }
        }
    }
    let total = fid.len() as f64;
    let pct = |a: usize, b: usize| 100.0 * a as f64 / (b.max(1)) as f64;
    format!(
        "hit/miss agree {:.3} % ({} hit, {} empty; {} only Fidget, {} only frepray); \
         both hit: same voxel {:.2} %, within 1 voxel {:.3} %, max {} voxels \
         ({} pixels > 1 voxel nearer in frepray, {} farther), mean \\|ζ − (d − ½)\\| {:.3} voxel{}",
        100.0 * (both + both_miss) as f64 / total,
        both,
        both_miss,
        fid_only,
        frep_only,
        pct(same, both),
        pct(one, both),
        worst,
        nearer,
        farther,
        sum / both.max(1) as f64,
        if frep_only + nearer > 0 {
            format!(
                "; solid below frepray's crossing where it alone hits or is nearer: \
                 at most {thickest:.2} voxel thick"
            )
        } else {
            String::new()
        }
    )
}

/// Writes a 16-bit grayscale PNG (values in [0, 1]; NaN → 0).
fn png16(path: &Path, n: usize, v: impl Iterator<Item = f32>) -> Result<(), Box<dyn Error>> {
    let mut bytes = Vec::with_capacity(2 * n * n);
    for x in v {
        let q = if x.is_nan() {
            0
        } else {
            (x.clamp(0.0, 1.0) * 65535.0).round() as u16
        };
        bytes.extend_from_slice(&q.to_be_bytes());
    }
    let w = std::io::BufWriter::new(std::fs::File::create(path)?);
    let mut enc = png::Encoder::new(w, n as u32, n as u32);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Sixteen);
    let mut wr = enc.write_header()?;
    wr.write_image_data(&bytes)?;
    wr.finish()?;
    Ok(())
}

/// Writes an 8-bit agreement map: black both empty, grey both hit within one voxel,
/// white disagreement (hit/miss or more than one voxel apart).
fn agreement_png(path: &Path, n: usize, fid: &[u32], frep: &[f32]) -> Result<(), Box<dyn Error>> {
    let bytes: Vec<u8> = fid
        .iter()
        .zip(frep)
        .map(|(&d, &z)| {
            let q = quantise(z, n);
            match (d, q) {
                (0, 0) => 0,
                (0, _) | (_, 0) => 255,
                (a, b) if (a as i64 - b as i64).abs() > 1 => 255,
                _ => 96,
            }
        })
        .collect();
    let w = std::io::BufWriter::new(std::fs::File::create(path)?);
    let mut enc = png::Encoder::new(w, n as u32, n as u32);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Eight);
    let mut wr = enc.write_header()?;
    wr.write_image_data(&bytes)?;
    wr.finish()?;
    Ok(())
}

/// Renders the model at N² with both systems, at 1 thread and at all threads.
pub fn run(m: &Model, n: usize, args: &Args) -> Result<Rendered, Box<dyn Error>> {
    let h = m.half;
    let cfg = RenderConfig {
        image_size: VoxelSize::from(n as u32),
        world_to_model: nalgebra::Matrix4::new_scaling(h as f32),
    };
    let all = rayon::current_num_threads();
    let vm = VmShape::new(&m.ctx, m.root)?;
    let jit = JitShape::new(&m.ctx, m.root)?;
    let global = ThreadPool::Global;
    let reps = args.reps;
    let (t_vm1, d_vm) = fidget_render(&vm, &cfg, None, reps)?;
    let (t_vma, _) = fidget_render(&vm, &cfg, Some(&global), reps)?;
    let (t_jit1, d_jit) = fidget_render(&jit, &cfg, None, reps)?;
    let (t_jita, _) = fidget_render(&jit, &cfg, Some(&global), reps)?;
    eprintln!(
        "   fidget {n}²: VM {:.1} / {:.1} ms, JIT {:.1} / {:.1} ms (1 / {all} threads)",
        t_vm1 * 1e3,
        t_vma * 1e3,
        t_jit1 * 1e3,
        t_jita * 1e3
    );

    let solid = Solid::build(&m.shape)?;
    let ray_reps = args.ray_reps;
    let (t_fa, d_frep) = frep_render(&solid, n, h, true, ray_reps);
    eprintln!("   frepray {n}² at {all} threads: {:.1} ms", t_fa * 1e3);
    let (t_f1, d_frep1) = frep_render(&solid, n, h, false, ray_reps);
    eprintln!("   frepray {n}² at 1 thread: {:.1} ms", t_f1 * 1e3);
    let deterministic = d_frep
        .iter()
        .zip(&d_frep1)
        .all(|(a, b)| a.to_bits() == b.to_bits());

    // Both depth images on one scale: Fidget's depth range of the hits onto [0.1, 1]
    // (brighter is nearer), misses black. Fidget's depth d is shown as its voxel centre.
    let (lo, hi) = d_jit
        .iter()
        .filter(|&&d| d > 0)
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &d| {
            (a.min(d as f32 - 0.5), b.max(d as f32 - 0.5))
        });
    let span = (hi - lo).max(1.0);
    let shade = |z: f32| {
        if z.is_nan() {
            f32::NAN
        } else {
            0.1 + 0.9 * (z - lo) / span
        }
    };
    let dir = &args.out;
    let stem = format!("{}_{n}", m.name);
    let fid_png = d_jit.iter().map(|&d| {
        if d == 0 {
            f32::NAN
        } else {
            shade(d as f32 - 0.5)
        }
    });
    png16(&dir.join(format!("fidget_{stem}.png")), n, fid_png)?;
    png16(
        &dir.join(format!("frepray_{stem}.png")),
        n,
        d_frep.iter().map(|&z| shade(z)),
    )?;
    agreement_png(
        &dir.join(format!("agreement_{stem}.png")),
        n,
        &d_jit,
        &d_frep,
    )?;

    let vm_same = d_vm.iter().zip(&d_jit).filter(|(a, b)| a != b).count();
    let px = (n * n) as f64;
    let row = |who: &str, threads: usize, secs: f64, note: &str| {
        format!(
            "| {} | {n}² | {who} | {threads} | {} | {} | {note} |",
            m.name,
            sig3(secs * 1e3),
            sig3(px / secs / 1e6)
        )
    };
    let vm_note = if vm_same == 0 {
        "identical depths".to_string()
    } else {
        format!("{vm_same} pixels differ")
    };
    let agree = agreement(&d_jit, &d_frep, n, &solid, h);
    let det = if deterministic {
        "same image at 1 and all threads"
    } else {
        "IMAGES DIFFER between thread counts"
    };
    let rows = vec![
        row("Fidget VM voxels", 1, t_vm1, &vm_note),
        row("Fidget VM voxels", all, t_vma, &vm_note),
        row("Fidget JIT voxels", 1, t_jit1, "(reference)"),
        row("Fidget JIT voxels", all, t_jita, "(reference)"),
        row("frepray rays (`Solid::intersect`)", 1, t_f1, det),
        row("frepray rays (`Solid::intersect`)", all, t_fa, &agree),
    ];
    for r in &rows {
        eprintln!("   {r}");
    }
    Ok(Rendered {
        rows,
        frep_depth: d_frep,
    })
}
