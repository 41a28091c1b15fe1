"""Renders outside the main thread: a cancel handle, Ctrl-C, and the interpreter's exit.

Ctrl-C and exit are process-level, so each runs a child `python -c …` that renders a
16 x 16 scene for hours unless stopped, sends it SIGINT or lets it exit, and checks the
exit status and the output within a timeout: a render that is not stopped fails the
test instead of hanging it."""

import select
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest

import frepray
from conftest import small_dict

#: Renders that take hours unless stopped (16 x 16 pixels, one thread).
LONG = dict(spp=10_000_000, threads=1)

PRELUDE = f"""
import signal, sys, threading, time
# As in a terminal, also when the tests themselves run in the background (SIGINT ignored).
signal.signal(signal.SIGINT, signal.default_int_handler)
# SIGTERM and SIGHUP at their defaults too (`nohup` and some CI runners ignore SIGHUP).
signal.signal(signal.SIGTERM, signal.SIG_DFL)
signal.signal(signal.SIGHUP, signal.SIG_DFL)
sys.path.insert(0, {str(Path(__file__).parent)!r})
import frepray
from conftest import small_dict
d = small_dict()
d["camera"]["resolution"] = [16, 16]
SCENE = frepray.load_dict(d)
LONG = {LONG!r}
"""


