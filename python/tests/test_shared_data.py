"""On the real characters of ../shared/data (skipped, visibly, when it is absent): MakeHuman baked from Python
is the CLI's asset byte for byte; the 40 recorded frames of its morph, refitted and detected from Python,
give the C++ runtime's pairs (as `spherechain play` reports them) for M1 and M2, and its narrow phase's
contacts; CesiumMan's walk from joint matrices; evaluate() on MakeHuman is `evaluate --json`."""
import numpy as np
import pytest

import spherechain
from conftest import CESIUM_MAN, MAKEHUMAN, Played, cli, load_json, require
from test_evaluate import without_timings
from test_runtime import played_pairs, records, region_pairs


@pytest.fixture(scope="module")
def makehuman(tmp_path_factory):
    require(MAKEHUMAN)
    return Played(tmp_path_factory.mktemp("makehuman"), MAKEHUMAN, play_args=("--narrow-phase",))


@pytest.fixture(scope="module")
def cesium_man(tmp_path_factory):
    require(CESIUM_MAN)
    return Played(tmp_path_factory.mktemp("cesium_man"), CESIUM_MAN, methods=("m2",), joints=True)


def test_makehuman_bake_is_the_cli_asset(makehuman):
    asset = spherechain.bake(MAKEHUMAN)
    assert asset.to_bytes() == makehuman.asset_path.read_bytes()
    assert asset.sphere_count == 128 and asset.vertex_count == 13380 and asset.triangle_count == 26756


@pytest.mark.parametrize("method", ["m1", "m2"])
def test_makehuman_frames_equal_the_runtime(makehuman, method):
    ws = spherechain.Model(makehuman.asset).workspace()
    frames = makehuman.json[method]["frames"]
    assert len(frames) == len(makehuman.positions) == 40
    pairs = 0
    for f, positions in enumerate(makehuman.positions):
        ws.refit(positions)
        got = ws.detect(method)
        assert records(got) == played_pairs(frames[f]), f"frame {f}"
        pairs += len(got)
    assert pairs > 0


def test_makehuman_narrow_phase_equals_the_runtime(makehuman):
    ws = spherechain.Model(makehuman.asset).workspace()
    for f in range(0, 40, 5):
        contacts = ws.narrow_phase(makehuman.positions[f])
        played = makehuman.json["m2"]["frames"][f]["narrow_phase"]
        assert len(contacts) == played["contacts"], f"frame {f}"
        deepest = region_pairs(makehuman.asset, contacts)
        assert sorted(deepest) == sorted(played["regions_in_contact"]), f"frame {f}"
        for key, depth in zip(played["regions_in_contact"], played.get("regions_in_contact_depth", [])):
            assert deepest[key] == np.float32(depth), f"frame {f} {key}"


def test_cesium_man_joints_and_vertices_equal_the_runtime(cesium_man):
    assert cesium_man.joints and len(cesium_man.joints) == len(cesium_man.positions)
    ws = spherechain.Model(cesium_man.asset).workspace()
    for f, (positions, matrices) in enumerate(zip(cesium_man.positions, cesium_man.joints)):
        ws.refit(positions)
        assert records(ws.detect("m2")) == played_pairs(cesium_man.json["m2"]["frames"][f]), f"frame {f}"
        ws.refit_joints(matrices)
        assert records(ws.detect("m2")) == played_pairs(cesium_man.json["joints"]["frames"][f]), f"frame {f}"


def test_makehuman_evaluate_is_evaluate_json(makehuman, tmp_path):
    out = tmp_path / "evaluate.json"
    cli("evaluate", makehuman.asset_path, "--mesh", MAKEHUMAN, "--frames", "16", "--no-coverage", "--json", out)
    report = spherechain.evaluate(spherechain.load(makehuman.asset_path), MAKEHUMAN, frames=16, coverage=False)
    assert report["animation"].startswith("morph"), "the default key poses were found"
    assert without_timings(report) == without_timings(load_json(out))
