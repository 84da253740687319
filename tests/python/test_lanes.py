"""The lane width of the sweeps (``lanes=``) changes nothing but the speed: the map and the
basins are the same with 1 (one trajectory at a time), 4 and 8 trajectories per thread."""

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


@pytest.mark.parametrize("bad", [0, 2, 3, 16, -4])
def test_a_bad_lane_width_names_the_argument(bad):
    with pytest.raises(ValueError, match="lanes"):
        bi.sweep.map([1.0], [0.1], lanes=bad)
    with pytest.raises(ValueError, match="lanes"):
        bi.sweep.basins(1.45, 0.05, [0.5], [0.0], lanes=bad)
