"""The offline side against the CLI, on the repository's own inputs (no shared data): bake() gives the CLI's
bytes for the same input, configuration and options; info() is `inspect --json`; save/load round trips;
the arrays view what info() counts; the bake report and the log lines."""
import json
import logging
import os

import numpy as np
import pytest

import spherechain
from conftest import BOXES, CREATURE, FAST, SOURCE_DIR, cli, load_json

LIMBS_DETACHED = SOURCE_DIR / "tests" / "data" / "implausible" / "limbs_detached.json"


@pytest.fixture(scope="module")
def baked(tmp_path_factory):
    """The creature baked by Python (config dict) and by the CLI (--config file), and the CLI's report."""
    work = tmp_path_factory.mktemp("baked")
    (work / "fast.json").write_text(json.dumps(FAST))
    cli("bake", CREATURE, "-o", work / "cli.sphc", "--config", work / "fast.json", "--report", work / "cli.json")
    asset = spherechain.bake(CREATURE, FAST)
    return work, asset


def test_bake_gives_the_cli_bytes(baked):
    work, asset = baked
    assert asset.to_bytes() == (work / "cli.sphc").read_bytes()
    assert asset.path is None
    # The configuration as a file path, as the CLI takes it: the same bytes.
    assert spherechain.bake(str(CREATURE), work / "fast.json").to_bytes() == asset.to_bytes()


def test_bake_options_give_the_cli_bytes(tmp_path):
    # region_map + force (an implausible body written anyway) through ApplyBakeOptions on both sides.
    cli("bake", BOXES, "-o", tmp_path / "cli.sphc", "--region-map", LIMBS_DETACHED, "--force")
    asset = spherechain.bake(BOXES, region_map=LIMBS_DETACHED, force=True)
    assert asset.to_bytes() == (tmp_path / "cli.sphc").read_bytes()
    assert asset.info()["forced_findings"], "the forced findings are in the asset"
    # An option overrides the configuration's key: regions "paper" over a config saying "extended".
    paper = spherechain.bake(BOXES, {"regions": "extended"}, region_map=LIMBS_DETACHED, force=True, regions="paper")
    cli("bake", BOXES, "-o", tmp_path / "paper.sphc", "--region-map", LIMBS_DETACHED, "--force", "--regions", "paper")
    assert paper.to_bytes() == (tmp_path / "paper.sphc").read_bytes()


def test_skin_weights_option_gives_the_cli_bytes(baked, tmp_path):
    # --skin-weights, the keyword and the configuration key write the same bytes; the asset grows by the rows.
    work, asset = baked
    (tmp_path / "fast.json").write_text(json.dumps(FAST))
    cli("bake", CREATURE, "-o", tmp_path / "skin.sphc", "--config", tmp_path / "fast.json", "--skin-weights")
    by_keyword = spherechain.bake(CREATURE, FAST, skin_weights=True)
    by_key = spherechain.bake(CREATURE, dict(FAST, skin_weights=True))
    assert by_keyword.to_bytes() == (tmp_path / "skin.sphc").read_bytes() == by_key.to_bytes()
    assert len(by_keyword.to_bytes()) > len(asset.to_bytes())
    # inspect says which asset carries them, and that both carry the crease rule; a golden v4 asset neither.
    assert by_keyword.info()["skin_contacts"]["skin_weights"] and not asset.info()["skin_contacts"]["skin_weights"]
    assert asset.info()["skin_contacts"]["crease"] > 0
    old = json.loads(cli("inspect", SOURCE_DIR / "tests" / "data" / "golden" / "v4" / "creature.sphc", "--json").stdout)
    assert old["skin_contacts"] == {"crease": None, "skin_weights": False}


def test_info_is_inspect_json(baked):
    work, asset = baked
    inspected = json.loads(cli("inspect", work / "cli.sphc", "--json").stdout)
    assert asset.info() == inspected
    assert spherechain.load(work / "cli.sphc").info() == inspected


def test_save_and_load_round_trip(baked, tmp_path):
    _, asset = baked
    path = tmp_path / "saved.sphc"
    asset.save(path)
    assert asset.path == str(path)
    assert path.read_bytes() == asset.to_bytes()
    loaded = spherechain.load(str(path))
    assert loaded.path == str(path) and loaded.to_bytes() == asset.to_bytes()
    for source in (asset.to_bytes(), bytearray(asset.to_bytes()), memoryview(asset.to_bytes()),
                   np.frombuffer(asset.to_bytes(), dtype=np.uint8)):
        from_bytes = spherechain.load(source)
        assert from_bytes.path is None and from_bytes.to_bytes() == asset.to_bytes()
    assert "spheres" in repr(loaded) and str(path) in repr(loaded)
    # A 2-D C-contiguous array is its bytes too; a strided one is refused.
    two_d = np.frombuffer(asset.to_bytes(), dtype=np.uint8).reshape(-1, 8)
    assert spherechain.load(two_d).to_bytes() == asset.to_bytes()
    with pytest.raises(ValueError, match="C-contiguous"):
        spherechain.load(np.frombuffer(asset.to_bytes() * 2, dtype=np.uint8)[::2])
    # A bytes path is the file system's name (os.fsencode), not the text "b'...'" (load() takes bytes as content).
    as_bytes = tmp_path / "as_bytes.sphc"
    asset.save(bytes(as_bytes))
    assert as_bytes.read_bytes() == asset.to_bytes() and asset.path == str(as_bytes)
    assert spherechain.bake(bytes(CREATURE), FAST).to_bytes() == asset.to_bytes()


