//! The FMU through its C functions, called from Rust: results against the core, step-size
//! independence, SI scaling, external inputs, FMU states, threads, and refused calls.

use std::ffi::{c_char, c_void, CStr, CString};
use std::sync::Mutex;

use bistable_core::{Event, Params, Simulator, Sinusoid, SolverOptions};
use bistable_impact::exports::*;
use bistable_impact::fmi2::*;
use bistable_impact::md::{var, GUID, VARS};

/// Messages logged by one instance: `(status, category, message)`.
type Log = Mutex<Vec<(fmi2Status, String, String)>>;

/// A logger with the fixed arguments of the variadic FMI logger plus the one `%s` argument.
/// x86-64 and AArch64 Linux pass these in the same registers whether or not the callee is
/// variadic; the C host tests a real variadic logger.
unsafe extern "C" fn record(
    env: fmi2ComponentEnvironment,
    _name: fmi2String,
    status: fmi2Status,
    category: fmi2String,
    format: fmi2String,
    msg: *const c_char,
) {
    let log = &*(env as *const Log);
    assert_eq!(CStr::from_ptr(format).to_str().unwrap(), "%s");
    let text = |p| CStr::from_ptr(p).to_string_lossy().into_owned();
    log.lock()
        .unwrap()
        .push((status, text(category), text(msg)));
}

fn vr(index: usize) -> fmi2ValueReference {
    VARS[index].vr
}

/// One instance with its log.
struct Fmu {
    c: fmi2Component,
    log: Box<Log>,
    _callbacks: Box<fmi2CallbackFunctions>,
    t: f64,
}

impl Fmu {
    fn with_guid(
        guid: &str,
        kind: fmi2Type,
    ) -> (fmi2Component, Box<Log>, Box<fmi2CallbackFunctions>) {
        let log: Box<Log> = Box::default();
        // SAFETY: the logger's leading arguments match; see `record`.
        let logger: fmi2CallbackLogger = unsafe {
            std::mem::transmute::<*const c_void, fmi2CallbackLogger>(record as *const c_void)
        };
        let callbacks = Box::new(fmi2CallbackFunctions {
            logger,
            allocateMemory: None,
            freeMemory: None,
            stepFinished: None,
            componentEnvironment: &*log as *const Log as *mut c_void,
        });
        let name = CString::new("test").unwrap();
        let guid = CString::new(guid).unwrap();
        let c = unsafe {
            fmi2Instantiate(
                name.as_ptr(),
                kind,
                guid.as_ptr(),
                std::ptr::null(),
                &*callbacks,
                fmi2False,
                fmi2True,
            )
        };
        (c, log, callbacks)
    }

    fn new() -> Self {
        let (c, log, callbacks) = Self::with_guid(GUID, fmi2CoSimulation);
        assert!(!c.is_null());
        Fmu {
            c,
            log,
            _callbacks: callbacks,
            t: 0.0,
        }
    }

    /// Instantiated, parameters `(index, value)` set, initialized at `t = 0`.
    fn started(params: &[(usize, f64)]) -> Self {
        let f = Self::new();
        unsafe {
            assert_eq!(fmi2SetupExperiment(f.c, 0, 0.0, 0.0, 0, 0.0), fmi2OK);
            f.set(params);
            assert_eq!(fmi2EnterInitializationMode(f.c), fmi2OK);
            assert_eq!(
                fmi2ExitInitializationMode(f.c),
                fmi2OK,
                "{:?}",
                f.messages()
            );
        }
        f
    }

    fn set(&self, params: &[(usize, f64)]) -> fmi2Status {
        let (reals, ints): (Vec<_>, Vec<_>) = params
            .iter()
            .partition(|(i, _)| VARS[*i].kind == bistable_impact::md::Kind::Real);
        let rv: Vec<_> = reals.iter().map(|(i, _)| vr(*i)).collect();
        let rx: Vec<_> = reals.iter().map(|(_, v)| *v).collect();
        let iv: Vec<_> = ints.iter().map(|(i, _)| vr(*i)).collect();
        let ix: Vec<_> = ints.iter().map(|(_, v)| *v as i32).collect();
        unsafe {
            let a = fmi2SetReal(self.c, rv.as_ptr(), rv.len(), rx.as_ptr());
            let b = fmi2SetInteger(self.c, iv.as_ptr(), iv.len(), ix.as_ptr());
            a.max(b)
        }
    }

