#!/usr/bin/env python3
"""Co-simulation of the bistable_impact FMU coupled to a shaker armature (fmpy + SciPy).

The FMU (external shaker mode, ``shaker_mode = 2``) is the mass on the bistable spring; the
plate it impacts is the armature of an electrodynamic shaker, modelled as a driven
mass-spring-damper (SI units: kg, N·s/m, N/m, m, s)::

    M y'' + C y' + K y = F(t)        (+ the impulses of the impacts when feedback is on)

The drive ``F`` is chosen so that the armature alone moves exactly on the sinusoid of the
FMU's internal shaker, ``y_p = (V/Omega) sin(Omega t)`` with ``y(0) = 0``, ``y'(0) = V``::

    F = M y_p'' + C y_p' + K y_p = (V/Omega) [(K - M Omega^2) sin(Omega t) + C Omega cos(Omega t)]

Without feedback the coupled run therefore reproduces the FMU's internal-sinusoid run up to the
plate reconstruction error (quintic Hermite from the sampled inputs, O(h^6) in position).

Coupling scheme (explicit, Jacobi-like, one-step lag), at each communication point ``t_k``:

1. set ``z_in = y(t_k)``, ``zdot_in = y'(t_k)`` (no input derivatives: the FMU rebuilds the plate
   over the step from the last three samples);
2. ``fmi2DoStep(t_k, h)`` on the FMU, and the armature ODE from ``t_k`` to ``t_k + h`` with
   ``solve_ivp`` (DOP853, tight tolerances);
3. with feedback on, read ``plate_impulse`` ``J_k`` (N·s, the momentum the mass gave the plate
   through the impacts of that step, negative = pushed down) and apply it as a velocity jump
   ``y' += J_k / M`` at ``t_k + h``.

The impulse of an impact at ``t_i`` inside a step is thus applied at the end of the step, up to
``h`` late: the armature position is off by up to ``|J| h / M`` per impact, and the FMU, which
keeps its plate continuous in position and velocity, sees the jump through the next samples only
(it blends the plate towards them over the following step). The total momentum is nevertheless
exact at the communication points: what the mass loses in an impact is given to the armature,
only later. The impulse of the impact at ``t = 0`` (mass at rest on the plate moving up,
processed in ``fmi2ExitInitializationMode``) is applied before the first step.

Run ``python fmu/examples/coupled_shaker.py --help`` for the command line; ``run`` and
``momentum_balance`` are the function API (used by ``tests/fmu/test_coupled.py``).
"""
import argparse
import contextlib
import math
from ctypes import CFUNCTYPE, c_char_p, c_int, c_void_p, cast
import pathlib
import shutil
import tempfile
import time

import numpy as np
from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)
from scipy.integrate import solve_ivp

ROOT = pathlib.Path(__file__).resolve().parents[2]
DEFAULT_FMU = ROOT / "target" / "fmu" / "bistable_impact.fmu"

#: FMU outputs recorded at every communication point.
OUTPUTS = ("x", "v", "z", "zdot", "plate_impulse", "impact_count", "in_contact",
           "last_impact_v_before", "last_impact_v_after")

#: Tolerances of the armature integration (relative; absolute ones scale with the motion).
RTOL = 1e-12


class Armature:
    """Driven mass-spring-damper ``M y'' + C y' + K y = F(t)`` whose drive makes the sinusoid
    ``y_p = (V/Omega) sin(Omega t)`` a solution. State ``(y, y', I)``, ``I`` the momentum the
    external forces ``F - C y' - K y`` gave the armature since the start (N·s)."""

    def __init__(self, M, C, K, Omega, V):
        if not (M > 0 and C >= 0 and K >= 0 and Omega > 0):
            raise ValueError("need M > 0, C >= 0, K >= 0, Omega > 0")
        self.M, self.C, self.K, self.Omega, self.V = M, C, K, Omega, V
        self.a = V / Omega
        self.state = np.array([0.0, V, 0.0])
        scale = max(abs(self.a), 1e-300)
        rate = max(Omega, math.sqrt(K / M), C / M)
        self.atol = 1e-15 * np.array([scale, scale * rate, M * scale * rate])

    def force(self, t):
        """The drive F(t) (N)."""
        w = self.Omega
        return self.a * ((self.K - self.M * w * w) * math.sin(w * t) + self.C * w * math.cos(w * t))

    def _rhs(self, t, s):
        f = self.force(t) - self.C * s[1] - self.K * s[0]
        return (s[1], f / self.M, f)

    def advance(self, t0, t1):
        """Integrates the state from t0 to t1 (no impulse inside)."""
        r = solve_ivp(self._rhs, (t0, t1), self.state, method="DOP853", rtol=RTOL,
                      atol=self.atol)
        if not r.success:
            raise RuntimeError(f"armature integration failed on [{t0}, {t1}]: {r.message}")
        self.state = r.y[:, -1].copy()

    def kick(self, impulse):
        """Applies an impulse (N·s) as a velocity jump."""
        self.state[1] += impulse / self.M


