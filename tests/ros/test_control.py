"""Control services, parameters and /diagnostics from rclpy: pause stops /clock, step advances
exactly N publish ticks, reset restarts impact indices at 0 from the requested state (equal to
the core's run from that state), refused requests answer with a reason; parameter descriptors
(units, ranges, read_only), use_sim_time refused, one type on /clock; /diagnostics at 1 Hz."""
import math
import re
import sys

from bistable_impact_msgs.msg import ImpactEvent, MassState, ShakerCommand
from bistable_impact_msgs.srv import ResetState, Step
from common import NodeProcess, Spinner, assert_impacts_match, keep_all_impacts, reference
from rosgraph_msgs.msg import Clock
from std_srvs.srv import SetBool, Trigger

RATE = 20.0  # publish_rate of these tests [Hz]


class Peer(Spinner):
    """An rclpy peer with the node's topics and control service clients."""

    def __init__(self, domain):
        super().__init__(domain, "control_peer")
        n = self.node
        self.clocks, self.states, self.impacts = [], [], []
        n.create_subscription(Clock, "/clock", self.clocks.append, 10)
        n.create_subscription(MassState, "/bistable/mass_state", self.states.append, 100)
        n.create_subscription(ImpactEvent, "/bistable/impacts", self.impacts.append, keep_all_impacts())
        self.pause = n.create_client(SetBool, "/bistable/pause")
        self.step = n.create_client(Step, "/bistable/step")
        self.reset = n.create_client(Trigger, "/bistable/reset")
        self.reset_state = n.create_client(ResetState, "/bistable/reset_state")
        for c in (self.pause, self.step, self.reset, self.reset_state):
            assert c.wait_for_service(timeout_sec=20), c.srv_name

    def call(self, client, request, timeout=30):
        future = client.call_async(request)
        assert self.spin_until(future.done, timeout), client.srv_name
        return future.result()


def clock_s(c):
    return c.clock.sec + c.clock.nanosec * 1e-9


