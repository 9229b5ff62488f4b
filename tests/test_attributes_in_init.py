"""Every attribute of a class in the package is first set in ``__init__``: a method other than
``__init__`` (or ``__new__``, ``__post_init__``, ``__setstate__``) sets only attributes that an
``__init__`` of the class or of a base class in the package sets, a class-level assignment
declares, or a property names. The scan reads the source (``ast``); bases outside the package
are not seen."""

import ast
from pathlib import Path
from typing import NamedTuple

REPO = Path(__file__).resolve().parents[1]
PACKAGE = REPO / "bushenv"
CONSTRUCTORS = frozenset({"__init__", "__new__", "__post_init__", "__setstate__"})


class Late(NamedTuple):
    path: str
    line: int
    cls: str
    method: str
    attr: str


def _methods(cls: ast.ClassDef):
    return [f for f in cls.body if isinstance(f, ast.FunctionDef | ast.AsyncFunctionDef)]


def _self_stores(fn: ast.AST) -> set[str]:
    """Names of the ``self.X`` that ``fn`` stores: assigned (plain, annotated, augmented) or
    bound by ``for`` and ``with ... as``."""
    out = set()
    for node in ast.walk(fn):
        if isinstance(node, ast.Assign):
            targets = node.targets
        elif isinstance(node, ast.AnnAssign | ast.AugAssign | ast.For | ast.AsyncFor):
            targets = [node.target]
        elif isinstance(node, ast.withitem) and node.optional_vars is not None:
            targets = [node.optional_vars]
        else:
            continue
        for target in targets:
            for e in ast.walk(target):
                if (
                    isinstance(e, ast.Attribute)
                    and isinstance(e.ctx, ast.Store)
                    and isinstance(e.value, ast.Name)
                    and e.value.id == "self"
                ):
                    out.add(e.attr)
    return out


def _base_name(base: ast.expr) -> str | None:
    if isinstance(base, ast.Name):
        return base.id
    if isinstance(base, ast.Attribute):
        return base.attr
    return None


def late_attributes(sources: dict[str, str]) -> list[Late]:
    """The attributes that a method other than a constructor sets first, in ``sources``
    (path -> Python source). Bases are found by class name among ``sources``."""
    classes: dict[str, list[tuple[str, ast.ClassDef]]] = {}
    for path, text in sources.items():
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.ClassDef):
                classes.setdefault(node.name, []).append((path, node))

    def declared(cls: ast.ClassDef, seen: tuple[str, ...] = ()) -> set[str]:
        names = set()
        for item in cls.body:
            if isinstance(item, ast.Assign):
                names |= {t.id for t in item.targets if isinstance(t, ast.Name)}
            elif isinstance(item, ast.AnnAssign) and isinstance(item.target, ast.Name):
                names.add(item.target.id)
        for fn in _methods(cls):
            if fn.name in CONSTRUCTORS:
                names |= _self_stores(fn)
            if any(isinstance(d, ast.Name) and d.id == "property" for d in fn.decorator_list):
                names.add(fn.name)
        for base in map(_base_name, cls.bases):
            if base in classes and base not in seen:
                for _, base_cls in classes[base]:
                    names |= declared(base_cls, seen + (base,))
        return names

    late = []
    for name, defs in classes.items():
        for path, cls in defs:
            known = declared(cls, (name,))
            for fn in _methods(cls):
                if fn.name not in CONSTRUCTORS:
                    late += [
                        Late(path, fn.lineno, name, fn.name, attr)
                        for attr in sorted(_self_stores(fn) - known)
                    ]
    return sorted(late)


def _package_sources() -> dict[str, str]:
    return {p.relative_to(REPO).as_posix(): p.read_text() for p in PACKAGE.rglob("*.py")}


def test_every_attribute_is_first_set_in_init():
    late = [
        f"{x.path}:{x.line} {x.cls}.{x.method} sets {x.attr}"
        for x in late_attributes(_package_sources())
    ]
    assert not late, "set first outside __init__:\n" + "\n".join(late)


SYNTHETIC = """
class Base:
    shared = 0

    def __init__(self):
        self.a = 1

    @property
    def p(self):
        return 0


class Child(Base):
    def __init__(self):
        super().__init__()
        self.b = 2

    def reset(self):
        self.a, self.b = 0, 0  # both from an __init__
        self.shared += 1  # class-level
        self.late = 3  # first set here
        self.counter += 1  # never set in __init__ either

    def __setstate__(self, state):
        self.restored = state

    def helper(self):
        for self.loop in range(2):
            pass
        inner = lambda: None  # noqa: E731
        inner.x = 1  # not self
"""


def test_the_scan_finds_attributes_first_set_outside_init():
    late = late_attributes({"demo.py": SYNTHETIC})
    assert [(x.line, x.cls, x.method, x.attr) for x in late] == [
        (18, "Child", "reset", "counter"),
        (18, "Child", "reset", "late"),
        (27, "Child", "helper", "loop"),
    ]
    assert {x.path for x in late} == {"demo.py"}
