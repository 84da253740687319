"""A subscriber process of /bistable/impacts as a user's own node would be, for
test_interop_matrix.py (run as its own process, started before or together with the node).

    impact_reader.py VENDOR DOMAIN OUT [NAME]

VENDOR is `cyclone` (Eclipse Cyclone DDS through its Python binding, DDS topic
rt/bistable/impacts) or `fastdds` (rclpy on rmw_fastrtps). At once it creates one reliable,
transient-local, keep-all impact reader (named NAME, default `early`) and prints `ready`. Then
it takes commands, one a line, on its standard input (not signals: a signal can land on a DDS
thread and break its receiving):
    join   creates a second such reader in the same process (`late`, a reader joining mid-run
           next to the first: same participant for rclpy, same Cyclone DDS domain instance);
    count  prints the counts received so far as one JSON line;
    stop   (or end of input) takes what is left until nothing new comes for QUIET seconds,
           writes every reader's impacts to OUT as JSON ({name: {"joined_after": impacts the
           first reader held when it was created, "rows": [[index, t, phase, x, v_before,
           v_after, zdot, delta_k, ended_in_sticking], ...]}}) and exits 0.
SIGSTOP/SIGCONT stall it as a whole.
"""
import json
import os
import select
import sys
import time

from common import READER_FIELDS

QUIET = 0.5


def row(m):
    return [getattr(m, f) for f in READER_FIELDS]


class Cyclone:
    def __init__(self, domain):
        os.environ.setdefault("CYCLONEDDS_URI",
                              "<Tracing><Verbosity>severe</Verbosity><OutputFile>/dev/null</OutputFile></Tracing>")
        from cyclone_types import ImpactEvent
        from cyclonedds.core import Policy, Qos
        from cyclonedds.domain import DomainParticipant
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic
        from cyclonedds.util import duration

        self.type = ImpactEvent
        self.dp = DomainParticipant(domain)
        self.topic = Topic(self.dp, "rt/bistable/impacts", ImpactEvent)
        self.qos = Qos(Policy.Reliability.Reliable(max_blocking_time=duration(milliseconds=100)),
                       Policy.History.KeepAll, Policy.Durability.TransientLocal)
        self.DataReader = DataReader
        self.readers = []

    def subscribe(self, sink):
        self.readers.append((self.DataReader(self.dp, self.topic, qos=self.qos), sink))

    def poll(self, timeout):
        got = 0
        for reader, sink in self.readers:
            for s in reader.take(N=2000):
                # Invalid samples (the writer's departure) carry no impact.
                if isinstance(s, self.type):
                    sink.append(row(s))
                    got += 1
        if not got:
            time.sleep(timeout)
        return got


class FastDds:
    def __init__(self, domain):
        import rclpy
        from bistable_impact_msgs.msg import ImpactEvent
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
        from rclpy.signals import SignalHandlerOptions

        self.ctx = rclpy.Context()
        rclpy.init(context=self.ctx, domain_id=domain, signal_handler_options=SignalHandlerOptions.NO)
        self.node = Node(f"impact_reader_{os.getpid()}", context=self.ctx)
        self.ex = SingleThreadedExecutor(context=self.ctx)
        self.ex.add_node(self.node)
        self.type = ImpactEvent
        self.qos = QoSProfile(depth=1000, history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE,
                              durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.got = 0

    def subscribe(self, sink):
        def take(m):
            sink.append(row(m))
            self.got += 1
        self.node.create_subscription(self.type, "/bistable/impacts", take, self.qos)

    def poll(self, timeout):
        self.got = 0
        self.ex.spin_once(timeout_sec=timeout)
        for _ in range(200):
            before = self.got
            self.ex.spin_once(timeout_sec=0)
            if self.got == before:
                break
        return self.got


def main(vendor, domain, out, name="early"):
    peer = {"cyclone": Cyclone, "fastdds": FastDds}[vendor](int(domain))
    readers = {name: {"joined_after": 0, "rows": []}}
    peer.subscribe(readers[name]["rows"])
    print("ready", flush=True)
    while True:
        peer.poll(0.005)
        if not select.select([sys.stdin], [], [], 0)[0]:
            continue
        what = sys.stdin.readline().strip()
        if what in ("stop", ""):
            break
        if what == "join" and "late" not in readers:
            readers["late"] = {"joined_after": len(readers[name]["rows"]), "rows": []}
            peer.subscribe(readers["late"]["rows"])
        elif what == "count":
            print(json.dumps({k: len(r["rows"]) for k, r in readers.items()}), flush=True)
    quiet_since = time.monotonic()
    while time.monotonic() - quiet_since < QUIET:
        if peer.poll(0.01):
            quiet_since = time.monotonic()
    with open(out, "w") as f:
        json.dump(readers, f)


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))
