"""The stateful Simulator: events, callbacks, checkpoints and pickling."""

import pickle

import numpy as np
import pytest

import bistable_impact as bi


def test_events_match_simulate():
    s = bi.Simulator(1.75, 0.07)
    events = s.advance_to(200.0)
    t = [e["t"] for e in events if e["kind"] == "impact"]
    r = bi.simulate(1.75, 0.07, t_end=200.0)
    assert np.array_equal(np.array(t), r.impacts["t"])
    assert s.time == 200.0
    assert s.state()["t"] == 200.0
    assert s.stats()["impacts"] == len(t)


def test_callback_sees_every_event_and_can_stop():
    s = bi.Simulator(0.2, 0.05)
    seen = []
    assert s.advance_to(60.0, seen.append) is True
    kinds = {e["kind"] for e in seen}
    assert {"impact", "stick_start", "stick_end"} <= kinds
    s2 = bi.Simulator(0.2, 0.05)
    n = []

    def stop_at_third(e):
        n.append(e)
        return None if len(n) < 3 else False

    assert s2.advance_to(60.0, stop_at_third) is False
    assert len(n) == 3 and s2.time == n[-1]["t"]

    def boom(e):
        raise KeyError("from the callback")

    with pytest.raises(KeyError, match="from the callback"):
        bi.Simulator(1.75, 0.07).advance_to(10.0, boom)


def test_checkpoint_round_trip_is_bit_identical():
    a = bi.Simulator(2.45, 0.07)  # chaotic: any difference would grow
    a.advance_to(123.456)
    data = a.checkpoint()
    assert isinstance(data, bytes) and data[:8] == b"BICHKPT\0"
    b = bi.Simulator.from_checkpoint(data)
    assert b.checkpoint() == data
    assert b.state() == a.state()
    ea, eb = a.advance_to(800.0), b.advance_to(800.0)
    assert len(ea) > 50
    assert ea == eb  # exact equality of every float
    assert a.checkpoint() == b.checkpoint()
    c = pickle.loads(pickle.dumps(a))
    assert c.checkpoint() == a.checkpoint()
    assert c.advance_to(900.0) == a.advance_to(900.0)


def test_corrupt_checkpoints_raise_value_error():
    data = bi.Simulator(1.75, 0.07).checkpoint()
    for bad in (b"", data[:-1], data + b"\0", b"X" + data[1:]):
        with pytest.raises(ValueError):
            bi.Simulator.from_checkpoint(bad)
    flipped = bytearray(data)
    flipped[40] ^= 4
    with pytest.raises(ValueError, match="checksum"):
        bi.Simulator.from_checkpoint(bytes(flipped))
    with pytest.raises(TypeError):
        bi.Simulator.from_checkpoint("not bytes")


def test_set_sinusoid_continues_the_plate():
    s = bi.Simulator(1.75, 0.07)
    s.advance_to(50.0)
    z = s.state()["z"]
    s.set_sinusoid(2.0, 0.05)
    assert s.state()["z"] == pytest.approx(z, abs=1e-12)
    s.advance_to(100.0)
    with pytest.raises(ValueError, match="'omega'"):
        s.set_sinusoid(-1.0, 0.05)
    with pytest.raises(ValueError, match="'t'"):
        s.advance_to(float("nan"))
    with pytest.raises(RuntimeError, match="cannot go back in time"):
        s.advance_to(10.0)
