//! `frepray view`: a live preview in the browser. A local web server (127.0.0.1 only, a
//! random port unless one is asked for, a random token in every URL) renders a scene
//! or model progressively ([`session`]) and pushes each pass to the page as a
//! server-sent event; the page shows the image (exposure, tone map, zoom, any AOV, the
//! per-pixel standard error), the statistics and progress, a pixel inspector (samples,
//! mean, standard error, the optimal estimators' α per technique and depth), saves EXR
//! and PNG files, and switches the estimator. The scene and the files it names are
//! watched: a save restarts the render, an error is shown with its file, line and
//! column while the last good image stays.
//!
//! Nothing is served from the disk: the page is built in, images are made from the
//! render. Files are written only into the input's folder, under a plain file name. A
//! request without the token is refused.
//!
//! Routes (each with `token=`): `/` the page; `/events` the event stream (one JSON
//! object per change: [`status`]); `/image.png?view=color|stderr|aov:NAME&exposure=E&
//! tonemap=T`; `/pixel?x=&y=` the inspector's JSON; `/save?name=NAME.exr|.png` (POST);
//! `/estimator?name=NAME` (POST, restarts).

pub mod http;
pub mod session;

use crate::{Error, Film, Image, Settings, Tonemap};
use http::Request;
use serde_json::{json, Value};
use session::{Session, Snapshot};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// The page, built in.
const PAGE: &str = include_str!("page.html");

/// Connections served at once (each holds a thread; an event stream holds it for as
/// long as its page is open).
pub const MAX_CONNECTIONS: usize = 64;

/// A viewer, bound and ready to run.
pub struct Viewer {
    listener: TcpListener,
    token: String,
    folder: PathBuf,
    session: Arc<Session>,
}

/// A random token: 16 bytes from the system's generator, as hex.
fn token() -> Result<String, Error> {
    use std::io::Read;
    let mut b = [0u8; 16];
    std::fs::File::open("/dev/urandom")
        .and_then(|mut f| f.read_exact(&mut b))
        .map_err(|e| Error::Invalid(format!("no random token (/dev/urandom: {e})")))?;
    Ok(b.iter().map(|x| format!("{x:02x}")).collect())
}

impl Viewer {
    /// Binds 127.0.0.1:`port` (0: a free port) for `input` (a scene or model file)
    /// rendered with `settings`; `decompose` also renders every pass with rays through
    /// pixel centres, for the inspector's variance split (twice the work).
    pub fn bind(
        input: &Path,
        settings: Settings,
        port: u16,
        decompose: bool,
    ) -> Result<Viewer, Error> {
        if !input.is_file() {
            return Err(Error::Invalid(format!(
                "{}: not a file; expected a scene (.toml, .json) or a model (.frep, .hf, .vm)",
                input.display()
            )));
        }
        let listener = TcpListener::bind(("127.0.0.1", port))
            .map_err(|e| Error::Invalid(format!("127.0.0.1:{port}: {e}")))?;
        let folder = input
            .canonicalize()
            .ok()
            .and_then(|p| p.parent().map(Path::to_path_buf))
            .unwrap_or_else(|| PathBuf::from("."));
        Ok(Viewer {
            listener,
            token: token()?,
            folder,
            session: Arc::new(Session::new(input.to_path_buf(), settings, decompose)),
        })
    }

    /// The page's address, with its token.
    pub fn url(&self) -> String {
        let port = self.listener.local_addr().map(|a| a.port()).unwrap_or(0);
        format!("http://127.0.0.1:{port}/?token={}", self.token)
    }

