"""Floods the node's services for test_fault_flood.py (run as its own process, alongside the
command flooders): `request_peer.py DOMAIN SECONDS RATE`. Keeps up to 20 requests in flight, cycling
through requests that leave the real-time run as it is: refused steps (the node is running),
refused resets (NaN, below the plate, out of range), resume (already running: success),
refused parameter sets (NaN, start-up parameter, use_sim_time true), parameter gets and
descriptions, at most RATE requests a wall second (0: as fast as it can; the command flooders
already take the CPU, and a second busy Python process would starve the test's observer, whose
received rate the test checks). Waits for the services, prints "flooding", and when done one JSON line: requests
sent, answered, refusals expected and seen, and answers that were not as expected."""
import json
import math
import sys
import time

import rclpy
from bistable_impact_msgs.srv import ResetState, Step
from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import DescribeParameters, GetParameters, SetParameters
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_srvs.srv import SetBool


def double(name, x):
    return Parameter(name=name, value=ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=x))


def main(domain, seconds, rate):
    ctx = rclpy.Context()
    rclpy.init(context=ctx, domain_id=domain)
    node = Node("request_peer", context=ctx)
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(node)
    # rclpy's default service QoS keeps only the last 10 replies: with 20 requests in flight a
    # burst of answers (the node answers what it has read at each poll) would overflow it.
    qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
    clients = {
        "step": node.create_client(Step, "/bistable/step", qos_profile=qos),
        "reset_state": node.create_client(ResetState, "/bistable/reset_state", qos_profile=qos),
        "pause": node.create_client(SetBool, "/bistable/pause", qos_profile=qos),
        "set": node.create_client(SetParameters, "/bistable_impact/set_parameters", qos_profile=qos),
        "get": node.create_client(GetParameters, "/bistable_impact/get_parameters", qos_profile=qos),
        "describe": node.create_client(DescribeParameters, "/bistable_impact/describe_parameters", qos_profile=qos),
    }
    for c in clients.values():
        assert c.wait_for_service(timeout_sec=30), c.srv_name
    use_sim_time = Parameter(name="use_sim_time", value=ParameterValue(type=ParameterType.PARAMETER_BOOL,
                                                                         bool_value=True))
    # (client, request, check of the answer, refusals the node counts)
    cycle = [
        ("step", Step.Request(ticks=5), lambda r: not r.success and "pause it first" in r.message, 1),
        ("reset_state", ResetState.Request(x=math.nan, v=0.0), lambda r: not r.success, 1),
        ("reset_state", ResetState.Request(x=-1.0, v=0.0), lambda r: not r.success and "below" in r.message, 1),
        ("reset_state", ResetState.Request(x=0.0, v=1e9), lambda r: not r.success, 1),
        ("pause", SetBool.Request(data=False), lambda r: r.success and "already running" in r.message, 0),
        ("set", SetParameters.Request(parameters=[double("zeta", math.nan), double("Omega", 3.0), use_sim_time]),
         lambda r: [x.successful for x in r.results] == [False] * 3, 3),
        ("get", GetParameters.Request(names=["zeta", "Omega"]),
         lambda r: [v.double_value for v in r.values] == [0.02, 1.75], 0),
        ("describe", DescribeParameters.Request(names=["omega0"]),
         lambda r: r.descriptors[0].read_only and "rad/s" in r.descriptors[0].description, 0),
    ]
    sent = answered = refusals = 0
    wrong = []
    pending = []
    print("flooding", flush=True)
    start = time.monotonic()
    k = 0
    while time.monotonic() < start + seconds or pending:
        while (len(pending) < 20 and time.monotonic() < start + seconds
               and (rate <= 0 or sent < rate * (time.monotonic() - start))):
            name, req, check, refused = cycle[k % len(cycle)]
            k += 1
            pending.append((clients[name].call_async(req), name, check, refused))
            sent += 1
        ex.spin_once(timeout_sec=0.01)
        still = []
        for fut, name, check, refused in pending:
            if fut.done():
                answered += 1
                refusals += refused
                if not check(fut.result()):
                    wrong.append((name, str(fut.result())[:300]))
            else:
                still.append((fut, name, check, refused))
        pending = still
        if time.monotonic() > start + seconds + 60:
            break
    print(json.dumps({"seconds": round(time.monotonic() - start, 2), "sent": sent, "answered": answered,
                      "unanswered": len(pending), "refusals_expected": refusals, "wrong": wrong[:10],
                      "wrong_count": len(wrong)}), flush=True)
    node.destroy_node()
    rclpy.shutdown(context=ctx)


if __name__ == "__main__":
    main(int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3]))
