"""Floods /bistable/shaker_command as fast as rclpy can publish, for test_fault_flood.py (run as
its own process): `flood_peer.py DOMAIN SECONDS SEED OMEGA0 DELTA_X`.

The stream cycles through a shuffled pool: valid sinusoid commands equal to the running shaker
(Omega = 1.75, V = 0.07 in SI units for the node's OMEGA0 and DELTA_X; zero stamp: applied at
once, the motion goes on unchanged), the
well-formed invalid commands of hostile.py and malformed samples (truncated, garbage, unknown
encapsulation, invalid UTF-8, empty). Serialized samples are published raw (publish(bytes)),
the fastest way through rclpy. The publisher is reliable and keep-all, so DDS does not drop
commands on the way. Waits until the node has matched it, then prints "flooding" and, when
done, the counts by kind as one JSON line."""
import json
import random
import sys
import time
from collections import Counter

import hostile
import rclpy
import rclpy.duration
from bistable_impact_msgs.msg import MassState, ShakerCommand
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy


def main(domain, seconds, seed, omega0, delta_x):
    rng = random.Random(seed)
    ctx = rclpy.Context()
    rclpy.init(context=ctx, domain_id=domain)
    node = Node("flood_peer", context=ctx)
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(node)
    states = []
    node.create_subscription(MassState, "/bistable/mass_state", lambda m: states.append(m.t), 10)
    pub = node.create_publisher(ShakerCommand, "/bistable/shaker_command",
                                QoSProfile(depth=1000, history=HistoryPolicy.KEEP_ALL,
                                           reliability=ReliabilityPolicy.RELIABLE))
    end = time.monotonic() + 30
    while time.monotonic() < end and not (states and pub.get_subscription_count()):
        ex.spin_once(timeout_sec=0.05)
    # The node's reader may learn of this writer a little after the writer has matched it.
    t_end = time.monotonic() + 1.0
    while time.monotonic() < t_end:
        ex.spin_once(timeout_sec=0.05)

    pool = [("valid", hostile.sinusoid(1.75 * omega0, 0.07 * omega0 * delta_x))] * 20
    invalid = hostile.invalid_commands(states[-1] if states else 0.0, omega0, delta_x)
    for kind, payloads in invalid.items():
        if kind == "external_not_after_frontier":
            continue  # refused only relative to the node's time; the others always are
        pool += [("invalid_" + kind, p) for p in payloads]
    for kind, make in hostile.malformed_samples(rng).items():
        pool += [("malformed_" + kind, make(rng)) for _ in range(5)]
    pool += [("malformed_empty", b"")] * 2
    rng.shuffle(pool)
    sent = Counter()
    print("flooding", flush=True)
    start = time.monotonic()
    end = start + seconds
    k = 0
    while True:
        for kind, payload in pool:
            pub.publish(payload)
            sent[kind] += 1
        k += 1
        if k % 4 == 0:
            ex.spin_once(timeout_sec=0)  # keep the participant's own traffic going
            if time.monotonic() >= end:
                break
    wall = time.monotonic() - start
    # Hand everything over before leaving (a destroyed writer would not repair losses).
    acked = pub.wait_for_all_acked(rclpy.duration.Duration(seconds=30))
    total = sum(sent.values())
    print(json.dumps({"seconds": round(wall, 2), "sent": total, "per_second": round(total / wall), "all_acked": acked,
                      "by_kind": dict(sorted(sent.items()))}), flush=True)
    node.destroy_node()
    rclpy.shutdown(context=ctx)


if __name__ == "__main__":
    main(int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5]))
