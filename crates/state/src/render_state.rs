//! The render state: every pixel's sums over a range of samples, as one flat array that
//! merges exactly, serialises to a documented file and resolves to an [`Image`].
//!
//! **What is stored.** One record per pixel, row by row, of [`Record::stride`] words:
//! `[N | outside-MIS Σ (R, G, B) | AOV Σ (7 or 0) | one MIS block per vertex depth (per
//! vertex depth and MIS light in per-light mode, block d·L + l for depth d and light l)]`
//! ([`crate::record`], [`mis::Kernel`]). Sums, never estimates (DESIGN.md §4); an
//! estimate is resolved from them only by [`RenderState::image`]: per pixel
//! `Σ_outside/N + Σ_blocks (N_b/N)·estimate_b` (module docs of `render::integrator`).
//!
//! **Merging.** Two states of the same scene and settings ([`StateHeader`] equal) over
//! disjoint sample ranges merge by adding their records ([`mis::Kernel::merge`] for the MIS
//! blocks). For the heuristics and the direct and uncorrelated optimal estimators the result
//! is the state of one render over the union of the ranges, to the rounding of the order of
//! the additions: every sample's random numbers depend on its global index only
//! ([`crate::sampler`]), and the uncorrelated estimator's sets are keyed by that index. The
//! progressive and full-weights estimators merge into an equally valid (unbiased) estimate,
//! not the single run's: each range solved α from its own samples ([`mis::progressive`]).
//! Overlapping ranges are refused: the same samples would count twice.
//!
//! **File format** (version 1, little-endian throughout):
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic `FREPSTAT` |
//! | 4 | format version, u32 (1) |
//! | 4 | header length H, u32 |
//! | H | header, UTF-8 JSON: size, integrator, estimator and parameters, techniques, depths, AOVs, per-light count, seed, scene hash, sample ranges, partial flag, record stride |
//! | 8 | word count W = width · height · stride, u64 |
//! | 8W | the records, f64 |
//! | 8 | FNV-1a 64 hash of every byte before it, u64 |

use crate::aov::Aov;
use crate::error::Error;
use crate::image::Image;
use crate::options::RenderOptions;
use crate::output::write_atomically;
use crate::record::Record;
use crate::tally::Tally;
use crate::{Rgb, Technique};
use mis::{Kernel, Method, Params};
use scene::IntegratorKind;
use serde_json::{json, Value};
use std::fmt::Write as _;
use std::io::Write as _;
use std::ops::Range;
use std::path::Path;

/// One pixel of a state, for an inspector ([`RenderState::pixel_detail`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PixelDetail {
    /// Samples summed.
    pub samples: u64,
    /// The pixel's estimate.
    pub estimate: Rgb,
    /// The part added outside MIS (emitters seen directly, deltas), per sample.
    pub outside: Rgb,
    /// The MIS blocks, by depth (and light in per-light mode).
    pub blocks: Vec<BlockDetail>,
}

/// One MIS block of a pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct BlockDetail {
    /// Vertex depth (0: the first vertex the camera ray meets).
    pub depth: usize,
    /// The light, in per-light mode (else 0).
    pub light: usize,
    /// The estimator's completed iterations.
    pub iterations: u64,
    /// Its estimate (per iteration of the block).
    pub estimate: Rgb,
    /// The optimal estimators' α, channel-major (R's T values, then G's, then B's);
    /// None for the heuristics and the uncorrelated estimator.
    pub alpha: Option<Vec<f64>>,
}

