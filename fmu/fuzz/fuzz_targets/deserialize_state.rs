//! Arbitrary bytes into `fmi2DeSerializeFMUstate`, then `fmi2SetFMUstate`, `fmi2DoStep`,
//! `fmi2GetReal`. Input: one mode byte, then the buffer.
//!   bit 0     recompute the declared length and the checksum (reach the field checks)
//!   bits 1-2  the receiving instance: fresh, running (internal shaker), running (external), or
//!             in initialization mode
//! Invariants: the call returns OK or Error; refused bytes give no handle and leave the instance's
//! outputs bit for bit as they were; accepted bytes are a well-formed state whose serialization is
//! the same bytes, which restores (fmi2SetFMUstate OK) to outputs that are finite and physical
//! (checked whenever they are read), restores again to the same outputs bit for bit, and steps on
//! with statuses OK, Discard or Error only.
#![no_main]

use bistable_fmu_fuzz::{fix_up, same, status, Fmu};
use bistable_impact::exports2::*;
use bistable_impact::fmi2::*;
use bistable_impact::instance::Lifecycle;
use bistable_impact::md::var;
use bistable_impact::state::Snapshot;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    let mut bytes = rest.to_vec();
    if mode & 1 == 1 {
        fix_up(&mut bytes);
    }
    let f = match (mode >> 1) & 3 {
        0 => Fmu::new(),
        1 => Fmu::started(false, &[(var::Omega, 0.3), (var::V, 0.05)]),
        2 => Fmu::started(true, &[(var::zdot_in, 0.07)]),
        _ => {
            let f = Fmu::new();
            assert_eq!(unsafe { fmi2EnterInitializationMode(f.c) }, fmi2OK);
            f
        }
    };
    let before = f.outputs();
    let mut h: fmi2FMUstate = std::ptr::null_mut();
    let st =
        status(unsafe { fmi2DeSerializeFMUstate(f.c, bytes.as_ptr().cast(), bytes.len(), &mut h) });
    if st != fmi2OK {
        assert_eq!(st, fmi2Error);
        assert!(h.is_null(), "a handle from refused bytes");
        assert!(
            same(&before, &f.outputs()),
            "refused bytes changed the instance"
        );
        return;
    }
    assert!(!h.is_null());
    let snap = Snapshot::deserialize(&bytes).expect("accepted bytes are a well-formed state");
    // Serializing the state gives back the same bytes.
    let mut size = 0;
    assert_eq!(
        unsafe { fmi2SerializedFMUstateSize(f.c, h, &mut size) },
        fmi2OK
    );
    let mut again = vec![0u8; size];
    let s = unsafe { fmi2SerializeFMUstate(f.c, h, again.as_mut_ptr().cast(), size) };
    assert_eq!(s, fmi2OK);
    assert!(again == bytes, "serialize(deserialize(bytes)) != bytes");
    // Restoring works and gives finite, physical outputs (readable whenever a model runs).
    assert_eq!(status(unsafe { fmi2SetFMUstate(f.c, h) }), fmi2OK);
    let out = f.outputs();
    let readable = !matches!(snap.lifecycle, Lifecycle::Instantiated);
    if snap.model.is_some() && readable {
        assert!(
            out.is_some(),
            "a restored running model has no readable outputs"
        );
    }
    // Steps from it (only StepComplete allows them).
    if let (Lifecycle::StepComplete, Some(m)) = (snap.lifecycle, &snap.model) {
        let mut t = m.time;
        for dt in [1e-3, 0.25] {
            let s = status(unsafe { fmi2DoStep(f.c, t, dt, fmi2False) });
            let o = f.outputs();
            if s != fmi2OK {
                break;
            }
            assert!(o.is_some());
            t += dt;
        }
        // Back to the state: the same outputs as right after the first restore.
        assert_eq!(unsafe { fmi2SetFMUstate(f.c, h) }, fmi2OK);
        assert!(same(&out, &f.outputs()), "restoring twice differs");
    }
    assert_eq!(unsafe { fmi2FreeFMUstate(f.c, &mut h) }, fmi2OK);
});
