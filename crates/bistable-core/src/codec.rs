//! A versioned, checked byte format for [`Checkpoint`]s, and the little-endian field writer and
//! reader it is built from (used by the FMU's state format too, so both share one serializer).
//!
//! Fields are little endian: `u8`, `u32`, `u64`, `f64` as its bit pattern, pairs `(hi, lo)` as
//! two `f64`; an option is a `u8` tag (0/1) followed by the value; enums are `u8` tags.
//!
//! [`Checkpoint::to_bytes`] frames a checkpoint as: magic `BICHKPT\0` (8 bytes), format version
//! `u32`, total length `u64`, the checkpoint's fields ([`put_checkpoint`]), and an FNV-1a 64
//! checksum of all bytes before it. [`Checkpoint::from_bytes`] refuses a wrong magic, version,
//! length or checksum, truncation, unknown tags and trailing bytes; the values themselves are
//! checked when a simulator is rebuilt from the checkpoint
//! ([`crate::Simulator::from_checkpoint`]).

use crate::checkpoint::{Checkpoint, KeptFlight, PlateRecord};
use crate::events::{ContactMode, Impact, StickCause, Well};
use crate::params::ChatterRule;
use crate::shaker::MAX_POLY_DEGREE;
use crate::simulator::Stats;

/// First bytes of a serialized checkpoint.
pub const MAGIC: &[u8; 8] = b"BICHKPT\0";
/// Format version of [`Checkpoint::to_bytes`]; bump on any layout change.
pub const VERSION: u32 = 2;

/// Appends little-endian fields to a byte vector.
#[derive(Debug, Default, Clone)]
pub struct Writer(pub Vec<u8>);

impl Writer {
    /// One byte.
    pub fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    /// Four bytes.
    pub fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    /// Eight bytes.
    pub fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    /// The bit pattern of `v` (exact, NaN payloads included).
    pub fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    /// Two `f64` (e.g. an instant `(hi, lo)`).
    pub fn pair(&mut self, (a, b): (f64, f64)) {
        self.f64(a);
        self.f64(b);
    }
    /// A tag 0 (`None`) or 1 followed by the value written by `put`.
    pub fn opt<T>(&mut self, v: Option<T>, put: impl FnOnce(&mut Self, T)) {
        match v {
            None => self.u8(0),
            Some(x) => {
                self.u8(1);
                put(self, x);
            }
        }
    }
}

/// Result of a read: the error is a one-line message naming what is read.
pub type Res<T> = Result<T, String>;

/// Reads fields in order; every read checks the remaining length. `what` names the format in
/// messages ("truncated {what}: …", "corrupt {what}: …").
#[derive(Debug, Clone)]
pub struct Reader<'a> {
    /// The bytes being read.
    pub bytes: &'a [u8],
    /// Position of the next read.
    pub pos: usize,
    /// Name of the format in messages, e.g. "checkpoint".
    pub what: &'static str,
}

impl<'a> Reader<'a> {
    /// A reader at the start of `bytes`.
    pub fn new(bytes: &'a [u8], what: &'static str) -> Self {
        Self {
            bytes,
            pos: 0,
            what,
        }
    }
    /// The next `n` bytes.
    pub fn take(&mut self, n: usize) -> Res<&'a [u8]> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| {
            format!(
                "truncated {}: {n} more bytes needed at byte {}",
                self.what, self.pos
            )
        })?;
        let s = &self.bytes[self.pos..end];
        self.pos = end;
        Ok(s)
    }
    /// One byte.
    pub fn u8(&mut self) -> Res<u8> {
        Ok(self.take(1)?[0])
    }
    /// Four bytes.
    pub fn u32(&mut self) -> Res<u32> {
        Ok(u32::from_le_bytes(
            self.take(4)?.try_into().unwrap_or_default(),
        ))
    }
    /// Eight bytes.
    pub fn u64(&mut self) -> Res<u64> {
        Ok(u64::from_le_bytes(
            self.take(8)?.try_into().unwrap_or_default(),
        ))
    }
    /// An `f64` from its bit pattern.
    pub fn f64(&mut self) -> Res<f64> {
        Ok(f64::from_bits(self.u64()?))
    }
    /// Two `f64`.
    pub fn pair(&mut self) -> Res<(f64, f64)> {
        Ok((self.f64()?, self.f64()?))
    }
    /// A `u8` tag below `count`; `what` names it in the error.
    pub fn tag(&mut self, what: &str, count: u8) -> Res<u8> {
        let t = self.u8()?;
        if t < count {
            Ok(t)
        } else {
            Err(format!(
                "corrupt {}: invalid {what} tag {t} at byte {}",
                self.what,
                self.pos - 1
            ))
        }
    }
    /// A tag 0 or 1.
    pub fn bool(&mut self, what: &str) -> Res<bool> {
        Ok(self.tag(what, 2)? == 1)
    }
    /// An option written by [`Writer::opt`].
    pub fn opt<T>(&mut self, what: &str, get: impl FnOnce(&mut Self) -> Res<T>) -> Res<Option<T>> {
        if self.bool(what)? {
            get(self).map(Some)
        } else {
            Ok(None)
        }
    }
}

