"""The per-frame side against the C++ runtime as the CLI runs it (`spherechain play`), on the synthetic
creature's clip 'cross' (no shared data): the frames `play --dump-frames` recorded, refitted and detected
from Python, give play's pairs (same pairs, order and float32 depths) for M1 and M2, from vertices and from
joint matrices; the narrow phase gives play's contacts; strided (interleaved) positions are read in place;
the out= buffer, spheres, threads and lifetimes."""
import gc
import threading

import numpy as np
import pytest

import spherechain
from spherechain import PAIR_DTYPE


def records(pairs):
    return [(int(p["a"]), int(p["b"]), np.float32(p["depth"])) for p in pairs]


def played_pairs(frame):
    return [(p["a"], p["b"], np.float32(p["depth"])) for p in frame["pairs"]]


def region_pairs(asset, contacts):
    regions = asset.sphere_regions

    def region(s):
        return int(regions[s]) if s < len(regions) else -1

    deepest = {}
    for c in contacts:
        ra, rb = region(int(c["sphere_a"])), region(int(c["sphere_b"]))
        key = f"R{min(ra, rb)}-R{max(ra, rb)}"
        deepest[key] = max(deepest.get(key, np.float32(0)), c["depth"])
    return deepest


@pytest.mark.parametrize("method", ["m1", "m2"])
def test_refit_detect_equal_play(creature, method):
    ws = spherechain.Model(creature.asset).workspace()
    frames = creature.json[method]["frames"]
    assert len(frames) == len(creature.positions) == 10
    assert any(f["pairs"] for f in frames), "the clip makes pairs"
    for f, positions in enumerate(creature.positions):
        ws.refit(positions)
        got = ws.detect(method)
        assert got.dtype == PAIR_DTYPE
        assert records(got) == played_pairs(frames[f]), f"frame {f}"
    ws.reset()
    assert records(ws.detect(method)) == played_pairs(creature.json[method]["bind"])


def test_refit_joints_detect_equal_play(creature):
    assert creature.joints, "play --dump-frames wrote the joint matrices"
    ws = spherechain.Model(creature.asset).workspace()
    for f, matrices in enumerate(creature.joints):
        ws.refit_joints(matrices)
        assert records(ws.detect("m2")) == played_pairs(creature.json["joints"]["frames"][f]), f"frame {f}"