def run_child(code, sigint_after=None, timeout=15.0, sig=signal.SIGINT):
    """Runs `code` after PRELUDE in a child Python; with `sigint_after`, sends it `sig`
    (SIGINT) that many seconds after it prints "rendering". Returns (status, stdout,
    stderr)."""
    p = subprocess.Popen([sys.executable, "-c", PRELUDE + textwrap.dedent(code)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        if sigint_after is not None:
            ready, _, _ = select.select([p.stdout], [], [], timeout)
            line = p.stdout.readline() if ready else ""
            assert line.strip() == "rendering", p.communicate(timeout=timeout)
            time.sleep(sigint_after)
            p.send_signal(sig)
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        p.kill()
        out, err = p.communicate()
        pytest.fail(f"the child still ran {timeout} s later\nstdout: {out}\nstderr: {err}")
    return p.returncode, out, err


def test_cancel_stops_a_render_in_another_thread():
    scene = frepray.load_dict(small_dict())
    cancel = frepray.Cancel()
    caught = []

    def work():
        try:
            frepray.render(scene, cancel=cancel, **LONG)
        except BaseException as e:  # noqa: B036 - the test inspects what was raised
            caught.append(e)

    t = threading.Thread(target=work)
    t.start()
    time.sleep(0.3)
    assert t.is_alive() and not cancel.cancelled
    cancel.cancel()
    t.join(5)
    assert not t.is_alive(), "the render ran on after cancel()"
    (e,) = caught
    assert isinstance(e, frepray.Cancelled) and isinstance(e, frepray.Error)
    assert e.state.partial
    assert 0 < e.state.sample_counts().max() < LONG["spp"]
    # A cancelled handle stops a render at once, and a model preview too.
    t0 = time.monotonic()
    with pytest.raises(frepray.Cancelled):
        frepray.render(scene, cancel=cancel, **LONG)
    m = frepray.model("output sphere([0, 0, 0], 1)")
    with pytest.raises(frepray.Cancelled) as e:
        m.preview(16, 16, spp=LONG["spp"], cancel=cancel)
    assert time.monotonic() - t0 < 5
    assert e.value.state.sample_counts().max() < LONG["spp"]


def test_cancel_stops_an_experiment(tmp_path):
    scene = frepray.load_dict(small_dict())
    cancel = frepray.Cancel()
    threading.Timer(0.3, cancel.cancel).start()
    t0 = time.monotonic()
    with pytest.raises(frepray.Cancelled):
        frepray.experiment(scene, ["balance"], [1], reference_spp=LONG["spp"], threads=1,
                           out=tmp_path, cancel=cancel)
    assert time.monotonic() - t0 < 5


POOL = """
from concurrent.futures import ThreadPoolExecutor
try:
    with ThreadPoolExecutor(1) as pool:
        f = pool.submit(frepray.render, SCENE, **LONG)
        print("rendering", flush=True)
        f.result()
except KeyboardInterrupt:
    e = f.exception(timeout=5)
    print(type(e).__name__, e.state.partial, e.state.sample_counts().max() < LONG["spp"])
"""

ASYNCIO = """
import asyncio
async def main():
    loop = asyncio.get_running_loop()
    f = loop.run_in_executor(None, lambda: frepray.render(SCENE, **LONG))
    print("rendering", flush=True)
    await f
try:
    asyncio.run(main())
except KeyboardInterrupt:
    print("KeyboardInterrupt True True")
"""

# IPython replaces SIGINT's handler before each cell: the hook must come back.
REPLACED = """
frepray.render(SCENE, spp=1)
signal.signal(signal.SIGINT, signal.default_int_handler)
""" + POOL


@pytest.mark.parametrize("code", [POOL, ASYNCIO, REPLACED],
                         ids=["thread-pool", "asyncio", "handler-replaced"])
def test_ctrl_c_stops_renders_in_other_threads(code):
    # Was: the worker rendered on after KeyboardInterrupt, and the pool's shutdown (or
    # asyncio's) waited for it: still running 30 s later.
    status, out, err = run_child(code, sigint_after=0.5)
    assert status == 0, err
    assert out.split() == ["KeyboardInterrupt", "True", "True"], (out, err)


def test_interpreter_exit_during_renders_in_daemon_threads():
    # Was: "FATAL: exception not rethrown" and SIGABRT: the render's thread took the
    # GIL after finalisation began and was unwound through Rust frames.
    status, out, err = run_child("""
        for _ in range(2):
            threading.Thread(target=frepray.render, args=(SCENE,), kwargs=LONG,
                             daemon=True).start()
        time.sleep(0.5)
        print("exiting")
    """)
    assert status == 0, err
    assert out.strip() == "exiting"
    assert "FATAL" not in err and "Abort" not in err, err


def test_a_cancelled_render_resumes_to_the_uninterrupted_one():
    """A render stopped part-way holds every pixel at fewer samples; ``resume=`` renders
    the rest into the uninterrupted render's state, bit for bit (even for the progressive
    estimator, whose weights depend on each pixel's samples in order)."""
    d = small_dict()
    d["camera"]["resolution"] = [12, 8]
    scene = frepray.load_dict(d)
    opts = dict(spp=16384, seed=3, threads=1, estimator="optimal-progressive")
    whole = frepray.render(scene, **opts)
    cancel = frepray.Cancel()
    threading.Timer(0.1, cancel.cancel).start()
    with pytest.raises(frepray.Cancelled) as e:
        frepray.render(scene, cancel=cancel, **opts)
    partial = e.value.state
    assert partial.partial
    resumed = frepray.render(scene, resume=partial, **opts)
    assert not resumed.partial
    assert resumed.to_bytes() == whole.to_bytes()
    with pytest.raises(ValueError, match="resume continues"):
        frepray.render(scene, resume=partial, samples=(0, 8), **opts)
    with pytest.raises(frepray.Error, match="seed is 3 here and 4 there"):
        frepray.render(scene, resume=partial, **{**opts, "seed": 4})


@pytest.mark.parametrize("sig,status", [(signal.SIGTERM, 143), (signal.SIGHUP, 129)],
                         ids=["SIGTERM", "SIGHUP"])
def test_sigterm_and_sighup_stop_a_render_and_keep_it(sig, status):
    # Was: the default action killed the process, the render lost. Now SystemExit with
    # the partial state: caught, it can be saved; uncaught, the status is 128 + signal.
    code, out, err = run_child("""
        try:
            print("rendering", flush=True)
            frepray.render(SCENE, **LONG)
        except SystemExit as e:
            print(e.code, e.state.partial, e.state.sample_counts().min() >= 1)
            raise
        finally:
            print("finally ran")
    """, sigint_after=0.5, sig=sig)
    assert code == status, err
    assert out.split() == [str(status), "True", "True", "finally", "ran"], (out, err)
    # The handler is put back after the render: the signal's default action again.
    code, out, err = run_child("""
        frepray.render(SCENE, spp=1)
        print(signal.getsignal(signal.SIGTERM) is signal.SIG_DFL,
              signal.getsignal(signal.SIGHUP) is signal.SIG_DFL)
    """)
    assert code == 0 and out.split() == ["True", "True"], (out, err)
