"""Helpers of the ROS 2 interop tests: the node as a subprocess, the core's reference impact
list, spinning an rclpy node until a condition holds, the impact subscription of the checks,
and the fault tests' report files."""
import csv
import ctypes
import io
import json
import os
import pathlib
import re
import select
import signal
import subprocess
import sys
import threading
import time
from types import SimpleNamespace

ROOT = pathlib.Path(__file__).resolve().parents[2]
NODE = os.environ.get("BISTABLE_NODE", str(ROOT / "target/release/bistable_impact_node"))
REFERENCE = os.environ.get("BISTABLE_REFERENCE", str(ROOT / "target/release/examples/reference_impacts"))
PARAMS_FILE = ROOT / "ros/bistable_impact_node/config/bistable_impact.yaml"
IMPACT_FIELDS = ["t", "phase", "x", "v_before", "v_after", "zdot", "delta_k"]
# The columns of an impact row as impact_reader.py writes them.
READER_FIELDS = ["index", *IMPACT_FIELDS, "ended_in_sticking"]


_prctl = ctypes.CDLL(None, use_errno=True).prctl


def _die_with_parent():
    """In the child before exec: SIGKILL when the test process dies (no orphaned nodes)."""
    _prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG


class NodeProcess:
    """bistable_impact_node with ROS arguments, in DDS domain `domain` (`env`: more environment
    variables). Its stderr is read as it comes (a full pipe would block the node's logging),
    keeping at most `keep_lines` lines: the first half and the most recent half."""

    def __init__(self, *ros_args, domain=0, keep_lines=20000, env=None):
        env = dict(os.environ, ROS_DOMAIN_ID=str(domain), **(env or {}))
        self.proc = subprocess.Popen([NODE, "--ros-args", *ros_args], stderr=subprocess.PIPE, text=True, env=env,
                                     preexec_fn=_die_with_parent)
        self.log = None
        self.lines_seen = 0
        self._head, self._tail = [], []
        self._keep = keep_lines // 2
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self):
        for line in self.proc.stderr:
            self.lines_seen += 1
            if len(self._head) < self._keep:
                self._head.append(line)
            else:
                self._tail.append(line)
                if len(self._tail) > 2 * self._keep:
                    del self._tail[:self._keep]

    @property
    def pid(self):
        return self.proc.pid

    def alive(self):
        return self.proc.poll() is None

    def wait_for_line(self, needle, timeout):
        """Waits until a line of the log so far contains `needle`; returns that line, or None
        after `timeout` seconds or when the node has exited."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            for line in self._head + self._tail[-self._keep:]:
                if needle in line:
                    return line
            if not self.alive():
                return None
            time.sleep(0.01)
        return None

    def interrupt(self):
        """Sends SIGINT (the node then stops by itself; `stop` collects it)."""
        if self.alive():
            self.proc.send_signal(signal.SIGINT)

    def stop(self):
        """Stops the node with SIGINT (as ros2 launch does) and returns its log; the node must
        exit by itself with status 0."""
        if self.log is None:
            if self.alive():
                self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(timeout=30)
            finally:
                if self.proc.poll() is None:
                    self.proc.kill()
                self._reader.join(timeout=10)
            tail = self._tail[-self._keep:] if len(self._tail) > self._keep else self._tail
            skipped = self.lines_seen - len(self._head) - len(tail)
            self.log = "".join(self._head + ([f"[... {skipped} lines ...]\n"] if skipped else []) + tail)
            assert self.proc.returncode == 0, self.log
        return self.log


class ReaderProcess:
    """One impact_reader.py process: a subscriber of /bistable/impacts as a user's own node would
    be (see that file)."""

    def __init__(self, vendor, domain, out, name="early"):
        self.vendor, self.out, self.ready = vendor, out, False
        self.proc = subprocess.Popen([sys.executable, str(pathlib.Path(__file__).with_name("impact_reader.py")), vendor, str(domain), out,
                                      name], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                                     preexec_fn=_die_with_parent)

    def command(self, what):
        """Sends a command line (impact_reader.py: join, count, stop)."""
        self.proc.stdin.write(what + "\n")
        self.proc.stdin.flush()

    def _line(self, timeout):
        """The next line it printed, or None after `timeout` seconds."""
        if not select.select([self.proc.stdout], [], [], timeout)[0]:
            return None
        return self.proc.stdout.readline()

    def counts(self, timeout=5.0):
        """What its readers have received so far ({name: count}), asked once it has said
        `ready`; {} while it has not."""
        while not self.ready:
            line = self._line(0)
            if line is None:
                return {}
            self.ready = line.strip() == "ready"
        self.command("count")
        end = time.monotonic() + timeout
        while (line := self._line(max(0.0, end - time.monotonic()))) is not None:
            if line.startswith("{"):
                return json.loads(line)
        return {}

    def join(self, domain, tmp_path, k, same_process=False):
        """A second reader of the same vendor: in a new process (returned), or with
        `same_process` in this one (None returned)."""
        if same_process:
            self.command("join")
            return None
        return ReaderProcess(self.vendor, domain, str(tmp_path / f"late{k}.json"), "late")

    def signal(self, sig):
        self.proc.send_signal(sig)

    def collect(self):
        """Stops it and returns {reader name: {"joined_after", "rows"}}."""
        try:
            self.command("stop")
        except BrokenPipeError:  # it has exited: its status tells
            pass
        try:
            self.proc.wait(timeout=60)
        finally:
            if self.proc.poll() is None:
                self.proc.kill()
        assert self.proc.returncode == 0, (self.vendor, self.proc.returncode)
        with open(self.out) as f:
            return json.load(f)


SUMMARY = re.compile(r"stopping at t = (?P<t>\S+) s: (?P<located>\d+) impacts located, (?P<published>\d+) published "
                     r"\((?P<failed>\d+) failed\), (?P<states>\d+) states published \((?P<dropped>\d+) dropped, "
                     r"(?P<unsubscribed>\d+) without subscriber\), "
                     r"(?P<accepted>\d+) commands accepted, (?P<refused>\d+) refused, (?P<dropped_when_due>\d+) dropped when due; "
                     r"(?:(?P<requests_refused>\d+) requests refused, (?P<resets>\d+) resets; )?"
                     r"(?P<paced_ticks>\d+) paced ticks, lateness max (?P<max_lateness_ms>\S+) ms, (?P<late_ticks>\d+) over 10 ms")


def summary(log):
    """The node's shutdown summary as numbers (t in s, counts as ints)."""
    m = SUMMARY.search(log)
    assert m, log[-3000:]
    return {k: (float(v) if k in ("t", "max_lateness_ms") else int(v or 0)) for k, v in m.groupdict().items()}


