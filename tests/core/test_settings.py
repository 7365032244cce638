import dataclasses
from typing import Literal, Optional

import pytest

from torchsym.core.settings import Settings, Solver, group, resolve_settings, setting
from torchsym.errors import ConfigError


@dataclasses.dataclass(frozen=True)
class Refine(Settings):
    """Refinement."""

    enabled: bool = setting(True, "run the refinement")
    max_iters: int = setting(4, "refinement rounds", low=0)
    step: float = setting(0.5, "step size", low=0.0, low_open=True, high=1.0)


@dataclasses.dataclass(frozen=True)
class Toy(Settings):
    n_samples: int = setting(500, "points sampled", low=1)
    eps_theta: float = setting(2.0, "angle tolerance", unit="deg", low=0.0, high=180.0)
    mode: Literal["fast", "exact"] = setting("fast", "search mode")
    max_side: Optional[int] = setting(640, "longer side of the working copy", unit="px", low=32)
    scales: tuple[float, ...] = setting((1.0, 2.0), "scales", low=0.0, low_open=True)
    refine: Refine = group(Refine)
    seed: int = setting(0, "seed of the module's generator", low=0)

    def check(self) -> None:
        if self.mode == "exact" and self.n_samples > 10_000:
            raise ConfigError("n_samples: at most 10000 with mode 'exact'")


class ToySolver(Solver):
    settings_class = Toy

    def forward(self, x):
        return x


class TestSettings:
    def test_defaults(self):
        s = Toy()
        assert s.n_samples == 500 and s.refine.max_iters == 4 and s.scales == (1.0, 2.0)

    def test_int_becomes_float(self):
        s = Toy(eps_theta=3)
        assert isinstance(s.eps_theta, float)

    @pytest.mark.parametrize(
        "kw, msg",
        [
            ({"n_samples": 0}, r"n_samples: expected an int >= 1, got 0"),
            ({"n_samples": 2.5}, r"n_samples: expected an int"),
            ({"n_samples": True}, r"n_samples: expected an int"),
            ({"eps_theta": float("nan")}, r"eps_theta: expected a finite number"),
            ({"eps_theta": 200}, r"eps_theta: expected a finite number >= 0.0 and <= 180.0"),
            ({"mode": "quick"}, r"mode: expected one of 'fast', 'exact'"),
            ({"max_side": 8}, r"max_side: expected an int >= 32 or null"),
            ({"scales": (1.0, -1.0)}, r"scales\[1\]"),
            ({"scales": 3}, r"scales: expected a list"),
        ],
    )
    def test_exception(self, kw, msg):
        with pytest.raises(ConfigError, match=msg):
            Toy(**kw)

    def test_bool_is_not_a_string(self):
        with pytest.raises(ConfigError, match="enabled: expected true or false, got 'yes'"):
            Toy().replace({"refine": {"enabled": "yes"}})

    def test_optional_none(self):
        assert Toy(max_side=None).max_side is None

    def test_cross_field_check(self):
        with pytest.raises(ConfigError, match="at most 10000"):
            Toy(mode="exact", n_samples=20_000)

    def test_from_dict_nested(self):
        s = Toy.from_dict({"n_samples": 7, "refine": {"max_iters": 2}})
        assert s.n_samples == 7 and s.refine.max_iters == 2 and s.refine.step == 0.5

    def test_from_dict_typo_at_depth(self):
        with pytest.raises(ConfigError, match=r"refine\.max_iter: unknown setting of Refine \(did you mean 'max_iters'\?\); valid: enabled, max_iters, step"):
            Toy.from_dict({"refine": {"max_iter": 2}})

    def test_from_dict_value_at_depth_named(self):
        with pytest.raises(ConfigError, match=r"refine\.max_iters: expected an int >= 0, got -1"):
            Toy.from_dict({"refine": {"max_iters": -1}})

    def test_group_not_a_mapping(self):
        with pytest.raises(ConfigError, match="refine: expected a mapping of Refine settings"):
            Toy.from_dict({"refine": 3})

    def test_replace_dotted_and_nested(self):
        s = Toy().replace({"refine.max_iters": 9}, n_samples=3)
        assert s.refine.max_iters == 9 and s.n_samples == 3
        assert Toy().replace(refine={"step": 0.25}).refine == Refine(step=0.25)

    def test_replace_keeps_other_group_fields(self):
        s = Toy(refine=Refine(max_iters=7)).replace({"refine.step": 0.1})
        assert s.refine.max_iters == 7

    def test_round_trip(self):
        s = Toy(n_samples=3, refine=Refine(max_iters=1), scales=(3.0,))
        assert Toy.from_dict(s.to_dict()) == s

    def test_changed(self):
        assert Toy(n_samples=3).replace({"refine.max_iters": 1}).changed() == {"n_samples": 3, "refine.max_iters": 1}

    def test_describe(self):
        rows = {r[0]: r for r in Toy.describe()}
        assert rows["eps_theta"][3] == "deg" and rows["refine.max_iters"][4] == "refinement rounds"

    def test_frozen_and_hashable(self):
        s = Toy()
        with pytest.raises(dataclasses.FrozenInstanceError):
            s.n_samples = 3  # type: ignore[misc]
        assert hash(s) == hash(Toy())


class TestResolveAndSolver:
    def test_resolve(self):
        assert resolve_settings(Toy, None, {"n_samples": 2}).n_samples == 2
        assert resolve_settings(Toy, {"refine": {"max_iters": 0}}).refine.max_iters == 0
        with pytest.raises(ConfigError, match="settings: expected Toy"):
            resolve_settings(Toy, Refine())

    def test_solver_holds_settings(self):
        m = ToySolver(n_samples=3)
        assert m.settings == Toy(n_samples=3)
        assert "n_samples=3" in repr(m)
        assert ToySolver(Toy(n_samples=3), seed=2).settings.seed == 2


def _settings_classes():
    import torchsym
    from torchsym.core.settings import Settings

    torchsym.load_all()
    seen, todo = [], [Settings]
    while todo:
        for sub in todo.pop().__subclasses__():
            if sub not in seen:
                seen.append(sub)
                todo.append(sub)
    return seen


def test_every_number_setting_has_an_upper_bound():
    """A bound a real use never meets and a machine can afford: explicit, or the default's
    ceiling (:func:`torchsym.core.settings.default_ceiling`); a seed's is MAX_SEED."""
    import typing

    missing = []
    for cls in _settings_classes():
        if not cls.__module__.startswith("torchsym."):
            continue  # settings defined by tests
        hints = typing.get_type_hints(cls)
        for f in dataclasses.fields(cls):
            args = typing.get_args(hints[f.name]) or (hints[f.name],)
            if (int in args or float in args) and bool not in args and f.metadata.get("high") is None:
                missing.append(f"{cls.__qualname__}.{f.name}")
    assert not missing, f"number settings without an upper bound: {missing}"


def test_default_ceiling():
    from torchsym.core.settings import MAX_SEED, default_ceiling

    assert default_ceiling(10, "points") == 1000 and default_ceiling(0.005, "tolerance") == 1.0
    assert default_ceiling(0, "a flag") is None and default_ceiling(None, "x") is None
    assert default_ceiling(0, "seed of the generator") == MAX_SEED
    assert default_ceiling((3, 50), "sizes") == 10000
