"""Figs 5, 7, 8, 9, 10, 11, 12, 13, A1, A2, convergence, sensitivity on synthetic contract data."""
import math

import numpy as np
import pandas as pd
import pytest

import synthetic_data as syn
from granudep.cli import main
from granudep.figures import FIGURES, isph2d, regression, sections, studies
from test_figures_runout import check_png


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("fig2d")
    f = {"isph": syn.save(syn.isph_run("T22-A70"), d / "T22-A70.nc"),
         "isph16": syn.save(syn.isph_run("T16-A50", H0=0.1, theta=16.0, runout=0.1), d / "T16-A50.nc"),
         "sec": syn.save(syn.sections("T22-A70"), d / "sec_T22-A70.nc"),
         "wm": syn.save(syn.wm_sections("T22-A70"), d / "wm_T22-A70.nc"),
         "crit": str(d / "critical.csv"), "coef": str(d / "coefficients.csv"), "sens": str(d / "sens.csv")}
    crit = pd.concat([syn.critical_table("T22-A70", 22.0, 0.7),
                      syn.critical_table("T16-A50", 16.0, 0.5, A=-0.05, B=0.08)])
    crit.to_csv(f["crit"], index=False)
    coef = syn.coefficients_table()
    coef = coef[coef.case != "T22-A70"]
    coef = pd.concat([coef, pd.DataFrame([{"case": "T22-A70", "theta_deg": 22.0, "a": 0.7, "A": -0.03, "B": 0.05,
                                           "r2": 1.0}])])
    coef.to_csv(f["coef"], index=False)
    pd.DataFrame({"parameter": ["phi_internal_deg"] * 3 + ["critical_speed"] * 2,
                  "value": [23.5, 25.5, 27.5, 0.05, 0.1], "A": [-0.03, -0.031, -0.032, -0.02, -0.03],
                  "B": [0.05, 0.04, 0.03, 0.05, 0.04], "final_runout_norm": [2.0, 1.9, 1.8, 2.1, 1.9],
                  "baseline": [0, 1, 0, 0, 1]}).to_csv(f["sens"], index=False)
    f["conv_isph"] = [syn.save(syn.isph_run("T22-A70", dx=dx, runout=0.3 + dx), d / f"c_dx{dx}.nc")
                      for dx in (0.02, 0.01)]
    f["conv_crit"] = []
    for dx in (0.02, 0.01):
        p = d / f"T22-A70_dx{dx}"
        p.mkdir()
        syn.critical_table().to_csv(p / "critical.csv", index=False)
        f["conv_crit"].append(str(p / "critical.csv"))
    f["conv_da"] = [syn.save(syn.da_run("1D-A70", True, n=n), d / f"da_n{n}.nc") for n in (20, 40)]
    return f


def test_surface_and_interface_profiles_exact():
    dx = 0.01
    X, Y = np.meshgrid(np.arange(dx / 2, 0.1, dx), np.arange(dx / 2, 0.05, dx))  # 10 columns, 5 layers
    x, y = X.ravel(), Y.ravel()
    xc, top = isph2d.surface_profile(x, y, dx, width=dx)
    assert np.allclose(top[:10], 0.05)  # highest centre 0.045 + dx/2
    dep = y < 0.02  # two deposited layers under three flowing ones
    xc, yi = isph2d.interface_profile(x, y, dep, dx, width=dx)
    assert np.allclose(yi[:10], 0.02)
    yi_all = isph2d.interface_profile(x, y, np.ones_like(dep), dx, width=dx)[1]
    assert np.allclose(yi_all[:10], 0.05)  # all at rest: interface at the free surface


