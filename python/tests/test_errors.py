"""Every error path (no shared data): arguments of the wrong type, dtype, shape, strides or size; NaN and
infinite inputs; closed, truncated, bit-flipped, too old and too new assets; the bake's and evaluate's errors
(the CLI's message and code). Each raises — ValueError / TypeError for arguments, StatusError with the runtime
status name, BakeError / EvaluateError as the CLI prints them — and never crashes."""
import json
import os
import random
import shutil
import struct
import threading
import time

import numpy as np
import pytest

import spherechain
from conftest import BOXES, CREATURE, FAST, GOLDEN, SOURCE_DIR, cli_error
from spherechain import PAIR_DTYPE, BakeError, EvaluateError, StatusError

LIMBS_DETACHED = SOURCE_DIR / "tests" / "data" / "implausible" / "limbs_detached.json"


@pytest.fixture(scope="module")
def asset():
    return spherechain.bake(CREATURE, FAST)


@pytest.fixture
def ws(asset):
    return spherechain.Model(asset).workspace()


def status_of(excinfo):
    e = excinfo.value
    assert isinstance(e, StatusError) and isinstance(e, ValueError) and isinstance(e, spherechain.Error)
    assert str(e).startswith(e.status + ":"), str(e)
    return e.status


# ---- positions ---------------------------------------------------------------------------------------
def test_positions_of_the_wrong_kind(asset, ws):
    V = asset.vertex_count
    good = np.asarray(asset.bind_positions)
    cases = {
        "a list": good.tolist(),
        "float64": good.astype(np.float64),
        "float16": good.astype(np.float16),
        "int32": good.astype(np.int32),
        "(V, 4)": np.zeros((V, 4), np.float32),
        "(3V,)": good.reshape(-1),
        "(V, 3, 1)": good.reshape(V, 3, 1),
        "Fortran order": np.asfortranarray(good),
        "big-endian": good.astype(">f4"),
        "negative row stride": good[::-1],
    }
    for what, positions in cases.items():
        for call in (ws.refit, ws.narrow_phase):
            with pytest.raises(ValueError) as e:
                call(positions)
            assert not isinstance(e.value, StatusError), what
            message = str(e.value)
            assert "float32" in message and f"({V}, 3)" in message, (what, message)  # what it expects ...
            got = type(positions).__name__ if isinstance(positions, list) else str(positions.dtype)
            assert got in message, (what, message)  # ... and what it got


def test_positions_of_the_wrong_size_stride_alignment(asset, ws):
    V = asset.vertex_count
    good = np.asarray(asset.bind_positions)
    for positions in (good[:-1], np.zeros((V + 1, 3), np.float32), np.zeros((0, 3), np.float32)):
        for call in (ws.refit, ws.narrow_phase):
            with pytest.raises(StatusError) as e:
                call(positions)
            assert status_of(e) == "kErrorVertexCount"
            assert f"positions have {len(positions)} rows, the asset {V} vertices" in str(e.value)
    # A row stride of 0 (broadcast) and one that is not a multiple of 4.
    broadcast = np.broadcast_to(good[0], (V, 3))
    raw = np.zeros(V * 14 + 16, np.uint8)
    odd = np.lib.stride_tricks.as_strided(raw.view(np.float32)[:1], shape=(V, 3), strides=(14, 4))
    # Misaligned: float32 data at an odd address. narrow_phase reads the positions as refit does.
    buffer = np.zeros(V * 12 + 1, np.uint8)
    misaligned = np.frombuffer(buffer.data, dtype=np.float32, count=V * 3, offset=1).reshape(V, 3)
    for call in (ws.refit, ws.narrow_phase):
        for positions, status in ((broadcast, "kErrorStride"), (odd, "kErrorStride"), (misaligned, "kErrorAlignment")):
            with pytest.raises(StatusError) as e:
                call(positions)
            assert status_of(e) == status, call


