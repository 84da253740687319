"""Hostile shaker commands for the fault tests: well-formed commands the node must refuse (one
list per kind, each refused whatever the node's state), malformed CDR samples (raw serialized
bytes published through rclpy, which Fast DDS sends as they are), and valid commands written in
unusual but legal encodings. Commands are built as CDR bytes directly (XCDR1, as rosidl)."""
import math
import struct

CDR_LE = b"\x00\x01\x00\x00"
CDR_BE = b"\x00\x00\x00\x00"
INT32_MIN, INT32_MAX, UINT32_MAX = -(2**31), 2**31 - 1, 2**32 - 1
NAN, INF = math.nan, math.inf
# Largest accepted nondimensional value (sim.rs MAX_NONDIMENSIONAL); the tests run with
# omega0 = 1 rad/s and delta_x = 1 m, so SI values equal nondimensional ones.
MAX_ND = 1e6
MIN_OMEGA = 1e-6  # the core's smallest Ω (OMEGA_RANGE)


def stamp_of(t):
    """(sec, nanosec) of `t` seconds, rounded to the nanosecond."""
    ns = round(t * 1e9)
    return ns // 1_000_000_000, ns % 1_000_000_000


def cdr(sec=0, nanosec=0, frame=b"", mode=0, omega=0.0, velocity=0.0, z=0.0, zdot=0.0, big_endian=False):
    """A ShakerCommand serialized as rosidl does (encapsulation header + XCDR1 body)."""
    o = ">" if big_endian else "<"
    body = struct.pack(o + "iII", sec, nanosec, len(frame) + 1) + frame + b"\x00" + struct.pack("B", mode)
    body += b"\x00" * (-len(body) % 8)
    body += struct.pack(o + "4d", omega, velocity, z, zdot)
    return (CDR_BE if big_endian else CDR_LE) + body


def sinusoid(omega, velocity, t=None, **kw):
    """MODE_SINUSOID at simulation time `t` (None: a zero stamp, "now")."""
    sec, ns = (0, 0) if t is None else stamp_of(t)
    return cdr(sec, ns, mode=0, omega=omega, velocity=velocity, **kw)


def invalid_commands(frontier, omega0=1.0, delta_x=1.0):
    """Well-formed commands the node refuses whatever its state, by kind, for a node with
    `omega0` [rad/s] and `delta_x` [m] (the limits are nondimensional). `frontier` [s] is a time
    not after the node's command frontier (current time or end of the queued commands):
    external samples stamped there are refused as not after it."""
    w, lv = omega0, omega0 * delta_x  # SI scales of frequency and velocity
    ok_w, ok_v = 1.75 * w, 0.07 * lv
    later = frontier + 0.5
    sec, ns = stamp_of(later)
    kinds = {
        "omega_nonfinite": [sinusoid(x, ok_v) for x in (NAN, INF, -INF)],
        "omega_not_positive": [sinusoid(x, ok_v) for x in (0.0, -0.0, -1e-300, -ok_w)],
        "omega_huge": [sinusoid(x, ok_v) for x in (MAX_ND * w * (1 + 1e-15), 10 * MAX_ND * w, 1e300,
                                                    1.7976931348623157e308)],
        "velocity_nonfinite": [sinusoid(ok_w, x) for x in (NAN, INF, -INF)],
        "velocity_negative": [sinusoid(ok_w, x) for x in (-5e-324, -1e-300, -ok_v, -1e300)],
        "velocity_huge": [sinusoid(ok_w, x) for x in (MAX_ND * lv * (1 + 1e-15), 10 * MAX_ND * lv, 1e300)],
        "omega_tiny": [sinusoid(x, ok_v) for x in (5e-324, 1e-300, MIN_OMEGA * w * (1 - 1e-15))],
        "amplitude_huge": [sinusoid(a, b) for a, b in ((MIN_OMEGA * w, 2 * lv), (1e-3 * w, 2e3 * lv))],
        "unused_field_nonfinite": [sinusoid(ok_w, ok_v, z=NAN), sinusoid(ok_w, ok_v, zdot=-INF),
                                   cdr(sec, ns, mode=1, z=0.0, zdot=0.0, omega=NAN)],
        "external_nonfinite": [cdr(sec, ns, mode=1, z=z, zdot=zd) for z, zd in ((NAN, 0.0), (0.0, INF), (-INF, NAN))],
        "external_huge": [cdr(sec, ns, mode=1, z=z, zdot=zd)
                          for z, zd in ((2 * MAX_ND * delta_x, 0.0), (0.0, -2 * MAX_ND * lv), (1e300, 1e300))],
        "external_not_after_frontier": [cdr(*stamp_of(frontier), mode=1, z=0.01), cdr(0, 1, mode=1, z=0.01),
                                        cdr(1, 0, mode=1, z=0.01)],
        "stamp_negative": [cdr(s, 0, mode=0, omega=ok_w, velocity=ok_v) for s in (-1, INT32_MIN)],
        "stamp_nanosec_overflow": [cdr(1, n, mode=0, omega=ok_w, velocity=ok_v) for n in (1_000_000_000, UINT32_MAX)],
        "mode_unknown": [cdr(mode=m, omega=ok_w, velocity=ok_v) for m in (2, 3, 128, 255)],
    }
    return kinds