def test_load_takes_bytes_as_contents_never_as_a_path(baked, tmp_path):
    """load(): a bytes object is the file's contents (documented: load's path is str or os.PathLike, and the stub's
    load takes no bytes path); a bytes path goes through os.fsdecode or a PathLike, which may return bytes."""
    _, asset = baked
    path = tmp_path / "contents.sphc"
    asset.save(os.fsencode(path))  # save(): a bytes path is a path
    with pytest.raises(spherechain.StatusError):  # load(): the same bytes are taken as a (far too short) asset
        spherechain.load(os.fsencode(path))
    assert spherechain.load(os.fsdecode(os.fsencode(path))).path == str(path)

    class BytesPath:
        def __fspath__(self):
            return os.fsencode(path)

    loaded = spherechain.load(BytesPath())
    assert loaded.path == str(path) and loaded.to_bytes() == asset.to_bytes()


def test_config_dict_takes_numpy_scalars(baked):
    _, asset = baked
    as_numpy = {k: (np.float64(v) if isinstance(v, float) else np.int64(v) if isinstance(v, int) and
                    not isinstance(v, bool) else v) for k, v in FAST.items()}
    assert any(isinstance(v, np.generic) for v in as_numpy.values())
    assert spherechain.bake(CREATURE, as_numpy).to_bytes() == asset.to_bytes()
    with pytest.raises(spherechain.BakeError, match="the config dict") as e:
        spherechain.bake(CREATURE, {"max_spheres": object()})
    assert e.value.code == "config"


def test_arrays_view_what_info_counts(baked):
    _, asset = baked
    info = asset.info()
    S, V, T = asset.sphere_count, asset.vertex_count, asset.triangle_count
    assert (S, V, T) == (info["spheres"], info["vertices"], info["triangles"])
    spheres = asset.bind_spheres
    assert spheres.dtype == np.float32 and spheres.shape == (S, 4)
    assert not spheres.flags.writeable and (spheres[:, 3] > 0).all()
    regions, tri_regions = asset.sphere_regions, asset.triangle_regions
    assert regions.dtype == np.uint8 and regions.shape == (S,)
    assert tri_regions.dtype == np.uint8 and tri_regions.shape == (T,)
    names = asset.region_names
    assert names == list(info["regions"].keys()) or sorted(names) == sorted(info["regions"].keys())
    for k, name in enumerate(names):
        assert int((regions == k).sum()) == info["regions"][name]["spheres"], name
        assert int((tri_regions == k).sum()) == info["regions"][name]["triangles"], name
    bind = asset.bind_positions
    assert bind.dtype == np.float32 and bind.shape == (V, 3) and not bind.flags.writeable
    assert asset.schema_version == info["schema_version"] and asset.joint_count == info["joint_refit"]["joints"]
    assert asset.chain_count == len(info["chains"])


def test_views_keep_the_bytes_alive(baked):
    _, asset = baked
    copy = spherechain.load(asset.to_bytes())
    spheres, expected = copy.bind_spheres, copy.bind_spheres.copy()
    copy.close()
    del copy
    import gc
    gc.collect()
    np.testing.assert_array_equal(spheres, expected)


def test_report_is_the_cli_report(baked):
    work, asset = baked
    cli_report, report = load_json(work / "cli.json"), asset.report
    for r in (cli_report, report):
        r.pop("timings_ms")
    assert report == cli_report
    assert spherechain.load(work / "cli.sphc").report is None


def test_bake_logs_to_the_spherechain_logger(caplog):
    with caplog.at_level(logging.DEBUG, logger="spherechain"):
        spherechain.bake(CREATURE, FAST)
    assert any(r.name == "spherechain" for r in caplog.records)


def test_version_and_dtypes():
    assert spherechain.__version__ == "0.1.0"
    assert spherechain.SCHEMA_VERSION >= 4
    assert spherechain.PAIR_DTYPE.itemsize == 12 and spherechain.PAIR_DTYPE.names == ("a", "b", "depth", "chains")
    assert spherechain.CONTACT_DTYPE.itemsize == 28
    assert spherechain.CONTACT_DTYPE.names == ("triangle_a", "triangle_b", "sphere_a", "sphere_b", "depth", "direction")
