"""The GIL is released while Rust computes: two threads are inside `simulate` at once."""

import threading

import bistable_impact as bi


def test_two_threads_overlap_inside_rust():
    results = {}

    def run(name):
        # Chaotic case, long enough (a few tenths of a second) for the two computations to meet.
        results[name] = bi.simulate(2.45, 0.07, t_end=300000.0).summary

    threads = [threading.Thread(target=run, args=(n,)) for n in "ab"]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    a, b = results["a"], results["b"]
    # Both computations (timestamps taken inside Rust) were running at the same instant: with
    # the GIL held during the computation one would have to end before the other starts.
    overlap = min(a["finished_at"], b["finished_at"]) - max(a["started_at"], b["started_at"])
    shortest = min(a["finished_at"] - a["started_at"], b["finished_at"] - b["started_at"])
    print(f"overlap {overlap:.3f} s of the shorter run's {shortest:.3f} s")
    assert overlap > 0.25 * shortest
