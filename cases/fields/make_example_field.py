"""Regenerate cases/fields/example-field.csv (a user running-mean field, format in docs/wind.md).

Run from the repository root: ``python cases/fields/make_example_field.py``.

The example tabulates linecheck's own analytic downburst with its default shape
(r_max = 1.2 D_j, R_r = D_j/2, z_max = 0.025 D_j, T1 = 120 s, T_f = 600 s) on a coarse
grid, in units of V_max (linecheck rescales any table so that the peak running mean at
point p equals V_ref).  Replace it with CFD or measured data in the same layout.
"""

from pathlib import Path

import numpy as np

from linecheck.core.wind.mean import (
    R_MAX_OVER_DJ, RADIAL_DECAY_OVER_DJ, T1_DEFAULT, T_F_DEFAULT, Z_MAX_OVER_DJ,
    intensity, radial_profile, vertical_profile, wood_delta,
)

HERE = Path(__file__).parent

R = np.round(np.arange(0.0, 4.0 + 1e-9, 0.2), 6)  # r / D_j
Z = np.array([0.025, 0.05, 0.075, 0.1])  # z / D_j
T = np.arange(0.0, 600.0 + 1e-9, 30.0)  # s


def main() -> None:
    lines = [
        "# linecheck running-mean field (docs/wind.md): radial outflow speed on an (r/D_j, z/D_j, t) grid.",
        "# Tabulated from the analytic model (Holmes & Oliver 2000 radial, Wood et al. 2001 vertical,",
        "# Chay et al. 2006 intensity; T1 = 120 s, T_f = 600 s) in units of V_max; any unit works",
        "# because linecheck scales the table so the peak running mean at point p equals V_ref.",
        "r_over_dj,z_over_dj,t,v_radial",
    ]
    delta = wood_delta(Z_MAX_OVER_DJ)  # in units of D_j
    for r in R:
        fr = float(radial_profile(r, R_MAX_OVER_DJ, RADIAL_DECAY_OVER_DJ))
        for z in Z:
            fz = float(vertical_profile(z, delta))
            for t in T:
                v = fr * fz * float(intensity(t, T1_DEFAULT, T_F_DEFAULT))
                lines.append(f"{r:g},{z:g},{t:g},{v:.6f}")
    (HERE / "example-field.csv").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
