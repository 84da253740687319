"""A real ROS 2 peer (rclpy on rmw_fastrtps, PyPI wheels, interface package built by rosidl)
against bistable_impact_node: topics, impacts equal to the core simulator's, /clock with
use_sim_time, the graph, parameter services, shaker commands, rosout."""
import math
import time

import pytest
import rclpy
from bistable_impact_msgs.msg import ImpactEvent, MassState, ShakerCommand
from common import PARAMS_FILE, NodeProcess, assert_impacts_match, reference
from rcl_interfaces.msg import Log
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock

RELIABLE_DEEP = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
IMPACTS_QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
ROSOUT_QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)


class Peer:
    """An rclpy node subscribed to every topic of the node (and /rosout)."""

    def __init__(self, domain, use_sim_time=False):
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain)
        self.node = Node("peer", context=self.context, parameter_overrides=[Parameter("use_sim_time", value=use_sim_time)])
        self.states, self.impacts, self.clocks, self.logs = [], [], [], []
        self.node.create_subscription(MassState, "/bistable/mass_state", self.states.append, RELIABLE_DEEP)
        self.node.create_subscription(ImpactEvent, "/bistable/impacts", self.impacts.append, IMPACTS_QOS)
        self.node.create_subscription(Clock, "/clock", self.clocks.append, 10)
        self.node.create_subscription(Log, "/rosout", self.logs.append, ROSOUT_QOS)
        self.executor = rclpy.executors.SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def _spin(self, cond, timeout):
        end = time.monotonic() + timeout
        while time.monotonic() < end and not cond():
            self.executor.spin_once(timeout_sec=0.05)
        return cond()

    def wait(self, future, timeout=10.0):
        assert self._spin(future.done, timeout), "no answer"
        return future.result()

    def logged(self, text):
        return [m.msg for m in self.logs if text in m.msg and m.name == "bistable_impact"]

    def close(self):
        self.node.destroy_node()
        rclpy.shutdown(context=self.context)


@pytest.fixture
def peer_factory():
    made = []

    def make(domain, **kw):
        made.append(Peer(domain, **kw))
        return made[-1]

    yield make
    for p in made:
        p.close()


def test_topics_impacts_clock_graph_and_parameters(peer_factory):
    domain = 17
    peer = peer_factory(domain, use_sim_time=True)
    node = NodeProcess("--params-file", str(PARAMS_FILE), "-p", "real_time_factor:=25.0", "-p", "publish_rate:=20",
                       domain=domain)
    try:
        assert peer._spin(lambda: peer.impacts and peer.impacts[-1].t > 60.0, 30), "no impacts"
        # The graph: node, topics and types.
        names = peer.node.get_node_names_and_namespaces()
        assert ("bistable_impact", "/") in names
        topics = dict(peer.node.get_topic_names_and_types())
        assert topics["/bistable/mass_state"] == ["bistable_impact_msgs/msg/MassState"]
        assert topics["/bistable/impacts"] == ["bistable_impact_msgs/msg/ImpactEvent"]
        assert topics["/bistable/shaker_command"] == ["bistable_impact_msgs/msg/ShakerCommand"]
        assert "rosgraph_msgs/msg/Clock" in topics["/clock"]
        # use_sim_time: the peer's clock follows the node's /clock, not the wall clock.
        assert peer._spin(lambda: len(peer.clocks) > 10, 5)
        now = peer.node.get_clock().now().nanoseconds * 1e-9
        last = peer.clocks[-1].clock.sec + peer.clocks[-1].clock.nanosec * 1e-9
        assert 0 < now < 1e6 and abs(now - last) < 2.0, (now, last)

        # Parameter services.
        client = AsyncParameterClient(peer.node, "bistable_impact")
        assert client.wait_for_services(timeout_sec=10)
        listed = peer.wait(client.list_parameters()).result.names
        for name in ["zeta", "e", "omega0", "delta_x", "Omega", "V", "publish_rate", "real_time_factor", "frame_id",
                     "use_sim_time"]:
            assert name in listed
        values = peer.wait(client.get_parameters(["zeta", "Omega", "publish_rate", "frame_id"])).values
        assert [values[0].double_value, values[1].double_value, values[2].double_value, values[3].string_value] == [
            0.02, 1.75, 20.0, "shaker_base"]
        bad = [Parameter("zeta", value=math.nan), Parameter("e", value=1.5), Parameter("V", value=-0.1),
               Parameter("Omega", value=2.0), Parameter("zeta", value="abc"), Parameter("publish_rate", value=math.inf)]
        results = peer.wait(client.set_parameters(bad)).results
        assert [r.successful for r in results] == [False] * len(bad)
        assert "invalid zeta" in results[0].reason and "invalid e" in results[1].reason
        assert "fixed at start-up" in results[3].reason and "type" in results[4].reason.lower()
        t_set = peer.states[-1].t
        results = peer.wait(client.set_parameters([Parameter("publish_rate", value=40.0),
                                                   Parameter("frame_id", value="lab")])).results
        assert all(r.successful for r in results), [r.reason for r in results]
        values = peer.wait(client.get_parameters(["zeta", "publish_rate"])).values
        assert (values[0].double_value, values[1].double_value) == (0.02, 40.0)
        # Still running, now at 40 Hz of simulation time with the new frame.
        assert peer._spin(lambda: len([s for s in peer.states if s.header.frame_id == "lab"]) > 50, 20)
        lab = [s.t for s in peer.states if s.header.frame_id == "lab"]
        steps = [b - a for a, b in zip(lab, lab[1:])]
        assert max(abs(d - 0.025) for d in steps) < 1e-9, steps
        early = [s.t for s in peer.states if s.t < t_set]
        assert all(abs((b - a) - 0.05) < 1e-9 for a, b in zip(early, early[1:]))
        # rosout: start-up, parameter changes, refusals.
        assert peer._spin(lambda: peer.logged("refused parameter zeta"), 5)
        assert peer.logged("parameter publish_rate changed")
    finally:
        log = node.stop()
    assert "started /bistable_impact in DDS domain 17" in log
    # Every impact, from index 0, equal to the core simulator's.
    ref = reference(1.75, 0.07, peer.impacts[-1].t + 1.0)
    assert len(peer.impacts) > 15
    assert_impacts_match(peer.impacts, ref)
    assert peer.impacts[3].header.stamp.sec == int(ref[3]["t"])
    # States: SI values with the default omega0 = delta_x = 1, consistent energies.
    s = peer.states[-1]
    assert abs(s.kinetic_energy - 0.5 * s.v ** 2) < 1e-15 and s.well in (1, 2)
    assert s.impact_count >= peer.impacts[-1].index