def test_fig5_and_claims_quote_the_one_failure_plane(tmp_path):
    """Particles in front of a plane 35° from the bed through the gate foot move at t = t_c (and have
    slumped by then): Fig 5's note and the claims scorecard quote isph.analysis.failure_plane_angle,
    from the horizontal (35° + θ within a layer's slope error)."""
    from granudep.report import claims
    from granudep.isph.analysis import failure_plane_angle
    ds = syn.isph_run(dx=0.004)
    L0, dx = 0.2, 0.004
    x0, y0 = ds["x"].values[0], ds["y"].values[0]  # the initial lattice
    moving = x0 > L0 - y0 / np.tan(np.radians(35.0))
    tc = math.sqrt(0.14 / (9.81 * math.cos(math.radians(22))))
    i = int(np.argmin(np.abs(ds["time"].values - tc)))
    ds["x"].values[i] = np.where(moving, x0 + 0.05, x0)
    ds["u"].values[i] = np.where(moving, 1.0, 0.0)
    ds["v"].values[i] = 0.0
    fp = failure_plane_angle(ds, t_norm=1.0)
    assert fp["time"] == pytest.approx(float(ds["time"].values[i]))
    assert fp["angle_deg"] == pytest.approx(35.0, abs=1.0)
    assert fp["angle_horizontal_deg"] == pytest.approx(fp["angle_deg"] + 22.0)
    text = " ".join(t.get_text() for t in isph2d.fig5(ds).texts).lower()
    assert f"failure plane in this run: {fp['angle_horizontal_deg']:.1f}° from the horizontal" in text
    angle, _ = claims._failure_angle(syn.save(ds, tmp_path / "T22-A70.nc"))
    assert angle == pytest.approx(fp["angle_horizontal_deg"])


def test_velocity_profile_layer_means(files):
    ds = syn.isph_run(dx=0.01)
    ds["u"].values[5] = ds["y"].values[5] * 10.0  # u = 10 y
    yy, uu = isph2d.velocity_profile(ds, x_m=float(np.median(ds["x"].values[5])), i=5)
    assert yy.size >= 3
    assert np.allclose(uu, 10 * yy, atol=10 * 0.5 * 0.01)  # within half a layer


def test_fig9_fit_lines_use_planted_rate(files):
    fig = sections.fig9([files["sec"]], files["crit"])
    ax = fig.axes[0]
    fits = [l for l in ax.get_lines() if l.get_linestyle() == "-" and len(l.get_xdata()) == 2]
    assert len(fits) == 4
    for l in fits:
        x, y = l.get_xdata(), l.get_ydata()
        assert y[0] == pytest.approx(0.0) and (y[1] - y[0]) / (x[1] - x[0]) == pytest.approx(syn.SECTION_RATE)
    onsets = sorted(l.get_xdata()[0] for l in ax.get_lines() if l.get_marker() == "o" and len(l.get_xdata()) == 1)
    assert onsets == pytest.approx([8.4, 9.2, 10.0, 10.8])  # planted (t_s)_C at [x] = 0.2 … 0.8


def test_fig12_lines_are_eq36(files):
    fig = regression.fig12(files["crit"], files["coef"])
    ax22 = fig.axes[1]
    assert ax22.get_title(loc="left") == "(b) θ = 22°"
    line = [l for l in ax22.get_lines() if len(l.get_xdata()) == 2 and l.get_linestyle() == "-"][0]
    assert list(line.get_ydata()) == pytest.approx([0.05, 0.02])  # B, A + B


def test_fig13_has_paper_table5(files):
    fig = regression.fig13(files["coef"])
    paper = [l for l in fig.axes[0].get_lines() if l.get_label().startswith("paper")][0]
    assert list(paper.get_ydata()) == pytest.approx([-0.0541, -0.0455, -0.0313, -0.0240])


def test_figA2_rms_planted(files):
    ds = syn.wm_sections()
    rms = sections.rms_deviation(ds)
    m = ds["momentum_norm"].values[1]
    dec = ds["deceleration"].values.astype(bool)
    for j, f in enumerate((1, 2, 3, 4)):
        expect = [np.sqrt(np.mean((0.01 * (f - 2) * m[i][dec[i]]) ** 2)) if dec[i].any() else np.nan
                  for i in range(m.shape[0])]
        np.testing.assert_allclose(rms[j], expect, rtol=1e-12)


