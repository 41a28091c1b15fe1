//! The readers under test, their seed corpora (every shipped file of the kind, and the
//! examples in the docs) and the sandbox scenes resolve against.

use frep::read::{read_str, Format};
use scene::SceneFormat;
use std::path::{Path, PathBuf};

/// Seeds larger than this are skipped: they slow every mutant down and add little.
const MAX_SEED: u64 = 200 << 10;

/// One reader.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// `.frep` models.
    Frep,
    /// HyperFun `.hf` models.
    Hf,
    /// Fidget `.vm` tapes.
    Vm,
    /// TOML scene text to a description (the text reader alone: fast).
    Toml,
    /// JSON scene text to a description.
    Json,
    /// TOML scenes parsed and resolved (models read, bounds computed: about 1 ms each).
    TomlResolve,
    /// JSON scenes parsed and resolved, and resolved again as data (`load_value`).
    JsonResolve,
    /// Render-state files (`RenderState::from_bytes`), each input also with its checksum
    /// made valid, so that mutants reach the header and the records.
    State,
    /// Fails on purpose as `$FUZZ_SELFTEST` says (panic, slow, memory, stack), to show
    /// that each guard catches and saves its input (`run.sh selftest`).
    SelfTest,
}

impl Target {
    /// Every target, in the order `run.sh all` takes them.
    pub const ALL: [Target; 8] = [
        Target::Frep,
        Target::Hf,
        Target::Vm,
        Target::Toml,
        Target::Json,
        Target::TomlResolve,
        Target::JsonResolve,
        Target::State,
    ];

    /// The target named on the command line.
    pub fn from_name(s: &str) -> Option<Target> {
        let all = Target::ALL.into_iter().chain([Target::SelfTest]);
        all.into_iter().find(|t| t.name() == s)
    }

    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Target::TomlResolve => "toml-resolve",
            Target::JsonResolve => "json-resolve",
            Target::SelfTest => "selftest",
            t => t.ext(),
        }
    }

    /// The extension of its files, and the language of the docs' code blocks it reads.
    fn ext(self) -> &'static str {
        match self {
            Target::Frep => "frep",
            Target::Hf => "hf",
            Target::Vm => "vm",
            Target::Toml | Target::TomlResolve => "toml",
            Target::State => "state",
            Target::Json | Target::JsonResolve => "json",
            Target::SelfTest => "selftest",
        }
    }
}

/// The repository root (the fuzzer lives in `ROOT/fuzz`).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every shipped file of the target's kind under `models/` and `scenes/`, and the docs'
/// code blocks in its language.
pub fn seeds(t: Target) -> Vec<Vec<u8>> {
    if t == Target::SelfTest {
        return vec![std::env::var("FUZZ_SELFTEST")
            .unwrap_or_default()
            .into_bytes()];
    }
    if t == Target::State {
        return state_seeds();
    }
    let r = root();
    let mut files = Vec::new();
    for dir in [r.join("models"), r.join("scenes")] {
        walk(&dir, &mut files);
    }
    files.sort();
    let mut out: Vec<Vec<u8>> = files
        .iter()
        .filter(|p| p.extension().and_then(|e| e.to_str()) == Some(t.ext()))
        .filter(|p| std::fs::metadata(p).is_ok_and(|m| m.len() <= MAX_SEED))
        .filter_map(|p| std::fs::read(p).ok())
        .collect();
    let mut docs = Vec::new();
    walk(&r.join("docs"), &mut docs);
    docs.sort();
    for d in docs
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
    {
        out.extend(fenced(
            &std::fs::read_to_string(d).unwrap_or_default(),
            t.ext(),
        ));
    }
    out
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            walk(&p, out);
        } else {
            out.push(p);
        }
    }
}

/// The bodies of the ```` ```lang ```` blocks of a Markdown text.
fn fenced(md: &str, lang: &str) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    let mut body: Option<String> = None;
    for line in md.lines() {
        let l = line.trim_start();
        match &mut body {
            None if l.strip_prefix("```") == Some(lang) => body = Some(String::new()),
            Some(b) if l.starts_with("```") => {
                out.push(std::mem::take(b).into_bytes());
                body = None;
            }
            Some(b) => {
                b.push_str(line);
                b.push('\n');
            }
            None => {}
        }
    }
    out
}