#: The logger as this FMU calls it: the format is always "%s" and the message follows it.
_LOGGER_TYPE = CFUNCTYPE(None, c_void_p, c_char_p, c_int, c_char_p, c_char_p, c_char_p)


class _Fmu:
    """One FMU instance over fmpy's FMU2Slave, with an optional message log."""

    def __init__(self, fmu_path, unzipped, log_events):
        md = read_model_description(fmu_path)
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.types = {v.name: v.type for v in md.modelVariables}
        self.starts = {v.name: v.start for v in md.modelVariables}
        self.messages = []  # (step index, message); step 0 = initialization
        self.step_index = 0
        callbacks = None
        if log_events:
            callbacks = fmi2CallbackFunctions()
            # This FMU always logs `logger(env, name, status, category, "%s", message)`, so the
            # message is the sixth argument. (fmpy's `addLoggerProxy`, which formats any variadic
            # message, keeps one process-wide pointer to the last logger it wrapped: once this
            # instance's callback is garbage-collected, every later fmpy instance that logs
            # through the proxy would call freed memory.)
            self._logger = _LOGGER_TYPE(self._log)
            callbacks.logger = cast(self._logger, fmi2CallbackLoggerTYPE)
            # fmpy's default allocator pair (FMI 2.0 requires them).
            callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
            callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self._callbacks = callbacks  # keeps the ctypes objects alive
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped,
                             modelIdentifier=md.coSimulation.modelIdentifier,
                             instanceName="coupled")
        self.fmu.instantiate(callbacks=callbacks, loggingOn=log_events)
        if log_events:
            self.fmu.setDebugLogging(True, ["logEvents"])

    def _log(self, env, name, status, category, fmt, message):
        self.messages.append((self.step_index, message.decode(errors="replace")))

    def set(self, **values):
        for name, value in values.items():
            if self.types[name] == "Real":
                self.fmu.setReal([self.vr[name]], [float(value)])
            else:
                self.fmu.setInteger([self.vr[name]], [int(value)])

    def get(self, names):
        out = []
        for n in names:
            if self.types[n] == "Real":
                out.append(self.fmu.getReal([self.vr[n]])[0])
            elif self.types[n] == "Boolean":
                out.append(float(self.fmu.getBoolean([self.vr[n]])[0]))
            else:
                out.append(float(self.fmu.getInteger([self.vr[n]])[0]))
        return out

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


@contextlib.contextmanager
def _instance(fmu_path, unzipped, log_events):
    """An instance of the FMU at ``fmu_path``, from ``unzipped`` or, when it is None, from a
    temporary extraction removed afterwards; terminated and freed on exit."""
    tmp = None
    if unzipped is None:
        tmp = tempfile.mkdtemp(prefix="coupled_shaker_")
        extract(str(fmu_path), tmp)
        unzipped = tmp
    fmu = _Fmu(str(fmu_path), unzipped, log_events)
    try:
        yield fmu
    finally:
        fmu.close()
        if tmp:
            shutil.rmtree(tmp, ignore_errors=True)


def _fmu_drive(fmu, Omega, V, params):
    """The FMU's nondimensional ``Omega`` (ratio to omega0) and ``V`` (unit omega0 delta_x) of
    the SI drive ``Omega`` (rad/s), ``V`` (m/s)."""
    params = params or {}
    w0 = params.get("omega0", float(fmu.starts["omega0"]))
    dx = params.get("delta_x", float(fmu.starts["delta_x"]))
    return Omega / w0, V / (w0 * dx)


