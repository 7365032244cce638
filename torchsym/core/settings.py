"""Settings objects: one frozen dataclass per solver, validated once.

A solver's settings are written down in one place, a subclass of :class:`Settings` whose
fields are declared with :func:`setting` (a default, a one-line meaning, a unit and the
allowed range) or :func:`group` (a nested :class:`Settings`, for settings whose names
already share a purpose, in the style of Open3D's ``ICPConvergenceCriteria``)::

    @dataclasses.dataclass(frozen=True)
    class Refine(Settings):
        max_iters: int = setting(4, "refinement rounds", low=0)
        n_neighbors: int = setting(25, "neighbours per vertex", low=1)

    @dataclasses.dataclass(frozen=True)
    class MySettings(Settings):
        n_samples: int = setting(500, "points sampled to score candidates", low=1)
        eps_theta: float = setting(2.0, "angle tolerance", unit="deg", low=0.0, high=180.0)
        refine: Refine = group(Refine)

Construction checks every field against its annotation (``bool`` fields take only
``True``/``False``, ``int`` fields no floats or bools, ``Literal`` fields one of their
values) and its range, and raises :class:`~torchsym.errors.ConfigError` naming the field
by its dotted path (``refine.max_iters: expected an int >= 0, got -1``). The function of a
method takes ``settings`` (and keyword overrides, see :func:`resolve_settings`); its
``nn.Module`` holds the settings (:class:`Solver`); the registry and the YAML checker read
the same fields, so a YAML step may nest groups (``refine: {max_iters: 2}``) and a typo at
any depth is reported with the valid names.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import types
import typing
from collections.abc import Callable, Mapping
from typing import Any, ClassVar, Literal, TypeVar, Union, get_args, get_origin

from torch import nn

from torchsym.errors import ConfigError

__all__ = ["Settings", "Solver", "group", "resolve_settings", "setting"]

S = TypeVar("S", bound="Settings")

_MISSING = dataclasses.MISSING


def setting(
    default: Any,
    doc: str,
    *,
    unit: str = "",
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
) -> Any:
    """A settings field: its default, a one-line meaning, its unit and its allowed range.

    Args:
        default: the default value (immutable: a number, string, bool, None or tuple).
        doc: what the setting means, one line (read by the glossary and ``--help``).
        unit: ``"deg"``, ``"px"``, ``"s"``, ``"input units"``, ``"x spacing"``... or empty
            for counts, flags and fractions.
        low, high: inclusive bounds (exclusive with ``low_open`` / ``high_open``) for
            numbers; for a tuple, each element. Without ``high``, a positive number's
            bound is :func:`default_ceiling` of its default (a seed's, the largest a
            ``torch.Generator`` takes): every setting has a bound that a real use never
            meets and a machine can afford, so a mistyped 1e9 is an error, not gigabytes.
    """
    derived = high is None
    if derived:
        high = default_ceiling(default, doc)
    meta = {"doc": doc, "unit": unit, "low": low, "high": high, "low_open": low_open, "high_open": high_open,
            "derived_high": derived and high is not None}
    return dataclasses.field(default=default, metadata=meta)


#: the largest seed: ``torch.Generator.manual_seed`` takes up to 2**64 - 1
MAX_SEED = 2**64 - 1


def default_ceiling(default: Any, doc: str = "") -> float | None:
    """The upper bound of a setting declared without one: :data:`MAX_SEED` for a seed;
    for a positive number, 100x its default rounded up to a power of ten (a count of 10:
    1,000; a tolerance of 0.005: 1); None for other defaults (0, None, strings, flags),
    which declare their ``high``. Tuples: their largest element's."""
    if "seed" in doc.lower().split(" ")[:4] or doc.lower().startswith("seed"):
        return MAX_SEED
    values = default if isinstance(default, tuple) else (default,)
    numbers = [abs(v) for v in values if isinstance(v, (int, float)) and not isinstance(v, bool) and v]
    if not numbers or len(numbers) != len(values):
        return None
    ceiling = 10.0 ** math.ceil(math.log10(100 * max(numbers)))
    return int(ceiling) if all(isinstance(v, int) for v in values) else ceiling