def test_pause_step_reset():
    domain = 61
    node = NodeProcess("-p", "real_time_factor:=20.0", "-p", f"publish_rate:={RATE}", domain=domain)
    peer = Peer(domain)
    try:
        assert peer.spin_until(lambda: peer.states and peer.states[-1].t > 20.0, 60)
        # Pause: /clock stops at the time the response gives.
        r = peer.call(peer.pause, SetBool.Request(data=True))
        assert r.success, r.message
        t_pause = float(re.search(r"paused at t = (\S+) s", r.message).group(1))
        peer.spin_for(1.0)
        n_clocks, n_states, n_impacts = len(peer.clocks), len(peer.states), len(peer.impacts)
        assert clock_s(peer.clocks[-1]) == round(t_pause * 1e9) * 1e-9 or abs(clock_s(peer.clocks[-1]) - t_pause) < 1e-9
        assert peer.states[-1].t == t_pause
        peer.spin_for(2.0)
        assert (len(peer.clocks), len(peer.states), len(peer.impacts)) == (n_clocks, n_states, n_impacts)
        assert peer.call(peer.pause, SetBool.Request(data=True)).success  # already paused

        # Refused steps, with reasons; nothing moves.
        for ticks, needle in [(0, "1..=100000"), (100001, "1..=100000")]:
            r = peer.call(peer.step, Step.Request(ticks=ticks))
            assert not r.success and needle in r.message, r.message
            assert r.t == t_pause
        # Step 7 ticks: exactly 7 states, one per tick, then paused again.
        r = peer.call(peer.step, Step.Request(ticks=7))
        assert r.success, r.message
        assert abs(r.t - (t_pause + 7 / RATE)) < 1e-9, (r.t, t_pause)
        peer.spin_for(1.5)
        new = [s.t for s in peer.states[n_states:]]
        assert len(new) == 7, new
        for k, t in enumerate(new, 1):
            assert abs(t - (t_pause + k / RATE)) < 1e-9, new
        assert abs(clock_s(peer.clocks[-1]) - r.t) < 1e-9
        assert peer.states[-1].impact_count == r.impact_count
        # A step while running is refused.
        assert peer.call(peer.pause, SetBool.Request(data=False)).success
        r = peer.call(peer.step, Step.Request(ticks=3))
        assert not r.success and "pause it first" in r.message, r.message
        assert peer.spin_until(lambda: peer.states[-1].t > t_pause + 2.0, 30), "resumed"
        assert peer.call(peer.pause, SetBool.Request(data=True)).success

        # Refused resets change nothing.
        t_before, count_before = peer.states[-1].t, peer.states[-1].impact_count
        for x, v, needle in [(-0.01, 0.0, "below the plate"), (math.nan, 0.0, "not finite"),
                             (0.5, math.inf, "not finite"), (2e6, 0.0, "out of range")]:
            r = peer.call(peer.reset_state, ResetState.Request(x=x, v=v))
            assert not r.success and needle in r.message, (x, v, r.message)
        peer.spin_for(0.5)
        assert peer.states[-1].t == t_before and peer.states[-1].impact_count == count_before
        old_impacts = len(peer.impacts)
        assert old_impacts > 3
        # Reset to (x, v) while paused: state at t = 0 published, still paused.
        r = peer.call(peer.reset_state, ResetState.Request(x=0.02, v=-0.05))
        assert r.success, r.message
        assert peer.spin_until(lambda: peer.states[-1].t == 0.0, 10)
        s = peer.states[-1]
        assert (s.x, s.v, s.z, s.impact_count) == (0.02, -0.05, 0.0, 0)
        peer.spin_for(1.0)
        assert peer.states[-1].t == 0.0, "still paused"
        assert peer.call(peer.pause, SetBool.Request(data=False)).success
        assert peer.spin_until(lambda: peer.states[-1].t > 40.0, 60)
        # Reset to the initial condition while running.
        assert peer.call(peer.pause, SetBool.Request(data=True)).success
        peer.spin_for(0.5)
        after_state = list(peer.impacts[old_impacts:])
        r = peer.call(peer.reset, Trigger.Request())
        assert r.success and "impact indices restart at 0" in r.message, r.message
        assert peer.call(peer.pause, SetBool.Request(data=False)).success
        assert peer.spin_until(lambda: peer.states[-1].t > 30.0 and peer.states[-1].t < 100.0, 60)
    finally:
        log = node.stop()
        peer.close()
    # The first run: indices contiguous from 0; then each reset restarts them at 0.
    runs, run = [], []
    for m in peer.impacts:
        if run and m.index == 0:
            runs.append(run)
            run = []
        run.append(m)
    runs.append(run)
    assert len(runs) == 3, [len(r) for r in runs]
    assert_impacts_match(runs[0], reference(1.75, 0.07, runs[0][-1].t + 1.0))
    assert len(runs[1]) > 5 and runs[1][0].index == 0 and runs[1] == after_state[:len(runs[1])]
    assert_impacts_match(runs[1], reference(1.75, 0.07, runs[1][-1].t + 1.0, state=(0.02, -0.05)))
    assert len(runs[2]) > 5
    assert_impacts_match(runs[2], reference(1.75, 0.07, runs[2][-1].t + 1.0))
    assert "2 resets" in log and "refused reset request" in log and "refused step request" in log


