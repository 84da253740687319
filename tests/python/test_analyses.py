"""orbit, continue_omega, atlas, bifurcation, energy_map and spectrum against the CLI run with the same
arguments (its JSON and CSV files), and against analytic identities (det M of the monodromy
matrix, the energy ratio of Eq. 13, the impacts of `simulate`)."""

import json
import math
import subprocess

import numpy as np
import pandas as pd
import pytest

import bistable_impact as bi

# The adapter calls the same bistable-analysis code as the CLI: results agree to rounding
# (in practice bit for bit); 1e-12 relative leaves room for a different compilation unit.
REL = 1e-12


def run_cli(cli, *args):
    out = subprocess.run([str(cli), *map(str, args)], capture_output=True, text=True)
    return out


def cli_json(cli, *args):
    out = run_cli(cli, *args, "--json")
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def close(a, b):
    if a is None or b is None:
        return a is b
    if isinstance(a, bool) or isinstance(b, bool) or isinstance(a, str):
        return a == b
    return math.isclose(a, b, rel_tol=REL, abs_tol=1e-15)


def assert_frames_equal(df, csv, bool_cols=()):
    ref = pd.read_csv(csv)
    for c in bool_cols:
        ref[c] = ref[c].astype(bool)
    assert list(df.columns) == list(ref.columns)
    assert len(df) == len(ref) > 0
    for c in ref.columns:
        if ref[c].dtype == bool:
            assert (df[c].to_numpy() == ref[c].to_numpy()).all(), c
        elif not pd.api.types.is_numeric_dtype(ref[c]):
            assert list(df[c]) == list(ref[c]), c
        else:
            np.testing.assert_allclose(df[c].to_numpy(float), ref[c].to_numpy(float),
                                       rtol=REL, atol=1e-15, err_msg=c)


# -- orbit ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "args, kwargs",
    [
        (["--omega", 1.75, "--velocity", 0.07], dict(omega=1.75, velocity=0.07)),
        (["--omega", 2.2, "--velocity", 0.07, "--period", 2],
         dict(omega=2.2, velocity=0.07, period=2)),
        (["--omega", 2.2, "--velocity", 0.07, "--guess", "0.05,0.1", "--restitution", 0.8],
         dict(omega=2.2, velocity=0.07, guess=(0.05, 0.1), restitution=0.8)),
    ],
)
def test_orbit_equals_cli(cli, args, kwargs):
    ref = cli_json(cli, "orbit", *args)
    got = bi.orbit(**kwargs)
    assert set(got) == set(ref)
    for k, v in ref.items():
        if k == "guess_source":
            assert got[k] == v.replace("--guess", "guess")
        elif k == "multipliers":
            for m, r in zip(got[k], v):
                assert all(close(m[q], r[q]) for q in ("re", "im", "abs")), (m, r)
        elif k in ("monodromy", "cycle_max", "guess"):
            np.testing.assert_allclose(np.asarray(got[k]), np.asarray(v), rtol=REL, atol=1e-15)
        else:
            assert close(got[k], v), (k, got[k], v)


def test_orbit_monodromy_identities():
    # Without sticking, det M = e^(2·impacts)·exp(−2ζ·pT) (Liouville with saltation), and the
    # multipliers are the eigenvalues of M: their product is det M, their sum its trace.
    o = bi.orbit(2.2, 0.07, period=2)
    m = o["monodromy"]
    assert m.shape == (2, 2) and not o["sticks"]
    p, zeta, e, w = 2, 0.02, 0.85, 2.2
    det_identity = e ** (2 * o["impacts"]) * math.exp(-2 * zeta * p * 2 * math.pi / w)
    assert math.isclose(o["det_identity"], det_identity, rel_tol=1e-13)
    assert math.isclose(np.linalg.det(m), det_identity, rel_tol=1e-8)
    lam = [complex(q["re"], q["im"]) for q in o["multipliers"]]
    assert abs(lam[0] * lam[1] - np.linalg.det(m)) < 1e-10
    assert abs(lam[0] + lam[1] - np.trace(m)) < 1e-10
    assert o["stable"] == (o["max_abs_multiplier"] < 1)
    assert math.isclose(o["floquet_exponent"],
                        math.log(o["max_abs_multiplier"]) / (p * 2 * math.pi / w), rel_tol=1e-13)


