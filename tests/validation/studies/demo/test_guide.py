"""``demo.md``: a guide that teaches (goals, how to open the recording, each step with its key plot
and what to look at, exercises with predictions, the paper)."""

from __future__ import annotations

from validation.studies.demo import PAPER, STEPS, demo_markdown, is_controlled


def test_the_guide_teaches(scenes):
    runs = [(s, scenes[s.prefix], None) for s in STEPS]
    md = demo_markdown(runs, 10.0, 1e-12, True, shown="out/demo/demo.rrd")
    assert md.startswith("# ")
    head = md.split("# The four steps")[0]
    assert "# Learning goals" in head and "    rerun out/demo/demo.rrd" in head
    for step in STEPS:
        section = md.split(f"## {step.title}")[1].split("\n## ")[0]
        assert "**What to look at:**" in section and "**Key plot:**" in section
        assert ("No control acts" in section) == (not is_controlled(scenes[step.prefix]))
    exercises = md.split("# Exercises")[1]
    assert exercises.count("**Exercise ") >= 2 and "*Prediction.*" in exercises
    assert "tumble simulate" in exercises and "γ" in exercises
    for part in ("Koganti", "Udwadia", "Journal of Guidance, Control, and Dynamics", "1.G000633"):
        assert part in PAPER
    assert md.rstrip().endswith(PAPER)
    assert md.count("## ") == len(
        STEPS
    )  # one section per step (tests/validation/recording/test_recording.py)