def run(M, C, K, h, t_end, feedback=True, fmu_path=DEFAULT_FMU, Omega=1.75, V=0.07,
        params=None, impulse_gain=1.0, log_events=False, unzipped=None):
    """Co-simulates the FMU (external mode) with the armature ``(M, C, K)`` from 0 to ``t_end``
    with communication step ``h`` (s); the armature alone would follow
    ``y = (V/Omega) sin(Omega t)`` (``Omega`` in rad/s, ``V`` in m/s).

    ``params``: further FMU start values (e.g. ``{"zeta": 0.0}``). ``impulse_gain`` multiplies
    the fed-back impulse (1: physical; -1 feeds it with the wrong sign, for checking tests).
    ``log_events`` collects the FMU's ``logEvents`` messages. ``unzipped``: a directory the FMU
    is already extracted to (else a temporary one is used).

    Returns a dict of arrays over the ``n + 1`` communication points ``t`` (index 0 = after
    initialization): the FMU outputs of ``OUTPUTS`` (``plate_impulse[k]`` is that of the step
    ending at ``t[k]``, ``[0]`` the initialization's), the armature ``y``, ``ydot`` (after the
    kick at ``t[k]``) and ``ydot_before`` (before it), ``I_armature`` (momentum given to the
    armature by ``F - C y' - K y`` since 0), plus ``M``, ``C``, ``K``, ``mass``, ``omega0``,
    ``delta_x``, ``zeta``, ``v0`` and the ``messages`` ``(step index, text)``.
    """
    n = max(1, round(t_end / h))
    t = np.linspace(0.0, n * h, n + 1)
    arm = Armature(M, C, K, Omega, V)
    with _instance(fmu_path, unzipped, log_events) as fmu:
        # The FMU's Omega only sets the reference of last_impact_phase in external mode.
        start = {"shaker_mode": 2, "Omega": _fmu_drive(fmu, Omega, V, params)[0], "z_in": 0.0,
                 "zdot_in": V}
        start.update(params or {})
        fmu.fmu.setupExperiment(startTime=0.0)
        fmu.set(**start)
        fmu.fmu.enterInitializationMode()
        fmu.fmu.exitInitializationMode()
        consts = dict(zip(("mass", "omega0", "delta_x", "zeta", "v0"),
                          fmu.get(("mass", "omega0", "delta_x", "zeta", "v0"))))
        out = {name: np.empty(n + 1) for name in OUTPUTS}
        y, ydot, ydot_before, i_arm = (np.empty(n + 1) for _ in range(4))

        def record(k):
            for name, value in zip(OUTPUTS, fmu.get(OUTPUTS)):
                out[name][k] = value
            ydot_before[k] = arm.state[1]
            if feedback:
                arm.kick(impulse_gain * out["plate_impulse"][k])
            y[k], ydot[k], i_arm[k] = arm.state

        record(0)
        for k in range(n):
            fmu.step_index = k + 1
            fmu.set(z_in=arm.state[0], zdot_in=arm.state[1])
            fmu.fmu.doStep(currentCommunicationPoint=t[k], communicationStepSize=t[k + 1] - t[k])
            arm.advance(t[k], t[k + 1])
            record(k + 1)
    result = dict(out, t=t, y=y, ydot=ydot, ydot_before=ydot_before, I_armature=i_arm,
                  M=M, C=C, K=K, Omega=Omega, V=V, h=h, feedback=feedback,
                  messages=fmu.messages, **consts)
    return result


def force_term(x):
    """``U'(x) = x(1 - x)(1 - 2x)`` (crates/bistable-core/src/potential.rs)."""
    return x * (1.0 - x) * (1.0 - 2.0 * x)


