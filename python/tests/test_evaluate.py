"""evaluate() returns what `spherechain evaluate --json` writes (timings aside), on the creature's clip (no
shared data) and options passed through (--refit, --regions, --sweep-margin, --no-coverage, --crease)."""
import re

import pytest

import spherechain
from conftest import CREATURE, FAST, cli, load_json

TIMING = re.compile(r"(^|_)(us|ms)($|_)")


def without_timings(value):
    """The report with every timing (keys with a "us" or "ms" word) left out: they differ run to run."""
    if isinstance(value, dict):
        return {k: without_timings(v) for k, v in value.items() if not TIMING.search(k)}
    if isinstance(value, list):
        return [without_timings(v) for v in value]
    return value


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    path = tmp_path_factory.mktemp("evaluate") / "creature.sphc"
    spherechain.bake(CREATURE, FAST).save(path)
    return path


@pytest.mark.parametrize("kwargs, flags", [
    ({"clip": "cross", "frames": 6}, ["--clip", "cross", "--frames", "6"]),
    ({"clip": "cross", "frames": 4, "refit": "joints", "regions": "asset", "coverage": False, "crease": 0.05,
      "sweep_margin": [0.0, 0.004]},
     ["--clip", "cross", "--frames", "4", "--refit", "joints", "--regions", "asset", "--no-coverage", "--crease", "0.05",
      "--sweep-margin=0,0.004"]),
    ({"frames": 4, "margin": 0.02, "sweep_margin": "auto", "coverage": False},
     ["--frames", "4", "--margin", "0.02", "--sweep-margin", "--no-coverage"]),
])
def test_evaluate_is_evaluate_json(saved, tmp_path, kwargs, flags):
    out = tmp_path / "evaluate.json"
    cli("evaluate", saved, "--mesh", CREATURE, *flags, "--json", out)
    report = spherechain.evaluate(spherechain.load(saved), CREATURE, **kwargs)
    assert without_timings(report) == without_timings(load_json(out))
    assert report["asset"] == str(saved) and report["mesh"] == str(CREATURE)


def test_evaluate_in_memory_asset_and_png(tmp_path):
    png = tmp_path / "missed.png"
    report = spherechain.evaluate(spherechain.bake(CREATURE, FAST), CREATURE, clip="cross", frames=4, coverage=False,
                                  png=png)
    assert report["asset"] == "(in memory)" and len(report["frames"]) == 4
    assert png.exists() or not report["summary"], "the picture is written when rsvg-convert is there"


def test_evaluate_outputs_checked_before_any_frame(saved, tmp_path):
    """png may not name an input (the CLI refuses it too), nor a missing folder or a folder; refused before a frame."""
    import shutil
    asset_copy = tmp_path / "creature.sphc"
    shutil.copy(saved, asset_copy)
    before = asset_copy.read_bytes()
    asset = spherechain.load(asset_copy)
    for png, code, words in ((asset_copy, "config", "png '.*' is also asset"),
                             (CREATURE, "config", "png '.*' is also mesh"),
                             (tmp_path / "missing" / "m.png", "io", "folder '.*' does not exist"),
                             (tmp_path, "io", "it is a folder")):
        with pytest.raises(spherechain.EvaluateError, match=words) as e:
            spherechain.evaluate(asset, CREATURE, clip="cross", frames=2, coverage=False, png=png)
        assert e.value.code == code
    assert asset_copy.read_bytes() == before
    pose = tmp_path / "pose.json"
    pose.write_text("{}")
    with pytest.raises(spherechain.EvaluateError, match="is also an input"):
        spherechain.evaluate(asset, CREATURE, frames=2, coverage=False, morph=[pose], png=pose)
    assert pose.read_text() == "{}"


def test_evaluate_morph_one_path(saved, tmp_path):
    """morph= a str or a pathlib.Path is one pose file (not a sequence of one-letter names)."""
    import pathlib
    missing = tmp_path / "no_such_pose.json"
    for morph in (str(missing), pathlib.Path(missing)):
        with pytest.raises(spherechain.EvaluateError, match="no_such_pose"):
            spherechain.evaluate(spherechain.load(saved), CREATURE, frames=4, coverage=False, morph=morph)
    with pytest.raises(TypeError, match="morph"):
        spherechain.evaluate(spherechain.load(saved), CREATURE, frames=4, coverage=False, morph=3)
