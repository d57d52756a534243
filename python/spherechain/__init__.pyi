# Type stubs of the package spherechain (the native module spherechain._spherechain, re-exported).
# Shapes: #V vertices, #T triangles, #S spheres, #J joints. Lengths in the character's source units.
import os
from typing import Any, Literal, Mapping, Sequence, SupportsIndex, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str
SCHEMA_VERSION: int
#: Workspace.detect() records: a uint16, b uint16 (sphere indices, a < b), depth float32 (rA + rB - |cA - cB|,
#: source units), chains uint32 (bit c: both in chain c). 12 bytes, runtime::Collision.
PAIR_DTYPE: np.dtype[np.void]
#: Workspace.narrow_phase() records: triangle_a, triangle_b uint32; sphere_a, sphere_b uint16; depth float32
#: (source units); direction float32 (3,) (unit push). 28 bytes.
CONTACT_DTYPE: np.dtype[np.void]

#: A path argument of save(), bake() and evaluate(): bytes are the file system's bytes (os.fsencode).
_Path = Union[str, bytes, os.PathLike[str], os.PathLike[bytes]]
#: load()'s source: a path, but never bytes (bytes-like objects are the file's contents).
_LoadPath = Union[str, os.PathLike[str], os.PathLike[bytes]]
_Float32Array = npt.NDArray[np.float32]
_Records = npt.NDArray[np.void]

class Error(Exception):
    """Base class of every error spherechain raises (besides ValueError / TypeError for bad arguments)."""

class StatusError(Error, ValueError):
    """A runtime call failed."""
    status: str  # the runtime status name, e.g. "kErrorVertexCount"
    code: int    # its value (runtime/status.h)

class OfflineError(Error):
    """An offline tool failed."""
    code: str     # "io", "format", "invalid-mesh", "segmentation", "fit", "config", "internal", "implausible"
    message: str

class BakeError(OfflineError):
    """bake() failed; str() is what `spherechain bake` prints after "error: "."""

class EvaluateError(OfflineError):
    """evaluate() failed; str() is what `spherechain evaluate` prints after "error: "."""

class Asset:
    """A verified .sphc asset in memory (bake() or load())."""
    def save(self, path: _Path) -> None:
        """Writes the bytes atomically to `path` (str, bytes or os.PathLike); `path` becomes the asset's path."""
    def info(self) -> dict[str, Any]:
        """What `spherechain inspect --json` prints."""
    def to_bytes(self) -> bytes:
        """The .sphc file's bytes (a copy)."""
    def close(self) -> None:
        """Drops this object's reference to the bytes (Models and Workspaces keep theirs); later uses of the
        bytes raise StatusError kErrorNullArgument (path, report, closed and repr still answer)."""
    @property
    def closed(self) -> bool: ...
    def __enter__(self) -> Asset: ...
    def __exit__(self, *args: object) -> None: ...
    @property
    def path(self) -> str | None:
        """The file loaded from or last saved to; None for one only in memory."""
    @property
    def report(self) -> dict[str, Any] | None:
        """A baked asset's bake report (`bake --report`); None for a loaded asset."""
    @property
    def schema_version(self) -> int: ...
    @property
    def sphere_count(self) -> int:
        """#S."""
    @property
    def vertex_count(self) -> int:
        """#V."""
    @property
    def triangle_count(self) -> int:
        """#T."""
    @property
    def chain_count(self) -> int: ...
    @property
    def joint_count(self) -> int:
        """#J (0 without joint weights)."""
    @property
    def region_names(self) -> list[str]:
        """Names of the region values (index = value)."""
    @property
    def bind_spheres(self) -> _Float32Array:
        """float32 (#S, 4): x, y, z, r at bind pose [source units]. Read-only view of the asset's bytes."""
    @property
    def bind_positions(self) -> _Float32Array | None:
        """float32 (#V, 3): the vertex buffer as baked [source units]. Read-only view; None for older assets."""
    @property
    def sphere_regions(self) -> npt.NDArray[np.uint8] | None:
        """uint8 (#S,): region per sphere. Read-only view."""
    @property
    def triangle_regions(self) -> npt.NDArray[np.uint8] | None:
        """uint8 (#T,): region per triangle. Read-only view."""

