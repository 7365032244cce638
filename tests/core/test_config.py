from pathlib import Path

import pytest

import torchsym
from torchsym.core.config import build_pipeline, default_config, load_config
from torchsym.core.config import load_yaml
from torchsym.errors import ConfigError, InputFileError

CONFIGS = sorted((Path(__file__).resolve().parents[2] / "configs").glob("*.yaml"))


class TestConfigs:
    def test_there_are_configs(self):
        assert any(p.name == "pointcloud_plane.yaml" for p in CONFIGS)

    def test_every_solver_has_a_config(self):
        import yaml

        used = {step["name"] if isinstance(step, dict) else step
                for p in CONFIGS for step in yaml.safe_load(p.read_text())["steps"]}
        missing = set(torchsym.SOLVERS.names()) - used
        assert not missing, f"registered solvers without a file in configs/: {sorted(missing)}"

    @pytest.mark.parametrize("path", CONFIGS, ids=[p.name for p in CONFIGS])
    def test_every_config_builds(self, path):
        pipe = build_pipeline(path)
        assert len(pipe.steps) >= 1
        assert pipe.input_kind in ("pointcloud", "points", "image", "mesh", "multiview")


class TestConfigsByName:
    def test_installed_configs_are_the_repository_folder(self):
        from torchsym.core.config import CONFIG_DIR, list_configs

        assert sorted(list_configs()) == [p.stem for p in CONFIGS]
        assert all(text for text in list_configs().values()), "every config has a description"
        assert CONFIG_DIR.resolve() == CONFIGS[0].parent.resolve()

    @pytest.mark.parametrize("name", ["pointcloud_plane", "pointcloud_plane.yaml"])
    def test_name_or_path(self, name, tmp_path, monkeypatch):
        monkeypatch.chdir(tmp_path)  # no configs/ folder here: the name alone finds it
        want = load_config(CONFIGS[0].parent / "pointcloud_plane.yaml")
        got = load_config(name)
        assert (got.input, got.steps, got.source) == (want.input, want.steps, name)

    def test_a_local_file_wins_over_a_name(self, tmp_path, monkeypatch):
        monkeypatch.chdir(tmp_path)
        (tmp_path / "pointcloud_plane.yaml").write_text("input: points\nsteps: [pointsymm]\n")
        assert load_config("pointcloud_plane.yaml").input == "points"

    def test_unknown_name_lists_the_installed(self):
        with pytest.raises(InputFileError, match="did you mean 'pointcloud_plane'.*installed: image_axes"):
            load_config("pointcloud_plan")

    def test_cli_lists_them(self, capsys):
        from torchsym.cli import main

        assert main(["configs"]) == 0
        lines = capsys.readouterr().out.splitlines()
        assert len(lines) == len(CONFIGS) + 1 and lines[0].startswith("image_axes ")


class TestLoadConfig:
    def test_unknown_top_key(self):
        with pytest.raises(ConfigError, match=r"unknown key 'step' \(did you mean 'steps'\?\)"):
            load_config({"input": "pointcloud", "step": []})

    def test_unknown_solver(self):
        with pytest.raises(ConfigError, match=r"unknown solver 'reflection_plan' \(did you mean 'reflection_plane'\?\)"):
            load_config({"input": "pointcloud", "steps": [{"name": "reflection_plan"}]})

    def test_unknown_param_lists_valid(self):
        with pytest.raises(ConfigError) as err:
            load_config({"input": "pointcloud", "steps": [{"name": "reflection_plane", "params": {"n_start": 2}}]})
        msg = str(err.value)
        assert "n_start: unknown setting" in msg and "did you mean 'n_starts'" in msg and "valid:" in msg

    def test_bad_kind(self):
        with pytest.raises(ConfigError, match="'input' must be one of"):
            load_config({"input": "video", "steps": ["reflection_plane"]})

    def test_kind_mismatch(self):
        with pytest.raises(ConfigError, match="takes 'pointcloud' input, but the config's input is 'image'"):
            load_config({"input": "image", "steps": ["reflection_plane"]})

    def test_bad_value_reported(self):
        with pytest.raises(ConfigError, match="n_starts: expected an int >= 1, got 0"):
            build_pipeline({"input": "pointcloud", "steps": [{"name": "reflection_plane", "params": {"n_starts": 0}}]})

    def test_missing_file(self, tmp_path):
        with pytest.raises(InputFileError, match="does not exist"):
            load_config(tmp_path / "nope.yaml")

    def test_bad_yaml(self, tmp_path):
        p = tmp_path / "bad.yaml"
        p.write_text("input: [unclosed")
        with pytest.raises(ConfigError, match="not valid YAML"):
            load_config(p)

    def test_billion_laughs_refused_quickly(self, tmp_path):
        lines = ['a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]']
        for i, c in enumerate("bcdefghi"):
            prev = "abcdefghi"[i]
            lines.append(f"{c}: &{c} [" + ",".join([f"*{prev}"] * 9) + "]")
        p = tmp_path / "laughs.yaml"
        p.write_text("input: pointcloud\ndescription:\n" + "\n".join("  " + x for x in lines) + "\nsteps: [reflection_plane]\n")
        with pytest.raises(ConfigError, match="more than 16 aliases"):
            load_config(p)

    def test_deep_nesting_refused(self, tmp_path):
        p = tmp_path / "deep.yaml"
        p.write_text("input: pointcloud\nsteps: [reflection_plane]\ndescription: " + "[" * 5000 + "]" * 5000 + "\n")
        with pytest.raises(ConfigError, match="nested deeper than 32"):
            load_config(p)

    def test_a_few_aliases_allowed(self):
        assert load_yaml("x: &x 3\ny: *x\n", "t") == {"x": 3, "y": 3}


    def test_overrides_checked(self):
        cfg = default_config("pointcloud")
        with pytest.raises(ConfigError, match="bogus: unknown setting"):
            cfg.with_overrides({"bogus": 1})

    def test_detect_with_overrides(self):
        cloud = torchsym.pointcloud.planted_symmetric_cloud(800, generator=1)
        res = torchsym.detect(cloud.points, n_starts=1)
        assert res.score > 0.9