def group(cls: type[S], doc: str = "") -> Any:
    """A nested group of settings, defaulting to ``cls()``."""
    return dataclasses.field(default_factory=cls, metadata={"doc": doc or (cls.__doc__ or "").strip().splitlines()[0]})


def _suggest(word: str, choices: list[str]) -> str:
    close = difflib.get_close_matches(word, choices, n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _describe(hint: Any) -> str:
    origin = get_origin(hint)
    if origin is Literal:
        return "one of " + ", ".join(repr(a) for a in get_args(hint))
    if origin in (Union, types.UnionType):
        return " or ".join(_describe(a) for a in get_args(hint))
    if origin is tuple:
        return "a list of " + _describe(get_args(hint)[0]) + "s"
    if hint is type(None):
        return "null"
    name = getattr(hint, "__name__", str(hint))
    return {"int": "an int", "float": "a number", "bool": "true or false", "str": "a string"}.get(name, name)


def _range_text(meta: Mapping[str, Any]) -> str:
    parts = []
    if meta.get("low") is not None:
        parts.append(f"{'>' if meta['low_open'] else '>='} {meta['low']}")
    if meta.get("high") is not None:
        parts.append(f"{'<' if meta['high_open'] else '<='} {meta['high']}")
    return " and ".join(parts)


# A float setting enters float32 arithmetic, often squared (a sigma, a tolerance): its
# magnitude must keep its square a normal float32 number, or 0.
FLOAT_MAGNITUDE = (1e-18, 1e18)


def _in_range(value: float, meta: Mapping[str, Any]) -> bool:
    if isinstance(value, float) and not math.isfinite(value):
        return False
    if isinstance(value, float) and value != 0 and not FLOAT_MAGNITUDE[0] <= abs(value) <= FLOAT_MAGNITUDE[1]:
        return False
    low, high = meta.get("low"), meta.get("high")
    if low is not None and (value <= low if meta["low_open"] else value < low):
        return False
    if high is not None and (value >= high if meta["high_open"] else value > high):
        return False
    return True


def _coerce(value: Any, hint: Any, meta: Mapping[str, Any], path: str) -> Any:
    """``value`` checked against the annotation ``hint`` and the range in ``meta``.

    Ints are accepted for float fields (and become floats), lists for tuple fields;
    nothing else is converted.
    """
    origin = get_origin(hint)
    if origin in (Union, types.UnionType):
        args = get_args(hint)
        if value is None and type(None) in args:
            return None
        for a in args:
            if a is type(None):
                continue
            try:
                return _coerce(value, a, meta, path)
            except ConfigError:
                continue  # try the union's next type
        kinds = " or ".join(_describe(a) for a in args if a is not type(None))
        null = " or null" if type(None) in args else ""
        raise ConfigError(f"{path}: expected {kinds}{_with_range(meta)}{null}, got {value!r}")
    if origin is Literal:
        if any(value == a and type(value) is type(a) for a in get_args(hint)):
            return value
        raise ConfigError(f"{path}: expected {_describe(hint)}, got {value!r}{_suggest(str(value), [str(a) for a in get_args(hint)])}")
    if origin is tuple:
        if not isinstance(value, (tuple, list)):
            raise ConfigError(f"{path}: expected {_describe(hint)}, got {value!r}")
        item = get_args(hint)[0]
        return tuple(_coerce(v, item, meta, f"{path}[{i}]") for i, v in enumerate(value))
    if hint is bool:
        if isinstance(value, bool):
            return value
        raise ConfigError(f"{path}: expected true or false, got {value!r}")
    if hint is int:
        if isinstance(value, int) and not isinstance(value, bool) and _in_range(value, meta):
            return int(value)
        raise ConfigError(f"{path}: expected an int{_with_range(meta, value)}, got {value!r}")
    if hint is float:
        if isinstance(value, (int, float)) and not isinstance(value, bool) and _in_range(float(value), meta):
            return float(value)
        if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value != 0:
            if not FLOAT_MAGNITUDE[0] <= abs(value) <= FLOAT_MAGNITUDE[1]:
                raise ConfigError(
                    f"{path}: expected 0 or a magnitude in [{FLOAT_MAGNITUDE[0]:g}, {FLOAT_MAGNITUDE[1]:g}] "
                    f"(its square a normal float32 number), got {value!r}"
                )
        raise ConfigError(f"{path}: expected a finite number{_with_range(meta, value)}, got {value!r}")
    if hint is str:
        if isinstance(value, str):
            return value
        raise ConfigError(f"{path}: expected a string, got {value!r}")
    if isinstance(hint, type) and issubclass(hint, Settings):
        if isinstance(value, hint):
            return value
        if isinstance(value, Mapping):
            return hint.from_dict(value, where=path)
        raise ConfigError(f"{path}: expected a mapping of {hint.__name__} settings, got {value!r}")
    return value


def _with_range(meta: Mapping[str, Any], value: Any = None) -> str:
    """The range in an error message; a derived upper bound (:func:`default_ceiling`) only
    when ``value`` passed it, so a value below the low bound reads as before."""
    if meta.get("derived_high") and not (isinstance(value, (int, float)) and value > meta["high"]):
        meta = {**meta, "high": None}
    text = _range_text(meta)
    return f" {text}" if text else ""


@dataclasses.dataclass(frozen=True)
class Settings:
    """Base of every solver's settings: a frozen dataclass checked field by field on
    construction (types from the annotations, ranges from :func:`setting`).

    Subclasses may add cross-field checks in :meth:`check`, raising
    :class:`~torchsym.errors.ConfigError` that names the fields.
    """

    _hints_cache: ClassVar[dict[type, dict[str, Any]]] = {}

    @classmethod
    def _hints(cls) -> dict[str, Any]:
        hints = Settings._hints_cache.get(cls)
        if hints is None:
            hints = typing.get_type_hints(cls)
            Settings._hints_cache[cls] = hints
        return hints

    def __post_init__(self) -> None:
        hints = self._hints()
        prefix = getattr(self, "_path", "")
        for f in dataclasses.fields(self):
            path = f"{prefix}{f.name}"
            value = _coerce(getattr(self, f.name), hints[f.name], f.metadata, path)
            object.__setattr__(self, f.name, value)
        self.check()

    def check(self) -> None:
        """Cross-field checks; the base class has none."""

    # -- construction from plain data -------------------------------------------------
    @classmethod
    def field_names(cls) -> list[str]:
        """The names of this class's fields (groups by their own name)."""
        return [f.name for f in dataclasses.fields(cls)]

    @classmethod
    def _checked(
        cls, mapping: Mapping[str, Any], prefix: str, group: Callable[[str, type, Mapping[str, Any], str], Any]
    ) -> dict[str, Any]:
        """``mapping`` with every key checked against the fields (an unknown one is a
        :class:`ConfigError` listing the valid names) and a group given as a mapping turned
        into its settings by ``group(key, group_class, mapping, path)``. A group given as
        anything but a mapping or its settings class is a :class:`ConfigError`."""
        names = cls.field_names()
        hints = cls._hints()
        values = {}
        for key, value in mapping.items():
            if key not in names:
                raise ConfigError(
                    f"{prefix}{key}: unknown setting of {cls.__name__}{_suggest(str(key), names)}; "
                    f"valid: {', '.join(names)}"
                )
            hint = hints[key]
            if isinstance(hint, type) and issubclass(hint, Settings):
                if isinstance(value, Mapping):
                    value = group(key, hint, value, f"{prefix}{key}")
                elif not isinstance(value, hint):
                    raise ConfigError(f"{prefix}{key}: expected a mapping of {hint.__name__} settings, got {value!r}")
            values[key] = value
        return values

    @classmethod
    def from_dict(cls: type[S], mapping: Mapping[str, Any] | None, *, where: str = "") -> S:
        """Settings from a (nested) mapping, as read from YAML; missing keys keep their
        defaults. Unknown keys are a :class:`ConfigError` listing the valid names.

        ``where`` prefixes the field paths in messages (e.g. ``"refine"``).
        """
        prefix = f"{where}." if where else ""
        values = cls._checked(dict(mapping or {}), prefix, lambda key, hint, value, path: hint.from_dict(value, where=path))
        return _build(cls, values, prefix)

    def replace(self: S, overrides: Mapping[str, Any] | None = None, *, where: str = "", **kw: Any) -> S:
        """A copy with ``overrides`` applied; a group may be given as a mapping of its
        own overrides (``refine={"max_iters": 2}``) or by a dotted key
        (``"refine.max_iters": 2``). Checked like :meth:`from_dict`."""
        merged: dict[str, Any] = {}
        for key, value in {**dict(overrides or {}), **kw}.items():
            head, _, rest = str(key).partition(".")
            if rest:
                merged.setdefault(head, {})
                if not isinstance(merged[head], dict):
                    merged[head] = {}
                merged[head][rest] = value
            else:
                merged[head] = value
        prefix = f"{where}." if where else ""
        values = self._checked(merged, prefix, lambda key, hint, value, path: getattr(self, key).replace(value, where=path))
        current = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        return _build(type(self), {**current, **values}, prefix)

    def to_dict(self) -> dict[str, Any]:
        """Plain nested Python (tuples as lists), as a YAML step's ``params``."""
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            out[f.name] = v.to_dict() if isinstance(v, Settings) else list(v) if isinstance(v, tuple) else v
        return out

    def changed(self) -> dict[str, Any]:
        """The settings that differ from the class's defaults, flattened to dotted keys."""
        default = type(self)()
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):
            v, d = getattr(self, f.name), getattr(default, f.name)
            if isinstance(v, Settings):
                out.update({f"{f.name}.{k}": x for k, x in v.changed().items()})
            elif v != d:
                out[f.name] = v
        return out

    @classmethod
    def describe(cls, prefix: str = "") -> list[tuple[str, str, str, str, str]]:
        """One row per leaf setting: ``(dotted name, type, default, unit, meaning)``."""
        rows = []
        hints = cls._hints()
        for f in dataclasses.fields(cls):
            hint = hints[f.name]
            if isinstance(hint, type) and issubclass(hint, Settings):
                rows += hint.describe(f"{prefix}{f.name}.")
                continue
            default = f.default if f.default is not _MISSING else f.default_factory()  # type: ignore[misc]
            rng = _range_text(f.metadata)
            rows.append(
                (
                    f"{prefix}{f.name}",
                    _describe(hint) + (f", {rng}" if rng else ""),
                    repr(default),
                    f.metadata.get("unit", ""),
                    f.metadata.get("doc", ""),
                )
            )
        return rows


