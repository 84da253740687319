"""Every impact to every reliable subscriber, with each DDS vendor, started the way users start
it: subscriber processes (Cyclone DDS, Fast DDS through rclpy, or both) and a free-running node
(real_time_factor 0) are started together, as one launch file starts them; the node holds the
simulation at t = 0 until they are matched (`wait_for_impact_subscriptions`, the README's way to
start a lossless free-running run), and nothing in the test freezes or paces it.

Each subscriber process (impact_reader.py) has a reliable, transient-local, keep-all reader from
its start. About a second into the stream a second such reader joins for each: for the first
process of a run in that same process (next to a reader that is streaming: Cyclone DDS buffers
for the newcomer what its process receives before the node has matched it), for the others in a
process of its own (MATRIX_JOIN=same or own puts every one there). The run ends by
SIGINT while impacts stream; the node must publish every impact it located and wait for every
acknowledgement; then the processes drain and write what they got. Checks: the node's summary
(located = published, none failed, all acknowledged by every matched subscription), every
early reader has exactly the indices 0..N-1, equal to the core's impacts to 1e-12, and every late
reader a contiguous run up to N-1 that starts at least `history_depth` back (or at 0).

Cases: Cyclone-only, Fast DDS-only, mixed, and mixed with the Fast DDS process stalled (SIGSTOP
for STALL_SECONDS, SIGCONT: the node waits for it, nothing is lost anywhere; its second reader
is created as it resumes, while its first one is catching up on repairs), in the chatter case
(Omega 0.2, V 0.05, the fastest stream). MATRIX_REPEAT (1) runs each that many times (make
stress-ros: 20); MATRIX_SECONDS (3) of streaming; MATRIX_MIN_RATE (4000) impacts per wall second
at least when the late readers join or over the run, without a stalled reader. Figures printed as MATRIX {...} lines."""
import json
import os
import signal
import time

import pytest
from common import NodeProcess, ReaderProcess, check_stream, impacts_of, reference, report_file, summary

SECONDS = float(os.environ.get("MATRIX_SECONDS", "3"))
REPEAT = int(os.environ.get("MATRIX_REPEAT", "1"))
STALL_SECONDS = 2.0
# Lowest rate [impacts per wall second] of a run without a stalled reader (here: 6,400-7,100
# with rclpy readers, 22,000-31,000 with Cyclone DDS readers only).
MIN_RATE = float(os.environ.get("MATRIX_MIN_RATE", "4000"))
JOIN = os.environ.get("MATRIX_JOIN", "alternate")
assert JOIN in ("alternate", "same", "own"), f"MATRIX_JOIN={JOIN}: alternate, same or own"


def same_process(k):
    """Whether the late reader for the k-th reader process joins in that process."""
    return JOIN == "same" or (JOIN == "alternate" and k == 0)
DEPTH = 1000
CHATTER = (0.2, 0.05)
CASES = {
    "cyclone": ["cyclone", "cyclone"],
    "fastdds": ["fastdds", "fastdds"],
    "mixed": ["cyclone", "fastdds"],
    "mixed_stalled": ["cyclone", "cyclone", "fastdds"],
}