    /// Serves until `stop` is set (Ctrl-C): renders, watches the inputs, answers pages;
    /// then stops the render and closes every connection.
    pub fn run(self, stop: &AtomicBool) -> Result<(), Error> {
        let session = self.session.clone();
        let render = {
            let s = session.clone();
            std::thread::spawn(move || s.run())
        };
        let watch = {
            let s = session.clone();
            std::thread::spawn(move || session::watch(&s))
        };
        self.listener
            .set_nonblocking(true)
            .map_err(|e| Error::Invalid(e.to_string()))?;
        let shared = Arc::new((self.token.clone(), self.folder.clone()));
        let open = Arc::new(AtomicUsize::new(0));
        while !stop.load(Ordering::SeqCst) {
            match self.listener.accept() {
                Ok((stream, _)) => {
                    let _ = stream.set_nonblocking(false);
                    // A thread per connection, at most MAX_CONNECTIONS at once: past
                    // that, an answer and no thread.
                    if open.fetch_add(1, Ordering::SeqCst) >= MAX_CONNECTIONS {
                        open.fetch_sub(1, Ordering::SeqCst);
                        refuse(&stream);
                        continue;
                    }
                    let (session, shared, open) = (session.clone(), shared.clone(), open.clone());
                    std::thread::spawn(move || {
                        serve(&stream, &session, &shared.0, &shared.1);
                        open.fetch_sub(1, Ordering::SeqCst);
                    });
                }
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                    std::thread::sleep(Duration::from_millis(20));
                }
                Err(_) => std::thread::sleep(Duration::from_millis(20)),
            }
        }
        session.shut_down();
        let _ = render.join();
        let _ = watch.join();
        Ok(())
    }
}

/// Answers a connection past [`MAX_CONNECTIONS`] with 503, having read what of its
/// request has arrived (within 50 ms: closing over unread bytes would reset it).
fn refuse(stream: &TcpStream) {
    use std::io::Read;
    let _ = stream.set_read_timeout(Some(Duration::from_millis(50)));
    let _ = (&*stream).read(&mut [0u8; 4096]);
    let _ = http::error(stream, "503 Service Unavailable", "too many connections");
    let _ = stream.shutdown(std::net::Shutdown::Write);
}

/// Answers one connection.
fn serve(stream: &TcpStream, session: &Session, token: &str, folder: &Path) {
    let Some(req) = http::read_request(stream) else {
        let _ = http::error(stream, "400 Bad Request", "not an HTTP request");
        return;
    };
    if req.param("token") != Some(token) {
        let _ = http::error(stream, "403 Forbidden", "the token is missing or wrong");
        return;
    }
    let _ = match (req.method.as_str(), req.path.as_str()) {
        ("GET", "/") => http::respond(
            stream,
            "200 OK",
            "text/html; charset=utf-8",
            PAGE.as_bytes(),
        ),
        ("GET", "/events") => events(stream, session),
        ("GET", "/status") => http::json(stream, "200 OK", &status(&lock(session))),
        ("GET", "/image.png") => image_png(stream, session, &req),
        ("GET", "/pixel") => pixel(stream, session, &req),
        ("POST", "/save") => save(stream, session, &req, folder),
        ("POST", "/estimator") => estimator(stream, session, &req),
        _ => http::error(stream, "404 Not Found", "no such page"),
    };
}

/// Every estimator's name.
fn estimator_names() -> Vec<&'static str> {
    crate::Method::ALL.iter().map(|m| m.name()).collect()
}

fn lock(session: &Session) -> std::sync::MutexGuard<'_, Snapshot> {
    session.snap.lock().unwrap_or_else(|e| e.into_inner())
}

/// What the page is told at every change.
pub fn status(s: &Snapshot) -> Value {
    let (w, h) = s.image.as_ref().map_or((0, 0), |i| (i.width(), i.height()));
    let per_s = |n: u64| {
        if s.seconds > 0.0 {
            n as f64 / s.seconds / 1e6
        } else {
            0.0
        }
    };
    json!({
        "version": s.version,
        "generation": s.generation,
        "width": w,
        "height": h,
        "passes": s.passes,
        "spp": s.spp.0,
        "spp_target": s.spp.1,
        "seconds": s.seconds,
        "samples": s.samples,
        "msamples_per_s": per_s(s.samples),
        "mrays_per_s": per_s(s.rays),
        "estimator": s.estimator,
        "techniques": s.techniques,
        "aovs": s.image.as_ref().map(|i| i.aov_names().to_vec()).unwrap_or_default(),
        "has_stderr": !s.stderr.is_empty(),
        "decompose": !s.stderr_centered.is_empty(),
        "estimators": estimator_names(),
        "error": s.error.as_ref().map(|e| json!({
            "message": e.message, "file": e.file, "line": e.line, "column": e.column,
        })),
    })
}

