"""YAML configs that build solver pipelines.

A config file names the input kind and a list of steps; each step names a registered
solver and its settings::

    input: pointcloud
    steps:
      - name: reflection_plane
        params:
          init: {n_samples: 500}

Every key is checked before anything is built: unknown top-level keys, unknown solver
names and parameters that the solver's constructor does not take are reported with the
valid names. Files are read with ``yaml.safe_load``; a config never names import paths.
"""

from __future__ import annotations

import dataclasses
import difflib
from pathlib import Path
from collections.abc import Sequence
from typing import Any, Mapping

import yaml
from torch import nn

from torchsym.core.registry import INPUT_KINDS, SOLVERS, SolverEntry
from torchsym.errors import ConfigError, InputFileError, TorchsymError

__all__ = [
    "Pipeline", "PipelineConfig", "StepConfig", "SurfaceSampling", "build_pipeline", "config_path", "default_config",
    "list_configs", "load_config", "load_yaml", "parse_overrides",
]

#: the configs installed with the package (``torchsym/configs/*.yaml``; ``configs/`` of a
#: source checkout is the same folder)
CONFIG_DIR = Path(__file__).resolve().parents[1] / "configs"


def list_configs() -> dict[str, str]:
    """``{name: description}`` of the configs installed with the package, by name."""
    out = {}
    for path in sorted(CONFIG_DIR.glob("*.yaml")):
        try:
            raw = yaml.safe_load(path.read_text())
        except (OSError, yaml.YAMLError):
            continue
        text = raw.get("description", "") if isinstance(raw, Mapping) else ""
        out[path.stem] = " ".join(str(text).split())
    return out


def config_path(config: str | Path) -> Path:
    """The file a config argument names: an existing path as given; otherwise a name
    (``pointcloud_plane``, with or without ``.yaml``) of a config installed with the package.

    Raises:
        InputFileError: neither a file nor the name of an installed config (the names are
            listed).
    """
    path = Path(config)
    if path.is_file():
        return path
    name = path.name[: -len(path.suffix)] if path.suffix in (".yaml", ".yml") else path.name
    if str(path) in (path.name, name + ".yaml", name + ".yml") and (CONFIG_DIR / f"{name}.yaml").is_file():
        return CONFIG_DIR / f"{name}.yaml"
    names = sorted(list_configs())
    raise InputFileError(
        f"config: file {str(path)!r} does not exist and is not the name of an installed config"
        f"{_suggest(name, names)}; installed: {', '.join(names) or 'none'}"
    )

_TOP_KEYS = {"input", "steps", "description", "surface"}
_STEP_KEYS = {"name", "params"}

#: at most this many YAML aliases (``*name``) in one text: a config needs none, and a
#: chain of aliases to aliases grows exponentially when expanded ("billion laughs")
MAX_ALIASES = 16
#: at most this many nested collections
MAX_DEPTH = 32
#: at most this many characters
MAX_CHARS = 1_000_000


