"""Engine settings in scene files (issue 42, item 3): each engine's settings dataclass is the
one place a setting's default, range and check live; the scene schema's table for it is made
from the dataclass, so every field is reachable from TOML, and a bad value is refused once,
by the dataclass, with its file and line."""

from __future__ import annotations

import dataclasses
import re
import textwrap
import tomllib
from pathlib import Path
from typing import Any

import pytest

from carom.engines import registry
from carom.engines.edmd.settings import EdmdSettings
from carom.engines.stepped.settings import RigidSettings
from carom.scene import Scene
from carom.scene.schema import SceneError, settings_tables

ROOT = Path(__file__).resolve().parents[2]

HEAD = """
[world]
dimension = 2
box = [1.0, 1.0]
{world}

[[bodies]]
positions = [[0.5, 0.5]]
radius = 0.1

[run]
until = 1.0
"""


def scene(tables: str, world: str = "") -> Scene:
    text = textwrap.dedent(HEAD.format(world=world)) + textwrap.dedent(tables)
    return Scene.from_dict(tomllib.loads(text), "scene.toml", text)


def other_value(value: Any) -> Any:
    """A valid value of a field that differs from its default ``value``."""
    if isinstance(value, bool):
        return not value
    if isinstance(value, int):
        return value + 1
    return 0.5 * value if value else 1e-3


def test_each_engine_with_settings_has_a_table_made_from_its_dataclass() -> None:
    tables = settings_tables()
    with_settings = [e for e in registry.engines() if e.settings is not None]
    assert set(tables) == {e.name for e in with_settings} == {"edmd", "rigid"}
    for entry in with_settings:
        assert entry.settings is not None
        fields = dataclasses.fields(entry.settings)
        # every field a row, its default the dataclass's own
        assert {k: row[2] for k, row in tables[entry.name].items()} == {
            f.name: f.default for f in fields
        }


@pytest.mark.parametrize("field", [f.name for f in dataclasses.fields(RigidSettings)])
def test_every_rigid_setting_is_reachable_from_toml(field: str) -> None:
    value = other_value(getattr(RigidSettings(), field))
    shown = str(value).lower() if isinstance(value, bool) else repr(value)
    built = scene(f"[rigid]\n{field} = {shown}\n").settings["rigid"]
    assert getattr(built, field) == value
    assert built == dataclasses.replace(RigidSettings(), **{field: value})


def test_the_event_driven_settings_are_reachable_from_toml_and_world_t_c_still_read() -> None:
    built = scene("[edmd]\nt_c = 2e-6\nshell_thickness = 0.05\n").settings["edmd"]
    assert built == EdmdSettings(t_c=2e-6, shell_thickness=0.05)
    assert scene("", world="t_c = 3e-6").settings["edmd"] == EdmdSettings(t_c=3e-6)
    assert scene("").build().settings == EdmdSettings()  # the dataclass's default, once
    with pytest.raises(SceneError, match=r"\[world\] t_c: is also given as \[edmd\] t_c"):
        scene("[edmd]\nt_c = 2e-6\n", world="t_c = 3e-6")
    # a checked scene keeps it in its settings; a t_c put back in its world is refused, not
    # silently left unread
    checked = scene("")
    checked.world["t_c"] = 1e-3
    with pytest.raises(SceneError, match=r"scene.settings\['edmd'\] = EdmdSettings\(t_c=...\)"):
        checked.build()


@pytest.mark.parametrize(
    ("tables", "world", "where", "message"),
    [
        ("[rigid]\nsubsteps = 0\n", "", r"\[rigid\] substeps", r"from 1 to 64; got 0"),
        ("[rigid]\ndamping_ratio = 0.0\n", "", r"\[rigid\] damping_ratio", r"positive number"),
        ("[rigid]\nsleep = 1\n", "", r"\[rigid\] sleep", r"true or false; got 1"),
        ("[edmd]\nt_c = -1.0\n", "", r"\[edmd\] t_c", r">= 0 and finite; got -1.0"),
        ("", "t_c = -1.0", r"\[world\] t_c", r">= 0 and finite; got -1.0"),
    ],
)
def test_a_bad_setting_is_named_by_file_line_and_key(
    tables: str, world: str, where: str, message: str
) -> None:
    with pytest.raises(SceneError, match=where + r": .*" + message) as caught:
        scene(tables, world)
    assert re.match(r"scene.toml:\d+: ", str(caught.value))  # the line of the key


def test_scenes_md_lists_every_setting() -> None:
    text = (ROOT / "docs" / "scenes.md").read_text()
    for name, rows in settings_tables().items():
        section = text.split(f"## `[{name}]`", 1)[1].split("\n## ", 1)[0]
        for key in rows:
            assert f"| `{key}` |" in section, (name, key)
