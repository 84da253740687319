"""ROS_AUTOMATIC_DISCOVERY_RANGE / ROS_LOCALHOST_ONLY as rmw reads them: with LOCALHOST the node
announces only loopback locators (a second interface, a veth pair v0/v1 with v0 at 10.213.7.1 in
this test's network namespace, is neither used nor announced) and is still found by a local rclpy peer; by default
(SUBNET) it announces dummy0 too; OFF and unknown values stop it with exit status 2."""
import socket
import struct
import subprocess
import time

from bistable_impact_msgs.msg import MassState
from common import NODE, NodeProcess, Spinner

DUMMY = "10.213.7.1"
SPDP_GROUP = "239.255.0.1"


def second_interface():
    """A veth pair v0/v1, v0 at DUMMY, in this network namespace (ros/netns.sh makes the test
    root in it; the kernel here has no dummy interfaces)."""
    if subprocess.run(["ip", "addr", "show", "v0"], capture_output=True).returncode != 0:
        for cmd in (["ip", "link", "add", "v0", "type", "veth", "peer", "name", "v1"],
                    ["ip", "addr", "add", f"{DUMMY}/24", "dev", "v0"],
                    ["ip", "link", "set", "v1", "up"],
                    ["ip", "link", "set", "v0", "up"]):
            subprocess.run(cmd, check=True)


def spdp_payloads(domain, seconds):
    """The node's SPDP datagrams (RTPS vendor id 0x0112, RustDDS; the rclpy peer's Fast DDS is
    0x010f) sent to the domain's discovery multicast group over `seconds`."""
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEPORT, 1)
    s.bind(("", 7400 + 250 * domain))
    for iface in ("127.0.0.1", DUMMY):
        s.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP,
                     struct.pack("4s4s", socket.inet_aton(SPDP_GROUP), socket.inet_aton(iface)))
    s.settimeout(0.2)
    got, end = [], time.monotonic() + seconds
    while time.monotonic() < end:
        try:
            got.append(s.recv(65536))
        except socket.timeout:
            pass
    s.close()
    return [p for p in got if p.startswith(b"RTPS") and p[6:8] == b"\x01\x12"]


def announces(payloads, address):
    return any(socket.inet_aton(address) in p for p in payloads)


def run_node(domain, env, seconds=6.0):
    """SPDP payloads of a node started with `env`, and whether a local rclpy peer got its states."""
    import os
    saved = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    try:
        node = NodeProcess("-p", "real_time_factor:=5.0", domain=domain)
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    peer = Spinner(domain, "discovery_peer")
    states = []
    peer.node.create_subscription(MassState, "/bistable/mass_state", states.append, 10)
    try:
        payloads = spdp_payloads(domain, seconds)
        peer.spin_until(lambda: len(states) > 5, 30)
    finally:
        log = node.stop()
        peer.close()
    return payloads, len(states) > 5, log


def test_localhost_range_announces_loopback_only():
    second_interface()
    # The node's own packets: those that carry its participant's locators on loopback.
    payloads, found, log = run_node(71, {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"})
    assert "DDS discovery range LOCALHOST" in log
    assert found, "a local peer finds a LOCALHOST node"
    assert payloads and not announces(payloads, DUMMY), len(payloads)
    payloads, found, log = run_node(72, {"ROS_LOCALHOST_ONLY": "1", "ROS_AUTOMATIC_DISCOVERY_RANGE": ""})
    assert "DDS discovery range LOCALHOST" in log and found
    assert payloads and not announces(payloads, DUMMY)
    # By default (SUBNET) the second interface is announced.
    payloads, found, log = run_node(73, {"ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET"})
    assert "DDS discovery range SUBNET" in log and found
    assert announces(payloads, DUMMY), len(payloads)


def test_off_and_unknown_ranges_are_refused():
    import os
    for value, needle in [("OFF", "not supported"), ("lan", "must be SUBNET")]:
        env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE=value)
        r = subprocess.run([NODE, "--ros-args"], capture_output=True, text=True, timeout=20, env=env)
        assert r.returncode == 2 and needle in r.stderr, (value, r.returncode, r.stderr)
