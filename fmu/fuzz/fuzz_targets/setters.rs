//! An arbitrary sequence of setter and lifecycle calls: fmi2SetReal/Integer/Boolean/String with
//! arbitrary value references and values (NaN, +-inf, huge, tiny), NULL arrays,
//! fmi2SetRealInputDerivatives, fmi2SetupExperiment, Enter/ExitInitializationMode, fmi2DoStep
//! with arbitrary step sizes and communication points, fmi2Terminate, fmi2Reset, and a rollback
//! through fmi2GetFMUstate/fmi2SetFMUstate.
//! Invariants: every status is OK, Warning, Discard or Error; the outputs, read after every call
//! when the state allows it, are finite and physical; a call refused with fmi2Error leaves them
//! bit for bit as they were; a rollback repeats a step bit for bit.
#![no_main]

use bistable_fmu_fuzz::{same, status, Fmu};
use bistable_impact::exports2::*;
use bistable_impact::fmi2::*;
use bistable_impact::md::{var, VARS};
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;

const SPECIALS: [f64; 14] = [
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    0.0,
    -0.0,
    1e300,
    -1e300,
    1e-300,
    5e-324,
    f64::MAX,
    1e12,
    -1e12,
    1e20,
    1e6,
];

/// A value: a special one, any bit pattern, or a small multiple of 1/16.
#[derive(Arbitrary, Debug, Clone, Copy)]
enum Value {
    Special(u8),
    Raw(f64),
    Small(i8),
}

impl Value {
    fn get(self) -> f64 {
        match self {
            Value::Special(k) => SPECIALS[usize::from(k) % SPECIALS.len()],
            Value::Raw(x) => x,
            Value::Small(k) => f64::from(k) / 16.0,
        }
    }
}

/// A value reference: one of the model's (by index) or any number.
#[derive(Arbitrary, Debug, Clone, Copy)]
enum Vr {
    Index(u8),
    Raw(u32),
}

impl Vr {
    fn get(self) -> fmi2ValueReference {
        match self {
            Vr::Index(k) => VARS[usize::from(k) % VARS.len()].vr,
            Vr::Raw(r) => r,
        }
    }
}

/// Special step sizes: refused ones, and 1e4 (refused when it spans more than 1e6 radians,
/// skipped when it is valid but long, see [`long_but_valid`]).
const STEP_SPECIALS: [f64; 13] = [
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    0.0,
    -0.0,
    1e300,
    -1e300,
    1e-300,
    5e-324,
    f64::MAX,
    1e12,
    1e20,
    1e4,
];

/// A step size: up to 2 s in 32768ths, `m * 10^e` (e in [-330, 2]), or a special value.
#[derive(Arbitrary, Debug, Clone, Copy)]
enum Step {
    Unit(u16),
    Pow(i8, i16),
    Special(u8),
}

impl Step {
    fn get(self) -> f64 {
        match self {
            Step::Unit(u) => (f64::from(u) + 1.0) / 32768.0,
            Step::Pow(m, e) => f64::from(m) * 10f64.powi(i32::from(e).clamp(-330, 2)),
            Step::Special(k) => STEP_SPECIALS[usize::from(k) % STEP_SPECIALS.len()],
        }
    }
}

#[derive(Arbitrary, Debug)]
enum Op {
    SetReal(Vec<(Vr, Value)>),
    SetInteger(Vec<(Vr, i32)>),
    SetBoolean(Vec<(Vr, i32)>),
    SetString(Vec<(Vr, bool)>),
    /// A setter with `n > 0` and a NULL value-reference array (`true`) or value array.
    SetNull(u8, bool),
    InputDerivatives(Vec<(Vr, i32, Value)>),
    Setup(Option<Value>, Value, Option<Value>),
    Enter,
    Exit,
    /// A step from the current time (or off it by the value) of the given size.
    DoStep(Option<Value>, Step),
    Terminate,
    Reset,
    /// Get a state, step, restore, step again: the two steps agree bit for bit.
    Rollback(Step),
}

/// A step of `dt` seconds that the FMU would accept but that spans more than 1e3 shaker radians:
/// its cost grows with its length (up to seconds, ten times more under the sanitizer), not a
/// fault, so it is skipped. Steps beyond the FMU's limit (1e6 radians) are made and refused.
fn long_but_valid(f: &Fmu, dt: f64) -> bool {
    let radians = (dt * f.real(var::omega0)).abs() * f.real(var::Omega).max(1.0);
    radians > 1e3 && radians <= 1e6
}

