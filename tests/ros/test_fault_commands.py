"""Hostile shaker commands at a high rate while the node runs in real time
(real_time_factor 1, 100 Hz): well-formed commands the node must refuse (non-finite, negative,
zero and huge values in every field, bad stamps, unknown modes, external samples not after the
frontier, a full queue), malformed CDR samples (truncated, garbage, unknown encapsulations,
invalid UTF-8, empty samples) through rclpy's raw publish and garbage from a Cyclone DDS writer
whose type has the same name, mixed with valid commands whose effect is checked state by state:
they take effect at max(stamp, now, end of the queue) as documented, in unusual encodings too
(big-endian, trailing bytes, a 100 kB frame_id), including extreme accepted values.

FAULT_COMMAND_SECONDS (default 10) sets the length of the mixed phase; the figures are printed
as one JSON line (FAULT_COMMANDS ...) and written to $FAULT_REPORT_DIR/commands.json if set."""
import json
import math
import os
import random
import time
from collections import Counter
from dataclasses import dataclass

import hostile
from bistable_impact_msgs.msg import ImpactEvent, MassState, ShakerCommand
from common import NodeProcess, Spinner, report_file, rss_kib, summary
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import sequence, uint8
from cyclonedds.pub import DataWriter
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from rcl_interfaces.msg import Log
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

SECONDS = float(os.environ.get("FAULT_COMMAND_SECONDS", "10"))
RATE = 100.0
GROUP_EVERY = 0.25  # simulated seconds between groups of valid commands
LEAD = 1.0  # a group is sent this long (simulated) before its instant
INITIAL = (1.75, 0.07)
# Cyclone DDS warns about every Fast DDS vendor-specific submessage it sees; keep the output short.
os.environ.setdefault("CYCLONEDDS_URI", "<Tracing><Verbosity>severe</Verbosity><OutputFile>/dev/null</OutputFile></Tracing>")


@dataclass
class RawCommand(IdlStruct, typename="bistable_impact_msgs::msg::dds_::ShakerCommand_"):
    """Cyclone DDS type with the node's type name but another layout: its samples are a length
    and that many bytes, which the node reads as a (too short) ShakerCommand."""

    data: sequence[uint8]


class Recorder:
    def __init__(self):
        self.states, self.impacts, self.logs = [], [], []

    def state(self, m):
        self.states.append((m.t, m.shaker_mode, m.shaker_omega, m.shaker_velocity, m.impact_count,
                            (m.x, m.v, m.z, m.zdot, m.kinetic_energy, m.potential_energy), m.well))

    @property
    def now(self):
        return self.states[-1][0] if self.states else 0.0

    def logged(self, text):
        return sum(text in m.msg for m in self.logs if m.name == "bistable_impact")


def expected_shaker(groups, t):
    """The shaker (omega, velocity) the node must show at simulation time t."""
    value = INITIAL
    for at, w, v in groups:
        if at < t:
            value = (w, v)
        else:
            break
    return value