class TestRegistry:
    def test_default_solver(self):
        assert torchsym.SOLVERS.default_for("pointcloud").name == "reflection_plane"

    def test_get_unknown_lists_names(self):
        with pytest.raises(ConfigError, match="known: .*reflection_plane"):
            torchsym.SOLVERS.get("nope")

    def test_solvers_importable_from_top_level(self):
        for entry in torchsym.SOLVERS:
            assert getattr(torchsym, entry.cls.__name__) is entry.cls


class TestSurfaceSampling:
    def test_default_and_yaml(self):
        cfg = load_config({"input": "pointcloud", "steps": ["reflection_plane"], "surface": {"points": 5000, "seed": 3}})
        assert (cfg.surface.points, cfg.surface.seed) == (5000, 3)
        assert cfg.to_dict()["surface"] == {"points": 5000, "seed": 3}
        assert load_config({"input": "pointcloud", "steps": ["reflection_plane"]}).surface.points == 20000
        assert "surface" not in load_config({"input": "image", "steps": ["ksymmetry"]}).to_dict()

    def test_override(self):
        cfg = load_config({"input": "pointcloud", "steps": ["reflection_plane"]})
        new = cfg.with_overrides({"surface.points": 100, "n_starts": 2})
        assert new.surface.points == 100 and new.steps[0].params["n_starts"] == 2 and cfg.surface.points == 20000

    @pytest.mark.parametrize("surface, message", [
        ({"points": 0}, r"surface.points: expected an integer in \[4, 2000000\], got 0"),
        ({"points": True}, "surface.points: expected an integer"),
        ({"pionts": 5}, "unknown key 'pionts' \\(did you mean 'points'\\?\\); valid keys: points, seed"),
        ([1], "'surface' must be a mapping"),
    ])
    def test_exception(self, surface, message):
        with pytest.raises(ConfigError, match=message):
            load_config({"input": "pointcloud", "steps": ["reflection_plane"], "surface": surface})


class TestParseOverrides:
    def test_values(self):
        from torchsym.core.config import parse_overrides

        assert parse_overrides(["a=1", "b.c=[1, 2]", " d = x=y"]) == {"a": 1, "b.c": [1, 2], "d": "x=y"}

    @pytest.mark.parametrize("item, message", [
        ("novalue", "--set: expected KEY=VALUE, got 'novalue'"),
        ("=3", "--set: expected KEY=VALUE"),
        ("a=&x [1, *x]", "a YAML anchor or alias"),
        ("a=" + "[" * 9 + "1" + "]" * 9, "nested at most 8 deep"),
        ("a=!!python/object/apply:os.system [echo]", "--set: a="),
    ])
    def test_exception(self, item, message):
        from torchsym.core.config import parse_overrides

        with pytest.raises(ConfigError, match=message.replace("[", "\\[")):
            parse_overrides([item])