/// The event stream: the status now, then at every change (a comment every 10 s keeps
/// the connection alive); ends when the page goes away or the viewer stops.
fn events(mut stream: &TcpStream, session: &Session) -> std::io::Result<()> {
    use std::io::Write;
    write!(
        stream,
        "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\n\
         Connection: close\r\n\r\n"
    )?;
    let mut seen = u64::MAX;
    loop {
        let msg = {
            let mut s = lock(session);
            while s.version == seen && !session.stop.load(Ordering::SeqCst) {
                let (g, timeout) = session
                    .changed
                    .wait_timeout(s, Duration::from_secs(10))
                    .unwrap_or_else(|e| e.into_inner());
                s = g;
                if timeout.timed_out() {
                    break;
                }
            }
            if session.stop.load(Ordering::SeqCst) {
                return Ok(());
            }
            if s.version == seen {
                None
            } else {
                seen = s.version;
                Some(status(&s))
            }
        };
        match msg {
            Some(v) => write!(stream, "data: {v}\n\n")?,
            None => write!(stream, ": alive\n\n")?,
        }
        stream.flush()?;
    }
}

/// The page's exposure (stops) and tone map from a request (defaults where missing
/// or malformed).
fn film(req: &Request) -> Film {
    Film {
        exposure: req
            .param("exposure")
            .and_then(|e| e.parse().ok())
            .filter(|e: &f64| e.is_finite())
            .unwrap_or(0.0),
        tonemap: req
            .param("tonemap")
            .and_then(|t| t.parse::<Tonemap>().ok())
            .unwrap_or_default(),
    }
}

/// The answer before the first pass has finished.
fn not_ready(stream: &TcpStream) -> std::io::Result<()> {
    http::error(
        stream,
        "503 Service Unavailable",
        "no pass has finished yet",
    )
}

/// The image as the page asked for it, as PNG.
fn image_png(stream: &TcpStream, session: &Session, req: &Request) -> std::io::Result<()> {
    let film = film(req);
    let view = req.param("view").unwrap_or("color");
    let png = {
        let s = lock(session);
        let Some(img) = &s.image else {
            return not_ready(stream);
        };
        match rgb8(img, &s.stderr, view, &film) {
            Ok(bytes) => encode_png(&bytes, img.width(), img.height()),
            Err(e) => return http::error(stream, "400 Bad Request", &e),
        }
    };
    match png {
        Ok(p) => http::respond(stream, "200 OK", "image/png", &p),
        Err(e) => http::error(stream, "500 Internal Server Error", &e.to_string()),
    }
}

/// 8-bit sRGB pixels of a view: the colour through `film`; the standard error as grey
/// through `film`; an AOV: depth and normals as `render` shows them, albedo as colour.
pub fn rgb8(img: &Image, stderr: &[f32], view: &str, film: &Film) -> Result<Vec<u8>, String> {
    use render::color::srgb_u8;
    let c = img.channels();
    let pixels = img.data().chunks_exact(c);
    Ok(match view {
        "color" => pixels
            .flat_map(|p| [0, 1, 2].map(|k| srgb_u8(film.map(p[k]))))
            .collect(),
        "stderr" => {
            if stderr.is_empty() {
                return Err("no standard error before the second pass".into());
            }
            stderr
                .iter()
                .flat_map(|&e| [srgb_u8(film.map(f64::from(e))); 3])
                .collect()
        }
        aov => {
            let name = aov.strip_prefix("aov:").unwrap_or(aov);
            let first = |prefix: &str| img.aov_index(prefix);
            let (at, values) = match name {
                "depth" => (first("depth"), Some(crate::value_png::Values::Depth)),
                "normal" => (first("normal.X"), Some(crate::value_png::Values::Normals)),
                "albedo" => (first("albedo.R"), None),
                _ => (None, None),
            };
            let Some(at) = at else {
                return Err(format!("no view {view:?}: the render has no such AOV"));
            };
            let n = if name == "depth" { 1 } else { 3 };
            let mut v = Image::new(img.width(), img.height(), &[]);
            for (k, p) in img.data().chunks_exact(c).enumerate() {
                let (x, y) = ((k as u32) % img.width(), (k as u32) / img.width());
                let q = [0, 1, 2].map(|i| p[3 + at + if n == 1 { 0 } else { i }]);
                v.set_rgb(x, y, render::Rgb::from_array(q));
            }
            match values {
                Some(vals) => vals.rgb8(&v),
                None => v
                    .data()
                    .chunks_exact(3)
                    .flat_map(|p| [0, 1, 2].map(|k| srgb_u8(p[k])))
                    .collect(),
            }
        }
    })
}

fn encode_png(rgb: &[u8], w: u32, h: u32) -> std::io::Result<Vec<u8>> {
    let mut out = Vec::new();
    render::png_io::write_rgb8(&mut out, rgb, w, h)?;
    Ok(out)
}

