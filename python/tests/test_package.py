"""The package's surface: the stubs describe the extension module exactly,
py.typed ships, and the public names are documented."""

import ast
import inspect
import pathlib

import splinewatch
from splinewatch import _splinewatch

PACKAGE = pathlib.Path(splinewatch.__file__).parent


def _public(names):
    return {n for n in names if not n.startswith("_") or n == "__version__"}


def test_the_stubs_name_exactly_what_the_extension_module_has():
    tree = ast.parse((PACKAGE / "_splinewatch.pyi").read_text())
    stubbed = {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            stubbed[node.name] = None
        elif isinstance(node, ast.ClassDef):
            stubbed[node.name] = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
        elif isinstance(node, ast.AnnAssign):
            stubbed[node.target.id] = None
    assert set(stubbed) == _public(dir(_splinewatch))
    for name, methods in stubbed.items():
        if methods is not None:
            assert methods == _public(dir(getattr(_splinewatch, name))) - {"__version__"}, name


def test_py_typed_ships_and_every_public_name_has_a_numpydoc_docstring():
    assert (PACKAGE / "py.typed").exists()
    for name in splinewatch.__all__:
        if name == "__version__":
            continue
        obj = getattr(splinewatch, name)
        doc = inspect.getdoc(obj)
        assert doc and len(doc) > 40, name
        if inspect.isfunction(obj) and inspect.signature(obj).parameters:
            assert "Parameters\n----------" in doc and "Returns\n-------" in doc, name
