"""A ROS 2 peer that comes and goes, for test_fault_churn.py (run as its own process).

    churn_peer.py DOMAIN SECONDS SEED RATE    creates rclpy participants one after the other; in
        each, subscriptions on /bistable/mass_state and /bistable/impacts with random QoS
        (reliable or best effort, volatile or transient local, depth 1 to 1000) are created,
        spun for 0 to 0.3 s and destroyed, 1 to 8 times, then the participant is shut down.
        Every received state must be on the RATE grid, and the impacts one subscription
        receives must come in order. Prints the counts as one JSON line.
    churn_peer.py DOMAIN hold                 one participant with a reliable, transient-local
        impact subscription and a reliable state subscription, spinning until killed (the
        test kills it with SIGKILL: a subscriber that vanishes without a goodbye).
"""
import json
import random
import sys
import time
from collections import Counter

import rclpy
from bistable_impact_msgs.msg import ImpactEvent, MassState
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy


def participant(domain, name):
    ctx = rclpy.Context()
    rclpy.init(context=ctx, domain_id=domain)
    node = Node(name, context=ctx)
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(node)
    return ctx, node, ex


def spin(ex, seconds):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        ex.spin_once(timeout_sec=min(0.02, max(0.0, end - time.monotonic())))


class ImpactChecker:
    """Checks the impact indices one subscription receives: never repeated or out of order;
    gaps (its own history overflowing while this process waits for the CPU, or best effort)
    are counted."""

    def __init__(self, stats):
        self.stats, self.last = stats, None

    def __call__(self, m):
        self.stats["impacts_received"] += 1
        if self.last is not None:
            if m.index <= self.last:
                self.stats["impacts_out_of_order"] += 1
            elif m.index != self.last + 1:
                self.stats["impact_gaps_by_subscriber_qos"] += 1
        self.last = m.index


def churn(domain, seconds, seed, rate):
    rng = random.Random(seed)
    stats = Counter()

    def on_state(m):
        stats["states_received"] += 1
        k = m.t * rate
        stats["states_off_grid"] += abs(k - round(k)) > 1e-6 * max(1.0, k)

    end = time.monotonic() + seconds
    while time.monotonic() < end:
        ctx, node, ex = participant(domain, f"churn_{stats['participants']}")
        stats["participants"] += 1
        for _ in range(rng.randint(1, 8)):
            subs = []
            for topic, kind in (("/bistable/mass_state", MassState), ("/bistable/impacts", ImpactEvent)):
                if rng.random() < 0.2:
                    continue
                qos = QoSProfile(depth=rng.choice([1, 10, 100, 1000]),
                                 reliability=rng.choice([ReliabilityPolicy.RELIABLE, ReliabilityPolicy.BEST_EFFORT]))
                if kind is ImpactEvent and qos.reliability == ReliabilityPolicy.RELIABLE and rng.random() < 0.5:
                    qos.durability = DurabilityPolicy.TRANSIENT_LOCAL
                    stats["transient_local_subscriptions"] += 1
                cb = on_state if kind is MassState else ImpactChecker(stats)
                subs.append(node.create_subscription(kind, topic, cb, qos))
                stats["subscriptions"] += 1
            spin(ex, rng.uniform(0.0, 0.3))
            for s in subs:
                node.destroy_subscription(s)
            stats["subscription_cycles"] += 1
        ex.shutdown(timeout_sec=1)
        node.destroy_node()
        rclpy.shutdown(context=ctx)
    print(json.dumps(stats), flush=True)


def hold(domain):
    ctx, node, ex = participant(domain, "held_peer")
    reliable = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    durable = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    node.create_subscription(ImpactEvent, "/bistable/impacts", lambda m: None, durable)
    node.create_subscription(MassState, "/bistable/mass_state", lambda m: None, reliable)
    print("ready", flush=True)
    while True:
        ex.spin_once(timeout_sec=0.05)


if __name__ == "__main__":
    if sys.argv[2] == "hold":
        hold(int(sys.argv[1]))
    else:
        churn(int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4]))