def test_non_finite_positions(asset, ws):
    good = np.array(asset.bind_positions)
    for bad in (np.nan, np.inf, -np.inf):
        positions = np.full_like(good, bad)
        with pytest.raises(StatusError) as e:
            ws.refit(positions)
        assert status_of(e) == "kErrorNonFinitePositions"
        assert len(ws.detect("m2")) == 0, "non-finite spheres overlap nothing"
        with pytest.raises(StatusError) as e:
            ws.narrow_phase(positions)
        assert status_of(e) == "kErrorNonFinitePositions"
    ws.refit(good)  # recovers
    assert np.isfinite(ws.spheres).all()


def test_bad_call_arguments(asset, ws):
    good = np.asarray(asset.bind_positions)
    with pytest.raises(ValueError, match="mode"):
        ws.refit(good, mode="fast")
    with pytest.raises(ValueError, match="method"):
        ws.detect("m3")
    with pytest.raises(ValueError, match="method"):
        ws.detect(1)
    with pytest.raises(ValueError, match="margin"):
        ws.detect(margin=-1.0)
    with pytest.raises(TypeError):
        ws.detect(margin="wide")
    # Not finite as a float32 (NaN, inf, a double past 3.4e38 that would round to inf): ValueError naming it.
    for bad in (float("nan"), float("inf"), 1e39):
        for name in ("margin", "fold_margin"):
            with pytest.raises(ValueError, match=f"{name}: .* must be a finite number >= 0") as e:
                ws.detect(**{name: bad})
            assert not isinstance(e.value, StatusError)
        with pytest.raises(ValueError, match="closing: .* must be a finite number >= 0") as e:
            ws.fold_pairs(bad)  # 1e39 was inf in the runtime: "the asset has no crease rule", untrue here
        assert not isinstance(e.value, StatusError)
    assert ws.detect(margin=3e38).dtype == PAIR_DTYPE  # the largest float32s are lengths still
    assert ws.fold_pairs(3e38).dtype == PAIR_DTYPE
    with pytest.raises(StatusError) as e:
        ws.detect(fold_margin=0.01)  # the creature has no fold margin
    assert status_of(e) == "kErrorInvalidJob"
    with pytest.raises(TypeError, match="unexpected keyword argument 'positons'"):
        ws.refit(positons=good)
    with pytest.raises(TypeError, match="missing required argument 'positions'"):
        ws.refit()
    with pytest.raises(TypeError, match="at most"):
        ws.detect("m1", None, None, None, None)
    with pytest.raises(TypeError, match="multiple values"):
        ws.refit(good, positions=good)
    with pytest.raises(TypeError):
        spherechain.Workspace()
    with pytest.raises(TypeError):
        spherechain.Model("not an asset")


def test_no_instance_without_its_data(asset):
    # __new__ alone must not give an object whose methods read storage that was never constructed.
    with pytest.raises(TypeError, match="Workspace cannot be made directly: use Model.workspace"):
        spherechain.Workspace.__new__(spherechain.Workspace)
    with pytest.raises(TypeError, match="Asset cannot be made directly: use spherechain.load"):
        spherechain.Asset.__new__(spherechain.Asset)
    with pytest.raises(TypeError, match="Model"):
        spherechain.Model.__new__(spherechain.Model)
    # Nor pybind11's own __new__ or object's, past the class's: Python refuses them (the type's tp_new is its own).
    for cls in (spherechain.Workspace, spherechain.Asset, spherechain.Model):
        for base_new in (cls.__mro__[1].__new__, object.__new__):
            with pytest.raises(TypeError, match="is not safe"):
                base_new(cls)
    class Sub(spherechain.Asset):  # a Python subclass inherits the refusal, with or without its own __new__
        pass
    with pytest.raises(TypeError, match="Asset cannot be made directly"):
        Sub()
    class SubNew(spherechain.Asset):
        def __new__(cls):
            return spherechain.Asset.__mro__[1].__new__(cls)
    with pytest.raises(TypeError, match="is not safe"):
        SubNew()
    model = spherechain.Model.__new__(spherechain.Model, asset)  # __new__ builds it whole
    assert model.sphere_count == asset.sphere_count and model.vertex_count == asset.vertex_count
    assert model.workspace().spheres.shape == (asset.sphere_count, 4)
    model.__init__(asset)  # a second __init__ changes nothing
    assert spherechain.Model(asset=asset).sphere_count == asset.sphere_count
    with pytest.raises(TypeError):
        type("Sub", (spherechain.Model,), {})  # final: a subclass would get a Model from __new__


