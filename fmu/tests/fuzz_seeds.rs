//! The seed corpus of the `deserialize_state` fuzz target (`fmu/fuzz/seeds/deserialize_state/`):
//! serialized states in every lifecycle state and both shaker modes, each prefixed by the
//! target's mode byte. This test checks that the committed seeds are still accepted states;
//! `BISTABLE_UPDATE_FUZZ_SEEDS=1 cargo test -p bistable-fmu --test fuzz_seeds` rewrites them
//! (after a change of the state format).

use std::ffi::CString;
use std::path::PathBuf;
use std::ptr;

use bistable_impact::exports2::*;
use bistable_impact::fmi2::*;
use bistable_impact::md::{var, GUID, VARS};

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds/deserialize_state")
}

/// An instance and the callbacks it points to (kept alive with it).
struct Fmu(
    fmi2Component,
    #[allow(dead_code)] Box<fmi2CallbackFunctions>,
);

impl Fmu {
    fn new() -> Self {
        let cb = Box::new(fmi2CallbackFunctions {
            logger: None,
            allocateMemory: None,
            freeMemory: None,
            stepFinished: None,
            componentEnvironment: ptr::null_mut(),
        });
        let (name, guid) = (CString::new("seeds").unwrap(), CString::new(GUID).unwrap());
        let c = unsafe {
            fmi2Instantiate(
                name.as_ptr(),
                fmi2CoSimulation,
                guid.as_ptr(),
                ptr::null(),
                &*cb,
                0,
                0,
            )
        };
        assert!(!c.is_null());
        Fmu(c, cb)
    }

    fn set(&self, i: usize, v: f64) {
        let s = unsafe {
            if i == var::shaker_mode {
                fmi2SetInteger(self.0, &VARS[i].vr, 1, &(v as i32))
            } else {
                fmi2SetReal(self.0, &VARS[i].vr, 1, &v)
            }
        };
        assert_eq!(s, fmi2OK);
    }

    fn bytes(&self) -> Vec<u8> {
        let mut h: fmi2FMUstate = ptr::null_mut();
        let mut n = 0;
        unsafe {
            assert_eq!(fmi2GetFMUstate(self.0, &mut h), fmi2OK);
            assert_eq!(fmi2SerializedFMUstateSize(self.0, h, &mut n), fmi2OK);
            let mut b = vec![0u8; n];
            let s = fmi2SerializeFMUstate(self.0, h, b.as_mut_ptr().cast(), n);
            assert_eq!(s, fmi2OK);
            assert_eq!(fmi2FreeFMUstate(self.0, &mut h), fmi2OK);
            b
        }
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        unsafe { fmi2FreeInstance(self.0) };
    }
}

/// `(file name, mode byte, state bytes)` of each seed.
fn seeds() -> Vec<(&'static str, u8, Vec<u8>)> {
    let mut out = Vec::new();
    let f = Fmu::new();
    out.push(("instantiated", 0, f.bytes()));
    let g = Fmu::new();
    g.set(var::shaker_mode, 2.0);
    unsafe { assert_eq!(fmi2EnterInitializationMode(g.0), fmi2OK) };
    g.set(var::zdot_in, 0.07);
    out.push(("initialization_external", 2, g.bytes()));
    unsafe {
        // Internal shaker, mid-flight, then riding the plate after a chatter sequence.
        let f = Fmu::new();
        assert_eq!(fmi2EnterInitializationMode(f.0), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(f.0), fmi2OK);
        assert_eq!(fmi2DoStep(f.0, 0.0, 3.3, 0), fmi2OK);
        out.push(("baseline_flight", 0, f.bytes()));
        assert_eq!(fmi2Terminate(f.0), fmi2OK);
        out.push(("terminated", 4, f.bytes()));
        let f = Fmu::new();
        f.set(var::Omega, 0.3);
        f.set(var::V, 0.05);
        assert_eq!(fmi2EnterInitializationMode(f.0), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(f.0), fmi2OK);
        assert_eq!(fmi2DoStep(f.0, 0.0, 12.0, 0), fmi2OK);
        out.push(("chatter_sticking", 3, f.bytes()));
        // External plate with input derivatives for the next step.
        let f = Fmu::new();
        f.set(var::shaker_mode, 2.0);
        f.set(var::zdot_in, 0.07);
        assert_eq!(fmi2EnterInitializationMode(f.0), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(f.0), fmi2OK);
        assert_eq!(fmi2DoStep(f.0, 0.0, 0.5, 0), fmi2OK);
        let s = fmi2SetRealInputDerivatives(f.0, &VARS[var::z_in].vr, 1, &3, &-0.02);
        assert_eq!(s, fmi2OK);
        out.push(("external_derivatives", 5, f.bytes()));
        // A Discard (input derivative 1e300 m/s^5): state StepFailed.
        let s = fmi2SetRealInputDerivatives(f.0, &VARS[var::z_in].vr, 1, &5, &1e300);
        assert_eq!(s, fmi2OK);
        assert_eq!(fmi2DoStep(f.0, 0.5, 10.0, 0), fmi2Discard);
        out.push(("step_failed", 1, f.bytes()));
    }
    out
}

#[test]
fn committed_fuzz_seeds_are_accepted_states() {
    if std::env::var_os("BISTABLE_UPDATE_FUZZ_SEEDS").is_some() {
        std::fs::create_dir_all(dir()).unwrap();
        for (name, mode, bytes) in seeds() {
            let mut data = vec![mode];
            data.extend_from_slice(&bytes);
            std::fs::write(dir().join(name), data).unwrap();
        }
    }
    let mut n = 0;
    for entry in std::fs::read_dir(dir()).expect("fmu/fuzz/seeds/deserialize_state") {
        let data = std::fs::read(entry.unwrap().path()).unwrap();
        let f = Fmu::new();
        let mut h: fmi2FMUstate = ptr::null_mut();
        let bytes = &data[1..];
        let s = unsafe { fmi2DeSerializeFMUstate(f.0, bytes.as_ptr().cast(), bytes.len(), &mut h) };
        assert_eq!(
            s, fmi2OK,
            "a committed seed is refused: regenerate (see above)"
        );
        assert_eq!(unsafe { fmi2SetFMUstate(f.0, h) }, fmi2OK);
        n += 1;
    }
    assert_eq!(n, seeds().len());
}
