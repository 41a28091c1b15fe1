//! Never lose work, never hang, never surprise (docs/reliability.md): Ctrl-C, outputs
//! checked before work, resource limits, readers' and options' edge cases, the
//! experiment's cache. Every file goes under the target folder, none into the sources.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

fn frepray() -> Command {
    Command::new(env!("CARGO_BIN_EXE_frepray"))
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A fresh, empty folder under the target folder.
fn out_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("reliability")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs and checks that it took less than `limit`.
fn run_within(cmd: &mut Command, limit: Duration) -> Output {
    let t = Instant::now();
    let o = cmd.output().unwrap();
    assert!(
        t.elapsed() < limit,
        "took {:?}: {}",
        t.elapsed(),
        stderr(&o)
    );
    o
}

fn sigint(child: &Child) {
    signal(child, "INT");
}

/// Sends the signal `name` (`INT`, `TERM`, `HUP`) to the child.
fn signal(child: &Child, name: &str) {
    let st = Command::new("kill")
        .arg(format!("-{name}"))
        .arg(child.id().to_string())
        .status()
        .unwrap();
    assert!(st.success());
}

/// Waits for the child at most `limit`; its exit code and the time it took.
fn wait_within(child: &mut Child, limit: Duration) -> (Option<i32>, Duration) {
    let t = Instant::now();
    loop {
        if let Some(st) = child.try_wait().unwrap() {
            return (st.code(), t.elapsed());
        }
        if t.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("still running {limit:?} after SIGINT");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Everything the child wrote to its (piped) stderr.
fn child_stderr(child: &mut Child) -> String {
    use std::io::Read;
    let mut s = String::new();
    child.stderr.take().unwrap().read_to_string(&mut s).unwrap();
    s
}

/// A render of the Cornell box at `w × h` that takes hours unless stopped, to `out`,
/// with stderr piped.
fn long_render(out: &Path, w: u32, h: u32) -> Child {
    frepray()
        .arg("render")
        .arg(root().join("scenes/cornell.toml"))
        .args(["--spp", "100000", "--quiet", "--width"])
        .arg(w.to_string())
        .arg("--height")
        .arg(h.to_string())
        .arg("-o")
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Waits until `path` exists (the process got that far), at most `limit`.
fn wait_for(path: &Path, limit: Duration) {
    let t = Instant::now();
    while !path.exists() {
        assert!(t.elapsed() < limit, "{} never appeared", path.display());
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Channel `name` of an EXR (panics if the file is not a readable EXR).
fn exr_channel(path: &Path, name: &str) -> Vec<f32> {
    let img = exr::prelude::read_all_flat_layers_from_file(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let ch = img.layer_data[0]
        .channel_data
        .list
        .iter()
        .find(|c| c.name.to_string() == name)
        .unwrap();
    ch.sample_data.values_as_f32().collect()
}

/// SIGINT at a huge spp: the render stops within 2 s, writes a valid partial EXR
/// beside (not over) a finished file of the same name, and exits with 130.
#[test]
fn sigint_stops_a_render_within_two_seconds_with_status_130() {
    let dir = out_dir("sigint");
    let out = dir.join("cornell.exr");
    std::fs::write(&out, b"a finished render").unwrap();
    let mut child = long_render(&out, 48, 32);
    std::thread::sleep(Duration::from_millis(2500));
    sigint(&child);
    let (code, took) = wait_within(&mut child, Duration::from_secs(10));
    let err = child_stderr(&mut child);
    assert_eq!(code, Some(130), "{err}");
    assert!(
        took < Duration::from_secs(2),
        "stopped after {took:?}: {err}"
    );
    assert_eq!(std::fs::read(&out).unwrap(), b"a finished render");
    let partial = dir.join("cornell.partial.exr");
    let r = exr_channel(&partial, "R");
    assert_eq!(r.len(), 48 * 32);
    assert!(r.iter().all(|v| v.is_finite()));
    assert!(err.contains("cornell.partial.exr"), "{err}");
}

/// A render stopped by a signal leaves a state to resume from (`NAME.partial.state`,
/// written even when only an image was asked for), whose partial image already covers
/// every pixel; `render --resume` renders the rest, giving the uninterrupted render's
/// state and image bit for bit.
#[test]
fn an_interrupted_render_resumes_to_the_uninterrupted_one() {
    let dir = out_dir("resume");
    let render = |spp: u32, outs: &[&str], extra: &[String]| {
        let mut c = frepray();
        c.arg("render")
            .arg(root().join("scenes/cornell.toml"))
            .args(["--width", "24", "--height", "16", "--quiet", "--seed", "5"])
            .args(["--integrator", "path", "--estimator", "optimal-progressive"])
            .arg("--spp")
            .arg(spp.to_string())
            .args(extra);
        for o in outs {
            c.arg("-o").arg(dir.join(o));
        }
        c.stdout(Stdio::null()).stderr(Stdio::piped());
        c
    };
    // A render long enough to interrupt half-way: spp doubled until it takes 2 s.
    let mut spp = 64;
    let full_time = loop {
        let t = Instant::now();
        let o = render(spp, &["full.exr", "full.state"], &[])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        if t.elapsed() > Duration::from_secs(2) || spp >= 1 << 20 {
            break t.elapsed();
        }
        spp *= 2;
    };
    let mut child = render(spp, &["cut.exr"], &[]).spawn().unwrap();
    std::thread::sleep(full_time / 2);
    sigint(&child);
    let (code, _) = wait_within(&mut child, Duration::from_secs(10));
    let err = child_stderr(&mut child);
    assert_eq!(code, Some(130), "{err}");
    let partial = dir.join("cut.partial.state");
    assert!(
        err.contains(&format!("--resume {}", partial.display())),
        "{err}"
    );
    // The whole image at fewer samples: every pixel has some, none has all.
    assert_eq!(
        exr_channel(&dir.join("cut.partial.exr"), "R").len(),
        24 * 16
    );
    let cut = frepray::RenderState::read(&partial).unwrap();
    let counts: Vec<u64> = (0..16)
        .flat_map(|y| (0..24).map(move |x| (x, y)))
        .map(|(x, y)| cut.iterations(x, y))
        .collect();
    assert!(
        counts.iter().all(|&n| n >= 1 && n < u64::from(spp)),
        "{counts:?}"
    );
    let resume = ["--resume".to_string(), partial.display().to_string()];
    let o = render(spp, &["resumed.exr", "resumed.state"], &resume)
        .output()
        .unwrap();
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("resuming: "), "{err}");
    assert!(
        std::fs::read(dir.join("resumed.state")).unwrap()
            == std::fs::read(dir.join("full.state")).unwrap(),
        "the resumed state differs from the uninterrupted one"
    );
    for c in ["R", "G", "B"] {
        let (a, b) = (
            exr_channel(&dir.join("resumed.exr"), c),
            exr_channel(&dir.join("full.exr"), c),
        );
        assert!(
            a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()),
            "{c}"
        );
    }
    // Another depth is another render: refused, naming the difference.
    let o = render(
        spp,
        &["other.exr"],
        &[&["--max-depth".into(), "2".into()], &resume[..]].concat(),
    )
    .output()
    .unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("max_depth is") && err.contains("here and 2 there"),
        "{err}"
    );
}

/// SIGTERM (schedulers, `timeout`, container stops) and SIGHUP (a closed terminal) stop
/// a render as Ctrl-C does: the partial result is written, and the status is 128 + the
/// signal (143, 129).
#[test]
fn sigterm_and_sighup_keep_the_render() {
    for (name, status) in [("TERM", 143), ("HUP", 129)] {
        let dir = out_dir(&format!("sig{name}"));
        let out = dir.join("cornell.exr");
        let mut child = long_render(&out, 24, 16);
        std::thread::sleep(Duration::from_millis(2000));
        signal(&child, name);
        let (code, took) = wait_within(&mut child, Duration::from_secs(10));
        let err = child_stderr(&mut child);
        assert_eq!(code, Some(status), "SIG{name}: {err}");
        assert!(took < Duration::from_secs(2), "SIG{name}: {took:?}");
        assert!(!out.exists(), "SIG{name}");
        let r = exr_channel(&dir.join("cornell.partial.exr"), "R");
        assert_eq!(r.len(), 24 * 16, "SIG{name}");
        assert!(r.iter().all(|v| v.is_finite() && *v >= 0.0), "SIG{name}");
        assert!(err.contains(&format!("SIG{name}")), "SIG{name}: {err}");
    }
}

/// `bench` stops on SIGTERM as on Ctrl-C, with status 143.
#[test]
fn sigterm_stops_bench() {
    let mut child = frepray()
        .arg("bench")
        .arg(root().join("scenes/cornell.toml"))
        .args(["--spp", "100000", "--width", "16", "--height", "16"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(2500));
    signal(&child, "TERM");
    let (code, took) = wait_within(&mut child, Duration::from_secs(10));
    assert_eq!(code, Some(143));
    assert!(took < Duration::from_secs(2), "{took:?}");
}

/// A second Ctrl-C quits at once (130), whatever the first one is waiting for.
#[test]
fn second_sigint_quits_at_once() {
    let dir = out_dir("sigint2");
    let mut child = frepray()
        .arg("render")
        .arg(root().join("scenes/cornell.toml"))
        .args([
            "--spp", "100000", "--width", "16", "--height", "16", "--quiet", "-o",
        ])
        .arg(dir.join("c.exr"))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(2500));
    sigint(&child);
    sigint(&child);
    let (code, took) = wait_within(&mut child, Duration::from_secs(10));
    assert_eq!(code, Some(130));
    assert!(took < Duration::from_secs(2), "{took:?}");
}

/// An interrupted experiment keeps its reference samples; a rerun continues them.
#[test]
fn interrupted_experiment_keeps_the_reference() {
    let dir = out_dir("exp-sigint");
    let exp = dir.join("exp");
    let args = |c: &mut Command| {
        c.arg("experiment")
            .arg(root().join("scenes/cornell.toml"))
            .args([
                "--width",
                "4",
                "--height",
                "4",
                "--spp",
                "1",
                "--estimators",
                "balance",
                "--reference-spp",
                "640000",
                "--out",
            ])
            .arg(&exp);
    };
    let mut c = frepray();
    args(&mut c);
    let mut child = c
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The output folder is made before the reference starts; then wait for some of
    // its 32 chunks to finish.
    wait_for(&exp.join("images"), Duration::from_secs(30));
    std::thread::sleep(Duration::from_millis(3000));
    sigint(&child);
    let (code, _) = wait_within(&mut child, Duration::from_secs(10));
    let err = child_stderr(&mut child);
    assert_eq!(code, Some(130), "{err}");
    // The reference renders in two halves (their difference estimates its noise); the
    // interrupt lands in the first or, on a fast machine, the second.
    let kept = [
        exp.join("reference.partial.state"),
        exp.join("reference-2.partial.state"),
    ];
    assert!(kept.iter().any(|k| k.is_file()), "{err}");
    assert!(err.contains("samples kept in"), "{err}");
    // The rerun continues from the kept samples (then it is interrupted again: the
    // whole reference would take too long for a test).
    let mut c = frepray();
    args(&mut c);
    let mut child = c
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(2500));
    sigint(&child);
    let (code, _) = wait_within(&mut child, Duration::from_secs(10));
    let err = child_stderr(&mut child);
    assert_eq!(code, Some(130), "{err}");
    assert!(err.contains("reference: continuing from"), "{err}");
}

/// Outputs that cannot be written are refused before any rendering (the huge spp
/// would take hours); an unknown kind of output too.
#[test]
fn unwritable_outputs_are_refused_before_rendering() {
    let dir = out_dir("unwritable");
    let good = dir.join("good.exr");
    std::fs::create_dir_all(dir.join("folder.exr")).unwrap();
    for (bad, says) in [
        (dir.join("no/such/folder/x.exr"), "does not exist"),
        (dir.join("folder.exr"), "is a folder"),
        (dir.join("x.jpg"), "unknown output format"),
    ] {
        for input in ["scenes/cornell.toml", "models/examples/bumpy_ball.frep"] {
            let o = run_within(
                frepray()
                    .arg("render")
                    .arg(root().join(input))
                    .args(["--spp", "1000000", "-o"])
                    .arg(&good)
                    .arg("-o")
                    .arg(&bad),
                Duration::from_secs(20),
            );
            let err = stderr(&o);
            assert_eq!(o.status.code(), Some(1), "{err}");
            assert!(err.contains(says), "{input}: {err}");
            assert!(!good.exists());
        }
    }
}

/// An output that would replace a file the scene reads (its environment map) is refused
/// before rendering, and the file is left as it was.
#[test]
fn outputs_never_replace_the_scene_inputs() {
    let dir = out_dir("inputs");
    for f in ["environment.toml", "sky.exr"] {
        std::fs::copy(root().join("scenes").join(f), dir.join(f)).unwrap();
    }
    let before = std::fs::read(dir.join("sky.exr")).unwrap();
    let o = run_within(
        frepray()
            .arg("render")
            .arg(dir.join("environment.toml"))
            .args(["--spp", "1", "--width", "8", "--height", "8", "-o"])
            .arg(dir.join("sky.exr")),
        Duration::from_secs(20),
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("is a file the scene reads"), "{err}");
    assert_eq!(std::fs::read(dir.join("sky.exr")).unwrap(), before);
}

/// A render too large for memory is refused up front with its estimate; so is one
/// over `--max-memory`, and an absurd thread count.
#[test]
fn oversize_renders_and_thread_counts_are_refused_with_an_estimate() {
    let dir = out_dir("oversize");
    for input in ["scenes/cornell.toml", "models/examples/bumpy_ball.frep"] {
        let o = run_within(
            frepray()
                .arg("render")
                .arg(root().join(input))
                .args(["--width", "100000", "--height", "100000", "-o"])
                .arg(dir.join("huge.exr")),
            Duration::from_secs(20),
        );
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(
            err.contains("100000×100000") && err.contains("needs about") && err.contains("GiB"),
            "{input}: {err}"
        );
        let o = run_within(
            frepray()
                .arg("render")
                .arg(root().join(input))
                .args([
                    "--width",
                    "256",
                    "--height",
                    "256",
                    "--max-memory",
                    "1M",
                    "-o",
                ])
                .arg(dir.join("limited.exr")),
            Duration::from_secs(20),
        );
        let err = stderr(&o);
        assert!(err.contains("--max-memory") && err.contains("MiB"), "{err}");
        // A --max-memory above what the machine has cannot make the allocation succeed:
        // refused (it once aborted with status 134).
        let o = run_within(
            frepray()
                .arg("render")
                .arg(root().join(input))
                .args(["--width", "100000", "--height", "100000"])
                .args(["--max-memory", "1000T", "-o"])
                .arg(dir.join("huge.exr")),
            Duration::from_secs(20),
        );
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(
            err.contains("memory this machine has (RAM and swap; --max-memory asked for more)"),
            "{input}: {err}"
        );
        let o = run_within(
            frepray()
                .arg("render")
                .arg(root().join(input))
                .args(["--threads", "100000", "-o"])
                .arg(dir.join("threads.exr")),
            Duration::from_secs(20),
        );
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(err.contains("--threads 100000: at most"), "{err}");
    }
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
}

/// `experiment` and `bench` take `--max-memory` too, and refuse an oversize render up
/// front with the message of `render` (the experiment writes nothing).
#[test]
fn experiment_and_bench_check_memory_up_front() {
    let dir = out_dir("memory-commands");
    let out = dir.join("exp");
    for args in [
        vec!["experiment", "--spp", "1", "--reference-spp", "2", "-o"],
        vec!["bench", "--spp", "1"],
    ] {
        let mut cmd = frepray();
        cmd.args(&args);
        if args[0] == "experiment" {
            cmd.arg(&out);
        }
        let o = run_within(
            cmd.arg(root().join("scenes/cornell.toml")).args([
                "--width",
                "256",
                "--height",
                "256",
                "--max-memory",
                "1M",
            ]),
            Duration::from_secs(20),
        );
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains("256×256 render with these settings needs about")
                && err.contains("more than the --max-memory (1.0 MiB)"),
            "{args:?}: {err}"
        );
    }
    assert!(!out.exists());
}

/// Editing a model that a scene reads invalidates the experiment's finished renders.
#[test]
fn experiment_cache_follows_the_models_a_scene_reads() {
    let dir = out_dir("exp-cache");
    std::fs::write(
        dir.join("blob.frep"),
        "bounds([-1, -1, -1], [1, 1, 1])\noutput sphere([0, 0, 0], 0.6)\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("scene.toml"),
        r#"[camera]
eye = [0, -4, 1]
target = [0, 0, 0]
fov = 40
resolution = [8, 6]

[render]
integrator = "direct"
spp = 1

[materials.white]
type = "diffuse"
reflectance = [0.7, 0.7, 0.7]

[[objects]]
name = "blob"
model = "blob.frep"
material = "white"

[[lights]]
type = "sphere"
center = [0, -2, 3]
radius = 0.5
radiance = [10, 10, 10]
"#,
    )
    .unwrap();
    let run = || {
        let o = frepray()
            .arg("experiment")
            .arg(dir.join("scene.toml"))
            .args([
                "--spp",
                "1,2",
                "--estimators",
                "balance",
                "--reference-spp",
                "8",
            ])
            .arg("--out")
            .arg(dir.join("exp"))
            .output()
            .unwrap();
        let err = stderr(&o);
        assert!(o.status.success(), "{err}");
        err
    };
    run();
    assert!(run().contains("reusing"), "an unchanged rerun reuses");
    std::fs::write(
        dir.join("blob.frep"),
        "bounds([-1, -1, -1], [1, 1, 1])\noutput sphere([0, 0, 0], 0.8)\n",
    )
    .unwrap();
    let err = run();
    assert!(err.contains("starting afresh"), "{err}");
    assert!(!err.contains("reusing"), "{err}");
}

/// A given reference of the wrong size is refused before anything is rendered.
#[test]
fn experiment_checks_the_reference_size_first() {
    let dir = out_dir("exp-ref");
    let reference = dir.join("ref.exr");
    let o = frepray()
        .arg("render")
        .arg(root().join("scenes/cornell.toml"))
        .args(["--spp", "1", "--width", "8", "--height", "8", "-o"])
        .arg(&reference)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let o = run_within(
        frepray()
            .arg("experiment")
            .arg(root().join("scenes/cornell.toml"))
            .args([
                "--width",
                "16",
                "--height",
                "8",
                "--spp",
                "100000",
                "--reference",
            ])
            .arg(&reference)
            .arg("--out")
            .arg(dir.join("exp")),
        Duration::from_secs(20),
    );
    let err = stderr(&o);
    assert!(!o.status.success());
    assert!(err.contains("8×8") && err.contains("16×8"), "{err}");
}

/// Options: negative values reach the range check; the same size error for `bench`
/// and `render`; options that do not apply are a warning; depth and normals are not
/// written to PNG, for scenes and models alike.
#[test]
fn options_are_consistent() {
    let dir = out_dir("options");
    let cornell = root().join("scenes/cornell.toml");
    let o = frepray()
        .arg("render")
        .arg(&cornell)
        .args(["--estimator", "optimal-direct", "--ridge", "-1", "-o"])
        .arg(dir.join("r.exr"))
        .output()
        .unwrap();
    let err = stderr(&o);
    assert!(!o.status.success());
    assert!(err.contains("--ridge") && !err.contains("tip:"), "{err}");
    let size_error = |cmd: &str| {
        let mut c = frepray();
        c.arg(cmd).arg(&cornell).args(["--width", "0"]);
        if cmd == "render" {
            c.arg("-o").arg(dir.join("w.exr"));
        }
        let o = c.output().unwrap();
        assert!(!o.status.success());
        stderr(&o)
    };
    assert_eq!(size_error("render"), size_error("bench"));
    let o = frepray()
        .arg("render")
        .arg(&cornell)
        .args(["--spp", "1", "--width", "4", "--height", "4", "--beta", "3"])
        .args(["--integrator", "direct", "--max-depth", "3", "-o"])
        .arg(dir.join("warn.exr"))
        .output()
        .unwrap();
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("warning: --beta has no effect"), "{err}");
    assert!(err.contains("warning: --max-depth has no effect"), "{err}");
    // An experiment warns about a flag that no estimator of its sweep uses, and only
    // then; `bench` takes the same flags (one set, `SceneFlags`).
    let experiment = |flag: &str, estimators: &str| {
        let o = frepray()
            .arg("experiment")
            .arg(&cornell)
            .args([
                "--spp",
                "1",
                "--reference-spp",
                "2",
                "--repeats",
                "1",
                "--quiet",
            ])
            .args(["--width", "4", "--height", "3", flag, "3"])
            .args(["--estimators", estimators, "-o"])
            .arg(dir.join(format!("exp{flag}{estimators}")))
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        stderr(&o)
    };
    assert!(!experiment("--beta", "balance,power").contains("warning"));
    let err = experiment("--beta", "balance,optimal-direct");
    assert!(err.contains("warning: --beta has no effect"), "{err}");
    let o = frepray()
        .arg("bench")
        .arg(&cornell)
        .args([
            "--spp",
            "1",
            "--width",
            "4",
            "--height",
            "3",
            "--pixel-center",
        ])
        .args(["--hide-emitters", "--max-depth", "2"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("| 4×3 | 1 |"));
}

/// `check` reads scenes too; an unknown kind of file lists every kind, no `0:0`.
#[test]
fn check_reads_scenes_and_names_every_kind() {
    let o = frepray()
        .arg("check")
        .arg(root().join("scenes/table.toml"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("objects:") && text.contains("lights:"),
        "{text}"
    );
    let dir = out_dir("check");
    let odd = dir.join("model.obj");
    std::fs::write(&odd, "v 0 0 0\n").unwrap();
    for cmd in ["check", "render"] {
        let mut c = frepray();
        c.arg(cmd).arg(&odd);
        if cmd == "render" {
            c.arg("-o").arg(dir.join("x.exr"));
        }
        let o = c.output().unwrap();
        let err = stderr(&o);
        assert!(!o.status.success());
        for kind in [".toml", ".json", ".frep", ".hf", ".vm"] {
            assert!(err.contains(kind), "{cmd}: {err}");
        }
        assert!(!err.contains(":0:0"), "{err}");
    }
    let o = frepray().arg("--help").output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("physically based renderer"), "{text}");
}

/// A negative number for an unsigned option is refused as a value of that option, not
/// with clap's tip to write `-- -1` (which would make it the input file).
#[test]
fn negative_numbers_are_refused_as_values() {
    for (cmd, flag) in [
        ("render", "--seed"),
        ("bench", "--spp"),
        ("experiment", "--width"),
    ] {
        let o = frepray()
            .arg(cmd)
            .arg(root().join("scenes/cornell.toml"))
            .args([flag, "-1"])
            .output()
            .unwrap();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(
            err.contains(&format!("invalid value '-1' for '{flag} ")),
            "{err}"
        );
        assert!(!err.contains("-- -1"), "{err}");
    }
}

/// `bench --plot` writes SVG: another name is refused before anything runs, not
/// written as SVG under a name that says otherwise.
#[test]
fn bench_plot_refuses_a_name_that_is_not_svg() {
    let dir = out_dir("plot");
    let o = frepray()
        .arg("bench")
        .arg(root().join("scenes/cornell.toml"))
        .args(["--spp", "1", "--width", "4", "--height", "4", "--plot"])
        .arg(dir.join("stages.png"))
        .output()
        .unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("stages.png: --plot writes an SVG drawing; name it .svg"),
        "{err}"
    );
    assert!(!dir.join("stages.png").exists());
}

/// A scene file's range errors say "a positive number", not the smallest double.
#[test]
fn range_errors_read_as_words() {
    let dir = out_dir("range");
    let text = std::fs::read_to_string(root().join("scenes/cornell.toml"))
        .unwrap()
        .replace("size = [0.5, 0.4]", "size = [-0.5, 0.4]");
    let scene = dir.join("bad.toml");
    std::fs::write(&scene, text).unwrap();
    let o = frepray().arg("check").arg(&scene).output().unwrap();
    let err = stderr(&o);
    assert!(!o.status.success());
    assert!(err.contains("expected a positive number"), "{err}");
    assert!(!err.contains("e-308") && err.len() < 400, "{err}");
}

/// Numbers so large that the light transport's sums overflow (a power of 1e308 gave NaN
/// pixels without a word) are refused, naming the key; NaN or infinite pixels that get
/// into an image all the same (here from a crafted state) are reported.
#[test]
fn overflowing_values_are_refused_or_reported() {
    let dir = out_dir("overflow");
    let text = std::fs::read_to_string(root().join("scenes/cornell.toml"))
        .unwrap()
        .replace("power = 30", "power = 1e308");
    let scene = dir.join("bright.toml");
    std::fs::write(&scene, text).unwrap();
    let o = frepray()
        .args(["render", "--spp", "1", "-o"])
        .arg(dir.join("bright.exr"))
        .arg(&scene)
        .output()
        .unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("lights[0].power: 1e308 is too large: scene numbers are at most 1e30"),
        "{err}"
    );
    // A state whose sums hold an infinity: `merge` writes the image and says so.
    let state = dir.join("s.state");
    let o = frepray()
        .arg("render")
        .arg(root().join("scenes/cornell.toml"))
        .args([
            "--spp", "1", "--width", "4", "--height", "3", "--quiet", "-o",
        ])
        .arg(&state)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let mut s = frepray::RenderState::read(&state).unwrap();
    s.data_mut()[1] = f64::INFINITY; // pixel (0, 0), red outside MIS
    s.write(&state).unwrap();
    let o = frepray()
        .arg("merge")
        .arg(&state)
        .arg("-o")
        .arg(dir.join("m.exr"))
        .output()
        .unwrap();
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("warning: 1 of 12 pixels are not finite"),
        "{err}"
    );
}