class _BoundedLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` that refuses more than :data:`MAX_ALIASES` aliases and more
    than :data:`MAX_DEPTH` nested collections, as it composes the document."""

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self._aliases = 0
        self._depth = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        if self.check_event(yaml.AliasEvent):
            self._aliases += 1
            if self._aliases > MAX_ALIASES:
                raise _Refused(f"more than {MAX_ALIASES} aliases (*name)")
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                raise _Refused(f"collections nested deeper than {MAX_DEPTH}")
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


class _Refused(Exception):
    """A YAML document past a bound of :class:`_BoundedLoader`."""


def load_yaml(text: str, where: str) -> Any:
    """Parse YAML ``text`` safely: ``yaml.safe_load`` with bounded aliases, depth and size.

    Raises:
        ConfigError: invalid YAML, or past a bound; the message starts with ``where``
            (e.g. ``config`` or ``--set``).
    """
    if len(text) > MAX_CHARS:
        raise ConfigError(f"{where}: more than {MAX_CHARS} characters of YAML")
    loader = _BoundedLoader(text)
    try:
        return loader.get_single_data()
    except _Refused as exc:
        raise ConfigError(f"{where}: refused YAML with {exc}") from None
    except yaml.YAMLError as exc:
        raise ConfigError(f"{where}: not valid YAML ({' '.join(str(exc).split())})") from None
    finally:
        loader.dispose()


#: a ``--set`` value nests at most this deep (a setting is a number, a word or a small group)
MAX_SET_DEPTH = 8


def parse_overrides(items: Sequence[str]) -> dict[str, Any]:
    """``KEY=VALUE`` strings (``--set`` of ``torchsym detect`` and ``torchsym run``) as a
    mapping; each value is one plain YAML value: no anchors or aliases, nested at most
    :data:`MAX_SET_DEPTH` deep, read by :func:`load_yaml`.

    Raises:
        ConfigError: no ``=``, an empty key, or a value that is not a plain YAML value;
            the message starts with ``--set: KEY=VALUE``.
    """
    out: dict[str, Any] = {}
    for item in items:
        key, eq, text = str(item).partition("=")
        key = key.strip()
        if not eq or not key:
            raise ConfigError(f"--set: expected KEY=VALUE, got {item!r}")
        where = f"--set: {key}={text!r}"
        try:
            depth = 0
            for event in yaml.parse(text, Loader=yaml.SafeLoader):
                if isinstance(event, yaml.AliasEvent) or getattr(event, "anchor", None):
                    raise ConfigError(f"{where}: expected a plain value, got a YAML anchor or alias")
                depth += isinstance(event, (yaml.MappingStartEvent, yaml.SequenceStartEvent))
                depth -= isinstance(event, (yaml.MappingEndEvent, yaml.SequenceEndEvent))
                if depth > MAX_SET_DEPTH:
                    raise ConfigError(f"{where}: expected a value nested at most {MAX_SET_DEPTH} deep")
        except (yaml.YAMLError, RecursionError) as exc:
            problem = " ".join(str(exc).split()) or type(exc).__name__
            raise ConfigError(f"{where} is not a valid YAML value ({problem})") from None
        out[key] = load_yaml(text, where)
    return out


@dataclasses.dataclass(frozen=True)
class SurfaceSampling:
    """How a mesh becomes the input of a point pipeline (``input: pointcloud`` or ``points``):
    ``points`` samples drawn uniformly by area on its surface
    (:func:`torchsym.geometry.sample_surface`) with a generator seeded by ``seed``.
    20,000 points cover a CAD model's large flat faces as well as its curved parts;
    its vertices alone do not. YAML: ``surface: {points: 20000, seed: 0}``."""

    points: int = 20_000
    seed: int = 0

    def __post_init__(self) -> None:
        for name, low, high in (("points", 4, MAX_SURFACE_POINTS), ("seed", 0, 2**63 - 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
                raise ConfigError(f"surface.{name}: expected an integer in [{low}, {high}], got {value!r}")

    @classmethod
    def from_dict(cls, raw: Any, where: str) -> "SurfaceSampling":
        if not isinstance(raw, Mapping):
            raise ConfigError(f"{where}: 'surface' must be a mapping with keys points, seed, got {raw!r}")
        unknown = [k for k in raw if k not in ("points", "seed")]
        if unknown:
            raise ConfigError(f"{where}: surface: unknown key {unknown[0]!r}{_suggest(str(unknown[0]), ['points', 'seed'])}; valid keys: points, seed")
        try:
            return cls(**raw)
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}") from None


#: most points :class:`SurfaceSampling` draws: 100x the default, the rule of every setting
#: (:func:`torchsym.core.settings.default_ceiling`); the point pipelines subsample far below it
MAX_SURFACE_POINTS = 2_000_000


@dataclasses.dataclass(frozen=True)
class StepConfig:
    """One step: a registered solver name and its settings."""

    name: str
    params: dict[str, Any]


@dataclasses.dataclass(frozen=True)
class PipelineConfig:
    """A validated config: the input kind and its steps, in order."""

    input: str
    steps: tuple[StepConfig, ...]
    description: str = ""
    source: str = "<dict>"
    surface: SurfaceSampling = SurfaceSampling()

    def with_overrides(self, overrides: Mapping[str, Any]) -> "PipelineConfig":
        """A copy whose last step's params are updated by ``overrides`` (checked); a
        group's setting may be named by a dotted key (``refine.max_iters``) or given as a
        mapping (``refine={"max_iters": 2}``)."""
        if not overrides:
            return self
        surface = {k.split(".", 1)[1]: v for k, v in overrides.items() if k.startswith("surface.")}
        if surface:
            merged = {**dataclasses.asdict(self.surface), **surface}
            new = dataclasses.replace(self, surface=SurfaceSampling.from_dict(merged, "overrides"))
            return new.with_overrides({k: v for k, v in overrides.items() if not k.startswith("surface.")})
        last = self.steps[-1]
        entry = SOLVERS.get(last.name)
        base = entry.settings(last.params, where=f"{self.source}: steps[{len(self.steps) - 1}]")
        try:
            new = base.replace(overrides, where="overrides")
        except ConfigError as exc:
            raise ConfigError(f"{self.source}: solver {last.name!r}: {exc}") from None
        step = StepConfig(last.name, new.to_dict())
        return dataclasses.replace(self, steps=self.steps[:-1] + (step,))

    def to_dict(self) -> dict[str, Any]:
        out = {
            "input": self.input,
            "description": self.description,
            "steps": [{"name": s.name, "params": dict(s.params)} for s in self.steps],
        }
        if self.input in ("pointcloud", "points"):
            out["surface"] = dataclasses.asdict(self.surface)
        return out


def _suggest(word: str, choices: list[str]) -> str:
    close = difflib.get_close_matches(word, choices, n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _check_params(entry: SolverEntry, params: Mapping[str, Any], where: str) -> None:
    entry.settings(params, where=where)


def load_config(config: str | Path | Mapping[str, Any]) -> PipelineConfig:
    """Read and validate a config from a YAML file path, an installed config's name
    (:func:`config_path`, e.g. ``"pointcloud_plane"``) or a mapping.

    Raises:
        InputFileError: the file does not exist or cannot be read as text.
        ConfigError: not valid YAML (or past the bounds of :func:`load_yaml`), unknown keys, unknown solver names or parameters, bad types.
    """
    source = "<dict>"
    if isinstance(config, (str, Path)):
        path = config_path(config)
        source = str(config)
        try:
            text = path.read_text()
        except (OSError, UnicodeDecodeError) as exc:
            raise InputFileError(f"config: cannot read {str(path)!r} as text ({exc})") from None
        raw = load_yaml(text, f"config {str(path)!r}")
    else:
        raw = config
    if not isinstance(raw, Mapping):
        raise ConfigError(f"{source}: expected a mapping with keys {sorted(_TOP_KEYS)}, got {type(raw).__name__}")
    for key in raw:
        if key not in _TOP_KEYS:
            raise ConfigError(f"{source}: unknown key {key!r}{_suggest(str(key), sorted(_TOP_KEYS))}; valid keys: {', '.join(sorted(_TOP_KEYS))}")
    kind = raw.get("input")
    if kind not in INPUT_KINDS or kind == "any":
        kinds = sorted(k for k in INPUT_KINDS if k != "any")
        raise ConfigError(f"{source}: 'input' must be one of {', '.join(kinds)}, got {kind!r}")
    steps_raw = raw.get("steps")
    if not isinstance(steps_raw, list) or not steps_raw:
        raise ConfigError(f"{source}: 'steps' must be a non-empty list of {{name, params}}, got {steps_raw!r}")
    steps = []
    for i, s in enumerate(steps_raw):
        where = f"{source}: steps[{i}]"
        if isinstance(s, str):
            s = {"name": s}
        if not isinstance(s, Mapping):
            raise ConfigError(f"{where}: expected a mapping with 'name' and 'params', got {s!r}")
        for key in s:
            if key not in _STEP_KEYS:
                raise ConfigError(f"{where}: unknown key {key!r}{_suggest(str(key), sorted(_STEP_KEYS))}; valid keys: name, params")
        name = s.get("name")
        if not isinstance(name, str):
            raise ConfigError(f"{where}: 'name' must be a solver name, got {name!r}")
        if name not in SOLVERS:
            raise ConfigError(f"{where}: unknown solver {name!r}{_suggest(name, SOLVERS.names())}; known: {', '.join(SOLVERS.names())}")
        params = s.get("params") or {}
        if not isinstance(params, Mapping):
            raise ConfigError(f"{where}: 'params' must be a mapping, got {params!r}")
        entry = SOLVERS.get(name)
        _check_params(entry, params, where)
        if i == 0 and entry.kind not in (kind, "any"):
            raise ConfigError(f"{where}: solver {name!r} takes {entry.kind!r} input, but the config's input is {kind!r}")
        if i > 0 and entry.kind != "any":
            raise ConfigError(f"{where}: solver {name!r} takes {entry.kind!r} input, not the previous step's result")
        steps.append(StepConfig(name, dict(params)))
    surface = SurfaceSampling.from_dict(raw["surface"], source) if "surface" in raw else SurfaceSampling()
    return PipelineConfig(kind, tuple(steps), str(raw.get("description", "")), source, surface)


def default_config(kind: str) -> PipelineConfig:
    """The default one-step pipeline for inputs of ``kind``."""
    entry = SOLVERS.default_for(kind)
    return PipelineConfig(kind, (StepConfig(entry.name, {}),), f"default pipeline for {kind}", "<default>")


class Pipeline(nn.Module):
    """Registered solvers run in order; each step gets the previous step's output."""

    def __init__(self, config: PipelineConfig) -> None:
        super().__init__()
        self.config = config
        steps = []
        for i, s in enumerate(config.steps):
            entry = SOLVERS.get(s.name)
            try:
                steps.append(entry.cls(entry.settings(s.params)))
            except TorchsymError as exc:
                raise ConfigError(f"{config.source}: steps[{i}] ({s.name}): {exc}") from None
        self.steps = nn.ModuleList(steps)

    @property
    def input_kind(self) -> str:
        return self.config.input

    def forward(self, data: Any) -> Any:
        out = data
        for step in self.steps:
            out = step(out)
        return out

    def extra_repr(self) -> str:
        return f"input={self.config.input!r}, source={self.config.source!r}"


def build_pipeline(config: str | Path | Mapping[str, Any] | PipelineConfig, **overrides: Any) -> Pipeline:
    """Build a :class:`Pipeline` from a config (path, mapping or :class:`PipelineConfig`).

    ``overrides`` update the last step's settings and are checked like the file's.
    """
    cfg = config if isinstance(config, PipelineConfig) else load_config(config)
    return Pipeline(cfg.with_overrides(overrides))
