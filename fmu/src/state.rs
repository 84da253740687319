//! FMU states: a pointer-free snapshot of an instance and its versioned byte format.
//!
//! Layout (little endian): magic `BIFMUST\0` (8 bytes), format version `u32`, total length `u64`,
//! guid (`u32` length + bytes), the fields below in order, and an FNV-1a 64 checksum of all bytes
//! before it. Options are a `u8` tag (0/1) followed by the value; enums are `u8` tags; the FMI
//! version is a tag (0: 2.0, 1: 3.0) and, for 3.0, the event-mode and early-return flags. Decoding
//! refuses a wrong magic, version, length, checksum or guid, truncation, unknown tags and
//! trailing bytes; the instance then checks the values themselves (ranges, core checkpoint).
//! The field writer and reader and the layout of the core checkpoint inside are
//! `bistable_core::codec`'s (shared with the core's own checkpoint byte format).

use bistable_core::codec::{
    checksum, get_checkpoint, get_impact, put_checkpoint, put_impact, Reader, Res, Writer, CAUSES,
};
use bistable_core::sampled::MAX_SAMPLES;
use bistable_core::{ContactMode, Instant, Sample, Well};

use crate::instance::{Api, Interface, Lifecycle};
use crate::md::GUID;
use crate::me::{SavedMe, Tail};
use crate::model::checkpoint::SavedModel;
use crate::model::plate::{PlateInputs, MAX_PLATE_ORDER};

/// First bytes of every serialized state.
pub const MAGIC: &[u8; 8] = b"BIFMUST\0";
/// Format version; bump on any layout change.
pub const VERSION: u32 = 5;

/// Everything an instance needs to continue exactly from a saved point.
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot {
    /// Interface of the instance that made it (only such an instance accepts it).
    pub interface: Interface,
    /// FMI version and options of the instance that made it (likewise).
    pub api: Api,
    /// Lifecycle state.
    pub lifecycle: Lifecycle,
    /// Values of all variables (SI), in model-description order.
    pub values: Vec<f64>,
    /// Plate input derivatives given for the next step.
    pub inputs: PlateInputs,
    /// Start time (s).
    pub start_time: f64,
    /// Stop time (s), if defined.
    pub stop_time: Option<f64>,
    /// End of the last successful step (s).
    pub last_successful_time: f64,
    /// The slave asked to end the simulation.
    pub terminated: bool,
    /// The running co-simulation model, after initialization.
    pub model: Option<SavedModel>,
    /// The running Model Exchange model, after initialization.
    pub me: Option<SavedMe>,
}

const LIFECYCLES: [Lifecycle; 8] = [
    Lifecycle::Instantiated,
    Lifecycle::InitializationMode,
    Lifecycle::StepComplete,
    Lifecycle::StepFailed,
    Lifecycle::Terminated,
    Lifecycle::Error,
    Lifecycle::EventMode,
    Lifecycle::ContinuousTimeMode,
];
const INTERFACES: [Interface; 2] = [Interface::ModelExchange, Interface::CoSimulation];
fn index_of<T: PartialEq>(all: &[T], v: &T) -> u8 {
    all.iter().position(|x| x == v).unwrap_or_default() as u8
}

impl Snapshot {
    /// The byte form (see the module documentation).
    pub fn serialize(&self) -> Vec<u8> {
        let mut w = Writer(Vec::with_capacity(1024));
        w.0.extend_from_slice(MAGIC);
        w.u32(VERSION);
        w.u64(0); // total length, patched below
        w.u32(GUID.len() as u32);
        w.0.extend_from_slice(GUID.as_bytes());
        w.u8(index_of(&INTERFACES, &self.interface));
        match self.api {
            Api::Fmi2 => w.u8(0),
            Api::Fmi3 {
                event_mode,
                early_return,
            } => {
                w.u8(1);
                w.u8(u8::from(event_mode));
                w.u8(u8::from(early_return));
            }
        }
        w.u8(index_of(&LIFECYCLES, &self.lifecycle));
        w.u32(self.values.len() as u32);
        self.values.iter().for_each(|&v| w.f64(v));
        self.inputs.iter().for_each(|&d| w.opt(d, Writer::f64));
        w.f64(self.start_time);
        w.opt(self.stop_time, Writer::f64);
        w.f64(self.last_successful_time);
        w.u8(u8::from(self.terminated));
        w.opt(self.model.as_ref(), |w, m| {
            put_checkpoint(w, &m.checkpoint);
            let (a, b, c, d, e, f) = m.phase_ref;
            [a, b, c, d, e, f].iter().for_each(|&v| w.f64(v));
            w.pair(m.applied);
            w.u8(m.history.len() as u8);
            for (s, joined) in &m.history {
                w.pair(s.t.parts());
                w.pair((s.z, s.zdot));
                w.u8(u8::from(*joined));
            }
            w.f64(m.impulse);
            w.f64(m.time);
            w.u8(u8::from(m.at_event));
        });
        w.opt(self.me.as_ref(), put_me);
        let total = (w.0.len() + 8) as u64;
        w.0[12..20].copy_from_slice(&total.to_le_bytes());
        let sum = checksum(&w.0);
        w.u64(sum);
        w.0
    }