    fn real(&self, index: usize) -> f64 {
        let mut v = f64::NAN;
        assert_eq!(
            unsafe { fmi2GetReal(self.c, &vr(index), 1, &mut v) },
            fmi2OK
        );
        v
    }

    fn int(&self, index: usize) -> i32 {
        let mut v = -1;
        assert_eq!(
            unsafe { fmi2GetInteger(self.c, &vr(index), 1, &mut v) },
            fmi2OK
        );
        v
    }

    fn step(&mut self, h: f64) -> fmi2Status {
        let s = unsafe { fmi2DoStep(self.c, self.t, h, fmi2True) };
        if s == fmi2OK {
            self.t += h;
        }
        s
    }

    /// Steps of size `h` up to `t_end`, the last one shortened to land on it; returns the
    /// distinct last impacts seen `(count, time, v_after)`.
    fn run(&mut self, t_end: f64, h: f64) -> Vec<(i32, f64, f64)> {
        let mut seen = Vec::new();
        let n = ((t_end - self.t) / h).ceil() as usize;
        let t0 = self.t;
        for k in 1..=n {
            let next = if k == n { t_end } else { t0 + k as f64 * h };
            let s = unsafe { fmi2DoStep(self.c, self.t, next - self.t, fmi2True) };
            assert_eq!(s, fmi2OK, "{:?}", self.messages());
            self.t = next;
            let count = self.int(var::impact_count);
            if seen.last().is_none_or(|l: &(i32, f64, f64)| l.0 != count) {
                seen.push((
                    count,
                    self.real(var::last_impact_time),
                    self.real(var::last_impact_v_after),
                ));
            }
        }
        seen
    }

    fn messages(&self) -> Vec<String> {
        self.log
            .lock()
            .unwrap()
            .iter()
            .map(|m| m.2.clone())
            .collect()
    }

    /// The last logged message, which must be an error mentioning `needle`.
    fn assert_refused(&self, status: fmi2Status, needle: &str) {
        assert_eq!(status, fmi2Error, "expected a refusal mentioning {needle}");
        let log = self.log.lock().unwrap();
        let (st, category, msg) = log.last().expect("a logged reason");
        assert_eq!((*st, category.as_str()), (fmi2Error, "logStatusError"));
        assert!(msg.contains(needle), "{msg:?} should mention {needle:?}");
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        unsafe { fmi2FreeInstance(self.c) };
    }
}

fn core_sim(omega: f64, v: f64) -> Simulator {
    let plate = Sinusoid::new(omega, v).unwrap();
    Simulator::new(Params::paper(), plate.into(), SolverOptions::default()).unwrap()
}

#[test]
fn defaults_are_the_nondimensional_model_bit_for_bit() {
    let mut f = Fmu::started(&[]);
    // Impact 0 at t = 0 is processed at initialization.
    assert_eq!(f.int(var::impact_count), 1);
    assert!((f.real(var::v) - 1.85 * 0.07).abs() < 1e-16);
    let mut sim = core_sim(1.75, 0.07);
    for t in [0.5, 7.25, 20.0] {
        assert_eq!(f.step(t - f.t), fmi2OK);
        sim.advance_to(t, &mut |_: &Event| {}).unwrap();
        let st = sim.state();
        assert_eq!((f.real(var::x), f.real(var::v)), (st.x, st.v));
        assert_eq!((f.real(var::z), f.real(var::zdot)), (st.z, st.zdot));
        assert_eq!(f.real(var::kinetic_energy), st.kinetic_energy());
        assert_eq!(f.real(var::potential_energy), st.potential_energy());
        assert_eq!(f.int(var::impact_count) as u64, sim.stats().impacts);
        let last = sim.last_impact().unwrap();
        assert_eq!(f.real(var::last_impact_time), last.t);
        assert_eq!(f.real(var::last_impact_phase), last.phase.unwrap());
        assert_eq!(f.real(var::last_impact_v_before), last.v_before);
        assert_eq!(f.real(var::last_impact_v_after), last.v_after);
        assert_eq!(f.real(var::last_impact_delta_k), last.delta_k);
    }
    assert!(f.int(var::impact_count) > 3);
}