def test_shaker_commands_change_the_response_as_predicted(peer_factory):
    domain = 23
    peer = peer_factory(domain)
    pub = peer.node.create_publisher(ShakerCommand, "/bistable/shaker_command", RELIABLE_DEEP)
    node = NodeProcess("-p", "real_time_factor:=10.0", "-p", "publish_rate:=10.0", domain=domain)
    try:
        assert peer._spin(lambda: pub.get_subscription_count() > 0 and peer.states, 10)
        assert peer.states[-1].t < 30.0, "too late to schedule the command"

        def command(mode, stamp=0.0, omega=0.0, velocity=0.0, z=0.0, zdot=0.0):
            c = ShakerCommand(mode=mode, omega=omega, velocity=velocity, z=z, zdot=zdot)
            c.header.stamp.sec, c.header.stamp.nanosec = int(stamp), round((stamp % 1) * 1e9)
            pub.publish(c)

        # Bad commands first: refused with reasons, the node goes on.
        command(ShakerCommand.MODE_SINUSOID, omega=math.nan, velocity=0.1)
        command(9, omega=2.0, velocity=0.1)
        command(ShakerCommand.MODE_SINUSOID, omega=2.0, velocity=-0.1)
        command(ShakerCommand.MODE_EXTERNAL, z=math.inf)
        # The set-point change, at simulation time 40.25 s.
        command(ShakerCommand.MODE_SINUSOID, stamp=40.25, omega=2.5, velocity=0.1)
        assert peer._spin(lambda: peer.impacts and peer.impacts[-1].t > 100.0, 30)
        assert peer._spin(lambda: len(peer.logged("refused shaker command")) >= 4, 5)
        reasons = " | ".join(peer.logged("refused shaker command"))
        for needle in ["omega = nan", "unknown mode 9", "velocity = -0.1", "z = inf"]:
            assert needle in reasons.lower(), reasons
        assert peer.logged("accepted command: shaker sinusoid omega = 2.5 rad/s")
    finally:
        log = node.stop()
    assert "4 refused" in log and "1 commands accepted" in log
    before = [s for s in peer.states if s.t < 40.25]
    after = [s for s in peer.states if s.t > 40.25]
    assert before[-1].shaker_omega == 1.75 and after[0].shaker_omega == 2.5 and after[0].shaker_velocity == 0.1
    # No jump in plate position across the switch (|ż| <= 0.1 over 0.1 s).
    assert abs(after[0].z - before[-1].z) <= 0.1 * (after[0].t - before[-1].t) + 1e-12
    ref = reference(1.75, 0.07, peer.impacts[-1].t + 1.0, switch=(40.25, 2.5, 0.1))
    assert any(r["t"] > 40.25 for r in ref[: len(peer.impacts)])
    assert_impacts_match(peer.impacts, ref)
    # The prediction differs from the unswitched response.
    unswitched = reference(1.75, 0.07, peer.impacts[-1].t)
    late = [m for m in peer.impacts if m.t > 45.0][0]
    assert abs(unswitched[late.index]["t"] - late.t) > 1e-3