fuzz_target!(|ops: Vec<Op>| {
    let f = Fmu::new();
    let (mut t, mut start) = (0.0, 0.0);
    for op in ops.into_iter().take(64) {
        let before = f.outputs();
        let s = unsafe {
            match &op {
                Op::SetReal(v) => {
                    let (r, x): (Vec<_>, Vec<_>) =
                        v.iter().map(|(r, x)| (r.get(), x.get())).unzip();
                    fmi2SetReal(f.c, r.as_ptr(), r.len(), x.as_ptr())
                }
                Op::SetInteger(v) => {
                    let (r, x): (Vec<_>, Vec<_>) = v.iter().map(|(r, x)| (r.get(), *x)).unzip();
                    fmi2SetInteger(f.c, r.as_ptr(), r.len(), x.as_ptr())
                }
                Op::SetBoolean(v) => {
                    let (r, x): (Vec<_>, Vec<_>) = v.iter().map(|(r, x)| (r.get(), *x)).unzip();
                    fmi2SetBoolean(f.c, r.as_ptr(), r.len(), x.as_ptr())
                }
                Op::SetString(v) => {
                    let r: Vec<_> = v.iter().map(|(r, _)| r.get()).collect();
                    let x: Vec<fmi2String> = v
                        .iter()
                        .map(|(_, some)| {
                            if *some {
                                c"x".as_ptr()
                            } else {
                                std::ptr::null()
                            }
                        })
                        .collect();
                    fmi2SetString(f.c, r.as_ptr(), r.len(), x.as_ptr())
                }
                Op::SetNull(n, vr_null) => {
                    let n = usize::from(*n).max(1);
                    let r = vec![0; n];
                    let x = vec![0.5; n];
                    if *vr_null {
                        fmi2SetReal(f.c, std::ptr::null(), n, x.as_ptr())
                    } else {
                        fmi2SetReal(f.c, r.as_ptr(), n, std::ptr::null())
                    }
                }
                Op::InputDerivatives(v) => {
                    let r: Vec<_> = v.iter().map(|d| d.0.get()).collect();
                    let o: Vec<_> = v.iter().map(|d| d.1).collect();
                    let x: Vec<_> = v.iter().map(|d| d.2.get()).collect();
                    fmi2SetRealInputDerivatives(f.c, r.as_ptr(), r.len(), o.as_ptr(), x.as_ptr())
                }
                Op::Setup(tol, st, stop) => {
                    let s = fmi2SetupExperiment(
                        f.c,
                        tol.is_some().into(),
                        tol.map_or(0.0, Value::get),
                        st.get(),
                        stop.is_some().into(),
                        stop.map_or(0.0, Value::get),
                    );
                    if s == fmi2OK {
                        start = st.get();
                    }
                    s
                }
                Op::Enter => fmi2EnterInitializationMode(f.c),
                Op::Exit => {
                    let s = fmi2ExitInitializationMode(f.c);
                    if s == fmi2OK {
                        t = start;
                    }
                    s
                }
                Op::DoStep(off, h) => {
                    let tc = t + off.map_or(0.0, Value::get);
                    if long_but_valid(&f, tc + h.get() - t) {
                        continue;
                    }
                    let s = fmi2DoStep(f.c, tc, h.get(), fmi2False);
                    if s == fmi2OK {
                        t = tc + h.get();
                    }
                    s
                }
                Op::Terminate => fmi2Terminate(f.c),
                Op::Reset => {
                    let s = fmi2Reset(f.c);
                    (t, start) = (0.0, 0.0);
                    s
                }
                Op::Rollback(h) if long_but_valid(&f, h.get()) => continue,
                Op::Rollback(h) => {
                    let mut state: fmi2FMUstate = std::ptr::null_mut();
                    let s = status(fmi2GetFMUstate(f.c, &mut state));
                    if s == fmi2OK {
                        let first = status(fmi2DoStep(f.c, t, h.get(), fmi2False));
                        let after = f.outputs();
                        assert_eq!(fmi2SetFMUstate(f.c, state), fmi2OK);
                        assert!(same(&before, &f.outputs()), "restore differs");
                        let second = status(fmi2DoStep(f.c, t, h.get(), fmi2False));
                        assert_eq!(first, second, "a repeated step returned another status");
                        if first == fmi2OK {
                            assert!(same(&after, &f.outputs()), "a repeated step differs");
                            t += h.get();
                        }
                        assert_eq!(fmi2FreeFMUstate(f.c, &mut state), fmi2OK);
                    }
                    s
                }
            }
        };
        let after = f.outputs();
        if status(s) == fmi2Error {
            assert!(
                same(&before, &after),
                "{op:?} was refused but changed the outputs"
            );
        }
    }
});