    /// Parses bytes made by [`Snapshot::serialize`], refusing anything else.
    pub fn deserialize(bytes: &[u8]) -> Res<Self> {
        let mut r = Reader::new(bytes, "FMU state");
        if r.take(MAGIC.len())? != MAGIC {
            return Err("not a bistable_impact FMU state (wrong magic bytes)".into());
        }
        let version = r.u32()?;
        if version != VERSION {
            return Err(format!("FMU state format version {version} is not supported (this FMU reads version {VERSION})"));
        }
        let total = r.u64()?;
        if total != bytes.len() as u64 {
            return Err(format!(
                "FMU state is {} bytes but declares {total}: truncated or padded",
                bytes.len()
            ));
        }
        let (body, sum) = bytes.split_at(bytes.len() - 8);
        if checksum(body) != u64::from_le_bytes(sum.try_into().unwrap_or_default()) {
            return Err("corrupt FMU state: checksum mismatch".into());
        }
        r.bytes = body;
        let n = r.u32()? as usize;
        let guid = r.take(n)?;
        if guid != GUID.as_bytes() {
            return Err(format!(
                "FMU state belongs to guid {} , this FMU is {GUID}",
                String::from_utf8_lossy(guid)
            ));
        }
        let interface = INTERFACES[usize::from(r.tag("interface", INTERFACES.len() as u8)?)];
        let api = match r.tag("FMI version", 2)? {
            0 => Api::Fmi2,
            _ => Api::Fmi3 {
                event_mode: r.bool("event mode")?,
                early_return: r.bool("early return")?,
            },
        };
        let lifecycle = LIFECYCLES[usize::from(r.tag("lifecycle", LIFECYCLES.len() as u8)?)];
        let n = r.u32()? as usize;
        if n != crate::md::VARS.len() {
            return Err(format!(
                "FMU state holds {n} variables, the model has {}",
                crate::md::VARS.len()
            ));
        }
        let values = (0..n).map(|_| r.f64()).collect::<Res<Vec<_>>>()?;
        let mut inputs = [None; MAX_PLATE_ORDER + 1];
        for d in inputs.iter_mut() {
            *d = r.opt("input derivative", Reader::f64)?;
        }
        let snap = Snapshot {
            interface,
            api,
            lifecycle,
            values,
            inputs,
            start_time: r.f64()?,
            stop_time: r.opt("stop time", Reader::f64)?,
            last_successful_time: r.f64()?,
            terminated: r.bool("terminated")?,
            model: r.opt("model", |r| {
                Ok(SavedModel {
                    checkpoint: get_checkpoint(r)?,
                    phase_ref: (r.f64()?, r.f64()?, r.f64()?, r.f64()?, r.f64()?, r.f64()?),
                    applied: r.pair()?,
                    history: get_history(r)?,
                    impulse: r.f64()?,
                    time: r.f64()?,
                    at_event: r.bool("at event")?,
                })
            })?,
            me: r.opt("Model Exchange state", get_me)?,
        };
        if r.pos != body.len() {
            return Err(format!(
                "corrupt FMU state: {} unexpected bytes at the end",
                body.len() - r.pos
            ));
        }
        Ok(snap)
    }
}

/// Plate samples of a saved model: a count of at most [`MAX_SAMPLES`], then per sample its
/// instant `(hi, lo)`, `z`, `ż` and the `joined` flag (values are checked on restore).
fn get_history(r: &mut Reader) -> Res<Vec<(Sample, bool)>> {
    let n = r.u8()?;
    if usize::from(n) > MAX_SAMPLES {
        return Err(format!(
            "corrupt FMU state: {n} plate samples (at most {MAX_SAMPLES})"
        ));
    }
    (0..n)
        .map(|_| {
            let (hi, lo) = r.pair()?;
            let t = Instant::from_parts(hi, lo)
                .ok_or("corrupt FMU state: invalid plate sample instant")?;
            let (z, zdot) = r.pair()?;
            Ok((Sample { t, z, zdot }, r.bool("plate sample joined")?))
        })
        .collect()
}

fn put_me(w: &mut Writer, m: &SavedMe) {
    let (a, b, c, d, e, f) = m.phase_ref;
    [a, b, c, d, e, f].iter().for_each(|&v| w.f64(v));
    w.pair(m.applied);
    w.f64(m.tau);
    w.f64(m.event_tau);
    w.f64(m.x);
    w.f64(m.v);
    w.u8(u8::from(m.contact == ContactMode::Sticking));
    w.u8(u8::from(m.well == Well::Two));
    w.u64(m.impacts);
    w.u64(m.snap_throughs);
    w.opt(m.last_impact.as_ref(), put_impact);
    w.f64(m.impulse);
    w.opt(m.tail.as_ref(), |w, t| {
        w.f64(t.until);
        w.u8(index_of(&CAUSES, &t.cause));
        w.u64(t.impacts);
        w.opt(t.last.as_ref(), put_impact);
        w.f64(t.impulse);
    });
}