def rss_kib(pid, field="VmRSS"):
    """Resident set size (VmRSS) or its peak (VmHWM) of process `pid` [KiB]."""
    with open(f"/proc/{pid}/status") as f:
        return int(re.search(rf"^{field}:\s+(\d+) kB", f.read(), re.M).group(1))


def reference(omega, v, t_end, switch=None, state=None):
    """The core simulator's impacts (ζ = 0.02, e = 0.85) up to `t_end`, optionally with the
    shaker switched to (Ω2, V2) at T: switch = (T, Ω2, V2), or from the mass state
    state = (x0, v0) at time 0 (nondimensional)."""
    extra = switch or state or ()
    args = [REFERENCE, str(omega), str(v), str(t_end)] + [repr(float(a)) for a in extra]
    out = subprocess.run(args, check=True, capture_output=True, text=True).stdout
    return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(io.StringIO(out))]


def impacts_of(rows):
    """impact_reader.py's rows as impacts with the message's field names."""
    return [SimpleNamespace(**dict(zip(READER_FIELDS, r))) for r in rows]


def check_stream(got, ref, first, last, name):
    """`got` holds the impacts first..last, each once, in order, equal to the reference."""
    indices = [m.index for m in got]
    assert indices == list(range(first, last + 1)), (
        f"{name}: {len(indices)} received, expected {first}..{last}; missing "
        f"{sorted(set(range(first, last + 1)) - set(indices))[:10]}, duplicated "
        f"{len(indices) - len(set(indices))}")
    for m in got:
        r = ref[m.index]
        for f in IMPACT_FIELDS:
            assert abs(getattr(m, f) - r[f]) <= 1e-12, f"{name}: impact {m.index} {f}: {getattr(m, f)} vs {r[f]}"
        assert m.ended_in_sticking == bool(r["ended_in_sticking"]), (name, m.index)


def assert_impacts_match(received, ref, tol=1e-12):
    """Every received impact, indices contiguous from 0, equal to the reference within `tol`."""
    assert [m.index for m in received] == list(range(len(received)))
    assert len(received) <= len(ref)
    for m, r in zip(received, ref):
        for f in IMPACT_FIELDS:
            got, want = getattr(m, f), r[f]
            assert abs(got - want) <= tol, f"impact {m.index} {f}: {got} vs {want}"
        assert m.ended_in_sticking == bool(r["ended_in_sticking"])


class Spinner:
    """An rclpy context, node and executor of one test peer in DDS domain `domain`."""

    def __init__(self, domain, name="fault_peer"):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node

        self.rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain)
        self.node = Node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def spin_until(self, cond, timeout, step=0.02):
        """Spins until `cond()` holds or `timeout` seconds passed; returns `cond()`."""
        end = time.monotonic() + timeout
        while not cond() and time.monotonic() < end:
            self.executor.spin_once(timeout_sec=step)
        return cond()

    def spin_for(self, seconds, step=0.02):
        self.spin_until(lambda: False, seconds, step)

    def drain(self, n=10):
        """Runs up to `n` callbacks that are ready now, without waiting."""
        for _ in range(n):
            self.executor.spin_once(timeout_sec=0)

    def close(self):
        self.executor.shutdown(timeout_sec=1)
        self.node.destroy_node()
        self.rclpy.shutdown(context=self.context)


def keep_all_impacts():
    """QoS of a subscriber that must see every impact: reliable, transient local and keep-all, so
    that its own history never drops one when the Python process falls behind (the node waits
    only for acknowledgements, which DDS sends on receipt) and the check is about the node."""
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

    return QoSProfile(depth=1000, history=HistoryPolicy.KEEP_ALL,
                      reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL)


def report_file(name, content):
    """Writes `content` (a dict as JSON, else text) to $FAULT_REPORT_DIR/`name` when it is set."""
    out = os.environ.get("FAULT_REPORT_DIR")
    if out:
        with open(os.path.join(out, name), "w") as f:
            if isinstance(content, dict):
                json.dump(content, f, indent=1)
            else:
                f.write(content)
