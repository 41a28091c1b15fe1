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
    /// Fails on purpose as `$FUZZ_SELFTEST` says (panic, slow, memory, stack), to show
    /// that each guard catches and saves its input (`run.sh selftest`).
    SelfTest,
}

impl Target {
    /// Every target, in the order `run.sh all` takes them.
    pub const ALL: [Target; 7] = [
        Target::Frep,
        Target::Hf,
        Target::Vm,
        Target::Toml,
        Target::Json,
        Target::TomlResolve,
        Target::JsonResolve,
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
            Target::Json | Target::JsonResolve => "json",
            Target::SelfTest => "selftest",
        }
    }
}

/// The repository root (the fuzzer lives in `ROOT/fuzz`).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every shipped file of the target's kind under `models/`, `scenes/` and the shared
/// models (`../shared/models`), and the docs' code blocks in its language.
pub fn seeds(t: Target) -> Vec<Vec<u8>> {
    if t == Target::SelfTest {
        return vec![std::env::var("FUZZ_SELFTEST")
            .unwrap_or_default()
            .into_bytes()];
    }
    let r = root();
    let mut files = Vec::new();
    for dir in [
        r.join("models"),
        r.join("scenes"),
        r.join("../shared/models"),
    ] {
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
        walk(&r.join("../shared/models"), &mut models);
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
        Target::SelfTest => self_test(input),
    }
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
