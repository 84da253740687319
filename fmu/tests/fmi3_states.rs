//! FMI 3.0 co-simulation FMU states through the C functions: states taken at an early return.

use std::ffi::CString;
use std::ptr;

use bistable_impact::exports3::*;
use bistable_impact::fmi3::*;
use bistable_impact::md::{var, GUID, VARS};

/// An FMU state taken at an early return between two events of one instant is the instance's
/// own: its restore check must not take the pending event for a state beyond its step ("simulator
/// time is not inside its current step"). Here the mass (v0 = -1e8 m/s, in range) hits the plate
/// at t = 3.2e-9 s with e = 0; the plastic impact starts sticking at the same instant, an event
/// still pending when the step returns early at the impact. The state restores, and the step
/// after it repeats the original step bit for bit.
#[test]
fn a_state_between_two_events_of_one_instant_restores_and_repeats_the_step() {
    unsafe {
        let name = CString::new("fmi3_states").unwrap();
        let token = CString::new(GUID).unwrap();
        let c = fmi3InstantiateCoSimulation(
            name.as_ptr(),
            token.as_ptr(),
            ptr::null(),
            false,
            false,
            true,
            true,
            ptr::null(),
            0,
            ptr::null_mut(),
            None,
            None,
        );
        assert!(!c.is_null());
        let set = |i: usize, v: f64| {
            let r = VARS[i].vr;
            assert_eq!(fmi3SetFloat64(c, &r, 1, &v, 1), fmi3OK, "{}", VARS[i].name);
        };
        let get = |i: usize| {
            let (r, mut v) = (VARS[i].vr, f64::NAN);
            assert_eq!(fmi3GetFloat64(c, &r, 1, &mut v, 1), fmi3OK);
            v
        };
        let count = || {
            let (r, mut n) = (VARS[var::impact_count].vr, -1);
            assert_eq!(fmi3GetInt32(c, &r, 1, &mut n, 1), fmi3OK);
            n
        };
        set(var::delta_x, 1.4244430669251051);
        set(var::x0, 0.32054588946603635);
        assert_eq!(
            fmi3EnterInitializationMode(c, false, 0.0, 0.0, false, 0.0),
            fmi3OK
        );
        set(var::omega0, 0.8159462286151973);
        set(var::v0, -1e8);
        set(var::e, 0.0);
        assert_eq!(fmi3ExitInitializationMode(c), fmi3OK);
        assert_eq!(fmi3EnterStepMode(c), fmi3OK);
        let (mut handling, mut terminate, mut early, mut last) = (false, false, false, f64::NAN);
        let mut step = |tc: f64, h: f64| {
            let s = fmi3DoStep(
                c,
                tc,
                h,
                false,
                &mut handling,
                &mut terminate,
                &mut early,
                &mut last,
            );
            assert_eq!(s, fmi3OK);
            (early, last)
        };
        let (early_return, t_impact) = step(0.0, 5e-5);
        assert!(
            early_return && t_impact > 0.0 && t_impact < 1e-8,
            "{t_impact}"
        );
        assert_eq!(count(), 1);
        assert_eq!(fmi3EnterEventMode(c), fmi3OK);
        let mut state: fmi3FMUState = ptr::null_mut();
        assert_eq!(fmi3GetFMUState(c, &mut state), fmi3OK);
        assert_eq!(fmi3SetFMUState(c, state), fmi3OK, "its own state restores");
        let outputs = [var::x, var::v, var::z, var::last_impact_time];
        let mut after = Vec::new();
        for _ in 0..2 {
            assert_eq!(fmi3EnterStepMode(c), fmi3OK);
            let end = step(t_impact, 1e-3);
            let values: Vec<u64> = outputs.iter().map(|&i| get(i).to_bits()).collect();
            after.push((end.0, end.1.to_bits(), values, count()));
            assert_eq!(fmi3SetFMUState(c, state), fmi3OK);
        }
        assert_eq!(
            after[0], after[1],
            "the step after a restore repeats the first"
        );
        assert_eq!(fmi3FreeFMUState(c, &mut state), fmi3OK);
        fmi3FreeInstance(c);
    }
}