class Model:
    """What every character of one asset shares; immutable, thread-safe."""
    def __init__(self, asset: Asset) -> None: ...
    def workspace(self) -> Workspace:
        """A new Workspace (one character) at the bind pose."""
    def detect_bound(self, method: Literal["m1", "m2"] = "m1") -> int:
        """Most pairs detect(method) can report."""
    @property
    def sphere_count(self) -> int: ...
    @property
    def vertex_count(self) -> int: ...
    @property
    def joint_count(self) -> int: ...
    @property
    def chain_count(self) -> int: ...
    @property
    def contact_margin(self) -> float:
        """The asset's contact margin [source units]."""
    @property
    def fold_margin(self) -> float | None:
        """The asset's fold margin [source units], or None."""

class Workspace:
    """One character's spheres and scratch; one call at a time; the GIL is released while the runtime runs."""
    def refit(self, positions: _Float32Array, mode: Literal["frame", "paper"] = "frame") -> None:
        """Refits the spheres to float32 (#V, 3) positions, read in place: strides[1] == 4, and a row stride
        of at least 12 bytes that is a multiple of 4."""
    def refit_joints(self, matrices: _Float32Array) -> None:
        """Refits the spheres from float32 (#J, 3, 4) C-contiguous, 4-byte aligned skinning matrices."""
    @overload
    def detect(
        self,
        method: Literal["m1", "m2"] = "m1",
        margin: float | None = None,
        fold_margin: float | None = None,
        out: None = None,
    ) -> _Records:
        """Sphere pairs: a new PAIR_DTYPE array."""
    @overload
    def detect(
        self,
        method: Literal["m1", "m2"] = "m1",
        margin: float | None = None,
        fold_margin: float | None = None,
        *,
        out: _Records,
    ) -> int:
        """Sphere pairs written into `out` (PAIR_DTYPE); returns their count (> len(out): truncated)."""
    def narrow_phase(
        self,
        positions: _Float32Array,
        exclusions: Literal["crease", "asset", "none"] | None = None,
        pairs: _Records | None = None,
        regions: Literal["surrounding", "reach"] = "surrounding",
        crease: float | None = None,
        matrices: _Float32Array | None = None,
    ) -> _Records:
        """Exact triangle contacts: a new CONTACT_DTYPE array."""
    def fold_pairs(self, closing: float) -> _Records:
        """Excluded sphere pairs whose centres closed by more than `closing` since bind: a new PAIR_DTYPE array."""
    def reset(self) -> None:
        """Spheres back to the bind pose."""
    @property
    def spheres(self) -> _Float32Array:
        """float32 (#S, 4): the current spheres (a copy)."""
    @property
    def model(self) -> Model: ...

def load(source: _LoadPath | bytes | bytearray | memoryview | npt.NDArray[np.uint8]) -> Asset:
    """Loads and verifies a .sphc asset from a path (str, os.PathLike) or the file's contents (bytes-like: a bytes
    object is always the contents, never a path)."""

def bake(
    path: _Path,
    config: Mapping[str, Any] | _Path | None = None,
    *,
    regions: Literal["extended", "paper"] | None = None,
    segmentation: Literal["auto", "rig", "geometry", "skeleton", "map"] | None = None,
    region_map: _Path | None = None,
    vertices: Literal["joined", "source"] | None = None,
    rig: _Path | None = None,
    disk_step: float | None = None,
    force: bool = False,
    skin_weights: bool = False,
) -> Asset:
    """Bakes a character file (what `spherechain bake` writes, byte for byte)."""

def evaluate(
    asset: Asset,
    mesh: _Path,
    clip: str | None = None,
    frames: SupportsIndex = 40,
    *,
    morph: bool | _Path | Sequence[_Path] | None = None,
    poses_dir: _Path | None = None,
    rig: _Path | None = None,
    margin: float = 0.01,
    crease: float = 0.03,
    refit: Literal["frame", "paper", "joints"] = "frame",
    regions: Literal["asset", "paper"] = "asset",
    coverage: bool = True,
    sweep_margin: str | Sequence[float] | None = None,
    png: _Path | None = None,
) -> dict[str, Any]:
    """What `spherechain evaluate --json` writes, as a dict."""
