"""sweep.map on dask.distributed clusters: equal to the CLI's map CSV on a LocalCluster of two
worker processes, also with one of them killed mid-sweep (every point exactly once); a sweep
stopped part way resumes from its store and computes only the missing chunks (or, without a
client, points); Ctrl-C stops a local sweep."""

import os
import signal
import subprocess
import sys
import textwrap

import pytest

import bistable_impact as bi

pd = pytest.importorskip("pandas")
distributed = pytest.importorskip("distributed")

# Points of ~20 ms (the full 2000 natural periods, no early stop), so that chunks are still
# running when the first one is back.
OPTS = {"max_periods": 2000.0, "full": True, "lyapunov_periods": 50}
W = bi.linspace(0.5, 3.0, 8)
V = bi.linspace(0.03, 0.15, 5)


def cli_map(cli, tmp_path, w, v, options=("--max-periods", "2000", "--full")):
    out = tmp_path / "cli_map.csv"
    subprocess.run(
        [str(cli), "map", f"--omega-range={float(w[0])!r}:{float(w[-1])!r}:{len(w)}",
         f"--velocity-range={float(v[0])!r}:{float(v[-1])!r}:{len(v)}", *options,
         "--lyapunov-periods", "50", "--threads", "2", "--out", str(out)],
        check=True, capture_output=True,
    )  # fmt: skip
    return bi.sweep.read_csv(out)


def assert_same_map(df, ref):
    """Point for point equal (wall times aside), each grid point exactly once."""
    assert list(df.columns) == list(ref.columns)
    key = ["omega", "velocity"]
    assert not df.duplicated(key).any() and not ref.duplicated(key).any()
    a = df.drop(columns="wall_time_s").sort_values(key).reset_index(drop=True)
    b = ref.drop(columns="wall_time_s").sort_values(key).reset_index(drop=True)
    assert len(a) == len(b)
    for c in a.columns:
        x, y = a[c].astype(object).where(a[c].notna(), None), b[c].astype(object).where(b[c].notna(), None)
        assert list(x) == list(y), c


def test_60_by_40_map_on_two_worker_processes_equals_the_cli(cli, tmp_path):
    # The issue's acceptance grid (Fig. 9's ranges), with short runs (at most 300 natural
    # periods, the same on both sides) to keep the suite fast; on the package's lean cluster,
    # whose settings reach the scheduler and the worker processes.
    import dask

    w, v = bi.linspace(0.2, 3.5, 60), bi.linspace(0.005, 0.2, 40)
    ref = cli_map(cli, tmp_path, w, v, options=("--max-periods", "300"))
    with bi.cluster.local_cluster(n_workers=2) as cluster, distributed.Client(cluster) as client:
        keys = list(bi.cluster.LEAN_CONFIG)
        settings = lambda: [dask.config.get(k) for k in keys]  # noqa: E731
        assert settings() != list(bi.cluster.LEAN_CONFIG.values())  # not left set here
        for got in client.run(settings).values():  # the worker processes'
            assert got == list(bi.cluster.LEAN_CONFIG.values())
        # The scheduler (in this process) read its health-check interval [s] when it started.
        assert client.run_on_scheduler(lambda dask_scheduler: dask_scheduler._tick_interval) == 1.0
        df = bi.sweep.map(w, v, client=client, max_periods=300.0, lyapunov_periods=50)
    assert len(df) == 2400 and len(set(df["class"])) == 3
    assert_same_map(df, ref)


def test_map_with_a_worker_killed_mid_sweep_equals_the_cli(cli, tmp_path):
    ref = cli_map(cli, tmp_path, W, V)
    store = str(tmp_path / "map.csv")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        pids = client.run(os.getpid)
        killed = []
        calls = []

        def on_chunk(done, total):
            calls.append(done)
            if not killed:
                # Kill the worker process that is running chunks now (SIGKILL: no clean-up).
                busy = {a: ks for a, ks in client.processing().items() if ks}
                addr = max(busy, key=lambda a: len(busy[a]))
                killed.append((addr, len(busy[addr])))
                os.kill(pids[addr], signal.SIGKILL)

        df = bi.sweep.map(W, V, client=client, store=store, chunk=2, progress=on_chunk, **OPTS)
    assert killed and killed[0][1] >= 1, "a worker was killed while it had chunks"
    # Each chunk's result was taken once: 20 chunks of 2 points, the counts add up to 40.
    assert len(calls) == 20 and calls[-1] == 40 and calls == sorted(set(calls))
    assert len(df) == 40
    assert_same_map(df, ref)
    assert_same_map(bi.sweep.read_csv(store), ref)


