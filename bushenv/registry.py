"""One registry per kind of thing (models, searchers, targets, effects): the only list of names.

A ``Registry`` maps a short lowercase name to an entry. CLI choices, "known names:" messages
and doc tables are built from it, so adding a thing is one registry line; a test can add a
dummy entry at run time and see every consumer accept it. An entry given as a
``"module:attribute"`` string (Gymnasium's ``entry_point``) is imported on first use, so a
registry can name things that import heavy packages (torch) or sit above it in the layers.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, Generic, TypeVar

T = TypeVar("T")


def load_entry_point(path: str) -> Any:
    """The object a ``"package.module:attribute"`` string names."""
    module, _, attr = path.partition(":")
    if not module or not attr:
        raise ValueError(f"entry point {path!r} must look like 'package.module:attribute'")
    return getattr(importlib.import_module(module), attr)


class Registry(Generic[T]):
    """name -> entry, in registration order; unknown names raise ``error`` listing the known.

    Parameters
    ----------
    kind : str
        What the entries are ("model", "searcher", ...), for messages.
    error : type[Exception]
        Raised for unknown or duplicate names (a ``ValueError`` subclass of the caller's module).
    """

    def __init__(self, kind: str, error: type[Exception] = KeyError) -> None:
        self.kind = kind
        self.error = error
        self._entries: dict[str, T] = {}
        self._aliases: dict[str, str] = {}

    def alias(self, old: str, name: str) -> None:
        """Let ``old`` (a name files or users wrote before) find ``name``'s entry; it is not
        listed among the names."""
        self._known(name)
        if old in self._entries:
            raise self.error(f"{self.kind} {old!r} is registered already")
        self._aliases[old] = name

    def canonical(self, name: str) -> str:
        """The registered name ``name`` stands for (itself, or what its alias points to)."""
        return self._aliases.get(name, name) if isinstance(name, str) else name

    def add(self, name: str, entry: T, *, replace: bool = False) -> T:
        """Register ``entry`` under ``name``; refuses a taken name unless ``replace``."""
        if not isinstance(name, str) or not name or name != name.strip():
            raise self.error(f"{self.kind} names are non-empty strings, got {name!r}")
        if name in self._entries and not replace:
            raise self.error(f"{self.kind} {name!r} is registered already")
        self._entries[name] = entry
        return entry

    def remove(self, name: str) -> T:
        return self._entries.pop(self._known(name))

    @contextmanager
    def temporarily(self, name: str, entry: T) -> Iterator[T]:
        """``entry`` registered under ``name`` inside the ``with`` block only (tests)."""
        self.add(name, entry)
        try:
            yield entry
        finally:
            self._entries.pop(name, None)

    def _known(self, name: Any) -> str:
        name = self.canonical(name)
        if not isinstance(name, str) or name not in self._entries:
            raise self.error(self.unknown_message(name))
        return name

    def unknown_message(self, name: Any) -> str:
        return f"unknown {self.kind} {name!r}; known names: {', '.join(self.names())}"

    def __getitem__(self, name: str) -> T:
        return self._entries[self._known(name)]

    def get(self, name: str, default: Any = None) -> T | Any:
        return self._entries.get(self.canonical(name), default)

    def names(self) -> tuple[str, ...]:
        return tuple(self._entries)

    def items(self):
        return self._entries.items()

    def values(self):
        return self._entries.values()

    def __contains__(self, name: object) -> bool:
        return name in self._entries or name in self._aliases

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}: {', '.join(self.names())})"
