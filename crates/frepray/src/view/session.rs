//! The viewer's render: passes of doubling sample counts into one state, the latest
//! pass published as a [`Snapshot`], restarted when a file it reads changes or the page
//! asks for another estimator.
//!
//! Each pass's samples are split between two states, A and B (disjoint sample ranges of
//! one render, merged for display): the difference of their estimates gives each
//! pixel's standard error without second moments, `|a − b| √(n_a n_b) / (n_a + n_b)`
//! (Var(a − b) = σ²(1/n_a + 1/n_b), Var(mean) = σ²/(n_a + n_b)): a one-degree-of-freedom
//! estimate, noisy pixel by pixel but unbiased.

use crate::{Error, Image, RenderOptions, RenderState, RenderStats, Scene, Settings};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::{Duration, Instant, SystemTime};

/// The most samples per pixel one pass renders (later passes stay this size).
pub const MAX_PASS: u32 = 64;

/// A scene or model that failed to load: where, and what was expected.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LoadError {
    /// The message, as the command line prints it.
    pub message: String,
    /// The file (empty when unknown).
    pub file: String,
    /// 1-based line (0: none).
    pub line: usize,
    /// 1-based column (0: none).
    pub column: usize,
}

/// What the page shows: the latest pass, or the latest error beside the last good image.
#[derive(Default)]
pub struct Snapshot {
    /// Bumped at every change; the page reloads the image when it moves.
    pub version: u64,
    /// Bumped at every restart (a new scene or estimator).
    pub generation: u64,
    /// The merged state of the finished passes.
    pub state: Option<RenderState>,
    /// Its image (colour and AOVs), resolved once per pass.
    pub image: Option<Image>,
    /// Per pixel, the standard error of the luminance (module docs); empty before two
    /// passes.
    pub stderr: Vec<f32>,
    /// With the decomposition on, the same from a render with every camera ray through
    /// its pixel's centre: the directions' share of the error, without the pixel
    /// footprint's (as `experiment --decompose` splits it); else empty.
    pub stderr_centered: Vec<f32>,
    /// Samples per pixel rendered and aimed at.
    pub spp: (u32, u32),
    /// Passes finished in this generation.
    pub passes: u32,
    /// The render's statistics, summed over its passes.
    pub seconds: f64,
    /// Samples and rays rendered in this generation.
    pub samples: u64,
    /// Rays traced in this generation.
    pub rays: u64,
    /// The estimator rendering, and its techniques (names with draws).
    pub estimator: String,
    /// The techniques, as `name:draws`.
    pub techniques: Vec<String>,
    /// The latest load error (cleared by a good load).
    pub error: Option<LoadError>,
    /// The files the render reads (the scene and what it names), watched for edits.
    pub inputs: Vec<PathBuf>,
}

/// The render's shared state: the snapshot, its condition variable, and the flags that
/// interrupt a pass.
pub struct Session {
    /// The scene or model file.
    pub input: PathBuf,
    /// The command line's settings (the estimator may be replaced by the page).
    pub settings: Mutex<Settings>,
    /// The latest snapshot.
    pub snap: Mutex<Snapshot>,
    /// Signalled when the snapshot changes.
    pub changed: Condvar,
    /// Set to end the current pass early: a restart is due.
    pub interrupt: AtomicBool,
    /// Set to restart (a file changed, another estimator).
    pub restart: AtomicBool,
    /// Set to stop the viewer.
    pub stop: AtomicBool,
    /// Also render every pass with rays through pixel centres, to split each pixel's
    /// variance into the footprint's and the directions' parts (twice the work).
    pub decompose: bool,
}

impl Session {
    /// A session over `input` with `settings`; `decompose`: see [`Session::decompose`].
    pub fn new(input: PathBuf, settings: Settings, decompose: bool) -> Session {
        Session {
            decompose,
            input,
            settings: Mutex::new(settings),
            snap: Mutex::new(Snapshot::default()),
            changed: Condvar::new(),
            interrupt: AtomicBool::new(false),
            restart: AtomicBool::new(false),
            stop: AtomicBool::new(false),
        }
    }

    /// Asks for a restart (the current pass ends early).
    pub fn request_restart(&self) {
        self.restart.store(true, Ordering::SeqCst);
        self.interrupt.store(true, Ordering::SeqCst);
    }

