"""Figure: a large bulk tension reverses the slip at one end (general solver).

Run:  python benchmarks/figure_sigma_reversal.py   -> docs/figures/sigma_reversal.png
Hertz, constant P, then Q = 0.3 f P and sigma raised together; with moderate
sigma both slip zones carry q = +f p, with large sigma the left one reverses.
"""
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
from matplotlib.figure import Figure  # noqa: E402

import halfslip as hs  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TEXT = """
name: tension-{sigma}
material: {{E: 200.0e9, nu: 0.3}}
friction: 0.6
geometry: {{kind: hertz, radius: 50.0e-3}}
loads:
  - ramp: {{to: {{P: 1.0e5}}, duration: 1, steps: 4}}
  - ramp: {{to: {{Q: 1.8e4, sigma: {sigma}}}, duration: 1, steps: 20}}
output: {{fields: [p, q], points: 401}}
"""


def main():
    fig = Figure(figsize=(10, 4.5))
    ax = fig.add_subplot()
    for sigma, style in ((2.0e7, "-"), (1.5e8, "--")):
        ds = hs.simulate(hs.parse_scene(TEXT.format(sigma=sigma)), method="general")
        last = ds.isel(t=-1)
        x = ds.x.values * 1e6
        colour = "C0" if sigma < 1e8 else "C1"
        ax.plot(x, last.q.values / 1e6, style, color=colour, label=f"q, σ = {sigma / 1e6:.0f} MPa")
        ax.axvspan(float(last.stick_left) * 1e6, float(last.stick_right) * 1e6, alpha=0.08, color=colour,
                   label=f"stick zone, σ = {sigma / 1e6:.0f} MPa")
    f = 0.6
    ax.plot(x, f * last.p.values / 1e6, "k:", lw=1, label="+f p and -f p")
    ax.plot(x, -f * last.p.values / 1e6, "k:", lw=1)
    ax.set_xlabel("x [µm]")
    ax.set_ylabel("shear traction [MPa]")
    ax.set_title("Q = 0.3 fP with bulk tension: large σ reverses the slip at the left end")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.subplots_adjust(right=0.72)
    out = ROOT / "docs" / "figures" / "sigma_reversal.png"
    fig.savefig(out, dpi=110)
    print(out)


if __name__ == "__main__":
    main()
