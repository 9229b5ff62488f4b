"""Identification options: ONE dataclass per method; each field is an option of ``bushenv fit``.

A field is declared with ``option(default, help, choices=...)``; the registry entry of a model
names its class (``ModelEntry.options``), and ``bushenv fit`` builds its flags, their help and
their defaults from these classes (``--n-past-x`` for ``n_past_x``). The library takes the same
names as keyword arguments. Nothing else lists option names.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from bushenv.identify.data import IdentificationError


def option(default: Any, help: str, choices: tuple[str, ...] | None = None) -> Any:
    """A dataclass field carrying its help text (and its allowed values, for strings)."""
    return dataclasses.field(default=default, metadata={"help": help, "choices": choices})


def option_like(cls: type, name: str, default: Any = dataclasses.MISSING) -> Any:
    """Option ``name`` of the options class ``cls`` again, with its help and choices, at
    ``default`` when given (another method's same option, or a subclass's own default)."""
    f = cls.__dataclass_fields__[name]
    value = f.default if default is dataclasses.MISSING else default
    return option(value, f.metadata["help"], f.metadata.get("choices"))


def option_fields(cls: type) -> list[dataclasses.Field]:
    return [f for f in dataclasses.fields(cls) if "help" in f.metadata]


def flag_of(name: str) -> str:
    return "--" + name.replace("_", "-")


def check_choices(opts: Any) -> None:
    """Every string option holds one of its choices; every number the type of its default."""
    for f in option_fields(type(opts)):
        value = getattr(opts, f.name)
        choices = f.metadata.get("choices")
        if choices and value not in choices:
            raise IdentificationError(
                f"option {f.name} must be one of {', '.join(choices)}, got {value!r}"
            )


def options_of(cls: type, given: Any, model: str) -> Any:
    """An instance of the options class ``cls`` from None, an instance or a mapping of names.

    Refuses a name ``cls`` does not declare (``unknown options [...] for model M; its
    options: ...``) and values of the wrong kind; runs the class's own ``check()``.
    """
    if given is None:
        given = {}
    if isinstance(given, cls):
        opts = given
    elif isinstance(given, Mapping):
        implied = getattr(cls, "implied", None)  # options one given option implies
        given = implied(dict(given)) if implied else given
        known = {f.name: f for f in option_fields(cls)}
        unknown = sorted(set(given) - set(known))
        if unknown:
            listed = ", ".join(known) or "none"
            raise IdentificationError(
                f"unknown options {unknown} for model {model!r}; its options: {listed}"
            )
        opts = cls(**{k: coerce(known[k], v) for k, v in given.items()})
    else:
        raise IdentificationError(
            f"options for model {model!r} must be a {cls.__name__} or a dict, "
            f"got {type(given).__name__}"
        )
    check_choices(opts)
    check = getattr(opts, "check", None)
    if check is not None:
        check()
    return opts


def coerce(f: dataclasses.Field, value: Any) -> Any:
    """``value`` as the type of the field's default (ints stay ints, tuples of ints)."""
    default = f.default
    try:
        if isinstance(default, tuple):
            items = value.split(",") if isinstance(value, str) else list(value)
            kind = type(default[0]) if default else int
            return tuple(_scalar(kind, v) for v in items if str(v).strip() != "")
        return _scalar(type(default), value)
    except (TypeError, ValueError):
        raise IdentificationError(
            f"option {f.name}: {value!r} is not {_kind_text(default)}"
        ) from None


def _scalar(kind: type, value: Any) -> Any:
    if kind is bool:
        raise TypeError("bool options are not supported")
    if kind is int:
        if isinstance(value, float) and not value.is_integer():
            raise ValueError(value)
        return int(str(value).strip()) if isinstance(value, str) else int(value)
    if kind is float:
        return float(value)
    if kind is str:
        if not isinstance(value, str):
            raise TypeError(value)
        return value
    return value


def _kind_text(default: Any) -> str:
    if isinstance(default, tuple):
        return "a comma-separated list of integers"
    return {int: "an integer", float: "a number", str: "text"}.get(type(default), "valid")


def describe(default: Any) -> str:
    """A default as the command line would take it: tuples as comma lists."""
    if isinstance(default, tuple):
        return ",".join(str(v) for v in default)
    return str(default)


def as_dict(opts: Any) -> dict[str, Any]:
    """Every option and its value (tuples as lists): what a model card records."""
    return {f.name: _plain(getattr(opts, f.name)) for f in option_fields(type(opts))}


def _plain(v: Any) -> Any:
    return list(v) if isinstance(v, tuple) else v


@dataclasses.dataclass(frozen=True)
class NoOptions:
    """A method without options (least squares is exact)."""