/// Pathological but legal functions finish within a bounded time per ray; a model
/// file too large to lower is refused with its size.
#[test]
fn pathological_functions_finish_and_huge_models_are_refused() {
    let dir = out_dir("pathological");
    for (name, f) in [
        ("div0", "x / 0"),
        ("inverse", "1 / sqrt(x*x + y*y + z*z) - 1"),
        ("pow", "pow(sphere([0, 0, 0], 1), 1e300)"),
    ] {
        let model = dir.join(format!("{name}.frep"));
        std::fs::write(
            &model,
            format!("bounds([-2, -2, -2], [2, 2, 2])\noutput {f}\n"),
        )
        .unwrap();
        let o = run_within(
            frepray()
                .arg("render")
                .arg(&model)
                .args(["--width", "16", "--height", "16", "--spp", "1", "-o"])
                .arg(dir.join(format!("{name}.exr"))),
            Duration::from_secs(60),
        );
        assert!(o.status.success(), "{name}: {}", stderr(&o));
    }
    let huge = dir.join("huge.vm");
    std::fs::File::create(&huge)
        .unwrap()
        .set_len(50 << 20)
        .unwrap();
    let o = run_within(frepray().arg("check").arg(&huge), Duration::from_secs(10));
    let err = stderr(&o);
    assert!(!o.status.success());
    assert!(err.contains("more than the 16777216"), "{err}");
}