    /// Stops the render and wakes every waiting page.
    pub fn shut_down(&self) {
        self.stop.store(true, Ordering::SeqCst);
        self.interrupt.store(true, Ordering::SeqCst);
        self.changed.notify_all();
    }

    fn publish(&self, f: impl FnOnce(&mut Snapshot)) {
        let mut s = self.snap.lock().unwrap_or_else(|e| e.into_inner());
        f(&mut s);
        s.version += 1;
        drop(s);
        self.changed.notify_all();
    }

    /// Renders until stopped: loads, renders passes, waits for a change, again.
    pub fn run(&self) {
        let mut generation = 0;
        while !self.stop.load(Ordering::SeqCst) {
            self.restart.store(false, Ordering::SeqCst);
            self.interrupt.store(false, Ordering::SeqCst);
            generation += 1;
            match self.load() {
                Ok((scene, options)) => {
                    let inputs = inputs_of(&self.input, &scene);
                    self.publish(|s| {
                        s.error = None;
                        s.inputs = inputs;
                    });
                    if let Err(e) = self.render(&scene, &options, generation) {
                        self.publish(|s| s.error = Some(plain_error(&e.to_string())));
                    }
                }
                Err(e) => self.publish(|s| {
                    s.error = Some(e);
                    if s.inputs.is_empty() {
                        s.inputs = vec![self.input.clone()];
                    }
                }),
            }
            // Idle until a restart or the end.
            while !self.stop.load(Ordering::SeqCst) && !self.restart.load(Ordering::SeqCst) {
                std::thread::sleep(Duration::from_millis(50));
            }
        }
    }

    /// The scene (or a model's preview scene) and its render options.
    fn load(&self) -> Result<(Scene, RenderOptions), LoadError> {
        let settings = self
            .settings
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone();
        let is_scene = matches!(
            self.input
                .extension()
                .and_then(|e| e.to_str())
                .map(str::to_ascii_lowercase)
                .as_deref(),
            Some("toml" | "json")
        );
        if is_scene {
            let scene =
                crate::load_with(&self.input, &settings.overrides).map_err(|e| match &e {
                    Error::Scene(se) => LoadError {
                        message: e.to_string(),
                        file: se.file.clone(),
                        line: se.line,
                        column: se.column,
                    },
                    _ => plain_error(&e.to_string()),
                })?;
            let (options, _) = scene
                .options_with(&settings)
                .map_err(|e| plain_error(&e.to_string()))?;
            return Ok((scene, options));
        }
        let model = crate::preview::load(&self.input).map_err(|e| match &e {
            Error::Read(r) => LoadError {
                message: e.to_string(),
                file: r.file.clone(),
                line: r.line,
                column: r.column,
            },
            _ => plain_error(&e.to_string()),
        })?;
        let o = &settings.overrides;
        let preview = crate::preview::PreviewOptions {
            width: o.width.unwrap_or(512),
            height: o.height.unwrap_or(512),
            spp: o.spp.unwrap_or(64),
            ..Default::default()
        };
        let scene = crate::preview::model_scene(model, &preview)
            .map_err(|e| plain_error(&e.to_string()))?;
        let options = scene.options().map_err(|e| plain_error(&e.to_string()))?;
        Ok((scene, options))
    }

