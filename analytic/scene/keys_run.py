"""The scene format's keys of the given torque, the engines' settings and the later layers' tables: one :class:`~analytic.scene.key.Key` each (type, unit, default,
bounds, meaning, the effect that reads it), in the order of the reference.

Part of :data:`analytic.scene.schema.KEYS`, the one table the loader, its cross-field rules and
``docs/scene-format.md`` read.
"""

from __future__ import annotations

from analytic.effects import Effect, MjIntegrator, SolverMethod, SpringModel
from analytic.scene.key import Key, Kind, Need

_R = Need.REQUIRED
_C = Need.CONDITIONAL

RUN_KEYS: tuple[Key, ...] = (
    # ---- [external_torque] ---------------------------------------------------------------------
    Key(
        "",
        "external_torque",
        Kind.TABLE,
        "",
        "A given torque on BR, body axes (Remark 2): `τ_g(t) = constant + amplitude · "
        "cos(frequency · t)`. Acts with the effect `external_torque`.",
        _C,
        when="required by the effect external_torque",
        effect=Effect.EXTERNAL_TORQUE,
        effect_needs=True,
    ),
    Key(
        "external_torque",
        "constant",
        Kind.VECTOR3,
        "N·m",
        "Constant part, body axes.",
        default=[0.0, 0.0, 0.0],
    ),
    Key(
        "external_torque",
        "amplitude",
        Kind.VECTOR3,
        "N·m",
        "Amplitude of the cosine part, body axes.",
        default=[0.0, 0.0, 0.0],
    ),
    Key("external_torque", "frequency", Kind.NUMBER, "rad/s", "Its frequency.", default=0.0),
    # ---- [solver] ------------------------------------------------------------------------------
    Key(
        "",
        "solver",
        Kind.TABLE,
        "",
        "How the analytic plant (and Pinocchio) integrate: scipy `solve_ivp`.",
        default_text="the defaults below",
    ),
    Key(
        "solver",
        "method",
        Kind.CHOICE,
        "",
        "The scipy integrator.",
        default=SolverMethod.DOP853.value,
        choices=SolverMethod,
    ),
    Key("solver", "rtol", Kind.NUMBER, "", "Relative tolerance.", default=1e-12, bounds="> 0"),
    Key(
        "solver",
        "atol",
        Kind.NUMBER,
        "",
        "Absolute tolerance, in each coordinate's unit (m, 1, m).",
        default=1e-13,
        bounds="> 0",
    ),
    Key(
        "solver",
        "max_step",
        Kind.NUMBER,
        "s",
        "Largest step the integrator may take.",
        default_text="no limit",
        bounds="> 0",
    ),
    # ---- [output] ------------------------------------------------------------------------------
    Key(
        "",
        "output",
        Kind.TABLE,
        "",
        "Horizon and sampling, shared by every plant: samples at `0, 1/rate, 2/rate, …` and at "
        "`t_end` exactly.",
        default_text="the defaults below",
    ),
    Key(
        "output",
        "t_end",
        Kind.NUMBER,
        "s",
        "The horizon.",
        default=20.0,
        bounds="> 0, at least one MuJoCo step; ≤ {MAX_OUTPUT_SAMPLES} samples",
    ),
    Key(
        "output",
        "rate",
        Kind.NUMBER,
        "Hz",
        "Samples per second; `1/rate` a whole number of MuJoCo steps.",
        default=100.0,
        bounds="> 0",
    ),
    # ---- [mujoco] ------------------------------------------------------------------------------
    Key(
        "",
        "mujoco",
        Kind.TABLE,
        "",
        "The MuJoCo twin's settings.",
        default_text="the defaults below",
    ),
    Key(
        "mujoco",
        "integrator",
        Kind.CHOICE,
        "",
        "MuJoCo's integrator.",
        default=MjIntegrator.RK4.value,
        choices=MjIntegrator,
    ),
    Key(
        "mujoco",
        "timestep",
        Kind.NUMBER,
        "s",
        "MuJoCo's fixed step.",
        default=2.5e-4,
        bounds="> 0; ≤ {MAX_MUJOCO_STEPS} steps per run",
    ),
    Key(
        "mujoco",
        "spring_model",
        Kind.CHOICE,
        "",
        "How MuJoCo represents the springs.",
        default=SpringModel.TENDON.value,
        choices=SpringModel,
    ),
    # ---- [hard_case] ---------------------------------------------------------------------------
    Key(
        "",
        "hard_case",
        Kind.TABLE,
        "",
        "The criterion of a hard case (`validation/scenes/hard/*.toml`): the checks, their "
        "references, bounds and reasons. The loader keeps the table verbatim; the hard-case suite "
        "validates it (format: `docs/hard_cases.md`).",
        default_text="none (not a hard case)",
    ),
    # ---- [mjx] ---------------------------------------------------------------------------------
    Key(
        "",
        "mjx",
        Kind.TABLE,
        "",
        "How the `mjx` plant (MuJoCo's MJX on JAX, an optional plugin) runs this scene: "
        '`precision` ("float32" or "float64"), `device` (a JAX platform such as "cpu" or '
        '"cuda:0", "" for JAX\'s default), `timestep` (s) and `controller` ("jax" or "host"). '
        "The loader keeps the table verbatim; the plant validates it (`mj_bridge/mjx_settings.py`).",
        default_text="float64 on JAX's default device at the [mujoco] timestep, the JAX controller",
    ),
    # ---- [thresholds] --------------------------------------------------------------------------
    Key(
        "",
        "thresholds",
        Kind.TABLE,
        "",
        "Overrides of the comparison's named thresholds (`tumble validate`, the pytest plugin), "
        "by the names listed below. The loader checks the entries' shape, the comparison their names.",
        default_text="the defaults",
    ),
    Key(
        "thresholds",
        "<name>",
        Kind.NUMBER_OR_VALUE_TABLE,
        "the threshold's",
        "A new bound for the named threshold: a number (the whole bound, no relative part), "
        'or `{{ value = …, rtol = …, reason = "…" }}`.',
        bounds="finite, ≥ 0; a known name",
    ),
    Key(
        "thresholds",
        "hard_<criterion>",
        Kind.NUMBER_OR_STRING,
        "the criterion's",
        "A criterion of the hard-case suite (`validation/scenes/hard/*.toml`): a bound, or "
        "`hard_criterion`, the criterion in a sentence.",
        bounds="a number ≥ 0 or a string",
    ),
    Key(
        "thresholds.<name>", "value", Kind.NUMBER, "the threshold's", "The bound.", _R, bounds="≥ 0"
    ),
    Key(
        "thresholds.<name>",
        "rtol",
        Kind.NUMBER,
        "1",
        "The relative part of the bound, which becomes `value + rtol × scale`, scale the "
        "quantity's largest magnitude over the run across the compared plants (as scipy's "
        "`atol + rtol·|y|`); only for the names with an rtol column entry in the table above.",
        bounds="finite, ≥ 0",
        default_text="0 (the value is the whole bound)",
    ),
    Key(
        "thresholds.<name>",
        "reason",
        Kind.STRING,
        "",
        "Why this bound; shown in reports.",
        default_text='"set by the scene"',
    ),
)
"""``[external_torque]``, ``[solver]``, ``[output]``, ``[mujoco]``, ``[hard_case]``, ``[thresholds]``."""
