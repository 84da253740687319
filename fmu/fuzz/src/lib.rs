//! What the fuzz targets share: an FMU instance driven only through the exported `extern "C"`
//! functions, and the invariants checked after the calls. A violated invariant panics, which
//! libFuzzer reports as a crash (so does a panic inside the FMU: the fuzzer's panic hook aborts
//! before the FMU's `catch_unwind` could turn it into `fmi2Error`).
#![allow(clippy::missing_safety_doc)]

use std::ffi::CString;
use std::ptr;

use bistable_impact::exports2::*;
use bistable_impact::fmi2::*;
use bistable_impact::md::{var, Causality, Kind, GUID, VARS};

/// The mass may be below the plate by at most this much, relative to `max(delta_x, |x|, |z|)`
/// (the C host's fuzz mode uses the same bound).
pub const GAP_BOUND: f64 = 1e-12;

/// One instance (no logger: refusals are silent, which keeps the targets fast).
pub struct Fmu {
    pub c: fmi2Component,
    _callbacks: Box<fmi2CallbackFunctions>,
}

/// Value reference of the variable with index `i`.
pub fn vr(i: usize) -> fmi2ValueReference {
    VARS[i].vr
}

/// Asserts that `s` is one of the four statuses a call may return.
pub fn status(s: fmi2Status) -> fmi2Status {
    assert!(
        (fmi2OK..=fmi2Error).contains(&s),
        "status {s} is not OK, Warning, Discard or Error"
    );
    s
}

impl Default for Fmu {
    fn default() -> Self {
        Self::new()
    }
}

impl Fmu {
    /// A new instance (state Instantiated).
    pub fn new() -> Self {
        let callbacks = Box::new(fmi2CallbackFunctions {
            logger: None,
            allocateMemory: None,
            freeMemory: None,
            stepFinished: None,
            componentEnvironment: ptr::null_mut(),
        });
        let name = CString::new("fuzz").unwrap();
        let guid = CString::new(GUID).unwrap();
        let c = unsafe {
            fmi2Instantiate(
                name.as_ptr(),
                fmi2CoSimulation,
                guid.as_ptr(),
                ptr::null(),
                &*callbacks,
                fmi2False,
                fmi2False,
            )
        };
        assert!(!c.is_null());
        Fmu {
            c,
            _callbacks: callbacks,
        }
    }

    /// An instance initialized at t = 0 with the given Real parameters (and shaker mode).
    pub fn started(external: bool, reals: &[(usize, f64)]) -> Self {
        let f = Self::new();
        unsafe {
            let mode = if external { 2 } else { 1 };
            assert_eq!(fmi2SetInteger(f.c, &vr(var::shaker_mode), 1, &mode), fmi2OK);
            for &(i, v) in reals {
                assert_eq!(fmi2SetReal(f.c, &vr(i), 1, &v), fmi2OK);
            }
            assert_eq!(fmi2EnterInitializationMode(f.c), fmi2OK);
            assert_eq!(fmi2ExitInitializationMode(f.c), fmi2OK);
        }
        f
    }

    /// A Real value (NaN if refused).
    pub fn real(&self, i: usize) -> f64 {
        let mut x = f64::NAN;
        unsafe { fmi2GetReal(self.c, &vr(i), 1, &mut x) };
        x
    }