/// Everything that gives a state's sums their meaning; states merge only when equal.
#[derive(Clone, Debug, PartialEq)]
pub struct StateHeader {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The integrator.
    pub integrator: IntegratorKind,
    /// How the draws are combined.
    pub method: Method,
    /// The method's parameters.
    pub params: Params,
    /// Techniques and their draws per vertex.
    pub techniques: Vec<(Technique, u32)>,
    /// Maximum path depth.
    pub max_depth: u32,
    /// Minimum path depth (0: all).
    pub min_depth: u32,
    /// Roulette starts after this many vertices.
    pub rr_depth: u32,
    /// Whether emitters seen by the camera are left out.
    pub hide_emitters: bool,
    /// Extra channels.
    pub aovs: Vec<Aov>,
    /// Whether camera rays went through pixel centres (a diagnostic render).
    pub pixel_center: bool,
    /// Per-light mode: the number of MIS lights with an estimator each (0: off).
    pub per_light: u32,
    /// The training of `light-trained`.
    pub training: scene::Training,
    /// The seed of the random streams.
    pub seed: u64,
    /// A hash of the scene (0: unknown).
    pub scene_hash: u64,
}

impl StateHeader {
    /// The header of a render of a `width` × `height` image with `o`.
    pub fn new(width: u32, height: u32, o: &RenderOptions) -> Self {
        Self {
            width,
            height,
            integrator: o.integrator,
            method: o.method,
            // Explicit ridge: a header read back from a file equals the one it was written from.
            params: o.params.resolved(o.method),
            techniques: o.techniques.clone(),
            max_depth: o.max_depth,
            min_depth: o.min_depth,
            rr_depth: o.rr_depth,
            hide_emitters: o.hide_emitters,
            aovs: o.aovs.clone(),
            pixel_center: o.pixel_center,
            per_light: o.per_light,
            training: o.training,
            seed: o.seed,
            scene_hash: o.scene_hash,
        }
    }

    /// The render options this header describes (loop settings at their defaults).
    pub fn options(&self) -> RenderOptions {
        RenderOptions {
            integrator: self.integrator,
            method: self.method,
            params: self.params,
            techniques: self.techniques.clone(),
            max_depth: self.max_depth,
            min_depth: self.min_depth,
            rr_depth: self.rr_depth,
            hide_emitters: self.hide_emitters,
            aovs: self.aovs.clone(),
            pixel_center: self.pixel_center,
            per_light: self.per_light,
            training: self.training,
            seed: self.seed,
            scene_hash: self.scene_hash,
            ..RenderOptions::default()
        }
    }

    fn to_json(&self) -> Value {
        json!({
            "width": self.width,
            "height": self.height,
            "integrator": self.integrator.name(),
            "estimator": self.method.name(),
            "beta": self.params.beta,
            "cutoff": self.params.cutoff,
            "ridge": self.params.ridge_for(self.method),
            "warmup": self.params.warmup,
            "train": self.params.train,
            "techniques": self.techniques.iter().map(|(t, n)| json!([t.name(), n])).collect::<Vec<_>>(),
            "max_depth": self.max_depth,
            "min_depth": self.min_depth,
            "rr_depth": self.rr_depth,
            "hide_emitters": self.hide_emitters,
            "aovs": self.aovs.iter().map(|a| a.name()).collect::<Vec<_>>(),
            "pixel_center": self.pixel_center,
            "per_light": self.per_light,
            "trained_grid": self.training.grid,
            "trained_floor": self.training.floor,
            "trained_spp": self.training.spp,
            "seed": self.seed,
            "scene_hash": format!("{:016x}", self.scene_hash),
        })
    }