#[test]
fn the_trajectory_does_not_depend_on_the_step_size() {
    let mut runs = Vec::new();
    for h in [1e-3, 0.01, 0.1, 1.0, 10.0] {
        let mut f = Fmu::started(&[]);
        let mut states = Vec::new();
        for t_end in [50.0, 100.0, 150.0, 200.0] {
            let seen = f.run(t_end, h);
            states.push((f.real(var::x), f.real(var::v), *seen.last().unwrap()));
        }
        runs.push((h, states));
    }
    let (_, reference) = &runs[0];
    for (h, states) in &runs[1..] {
        for (a, b) in reference.iter().zip(states) {
            assert!(
                (a.0 - b.0).abs() <= 1e-12 && (a.1 - b.1).abs() <= 1e-12,
                "h={h}: {a:?} vs {b:?}"
            );
            assert_eq!(a.2 .0, b.2 .0, "h={h}: impact count");
            assert!((a.2 .1 - b.2 .1).abs() <= 1e-12 && (a.2 .2 - b.2 .2).abs() <= 1e-12);
        }
    }
}

#[test]
fn every_impact_is_seen_with_small_steps_and_logged() {
    let mut f = Fmu::started(&[]);
    let seen = f.run(100.0, 0.01);
    let mut sim = core_sim(1.75, 0.07);
    let impacts: Vec<_> = sim
        .events_until(100.0)
        .unwrap()
        .into_iter()
        .filter_map(|e| match e {
            Event::Impact(i) => Some(i),
            _ => None,
        })
        .collect();
    assert!(impacts.len() > 10);
    for (count, t, va) in seen {
        let i = &impacts[count as usize - 1];
        assert_eq!((t, va), (i.t, i.v_after));
    }
    let logged: Vec<_> = f
        .messages()
        .into_iter()
        .filter(|m| m.starts_with("impact "))
        .collect();
    assert_eq!(logged.len(), impacts.len());
    assert!(logged[3].starts_with(&format!("impact 3 at t={:.17e} s", impacts[3].t)));
}

#[test]
fn si_units_scale_the_nondimensional_solution() {
    let (w0, dx, m) = (2.0 * std::f64::consts::PI * 3.08, 0.02819, 0.5);
    let mut f = Fmu::started(&[(var::omega0, w0), (var::delta_x, dx), (var::mass, m)]);
    let tau = 30.0;
    assert_eq!(f.step(tau / w0), fmi2OK);
    let mut sim = core_sim(1.75, 0.07);
    sim.advance_to(w0 * (tau / w0), &mut |_: &Event| {})
        .unwrap();
    let st = sim.state();
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1e-300);
    assert!(close(f.real(var::x), st.x * dx));
    assert!(close(f.real(var::v), st.v * w0 * dx));
    assert!(close(f.real(var::zdot), st.zdot * w0 * dx));
    assert!(close(
        f.real(var::kinetic_energy),
        m * 0.5 * (st.v * w0 * dx).powi(2)
    ));
    assert!(close(
        f.real(var::last_impact_time),
        sim.last_impact().unwrap().t / w0
    ));
}