def test_orbit_errors(cli):
    with pytest.raises(ValueError, match=r"^invalid value '0' for 'period': must be in \[1, 64\]$"):
        bi.orbit(1.75, 0.07, period=0)
    with pytest.raises(ValueError, match="for 'guess': must be two finite numbers"):
        bi.orbit(1.75, 0.07, guess=(float("nan"), 0.0))
    with pytest.raises(ValueError, match="for 'omega'"):
        bi.orbit(-1.0, 0.07)
    with pytest.raises(ValueError, match="for 'guess'"):
        bi.orbit(1.75, 0.07, guess=(1.0,))
    with pytest.raises(TypeError):
        bi.orbit(1.75, 0.07, guess=("a", 1.0))
    # Newton failing: the CLI's message (and its exit code 1 is a RuntimeError).
    ref = run_cli(cli, "orbit", "--omega", 1.75, "--velocity", 0.07, "--guess", "0.9,3")
    assert ref.returncode == 1
    with pytest.raises(RuntimeError) as e:
        bi.orbit(1.75, 0.07, guess=(0.9, 3.0))
    assert "error: " + str(e.value) == ref.stderr.strip()


# -- continue_omega ------------------------------------------------------------------------


def test_continue_omega_natural_equals_cli(cli, tmp_path):
    csv = tmp_path / "c.csv"
    ref = cli_json(cli, "orbit", "--continue-omega", "1.6:2.4:9", "--velocity", "0.05,0.07",
                   "--settle", 300, "--out", csv, "--threads", 2)
    got = bi.continue_omega(bi.linspace(1.6, 2.4, 9), [0.05, 0.07], settle=300, threads=2)
    for k in ("period", "method", "omega_range", "branches"):
        assert got[k] == ref[k], k
    df = got["orbits"].copy()
    df["cycle_max"] = [";".join(repr(float(x)) for x in c) for c in df["cycle_max"]]
    ref_df = pd.read_csv(csv, dtype={"cycle_max": str})
    # The CSV's numbers are Rust's shortest round-trip forms, as Python's repr of the floats.
    ref_df["cycle_max"] = [";".join(repr(float(x)) for x in s.split(";")) for s in ref_df["cycle_max"]]
    ref_csv = tmp_path / "ref.csv"
    ref_df.to_csv(ref_csv, index=False)
    assert_frames_equal(df, ref_csv, bool_cols=("stable", "sticks"))


def test_continue_omega_arclength_equals_cli(cli, tmp_path):
    csv = tmp_path / "a.csv"
    ref = cli_json(cli, "orbit", "--continue-omega", "1.6:2.4:9", "--velocity", 0.07,
                   "--settle", 300, "--arclength", "--out", csv, "--threads", 1)
    got = bi.continue_omega(bi.linspace(1.6, 2.4, 9), 0.07, settle=300, method="arclength",
                            threads=1)
    assert got["method"] == "pseudo-arclength"
    for k in ("period", "omega_range"):
        assert got[k] == ref[k]
    for b, r in zip(got["branches"], ref["branches"]):
        assert all(close(b[k], r[k]) for k in r), (b, r)
    assert_frames_equal(got["orbits"], csv, bool_cols=("stable",))


def test_continue_omega_bifurcations_equal_cli(cli, tmp_path):
    # Fig. 6: the P-2 → P-4 doubling at V = 0.07 on the coarse grid of issue 22.
    csv = tmp_path / "p2.csv"
    ref = cli_json(cli, "orbit", "--continue-omega", "2.05:2.25:41", "--velocity", 0.07,
                   "--period", 2, "--out", csv, "--threads", 2)
    got = bi.continue_omega(bi.linspace(2.05, 2.25, 41), 0.07, period=2, threads=2)
    df = got["bifurcations"]
    assert list(df.columns) == list(bi.analyses.BIFURCATION_COLUMNS)
    assert list(df["kind"]) == ["period_doubling"]
    assert 2.23 < df["omega"][0] < 2.24
    assert abs(df["multiplier_1_re"][0] + 1.0) < 1e-8
    assert len(ref["bifurcations"]) == 1 and close(ref["bifurcations"][0]["omega"], df["omega"][0])
    assert_frames_equal(df, tmp_path / "p2_bifurcations.csv",
                        bool_cols=("sticks_before", "sticks_after"))