def test_bad_out_and_pairs(asset, ws):
    good = np.asarray(asset.bind_positions)
    for out in (np.empty(10, np.float32), np.empty((2, 10), PAIR_DTYPE), np.empty(20, PAIR_DTYPE)[::2], [1, 2]):
        with pytest.raises(ValueError, match="PAIR_DTYPE"):
            ws.detect(out=out)
    readonly = np.empty(10, PAIR_DTYPE)
    readonly.flags.writeable = False
    with pytest.raises(ValueError, match="writable"):
        ws.detect(out=readonly)
    # An equivalent dtype made elsewhere is accepted.
    assert ws.detect(out=np.empty(10, np.dtype(PAIR_DTYPE.descr))) == 0
    with pytest.raises(ValueError, match="PAIR_DTYPE"):
        ws.narrow_phase(good, pairs=np.zeros(3, np.uint32))
    with pytest.raises(ValueError, match="exclusions"):
        ws.narrow_phase(good, exclusions="some")
    with pytest.raises(ValueError, match="regions"):
        ws.narrow_phase(good, regions="everywhere")
    pairs = np.zeros(1, PAIR_DTYPE)
    pairs[0] = (5, 5, 0.0, 0)  # a >= b
    with pytest.raises(StatusError) as e:
        ws.narrow_phase(good, exclusions="crease", pairs=pairs)
    assert status_of(e) == "kErrorIndexOutOfRange"
    with pytest.raises(ValueError, match="closing"):
        ws.fold_pairs(-1.0)
    with pytest.raises(ValueError, match="closing"):
        ws.fold_pairs(float("nan"))
    with pytest.raises(StatusError) as e:
        ws.narrow_phase(good, pairs=pairs)
    assert status_of(e) == "kErrorIndexOutOfRange"
    with pytest.raises(StatusError) as e:
        ws.narrow_phase(good, exclusions="crease", crease=1e-9)  # narrower than baked
    assert status_of(e) == "kErrorInvalidJob" and "below the asset's" in str(e.value)
    with pytest.raises(StatusError) as e:
        ws.narrow_phase(good, exclusions="asset", crease=0.05)  # a crease outside the crease rule: not ignored
    assert status_of(e) == "kErrorInvalidJob" and "crease is for exclusions \"crease\" only" in str(e.value)
    for bad in (0.0, -0.05, float("nan"), float("inf"), 1e300):
        with pytest.raises(ValueError, match="crease: .* must be a finite number > 0"):
            ws.narrow_phase(good, exclusions="crease", crease=bad)
    with pytest.raises(TypeError, match="exclusions"):
        ws.narrow_phase(good, exclusions=1)
    with pytest.raises(TypeError, match="crease"):
        ws.narrow_phase(good, exclusions="crease", crease="wide")
    # Records read and written in place must sit at the structs' alignment (4), not at any byte.
    misaligned = np.frombuffer(bytearray(12 * 20 + 1), PAIR_DTYPE, count=20, offset=1)
    assert not misaligned.flags.aligned
    with pytest.raises(ValueError, match="PAIR_DTYPE"):
        ws.detect(out=misaligned)
    with pytest.raises(ValueError, match="PAIR_DTYPE"):
        ws.narrow_phase(good, pairs=misaligned)
    # A packed (align=False) equivalent dtype: NumPy calls any address aligned, the runtime's structs need 4.
    packed = np.dtype(PAIR_DTYPE.descr)
    assert packed.alignment == 1 and packed.itemsize == PAIR_DTYPE.itemsize
    for offset in (1, 2, 3):
        odd = np.frombuffer(bytearray(12 * 20 + 4), packed, count=20, offset=offset)
        assert odd.flags.aligned and odd.ctypes.data % 4 != 0
        with pytest.raises(ValueError, match="out: the records' data must be aligned to 4 bytes"):
            ws.detect(out=odd)
        with pytest.raises(ValueError, match="pairs: the records' data must be aligned to 4 bytes"):
            ws.narrow_phase(good, pairs=odd)
    at_four = np.frombuffer(bytearray(12 * 20 + 4), packed, count=20, offset=4)  # packed but at 4: accepted
    assert ws.detect(out=at_four) == len(ws.detect())
    ws.narrow_phase(good, exclusions="asset", pairs=at_four[:0])


