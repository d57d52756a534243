"""Shared fixtures of the spherechain Python tests (run by ctest: python/CMakeLists.txt sets the environment).

SPHERECHAIN_CLI: the `spherechain` executable of the same build; SPHERECHAIN_SHARED_DATA: ../shared/data
(tests that need it skip when it is absent); SPHERECHAIN_SOURCE_DIR: the source tree (tests/data).
"""
import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

SOURCE_DIR = Path(os.environ.get("SPHERECHAIN_SOURCE_DIR", Path(__file__).resolve().parents[2]))
SHARED_DATA = Path(os.environ.get("SPHERECHAIN_SHARED_DATA", SOURCE_DIR.parent / "shared" / "data"))
CLI = os.environ.get("SPHERECHAIN_CLI", str(SOURCE_DIR / "build" / "dev" / "cli" / "spherechain"))

CREATURE = SOURCE_DIR / "tests" / "data" / "creature" / "creature.gltf"
BOXES = SOURCE_DIR / "tests" / "data" / "implausible" / "boxes.obj"
GOLDEN = SOURCE_DIR / "tests" / "data" / "golden"
MAKEHUMAN = SHARED_DATA / "makehuman" / "base.obj"
CESIUM_MAN = SHARED_DATA / "gltf" / "CesiumMan.gltf"
# The creature bakes in ~0.2 s with a coarser voxel grid (tests/cli/creature.cmake does the same).
FAST = {"cover_voxel_rel": 0.01}


def require(path):
    """Skips the calling test (visibly: pytest -rs) when a shared-data input is absent."""
    if not Path(path).exists():
        pytest.skip(f"required test input not found: {path} (../shared/data is absent)")
    return Path(path)


def cli(*args, check=True):
    """Runs `spherechain -q ARGS...` (warnings and errors only; inspect and --json outputs unchanged); returns the
    CompletedProcess (text). check: fail the test on a non-zero exit."""
    if not Path(CLI).exists():
        pytest.fail(f"the CLI is not built: {CLI}")
    r = subprocess.run([CLI, "-q", *map(str, args)], capture_output=True, text=True)
    if check and r.returncode != 0:
        pytest.fail(f"spherechain {' '.join(map(str, args))}: exit {r.returncode}\n{r.stdout}{r.stderr}")
    return r


def cli_error(*args):
    """The CLI's error line without 'error: ' (it must fail: exit 1, or 2 for a usage error)."""
    r = cli(*args, check=False)
    assert r.returncode in (1, 2), f"exit {r.returncode}: {r.stdout}{r.stderr}"
    lines = [line for line in r.stderr.splitlines() if line.startswith("error: ")]
    assert lines, r.stderr
    return lines[-1][len("error: "):]


def read_frames(folder, vertex_count, joint_count=0):
    """The frames `spherechain play --dump-frames` wrote: positions float32 (#V, 3) and, when there, the joint
    matrices float32 (#J, 3, 4), in frame order."""
    positions, joints = [], []
    for p in sorted(Path(folder).glob("frame_*.f32")):
        positions.append(np.fromfile(p, dtype=np.float32).reshape(vertex_count, 3))
        j = p.with_suffix(".joints")
        if joint_count and j.exists():
            joints.append(np.fromfile(j, dtype=np.float32).reshape(joint_count, 3, 4))
    assert positions, f"no frames in {folder}"
    return positions, joints


def load_json(path):
    return json.loads(Path(path).read_text())


class Played:
    """A baked asset and what `spherechain play` made of it: the frames and its JSON per method."""

    def __init__(self, work, mesh, config=None, play_args=(), methods=("m1", "m2"), joints=False):
        import spherechain

        self.work = Path(work)
        self.mesh = Path(mesh)
        self.asset_path = self.work / "asset.sphc"
        args = ["bake", mesh, "-o", self.asset_path]
        if config:
            (self.work / "config.json").write_text(json.dumps(config))
            args += ["--config", self.work / "config.json"]
        cli(*args)
        self.asset = spherechain.load(self.asset_path)
        frames_dir = self.work / "frames"
        frames_dir.mkdir()
        self.json = {}
        for method in methods:
            out = self.work / f"play_{method}.json"
            extra = ["--dump-frames", frames_dir] if method == methods[0] else []
            cli("play", self.asset_path, "--mesh", mesh, "--method", method, "--repeat", "1", "--json", out,
                *play_args, *extra)
            self.json[method] = load_json(out)
        if joints:
            out = self.work / "play_joints.json"
            cli("play", self.asset_path, "--mesh", mesh, "--method", "m2", "--repeat", "1", "--refit", "joints",
                "--json", out, *play_args)
            self.json["joints"] = load_json(out)
        self.positions, self.joints = read_frames(frames_dir, self.asset.vertex_count, self.asset.joint_count)


@pytest.fixture(scope="session")
def creature(tmp_path_factory):
    """The synthetic creature (tests/data/creature, no shared data) baked by the CLI and its clip 'cross'
    (the fore legs crossing) played over 10 frames with the narrow phase."""
    return Played(tmp_path_factory.mktemp("creature"), CREATURE, FAST,
                  ("--clip", "cross", "--frames", "10", "--narrow-phase"), joints=True)