def test_atlas_equals_cli(cli, tmp_path):
    # The fold of the P-1 resonance and the high-energy branch's doubling from V = 0.05
    # (docs/bifurcations.md): both kinds, by arclength continuation.
    csv = tmp_path / "fold.csv"
    ref = cli_json(cli, "atlas", "--continue-omega", "1.2:1.6:41", "--velocity", 0.05,
                   "--arclength", "--velocity-bounds", "0.03,0.07", "--out", csv,
                   "--threads", 2)
    df = bi.atlas(bi.linspace(1.2, 1.6, 41), 0.05, (0.03, 0.07), method="arclength", threads=2)
    assert list(df.columns) == list(bi.analyses.ATLAS_COLUMNS)
    assert sorted(set(df["kind"])) == ["fold", "period_doubling"]
    assert [c["points"] for c in ref["curves"]] == list(df.groupby("curve").size())
    assert_frames_equal(df, csv)


def test_atlas_points_equal_cli(cli, tmp_path):
    # The resonance fold from V = 0.05 down to its cusp, and its crossing with the
    # high-energy branch's doubling (docs/bifurcations.md).
    csv = tmp_path / "cusp.csv"
    ref = cli_json(cli, "atlas", "--continue-omega", "1.0:2.5:61", "--velocity", 0.05,
                   "--arclength", "--velocity-bounds", "0.001,0.2", "--max-points", 2000,
                   "--out", csv, "--threads", 2)
    curves, pts = bi.atlas(bi.linspace(1.0, 2.5, 61), 0.05, (0.001, 0.2), method="arclength",
                           max_points=2000, threads=2, points=True)
    assert_frames_equal(curves, csv)
    assert list(pts.columns) == list(bi.analyses.ATLAS_POINT_COLUMNS)
    assert {"cusp", "crossing"} <= set(pts["kind"])
    assert list(pts["kind"]) == [p["kind"] for p in ref["points"]]
    ref_csv = pd.read_csv(tmp_path / "cusp_points.csv")
    # The CSV leaves other_curve and other_index empty where the DataFrame has -1.
    for c in ("other_curve", "other_index"):
        ref_csv[c] = ref_csv[c].fillna(-1).astype(int)
    ref_csv.to_csv(tmp_path / "cusp_points_filled.csv", index=False)
    assert_frames_equal(pts, tmp_path / "cusp_points_filled.csv")
    cusp = pts[pts["kind"] == "cusp"].iloc[0]
    assert abs(cusp["omega"] - 1.8141767194) < 1e-9 and abs(cusp["velocity"] - 0.0071755267) < 1e-9
    # Without points=True, the curves alone, as before.
    assert bi.atlas(bi.linspace(1.2, 1.6, 41), 0.05, (0.03, 0.07), method="arclength",
                    threads=2).equals(bi.atlas(bi.linspace(1.2, 1.6, 41), 0.05, (0.03, 0.07),
                                               method="arclength", threads=2, points=True)[0])


def test_atlas_errors():
    w = bi.linspace(2.05, 2.25, 5)
    with pytest.raises(ValueError, match="for 'velocity_bounds'"):
        bi.atlas(w, 0.07, (0.08, 0.09))
    with pytest.raises(ValueError, match="for 'ds'"):
        bi.atlas(w, 0.07, (0.06, 0.08), ds=0.0)
    with pytest.raises(ValueError, match="for 'method'"):
        bi.atlas(w, 0.07, (0.06, 0.08), method="secant")
    with pytest.raises(ValueError, match="for 'omega'"):
        bi.atlas([2.0, -1.0], 0.07, (0.06, 0.08))


def test_continue_omega_errors():
    w = bi.linspace(1.6, 2.4, 3)
    with pytest.raises(ValueError, match="for 'method': must be 'natural' or 'arclength'"):
        bi.continue_omega(w, 0.07, method="secant")
    with pytest.raises(ValueError, match="for 'omega'"):
        bi.continue_omega([1.0, -1.0], 0.07)
    with pytest.raises(ValueError, match="for 'omega': must have at least one value"):
        bi.continue_omega([], 0.07)
    with pytest.raises(ValueError, match="for 'velocity'"):
        bi.continue_omega(w, float("nan"))
    with pytest.raises(ValueError, match="for 'threads': must be in \\[0, 1024\\]"):
        bi.continue_omega(w, 0.07, threads=-1)


