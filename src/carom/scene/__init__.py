"""Scenes: a world, its bodies and a run, written in TOML or as nested dicts.

A scene file has the tables ``[scene]``, ``[world]``, ``[[materials]]``, ``[[bodies]]``, the
generators (``[[row]]``, ``[[rack]]``, ``[[lattice]]``, ``[[pegs]]``), ``[[gas]]``, ``[run]``
and ``[outputs]``; ``docs/scenes.md`` documents every key, unit and default.
:func:`load_scene` reads and checks a file (:mod:`carom.scene.load`, against
:mod:`carom.scene.schema`) and :meth:`Scene.build` makes the :class:`carom.World`
(:mod:`carom.scene.build`, placing bodies with :mod:`carom.scene.layouts`). Every error is a
:class:`SceneError` (a ``CaromError``) that names the file, the key, its line when it can be
found, what is wrong and how to fix it.
"""

from carom.scene.load import Scene, builtin_scenes, find_scene, load_scene
from carom.scene.schema import SceneError

__all__ = ["Scene", "SceneError", "builtin_scenes", "find_scene", "load_scene"]