def momentum_balance(r):
    """Momentum balance of a run with feedback, all in N·s.

    Total momentum ``P = M y' + m v``; the impacts only exchange momentum between mass and
    armature, so ``P(end) - P(0-)`` must equal the impulse of the external forces:
    ``I_armature = ∫ (F - C y' - K y) dt`` (integrated with the armature ODE) and, on the mass,
    the spring ``I_spring = ∫ -m omega0^2 delta_x U'(x/delta_x) dt`` (trapezoid over the
    communication points: x is continuous, its kinks at impacts make the error O(h^2)) plus the
    damping ``I_damping = ∫ -2 m zeta omega0 v dt = -2 m zeta omega0 (x(end) - x(0))`` (exact,
    x is continuous across impacts). ``P0`` is taken before the impact at t = 0 (``v0``),
    ``P1`` after the last kick. Returns those terms and
    ``error = P1 - P0 - I_armature - I_spring - I_damping``."""
    m, w0, dx, zeta = r["mass"], r["omega0"], r["delta_x"], r["zeta"]
    x, v, t = r["x"], r["v"], r["t"]
    f_spring = -m * w0 * w0 * dx * force_term(x / dx)
    i_spring = float(np.sum(0.5 * (f_spring[1:] + f_spring[:-1]) * np.diff(t)))
    i_damping = -2.0 * m * zeta * w0 * (x[-1] - x[0]) + 0.0  # + 0.0: no -0.0 when zeta = 0
    p0 = r["M"] * r["V"] + m * r["v0"]
    p1 = r["M"] * r["ydot"][-1] + m * v[-1]
    i_arm = float(r["I_armature"][-1])
    return dict(P0=p0, P1=p1, I_armature=i_arm, I_spring=i_spring, I_damping=i_damping,
                error=float(p1 - p0 - i_arm - i_spring - i_damping))


def internal_reference(t_end, h, fmu_path=DEFAULT_FMU, Omega=1.75, V=0.07, params=None,
                       unzipped=None):
    """The FMU's own sinusoid (internal mode, plate ``(V/Omega) sin(Omega t)``, SI ``Omega``,
    ``V`` as in ``run``) at the communication points: (t, x)."""
    n = max(1, round(t_end / h))
    t = np.linspace(0.0, n * h, n + 1)
    with _instance(fmu_path, unzipped, False) as fmu:
        fmu.fmu.setupExperiment(startTime=0.0)
        w, v = _fmu_drive(fmu, Omega, V, params)
        fmu.set(Omega=w, V=v, **(params or {}))
        fmu.fmu.enterInitializationMode()
        fmu.fmu.exitInitializationMode()
        x = np.empty(n + 1)
        x[0] = fmu.get(("x",))[0]
        for k in range(n):
            fmu.fmu.doStep(currentCommunicationPoint=t[k], communicationStepSize=t[k + 1] - t[k])
            x[k + 1] = fmu.get(("x",))[0]
    return t, x


