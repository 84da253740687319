"""Helpers of the ROS 2 interop tests: the node as a subprocess, the core's reference impact
list, and spinning an rclpy node until a condition holds."""
import csv
import io
import os
import pathlib
import signal
import subprocess

ROOT = pathlib.Path(__file__).resolve().parents[2]
NODE = os.environ.get("BISTABLE_NODE", str(ROOT / "target/release/bistable_impact_node"))
REFERENCE = os.environ.get("BISTABLE_REFERENCE", str(ROOT / "target/release/examples/reference_impacts"))
PARAMS_FILE = ROOT / "ros/bistable_impact_node/config/bistable_impact.yaml"
IMPACT_FIELDS = ["t", "phase", "x", "v_before", "v_after", "zdot", "delta_k"]


class NodeProcess:
    """bistable_impact_node with ROS arguments, in DDS domain `domain`; stderr is collected."""

    def __init__(self, *ros_args, domain=0):
        env = dict(os.environ, ROS_DOMAIN_ID=str(domain))
        self.proc = subprocess.Popen([NODE, "--ros-args", *ros_args], stderr=subprocess.PIPE, text=True, env=env)
        self.log = None

    @property
    def pid(self):
        return self.proc.pid

    def stop(self):
        """Stops the node with SIGINT (as ros2 launch does) and returns its log; the node must
        exit by itself with status 0."""
        if self.log is None:
            self.proc.send_signal(signal.SIGINT)
            _, self.log = self.proc.communicate(timeout=30)
            assert self.proc.returncode == 0, self.log
        return self.log


def reference(omega, v, t_end, switch=None):
    """The core simulator's impacts (ζ = 0.02, e = 0.85) up to `t_end`, optionally with the
    shaker switched to (Ω2, V2) at T: switch = (T, Ω2, V2)."""
    args = [REFERENCE, str(omega), str(v), str(t_end)] + ([str(a) for a in switch] if switch else [])
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout
    return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(io.StringIO(out))]


def assert_impacts_match(received, ref, tol=1e-12):
    """Every received impact, indices contiguous from 0, equal to the reference within `tol`."""
    assert [m.index for m in received] == list(range(len(received)))
    assert len(received) <= len(ref)
    for m, r in zip(received, ref):
        for f in IMPACT_FIELDS:
            got, want = getattr(m, f), r[f]
            assert abs(got - want) <= tol, f"impact {m.index} {f}: {got} vs {want}"
        assert m.ended_in_sticking == bool(r["ended_in_sticking"])