def test_hostile_commands_are_refused_and_valid_ones_applied():
    domain = 51
    rng = random.Random(20240611)
    sp = Spinner(domain, "fault_commands_peer")
    rec = Recorder()
    reliable = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    durable = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    sp.node.create_subscription(MassState, "/bistable/mass_state", rec.state, reliable)
    sp.node.create_subscription(ImpactEvent, "/bistable/impacts", lambda m: rec.impacts.append(m), durable)
    sp.node.create_subscription(Log, "/rosout", rec.logs.append, durable)
    # Keep-all: DDS never discards a command before the node has it.
    pub = sp.node.create_publisher(ShakerCommand, "/bistable/shaker_command",
                                   QoSProfile(depth=1000, history=HistoryPolicy.KEEP_ALL,
                                              reliability=ReliabilityPolicy.RELIABLE))
    dp = DomainParticipant(domain)
    cyclone = DataWriter(dp, Topic(dp, "rt/bistable/shaker_command", RawCommand),
                         qos=Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepAll))
    node = NodeProcess("-p", "real_time_factor:=1.0", "-p", f"publish_rate:={RATE}", domain=domain)
    sent = Counter()
    groups = []
    probes = {"rclpy": 0, "cyclone": 0}
    rss = []
    try:
        assert sp.spin_until(lambda: rec.states and pub.get_subscription_count() > 0
                             and cyclone.get_matched_subscriptions(), 30), "node not matched"

        # Handshake: until the node has seen one sample from each writer (earlier ones may be
        # lost to discovery; they are counted as probes).
        def probe_rclpy():
            probes["rclpy"] += 1
            pub.publish(hostile.sinusoid(*INITIAL))

        def probe_cyclone():
            probes["cyclone"] += 1
            cyclone.write(RawCommand([1, 2, 3]))

        for probe, text in ((probe_rclpy, "accepted command"), (probe_cyclone, "deserialization")):
            deadline = time.monotonic() + 20
            while not rec.logged(text) and time.monotonic() < deadline:
                probe()
                sp.spin_for(0.25)
            assert rec.logged(text), f"handshake: no '{text}' on /rosout"
        sp.spin_for(0.5)

        # Mixed phase.
        malformed = hostile.malformed_samples(rng)
        odd_kinds = ["big_endian", "trailing_bytes", "huge_frame_id"]
        next_at = math.floor(rec.now) + 2 + 0.005
        k = 0
        start = time.monotonic()
        next_rss = start
        phase_end = start + SECONDS
        while time.monotonic() < phase_end:
            sp.drain(5)
            now = rec.now
            if time.monotonic() >= next_rss:
                rss.append(rss_kib(node.pid))
                next_rss += 1.0
            if now >= next_at - LEAD:
                # A group of valid commands, all taking effect at next_at, the last one wins.
                at = next_at
                w1, v1 = rng.uniform(1.5, 2.2), rng.uniform(0.04, 0.1)
                w2, v2 = rng.uniform(1.5, 2.2), rng.uniform(0.04, 0.1)
                w3, v3 = rng.uniform(1.5, 2.2), rng.uniform(0.04, 0.1)
                pub.publish(hostile.sinusoid(w1, v1, t=at))  # the instant
                pub.publish(hostile.sinusoid(hostile.MAX_ND, hostile.MAX_ND, t=at - 0.1))  # out of order: at
                pub.publish(hostile.sinusoid(hostile.MIN_OMEGA, -0.0))  # extreme but valid, zero stamp: at
                pub.publish(hostile.odd_valid(w2, v2, t=1e-9, kind=odd_kinds[k % 3]))  # far past: at
                pub.publish(hostile.sinusoid(w3, v3, t=at - 0.2))  # out of order: at
                sent["valid"] += 5
                sent["valid_" + odd_kinds[k % 3]] += 1
                groups.append((at, w3, v3))
                next_at += GROUP_EVERY
                k += 1
                invalid = hostile.invalid_commands(frontier=now)
                invalid_stream = hostile.shuffled_round_robin(invalid, rng)
                continue
            if k == 0:
                continue
            for _ in range(40):
                r = rng.random()
                if r < 0.70:
                    kind, payloads = next(invalid_stream)
                    pub.publish(rng.choice(payloads))
                    sent["invalid_" + kind] += 1
                elif r < 0.95:
                    kind = rng.choice(list(malformed))
                    pub.publish(malformed[kind](rng))
                    sent["malformed_" + kind] += 1
                elif r < 0.99:
                    cyclone.write(RawCommand(list(rng.randbytes(rng.randrange(0, 36)))))
                    sent["malformed_cyclone_wrong_type"] += 1
                else:
                    pub.publish(b"")
                    sent["malformed_empty"] += 1
        mixed_wall = time.monotonic() - start

        # Let the last group take effect, then fill the command queue with valid commands
        # for the far future: 1024 are queued, the rest refused.
        assert sp.spin_until(lambda: rec.now > groups[-1][0] + 0.2, 10), "the node stopped advancing"
        for _ in range(1100):
            pub.publish(hostile.sinusoid(1.0, 0.1, t=2.0**31 - 1))
        sent["far_future"] = 1100
        t_flood = rec.now
        assert sp.spin_until(lambda: rec.now > t_flood + 1.0, 10), "the node stopped advancing"
        rss.append(rss_kib(node.pid))
        peak = rss_kib(node.pid, "VmHWM")
        assert node.alive()
    finally:
        log = node.stop()
        sp.spin_for(1.0)
        sp.close()
    report_file("commands-node.log", log)
    s = summary(log)

    # Counts: every valid command accepted (plus the probes that arrived), every refused one
    # refused; empty samples never reach the node.
    valid = sent["valid"] + 1024
    refused_expected = sum(n for kind, n in sent.items() if kind.startswith(("invalid_", "malformed_"))
                           and kind != "malformed_empty") + 1100 - 1024
    assert 1 <= s["accepted"] - valid <= probes["rclpy"], (s, sent, probes)
    assert 1 <= s["refused"] - refused_expected <= probes["cyclone"], (s, refused_expected, sent, probes)
    # Every reason is logged.
    for needle in ("is not finite", "omega = -1.75 rad/s must be in [1e-6, 1e6]·omega0",
                   "omega = 5e-324 rad/s must be in [1e-6, 1e6]·omega0", "velocity = -0.07 m/s must be >= 0",
                   "the plate's displacement amplitude",
                   "is out of range", "is not after", "invalid stamp", "unknown mode",
                   "deserialization error"):
        assert needle in log, needle

    # States: contiguous on the 100 Hz grid, finite, always the sinusoid shown by the schedule.
    ts = [st[0] for st in rec.states]
    assert s["dropped"] == 0 and s["failed"] == 0
    assert all(abs((b - a) * RATE - 1) < 1e-6 for a, b in zip(ts, ts[1:])), "states missing or off the grid"
    mismatches = []
    for t, mode, w, v, count, values, well in rec.states:
        assert mode == 0 and all(math.isfinite(x) for x in values) and well in (1, 2), (t, values)
        ew, ev = expected_shaker(groups, t)
        if abs(w - ew) > 1e-12 * ew or abs(v - ev) > 1e-12 * ev:
            mismatches.append((t, (w, v), (ew, ev)))
    assert not mismatches, mismatches[:5]
    assert rec.states[-1][0] > groups[-1][0] + 1.0

    # Impacts: every one, in order, finite.
    assert [m.index for m in rec.impacts] == list(range(len(rec.impacts)))
    assert len(rec.impacts) == s["published"] and s["published"] >= s["located"] - 1
    assert all(math.isfinite(m.t) and math.isfinite(m.v_after) for m in rec.impacts)

    hostile_sent = sum(n for kind, n in sent.items() if kind.startswith(("invalid_", "malformed_")))
    report = {
        "mixed_phase_wall_s": round(mixed_wall, 1),
        "valid_sent": sent["valid"],
        "valid_groups": len(groups),
        "far_future_sent": 1100,
        "hostile_sent": hostile_sent,
        "hostile_per_s": round(hostile_sent / mixed_wall),
        "sent_by_kind": dict(sorted(sent.items())),
        "probes": probes,
        "node": s,
        "states_received": len(rec.states),
        "impacts_received": len(rec.impacts),
        "rss_kib_per_s": rss,
        "peak_rss_kib": peak,
    }
    print("FAULT_COMMANDS " + json.dumps(report))
    report_file("commands.json", report)