/// Feeds the plate of the internal sinusoid through the inputs, with derivatives up to order
/// `orders`, and returns `(x, v, impact count, last impact time)` at `t_end`.
fn external_run(h: f64, t_end: f64, orders: usize) -> (f64, f64, i32, f64) {
    let (omega, v) = (1.75, 0.07);
    let mut f = Fmu::started(&[(var::shaker_mode, 2.0), (var::z_in, 0.0), (var::zdot_in, v)]);
    while f.t < t_end - 1e-9 {
        let th = omega * f.t;
        // d^k z/dt^k = V Ω^(k-1) sin(θ + kπ/2) / ... for z = (V/Ω) sin θ
        let d = |k: i32| {
            v / omega * omega.powi(k) * (th + k as f64 * std::f64::consts::FRAC_PI_2).sin()
        };
        assert_eq!(f.set(&[(var::z_in, d(0)), (var::zdot_in, d(1))]), fmi2OK);
        let ks: Vec<i32> = (2..=orders as i32).collect();
        let vrs = vec![vr(var::z_in); ks.len()];
        let vals: Vec<f64> = ks.iter().map(|&k| d(k)).collect();
        let s = unsafe {
            fmi2SetRealInputDerivatives(f.c, vrs.as_ptr(), ks.len(), ks.as_ptr(), vals.as_ptr())
        };
        assert_eq!(s, fmi2OK);
        assert_eq!(f.step(h.min(t_end - f.t)), fmi2OK, "{:?}", f.messages());
    }
    (
        f.real(var::x),
        f.real(var::v),
        f.int(var::impact_count),
        f.real(var::last_impact_time),
    )
}

#[test]
fn external_inputs_with_derivatives_reproduce_the_internal_sinusoid() {
    let mut internal = Fmu::started(&[]);
    internal.run(60.0, 0.01);
    let want = (
        internal.real(var::x),
        internal.real(var::v),
        internal.int(var::impact_count),
        internal.real(var::last_impact_time),
    );
    let got = external_run(0.01, 60.0, 5);
    assert_eq!(got.2, want.2);
    for (a, b) in [(got.0, want.0), (got.1, want.1), (got.3, want.3)] {
        assert!((a - b).abs() < 1e-9, "{got:?} vs {want:?}");
    }
    // Without the higher derivatives the plate is only first-order accurate per step.
    let coarse = external_run(0.01, 60.0, 1);
    assert!((coarse.0 - want.0).abs() > 1e-7);
}

#[test]
fn fmu_states_roll_back_and_serialize_bit_for_bit() {
    let mut f = Fmu::started(&[(var::Omega, 0.3), (var::V, 0.05)]);
    f.run(12.0, 0.5);
    let mut state: fmi2FMUstate = std::ptr::null_mut();
    unsafe {
        assert_eq!(fmi2GetFMUstate(f.c, &mut state), fmi2OK);
        f.run(30.0, 0.5);
        let first = (f.real(var::x), f.real(var::v), f.int(var::impact_count));
        assert_eq!(fmi2SetFMUstate(f.c, state), fmi2OK);
        f.t = 12.0;
        f.run(30.0, 0.5);
        assert_eq!(
            first,
            (f.real(var::x), f.real(var::v), f.int(var::impact_count))
        );

        let mut size = 0;
        assert_eq!(fmi2SerializedFMUstateSize(f.c, state, &mut size), fmi2OK);
        let mut bytes = vec![0 as fmi2Byte; size];
        assert_eq!(
            fmi2SerializeFMUstate(f.c, state, bytes.as_mut_ptr(), size),
            fmi2OK
        );
        let mut g = Fmu::new();
        let mut restored: fmi2FMUstate = std::ptr::null_mut();
        assert_eq!(
            fmi2DeSerializeFMUstate(g.c, bytes.as_ptr(), size, &mut restored),
            fmi2OK
        );
        assert_eq!(fmi2SetFMUstate(g.c, restored), fmi2OK);
        g.t = 12.0;
        g.run(30.0, 0.5);
        assert_eq!(
            first,
            (g.real(var::x), g.real(var::v), g.int(var::impact_count))
        );

        // Truncated, corrupted and foreign bytes are refused.
        let mut other: fmi2FMUstate = std::ptr::null_mut();
        let s = fmi2DeSerializeFMUstate(g.c, bytes.as_ptr(), size - 1, &mut other);
        g.assert_refused(s, "bytes");
        for at in [0, 9, size / 2, size - 3] {
            let mut bad = bytes.clone();
            bad[at] ^= 0x10;
            let s = fmi2DeSerializeFMUstate(g.c, bad.as_ptr(), size, &mut other);
            assert_eq!(s, fmi2Error, "flipped byte {at}");
        }
        assert!(other.is_null());
        g.assert_refused(fmi2SetFMUstate(g.c, state), "not created by this instance");
        assert_eq!(fmi2FreeFMUstate(g.c, &mut restored), fmi2OK);
        assert!(restored.is_null());
        assert_eq!(fmi2FreeFMUstate(f.c, &mut state), fmi2OK);
    }
}