def test_narrow_phase_statuses(asset, ws):
    """What narrow_phase's docstring lists beside the arguments' errors: pair indices and an asset without
    triangles (the positions' alignment and stride: test_positions_of_the_wrong_size_stride_alignment)."""
    S = asset.sphere_count
    good = np.asarray(asset.bind_positions)
    for a, b in ((0, S), (3, 0xFFFF), (2, 2), (7, 1)):
        pairs = np.zeros(2, PAIR_DTYPE)
        pairs[0] = (0, 1, 0.0, 0)
        pairs[1] = (a, b, 0.0, 0)
        for exclusions in ("asset", "none", "crease"):
            with pytest.raises(StatusError) as e:
                ws.narrow_phase(good, exclusions=exclusions, pairs=pairs)
            assert status_of(e) == "kErrorIndexOutOfRange"
    old = spherechain.Model(spherechain.load(GOLDEN / "v1" / "cesium_man.sphc")).workspace()
    zeros = np.zeros((old.model.vertex_count, 3), np.float32)
    for call in (lambda: old.narrow_phase(zeros, exclusions="asset"), lambda: old.fold_pairs(0.0)):
        with pytest.raises(StatusError) as e:
            call()
        assert status_of(e) == "kErrorMissingField" and "triangles" in str(e.value)


def test_pairs_are_the_callers_until_the_call_then_copied(asset, ws):
    """narrow_phase copies `pairs` before it releases the GIL: the job checks the indices and reads them again, so
    another thread writing the caller's array in between must not reach the runtime (an index past #S read and
    written out of bounds). Each call sees one state of the array: it returns, or raises kErrorIndexOutOfRange."""
    good = np.asarray(asset.bind_positions)
    pairs = np.zeros(20000, PAIR_DTYPE)
    pairs["a"], pairs["b"] = 0, 1
    ws.narrow_phase(good, exclusions="asset", pairs=pairs)
    pairs["b"] = 0xFFFF  # the same array changed after a call: the next call checks it again
    with pytest.raises(StatusError) as e:
        ws.narrow_phase(good, exclusions="asset", pairs=pairs)
    assert status_of(e) == "kErrorIndexOutOfRange"
    pairs["b"] = 1

    stop = threading.Event()
    def flip():
        b = pairs["b"]
        while not stop.is_set():
            b[:] = 0xFFFF
            b[:] = 1
    flipper = threading.Thread(target=flip)
    flipper.start()
    outcomes = set()
    try:
        end = time.monotonic() + 1.5
        while time.monotonic() < end:
            try:
                ws.narrow_phase(good, exclusions="asset", pairs=pairs)
                outcomes.add("ok")
            except StatusError as e:
                assert e.status == "kErrorIndexOutOfRange", e
                outcomes.add(e.status)
    finally:
        stop.set()
        flipper.join()
    assert outcomes, "no call ran"