/// The channel names of an EXR.
fn exr_channels(path: &Path) -> Vec<String> {
    let img = exr::prelude::read_all_flat_layers_from_file(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    img.layer_data[0]
        .channel_data
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect()
}

/// AOV channels have the same names and miss values for a scene and a bare model.
#[test]
fn aov_channels_and_misses_agree_for_scenes_and_models() {
    let dir = out_dir("aovs");
    std::fs::write(
        dir.join("ball.toml"),
        r#"[camera]
eye = [0, -4, 0]
target = [0, 0, 0]
fov = 30
resolution = [16, 16]

[render]
integrator = "direct"
spp = 1

[materials.white]
type = "diffuse"
reflectance = [0.7, 0.7, 0.7]

[[objects]]
name = "ball"
solid = "sphere([0, 0, 0], 0.3)"
material = "white"

[[lights]]
type = "sphere"
center = [0, -2, 3]
radius = 0.5
radiance = [10, 10, 10]
"#,
    )
    .unwrap();
    let render = |input: PathBuf, args: &[&str], out: &str| {
        let path = dir.join(out);
        let o = frepray()
            .arg("render")
            .arg(input)
            .args(["--width", "16", "--height", "16", "--spp", "1"])
            .args(args)
            .arg("-o")
            .arg(&path)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        path
    };
    let scene = render(
        dir.join("ball.toml"),
        &["--aovs", "depth,normal"],
        "scene.exr",
    );
    let ball = root().join("models/examples/bumpy_ball.frep");
    let depth = render(ball.clone(), &["--integrator", "depth"], "depth.exr");
    let normals = render(ball, &["--integrator", "normals"], "normals.exr");
    let scene_channels = exr_channels(&scene);
    for (model, names) in [
        (&depth, exr_channels(&depth)),
        (&normals, exr_channels(&normals)),
    ] {
        for n in names
            .iter()
            .filter(|n| !["R", "G", "B"].contains(&n.as_str()))
        {
            assert!(
                scene_channels.contains(n),
                "{n} of {model:?} not in {scene_channels:?}"
            );
            // The top-left pixel misses in both pictures: the same miss value.
            let (a, b) = (exr_channel(&scene, n)[0], exr_channel(model, n)[0]);
            assert!(a == b || (a.is_nan() && b.is_nan()), "{n}: {a} and {b}");
        }
    }
}

/// A message that cannot be written never costs the render: with stderr on a full disk
/// (`/dev/full`) or a pipe whose reader has gone, `render` exits 0 and writes its output
/// whole (the same bytes as with stderr intact).
#[test]
fn a_broken_stderr_keeps_the_render() {
    let d = out_dir("broken-stderr");
    let scene = root().join("scenes/many-lights.toml");
    let args = |name: &str| {
        let mut c = frepray();
        c.args([
            "render",
            scene.to_str().unwrap(),
            "--width",
            "32",
            "--height",
            "24",
        ])
        .args(["--spp", "2", "--seed", "5", "-o"])
        .arg(d.join(name));
        c
    };
    let ok = args("ok.exr").output().unwrap();
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    // The same pixels (the headers record each render's own statistics).
    let pixels = |p: &Path| frepray::Image::read_exr(p).unwrap().data().to_vec();
    let want = pixels(&d.join("ok.exr"));
    // stderr on a device that is always full.
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let st = args("full.exr").stderr(full).status().unwrap();
    assert!(st.success(), "{st:?}");
    assert_eq!(pixels(&d.join("full.exr")), want);
    // stderr a pipe whose reading end is closed before anything is written.
    let mut child = args("pipe.exr").stderr(Stdio::piped()).spawn().unwrap();
    drop(child.stderr.take());
    let st = child.wait().unwrap();
    assert!(st.success(), "{st:?}");
    assert_eq!(pixels(&d.join("pipe.exr")), want);
}

/// Usage errors (the argument parser's) exit 2, as docs/reliability.md lists; errors in
/// what the arguments name exit 1.
#[test]
fn usage_errors_exit_2_and_input_errors_exit_1() {
    let cornell = root().join("scenes/cornell.toml");
    let out = out_dir("usage").join("x.exr");
    for args in [
        vec!["render", "--no-such-flag"],
        vec!["render", "--spp", "many", "-o"],
        vec!["no-such-command"],
        vec!["render"],
    ] {
        let mut c = frepray();
        c.args(&args);
        if args.last() == Some(&"-o") {
            c.arg(&out);
        }
        let o = c.arg(&cornell).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("try '--help'"),
            "{args:?}: {}",
            stderr(&o)
        );
    }
    let o = frepray()
        .args(["render", "--estimator", "nonsense", "-o"])
        .arg(&out)
        .arg(&cornell)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(!out.exists());
}
