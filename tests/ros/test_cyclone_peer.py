"""A second, independent DDS implementation (Eclipse Cyclone DDS, Python binding) receives the
node's topics as plain DDS topics `rt/...` with the ROS 2 type names, and sends it a shaker
command."""
import math
import time

from common import NodeProcess, assert_impacts_match, reference
from cyclone_types import Clock, Header, ImpactEvent, MassState, ShakerCommand, Time
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration


RELIABLE = Policy.Reliability.Reliable(max_blocking_time=duration(milliseconds=100))


def test_cyclone_dds_peer_receives_every_topic_and_commands():
    domain = 31
    dp = DomainParticipant(domain)
    qos = Qos(RELIABLE, Policy.History.KeepLast(1000))
    durable = Qos(RELIABLE, Policy.History.KeepLast(1000), Policy.Durability.TransientLocal)
    states = DataReader(dp, Topic(dp, "rt/bistable/mass_state", MassState), qos=qos)
    impacts = DataReader(dp, Topic(dp, "rt/bistable/impacts", ImpactEvent), qos=durable)
    clocks = DataReader(dp, Topic(dp, "rt/clock", Clock), qos=Qos(Policy.Reliability.BestEffort))
    commands = DataWriter(dp, Topic(dp, "rt/bistable/shaker_command", ShakerCommand), qos=qos)
    node = NodeProcess("-p", "real_time_factor:=10.0", "-p", "publish_rate:=10.0", domain=domain)
    got_states, got_impacts, got_clocks = [], [], []
    sent = False
    try:
        end = time.monotonic() + 30
        while time.monotonic() < end and not (got_impacts and got_impacts[-1].t > 80.0):
            got_states += states.take(N=1000)
            got_impacts += impacts.take(N=1000)
            got_clocks += clocks.take(N=1000)
            if not sent and got_states and commands.get_matched_subscriptions() and got_states[-1].t < 30:
                cmd = ShakerCommand(Header(Time(50, 0), ""), 0, 2.5, 0.1, 0.0, 0.0)
                commands.write(cmd)
                sent = True
            time.sleep(0.02)
    finally:
        log = node.stop()
    assert sent, "command subscription never matched"
    assert "1 commands accepted" in log, log
    assert len(got_states) > 100 and len(got_clocks) > 100
    ts = [s.t for s in got_states]
    assert all(abs((b - a) - 0.1) < 1e-9 for a, b in zip(ts, ts[1:]))
    assert got_clocks[-1].clock.sec > 50
    late = [s for s in got_states if s.t > 50.0]
    assert late and late[0].shaker_omega == 2.5 and not math.isnan(late[0].x)
    ref = reference(1.75, 0.07, got_impacts[-1].t + 1.0, switch=(50.0, 2.5, 0.1))
    assert len(got_impacts) > 10
    assert_impacts_match(got_impacts, ref)
