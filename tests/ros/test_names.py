"""ROS names as rcl resolves them: two nodes in namespaces /rig1 and /rig2 (different Omega) in
one DDS domain, each peer subscription sees only its rig's impacts, equal to the core's; topic,
node name and /clock remapping; invalid rules refused with exit status 2."""
import re
import subprocess

from bistable_impact_msgs.msg import ImpactEvent
from common import NODE, NodeProcess, Spinner, assert_impacts_match, keep_all_impacts, reference
from rosgraph_msgs.msg import Clock

RIG1 = ("-r", "__ns:=/rig1", "-r", "/clock:=clock", "-p", "Omega:=1.75")
# rig2 also renames the node and remaps its impacts to a private name and its clock.
RIG2 = ("-r", "__ns:=/rig2", "-r", "__node:=sim2", "-r", "bistable/impacts:=~/hits",
        "-r", "/clock:=clock", "-p", "Omega:=2.2")


def discovery_lines(log, most=120):
    """The node's own lines and the DDS layer's discovery events of `log`, at most `most`."""
    keep = re.compile(r"\]: (?!DDS)|participant|Participant|Matched|matched|ocator|route|Route|WARN|ERROR")
    lines = [line[:300] for line in log.splitlines() if keep.search(line)]
    return "\n".join(lines[:most // 2] + ["[...]"] + lines[-most // 2:] if len(lines) > most else lines)


def test_two_rigs_in_one_domain_see_only_their_own_impacts():
    domain = 55  # its own: Fast DDS's shared-memory transport reaches across network namespaces
    peer = Spinner(domain, "names_peer")
    got = {name: [] for name in ["/rig1/bistable/impacts", "/rig2/sim2/hits", "/rig2/bistable/impacts",
                                 "/bistable/impacts"]}
    for name, sink in got.items():
        peer.node.create_subscription(ImpactEvent, name, sink.append, keep_all_impacts())
    clocks = {name: [] for name in ["/rig1/clock", "/rig2/clock", "/clock"]}
    for name, sink in clocks.items():
        peer.node.create_subscription(Clock, name, sink.append, 10)
    common = ("-p", "real_time_factor:=25.0", "-p", "publish_rate:=20")
    # The DDS layer's discovery events in the nodes' logs, for a failure to show which side
    # discovery stopped on (e.g. the nodes matched the peer's readers while the peer knew only
    # their last-created writer, and no sample arrived).
    dds_info = {"BISTABLE_DDS_LOG": "info"}
    rig1 = NodeProcess(*RIG1, *common, domain=domain, env=dds_info)
    rig2 = NodeProcess(*RIG2, *common, domain=domain, env=dds_info)
    try:
        done = lambda: all(got[n] and got[n][-1].t > 60.0 for n in ["/rig1/bistable/impacts", "/rig2/sim2/hits"])
        if not peer.spin_until(done, 40):
            # Everything that tells discovery from the nodes apart: what the peer saw and the nodes' logs.
            seen = {n: len(v) for n, v in {**got, **clocks}.items()}
            graph = (peer.node.get_node_names_and_namespaces(), sorted(dict(peer.node.get_topic_names_and_types())))
            publishers = {n: [(str(i.endpoint_gid), str(i.qos_profile.reliability)) for i in
                              peer.node.get_publishers_info_by_topic(n)] for n in got}
            # The namespace's sockets (ports, receive queues) of the peer and both nodes.
            sockets = subprocess.run(["ss", "-uanp"], capture_output=True, text=True).stdout
            logs = [discovery_lines(p.stop()) for p in (rig1, rig2)]
            raise AssertionError(f"no impacts to t = 60 within 40 s: received {seen}; graph {graph}; "
                                 f"publishers {publishers}; sockets:\n{sockets}\n"
                                 f"rig1 log:\n{logs[0]}\nrig2 log:\n{logs[1]}")
        # The ROS graph is eventually consistent: the announcement of a node's reader (shaker_command)
        # can reach the peer after the first samples of the node's writers (the impacts to t = 60
        # can arrive before the readers are in the graph), so the graph is awaited on its own.
        wanted = ["/rig1/bistable/mass_state", "/rig1/bistable/impacts", "/rig1/bistable/shaker_command",
                  "/rig2/bistable/mass_state", "/rig2/sim2/hits", "/rig2/bistable/shaker_command"]
        graph = lambda: (peer.node.get_node_names_and_namespaces(), dict(peer.node.get_topic_names_and_types()))
        complete = lambda: (("bistable_impact", "/rig1") in graph()[0] and ("sim2", "/rig2") in graph()[0]
                            and all(name in graph()[1] for name in wanted))
        assert peer.spin_until(complete, 15), (graph()[0], sorted(graph()[1]))
        topics = graph()[1]
        assert topics["/rig2/sim2/hits"] == ["bistable_impact_msgs/msg/ImpactEvent"]
        assert "rosgraph_msgs/msg/Clock" in topics["/rig1/clock"] and "rosgraph_msgs/msg/Clock" in topics["/rig2/clock"]
        # Only the peer's own subscriptions are on the unremapped names.
        assert "bistable_impact_msgs/msg/MassState" not in topics.get("/bistable/mass_state", [])
    finally:
        log1, log2 = rig1.stop(), rig2.stop()
        peer.close()
    assert "started /rig1/bistable_impact" in log1 and "started /rig2/sim2" in log2
    assert "bistable/impacts -> /rig2/sim2/hits" in log2, log2[:3000]
    assert got["/rig2/bistable/impacts"] == [] and got["/bistable/impacts"] == []
    assert clocks["/clock"] == [] and clocks["/rig1/clock"] and clocks["/rig2/clock"]
    for name, omega in [("/rig1/bistable/impacts", 1.75), ("/rig2/sim2/hits", 2.2)]:
        impacts = got[name]
        assert len(impacts) > 15, name
        assert_impacts_match(impacts, reference(omega, 0.07, impacts[-1].t + 1.0))
    # Different rigs, different responses.
    assert abs(got["/rig1/bistable/impacts"][5].t - got["/rig2/sim2/hits"][5].t) > 1e-3


def test_invalid_remapping_rules_are_refused_with_status_2():
    for rule, needle in [("__ns:=rig1", "must be absolute"), ("bistable/impacts:=1hits", "digit"),
                         ("bistable/*:=x", "wildcards"), ("__node:=a/b", "contains '/'"),
                         ("bistable/impacts:={nodes}/x", "unknown substitution"), ("impacts", "from:=to")]:
        r = subprocess.run([NODE, "--ros-args", "-r", rule], capture_output=True, text=True, timeout=10)
        assert r.returncode == 2 and needle in r.stderr and rule in r.stderr, (rule, r.returncode, r.stderr)