    /// Every output (by variable index; other entries NaN), or `None` if reading is refused (as
    /// in state Instantiated). When the read succeeds the outputs are checked (see
    /// [`check_outputs`]); the three typed reads must agree.
    pub fn outputs(&self) -> Option<Vec<f64>> {
        let mut out = vec![f64::NAN; VARS.len()];
        let mut statuses = Vec::new();
        for kind in [Kind::Real, Kind::Integer, Kind::Boolean] {
            let idx: Vec<usize> = (0..VARS.len())
                .filter(|&i| VARS[i].causality == Causality::Output && VARS[i].kind == kind)
                .collect();
            let vrs: Vec<fmi2ValueReference> = idx.iter().map(|&i| vr(i)).collect();
            let s = unsafe {
                match kind {
                    Kind::Real => {
                        let mut v = vec![0.0; vrs.len()];
                        let s = fmi2GetReal(self.c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr());
                        idx.iter().zip(&v).for_each(|(&i, &x)| out[i] = x);
                        s
                    }
                    Kind::Integer => {
                        let mut v = vec![0; vrs.len()];
                        let s = fmi2GetInteger(self.c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr());
                        idx.iter()
                            .zip(&v)
                            .for_each(|(&i, &x)| out[i] = f64::from(x));
                        s
                    }
                    _ => {
                        let mut v = vec![0; vrs.len()];
                        let s = fmi2GetBoolean(self.c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr());
                        idx.iter()
                            .zip(&v)
                            .for_each(|(&i, &x)| out[i] = f64::from(x));
                        s
                    }
                }
            };
            statuses.push(status(s));
        }
        assert!(
            statuses.iter().all(|&s| s == statuses[0]),
            "typed output reads disagree: {statuses:?}"
        );
        if statuses[0] != fmi2OK {
            assert_eq!(statuses[0], fmi2Error);
            return None;
        }
        check_outputs(&out, self.real(var::delta_x), self.real(var::mass));
        Some(out)
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        unsafe { fmi2FreeInstance(self.c) };
    }
}

/// Outputs read with status OK are finite and physical: the mass not below the plate beyond
/// [`GAP_BOUND`], energies >= 0 and the kinetic one `mass v^2/2`, the well the side of the
/// barrier x is on, contact means x = z and v = zdot, counts >= 0, the phase in [0, 1].
pub fn check_outputs(o: &[f64], delta_x: f64, mass: f64) {
    for (i, v) in VARS.iter().enumerate() {
        if v.causality == Causality::Output {
            assert!(
                o[i].is_finite(),
                "output {} = {} is not finite",
                v.name,
                o[i]
            );
        }
    }
    let (x, z, v) = (o[var::x], o[var::z], o[var::v]);
    let scale = delta_x.max(x.abs()).max(z.abs());
    assert!(
        x - z >= -GAP_BOUND * scale,
        "mass below the plate: x = {x}, z = {z}"
    );
    assert!(o[var::kinetic_energy] >= 0.0 && o[var::potential_energy] >= 0.0);
    let ke = 0.5 * mass * v * v;
    assert!(
        (o[var::kinetic_energy] - ke).abs() <= 1e-12 * ke + 1e-300,
        "kinetic energy {} != mass v^2/2 = {ke}",
        o[var::kinetic_energy]
    );
    let well = o[var::well];
    assert!(well == 1.0 || well == 2.0);
    if (x - 0.5 * delta_x).abs() > 1e-9 * delta_x {
        let expected = if x < 0.5 * delta_x { 1.0 } else { 2.0 };
        assert_eq!(
            well, expected,
            "well {well} for x = {x}, delta_x = {delta_x}"
        );
    }
    if o[var::in_contact] == 1.0 {
        assert!(
            x == z && v == o[var::zdot],
            "in contact but x != z or v != zdot"
        );
    }
    assert!(o[var::impact_count] >= 0.0 && o[var::snap_through_count] >= 0.0);
    let phase = o[var::last_impact_phase];
    assert!((0.0..=1.0).contains(&phase), "last impact phase {phase}");
}

/// Outputs equal bit for bit.
pub fn same(a: &Option<Vec<f64>>, b: &Option<Vec<f64>>) -> bool {
    match (a, b) {
        (Some(a), Some(b)) => a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()),
        (None, None) => true,
        _ => false,
    }
}

/// Makes `bytes` pass the FMU state format's envelope: declared length (bytes 12..20) and the
/// FNV-1a 64 checksum in the last 8 bytes (see `fmu/src/state.rs`), so that the fuzzer reaches
/// the field checks behind it. Too short buffers are left alone.
pub fn fix_up(bytes: &mut [u8]) {
    let n = bytes.len();
    if n < 28 {
        return;
    }
    bytes[12..20].copy_from_slice(&(n as u64).to_le_bytes());
    let sum = bytes[..n - 8]
        .iter()
        .fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
            (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
        });
    bytes[n - 8..].copy_from_slice(&sum.to_le_bytes());
}