    fn from_json(v: &Value) -> Result<Self, String> {
        let field = |k: &str| v.get(k).ok_or_else(|| format!("header lacks {k:?}"));
        let uint = |k: &str| {
            field(k)?
                .as_u64()
                .ok_or_else(|| format!("header {k:?} is not an unsigned integer"))
        };
        let u32_ =
            |k: &str| u32::try_from(uint(k)?).map_err(|_| format!("header {k:?} exceeds 32 bits"));
        let float = |k: &str| {
            field(k)?
                .as_f64()
                .ok_or_else(|| format!("header {k:?} is not a number"))
        };
        let text = |k: &str| {
            field(k)?
                .as_str()
                .ok_or_else(|| format!("header {k:?} is not a string"))
        };
        let list = |k: &str| {
            field(k)?
                .as_array()
                .ok_or_else(|| format!("header {k:?} is not a list"))
        };
        let techniques = list("techniques")?
            .iter()
            .map(|t| {
                let name = t.get(0).and_then(Value::as_str);
                let n = t.get(1).and_then(Value::as_u64);
                match (name, n) {
                    (Some(name), Some(n)) => Ok((
                        Technique::from(
                            name.parse::<scene::TechniqueKind>()
                                .map_err(|e| e.to_string())?,
                        ),
                        u32::try_from(n).map_err(|_| "technique count exceeds 32 bits")?,
                    )),
                    _ => Err(format!("header technique {t} is not [name, count]")),
                }
            })
            .collect::<Result<_, String>>()?;
        let aovs = list("aovs")?
            .iter()
            .map(|a| {
                let name = a.as_str().ok_or("AOV names are strings")?;
                name.parse::<Aov>().map_err(|e| e.to_string())
            })
            .collect::<Result<_, String>>()?;
        Ok(Self {
            width: u32_("width")?,
            height: u32_("height")?,
            integrator: text("integrator")?.parse().map_err(|e| format!("{e}"))?,
            method: text("estimator")?.parse().map_err(|e| format!("{e}"))?,
            params: Params {
                beta: float("beta")?,
                cutoff: float("cutoff")?,
                ridge: Some(float("ridge")?),
                warmup: uint("warmup")?,
                train: uint("train")?,
            },
            techniques,
            max_depth: u32_("max_depth")?,
            // Absent from states written before the option existed: all depths.
            min_depth: match v.get("min_depth") {
                None => 0,
                Some(_) => u32_("min_depth")?,
            },
            rr_depth: u32_("rr_depth")?,
            hide_emitters: field("hide_emitters")?
                .as_bool()
                .ok_or("header \"hide_emitters\" is not a boolean")?,
            aovs,
            // Absent in states written before the option existed: jittered.
            pixel_center: match v.get("pixel_center") {
                None => false,
                Some(b) => b
                    .as_bool()
                    .ok_or("header \"pixel_center\" is not a boolean")?,
            },
            // Absent from states written before per-light mode existed: off.
            per_light: match v.get("per_light") {
                None => 0,
                Some(_) => u32_("per_light")?,
            },
            // Absent from states written before these options existed: the defaults.
            training: {
                let d = scene::Training::default();
                scene::Training {
                    grid: match v.get("trained_grid") {
                        None => d.grid,
                        Some(_) => u32_("trained_grid")?,
                    },
                    floor: match v.get("trained_floor") {
                        None => d.floor,
                        Some(_) => float("trained_floor")?,
                    },
                    spp: match v.get("trained_spp") {
                        None => d.spp,
                        Some(_) => u32_("trained_spp")?,
                    },
                }
            },
            seed: uint("seed")?,
            scene_hash: u64::from_str_radix(text("scene_hash")?, 16)
                .map_err(|e| format!("header \"scene_hash\": {e}"))?,
        })
    }

    /// The first field in which two headers differ, for messages.
    pub fn difference(&self, o: &StateHeader) -> String {
        let (a, b) = (self.to_json(), o.to_json());
        let (a, b) = (a.as_object().unwrap(), b.as_object().unwrap());
        a.iter()
            .find(|(k, v)| b.get(*k) != Some(v))
            .map(|(k, v)| format!("{k} is {v} here and {} there", b[k]))
            .unwrap_or_default()
    }
}

/// Every pixel's sums over a set of sample ranges (module docs).
#[derive(Clone, Debug)]
pub struct RenderState {
    header: StateHeader,
    /// Disjoint, sorted, coalesced sample ranges.
    samples: Vec<Range<u32>>,
    partial: bool,
    record: Record,
    kernel: Option<Kernel>,
    data: Vec<f64>,
}

impl PartialEq for RenderState {
    /// Equal headers, sample ranges, partial flags and records, bit for bit.
    fn eq(&self, o: &Self) -> bool {
        self.header == o.header
            && self.samples == o.samples
            && self.partial == o.partial
            && self.data.len() == o.data.len()
            && self
                .data
                .iter()
                .zip(&o.data)
                .all(|(a, b)| a.to_bits() == b.to_bits())
    }
}