# -- bifurcation ---------------------------------------------------------------------------


def test_bifurcation_equals_cli(cli, tmp_path):
    csv = tmp_path / "b.csv"
    ref = cli_json(cli, "bifurcation", "--param", "omega", "--range", "2.0:2.5:6",
                   "--velocity", 0.07, "--transient", 200, "--record", 16, "--out", csv,
                   "--threads", 2)
    got = bi.bifurcation("omega", bi.linspace(2.0, 2.5, 6), velocity=0.07, transient=200,
                         record=16, threads=2)
    for k in ("param", "range", "transient", "record", "branches"):
        assert got[k] == ref[k], k
    assert len(got["points"]) == len(ref["points"]) == 6
    for p, r in zip(got["points"], ref["points"]):
        assert all(close(p[k], r[k]) for k in r), (p, r)
    assert_frames_equal(got["data"], csv)
    orbits = got["orbits"].drop(columns="cycle_max")
    ref_orbits = pd.read_csv(tmp_path / "b_orbits.csv").drop(columns="cycle_max")
    ref_orbits.to_csv(tmp_path / "o.csv", index=False)
    assert_frames_equal(orbits, tmp_path / "o.csv", bool_cols=("stable", "sticks"))
    # Period 2 at Ω = 2.2 (the paper's Fig. 6): two maxima alternate.
    assert [p["period"] for p in got["points"]][:3] == [1, 1, 2]


def test_bifurcation_in_velocity_without_branches(cli):
    ref = cli_json(cli, "bifurcation", "--param", "velocity", "--range", "0.01:0.1:4",
                   "--omega", 0.85, "--record", 8, "--transient", 50, "--no-branches")
    got = bi.bifurcation("velocity", bi.linspace(0.01, 0.1, 4), omega=0.85, record=8,
                         transient=50, branch_periods=())
    assert got["range"] == ref["range"] and got["branches"] == [] and len(got["orbits"]) == 0
    for p, r in zip(got["points"], ref["points"]):
        assert all(close(p[k], r[k]) for k in r), (p, r)


def test_bifurcation_errors():
    w = [2.0, 2.1]
    cases = [
        (dict(param="frequency", values=w, velocity=0.07), "param", "must be 'omega' or 'velocity'"),
        (dict(param="omega", values=w), "velocity", "is required with param='omega'"),
        (dict(param="omega", values=[2.0, -1.0], velocity=0.07), "values",
         "Ω must be in [1e-6, 1e6]"),
        (dict(param="velocity", values=[-0.1], omega=1.0), "values", "V must be in [0, 1e6]"),
        (dict(param="omega", values=w, velocity=0.07, record=0), "record",
         "must be in [1, 100000000]"),
        (dict(param="omega", values=w, velocity=0.07, samples=4), "samples",
         "must be in [8, 4096]"),
        (dict(param="omega", values=w, velocity=0.07, branch_periods=[1, 65]), "branch_periods",
         "must be in [1, 64]"),
    ]
    for kwargs, name, rule in cases:
        with pytest.raises(ValueError) as e:
            bi.bifurcation(**kwargs)
        assert f"for '{name}'" in str(e.value) and rule in str(e.value), str(e.value)


# -- spectrum ------------------------------------------------------------------------------


def test_spectrum_equals_cli(cli, tmp_path):
    csv = tmp_path / "s.csv"
    ref = cli_json(cli, "spectrum", "--omega", 2.2, "--velocity", 0.07, "--record", 64,
                   "--out", csv)
    got = bi.spectrum(2.2, 0.07, record=64)
    ref.pop("files")
    assert set(got) - {"spectrum"} == set(ref)
    assert all(close(got[k], ref[k]) for k in ref), (got, ref)
    assert_frames_equal(got["spectrum"], csv)
    # Period 2: lines at multiples of Ω/2 only (bins k = 32·j with 64 recorded periods; the
    # Hann window spreads a line over its neighbours k ± 1).
    s = got["spectrum"]
    assert got["period"] == 2 and got["peak_freq_over_omega"] == 0.5
    k = np.rint(s.freq_over_omega * 64).astype(int) % 32
    off = s.amplitude[(k > 1) & (k < 31)].max()
    assert off < 1e-9 * got["peak_amplitude"]