def plot(r, path):
    """x, z over time and the armature momentum M y', written to a PNG."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a1, a2) = plt.subplots(2, 1, sharex=True, figsize=(9, 6))
    a1.plot(r["t"], r["x"], label="mass x")
    a1.plot(r["t"], r["z"], label="plate z (FMU)")
    a1.plot(r["t"], r["y"], "--", lw=0.8, label="armature y")
    a1.set_ylabel("position (m)")
    a1.legend(loc="upper right")
    a2.plot(r["t"], r["M"] * r["ydot"], label="armature momentum M y'")
    a2.plot(r["t"], r["M"] * r["V"] * np.cos(r["Omega"] * r["t"]), ":", lw=0.8,
            label="prescribed M V cos(Omega t)")
    a2.set_ylabel("momentum (N s)")
    a2.set_xlabel("time (s)")
    a2.legend(loc="upper right")
    fb = "feedback" if r["feedback"] else "no feedback"
    a1.set_title(f"M={r['M']:g} kg, C={r['C']:g} N s/m, K={r['K']:g} N/m, h={r['h']:g} s, {fb}")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    p = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0] + " The armature M y'' + C y' + K y = F(t) is "
        "driven so that, alone, it follows y = (V/Omega) sin(Omega t); its y, y' feed the FMU's "
        "z_in, zdot_in at every communication point, and with --feedback the FMU's "
        "plate_impulse of each step is applied to it as a velocity jump J/M at the end of the "
        "step (explicit coupling, one-step lag). SI units throughout; the FMU's defaults "
        "(omega0 = 1 rad/s, delta_x = 1 m, mass = 1 kg) make them the paper's nondimensional "
        "ones.",
        epilog="examples: light armature with feedback and a plot: --M 2 --plot coupled.png; "
        "heavy armature against the internal sinusoid: --M 1e9 --h 0.05 --t-end 100 --compare. "
        "Printed: impacts, impulses, final state, the momentum balance (feedback on) and the "
        "wall time.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--fmu", default=str(DEFAULT_FMU), help="path of bistable_impact.fmu")
    p.add_argument("--M", type=float, default=2.0, help="armature mass (kg)")
    p.add_argument("--fn", type=float, default=10.0,
                   help="armature natural frequency sqrt(K/M) (rad/s); sets K unless --K given")
    p.add_argument("--zeta-a", type=float, default=0.1,
                   help="armature damping ratio C/(2 sqrt(K M)); sets C unless --C given")
    p.add_argument("--K", type=float, help="armature stiffness (N/m)")
    p.add_argument("--C", type=float, help="armature damping (N s/m)")
    p.add_argument("--Omega", type=float, default=1.75,
                   help="drive frequency (rad/s; the FMU's Omega is this over omega0)")
    p.add_argument("--V", type=float, default=0.07,
                   help="velocity amplitude of the prescribed armature motion (m/s)")
    p.add_argument("--h", type=float, default=0.01, help="communication step (s)")
    p.add_argument("--t-end", type=float, default=60.0, help="end time (s)")
    p.add_argument("--feedback", action=argparse.BooleanOptionalAction, default=True,
                   help="apply each step's plate_impulse to the armature (two-way coupling); "
                   "--no-feedback: one-way, the armature follows the prescribed sinusoid")
    p.add_argument("--zeta", type=float, help="damping ratio of the mass (FMU default 0.02)")
    p.add_argument("--e", type=float, help="coefficient of restitution (FMU default 0.85)")
    p.add_argument("--compare", action="store_true",
                   help="also run the FMU's internal sinusoid and print max |x - x_internal|")
    p.add_argument("--plot", metavar="FILE", help="write a PNG: x, z, y over time and M y'")
    a = p.parse_args(argv)
    K = a.K if a.K is not None else a.M * a.fn ** 2
    C = a.C if a.C is not None else 2.0 * a.zeta_a * math.sqrt(K * a.M)
    params = {k: v for k, v in (("zeta", a.zeta), ("e", a.e)) if v is not None}
    t0 = time.perf_counter()
    r = run(a.M, C, K, a.h, a.t_end, feedback=a.feedback, fmu_path=a.fmu, Omega=a.Omega,
            V=a.V, params=params)
    wall = time.perf_counter() - t0
    J = r["plate_impulse"]
    print(f"armature M={a.M:g} kg C={C:g} N s/m K={K:g} N/m (natural frequency "
          f"{math.sqrt(K / a.M):g} rad/s), Omega={a.Omega:g} rad/s V={a.V:g} m/s, "
          f"h={a.h:g} s, t_end={r['t'][-1]:g} s, feedback {'on' if a.feedback else 'off'}")
    print(f"impacts: {int(r['impact_count'][-1])}, steps in contact: "
          f"{int(np.sum(r['in_contact']))}, total impulse on the plate {np.sum(J):.6g} N s "
          f"(initialization {J[0]:.6g} N s)")
    print(f"final x={r['x'][-1]:.9g} m v={r['v'][-1]:.9g} m/s, armature y={r['y'][-1]:.9g} m "
          f"y'={r['ydot'][-1]:.9g} m/s, max |y - y_p| = "
          f"{np.max(np.abs(r['y'] - a.V / a.Omega * np.sin(a.Omega * r['t']))):.3g} m")
    if a.feedback:
        b = momentum_balance(r)
        print(f"momentum: P(0-)={b['P0']:.12g} P(end)={b['P1']:.12g} external impulses: "
              f"armature {b['I_armature']:.12g} spring {b['I_spring']:.12g} damping "
              f"{b['I_damping']:.12g}; "
              f"balance error {b['error']:.3g} N s "
              f"({b['error'] / max(abs(b['P0']), abs(b['P1'])):.2g} of the momentum)")
    if a.compare:
        _, x_int = internal_reference(r["t"][-1], a.h, a.fmu, a.Omega, a.V, params)
        print(f"max |x - x_internal| = {np.max(np.abs(r['x'] - x_int)):.3g} m")
    print(f"wall time {wall:.2f} s")
    if a.plot:
        plot(r, a.plot)
        print(f"wrote {a.plot}")


if __name__ == "__main__":
    main()
