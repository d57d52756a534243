"""spherechain — self-collision detection for animated characters with sphere chains, from Python.

Offline: bake() a character file into an Asset (what `spherechain bake` writes, byte for byte), load() and
save() .sphc files, Asset.info() (what `spherechain inspect --json` prints), evaluate() (what
`spherechain evaluate --json` writes).

Per frame, zero-copy on NumPy arrays: Model(asset) once per asset, Model.workspace() once per character,
then Workspace.refit(positions) or refit_joints(matrices), Workspace.detect() (sphere pairs, PAIR_DTYPE)
and Workspace.narrow_phase(positions) (triangle contacts, CONTACT_DTYPE).

Errors: StatusError (a runtime status: .status is its name), BakeError and EvaluateError (.code and
.message, as the CLI prints them), all subclasses of spherechain.Error; ValueError for an argument of the
wrong dtype or shape. docs/python.md has the whole guide.
"""
from ._spherechain import (  # noqa: F401
    CONTACT_DTYPE,
    PAIR_DTYPE,
    SCHEMA_VERSION,
    Asset,
    BakeError,
    Error,
    EvaluateError,
    Model,
    OfflineError,
    StatusError,
    Workspace,
    __version__,
    bake,
    evaluate,
    load,
)

__all__ = [
    "Asset",
    "BakeError",
    "CONTACT_DTYPE",
    "Error",
    "EvaluateError",
    "Model",
    "OfflineError",
    "PAIR_DTYPE",
    "SCHEMA_VERSION",
    "StatusError",
    "Workspace",
    "bake",
    "evaluate",
    "load",
]

# Show the public names as spherechain.X (help(), repr, tracebacks), not spherechain._spherechain.X.
for _name in ("Asset", "Model", "Workspace", "bake", "evaluate", "load"):
    try:
        globals()[_name].__module__ = __name__
    except (AttributeError, TypeError):
        pass
del _name