    /// Renders passes of 1, 1, 2, 4, … samples (at most [`MAX_PASS`]) up to the
    /// options' spp, publishing each; returns early on an interrupt.
    fn render(&self, scene: &Scene, options: &RenderOptions, generation: u64) -> Result<(), Error> {
        let target = options.spp.max(1);
        let techniques: Vec<String> = options
            .techniques
            .iter()
            .map(|(t, n)| format!("{}:{n}", t.name()))
            .collect();
        self.publish(|s| {
            s.generation = generation;
            s.state = None;
            s.passes = 0;
            s.spp = (0, target);
            s.seconds = 0.0;
            s.samples = 0;
            s.rays = 0;
            s.estimator = options.method.name().to_string();
            s.techniques = techniques;
            s.stderr.clear();
            s.stderr_centered.clear();
        });
        let centered = RenderOptions {
            pixel_center: true,
            ..options.clone()
        };
        let (mut a, mut b): (Option<RenderState>, Option<RenderState>) = (None, None);
        let (mut c, mut d): (Option<RenderState>, Option<RenderState>) = (None, None);
        let (mut done, mut pass) = (0u32, 0u32);
        while done < target {
            let n = match pass {
                0 | 1 => 1,
                _ => done.min(MAX_PASS),
            }
            .min(target - done);
            // Both halves of the pass (the first passes: one sample, to A then to B).
            let na = match pass {
                0 => n,
                1 => 0,
                _ => n.div_ceil(2),
            };
            let started = Instant::now();
            let mut stats: Vec<RenderStats> = Vec::new();
            let mut halves = vec![
                (options, done..done + na, &mut a),
                (options, done + na..done + n, &mut b),
            ];
            if self.decompose {
                halves.push((&centered, done..done + na, &mut c));
                halves.push((&centered, done + na..done + n, &mut d));
            }
            for (o, range, half) in halves {
                if range.is_empty() {
                    continue;
                }
                let (part, st) = scene.render_with(o, range, &self.interrupt, &|_, _| {})?;
                if st.stopped {
                    return Ok(());
                }
                stats.push(st);
                match half {
                    Some(h) => h.merge(&part)?,
                    None => *half = Some(part),
                }
            }
            done += n;
            pass += 1;
            let mut merged = a.clone().expect("the first pass renders into A");
            if let Some(b) = &b {
                merged.merge(b)?;
            }
            let image = merged.image();
            let stderr = match (&a, &b) {
                (Some(a), Some(b)) => standard_errors(a, b),
                _ => Vec::new(),
            };
            let stderr_centered = match (&c, &d) {
                (Some(c), Some(d)) => standard_errors(c, d),
                _ => Vec::new(),
            };
            let seconds = started.elapsed().as_secs_f64();
            self.publish(|s| {
                s.passes = pass;
                s.spp = (done, target);
                s.seconds += seconds;
                s.samples += stats.iter().map(|t| t.samples).sum::<u64>();
                s.rays += stats.iter().map(|t| t.rays.total()).sum::<u64>();
                s.image = Some(image);
                s.stderr = stderr;
                s.stderr_centered = stderr_centered;
                s.state = Some(merged);
            });
            if self.interrupt.load(Ordering::SeqCst) {
                return Ok(());
            }
        }
        Ok(())
    }
}

/// A message without a position.
fn plain_error(message: &str) -> LoadError {
    LoadError {
        message: message.to_string(),
        file: String::new(),
        line: 0,
        column: 0,
    }
}

/// The files a render reads: the input and, for a scene, what it names.
fn inputs_of(input: &Path, scene: &Scene) -> Vec<PathBuf> {
    std::iter::once(input.to_path_buf())
        .chain(scene.data().inputs.iter().cloned())
        .collect()
}

/// Each pixel's standard error of the luminance from the two halves (module docs).
fn standard_errors(a: &RenderState, b: &RenderState) -> Vec<f32> {
    let w = a.header().width;
    let h = a.header().height;
    let lum = |c: render::Rgb| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let (na, nb) = (a.iterations(x, y) as f64, b.iterations(x, y) as f64);
            if na == 0.0 || nb == 0.0 {
                return 0.0;
            }
            let d = lum(a.rgb(x, y)) - lum(b.rgb(x, y));
            (d.abs() * (na * nb).sqrt() / (na + nb)) as f32
        })
        .collect()
}

/// The modification times of `files` (None where one cannot be read).
pub fn stamps(files: &[PathBuf]) -> Vec<Option<SystemTime>> {
    files
        .iter()
        .map(|f| std::fs::metadata(f).and_then(|m| m.modified()).ok())
        .collect()
}

/// Watches the session's inputs: a restart when any changes (polled every 200 ms).
pub fn watch(session: &Session) {
    let mut last: Option<(Vec<PathBuf>, Vec<Option<SystemTime>>)> = None;
    while !session.stop.load(Ordering::SeqCst) {
        std::thread::sleep(Duration::from_millis(200));
        let files = session
            .snap
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .inputs
            .clone();
        if files.is_empty() {
            continue;
        }
        let now = stamps(&files);
        match &last {
            Some((f, t)) if *f == files && *t != now => {
                session.request_restart();
                last = Some((files, now));
            }
            Some((f, _)) if *f == files => {}
            _ => last = Some((files, now)),
        }
    }
}
