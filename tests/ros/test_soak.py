"""Soak: the node runs free (real_time_factor 0) for SOAK_SECONDS (default 60) with an rclpy
subscriber on every topic: no impact lost (indices contiguous, count equal to what the node
published), every received state on the configured grid of simulation time, memory flat.
Prints the throughput (simulated time per wall second, messages per second) and peak RSS."""
import json
import os
import re
import time

import rclpy
from bistable_impact_msgs.msg import ImpactEvent, MassState
from common import NodeProcess, keep_all_impacts
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock

SECONDS = float(os.environ.get("SOAK_SECONDS", "60"))
RATE = float(os.environ.get("SOAK_RATE", "100"))


def rss_kib(pid, field):
    with open(f"/proc/{pid}/status") as f:
        return int(re.search(rf"^{field}:\s+(\d+) kB", f.read(), re.M).group(1))


class Counter:
    """Checks messages as they arrive, keeping only counts (the soak must not grow itself)."""

    def __init__(self):
        self.states = self.clocks = self.impacts = 0
        self.next_index = 0
        self.gaps = 0
        self.off_grid = 0
        self.last_t = 0.0

    def state(self, m):
        self.states += 1
        k = m.t * RATE
        self.off_grid += abs(k - round(k)) > 1e-6 * max(1.0, k)
        self.last_t = m.t

    def impact(self, m):
        self.gaps += m.index != self.next_index
        self.next_index = m.index + 1
        self.impacts += 1

    def clock(self, m):
        self.clocks += 1


def test_soak_free_running():
    domain = 41
    ctx = rclpy.Context()
    rclpy.init(context=ctx, domain_id=domain)
    peer = Node("soak_peer", context=ctx)
    c = Counter()
    deep = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    peer.create_subscription(MassState, "/bistable/mass_state", c.state, deep)
    peer.create_subscription(Clock, "/clock", c.clock, 10)
    peer.create_subscription(ImpactEvent, "/bistable/impacts", c.impact, keep_all_impacts())
    ex = rclpy.executors.SingleThreadedExecutor(context=ctx)
    ex.add_node(peer)
    node = NodeProcess("-p", "real_time_factor:=0.0", "-p", f"publish_rate:={RATE}", domain=domain)
    rss = []
    try:
        start = time.monotonic()
        next_sample = start
        while time.monotonic() - start < SECONDS:
            ex.spin_once(timeout_sec=0.01)
            if time.monotonic() >= next_sample:
                rss.append(rss_kib(node.pid, "VmRSS"))
                next_sample += 1.0
        peak = rss_kib(node.pid, "VmHWM")
        wall = time.monotonic() - start
    finally:
        log = node.stop()
        # Drain what is still in flight.
        end = time.monotonic() + 3
        while time.monotonic() < end:
            ex.spin_once(timeout_sec=0.05)
        peer.destroy_node()
        rclpy.shutdown(context=ctx)
    m = re.search(r"stopping at t = (\S+) s: (\d+) impacts located, (\d+) published \((\d+) failed\), "
                  r"(\d+) states published \((\d+) dropped, (\d+) without subscriber\)", log)
    assert m, log
    t_end, located, published, failed, states, dropped, unsubscribed = float(m[1]), *map(int, m.groups()[1:])
    # No impact lost: every published impact arrived, in order, from index 0.
    assert failed == 0 and c.gaps == 0 and c.impacts == published and published >= located - 1 > 0
    # States: on the configured grid, all of them published or counted as dropped or as due
    # before the subscriber matched.
    assert c.off_grid == 0 and c.states > 0
    assert states + dropped + unsubscribed == round(t_end * RATE) + 1, (states, dropped, unsubscribed, t_end)
    # Memory flat: the DDS send windows and histories fill during the first half; over the
    # second half RSS grows by less than 2 MiB.
    warm = rss[len(rss) // 2]
    print("RSS KiB per second:", rss)
    assert max(rss[len(rss) // 2:]) - warm < 2048, rss
    report = {
        "seconds": round(wall, 1),
        "publish_rate_hz": RATE,
        "sim_seconds": round(t_end, 1),
        "sim_seconds_per_wall_second": round(t_end / wall, 1),
        "impacts": published,
        "states_published": states,
        "states_dropped": dropped,
        "states_without_subscriber": unsubscribed,
        "messages_published_per_second": round((states + published + c.clocks) / wall),
        "states_received": c.states,
        "clocks_received": c.clocks,
        "messages_received_per_second": round((c.states + c.impacts + c.clocks) / wall),
        "rss_kib_after_warmup": warm,
        "rss_kib_end": rss[-1],
        "peak_rss_kib": peak,
    }
    print("SOAK " + json.dumps(report))
    out = os.environ.get("SOAK_REPORT")
    if out:
        with open(out, "w") as f:
            json.dump(report, f, indent=1)
