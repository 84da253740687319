"""Shaker set-points through ROS: a sinusoid command ramps the plate to the new set-point (two
periods of the new frequency) with position and velocity continuous, also after external
motion, and the plate ends on (V/Omega) sin(.) about the initial centre however many commands
came before; command fields the mode does not use must be 0."""
import math

from bistable_impact_msgs.msg import MassState, ShakerCommand
from common import NodeProcess, Spinner, summary
from rclpy.qos import QoSProfile, ReliabilityPolicy

RATE = 200.0
DEEP = QoSProfile(depth=10000, reliability=ReliabilityPolicy.RELIABLE)
# (stamp s, omega rad/s, velocity m/s): amplitude and frequency changes, several while the
# previous ramp still runs; then external motion to a plate at rest off centre, then a sinusoid.
SINUSOIDS = [(5.0, 2.5, 0.3), (8.0, 2.5, 0.05), (11.0, 1.75, 0.3), (12.5, 1.75, 0.05), (16.0, 3.0, 0.3),
             (19.0, 2.0, 0.05), (21.0, 2.5, 0.25)]
EXTERNAL = (26.0, 0.1, 0.0)
LAST = (2.0, 0.3)
END = 45.0


def stamped(mode, stamp, **fields):
    c = ShakerCommand(mode=mode, **fields)
    c.header.stamp.sec, c.header.stamp.nanosec = int(stamp), round((stamp % 1) * 1e9)
    return c


def test_setpoints_keep_the_plate_smooth_and_centred():
    domain = 57
    peer = Spinner(domain, "setpoint_peer")
    states = []
    peer.node.create_subscription(MassState, "/bistable/mass_state", states.append, DEEP)
    pub = peer.node.create_publisher(ShakerCommand, "/bistable/shaker_command", DEEP)
    node = NodeProcess("-p", "real_time_factor:=5.0", "-p", f"publish_rate:={RATE}", domain=domain)
    try:
        assert peer.spin_until(lambda: pub.get_subscription_count() > 0 and states, 10)
        assert states[-1].t < 4.0, "too late to schedule the commands"
        # Refused: fields the mode does not use are not 0.
        pub.publish(stamped(ShakerCommand.MODE_SINUSOID, 0.0, omega=2.0, velocity=0.1, z=0.5))
        pub.publish(stamped(ShakerCommand.MODE_EXTERNAL, 0.0, omega=2.0, z=0.1))
        for stamp, omega, velocity in SINUSOIDS:
            pub.publish(stamped(ShakerCommand.MODE_SINUSOID, stamp, omega=omega, velocity=velocity))
        stamp, z, zdot = EXTERNAL
        pub.publish(stamped(ShakerCommand.MODE_EXTERNAL, stamp, z=z, zdot=zdot))
        pub.publish(stamped(ShakerCommand.MODE_SINUSOID, 0.0, omega=LAST[0], velocity=LAST[1]))
        assert peer.spin_until(lambda: states[-1].t >= END, 30), states[-1].t
    finally:
        log = node.stop()
        peer.close()
    s = summary(log)
    assert (s["accepted"], s["refused"], s["dropped_when_due"]) == (len(SINUSOIDS) + 2, 2, 0), s
    assert "z = 0.5 is not used by MODE_SINUSOID and must be 0" in log
    assert "omega = 2 is not used by MODE_EXTERNAL and must be 0" in log
    ts = [m.t for m in states]
    assert all(abs((b - a) - 1 / RATE) < 1e-9 for a, b in zip(ts, ts[1:])), "a state is missing"
    # Position and velocity continuous: from one state to the next (5 ms) the plate velocity
    # changes by at most its largest acceleration (|z''| < 3 m/s^2 here) times 5 ms; a jump of
    # the velocity amplitude (0.05 to 0.3 m/s, as before the ramps) would be far above that.
    dzdot = max(abs(b.zdot - a.zdot) for a, b in zip(states, states[1:]))
    dz = max(abs(b.z - a.z) for a, b in zip(states, states[1:]))
    assert dzdot < 3.0 / RATE and dz < 0.35 / RATE, (dzdot, dz)
    # The external sample is reached, then the last ramp (2 periods of 2 rad/s) starts there.
    at_sample = [m for m in states if abs(m.t - EXTERNAL[0]) < 1e-9][0]
    assert abs(at_sample.z - EXTERNAL[1]) < 1e-12 and abs(at_sample.zdot - EXTERNAL[2]) < 1e-12
    assert at_sample.shaker_omega == LAST[0] or math.isnan(at_sample.shaker_omega)
    # Steady on (V/Omega) sin(.) about 0: z^2 + (zdot/Omega)^2 = (V/Omega)^2, mean 0.
    ramp_end = EXTERNAL[0] + 2 * 2 * math.pi / LAST[0]
    steady = [m for m in states if m.t > ramp_end + 1e-6]
    assert len(steady) > 1000
    amplitude = LAST[1] / LAST[0]
    err = max(abs(math.hypot(m.z, m.zdot / LAST[0]) - amplitude) for m in steady)
    assert err < 1e-12, err
    assert all(m.shaker_omega == LAST[0] and m.shaker_velocity == LAST[1] for m in steady)
    period = 2 * math.pi / LAST[0]
    periods = math.floor((steady[-1].t - steady[0].t) / period)
    whole = [m.z for m in steady[:round(periods * period * RATE)]]
    mean = sum(whole) / len(whole)
    print(f"SETPOINTS centre error {err:.3e} m, sampled mean {mean:.3e} m, largest step of zdot {dzdot:.4f} m/s")
    assert abs(mean) < 0.01 * amplitude