/// The inspector's JSON for pixel (x, y).
fn pixel(stream: &TcpStream, session: &Session, req: &Request) -> std::io::Result<()> {
    let coord = |k: &str| req.param(k).and_then(|v| v.parse::<u32>().ok());
    let (Some(x), Some(y)) = (coord("x"), coord("y")) else {
        return http::error(stream, "400 Bad Request", "expected x and y, whole numbers");
    };
    let s = lock(session);
    let Some(state) = &s.state else {
        return not_ready(stream);
    };
    let h = state.header();
    if x >= h.width || y >= h.height {
        return http::error(stream, "400 Bad Request", "the pixel is outside the image");
    }
    let d = state.pixel_detail(x, y);
    let stderr = s
        .stderr
        .get((y * h.width + x) as usize)
        .map(|&e| f64::from(e));
    // The variance of the pixel's mean (luminance), and its split into the directions'
    // part (rays through the pixel's centre) and the footprint's (the rest).
    let centered = s
        .stderr_centered
        .get((y * h.width + x) as usize)
        .map(|&e| f64::from(e));
    let variance = match (stderr, centered) {
        (Some(t), Some(c)) => json!({
            "total": t * t,
            "directions": c * c,
            "footprint": (t * t - c * c).max(0.0),
        }),
        _ => Value::Null,
    };
    let t = h.techniques.len();
    let blocks: Vec<Value> = d
        .blocks
        .iter()
        .map(|b| {
            json!({
                "depth": b.depth,
                "light": b.light,
                "iterations": b.iterations,
                "estimate": b.estimate.to_array(),
                // α per technique: the channels' mean, and each channel's.
                "alpha": b.alpha.as_ref().map(|a| {
                    (0..t).map(|i| (a[i] + a[t + i] + a[2 * t + i]) / 3.0).collect::<Vec<f64>>()
                }),
                "alpha_rgb": b.alpha,
            })
        })
        .collect();
    let value = json!({
        "x": x,
        "y": y,
        "samples": d.samples,
        "mean": d.estimate.to_array(),
        "stderr": stderr,
        "variance": variance,
        "outside": d.outside.to_array(),
        "estimator": h.method.name(),
        "techniques": h.techniques.iter().map(|(t, n)| format!("{}:{n}", t.name())).collect::<Vec<_>>(),
        "blocks": blocks,
    });
    drop(s);
    http::json(stream, "200 OK", &value)
}

/// Writes the current image into the input's folder as `name` (a plain .exr or .png
/// file name), through the same image code as `render`.
fn save(
    stream: &TcpStream,
    session: &Session,
    req: &Request,
    folder: &Path,
) -> std::io::Result<()> {
    let name = req.param("name").unwrap_or("");
    let plain = !name.is_empty()
        && !name.starts_with('.')
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c));
    let ext = Path::new(name)
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !plain || !matches!(ext.as_deref(), Some("exr" | "png")) {
        return http::error(
            stream,
            "400 Bad Request",
            "expected a plain file name ending in .exr or .png (letters, digits, - _ .)",
        );
    }
    let (img, film) = {
        let s = lock(session);
        let Some(state) = &s.state else {
            return not_ready(stream);
        };
        (state.image(), film(req))
    };
    let path = folder.join(name);
    let written = match ext.as_deref() {
        Some("exr") => img.write_exr(&path),
        _ => img.write_png_film(&path, &film),
    };
    match written {
        Ok(()) => http::json(
            stream,
            "200 OK",
            &json!({ "written": path.display().to_string() }),
        ),
        Err(e) => http::error(
            stream,
            "500 Internal Server Error",
            &format!("{}: {e}", path.display()),
        ),
    }
}

/// Switches the estimator and restarts.
fn estimator(stream: &TcpStream, session: &Session, req: &Request) -> std::io::Result<()> {
    let name = req.param("name").unwrap_or("");
    let Ok(m) = name.parse::<crate::Method>() else {
        return http::error(
            stream,
            "400 Bad Request",
            &format!(
                "unknown estimator {name:?}; known: {}",
                estimator_names().join(", ")
            ),
        );
    };
    session
        .settings
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .overrides
        .estimator = Some(m.name().to_string());
    session.request_restart();
    http::json(stream, "200 OK", &json!({ "estimator": m.name() }))
}