def malformed_samples(rng):
    """Serialized samples that are not a ShakerCommand, by kind (each a function of `rng` that
    returns fresh bytes). The node's DDS layer fails to deserialize them."""
    valid = cdr(mode=0, omega=1.75, velocity=0.07)

    # Fast DDS pads a raw sample with zeros to a multiple of 4 bytes: a sample cut at 49 to 51
    # bytes arrives whole again. Shorter ones lack at least the last double.
    def truncated(r):
        return valid[: r.randrange(1, 49)]

    def garbage(r):
        # Any body shorter than the 48 bytes of the smallest ShakerCommand (after padding to
        # 4 bytes) ends too early.
        return CDR_LE + r.randbytes(r.randrange(0, 45))

    def garbage_long(r):
        # Random bytes, with a frame_id length larger than the sample.
        body = bytearray(r.randbytes(r.randrange(48, 300)))
        body[8:12] = struct.pack("<I", r.randrange(len(body), 2**32))
        return CDR_LE + bytes(body)

    def bad_encapsulation(r):
        ident = r.choice([0x0002, 0x0006, 0x0007, 0x0008, 0x0009, 0x000A, 0x000B, 0x1234, 0xFFFF])
        return struct.pack(">H", ident) + b"\x00\x00" + valid[4:]

    def bad_utf8(r):
        return cdr(frame=bytes([0xFF, 0xFE, r.randrange(0x80, 0xC0)]), mode=0, omega=1.75, velocity=0.07)

    return {
        "truncated": truncated,
        "garbage_short": garbage,
        "garbage_long_string": garbage_long,
        "bad_encapsulation": bad_encapsulation,
        "bad_utf8_frame_id": bad_utf8,
    }


def odd_valid(omega, velocity, t=None, kind="big_endian"):
    """A valid command in a legal but unusual encoding: big-endian CDR, trailing bytes after the
    last field (ignored, as for an appendable type), or a 100 kB frame_id (fragmented)."""
    sec, ns = (0, 0) if t is None else stamp_of(t)
    if kind == "big_endian":
        return cdr(sec, ns, mode=0, omega=omega, velocity=velocity, big_endian=True)
    if kind == "trailing_bytes":
        return cdr(sec, ns, mode=0, omega=omega, velocity=velocity) + bytes(range(256)) * 4
    if kind == "huge_frame_id":
        return cdr(sec, ns, frame=b"f" * 100_000, mode=0, omega=omega, velocity=velocity)
    raise ValueError(kind)


def shuffled_round_robin(kinds, rng):
    """An endless stream of (kind, payload) cycling through the kinds in random order."""
    names = list(kinds)
    while True:
        rng.shuffle(names)
        for name in names:
            yield name, kinds[name]