/// Where a state file went wrong.
fn corrupt(what: impl std::fmt::Display) -> Error {
    Error::Corrupt(what.to_string())
}

const MAGIC: &[u8; 8] = b"FREPSTAT";
const VERSION: u32 = 1;

/// FNV-1a, 64 bits: the state file's checksum and the scene hash of states.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// What a state file's first bytes say: the header, checked, and where the records are.
struct Head {
    header: StateHeader,
    samples: Vec<Range<u32>>,
    partial: bool,
    /// Byte offset of the records.
    records: usize,
    /// The file's length the header implies.
    file_len: u64,
}

impl Head {
    /// Parses magic, version, header and word count from the start of a state's bytes
    /// (the records need not be there), checking the header's fields as a render's options
    /// are checked and its word count against its size, before anything is allocated.
    fn parse(bytes: &[u8]) -> Result<Head, Error> {
        let take = |at: usize, n: usize| -> Result<&[u8], Error> {
            bytes
                .get(at..at.checked_add(n).ok_or_else(|| corrupt("truncated"))?)
                .ok_or_else(|| corrupt(format!("truncated at byte {at}")))
        };
        if take(0, 8)? != MAGIC {
            return Err(corrupt("no FREPSTAT magic at the start"));
        }
        let version = u32::from_le_bytes(take(8, 4)?.try_into().unwrap());
        if version != VERSION {
            return Err(corrupt(format!(
                "format version {version}; this frepray reads version {VERSION}"
            )));
        }
        let hlen = u32::from_le_bytes(take(12, 4)?.try_into().unwrap()) as usize;
        let text = std::str::from_utf8(take(16, hlen)?).map_err(corrupt)?;
        let at = 16 + hlen;
        let words = u64::from_le_bytes(take(at, 8)?.try_into().unwrap());
        let v: Value = serde_json::from_str(text).map_err(|e| corrupt(format!("header: {e}")))?;
        let header = StateHeader::from_json(&v).map_err(corrupt)?;
        // The header's options as a render checks them (so that nothing below sizes
        // tables from a depth or light count no render would have).
        let mut o = header.options();
        o.spp = 1;
        o.validate().map_err(|e| corrupt(format!("header: {e}")))?;
        // The header's size against the words present: a header that claims more than
        // the file holds is an error, not an allocation.
        let (record, _, want) = RenderState::layout(&header).map_err(corrupt)?;
        let stride = v.get("stride").and_then(Value::as_u64);
        if stride != Some(record.stride() as u64) || want as u64 != words {
            let stride = stride.map_or("none".into(), |s| s.to_string());
            return Err(corrupt(format!(
                "the records do not match the header ({words} words of stride {stride}; \
                 {}×{} pixels of stride {} need {want})",
                header.width,
                header.height,
                record.stride()
            )));
        }
        let mut samples: Vec<Range<u32>> = Vec::new();
        let ranges = v
            .get("samples")
            .and_then(Value::as_array)
            .ok_or_else(|| corrupt("header lacks \"samples\""))?;
        for r in ranges {
            let bound = |k: usize| {
                r.get(k)
                    .and_then(Value::as_u64)
                    .and_then(|a| u32::try_from(a).ok())
            };
            match (bound(0), bound(1)) {
                (Some(a), Some(b)) if a < b && samples.last().is_none_or(|l| l.end < a) => {
                    samples.push(a..b)
                }
                _ => {
                    return Err(corrupt(format!(
                        "sample range {r} is not an increasing [start, end]"
                    )))
                }
            }
        }
        let file_len = (at as u64 + 16)
            .checked_add(
                words
                    .checked_mul(8)
                    .ok_or_else(|| corrupt("impossible word count"))?,
            )
            .ok_or_else(|| corrupt("impossible word count"))?;
        Ok(Head {
            header,
            samples,
            partial: v.get("partial").and_then(Value::as_bool).unwrap_or(false),
            records: at + 8,
            file_len,
        })
    }
}