def test_parameter_descriptors_and_use_sim_time():
    from rcl_interfaces.msg import ParameterEvent, ParameterType
    from rclpy.parameter import Parameter
    from rclpy.parameter_client import AsyncParameterClient

    domain = 62
    node = NodeProcess("-p", "real_time_factor:=5.0", "-p", "use_sim_time:=true", domain=domain)
    peer = Spinner(domain, "param_peer")
    events = []
    peer.node.create_subscription(ParameterEvent, "/parameter_events", events.append, 100)
    try:
        client = AsyncParameterClient(peer.node, "bistable_impact")
        assert client.wait_for_services(timeout_sec=20)

        def wait(future):
            assert peer.spin_until(future.done, 20)
            return future.result()

        names = ["zeta", "e", "omega0", "delta_x", "Omega", "V", "publish_rate", "real_time_factor", "frame_id",
                 "history_depth", "use_sim_time", "nope"]
        d = {n: x for n, x in zip(names, wait(client.describe_parameters(names)).descriptors)}
        big = sys.float_info.max
        for name, unit, lo, hi, read_only in [
                ("zeta", "[-]", 0.0, big, False), ("e", "[-]", 0.0, 1.0, False),
                ("omega0", "[rad/s]", 5e-324, big, True), ("delta_x", "[m]", 5e-324, big, True),
                ("Omega", "[-]", 1e-6, 1e6, True), ("V", "[-]", 0.0, 1e6, True),
                ("publish_rate", "[Hz", 5e-324, 1e6, False), ("real_time_factor", "[-]", 0.0, big, False)]:
            x = d[name]
            assert x.name == name and x.type == ParameterType.PARAMETER_DOUBLE, name
            assert unit in x.description, (name, x.description)
            assert len(x.floating_point_range) == 1 and not x.integer_range, name
            r = x.floating_point_range[0]
            assert (r.from_value, r.to_value, x.read_only) == (lo, hi, read_only), (name, r, x.read_only)
        h = d["history_depth"]
        assert h.type == ParameterType.PARAMETER_INTEGER and h.read_only
        assert (h.integer_range[0].from_value, h.integer_range[0].to_value) == (1, 8192)
        assert d["frame_id"].type == ParameterType.PARAMETER_STRING and not d["frame_id"].read_only
        assert d["use_sim_time"].type == ParameterType.PARAMETER_BOOL
        assert d["nope"].type == ParameterType.PARAMETER_NOT_SET

        # use_sim_time: the start-up true was ignored (logged); a set to true is refused.
        assert wait(client.get_parameters(["use_sim_time"])).values[0].bool_value is False
        r = wait(client.set_parameters([Parameter("use_sim_time", value=True)])).results[0]
        assert not r.successful and "owns the simulation clock" in r.reason, r.reason
        assert wait(client.set_parameters([Parameter("use_sim_time", value=False)])).results[0].successful
        # A runtime change is published on /parameter_events; an atomic set with one bad
        # value changes nothing.
        assert wait(client.set_parameters([Parameter("zeta", value=0.03)])).results[0].successful
        assert peer.spin_until(lambda: any(p.name == "zeta" and p.value.double_value == 0.03
                                           for ev in events for p in ev.changed_parameters), 10)
        r = wait(client.set_parameters_atomically([Parameter("zeta", value=0.04), Parameter("e", value=1.5)]))
        assert not r.result.successful and "invalid e" in r.result.reason, r.result.reason
        assert wait(client.get_parameters(["zeta"])).values[0].double_value == 0.03
        r = wait(client.set_parameters([Parameter("Omega", value=2.0)])).results[0]
        assert not r.successful and "fixed at start-up" in r.reason
        # One type on /clock: the node runs no subscription of its own on it.
        assert peer.spin_until(lambda: "/clock" in dict(peer.node.get_topic_names_and_types()), 10)
        assert dict(peer.node.get_topic_names_and_types())["/clock"] == ["rosgraph_msgs/msg/Clock"]
    finally:
        log = node.stop()
        peer.close()
    assert "use_sim_time:=true ignored" in log and "refused parameter use_sim_time" in log


def test_diagnostics():
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus

    domain = 63
    node = NodeProcess("-p", "real_time_factor:=10.0", "-p", f"publish_rate:={RATE}", domain=domain)
    peer = Peer(domain)
    reports = []
    peer.node.create_subscription(DiagnosticArray, "/diagnostics", reports.append, 10)
    commands = peer.node.create_publisher(ShakerCommand, "/bistable/shaker_command", 10)

    def values(report):
        assert len(report.status) == 1
        return {kv.key: kv.value for kv in report.status[0].values}

    try:
        assert peer.spin_until(lambda: len(reports) >= 3 and commands.get_subscription_count() > 0, 60)
        commands.publish(ShakerCommand(mode=7))
        assert not peer.call(peer.step, Step.Request(ticks=1)).success
        n = len(reports)
        assert peer.spin_until(lambda: len(reports) >= n + 2, 30)
        assert peer.call(peer.pause, SetBool.Request(data=True)).success
        n = len(reports)
        assert peer.spin_until(lambda: len(reports) >= n + 3, 30)
    finally:
        node.stop()
        peer.close()
    st = reports[-1].status[0]
    assert st.name == "bistable_impact: simulation" and st.hardware_id == "/bistable_impact"
    running = [values(r) for r in reports[:n] if values(r)["integrator status"] == "running"]
    assert len(running) >= 3
    for v in running:
        for key in ["states dropped", "impact count", "commands refused", "requests refused", "impacts published"]:
            assert int(v[key]) >= 0, key
        assert 0.0 < float(v["real-time factor achieved"]) < 100.0, v
        assert float(v["worst lateness [ms]"]) >= float(v["worst lateness, last period [ms]"]) >= 0.0
        assert v["real-time factor set"] == "10"
    counts = [int(v["impact count"]) for v in running]
    assert counts == sorted(counts) and counts[-1] > 0
    last = values(reports[-1])
    assert last["integrator status"] == "paused" and float(last["real-time factor achieved"]) == 0.0
    assert st.level == DiagnosticStatus.OK
    assert int(last["commands refused"]) == 1 and int(last["requests refused"]) == 1
    stamps = [r.header.stamp.sec + r.header.stamp.nanosec * 1e-9 for r in reports]
    assert all(b > a for a, b in zip(stamps, stamps[1:])) and stamps[0] > 1.6e9  # wall clock