ALL = {
    "fig5": lambda f: [f["isph"]],
    "fig6": lambda f: [f["isph"], f["isph16"]],
    "fig7": lambda f: [f["isph"], f["isph16"], f["sec"]],
    "figA3": lambda f: [f["isph"]],
    "fig8": lambda f: [f["sec"]],
    "fig9": lambda f: [f["sec"], f["crit"]],
    "fig10": lambda f: [f["isph"], f["isph16"], f["sec"]],
    "fig11": lambda f: [f["sec"], f["crit"]],
    "fig12": lambda f: [f["crit"], f["coef"]],
    "fig13": lambda f: [f["coef"]],
    "figA1": lambda f: [f["wm"]],
    "figA2": lambda f: [f["wm"]],
    "convergence": lambda f: [*f["conv_isph"], *f["conv_crit"], *f["conv_da"]],
    "sensitivity": lambda f: [f["sens"]],
}


def test_every_cli_name_is_tested():
    # fig15-17 and the reading-matrix and fig12r figures are tested in their own files
    assert set(ALL) | {"fig15", "fig16", "fig17", "reading-matrix", "fig12r"} == set(FIGURES)


@pytest.mark.parametrize("name", sorted(ALL))
def test_cli_png(files, tmp_path, name):
    out = tmp_path / f"{name}.png"
    assert main(["figure", name, "-o", str(out), *ALL[name](files)]) == 0
    check_png(out)


def test_wrong_input_kind_refused(files, tmp_path, capsys):
    assert main(["figure", "fig8", "-o", str(tmp_path / "x.png"), files["crit"]]) == 2
    assert "'critical' file" in capsys.readouterr().err


def test_outflow_particles_are_not_drawn():
    # particle 0 leaves through the outflow at t = 0.5 s and sits frozen at x = 4.2 m afterwards
    ds = syn.isph_run("T22-A70")
    t = ds["time"].values
    gone = t >= 0.5
    x = ds["x"].values.copy()
    x[gone, 0] = 4.2
    ds["x"].values[:] = x
    ot = np.full(ds.sizes["particle"], np.nan)
    ot[0] = 0.5
    ds["outflow_time"] = (("particle",), ot, {"units": "s", "long_name": "outflow time"})
    late = int(np.flatnonzero(gone)[-1])
    assert isph2d.present(ds, late).sum() == ds.sizes["particle"] - 1 and isph2d.present(ds, 0).all()
    fig = isph2d.fig7([ds], ts=[t[late] / isph2d.scales(ds)["tc"]])
    assert fig.axes[0].get_xlim()[1] < 1.0          # the mass (front 0.5 m), not the end of the bed
    fig = isph2d.fig5(ds, times=[t[late]])
    xs = np.concatenate([ln.get_xdata() for ln in fig.axes[0].lines if len(ln.get_xdata()) > 2])
    assert xs.max() < 1.0


def test_convergence_fronts_are_drawn_only_where_their_thickness_is_resolved():
    """A thickness threshold below two particle layers is not a front of that run (NaN, not drawn)."""
    from granudep.figures.studies import _front_row
    rows = {}
    for dx in (0.004, 0.002, 0.0005):
        ds = syn.isph_run(dx=dx)
        ds = ds.assign(final_front_v99=ds["final_front_position"] + 0.01, final_front_5mm=ds["final_front_position"],
                       final_front_2d=ds["final_front_position"] + 0.02)
        ds.attrs["d"] = 0.0007
        rows[dx] = _front_row(ds)
    assert all(np.isfinite(r["v99"]) for r in rows.values())
    assert np.isnan(rows[0.004]["5mm"]) and np.isfinite(rows[0.002]["5mm"])      # 5 mm vs 2 dx = 8 / 4 mm
    assert np.isnan(rows[0.002]["2d"]) and np.isfinite(rows[0.0005]["2d"])        # 1.4 mm vs 4 / 1 mm
    assert abs(rows[0.0005]["2d"] - rows[0.0005]["v99"] - 0.01 / 0.2) < 1e-12