def test_refit_of_finite_positions_that_overflow(asset, ws):
    good = np.asarray(asset.bind_positions, dtype=np.float64)
    huge = (good * 1e37).clip(-3e38, 3e38).astype(np.float32)
    assert np.isfinite(huge).all()
    with pytest.raises(StatusError) as e:
        ws.refit(huge)
    assert status_of(e) == "kErrorNonFinitePositions"
    assert "every position is finite" in str(e.value) and "NaN or infinite;" not in str(e.value)
    nan = np.array(asset.bind_positions)
    nan[:] = np.nan
    with pytest.raises(StatusError) as e:
        ws.refit(nan)
    assert "is NaN or infinite" in str(e.value)


def test_joint_matrices(asset, ws):
    J = asset.joint_count
    assert J > 0
    identity = np.zeros((J, 3, 4), np.float32)
    identity[:, 0, 0] = identity[:, 1, 1] = identity[:, 2, 2] = 1
    ws.refit_joints(identity)
    np.testing.assert_allclose(ws.spheres, asset.bind_spheres, rtol=1e-6, atol=1e-6)
    for bad in (identity.astype(np.float64), identity.reshape(J, 12), identity.reshape(J, 4, 3),
                np.ascontiguousarray(identity.transpose(0, 2, 1)).transpose(0, 2, 1), identity.tolist()):
        with pytest.raises(ValueError) as e:
            ws.refit_joints(bad)
        assert f"({J}, 3, 4)" in str(e.value)
    for count in (J - 1, J + 1):
        with pytest.raises(StatusError) as e:
            ws.refit_joints(np.zeros((count, 3, 4), np.float32))
        assert status_of(e) == "kErrorJointCount" and f"{count} matrices, the asset {J} joints" in str(e.value)
    nan = identity.copy()
    nan[:, 0, 3] = np.nan
    ws.reset()
    with pytest.raises(StatusError) as e:
        ws.refit_joints(nan)
    assert status_of(e) == "kErrorNonFiniteJoints"
    np.testing.assert_array_equal(ws.spheres, asset.bind_spheres)  # untouched
    # The narrow phase's matrices: the same shape, and aligned (an unaligned view is not a positions problem).
    misaligned = np.frombuffer(bytearray(identity.nbytes + 1), np.float32, count=J * 12, offset=1).reshape(J, 3, 4)
    assert not misaligned.flags.aligned
    for call in (lambda: ws.narrow_phase(np.asarray(asset.bind_positions), exclusions="crease", matrices=misaligned),
                 lambda: ws.refit_joints(misaligned)):  # the same check before either job: ValueError, not a status
        with pytest.raises(ValueError, match=rf"matrices: expected an aligned, .*\({J}, 3, 4\).* not aligned") as e:
            call()
        assert not isinstance(e.value, StatusError)
    old = spherechain.Model(spherechain.load(GOLDEN / "v2" / "cesium_man.sphc")).workspace()
    with pytest.raises(StatusError) as e:
        old.refit_joints(np.zeros((0, 3, 4), np.float32))
    assert status_of(e) == "kErrorMissingField"


def test_old_assets(asset):
    for version in ("v1", "v2", "v3"):
        old = spherechain.load(GOLDEN / version / "cesium_man.sphc")
        ws = spherechain.Model(old).workspace()
        zeros = np.zeros((old.vertex_count, 3), np.float32)
        ws.refit(zeros)
        ws.detect("m2")
        try:
            ws.narrow_phase(zeros)  # the asset's exclusions when it has triangles
        except StatusError as e:
            # baked before the narrow phase; or, with its triangles, every one collapsed onto the origin: each
            # box overlaps every other, past the job's budget (no pose of the character)
            assert e.status in ("kErrorMissingField", "kErrorFrameTangled"), e
        with pytest.raises(StatusError) as e:
            ws.narrow_phase(zeros, exclusions="crease")
        assert status_of(e) == "kErrorMissingField"
        assert old.bind_positions is None