def test_spectrum_errors():
    for kwargs, name in [
        (dict(record=7), "record"),
        (dict(samples=3), "samples"),
        (dict(record=1 << 20, samples=128), "record"),
        (dict(max_freq=float("nan")), "max_freq"),
        (dict(velocity=-1.0), "velocity"),
    ]:
        args = dict(omega=2.2, velocity=0.07)
        args.update(kwargs)
        with pytest.raises(ValueError, match=f"for '{name}'"):
            bi.spectrum(**args)


# -- energy_map ----------------------------------------------------------------------------


def test_energy_map_is_eq13():
    e = 0.7
    m = bi.energy_map(restitution=e, nx=40, ny=30)
    phi = 2 * np.pi * m["phase"][:, None]
    u = m["u"][None, :]
    ratio = (((1 + e) * np.cos(phi) - e * u) ** 2 - u**2) / (1 + e) ** 2
    contact = u <= np.cos(phi)
    assert m["ratio"].shape == (40, 30)
    assert (np.isnan(m["ratio"]) == ~contact).all()
    np.testing.assert_allclose(m["ratio"][contact], ratio[contact], rtol=1e-13, atol=1e-15)
    assert m["max_abs"] == max(1.0, np.nanmax(np.abs(m["ratio"])))
    # Default range: down to below the neutral line u = −(1+e)/(1−e) at φ = 0, up to 1.5.
    lo, hi = m["u_range"]
    assert hi == 1.5 and lo < -(1 + e) / (1 - e)
    assert np.allclose(np.diff(m["phase"]), 1 / 40) and m["phase"][0] == 1 / 80


def test_energy_map_overlay_is_the_runs_impacts():
    w, v, n = 2.45, 0.07, 20.0
    m = bi.energy_map(omega=w, velocity=v, periods=n, u_range=(-3.0, 1.5))
    r = bi.simulate(w, v, periods=n)
    imp = r.impacts
    keep = ~np.isnan(imp["phase"])
    df = m["impacts"]
    assert len(df) == keep.sum() > 10
    np.testing.assert_array_equal(df["phase"], imp["phase"][keep])
    np.testing.assert_allclose(df["u"], imp["v_before"][keep] / v, rtol=1e-15)
    np.testing.assert_allclose(df["time_fraction"], imp["t"][keep] / (2 * np.pi * n), rtol=1e-15)


def test_energy_map_errors(cli):
    ref = run_cli(cli, "energy-map", "--restitution", 1.0, "--plot", "/nonexistent/x.png")
    assert ref.returncode == 2
    with pytest.raises(ValueError) as e:
        bi.energy_map(restitution=1.0)
    assert ref.stderr.strip() == "error: " + str(e.value).replace("'restitution'", "'--restitution'").replace("'1.0'", "'1'")
    with pytest.raises(ValueError, match="for 'u_range'"):
        bi.energy_map(u_range=(1.0, 0.0))
    with pytest.raises(ValueError, match="for 'nx'"):
        bi.energy_map(nx=0)
    with pytest.raises(ValueError, match="both or neither"):
        bi.energy_map(omega=2.0)
    with pytest.raises(ValueError, match="for 'velocity': must be > 0 for the overlay"):
        bi.energy_map(omega=2.0, velocity=0.0)
    with pytest.raises(ValueError, match="for 'periods'"):
        bi.energy_map(omega=2.0, velocity=0.07, periods=-1.0)


