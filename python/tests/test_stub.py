"""The type stub (spherechain/__init__.pyi, beside the module with py.typed) names what the module has: the same
public names, the same members per class, the same parameters per function and method, the same exception
bases; and every public function, class and method has a docstring (with shapes where it takes arrays)."""
import ast
import inspect
from pathlib import Path

import spherechain

PACKAGE = Path(spherechain.__file__).parent
STUB = ast.parse((PACKAGE / "__init__.pyi").read_text())
DUNDERS = {"__init__", "__enter__", "__exit__"}


def stub_top_level():
    names = {}
    for node in STUB.body:
        if isinstance(node, (ast.ClassDef, ast.FunctionDef)):
            names[node.name] = node
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names[node.target.id] = node
    return {k: v for k, v in names.items() if not k.startswith("_") or k == "__version__"}


def stub_params(fn):
    a = fn.args
    return [p.arg for p in a.posonlyargs + a.args + a.kwonlyargs if p.arg != "self"]


def runtime_params(obj):
    """Parameter names of a function or method: from its signature, else from pybind11's docstring line."""
    try:
        return [p for p in inspect.signature(obj).parameters if p != "self"]
    except (TypeError, ValueError):
        pass
    line = obj.__doc__.splitlines()[0]
    inner, depth, parts, cur = line[line.index("(") + 1:], 0, [], ""
    for ch in inner:
        if ch in "[(":
            depth += 1
        elif ch in "])":
            if depth == 0:
                break
            depth -= 1
        if ch == "," and depth == 0:
            parts.append(cur)
            cur = ""
        else:
            cur += ch
    parts.append(cur)
    names = [p.split(":")[0].split("=")[0].strip() for p in parts]
    return [n for n in names if n and n not in ("self", "*")]


def test_package_files():
    assert (PACKAGE / "py.typed").exists()
    assert any(PACKAGE.glob("_spherechain*.so"))


def test_top_level_names_match():
    stub = stub_top_level()
    assert set(stub) == set(spherechain.__all__) | {"__version__"}
    for name in stub:
        assert hasattr(spherechain, name), name
    public = {n for n in dir(spherechain) if not n.startswith("_")}
    assert public == set(spherechain.__all__)


def test_classes_match():
    for name, node in stub_top_level().items():
        if not isinstance(node, ast.ClassDef):
            continue
        cls = getattr(spherechain, name)
        assert isinstance(cls, type), name
        stub_bases = [b.id for b in node.bases if isinstance(b, ast.Name)]
        assert stub_bases == [b.__name__ for b in cls.__bases__ if b.__name__ != "object" and
                              not b.__name__.startswith("pybind11")], name
        if issubclass(cls, BaseException):
            continue  # their attributes (status, code, message) are set on the instance raised
        members = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
        public = {n for n in dir(cls) if not n.startswith("_")}
        assert {m for m in members if not m.startswith("_")} == public, name
        for m in members & DUNDERS:
            assert m in vars(cls), f"{name}.{m}"
        for n in node.body:
            if not isinstance(n, ast.FunctionDef) or n.name in ("__enter__", "__exit__"):
                continue
            if any(isinstance(d, ast.Name) and d.id == "property" for d in n.decorator_list):
                assert isinstance(vars(cls)[n.name], property), f"{name}.{n.name}"
                continue
            assert stub_params(n) == runtime_params(getattr(cls, n.name)), f"{name}.{n.name}"


def test_functions_match():
    for name, node in stub_top_level().items():
        if isinstance(node, ast.FunctionDef):
            assert stub_params(node) == runtime_params(getattr(spherechain, name)), name


def test_docstrings():
    for name in spherechain.__all__:
        obj = getattr(spherechain, name)
        if callable(obj):
            assert obj.__doc__ and len(obj.__doc__) > 20, name
        if isinstance(obj, type) and not issubclass(obj, BaseException):
            for member, value in vars(obj).items():
                if not member.startswith("_"):
                    assert value.__doc__ and value.__doc__.strip(), f"{name}.{member}"
    for method, shape in (("refit", "(#V, 3)"), ("refit_joints", "(#J, 3, 4)"), ("narrow_phase", "(#V, 3)")):
        doc = getattr(spherechain.Workspace, method).__doc__
        assert shape in doc and "float32" in doc, method
    assert "source units" in spherechain.Workspace.refit.__doc__


def test_load_takes_no_bytes_path():
    """load(source): bytes are the file's contents (its docstring and docs/python.md), so the stub's path part of
    `source` must not be _Path (which holds bytes: a bytes path for save(), bake(), evaluate())."""
    aliases = {n.targets[0].id: ast.unparse(n.value) for n in STUB.body
               if isinstance(n, ast.Assign) and isinstance(n.targets[0], ast.Name)}
    assert "bytes" in aliases["_Path"]
    load = next(n for n in STUB.body if isinstance(n, ast.FunctionDef) and n.name == "load")
    annotation = ast.unparse(load.args.args[0].annotation)
    path_aliases = [part.strip() for part in annotation.split("|") if part.strip() in aliases]
    assert path_aliases == ["_LoadPath"], annotation
    assert "bytes" not in aliases["_LoadPath"].replace("os.PathLike[bytes]", ""), aliases["_LoadPath"]
    assert "contents" in spherechain.load.__doc__ and "never a path" in spherechain.load.__doc__
    for fn in (spherechain.Asset.save, spherechain.bake, spherechain.evaluate):
        assert "bytes" in fn.__doc__, fn