impl RenderState {
    /// An empty state (every sum 0) for samples `samples` of a render with `header`.
    /// Errors when the header's options are invalid.
    pub fn new(header: StateHeader, samples: Range<u32>) -> Result<Self, Error> {
        let (record, kernel, words) = Self::layout(&header)?;
        let data = crate::limits::zeroed(words, "the render state")?;
        Ok(Self {
            header,
            samples: if samples.is_empty() {
                vec![]
            } else {
                vec![samples]
            },
            partial: false,
            record,
            kernel,
            data,
        })
    }

    /// A state's record layout, estimator kernel and word count for `header`, nothing
    /// allocated for the sums (so that a file's header can be checked against its size
    /// before they are).
    fn layout(header: &StateHeader) -> Result<(Record, Option<Kernel>, usize), Error> {
        let it = Tally::new(&header.options())?;
        let record = it.record;
        let kernel = it.kernel().cloned();
        let n = header.width as usize * header.height as usize;
        let words = n
            .checked_mul(record.stride())
            .ok_or_else(|| Error::Limit("the render state would not fit in memory".into()))?;
        Ok((record, kernel, words))
    }

    /// What the sums mean.
    pub fn header(&self) -> &StateHeader {
        &self.header
    }
    /// The sample ranges summed (disjoint, sorted, adjacent ones joined).
    pub fn samples(&self) -> &[Range<u32>] {
        &self.samples
    }
    /// Whether some pixel got fewer samples than the ranges say (a stopped render).
    pub fn is_partial(&self) -> bool {
        self.partial
    }
    /// Marks the state as partial (a stopped render).
    pub fn set_partial(&mut self) {
        self.partial = true;
    }
    /// The layout of one pixel's record.
    pub fn record(&self) -> &Record {
        &self.record
    }
    /// Every record, row by row.
    pub fn data(&self) -> &[f64] {
        &self.data
    }
    /// Every record, to write (the render loop fills it).
    pub fn data_mut(&mut self) -> &mut [f64] {
        &mut self.data
    }
    /// The record of pixel (x, y).
    pub fn pixel(&self, x: u32, y: u32) -> &[f64] {
        assert!(
            x < self.header.width && y < self.header.height,
            "pixel outside the image"
        );
        let s = self.record.stride();
        let i = (y as usize * self.header.width as usize + x as usize) * s;
        &self.data[i..i + s]
    }
    /// Samples summed in pixel (x, y).
    pub fn iterations(&self, x: u32, y: u32) -> u64 {
        self.pixel(x, y)[0] as u64
    }

    /// The estimate of one record (module docs).
    fn value(&self, rec: &[f64]) -> Rgb {
        let n = rec[0];
        if n == 0.0 {
            return Rgb::ZERO;
        }
        let o = Record::OUTSIDE;
        let mut v = Rgb::new(rec[o], rec[o + 1], rec[o + 2]) / n;
        if let Some(k) = &self.kernel {
            let mut out = [0.0; 3];
            for i in 0..self.record.blocks() {
                let block = &rec[self.record.block_range(i)];
                let nd = k.iterations(block);
                if nd > 0 {
                    k.estimate(block, &mut out);
                    v += Rgb::from_array(out) * (nd as f64 / n);
                }
            }
        }
        v
    }

    /// What pixel (x, y) holds, for an inspector: its samples, its estimate, and per
    /// MIS block (vertex depth, and light in per-light mode) its iterations, estimate
    /// and the optimal estimators' α ([`mis::Kernel::alpha`]).
    pub fn pixel_detail(&self, x: u32, y: u32) -> PixelDetail {
        let rec = self.pixel(x, y);
        let n = rec[0];
        let o = Record::OUTSIDE;
        let outside = if n > 0.0 {
            Rgb::new(rec[o], rec[o + 1], rec[o + 2]) / n
        } else {
            Rgb::ZERO
        };
        let mut blocks = Vec::new();
        if let Some(k) = &self.kernel {
            for i in 0..self.record.blocks() {
                let block = &rec[self.record.block_range(i)];
                let iterations = k.iterations(block);
                let mut est = [0.0; 3];
                if iterations > 0 {
                    k.estimate(block, &mut est);
                }
                blocks.push(BlockDetail {
                    depth: i / self.record.lights,
                    light: i % self.record.lights,
                    iterations,
                    estimate: Rgb::from_array(est),
                    alpha: (iterations > 0).then(|| k.alpha(block)).flatten(),
                });
            }
        }
        PixelDetail {
            samples: n as u64,
            estimate: self.value(rec),
            outside,
            blocks,
        }
    }

