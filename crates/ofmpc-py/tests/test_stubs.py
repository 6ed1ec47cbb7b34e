"""The type stubs (ofmpc/__init__.pyi) describe the module as it is: every public
name, class member and function of the stubs exists at run time and vice versa, and
every public object has a docstring."""

from __future__ import annotations

import ast
import pathlib

import ofmpc

STUBS = pathlib.Path(ofmpc.__file__).with_name("__init__.pyi")


def stub_names():
    tree = ast.parse(STUBS.read_text())
    top, members = set(), {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            top.add(node.name)
            members[node.name] = {
                n.name for n in node.body if isinstance(n, ast.FunctionDef) and not n.name.startswith("_")
            }
        elif isinstance(node, ast.FunctionDef):
            top.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            top.add(node.target.id)
    return top, members


def test_stubs_match_the_runtime_module():
    assert STUBS.exists() and STUBS.with_name("py.typed").exists()
    top, members = stub_names()
    public = {n for n in ofmpc.__all__}
    assert public <= top, f"missing from the stubs: {public - top}"
    for name in top - {"ArrayLike", "F64Array"}:
        assert hasattr(ofmpc, name), f"the stubs declare ofmpc.{name}, the module has none"
    for cls, names in members.items():
        obj = getattr(ofmpc, cls)
        inherited = set(dir(BaseException)) if issubclass(obj, BaseException) else set()
        runtime = {n for n in dir(obj) if not n.startswith("_") and n not in inherited}
        assert names == runtime, f"{cls}: stubs only {names - runtime}, runtime only {runtime - names}"


def test_every_public_object_has_a_docstring():
    for name in ofmpc.__all__:
        obj = getattr(ofmpc, name)
        if callable(obj):
            assert (obj.__doc__ or "").strip(), name
            inherited = set(dir(BaseException)) if isinstance(obj, type) and issubclass(obj, BaseException) else set()
            for member in dir(obj) if isinstance(obj, type) else []:
                if not member.startswith("_") and member not in inherited:
                    assert (getattr(obj, member).__doc__ or "").strip(), f"{name}.{member}"