/// A scratch folder holding what the seed scenes refer to (their models and the sky
/// map), so that scenes resolve as shipped; removed on drop.
pub struct Sandbox {
    /// The folder; scenes are parsed as if they were `dir/scene.EXT`.
    pub dir: PathBuf,
}

impl Sandbox {
    /// Copies `scenes/` (with its `models/`) and the shipped models into a new folder.
    pub fn new() -> Sandbox {
        let dir = std::env::temp_dir().join(format!("frepray-fuzz-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("models")).unwrap();
        let r = root();
        let mut files = Vec::new();
        walk(&r.join("scenes"), &mut files);
        for f in &files {
            let rel = f.strip_prefix(r.join("scenes")).unwrap();
            let to = dir.join(rel);
            std::fs::create_dir_all(to.parent().unwrap()).unwrap();
            std::fs::copy(f, &to).unwrap();
        }
        let mut models = Vec::new();
        walk(&r.join("models"), &mut models);
        for f in models {
            if std::fs::metadata(&f).is_ok_and(|m| m.len() <= MAX_SEED) {
                let _ = std::fs::copy(&f, dir.join("models").join(f.file_name().unwrap()));
            }
        }
        Sandbox { dir }
    }
}

impl Drop for Sandbox {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// Runs the target's reader on one input; errors are the expected outcome, only panics
/// (caught by the caller), hangs and unbounded memory are bugs.
pub fn run(t: Target, input: &[u8], sandbox: &Path) {
    let text = String::from_utf8_lossy(input);
    match t {
        Target::Frep => drop(read_str(&text, Format::Frep, "fuzz.frep")),
        Target::Hf => drop(read_str(&text, Format::HyperFun, "fuzz.hf")),
        Target::Vm => drop(read_str(&text, Format::Vm, "fuzz.vm")),
        Target::Toml => drop(scene::parse_description(&text, SceneFormat::Toml, "f.toml")),
        Target::Json => drop(scene::parse_description(&text, SceneFormat::Json, "f.json")),
        Target::TomlResolve => drop(scene::parse(
            &text,
            SceneFormat::Toml,
            &sandbox.join("scene.toml"),
        )),
        Target::JsonResolve => {
            drop(scene::parse(
                &text,
                SceneFormat::Json,
                &sandbox.join("scene.json"),
            ));
            if let Ok(v) = serde_json::from_str::<serde_json::Value>(&text) {
                drop(scene::load_value(v, sandbox));
            }
        }
        Target::State => {
            read_state(input);
            // The same bytes with a valid checksum (what a crafted file would have), so
            // that mutants get past it to the header and the records; and, when an edit
            // moved the word count (text inserted into or cut from the header), with the
            // header length made to match as well.
            if let Some(fixed) = with_checksum(input) {
                read_state(&fixed);
                if let Some(relen) = with_header_length(&fixed) {
                    read_state(&relen);
                }
            }
        }
        Target::SelfTest => self_test(input),
    }
}

/// `bytes` with the last 8 replaced by the FNV-1a of the others (None when shorter).
fn with_checksum(bytes: &[u8]) -> Option<Vec<u8>> {
    let body = &bytes[..bytes.len().checked_sub(8)?];
    let mut fixed = body.to_vec();
    fixed.extend_from_slice(&render::fnv1a(body).to_le_bytes());
    Some(fixed)
}

/// A state's bytes (checksum valid) whose header length field (bytes 12..16) is wrong
/// for where its word count now lies, with that field and the checksum fixed: the word
/// count is the first u64 at or after byte 16 that counts exactly the 8-byte words
/// between it and the checksum. None when there is none or the field already fits.
fn with_header_length(bytes: &[u8]) -> Option<Vec<u8>> {
    let len = bytes.len();
    let stored = u32::from_le_bytes(bytes.get(12..16)?.try_into().ok()?) as usize;
    let at = (16..=len.checked_sub(24)?)
        .filter(|&p| (len - 16 - p).is_multiple_of(8))
        .find(|&p| {
            let w = u64::from_le_bytes(bytes[p..p + 8].try_into().unwrap());
            w == ((len - 16 - p) / 8) as u64
        })?;
    let hlen = u32::try_from(at - 16).ok()?;
    if hlen as usize == stored {
        return None;
    }
    let mut fixed = bytes.to_vec();
    fixed[12..16].copy_from_slice(&hlen.to_le_bytes());
    with_checksum(&fixed)
}

/// The header text and the record bytes of a state's bytes that read.
fn parts(bytes: &[u8]) -> (&[u8], &[u8]) {
    let hlen = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    (&bytes[16..16 + hlen], &bytes[24 + hlen..bytes.len() - 8])
}

/// Reads a state; one that reads must write itself back as it was read and resolve.
/// Properties: the records are written back bit for bit; the whole file is, when its
/// header is already in the written form (compact JSON, keys sorted, every field, as
/// `to_bytes` makes: every seed); what `to_bytes` writes reads back to an equal state
/// and is written again unchanged. (Other JSON spellings of a header are valid and are
/// rewritten in that form, so the bytes of every accepted input need not come back.)
fn read_state(bytes: &[u8]) {
    let Ok(s) = render::RenderState::from_bytes(bytes) else {
        return;
    };
    let out = s.to_bytes();
    let ((text_in, rec_in), (text_out, rec_out)) = (parts(bytes), parts(&out));
    assert!(
        rec_in == rec_out,
        "the records did not come back bit for bit"
    );
    if text_in == text_out {
        assert!(
            out == bytes,
            "a state in the written form did not come back byte for byte"
        );
    }
    let again = match render::RenderState::from_bytes(&out) {
        Ok(a) => a,
        Err(e) => panic!("a state's own bytes do not read: {e}"),
    };
    assert!(
        again == s,
        "a state's round trip changed it: {:?} became {:?}",
        s.header(),
        again.header()
    );
    assert!(
        again.to_bytes() == out,
        "a state's bytes changed when written again"
    );
    let _ = s.summary();
    if u64::from(s.header().width) * u64::from(s.header().height) <= 4096 {
        let _ = s.image();
    }
}

/// The seed renders' scene: a diffuse ball filling the view, on a floor, under a sphere
/// light and a rectangle light (two MIS lights), at `w` × `h` pixels.
fn seed_scene(w: u32, h: u32) -> render::scene::Scene {
    let text = format!(
        r#"
camera = {{ eye = [0, -2.5, 0.3], target = [0, 0, 0], fov = 30, resolution = [{w}, {h}] }}
materials.white = {{ type = "diffuse", reflectance = 0.8 }}
objects = [
  {{ solid = "sphere([0, 0, 0], 1)", material = "white" }},
  {{ solid = "box([0, 0, -1.05], [8, 8, 0.1])", material = "white" }},
]
lights = [
  {{ type = "sphere", center = [0, -2, 3], radius = 0.5, power = 100 }},
  {{ type = "rect", center = [1, 0, 3], size = [0.5, 0.5], normal = [0, 0, -1], power = 50 }},
]
"#
    );
    render::scene::parse_scene(
        &text,
        render::scene::SceneFormat::Toml,
        Path::new("seed.toml"),
    )
    .expect("the seed scene")
    .0
}

/// Real states of tiny renders (each within the mutants' 4 kB): every integrator,
/// estimator, technique and AOV name, per-light mode, light training, the optional
/// header fields away from their defaults, a merge of two ranges and a partial state,
/// so that the header's JSON (text the mutator edits, and the source of its tokens)
/// holds every name and field a state can have.
fn state_seeds() -> Vec<Vec<u8>> {
    use mis::Method as M;
    use render::integrator::{Aov, IntegratorKind as I, RenderOptions};
    use scene::TechniqueKind as T;
    let tech =
        |ts: &[T]| -> Vec<(render::Technique, u32)> { ts.iter().map(|&t| (t.into(), 1)).collect() };
    let base = |integrator, method, ts: &[T]| RenderOptions {
        integrator,
        method,
        techniques: tech(ts),
        max_depth: 2,
        threads: 1,
        ..RenderOptions::default()
    };
    let two = [T::Bsdf, T::LightPower];
    // (width, height, options, samples rendered)
    let mut runs = vec![
        (3, 2, base(I::Direct, M::Balance, &two), 0..2),
        (
            3,
            2,
            RenderOptions {
                aovs: vec![Aov::Depth],
                ..base(
                    I::Direct,
                    M::OptimalUncorrelated,
                    &[T::LightPower, T::LightArea, T::Bsdf],
                )
            },
            0..4,
        ),
        (
            3,
            2,
            RenderOptions {
                aovs: vec![Aov::Normal, Aov::Albedo],
                ..base(I::Path, M::OptimalDirect, &two)
            },
            0..2,
        ),
        (
            2,
            1,
            RenderOptions {
                per_light: 2,
                params: mis::Params {
                    warmup: 1,
                    ..Default::default()
                },
                ..base(I::Path, M::OptimalProgressive, &[T::LightUniform, T::Bsdf])
            },
            0..3,
        ),
        (
            3,
            2,
            RenderOptions {
                params: mis::Params {
                    beta: 3.0,
                    ..Default::default()
                },
                hide_emitters: true,
                pixel_center: true,
                seed: 7,
                scene_hash: 0x0123_4567_89ab_cdef,
                ..base(I::Path, M::Power, &[T::LightSpatial, T::CosineHemisphere])
            },
            3..5,
        ),
        (
            3,
            2,
            RenderOptions {
                min_depth: 1,
                params: mis::Params {
                    cutoff: 0.25,
                    ridge: Some(0.5),
                    ..Default::default()
                },
                ..base(I::Direct, M::Cutoff, &[T::Light(0), T::Light(1), T::Bsdf])
            },
            0..2,
        ),
        (
            3,
            2,
            base(I::Direct, M::Maximum, &[T::LightArea, T::Bsdf]),
            0..1,
        ),
        (
            2,
            2,
            RenderOptions {
                training: scene::Training {
                    grid: 2,
                    floor: 0.25,
                    spp: 1,
                },
                params: mis::Params {
                    train: 1,
                    ..Default::default()
                },
                ..base(I::Direct, M::OptimalFull, &[T::LightTrained, T::Bsdf])
            },
            0..2,
        ),
    ];
    for i in [I::Depth, I::Normals, I::Albedo] {
        runs.push((3, 2, base(i, M::Balance, &two), 0..1));
    }
    let stop = std::sync::atomic::AtomicBool::new(false);
    let render = |w, h, o: &RenderOptions, r| {
        render::render_range(&seed_scene(w, h), o, r, &stop, &|_, _| {})
            .expect("a seed render")
            .0
    };
    let mut out = Vec::new();
    for (w, h, o, r) in &runs {
        out.push(render(*w, *h, o, r.clone()).to_bytes());
    }
    // Two ranges merged, and a stopped render's state.
    let (o, r) = (&runs[0].2, 4..6);
    let mut merged = render(3, 2, o, 0..2);
    merged.merge(&render(3, 2, o, r)).expect("a seed merge");
    out.push(merged.to_bytes());
    let mut partial = render(3, 2, o, 0..3);
    partial.set_partial();
    out.push(partial.to_bytes());
    out
}

fn self_test(input: &[u8]) {
    match input {
        b"panic" => panic!("selftest"),
        b"slow" => {
            // 1.1 s of CPU time, the measure of a hang.
            let t = crate::guard::thread_cpu();
            while crate::guard::thread_cpu() - t < std::time::Duration::from_millis(1100) {
                std::hint::black_box(0);
            }
        }
        b"memory" => drop(std::hint::black_box(vec![1u8; 2 << 30])),
        b"stack" => drop(deep(std::hint::black_box(1 << 40))),
        _ => {}
    }
}

/// Recursion without bound (a stack overflow).
fn deep(n: u64) -> u64 {
    let pad = std::hint::black_box([n; 64]);
    if n == 0 {
        0
    } else {
        deep(n - 1).wrapping_add(pad[3])
    }
}