#[test]
fn instances_run_in_parallel_threads_with_identical_results() {
    let cases = [(1.75, 0.07), (2.5, 0.07), (0.85, 0.15), (0.3, 0.05)];
    let run = |(omega, v): (f64, f64)| {
        let mut f = Fmu::started(&[(var::Omega, omega), (var::V, v)]);
        f.run(80.0, 0.1);
        (f.real(var::x), f.real(var::v), f.int(var::impact_count))
    };
    let serial: Vec<_> = cases.iter().map(|&c| run(c)).collect();
    let parallel: Vec<_> = std::thread::scope(|s| {
        let handles: Vec<_> = cases.iter().map(|&c| s.spawn(move || run(c))).collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    assert_eq!(serial, parallel);
}

#[test]
fn tunable_shaker_change_keeps_the_plate_continuous() {
    let mut f = Fmu::started(&[]);
    f.run(10.0, 0.1);
    let z = f.real(var::z);
    assert_eq!(f.set(&[(var::Omega, 2.5), (var::V, 0.1)]), fmi2OK);
    assert_eq!(f.step(1e-9), fmi2OK);
    assert!((f.real(var::z) - z).abs() < 1e-9);
    assert!((f.real(var::zdot).abs() - 0.1 * f64::cos(0.0)).abs() <= 0.1);
}

#[test]
fn illegal_calls_and_bad_values_are_refused_with_a_reason() {
    let (c, log, _cb) = Fmu::with_guid("{00000000-0000-0000-0000-000000000000}", fmi2CoSimulation);
    assert!(c.is_null());
    assert!(log.lock().unwrap()[0].2.contains("does not match"));
    let (c, log, _cb) = Fmu::with_guid(GUID, fmi2ModelExchange);
    assert!(c.is_null());
    assert!(log.lock().unwrap()[0].2.contains("co-simulation only"));

    let mut f = Fmu::new();
    unsafe {
        f.assert_refused(
            fmi2DoStep(f.c, 0.0, 0.1, 0),
            "not allowed in state Instantiated",
        );
        f.assert_refused(fmi2ExitInitializationMode(f.c), "not allowed");
        f.assert_refused(
            f.set(&[(var::zeta, f64::NAN)]),
            "zeta = NaN is out of range",
        );
        f.assert_refused(
            f.set(&[(var::e, 1.5)]),
            "e = 1.5 is out of range: must be finite and in [0, 1]",
        );
        f.assert_refused(f.set(&[(var::x, 1.0)]), "is an output");
        f.assert_refused(f.set(&[(var::shaker_mode, 3.0)]), "shaker_mode = 3");
        let bad_vr = 9999;
        f.assert_refused(
            fmi2SetReal(f.c, &bad_vr, 1, &1.0),
            "unknown value reference 9999",
        );
        f.assert_refused(fmi2SetReal(f.c, std::ptr::null(), 1, &1.0), "vr is NULL");
        f.assert_refused(
            fmi2SetInteger(f.c, &vr(var::zeta), 1, &1),
            "is Real, not Integer",
        );
        f.assert_refused(
            fmi2SetupExperiment(f.c, 0, 0.0, f64::INFINITY, 0, 0.0),
            "startTime",
        );
        // A refused set changes nothing, not even the valid values in the same call.
        assert_eq!(f.set(&[(var::zeta, 0.5), (var::e, -1.0)]), fmi2Error);
        assert_eq!(fmi2EnterInitializationMode(f.c), fmi2OK);
        assert_eq!(f.real(var::zeta), 0.02);
        // x0 below the plate is refused at the end of initialization.
        assert_eq!(f.set(&[(var::x0, -0.5)]), fmi2OK);
        f.assert_refused(fmi2ExitInitializationMode(f.c), "below the plate");
        assert_eq!(f.set(&[(var::x0, 0.0)]), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(f.c), fmi2OK);
        f.assert_refused(f.set(&[(var::zeta, 0.1)]), "fixed parameter");
        f.assert_refused(fmi2DoStep(f.c, 0.0, -1.0, 0), "communicationStepSize = -1");
        f.assert_refused(
            fmi2DoStep(f.c, 0.0, f64::NAN, 0),
            "communicationStepSize = NaN",
        );
        f.assert_refused(fmi2DoStep(f.c, 5.0, 1.0, 0), "does not match");
        f.assert_refused(fmi2CancelStep(f.c), "synchronous");
        let mut value = 0.0;
        f.assert_refused(
            fmi2GetReal(f.c, &vr(var::x), 1, std::ptr::null_mut()),
            "value is NULL",
        );
        f.assert_refused(
            fmi2GetDirectionalDerivative(f.c, &0, 1, &0, 1, &1.0, &mut value),
            "not provided",
        );
        let mut status = fmi2OK;
        assert_eq!(
            fmi2GetStatus(f.c, fmi2DoStepStatus, &mut status),
            fmi2Discard
        );
        f.assert_refused(
            fmi2GetRealStatus(f.c, 42, &mut value),
            "unknown status kind 42",
        );
        let cat = CString::new("logNonsense").unwrap();
        f.assert_refused(
            fmi2SetDebugLogging(f.c, fmi2True, 1, &cat.as_ptr()),
            "unknown log category",
        );
        let two = 2;
        f.assert_refused(
            fmi2SetRealInputDerivatives(f.c, &vr(var::x), 1, &two, &1.0),
            "only z_in and zdot_in",
        );
        f.assert_refused(
            fmi2SetRealInputDerivatives(f.c, &vr(var::z_in), 1, &9, &1.0),
            "order 9",
        );
        // The instance still works after all this.
        assert_eq!(f.step(1.0), fmi2OK);
        assert!(f.int(var::impact_count) >= 1);
        assert_eq!(fmi2Terminate(f.c), fmi2OK);
        f.assert_refused(
            fmi2DoStep(f.c, 1.0, 1.0, 0),
            "not allowed in state Terminated",
        );
        assert_eq!(fmi2Reset(f.c), fmi2OK);
        assert_eq!(f.set(&[(var::zeta, 0.1)]), fmi2OK);
        // NULL component: refused without a crash.
        assert_eq!(fmi2DoStep(std::ptr::null_mut(), 0.0, 1.0, 0), fmi2Error);
    }
}

#[test]
fn a_step_that_cannot_finish_is_a_discard_with_terminated_status() {
    // A plate input whose fifth derivative is 1e300 m/s^5 hurls the mass out of the range of
    // doubles within the step: the core stops with a non-finite state.
    let mut f = Fmu::started(&[(var::shaker_mode, 2.0)]);
    let s = unsafe { fmi2SetRealInputDerivatives(f.c, &vr(var::z_in), 1, &5, &1e300) };
    assert_eq!(s, fmi2OK);
    assert_eq!(f.step(10.0), fmi2Discard, "{:?}", f.messages());
    let (st, category, msg) = f.log.lock().unwrap().last().cloned().unwrap();
    assert_eq!((st, category.as_str()), (fmi2Discard, "logStatusDiscard"));
    assert!(msg.contains("no longer finite"), "{msg}");
    let (mut term, mut t) = (fmi2False, f64::NAN);
    unsafe {
        assert_eq!(fmi2GetBooleanStatus(f.c, fmi2Terminated, &mut term), fmi2OK);
        assert_eq!(
            fmi2GetRealStatus(f.c, fmi2LastSuccessfulTime, &mut t),
            fmi2OK
        );
        assert_eq!(term, fmi2True);
        assert!((0.0..10.0).contains(&t), "{t}");
        f.assert_refused(
            fmi2DoStep(f.c, t, 1.0, 0),
            "not allowed in state StepFailed",
        );
        assert_eq!(fmi2Terminate(f.c), fmi2OK);
    }
}

#[test]
fn a_later_start_time_shifts_the_run_and_the_shaker_phase() {
    let mut reference = Fmu::started(&[]);
    reference.run(20.0, 0.5);
    let mut f = Fmu::new();
    unsafe {
        assert_eq!(fmi2SetupExperiment(f.c, 0, 0.0, 100.0, 1, 120.0), fmi2OK);
        assert_eq!(fmi2EnterInitializationMode(f.c), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(f.c), fmi2OK);
        f.assert_refused(
            fmi2DoStep(f.c, 0.0, 1.0, 0),
            "does not match the FMU's time 100",
        );
    }
    f.t = 100.0;
    f.run(120.0, 0.5);
    for (a, b) in [
        (f.real(var::x), reference.real(var::x)),
        (f.real(var::v), reference.real(var::v)),
        (
            f.real(var::last_impact_time) - 100.0,
            reference.real(var::last_impact_time),
        ),
        (
            f.real(var::last_impact_phase),
            reference.real(var::last_impact_phase),
        ),
    ] {
        assert!((a - b).abs() < 1e-11, "{a} vs {b}");
    }
    assert_eq!(f.int(var::impact_count), reference.int(var::impact_count));
    // The stop time is enforced.
    let s = unsafe { fmi2DoStep(f.c, 120.0, 1.0, 0) };
    f.assert_refused(s, "beyond stopTime = 120");
}

#[test]
fn debug_logging_follows_the_enabled_categories() {
    let mut f = Fmu::new();
    unsafe {
        // Instantiated with logging on: events are logged.
        assert_eq!(fmi2SetupExperiment(f.c, 0, 0.0, 0.0, 0, 0.0), fmi2OK);
        let none: [fmi2String; 0] = [];
        assert_eq!(
            fmi2SetDebugLogging(f.c, fmi2False, 0, none.as_ptr()),
            fmi2OK
        );
        assert_eq!(fmi2EnterInitializationMode(f.c), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(f.c), fmi2OK);
        assert_eq!(f.step(20.0), fmi2OK);
        assert!(f.messages().is_empty(), "{:?}", f.messages());
        // Only logEvents on: impacts appear, with the category.
        let events = CString::new("logEvents").unwrap();
        assert_eq!(
            fmi2SetDebugLogging(f.c, fmi2True, 1, &events.as_ptr()),
            fmi2OK
        );
        assert_eq!(f.step(20.0), fmi2OK);
        let log = f.log.lock().unwrap();
        assert!(log.len() >= 3);
        assert!(log.iter().all(|(s, c, _)| *s == fmi2OK && c == "logEvents"));
    }
}

#[test]
fn input_derivatives_set_during_initialization_shape_the_first_step() {
    let run = |orders: &[i32]| {
        let f = Fmu::new();
        unsafe {
            assert_eq!(fmi2SetupExperiment(f.c, 0, 0.0, 0.0, 0, 0.0), fmi2OK);
            assert_eq!(fmi2EnterInitializationMode(f.c), fmi2OK);
            assert_eq!(
                f.set(&[(var::shaker_mode, 2.0), (var::zdot_in, 0.07)]),
                fmi2OK
            );
            let vals = vec![-0.5; orders.len()];
            let vrs = vec![vr(var::zdot_in); orders.len()];
            let s = fmi2SetRealInputDerivatives(
                f.c,
                vrs.as_ptr(),
                orders.len(),
                orders.as_ptr(),
                vals.as_ptr(),
            );
            assert_eq!(s, fmi2OK);
            assert_eq!(fmi2ExitInitializationMode(f.c), fmi2OK);
            assert_eq!(fmi2DoStep(f.c, 0.0, 0.5, 0), fmi2OK);
        }
        f.real(var::zdot)
    };
    // zdot(0.5) = 0.07 - 0.5 * 0.5 with the acceleration given, 0.07 without.
    assert!((run(&[1]) - (0.07 - 0.25)).abs() < 1e-15);
    assert!((run(&[]) - 0.07).abs() < 1e-15);
}