/// FNV-1a, 64 bits.
pub fn checksum(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// Stick causes in the order of their tags.
pub const CAUSES: [StickCause; 4] = [
    StickCause::Accumulation,
    StickCause::FixedGap,
    StickCause::Plastic,
    StickCause::ZenoGuard,
];

/// Tag of `cause` (its index in [`CAUSES`]).
pub fn cause_tag(cause: StickCause) -> u8 {
    CAUSES.iter().position(|c| *c == cause).unwrap_or_default() as u8
}

/// Reads a stick cause tag.
pub fn get_cause(r: &mut Reader) -> Res<StickCause> {
    Ok(CAUSES[usize::from(r.tag("stick cause", CAUSES.len() as u8)?)])
}

/// Writes an impact.
pub fn put_impact(w: &mut Writer, i: &Impact) {
    w.u64(i.index);
    w.f64(i.t);
    w.opt(i.phase, Writer::f64);
    w.f64(i.x);
    w.f64(i.v_before);
    w.f64(i.v_after);
    w.f64(i.zdot);
    w.f64(i.delta_k);
}

/// Reads an impact written by [`put_impact`].
pub fn get_impact(r: &mut Reader) -> Res<Impact> {
    Ok(Impact {
        index: r.u64()?,
        t: r.f64()?,
        phase: r.opt("phase", Reader::f64)?,
        x: r.f64()?,
        v_before: r.f64()?,
        v_after: r.f64()?,
        zdot: r.f64()?,
        delta_k: r.f64()?,
    })
}

/// Writes the fields of a checkpoint (no framing).
pub fn put_checkpoint(w: &mut Writer, c: &Checkpoint) {
    w.f64(c.zeta);
    w.f64(c.restitution);
    w.f64(c.tol);
    w.u64(c.order as u64);
    match c.chatter {
        ChatterRule::Accumulation { horizon } => {
            w.u8(0);
            w.f64(horizon);
        }
        ChatterRule::FixedGap { gap } => {
            w.u8(1);
            w.f64(gap);
        }
    }
    w.u32(c.max_chatter_impacts);
    match c.plate {
        PlateRecord::Sinusoid {
            omega,
            velocity,
            origin,
            phase0,
            offset,
        } => {
            w.u8(0);
            [omega, velocity].iter().for_each(|&v| w.f64(v));
            w.pair(origin);
            [phase0, offset].iter().for_each(|&v| w.f64(v));
        }
        PlateRecord::Poly { start, end, coeffs } => {
            w.u8(1);
            w.pair(start);
            w.pair(end);
            coeffs.iter().for_each(|&v| w.f64(v));
        }
    }
    w.pair(c.t0);
    w.u8(u8::from(c.mode == ContactMode::Sticking));
    w.f64(c.u0);
    w.f64(c.w0);
    w.u8(c.pinned);
    w.u8(u8::from(c.on_barrier));
    w.u8(u8::from(c.well == Well::Two));
    w.pair(c.now);
    w.opt(c.last_impact.as_ref(), put_impact);
    w.opt(c.last_impact_t, Writer::pair);
    w.u32(c.short_flights);
    let s = c.stats;
    [s.steps, s.impacts, s.sticks, s.snap_throughs]
        .iter()
        .for_each(|&v| w.u64(v));
    w.opt(c.tail, |w, (len, cause)| {
        w.f64(len);
        w.u8(cause_tag(cause));
    });
    w.opt(c.kept, |w, k| {
        [k.x0, k.v0, k.reach].iter().for_each(|&v| w.f64(v));
        w.opt(k.anchor, |w, (s, x, v)| {
            [s, x, v].iter().for_each(|&a| w.f64(a));
        });
    });
}

/// Reads the fields written by [`put_checkpoint`].
pub fn get_checkpoint(r: &mut Reader) -> Res<Checkpoint> {
    let zeta = r.f64()?;
    let restitution = r.f64()?;
    let tol = r.f64()?;
    let what = r.what;
    let order = usize::try_from(r.u64()?).map_err(|_| format!("corrupt {what}: order"))?;
    let chatter = match r.tag("chatter rule", 2)? {
        0 => ChatterRule::Accumulation { horizon: r.f64()? },
        _ => ChatterRule::FixedGap { gap: r.f64()? },
    };
    let max_chatter_impacts = r.u32()?;
    let plate = match r.tag("plate", 2)? {
        0 => PlateRecord::Sinusoid {
            omega: r.f64()?,
            velocity: r.f64()?,
            origin: r.pair()?,
            phase0: r.f64()?,
            offset: r.f64()?,
        },
        _ => {
            let start = r.pair()?;
            let end = r.pair()?;
            let mut coeffs = [0.0; MAX_POLY_DEGREE + 1];
            for c in coeffs.iter_mut() {
                *c = r.f64()?;
            }
            PlateRecord::Poly { start, end, coeffs }
        }
    };
    Ok(Checkpoint {
        zeta,
        restitution,
        tol,
        order,
        chatter,
        max_chatter_impacts,
        plate,
        t0: r.pair()?,
        mode: if r.bool("contact mode")? {
            ContactMode::Sticking
        } else {
            ContactMode::Free
        },
        u0: r.f64()?,
        w0: r.f64()?,
        pinned: r.u8()?,
        on_barrier: r.bool("on_barrier")?,
        well: if r.bool("well")? {
            Well::Two
        } else {
            Well::One
        },
        now: r.pair()?,
        last_impact: r.opt("last impact", get_impact)?,
        last_impact_t: r.opt("last impact time", Reader::pair)?,
        short_flights: r.u32()?,
        stats: Stats {
            steps: r.u64()?,
            impacts: r.u64()?,
            sticks: r.u64()?,
            snap_throughs: r.u64()?,
        },
        tail: r.opt("chatter tail", |r| {
            let len = r.f64()?;
            Ok((len, get_cause(r)?))
        })?,
        kept: r.opt("kept flight", |r| {
            Ok(KeptFlight {
                x0: r.f64()?,
                v0: r.f64()?,
                reach: r.f64()?,
                anchor: r.opt("kept flight anchor", |r| Ok((r.f64()?, r.f64()?, r.f64()?)))?,
            })
        })?,
    })
}

impl Checkpoint {
    /// The framed byte form (see the module documentation): exact, pointer-free, portable.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = Writer(Vec::with_capacity(320));
        w.0.extend_from_slice(MAGIC);
        w.u32(VERSION);
        w.u64(0); // total length, patched below
        put_checkpoint(&mut w, self);
        let total = (w.0.len() + 8) as u64;
        w.0[12..20].copy_from_slice(&total.to_le_bytes());
        let sum = checksum(&w.0);
        w.u64(sum);
        w.0
    }

    /// Parses bytes made by [`Checkpoint::to_bytes`], refusing anything else (the error says
    /// why). The values are checked by [`crate::Simulator::from_checkpoint`].
    pub fn from_bytes(bytes: &[u8]) -> Res<Self> {
        let mut r = Reader::new(bytes, "checkpoint");
        if r.take(MAGIC.len())? != MAGIC {
            return Err("not a bistable checkpoint (wrong magic bytes)".into());
        }
        let version = r.u32()?;
        if version != VERSION {
            return Err(format!(
                "checkpoint format version {version} is not supported (this build reads version {VERSION})"
            ));
        }
        let total = r.u64()?;
        if total != bytes.len() as u64 {
            return Err(format!(
                "checkpoint is {} bytes but declares {total}: truncated or padded",
                bytes.len()
            ));
        }
        let (body, sum) = bytes.split_at(bytes.len() - 8);
        if checksum(body) != u64::from_le_bytes(sum.try_into().unwrap_or_default()) {
            return Err("corrupt checkpoint: checksum mismatch".into());
        }
        r.bytes = body;
        let c = get_checkpoint(&mut r)?;
        if r.pos != body.len() {
            return Err(format!(
                "corrupt checkpoint: {} unexpected bytes at the end",
                body.len() - r.pos
            ));
        }
        Ok(c)
    }
}

