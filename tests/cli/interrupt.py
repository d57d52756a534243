#!/usr/bin/env python3
"""An interrupted command leaves no hidden temporary behind, and its outputs keep what an earlier run wrote.

interrupt.py CLI GLTF WORK

Bakes GLTF, runs `play --dump-frames` of 4 frames with --json (the earlier run), then for each of SIGINT,
SIGTERM, SIGHUP, and SIGINT with SIGTERM right behind it, starts a run of 100,000 frames into the same folder and JSON, waits until its first frame's
hidden temporary exists, sends the signal, and checks: the process ended by that signal, the folder holds the
earlier run's frames byte for byte and nothing else, the JSON is the earlier one, no hidden file is left beside it.
Exit 0 when all hold ("SKIPPED" when GLTF is missing); 1 with what failed.
"""
import os
import signal
import subprocess
import sys
import time


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def snapshot(folder):
    return {name: open(os.path.join(folder, name), "rb").read() for name in sorted(os.listdir(folder))}


def hidden(folder):
    return sorted(name for name in os.listdir(folder) if name.startswith("."))


def main():
    cli, gltf, work = sys.argv[1:4]
    if not os.path.exists(gltf):
        print("SKIPPED: %s not found (the shared data)" % gltf)
        return 0
    os.makedirs(work, exist_ok=True)
    frames = os.path.join(work, "frames")
    report = os.path.join(work, "p.json")
    asset = os.path.join(work, "cm.sphc")
    os.makedirs(frames, exist_ok=True)
    for name in os.listdir(frames):
        os.remove(os.path.join(frames, name))
    for old in hidden(work):
        os.remove(os.path.join(work, old))

    subprocess.run([cli, "-q", "bake", gltf, "-o", asset], check=True)
    play = [cli, "-q", "play", asset, "--mesh", gltf, "--repeat", "1", "--dump-frames", frames, "--json", report]
    subprocess.run(play + ["--frames", "4"], check=True, stdout=subprocess.DEVNULL)
    earlier = snapshot(frames)
    earlier_report = open(report, "rb").read()
    if len(earlier) != 8:  # frame_0000..0003, .f32 and .joints
        fail("the earlier run wrote %d files, expected 8: %s" % (len(earlier), list(earlier)))

    # The last case sends SIGINT and SIGTERM back to back: the second waits while the first is handled.
    for sig, then in ((signal.SIGINT, None), (signal.SIGTERM, None), (signal.SIGHUP, None),
                      (signal.SIGINT, signal.SIGTERM)):
        name = signal.Signals(sig).name + ("+" + signal.Signals(then).name if then else "")
        # The signal's default action in the child, whatever this test's parent set (a background job ignores
        # SIGINT, nohup SIGHUP): the CLI keeps a signal its caller ignores.
        def defaults(signals=(sig, then)):
            for s in signals:
                if s:
                    signal.signal(s, signal.SIG_DFL)

        run = subprocess.Popen(play + ["--frames", "100000"], stdout=subprocess.DEVNULL, preexec_fn=defaults)
        deadline = time.monotonic() + 120
        while not hidden(frames):
            if run.poll() is not None:
                fail("%s: play ended (exit %s) before writing a frame" % (name, run.returncode))
            if time.monotonic() > deadline:
                run.kill()
                fail("%s: no frame temporary after 120 s" % name)
            time.sleep(0.01)
        staged = len(hidden(frames))
        run.send_signal(sig)
        if then:
            run.send_signal(then)
        try:
            code = run.wait(timeout=60)
        except subprocess.TimeoutExpired:
            run.kill()
            fail("%s: play still running 60 s after the signal" % name)  # a handler waiting on itself
        if code not in (-sig, -(then or sig)):
            fail("%s: play ended with %s, expected death by the signal (%d)" % (name, code, -sig))
        left = hidden(frames) + hidden(work)
        if left:
            fail("%s: %d hidden files left (%d staged when signalled), e.g. %s" % (name, len(left), staged, left[:3]))
        if snapshot(frames) != earlier:
            fail("%s: the folder does not hold the earlier run's frames byte for byte" % name)
        if open(report, "rb").read() != earlier_report:
            fail("%s: the JSON is not the earlier run's" % name)
        print("%s: ended by the signal with %d+ temporaries staged; none left, earlier outputs kept" % (name, staged))
    return 0


if __name__ == "__main__":
    sys.exit(main())