def test_resumed_sweep_computes_only_the_missing_chunks(tmp_path):
    store = str(tmp_path / "map.csv")
    w, v = W[:6], V[:4]  # 24 points, 6 chunks of 4

    class Stop(Exception):
        pass

    def stop_after_two(done, total):
        if done >= 8:
            raise Stop  # a crash of the client after two chunks

    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        with pytest.raises(Stop):
            bi.sweep.map(w, v, client=client, store=store, chunk=4, progress=stop_after_two, **OPTS)
        kept = pd.read_csv(store)
        assert len(kept) == 8  # the two finished chunks, appended as they came back
        calls = []
        df = bi.sweep.map(w, v, client=client, store=store, chunk=4,
                          progress=lambda d, t: calls.append((d, t)), **OPTS)
        # A bad point raises on the client as it would locally (from the worker's task).
        with pytest.raises(ValueError, match=r"for 'omega': must be in \[1e-6, 1e6\]"):
            bi.sweep.map([-1.0], [0.1], client=client, **OPTS)
    # Only the 16 missing points were sent, in 4 chunks.
    assert calls == [(4, 16), (8, 16), (12, 16), (16, 16)]
    assert len(df) == 24 and not df.duplicated(["omega", "velocity"]).any()
    # The kept rows were read back, not computed again (same wall times).
    merged = df.merge(kept, on=["omega", "velocity"], suffixes=("", "_kept"))
    assert len(merged) == 8
    assert (merged["wall_time_s"] == merged["wall_time_s_kept"]).all()
    # And the whole map equals a local sweep (wall times aside).
    local = bi.sweep.map(w, v, threads=2, **OPTS)
    assert_same_map(df, local)


def test_ctrl_c_stops_a_local_sweep(tmp_path):
    # In a child process: it reports the first point done, then gets SIGINT; the sweep must
    # raise KeyboardInterrupt after the points in progress, long before the 400 points.
    script = textwrap.dedent(
        """
        import signal, sys
        signal.signal(signal.SIGINT, signal.default_int_handler)  # also when started ignored
        import bistable_impact as bi
        seen = []
        def progress(done, total):
            seen.append(done)
            if done == 1:
                print("started", flush=True)
                sys.stdin.readline()  # the parent has sent SIGINT
        try:
            bi.sweep.map(bi.linspace(0.5, 3.0, 40), bi.linspace(0.03, 0.15, 10), threads=1,
                         progress=progress, max_periods=2000.0, full=True, lyapunov_periods=50)
        except KeyboardInterrupt:
            print("interrupted", len(seen), flush=True)
        """
    )
    child = subprocess.Popen([sys.executable, "-c", script], stdin=subprocess.PIPE,
                             stdout=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == "started"
    child.send_signal(signal.SIGINT)
    child.stdin.write("\n")
    child.stdin.flush()
    out, _ = child.communicate(timeout=120)
    assert child.returncode == 0
    word, n = out.split()
    assert word == "interrupted" and int(n) <= 2, out


def test_local_sweep_stopped_part_way_keeps_its_points(tmp_path):
    # Without a client: an exception after 100 of 160 points (as Ctrl-C would raise) leaves the
    # finished points in the store; the rerun computes only the others.
    store = str(tmp_path / "map.csv")
    w, v = bi.linspace(0.5, 3.0, 16), bi.linspace(0.03, 0.15, 10)
    opts = {"max_periods": 300.0, "lyapunov_periods": 50}

    class Stop(Exception):
        pass

    def stop_at_100(done, total):
        if done == 100:
            raise Stop

    with pytest.raises(Stop):
        bi.sweep.map(w, v, store=store, threads=2, progress=stop_at_100, **opts)
    kept = pd.read_csv(store)
    # The 100 points reported done (points still running when it stopped are dropped).
    assert len(kept) == 100 and not kept.duplicated(["omega", "velocity"]).any()
    totals = []
    df = bi.sweep.map(w, v, store=store, threads=2, progress=lambda d, t: totals.append(t), **opts)
    assert set(totals) == {160 - len(kept)} and len(totals) == 160 - len(kept)
    assert len(df) == 160
    merged = df.merge(kept, on=["omega", "velocity"], suffixes=("", "_kept"))
    assert (merged["wall_time_s"] == merged["wall_time_s_kept"]).all()
    assert_same_map(df, bi.sweep.map(w, v, threads=2, **opts))
