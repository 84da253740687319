"""Every plot kind of the CLI renders from a small case: the PNG is written, decodes, and is
not blank (many colours, a good share of non-white pixels). What the pictures say (legends,
colour bars, axis ranges with far points left out) is checked by eye; the rule that leaves a
few far points out of an axis range is unit-tested in crates/bistable-cli/src/plot.rs."""

import subprocess

import pytest

PIL = pytest.importorskip("PIL.Image")

KINDS = {
    "simulate": (["simulate", "--omega", "1.75", "--velocity", "0.07", "--periods", "20",
                  "--plot", "{out}/sim"],
                 ["sim/waveform.png", "sim/phase_portrait.png", "sim/energy_per_impact.png"]),
    "chatter": (["simulate", "--omega", "0.2", "--velocity", "0.05", "--t-end", "60",
                 "--plot", "{out}/chatter"],
                ["chatter/waveform.png", "chatter/phase_portrait.png",
                 "chatter/energy_per_impact.png"]),
    "map": (["map", "--omega-range", "0.5:2.5:5", "--velocity-range", "0.03:0.15:4",
             "--max-periods", "300", "--out", "{out}/map.csv", "--plot", "{out}/map.png"],
            ["map.png"]),
    "basins": (["basins", "--omega", "1.45", "--velocity", "0.05", "--x-range", "0:1.2:6",
                "--v-range", "-0.6:0.6:6", "--max-periods", "300", "--out", "{out}/b.csv",
                "--plot", "{out}/basins.png"],
               ["basins.png"]),
    "bifurcation": (["bifurcation", "--param", "omega", "--range", "2.0:2.7:8", "--velocity",
                     "0.07", "--transient", "100", "--record", "20", "--out", "{out}/bif.csv",
                     "--plot", "{out}/bifurcation.png"],
                    ["bifurcation.png"]),
    "orbits": (["orbit", "--continue-omega", "1.5:2.5:6", "--velocity", "0.07",
                "--out", "{out}/orbits.csv", "--plot", "{out}/orbits.png"],
               ["orbits.png"]),
    "energy-map": (["energy-map", "--overlay", "--omega", "2.45", "--velocity", "0.07",
                    "--periods", "30", "--plot", "{out}/energy_map.png"],
                   ["energy_map.png"]),
    "spectrum": (["spectrum", "--omega", "2.2", "--velocity", "0.07",
                  "--plot", "{out}/spectrum.png"],
                 ["spectrum.png"]),
}


def non_trivial(path):
    img = PIL.open(path).convert("RGB")
    w, h = img.size
    assert w >= 800 and h >= 500, (path, img.size)
    small = img.resize((w // 4, h // 4))
    pixels = [small.getpixel((x, y)) for y in range(small.height) for x in range(small.width)]
    colours = len(set(pixels))
    inked = sum(1 for p in pixels if min(p) < 235) / len(pixels)
    assert colours >= 20 and inked > 0.02, (path, colours, inked)
    return img


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_each_plot_kind_renders(cli, tmp_path, kind):
    args, files = KINDS[kind]
    args = [a.format(out=tmp_path) for a in args]
    r = subprocess.run([str(cli), *args], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    for f in files:
        path = tmp_path / f
        assert path.exists() and path.stat().st_size > 10_000, path
        non_trivial(path)
