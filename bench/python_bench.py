#!/usr/bin/env python3
"""The Python layer's cost per call: Workspace.refit / detect / refit_joints from Python against the same
runtime jobs timed in C++ in the same process, on the same workspace and frames.

    build/dev/cli/spherechain bake ../shared/data/makehuman/base.obj -o mh.sphc
    mkdir -p frames && build/dev/cli/spherechain play mh.sphc --mesh ../shared/data/makehuman/base.obj --dump-frames frames
    PYTHONPATH=build/dev/python /usr/bin/python3 bench/python_bench.py mh.sphc frames --runs 5

Both sides are measured as bench/runtime_bench measures its sphere rows: per frame a batch of R calls (--reps),
the median per call over 5 rounds x the frames, the best median of K runs (--runs; a loaded machine only ever
makes a median slower). Detect rows run on each frame's spheres, refitted before the batch. The C++ side is
spherechain._spherechain._time_jobs (RefitJob / DetectJob / JointRefitJob::Run in a loop, no Python).
Python calls go through a local name (`refit = ws.refit`), in a plain for loop, which is counted.
"""
import argparse
import glob
import os
import sys
import time

import numpy as np

import spherechain
from spherechain import _spherechain


def load_frames(folder, vertex_count, joint_count):
    positions, joints = [], []
    for path in sorted(glob.glob(os.path.join(folder, "frame_*.f32"))):
        p = np.fromfile(path, dtype=np.float32)
        if p.size != 3 * vertex_count:
            sys.exit(f"{path}: {p.size} floats, the asset has {vertex_count} vertices")
        positions.append(p.reshape(vertex_count, 3))
        j = path[:-4] + ".joints"
        if joint_count and os.path.exists(j):
            joints.append(np.fromfile(j, dtype=np.float32).reshape(joint_count, 3, 4))
    if not positions:
        sys.exit(f"{folder}: no frame_NNNN.f32 (spherechain play ... --dump-frames {folder})")
    return positions, joints if len(joints) == len(positions) else []


def median_us(count, reps, prepare, batch):
    """Median over 5 rounds x `count` frames of batch(f) (which makes `reps` calls), per call, in µs."""
    samples = []
    for _ in range(5):
        for f in range(count):
            prepare(f)
            t0 = time.perf_counter_ns()
            batch(f)
            samples.append((time.perf_counter_ns() - t0) / 1e3 / reps)
    samples.sort()
    return samples[len(samples) // 2]


def python_rows(ws, model, frames, joints, reps):
    refit, detect = ws.refit, ws.detect
    out = np.empty(model.detect_bound("m2"), spherechain.PAIR_DTYPE)
    loop = range(reps)

    def nothing(f):
        pass

    def refit_frame(f):
        refit(frames[f])

    def refit_batch(f):
        p = frames[f]
        for _ in loop:
            refit(p)

    def detect_batch(method, into):
        if into is None:
            def run(f):
                for _ in loop:
                    detect(method)
        else:
            def run(f):
                for _ in loop:
                    detect(method, None, None, into)
        return run

    def refit_m1_batch(f):
        p = frames[f]
        for _ in loop:
            refit(p)
            detect("m1", None, None, out)

    rows = {
        "refit": median_us(len(frames), reps, nothing, refit_batch),
        "detect_m1": median_us(len(frames), reps, refit_frame, detect_batch("m1", out)),
        "detect_m1 (new array)": median_us(len(frames), reps, refit_frame, detect_batch("m1", None)),
        "detect_m2": median_us(len(frames), reps, refit_frame, detect_batch("m2", out)),
        "detect_m2 (new array)": median_us(len(frames), reps, refit_frame, detect_batch("m2", None)),
        "refit_m1": median_us(len(frames), reps, nothing, refit_m1_batch),
    }
    if joints:
        refit_joints = ws.refit_joints

        def joints_batch(f):
            m = joints[f]
            for _ in loop:
                refit_joints(m)

        rows["refit_joints"] = median_us(len(joints), reps, nothing, joints_batch)
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("asset")
    parser.add_argument("frames", help="folder of frame_NNNN.f32 (and .joints) from `spherechain play --dump-frames`")
    parser.add_argument("--reps", type=int, default=200, help="calls per timed batch (default 200)")
    parser.add_argument("--runs", type=int, default=3, help="measure K times, keep each row's best median (default 3)")
    a = parser.parse_args()

    asset = spherechain.load(a.asset)
    model = spherechain.Model(asset)
    ws = model.workspace()
    frames, joints = load_frames(a.frames, asset.vertex_count, asset.joint_count)
    py, cpp = {}, {}
    for _ in range(a.runs):
        for k, v in python_rows(ws, model, frames, joints, a.reps).items():
            py[k] = min(v, py.get(k, v))
        for k, v in _spherechain._time_jobs(ws, frames, joints or None, a.reps).items():
            cpp[k] = min(v, cpp.get(k, v))

    print(f"{a.asset}: {asset.sphere_count} spheres, {asset.vertex_count} vertices, {len(frames)} frames; "
          f"spherechain {spherechain.__version__}, Python {sys.version.split()[0]}, NumPy {np.__version__}")
    print(f"us per call, best of {a.runs} medians (batches of {a.reps} calls)")
    print(f"{'call':34s} {'Python':>8s} {'C++':>8s} {'added':>8s}")
    labels = {
        "refit": ("ws.refit(positions)", "refit"),
        "detect_m1": ('ws.detect("m1", out=buffer)', "detect_m1"),
        "detect_m1 (new array)": ('ws.detect("m1")', "detect_m1"),
        "detect_m2": ('ws.detect("m2", out=buffer)', "detect_m2"),
        "detect_m2 (new array)": ('ws.detect("m2")', "detect_m2"),
        "refit_m1": ("refit + detect m1 (out=)", "refit_m1"),
        "refit_joints": ("ws.refit_joints(matrices)", "refit_joints"),
    }
    for key, (label, cpp_key) in labels.items():
        if key in py:
            print(f"{label:34s} {py[key]:8.3f} {cpp[cpp_key]:8.3f} {py[key] - cpp[cpp_key]:8.3f}")


if __name__ == "__main__":
    main()
