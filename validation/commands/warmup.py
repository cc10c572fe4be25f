"""``tumble warmup``: every numba kernel the installed plants need for a scene (default: every
built-in scene) compiled or loaded from numba's cache, one line per kernel with its time, so that
an image or a CI job pays the one-time compile when it is built. Exits 1 when a kernel failed."""

from __future__ import annotations

import argparse

from validation.commands import EXIT_FAILED
from validation.commands.options import add_scene

NAME = "warmup"
HELP = "compile every numba kernel a scene needs (default: every built-in scene)"
DESCRIPTION = (
    "Compile (or load from numba's cache) every numba kernel the installed plants need for SCENE "
    "(default: every built-in scene), printing one line per kernel with its time, so that a "
    "Docker image or a CI job pays the one-time compile when it is built. Exits 1 when a kernel "
    "failed to compile."
)
CHOOSES_PLANTS = True


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_scene(p, every_builtin=True)


def run(args: argparse.Namespace) -> int:
    from mj_bridge.plants import installed_plants
    from validation.runs.warmup import builtin_scenes, warm_up_command
    from validation.scenes import resolve_scene

    scenes = [resolve_scene(args.scene)] if args.scene else builtin_scenes()
    engines = list(installed_plants())
    ok = warm_up_command(scenes, engines, out=lambda s: print(s, flush=True))
    return 0 if ok else EXIT_FAILED
