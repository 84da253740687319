"""The lane width of the sweeps (``lanes=``) changes nothing but the speed: the map, the
basins, the bifurcation data and the continued orbits are the same with 1 (one trajectory at a
time), 4 and 8 trajectories per thread."""

import pytest

import bistable_impact as bi


def _without_wall_time(df):
    return df.drop(columns=[c for c in df.columns if "wall" in c]).reset_index(drop=True)


def test_map_is_the_same_for_every_lane_width():
    omega, velocity = bi.linspace(0.4, 3.2, 8), bi.linspace(0.02, 0.2, 5)
    maps = {n: bi.sweep.map(omega, velocity, threads=2, lanes=n) for n in (1, 4, 8)}
    assert len(maps[1]) == 40
    for n in (4, 8):
        assert _without_wall_time(maps[n]).equals(_without_wall_time(maps[1])), n


def test_basins_are_the_same_for_every_lane_width():
    x0, v0 = bi.linspace(0.0, 1.2, 12), bi.linspace(-0.6, 0.6, 10)
    runs = {n: bi.sweep.basins(1.45, 0.05, x0, v0, lanes=n) for n in (1, 4, 8)}
    cells, attractors = runs[1]
    assert len(cells) == 120 and len(attractors) >= 2
    for n in (4, 8):
        assert runs[n][0].equals(cells), n
        assert runs[n][1] == attractors, n


def test_bifurcation_is_the_same_for_every_lane_width():
    values = bi.linspace(2.0, 2.7, 15)
    runs = {
        n: bi.bifurcation("omega", values, velocity=0.07, transient=200, record=20, lanes=n)
        for n in (1, 4, 8)
    }
    assert len(runs[1]["points"]) == 15
    for n in (4, 8):
        assert runs[n]["data"].equals(runs[1]["data"]), n
        assert runs[n]["orbits"].equals(runs[1]["orbits"]), n
        assert runs[n]["points"] == runs[1]["points"], n


def test_continued_orbits_are_the_same_for_every_lane_width():
    omega = bi.linspace(1.2, 2.4, 13)
    runs = {n: bi.continue_omega(omega, 0.05, settle=200, lanes=n) for n in (1, 4, 8)}
    assert len(runs[1]["orbits"]) > 0
    for n in (4, 8):
        assert runs[n]["orbits"].equals(runs[1]["orbits"]), n


@pytest.mark.parametrize("bad", [0, 2, 3, 16, -4])
def test_a_bad_lane_width_names_the_argument(bad):
    with pytest.raises(ValueError, match="lanes"):
        bi.sweep.map([1.0], [0.1], lanes=bad)
    with pytest.raises(ValueError, match="lanes"):
        bi.sweep.basins(1.45, 0.05, [0.5], [0.0], lanes=bad)
    with pytest.raises(ValueError, match="lanes"):
        bi.bifurcation("omega", [2.0], velocity=0.07, lanes=bad)
    with pytest.raises(ValueError, match="lanes"):
        bi.continue_omega([1.2, 1.3], 0.05, lanes=bad)