def test_linspace_is_the_cli_range(cli, tmp_path):
    # The CLI's map over A:B:N and `python -m bistable_impact map` over the same ranges have
    # exactly the values of bi.linspace (one formula, bistable_analysis::grid).
    import sys

    w = bi.linspace(0.2, 3.5, 7)
    assert w[0] == 0.2 and w[-1] == 3.5 and len(w) == 7
    assert list(bi.linspace(3.0, 1.0, 3)) == [3.0, 2.0, 1.0]
    ranges = ["--omega-range", "0.2:3.5:7", "--velocity-range", "0.01:0.19:3",
              "--max-periods", "300"]  # fmt: skip
    cli_csv, py_csv = tmp_path / "cli.csv", tmp_path / "py.csv"
    subprocess.run([str(cli), "map", *ranges, "--out", str(cli_csv)], check=True,
                   capture_output=True)  # fmt: skip
    subprocess.run([sys.executable, "-m", "bistable_impact", "map", *ranges, "--out",
                    str(py_csv)], check=True, capture_output=True)  # fmt: skip
    ref, got = pd.read_csv(cli_csv), pd.read_csv(py_csv)
    assert sorted(set(ref["omega"])) == sorted(set(got["omega"])) == list(w)
    assert sorted(set(ref["velocity"])) == sorted(set(got["velocity"])) == list(
        bi.linspace(0.01, 0.19, 3)
    )
    # Malformed ranges are refused as by the CLI (exit code 2).
    for bad in ("1:2:1", "1:1:3", "nan:2:3", "1:2:0"):
        r = subprocess.run([sys.executable, "-m", "bistable_impact", "map", "--omega-range", bad,
                            "--velocity-range", "0.1:0.1:1"], capture_output=True, text=True)  # fmt: skip
        c = run_cli(cli, "map", "--omega-range", bad, "--velocity-range", "0.1:0.1:1", "--out",
                    str(tmp_path / "x.csv"))
        assert r.returncode == c.returncode == 2, (bad, r.stderr, c.stderr)


# -- arguments and the GIL -----------------------------------------------------------------


@pytest.mark.parametrize(
    "call",
    [
        lambda: bi.orbit("1.75", 0.07),
        lambda: bi.orbit(1.75, 0.07, period=1.5),
        lambda: bi.continue_omega([1.0, 2.0], 0.07, method=1),
        lambda: bi.bifurcation("omega", [2.0], velocity="fast"),
        lambda: bi.bifurcation("omega", [2.0], velocity=0.07, branch_periods=["a"]),
        lambda: bi.energy_map(nx=2.5),
        lambda: bi.energy_map(u_range="wide"),
        lambda: bi.spectrum(2.2, 0.07, record=None),
    ],
)
def test_wrong_types_raise(call):
    # TypeError for a wrong type; ValueError where a string reaches numpy's float conversion.
    with pytest.raises((TypeError, ValueError)):
        call()


def test_absurd_sizes_are_refused_not_allocated():
    with pytest.raises(ValueError, match="for 'nx'"):
        bi.energy_map(nx=100_000, ny=100_000)
    with pytest.raises(ValueError, match="for 'record'"):
        bi.bifurcation("omega", [2.0, 2.1], velocity=0.07, record=4_000_000_000)
    with pytest.raises(ValueError, match="for 'record'"):
        bi.spectrum(2.2, 0.07, record=1 << 24, samples=64)
    with pytest.raises((OverflowError, ValueError)):
        bi.orbit(1.75, 0.07, settle=-1)


@pytest.mark.parametrize(
    "call",
    [
        lambda: bi.bifurcation("omega", bi.linspace(2.0, 2.5, 6), velocity=0.07, transient=3000,
                               threads=1),
        lambda: bi.continue_omega(bi.linspace(1.6, 2.4, 9), 0.07, settle=3000, threads=1),
        lambda: bi.spectrum(2.45, 0.07, record=8192),
        lambda: bi.orbit(2.2, 0.07, period=2, settle=50000),
        lambda: bi.energy_map(omega=2.45, velocity=0.07, periods=20000, nx=8, ny=8),
    ],
)
def test_the_gil_is_released(call):
    # This thread counts while another is inside the call (0.3 to 1 s). With the GIL held for
    # the whole native call the count could only advance in the switch intervals (0.1 ms here)
    # around the worker's reads of it: a GIL-holding C call (sorted() of 3e6 floats, 0.5 s)
    # let it advance by at most 4e4 in 5 trials on this machine; released, it advances for the
    # whole call (over 1e6 counts for most of these calls).
    import sys
    import threading

    count = [0]
    seen = {}
    finished = threading.Event()

    def work():
        seen["before"] = count[0]
        call()
        seen["after"] = count[0]
        finished.set()

    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-4)
    try:
        worker = threading.Thread(target=work)
        worker.start()
        while not finished.is_set():
            count[0] += 1
        worker.join()
    finally:
        sys.setswitchinterval(old)
    during = seen["after"] - seen["before"]
    assert during > 150_000, during