fn get_me(r: &mut Reader) -> Res<SavedMe> {
    Ok(SavedMe {
        phase_ref: (r.f64()?, r.f64()?, r.f64()?, r.f64()?, r.f64()?, r.f64()?),
        applied: r.pair()?,
        tau: r.f64()?,
        event_tau: r.f64()?,
        x: r.f64()?,
        v: r.f64()?,
        contact: if r.bool("contact mode")? {
            ContactMode::Sticking
        } else {
            ContactMode::Free
        },
        well: if r.bool("well")? {
            Well::Two
        } else {
            Well::One
        },
        impacts: r.u64()?,
        snap_throughs: r.u64()?,
        last_impact: r.opt("last impact", get_impact)?,
        impulse: r.f64()?,
        tail: r.opt("chatter tail", |r| {
            Ok(Tail {
                until: r.f64()?,
                cause: CAUSES[usize::from(r.tag("stick cause", CAUSES.len() as u8)?)],
                impacts: r.u64()?,
                last: r.opt("last impact", get_impact)?,
                impulse: r.f64()?,
            })
        })?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::md::{var, VARS};
    use crate::model::Model;
    use bistable_core::PlateRecord;

    /// Snapshots of models in both shaker modes, one riding a chatter tail or stuck.
    fn samples() -> Vec<Snapshot> {
        let mut out = Vec::new();
        for (mode, omega, v, t_end) in [(1.0, 0.3, 0.05, 30.0), (2.0, 1.75, 0.07, 3.0)] {
            let mut values: Vec<f64> = VARS.iter().map(|x| x.start).collect();
            values[var::shaker_mode] = mode;
            (values[var::Omega], values[var::V]) = (omega, v);
            values[var::zdot_in] = 0.07;
            let inputs = [None, None, Some(-0.1), None, None, Some(1e-3)];
            let mut events = Vec::new();
            let mut m = Model::start(&values, &inputs, 0.0, &mut events).unwrap();
            m.step(t_end, &values, &inputs, &mut events, false)
                .ok()
                .unwrap();
            out.push(Snapshot {
                interface: Interface::CoSimulation,
                api: Api::Fmi2,
                me: None,
                lifecycle: Lifecycle::StepComplete,
                values,
                inputs,
                start_time: 0.0,
                stop_time: Some(100.0),
                last_successful_time: t_end,
                terminated: false,
                model: Some(m.save().unwrap()),
            });
        }
        out
    }

    #[test]
    fn round_trip_is_exact_for_both_plate_kinds() {
        let snaps = samples();
        let kinds: Vec<_> = snaps
            .iter()
            .map(|s| {
                matches!(
                    s.model.as_ref().unwrap().checkpoint.plate,
                    PlateRecord::Poly { .. }
                )
            })
            .collect();
        assert_eq!(kinds, [false, true]);
        for s in snaps {
            let bytes = s.serialize();
            assert_eq!(&bytes[..8], MAGIC);
            assert_eq!(Snapshot::deserialize(&bytes).unwrap(), s);
        }
    }

    #[test]
    fn every_truncation_and_single_bit_flip_is_refused() {
        let bytes = samples()[0].serialize();
        for n in 0..bytes.len() {
            assert!(Snapshot::deserialize(&bytes[..n]).is_err(), "length {n}");
        }
        for i in 0..bytes.len() {
            let mut bad = bytes.clone();
            bad[i] ^= 1 << (i % 8);
            assert!(Snapshot::deserialize(&bad).is_err(), "flip at {i}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(Snapshot::deserialize(&longer)
            .unwrap_err()
            .contains("declares"));
    }

    #[test]
    fn a_well_formed_state_with_bad_values_is_refused_by_validation() {
        let mut s = samples()[0].clone();
        s.values[var::e] = 2.0;
        let bytes = s.serialize();
        let back = Snapshot::deserialize(&bytes).unwrap();
        let err = crate::instance::Instance::validate(&back).err().unwrap();
        assert!(err.contains("e = 2"), "{err}");
        let mut s = samples()[1].clone();
        if let Some(m) = s.model.as_mut() {
            m.checkpoint.u0 = -1.0;
        }
        let err = crate::instance::Instance::validate(&s).err().unwrap();
        assert!(err.contains("u0"), "{err}");
        let mut s = samples()[0].clone();
        s.values[var::zeta] = 0.5;
        let err = crate::instance::Instance::validate(&s).err().unwrap();
        assert!(err.contains("does not match its parameters"), "{err}");
        let mut s = samples()[0].clone();
        s.values[var::shaker_mode] = 2.0;
        let err = crate::instance::Instance::validate(&s).err().unwrap();
        assert!(err.contains("shaker_mode"), "{err}");
    }
}