def run(domain, vendors, tmp_path, stall=False):
    omega, v = CHATTER
    readers = [ReaderProcess(kind, domain, str(tmp_path / f"reader{k}.json")) for k, kind in enumerate(vendors)]
    node = NodeProcess("-p", "real_time_factor:=0.0", "-p", "publish_rate:=10.0", "-p", f"Omega:={omega}",
                       "-p", f"V:={v}", "-p", f"history_depth:={DEPTH}",
                       "-p", f"wait_for_impact_subscriptions:={len(vendors)}",
                       "-p", "wait_for_impact_subscriptions_timeout:=60", domain=domain)
    joiners = []  # late readers' own processes (None: joined in the process at that index)
    try:
        opened = node.wait_for_line("starting the simulation", 65)
        assert opened and "impact subscriptions matched after" in opened, opened or node.stop()
        started = time.monotonic()
        time.sleep(1.0)
        # The stream's rate when the late readers join: what the first process's reader has
        # taken per wall second since the start (a lower bound: rclpy takes them later).
        join_rate = readers[0].counts().get("early", 0) / (time.monotonic() - started)
        first_ones = readers[:-1] if stall else readers
        joiners += [r.join(domain, tmp_path, k, same_process(k)) for k, r in enumerate(first_ones)]
        seconds = SECONDS
        if stall:
            # The last process (Fast DDS) stalls; the node waits for it (its send window fills).
            # Its late reader joins as it resumes, while its early one catches up on repairs.
            readers[-1].signal(signal.SIGSTOP)
            time.sleep(STALL_SECONDS)
            readers[-1].signal(signal.SIGCONT)
            joiners.append(readers[-1].join(domain, tmp_path, len(readers) - 1, JOIN == "same"))
            seconds = max(SECONDS, 1.0 + STALL_SECONDS + 1.5)
        time.sleep(max(0.0, seconds - (time.monotonic() - started)))
        # A reader in a new process is matched by the node after its participant is discovered
        # (1 to 2 s at 30,000 impacts a second): stream on until every late reader streams too.
        until = time.monotonic() + 30
        while time.monotonic() < until and not all(
                (r or readers[k]).counts().get("late") for k, r in enumerate(joiners)):
            time.sleep(0.2)
        node.interrupt()
        stopped = time.monotonic()
        node.proc.wait(timeout=30)
    finally:
        log = node.stop()
        got = [r.collect() for r in readers]
        for k, r in enumerate(joiners):
            if r is not None:
                got[k].update(r.collect())
    s = summary(log)
    n = s["published"]
    report = {"vendors": vendors, "stall": stall, "published": n, "located": s["located"],
              "impacts_per_wall_second": round(n / (stopped - started)),
              "at_join_per_wall_second": round(join_rate),
              "received": [{k: len(x["rows"]) for k, x in g.items()} for g in got],
              "late_first": [g["late"]["rows"][0][0] if g.get("late", {}).get("rows") else None for g in got],
              "late_joined_after": [g.get("late", {}).get("joined_after") for g in got]}
    print("MATRIX " + json.dumps(report))
    print("\n".join(line for line in log.splitlines() if "impacts: " in line or "starting the simulation" in line))
    if not stall:
        # The late readers joined a fast stream (their test is about that): as the first
        # process took it before they joined, or over the whole run (lower when a late reader
        # catches up on its history by repair, which holds the node).
        assert max(report["at_join_per_wall_second"], report["impacts_per_wall_second"]) >= MIN_RATE, report
    assert s["failed"] == 0 and n == s["located"], report
    assert f"impacts: all {n} published acknowledged by the {2 * len(vendors)} matched subscriptions" in log, log[-3000:]
    impacts = [{k: impacts_of(x["rows"]) for k, x in g.items()} for g in got]
    last_t = max(m.t for g in impacts for ms in g.values() for m in ms)
    ref = reference(omega, v, last_t + 1.0)
    assert len(ref) >= n, (len(ref), n)
    for k, g in enumerate(impacts):
        name = f"{vendors[k]} process {k}"
        check_stream(g["early"], ref, 0, n - 1, f"{name} early")
        late = g["late"]
        assert late, report
        first = late[0].index
        # The last history_depth impacts published when it matched (more when a reader of the
        # same process had not acknowledged older ones), then every one.
        assert first == 0 or first + DEPTH <= n, report
        check_stream(late, ref, first, n - 1, f"{name} late")
    return report


@pytest.mark.parametrize("repeat", range(REPEAT))
@pytest.mark.parametrize("case", list(CASES))
def test_every_impact_every_vendor(case, repeat, tmp_path):
    domain = 70 + list(CASES).index(case)
    report = run(domain, CASES[case], tmp_path, stall=case.endswith("stalled"))
    report_file(f"matrix_{case}_{repeat}.json", report)