def _build(cls: type[S], values: dict[str, Any], prefix: str) -> S:
    """``cls(**values)``, its messages naming fields by their path below ``prefix``."""
    obj = cls.__new__(cls)
    object.__setattr__(obj, "_path", prefix)
    try:
        cls.__init__(obj, **values)
    finally:
        object.__delattr__(obj, "_path")
    return obj


def resolve_settings(
    cls: type[S], settings: S | Mapping[str, Any] | None = None, overrides: Mapping[str, Any] | None = None
) -> S:
    """The settings a function or module runs with: ``settings`` (an instance of ``cls``,
    a mapping as in YAML, or None for the defaults) with keyword ``overrides`` applied.

    Raises:
        ConfigError: ``settings`` is of another class, or a key or value is invalid.
    """
    if settings is None:
        base = cls()
    elif isinstance(settings, cls):
        base = settings
    elif isinstance(settings, Mapping):
        base = cls.from_dict(settings)
    else:
        raise ConfigError(f"settings: expected {cls.__name__}, a mapping or None, got {type(settings).__name__}")
    return base.replace(overrides) if overrides else base


class Solver(nn.Module):
    """Base of every solver module: holds its :class:`Settings` and calls its function.

    Subclasses set ``settings_class`` and implement ``forward(data, generator=None)``
    by calling the method's function with ``self.settings``; ``forward`` never changes
    ``self``. Construct with a settings object, a mapping, keyword overrides, or both::

        ReflectionPlaneDetector(n_starts=5)
        ReflectionPlaneDetector(PlaneSettings(n_starts=5), seed=1)
    """

    settings_class: ClassVar[type[Settings]] = Settings

    def __init__(self, settings: Settings | Mapping[str, Any] | None = None, **overrides: Any) -> None:
        super().__init__()
        self.settings = resolve_settings(self.settings_class, settings, overrides)

    def extra_repr(self) -> str:
        return ", ".join(f"{k}={v!r}" for k, v in self.settings.changed().items())