#[cfg(test)]
mod tests {
    use crate::{Checkpoint, Params, Simulator, Sinusoid, SolverOptions};

    fn sample() -> Checkpoint {
        let plate = Sinusoid::new(1.75, 0.07).unwrap();
        let mut sim =
            Simulator::new(Params::paper(), plate.into(), SolverOptions::default()).unwrap();
        sim.advance_to(37.5, &mut |_: &crate::Event| {}).unwrap();
        sim.checkpoint()
    }

    #[test]
    fn round_trip_is_exact() {
        let c = sample();
        let bytes = c.to_bytes();
        assert_eq!(&bytes[..8], super::MAGIC);
        assert_eq!(Checkpoint::from_bytes(&bytes).unwrap(), c);
    }

    #[test]
    fn every_truncation_and_single_bit_flip_is_refused() {
        let bytes = sample().to_bytes();
        for n in 0..bytes.len() {
            assert!(Checkpoint::from_bytes(&bytes[..n]).is_err(), "length {n}");
        }
        for i in 0..bytes.len() {
            let mut bad = bytes.clone();
            bad[i] ^= 1 << (i % 8);
            assert!(Checkpoint::from_bytes(&bad).is_err(), "flip at {i}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(Checkpoint::from_bytes(&longer)
            .unwrap_err()
            .contains("declares"));
    }
}