    /// The estimate of pixel (x, y).
    pub fn rgb(&self, x: u32, y: u32) -> Rgb {
        self.value(self.pixel(x, y))
    }

    /// Resolves the sums into an image: the estimate of every pixel and the means of the
    /// AOV channels (pixels without samples are 0).
    pub fn image(&self) -> Image {
        let names: Vec<&str> = self
            .header
            .aovs
            .iter()
            .flat_map(|a| a.channels().iter().copied())
            .collect();
        let (w, h) = (self.header.width, self.header.height);
        let mut img = Image::new(w, h, &names);
        for y in 0..h {
            for x in 0..w {
                let rec = self.pixel(x, y);
                img.set_rgb(x, y, self.value(rec));
                let n = rec[0].max(1.0);
                let mut c = 0;
                for a in &self.header.aovs {
                    for k in 0..a.channels().len() {
                        img.set_aov(x, y, c, rec[Record::AOV + a.offset() + k] / n);
                        c += 1;
                    }
                }
            }
        }
        self.describe(&mut img);
        img
    }

    /// Records in `img`'s EXR attributes what made it: frepray's version, the scene's
    /// hash, the resolved settings (the header as the state file stores it, one JSON
    /// object), the sample ranges and whether the render is partial; the settings also
    /// one by one, for people reading them with `frepray check` or `exrheader`.
    fn describe(&self, img: &mut Image) {
        let h = &self.header;
        let p = scene::ATTRIBUTE_PREFIX;
        let techniques: Vec<String> = h
            .techniques
            .iter()
            .map(|(t, n)| format!("{}:{n}", t.name()))
            .collect();
        let samples: Vec<String> = self
            .samples
            .iter()
            .map(|r| format!("{}..{}", r.start, r.end))
            .collect();
        img.set_attribute("software", format!("frepray {}", env!("CARGO_PKG_VERSION")));
        img.set_attribute(&format!("{p}version"), env!("CARGO_PKG_VERSION"));
        img.set_attribute(&format!("{p}scene_hash"), format!("{:016x}", h.scene_hash));
        img.set_attribute(&format!("{p}settings"), h.to_json().to_string());
        img.set_attribute(&format!("{p}integrator"), h.integrator.name());
        img.set_attribute(&format!("{p}estimator"), h.method.name());
        img.set_attribute(&format!("{p}techniques"), techniques.join(","));
        img.set_attribute(&format!("{p}seed"), h.seed.to_string());
        img.set_attribute(&format!("{p}samples"), samples.join(","));
        img.set_attribute(
            &format!("{p}partial"),
            if self.partial { "yes" } else { "no" },
        );
    }

    /// Adds the sums of `other`, a state of the same header over disjoint samples.
    pub fn merge(&mut self, other: &RenderState) -> Result<(), Error> {
        if self.header != other.header {
            return Err(Error::Mismatch(self.header.difference(&other.header)));
        }
        let mut all: Vec<Range<u32>> = self.samples.iter().chain(&other.samples).cloned().collect();
        all.sort_by_key(|r| r.start);
        let mut joined: Vec<Range<u32>> = Vec::new();
        for r in all {
            match joined.last_mut() {
                Some(last) if r.start < last.end => return Err(Error::Overlap(last.clone(), r)),
                Some(last) if r.start == last.end => last.end = r.end,
                _ => joined.push(r),
            }
        }
        let s = self.record.stride();
        let mis_from = Record::AOV + self.record.aov;
        for (a, b) in self
            .data
            .chunks_exact_mut(s)
            .zip(other.data.chunks_exact(s))
        {
            for (x, y) in a[..mis_from].iter_mut().zip(&b[..mis_from]) {
                *x += y;
            }
            if let Some(k) = &self.kernel {
                for i in 0..self.record.blocks() {
                    let r = self.record.block_range(i);
                    k.merge(&mut a[r.clone()], &b[r]);
                }
            }
        }
        self.samples = joined;
        self.partial |= other.partial;
        Ok(())
    }

