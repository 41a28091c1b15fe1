//! `frepray view`'s server with a real HTTP client: the token, the folder restriction,
//! the passes and the inspector, concurrent pages and one that goes away, live edits
//! (a change restarts, an error is located and the last image stays), a clean stop.

use frepray::view::Viewer;
use frepray::Settings;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

const SCENE: &str = r#"
camera = { eye = [0, -4, 1.5], target = [0, 0, 0.3], resolution = [24, 18] }
render = { integrator = "direct", estimator = "optimal-direct", spp = 8 }
materials.white = { type = "diffuse", reflectance = 0.7 }
objects = [
  { solid = "z + 1", material = "white" },
  { solid = "sphere([0, 0, 0], 1)", material = "white" },
]
lights = [{ type = "sphere", center = [1, -2, 3], radius = 0.4, power = POWER }]
"#;

struct Running {
    port: u16,
    token: String,
    dir: PathBuf,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Running {
    fn start(name: &str, decompose: bool) -> Running {
        let dir = std::env::temp_dir().join(format!("frepray-view-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("scene.toml"), SCENE.replace("POWER", "100")).unwrap();
        let viewer =
            Viewer::bind(&dir.join("scene.toml"), Settings::default(), 0, decompose).unwrap();
        let url = viewer.url();
        let port = url
            .split(':')
            .nth(2)
            .unwrap()
            .split('/')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        let token = url.split("token=").nth(1).unwrap().to_string();
        let stop = Arc::new(AtomicBool::new(false));
        let s = stop.clone();
        let thread = std::thread::spawn(move || viewer.run(&s).unwrap());
        Running {
            port,
            token,
            dir,
            stop,
            thread: Some(thread),
        }
    }

    /// A request: (status code, body).
    fn request(&self, method: &str, path: &str) -> (u16, Vec<u8>) {
        let mut s = TcpStream::connect(("127.0.0.1", self.port)).unwrap();
        write!(s, "{method} {path} HTTP/1.1\r\nHost: localhost\r\n\r\n").unwrap();
        let mut out = Vec::new();
        s.read_to_end(&mut out).unwrap();
        let head_end = out.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
        let head = String::from_utf8_lossy(&out[..head_end]).to_string();
        let code = head.split_whitespace().nth(1).unwrap().parse().unwrap();
        (code, out[head_end + 4..].to_vec())
    }

    fn get(&self, path: &str) -> (u16, Vec<u8>) {
        let sep = if path.contains('?') { '&' } else { '?' };
        self.request("GET", &format!("{path}{sep}token={}", self.token))
    }

    fn json(&self, path: &str) -> serde_json::Value {
        let (code, body) = self.get(path);
        assert_eq!(code, 200, "{path}: {}", String::from_utf8_lossy(&body));
        serde_json::from_slice(&body).unwrap()
    }

    /// Polls the status until `done` holds (or fails after 60 s).
    fn wait(&self, what: &str, done: impl Fn(&serde_json::Value) -> bool) -> serde_json::Value {
        let start = Instant::now();
        loop {
            let s = self.json("/status");
            if done(&s) {
                return s;
            }
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "waiting for {what}: {s}"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    fn finish(mut self) {
        self.stop.store(true, Ordering::SeqCst);
        let t = self.thread.take().unwrap();
        let start = Instant::now();
        while !t.is_finished() {
            assert!(
                start.elapsed() < Duration::from_secs(20),
                "the viewer did not stop"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        t.join().unwrap();
        assert!(
            TcpStream::connect(("127.0.0.1", self.port)).is_err(),
            "still listening"
        );
        std::fs::remove_dir_all(&self.dir).unwrap();
    }
}

/// The PNG's width and height (from its IHDR chunk).
fn png_size(png: &[u8]) -> (u32, u32) {
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let be = |o: usize| u32::from_be_bytes(png[o..o + 4].try_into().unwrap());
    (be(16), be(20))
}

/// Requests without the right token are refused; nothing but the built-in page and
/// the render's own products is served; files are saved only into the scene's folder
/// under a plain name; the inspector reports samples, the standard error and α; the
/// estimator switches and restarts; the viewer stops cleanly.
#[test]
fn token_folder_inspector_and_estimator() {
    let v = Running::start("basics", false);
    for path in ["/", "/status", "/image.png", "/?token=wrong"] {
        assert_eq!(v.request("GET", path).0, 403, "{path}");
    }
    let (code, page) = v.get("/");
    assert_eq!(code, 200);
    assert!(String::from_utf8_lossy(&page).contains("frepray view"));
    for path in [
        "/../scene.toml",
        "/scene.toml",
        "/etc/passwd",
        "/%2e%2e/scene.toml",
    ] {
        assert_eq!(v.get(path).0, 404, "{path}");
    }
    let s = v.wait("the last pass", |s| s["spp"] == 8);
    assert_eq!(
        (s["width"].as_u64(), s["height"].as_u64()),
        (Some(24), Some(18))
    );
    assert!(s["has_stderr"].as_bool().unwrap() && s["passes"].as_u64().unwrap() >= 3);
    for view in ["color", "stderr"] {
        let (code, png) = v.get(&format!("/image.png?view={view}&exposure=1&tonemap=aces"));
        assert_eq!(code, 200, "{view}");
        assert_eq!(png_size(&png), (24, 18));
    }
    assert_eq!(v.get("/image.png?view=aov:depth").0, 400);
    let p = v.json("/pixel?x=12&y=9");
    assert_eq!(p["samples"], 8);
    let alpha = p["blocks"][0]["alpha"]
        .as_array()
        .expect("optimal-direct keeps α");
    assert_eq!(alpha.len(), p["techniques"].as_array().unwrap().len());
    assert!(p["stderr"].as_f64().unwrap() >= 0.0);
    assert_eq!(v.get("/pixel?x=24&y=0").0, 400);
    let escape = format!("frepray-view-escape-{}.exr", std::process::id());
    for bad in [
        format!("../{escape}"),
        format!("%2e%2e%2f{escape}"),
        "a/b.exr".into(),
        ".hidden.exr".into(),
        "x.txt".into(),
    ] {
        let (code, _) = v.request("POST", &format!("/save?name={bad}&token={}", v.token));
        assert_eq!(code, 400, "{bad}");
    }
    assert!(!v.dir.parent().unwrap().join(&escape).exists());
    let (code, _) = v.request("POST", &format!("/save?name=shot.exr&token={}", v.token));
    assert_eq!(code, 200);
    let img = frepray::Image::read_exr(v.dir.join("shot.exr")).unwrap();
    assert_eq!((img.width(), img.height()), (24, 18));
    assert_eq!(img.attribute("frepray.estimator"), Some("optimal-direct"));
    let (code, _) = v.request(
        "POST",
        &format!("/estimator?name=balance&token={}", v.token),
    );
    assert_eq!(code, 200);
    v.wait("the balance render", |s| {
        s["estimator"] == "balance" && s["spp"] == 8
    });
    let p = v.json("/pixel?x=12&y=9");
    assert!(p["blocks"][0]["alpha"].is_null(), "{p}");
    assert_eq!(
        v.request("POST", &format!("/estimator?name=nope&token={}", v.token))
            .0,
        400
    );
    v.finish();
}

/// Reads events from a stream until one satisfies `done`.
fn next_event(
    r: &mut impl BufRead,
    done: impl Fn(&serde_json::Value) -> bool,
) -> serde_json::Value {
    loop {
        let mut line = String::new();
        assert!(r.read_line(&mut line).unwrap() > 0, "the stream ended");
        if let Some(data) = line.strip_prefix("data: ") {
            let v: serde_json::Value = serde_json::from_str(data.trim()).unwrap();
            if done(&v) {
                return v;
            }
        }
    }
}

fn events(v: &Running) -> BufReader<TcpStream> {
    let mut s = TcpStream::connect(("127.0.0.1", v.port)).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
    write!(s, "GET /events?token={} HTTP/1.1\r\n\r\n", v.token).unwrap();
    let mut r = BufReader::new(s);
    let mut line = String::new();
    r.read_line(&mut line).unwrap();
    assert!(line.starts_with("HTTP/1.1 200"), "{line}");
    r
}

/// Two pages follow the passes at once; one goes away mid-render and the other goes
/// on. Saving the scene restarts the render (a new generation, a brighter image); a
/// broken scene is reported with its line and column while the last image stays; the
/// fix clears the error.
#[test]
fn pages_follow_passes_and_edits() {
    let v = Running::start("edits", false);
    let (mut a, b) = (events(&v), events(&v));
    next_event(&mut a, |s| s["passes"].as_u64() >= Some(1));
    drop(b); // a page that goes away
    let first = next_event(&mut a, |s| s["spp"] == 8);
    let before = v.json("/pixel?x=12&y=9")["mean"][0].as_f64().unwrap();
    // Let the watcher take the first modification times, then edit.
    std::thread::sleep(Duration::from_millis(600));
    std::fs::write(v.dir.join("scene.toml"), SCENE.replace("POWER", "400")).unwrap();
    let g = first["generation"].as_u64().unwrap();
    next_event(&mut a, |s| {
        s["generation"].as_u64() > Some(g) && s["spp"] == 8
    });
    let after = v.json("/pixel?x=12&y=9")["mean"][0].as_f64().unwrap();
    assert!(after > 2.0 * before, "{before} → {after}");
    std::thread::sleep(Duration::from_millis(300));
    let broken = SCENE
        .replace("POWER", "400")
        .replace("reflectance = 0.7", "reflectance = oops");
    std::fs::write(v.dir.join("scene.toml"), &broken).unwrap();
    let e = next_event(&mut a, |s| !s["error"].is_null());
    let err = &e["error"];
    assert!(
        err["file"].as_str().unwrap().ends_with("scene.toml"),
        "{err}"
    );
    assert_eq!(err["line"], 4, "{err}");
    assert!(err["column"].as_u64().unwrap() > 0, "{err}");
    assert_eq!(v.get("/image.png").0, 200, "the last good image stays");
    std::thread::sleep(Duration::from_millis(300));
    std::fs::write(v.dir.join("scene.toml"), SCENE.replace("POWER", "100")).unwrap();
    next_event(&mut a, |s| s["error"].is_null() && s["spp"] == 8);
    v.finish();
}

/// With the decomposition, the inspector splits a pixel's variance: the directions'
/// part from rays through pixel centres, the footprint's the rest (never negative);
/// over a grid of pixels both parts are present (the scene has edges and soft
/// shadows).
#[test]
fn the_inspector_splits_the_variance() {
    let v = Running::start("decompose", true);
    let s = v.wait("the last pass", |s| s["spp"] == 8);
    assert_eq!(s["decompose"], true);
    let (mut footprint, mut directions) = (0.0, 0.0);
    for y in (1..18).step_by(3) {
        for x in (1..24).step_by(3) {
            let p = v.json(&format!("/pixel?x={x}&y={y}"));
            let var = &p["variance"];
            let (t, d, f) = (
                var["total"].as_f64().unwrap(),
                var["directions"].as_f64().unwrap(),
                var["footprint"].as_f64().unwrap(),
            );
            assert!(d >= 0.0 && f >= 0.0 && f == (t - d).max(0.0), "{var}");
            footprint += f;
            directions += d;
        }
    }
    assert!(
        footprint > 0.0 && directions > 0.0,
        "{footprint} {directions}"
    );
    v.finish();
}

/// Connections are capped: with MAX_CONNECTIONS of them open and silent, the next is
/// answered 503 at once; when they close, pages are served again.
#[test]
fn connections_are_capped() {
    let v = Running::start("cap", false);
    v.wait("the first pass", |s| s["passes"].as_u64() >= Some(1));
    let idle: Vec<TcpStream> = (0..frepray::view::MAX_CONNECTIONS)
        .map(|_| TcpStream::connect(("127.0.0.1", v.port)).unwrap())
        .collect();
    // Let the server take them all.
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(v.get("/status").0, 503);
    drop(idle);
    let start = Instant::now();
    while v.get("/status").0 != 200 {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "never served again"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    v.finish();
}
