"""Regenerate cases/paper/*.toml and cases/validation/*.toml (paper Tables 1-3).

Run from the repository root: ``python cases/make_paper_cases.py``.
"""

from pathlib import Path

HERE = Path(__file__).parent

LINE = """[line]
spans = {spans}
span_length = {L:.1f}      # m, L_x
sag = {sag:.4f}            # m, L_x/30 (Table 1)
weight = 17.92          # N/m (Table 1)
diameter = 0.022        # m2/m projected area (Table 1)
drag_coefficient = 1.0  # ASCE 74 (Table 1)
area = 0.7e-4           # m2 (Table 1)
elastic_modulus = 5.2e10  # Pa (Table 1)
height = 43.0           # m average elevation (Table 1)
insulator_length = 4.0  # m (Table 1)
supports = {supports}
tower_of_interest = {toi}
elements_per_span = 10
"""

WIND = """[wind]
type = "{wtype}"
v_ref = {V:.1f}           # m/s
turbulence_intensity = 0.12
air_density = 1.25
coherence_decay = 10.0
fft_length = "record"  # the synthesis' inverse FFT as long as the record (pinned; docs/wind.md)
"""

ANALYSIS = """[analysis]
duration = 600.0
time_step = 0.05
realizations = 10
seed = {seed}
damping = "paper"        # Eq. 13 exactly (transverse only), as in the paper
drag = "linear"          # Eq. 5: the v^2 term dropped, as in the paper
tension = "linear"       # reactions linear in the motion, as in the paper
"""


def main() -> None:
    out = HERE / "paper"
    out.mkdir(exist_ok=True)
    for n in range(1, 13):
        kind = "Db_x" if n <= 4 else "Db_y" if n <= 8 else "Sy"
        L = 300.0 if n in (1, 2, 5, 6, 9, 10) else 500.0
        V = 40.0 if n % 2 else 20.0
        for system, spans, toi in (("single", 1, 1), ("six", 6, 4)):
            supports = '["strain", "strain"]' if spans == 1 else (
                '["strain", "suspension", "suspension", "suspension", "suspension", "suspension", "strain"]')
            name = f"case{n:02d}-{system}"
            label = {"Db_x": "Downburst Db_x", "Db_y": "Downburst Db_y", "Sy": "Synoptic"}[kind]
            sysname = "single span" if spans == 1 else "six spans"
            text = f'name = "{name}"\n'
            text += f'description = "{label}, L = {L:.0f} m, Vref = {V:.0f} m/s, {sysname} (paper case {n})"\n\n'
            text += LINE.format(spans=spans, L=L, sag=L / 30, supports=supports, toi=toi) + "\n"
            text += WIND.format(wtype="synoptic" if kind == "Sy" else "downburst", V=V)
            if kind != "Sy":
                text += f'\n[wind.downburst]\nmodel = "holmes-oliver"   # pinned: the documented results (docs/wind.md, "Downburst models")\npreset = "{kind}"   # D_j = 2 L_x (Table 2)\n'
                text += "\n" + ANALYSIS.replace("duration = 600.0\n", "").format(seed=2015 + n)
            else:
                text += "\n" + ANALYSIS.format(seed=2015 + n)
            (out / f"{name}.toml").write_text(text)

    val = HERE / "validation"
    val.mkdir(exist_ok=True)
    for V in (10, 20, 30):
        text = f'''name = "matheson-holmes-v{V}"
description = "Matheson & Holmes (1981) single span, Vref = {V} m/s (paper Tables 3-4)"

# Table 3: span 300 m, sag 6.78 m, mass 1.69 kg/m, projected area 0.0293 m2/m, I = 0.15.
# Not given by the paper (assumptions, see docs/validation.md): conductor E*A = 6.8e10 Pa x 5.0e-4 m2
# (an ACSR of this mass and diameter), air density 1.2 kg/m3 (Australian practice of the
# original study), C_d = 1.0, L_u = 52/0.3 m (synoptic default).
[line]
spans = 1
span_length = 300.0
sag = 6.78
weight = 16.5789        # N/m = 1.69 kg/m x 9.81
diameter = 0.0293
drag_coefficient = 1.0
area = 5.0e-4
elastic_modulus = 6.8e10
height = 10.0
insulator_length = 4.0
supports = ["strain", "strain"]
tower_of_interest = 1

[wind]
type = "synoptic"
v_ref = {V:.1f}
turbulence_intensity = 0.15
air_density = 1.2
coherence_decay = 10.0
fft_length = "record"  # the synthesis' inverse FFT as long as the record (pinned; docs/wind.md)

[analysis]
duration = 600.0
time_step = 0.05
realizations = 10
seed = {1000 + V}
damping = "paper"        # Eq. 13 exactly (transverse only), as in the paper
drag = "linear"          # Eq. 5, as in the paper
tension = "linear"       # as in the paper
'''
        (val / f"matheson-holmes-v{V}.toml").write_text(text)


if __name__ == "__main__":
    main()