def test_narrow_phase_equals_play(creature):
    ws = spherechain.Model(creature.asset).workspace()
    found = 0
    for f, positions in enumerate(creature.positions):
        contacts = ws.narrow_phase(positions)
        played = creature.json["m1"]["frames"][f]["narrow_phase"]
        assert contacts.dtype == spherechain.CONTACT_DTYPE
        assert len(contacts) == played["contacts"], f"frame {f}"
        deepest = region_pairs(creature.asset, contacts)
        assert sorted(deepest) == sorted(played["regions_in_contact"]), f"frame {f}"
        if "regions_in_contact_depth" in played:
            for key, depth in zip(played["regions_in_contact"], played["regions_in_contact_depth"]):
                assert deepest[key] == np.float32(depth), f"frame {f} {key}"
        if len(contacts):
            assert (contacts["depth"] >= 0).all()
            norms = np.linalg.norm(contacts["direction"], axis=1)
            assert np.all((np.abs(norms - 1) < 1e-5) | (norms == 0))
        found += len(contacts)
    assert found > 0, "the fore legs cross"
    # Behind the proxy's pairs, with the asset's exclusions: a subset of the unrestricted asset-exclusion answer.
    positions = creature.positions[5]
    ws.refit(positions)
    pairs = ws.detect("m2")
    behind = ws.narrow_phase(positions, pairs=pairs)
    every = ws.narrow_phase(positions, exclusions="asset")
    key = lambda c: (int(c["triangle_a"]), int(c["triangle_b"]))  # noqa: E731
    assert {key(c) for c in behind} <= {key(c) for c in every}
    assert np.isnan(every["depth"]).all(), "depths only under the crease rule"
    reach = ws.narrow_phase(positions, pairs=pairs, regions="reach")
    assert len(reach) >= len(behind)
    # The skin's contacts behind the proxy's pairs and its folds (play --narrow-behind): a subset of the crease
    # answer, with its depths; the folds are excluded neighbours that came closer than at bind.
    crease = ws.narrow_phase(positions)
    margin = ws.model.contact_margin
    wide = ws.detect("m2", margin=1.5 * margin, fold_margin=None if ws.model.fold_margin is None else 1.5 * margin)
    folds = ws.fold_pairs(2 * margin)
    assert folds.dtype == spherechain.PAIR_DTYPE and (folds["a"] < folds["b"]).all()
    assert len(ws.fold_pairs(1e6)) == 0, "no pair closes by a kilometre"
    restricted = ws.narrow_phase(positions, exclusions="crease", pairs=np.concatenate([wide, folds]), regions="reach")
    assert {key(c) for c in restricted} <= {key(c) for c in crease}
    assert len(restricted) > 0 and not np.isnan(restricted["depth"]).any()
    # Every pair listed: every contact between owned triangles.
    S = len(ws.spheres)
    every_pair = np.zeros(S * (S - 1) // 2, spherechain.PAIR_DTYPE)
    every_pair["a"], every_pair["b"] = np.triu_indices(S, 1)
    whole = {key(c) for c in ws.narrow_phase(positions, exclusions="crease", pairs=every_pair)}
    assert {key(c) for c in crease if c["sphere_a"] != 0xFFFF and c["sphere_b"] != 0xFFFF} <= whole


def test_narrow_phase_with_joint_matrices(creature):
    # Baked with the skin weights: the recorded frames' matrices skip neighbouring skin that moved rigidly,
    # and the contacts (records, depths, order) are those without them. Without the weights: refused.
    from conftest import FAST, CREATURE
    weighted = spherechain.Model(spherechain.bake(CREATURE, dict(FAST, skin_weights=True))).workspace()
    found = 0
    for f, (positions, matrices) in enumerate(zip(creature.positions, creature.joints)):
        plain = weighted.narrow_phase(positions)
        culled = weighted.narrow_phase(positions, matrices=matrices)
        assert plain.tobytes() == culled.tobytes(), f"frame {f}"
        found += len(culled)
    assert found > 0, "the clip makes contacts"
    ws = spherechain.Model(creature.asset).workspace()
    with pytest.raises(spherechain.StatusError) as e:
        ws.narrow_phase(creature.positions[0], matrices=creature.joints[0])
    assert e.value.status == "kErrorMissingField"
    with pytest.raises(ValueError):
        weighted.narrow_phase(creature.positions[0], matrices=creature.joints[0][:, :2])


def test_strided_positions_are_read_in_place(creature):
    """An interleaved vertex buffer (8 floats a vertex, x y z at floats 2..4) gives the contiguous answer."""
    model = spherechain.Model(creature.asset)
    contiguous, strided = model.workspace(), model.workspace()
    for positions in creature.positions:
        buffer = np.zeros((len(positions), 8), dtype=np.float32)
        buffer[:, 2:5] = positions
        view = buffer[:, 2:5]
        assert view.strides == (32, 4) and not view.flags.c_contiguous
        contiguous.refit(positions)
        strided.refit(view)
        np.testing.assert_array_equal(contiguous.spheres, strided.spheres)
        assert records(contiguous.detect("m2")) == records(strided.detect("m2"))
        assert len(contiguous.narrow_phase(positions)) == len(strided.narrow_phase(view))


def test_refit_paper_mode(creature):
    ws = spherechain.Model(creature.asset).workspace()
    ws.refit(creature.positions[3], mode="paper")
    paper = ws.spheres
    ws.refit(creature.positions[3])
    assert paper.shape == ws.spheres.shape and not np.array_equal(paper, ws.spheres)


def test_out_buffer(creature):
    model = spherechain.Model(creature.asset)
    ws = model.workspace()
    out = np.empty(model.detect_bound("m2"), PAIR_DTYPE)
    for positions in creature.positions:
        ws.refit(positions)
        for method in ("m1", "m2"):
            expected = ws.detect(method)
            n = ws.detect(method, out=out)
            assert isinstance(n, int) and n == len(expected)
            assert records(out[:n]) == records(expected)
    ws.refit(creature.positions[5])
    expected = ws.detect("m2")
    assert len(expected) >= 2
    small = np.zeros(1, PAIR_DTYPE)
    assert ws.detect("m2", out=small) == len(expected), "the count says how many there were"
    assert records(small) == records(expected[:1]), "truncated to the first"
    assert ws.detect("m2", None, None, out) == len(expected), "positional out"
    assert model.detect_bound("m1") <= model.detect_bound("m2")
    # A frame with more pairs than the workspace's first buffer (4,096 records): a margin wider than the body
    # makes every pair that is not excluded overlap. detect() grows its buffer and returns them all.
    everything = ws.detect("m2", margin=1e6)
    assert 4096 < len(everything) <= model.detect_bound("m2")
    n = ws.detect("m2", margin=1e6, out=out)
    assert n == len(everything) and records(out[:n]) == records(everything)


def test_spheres_and_margins(creature):
    asset = creature.asset
    model = spherechain.Model(asset)
    ws = model.workspace()
    np.testing.assert_array_equal(ws.spheres, asset.bind_spheres)
    ws.refit(asset.bind_positions)
    np.testing.assert_allclose(ws.spheres, asset.bind_spheres, rtol=1e-4, atol=1e-4 * asset.bind_spheres[:, 3].max())
    ws.refit(creature.positions[5])
    assert not np.array_equal(ws.spheres, asset.bind_spheres)
    ws.reset()
    np.testing.assert_array_equal(ws.spheres, asset.bind_spheres)
    assert model.sphere_count == asset.sphere_count and model.vertex_count == asset.vertex_count
    assert model.joint_count == asset.joint_count and model.chain_count == asset.chain_count
    assert model.contact_margin > 0 and model.fold_margin is None  # a creature has no fold margin
    ws.refit(creature.positions[5])
    default = ws.detect("m2")
    assert records(ws.detect("m2", margin=model.contact_margin)) == records(default)
    assert len(ws.detect("m2", margin=0.0)) <= len(default) <= len(ws.detect("m2", margin=10 * model.contact_margin))
    assert ws.model.sphere_count == model.sphere_count


def test_workspaces_on_threads(creature):
    """One Model, one Workspace per thread, the GIL released in the calls: each thread's answers are the
    single-threaded ones."""
    model = spherechain.Model(creature.asset)
    single = model.workspace()
    expected = []
    for positions in creature.positions:
        single.refit(positions)
        expected.append(records(single.detect("m2")))
    results, errors = {}, []

    def run(k):
        try:
            ws = model.workspace()
            got = []
            for _ in range(50):
                for positions in creature.positions:
                    ws.refit(positions)
                    got.append(records(ws.detect("m2")))
            results[k] = got
        except Exception as e:  # pragma: no cover - reported below
            errors.append(e)

    threads = [threading.Thread(target=run, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    for got in results.values():
        assert got == expected * 50


def test_workspace_outlives_model_and_asset(creature):
    asset = spherechain.load(creature.asset.to_bytes())
    ws = spherechain.Model(asset).workspace()
    asset.close()
    del asset
    gc.collect()
    ws.refit(creature.positions[5])
    assert records(ws.detect("m2")) == played_pairs(creature.json["m2"]["frames"][5])
    assert len(ws.narrow_phase(creature.positions[5])) == creature.json["m1"]["frames"][5]["narrow_phase"]["contacts"]