    /// The state as bytes in the documented format (module docs).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut header = self.header.to_json();
        let h = header.as_object_mut().expect("an object");
        h.insert(
            "samples".into(),
            self.samples
                .iter()
                .map(|r| json!([r.start, r.end]))
                .collect(),
        );
        h.insert("partial".into(), json!(self.partial));
        h.insert("stride".into(), json!(self.record.stride()));
        let text = header.to_string();
        let mut out = Vec::with_capacity(32 + text.len() + 8 * self.data.len());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&(text.len() as u32).to_le_bytes());
        out.extend_from_slice(text.as_bytes());
        out.extend_from_slice(&(self.data.len() as u64).to_le_bytes());
        for v in &self.data {
            out.extend_from_slice(&v.to_le_bytes());
        }
        let hash = fnv1a(&out);
        out.extend_from_slice(&hash.to_le_bytes());
        out
    }

    /// Reads a state from bytes in the documented format; every inconsistency is an error
    /// that says what is wrong. Nothing is allocated for the records before the header
    /// has been checked against the bytes present, and the sample counts are checked
    /// after (a hand-made state with NaN or negative counts would resolve to nonsense).
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, Error> {
        let head = Head::parse(bytes)?;
        if bytes.len() as u64 != head.file_len {
            return Err(corrupt(format!(
                "{} bytes, the header says {}",
                bytes.len(),
                head.file_len
            )));
        }
        let end = bytes.len() - 8;
        let stored = u64::from_le_bytes(bytes[end..].try_into().unwrap());
        if stored != fnv1a(&bytes[..end]) {
            return Err(corrupt("checksum mismatch (the file is damaged)"));
        }
        let mut state = RenderState::new(head.header, 0..0).map_err(corrupt)?;
        state.samples = head.samples;
        state.partial = head.partial;
        for (d, c) in state
            .data
            .iter_mut()
            .zip(bytes[head.records..end].chunks_exact(8))
        {
            *d = f64::from_le_bytes(c.try_into().unwrap());
        }
        state.check_counts()?;
        Ok(state)
    }

    /// Checks every pixel's sample count N (and each MIS block's) against the sample
    /// ranges: whole numbers, 0 ≤ N_block ≤ N ≤ the samples of the ranges.
    fn check_counts(&self) -> Result<(), Error> {
        let total: u64 = self
            .samples
            .iter()
            .map(|r| u64::from(r.end - r.start))
            .sum();
        let whole = |v: f64, most: f64| v.fract() == 0.0 && (0.0..=most).contains(&v);
        let s = self.record.stride();
        for (k, rec) in self.data.chunks_exact(s).enumerate() {
            let (x, y) = (
                k % self.header.width as usize,
                k / self.header.width as usize,
            );
            let n = rec[0];
            if !whole(n, total as f64) {
                return Err(corrupt(format!(
                    "pixel ({x}, {y}) holds {n} samples; its ranges have {total}"
                )));
            }
            if let Some(kernel) = &self.kernel {
                for b in 0..self.record.blocks() {
                    let block = &rec[self.record.block_range(b)];
                    let counts = kernel.count_words(block);
                    if !counts.iter().all(|&c| whole(c, n)) || kernel.iterations(block) as f64 > n {
                        return Err(corrupt(format!(
                            "pixel ({x}, {y}), MIS block {b}: sample counts {counts:?} \
                             against the pixel's {n}"
                        )));
                    }
                }
            }
        }
        Ok(())
    }

    /// Writes the state to `path` (whole or not at all).
    pub fn write(&self, path: impl AsRef<Path>) -> Result<(), Error> {
        let (path, bytes) = (path.as_ref(), self.to_bytes());
        write_atomically(path, |w| w.write_all(&bytes)).map_err(|source| Error::Io {
            path: path.into(),
            source,
        })
    }

    /// Reads a state written by [`RenderState::write`]; errors name the file. Only a
    /// regular file is read (a FIFO would block, a device never end), only once its
    /// first bytes are a state's magic (a large file of another kind is not read whole),
    /// only when its size is what its header says, and only when that fits in the
    /// memory available ([`crate::limits::memory_limit`]): every check before the
    /// records are read.
    pub fn read(path: impl AsRef<Path>) -> Result<Self, Error> {
        use std::io::Read as _;
        let path = path.as_ref();
        let in_file = |e: Error| Error::InFile {
            path: path.into(),
            source: Box::new(e),
        };
        let io = |source| Error::Io {
            path: path.into(),
            source,
        };
        // Checked before opening: opening a FIFO for reading blocks until a writer comes.
        let meta = std::fs::metadata(path).map_err(io)?;
        if !meta.is_file() {
            return Err(in_file(corrupt("not a regular file")));
        }
        let mut file = std::fs::File::open(path).map_err(io)?;
        let mut bytes = Vec::new();
        let mut more =
            |bytes: &mut Vec<u8>, n: u64| (&mut file).take(n).read_to_end(bytes).map(|_| ());
        more(&mut bytes, 16).map_err(io)?;
        if bytes.len() < 16 || &bytes[..8] != MAGIC {
            return Self::from_bytes(&bytes).map_err(in_file);
        }
        let hlen = u32::from_le_bytes(bytes[12..16].try_into().unwrap());
        if u64::from(hlen) + 24 > meta.len() {
            return Self::from_bytes(&bytes).map_err(in_file);
        }
        more(&mut bytes, u64::from(hlen) + 8).map_err(io)?;
        let head = Head::parse(&bytes).map_err(in_file)?;
        if meta.len() != head.file_len {
            return Err(in_file(corrupt(format!(
                "the file is {} bytes, its header says {}",
                meta.len(),
                head.file_len
            ))));
        }
        let (limit, what) = crate::limits::memory_limit(0);
        if head.file_len > limit {
            return Err(in_file(Error::Limit(format!(
                "the state is {} ({} bytes), more than the {what} ({})",
                crate::limits::bytes(head.file_len),
                head.file_len,
                crate::limits::bytes(limit)
            ))));
        }
        bytes.reserve_exact((head.file_len as usize).saturating_sub(bytes.len()));
        file.read_to_end(&mut bytes).map_err(io)?;
        Self::from_bytes(&bytes).map_err(in_file)
    }

    /// A one-line summary: size, estimator, samples.
    pub fn summary(&self) -> String {
        let mut s = format!(
            "{}×{} {} {} seed {}, samples",
            self.header.width,
            self.header.height,
            self.header.integrator,
            self.header.method,
            self.header.seed
        );
        for r in &self.samples {
            let _ = write!(s, " {}..{}", r.start, r.end);
        }
        if self.partial {
            s.push_str(" (partial)");
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An image's `frepray.settings` attribute is its state's header: it reads back as
    /// the same header; the samples, partial flag and scene hash are recorded beside it.
    #[test]
    fn an_image_records_its_header() {
        let o = RenderOptions {
            seed: 9,
            scene_hash: 0xabc,
            ..RenderOptions::default()
        };
        let mut s = RenderState::new(StateHeader::new(4, 3, &o), 2..5).unwrap();
        s.set_partial();
        let img = s.image();
        let v: Value = serde_json::from_str(img.attribute("frepray.settings").unwrap()).unwrap();
        assert_eq!(StateHeader::from_json(&v).unwrap(), *s.header());
        assert_eq!(img.attribute("frepray.samples"), Some("2..5"));
        assert_eq!(img.attribute("frepray.partial"), Some("yes"));
        assert_eq!(img.attribute("frepray.seed"), Some("9"));
        assert_eq!(
            img.attribute("frepray.scene_hash"),
            Some("0000000000000abc")
        );
    }
}
