"""Whose quantity a series or a check is: one plant, or the difference of two.

A :class:`Subject` is a plant's name (``"mujoco"``) or a pair in report order
(``"analytic vs mujoco"``, :func:`mj_bridge.registry.order_key`); :func:`subject_order_key` sorts
subjects in report order; :func:`pair_subject` is the subject of two runs and :func:`diff_key` the
key of their difference series. A change to how plants and pairs are named, keyed or ordered in
every output costs this module only. ``validation.compare.checks.Subject`` is the documented path
(``docs/plugins.md``).
"""

from __future__ import annotations

from typing import ClassVar

from analytic.trajectory import Engine, Trajectory

PAIR_SEPARATOR = " vs "


class Subject(str):
    """Whose quantity a series or check is: one plant (its name, ``"mujoco"``) or the difference of
    two (``"analytic vs mujoco"``, the two in report order: :func:`mj_bridge.registry.order_key`).

    Open: any plant name, a built-in's, a plugin's or another label (ordered last). A ``str``, so
    it equals, hashes and serialises as its text; compare subjects with ``==``, not ``is``. The
    built-in plants and their pairs are the class constants :attr:`ANALYTIC`, :attr:`MUJOCO`,
    :attr:`PINOCCHIO`, :attr:`BOTH` (the reference pair, analytic vs MuJoCo),
    :attr:`ANALYTIC_PINOCCHIO` and :attr:`MUJOCO_PINOCCHIO`.
    """

    __slots__ = ()

    ANALYTIC: ClassVar[Subject]
    MUJOCO: ClassVar[Subject]
    PINOCCHIO: ClassVar[Subject]
    BOTH: ClassVar[Subject]
    ANALYTIC_PINOCCHIO: ClassVar[Subject]
    MUJOCO_PINOCCHIO: ClassVar[Subject]

    def __new__(cls, text: str) -> Subject:
        text = str(text)
        parts = text.split(PAIR_SEPARATOR)
        if len(parts) > 2 or not all(p and p == p.strip() for p in parts):
            raise ValueError(
                f"subject: a plant name or 'a vs b', each a non-empty name (got {text!r})"
            )
        return super().__new__(cls, text)

    @classmethod
    def plant(cls, name: str) -> Subject:
        """The subject of plant ``name`` alone (``ValueError`` for a name holding ``" vs "``)."""
        s = cls(name)
        if s.is_pair:
            raise ValueError(f"subject: a plant name cannot hold {PAIR_SEPARATOR!r} (got {name!r})")
        return s

    @classmethod
    def pair(cls, a: str, b: str) -> Subject:
        """The subject of the difference of plants ``a`` and ``b`` (names, either order), the
        two in report order."""
        # deferred: mj_bridge.registry reads installed metadata (importlib.metadata, ~20 ms by python -X importtime), paid only when plants are ordered
        from mj_bridge.registry import order_key

        first, second = sorted((str(cls.plant(a)), str(cls.plant(b))), key=order_key)
        if first == second:
            raise ValueError(f"subject: a pair of two different plants (got {a!r} twice)")
        return cls(f"{first}{PAIR_SEPARATOR}{second}")

    @property
    def value(self) -> str:
        """The text, a plain ``str`` (as an enum member's ``value``)."""
        return str.__str__(self)

    @property
    def is_pair(self) -> bool:
        return PAIR_SEPARATOR in self

    @property
    def plants(self) -> tuple[str, ...]:
        """The plant names this subject is about (two for a pair)."""
        return tuple(self.value.split(PAIR_SEPARATOR))

    @property
    def slug(self) -> str:
        """``analytic_vs_mujoco``: the subject in keys, labels and entity paths."""
        return self.value.replace(PAIR_SEPARATOR, "_vs_")

    def __repr__(self) -> str:
        return f"Subject({self.value!r})"


Subject.ANALYTIC = Subject(Engine.ANALYTIC.value)
Subject.MUJOCO = Subject(Engine.MUJOCO.value)
Subject.PINOCCHIO = Subject(Engine.PINOCCHIO.value)
Subject.BOTH = Subject("analytic vs mujoco")
Subject.ANALYTIC_PINOCCHIO = Subject("analytic vs pinocchio")
Subject.MUJOCO_PINOCCHIO = Subject("mujoco vs pinocchio")


def subject_order_key(subject: str) -> tuple:
    """Sort key of subjects in report order: the plants first (in report order), then the pairs
    (by their first plant, then their second)."""
    from mj_bridge.registry import order_key

    s = Subject(subject)
    return (len(s.plants), *(order_key(p) for p in s.plants))


def pair_subject(a: Trajectory, b: Trajectory) -> Subject:
    """The subject of ``a`` vs ``b``; two runs of one engine are compared as the reference pair."""
    if a.engine == b.engine:
        return Subject.BOTH
    return Subject.pair(a.engine, b.engine)


def diff_key(subject: Subject, name: str) -> str:
    """Key of a difference series: ``diff.<name>`` for analytic vs MuJoCo (the two-plant report's
    keys), ``diff_<pair slug>.<name>`` for any other pair."""
    return f"diff.{name}" if subject == Subject.BOTH else f"diff_{subject.slug}.{name}"


__all__ = ["PAIR_SEPARATOR", "Subject", "diff_key", "pair_subject", "subject_order_key"]
