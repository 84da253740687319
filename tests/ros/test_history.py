"""Exact history of /bistable/impacts: a transient-local subscriber that joins at any time gets
exactly the last `history_depth` impacts, contiguous, then the live stream without gap or
duplicate, at more than 2,000 impacts per wall second.

The node starts frozen (real_time_factor 1e-9) until the observer has its first impacts, then
runs the baseline shaker paced at HISTORY_RTF (12000) simulated seconds per wall
second (~3,300 impacts/s when the machine keeps up) with history_depth 1500. A keep-all
observer subscribes from the start and sees everything; late joiners subscribe at random
instants while impacts stream (one at a time, until they have 1000 live impacts), then one
while the simulation is paused (real_time_factor 1e-9: nothing new is published, so the
joiner must get exactly the indices [M - N, M) of the M impacts published so far) and stays
after it resumes. Figures printed as HISTORY {...}.

Before the RustDDS history patch a late joiner got everything the writer still held (all
13,521 impacts from index 0 here; 128 stale ones, a gap and the last 8,193 in a longer run)."""
import json
import os
import random
import time

from bistable_impact_msgs.msg import ImpactEvent
from common import NodeProcess, Spinner, keep_all_impacts, summary
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient

DEPTH = 1500
RTF = float(os.environ.get("HISTORY_RTF", "12000"))


class Sub:
    """One impact subscription: indices only (and the wall time of the first sample)."""

    def __init__(self, peer):
        self.indices = []
        self.sub = peer.node.create_subscription(ImpactEvent, "/bistable/impacts", self.take, keep_all_impacts())

    def take(self, m):
        if not self.indices:
            self.first_wall = time.monotonic()
        self.indices.append(m.index)


def assert_history_then_live(indices, depth, lowest_last, name):
    """`depth` history impacts, then the live stream: contiguous, no duplicate, and the
    history ends at or after `lowest_last` (an impact published before the subscription)."""
    assert indices, name
    first = indices[0]
    assert indices == list(range(first, first + len(indices))), f"{name}: gap or duplicate {indices[:5]}..."
    assert first > 0 and first + depth - 1 >= lowest_last, (name, first, lowest_last)


def test_late_joiners_get_exactly_the_last_n_impacts_then_the_live_stream():
    domain = 53
    rng = random.Random(7)
    peer = Spinner(domain, "history_peer")
    observer = Sub(peer)
    params = AsyncParameterClient(peer.node, "bistable_impact")

    def set_rtf(value):
        future = params.set_parameters([Parameter("real_time_factor", value=value)])
        assert peer.spin_until(future.done, 10) and future.result().results[0].successful

    # The node starts frozen (the impacts of its first 100 s only), so that the observer is
    # matched before the stream starts however long discovery takes on a loaded machine.
    node = NodeProcess("-p", "real_time_factor:=1e-9", "-p", "publish_rate:=0.01", "-p", f"history_depth:={DEPTH}",
                       domain=domain)
    joiners = []
    try:
        assert peer.spin_until(lambda: observer.indices, 30), "observer not matched"
        assert params.wait_for_services(timeout_sec=20)
        started, start_count = time.monotonic(), len(observer.indices)
        set_rtf(RTF)
        assert peer.spin_until(lambda: len(observer.indices) > 2 * DEPTH, 20), len(observer.indices)
        # Joiners at random instants while the impacts stream, each subscribed for a second (one
        # at a time, so that the Python peer keeps up).
        for _ in range(3):
            peer.spin_for(rng.uniform(0.2, 0.8))
            joiner = Sub(peer)
            joiners.append((joiner, observer.indices[-1]))
            peer.spin_until(lambda: len(joiner.indices) >= DEPTH + 1000, 10)
            peer.node.destroy_subscription(joiner.sub)
        # Freeze: pace the simulation at 1e-9 simulated seconds per wall second (the next
        # state, 100 s of simulation time ahead, is due in 3,000 years).
        set_rtf(1e-9)
        paused_at = time.monotonic()  # after the node has the new value: a lower bound on the rate
        last = -1
        while len(observer.indices) != last:
            last = len(observer.indices)
            peer.spin_for(0.5)
        frozen = len(observer.indices)
        # The node's rate: what it published from the start of the stream up to the pause (the
        # observer may lag behind).
        rate = (frozen - start_count) / (paused_at - started)
        assert observer.indices == list(range(frozen))
        late = Sub(peer)
        assert peer.spin_until(lambda: len(late.indices) >= DEPTH, 10), len(late.indices)
        peer.spin_for(1.0)
        frozen_got = list(late.indices)
        # Resume.
        set_rtf(RTF)
        assert peer.spin_until(lambda: min(len(observer.indices), late.indices[-1]) > frozen + 1000, 20), (
            frozen, len(observer.indices), late.indices[-1])
    finally:
        node.stop()
        peer.close()
    n = len(observer.indices)
    report = {"impacts_per_wall_second": round(rate), "history_depth": DEPTH, "frozen_at": frozen,
              "frozen_joiner_first": frozen_got[0] if frozen_got else None, "frozen_joiner_count": len(frozen_got),
              "joiners": [{"first": j.indices[0] if j.indices else None, "received": len(j.indices),
                           "observer_last_at_join": last} for j, last in joiners]}
    print("HISTORY " + json.dumps(report))
    assert rate >= 2000, report
    # The observer saw every impact from index 0.
    assert observer.indices == list(range(n))
    # Frozen: exactly the last DEPTH impacts, nothing else until the stream resumed.
    assert frozen_got == list(range(frozen - DEPTH, frozen)), report
    assert late.indices == list(range(frozen - DEPTH, frozen - DEPTH + len(late.indices))), report
    assert summary(node.log)["failed"] == 0
    for k, (j, last) in enumerate(joiners):
        assert_history_then_live(j.indices, DEPTH, last, f"joiner {k}")
        # ... and then a second of the live stream.
        assert len(j.indices) >= DEPTH + 1000, (k, j.indices[0], j.indices[-1])