# ---- assets that are closed, corrupt, truncated, of another version ----------------------------------
def test_closed_asset(asset):
    copy = spherechain.load(asset.to_bytes())
    ws = spherechain.Model(copy).workspace()
    with copy:
        pass
    assert copy.closed and "closed" in repr(copy)
    for use in (lambda: spherechain.Model(copy), copy.info, copy.to_bytes, lambda: copy.bind_spheres,
                lambda: copy.sphere_count, lambda: copy.save("x.sphc"),
                lambda: spherechain.evaluate(copy, CREATURE)):
        with pytest.raises(StatusError) as e:
            use()
        assert status_of(e) == "kErrorNullArgument" and "closed" in str(e.value)
    ws.refit(asset.bind_positions)  # the workspace holds the bytes
    ws.detect()


def schema_version_patched(data, version):
    b = bytearray(data)
    root = struct.unpack_from("<I", b, 0)[0]
    vtable = root - struct.unpack_from("<i", b, root)[0]
    field = struct.unpack_from("<H", b, vtable + 4)[0]  # Asset.schema_version, the table's first field
    struct.pack_into("<I", b, root + field, version)
    return bytes(b)


def test_corrupt_and_foreign_bytes(asset, tmp_path):
    data = asset.to_bytes()
    cases = {
        b"": "kErrorAssetTooSmall",
        data[:4]: "kErrorAssetTooSmall",
        b"\0" * 4 + b"NOPE" + data[8:]: "kErrorIdentifier",
        schema_version_patched(data, spherechain.SCHEMA_VERSION + 1): "kErrorVersionTooNew",
        schema_version_patched(data, 0): "kErrorVersionTooOld",
        data[: len(data) // 2]: None,  # some verifier error
    }
    for bytes_, status in cases.items():
        with pytest.raises(StatusError) as e:
            spherechain.load(bytes_)
        assert status is None or status_of(e) == status, str(e.value)
        path = tmp_path / "bad.sphc"
        path.write_bytes(bytes_)
        with pytest.raises(StatusError) as e:
            spherechain.load(path)
        assert str(path) in str(e.value)
    with pytest.raises(FileNotFoundError, match="no such file"):
        spherechain.load(tmp_path / "missing.sphc")
    with pytest.raises(OSError, match="folder"):
        spherechain.load(tmp_path)
    with pytest.raises(ValueError, match="contiguous"):
        spherechain.load(np.frombuffer(data, np.uint8)[::2])
    with pytest.raises(TypeError):
        spherechain.load(42)
    with pytest.raises(OSError):
        asset.save(tmp_path / "no" / "such" / "folder.sphc")


def exercise(loaded):
    """Whatever verified must run: model, workspace, refit, detect, narrow phase."""
    try:
        ws = spherechain.Model(loaded).workspace()
    except StatusError:
        return
    zeros = np.zeros((loaded.vertex_count, 3), np.float32)
    try:
        ws.refit(zeros)
    except StatusError:
        pass
    ws.detect("m1")
    ws.detect("m2")
    try:
        ws.narrow_phase(zeros)
    except StatusError:
        pass


def test_truncated_and_bit_flipped_assets_never_crash():
    data = (GOLDEN / "v4" / "creature.sphc").read_bytes()
    sizes = sorted(set(range(0, len(data), max(1, len(data) // 200))) | set(range(len(data) - 64, len(data))))
    for size in sizes:
        with pytest.raises(StatusError):
            spherechain.load(data[:size])
    rng = random.Random(1234)
    loaded = 0
    for _ in range(300):
        b = bytearray(data)
        bit = rng.randrange(len(b) * 8)
        b[bit // 8] ^= 1 << (bit % 8)
        try:
            a = spherechain.load(bytes(b))
        except StatusError:
            continue
        loaded += 1
        a.info()
        exercise(a)
    assert loaded > 0, "some flips land in values the loader accepts: those must run too"


def test_workspace_used_by_two_threads_at_once(asset):
    """One workspace per thread is the rule; breaking it raises RuntimeError, never races."""
    ws = spherechain.Model(asset).workspace()
    positions = np.asarray(asset.bind_positions)
    errors = []

    def hammer():
        for _ in range(2000):
            try:
                ws.refit(positions)
                ws.detect("m2")
            except RuntimeError as e:
                errors.append(e)

    threads = [threading.Thread(target=hammer) for _ in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert all("another thread" in str(e) for e in errors)


# ---- bake --------------------------------------------------------------------------------------------
def test_bake_errors_are_the_cli_errors(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"bogus": 1}))
    expected = cli_error("bake", CREATURE, "-o", tmp_path / "x.sphc", "--config", bad)
    with pytest.raises(BakeError) as e:
        spherechain.bake(CREATURE, str(bad))
    assert str(e.value) == expected and e.value.code == "config" and "unknown key 'bogus'" in e.value.message
    expected = cli_error("bake", BOXES, "-o", tmp_path / "x.sphc", "--region-map", LIMBS_DETACHED)
    with pytest.raises(BakeError) as e:
        spherechain.bake(BOXES, region_map=LIMBS_DETACHED)
    assert str(e.value) == expected and e.value.code == "implausible" and "PLAUS-LIMB-DETACHED" in str(e.value)
    assert isinstance(e.value, spherechain.OfflineError) and isinstance(e.value, spherechain.Error)
    assert not list(tmp_path.glob("x*")), "the CLI wrote nothing"


def test_bake_errors(tmp_path):
    cases = [
        ((tmp_path / "missing.obj",), {}, "io"),
        ((CREATURE, {"bogus": 1}), {}, "config"),
        ((CREATURE, {"max_spheres": "many"}), {}, "config"),
        ((CREATURE, {"max_spheres": 1}), {}, "config"),
        ((CREATURE,), {"regions": "some"}, "config"),
        ((CREATURE,), {"segmentation": "magic"}, "config"),
        ((CREATURE,), {"segmentation": "map"}, "config"),
        ((CREATURE,), {"vertices": "welded"}, "config"),
        ((CREATURE,), {"disk_step": -1.0}, "config"),
        ((CREATURE,), {"disk_step": float("nan")}, "config"),
        ((CREATURE, tmp_path / "missing.json"), {}, "io"),
        ((BOXES,), {"segmentation": "skeleton"}, "segmentation"),
    ]
    for args, kwargs, code in cases:
        with pytest.raises(BakeError) as e:
            spherechain.bake(*args, **kwargs)
        assert e.value.code == code, (args, kwargs, str(e.value))
        assert str(e.value) == f"{code}: {e.value.message}"
    (tmp_path / "broken.json").write_text("{")
    with pytest.raises(BakeError, match="not valid JSON"):
        spherechain.bake(CREATURE, tmp_path / "broken.json")
    with pytest.raises(TypeError):
        spherechain.bake(CREATURE, colour="red")
    with pytest.raises(TypeError):
        spherechain.bake(CREATURE, None, "paper")  # options are keywords
    with pytest.raises(TypeError):
        spherechain.bake(CREATURE, regions=5)
    # A value json cannot write: its own message, without pybind11's traceback of json.dumps.
    with pytest.raises(BakeError) as e:
        spherechain.bake(CREATURE, {"max_spheres": {1, 2}})
    assert e.value.code == "config" and "set is not a JSON value" in e.value.message, str(e.value)
    assert "At:" not in e.value.message and "encoder.py" not in e.value.message, str(e.value)


def test_paths_with_a_nul_or_bytes_that_are_not_utf8(asset, tmp_path):
    # A NUL inside a path: ValueError, as open() — the file system would stop there and use another file.
    asset.save(tmp_path / "a.sphc")
    for call in (lambda: spherechain.load(str(tmp_path / "a.sphc") + "\0garbage"),
                 lambda: asset.save(str(tmp_path / "b.sphc") + "\0.bak"),
                 lambda: spherechain.bake(str(CREATURE) + "\0x"),
                 lambda: spherechain.evaluate(asset, str(CREATURE) + "\0x")):
        with pytest.raises(ValueError, match="embedded null byte"):
            call()
    assert not (tmp_path / "b.sphc").exists()
    # Bytes that are not UTF-8 (the file system's own): the documented exception, its message escaped.
    odd = bytes(tmp_path) + b"/\xff"
    with pytest.raises(FileNotFoundError, match=r"\\xff/missing.sphc': no such file"):
        spherechain.load(os.fsdecode(odd + b"/missing.sphc"))  # load() takes bytes as an asset's bytes
    with pytest.raises(OSError, match=r"\\xff"):
        asset.save(odd + b"/no/x.sphc")
    with pytest.raises(BakeError) as e:
        spherechain.bake(odd + b"/missing.obj")
    assert e.value.code == "io" and "\\xff/missing.obj" in e.value.message, str(e.value)
    with pytest.raises(EvaluateError) as e:
        spherechain.evaluate(asset, odd + b"/missing.gltf")
    assert "\\xff" in str(e.value)
    corrupt = odd + b"bad.sphc"
    with open(corrupt, "wb") as f:
        f.write(b"x" * 64)
    with pytest.raises(StatusError, match=r"\\xffbad.sphc"):
        spherechain.load(os.fsdecode(corrupt))
    # A valid input at such a path bakes (its report was a RuntimeError of nlohmann::json).
    os.mkdir(odd)
    shutil.copy(CREATURE, odd + b"/creature.gltf")
    baked = spherechain.bake(odd + b"/creature.gltf", FAST)
    assert baked.report is not None and baked.sphere_count == asset.sphere_count


def test_a_region_name_that_is_not_utf8(asset):
    # The verifier lets any bytes through in a name: region_names escapes them, as info() does.
    data = bytearray(asset.to_bytes())
    name = asset.region_names[0].encode()
    at = data.find(name)
    assert at > 0
    data[at] = 0xFF
    names = spherechain.load(bytes(data)).region_names
    assert names[0] == "\\xff" + asset.region_names[0][1:], names


# ---- evaluate ----------------------------------------------------------------------------------------
def test_evaluate_errors_are_the_cli_errors(asset, tmp_path):
    path = tmp_path / "creature.sphc"
    asset.save(path)
    loaded = spherechain.load(path)
    cases = [
        ((loaded, BOXES), {}, ["--mesh", BOXES], "invalid-mesh"),
        ((loaded, CREATURE), {"clip": "nope"}, ["--mesh", CREATURE, "--clip", "nope"], "config"),
        ((loaded, CREATURE), {"sweep_margin": "x"}, ["--mesh", CREATURE, "--sweep-margin", "x"], "config"),
        ((loaded, CREATURE), {"margin": 2.0}, ["--mesh", CREATURE, "--margin", "2"], "config"),
    ]
    for args, kwargs, cli_args, code in cases:
        with pytest.raises(EvaluateError) as e:
            spherechain.evaluate(*args, **kwargs)
        assert e.value.code == code, str(e.value)
        assert str(e.value) == cli_error("evaluate", path, *cli_args), kwargs
    # The CLI refuses --frames 0 or past a million while parsing (a usage error, exit 2); the function says it
    # as a config error, whatever the integer (pybind11 raised TypeError for what does not fit 32 bits).
    for frames in (0, -1, 1_000_001, 2**32, 2**70):
        with pytest.raises(EvaluateError) as e:
            spherechain.evaluate(loaded, CREATURE, refit="paper", frames=frames)
        assert e.value.code == "config" and f"frames: {frames} is not in [1, 1000000]" in str(e.value), str(e.value)
    with pytest.raises(TypeError):
        spherechain.evaluate(loaded, CREATURE, frames=2.5)
    with pytest.raises(EvaluateError, match="regions"):
        spherechain.evaluate(loaded, CREATURE, regions="limbs")
    with pytest.raises(EvaluateError) as e:
        spherechain.evaluate(loaded, CREATURE, refit="joints", clip="cross", frames=2, sweep_margin=[0.5])
    assert e.value.code == "config" and "sweep-margin" in str(e.value)
