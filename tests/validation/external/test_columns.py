"""The column schema (validation/external/columns.py): the header it makes, and the documented table."""

from __future__ import annotations

from pathlib import Path

from validation.external import COLUMNS
from validation.external.columns import header

DOC = Path(__file__).resolve().parents[3] / "docs" / "trajectory-format.md"


def test_header_for_two_masses_is_the_documented_order():
    assert header(2) == (
        "t", "R_x", "R_y", "R_z", "u_w", "u_x", "u_y", "u_z", "p_1", "p_2",
        "v_x", "v_y", "v_z", "omega_x", "omega_y", "omega_z", "pdot_1", "pdot_2",
        "tau_x", "tau_y", "tau_z", "F_1", "F_2",
        "W", "I_L_x", "I_L_y", "I_L_z", "I_P_x", "I_P_y", "I_P_z",
    )  # fmt: skip
    assert header(0, frozenset()) == ("t", "R_x", "R_y", "R_z", "u_w", "u_x", "u_y", "u_z")


def test_docs_table_lists_every_column_with_its_unit_and_frame():
    text = DOC.read_text(encoding="utf-8")
    rows = [line for line in text.splitlines() if line.startswith("| `")]
    for col in COLUMNS:
        name = f"`{col.name}_1` … `{col.name}_n`" if col.per_mass else f"`{col.name}`"
        row = next((r for r in rows if name in r), None)
        assert row is not None, f"{col.name} missing from the columns table"
        cells = [c.strip() for c in row.split("|")]
        assert cells[2] == col.unit and cells[3] == (col.frame or ""), row
